/*
 * tiles.c - the tiling and the tracer pool (tiles.h).
 */
#include "common/tiles.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Threads a pool starts at most: far more than any machine's cores, small
 * enough that a mistaken -j cannot exhaust the process. */
#define POOL_MAX_THREADS 1024

void tiling_init_region(struct tiling *tg, uint32_t w, uint32_t h, uint32_t side, uint32_t x0, uint32_t y0,
			uint32_t x1, uint32_t y1)
{
	if (side == 0)
		side = TILE_DEFAULT;
	if (side > TILE_MAX_SIDE)
		side = TILE_MAX_SIDE;
	tg->w = w;
	tg->h = h;
	tg->side = side;
	tg->x0 = x0;
	tg->y0 = y0;
	tg->x1 = x1;
	tg->y1 = y1;
	tg->nx = (x1 - x0 + side - 1) / side;
	tg->ny = (y1 - y0 + side - 1) / side;
	tg->n = tg->nx * tg->ny; /* at most 65536^2 / 1: limits.h caps images far below */
}

void tiling_init(struct tiling *tg, uint32_t w, uint32_t h, uint32_t side)
{
	tiling_init_region(tg, w, h, side, 0, 0, w, h);
}

struct tile_rect tiling_rect(const struct tiling *tg, uint32_t i)
{
	struct tile_rect r;
	r.x = tg->x0 + (i % tg->nx) * tg->side;
	r.y = tg->y0 + (i / tg->nx) * tg->side;
	r.w = tg->x1 - r.x < tg->side ? tg->x1 - r.x : tg->side;
	r.h = tg->y1 - r.y < tg->side ? tg->y1 - r.y : tg->side;
	return r;
}

struct tile_pool {
	const struct tile_source *src;
	pthread_t *tid;
	int n;
};

/* One tracer: take, trace, done, until take says stop. Its buffer grows to
 * the largest tile it has seen (and is replaced when done keeps it). */
static void *pool_thread(void *arg)
{
	const struct tile_source *src = arg;
	uint8_t *buf = NULL;
	size_t cap = 0;
	struct tile_work w;
	while (src->take(src->ctx, &w)) {
		size_t need = (size_t)w.rect.w * w.rect.h * render_pixel_bytes(w.px);
		if (need > cap || !buf) {
			free(buf);
			cap = need;
			buf = malloc(cap ? cap : 1);
		}
		if (!buf) {
			cap = 0;
			src->done(src->ctx, &w, &buf, -1);
			continue;
		}
		struct timespec t0, t1;
		clock_gettime(CLOCK_MONOTONIC, &t0);
		int ok = renderer_tile_px(w.r, w.rect, w.px, buf, w.cancel);
		clock_gettime(CLOCK_MONOTONIC, &t1);
		w.trace_s = (double)(t1.tv_sec - t0.tv_sec) + (t1.tv_nsec - t0.tv_nsec) * 1e-9;
		src->done(src->ctx, &w, &buf, ok);
		if (!buf)
			cap = 0;
	}
	free(buf);
	return NULL;
}

struct tile_pool *tile_pool_start(int threads, const struct tile_source *src)
{
	if (threads <= 0)
		threads = render_ncpus();
	if (threads > POOL_MAX_THREADS)
		threads = POOL_MAX_THREADS;
	struct tile_pool *p = calloc(1, sizeof *p);
	if (!p || !(p->tid = calloc((size_t)threads, sizeof *p->tid))) {
		free(p);
		return NULL;
	}
	p->src = src;
	for (int i = 0; i < threads; i++) {
		if (pthread_create(&p->tid[p->n], NULL, pool_thread, (void *)src) != 0)
			break;
		p->n++;
	}
	if (p->n == 0) {
		free(p->tid);
		free(p);
		return NULL;
	}
	return p;
}

int tile_pool_threads(const struct tile_pool *p) { return p->n; }

void tile_pool_join(struct tile_pool *p)
{
	if (!p)
		return;
	for (int i = 0; i < p->n; i++)
		pthread_join(p->tid[i], NULL);
	free(p->tid);
	free(p);
}

int tile_pool_run(int threads, const struct tile_source *src)
{
	if (threads <= 0)
		threads = render_ncpus();
	struct tile_pool *p = threads > 1 ? tile_pool_start(threads - 1, src) : NULL;
	int n = 1 + (p ? p->n : 0);
	pool_thread((void *)src); /* the caller works too */
	tile_pool_join(p);
	return n;
}

/* ---- render_image: the local render as a tile source ---- */

struct image_source {
	const struct renderer *r;
	struct tiling tg;
	uint8_t *image;
	const struct render_progress *progress;
	atomic_int *cancel;
	atomic_uint_fast64_t next; /* next tile to hand out */
	pthread_mutex_t lock;      /* guards done and progress calls */
	uint64_t done;
};

static int image_take(void *ctx, struct tile_work *w)
{
	struct image_source *s = ctx;
	if (s->cancel && atomic_load_explicit(s->cancel, memory_order_relaxed))
		return 0;
	uint64_t k = atomic_fetch_add(&s->next, 1);
	if (k >= s->tg.n)
		return 0;
	*w = (struct tile_work){ s->r, tiling_rect(&s->tg, (uint32_t)k), s->cancel, k, NULL, 0, RENDER_RGB8 };
	return 1;
}

static void image_done(void *ctx, const struct tile_work *w, uint8_t **rgb, int ok)
{
	struct image_source *s = ctx;
	if (ok != 1)
		return; /* cancelled: the tile stays as it was; out of memory: the other threads carry on */
	const struct tile_rect *t = &w->rect;
	for (uint32_t j = 0; j < t->h; j++)
		memcpy(s->image + (((size_t)t->y + j) * s->tg.w + t->x) * 3, *rgb + (size_t)j * t->w * 3,
		       (size_t)t->w * 3);
	pthread_mutex_lock(&s->lock);
	s->done++;
	if (s->progress && s->progress->fn)
		s->progress->fn(s->progress->arg, s->done, s->tg.n);
	pthread_mutex_unlock(&s->lock);
}

uint64_t render_image(const struct renderer *r, int threads, uint32_t tile, uint8_t *image,
		      const struct render_progress *progress, atomic_int *cancel)
{
	struct image_source s;
	memset(&s, 0, sizeof s);
	uint32_t w, h;
	renderer_size(r, &w, &h);
	s.r = r;
	tiling_init(&s.tg, w, h, tile);
	s.image = image;
	s.progress = progress;
	s.cancel = cancel;
	atomic_init(&s.next, 0);
	pthread_mutex_init(&s.lock, NULL);
	if (threads <= 0)
		threads = render_ncpus();
	if ((uint64_t)threads > s.tg.n)
		threads = (int)s.tg.n;
	struct tile_source src = { image_take, image_done, &s };
	tile_pool_run(threads, &src);
	pthread_mutex_destroy(&s.lock);
	return s.done;
}

uint64_t render_tile_count(uint32_t w, uint32_t h, uint32_t tile)
{
	struct tiling tg;
	tiling_init(&tg, w, h, tile);
	return tg.n;
}
