/*
 * bench_secondary.c - the figure for single incoherent rays: the mirror
 * rays of a frame, traced one at a time with accel_intersect (closest hit,
 * no shading), as the renderer traces the reflections off curved surfaces
 * (docs/performance.md, round 16).
 *
 * The rays are made as the renderer makes them: every pixel centre's eye
 * hit whose material reflects sends a ray reflected about the shading
 * normal facing the viewer, from accel_offset_point, and so on from its
 * hit while the weight (the product of spec-colour x reflection maxima)
 * stays at 1/512 or more, down to LIM_TRACE_DEPTH bounces. Shaders, which
 * may perturb the normal or the material, are left out. The rays are made
 * once, then traced in three orders, FRAMES times each, interleaved:
 *   - "first": the first bounces alone, in pixel order;
 *   - "all": every bounce in the renderer's order: a pixel's chain, then
 *     the next pixel's, pixels in the order tiles of TILE_DEFAULT and
 *     their 8x8 and 2x2 blocks take them (render.c);
 *   - "shuffled": the same rays in a fixed pseudo-random order (what
 *     tracing them with nothing in common between neighbours costs).
 * It prints each order's best rate in Mrays/s of thread CPU time, and a
 * hash of the hits of "all" and "shuffled", which must agree.
 *
 *   bench_secondary [SCENE [FRAMES [WIDTHxHEIGHT]]]
 *
 * Defaults: tests/data/spd/balls_s4.sce, 5 frames, 1280x960. Not a test:
 * prints figures only.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/accel.h"
#include "common/camera.h"
#include "common/limits.h"
#include "common/shade.h"
#include "common/tiles.h"
#include "bench/bench_scene.h"

struct set {
	struct ray *r;
	size_t n, cap;
};

static int push(struct set *s, const struct ray *r)
{
	struct ray *nr = bs_grow(s->r, &s->cap, s->n, sizeof *nr, 65536);
	if (!nr)
		return -1;
	s->r = nr;
	s->r[s->n++] = *r;
	return 0;
}

static double maxc(vec3 v) { return v.x > v.y ? (v.x > v.z ? v.x : v.z) : (v.y > v.z ? v.y : v.z); }

/* The mirror ray off hit h of ray r, when h's material reflects with the
 * weight kept at SHADE_MIN_WEIGHT or more; *w is updated. surf_prepare's facing
 * test and reflect_ray's fallback (shade.c), without shaders. */
static bool mirror(const struct scene *sc, const struct ray *r, const struct hit *h, double *w, struct ray *out)
{
	if (sc->image.no_reflections || h->material == SCENE_NONE || h->material >= sc->n_materials)
		return false;
	const struct scene_material *m = &sc->materials[h->material];
	if (!(m->reflection > 0))
		return false;
	*w *= maxc(v3_scale(m->spec_colour, m->reflection));
	if (!(*w >= SHADE_MIN_WEIGHT))
		return false;
	vec3 ng = h->ng, n = h->n;
	if (!(v3_dot(ng, r->d) < 0)) { /* turned to face the viewer */
		ng = v3_neg(ng);
		n = v3_neg(n);
	}
	vec3 rd = v3_sub(r->d, v3_scale(n, 2 * v3_dot(r->d, n)));
	if (v3_dot(rd, ng) <= 0)
		rd = v3_sub(r->d, v3_scale(ng, 2 * v3_dot(r->d, ng)));
	*out = (struct ray){ accel_offset_point(h->p, ng, rd), rd, 0, INFINITY };
	return true;
}

/* Pixel (x, y)'s chain of mirror rays appended to all (the first to
 * first too). */
static int pixel_rays(const struct scene *sc, const struct accel *a, const struct cam *c, uint32_t x, uint32_t y,
		      struct set *all, struct set *first)
{
	struct ray r = cam_ray(c, x + 0.5, y + 0.5), m;
	struct hit h;
	double w = 1;
	for (int depth = 0; depth < LIM_TRACE_DEPTH; depth++) {
		if (!accel_intersect(a, &r, &h) || !mirror(sc, &r, &h, &w, &m))
			break;
		if (push(all, &m) || (depth == 0 && push(first, &m)))
			return -1;
		r = m;
	}
	return 0;
}

/* Pixel p (0 .. T T - 1) of a tile of side T in the order tile_blocks
 * (render.c) shades them: the tile's 8x8 blocks row by row, each one's
 * sixteen 2x2 blocks as next_8x8 adds them, each 2x2 block row by row;
 * its place in the tile into *i, *j. */
_Static_assert(TILE_DEFAULT % 8 == 0, "whole 8x8 blocks in a tile");
static void tile_pixel(uint32_t T, uint32_t p, uint32_t *i, uint32_t *j)
{
	uint32_t blk = p / 64, b = p % 64 / 4, k = p % 4;
	*i = blk % (T / 8) * 8 + 2 * (b & 1) + 4 * (b >> 2 & 1) + (k & 1);
	*j = blk / (T / 8) * 8 + 2 * (b >> 1 & 1) + 4 * (b >> 3) + (k >> 1);
}

/* Every pixel's chain of mirror rays in the order the renderer shades the
 * pixels: TILE_DEFAULT tiles row by row, each in tile_pixel's order; a
 * pixel's whole chain before the next pixel's. */
static int make_rays(const struct scene *sc, const struct accel *a, const struct cam *c, struct set *all,
		     struct set *first)
{
	const uint32_t T = TILE_DEFAULT;
	for (uint32_t ty = 0; ty < c->h; ty += T)
		for (uint32_t tx = 0; tx < c->w; tx += T)
			for (uint32_t p = 0; p < T * T; p++) {
				uint32_t i, j;
				tile_pixel(T, p, &i, &j);
				if (tx + i < c->w && ty + j < c->h && pixel_rays(sc, a, c, tx + i, ty + j, all, first))
					return -1;
			}
	return 0;
}

/* Traces the rays of s; with hits not NULL, returns a hash of the hits
 * (a sum of per-ray hashes keyed by id[i], the ray's index as made, so
 * that any order gives the same) and counts them into *hits. */
static uint64_t pass(const struct accel *a, const struct set *s, const uint32_t *id, uint64_t *hits)
{
	uint64_t h64 = 0, nh = 0;
	for (size_t i = 0; i < s->n; i++) {
		struct hit h;
		if (accel_intersect(a, &s->r[i], &h) && hits) {
			nh++;
			uint32_t k = id ? id[i] : (uint32_t)i;
			h64 += bs_hash_hit(bs_fnv(1469598103934665603ull, &k, sizeof k), true, &h);
		}
	}
	if (hits)
		*hits = nh;
	return h64;
}

int main(int argc, char **argv)
{
	struct bs_bench b;
	int rc = bs_start(argc, argv, 5, "bench_secondary [SCENE [FRAMES [WIDTHxHEIGHT]]]", &b);
	if (rc)
		return rc;
	struct set all = { 0 }, first = { 0 }, shuf = { 0 };
	uint32_t *perm = NULL;
	int status = 1;
	if (make_rays(b.s, b.a, &b.c, &all, &first)) {
		printf("%s: out of memory\n", b.path);
		goto out;
	}
	if (all.n == 0) {
		status = 0;
		printf("%s %ux%u: no mirror rays (no reflective material seen)\n", b.path, b.w, b.h);
		goto out;
	}
	if (all.n > UINT32_MAX) {
		printf("%s: %zu mirror rays, more than this bench counts\n", b.path, all.n);
		goto out;
	}
	/* the shuffled copy: a fixed pseudo-random order (xorshift64), its
	 * rays stored in that order so that reading them costs what it costs
	 * in the others */
	perm = malloc(all.n * sizeof *perm);
	shuf = (struct set){ malloc(all.n * sizeof *shuf.r), all.n, all.n };
	if (!perm || !shuf.r) {
		printf("%s: out of memory\n", b.path);
		goto out;
	}
	uint64_t x = 88172645463325252ull;
	for (size_t i = 0; i < all.n; i++)
		perm[i] = (uint32_t)i;
	for (size_t i = all.n - 1; i > 0; i--) {
		x ^= x << 13, x ^= x >> 7, x ^= x << 17;
		size_t j = (size_t)(x % (i + 1));
		uint32_t t = perm[i];
		perm[i] = perm[j];
		perm[j] = t;
	}
	for (size_t i = 0; i < all.n; i++)
		shuf.r[i] = all.r[perm[i]];
	uint64_t hits, shits;
	uint64_t h_all = pass(b.a, &all, NULL, &hits), h_shuf = pass(b.a, &shuf, perm, &shits);
	const struct set *sets[3] = { &first, &all, &shuf };
	static const char *names[3] = { "first", "all", "shuffled" };
	double best[3] = { 1e300, 1e300, 1e300 };
	for (int f = 0; f < b.frames; f++) /* interleaved, so a load change hits all three */
		for (int k = 0; k < 3; k++) {
			double t0 = bs_cpu_now();
			pass(b.a, sets[k], NULL, NULL);
			double t = bs_cpu_now() - t0;
			best[k] = t < best[k] ? t : best[k];
		}
	printf("%s %ux%u: %zu mirror rays (%.3f per pixel; %zu first bounces), %llu hit; best of %d, thread CPU time:\n",
	       b.path, b.w, b.h, all.n, (double)all.n / ((double)b.w * b.h), first.n, (unsigned long long)hits, b.frames);
	for (int k = 0; k < 3; k++)
		printf("  %-8s %6.2f Mrays/s (%.1f ns a ray)\n", names[k], (double)sets[k]->n / best[k] * 1e-6,
		       best[k] / (double)sets[k]->n * 1e9);
	printf("  hits hash %016llx, shuffled %016llx%s\n", (unsigned long long)h_all, (unsigned long long)h_shuf,
	       h_all == h_shuf && hits == shits ? "" : " MISMATCH");
	status = h_all == h_shuf && hits == shits ? 0 : 1;
out:
	free(perm);
	free(shuf.r);
	free(all.r);
	free(first.r);
	accel_free(b.a);
	scene_free(b.s);
	return status;
}
