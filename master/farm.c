/*
 * farm.c - the master's side of the farm: connections to portray-worker
 * daemons, the tile scheduler, local threads joining in, assembly, progress
 * and the summary (farm.h; the protocol is docs/protocol.md).
 *
 * One event loop (the calling thread) drives every worker connection with
 * non-blocking sockets and poll(): each worker connects, shakes hands, gets
 * the scene and starts taking tiles on its own, with no barrier. Scheduling
 * is pull-based: a worker holds up to `depth` tiles in flight (sized from the
 * threads it announced), topped up as results arrive. Local threads take
 * tiles from the same queue. At the tail, when nothing is pending, idle
 * takers get duplicates of the oldest outstanding tiles; the first valid
 * result wins and the other holder is told to cancel.
 *
 * A worker that disconnects, goes silent past the heartbeat deadline, breaks
 * the protocol or returns an invalid tile loses its tiles back to the queue.
 * Connection failures are retried with back-off (a few times); protocol or
 * tile faults, version, build or secret mismatches drop the worker for good,
 * and so does a worker holding tiles that returns none for far longer than
 * its usual tile time (a hung tracer).
 *
 * Audits: a checksum catches corruption, not a worker that computes wrong
 * pixels. The master re-renders a sample of each worker's tiles itself (the
 * first FARM_AUDIT_PROBATION it delivers, then a fraction chosen by a salted
 * hash of tile and worker) on its local threads, which serve audits before
 * ordinary tiles. An audited tile is held back as a claim until the local
 * render of it is done, and the local pixels are the ones stored. A mismatch
 * distrusts the worker for the rest of the render: every tile it delivered
 * goes back to the queue, and it is dropped. So every pixel of the image
 * comes from the local renderer or from a worker never caught lying.
 */
#include "master/farm.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "proto/net.h"
#include "proto/proto.h"
#include "proto/serial.h"

/* workers named on one command line or in one workers file */
#define FARM_MAX_WORKERS 1024
/* reconnection attempts after a lost connection, with back-off 0.5 s, 1 s, 2 s ... */
#define FARM_MAX_RETRIES 3
#define FARM_BACKOFF_S 0.5
/* tiles in flight per worker: enough to hide a round trip, bounded by the worker's queue */
#define FARM_DEPTH_MAX 64
/* a line of a workers file */
#define FARM_LINE_MAX 512
/* tiles each worker delivers that are all audited before sampling takes over:
 * a broken build or bad RAM shows early, and a worker that lies from its
 * second tile on is caught for sure */
#define FARM_AUDIT_PROBATION 4
/* tile latencies kept per worker for its median (the hung-tile deadline) */
#define FARM_LAT_KEEP 31
/* hung-tile deadline: this many median tile latencies ... */
#define FARM_HANG_MEDIANS 10.0
/* ... but never less than this many heartbeat timeouts */
#define FARM_HANG_HB 3.0
/* before a worker's first result (no median yet): this many heartbeat timeouts */
#define FARM_HANG_HB_FIRST 10.0

/* ---- the scheduler: shared by the event loop and local threads ---- */

#define HOLDER_LOCAL 0xffffu
#define HOLDER_NONE 0xfffeu

struct ftile {
	struct tile_rect rect;
	uint8_t done;
	uint8_t queued;        /* in the pending queue */
	uint8_t audit_queued;  /* in the audit queue */
	uint16_t holder[2];    /* who traces it now (HOLDER_NONE = free slot) */
	uint16_t by;           /* who wrote the stored pixels (when done) */
	uint16_t claim_by;     /* who delivered claim */
	uint8_t *claim;        /* a worker's pixels awaiting their audit (owned), or NULL */
	double sent;           /* when first handed out (for "oldest outstanding") */
};

/* what the scheduler knows of a worker's honesty (locked) */
struct trust {
	uint8_t caught;        /* an audit failed: nothing more from it is used */
	uint8_t reported;      /* the event loop has dropped it and said so */
	uint32_t tile;         /* the tile whose audit failed */
	uint32_t requeued;     /* its tiles sent back to the queue */
};

struct sched {
	pthread_mutex_t mu;
	pthread_cond_t cv;
	struct ftile *t;
	uint32_t n, n_done;
	uint32_t *queue;       /* pending tile ids: ring buffer of n entries */
	uint32_t q_head, q_len;
	uint32_t redispatched, duplicates, dup_wasted;
	uint32_t *audits;      /* tile ids with a claim to re-render: ring buffer of n */
	uint32_t a_head, a_len;
	uint32_t n_audits, n_audit_failed;
	struct trust *trust;   /* per worker */
	uint32_t n_workers;
	uint8_t *image;
	uint32_t w, h;
	atomic_int stop;       /* finished or cancelled: local threads give up */
	int wake_fd;           /* event loop's self-pipe */
	uint32_t local_done;
};

static void sched_wake(struct sched *s)
{
	char b = 1;
	ssize_t r = write(s->wake_fd, &b, 1);
	(void)r;
}

static bool holds(const struct ftile *t, uint16_t who) { return t->holder[0] == who || t->holder[1] == who; }

static int holder_count(const struct ftile *t)
{
	return (t->holder[0] != HOLDER_NONE) + (t->holder[1] != HOLDER_NONE);
}

static void holder_add(struct ftile *t, uint16_t who)
{
	if (t->holder[0] == HOLDER_NONE)
		t->holder[0] = who;
	else
		t->holder[1] = who;
}

static void holder_del(struct ftile *t, uint16_t who)
{
	if (t->holder[0] == who)
		t->holder[0] = HOLDER_NONE;
	else if (t->holder[1] == who)
		t->holder[1] = HOLDER_NONE;
}

/* Pops a pending tile for `who`, or (dup_ok) duplicates the oldest outstanding
 * tile held by one other taker. Returns the tile id or UINT32_MAX. Locked. */
static uint32_t sched_take_locked(struct sched *s, uint16_t who, bool dup_ok, double now)
{
	while (s->q_len) {
		uint32_t id = s->queue[s->q_head];
		s->q_head = (s->q_head + 1) % s->n;
		s->q_len--;
		struct ftile *t = &s->t[id];
		t->queued = 0;
		if (t->done || holds(t, who))
			continue;
		if (t->sent > 0)
			s->redispatched++;
		else
			t->sent = now;
		holder_add(t, who);
		return id;
	}
	if (!dup_ok)
		return UINT32_MAX;
	uint32_t best = UINT32_MAX;
	for (uint32_t i = 0; i < s->n; i++) {
		struct ftile *t = &s->t[i];
		if (t->done || t->claim || holder_count(t) != 1 || holds(t, who))
			continue;
		if (best == UINT32_MAX || t->sent < s->t[best].sent)
			best = i;
	}
	if (best != UINT32_MAX) {
		holder_add(&s->t[best], who);
		s->duplicates++;
	}
	return best;
}

/* Puts tile id back at the front of the queue when it is not done, has no
 * holder, no claim awaiting audit and is not queued already. Locked. */
static void sched_requeue_locked(struct sched *s, uint32_t id)
{
	struct ftile *t = &s->t[id];
	if (!t->done && holder_count(t) == 0 && !t->claim && !t->queued) {
		/* lost tiles go to the front: they are the oldest work */
		s->q_head = (s->q_head + s->n - 1) % s->n;
		s->queue[s->q_head] = id;
		s->q_len++;
		t->queued = 1;
		pthread_cond_broadcast(&s->cv);
	}
}

/* Gives up `who`'s hold on tile id; back to the queue when nobody holds it. Locked. */
static void sched_release_locked(struct sched *s, uint32_t id, uint16_t who)
{
	holder_del(&s->t[id], who);
	sched_requeue_locked(s, id);
}

/* Copies rgb into the image as tile id, written by `who`; marks it done and
 * ends the render when it was the last. Locked. */
static void sched_store_locked(struct sched *s, uint32_t id, uint16_t who, const uint8_t *rgb)
{
	struct ftile *t = &s->t[id];
	const struct tile_rect *r = &t->rect;
	for (uint32_t y = 0; y < r->h; y++)
		memcpy(s->image + (((size_t)(r->y + y) * s->w) + r->x) * 3, rgb + (size_t)y * r->w * 3,
		       (size_t)r->w * 3);
	t->done = 1;
	t->by = who;
	s->n_done++;
	if (s->n_done == s->n) {
		atomic_store(&s->stop, 1);
		pthread_cond_broadcast(&s->cv);
		sched_wake(s);
	}
}

/*
 * Worker `who` failed the audit of tile `tile`: from now on nothing it sends
 * is used, and every tile it delivered in this render goes back to the queue
 * (stored ones are undone, claims still awaiting their audit are discarded).
 * The event loop drops its connection and reports it (trust[].reported).
 * Locked.
 */
static void sched_distrust_locked(struct sched *s, uint16_t who, uint32_t tile)
{
	if (who >= s->n_workers || s->trust[who].caught)
		return;
	struct trust *tr = &s->trust[who];
	tr->caught = 1;
	tr->tile = tile;
	tr->requeued = 1; /* the tile whose audit failed: the audit's pixels replace it */
	for (uint32_t i = 0; i < s->n; i++) {
		struct ftile *t = &s->t[i];
		if (t->done && t->by == who) {
			t->done = 0;
			t->by = HOLDER_NONE;
			s->n_done--;
			tr->requeued++;
			sched_requeue_locked(s, i);
		} else if (t->claim && t->claim_by == who) {
			free(t->claim);
			t->claim = NULL;
			tr->requeued++;
			sched_requeue_locked(s, i);
		}
	}
	pthread_cond_broadcast(&s->cv);
	sched_wake(s);
}

/*
 * Pixels for tile id from a trusted source (the local renderer): settles a
 * claim awaiting its audit (a mismatch distrusts the claimant), then stores
 * them unless the tile is done already. Returns true if they were used. Locked.
 */
static bool sched_trusted_locked(struct sched *s, uint32_t id, const uint8_t *rgb)
{
	struct ftile *t = &s->t[id];
	if (t->claim) {
		uint8_t *claim = t->claim;
		t->claim = NULL;
		s->n_audits++;
		if (memcmp(claim, rgb, (size_t)t->rect.w * t->rect.h * 3) != 0) {
			s->n_audit_failed++;
			sched_distrust_locked(s, t->claim_by, id);
		}
		free(claim);
	}
	if (t->done)
		return false;
	sched_store_locked(s, id, HOLDER_LOCAL, rgb);
	return true;
}

/* Stores a finished tile unless someone was first; returns true if it was used.
 * A local result (who == HOLDER_LOCAL) also settles a pending audit. Locked. */
static bool sched_finish_locked(struct sched *s, uint32_t id, uint16_t who, const uint8_t *rgb)
{
	struct ftile *t = &s->t[id];
	holder_del(t, who);
	if (who == HOLDER_LOCAL) {
		bool used = sched_trusted_locked(s, id, rgb);
		if (!used)
			s->dup_wasted++;
		return used;
	}
	if (t->done || t->claim) {
		s->dup_wasted++;
		return false;
	}
	sched_store_locked(s, id, who, rgb);
	return true;
}

/* Holds worker who's pixels for tile id as a claim (copied) and queues its
 * audit; false (nothing changed) if out of memory. Locked. */
static bool sched_claim_locked(struct sched *s, uint32_t id, uint16_t who, const uint8_t *rgb)
{
	struct ftile *t = &s->t[id];
	size_t n = (size_t)t->rect.w * t->rect.h * 3;
	uint8_t *copy = malloc(n);
	if (!copy)
		return false;
	memcpy(copy, rgb, n);
	holder_del(t, who);
	t->claim = copy;
	t->claim_by = who;
	if (!t->audit_queued) {
		s->audits[(s->a_head + s->a_len) % s->n] = id;
		s->a_len++;
		t->audit_queued = 1;
	}
	pthread_cond_broadcast(&s->cv);
	return true;
}

/* Pops a tile whose claim awaits its audit (skipping settled ones and those a
 * local thread traces anyway: its result settles the claim). Locked. */
static uint32_t sched_take_audit_locked(struct sched *s)
{
	while (s->a_len) {
		uint32_t id = s->audits[s->a_head];
		s->a_head = (s->a_head + 1) % s->n;
		s->a_len--;
		struct ftile *t = &s->t[id];
		t->audit_queued = 0;
		if (t->claim && !t->done && !holds(t, HOLDER_LOCAL))
			return id;
	}
	return UINT32_MAX;
}

/* ---- local threads ---- */

struct local {
	struct sched *s;
	const struct renderer *r;
	uint8_t *buf;          /* one tile (owned by farm_render) */
	bool audit_only;       /* --no-local: audits, never ordinary tiles */
};

/* A local thread: audits first (they hold tiles back and unmask liars early),
 * then ordinary tiles, until the render stops. */
static void *local_thread(void *arg)
{
	struct local *L = arg;
	struct sched *s = L->s;
	pthread_mutex_lock(&s->mu);
	while (!atomic_load(&s->stop)) {
		bool audit = true;
		uint32_t id = sched_take_audit_locked(s);
		if (id == UINT32_MAX && !L->audit_only) {
			audit = false;
			id = sched_take_locked(s, HOLDER_LOCAL, true, net_now());
		}
		if (id == UINT32_MAX) {
			pthread_cond_wait(&s->cv, &s->mu);
			continue;
		}
		struct tile_rect rect = s->t[id].rect;
		pthread_mutex_unlock(&s->mu);
		int ok = renderer_tile_cancellable(L->r, rect, L->buf, &s->stop);
		pthread_mutex_lock(&s->mu);
		if (audit) {
			if (ok)
				sched_trusted_locked(s, id, L->buf);
		} else if (ok) {
			if (sched_finish_locked(s, id, HOLDER_LOCAL, L->buf))
				s->local_done++;
		} else {
			holder_del(&s->t[id], HOLDER_LOCAL);
		}
	}
	pthread_mutex_unlock(&s->mu);
	return NULL;
}

/* ---- workers ---- */

enum wstate {
	W_IDLE,       /* not connected (waiting for a retry, or dropped) */
	W_CONNECTING,
	W_HELLO,      /* connected, our HELLO sent, waiting for the worker's */
	W_AUTH,       /* our proof sent, waiting for the worker's */
	W_OFFER,      /* scene offered, waiting for HAVE or NEED */
	W_SENDING,    /* streaming scene chunks */
	W_BUILDING,   /* waiting for SCENE_READY */
	W_READY,      /* taking tiles */
	W_DONE        /* BYE sent */
};

struct worker {
	char name[NET_HOST_LEN + NET_PORT_LEN + 4];
	char host[NET_HOST_LEN], port[NET_PORT_LEN];
	uint16_t index;
	enum wstate state;
	struct proto_conn *pc;
	double last_rx, last_hb, retry_at, connected_at;
	int retries;
	bool dropped;          /* for good */
	char why[300];         /* why it was last lost or dropped */
	uint8_t nonce[PROTO_NONCE_BYTES], peer_nonce[PROTO_NONCE_BYTES];
	uint32_t threads, depth;
	uint64_t sent_off;     /* scene bytes queued so far */
	uint32_t *inflight;    /* tile ids in flight on this connection */
	double sent_at[FARM_DEPTH_MAX]; /* when each was sent */
	uint32_t n_inflight;
	double busy_since;     /* when n_inflight last went from 0 to 1 */
	double last_result;    /* when its last valid result arrived */
	double lat[FARM_LAT_KEEP]; /* recent tile latencies (sent to result), a ring */
	uint32_t n_lat;
	double median;         /* their median, 0 before the first */
	uint32_t delivered;    /* tiles it delivered that were used or audited */
	uint32_t cancelled[FARM_DEPTH_MAX]; /* cancelled ids that may still be answered */
	uint32_t n_cancelled;
	/* statistics over all connections */
	uint32_t tiles_done;
	uint64_t bytes_out, bytes_in, scene_bytes;
	bool cache_hit;
	int connections;
	double rate_t0;
	uint32_t rate_n0;
	double rate;           /* tiles/s over the last second */
};

struct farm {
	const struct master_opts *o;
	struct sched s;
	struct worker *w;
	uint32_t n_w;
	uint8_t *scene;        /* encoded scene */
	size_t scene_len;
	uint8_t hash[PROTO_HASH_BYTES];
	uint8_t *secret;
	size_t secret_len;
	double hb_timeout, hb_interval;
	uint32_t tile;
	bool tty;
	double t0, last_progress;
	uint64_t bytes_total;
	uint32_t invalid_results;
	double audit;          /* fraction of tiles audited after the probation; 0: no audits */
	uint64_t audit_salt;   /* per render: a worker cannot tell which tiles are sampled */
};

static void flog(const struct farm *f, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void flog(const struct farm *f, const char *fmt, ...)
{
	if (f->o->quiet)
		return;
	va_list ap;
	va_start(ap, fmt);
	if (f->tty)
		fputs("\r\033[K", stderr);
	fputs("portray-master: ", stderr);
	vfprintf(stderr, fmt, ap);
	fputc('\n', stderr);
	va_end(ap);
}

/* Adds one "HOST:PORT" to the list; 0 or -1 with a message printed. */
static int add_worker(struct farm *f, const char *spec, const char *where)
{
	char err[300];
	if (f->n_w >= FARM_MAX_WORKERS) {
		fprintf(stderr, "portray-master: more than %d workers\n", FARM_MAX_WORKERS);
		return -1;
	}
	struct worker *w = &f->w[f->n_w];
	memset(w, 0, sizeof *w);
	if (net_parse_hostport(spec, w->host, w->port, err, sizeof err) < 0) {
		fprintf(stderr, "portray-master: %s: %s\n", where, err);
		return -1;
	}
	snprintf(w->name, sizeof w->name, "%s", spec);
	w->index = (uint16_t)f->n_w;
	w->state = W_IDLE;
	w->inflight = calloc(FARM_DEPTH_MAX, sizeof *w->inflight);
	if (!w->inflight) {
		fprintf(stderr, "portray-master: out of memory\n");
		return -1;
	}
	f->n_w++;
	return 0;
}

static int parse_workers(struct farm *f)
{
	f->w = calloc(FARM_MAX_WORKERS, sizeof *f->w);
	if (!f->w)
		return -1;
	if (f->o->workers) {
		char *list = strdup(f->o->workers), *save = NULL;
		if (!list)
			return -1;
		for (char *tok = strtok_r(list, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
			while (*tok == ' ')
				tok++;
			if (*tok && add_worker(f, tok, "-w") < 0) {
				free(list);
				return -1;
			}
		}
		free(list);
	}
	if (f->o->workers_file) {
		FILE *fp = fopen(f->o->workers_file, "r");
		if (!fp) {
			fprintf(stderr, "portray-master: %s: %s\n", f->o->workers_file, strerror(errno));
			return -1;
		}
		char line[FARM_LINE_MAX];
		int ln = 0;
		while (fgets(line, sizeof line, fp)) {
			ln++;
			char *hash = strchr(line, '#');
			if (hash)
				*hash = 0;
			char *p = line, *e;
			while (*p == ' ' || *p == '\t')
				p++;
			for (e = p + strlen(p); e > p && (e[-1] == '\n' || e[-1] == '\r' || e[-1] == ' ' || e[-1] == '\t');)
				*--e = 0;
			if (!*p)
				continue;
			char where[FARM_LINE_MAX + 64];
			snprintf(where, sizeof where, "%s:%d", f->o->workers_file, ln);
			if (add_worker(f, p, where) < 0) {
				fclose(fp);
				return -1;
			}
		}
		fclose(fp);
	}
	if (f->n_w == 0) {
		fprintf(stderr, "portray-master: no workers named (-w HOST:PORT or --workers-file)\n");
		return -1;
	}
	return 0;
}

static void worker_start(struct farm *f, struct worker *w)
{
	char err[300];
	int fd = net_connect_start(w->host, w->port, err, sizeof err);
	w->last_rx = net_now();
	w->connections++;
	if (fd < 0 || !(w->pc = proto_conn_new(fd))) {
		if (fd >= 0)
			close(fd);
		snprintf(w->why, sizeof w->why, "%s", fd < 0 ? err : "out of memory");
		w->state = W_IDLE;
		w->retry_at = net_now() + FARM_BACKOFF_S * pow(2, w->retries);
		if (++w->retries > FARM_MAX_RETRIES)
			w->dropped = true;
		flog(f, "worker %s: %s%s", w->name, w->why, w->dropped ? ": dropped" : ": will retry");
		return;
	}
	w->state = W_CONNECTING;
}

/* Closes w's connection (if any); its tiles in flight go back to the queue. */
static void worker_close(struct farm *f, struct worker *w)
{
	pthread_mutex_lock(&f->s.mu);
	for (uint32_t i = 0; i < w->n_inflight; i++)
		sched_release_locked(&f->s, w->inflight[i], w->index);
	pthread_mutex_unlock(&f->s.mu);
	w->n_inflight = 0;
	w->n_cancelled = 0;
	if (w->pc) {
		w->bytes_out += proto_conn_bytes_out(w->pc);
		w->bytes_in += proto_conn_bytes_in(w->pc);
		proto_conn_free(w->pc);
		w->pc = NULL;
	}
	w->state = W_IDLE;
}

/*
 * Ends the current connection to w: its tiles go back to the queue. fatal
 * drops the worker for good; otherwise it is retried with back-off.
 */
static void worker_lost(struct farm *f, struct worker *w, bool fatal, const char *fmt, ...)
	__attribute__((format(printf, 4, 5)));
static void worker_lost(struct farm *f, struct worker *w, bool fatal, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(w->why, sizeof w->why, fmt, ap);
	va_end(ap);
	worker_close(f, w);
	if (!fatal && w->retries < FARM_MAX_RETRIES && !atomic_load(&f->s.stop)) {
		w->retry_at = net_now() + FARM_BACKOFF_S * pow(2, w->retries);
		w->retries++;
		flog(f, "worker %s lost: %s (retry %d of %d in %.1f s)", w->name, w->why, w->retries,
		     FARM_MAX_RETRIES, w->retry_at - net_now());
	} else {
		w->dropped = true;
		flog(f, "worker %s dropped: %s", w->name, w->why);
	}
}

/* Refuses the peer: ERROR to it (best effort), then the worker is dropped. */
static void worker_refuse(struct farm *f, struct worker *w, int code, const char *fmt, ...)
	__attribute__((format(printf, 4, 5)));
static void worker_refuse(struct farm *f, struct worker *w, int code, const char *fmt, ...)
{
	char text[LIM_ERROR_TEXT + 1];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(text, sizeof text, fmt, ap);
	va_end(ap);
	if (w->pc) {
		proto_send_error(w->pc, code, "%s", text);
		proto_conn_flush(w->pc);
	}
	worker_lost(f, w, true, "%s (%s error)", text, proto_err_name(code));
}

static int send_hello(struct farm *f, struct worker *w)
{
	struct proto_hello h;
	memset(&h, 0, sizeof h);
	h.version = PROTO_VERSION;
	h.role = ROLE_MASTER;
	h.secret = f->secret != NULL;
	uint32_t ms = (uint32_t)(f->hb_interval * 1000);
	h.heartbeat_ms = ms ? ms : 1;
	memcpy(h.nonce, w->nonce, sizeof h.nonce);
	snprintf(h.build, sizeof h.build, "%s", proto_build_id());
	return proto_send_hello(w->pc, &h);
}

/* Tops up w's tiles in flight. */
static void dispatch(struct farm *f, struct worker *w)
{
	if (w->state != W_READY)
		return;
	double now = net_now();
	pthread_mutex_lock(&f->s.mu);
	/* a worker caught lying gets nothing more (the loop drops it next) */
	while (w->n_inflight < w->depth && !atomic_load(&f->s.stop) && !f->s.trust[w->index].caught) {
		/* duplicates only for an idle worker: the tail, not the middle */
		uint32_t id = sched_take_locked(&f->s, w->index, w->n_inflight == 0, now);
		if (id == UINT32_MAX)
			break;
		struct tile_rect r = f->s.t[id].rect;
		struct proto_tile t = { id, r.x, r.y, r.w, r.h };
		if (proto_send_tile(w->pc, &t) < 0) {
			sched_release_locked(&f->s, id, w->index);
			break;
		}
		if (w->n_inflight == 0)
			w->busy_since = now;
		w->sent_at[w->n_inflight] = now;
		w->inflight[w->n_inflight++] = id;
	}
	pthread_mutex_unlock(&f->s.mu);
}

/* Queues scene chunks while the connection's output is short. */
static void send_scene(struct farm *f, struct worker *w)
{
	while (w->sent_off < f->scene_len && proto_conn_outq(w->pc) < PROTO_OUT_HIGH_WATER) {
		size_t n = f->scene_len - w->sent_off;
		if (n > PROTO_CHUNK_BYTES)
			n = PROTO_CHUNK_BYTES;
		if (proto_send_data(w->pc, w->sent_off, f->scene + w->sent_off, (uint32_t)n) < 0)
			return;
		w->sent_off += n;
		w->scene_bytes += n;
	}
	if (w->sent_off == f->scene_len)
		w->state = W_BUILDING;
}

/*
 * Tells worker w that tile id is done elsewhere: it leaves w's tiles in flight
 * and joins the ids w may still answer (a tile already being traced is).
 */
static void cancel_on(struct worker *w, uint32_t id)
{
	for (uint32_t k = 0; k < w->n_inflight; k++) {
		if (w->inflight[k] != id)
			continue;
		w->n_inflight--;
		w->inflight[k] = w->inflight[w->n_inflight];
		w->sent_at[k] = w->sent_at[w->n_inflight];
		if (w->n_cancelled == FARM_DEPTH_MAX) /* forget the oldest */
			memmove(w->cancelled, w->cancelled + 1, --w->n_cancelled * sizeof *w->cancelled);
		w->cancelled[w->n_cancelled++] = id;
		proto_send_cancel(w->pc, id);
		return;
	}
}

/* Keeps a tile latency of w and its median (the hung-tile deadline). */
static void note_latency(struct worker *w, double dt)
{
	w->lat[w->n_lat % FARM_LAT_KEEP] = dt;
	w->n_lat++;
	uint32_t n = w->n_lat < FARM_LAT_KEEP ? w->n_lat : FARM_LAT_KEEP;
	double v[FARM_LAT_KEEP];
	memcpy(v, w->lat, n * sizeof *v);
	for (uint32_t i = 1; i < n; i++) /* insertion sort: a few dozen values */
		for (uint32_t j = i; j > 0 && v[j - 1] > v[j]; j--) {
			double x = v[j];
			v[j] = v[j - 1];
			v[j - 1] = x;
		}
	w->median = v[n / 2];
}

/* A 64-bit mix (splitmix64's finaliser): spreads the bits of x evenly. */
static uint64_t mix64(uint64_t x)
{
	x ^= x >> 30;
	x *= 0xbf58476d1ce4e5b9ULL;
	x ^= x >> 27;
	x *= 0x94d049bb133111ebULL;
	x ^= x >> 31;
	return x;
}

/*
 * Whether w's result for tile id is audited: every tile of its probation (the
 * first FARM_AUDIT_PROBATION it delivers), then the tiles a salted hash of
 * (tile, worker) puts below the audit fraction. The choice depends on neither
 * timing nor anything the worker can see (the salt is random per render).
 */
static bool audit_due(const struct farm *f, const struct worker *w, uint32_t id)
{
	if (f->audit <= 0)
		return false;
	if (w->delivered < FARM_AUDIT_PROBATION)
		return true;
	uint64_t h = mix64(f->audit_salt ^ mix64(((uint64_t)id << 16) ^ w->index));
	return (double)(h >> 11) * 0x1p-53 < f->audit;
}

/* A TILE_RESULT from w: check it against what was sent, then store it (or hold
 * it back for its audit). */
static void on_result(struct farm *f, struct worker *w, const struct proto_msg *m)
{
	const struct proto_tile *t = &m->u.result.tile;
	uint32_t k, c = UINT32_MAX;
	for (k = 0; k < w->n_inflight; k++)
		if (w->inflight[k] == t->id)
			break;
	if (k == w->n_inflight)
		for (c = 0; c < w->n_cancelled; c++)
			if (w->cancelled[c] == t->id)
				break;
	if (k == w->n_inflight && c >= w->n_cancelled) {
		f->invalid_results++;
		worker_refuse(f, w, PERR_PROTOCOL, "result for tile %u, which is not in flight on this connection", t->id);
		return;
	}
	const struct tile_rect *r = &f->s.t[t->id].rect;
	if (t->x != r->x || t->y != r->y || t->w != r->w || t->h != r->h) {
		f->invalid_results++;
		worker_refuse(f, w, PERR_PROTOCOL, "tile %u came back as %ux%u at (%u,%u), sent as %ux%u at (%u,%u)",
			      t->id, t->w, t->h, t->x, t->y, r->w, r->h, r->x, r->y);
		return;
	}
	if (crc32_update(0, m->u.result.pixels, (size_t)t->w * t->h * 3) != m->u.result.crc) {
		f->invalid_results++;
		worker_refuse(f, w, PERR_PROTOCOL, "tile %u failed its checksum", t->id);
		return;
	}
	/* a valid tile earns the worker its retries back (reaching READY does
	 * not: a worker failing every tile after READY was retried for ever) */
	w->retries = 0;
	double now = net_now();
	w->last_result = now;
	if (k == w->n_inflight) { /* answered after its CANCEL: someone else was first */
		w->cancelled[c] = w->cancelled[--w->n_cancelled];
		pthread_mutex_lock(&f->s.mu);
		f->s.dup_wasted++;
		pthread_mutex_unlock(&f->s.mu);
		return;
	}
	note_latency(w, now - w->sent_at[k]);
	w->n_inflight--;
	w->inflight[k] = w->inflight[w->n_inflight];
	w->sent_at[k] = w->sent_at[w->n_inflight];
	pthread_mutex_lock(&f->s.mu);
	struct ftile *ft = &f->s.t[t->id];
	uint16_t other = ft->holder[0] == w->index ? ft->holder[1] : ft->holder[0];
	bool used;
	if (f->s.trust[w->index].caught) { /* caught lying: nothing it sends is used */
		sched_release_locked(&f->s, t->id, w->index);
		used = false;
	} else if (!ft->done && !ft->claim && audit_due(f, w, t->id) &&
		   sched_claim_locked(&f->s, t->id, w->index, m->u.result.pixels)) {
		used = true; /* held back until the local render agrees */
	} else {
		/* not sampled, a duplicate, or no memory to hold a claim: stored
		 * as it is (undone if the worker is caught later) */
		used = sched_finish_locked(&f->s, t->id, w->index, m->u.result.pixels);
	}
	/* the other holder (if remote) may stop working on it */
	bool cancel_other = used && other < f->n_w && f->w[other].state == W_READY;
	if (cancel_other)
		holder_del(ft, other);
	pthread_mutex_unlock(&f->s.mu);
	if (used) {
		w->tiles_done++;
		w->delivered++;
		if (cancel_other)
			cancel_on(&f->w[other], t->id);
	}
}

/* One message from w, by state. */
static void on_message(struct farm *f, struct worker *w, const struct proto_msg *m)
{
	if (m->type == MSG_ERROR) {
		/* transient: the worker timed out, is shutting down, ran out of
		 * memory or is busy (connection or transfer limits): try again */
		bool fatal = m->u.error.code != PERR_TIMEOUT && m->u.error.code != PERR_SHUTDOWN &&
			     m->u.error.code != PERR_INTERNAL && m->u.error.code != PERR_LIMIT;
		worker_lost(f, w, fatal, "worker says: %s (%s error)", m->u.error.text, proto_err_name(m->u.error.code));
		return;
	}
	if (m->type == MSG_HEARTBEAT)
		return;
	switch (w->state) {
	case W_HELLO: {
		if (m->type != MSG_HELLO)
			break;
		const struct proto_hello *h = &m->u.hello;
		if (h->version != PROTO_VERSION || m->frame_version != PROTO_VERSION) {
			worker_refuse(f, w, PERR_VERSION,
				      "protocol version mismatch: worker speaks version %u, master speaks %u", h->version,
				      PROTO_VERSION);
			return;
		}
		if (h->role != ROLE_WORKER) {
			worker_refuse(f, w, PERR_PROTOCOL, "peer is not a worker");
			return;
		}
		if (strcmp(h->build, proto_build_id()) != 0) {
			worker_refuse(f, w, PERR_BUILD, "core build mismatch: worker runs '%s', master runs '%s'",
				      h->build, proto_build_id());
			return;
		}
		if (h->secret && !f->secret) {
			worker_refuse(f, w, PERR_AUTH, "the worker requires a shared secret: give --secret-file");
			return;
		}
		if (!h->secret && f->secret) {
			worker_refuse(f, w, PERR_AUTH, "the worker has no shared secret, this master has one");
			return;
		}
		memcpy(w->peer_nonce, h->nonce, PROTO_NONCE_BYTES);
		w->threads = h->threads ? h->threads : 1;
		w->depth = 2 * w->threads + 2;
		if (w->depth > FARM_DEPTH_MAX)
			w->depth = FARM_DEPTH_MAX;
		if (f->secret) {
			uint8_t mac[PROTO_MAC_BYTES];
			proto_auth_mac(f->secret, f->secret_len, ROLE_MASTER, w->nonce, w->peer_nonce, mac);
			proto_send_auth(w->pc, mac);
			w->state = W_AUTH;
		} else {
			proto_send_offer(w->pc, f->hash, f->scene_len, f->s.w, f->s.h);
			w->state = W_OFFER;
			proto_conn_set_limit(w->pc, LIM_FRAME_PAYLOAD); /* tile results from now on */
		}
		return;
	}
	case W_AUTH: {
		if (m->type != MSG_AUTH)
			break;
		uint8_t want[PROTO_MAC_BYTES];
		proto_auth_mac(f->secret, f->secret_len, ROLE_WORKER, w->nonce, w->peer_nonce, want);
		if (!proto_mac_equal(want, m->u.mac, PROTO_MAC_BYTES)) {
			worker_refuse(f, w, PERR_AUTH, "authentication failed: the worker's secret differs");
			return;
		}
		proto_send_offer(w->pc, f->hash, f->scene_len, f->s.w, f->s.h);
		w->state = W_OFFER;
		proto_conn_set_limit(w->pc, LIM_FRAME_PAYLOAD); /* tile results from now on */
		return;
	}
	case W_OFFER:
		if ((m->type == MSG_SCENE_HAVE || m->type == MSG_SCENE_NEED) &&
		    memcmp(m->u.hash, f->hash, PROTO_HASH_BYTES) == 0) {
			w->cache_hit = m->type == MSG_SCENE_HAVE;
			w->sent_off = 0;
			if (m->type == MSG_SCENE_NEED) {
				w->state = W_SENDING;
				send_scene(f, w);
			} else {
				w->state = W_BUILDING;
			}
			return;
		}
		break;
	case W_SENDING:
	case W_BUILDING:
		if (m->type == MSG_SCENE_READY && w->state == W_BUILDING &&
		    memcmp(m->u.ready.hash, f->hash, PROTO_HASH_BYTES) == 0) {
			w->state = W_READY;
			dispatch(f, w);
			return;
		}
		break;
	case W_READY:
		if (m->type == MSG_TILE_RESULT) {
			on_result(f, w, m);
			if (w->state == W_READY)
				dispatch(f, w);
			return;
		}
		break;
	default:
		break;
	}
	worker_refuse(f, w, PERR_PROTOCOL, "unexpected %s message", proto_type_name(m->type));
}

static void worker_input(struct farm *f, struct worker *w)
{
	const char *why;
	int r = proto_conn_read(w->pc, &why);
	if (r < 0) {
		/* bytes already buffered (an ERROR, say) are read before giving up */
		struct proto_msg m;
		int code;
		while (w->pc && proto_conn_next(w->pc, &m, &code, &why) > 0) {
			on_message(f, w, &m);
			if (w->state == W_IDLE)
				return;
		}
		if (w->pc)
			worker_lost(f, w, false, "%s", why);
		return;
	}
	struct proto_msg m;
	int code;
	while (w->pc) {
		int k = proto_conn_next(w->pc, &m, &code, &why);
		if (k == 0)
			break;
		if (k < 0) {
			worker_refuse(f, w, code, "%s", why);
			return;
		}
		w->last_rx = net_now(); /* whole frames only: trickled bytes are no heartbeat */
		on_message(f, w, &m);
	}
}

/* ---- progress and summary ---- */

static void progress(struct farm *f, bool force)
{
	double now = net_now();
	if (!f->tty || f->o->quiet || (!force && now - f->last_progress < 0.25))
		return;
	f->last_progress = now;
	pthread_mutex_lock(&f->s.mu);
	uint32_t done = f->s.n_done, n = f->s.n, local_done = f->s.local_done;
	pthread_mutex_unlock(&f->s.mu);
	double el = now - f->t0;
	char eta[32] = "?";
	if (done > 0 && done < n)
		snprintf(eta, sizeof eta, "%.0fs", el * (n - done) / done);
	else if (done == n)
		snprintf(eta, sizeof eta, "0s");
	char line[512];
	int len = snprintf(line, sizeof line, "farm %u/%u tiles %3.0f%% ETA %s | local %.1f t/s", done, n,
			   100.0 * done / n, eta, el > 0 ? local_done / el : 0.0);
	for (uint32_t i = 0; i < f->n_w && len < (int)sizeof line - 40; i++) {
		struct worker *w = &f->w[i];
		/* a recent rate: tiles over the last second or so */
		double dt = now - w->rate_t0;
		if (dt >= 1.0 || w->rate_t0 == 0) {
			if (w->rate_t0 > 0)
				w->rate = (w->tiles_done - w->rate_n0) / dt;
			w->rate_t0 = now;
			w->rate_n0 = w->tiles_done;
		}
		len += snprintf(line + len, sizeof line - (size_t)len, " | %s %.1f t/s%s", w->name, w->rate,
				w->dropped ? " (dropped)" : w->state == W_READY ? "" : " (-)");
	}
	fprintf(stderr, "\r\033[K%s", line);
}

static void summary(struct farm *f)
{
	if (f->tty && !f->o->quiet)
		fputs("\r\033[K", stderr);
	if (f->o->quiet)
		return;
	double el = net_now() - f->t0;
	uint64_t sent = 0, scene = 0;
	for (uint32_t i = 0; i < f->n_w; i++) {
		sent += f->w[i].bytes_out;
		scene += f->w[i].scene_bytes;
	}
	fprintf(stderr,
		"portray-master: farm: %u tiles of %u px in %.2f s; %u re-dispatched, %u duplicates (%u wasted), "
		"%u invalid results, %u audits (%u failed)\n",
		f->s.n, f->tile, el, f->s.redispatched, f->s.duplicates, f->s.dup_wasted, f->invalid_results,
		f->s.n_audits, f->s.n_audit_failed);
	fprintf(stderr, "portray-master:   %-24s %6u tiles %5.1f%%\n", "local", f->s.local_done,
		100.0 * f->s.local_done / f->s.n);
	for (uint32_t i = 0; i < f->n_w; i++) {
		struct worker *w = &f->w[i];
		fprintf(stderr,
			"portray-master:   %-24s %6u tiles %5.1f%%  %u threads  sent %llu B (scene %llu B, cache %s)  "
			"received %llu B%s%s\n",
			w->name, w->tiles_done, 100.0 * w->tiles_done / f->s.n, w->threads,
			(unsigned long long)w->bytes_out, (unsigned long long)w->scene_bytes,
			w->threads == 0 ? "-" : w->cache_hit ? "hit" : "miss", (unsigned long long)w->bytes_in,
			w->why[0] ? "  last problem: " : "", w->why);
	}
	fprintf(stderr, "portray-master: farm: bytes sent %llu (scene %llu, encoded scene %zu B)\n",
		(unsigned long long)sent, (unsigned long long)scene, f->scene_len);
}

/* ---- the loop ---- */

static bool any_worker_alive(const struct farm *f)
{
	for (uint32_t i = 0; i < f->n_w; i++)
		if (!f->w[i].dropped)
			return true;
	return false;
}

/* Drops the workers an audit caught since the last call, and says so. */
static void drop_caught(struct farm *f)
{
	for (uint32_t i = 0; i < f->n_w; i++) {
		struct worker *w = &f->w[i];
		pthread_mutex_lock(&f->s.mu);
		struct trust tr = f->s.trust[i];
		f->s.trust[i].reported = tr.caught;
		pthread_mutex_unlock(&f->s.mu);
		if (!tr.caught || tr.reported)
			continue;
		snprintf(w->why, sizeof w->why, "returned wrong pixels for tile %u (audit)", tr.tile);
		if (w->pc && w->state >= W_HELLO) {
			proto_send_error(w->pc, PERR_PROTOCOL, "wrong pixels for tile %u (audit)", tr.tile);
			proto_conn_flush(w->pc);
		}
		worker_close(f, w);
		w->dropped = true;
		w->tiles_done = 0; /* none of its tiles is kept */
		flog(f, "worker %s returned wrong pixels for tile %u (audit): dropped; its %u tiles re-rendered",
		     w->name, tr.tile, tr.requeued);
	}
}

/* The hung-tile deadline of w: how long it may hold tiles without returning any. */
static double hang_deadline(const struct farm *f, const struct worker *w)
{
	if (w->n_lat == 0)
		return FARM_HANG_HB_FIRST * f->hb_timeout;
	double d = FARM_HANG_MEDIANS * w->median;
	return d > FARM_HANG_HB * f->hb_timeout ? d : FARM_HANG_HB * f->hb_timeout;
}

/* Timers: connects due, heartbeat and hung-tile deadlines, our own heartbeats. */
static void tick(struct farm *f)
{
	double now = net_now();
	drop_caught(f);
	for (uint32_t i = 0; i < f->n_w; i++) {
		struct worker *w = &f->w[i];
		if (w->state == W_IDLE) {
			if (!w->dropped && now >= w->retry_at && !atomic_load(&f->s.stop))
				worker_start(f, w);
			continue;
		}
		if (w->state == W_DONE)
			continue;
		if (now - w->last_rx > f->hb_timeout) {
			worker_lost(f, w, false, "%s for %.1f s",
				    w->state == W_CONNECTING ? "no connection" : "no heartbeat", now - w->last_rx);
			continue;
		}
		if (w->state == W_READY && w->n_inflight > 0) {
			/* a tracer stuck on a tile while the worker heartbeats */
			double since = w->last_result > w->busy_since ? w->last_result : w->busy_since;
			double d = hang_deadline(f, w);
			if (now - since > d) {
				worker_refuse(f, w, PERR_TIMEOUT,
					      "hung: no tile result for %.1f s while holding %u tiles (deadline %.1f s)",
					      now - since, w->n_inflight, d);
				continue;
			}
		}
		/* from our offer on: a heartbeat before the handshake is done is a
		 * protocol error (protocol 2) */
		if (w->state >= W_OFFER && now - w->last_hb >= f->hb_interval) {
			proto_send_heartbeat(w->pc, 0, 0);
			w->last_hb = now;
		}
		if (w->state == W_SENDING)
			send_scene(f, w);
		if (w->state == W_READY)
			dispatch(f, w);
		if (proto_conn_flush(w->pc) < 0)
			worker_lost(f, w, false, "connection lost while sending");
	}
}

static int farm_loop(struct farm *f, atomic_int *cancel, int wake_rd)
{
	struct pollfd *pfd = calloc(f->n_w + 1, sizeof *pfd);
	if (!pfd)
		return -1;
	int rc = 0;
	for (;;) {
		if (atomic_load(cancel))
			atomic_store(&f->s.stop, 1);
		if (atomic_load(&f->s.stop))
			break;
		if (f->o->no_local && !any_worker_alive(f)) {
			rc = EXIT_NO_WORKERS;
			break;
		}
		tick(f);
		pfd[0] = (struct pollfd){ .fd = wake_rd, .events = POLLIN };
		for (uint32_t i = 0; i < f->n_w; i++) {
			struct worker *w = &f->w[i];
			short ev = 0;
			if (w->pc) {
				ev = w->state == W_CONNECTING ? POLLOUT : POLLIN;
				if (proto_conn_outq(w->pc))
					ev |= POLLOUT;
			}
			pfd[i + 1] = (struct pollfd){ .fd = w->pc ? proto_conn_fd(w->pc) : -1, .events = ev };
		}
		int k = poll(pfd, f->n_w + 1, 20);
		if (k < 0 && errno != EINTR)
			break;
		if (k > 0 && (pfd[0].revents & POLLIN)) {
			char b[64];
			while (read(wake_rd, b, sizeof b) > 0)
				;
		}
		for (uint32_t i = 0; k > 0 && i < f->n_w; i++) {
			struct worker *w = &f->w[i];
			short re = pfd[i + 1].revents;
			if (!w->pc || !re)
				continue;
			if (w->state == W_CONNECTING) {
				char err[300];
				if (net_connect_finish(proto_conn_fd(w->pc), err, sizeof err) < 0) {
					worker_lost(f, w, false, "%s", err);
					continue;
				}
				w->state = W_HELLO;
				/* an unauthenticated peer gets no big buffers from us */
				proto_conn_set_limit(w->pc, LIM_HANDSHAKE_PAYLOAD);
				w->last_rx = w->connected_at = net_now();
				w->last_hb = 0;
				/* a fresh nonce per connection, or no handshake: a
				 * predictable one would let a recorded proof be replayed */
				if (proto_random(w->nonce, sizeof w->nonce) < 0) {
					worker_lost(f, w, true, "no random source for the handshake nonce");
					continue;
				}
				if (send_hello(f, w) < 0) {
					worker_lost(f, w, false, "out of memory");
					continue;
				}
				proto_conn_flush(w->pc);
				continue;
			}
			if (re & (POLLIN | POLLHUP | POLLERR))
				worker_input(f, w);
			if (w->pc && (re & POLLOUT)) {
				if (w->state == W_SENDING)
					send_scene(f, w);
				if (proto_conn_flush(w->pc) < 0)
					worker_lost(f, w, false, "connection lost while sending");
			}
		}
		progress(f, false);
	}
	free(pfd);
	return rc;
}

/* Says goodbye to every connected worker, waiting at most a moment for the bytes to leave. */
static void farm_bye(struct farm *f)
{
	double until = net_now() + 1.0;
	for (uint32_t i = 0; i < f->n_w; i++) {
		struct worker *w = &f->w[i];
		if (w->pc && w->state >= W_HELLO) {
			proto_send_bye(w->pc);
			w->state = W_DONE;
		}
	}
	for (;;) {
		bool pending = false;
		for (uint32_t i = 0; i < f->n_w; i++) {
			struct worker *w = &f->w[i];
			if (w->pc && proto_conn_outq(w->pc)) {
				if (proto_conn_flush(w->pc) < 0)
					continue;
				pending |= proto_conn_outq(w->pc) > 0;
			}
		}
		if (!pending || net_now() > until)
			break;
		usleep(2000);
	}
	for (uint32_t i = 0; i < f->n_w; i++) {
		struct worker *w = &f->w[i];
		if (w->pc) {
			w->bytes_out += proto_conn_bytes_out(w->pc);
			w->bytes_in += proto_conn_bytes_in(w->pc);
			proto_conn_free(w->pc);
			w->pc = NULL;
		}
	}
}

int farm_render(const struct master_opts *o, const struct scene *sc, struct renderer *r, uint32_t w,
		uint32_t h, uint8_t *image, atomic_int *cancel)
{
	struct farm f;
	memset(&f, 0, sizeof f);
	f.o = o;
	f.t0 = net_now();
	f.tty = isatty(2) && !o->quiet;
	f.hb_timeout = o->heartbeat_s > 0 ? o->heartbeat_s : 10.0;
	f.hb_interval = f.hb_timeout / 4;
	int rc = EXIT_USAGE;
	int wake[2] = { -1, -1 };
	pthread_t *tids = NULL;
	struct local *L = NULL;
	int n_local = 0, n_threads = 0;
	bool sched_init = false;

	if (parse_workers(&f) < 0)
		goto out;
	if (o->secret_file) {
		char err[512], warn[512];
		if (proto_read_secret(o->secret_file, &f.secret, &f.secret_len, err, sizeof err, warn, sizeof warn) < 0) {
			fprintf(stderr, "portray-master: --secret-file: %s\n", err);
			goto out;
		}
		if (warn[0])
			fprintf(stderr, "portray-master: warning: --secret-file %s\n", warn);
	}
	rc = ERRLEVEL_FATAL;
	if (proto_scene_encode(sc, &f.scene, &f.scene_len) < 0) {
		fprintf(stderr, "portray-master: out of memory encoding the scene\n");
		goto out;
	}
	if (f.scene_len > LIM_SCENE_BYTES) {
		fprintf(stderr, "portray-master: the encoded scene (%zu bytes) is over the wire limit\n", f.scene_len);
		goto out;
	}
	proto_scene_hash(f.scene, f.scene_len, f.hash);

	/* tiles: the requested side, small enough for one frame */
	f.tile = o->tile ? o->tile : 32;
	while ((uint64_t)f.tile * f.tile > LIM_TILE_PIXELS)
		f.tile /= 2;
	uint32_t tx = (w + f.tile - 1) / f.tile, ty = (h + f.tile - 1) / f.tile;
	struct sched *s = &f.s;
	s->n = tx * ty;
	s->w = w;
	s->h = h;
	s->image = image;
	s->t = calloc(s->n, sizeof *s->t);
	s->queue = calloc(s->n, sizeof *s->queue);
	s->audits = calloc(s->n, sizeof *s->audits);
	s->trust = calloc(f.n_w, sizeof *s->trust);
	s->n_workers = f.n_w;
	if (!s->t || !s->queue || !s->audits || !s->trust || pipe(wake) < 0) {
		fprintf(stderr, "portray-master: out of memory for %u tiles\n", s->n);
		goto out;
	}
	for (int i = 0; i < 2; i++)
		fcntl(wake[i], F_SETFL, fcntl(wake[i], F_GETFL) | O_NONBLOCK);
	s->wake_fd = wake[1];
	for (uint32_t i = 0; i < s->n; i++) {
		struct ftile *t = &s->t[i];
		uint32_t x = (i % tx) * f.tile, y = (i / tx) * f.tile;
		t->rect = (struct tile_rect){ x, y, x + f.tile > w ? w - x : f.tile, y + f.tile > h ? h - y : f.tile };
		t->holder[0] = t->holder[1] = t->by = HOLDER_NONE;
		t->queued = 1;
		s->queue[i] = i;
	}
	s->q_len = s->n;
	pthread_mutex_init(&s->mu, NULL);
	pthread_cond_init(&s->cv, NULL);
	atomic_init(&s->stop, 0);
	sched_init = true;

	/* audits: on the local threads; with --no-local on one thread that takes
	 * nothing else. Buffers first: a thread that cannot trace would leave
	 * its audits waiting for ever */
	f.audit = o->audit;
	if (f.audit > 0 && proto_random((uint8_t *)&f.audit_salt, sizeof f.audit_salt) < 0)
		f.audit_salt = mix64((uint64_t)getpid() ^ (uint64_t)(net_now() * 1e9));
	n_threads = o->no_local ? (f.audit > 0) : o->threads > 0 ? o->threads : render_ncpus();
	if (n_threads > 0) {
		tids = calloc((size_t)n_threads, sizeof *tids);
		L = calloc((size_t)n_threads, sizeof *L);
		for (int i = 0; L && i < n_threads; i++) {
			L[i] = (struct local){ s, r, malloc((size_t)f.tile * f.tile * 3), o->no_local };
			if (!L[i].buf)
				n_threads = i;
		}
		if (!tids || !L || n_threads == 0) {
			fprintf(stderr, "portray-master: out of memory for local threads\n");
			rc = ERRLEVEL_FATAL;
			goto out;
		}
	}
	for (uint32_t i = 0; i < f.n_w; i++)
		worker_start(&f, &f.w[i]);
	for (int i = 0; i < n_threads; i++) {
		if (pthread_create(&tids[i], NULL, local_thread, &L[i]) != 0)
			break;
		n_local++;
	}
	if (n_threads > 0 && n_local == 0) {
		fprintf(stderr, "portray-master: cannot start a local thread\n");
		rc = ERRLEVEL_FATAL;
		goto out;
	}
	rc = farm_loop(&f, cancel, wake[0]);
	atomic_store(&s->stop, 1);
	pthread_mutex_lock(&s->mu);
	pthread_cond_broadcast(&s->cv);
	pthread_mutex_unlock(&s->mu);
	for (int i = 0; i < n_local; i++)
		pthread_join(tids[i], NULL);
	farm_bye(&f);
	progress(&f, true);
	summary(&f);
	if (rc == EXIT_NO_WORKERS)
		fprintf(stderr,
			"portray-master: every worker is lost and --no-local forbids rendering here: %u of %u tiles done\n",
			s->n_done, s->n);
	else if (rc == 0 && s->n_done < s->n && !atomic_load(cancel))
		rc = ERRLEVEL_FATAL;

out:
	if (sched_init) {
		pthread_mutex_destroy(&f.s.mu);
		pthread_cond_destroy(&f.s.cv);
	}
	for (uint32_t i = 0; f.w && i < f.n_w; i++) {
		proto_conn_free(f.w[i].pc);
		free(f.w[i].inflight);
	}
	free(f.w);
	free(tids);
	for (int i = 0; L && i < n_threads; i++)
		free(L[i].buf);
	free(L);
	for (uint32_t i = 0; f.s.t && i < f.s.n; i++)
		free(f.s.t[i].claim);
	free(f.s.t);
	free(f.s.queue);
	free(f.s.audits);
	free(f.s.trust);
	free(f.scene);
	free(f.secret);
	for (int i = 0; i < 2; i++)
		if (wake[i] >= 0)
			close(wake[i]);
	return rc;
}
