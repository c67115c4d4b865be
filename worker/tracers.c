/*
 * tracers.c - jobs, builds and the tracer pool's tile source (tracers.h).
 *
 * Who frees a job: whoever drops its last reference. On the event loop that
 * is done at once (the job's scene reference goes back to the cache, which
 * is the loop's); on a tracer (a cancelled tile of a job whose connection
 * is gone) the job goes on the ended list and the loop frees it when it
 * collects.
 */
#include "worker/tracers.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "proto/net.h"
#include "proto/serial.h"

static size_t tile_bytes(const struct proto_tile *t) { return proto_tile_bytes(t); }

/* Unlinks j from the round-robin when its last reference goes; true then
 * (the caller frees it, or hands it to the loop). Under the lock. */
static bool job_unref_locked(struct wk_tracers *t, struct wk_job *j)
{
	if (--j->refs > 0)
		return false;
	for (size_t i = 0; i < t->n_jobs; i++)
		if (t->jobs[i] == j) {
			t->jobs[i] = t->jobs[--t->n_jobs];
			break;
		}
	if (t->cursor >= t->n_jobs)
		t->cursor = 0;
	return true;
}

/* Frees an ended job (event loop: its scene reference goes to the cache). */
static void job_free(struct wk_tracers *t, struct wk_job *j)
{
	wk_cache_unref(t->cache, j->entry);
	free(j->q);
	free(j);
}

/* A tile of j could not be traced: its connection must end with an error
 * (never a tile dropped silently: the master would wait for it for ever).
 * Under the lock; the loop learns it from the job's fail note. */
static void job_fail_locked(struct wk_tracers *t, struct wk_job *j)
{
	if (j->failed)
		return;
	j->failed = true;
	j->refs++; /* the note's */
	j->fail_note = (struct wk_result){ .job = j };
	if (t->results_tail)
		t->results_tail->next = &j->fail_note;
	else
		t->results = &j->fail_note;
	t->results_tail = &j->fail_note;
}

/* ---- builds ---- */

/*
 * The one call that builds a renderer (so that cancellation comes to every
 * build at once): 0, -1 with err filled, or WK_BUILD_CANCELLED.
 */
static int build_renderer(const struct scene *s, struct renderer **r, struct scene_error *err, struct wk_entry *e)
{
	_Static_assert(RENDERER_CANCELLED == WK_BUILD_CANCELLED, "one value for a cancelled build");
	int rc = renderer_new_cancellable(s, r, err, &e->cancel);
	return rc == RENDERER_CANCELLED ? WK_BUILD_CANCELLED : rc ? WK_BUILD_FAILED : WK_BUILD_OK;
}

/* Decodes and builds e on a tracer thread, without the lock: fills the
 * builder's fields of e (cache.h), nothing else. */
static void build_entry(struct wk_entry *e)
{
	double t0 = net_now();
	struct scene_error err;
	struct scene *s = NULL;
	struct renderer *r = NULL;
	e->build_result = WK_BUILD_CANCELLED;
	if (atomic_load(&e->cancel))
		return;
	if (proto_scene_decode(e->bytes, e->len, &s, &err)) {
		snprintf(e->error, sizeof e->error, "%s", err.msg);
		goto fail;
	}
	if (atomic_load(&e->cancel))
		goto cancelled;
	int rc = build_renderer(s, &r, &err, e);
	if (rc == WK_BUILD_CANCELLED)
		goto cancelled;
	if (rc) {
		snprintf(e->error, sizeof e->error, "%s", err.msg);
		goto fail;
	}
	if (renderer_set_size(r, e->w, e->h)) {
		snprintf(e->error, sizeof e->error, "image size %ux%u refused", e->w, e->h);
		goto fail;
	}
	e->scene = s;
	e->r = r;
	e->build_ms = (uint32_t)((net_now() - t0) * 1000);
	e->build_result = WK_BUILD_OK;
	return;
fail:
	e->build_result = WK_BUILD_FAILED;
cancelled:
	renderer_free(r);
	scene_free(s);
}

int wk_tracers_build(struct wk_tracers *t, struct wk_entry *e)
{
	pthread_mutex_lock(&t->mu);
	if (t->n_builds == t->cap_builds) {
		size_t nc = t->cap_builds ? t->cap_builds * 2 : 8;
		struct wk_entry **p = realloc(t->builds, nc * sizeof *p);
		if (!p) {
			pthread_mutex_unlock(&t->mu);
			return -1;
		}
		t->builds = p;
		t->cap_builds = nc;
	}
	t->builds[t->n_builds++] = e;
	pthread_cond_signal(&t->cv);
	pthread_mutex_unlock(&t->mu);
	return 0;
}

/* ---- the tile source ---- */

/* The next job to take a tile from, round-robin; marks those skipped for
 * back-pressure. NULL when none has a tile for a tracer. Under the lock. */
static struct wk_job *pick_job(struct wk_tracers *t)
{
	for (size_t k = 0; k < t->n_jobs; k++) {
		size_t i = (t->cursor + k) % t->n_jobs;
		struct wk_job *j = t->jobs[i];
		if (!j->ready || j->failed || j->head == j->len || atomic_load(&j->cancel))
			continue;
		if (j->done_bytes + j->outq_bytes > PROTO_OUT_HIGH_WATER) {
			j->paused = true;
			continue;
		}
		t->cursor = (i + 1) % t->n_jobs;
		return j;
	}
	return NULL;
}

/* tile_source.take: builds first (each unblocks a whole job), then tiles
 * round-robin; waits while there is neither. */
static int tr_take(void *ctx, struct tile_work *w)
{
	struct wk_tracers *t = ctx;
	pthread_mutex_lock(&t->mu);
	while (!t->quit) {
		if (t->n_builds) {
			struct wk_entry *e = t->builds[0];
			memmove(t->builds, t->builds + 1, --t->n_builds * sizeof *t->builds);
			pthread_mutex_unlock(&t->mu);
			build_entry(e); /* slow: on this tracer, the lock free */
			pthread_mutex_lock(&t->mu);
			e->built_next = t->built;
			t->built = e;
			ev_wake(t->loop);
			continue;
		}
		struct wk_job *j = pick_job(t);
		if (!j) {
			pthread_cond_wait(&t->cv, &t->mu);
			continue;
		}
		struct proto_tile tile = j->q[j->head++];
		j->refs++; /* the tile's, until its result is released */
		j->running++;
		j->traced_bytes += tile_bytes(&tile);
		*w = (struct tile_work){ .r = j->entry->r,
					 .rect = { tile.x, tile.y, tile.w, tile.h },
					 .cancel = &j->cancel,
					 .id = tile.id,
					 .ptr = j,
					 .px = (enum render_pixel)tile.px };
		pthread_mutex_unlock(&t->mu);
		return 1;
	}
	pthread_mutex_unlock(&t->mu);
	return 0;
}

/* tile_source.done: a traced tile becomes a result on the done list (its
 * buffer taken over); an abandoned one is forgotten; a failed one fails
 * its job. */
static void tr_done(void *ctx, const struct tile_work *w, uint8_t **rgb, int ok)
{
	struct wk_tracers *t = ctx;
	struct wk_job *j = w->ptr;
	struct proto_tile tile = { (uint32_t)w->id, w->rect.x, w->rect.y, w->rect.w, w->rect.h, (uint8_t)w->px };
	size_t n = tile_bytes(&tile);
	ok = wk_fault_traced(t->faults, *rgb, ok, &j->cancel);
	struct wk_result *r = NULL;
	if (ok == 1 && (r = malloc(sizeof *r)))
		*r = (struct wk_result){ .job = j, .tile = tile, .crc = crc32_update(0, *rgb, n),
					 /* at least 1: 0 means "not measured" on the wire */
					 .trace_us = (uint32_t)(w->trace_s < 4000 ? w->trace_s * 1e6 : 4e9) + 1 };
	pthread_mutex_lock(&t->mu);
	j->running--;
	if (r && !atomic_load(&j->cancel)) {
		r->pixels = *rgb; /* the tile's reference moves to the result */
		*rgb = NULL;
		j->done_bytes += n;
		if (t->results_tail)
			t->results_tail->next = r;
		else
			t->results = r;
		t->results_tail = r;
		pthread_mutex_unlock(&t->mu);
		ev_wake(t->loop);
		return;
	}
	free(r);
	bool wake = false;
	if (ok != 0 && !atomic_load(&j->cancel)) { /* no pixels, no memory for the result */
		job_fail_locked(t, j);
		wake = true;
	}
	j->traced_bytes -= n;
	if (job_unref_locked(t, j)) {
		j->ended_next = t->ended;
		t->ended = j;
		wake = true;
	}
	pthread_mutex_unlock(&t->mu);
	if (wake)
		ev_wake(t->loop);
}

int wk_tracers_start(struct wk_tracers *t, int threads, struct ev_loop *loop, struct wk_cache *cache,
		     struct wk_faults *faults)
{
	memset(t, 0, sizeof *t);
	pthread_mutex_init(&t->mu, NULL);
	pthread_cond_init(&t->cv, NULL);
	t->loop = loop;
	t->cache = cache;
	t->faults = faults;
	t->src = (struct tile_source){ tr_take, tr_done, t };
	t->pool = tile_pool_start(threads, &t->src);
	return t->pool ? tile_pool_threads(t->pool) : 0;
}

void wk_tracers_stop(struct wk_tracers *t)
{
	pthread_mutex_lock(&t->mu);
	t->quit = true;
	for (size_t i = 0; i < t->n_jobs; i++)
		atomic_store(&t->jobs[i]->cancel, 1);
	pthread_cond_broadcast(&t->cv);
	pthread_mutex_unlock(&t->mu);
	tile_pool_join(t->pool);
	t->pool = NULL;
}

void wk_tracers_free(struct wk_tracers *t)
{
	struct wk_result *results;
	struct wk_entry *built;
	wk_tracers_collect(t, &results, &built);
	while (results) {
		struct wk_result *next = results->next;
		wk_result_release(t, results, SIZE_MAX);
		results = next;
	}
	for (; built; built = built->built_next)
		wk_cache_built(t->cache, built, built->build_result == WK_BUILD_OK);
	/* jobs still listed would be an owner's leak: the cache goes anyway */
	free(t->jobs);
	free(t->builds);
	pthread_cond_destroy(&t->cv);
	pthread_mutex_destroy(&t->mu);
}

/* ---- the event loop's side ---- */

void wk_tracers_collect(struct wk_tracers *t, struct wk_result **results, struct wk_entry **built)
{
	pthread_mutex_lock(&t->mu);
	*results = t->results;
	t->results = t->results_tail = NULL;
	struct wk_entry *b = t->built;
	t->built = NULL;
	struct wk_job *ended = t->ended;
	t->ended = NULL;
	bool quit = t->quit;
	pthread_mutex_unlock(&t->mu);
	*built = NULL;
	while (b) {
		struct wk_entry *next = b->built_next;
		/* wanted again after its cancel (cache.h): build it after all */
		if (b->build_result == WK_BUILD_CANCELLED && b->refs > 0 && !quit) {
			atomic_store(&b->cancel, 0);
			if (wk_tracers_build(t, b) == 0) {
				b = next;
				continue;
			}
			snprintf(b->error, sizeof b->error, "out of memory");
			b->build_result = WK_BUILD_FAILED;
		}
		b->built_next = *built;
		*built = b;
		b = next;
	}
	while (ended) {
		struct wk_job *next = ended->ended_next;
		job_free(t, ended);
		ended = next;
	}
}

void wk_result_release(struct wk_tracers *t, struct wk_result *r, size_t outq)
{
	struct wk_job *j = r->job;
	pthread_mutex_lock(&t->mu);
	if (r->pixels) {
		j->traced_bytes -= tile_bytes(&r->tile);
		j->done_bytes -= tile_bytes(&r->tile);
	}
	if (outq != SIZE_MAX)
		j->outq_bytes = outq;
	bool end = job_unref_locked(t, j);
	pthread_mutex_unlock(&t->mu);
	if (r != &j->fail_note) {
		free(r->pixels);
		free(r);
	}
	if (end)
		job_free(t, j);
}

struct wk_job *wk_job_new(struct wk_tracers *t, struct wk_entry *e, void *owner)
{
	struct wk_job *j = calloc(1, sizeof *j);
	if (!j)
		return NULL;
	j->entry = e;
	j->owner = owner;
	atomic_init(&j->cancel, 0);
	j->refs = 1;
	pthread_mutex_lock(&t->mu);
	if (t->n_jobs == t->cap_jobs) {
		size_t nc = t->cap_jobs ? t->cap_jobs * 2 : 16;
		struct wk_job **p = realloc(t->jobs, nc * sizeof *p);
		if (!p) {
			pthread_mutex_unlock(&t->mu);
			free(j);
			return NULL;
		}
		t->jobs = p;
		t->cap_jobs = nc;
	}
	t->jobs[t->n_jobs++] = j;
	pthread_mutex_unlock(&t->mu);
	return j;
}

void wk_job_start(struct wk_tracers *t, struct wk_job *j)
{
	pthread_mutex_lock(&t->mu);
	j->ready = true;
	if (j->head < j->len)
		pthread_cond_broadcast(&t->cv);
	pthread_mutex_unlock(&t->mu);
}

int wk_job_add_tile(struct wk_tracers *t, struct wk_job *j, const struct proto_tile *tile)
{
	int rc = 0;
	pthread_mutex_lock(&t->mu);
	if (j->len - j->head >= LIM_TILES_QUEUED) {
		rc = 1;
		goto out;
	}
	if (j->head > 0 && j->head == j->len)
		j->head = j->len = 0;
	if (j->len == j->cap) {
		if (j->head > 0) { /* room at the front: slide down */
			memmove(j->q, j->q + j->head, (j->len - j->head) * sizeof *j->q);
			j->len -= j->head;
			j->head = 0;
		} else {
			size_t nc = j->cap ? j->cap * 2 : 32;
			struct proto_tile *p = realloc(j->q, nc * sizeof *p);
			if (!p) {
				rc = -1;
				goto out;
			}
			j->q = p;
			j->cap = nc;
		}
	}
	j->q[j->len++] = *tile;
	if (j->ready)
		pthread_cond_signal(&t->cv);
out:
	pthread_mutex_unlock(&t->mu);
	return rc;
}

int wk_job_pop_tile(struct wk_tracers *t, struct wk_job *j, struct proto_tile *tile)
{
	pthread_mutex_lock(&t->mu);
	int got = j->head < j->len;
	if (got)
		*tile = j->q[j->head++];
	pthread_mutex_unlock(&t->mu);
	return got;
}

void wk_job_cancel_tiles(struct wk_tracers *t, struct wk_job *j, uint32_t id)
{
	pthread_mutex_lock(&t->mu);
	if (id == PROTO_CANCEL_ALL) {
		j->len = j->head;
	} else {
		size_t o = j->head;
		for (size_t i = j->head; i < j->len; i++)
			if (j->q[i].id != id)
				j->q[o++] = j->q[i];
		j->len = o;
	}
	pthread_mutex_unlock(&t->mu);
}

uint32_t wk_job_pending(struct wk_tracers *t, struct wk_job *j)
{
	pthread_mutex_lock(&t->mu);
	uint32_t n = (uint32_t)(j->len - j->head) + j->running;
	pthread_mutex_unlock(&t->mu);
	return n;
}

void wk_job_set_outq(struct wk_tracers *t, struct wk_job *j, size_t q)
{
	pthread_mutex_lock(&t->mu);
	j->outq_bytes = q;
	if (j->paused && j->done_bytes + q <= PROTO_OUT_HIGH_WATER) {
		j->paused = false;
		pthread_cond_broadcast(&t->cv);
	}
	pthread_mutex_unlock(&t->mu);
}

void wk_job_release(struct wk_tracers *t, struct wk_job *j)
{
	j->owner = NULL;
	pthread_mutex_lock(&t->mu);
	atomic_store(&j->cancel, 1);
	j->len = j->head; /* its queued tiles go */
	bool end = job_unref_locked(t, j);
	pthread_mutex_unlock(&t->mu);
	if (end)
		job_free(t, j);
}
