/*
 * cancel.h - the calling thread's cancel flag: how work deep inside the core
 * (one ray through nested instances, one pixel's filter samples, one
 * shading point's light samples, the acceleration build) learns that its
 * result is no longer wanted, without a parameter through every call on
 * the way (accel_intersect and the shading recursion have none).
 *
 * The entry points that take a caller's flag (renderer_tile_cancellable,
 * renderer_new_cancellable) open a scope on their thread with cancel_enter;
 * code below them polls it with cancel_poll where work can grow without
 * bound: when the traversal enters an instance, every CANCEL_STRIDE
 * iterations of long loops, once per filter sample and light sample. A
 * poll costs a thread-local load and a relaxed atomic load, and the polls
 * are placed where they are rare next to the work around them
 * (docs/performance.md gives the measured cost: none visible).
 *
 * Once a poll has seen the flag non-zero, every later poll in the scope
 * says true, even if the flag's owner clears it again, and cancel_seen
 * says so too. Code that sees a poll say true gives up at once and returns
 * something cheap and wrong (a ray: no hit; a pixel: black), so whoever
 * opened the scope must discard everything computed in it when
 * cancel_seen() is true, and may trust it when it is false: until a poll
 * says true, nothing behaves differently from a run without a flag.
 */
#ifndef PORTRAY_CANCEL_H
#define PORTRAY_CANCEL_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

/* What a fallible call of the core returns when it gave up because its
 * thread's flag was set (accel_build, bvh_build_ex; RENDERER_CANCELLED). */
#define CANCEL_RETURN (-2)

/* Iterations between polls in loops whose iterations cost nanoseconds
 * (build loops over primitives, lists of unbounded objects): 65536 of them
 * take well under a millisecond, and the poll's cost disappears. */
#define CANCEL_STRIDE 65536u

/* One thread's scope: the flag polled, never NULL (cancel_never stands for
 * "no flag", and cancel_always replaces the flag once a poll has seen it
 * set, which keeps later polls true and tells cancel_seen). */
struct cancel_scope {
	atomic_int *flag;
};

/* The calling thread's scope (cancel.c); use the functions below. */
extern _Thread_local struct cancel_scope cancel_cur;
/* Flags that are always 0 and always 1 (cancel.c). */
extern atomic_int cancel_never, cancel_always;

/* The slow half of cancel_poll: the flag was seen set (cancel.c). */
bool cancel_note(void);

/*
 * Opens a scope on the calling thread polling flag (may be NULL: polls
 * then say false), with nothing seen yet; the scope it replaces is saved
 * in *saved for cancel_leave, so scopes nest.
 */
void cancel_enter(atomic_int *flag, struct cancel_scope *saved);
/* Closes the scope cancel_enter opened, restoring *saved. */
void cancel_leave(const struct cancel_scope *saved);

/* True when the work in hand should give up: the scope's flag is set, or
 * was seen set by an earlier poll of the scope. */
static inline bool cancel_poll(void)
{
	/* one load of the scope and one of the flag: polls sit in hot loops */
	if (!atomic_load_explicit(cancel_cur.flag, memory_order_relaxed))
		return false;
	return cancel_note();
}

/* cancel_poll at every CANCEL_STRIDE-th value of a loop counter k from 0
 * (CANCEL_STRIDE - 1, 2 CANCEL_STRIDE - 1, ...), false at the others: for
 * loops of cheap iterations. Shorter loops never poll: they cost too
 * little to matter, and normal scenes pay nothing. */
static inline bool cancel_poll_every(uint64_t k)
{
	return (k & (CANCEL_STRIDE - 1)) == CANCEL_STRIDE - 1 && cancel_poll();
}

/* Whether some poll of the current scope has said true: the work done in
 * the scope is then incomplete and must not be used. */
static inline bool cancel_seen(void) { return cancel_cur.flag == &cancel_always; }

#endif
