/*
 * farm_int.h - the farm's rooms and what they share (master/farm.c:
 * orchestration, local threads, progress and summary; master/wconn.c: the
 * connection to one worker; master/sched.c: the tiles).
 */
#ifndef PORTRAY_FARM_INT_H
#define PORTRAY_FARM_INT_H

#include <stdbool.h>
#include <stdint.h>

#include "master/farm.h"
#include "master/progress.h"
#include "master/sched.h"
#include "master/workers.h"
#include "proto/evloop.h"
#include "proto/net.h"
#include "proto/proto.h"

/* reconnection attempts after a lost connection, with back-off 0.5 s, 1 s, 2 s ... */
#define FARM_MAX_RETRIES 3
#define FARM_BACKOFF_S 0.5
/* tiles in flight per worker at most: the worker's own queue bound */
#define FARM_DEPTH_MAX LIM_TILES_QUEUED
/* result bytes a worker's window may stand for at most (memory, both sides) */
#define FARM_WINDOW_BYTES (64u * 1024 * 1024)
/* seconds a tile's pixel takes one thread, assumed until a worker's first
 * result says (size_window): 0.5 ms for a tile of 32 x 32 */
#define FARM_SVC_GUESS_PX 0.5e-6
/* ... and never less than this a tile: with small tiles a near worker's
 * first window must not be the whole image before a tile is audited */
#define FARM_SVC_GUESS_MIN 0.5e-3
/* tile latencies kept per worker for its median (the hung-tile deadline) */
#define FARM_LAT_KEEP 31
/* hung-tile deadline: this many median tile latencies ... */
#define FARM_HANG_MEDIANS 10.0
/* ... but never less than this many heartbeat timeouts */
#define FARM_HANG_HB 3.0
/* before a worker's first result (no median yet): this many heartbeat timeouts */
#define FARM_HANG_HB_FIRST 10.0
/* workers that dialled in (--accept) connected at once, at most */
#define FARM_ACCEPT_MAX 256
/* a worker's scene build may take this many heartbeat timeouts ... */
#define FARM_BUILD_HB 10.0
/* ... plus this many times the master's own build of the same scene */
#define FARM_BUILD_LOCAL 20.0
/* the progress timer's period: the bar redraws, lines fall due, rates update */
#define FARM_PROGRESS_TICK_S 0.2
/* --min-workers: how often the workers that joined are counted */
#define FARM_JOIN_TICK_S 0.1
/* local tile buffers refused in a row before the local threads give up */
#define FARM_LOCAL_OOM_MAX 16

enum wstate {
	W_IDLE,       /* not connected (waiting for a retry, or dropped) */
	W_CONNECTING, /* TCP connect in progress */
	W_HELLO,      /* our HELLO (and, without a secret, our OFFER) sent: waiting for the worker's HELLO */
	W_AUTH,       /* our proof and OFFER sent: waiting for the worker's proof */
	W_OFFER,      /* waiting for HAVE or NEED */
	W_SENDING,    /* streaming scene chunks */
	W_BUILDING,   /* whole scene sent: waiting for SCENE_READY (first tiles already sent) */
	W_READY,      /* tracing tiles */
	W_DONE        /* BYE sent */
};

struct farm;

/* Something that watches the render from the loop: the live view, the journal. */
struct farm_observer {
	/* Tiles stored, or undone because their worker was caught lying, since
	 * the last call (sched_changes; read them with sched_tile_pixels). */
	void (*tiles)(void *arg, struct farm *f, const uint32_t *ids, uint32_t n);
	void *arg;
};
#define FARM_OBSERVERS_MAX 4

struct worker {
	struct farm *f;
	struct worker_addr addr;
	const char *name;
	uint16_t index;
	enum wstate state;
	struct proto_conn *pc;
	int fd;                 /* registered with the loop, or -1 */
	struct ev_timer tm;     /* the next of: state deadline, liveness, hung tile, heartbeat, retry */
	double state_at;        /* when the current state began */
	double deadline;        /* when the current state must be left (0: none) */
	double last_rx;         /* last whole frame where it counts as life (W_BUILDING, W_READY) */
	double last_hb;         /* our last heartbeat */
	double retry_at;
	int retries;
	bool dropped;           /* for good */
	bool accepted;          /* it dialled in (--accept): lost is gone, never redialled */
	double accepted_at;     /* when (the oldest unauthenticated one is evicted first) */
	bool spoke;             /* its HELLO passed the check */
	char why[300];          /* why it was last lost or dropped */
	uint8_t nonce[PROTO_NONCE_BYTES], peer_nonce[PROTO_NONCE_BYTES];
	uint32_t threads;
	uint32_t depth;         /* its window: tiles in flight at most */
	uint64_t sent_off;      /* scene bytes queued so far */
	/* tiles in flight on this connection, with when each was sent */
	uint32_t *inflight;
	double *sent_at;
	uint32_t n_inflight;
	uint32_t *cancelled;    /* cancelled ids that may still be answered */
	uint32_t n_cancelled;
	double busy_since;      /* when n_inflight last went from 0 to 1 */
	double last_result;     /* when its last valid result arrived */
	double lat[FARM_LAT_KEEP]; /* recent tile latencies (sent to result), a ring */
	uint32_t n_lat;
	double median;          /* their median, 0 before the first */
	/* the window: round trip and trace time per tile */
	double offer_at;        /* when our OFFER left (the reply measures a round trip) */
	double rtt;             /* seconds, 0 until measured */
	double svc;             /* mean trace time of one tile on one of its threads, 0 until known */
	uint32_t delivered;     /* tiles it delivered that were used or audited */
	/* statistics over all connections */
	uint32_t tiles_done;
	uint64_t bytes_out, bytes_in, scene_bytes;
	bool cache_hit;
	int connections;
	double rate_t0;
	uint32_t rate_n0;
	double rate;            /* tiles/s over the last second */
	bool joined;            /* was ready to trace once (--min-workers) */
};

struct farm {
	const struct master_opts *o;
	struct ev_loop *loop;
	struct sched *s;
	struct tiling tg;
	struct worker *w;
	uint32_t n_w, cap_w;    /* workers so far, and room (named + FARM_ACCEPT_MAX with --accept) */
	int lfd;                /* --accept's listening socket, or -1 */
	char accept_at[NET_HOST_LEN + NET_PORT_LEN + 4]; /* where it listens, the port as bound */
	bool said_waiting;      /* "waiting for workers to dial in" printed */
	uint32_t n_evicted;     /* dialled in, evicted unauthenticated to make room */
	uint32_t n_mute;        /* dialled in, gone before a valid HELLO (not logged one by one) */
	double log_since;       /* farm_log_limited's period, and its counts */
	uint32_t log_n, log_left_out;
	const uint8_t *scene;   /* encoded scene */
	size_t scene_len;
	uint8_t hash[PROTO_HASH_BYTES];
	uint32_t width, height;
	enum render_pixel px;   /* the pixels of every tile, local or on the wire */
	uint8_t *secret;
	size_t secret_len;
	double hb_timeout, hb_interval;
	double build_s;         /* the master's own build of the scene (the workers' build deadline) */
	atomic_int *cancel;
	bool tty;
	bool farmed;            /* workers named or --accept: else the local threads alone */
	atomic_int local_gave_up; /* the local threads found no memory for tiles */
	struct progress bar;    /* progress on stderr (master/progress.h) */
	struct progress_peer *peers; /* the farm part of its line, cap_w of them */
	double local_t0, local_rate; /* the local threads' rate over the last second */
	uint32_t local_n0;
	double t0;
	struct ev_timer progress;
	uint32_t invalid_results;
	struct farm_observer obs[FARM_OBSERVERS_MAX];
	uint32_t n_obs;
	struct ev_timer observe; /* drains the change list between its wakes (SCHED_CHANGE_WAKE_S) */
	int rc;                 /* the loop's verdict */
	/* the local threads, started at once or (--min-workers) once enough workers joined */
	const struct tile_source *src;
	int n_threads;
	struct tile_pool *pool;
	struct ev_timer join;   /* --min-workers: checks the workers that joined */
	double join_deadline;
	bool joined_enough;
	uint32_t n_joined;
};

/* farm.c */
void farm_log(const struct farm *f, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* farm_log for lines a flood of peers dialling in could repeat: at most
 * FARM_LOG_BURST per FARM_LOG_PERIOD_S, the rest counted. */
#define FARM_LOG_BURST 20
#define FARM_LOG_PERIOD_S 10.0
void farm_log_limited(struct farm *f, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Whether the render can go on: ends the loop (rc EXIT_NO_WORKERS) when
 * --no-local and no worker is left. */
void farm_check_alive(struct farm *f);
/* Adds an observer (before the loop runs). 0, or -1 when out of room or memory. */
int farm_observe(struct farm *f, const struct farm_observer *o);

/* wconn.c */
int worker_init(struct farm *f, struct worker *w, const struct worker_addr *a, uint16_t index);
void worker_free(struct worker *w);
/* Starts (or restarts) the connection. */
void worker_start(struct worker *w);
/* Takes over fd, a connection the worker dialled (--accept), and shakes hands. */
void worker_accepted(struct worker *w, int fd);
/* Tops up w's tiles in flight (when it takes tiles). */
void worker_dispatch(struct worker *w);
/* Drops w if an audit caught it, and says so. */
void worker_check_caught(struct worker *w);
/* BYE to a connected worker (the farm then flushes and frees). */
void worker_bye(struct worker *w);
/* Closes w's connection; its tiles in flight go back to the queue. */
void worker_close(struct worker *w);

#endif
