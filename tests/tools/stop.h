/*
 * stop.h - how the test tools (delayproxy, fakepeer) stop: SIGTERM or
 * SIGINT sets stop_flag and writes a byte to the wake pipe, whose read end
 * the tool polls beside its sockets, so a tool blocked in poll() ends at
 * once. One copy for both tools.
 */
#ifndef PORTRAY_TOOLS_STOP_H
#define PORTRAY_TOOLS_STOP_H

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <string.h>
#include <unistd.h>

static volatile sig_atomic_t stop_flag;
static int wake_pipe[2] = { -1, -1 }; /* poll wake_pipe[0] for POLLIN */

static void stop_on_signal(int sig)
{
	(void)sig;
	int e = errno;
	stop_flag = 1;
	ssize_t r = write(wake_pipe[1], "", 1);
	(void)r; /* a full pipe already wakes poll() */
	errno = e;
}

/* The wake pipe and the handlers (SIGPIPE ignored: a peer that goes is an
 * error return, not a death). 0, or -1 (errno) when no pipe could be made. */
static inline int stop_init(void)
{
	if (pipe(wake_pipe) < 0)
		return -1;
	fcntl(wake_pipe[1], F_SETFL, fcntl(wake_pipe[1], F_GETFL) | O_NONBLOCK);
	struct sigaction sa;
	memset(&sa, 0, sizeof sa);
	sa.sa_handler = stop_on_signal;
	sigaction(SIGTERM, &sa, NULL);
	sigaction(SIGINT, &sa, NULL);
	signal(SIGPIPE, SIG_IGN);
	return 0;
}

#endif
