/*
 * evloop.h - the one event loop of both daemons: poll() over registered file
 * descriptors plus a heap of timers whose nearest deadline is poll's timeout
 * (the design of Redis's ae, with a heap instead of a list). Nothing wakes
 * up to look at the clock: the loop sleeps until a descriptor is ready, a
 * timer is due, or another thread calls ev_wake.
 *
 * Single-threaded: every function but ev_wake belongs to the thread running
 * the loop. Timers are caller-owned structures (embed them in the object
 * they time), so arming and stopping never allocate.
 */
#ifndef PORTRAY_EVLOOP_H
#define PORTRAY_EVLOOP_H

#include <stdbool.h>
#include <stddef.h>

struct ev_loop;

/* Called when fd is ready; revents as poll() reports them (POLLHUP and
 * POLLERR included even when not asked for). */
typedef void (*ev_io_fn)(struct ev_loop *l, int fd, short revents, void *arg);
typedef void (*ev_fn)(struct ev_loop *l, void *arg);

/* A timer: set fn and arg once, then arm and stop it as often as needed. */
struct ev_timer {
	double at;      /* net_now() seconds when it fires */
	ev_fn fn;
	void *arg;
	size_t slot;    /* position in the heap + 1; EV_SLOT_OVERFLOW; 0 when not armed */
	struct ev_timer *ov_next; /* on the overflow list (the heap could not grow) */
};
#define EV_SLOT_OVERFLOW ((size_t)-1)

/* A new loop with its self-pipe; NULL when out of descriptors or memory. */
struct ev_loop *ev_new(void);
/* Frees the loop (registered descriptors are not closed: they are the caller's). */
void ev_free(struct ev_loop *l);

/*
 * Watches fd for events (POLLIN, POLLOUT; 0 = registered but not polled),
 * adding it or changing its events and callback. 0, or -1 out of memory.
 */
int ev_io_set(struct ev_loop *l, int fd, short events, ev_io_fn fn, void *arg);
/* Changes only the events of a registered fd (no-op when not registered). */
void ev_io_events(struct ev_loop *l, int fd, short events);
/* Stops watching fd (safe from inside any callback, even fd's own). */
void ev_io_del(struct ev_loop *l, int fd);

/* Initialises a timer (not armed). */
void ev_timer_init(struct ev_timer *t, ev_fn fn, void *arg);
/* Arms t to fire once at absolute time at (net_now() clock); re-arming moves it. */
void ev_timer_arm(struct ev_loop *l, struct ev_timer *t, double at);
/* Disarms t (no-op when not armed). Safe from inside any callback. */
void ev_timer_stop(struct ev_loop *l, struct ev_timer *t);
static inline bool ev_timer_armed(const struct ev_timer *t) { return t->slot != 0; }
/* Number of armed timers (for tests). */
size_t ev_timers(const struct ev_loop *l);

/*
 * Wakes the loop from another thread or a signal handler (async-signal-safe:
 * one write to a non-blocking pipe); the loop then calls the wake callback.
 */
void ev_wake(struct ev_loop *l);
void ev_on_wake(struct ev_loop *l, ev_fn fn, void *arg);

/* Runs one round: waits at most max_wait seconds (< 0: until something
 * happens), then dispatches ready descriptors and due timers. 0, or -1 when
 * poll failed (errno). */
int ev_run_once(struct ev_loop *l, double max_wait);
/* Runs rounds until ev_stop; 0, or -1 when poll failed. */
int ev_run(struct ev_loop *l);
/* Makes ev_run return after the current round. */
void ev_stop(struct ev_loop *l);

#endif
