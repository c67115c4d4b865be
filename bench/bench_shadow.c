/*
 * bench_shadow.c - the A/B figure for shadow rays: the eye rays of every
 * pixel centre find their closest hits (2x2 blocks, as the renderer), then
 * each hit sends one shadow ray to every point light that casts shadows
 * and lies in front of the surface (the ray shading makes: from
 * accel_offset_point to the light, tmin 0, tmax 1). Those rays, made once,
 * are traced FRAMES times three ways, one thread:
 *   single   accel_occluded, one ray at a time (the query before issue 13)
 *   hint     accel_occluded_hint with one last-blocker hint per light
 *   packet   accel_occluded4 over the rays of one 2x2 block toward one
 *            light, one hint per light (what the renderer does)
 *   light    accel_occluded_light, one ray at a time with one hint per
 *            light: the light's LIGHT BUFFER where it has one (what the
 *            renderer does for the shadow rays of reflection hits)
 * and prints the best frame's rate in Mrays/s of thread CPU time, and a
 * hash of the answers, which must be the same all four ways. Then the
 * same rays as SHADOW CROSSINGS (every surface on the segment, what a scene
 * with transparent materials asks for, with shading's filter,
 * shade_cross_filter), two ways whose hashes must agree:
 *   cross    accel_cross, one ray at a time, one hint per light
 *   cross4   accel_cross4 over the rays of one 2x2 block toward one light
 *            (what the renderer does for the eye hits of gears_s2)
 *
 *   bench_shadow [SCENE [FRAMES [WIDTHxHEIGHT]]]
 *
 * Defaults: tests/data/spd/balls_s4.sce, 7 frames, 1280x960. Target
 * (issue 13): >= 20 Mrays/s per core on balls_s4. Not a test.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/accel.h"
#include "common/camera.h"
#include "common/shade.h"
#include "bench/bench_scene.h"

/* Shadow rays in packets of four: n live rays (the rest repeat the last)
 * toward light `light`. */
struct pack {
	struct ray r[4];
	int n;
	uint32_t light;
};

struct set {
	struct pack *p;
	size_t n, cap;
	size_t rays;
};

static int push(struct set *s, const struct pack *p)
{
	struct pack *np = bs_grow(s->p, &s->cap, s->n, sizeof *np, 4096);
	if (!np)
		return -1;
	s->p = np;
	s->p[s->n++] = *p;
	s->rays += (size_t)p->n;
	return 0;
}

/* The shadow rays of the frame's primary hits, block by block, light by light. */
static int make_rays(const struct scene *sc, const struct accel *a, const struct cam *c, struct set *s)
{
	for (uint32_t y = 0; y < c->h; y += 2) {
		for (uint32_t x = 0; x < c->w; x += 2) {
			struct ray r[4];
			struct hit h[4];
			bool hit[4];
			bs_block_hits(a, c, x, y, r, h, hit);
			for (uint32_t l = 0; l < sc->n_lights; l++) {
				const struct scene_light *L = &sc->lights[l];
				if (L->shape != LIGHT_POINT || L->no_shadows)
					continue;
				struct pack p = { .n = 0, .light = l };
				for (uint32_t i = 0; i < 4; i++) {
					if (!hit[i] || x + (i & 1) >= c->w || y + (i >> 1) >= c->h)
						continue;
					vec3 ng = v3_dot(h[i].ng, r[i].d) < 0 ? h[i].ng : v3_neg(h[i].ng);
					vec3 to = v3_sub(L->position, h[i].p);
					double dist = v3_len(to);
					if (!(dist > 0) || v3_dot(ng, to) <= 0)
						continue;
					vec3 o = accel_offset_point(h[i].p, ng, v3_scale(to, 1 / dist));
					p.r[p.n++] = (struct ray){ o, v3_sub(L->position, o), 0, 1 };
				}
				if (!p.n)
					continue;
				for (int i = p.n; i < 4; i++)
					p.r[i] = p.r[p.n - 1];
				if (push(s, &p))
					return -1;
			}
		}
	}
	return 0;
}

enum mode { SINGLE, HINT, PACKET, LIGHT, CROSS, CROSS4, N_MODES };

/* Hash of a crossing query's answer: open, then each crossing's t and light. */
static uint64_t cross_hash(uint64_t h64, bool open, const struct accel_crossings *x)
{
	h64 = (h64 ^ (uint64_t)open) * 1099511628211ull;
	for (int k = 0; open && k < x->n; k++) {
		uint64_t b[4];
		memcpy(&b[0], &x->x[k].t, 8);
		memcpy(&b[1], &x->x[k].p.td, 8);
		memcpy(&b[2], &x->x[k].p.col.x, 8);
		memcpy(&b[3], &x->x[k].p.col.z, 8);
		for (int j = 0; j < 4; j++)
			h64 = (h64 ^ b[j]) * 1099511628211ull;
	}
	return h64;
}

/* One pass over the rays; returns the hash of the answers. */
static uint64_t pass(const struct accel *a, const struct set *s, enum mode m, uint32_t n_lights,
		     const struct accel_cross_filter *f)
{
	uint32_t *hint = malloc((n_lights ? n_lights : 1) * sizeof *hint);
	if (!hint)
		return 0;
	for (uint32_t l = 0; l < n_lights; l++)
		hint[l] = ACCEL_NO_HINT;
	uint64_t h64 = 1469598103934665603ull;
	for (size_t k = 0; k < s->n; k++) {
		const struct pack *p = &s->p[k];
		bool occ[4];
		if (m == CROSS || m == CROSS4) {
			static struct accel_crossings x[4];
			bool open[4];
			if (m == CROSS4)
				accel_cross4(a, p->r, f, x, open, &hint[p->light]);
			else
				for (int i = 0; i < p->n; i++)
					open[i] = accel_cross(a, &p->r[i], f, &x[i], &hint[p->light]);
			for (int i = 0; i < p->n; i++)
				h64 = cross_hash(h64, open[i], &x[i]);
			continue;
		}
		if (m == PACKET)
			accel_occluded4(a, p->r, occ, &hint[p->light]);
		else
			for (int i = 0; i < p->n; i++)
				occ[i] = m == HINT    ? accel_occluded_hint(a, &p->r[i], &hint[p->light])
					 : m == LIGHT ? accel_occluded_light(a, p->light, &p->r[i], &hint[p->light])
						      : accel_occluded(a, &p->r[i]);
		for (int i = 0; i < p->n; i++)
			h64 = (h64 ^ (uint64_t)occ[i]) * 1099511628211ull;
	}
	free(hint);
	return h64;
}

int main(int argc, char **argv)
{
	struct bs_bench b;
	int rc = bs_start(argc, argv, 7, "bench_shadow [SCENE [FRAMES [WIDTHxHEIGHT]]]", &b);
	if (rc)
		return rc;
	struct set s = { 0 };
	if (make_rays(b.s, b.a, &b.c, &s)) {
		printf("%s: out of memory\n", b.path);
		return 1;
	}
	static const char *names[N_MODES] = { "single", "hint", "packet", "light", "cross", "cross4" };
	uint64_t hash[N_MODES];
	double best[N_MODES];
	struct shade_ctx *sc; /* the crossings' filter: shading's */
	struct scene_error err;
	if (shade_ctx_new(b.s, b.a, &sc, &err)) {
		printf("%s: %s\n", b.path, err.msg);
		return 1;
	}
	const struct accel_cross_filter *filt = shade_cross_filter(sc);
	for (int m = 0; m < N_MODES; m++) {
		best[m] = INFINITY;
		hash[m] = pass(b.a, &s, (enum mode)m, b.s->n_lights, filt);
	}
	for (int f = 0; f < b.frames; f++) /* interleaved, so a load change hits all of them */
		for (int m = 0; m < N_MODES; m++) {
			double t0 = bs_cpu_now();
			pass(b.a, &s, (enum mode)m, b.s->n_lights, filt);
			double t = bs_cpu_now() - t0;
			best[m] = t < best[m] ? t : best[m];
		}
	printf("%s %ux%u: %zu shadow rays (%.2f per pixel), best of %d, thread CPU time:\n", b.path, b.w, b.h, s.rays,
	       (double)s.rays / ((double)b.w * b.h), b.frames);
	int bad = 0;
	for (int m = 0; m < N_MODES; m++) {
		bool same = hash[m] == hash[m < CROSS ? SINGLE : CROSS];
		bad |= !same;
		printf("  %-6s %6.2f Mrays/s; answers hash %016llx%s\n", names[m], (double)s.rays / best[m] * 1e-6,
		       (unsigned long long)hash[m], same ? "" : " MISMATCH");
	}
	shade_ctx_free(sc);
	free(s.p);
	accel_free(b.a);
	scene_free(b.s);
	return bad;
}
