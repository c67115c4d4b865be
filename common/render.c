/*
 * render.c - the tile renderer (render.h; the thread pool is tiles.c).
 *
 * The same code runs in the master (locally) and in every worker: a tile is
 * a rectangle of pixels, each pixel's colour comes from filter_pixel over
 * shade_trace, so it depends on the scene and the pixel alone. With one eye
 * ray per pixel (filter standard), the tile goes in 8x8 blocks whose eye
 * rays find their closest hits together (accel_intersect64, or
 * accel_intersect16 for the 4x4 blocks of one cut by an edge: the same
 * hits, faster), shaded as 2x2 blocks whose shadow rays toward each point
 * light go together too (shade_eye_hit4); each pixel gets exactly the
 * colour filter_pixel would give. Other filters trace super-sample grids
 * and adaptive corners four rays at a time the same way (filter_pixels4
 * over trace_shade4), a grid's packets running across four pixels of a
 * row.
 */
#include "common/render.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "common/accel.h"
#include "common/cancel.h"
#include "common/filter.h"
#include "common/shade.h"

/* render_ncpus at most: far more than any machine's cores, small enough
 * that a mistaken -j cannot exhaust the process. */
#define RENDER_MAX_THREADS 1024
/* Eye rays at least that trace_shade4 traces as a packet; fewer go one by
 * one: packets of two or three (the last ray repeated) made adaptive
 * renders of the teapot 3% slower (docs/performance.md, round 4). */
#define PACKET_MIN_RAYS 4

struct renderer {
	const struct scene *s;
	struct accel *accel;
	struct shade_ctx *shade;
	struct filter_chain fc;
	uint32_t w, h;
	atomic_uint_fast64_t rays; /* eye rays traced, all threads */
	atomic_uint_fast64_t secondary; /* mirror and transmitted rays, all threads */
};

int renderer_new(const struct scene *s, struct renderer **out, struct scene_error *err)
{
	return renderer_new_cancellable(s, out, err, NULL);
}

_Static_assert(RENDERER_CANCELLED == ACCEL_CANCELLED, "the build's give-up value is the renderer's");

/* The build runs in a cancel scope (cancel.h) whose polls accel_build and
 * bvh_build_ex make in their loops; shade_ctx_new and the camera are quick. */
int renderer_new_cancellable(const struct scene *s, struct renderer **out, struct scene_error *err,
			     atomic_int *cancel)
{
	*out = NULL;
	struct renderer *r = calloc(1, sizeof *r);
	if (!r)
		return scene_errorf(err, ERRLEVEL_FATAL, "out of memory");
	r->s = s;
	atomic_init(&r->rays, 0);
	atomic_init(&r->secondary, 0);
	struct cancel_scope saved;
	cancel_enter(cancel, &saved);
	int rc = accel_build(s, &r->accel, err);
	cancel_leave(&saved);
	if (rc)
		goto fail;
	rc = shade_ctx_new(s, r->accel, &r->shade, err);
	if (rc)
		goto fail;
	rc = renderer_set_size(r, (uint32_t)s->image.xsize, (uint32_t)s->image.ysize);
	if (rc) {
		rc = scene_errorf(err, ERRLEVEL_FATAL, "%s:%d:%d: error: camera is degenerate",
				  s->camera.loc.file ? s->camera.loc.file : "<scene>", s->camera.loc.line,
				  s->camera.loc.col);
		goto fail;
	}
	*out = r;
	return 0;
fail:
	renderer_free(r);
	return rc ? rc : ERRLEVEL_FATAL;
}

void renderer_free(struct renderer *r)
{
	if (!r)
		return;
	shade_ctx_free(r->shade);
	accel_free(r->accel);
	free(r);
}

void renderer_size(const struct renderer *r, uint32_t *w, uint32_t *h)
{
	*w = r->w;
	*h = r->h;
}

int renderer_set_size(struct renderer *r, uint32_t w, uint32_t h)
{
	if (w < 1 || h < 1 || w > LIM_IMAGE_SIDE || h > LIM_IMAGE_SIDE ||
	    (uint64_t)w * h > LIM_IMAGE_PIXELS)
		return -1;
	struct filter_chain fc;
	if (filter_chain_init(&fc, &r->s->camera, &r->s->image, w, h) < 0)
		return -1;
	r->fc = fc;
	r->w = w;
	r->h = h;
	return 0;
}

/* filter_trace_fn over the shading engine. */
static vec3 trace_shade(void *arg, const struct ray *ray, uint64_t seed)
{
	const struct renderer *r = arg;
	return shade_trace(r->shade, ray, seed);
}


/*
 * trace_shade4 once shade_eye_rays4 has made u and ok of e (n >= PACKET_MIN_RAYS;
 * fewer: u and ok unused).
 */
static void trace_ready4(const struct renderer *r, const struct ray e[4], const struct ray u[4], const bool ok[4],
			 const uint64_t seed[4], int n, vec3 out[4])
{
	if (n < PACKET_MIN_RAYS) { /* a packet of fewer rays costs four */
		for (int k = 0; k < n; k++)
			out[k] = trace_shade((void *)r, &e[k], seed[k]);
		return;
	}
	struct hit h[4];
	bool hit[4];
	accel_intersect4(r->accel, u, h, hit);
	const struct hit *hp[4];
	for (int k = 0; k < 4; k++)
		hp[k] = ok[k] && hit[k] ? &h[k] : NULL; /* !ok: black, as shade_eye_hit of a miss */
	shade_eye_hit4(r->shade, u, hp, seed, n, out);
}

/*
 * filter_trace4_fn over the shading engine: the colours of n <= 4 eye rays
 * e[k], their closest hits from one accel_intersect4 and their shadow rays
 * in packets (shade_eye_hit4), each what trace_shade gives (bit for bit).
 * Fewer than PACKET_MIN_RAYS rays go one by one through trace_shade; a
 * packet of fewer than four repeats its last ray.
 */
static void trace_shade4(void *arg, const struct ray e[4], const uint64_t seed[4], int n, vec3 out[4])
{
	struct ray u[4];
	bool ok[4];
	if (n >= PACKET_MIN_RAYS)
		shade_eye_rays4(e, n, u, ok);
	trace_ready4(arg, e, u, ok, seed, n, out);
}

/* Stores a filter colour as one pixel of a type (enum render_pixel). */
struct pixel_store {
	size_t bpp;
	void (*put)(vec3 c, uint8_t *out);
};

static void put_rgb8(vec3 c, uint8_t *out) { filter_quantise(c, out); }

static void put_le_float(double v, uint8_t *out)
{
	float f = (float)v;
	uint32_t u;
	memcpy(&u, &f, sizeof u);
	out[0] = (uint8_t)u;
	out[1] = (uint8_t)(u >> 8);
	out[2] = (uint8_t)(u >> 16);
	out[3] = (uint8_t)(u >> 24);
}

static void put_rgbf32(vec3 c, uint8_t *out)
{
	put_le_float(c.x, out);
	put_le_float(c.y, out + 4);
	put_le_float(c.z, out + 8);
}

/*
 * An 8x8 block of a tile for a filter_single_ray chain, as sixteen 2x2
 * blocks: block b (pixels at 4 * b in the arrays) lies at (2 (b & 1) +
 * 4 (b >> 2 & 1), 2 (b >> 1 & 1) + 4 (b >> 3)), so blocks 4 s to 4 s + 3
 * make the 4x4 block s. Each has its n[b] pixels inside the tile and the
 * image (0: none), in order, where their colours go, and their eye rays
 * (filter_eye_block, filter_eye_ray4) made ready for trace_ready4; traced
 * there, each colour is what filter_pixel over trace_shade gives.
 */
struct eye_8x8 {
	int n[16];
	int total;
	uint8_t *dst[64];
	struct ray e[64], u[64];
	bool ok[64];
	uint64_t seed[64];
};

/* Walk over a tile's 8x8 blocks, row by row. */
struct block_walk {
	const struct renderer *r;
	struct tile_rect t;
	const struct pixel_store *ps;
	uint8_t *rgb;
	uint32_t i, j; /* the next 8x8 block's top-left pixel in the tile */
};

/* The 2x2 block at tile pixel (i, j) as q's block b (the tile's pixels
 * outside the image on the way written black). */
static void add_block(const struct block_walk *w, uint32_t i, uint32_t j, struct eye_8x8 *q, int b)
{
	const struct renderer *r = w->r;
	struct tile_rect t = w->t;
	size_t bpp = w->ps->bpp;
	const int at = 4 * b;
	uint32_t px[4], py[4];
	int n = 0;
	for (uint32_t k = 0; k < 4; k++) {
		uint32_t ii = i + (k & 1), jj = j + (k >> 1);
		if (ii >= t.w || jj >= t.h)
			continue;
		uint64_t x = (uint64_t)t.x + ii, y = (uint64_t)t.y + jj;
		uint8_t *p = w->rgb + ((size_t)jj * t.w + ii) * bpp;
		if (x >= r->w || y >= r->h) {
			memset(p, 0, bpp);
			continue;
		}
		px[n] = (uint32_t)x;
		py[n] = (uint32_t)y;
		q->dst[at + n++] = p;
	}
	q->n[b] = n;
	q->total += n;
	if (n == 4) /* the whole block: its columns and rows shared */
		filter_eye_block(&r->fc, px[0], py[0], q->e + at, q->seed + at);
	else if (n)
		filter_eye_ray4(&r->fc, px, py, n, q->e + at, q->seed + at);
	if (n >= PACKET_MIN_RAYS)
		shade_eye_rays4(q->e + at, n, q->u + at, q->ok + at);
}

/* The next 8x8 block with a pixel inside the image into q; false at the
 * tile's end. */
static bool next_8x8(struct block_walk *w, struct eye_8x8 *q)
{
	struct tile_rect t = w->t;
	while (w->j < t.h) {
		uint32_t i = w->i, j = w->j;
		w->i += 8;
		if (w->i >= t.w) {
			w->i = 0;
			w->j += 8;
		}
		q->total = 0;
		for (int b = 0; b < 16; b++)
			add_block(w, i + 2 * (b & 1) + 4 * (b >> 2 & 1), j + 2 * (b >> 1 & 1) + 4 * (b >> 3), q, b);
		if (q->total)
			return true;
	}
	return false;
}

/* Shades q's 2x2 blocks from..to - 1, whole ones, from their hits h (block
 * b's at 4 * b). */
static void shade_blocks(const struct renderer *r, const struct eye_8x8 *q, int from, int to, const struct hit *h,
			 const bool *hit, vec3 out[64])
{
	for (int b = from; b < to; b++) {
		const struct hit *hp[4];
		for (int k = 0; k < 4; k++) /* !ok: black, as shade_eye_hit of a miss */
			hp[k] = q->ok[4 * b + k] && hit[4 * b + k] ? &h[4 * b + k] : NULL;
		shade_eye_hit4(r->shade, q->u + 4 * b, hp, q->seed + 4 * b, 4, out + 4 * b);
	}
}

/* The colours of q's pixels (block b's at 4 * b): a whole 8x8 block's
 * closest hits from one accel_intersect64, a whole 4x4 block's from one
 * accel_intersect16, each shaded 2x2 block by 2x2 block; any other 2x2
 * block through trace_ready4. */
static void trace_8x8(const struct renderer *r, const struct eye_8x8 *q, vec3 out[64])
{
	struct hit h[64];
	bool hit[64];
	if (q->total == 64) {
		accel_intersect64(r->accel, q->u, h, hit);
		shade_blocks(r, q, 0, 16, h, hit, out);
		return;
	}
	for (int s4 = 0; s4 < 4; s4++) {
		const int b0 = 4 * s4;
		if (q->n[b0] + q->n[b0 + 1] + q->n[b0 + 2] + q->n[b0 + 3] == 16) {
			accel_intersect16(r->accel, q->u + 4 * b0, h + 4 * b0, hit + 4 * b0);
			shade_blocks(r, q, b0, b0 + 4, h, hit, out);
			continue;
		}
		for (int b = b0; b < b0 + 4; b++)
			if (q->n[b])
				trace_ready4(r, q->e + 4 * b, q->u + 4 * b, q->ok + 4 * b, q->seed + 4 * b, q->n[b],
					     out + 4 * b);
	}
}

/*
 * renderer_tile_cancellable for a filter_single_ray chain, in 8x8 blocks;
 * stops at the first block that finds the thread's cancel flag set. The
 * next block's eye rays are made before this block is traced, so their
 * divisions and square roots run while this block's traversal does, not
 * in front of it.
 */
static void tile_blocks(const struct renderer *r, struct tile_rect t, const struct pixel_store *ps, uint8_t *rgb,
			uint64_t *rays)
{
	struct block_walk w = { r, t, ps, rgb, 0, 0 };
	struct eye_8x8 q[2];
	int cur = 0;
	bool have = next_8x8(&w, &q[0]);
	while (have) {
		if (cancel_poll())
			return;
		have = next_8x8(&w, &q[cur ^ 1]);
		const struct eye_8x8 *e = &q[cur];
		vec3 c[64];
		trace_8x8(r, e, c);
		for (int b = 0; b < 16; b++)
			for (int k = 0; k < e->n[b]; k++)
				ps->put(c[4 * b + k], e->dst[4 * b + k]);
		*rays += (uint64_t)e->total;
		cur ^= 1;
	}
}

/* renderer_tile_cancellable for any other chain, four pixels of a row at a
 * time (filter_pixels4: a super-sample grid's rays in packets across
 * them); stops at the first four that find the thread's cancel flag set. */
static void tile_pixels(const struct renderer *r, struct tile_rect t, const struct pixel_store *ps, uint8_t *rgb,
			uint64_t *rays)
{
	struct filter_scratch *scratch = filter_scratch_new(&r->fc); /* NULL: no cache, same colours */
	for (uint32_t j = 0; j < t.h; j++) {
		uint8_t *row = rgb + (size_t)j * t.w * ps->bpp;
		uint64_t y = (uint64_t)t.y + j;
		for (uint32_t i = 0; i < t.w; i += 4) {
			if (cancel_poll())
				goto out;
			uint32_t m = t.w - i < 4 ? t.w - i : 4; /* pixels of the tile */
			uint64_t x = (uint64_t)t.x + i;
			uint32_t n = y >= r->h || x >= r->w ? 0 : r->w - x < m ? (uint32_t)(r->w - x) : m; /* in the image */
			vec3 c[4];
			if (n)
				filter_pixels4(&r->fc, scratch, (uint32_t)x, (uint32_t)y, (int)n, trace_shade, trace_shade4,
					       (void *)r, rays, c);
			for (uint32_t k = 0; k < m; k++) {
				if (k < n)
					ps->put(c[k], row + (size_t)(i + k) * ps->bpp);
				else
					memset(row + (size_t)(i + k) * ps->bpp, 0, ps->bpp);
			}
		}
	}
out:
	filter_scratch_free(scratch);
}

/*
 * The tile runs in a cancel scope of its own (cancel.h): besides the polls
 * here, one per 8x8 block or four pixels, the filters poll once per sample
 * or packet, shading once per light of a shading point, and the traversal
 * when it enters an instance and every ACCEL_POLL_POPS subtrees, so one
 * pathological ray is abandoned too. Whatever they computed after a poll
 * saw the flag is wrong, so the tile is complete only when no poll did:
 * then every pixel is exactly what a run without a flag gives.
 */
int renderer_tile_px(const struct renderer *r, struct tile_rect t, enum render_pixel px, uint8_t *rgb,
		     atomic_int *cancel)
{
	static const struct pixel_store stores[2] = { [RENDER_RGB8] = { 3, put_rgb8 },
						      [RENDER_RGBF32] = { 12, put_rgbf32 } };
	const struct pixel_store *ps = &stores[px == RENDER_RGBF32];
	struct cancel_scope saved;
	cancel_enter(cancel, &saved);
	uint64_t rays = 0;
	(void)shade_take_secondary(); /* this thread's count starts at the tile */
	if (filter_single_ray(&r->fc))
		tile_blocks(r, t, ps, rgb, &rays);
	else
		tile_pixels(r, t, ps, rgb, &rays);
	int complete = !cancel_seen();
	cancel_leave(&saved);
	/* the counter is statistics only: casting away const is safe, r was
	 * allocated non-const by renderer_new */
	atomic_fetch_add_explicit(&((struct renderer *)r)->rays, rays, memory_order_relaxed);
	atomic_fetch_add_explicit(&((struct renderer *)r)->secondary, shade_take_secondary(), memory_order_relaxed);
	return complete;
}

int renderer_tile_cancellable(const struct renderer *r, struct tile_rect t, uint8_t *rgb, atomic_int *cancel)
{
	return renderer_tile_px(r, t, RENDER_RGB8, rgb, cancel);
}

void renderer_tile(const struct renderer *r, struct tile_rect t, uint8_t *rgb)
{
	(void)renderer_tile_cancellable(r, t, rgb, NULL);
}

uint64_t renderer_rays(const struct renderer *r)
{
	return atomic_load_explicit(&r->rays, memory_order_relaxed);
}

uint64_t renderer_secondary_rays(const struct renderer *r)
{
	return atomic_load_explicit(&r->secondary, memory_order_relaxed);
}

int renderer_warnings(const struct renderer *r, char *buf, size_t n)
{
	return filter_warnings(&r->s->camera, buf, n);
}

int render_ncpus(void)
{
	long n = sysconf(_SC_NPROCESSORS_ONLN);
	if (n < 1)
		return 1;
	return n > RENDER_MAX_THREADS ? RENDER_MAX_THREADS : (int)n;
}
