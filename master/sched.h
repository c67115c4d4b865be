/*
 * sched.h - the master's tile scheduler: which tile goes to whom, what is
 * done, duplicates at the tail, audits and distrust (no sockets: the farm's
 * event loop and the local threads call it; tests/unit/test_sched.c drives it
 * alone).
 *
 * Takers are numbered: workers 0..n_workers-1 and SCHED_LOCAL for the
 * master's own threads. A tile has at most two holders (the second one a
 * duplicate near the end). The image is written only here, under the lock.
 *
 * Audits: a worker's result that must be audited (sched_audit_due) is held
 * as a claim, not stored, until a local thread renders the tile itself; the
 * local pixels are the ones stored, and a mismatch distrusts the worker:
 * every tile it delivered goes back to the queue and it may deliver nothing
 * more (sched_caught tells the event loop to drop it).
 */
#ifndef PORTRAY_SCHED_H
#define PORTRAY_SCHED_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "common/tiles.h"

#define SCHED_LOCAL 0xffffu
#define SCHED_NONE 0xfffeu
#define SCHED_NO_TILE UINT32_MAX
/* takers other than the local threads: fits the holder field */
#define SCHED_MAX_WORKERS 4096u
/* tiles each worker delivers that are all audited before sampling takes over:
 * a broken build or bad RAM shows early, and a worker that lies from its
 * second tile on is caught for sure */
#define SCHED_AUDIT_PROBATION 4

struct sched;

/* Counters for the summary (a consistent copy, sched_stats). */
struct sched_stats {
	uint32_t n, done;              /* tiles in all and stored */
	uint32_t local_done;           /* stored from ordinary local tiles */
	uint32_t redispatched;         /* taken again after being lost */
	uint32_t duplicates, dup_wasted;
	uint32_t audits, audit_failed;
};

/* What the scheduler knows of a worker's honesty. */
struct sched_trust {
	bool caught;                   /* an audit failed: nothing more from it is used */
	uint32_t tile;                 /* the tile whose audit failed */
	uint32_t requeued;             /* its tiles sent back to the queue */
};

/*
 * A scheduler over the tiles of tg, writing pixels of bpp bytes (3 for
 * RGB8, 12 for RGBF32: render.h) into image (tg->w * tg->h * bpp bytes);
 * every tile's pixels, a worker's, a local thread's or a preloaded one's,
 * are rect w * h * bpp bytes, and audits compare them byte for byte. audit: the fraction of results audited after each
 * worker's probation (0: no audits); salt: random per render, so a worker
 * cannot tell which tiles are sampled. wake (may be NULL) is called, under
 * the lock, whenever the event loop has something to look at (the render
 * ended, a worker was caught). NULL when out of memory.
 */
struct sched *sched_new(const struct tiling *tg, uint32_t bpp, uint32_t n_workers, uint8_t *image, double audit,
			uint64_t salt, void (*wake)(void *), void *wake_arg);
void sched_free(struct sched *s);

/* ---- the event loop's side (workers) ---- */

/*
 * Pops a pending tile for worker who, or (dup_ok: the worker is idle near the
 * end) a duplicate of the oldest outstanding tile held by one other taker.
 * now is the time of handing out (a local thread's take counts as made at
 * the latest now given here). The tile id, or SCHED_NO_TILE.
 */
uint32_t sched_take(struct sched *s, uint16_t who, bool dup_ok, double now);
/* who gives up its hold on tile id (lost connection, refused result):
 * back to the front of the queue when nobody else holds it. */
void sched_release(struct sched *s, uint32_t id, uint16_t who);
/* Whether worker who's result for tile id must be audited, given how many
 * results it has delivered so far: its probation, then a salted sample. */
bool sched_audit_due(const struct sched *s, uint16_t who, uint32_t delivered, uint32_t id);

enum sched_outcome {
	SCHED_USED,      /* stored (or held as a claim awaiting its audit) */
	SCHED_WASTED,    /* someone was first, or the worker is distrusted */
};
/*
 * Worker who delivers tile id (already checked for size and checksum):
 * stored, or held as a claim when audit is true. *cancel_other gets the
 * other holder of the tile when it is a worker that may stop working on it
 * (SCHED_NONE otherwise); that holder's hold is removed.
 */
enum sched_outcome sched_result(struct sched *s, uint32_t id, uint16_t who, const uint8_t *rgb, bool audit,
				uint16_t *cancel_other);
/* Whether worker who was caught lying; the first call after it was caught
 * returns true in *first (so the loop reports it once). */
bool sched_caught(struct sched *s, uint16_t who, struct sched_trust *out, bool *first);

/* ---- the local threads' side ---- */

/*
 * Blocks until a local thread has work: an audit first (they hold tiles back
 * and unmask liars early), then (unless audit_only) an ordinary tile or a
 * duplicate. Returns 1 with *id and *audit, or 0 when the render stopped.
 */
int sched_local_take(struct sched *s, bool audit_only, uint32_t *id, bool *audit);
/* A local thread finished (ok) or abandoned (!ok) tile id. */
void sched_local_done(struct sched *s, uint32_t id, bool audit, const uint8_t *rgb, bool ok);

/* ---- the render as a whole ---- */

/* Rectangle of tile id. */
struct tile_rect sched_rect(const struct sched *s, uint32_t id);
/* Ends the render (finished or cancelled): local threads give up, takes stop. */
void sched_stop(struct sched *s);
/* The flag local tiles watch to abandon their work (set by sched_stop). */
atomic_int *sched_stop_flag(struct sched *s);
bool sched_finished(struct sched *s);
/* Bytes a pixel of the image and of every tile's pixels. */
uint32_t sched_bpp(const struct sched *s);
void sched_stats(struct sched *s, struct sched_stats *out);

/* ---- observers (the live view, the journal): what changed, and its pixels ---- */

/* From now on, keep a list of the tiles stored, or undone (their worker was
 * caught lying), and wake the loop when it turns non-empty, unless a change
 * woke it less than SCHED_CHANGE_WAKE_S ago: an observer's loop drains the
 * list at least that often by itself (a timer). 0, or -1 when out of memory. */
#define SCHED_CHANGE_WAKE_S 0.05
int sched_observe(struct sched *s);
/* Moves up to max tile ids from that list into ids (each once however often
 * it changed; look at its pixels to see what it is now). Returns how many. */
uint32_t sched_changes(struct sched *s, uint32_t *ids, uint32_t max);
/* Copies tile id's stored pixels (rect w*h*bpp bytes, rows top to bottom)
 * into out and returns true, or returns false when the tile is not done. */
bool sched_tile_pixels(struct sched *s, uint32_t id, uint8_t *out);
/* Before anything is taken: tile id is done already with pixels rgb (a
 * resumed render). 0, or -1 when it was not pending. Preloading the last
 * tile finishes the render. */
int sched_preload(struct sched *s, uint32_t id, const uint8_t *rgb);

#endif
