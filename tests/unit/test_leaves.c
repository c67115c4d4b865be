/*
 * test_leaves.c - the triangle pre-test on leaf blocks (LEAF BLOCKS in
 * accel_int.h, TRIANGLE PRE-TEST in accel_trace.h) never culls a hit. Scenes of
 * small patches of one to four triangles sharing vertices and edges (each
 * patch far from the others, so its triangles make one leaf of that many),
 * plus sliver triangles (split into several references: leaves that name
 * one triangle more than once), near the origin and 1000 units away. Rays
 * are aimed at the patches' vertices, edge midpoints, points along edges
 * and interiors, exactly and off by 1e-15 to 1e-7, from anywhere around
 * and from just above a patch's plane (grazing). Every query is compared
 * with accel_intersect_brute, which tests every triangle in double without
 * the pre-test: accel_intersect and accel_intersect4 give its hit bit for
 * bit; accel_occluded, accel_occluded_hint and accel_occluded4 say
 * "blocked" exactly when it hits. A pre-test that rejected a ray its
 * triangle is hit by fails here (a margin 100 times too small does).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/accel.h"
#include "common/rng.h"
#include "common/scene.h"
#include "tests/unit/check.h"
#include "tests/unit/same_hit.h"

#define N_PATCHES 64
#define N_RAYS 24000

struct patch {
	vec3 v[6];
	int n_tris;
};

static void add_tri(struct scene *s, vec3 a, vec3 b, vec3 c)
{
	struct scene_error err;
	struct scene_object o;
	scene_object_defaults(&o, PRIM_TRIANGLE);
	o.u.triangle.a = a;
	o.u.triangle.b = b;
	o.u.triangle.c = c;
	uint32_t id;
	CHECK(scene_add_object(s, &o, &id, &err) == 0);
	CHECK(scene_add_root(s, id, &err) == 0);
}

/* Patch p: 1 to 4 triangles sharing edge v0 v1 (pages of a book, opened a
 * little: their boxes nearly one, so the builder keeps them in one leaf),
 * or a sliver pair (long and thin: split into several references), 10
 * units from its neighbours, tilted so that rays of every dominant axis
 * meet it. */
static void make_patch(struct patch *P, int p, double x0)
{
	vec3 c = v3(x0 + 10.0 * (p % 8), 10.0 * (p / 8 % 8), 0.37 * (p % 5));
	double tilt = 0.3 * (p % 7) - 0.9;
	P->v[0] = c;
	if (p % 6 == 5) { /* slivers: two thin triangles sharing a long edge */
		P->v[1] = v3_add(c, v3(7.9, 0.05, 0.4 * tilt));
		P->v[2] = v3_add(c, v3(8.0, 0.11, 0.4 * tilt + 0.01));
		P->v[3] = v3_add(c, v3(0.1, 0.09, -0.02));
		P->n_tris = 2;
		return;
	}
	P->n_tris = 1 + p % 4;
	P->v[1] = v3_add(c, v3(1.0, 0.2, tilt));
	for (int i = 0; i < P->n_tris; i++) {
		double phi = 0.5 * i + tilt;
		P->v[2 + i] = v3_add(c, v3(0.5 + 0.05 * i, 0.8 * cos(phi), 0.8 * sin(phi)));
	}
}

/* The patch's triangle k: (v0, v1, v[k+2]), or the slivers' (v0 v1 v2) and
 * (v0 v2 v3). */
static void patch_tri(const struct patch *P, int p, int k, vec3 t[3])
{
	t[0] = P->v[0];
	if (p % 6 == 5) {
		t[1] = P->v[1 + k];
		t[2] = P->v[2 + k];
		return;
	}
	t[1] = P->v[1];
	t[2] = P->v[2 + k];
}

/* A point of patch p for ray k: a vertex, an edge's midpoint, a point along
 * an edge, or inside, moved off by e in a random direction. */
static vec3 target(const struct patch *P, int p, uint64_t k, double e)
{
	vec3 t[3];
	patch_tri(P, p, (int)(rng_uniform(41, k) * P->n_tris), t);
	int j = (int)(rng_uniform(42, k) * 3);
	vec3 a = t[j], b = t[(j + 1) % 3];
	vec3 q;
	switch (k % 4) {
	case 0: q = a; break;
	case 1: q = v3_scale(v3_add(a, b), 0.5); break;
	case 2: q = v3_lerp(a, b, rng_uniform(43, k)); break;
	default: {
		double u = rng_uniform(44, k), w = rng_uniform(45, k) * (1 - u);
		q = v3_add(v3_add(v3_scale(t[0], 1 - u - w), v3_scale(t[1], u)), v3_scale(t[2], w));
		break;
	}
	}
	vec3 d = v3(rng_uniform(46, k) - 0.5, rng_uniform(47, k) - 0.5, rng_uniform(48, k) - 0.5);
	return v3_add(q, v3_scale(d, e));
}

/* Whether brute force finds a hit in r's interval (what the any-hit
 * queries must answer). */
static bool brute_blocked(const struct accel *a, const struct ray *r)
{
	struct hit h;
	return accel_intersect_brute(a, r, &h);
}

static void leaf_blocks(double x0)
{
	struct scene *s = scene_new();
	struct patch P[N_PATCHES];
	for (int p = 0; p < N_PATCHES; p++) {
		make_patch(&P[p], p, x0);
		for (int k = 0; k < P[p].n_tris; k++) {
			vec3 t[3];
			patch_tri(&P[p], p, k, t);
			add_tri(s, t[0], t[1], t[2]);
		}
	}
	struct accel *a;
	struct scene_error err;
	CHECK(accel_build(s, &a, &err) == 0);
	static const double offs[] = { 0, 1e-15, 1e-12, 1e-9, 1e-7 };
	int single_bad = 0, occ_bad = 0, packet_bad = 0, hits = 0;
	uint32_t hint = ACCEL_NO_HINT;
	for (int k = 0; k < N_RAYS / 4; k++) {
		int p = (int)(rng_uniform(50, (uint64_t)k) * N_PATCHES);
		double e = offs[k % 5];
		vec3 c = P[p].v[0];
		vec3 o;
		if (k % 3 == 2) { /* grazing: just off the patch's plane, beside it */
			vec3 t[3];
			patch_tri(&P[p], p, 0, t);
			vec3 n = v3_norm(v3_cross(v3_sub(t[1], t[0]), v3_sub(t[2], t[0])));
			vec3 side = v3_norm(v3_sub(t[1], t[0]));
			o = v3_add(v3_add(c, v3_scale(side, -2 - rng_uniform(51, k))),
				   v3_scale(n, (rng_uniform(52, k) - 0.5) * 1e-3));
		} else {
			o = v3_add(c, v3(8 * rng_uniform(53, k) - 4, 8 * rng_uniform(54, k) - 4, 8 * rng_uniform(55, k) - 4));
		}
		struct ray r[4];
		for (int l = 0; l < 4; l++) {
			/* four neighbours from one origin (a packet), or four points of the patch */
			uint64_t kk = k % 2 ? 4ull * k + (uint64_t)l : 4ull * k;
			vec3 tl = target(&P[p], p, kk, e * (l + 1));
			r[l] = (struct ray){ o, v3_sub(tl, o), 0, INFINITY };
			if (k % 7 == 3) /* a window: a shadow ray toward a point past the patch */
				r[l].tmax = 1 + 1e-3 * l;
		}
		struct hit h4[4], h1, hb;
		bool hit4[4], occ4[4];
		accel_intersect4(a, r, h4, hit4);
		uint32_t h4hint = k % 5 == 4 ? (uint32_t)rng_mix((uint64_t)k) : hint;
		accel_occluded4(a, r, occ4, &h4hint);
		for (int l = 0; l < 4; l++) {
			bool bb = accel_intersect_brute(a, &r[l], &hb);
			bool b1 = accel_intersect(a, &r[l], &h1);
			hits += bb;
			single_bad += !same_hit(b1, &h1, bb, &hb);
			packet_bad += !same_hit(hit4[l], &h4[l], bb, &hb) || occ4[l] != brute_blocked(a, &r[l]);
			occ_bad += accel_occluded(a, &r[l]) != bb || accel_occluded_hint(a, &r[l], &hint) != bb;
		}
	}
	printf("leaf blocks (%s): %d rays, %d hits; unlike brute force: %d single, %d any-hit, %d packet\n",
	       x0 ? "1000 units away" : "at the origin", N_RAYS, hits, single_bad, occ_bad, packet_bad);
	CHECK(single_bad == 0);
	CHECK(occ_bad == 0);
	CHECK(packet_bad == 0);
	CHECK(hits > N_RAYS / 4);
	accel_free(a);
	scene_free(s);
}

int main(void)
{
	leaf_blocks(0);
	leaf_blocks(1000);
	TEST_MAIN_END();
}
