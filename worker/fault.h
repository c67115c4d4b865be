/*
 * fault.h - portray-worker's test hooks, in one place: a worker that lies,
 * hangs, fails or is slow on purpose (--test-fault, --test-delay-ms), so the
 * master's defences can be tested against a real process. None of them is
 * reachable without its hidden option.
 */
#ifndef PORTRAY_WORKER_FAULT_H
#define PORTRAY_WORKER_FAULT_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "proto/proto.h"

/* --test-fault lie: tiles 2, 2 + k, 2 + 2k, ... (counted from 1 over the
 * process) are wrong: never the first, which every master audits */
#define WK_LIE_EVERY 4
/* --test-fault hang-tile: the third tile hangs, after two results have given
 * the master a tile time */
#define WK_HANG_AT 3
/* --test-delay-ms at most (ten minutes: long enough for any test to act
 * while a tile is being traced) */
#define WK_DELAY_MAX_MS 600000
/* the test sleeps look at their job's cancel flag this often (ms), so a
 * cancelled tile ends within WK_SLEEP_STEP_MS like a traced one */
#define WK_SLEEP_STEP_MS 50

enum wk_fault {
	FAULT_NONE,
	FAULT_BAD_CHECKSUM, /* every result's checksum is wrong */
	FAULT_WRONG_SIZE,   /* every result is one pixel narrower than asked */
	FAULT_PROTO_VERSION, /* speaks PROTO_VERSION + 1 */
	FAULT_BUILD,        /* claims another core build */
	FAULT_BLACK,        /* answers every tile at once with black pixels */
	FAULT_TRACE_FAIL,   /* every tile fails as if out of memory */
	FAULT_LIE,          /* every WK_LIE_EVERY-th tile traced, from the second: one pixel's low bit
			     * flipped before the checksum (wrong pixels, valid checksum) */
	FAULT_HANG_TILE,    /* the WK_HANG_AT-th tile traced never finishes (until its job is cancelled) */
	FAULT_PROBE         /* claims another pixel probe fingerprint (a build that draws other pixels) */
};

struct wk_faults {
	enum wk_fault kind;
	int delay_ms;       /* --test-delay-ms: extra time per tile */
	atomic_uint traced; /* tiles traced so far, over the process (lie, hang-tile) */
};

/* Parses a --test-fault name: 0, or -1 when unknown. */
int wk_fault_parse(const char *name, enum wk_fault *out);
/* The protocol version this worker speaks (proto-version: one more). */
uint32_t wk_fault_version(const struct wk_faults *f);
/* The core build id this worker claims (build-id: another one). */
void wk_fault_build_id(const struct wk_faults *f, char *out, size_t n);
/* Whether tiles are answered at once with black pixels (black). */
static inline bool wk_fault_black(const struct wk_faults *f) { return f->kind == FAULT_BLACK; }

/*
 * On a tracer thread, after a tile of w*h pixels was traced into px with
 * result ok (tiles.h: 1 whole, 0 cancelled, -1 no memory), before its
 * checksum: fails it (trace-fail: -1), alters it (lie), hangs (hang-tile)
 * or sleeps (--test-delay-ms). Every sleep ends within WK_SLEEP_STEP_MS of
 * *cancel becoming non-zero (then 0 is returned: the tile is abandoned).
 * Returns ok as the tile now stands.
 */
int wk_fault_traced(struct wk_faults *f, uint8_t *px, int ok, atomic_int *cancel);
/* On the event loop, before a result is sent: bad-checksum, wrong-size. */
void wk_fault_result(const struct wk_faults *f, struct proto_tile *t, uint32_t *crc);

/* Sleeps ms milliseconds in steps of WK_SLEEP_STEP_MS, returning early (0)
 * when *cancel (may be NULL) becomes non-zero; 1 when it slept them all. */
int wk_sleep_cancellable(int ms, atomic_int *cancel);

#endif
