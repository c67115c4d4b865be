/*
 * filter.h - pixel sampling: the camera's filters layered in the order
 * written (docs/camera.md).
 *
 * The first standard or adaptive filter is the base: standard asks for one
 * value at the pixel centre; adaptive asks for values at the pixel's corners
 * and at the corners of sub-pixels where it subdivides. Every filter written
 * after the base multiplies each of those values into several rays:
 * super-sample (a grid of offsets), disk (random offsets within a radius,
 * tent-weighted), lens (random points on a thin-lens aperture). A later
 * standard adds nothing (one ray through the position passed down); a later
 * adaptive, and every filter before the base, is ignored (with a warning).
 *
 * Randomness: every random number is a function of (position, sample index,
 * layer) through common/rng.h, where position is the pixel for standard and
 * the corner's position on the 1/2^max-depth sub-pixel grid for adaptive, and
 * the sample index enumerates the layered samples in a fixed order. So a
 * pixel's value depends on the scene and the pixel only, never on the tile or
 * the thread, and an adaptive corner has one value wherever it is traced.
 */
#ifndef PORTRAY_FILTER_H
#define PORTRAY_FILTER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "common/camera.h"

/* Colour seen along an eye ray; seed is the (position, sample) stream. */
typedef vec3 (*filter_trace_fn)(void *arg, const struct ray *r, uint64_t seed);
/* The colours of n <= 4 eye rays at once: out[k] must be exactly what the
 * filter_trace_fn it goes with gives for (r[k], seed[k]) (a packet of
 * neighbouring rays traced together: accel_intersect4, shade_eye_hit4). */
typedef void (*filter_trace4_fn)(void *arg, const struct ray r[4], const uint64_t seed[4], int n, vec3 out[4]);

/* Columns and rows of a super-sample grid whose offsets the chain keeps
 * (a grid with more computes its offsets sample by sample). */
#define FILTER_GRID_TAB 16
/* Sample indices whose part of the seed (rng_seed_s) the chain keeps. */
#define FILTER_SEED_TAB 64

struct filter_chain {
	struct cam cam;
	struct scene_filter base;                 /* kind STANDARD or ADAPTIVE */
	struct scene_filter layers[LIM_FILTERS];  /* the multiplying filters after the base */
	int n_layers;
	int cache_size;                           /* adaptive corner cache entries (0 = none) */
	/* super-sample layer i's offsets from the incoming position, when its
	 * grid fits: column a's (a + 0.5) / x_samples - 0.5, row b's likewise */
	double grid_dx[LIM_FILTERS][FILTER_GRID_TAB], grid_dy[LIM_FILTERS][FILTER_GRID_TAB];
	uint64_t seed_s[FILTER_SEED_TAB];         /* rng_seed_s(s) of sample index s */
};

/*
 * Builds the chain for camera sc on a w x h image; cache sizes of 0 fall back
 * to im->intersect_buffer. Returns 0, or -1 for a degenerate camera.
 */
int filter_chain_init(struct filter_chain *fc, const struct scene_camera *sc,
		      const struct scene_image *im, uint32_t w, uint32_t h);

/*
 * Describes the filters that are ignored (written before the first standard
 * or adaptive filter, a later adaptive, or no base filter at all) as one
 * warning per line ("file:line:col: warning: ...\n") into buf (NUL-terminated,
 * truncated to n). Returns the number of ignored filters (0: buf is "").
 */
int filter_warnings(const struct scene_camera *sc, char *buf, size_t n);

/* Eye rays per pixel the chain traces for standard (adaptive: at the pixel's
 * corners before any subdivision, per corner). Saturates at UINT64_MAX. */
uint64_t filter_rays_per_sample(const struct filter_chain *fc);

/* Per-thread scratch for one tile: the adaptive corner cache. */
struct filter_scratch;
/* NULL on out of memory; for a standard chain it holds nothing. Caller frees. */
struct filter_scratch *filter_scratch_new(const struct filter_chain *fc);
void filter_scratch_free(struct filter_scratch *sc);

/*
 * Colour of pixel (x, y) (linear, unclamped): a pure function of the chain,
 * fn and the pixel. *rays (may be NULL) is increased by the eye rays traced.
 * scratch comes from filter_scratch_new for this chain (NULL: no cache).
 * Polls the calling thread's cancel flag (cancel.h) at every sample: once
 * it is seen set, the colour (and any corner cached in scratch) is wrong.
 */
vec3 filter_pixel(const struct filter_chain *fc, struct filter_scratch *scratch, uint32_t x,
		  uint32_t y, filter_trace_fn fn, void *arg, uint64_t *rays);

/*
 * filter_pixel with fn4 (may be NULL: filter_pixel) for the rays it can
 * trace four at a time: a super-sample grid that is the last layer (four
 * consecutive samples a packet) and the corners of adaptive with nothing
 * layered on it (the corners a square asks for at once). The same colour
 * bit for bit, the same *rays; the cancel flag is polled once a packet.
 */
vec3 filter_pixel4(const struct filter_chain *fc, struct filter_scratch *scratch, uint32_t x, uint32_t y,
		   filter_trace_fn fn, filter_trace4_fn fn4, void *arg, uint64_t *rays);

/* filter_eye_ray4 of the 2x2 block of pixels (x, y), (x + 1, y), (x, y + 1),
 * (x + 1, y + 1) in that order, bit for bit: its two columns and two rows
 * computed once (cam_col, cam_row), the four rays made unit together. */
void filter_eye_block(const struct filter_chain *fc, uint32_t x, uint32_t y, struct ray r[4], uint64_t seed[4]);

/*
 * filter_pixel4 of the n <= 4 pixels (x + p, y), p < n, into out[p], each
 * the same colour bit for bit, *rays increased by all their rays. When the
 * chain is standard with one super-sample grid layered on it (at most
 * FILTER_GRID_TAB columns and rows), the pixels' rays, in order, fill
 * packets of four across the pixels' boundaries (a 3 x 3 grid: nine
 * packets for four pixels, not eight and four single rays) and each
 * pixel's colours are summed in its own order; the cancel flag is polled
 * once a packet. Any other chain: filter_pixel4 pixel by pixel.
 */
void filter_pixels4(const struct filter_chain *fc, struct filter_scratch *scratch, uint32_t x, uint32_t y, int n,
		    filter_trace_fn fn, filter_trace4_fn fn4, void *arg, uint64_t *rays, vec3 out[4]);

/*
 * True when the chain traces one pinhole eye ray per pixel, through its
 * centre (filter standard with nothing layered on it). filter_pixel's
 * colour is then fn(arg, &r, seed) of the ray and seed filter_eye_ray
 * gives, so a caller may trace the eye rays of neighbouring pixels together
 * (accel_intersect4) and shade each one as filter_pixel would.
 */
bool filter_single_ray(const struct filter_chain *fc);
/* The eye ray through pixel (x, y)'s centre and its sample seed, as
 * filter_pixel traces them for a filter_single_ray chain. */
void filter_eye_ray(const struct filter_chain *fc, uint32_t x, uint32_t y, struct ray *r, uint64_t *seed);
/* filter_eye_ray of n <= 4 pixels (x[k], y[k]) into r[k] and seed[k], bit
 * for bit, the camera's divisions and square roots two at a time (cam_ray4). */
void filter_eye_ray4(const struct filter_chain *fc, const uint32_t x[4], const uint32_t y[4], int n, struct ray r[4],
		     uint64_t seed[4]);

/*
 * Colour at a continuous pixel position (px, py) with every layered filter
 * applied, seeded by integer position (sx, sy): what the base filter asks for.
 * Exposed for tests.
 */
vec3 filter_point(const struct filter_chain *fc, double px, double py, uint32_t sx, uint32_t sy,
		  filter_trace_fn fn, void *arg, uint64_t *rays);

/* Clamps each channel to [0,1] (NaN to 0) and rounds to 8 bits. */
void filter_quantise(vec3 c, uint8_t out[3]);

#endif
