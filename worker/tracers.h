/*
 * tracers.h - portray-worker's tracing side: the jobs (one per connection
 * that has a scene: its queue of tiles), the queue of scenes to build, and
 * the tracer threads, which are the shared tile pool (common/tiles.h) fed by
 * this module as its tile source.
 *
 * A tracer takes builds first (each unblocks a whole job), then tiles of
 * the jobs round-robin, one tile of each job in turn, so several masters
 * share the cores fairly. A job whose results pile up (traced and not yet
 * queued on its socket, plus its socket's output queue, above
 * PROTO_OUT_HIGH_WATER) gets no tracer until its master reads again
 * (back-pressure, decided here so that a busy event loop cannot let
 * results pile up). Finished work goes back to the event loop on done
 * lists, with an ev_wake.
 *
 * Threads: everything here but the pool runs on the event loop, under the
 * tracers' lock where it touches what the pool reads.
 */
#ifndef PORTRAY_WORKER_TRACERS_H
#define PORTRAY_WORKER_TRACERS_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "common/tiles.h"
#include "proto/evloop.h"
#include "proto/proto.h"
#include "worker/cache.h"
#include "worker/fault.h"

struct wk_job;

/* A traced tile on its way to the socket, or (pixels NULL) the news that a
 * tile of the job could not be traced (out of memory): the job must end. */
struct wk_result {
	struct wk_job *job;      /* holds a reference until wk_result_release */
	struct proto_tile tile;
	uint8_t *pixels;         /* proto_tile_bytes(&tile) bytes, owned; NULL for a failure */
	uint32_t crc;
	uint32_t trace_us;       /* time spent tracing it (the master sizes its window from it) */
	struct wk_result *next;
};

/* The tracing side of one connection. */
struct wk_job {
	/* fixed at creation */
	struct wk_entry *entry;  /* the scene, with a reference of the job's own */
	/* set when the job's connection goes (or at shutdown): its queued tiles
	 * are dropped and the tile being traced is abandoned */
	atomic_int cancel;
	/* event loop only: the connection, NULL once it is gone */
	void *owner;
	/* under the tracers' lock */
	struct proto_tile *q;    /* queued tiles, FIFO in q[head..len) */
	size_t head, len, cap;
	int refs;                /* the owner + tiles taken + results not yet released */
	uint32_t running;        /* tiles being traced */
	size_t traced_bytes;     /* result bytes taken by tracers and not yet queued on the socket */
	size_t done_bytes;       /* of those, traced and waiting for the loop (back-pressure counts
				  * these and the socket's queue, not tiles being traced: at most
				  * one per tracer, so large tiles still use every thread) */
	size_t outq_bytes;       /* the socket's output queue at the loop's last look */
	bool ready;              /* its scene is built: tracers may take its tiles */
	bool paused;             /* skipped for back-pressure: wake the tracers when it has room */
	bool failed;             /* a tile could not be traced: no more are */
	struct wk_result fail_note; /* the failure's result (one per job: no allocation) */
	struct wk_job *ended_next;
};

struct wk_tracers {
	pthread_mutex_t mu;
	pthread_cond_t cv;
	struct wk_job **jobs;    /* every live job, round-robin from cursor */
	size_t n_jobs, cap_jobs, cursor;
	struct wk_entry **builds; /* entries to build, FIFO */
	size_t n_builds, cap_builds;
	struct wk_result *results, *results_tail; /* done list: results, in order */
	struct wk_entry *built;  /* done list: builds (via built_next) */
	struct wk_job *ended;    /* jobs whose last reference a tracer dropped */
	bool quit;
	struct tile_source src;
	struct tile_pool *pool;
	struct ev_loop *loop;    /* woken when something is done */
	struct wk_cache *cache;
	struct wk_faults *faults;
};

/*
 * Starts `threads` tracers. Returns the number started, 0 when none could
 * be (t is then unusable but may be freed).
 */
int wk_tracers_start(struct wk_tracers *t, int threads, struct ev_loop *loop, struct wk_cache *cache,
		     struct wk_faults *faults);
/*
 * Ends the tracers: every job is cancelled, running builds and tiles give
 * up (cancel the cache's builds first), and the threads are joined. Within
 * WK_SLEEP_STEP_MS plus the tracing core's cancellation delay, but for a
 * renderer build, which cannot be interrupted yet.
 */
void wk_tracers_stop(struct wk_tracers *t);
/* Frees what is left (after stop, and after every owner released its job). */
void wk_tracers_free(struct wk_tracers *t);

/* Queues a build of e (BUILDING). 0, or -1 when out of memory. */
int wk_tracers_build(struct wk_tracers *t, struct wk_entry *e);

/*
 * Takes the done lists: *results (in order; release each with
 * wk_result_release) and *built (entries whose build ended, via built_next;
 * report each with wk_cache_built). A build that was cancelled while nobody
 * wanted its entry, wanted again since, is queued anew instead of reported.
 * Jobs that ended on a tracer are freed here.
 */
void wk_tracers_collect(struct wk_tracers *t, struct wk_result **results, struct wk_entry **built);
/*
 * Done with a result: its bytes are on the socket (or dropped). outq is the
 * socket's output queue now (back-pressure), SIZE_MAX when it is gone.
 */
void wk_result_release(struct wk_tracers *t, struct wk_result *r, size_t outq);

/*
 * A job for the connection owner on entry e, whose reference it takes (on
 * failure the caller keeps it). Tiles may be queued at once; tracers take
 * them after wk_job_start. NULL when out of memory.
 */
struct wk_job *wk_job_new(struct wk_tracers *t, struct wk_entry *e, void *owner);
/* Its scene is built (and SCENE_READY queued): tracers may take its tiles. */
void wk_job_start(struct wk_tracers *t, struct wk_job *j);
/* Queues a tile: 0, 1 when LIM_TILES_QUEUED are queued already, -1 out of memory. */
int wk_job_add_tile(struct wk_tracers *t, struct wk_job *j, const struct proto_tile *tile);
/* Takes the oldest queued tile back (the black fault answers it itself): 1, or 0 when none. */
int wk_job_pop_tile(struct wk_tracers *t, struct wk_job *j, struct proto_tile *tile);
/* Drops queued tile id (PROTO_CANCEL_ALL: all); one being traced is still answered. */
void wk_job_cancel_tiles(struct wk_tracers *t, struct wk_job *j, uint32_t id);
/* Tiles queued or being traced (for heartbeats). */
uint32_t wk_job_pending(struct wk_tracers *t, struct wk_job *j);
/* The socket's output queue is now q bytes (back-pressure: may wake tracers). */
void wk_job_set_outq(struct wk_tracers *t, struct wk_job *j, size_t q);
/* The owner is gone: the job is cancelled and ends once its tiles are back. */
void wk_job_release(struct wk_tracers *t, struct wk_job *j);

#endif
