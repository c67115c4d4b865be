/*
 * interrupt.c - SIGINT, SIGTERM, SIGHUP and the q/Esc keys end a render
 * early (interrupt.h).
 */
#include "master/interrupt.h"

#include <errno.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

/* How long the key thread waits in poll before checking whether to stop. */
#define KEY_POLL_MS 100
/* After Esc, bytes arriving within this time make it an escape sequence
 * (an arrow key, say), not a lone Esc. */
#define ESC_SEQ_MS 30

static atomic_int *g_cancel;
/* Shared by the main thread, the key thread and signal handlers that may run
 * on any thread: lock-free atomics (safe in handlers, C11 7.14.1.1), not
 * volatile sig_atomic_t, which only orders a handler against its own thread. */
static atomic_int g_reason;
static atomic_int g_sigints;  /* stop signals so far (SIGINT, SIGTERM, SIGHUP) */
static atomic_int g_signo;    /* the first of them */
static atomic_int g_raw;       /* terminal is in our mode */
static atomic_int g_want_raw;  /* key watching is on */
static struct termios g_saved;            /* terminal settings to restore */
static atomic_int g_stop;
static pthread_t g_thread;
static bool g_thread_on, g_active, g_atexit;

/* Signals that end the process while the terminal may be in our mode: the
 * handler restores the terminal, then dies of the signal as before. The
 * synchronous ones (SEGV, BUS, FPE, ILL) re-fault on return with the default
 * action; the others are raised again. (SIGTERM and SIGHUP stop the render
 * like SIGINT: g_stop_sigs.) */
static const int g_fatal_sigs[] = { SIGQUIT, SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL };
#define N_FATAL ((int)(sizeof g_fatal_sigs / sizeof g_fatal_sigs[0]))
/* Signals that stop the render (the finished part and the journal are
 * written); a second one of them kills the process the usual way. */
static const int g_stop_sigs[] = { SIGINT, SIGTERM, SIGHUP };
#define N_STOP ((int)(sizeof g_stop_sigs / sizeof g_stop_sigs[0]))
static struct sigaction g_old_stop[N_STOP], g_old_fatal[N_FATAL], g_old_tstp, g_old_cont;
static bool g_stop_set[N_STOP];

/* Async-signal-safe: tcsetattr is. */
static void term_restore(void)
{
	if (g_raw) {
		tcsetattr(STDIN_FILENO, TCSANOW, &g_saved);
		g_raw = 0;
	}
}

/* Non-canonical, no echo; signals (Ctrl-C) still work. Only in the foreground. */
static void term_raw(void)
{
	if (g_raw || !g_want_raw || tcgetpgrp(STDIN_FILENO) != getpgrp())
		return;
	struct termios t = g_saved;
	t.c_lflag &= ~(tcflag_t)(ICANON | ECHO);
	t.c_cc[VMIN] = 1;
	t.c_cc[VTIME] = 0;
	if (tcsetattr(STDIN_FILENO, TCSANOW, &t) == 0)
		g_raw = 1;
}

static void at_exit_restore(void) { term_restore(); }

/* who to tell when *g_cancel is set (interrupt_on_cancel); called from a
 * signal handler or the key thread: must be async-signal-safe (ev_wake is
 * one write). g_wake_busy counts calls under way, so that replacing the
 * callback waits for them: the caller may free what arg points to next. */
static _Atomic(void (*)(void *)) g_wake;
static _Atomic(void *) g_wake_arg;
static atomic_int g_wake_busy;

static void cancelled(void)
{
	int e = errno;
	atomic_fetch_add(&g_wake_busy, 1);
	void (*fn)(void *) = atomic_load(&g_wake);
	if (fn)
		fn(atomic_load(&g_wake_arg));
	atomic_fetch_sub(&g_wake_busy, 1);
	errno = e;
}

void interrupt_on_cancel(void (*fn)(void *), void *arg)
{
	atomic_store(&g_wake, NULL);
	while (atomic_load(&g_wake_busy) > 0) { /* a call with the old callback is under way */
		struct timespec ts = { 0, 100000 };
		nanosleep(&ts, NULL);
	}
	atomic_store(&g_wake_arg, arg);
	atomic_store(&g_wake, fn);
}

static void on_stop_signal(int sig)
{
	if (atomic_fetch_add(&g_sigints, 1) > 0) { /* a second one: die the usual way */
		term_restore();
		signal(sig, SIG_DFL);
		raise(sig);
		return;
	}
	g_signo = sig;
	g_reason = INTERRUPT_SIGNAL;
	if (g_cancel)
		atomic_store(g_cancel, 1);
	cancelled();
}

static void on_fatal(int sig)
{
	term_restore();
	signal(sig, SIG_DFL);
	raise(sig);
}

static void on_tstp(int sig)
{
	int saved_errno = errno;
	term_restore();
	struct sigaction dfl, mine;
	memset(&dfl, 0, sizeof dfl);
	dfl.sa_handler = SIG_DFL;
	sigaction(sig, &dfl, &mine);
	sigset_t set;
	sigemptyset(&set);
	sigaddset(&set, sig);
	sigprocmask(SIG_UNBLOCK, &set, NULL);
	raise(sig); /* stops here until SIGCONT */
	sigaction(sig, &mine, NULL);
	term_raw();
	errno = saved_errno;
}

static void on_cont(int sig)
{
	(void)sig;
	int saved_errno = errno;
	term_raw();
	errno = saved_errno;
}

/* Waits up to ms for a byte on stdin. 1 = readable, 0 = not, -1 = error/EOF. */
static int wait_key(int ms)
{
	struct pollfd pfd = { STDIN_FILENO, POLLIN, 0 };
	int n = poll(&pfd, 1, ms);
	if (n < 0)
		return errno == EINTR ? 0 : -1;
	if (n == 0)
		return 0;
	return (pfd.revents & POLLIN) ? 1 : -1;
}

static void *key_thread(void *arg)
{
	(void)arg;
	/* With SIGTTIN blocked in this thread, a read from the terminal while we
	 * are in the background fails with EIO instead of stopping the process
	 * (the foreground check below leaves a window between poll and read). */
	sigset_t ttin;
	sigemptyset(&ttin);
	sigaddset(&ttin, SIGTTIN);
	pthread_sigmask(SIG_BLOCK, &ttin, NULL);
	while (!atomic_load(&g_stop)) {
		if (tcgetpgrp(STDIN_FILENO) != getpgrp()) {
			/* in the background (the shell's `bg`): the keys are the
			 * shell's, and reading would stop us with SIGTTIN */
			poll(NULL, 0, KEY_POLL_MS);
			continue;
		}
		int w = wait_key(KEY_POLL_MS);
		if (w < 0)
			break;
		if (w == 0)
			continue;
		unsigned char ch;
		ssize_t n = read(STDIN_FILENO, &ch, 1);
		if (n <= 0) {
			if (n < 0 && (errno == EINTR || errno == EAGAIN))
				continue;
			if (n < 0 && errno == EIO) { /* moved to the background meanwhile */
				poll(NULL, 0, KEY_POLL_MS);
				continue;
			}
			break; /* EOF: no more keys */
		}
		int stop = ch == 'q' || ch == 'Q';
		if (ch == 0x1b) {
			if (wait_key(ESC_SEQ_MS) == 1) { /* an escape sequence: swallow what came */
				unsigned char junk[64];
				(void)read(STDIN_FILENO, junk, sizeof junk);
			} else {
				stop = 1;
			}
		}
		if (stop) {
			int none = INTERRUPT_NONE;
			atomic_compare_exchange_strong(&g_reason, &none, INTERRUPT_KEY);
			atomic_store(g_cancel, 1);
			cancelled();
			break;
		}
	}
	return NULL;
}

int interrupt_start(atomic_int *cancel, bool keys)
{
	if (g_active)
		return -1;
	g_active = true;
	g_cancel = cancel;
	g_reason = INTERRUPT_NONE;
	g_sigints = 0;
	g_signo = 0;
	atomic_store(&g_stop, 0);

	struct sigaction sa;
	memset(&sa, 0, sizeof sa);
	sigemptyset(&sa.sa_mask);
	sa.sa_handler = on_stop_signal;
	for (int i = 0; i < N_STOP; i++) {
		/* SIGTERM and SIGHUP left ignored (nohup) stay ignored; SIGINT is
		 * always ours, as before (a shell starts `cmd &` with it ignored) */
		g_stop_set[i] = sigaction(g_stop_sigs[i], NULL, &g_old_stop[i]) == 0 &&
				(g_stop_sigs[i] == SIGINT || g_old_stop[i].sa_handler != SIG_IGN);
		if (g_stop_set[i])
			sigaction(g_stop_sigs[i], &sa, NULL);
	}

	g_want_raw = 0;
	g_thread_on = false;
	if (keys && isatty(STDIN_FILENO) && tcgetpgrp(STDIN_FILENO) == getpgrp() &&
	    tcgetattr(STDIN_FILENO, &g_saved) == 0) {
		if (!g_atexit && atexit(at_exit_restore) == 0)
			g_atexit = true;
		sa.sa_handler = on_fatal;
		for (int i = 0; i < N_FATAL; i++)
			sigaction(g_fatal_sigs[i], &sa, &g_old_fatal[i]);
		sa.sa_handler = on_tstp;
		sigaction(SIGTSTP, &sa, &g_old_tstp);
		sa.sa_handler = on_cont;
		sigaction(SIGCONT, &sa, &g_old_cont);
		g_want_raw = 1;
		term_raw();
		if (g_raw && pthread_create(&g_thread, NULL, key_thread, NULL) == 0)
			g_thread_on = true;
		if (!g_thread_on) { /* no keys after all: leave the terminal alone */
			term_restore();
			g_want_raw = 0;
		}
	}
	return 0;
}

void interrupt_stop(void)
{
	if (!g_active)
		return;
	if (g_thread_on) {
		atomic_store(&g_stop, 1);
		pthread_join(g_thread, NULL);
		g_thread_on = false;
	}
	if (g_want_raw) {
		g_want_raw = 0;
		term_restore();
		for (int i = 0; i < N_FATAL; i++)
			sigaction(g_fatal_sigs[i], &g_old_fatal[i], NULL);
		sigaction(SIGTSTP, &g_old_tstp, NULL);
		sigaction(SIGCONT, &g_old_cont, NULL);
	}
	for (int i = 0; i < N_STOP; i++)
		if (g_stop_set[i])
			sigaction(g_stop_sigs[i], &g_old_stop[i], NULL);
	g_active = false;
}

enum interrupt_reason interrupt_reason(void)
{
	return (enum interrupt_reason)g_reason;
}

int interrupt_signal(void)
{
	return g_reason == INTERRUPT_SIGNAL ? atomic_load(&g_signo) : 0;
}
