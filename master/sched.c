/*
 * sched.c - the master's tile scheduler (sched.h).
 *
 * Pending tiles wait in a ring (lost tiles go back to its front: they are
 * the oldest work); audits in a second ring. Every public function takes the
 * one mutex; the *_locked helpers expect it held. The local threads sleep on
 * the condition variable; the event loop is told through the wake callback.
 */
#include "master/sched.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

struct ftile {
	uint8_t done;
	uint8_t queued;        /* in the pending queue */
	uint8_t audit_queued;  /* in the audit queue */
	uint8_t taken;         /* handed out before: taking it again is a redispatch */
	uint8_t changed;       /* in the change list (sched_changes) */
	uint16_t holder[2];    /* who traces it now (SCHED_NONE = free slot) */
	uint16_t by;           /* who wrote the stored pixels (when done) */
	uint16_t claim_by;     /* who delivered claim */
	uint8_t *claim;        /* a worker's pixels awaiting their audit (owned), or NULL */
	double sent;           /* when first handed out (for "oldest outstanding") */
};

struct trust {
	struct sched_trust t;
	bool reported;
};

struct sched {
	pthread_mutex_t mu;
	pthread_cond_t cv;
	struct tiling tg;
	struct ftile *t;
	uint32_t *queue;       /* pending tile ids: ring of n */
	uint32_t q_head, q_len;
	uint32_t *order;       /* tiles handed out, sorted by (sent, id): the tail's duplicates */
	uint32_t n_order, order_head; /* order[0..order_head) are done (distrust resets it) */
	uint32_t *audits;      /* tile ids with a claim to re-render: ring of n */
	uint32_t a_head, a_len;
	uint32_t *changes;     /* tiles stored or undone since sched_changes last ran: ring of n, or NULL */
	uint32_t c_head, c_len;
	double c_woke;         /* when a change last woke the loop (CLOCK_MONOTONIC s) */
	struct trust *trust;   /* per worker */
	uint32_t n_workers;
	struct sched_stats st;
	uint8_t *image;
	uint32_t bpp;          /* bytes a pixel */
	double audit;
	uint64_t salt;
	double now;            /* the latest time sched_take was given: local takes
				* are stamped with it (sched_local_take has no clock) */
	atomic_int stop;
	void (*wake)(void *);
	void *wake_arg;
};

static void wake_loop(struct sched *s)
{
	if (s->wake)
		s->wake(s->wake_arg);
}

static double mono_now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Tile id was stored or undone: an observer may want to know (sched_changes).
 * The list turning non-empty wakes the loop, but at most once every
 * SCHED_CHANGE_WAKE_S: a wake per tile cost a small render 12% of its time
 * in thread switches (1,200 tiles of 32x32 at 1280x960); in between, the
 * loop's observe timer drains the list (sched.h). */
static void changed_locked(struct sched *s, uint32_t id)
{
	struct ftile *t = &s->t[id];
	if (!s->changes || t->changed)
		return;
	t->changed = 1;
	s->changes[(s->c_head + s->c_len) % s->tg.n] = id;
	if (s->c_len++ == 0) {
		double now = mono_now();
		if (now - s->c_woke >= SCHED_CHANGE_WAKE_S) {
			s->c_woke = now;
			wake_loop(s);
		}
	}
}

static bool holds(const struct ftile *t, uint16_t who) { return t->holder[0] == who || t->holder[1] == who; }

static int holder_count(const struct ftile *t)
{
	return (t->holder[0] != SCHED_NONE) + (t->holder[1] != SCHED_NONE);
}

static void holder_add(struct ftile *t, uint16_t who)
{
	if (t->holder[0] == SCHED_NONE)
		t->holder[0] = who;
	else
		t->holder[1] = who;
}

static void holder_del(struct ftile *t, uint16_t who)
{
	if (t->holder[0] == who)
		t->holder[0] = SCHED_NONE;
	else if (t->holder[1] == who)
		t->holder[1] = SCHED_NONE;
}

struct sched *sched_new(const struct tiling *tg, uint32_t bpp, uint32_t n_workers, uint8_t *image, double audit,
			uint64_t salt, void (*wake)(void *), void *wake_arg)
{
	if (n_workers > SCHED_MAX_WORKERS || tg->n == 0 || bpp == 0)
		return NULL;
	struct sched *s = calloc(1, sizeof *s);
	if (!s)
		return NULL;
	s->tg = *tg;
	pthread_mutex_init(&s->mu, NULL); /* first: sched_free destroys them whatever failed below */
	pthread_cond_init(&s->cv, NULL);
	uint32_t n = tg->n;
	s->t = calloc(n, sizeof *s->t);
	s->queue = calloc(n, sizeof *s->queue);
	s->order = calloc(n, sizeof *s->order);
	s->audits = calloc(n, sizeof *s->audits);
	s->trust = calloc(n_workers ? n_workers : 1, sizeof *s->trust);
	if (!s->t || !s->queue || !s->order || !s->audits || !s->trust) {
		sched_free(s);
		return NULL;
	}
	for (uint32_t i = 0; i < n; i++) {
		s->t[i].holder[0] = s->t[i].holder[1] = s->t[i].by = SCHED_NONE;
		s->t[i].queued = 1;
		s->queue[i] = i;
	}
	s->q_len = n;
	s->st.n = n;
	s->n_workers = n_workers;
	s->image = image;
	s->bpp = bpp;
	s->audit = audit;
	s->salt = salt;
	s->wake = wake;
	s->wake_arg = wake_arg;
	atomic_init(&s->stop, 0);
	return s;
}

void sched_free(struct sched *s)
{
	if (!s)
		return;
	for (uint32_t i = 0; s->t && i < s->tg.n; i++)
		free(s->t[i].claim);
	pthread_mutex_destroy(&s->mu);
	pthread_cond_destroy(&s->cv);
	free(s->t);
	free(s->queue);
	free(s->order);
	free(s->audits);
	free(s->changes);
	free(s->trust);
	free(s);
}

struct tile_rect sched_rect(const struct sched *s, uint32_t id) { return tiling_rect(&s->tg, id); }

/* ---- the queue ---- */

/* Files tile id, handed out for the first time, into the order of hand-out
 * times (from the end: times come nearly in order). */
static void order_add(struct sched *s, uint32_t id)
{
	const struct ftile *t = &s->t[id];
	uint32_t k = s->n_order++;
	while (k > s->order_head) {
		const struct ftile *p = &s->t[s->order[k - 1]];
		if (p->sent < t->sent || (p->sent == t->sent && s->order[k - 1] < id))
			break;
		s->order[k] = s->order[k - 1];
		k--;
	}
	s->order[k] = id;
}

static uint32_t take_locked(struct sched *s, uint16_t who, bool dup_ok, double now)
{
	while (s->q_len) {
		uint32_t id = s->queue[s->q_head];
		s->q_head = (s->q_head + 1) % s->tg.n;
		s->q_len--;
		struct ftile *t = &s->t[id];
		t->queued = 0;
		if (t->done || holds(t, who))
			continue;
		if (t->taken) {
			s->st.redispatched++;
		} else {
			t->taken = 1;
			t->sent = now;
			order_add(s, id);
		}
		holder_add(t, who);
		return id;
	}
	if (!dup_ok)
		return SCHED_NO_TILE;
	/* the tail: the oldest tile that one other taker holds. Done tiles at
	 * the front of the order are passed for good, so the search costs the
	 * outstanding tiles, not the image's */
	while (s->order_head < s->n_order && s->t[s->order[s->order_head]].done)
		s->order_head++;
	for (uint32_t k = s->order_head; k < s->n_order; k++) {
		uint32_t id = s->order[k];
		struct ftile *t = &s->t[id];
		if (t->done || t->claim || holder_count(t) != 1 || holds(t, who))
			continue;
		holder_add(t, who);
		s->st.duplicates++;
		return id;
	}
	return SCHED_NO_TILE;
}

/* Back to the front of the queue when not done, unheld, with no claim
 * awaiting audit and not queued already. */
static void requeue_locked(struct sched *s, uint32_t id)
{
	struct ftile *t = &s->t[id];
	if (!t->done && holder_count(t) == 0 && !t->claim && !t->queued) {
		s->q_head = (s->q_head + s->tg.n - 1) % s->tg.n;
		s->queue[s->q_head] = id;
		s->q_len++;
		t->queued = 1;
		pthread_cond_broadcast(&s->cv);
	}
}

static void store_locked(struct sched *s, uint32_t id, uint16_t who, const uint8_t *rgb)
{
	struct ftile *t = &s->t[id];
	struct tile_rect r = tiling_rect(&s->tg, id);
	size_t bpp = s->bpp;
	for (uint32_t y = 0; y < r.h; y++)
		memcpy(s->image + (((size_t)(r.y + y) * s->tg.w) + r.x) * bpp, rgb + (size_t)y * r.w * bpp,
		       (size_t)r.w * bpp);
	t->done = 1;
	t->by = who;
	s->st.done++;
	changed_locked(s, id);
	if (s->st.done == s->tg.n) {
		atomic_store(&s->stop, 1);
		pthread_cond_broadcast(&s->cv);
		wake_loop(s);
	}
}

/* who failed the audit of tile: every tile it delivered goes back to the
 * queue (stored ones undone, claims discarded); the loop drops it. */
static void distrust_locked(struct sched *s, uint16_t who, uint32_t tile)
{
	if (who >= s->n_workers || s->trust[who].t.caught)
		return;
	struct sched_trust *tr = &s->trust[who].t;
	tr->caught = true;
	s->order_head = 0; /* tiles it delivered come undone, wherever they are in the order */
	tr->tile = tile;
	tr->requeued = 1; /* the tile whose audit failed: the audit's pixels replace it */
	for (uint32_t i = 0; i < s->tg.n; i++) {
		struct ftile *t = &s->t[i];
		if (t->done && t->by == who) {
			t->done = 0;
			t->by = SCHED_NONE;
			s->st.done--;
			changed_locked(s, i);
			tr->requeued++;
			requeue_locked(s, i);
		} else if (t->claim && t->claim_by == who) {
			free(t->claim);
			t->claim = NULL;
			tr->requeued++;
			requeue_locked(s, i);
		}
	}
	pthread_cond_broadcast(&s->cv);
	wake_loop(s);
}

/* Pixels from the local renderer: settle a claim awaiting its audit (a
 * mismatch distrusts the claimant), then store them unless done already. */
static bool trusted_locked(struct sched *s, uint32_t id, const uint8_t *rgb)
{
	struct ftile *t = &s->t[id];
	if (t->claim) {
		uint8_t *claim = t->claim;
		struct tile_rect r = tiling_rect(&s->tg, id);
		t->claim = NULL;
		s->st.audits++;
		if (memcmp(claim, rgb, (size_t)r.w * r.h * s->bpp) != 0) { /* bit-exact, floats too */
			s->st.audit_failed++;
			distrust_locked(s, t->claim_by, id);
		}
		free(claim);
	}
	if (t->done)
		return false;
	store_locked(s, id, SCHED_LOCAL, rgb);
	return true;
}

/* Queues the audit of tile id's claim unless it is queued already. */
static void audit_queue_locked(struct sched *s, uint32_t id)
{
	struct ftile *t = &s->t[id];
	if (!t->audit_queued) {
		s->audits[(s->a_head + s->a_len) % s->tg.n] = id;
		s->a_len++;
		t->audit_queued = 1;
		pthread_cond_broadcast(&s->cv);
	}
}

/* Holds who's pixels as a claim (copied) and queues the audit; false when
 * out of memory (nothing changed). */
static bool claim_locked(struct sched *s, uint32_t id, uint16_t who, const uint8_t *rgb)
{
	struct ftile *t = &s->t[id];
	struct tile_rect r = tiling_rect(&s->tg, id);
	size_t n = (size_t)r.w * r.h * s->bpp;
	uint8_t *copy = malloc(n);
	if (!copy)
		return false;
	memcpy(copy, rgb, n);
	holder_del(t, who);
	t->claim = copy;
	t->claim_by = who;
	audit_queue_locked(s, id);
	return true;
}

static uint32_t take_audit_locked(struct sched *s)
{
	while (s->a_len) {
		uint32_t id = s->audits[s->a_head];
		s->a_head = (s->a_head + 1) % s->tg.n;
		s->a_len--;
		struct ftile *t = &s->t[id];
		t->audit_queued = 0;
		/* settled meanwhile, or a local thread traces it anyway (its result settles the claim) */
		if (t->claim && !t->done && !holds(t, SCHED_LOCAL))
			return id;
	}
	return SCHED_NO_TILE;
}

/* ---- public: workers ---- */

uint32_t sched_take(struct sched *s, uint16_t who, bool dup_ok, double now)
{
	pthread_mutex_lock(&s->mu);
	uint32_t id = SCHED_NO_TILE;
	if (now > s->now)
		s->now = now;
	if (!atomic_load(&s->stop) && !(who < s->n_workers && s->trust[who].t.caught))
		id = take_locked(s, who, dup_ok, now);
	pthread_mutex_unlock(&s->mu);
	return id;
}

void sched_release(struct sched *s, uint32_t id, uint16_t who)
{
	pthread_mutex_lock(&s->mu);
	holder_del(&s->t[id], who);
	requeue_locked(s, id);
	pthread_mutex_unlock(&s->mu);
}

/* splitmix64's finaliser: spreads the bits of x evenly */
static uint64_t mix64(uint64_t x)
{
	x ^= x >> 30;
	x *= 0xbf58476d1ce4e5b9ULL;
	x ^= x >> 27;
	x *= 0x94d049bb133111ebULL;
	x ^= x >> 31;
	return x;
}

bool sched_audit_due(const struct sched *s, uint16_t who, uint32_t delivered, uint32_t id)
{
	if (s->audit <= 0)
		return false;
	if (delivered < SCHED_AUDIT_PROBATION)
		return true;
	/* depends on neither timing nor anything the worker can see */
	uint64_t h = mix64(s->salt ^ mix64(((uint64_t)id << 16) ^ who));
	return (double)(h >> 11) * 0x1p-53 < s->audit;
}

enum sched_outcome sched_result(struct sched *s, uint32_t id, uint16_t who, const uint8_t *rgb, bool audit,
				uint16_t *cancel_other)
{
	*cancel_other = SCHED_NONE;
	pthread_mutex_lock(&s->mu);
	struct ftile *t = &s->t[id];
	uint16_t other = t->holder[0] == who ? t->holder[1] : t->holder[0];
	bool used;
	if (who < s->n_workers && s->trust[who].t.caught) { /* nothing it sends is used */
		holder_del(t, who);
		requeue_locked(s, id);
		used = false;
	} else if (!t->done && !t->claim && audit && claim_locked(s, id, who, rgb)) {
		used = true; /* held back until the local render agrees */
	} else {
		/* not sampled, a duplicate, or no memory to hold a claim: stored
		 * as it is (undone if the worker is caught later) */
		holder_del(t, who);
		if (t->done || t->claim) {
			s->st.dup_wasted++;
			used = false;
		} else {
			store_locked(s, id, who, rgb);
			used = true;
		}
	}
	if (used && other < s->n_workers) {
		holder_del(t, other);
		*cancel_other = other;
	}
	pthread_mutex_unlock(&s->mu);
	return used ? SCHED_USED : SCHED_WASTED;
}

bool sched_caught(struct sched *s, uint16_t who, struct sched_trust *out, bool *first)
{
	if (who >= s->n_workers)
		return false;
	pthread_mutex_lock(&s->mu);
	struct trust *tr = &s->trust[who];
	*out = tr->t;
	*first = tr->t.caught && !tr->reported;
	if (tr->t.caught)
		tr->reported = true;
	pthread_mutex_unlock(&s->mu);
	return out->caught;
}

/* ---- public: local threads ---- */

int sched_local_take(struct sched *s, bool audit_only, uint32_t *id, bool *audit)
{
	pthread_mutex_lock(&s->mu);
	while (!atomic_load(&s->stop)) {
		*audit = true;
		*id = take_audit_locked(s);
		if (*id == SCHED_NO_TILE && !audit_only) {
			*audit = false;
			*id = take_locked(s, SCHED_LOCAL, true, s->now);
		}
		if (*id != SCHED_NO_TILE) {
			pthread_mutex_unlock(&s->mu);
			return 1;
		}
		pthread_cond_wait(&s->cv, &s->mu);
	}
	pthread_mutex_unlock(&s->mu);
	return 0;
}

void sched_local_done(struct sched *s, uint32_t id, bool audit, const uint8_t *rgb, bool ok)
{
	pthread_mutex_lock(&s->mu);
	struct ftile *t = &s->t[id];
	if (audit) {
		if (ok) {
			trusted_locked(s, id, rgb);
		} else if (t->claim) {
			/* abandoned (stopping, or no buffer): a claim must not wait for ever */
			audit_queue_locked(s, id);
		}
	} else {
		holder_del(t, SCHED_LOCAL);
		if (!ok) {
			requeue_locked(s, id);
			/* a claim on it skipped its audit while this thread traced
			 * the tile anyway (take_audit_locked): it needs one now */
			if (t->claim)
				audit_queue_locked(s, id);
		} else if (trusted_locked(s, id, rgb)) {
			s->st.local_done++;
		} else {
			s->st.dup_wasted++;
		}
	}
	pthread_mutex_unlock(&s->mu);
}

/* ---- public: the render ---- */

void sched_stop(struct sched *s)
{
	pthread_mutex_lock(&s->mu);
	atomic_store(&s->stop, 1);
	pthread_cond_broadcast(&s->cv);
	pthread_mutex_unlock(&s->mu);
}

atomic_int *sched_stop_flag(struct sched *s) { return &s->stop; }

uint32_t sched_bpp(const struct sched *s) { return s->bpp; }

bool sched_finished(struct sched *s)
{
	pthread_mutex_lock(&s->mu);
	bool f = s->st.done == s->tg.n;
	pthread_mutex_unlock(&s->mu);
	return f;
}

void sched_stats(struct sched *s, struct sched_stats *out)
{
	pthread_mutex_lock(&s->mu);
	*out = s->st;
	pthread_mutex_unlock(&s->mu);
}

/* ---- observers ---- */

int sched_observe(struct sched *s)
{
	pthread_mutex_lock(&s->mu);
	if (!s->changes)
		s->changes = calloc(s->tg.n, sizeof *s->changes);
	int rc = s->changes ? 0 : -1;
	pthread_mutex_unlock(&s->mu);
	return rc;
}

uint32_t sched_changes(struct sched *s, uint32_t *ids, uint32_t max)
{
	pthread_mutex_lock(&s->mu);
	uint32_t n = 0;
	for (; n < max && s->c_len > 0; n++) {
		ids[n] = s->changes[s->c_head];
		s->t[ids[n]].changed = 0;
		s->c_head = (s->c_head + 1) % s->tg.n;
		s->c_len--;
	}
	pthread_mutex_unlock(&s->mu);
	return n;
}

bool sched_tile_pixels(struct sched *s, uint32_t id, uint8_t *out)
{
	pthread_mutex_lock(&s->mu);
	bool done = s->t[id].done;
	if (done) {
		struct tile_rect r = tiling_rect(&s->tg, id);
		size_t bpp = s->bpp;
		for (uint32_t y = 0; y < r.h; y++)
			memcpy(out + (size_t)y * r.w * bpp, s->image + (((size_t)(r.y + y) * s->tg.w) + r.x) * bpp,
			       (size_t)r.w * bpp);
	}
	pthread_mutex_unlock(&s->mu);
	return done;
}

int sched_preload(struct sched *s, uint32_t id, const uint8_t *rgb)
{
	pthread_mutex_lock(&s->mu);
	struct ftile *t = &s->t[id];
	int rc = -1;
	if (!t->done && t->queued && !t->taken) {
		/* it stays in the queue, where take_locked passes done tiles (taking
		 * it out would cost the queue's length for each of a journal's
		 * tiles: 65,536 tiles took 10 s) */
		store_locked(s, id, SCHED_NONE, rgb);
		rc = 0;
	}
	pthread_mutex_unlock(&s->mu);
	return rc;
}
