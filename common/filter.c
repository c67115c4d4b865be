/*
 * filter.c - the camera's filters layered in the order written (filter.h,
 * docs/camera.md).
 *
 * Layered filters multiply a pixel into up to LIM_RAYS_PER_SAMPLE rays per
 * corner, and adaptive into up to 257 x 257 corners, so a pixel may take
 * hours: every sample polls the calling thread's cancel flag (cancel.h),
 * and once it is seen set the remaining samples are skipped (black) and
 * loops end, so the pixel returns at once with a wrong colour that the
 * caller discards.
 */
#include "common/filter.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/cancel.h"
#include "common/rng.h"
#include "common/xmath.h"

/* Purpose tag for the filters' own random numbers (the layer index is added),
 * so they never coincide with the streams shading derives from the seed. */
#define FILTER_RNG_TAG 0x46494c5445520000ull
/* Corner cache entries at most (40 MB a thread): only corners on pixel edges
 * are cached, and a 4096-pixel tile row at the deepest level has fewer. */
#define FILTER_CACHE_MAX (1 << 20)

static int is_base(enum filter_kind k) { return k == FILTER_STANDARD || k == FILTER_ADAPTIVE; }

/* Index of the first standard/adaptive filter, or -1. */
static int base_index(const struct scene_camera *sc)
{
	for (int i = 0; i < sc->n_filters; i++)
		if (is_base(sc->filters[i].kind))
			return i;
	return -1;
}

/* Offset of grid column (or row) a of n from the incoming position. */
static double grid_offset(uint64_t a, int n) { return ((double)a + 0.5) / n - 0.5; }

int filter_chain_init(struct filter_chain *fc, const struct scene_camera *sc,
		      const struct scene_image *im, uint32_t w, uint32_t h)
{
	memset(fc, 0, sizeof *fc);
	if (cam_init(&fc->cam, sc, w, h) < 0)
		return -1;
	int b = base_index(sc);
	if (b < 0) {
		scene_filter_defaults(&fc->base, FILTER_STANDARD);
		return 0;
	}
	fc->base = sc->filters[b];
	for (int i = b + 1; i < sc->n_filters && i < LIM_FILTERS; i++) {
		const struct scene_filter *f = &sc->filters[i];
		if (f->kind == FILTER_SUPERSAMPLE || f->kind == FILTER_DISK || f->kind == FILTER_LENS)
			fc->layers[fc->n_layers++] = *f;
	}
	for (int i = 0; i < fc->n_layers; i++) {
		const struct scene_filter *f = &fc->layers[i];
		if (f->kind != FILTER_SUPERSAMPLE)
			continue;
		for (int a = 0; a < f->x_samples && a < FILTER_GRID_TAB; a++)
			fc->grid_dx[i][a] = grid_offset(a, f->x_samples);
		for (int a = 0; a < f->y_samples && a < FILTER_GRID_TAB; a++)
			fc->grid_dy[i][a] = grid_offset(a, f->y_samples);
	}
	for (uint32_t k = 0; k < FILTER_SEED_TAB; k++)
		fc->seed_s[k] = rng_seed_s(k);
	if (fc->base.kind == FILTER_ADAPTIVE) {
		if (fc->base.max_depth < 0)
			fc->base.max_depth = 0;
		if (fc->base.max_depth > LIM_ADAPTIVE_DEPTH)
			fc->base.max_depth = LIM_ADAPTIVE_DEPTH;
		fc->cache_size = fc->base.cache_size > 0 ? fc->base.cache_size : im->intersect_buffer;
		if (fc->cache_size < 0)
			fc->cache_size = 0;
		if (fc->cache_size > FILTER_CACHE_MAX)
			fc->cache_size = FILTER_CACHE_MAX;
	}
	return 0;
}

/* Appends printf-style text to buf at *len without overflowing n. */
static void append(char *buf, size_t n, size_t *len, const char *fmt, ...)
	__attribute__((format(printf, 4, 5)));
static void append(char *buf, size_t n, size_t *len, const char *fmt, ...)
{
	if (*len + 1 >= n)
		return;
	va_list ap;
	va_start(ap, fmt);
	int k = vsnprintf(buf + *len, n - *len, fmt, ap);
	va_end(ap);
	if (k > 0)
		*len = *len + (size_t)k < n ? *len + (size_t)k : n - 1;
}

int filter_warnings(const struct scene_camera *sc, char *buf, size_t n)
{
	size_t len = 0;
	int count = 0;
	if (n)
		buf[0] = '\0';
	int b = base_index(sc);
	for (int i = 0; i < sc->n_filters; i++) {
		const struct scene_filter *f = &sc->filters[i];
		const char *why = NULL;
		if (b < 0)
			why = "there is no standard or adaptive filter";
		else if (i < b)
			why = "it comes before the first standard or adaptive filter";
		else if (i > b && f->kind == FILTER_ADAPTIVE)
			why = "only the first standard or adaptive filter samples the pixel";
		if (!why)
			continue;
		count++;
		append(buf, n, &len, "%s:%d:%d: warning: filter %s ignored: %s\n",
		       f->loc.file ? f->loc.file : "<scene>", f->loc.line, f->loc.col,
		       scene_filter_name(f->kind), why);
	}
	if (b < 0 && sc->n_filters > 0)
		append(buf, n, &len, "%s:%d:%d: warning: using filter standard\n",
		       sc->loc.file ? sc->loc.file : "<scene>", sc->loc.line, sc->loc.col);
	return count;
}

static uint64_t sat_mul(uint64_t a, uint64_t b)
{
	if (a && b > UINT64_MAX / a)
		return UINT64_MAX;
	return a * b;
}

/* Samples one layer multiplies each incoming sample into. */
static uint64_t layer_count(const struct scene_filter *f)
{
	switch (f->kind) {
	case FILTER_SUPERSAMPLE: return (uint64_t)f->x_samples * (uint64_t)f->y_samples;
	case FILTER_DISK:
	case FILTER_LENS: return (uint64_t)f->samples;
	default: return 1;
	}
}

uint64_t filter_rays_per_sample(const struct filter_chain *fc)
{
	uint64_t n = 1;
	for (int i = 0; i < fc->n_layers; i++)
		n = sat_mul(n, layer_count(&fc->layers[i]));
	return n;
}

/* ---- layered samples ---------------------------------------------------- */

/* The state one layer passes to the next. */
struct sample {
	double px, py;     /* continuous pixel position */
	double lu, lv;     /* aperture point (world units along right, down) */
	double focal;      /* focal distance, when lens */
	int lens;          /* a lens layer has chosen an aperture point */
	uint64_t s;        /* sample index so far (mixed radix over the layers) */
};

struct walk {
	const struct filter_chain *fc;
	uint32_t sx, sy;   /* seed position */
	filter_trace_fn fn;
	filter_trace4_fn fn4; /* NULL: every ray through fn */
	void *arg;
	uint64_t rays;
};

static uint64_t seed_of(uint32_t x, uint32_t y, uint64_t s)
{
	uint64_t seed = rng_seed(x, y, (uint32_t)s);
	return (s >> 32) ? rng_derive(seed, s >> 32) : seed;
}

/* seed_of(x, y, 0), out of line: inlined into the loops that make four eye
 * rays, gcc -O3 made four of them at once in SSE2, whose 64-bit products
 * take three 32-bit ones each (2% slower on tetra_s4's plain renders). */
static __attribute__((noinline)) uint64_t seed0(uint32_t x, uint32_t y) { return seed_of(x, y, 0); }

/* seed_of with the chain's rng_seed_s of the first sample indices. */
static inline uint64_t seed_tab(const struct filter_chain *fc, uint32_t x, uint32_t y, uint64_t s)
{
	return s < FILTER_SEED_TAB ? rng_seed_at(x, y, fc->seed_s[s]) : seed_of(x, y, s);
}

/* The eye ray of a sample that every layer has multiplied. */
static struct ray sample_ray(const struct filter_chain *fc, const struct sample *smp)
{
	return smp->lens ? cam_lens_ray(&fc->cam, smp->px, smp->py, smp->lu, smp->lv, smp->focal)
			 : cam_ray(&fc->cam, smp->px, smp->py);
}

/* Column a (or row) of n's offset: the chain's, or computed for a grid
 * wider than it keeps (the same expression, so the same double). */
static double grid_off(const double tab[FILTER_GRID_TAB], uint64_t a, int n)
{
	return n <= FILTER_GRID_TAB ? tab[a] : grid_offset(a, n);
}

/* Sample k of n of super-sample layer `layer` from smp. */
static struct sample grid_sample(const struct filter_chain *fc, int layer, struct sample smp, uint64_t n,
				 uint64_t k)
{
	const struct scene_filter *f = &fc->layers[layer];
	struct sample c = smp;
	c.s = smp.s * n + k;
	uint64_t a = k % (uint64_t)f->x_samples, b = k / (uint64_t)f->x_samples;
	c.px += grid_off(fc->grid_dx[layer], a, f->x_samples);
	c.py += grid_off(fc->grid_dy[layer], b, f->y_samples);
	return c;
}

/*
 * expand() of super-sample layer `layer` when it is the last one, four
 * samples a packet through w->fn4: the same rays and seeds, the colours
 * summed in the same order with the same weight (1), so the same mean bit
 * for bit. A pinhole grid that fits the chain's offsets computes the
 * camera's columns and rows once (cam_col, cam_row), walks the grid with
 * counters, and makes four directions unit together (cam_unit4).
 */
static vec3 expand_grid4(struct walk *w, int layer, struct sample smp)
{
	const struct filter_chain *fc = w->fc;
	const struct scene_filter *f = &fc->layers[layer];
	uint64_t n = layer_count(f), s0 = smp.s * n;
	uint32_t xs = (uint32_t)f->x_samples, ys = (uint32_t)f->y_samples;
	bool tab = !smp.lens && xs <= FILTER_GRID_TAB && ys <= FILTER_GRID_TAB;
	vec3 col[FILTER_GRID_TAB], row[FILTER_GRID_TAB];
	if (tab) {
		for (uint32_t a = 0; a < xs; a++)
			col[a] = cam_col(&fc->cam, smp.px + fc->grid_dx[layer][a]);
		for (uint32_t b = 0; b < ys; b++)
			row[b] = cam_row(&fc->cam, smp.py + fc->grid_dy[layer][b]);
	}
	uint32_t a = 0, b = 0; /* column and row of sample k */
	vec3 sum = v3(0, 0, 0);
	double wsum = 0;
	for (uint64_t k0 = 0; k0 < n; k0 += 4) {
		if (cancel_poll()) /* CANCELLATION: the samples left are skipped */
			break;
		struct ray r[4];
		uint64_t seed[4];
		int m = 0;
		if (tab) {
			vec3 d[4];
			for (uint64_t k = k0; k < n && m < 4; k++, m++) {
				d[m] = v3_add(fc->cam.vd, v3_add(col[a], row[b])); /* cam_dir's sum */
				seed[m] = seed_tab(fc, w->sx, w->sy, s0 + k);
				if (++a == xs) {
					a = 0;
					b++;
				}
			}
			cam_unit4(&fc->cam, d, m, r);
		} else {
			for (uint64_t k = k0; k < n && m < 4; k++, m++) {
				struct sample c = grid_sample(fc, layer, smp, n, k);
				r[m] = sample_ray(fc, &c);
				seed[m] = seed_tab(fc, w->sx, w->sy, c.s);
			}
		}
		vec3 v[4];
		w->fn4(w->arg, r, seed, m, v);
		w->rays += (uint64_t)m;
		for (int j = 0; j < m; j++) {
			sum = v3_add(sum, v3_scale(v[j], 1.0));
			wsum += 1.0;
		}
	}
	return wsum > 0 ? v3_scale(sum, 1.0 / wsum) : v3(0, 0, 0);
}

/* Colour of sample smp after layers [layer, n_layers) have multiplied it. */
static vec3 expand(struct walk *w, int layer, struct sample smp)
{
	const struct filter_chain *fc = w->fc;
	if (cancel_poll()) /* CANCELLATION: a wrong colour, never used */
		return v3(0, 0, 0);
	if (layer == fc->n_layers) {
		struct ray r = sample_ray(fc, &smp);
		w->rays++;
		return w->fn(w->arg, &r, seed_tab(fc, w->sx, w->sy, smp.s));
	}
	const struct scene_filter *f = &fc->layers[layer];
	if (w->fn4 && layer == fc->n_layers - 1 && f->kind == FILTER_SUPERSAMPLE)
		return expand_grid4(w, layer, smp);
	uint64_t n = layer_count(f);
	vec3 sum = v3(0, 0, 0);
	double wsum = 0;
	for (uint64_t k = 0; k < n; k++) {
		if (k && cancel_poll()) /* as at the top: the samples left are skipped */
			break;
		struct sample c = smp;
		c.s = smp.s * n + k;
		double weight = 1.0;
		if (f->kind == FILTER_SUPERSAMPLE) {
			c = grid_sample(fc, layer, smp, n, k);
		} else {
			/* uniform point in a disk of radius R: r = R sqrt(u1), angle 2 pi u2 */
			uint64_t rs = rng_derive(seed_tab(fc, w->sx, w->sy, c.s), FILTER_RNG_TAG + (uint64_t)layer);
			double u1 = rng_uniform(rs, 0), u2 = rng_uniform(rs, 1);
			double rr = f->radius * sqrt(u1), phi = 2.0 * M_PI * u2, sn, cs;
			xm_sincos(phi, &sn, &cs);
			double du = rr * cs, dv = rr * sn;
			if (f->kind == FILTER_DISK) {
				c.px += du;
				c.py += dv;
				weight = f->radius > 0 ? 1.0 - rr / f->radius : 1.0;
			} else {
				c.lu = du;
				c.lv = dv;
				c.focal = f->focal_length;
				c.lens = 1;
			}
		}
		vec3 v = expand(w, layer + 1, c);
		sum = v3_add(sum, v3_scale(v, weight));
		wsum += weight;
	}
	return wsum > 0 ? v3_scale(sum, 1.0 / wsum) : v3(0, 0, 0);
}

vec3 filter_point(const struct filter_chain *fc, double px, double py, uint32_t sx, uint32_t sy,
		  filter_trace_fn fn, void *arg, uint64_t *rays)
{
	struct walk w = { fc, sx, sy, fn, NULL, arg, 0 };
	struct sample smp = { px, py, 0, 0, 0, 0, 0 };
	vec3 v = expand(&w, 0, smp);
	if (rays)
		*rays += w.rays;
	return v;
}

/* ---- adaptive ------------------------------------------------------------ */

/* One corner cache entry: a corner on the sub-pixel grid and its colour. */
struct corner {
	uint32_t x, y;
	vec3 c;
	int used;
};

struct filter_scratch {
	struct corner *cache;
	uint32_t n;
};

struct filter_scratch *filter_scratch_new(const struct filter_chain *fc)
{
	struct filter_scratch *sc = calloc(1, sizeof *sc);
	if (!sc)
		return NULL;
	if (fc->base.kind == FILTER_ADAPTIVE && fc->cache_size > 0) {
		sc->cache = calloc((size_t)fc->cache_size, sizeof *sc->cache);
		if (!sc->cache) {
			free(sc);
			return NULL;
		}
		sc->n = (uint32_t)fc->cache_size;
	}
	return sc;
}

void filter_scratch_free(struct filter_scratch *sc)
{
	if (!sc)
		return;
	free(sc->cache);
	free(sc);
}

struct adapt {
	struct walk w;
	struct filter_scratch *scratch;
	uint32_t grid;     /* sub-pixel grid cells per pixel side: 2^max_depth */
};

/* The corner cache's slot for shared corner (x, y), or NULL (no cache, or
 * a corner inside a pixel, which no other pixel asks for). */
static struct corner *corner_slot(struct adapt *a, uint32_t x, uint32_t y)
{
	struct filter_scratch *sc = a->scratch;
	int shared = (x & (a->grid - 1)) == 0 || (y & (a->grid - 1)) == 0;
	if (!shared || !sc || !sc->n)
		return NULL;
	/* slot = hash scaled into [0, n) by a multiply, not a division */
	uint64_t hsh = rng_mix((uint64_t)x << 32 | y) >> 32;
	return &sc->cache[(hsh * sc->n) >> 32];
}

/*
 * Colour at grid corner (x, y): the corner cache holds corners on pixel edges,
 * the only ones another pixel can share; a corner's colour does not depend on
 * whether it came from the cache.
 */
static vec3 corner(struct adapt *a, uint32_t x, uint32_t y)
{
	struct corner *e = corner_slot(a, x, y);
	if (e && e->used && e->x == x && e->y == y)
		return e->c;
	a->w.sx = x;
	a->w.sy = y;
	struct sample smp = { (double)x / a->grid, (double)y / a->grid, 0, 0, 0, 0, 0 };
	vec3 v = expand(&a->w, 0, smp);
	if (e) {
		e->x = x;
		e->y = y;
		e->c = v;
		e->used = 1;
	}
	return v;
}

/*
 * corner() of n <= 5 corners (x[i], y[i]) in order, the ones not cached
 * traced four at a time through fn4 (adaptive with nothing layered on it,
 * and fn4 given; else corner() one by one). The cache ends as corner()
 * in turn would leave it, and a corner counts as cached exactly when it
 * would have: a slot that an earlier corner of the batch fills is a miss
 * for a later one (so *rays is the same too).
 */
static void corners(struct adapt *a, int n, const uint32_t x[], const uint32_t y[], vec3 out[])
{
	if (!a->w.fn4 || a->w.fc->n_layers) {
		for (int i = 0; i < n; i++)
			out[i] = corner(a, x[i], y[i]);
		return;
	}
	struct corner *e[5];
	int miss[5], n_miss = 0;
	for (int i = 0; i < n; i++) {
		e[i] = corner_slot(a, x[i], y[i]);
		bool filled = false; /* by an earlier miss of this batch */
		for (int j = 0; j < n_miss && e[i]; j++)
			filled |= e[miss[j]] == e[i];
		if (e[i] && !filled && e[i]->used && e[i]->x == x[i] && e[i]->y == y[i])
			out[i] = e[i]->c;
		else
			miss[n_miss++] = i;
	}
	if (n_miss == 1) { /* nothing to trace together: corner()'s lookup misses again */
		out[miss[0]] = corner(a, x[miss[0]], y[miss[0]]);
		return;
	}
	const struct filter_chain *fc = a->w.fc;
	for (int j0 = 0; j0 < n_miss; j0 += 4) {
		int m = n_miss - j0 < 4 ? n_miss - j0 : 4;
		struct ray r[4];
		uint64_t seed[4];
		double px[4], py[4];
		vec3 v[4] = { { 0, 0, 0 }, { 0, 0, 0 }, { 0, 0, 0 }, { 0, 0, 0 } };
		for (int j = 0; j < m; j++) { /* expand()'s last layer, as corner() calls it */
			int i = miss[j0 + j];
			px[j] = (double)x[i] / a->grid;
			py[j] = (double)y[i] / a->grid;
			seed[j] = seed0(x[i], y[i]);
		}
		cam_ray4(&fc->cam, px, py, m, r);
		if (!cancel_poll()) /* CANCELLATION: black, a wrong colour never used */
			a->w.fn4(a->w.arg, r, seed, m, v);
		a->w.rays += (uint64_t)m;
		for (int j = 0; j < m; j++) {
			int i = miss[j0 + j];
			out[i] = v[j];
			if (e[i]) {
				e[i]->x = x[i];
				e[i]->y = y[i];
				e[i]->c = v[j];
				e[i]->used = 1;
			}
		}
	}
}

/* Clamps to [0,1]; NaN becomes 0. Comparisons, not fmin/fmax: those are
 * library calls at -O2 and this runs for every corner. */
static inline double clamp01(double v) { return v > 0.0 ? (v < 1.0 ? v : 1.0) : 0.0; }

/* Largest channel difference between two colours as displayed (clamped). */
static double cdiff(vec3 a, vec3 b)
{
	double dx = fabs(clamp01(a.x) - clamp01(b.x));
	double dy = fabs(clamp01(a.y) - clamp01(b.y));
	double dz = fabs(clamp01(a.z) - clamp01(b.z));
	double m = dx > dy ? dx : dy;
	return m > dz ? m : dz;
}

/*
 * Average colour over the square with top-left grid corner (x, y) and side
 * size cells, given its corners (tl, tr, bl, br). It is split into four when
 * two corners sharing an edge differ by more than thr and depth levels remain.
 */
static vec3 adapt_square(struct adapt *a, uint32_t x, uint32_t y, uint32_t size, vec3 tl, vec3 tr,
			 vec3 bl, vec3 br, int depth, double thr)
{
	if (depth > 0 && size >= 2 &&
	    (cdiff(tl, tr) > thr || cdiff(bl, br) > thr || cdiff(tl, bl) > thr || cdiff(tr, br) > thr)) {
		uint32_t h = size / 2;
		const uint32_t cx[5] = { x + h, x, x + h, x + size, x + h };
		const uint32_t cy[5] = { y, y + h, y + h, y + h, y + size };
		vec3 cv[5];
		corners(a, 5, cx, cy, cv);
		vec3 t = cv[0], l = cv[1], m = cv[2], r = cv[3], b = cv[4];
		double nt = thr * a->w.fc->base.relax;
		vec3 s = adapt_square(a, x, y, h, tl, t, l, m, depth - 1, nt);
		s = v3_add(s, adapt_square(a, x + h, y, h, t, tr, m, r, depth - 1, nt));
		s = v3_add(s, adapt_square(a, x, y + h, h, l, m, bl, b, depth - 1, nt));
		s = v3_add(s, adapt_square(a, x + h, y + h, h, m, r, b, br, depth - 1, nt));
		return v3_scale(s, 0.25);
	}
	return v3_scale(v3_add(v3_add(tl, tr), v3_add(bl, br)), 0.25);
}

bool filter_single_ray(const struct filter_chain *fc)
{
	return fc->base.kind == FILTER_STANDARD && fc->n_layers == 0;
}

/* expand()'s last layer for the sample of a standard pixel: position (x +
 * 0.5, y + 0.5), sample index 0, no lens. */
void filter_eye_ray(const struct filter_chain *fc, uint32_t x, uint32_t y, struct ray *r, uint64_t *seed)
{
	*r = cam_ray(&fc->cam, x + 0.5, y + 0.5);
	*seed = seed_of(x, y, 0);
}

void filter_eye_ray4(const struct filter_chain *fc, const uint32_t x[4], const uint32_t y[4], int n, struct ray r[4],
		     uint64_t seed[4])
{
	double px[4], py[4];
	for (int k = 0; k < n; k++) {
		px[k] = x[k] + 0.5;
		py[k] = y[k] + 0.5;
		seed[k] = seed0(x[k], y[k]);
	}
	cam_ray4(&fc->cam, px, py, n, r);
}

void filter_eye_block(const struct filter_chain *fc, uint32_t x, uint32_t y, struct ray r[4], uint64_t seed[4])
{
	const struct cam *c = &fc->cam;
	vec3 c0 = cam_col(c, x + 0.5), c1 = cam_col(c, (x + 1) + 0.5);
	vec3 r0 = cam_row(c, y + 0.5), r1 = cam_row(c, (y + 1) + 0.5);
	vec3 d[4] = { v3_add(c->vd, v3_add(c0, r0)), v3_add(c->vd, v3_add(c1, r0)), v3_add(c->vd, v3_add(c0, r1)),
		      v3_add(c->vd, v3_add(c1, r1)) };
	cam_unit4(c, d, 4, r);
	seed[0] = seed0(x, y);
	seed[1] = seed0(x + 1, y);
	seed[2] = seed0(x, y + 1);
	seed[3] = seed0(x + 1, y + 1);
}

vec3 filter_pixel(const struct filter_chain *fc, struct filter_scratch *scratch, uint32_t x,
		  uint32_t y, filter_trace_fn fn, void *arg, uint64_t *rays)
{
	return filter_pixel4(fc, scratch, x, y, fn, NULL, arg, rays);
}

vec3 filter_pixel4(const struct filter_chain *fc, struct filter_scratch *scratch, uint32_t x, uint32_t y,
		   filter_trace_fn fn, filter_trace4_fn fn4, void *arg, uint64_t *rays)
{
	if (fc->base.kind != FILTER_ADAPTIVE) {
		struct walk w = { fc, x, y, fn, fn4, arg, 0 };
		struct sample smp = { x + 0.5, y + 0.5, 0, 0, 0, 0, 0 }; /* filter_point's */
		vec3 v = expand(&w, 0, smp);
		if (rays)
			*rays += w.rays;
		return v;
	}
	struct adapt a;
	a.w = (struct walk){ fc, 0, 0, fn, fn4, arg, 0 };
	a.scratch = scratch;
	a.grid = 1u << fc->base.max_depth;
	uint32_t g = a.grid, x0 = x * g, y0 = y * g;
	const uint32_t cx[4] = { x0, x0 + g, x0, x0 + g }, cy[4] = { y0, y0, y0 + g, y0 + g };
	vec3 cv[4];
	corners(&a, 4, cx, cy, cv);
	vec3 tl = cv[0], tr = cv[1], bl = cv[2], br = cv[3];
	vec3 v = adapt_square(&a, x0, y0, g, tl, tr, bl, br, fc->base.max_depth, fc->base.threshold);
	if (rays)
		*rays += a.w.rays;
	return v;
}

/* A packet of grid rays from several pixels: m <= 4 rays, their seeds
 * and the pixel each belongs to. */
struct grid_packet {
	int m;
	int pix[4];
	uint64_t seed[4];
	struct ray r[4];
};

/* The samples of filter_pixels4's pixels in order: pixel p, its sample k
 * in column a and row b of the grid. */
struct grid_stream {
	const struct filter_chain *fc;
	uint32_t x, y, xs;
	int n;
	uint64_t n_smp;
	const vec3 (*col)[FILTER_GRID_TAB]; /* cam_col of pixel p's column a */
	const vec3 *row;                    /* cam_row of row b */
	int p;
	uint32_t a, b;
	uint64_t k;
};

/* The stream's next (up to) four samples into g; g->m = 0 at its end. The
 * counters are kept in locals: g's stores could alias them. */
static void grid_fill(struct grid_stream *st, struct grid_packet *g)
{
	const struct filter_chain *fc = st->fc;
	vec3 d[4];
	int m = 0, p = st->p;
	uint32_t a = st->a, b = st->b;
	uint64_t k = st->k;
	while (m < 4 && p < st->n) {
		d[m] = v3_add(fc->cam.vd, v3_add(st->col[p][a], st->row[b])); /* cam_dir's sum */
		g->seed[m] = seed_tab(fc, st->x + (uint32_t)p, st->y, k);
		g->pix[m++] = p;
		if (++a == st->xs) {
			a = 0;
			b++;
		}
		if (++k == st->n_smp) {
			k = 0;
			a = b = 0;
			p++;
		}
	}
	st->p = p;
	st->a = a;
	st->b = b;
	st->k = k;
	g->m = m;
	if (m)
		cam_unit4(&fc->cam, d, m, g->r);
}

void filter_pixels4(const struct filter_chain *fc, struct filter_scratch *scratch, uint32_t x, uint32_t y, int n,
		    filter_trace_fn fn, filter_trace4_fn fn4, void *arg, uint64_t *rays, vec3 out[4])
{
	const struct scene_filter *f = &fc->layers[0];
	if (!fn4 || fc->base.kind != FILTER_STANDARD || fc->n_layers != 1 || f->kind != FILTER_SUPERSAMPLE ||
	    f->x_samples > FILTER_GRID_TAB || f->y_samples > FILTER_GRID_TAB) {
		for (int p = 0; p < n; p++)
			out[p] = filter_pixel4(fc, scratch, x + (uint32_t)p, y, fn, fn4, arg, rays);
		return;
	}
	/* expand_grid4 of each pixel's sample: position (x + p + 0.5, y +
	 * 0.5), index 0, seeded at (x + p, y) */
	vec3 col[4][FILTER_GRID_TAB], row[FILTER_GRID_TAB], sum[4];
	double wsum[4];
	struct grid_stream st = { fc, x, y, (uint32_t)f->x_samples, n, (uint64_t)f->x_samples * (uint64_t)f->y_samples,
				  col, row, 0, 0, 0, 0 };
	for (int p = 0; p < n; p++) {
		double px = (x + (uint32_t)p) + 0.5;
		for (int a = 0; a < f->x_samples; a++)
			col[p][a] = cam_col(&fc->cam, px + fc->grid_dx[0][a]);
		sum[p] = v3(0, 0, 0);
		wsum[p] = 0;
	}
	double py = y + 0.5;
	for (int b = 0; b < f->y_samples; b++)
		row[b] = cam_row(&fc->cam, py + fc->grid_dy[0][b]);
	/* the next packet is made before this one is traced, so its square
	 * roots and divisions run alongside this one's traversal */
	struct grid_packet pk[2];
	int cur = 0;
	uint64_t traced = 0;
	grid_fill(&st, &pk[0]);
	while (pk[cur].m > 0) {
		if (cancel_poll()) /* CANCELLATION: the samples left are skipped */
			break;
		grid_fill(&st, &pk[cur ^ 1]);
		const struct grid_packet *g = &pk[cur];
		vec3 v[4];
		fn4(arg, g->r, g->seed, g->m, v);
		traced += (uint64_t)g->m;
		for (int j = 0; j < g->m; j++) { /* expand_grid4's sums, pixel by pixel */
			int q = g->pix[j];
			sum[q] = v3_add(sum[q], v3_scale(v[j], 1.0));
			wsum[q] += 1.0;
		}
		cur ^= 1;
	}
	for (int p = 0; p < n; p++)
		out[p] = wsum[p] > 0 ? v3_scale(sum[p], 1.0 / wsum[p]) : v3(0, 0, 0);
	if (rays)
		*rays += traced;
}

void filter_quantise(vec3 c, uint8_t out[3])
{
	/* the values are >= 0.5, so truncation is floor */
	out[0] = (uint8_t)(clamp01(c.x) * 255.0 + 0.5);
	out[1] = (uint8_t)(clamp01(c.y) * 255.0 + 0.5);
	out[2] = (uint8_t)(clamp01(c.z) * 255.0 + 0.5);
}
