/*
 * interrupt.h - ending a render early (the manual's `nonstop`, issue 4):
 * SIGINT, SIGTERM and SIGHUP always end it; on a terminal, without
 * `nonstop`, so do q and Esc. Either way the caller writes the finished
 * part of the image and the journal.
 */
#ifndef PORTRAY_INTERRUPT_H
#define PORTRAY_INTERRUPT_H

#include <stdatomic.h>
#include <stdbool.h>

enum interrupt_reason {
	INTERRUPT_NONE = 0,
	INTERRUPT_SIGNAL, /* SIGINT (Ctrl-C), SIGTERM or SIGHUP: interrupt_signal */
	INTERRUPT_KEY     /* q, Q or Esc on the terminal */
};

/*
 * Starts watching until interrupt_stop: SIGINT, SIGTERM or SIGHUP sets
 * *cancel (a second of them kills the process the usual way; SIGTERM or
 * SIGHUP found ignored, as under nohup, stays ignored). When keys is true and stdin is a
 * terminal whose foreground we are, the terminal is put in non-canonical,
 * no-echo mode and a thread sets *cancel on q, Q or a lone Esc; the terminal
 * is restored by interrupt_stop, at exit, and before the process dies of
 * SIGQUIT, a crash (SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL) or a second
 * stop signal, or stops on SIGTSTP (raw mode
 * comes back on SIGCONT). One watch at a time. Returns 0, or -1 if already
 * watching.
 */
int interrupt_start(atomic_int *cancel, bool keys);
/*
 * fn(arg) is called right after *cancel is set (from the signal handler or
 * the key thread), so an event loop can wake up at once: it must be
 * async-signal-safe. NULL: nobody.
 */
void interrupt_on_cancel(void (*fn)(void *), void *arg);
/* Stops watching; restores the terminal and the previous signal handlers. */
void interrupt_stop(void);
/* Why *cancel was set, if by us. */
enum interrupt_reason interrupt_reason(void);
/* The signal that set it (SIGINT, SIGTERM, SIGHUP), or 0. */
int interrupt_signal(void);

#endif
