/*
 * main.c - portray-worker: a daemon that renders tiles for portray-master.
 *
 * One event-loop thread owns the listening socket and every connection (all
 * non-blocking, poll()); a pool of tracer threads takes tiles from the jobs'
 * queues round-robin, so several masters share the cores fairly, and builds
 * scenes (decode + acceleration) off the event loop, so heartbeats never
 * stop while the worker is busy. Finished work comes back to the loop through
 * a done list and a self-pipe. Scenes are cached by content hash, least
 * recently used first out, bounded by --cache-mb.
 *
 * Nothing a peer sends can make this program open a file or run anything:
 * a scene arrives as bytes (RAW meshes inside it) and is decoded with every
 * count bounded. A peer that breaks the protocol gets an ERROR and is closed.
 * Protocol reference: docs/protocol.md.
 */
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "common/render.h"
#include "common/scene.h"
#include "proto/net.h"
#include "proto/proto.h"
#include "proto/serial.h"

/* connections served at once: each costs a frame buffer (up to 4 MiB) */
#define WK_MAX_CONNS 256
/* seconds a peer may take from connect to its scene offer */
#define WK_HANDSHAKE_S 10.0
/* a master that sends nothing for this long (it heartbeats) is gone */
#define WK_IDLE_MIN_S 30.0
/* seconds the listening socket rests after accept() ran out of descriptors */
#define WK_ACCEPT_PAUSE_S 0.25
/* --test-fault lie: tiles 2, 2 + k, 2 + 2k, ... (counted from 1 over the
 * process) are wrong: never the first, which every master audits */
#define WK_LIE_EVERY 4
/* --test-fault hang-tile: the third tile hangs, after two results have given
 * the master a tile time */
#define WK_HANG_AT 3

/* default scene cache budget, MiB of encoded scene bytes */
#define WK_CACHE_MB_DEFAULT 1024

enum wk_fault {
	FAULT_NONE,
	FAULT_BAD_CHECKSUM,
	FAULT_WRONG_SIZE,
	FAULT_PROTO_VERSION,
	FAULT_BUILD,
	FAULT_BLACK,
	FAULT_TRACE_FAIL, /* every tile fails as if out of memory */
	FAULT_LIE,        /* every WK_LIE_EVERY-th tile traced, from the second: one pixel's low bit
			   * flipped before the checksum (wrong pixels, valid checksum) */
	FAULT_HANG_TILE   /* the WK_HANG_AT-th tile traced never finishes (until shutdown) */
};

/* ---- options and global state ---- */

static struct {
	int threads;
	uint8_t *secret;
	size_t secret_len;
	uint64_t cache_bytes;
	enum wk_fault fault;
	int delay_ms;      /* test hook: extra time per tile, so tests can act mid-render */
	double handshake_s; /* accept to scene offer (WK_HANDSHAKE_S; a test hook shortens it) */
} opt;

static volatile sig_atomic_t stop_flag;
static int wake_pipe[2] = { -1, -1 };

static void wk_log(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static void wk_log(const char *fmt, ...)
{
	char ts[32];
	time_t t = time(NULL);
	struct tm tm;
	gmtime_r(&t, &tm);
	strftime(ts, sizeof ts, "%H:%M:%S", &tm);
	va_list ap;
	va_start(ap, fmt);
	flockfile(stderr);
	fprintf(stderr, "portray-worker %s ", ts);
	vfprintf(stderr, fmt, ap);
	fputc('\n', stderr);
	funlockfile(stderr);
	va_end(ap);
}

static void wake(void)
{
	char b = 1;
	ssize_t r = write(wake_pipe[1], &b, 1);
	(void)r; /* a full pipe already means "wake up" */
}

static void on_signal(int sig)
{
	(void)sig;
	stop_flag = 1;
	int e = errno;
	wake();
	errno = e;
}

/* ---- scene cache ---- */

/* One built scene at one image size. Owned by the cache; refs counts jobs. */
struct wk_entry {
	uint8_t hash[PROTO_HASH_BYTES];
	uint32_t w, h;
	uint8_t *bytes; /* encoded scene (kept so another size can be built) */
	size_t len;
	struct scene *scene;
	struct renderer *r;
	int state;      /* 0 building, 1 ready, -1 failed */
	char error[sizeof ((struct scene_error *)0)->msg];
	int refs;
	double last_used;
	uint32_t build_ms;
	struct wk_entry *next;
};

static struct wk_entry *cache;
static uint64_t cache_used;

static void entry_free(struct wk_entry *e)
{
	renderer_free(e->r);
	scene_free(e->scene);
	free(e->bytes);
	free(e);
}

/*
 * Drops unreferenced entries that failed to build, then unreferenced ones
 * least recently used first until the budget holds. Event loop only.
 */
static void cache_trim(pthread_mutex_t *mu)
{
	pthread_mutex_lock(mu);
	for (;;) {
		struct wk_entry **victim = NULL;
		for (struct wk_entry **pp = &cache; *pp; pp = &(*pp)->next) {
			struct wk_entry *e = *pp;
			if (e->refs != 0 || e->state == 0)
				continue;
			if (e->state < 0) {
				victim = pp;
				break;
			}
			if (cache_used > opt.cache_bytes && (!victim || e->last_used < (*victim)->last_used))
				victim = pp;
		}
		if (!victim)
			break;
		struct wk_entry *e = *victim;
		*victim = e->next;
		cache_used -= e->len;
		pthread_mutex_unlock(mu);
		entry_free(e);
		pthread_mutex_lock(mu);
	}
	pthread_mutex_unlock(mu);
}

/* ---- jobs, tasks and the tracer pool ---- */

struct wk_conn;

/* The tracing side of one connection: its tile queue. Shared with the pool. */
struct wk_job {
	struct wk_conn *conn; /* NULL once the connection is gone */
	struct wk_entry *entry;
	struct proto_tile *q;  /* queued tiles, FIFO in q[head..len) */
	size_t head, len, cap;
	int refs;             /* the connection + tiles being traced */
	uint32_t running;
	/* back-pressure: result bytes held for this job = traced_bytes (tiles
	 * taken by tracers and not yet queued on the socket) + outq_bytes (the
	 * socket's queue at the loop's last look); no tile is taken while they
	 * exceed PROTO_OUT_HIGH_WATER, so a master that does not read costs at
	 * most that plus one tile per thread, however late the loop runs */
	size_t traced_bytes, outq_bytes;
	bool paused;          /* a tracer skipped it for that reason (the loop wakes them) */
	bool failed;          /* a tile could not be traced (out of memory): end the job */
};

struct wk_done {
	int kind;             /* 0 tile, 1 build */
	struct wk_job *job;
	struct proto_tile tile;
	uint8_t *pixels;      /* owned */
	uint32_t crc;
	uint32_t trace_us;
	int ok;
	struct wk_entry *entry;
	struct wk_done *next;
};

static struct {
	pthread_mutex_t mu;
	pthread_cond_t cv;
	struct wk_job **jobs; /* jobs with a queue, round-robin */
	size_t n_jobs, cap_jobs, cursor;
	struct wk_entry **builds; /* entries to build, FIFO */
	size_t n_builds, cap_builds;
	struct wk_done *done, *done_tail;
	int quit;
	atomic_int cancel_all;
} pool = { .mu = PTHREAD_MUTEX_INITIALIZER, .cv = PTHREAD_COND_INITIALIZER };

static void job_unref_locked(struct wk_job *j)
{
	if (--j->refs == 0) {
		for (size_t i = 0; i < pool.n_jobs; i++)
			if (pool.jobs[i] == j) {
				pool.jobs[i] = pool.jobs[--pool.n_jobs];
				break;
			}
		if (j->entry)
			j->entry->refs--;
		free(j->q);
		free(j);
	}
}

static void push_done(struct wk_done *d)
{
	d->next = NULL;
	if (pool.done_tail)
		pool.done_tail->next = d;
	else
		pool.done = d;
	pool.done_tail = d;
}

/* Builds one cache entry (called by a tracer thread without the lock). */
static void build_entry(struct wk_entry *e)
{
	double t0 = net_now();
	struct scene_error err;
	struct scene *s = NULL;
	struct renderer *r = NULL;
	if (proto_scene_decode(e->bytes, e->len, &s, &err)) {
		snprintf(e->error, sizeof e->error, "%s", err.msg);
		goto fail;
	}
	if (renderer_new(s, &r, &err)) {
		snprintf(e->error, sizeof e->error, "%s", err.msg);
		goto fail;
	}
	if (renderer_set_size(r, e->w, e->h)) {
		snprintf(e->error, sizeof e->error, "image size %ux%u refused", e->w, e->h);
		goto fail;
	}
	pthread_mutex_lock(&pool.mu); /* the event loop reads state under the lock */
	e->scene = s;
	e->r = r;
	e->build_ms = (uint32_t)((net_now() - t0) * 1000);
	e->state = 1;
	pthread_mutex_unlock(&pool.mu);
	return;
fail:
	renderer_free(r);
	scene_free(s);
	pthread_mutex_lock(&pool.mu);
	e->state = -1;
	pthread_mutex_unlock(&pool.mu);
}

/* Tracer thread: builds first (they unblock whole jobs), then tiles round-robin. */
static void *tracer(void *arg)
{
	(void)arg;
	pthread_mutex_lock(&pool.mu);
	for (;;) {
		if (pool.quit)
			break;
		if (pool.n_builds) {
			struct wk_entry *e = pool.builds[0];
			memmove(pool.builds, pool.builds + 1, --pool.n_builds * sizeof *pool.builds);
			pthread_mutex_unlock(&pool.mu);
			build_entry(e);
			struct wk_done *d = calloc(1, sizeof *d);
			pthread_mutex_lock(&pool.mu);
			if (d) {
				d->kind = 1;
				d->entry = e;
				push_done(d);
			} else {
				e->state = -1;
			}
			wake();
			continue;
		}
		struct wk_job *j = NULL;
		for (size_t k = 0; k < pool.n_jobs; k++) {
			struct wk_job *c = pool.jobs[(pool.cursor + k) % pool.n_jobs];
			if (c->head < c->len && c->conn) {
				if (c->traced_bytes + c->outq_bytes > PROTO_OUT_HIGH_WATER) {
					c->paused = true;
					continue;
				}
				j = c;
				pool.cursor = (pool.cursor + k + 1) % pool.n_jobs;
				break;
			}
		}
		if (!j) {
			pthread_cond_wait(&pool.cv, &pool.mu);
			continue;
		}
		struct proto_tile t = j->q[j->head++];
		j->refs++;
		j->running++;
		j->traced_bytes += (size_t)t.w * t.h * 3;
		const struct renderer *r = j->entry->r;
		pthread_mutex_unlock(&pool.mu);

		struct wk_done *d = calloc(1, sizeof *d);
		uint8_t *px = malloc((size_t)t.w * t.h * 3);
		int ok = 0;
		if (d && px) {
			struct tile_rect rect = { t.x, t.y, t.w, t.h };
			double t0 = net_now();
			ok = renderer_tile_cancellable(r, rect, px, &pool.cancel_all);
			d->trace_us = (uint32_t)((net_now() - t0) * 1e6) + 1;
			if (opt.fault == FAULT_TRACE_FAIL)
				ok = 0;
			if (opt.fault == FAULT_LIE || opt.fault == FAULT_HANG_TILE) {
				static atomic_uint traced;
				unsigned nth = atomic_fetch_add(&traced, 1) + 1;
				if (ok && opt.fault == FAULT_LIE && nth % WK_LIE_EVERY == 2 % WK_LIE_EVERY)
					px[0] ^= 1; /* the checksum is computed below, over this */
				while (opt.fault == FAULT_HANG_TILE && nth == WK_HANG_AT &&
				       !atomic_load(&pool.cancel_all)) {
					struct timespec ts = { 0, 50 * 1000000L };
					nanosleep(&ts, NULL);
				}
			}
			if (opt.delay_ms > 0) {
				struct timespec ts = { opt.delay_ms / 1000, (long)(opt.delay_ms % 1000) * 1000000L };
				nanosleep(&ts, NULL);
			}
		}
		pthread_mutex_lock(&pool.mu);
		j->running--;
		if (d && px && ok) {
			d->kind = 0;
			d->job = j; /* the done entry now holds the job's reference */
			d->tile = t;
			d->pixels = px;
			d->crc = crc32_update(0, px, (size_t)t.w * t.h * 3);
			push_done(d);
			wake();
		} else {
			/* never drop a tile silently: the master would wait for it
			 * for ever (only a shutdown cancels tiles on purpose) */
			if (!atomic_load(&pool.cancel_all)) {
				j->failed = true;
				wake();
			}
			j->traced_bytes -= (size_t)t.w * t.h * 3;
			free(d);
			free(px);
			job_unref_locked(j);
		}
	}
	pthread_mutex_unlock(&pool.mu);
	return NULL;
}

/* ---- connections ---- */

enum wk_state { ST_HELLO, ST_AUTH, ST_OFFER, ST_RECV, ST_BUILD, ST_READY, ST_CLOSING };

struct wk_conn {
	struct proto_conn *pc;
	char peer[96];
	enum wk_state state;
	uint8_t nonce[PROTO_NONCE_BYTES];
	uint8_t peer_nonce[PROTO_NONCE_BYTES];
	double hb_interval, last_hb, last_rx, deadline, started;
	uint8_t hash[PROTO_HASH_BYTES];
	uint32_t w, h;
	uint8_t *scene;        /* scene bytes being received, grows as they arrive */
	size_t scene_len, scene_cap;
	uint64_t scene_size;   /* as offered */
	struct wk_job *job;
	struct wk_entry *entry; /* the entry this job uses (also in job) */
	bool cache_hit;
	uint32_t tiles_done;
	bool got_tile;         /* the first TILE arrived (logged: tests wait for it) */
	bool logged;
};

static struct wk_conn *conns[WK_MAX_CONNS];
static size_t n_conns;

static void hex8(const uint8_t *h, char out[17])
{
	for (int i = 0; i < 8; i++)
		snprintf(out + 2 * i, 3, "%02x", h[i]);
}

/* The one log line of a job (once). */
static void job_log(struct wk_conn *c, const char *how)
{
	if (c->logged || c->state < ST_BUILD)
		return;
	char hx[17];
	hex8(c->hash, hx);
	wk_log("job %s scene %s %ux%u: %u tiles in %.2f s, scene cache %s (%llu scene bytes received), %s", c->peer,
	       hx, c->w, c->h, c->tiles_done, net_now() - c->started, c->cache_hit ? "hit" : "miss",
	       (unsigned long long)c->scene_len, how);
	c->logged = true;
}

/* Sends ERROR and moves to closing (the loop closes once the error is flushed). */
static void conn_fail(struct wk_conn *c, int code, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void conn_fail(struct wk_conn *c, int code, const char *fmt, ...)
{
	char text[LIM_ERROR_TEXT + 1];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(text, sizeof text, fmt, ap);
	va_end(ap);
	if (c->state >= ST_BUILD && c->state != ST_CLOSING && !c->logged) {
		char how[LIM_ERROR_TEXT + 64];
		snprintf(how, sizeof how, "ended: %s (%s error)", text, proto_err_name(code));
		job_log(c, how);
	} else {
		wk_log("%s: refused: %s (%s error)", c->peer, text, proto_err_name(code));
	}
	proto_send_error(c->pc, code, "%s", text);
	c->state = ST_CLOSING;
	c->deadline = net_now() + 2.0;
	c->logged = true;
}

static void conn_close(size_t i)
{
	struct wk_conn *c = conns[i];
	pthread_mutex_lock(&pool.mu);
	if (c->job) {
		c->job->conn = NULL;
		c->job->len = c->job->head; /* drop queued tiles */
		job_unref_locked(c->job);
	} else if (c->entry) {
		c->entry->refs--;
	}
	pthread_mutex_unlock(&pool.mu);
	proto_conn_free(c->pc);
	free(c->scene);
	free(c);
	conns[i] = conns[--n_conns];
}

static void send_hello(struct wk_conn *c)
{
	struct proto_hello h;
	memset(&h, 0, sizeof h);
	h.version = PROTO_VERSION;
	h.role = ROLE_WORKER;
	h.secret = opt.secret != NULL;
	h.threads = (uint16_t)(opt.threads > 65535 ? 65535 : opt.threads);
	memcpy(h.nonce, c->nonce, PROTO_NONCE_BYTES);
	snprintf(h.build, sizeof h.build, "%s%s", proto_build_id(), opt.fault == FAULT_BUILD ? "-other" : "");
	if (opt.fault == FAULT_PROTO_VERSION) {
		h.version = PROTO_VERSION + 1;
		proto_conn_set_version(c->pc, (uint16_t)(PROTO_VERSION + 1));
	}
	proto_send_hello(c->pc, &h);
}

/* The job can start: an entry is ready for this connection. */
static void job_start(struct wk_conn *c)
{
	struct wk_entry *e = c->entry;
	struct wk_job *j = calloc(1, sizeof *j);
	if (!j) {
		conn_fail(c, PERR_INTERNAL, "out of memory");
		return;
	}
	j->conn = c;
	j->entry = e; /* the connection's reference to e moves to the job */
	j->refs = 1;
	pthread_mutex_lock(&pool.mu);
	if (pool.n_jobs == pool.cap_jobs) {
		size_t nc = pool.cap_jobs ? pool.cap_jobs * 2 : 16;
		struct wk_job **p = realloc(pool.jobs, nc * sizeof *p);
		if (!p) {
			pthread_mutex_unlock(&pool.mu);
			free(j);
			conn_fail(c, PERR_INTERNAL, "out of memory");
			return;
		}
		pool.jobs = p;
		pool.cap_jobs = nc;
	}
	pool.jobs[pool.n_jobs++] = j;
	pthread_mutex_unlock(&pool.mu);
	c->job = j;
	c->state = ST_READY;
	proto_send_ready(c->pc, c->hash, c->cache_hit, e->build_ms);
}

/* Finds or creates the cache entry for (hash, w, h); NULL when none holds the bytes. */
static struct wk_entry *cache_find(const uint8_t *hash, uint32_t w, uint32_t h, bool *exact)
{
	struct wk_entry *same_hash = NULL;
	for (struct wk_entry *e = cache; e; e = e->next) {
		if (memcmp(e->hash, hash, PROTO_HASH_BYTES) != 0 || e->state < 0)
			continue;
		if (e->w == w && e->h == h) {
			*exact = true;
			return e;
		}
		same_hash = e;
	}
	*exact = false;
	return same_hash;
}

static void queue_build(struct wk_entry *e)
{
	pthread_mutex_lock(&pool.mu);
	if (pool.n_builds == pool.cap_builds) {
		size_t nc = pool.cap_builds ? pool.cap_builds * 2 : 8;
		struct wk_entry **p = realloc(pool.builds, nc * sizeof *p);
		if (!p) {
			e->state = -1;
			snprintf(e->error, sizeof e->error, "out of memory");
			pthread_mutex_unlock(&pool.mu);
			return;
		}
		pool.builds = p;
		pool.cap_builds = nc;
	}
	pool.builds[pool.n_builds++] = e;
	pthread_cond_signal(&pool.cv);
	pthread_mutex_unlock(&pool.mu);
}

/* A new entry owning bytes (taken); added to the cache and queued for building. */
static struct wk_entry *entry_new(struct wk_conn *c, uint8_t *bytes, size_t len)
{
	struct wk_entry *e = calloc(1, sizeof *e);
	if (!e) {
		free(bytes);
		return NULL;
	}
	memcpy(e->hash, c->hash, PROTO_HASH_BYTES);
	e->w = c->w;
	e->h = c->h;
	e->bytes = bytes;
	e->len = len;
	e->last_used = net_now();
	pthread_mutex_lock(&pool.mu);
	e->refs = 1;
	e->next = cache;
	cache = e;
	cache_used += len;
	pthread_mutex_unlock(&pool.mu);
	queue_build(e);
	return e;
}

/* The scene is available (cached or fully received): wait for it to be built. */
static void use_entry(struct wk_conn *c, struct wk_entry *e)
{
	c->entry = e;
	c->state = ST_BUILD;
	pthread_mutex_lock(&pool.mu);
	e->last_used = net_now();
	int state = e->state;
	pthread_mutex_unlock(&pool.mu);
	if (state == 1)
		job_start(c);
	else if (state < 0)
		conn_fail(c, PERR_SCENE, "scene rejected: %s", e->error);
}

static void on_offer(struct wk_conn *c, const struct proto_msg *m)
{
	memcpy(c->hash, m->u.offer.hash, PROTO_HASH_BYTES);
	c->w = m->u.offer.width;
	c->h = m->u.offer.height;
	c->scene_size = m->u.offer.size;
	c->started = net_now();
	if (c->scene_size > opt.cache_bytes) {
		conn_fail(c, PERR_LIMIT, "scene of %llu bytes exceeds this worker's --cache-mb",
			  (unsigned long long)c->scene_size);
		return;
	}
	/* scenes being received count against the same budget: many peers
	 * offering big scenes at once cannot make the worker hold more */
	uint64_t receiving = 0;
	for (size_t i = 0; i < n_conns; i++)
		if (conns[i]->state == ST_RECV)
			receiving += conns[i]->scene_size;
	if (receiving + c->scene_size > opt.cache_bytes) {
		conn_fail(c, PERR_LIMIT, "scenes being received would exceed this worker's --cache-mb: try again later");
		return;
	}
	bool exact;
	pthread_mutex_lock(&pool.mu);
	struct wk_entry *e = cache_find(c->hash, c->w, c->h, &exact);
	if (e && exact)
		e->refs++;
	pthread_mutex_unlock(&pool.mu);
	if (e && exact) {
		c->cache_hit = true;
		proto_send_hash(c->pc, MSG_SCENE_HAVE, c->hash);
		use_entry(c, e);
		return;
	}
	if (e) { /* same scene at another size: build again from the cached bytes */
		uint8_t *copy = malloc(e->len);
		if (copy) {
			memcpy(copy, e->bytes, e->len);
			struct wk_entry *ne = entry_new(c, copy, e->len);
			if (ne) {
				c->cache_hit = true;
				proto_send_hash(c->pc, MSG_SCENE_HAVE, c->hash);
				use_entry(c, ne);
				return;
			}
		}
	}
	proto_send_hash(c->pc, MSG_SCENE_NEED, c->hash);
	c->state = ST_RECV;
}

static void on_data(struct wk_conn *c, const struct proto_msg *m)
{
	if (m->u.data.offset != c->scene_len || c->scene_len + m->u.data.n > c->scene_size) {
		conn_fail(c, PERR_PROTOCOL, "scene chunk at offset %llu out of order or past the offered size",
			  (unsigned long long)m->u.data.offset);
		return;
	}
	if (c->scene_len + m->u.data.n > c->scene_cap) {
		/* grow with the bytes that actually arrived, never to the offered size at once */
		size_t nc = c->scene_cap ? c->scene_cap * 2 : PROTO_CHUNK_BYTES;
		while (nc < c->scene_len + m->u.data.n)
			nc *= 2;
		if (nc > c->scene_size)
			nc = (size_t)c->scene_size;
		uint8_t *p = realloc(c->scene, nc);
		if (!p) {
			conn_fail(c, PERR_INTERNAL, "out of memory for the scene");
			return;
		}
		c->scene = p;
		c->scene_cap = nc;
	}
	memcpy(c->scene + c->scene_len, m->u.data.bytes, m->u.data.n);
	c->scene_len += m->u.data.n;
	if (c->scene_len < c->scene_size)
		return;
	uint8_t h[PROTO_HASH_BYTES];
	proto_scene_hash(c->scene, c->scene_len, h);
	if (!proto_mac_equal(h, c->hash, PROTO_HASH_BYTES)) {
		conn_fail(c, PERR_SCENE, "scene bytes do not match the offered hash");
		return;
	}
	uint8_t *bytes = c->scene;
	size_t len = c->scene_len;
	c->scene = NULL;
	c->scene_cap = 0;
	/* another connection may have brought the same scene meanwhile: share it */
	bool exact;
	pthread_mutex_lock(&pool.mu);
	struct wk_entry *same = cache_find(c->hash, c->w, c->h, &exact);
	if (same && exact)
		same->refs++;
	pthread_mutex_unlock(&pool.mu);
	if (same && exact) {
		free(bytes);
		use_entry(c, same);
		return;
	}
	struct wk_entry *e = entry_new(c, bytes, len);
	if (!e) {
		conn_fail(c, PERR_INTERNAL, "out of memory");
		return;
	}
	use_entry(c, e);
	cache_trim(&pool.mu);
}

static void on_tile(struct wk_conn *c, const struct proto_msg *m)
{
	const struct proto_tile *t = &m->u.tile;
	if ((uint64_t)t->x + t->w > c->w || (uint64_t)t->y + t->h > c->h) {
		conn_fail(c, PERR_PROTOCOL, "tile %u (%u,%u %ux%u) is outside the %ux%u image", t->id, t->x, t->y,
			  t->w, t->h, c->w, c->h);
		return;
	}
	if (!c->got_tile) {
		char hx[17];
		hex8(c->hash, hx);
		wk_log("job %s scene %s %ux%u: started", c->peer, hx, c->w, c->h);
		c->got_tile = true;
	}
	if (opt.fault == FAULT_BLACK) { /* simulated worker: instant black tiles */
		size_t n = (size_t)t->w * t->h * 3;
		uint8_t *px = calloc(1, n);
		if (px) {
			proto_send_result(c->pc, t, px, crc32_update(0, px, n));
			c->tiles_done++;
		}
		free(px);
		return;
	}
	struct wk_job *j = c->job;
	pthread_mutex_lock(&pool.mu);
	int ok = 1;
	if (j->len - j->head >= LIM_TILES_QUEUED) {
		ok = 0;
	} else {
		if (j->head > 0 && j->head == j->len)
			j->head = j->len = 0;
		if (j->len == j->cap) {
			if (j->head > 0) {
				memmove(j->q, j->q + j->head, (j->len - j->head) * sizeof *j->q);
				j->len -= j->head;
				j->head = 0;
			} else {
				size_t nc = j->cap ? j->cap * 2 : 32;
				struct proto_tile *p = realloc(j->q, nc * sizeof *p);
				if (!p)
					ok = -1;
				else
					j->q = p, j->cap = nc;
			}
		}
		if (ok == 1) {
			j->q[j->len++] = *t;
			pthread_cond_signal(&pool.cv);
		}
	}
	pthread_mutex_unlock(&pool.mu);
	if (ok == 0)
		conn_fail(c, PERR_LIMIT, "more than %u tiles queued", LIM_TILES_QUEUED);
	else if (ok < 0)
		conn_fail(c, PERR_INTERNAL, "out of memory");
}

static void on_cancel(struct wk_conn *c, uint32_t id)
{
	struct wk_job *j = c->job;
	pthread_mutex_lock(&pool.mu);
	if (id == PROTO_CANCEL_ALL) {
		j->len = j->head;
	} else {
		size_t o = j->head;
		for (size_t i = j->head; i < j->len; i++)
			if (j->q[i].id != id)
				j->q[o++] = j->q[i];
		j->len = o;
	}
	pthread_mutex_unlock(&pool.mu);
}

/* One decoded message for connection c, by state. */
static void on_message(struct wk_conn *c, const struct proto_msg *m)
{
	if (m->type == MSG_ERROR) {
		wk_log("%s: peer says: %s (%s error)", c->peer, m->u.error.text, proto_err_name(m->u.error.code));
		job_log(c, "ended by the master's error");
		c->state = ST_CLOSING;
		c->deadline = net_now();
		c->logged = true;
		return;
	}
	if (m->type == MSG_HEARTBEAT)
		return; /* the master is alive: last_rx is updated per frame */
	if (m->type == MSG_BYE && c->state != ST_CLOSING)
		goto bye; /* in any state: a master whose render ended before its job started */
	switch (c->state) {
	case ST_HELLO: {
		if (m->type != MSG_HELLO)
			break;
		const struct proto_hello *h = &m->u.hello;
		uint32_t mine = opt.fault == FAULT_PROTO_VERSION ? PROTO_VERSION + 1 : PROTO_VERSION;
		if (h->version != mine || m->frame_version != mine) {
			conn_fail(c, PERR_VERSION, "protocol version mismatch: master speaks version %u, worker speaks %u",
				  h->version, mine);
			return;
		}
		if (h->role != ROLE_MASTER) {
			conn_fail(c, PERR_PROTOCOL, "peer is not a master");
			return;
		}
		if (strcmp(h->build, proto_build_id()) != 0) {
			conn_fail(c, PERR_BUILD, "core build mismatch: master runs '%s', worker runs '%s'", h->build,
				  proto_build_id());
			return;
		}
		if (!h->secret != !opt.secret) {
			conn_fail(c, PERR_AUTH, opt.secret ? "this worker requires a shared secret (--secret-file)"
							   : "this worker has no shared secret but the master has one");
			return;
		}
		memcpy(c->peer_nonce, h->nonce, PROTO_NONCE_BYTES);
		double hb = h->heartbeat_ms / 1000.0;
		c->hb_interval = hb < 0.05 ? 0.05 : hb > 10 ? 10 : hb;
		if (opt.secret) {
			c->state = ST_AUTH;
		} else {
			c->state = ST_OFFER;
			proto_conn_set_limit(c->pc, PROTO_MASTER_FRAME_MAX);
		}
		return;
	}
	case ST_AUTH: {
		if (m->type != MSG_AUTH)
			break;
		uint8_t want[PROTO_MAC_BYTES];
		proto_auth_mac(opt.secret, opt.secret_len, ROLE_MASTER, c->peer_nonce, c->nonce, want);
		if (!proto_mac_equal(want, m->u.mac, PROTO_MAC_BYTES)) {
			conn_fail(c, PERR_AUTH, "authentication failed: the master's secret differs from this worker's");
			return;
		}
		proto_auth_mac(opt.secret, opt.secret_len, ROLE_WORKER, c->peer_nonce, c->nonce, want);
		proto_send_auth(c->pc, want);
		c->state = ST_OFFER;
		/* authenticated: scene chunks may come now (nothing longer ever does) */
		proto_conn_set_limit(c->pc, PROTO_MASTER_FRAME_MAX);
		return;
	}
	case ST_OFFER:
		if (m->type != MSG_SCENE_OFFER)
			break;
		on_offer(c, m);
		return;
	case ST_RECV:
		if (m->type != MSG_SCENE_DATA)
			break;
		on_data(c, m);
		return;
	case ST_BUILD:
		if (m->type == MSG_BYE)
			goto bye;
		break;
	case ST_READY:
		if (m->type == MSG_TILE) {
			on_tile(c, m);
			return;
		}
		if (m->type == MSG_CANCEL) {
			on_cancel(c, m->u.cancel_id);
			return;
		}
		if (m->type == MSG_BYE)
			goto bye;
		break;
	case ST_CLOSING:
		return;
	}
	conn_fail(c, PERR_PROTOCOL, "unexpected %s message", proto_type_name(m->type));
	return;
bye:
	job_log(c, "done"); /* (no line for a job that never started) */
	c->logged = true;
	c->state = ST_CLOSING;
	c->deadline = net_now() + 2.0;
}

/* Reads and handles whatever connection c has; returns -1 when it must close now. */
static int conn_input(struct wk_conn *c)
{
	const char *why = NULL;
	int r = proto_conn_read(c->pc, &why);
	if (r < 0) {
		if (c->state != ST_CLOSING) {
			job_log(c, why ? why : "connection lost");
			if (!c->logged)
				wk_log("%s: %s", c->peer, why ? why : "connection lost");
		}
		return -1;
	}
	struct proto_msg m;
	int code;
	while (c->state != ST_CLOSING) {
		int k = proto_conn_next(c->pc, &m, &code, &why);
		if (k == 0)
			break;
		if (k < 0) {
			conn_fail(c, code, "%s", why);
			break;
		}
		/* only whole frames count as a sign of life: a peer trickling
		 * bytes of a frame it never finishes still times out */
		c->last_rx = net_now();
		on_message(c, &m);
	}
	return 0;
}

/* Results and builds finished by the tracer threads. */
static void drain_done(void)
{
	char b[64];
	while (read(wake_pipe[0], b, sizeof b) > 0)
		;
	pthread_mutex_lock(&pool.mu);
	struct wk_done *d = pool.done;
	pool.done = pool.done_tail = NULL;
	pthread_mutex_unlock(&pool.mu);
	while (d) {
		struct wk_done *next = d->next;
		if (d->kind == 1) {
			for (size_t i = 0; i < n_conns; i++) {
				struct wk_conn *c = conns[i];
				if (c->state == ST_BUILD && c->entry == d->entry)
					use_entry(c, d->entry);
			}
			cache_trim(&pool.mu); /* failed builds leave the cache */
		} else {
			struct wk_conn *c = d->job->conn;
			if (c && c->state == ST_READY) {
				struct proto_tile t = d->tile;
				uint32_t crc = d->crc;
				if (opt.fault == FAULT_BAD_CHECKSUM)
					crc ^= 0x5a5a5a5au;
				if (opt.fault == FAULT_WRONG_SIZE && t.w > 1)
					t.w -= 1; /* pixels then match the smaller rect */
				proto_send_result_timed(c->pc, &t, d->pixels, crc, d->trace_us);
				c->tiles_done++;
			}
			free(d->pixels);
			pthread_mutex_lock(&pool.mu);
			/* the bytes now sit in the output queue (or are gone) */
			d->job->traced_bytes -= (size_t)d->tile.w * d->tile.h * 3;
			if (c)
				d->job->outq_bytes = proto_conn_outq(c->pc);
			job_unref_locked(d->job);
			pthread_mutex_unlock(&pool.mu);
		}
		free(d);
		d = next;
	}
}

/* while out of file descriptors the listening socket is not polled until then
 * (it stays readable, and poll() would return at once for ever: a busy loop) */
static double accept_paused_until;

static void accept_all(int lfd)
{
	for (;;) {
		char peer[96];
		int fd = net_accept(lfd, peer, sizeof peer);
		if (fd < 0) {
			if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
				if (accept_paused_until == 0)
					wk_log("cannot accept: %s; pausing accepts", strerror(errno));
				accept_paused_until = net_now() + WK_ACCEPT_PAUSE_S;
			} else {
				accept_paused_until = 0;
			}
			return;
		}
		accept_paused_until = 0;
		struct wk_conn *c = calloc(1, sizeof *c);
		struct proto_conn *pc = c ? proto_conn_new(fd) : NULL;
		if (!pc || n_conns >= WK_MAX_CONNS) {
			if (pc) {
				proto_send_error(pc, PERR_LIMIT, "worker serves %d connections already", WK_MAX_CONNS);
				proto_conn_flush(pc);
				proto_conn_free(pc);
			} else {
				close(fd);
			}
			free(c);
			wk_log("%s: refused: too many connections or out of memory", peer);
			continue;
		}
		c->pc = pc;
		/* until the handshake is done, no frame longer than a HELLO */
		proto_conn_set_limit(pc, LIM_HANDSHAKE_PAYLOAD);
		snprintf(c->peer, sizeof c->peer, "%s", peer);
		c->state = ST_HELLO;
		c->last_rx = c->started = net_now();
		c->deadline = c->started + opt.handshake_s;
		c->hb_interval = 1.0;
		if (proto_random(c->nonce, sizeof c->nonce) < 0) {
			proto_conn_free(pc);
			free(c);
			wk_log("%s: refused: no random source", peer);
			continue;
		}
		send_hello(c);
		conns[n_conns++] = c;
	}
}

static bool job_failed(struct wk_job *j)
{
	pthread_mutex_lock(&pool.mu);
	bool f = j->failed;
	pthread_mutex_unlock(&pool.mu);
	return f;
}

/* Timers: handshake deadlines, idle masters, heartbeats, closing connections. */
static void tick(void)
{
	double now = net_now();
	for (size_t i = 0; i < n_conns;) {
		struct wk_conn *c = conns[i];
		bool drop = false;
		if (c->state == ST_CLOSING) {
			drop = proto_conn_outq(c->pc) == 0 || now > c->deadline;
		} else if (c->state < ST_RECV && now > c->deadline) {
			conn_fail(c, PERR_TIMEOUT, "handshake took longer than %.1f s", opt.handshake_s);
		} else if (c->state >= ST_OFFER) {
			/* heartbeats from the offer on: a long scene transfer or build
			 * must not look like a dead worker to the master */
			double idle = 6 * c->hb_interval + 5;
			if (idle < WK_IDLE_MIN_S)
				idle = WK_IDLE_MIN_S;
			if (now - c->last_rx > idle) {
				job_log(c, "master silent: dropped");
				conn_fail(c, PERR_TIMEOUT, "master silent for %.0f s", idle);
			} else if (now - c->last_hb >= c->hb_interval) {
				uint32_t queued = 0;
				if (c->job) {
					pthread_mutex_lock(&pool.mu);
					queued = (uint32_t)(c->job->len - c->job->head) + c->job->running;
					pthread_mutex_unlock(&pool.mu);
				}
				proto_send_heartbeat(c->pc, c->tiles_done, queued);
				c->last_hb = now;
			}
		}
		if (!drop && proto_conn_flush(c->pc) < 0 && c->state != ST_CLOSING) {
			job_log(c, "connection lost while sending");
			drop = true;
		} else if (!drop && c->state == ST_CLOSING && proto_conn_outq(c->pc) == 0) {
			drop = true;
		} else if (!drop && c->job && job_failed(c->job)) {
			conn_fail(c, PERR_INTERNAL, "out of memory tracing a tile");
		} else if (!drop && c->job) {
			/* back-pressure: the tracers see how much of this job's
			 * output waits; wake them when a paused job has room again */
			size_t q = proto_conn_outq(c->pc);
			pthread_mutex_lock(&pool.mu);
			struct wk_job *j = c->job;
			j->outq_bytes = q;
			if (j->paused && j->traced_bytes + q <= PROTO_OUT_HIGH_WATER) {
				j->paused = false;
				pthread_cond_broadcast(&pool.cv);
			}
			pthread_mutex_unlock(&pool.mu);
		}
		if (drop) {
			conn_close(i);
			cache_trim(&pool.mu); /* entries it used may be over the budget now */
		} else {
			i++;
		}
	}
}

static void usage(FILE *f)
{
	fprintf(f,
		"Usage: portray-worker [OPTION]...\n"
		"Render tiles for portray-master: a daemon serving several masters at once.\n"
		"\n"
		"      --listen ADDR:PORT  where to listen (default 127.0.0.1:%d; port 0 = any)\n"
		"  -j, --threads N         tracing threads (default: all cores)\n"
		"      --secret-file F     shared secret: masters must prove they know it\n"
		"      --port-file F       write the port listened on to F (useful with port 0)\n"
		"      --cache-mb N        scene cache budget in MiB of scene data (default %d)\n"
		"  -h, --help              show this help\n"
		"  -V, --version           show the version\n"
		"\n"
		"Logs a line when a job starts and one when it ends, on stderr.\n"
		"SIGTERM or SIGINT ends it cleanly.\n",
		PROTO_DEFAULT_PORT, WK_CACHE_MB_DEFAULT);
}

static int write_port_file(const char *path, int port)
{
	char tmp[4096];
	snprintf(tmp, sizeof tmp, "%s.tmp", path);
	FILE *f = fopen(tmp, "w");
	if (!f)
		return -1;
	fprintf(f, "%d\n", port);
	if (fclose(f) != 0 || rename(tmp, path) != 0)
		return -1;
	return 0;
}

enum { OPT_LISTEN = 256, OPT_SECRET, OPT_PORTFILE, OPT_CACHE, OPT_FAULT, OPT_DELAY, OPT_HANDSHAKE };

int main(int argc, char **argv)
{
	static const struct option longopts[] = {
		{ "listen", required_argument, NULL, OPT_LISTEN },
		{ "threads", required_argument, NULL, 'j' },
		{ "secret-file", required_argument, NULL, OPT_SECRET },
		{ "port-file", required_argument, NULL, OPT_PORTFILE },
		{ "cache-mb", required_argument, NULL, OPT_CACHE },
		{ "test-fault", required_argument, NULL, OPT_FAULT }, /* hidden: for tests */
		{ "test-delay-ms", required_argument, NULL, OPT_DELAY }, /* hidden: for tests */
		{ "test-handshake-ms", required_argument, NULL, OPT_HANDSHAKE }, /* hidden: for tests */
		{ "help", no_argument, NULL, 'h' },
		{ "version", no_argument, NULL, 'V' },
		{ NULL, 0, NULL, 0 },
	};
	const char *listen_at = "127.0.0.1:7411", *secret_file = NULL, *port_file = NULL;
	long cache_mb = WK_CACHE_MB_DEFAULT;
	int c;
	char *end;
	while ((c = getopt_long(argc, argv, "j:hV", longopts, NULL)) != -1) {
		switch (c) {
		case OPT_LISTEN: listen_at = optarg; break;
		case 'j':
			opt.threads = (int)strtol(optarg, &end, 10);
			if (*end || opt.threads < 0 || opt.threads > 4096) {
				fprintf(stderr, "portray-worker: -j wants a number 0..4096, not '%s'\n", optarg);
				return 64;
			}
			break;
		case OPT_SECRET: secret_file = optarg; break;
		case OPT_PORTFILE: port_file = optarg; break;
		case OPT_CACHE:
			cache_mb = strtol(optarg, &end, 10);
			if (*end || cache_mb < 1 || cache_mb > 1024 * 1024) {
				fprintf(stderr, "portray-worker: --cache-mb wants a number 1..1048576, not '%s'\n", optarg);
				return 64;
			}
			break;
		case OPT_FAULT:
			if (strcmp(optarg, "bad-checksum") == 0)
				opt.fault = FAULT_BAD_CHECKSUM;
			else if (strcmp(optarg, "wrong-size") == 0)
				opt.fault = FAULT_WRONG_SIZE;
			else if (strcmp(optarg, "proto-version") == 0)
				opt.fault = FAULT_PROTO_VERSION;
			else if (strcmp(optarg, "build-id") == 0)
				opt.fault = FAULT_BUILD;
			else if (strcmp(optarg, "black") == 0)
				opt.fault = FAULT_BLACK;
			else if (strcmp(optarg, "trace-fail") == 0)
				opt.fault = FAULT_TRACE_FAIL;
			else if (strcmp(optarg, "lie") == 0)
				opt.fault = FAULT_LIE;
			else if (strcmp(optarg, "hang-tile") == 0)
				opt.fault = FAULT_HANG_TILE;
			else {
				fprintf(stderr, "portray-worker: unknown --test-fault '%s'\n", optarg);
				return 64;
			}
			break;
		case OPT_DELAY:
			opt.delay_ms = (int)strtol(optarg, &end, 10);
			if (*end || opt.delay_ms < 0 || opt.delay_ms > 60000) {
				fprintf(stderr, "portray-worker: --test-delay-ms wants 0..60000\n");
				return 64;
			}
			break;
		case OPT_HANDSHAKE: {
			long ms = strtol(optarg, &end, 10);
			if (*end || ms < 1 || ms > 600000) {
				fprintf(stderr, "portray-worker: --test-handshake-ms wants 1..600000\n");
				return 64;
			}
			opt.handshake_s = ms / 1000.0;
			break;
		}
		case 'h': usage(stdout); return 0;
		case 'V': printf("portray-worker %s (protocol %u, %s)\n", PORTRAY_VERSION, PROTO_VERSION, proto_build_id()); return 0;
		default: usage(stderr); return 64;
		}
	}
	if (optind != argc) {
		fprintf(stderr, "portray-worker: unexpected argument '%s'\n", argv[optind]);
		usage(stderr);
		return 64;
	}
	if (opt.threads == 0)
		opt.threads = render_ncpus();
	if (opt.handshake_s == 0)
		opt.handshake_s = WK_HANDSHAKE_S;
	opt.cache_bytes = (uint64_t)cache_mb << 20;
	char err[512], warn[512];
	if (secret_file &&
	    proto_read_secret(secret_file, &opt.secret, &opt.secret_len, err, sizeof err, warn, sizeof warn) < 0) {
		fprintf(stderr, "portray-worker: %s\n", err);
		return 64;
	}
	if (secret_file && warn[0])
		fprintf(stderr, "portray-worker: warning: --secret-file %s\n", warn);
	char host[NET_HOST_LEN], port[NET_PORT_LEN];
	if (net_parse_hostport(listen_at, host, port, err, sizeof err) < 0) {
		fprintf(stderr, "portray-worker: --listen: %s\n", err);
		return 64;
	}
	int lfd = net_listen(host, port, err, sizeof err);
	if (lfd < 0) {
		fprintf(stderr, "portray-worker: %s\n", err);
		return 69;
	}
	int bound = net_local_port(lfd);
	if (port_file && write_port_file(port_file, bound) < 0) {
		fprintf(stderr, "portray-worker: cannot write %s: %s\n", port_file, strerror(errno));
		return 73;
	}
	if (pipe(wake_pipe) < 0) {
		perror("portray-worker: pipe");
		return 71;
	}
	for (int i = 0; i < 2; i++) {
		int fl = fcntl(wake_pipe[i], F_GETFL);
		fcntl(wake_pipe[i], F_SETFL, fl | O_NONBLOCK);
	}
	struct sigaction sa;
	memset(&sa, 0, sizeof sa);
	sa.sa_handler = on_signal;
	sigaction(SIGTERM, &sa, NULL);
	sigaction(SIGINT, &sa, NULL);
	signal(SIGPIPE, SIG_IGN);

	pthread_t *tids = calloc((size_t)opt.threads, sizeof *tids);
	int started = 0;
	for (int i = 0; tids && i < opt.threads; i++)
		if (pthread_create(&tids[i], NULL, tracer, NULL) == 0)
			started++;
	if (started == 0) {
		fprintf(stderr, "portray-worker: cannot start tracer threads\n");
		return 71;
	}
	wk_log("listening on %s:%d, %d threads, protocol %u, %s%s", host, bound, started, PROTO_VERSION,
	       proto_build_id(), opt.secret ? ", secret required" : "");

	struct pollfd *pfd = calloc(WK_MAX_CONNS + 2, sizeof *pfd);
	while (!stop_flag && pfd) {
		size_t n = 0;
		bool accepting = net_now() >= accept_paused_until;
		pfd[n++] = (struct pollfd){ .fd = accepting ? lfd : -1, .events = POLLIN };
		pfd[n++] = (struct pollfd){ .fd = wake_pipe[0], .events = POLLIN };
		for (size_t i = 0; i < n_conns; i++) {
			short ev = conns[i]->state == ST_CLOSING ? 0 : POLLIN;
			if (proto_conn_outq(conns[i]->pc))
				ev |= POLLOUT;
			pfd[n++] = (struct pollfd){ .fd = proto_conn_fd(conns[i]->pc), .events = ev };
		}
		int k = poll(pfd, (nfds_t)n, 50);
		if (k < 0 && errno != EINTR)
			break;
		if (k > 0 && (pfd[1].revents & POLLIN))
			drain_done();
		/* inputs first: connections closing now are removed by tick() below,
		 * so indices stay those of this poll round */
		size_t nc = n_conns;
		for (size_t i = 0; k > 0 && i < nc; i++) {
			struct wk_conn *cn = conns[i];
			if (pfd[i + 2].revents & (POLLIN | POLLHUP | POLLERR)) {
				if (cn->state == ST_CLOSING || conn_input(cn) < 0) {
					cn->state = ST_CLOSING;
					cn->deadline = 0;
					cn->logged = true;
				}
			}
		}
		if (k > 0 && (pfd[0].revents & POLLIN))
			accept_all(lfd);
		tick();
	}
	wk_log("shutting down (%zu connections)", n_conns);
	for (size_t i = 0; i < n_conns; i++) {
		job_log(conns[i], "cut off: worker shutting down");
		proto_send_error(conns[i]->pc, PERR_SHUTDOWN, "worker shutting down");
		proto_conn_flush(conns[i]->pc);
	}
	pthread_mutex_lock(&pool.mu);
	pool.quit = 1;
	atomic_store(&pool.cancel_all, 1);
	pthread_cond_broadcast(&pool.cv);
	pthread_mutex_unlock(&pool.mu);
	for (int i = 0; i < opt.threads; i++)
		if (tids[i])
			pthread_join(tids[i], NULL);
	while (n_conns)
		conn_close(n_conns - 1);
	drain_done();
	while (cache) {
		struct wk_entry *e = cache;
		cache = e->next;
		entry_free(e);
	}
	free(pool.jobs);
	free(pool.builds);
	free(pfd);
	free(tids);
	free(opt.secret);
	close(lfd);
	return 0;
}
