/*
 * test_lbuf.c - LIGHT BUFFERS (common/accel_light.c) change no answer:
 * accel_occluded_light gives accel_occluded's answer (the tree's) for
 * shadow rays toward each light, on a scene of spheres from tiny to large,
 * open cylinders at every tilt, a few boxes and triangles, a floor
 * triangle and a wall one, wide seen from most lights (NEAR, FLAT NEAR)
 * and a plane, with
 * lights far away, among the objects, at a sphere's surface, inside a
 * sphere and on a box's face. The rays start anywhere in and around the
 * scene (beyond the buffer's reach too), on the surfaces as shading starts
 * them (1e-9 off), very near the lights (1e-15 to 1e-2 away), on the
 * diagonals between cube faces, and in directions exactly along the axes;
 * each is asked with no hint, a right hint and a wrong one. The test
 * fails if a light that should have a buffer has none, or if the answers
 * are all the same (nothing would have been compared).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/accel_int.h"
#include "common/parse.h"
#include "common/rng.h"
#include "common/scene.h"
#include "tests/unit/check.h"
#include "tests/unit/scene_text.h"
#define RAND_VEC_SEED 0x13198a2e03707344ull
#include "tests/unit/rand_vec.h"

static double range(double a, double b) { return a + (b - a) * uniform(); }

/* The lights: far, among the objects, on sphere 0's surface (centre
 * (0 0 0), radius 1), inside sphere 1, on the box's top face, and very
 * far (the scene in a corner of one face: ZOOMED FACES). */
static const vec3 lights[] = {
	{ 30, 20, 25 }, { 0.3, 2.5, -0.7 }, { 1, 0, 0 }, { 3, 3, 3.05 }, { -2, -1.5, 1.25 }, { 150, -90, 120 },
};
#define N_LIGHTS (sizeof lights / sizeof lights[0])

/* the box and the triangles' corners (as written into the scene) */
static vec3 corners[8 + 3 * 21];
static int n_corners;
static vec3 tri_mid[21];
static vec3 sliver[3]; /* the sliver beside light 1 */

static char *scene_text(void)
{
	struct scene_text st = st_new(1 << 20);
#define PUT(...) st_put(&st, __VA_ARGS__)
	PUT("camera look-from (0 0 10) look-at (0 0 0) ;\nimage xsize 4 ysize 4 ;\n");
	for (size_t i = 0; i < N_LIGHTS; i++)
		PUT("light position (%.17g %.17g %.17g) ;\n", lights[i].x, lights[i].y, lights[i].z);
	PUT("object sphere centre (0 0 0) radius 1 ; ;\n");
	PUT("object sphere centre (3 3 3) radius 0.2 ; ;\n");
	PUT("object box a (-2.5 -2 0.25) b (-1.5 -1 1.25) ; ;\n");
	for (int k = 0; k < 8; k++)
		corners[n_corners++] = v3(k & 1 ? -1.5 : -2.5, k & 2 ? -1 : -2, k & 4 ? 1.25 : 0.25);
	PUT("object plane position (0 0 -6) normal (0 0 1) ; ;\n");
	for (int i = 0; i < 300; i++) { /* a cloud of spheres, tiny to large */
		vec3 c = v3(range(-5, 5), range(-5, 5), range(-5, 5));
		double r = exp(range(log(1e-3), log(0.6)));
		PUT("object sphere centre (%.17g %.17g %.17g) radius %.17g ; ;\n", c.x, c.y, c.z, r);
	}
	for (int i = 0; i < 120; i++) { /* open cylinders, sliced when long and tilted */
		vec3 a = v3(range(-5, 5), range(-5, 5), range(-5, 5)), b = v3_add(a, v3_scale(unit(), range(0.1, 6)));
		PUT("object cylinder from (%.17g %.17g %.17g) to (%.17g %.17g %.17g) radius %.17g ; ;\n", a.x, a.y, a.z,
		    b.x, b.y, b.z, range(0.005, 0.2));
	}
	for (int i = 0; i < 20; i++) { /* triangles, some large (split into pieces) */
		vec3 a = v3(range(-5, 5), range(-5, 5), range(-5, 5));
		double s = i < 4 ? 8 : 0.5;
		vec3 b = v3_add(a, v3_scale(unit(), s)), c = v3_add(a, v3_scale(unit(), s));
		corners[n_corners++] = a;
		corners[n_corners++] = b;
		corners[n_corners++] = c;
		tri_mid[i] = v3_scale(v3_add(a, v3_add(b, c)), 1.0 / 3);
		PUT("object triangle a (%.17g %.17g %.17g) b (%.17g %.17g %.17g) c (%.17g %.17g %.17g) ; ;\n", a.x, a.y,
		    a.z, b.x, b.y, b.z, c.x, c.y, c.z);
	}
	{ /* a floor triangle in the plane z = -5.5 (FLAT TRIANGLES), wide
	     seen from every light: NEAR, with its plane (FLAT NEAR); rays
	     from below it are blocked by it, rays from above never */
		vec3 a = v3(-40, -40, -5.5), b = v3(60, -40, -5.5), c = v3(-40, 60, -5.5);
		corners[n_corners++] = a;
		corners[n_corners++] = b;
		corners[n_corners++] = c;
		tri_mid[20] = v3_scale(v3_add(a, v3_add(b, c)), 1.0 / 3);
		PUT("object triangle a (%.17g %.17g %.17g) b (%.17g %.17g %.17g) c (%.17g %.17g %.17g) ; ;\n", a.x, a.y,
		    a.z, b.x, b.y, b.z, c.x, c.y, c.z);
		/* and a wall in x = 9: beyond the scene for most lights, between
		   it and the lights at x = 30 and 150 */
		PUT("object triangle a (9 -40 -40) b (9 60 -40) c (9 -40 60) ; ;\n");
	}
	{ /* a long diagonal sliver about half a unit from light 1, split into pieces
	     (LONG slivers, accel_build.c) of which several are WIDE: its NEAR
	     entry's box is their union */
		vec3 l = lights[1], o = v3(0.4, -0.4, 0.1);
		vec3 a = v3_add(l, v3_add(o, v3(-3, -3, -3))), b = v3_add(l, v3_add(o, v3(3, 3, 3)));
		vec3 c = v3_add(b, v3(0.05, -0.05, 0));
		sliver[0] = a, sliver[1] = b, sliver[2] = c;
		PUT("object triangle a (%.17g %.17g %.17g) b (%.17g %.17g %.17g) c (%.17g %.17g %.17g) ; ;\n", a.x, a.y,
		    a.z, b.x, b.y, b.z, c.x, c.y, c.z);
	}
#undef PUT
	if (!st.ok)
		free(st.t);
	return st.ok ? st.t : NULL;
}

static long asked, blocked, lit, differ;

/* One shadow ray from o toward light i at lp, asked of both with three hints. */
static void ask_lp(const struct accel *a, uint32_t i, vec3 lp, vec3 o)
{
	struct ray r = { o, v3_sub(lp, o), 0, 1 };
	if (!(v3_dot(r.d, r.d) > 0))
		return;
	bool tree = accel_occluded(a, &r);
	uint32_t hints[3] = { ACCEL_NO_HINT, ACCEL_NO_HINT, REF_MAKE(REF_SPHERE, 0) };
	uint32_t h = ACCEL_NO_HINT;
	if (accel_occluded_hint(a, &r, &h))
		hints[1] = h; /* the blocker the tree found */
	for (int k = 0; k < 3; k++) {
		uint32_t hint = hints[k];
		bool buf = accel_occluded_light(a, i, &r, &hint);
		asked++;
		if (buf != tree) {
			if (differ++ < 10)
				fprintf(stderr, "light %u from (%.17g %.17g %.17g): tree %d, buffer %d\n", i, o.x, o.y, o.z, tree,
					buf);
		}
	}
	if (tree)
		blocked++;
	else
		lit++;
}

static void ask(const struct accel *a, uint32_t i, vec3 o) { ask_lp(a, i, lights[i], o); }

static vec3 near_surface(vec3 c, double r);

/*
 * ZOOMED FACES over budget: a light at the origin, a dense cluster of 2,000
 * small spheres 50 away (a zoomed window on face -x) and 15 larger spheres
 * beyond it, each covering the whole window (16,384 cells zoomed, about
 * 3,000 unzoomed): zoomed, the entries would pass the budget, so the
 * buffer is built with whole faces instead of not at all; and it answers
 * as the tree does.
 */
static void zoom_budget(void)
{
	struct scene_text st = st_new(1 << 18);
#define PUT(...) st_put(&st, __VA_ARGS__)
	PUT("camera look-from (0 0 10) look-at (0 0 0) ;\nimage xsize 4 ysize 4 ;\nlight position (0 0 0) ;\n");
	for (int i = 0; i < 2000; i++)
		PUT("object sphere centre (%.17g %.17g %.17g) radius 0.01 ; ;\n", range(-51, -49), range(-1, 1), range(-1, 1));
	for (int k = 0; k < 15; k++) { /* box half-size / nearest depth about 0.43 */
		double x = 60 + 30 * k;
		PUT("object sphere centre (%.17g 0 0) radius %.17g ; ;\n", -x, 0.3 * x);
	}
#undef PUT
	CHECK(st.ok);
	struct scene *s = NULL;
	struct scene_error err = { 0 };
	CHECK(st.ok && parse_buffer("budget.sce", st.t, st.len, 0, &s, &err) == 0);
	free(st.t);
	struct accel *a = NULL;
	if (s)
		CHECK(accel_build(s, &a, &err) == 0);
	if (!a) {
		scene_free(s);
		return;
	}
	const struct lbuf *lb = a->lbuf ? a->lbuf[0] : NULL;
	CHECK(lb != NULL); /* with whole faces */
	if (lb)
		CHECK(lb->scale[1][0] == 0.5 * lb->n && lb->scale[1][1] == 0.5 * lb->n);
	long before = differ;
	vec3 lp = v3(0, 0, 0);
	for (int k = 0; k < 20000; k++) {
		const struct gsphere *g = &a->root->sph[rng_mix(state++) % a->root->n_sph];
		ask_lp(a, 0, lp, near_surface(v3_add(g->c, a->root->center), sqrt(g->r2)));
		ask_lp(a, 0, lp, v3(range(-600, -40), range(-200, 200), range(-200, 200)));
	}
	printf("test_lbuf: over budget zoomed, a buffer of whole faces: %ld answers differ\n", differ - before);
	accel_free(a);
	scene_free(s);
}

/* A point on or just off a sphere of the scene (centre c, radius r), as
 * shading starts a ray there: on it, or 1e-9 (of the coordinates) out or in. */
static vec3 near_surface(vec3 c, double r)
{
	vec3 n = unit(), p = v3_add(c, v3_scale(n, r));
	double m = 1 + fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z)));
	switch (rng_mix(state++) % 3) {
	case 0: return p;
	case 1: return v3_add(p, v3_scale(n, 1e-9 * m));
	default: return v3_sub(p, v3_scale(n, 1e-9 * m));
	}
}

/* A scene of a few objects keeps the tree alone (LBUF_MIN_REFS): its
 * light has no buffer, and accel_light_buffered says so. */
static void small_scene_unbuffered(void)
{
	static const char text[] = "camera look-from (0 0 10) look-at (0 0 0) ;\nimage xsize 4 ysize 4 ;\n"
				   "light position (5 5 5) ;\nobject sphere centre (0 0 0) radius 1 ; ;\n";
	struct scene *s = NULL;
	struct scene_error err = { 0 };
	CHECK(parse_buffer("small.sce", text, strlen(text), 0, &s, &err) == 0);
	struct accel *a = NULL;
	if (s)
		CHECK(accel_build(s, &a, &err) == 0);
	if (a)
		CHECK(!accel_light_buffered(a, 0));
	accel_free(a);
	scene_free(s);
}

int main(void)
{
	char *text = scene_text();
	CHECK(text != NULL);
	if (!text)
		TEST_MAIN_END();
	struct scene *s = NULL;
	struct scene_error err = { 0 };
	CHECK(parse_buffer("lbuf.sce", text, strlen(text), 0, &s, &err) == 0);
	free(text);
	if (!s) {
		fprintf(stderr, "%s\n", err.msg);
		TEST_MAIN_END();
	}
	struct accel *a = NULL;
	CHECK(accel_build(s, &a, &err) == 0);
	if (!a) {
		scene_free(s);
		TEST_MAIN_END();
	}
	for (uint32_t i = 0; i < N_LIGHTS; i++) { /* every light has a buffer: it is what is tested */
		if (!(a->lbuf && a->lbuf[i]))
			fprintf(stderr, "light %u: no buffer\n", i);
		CHECK(a->lbuf && a->lbuf[i] != NULL);
		CHECK(accel_light_buffered(a, i)); /* what shading asks (BUFFERED LIGHTS) */
	}
	CHECK(!accel_light_buffered(a, N_LIGHTS)); /* no such light */
	int flat_near = 0; /* FLAT NEAR: the floor and the wall in the NEAR lists of the lights that see them wide */
	for (uint32_t i = 0; i < N_LIGHTS; i++)
		for (uint32_t k = 0; a->lbuf && a->lbuf[i] && k < a->lbuf[i]->n_near; k++)
			flat_near += a->lbuf[i]->near[k].flat <= 2;
	printf("test_lbuf: %d flat NEAR triangles\n", flat_near);
	CHECK(flat_near > 0);
	small_scene_unbuffered();

	/* ZOOMED FACES (accel_light.c): some face's cells cover a window
	 * (the last light sees the whole scene in a small part of a face) */
	int zoomed = 0;
	for (uint32_t i = 0; i < N_LIGHTS; i++)
		for (int f = 0; a->lbuf && a->lbuf[i] && f < 6; f++)
			zoomed += a->lbuf[i]->scale[f][0] != 0.5 * a->lbuf[i]->n;
	printf("test_lbuf: %d zoomed faces\n", zoomed);
	CHECK(zoomed > 0);

	const struct gsphere *sph = a->root->sph;
	uint32_t n_sph = a->root->n_sph;
	for (uint32_t i = 0; i < N_LIGHTS; i++) {
		vec3 lp = lights[i];
		for (int k = 0; k < 20000; k++) /* anywhere in and around the scene, beyond R too */
			ask(a, i, v3(range(-8, 8), range(-8, 8), range(-8, 8)));
		for (int k = 0; k < 5000; k++) { /* below the floor and on it, beyond the wall and on it (FLAT NEAR) */
			ask(a, i, v3(range(-8, 8), range(-8, 8), k % 5 ? range(-7, -5.5) : -5.5));
			ask(a, i, v3(k % 5 ? range(9, 10) : 9, range(-8, 8), range(-8, 8)));
		}
		for (int k = 0; k < 200; k++) /* far beyond the buffer's reach */
			ask(a, i, v3_scale(unit(), 1e3));
		for (int k = 0; k < 20000; k++) { /* on the spheres, as shading starts rays */
			const struct gsphere *g = &sph[rng_mix(state++) % n_sph];
			ask(a, i, near_surface(v3_add(g->c, a->root->center), sqrt(g->r2)));
		}
		for (int k = 0; k < 5000; k++) /* very near the light */
			ask(a, i, v3_add(lp, v3_scale(unit(), exp(range(log(1e-15), log(1e-2))))));
		for (int k = 0; k < n_corners; k++) /* through the corners' edges of the boxes' projections */
			for (int m = 0; m < 40; m++) {
				vec3 x = corners[k], in = k < 8 ? v3_sub(v3(-2, -1.5, 0.75), x) : v3_sub(tri_mid[(k - 8) / 3], x);
				x = v3_add(x, v3_scale(in, m < 20 ? 1e-9 : exp(range(log(1e-12), log(1e-3)))));
				ask(a, i, v3_add(lp, v3_scale(v3_sub(x, lp), range(1.05, 4))));
			}
		for (int k = 0; i == 1 && k < 4000; k++) { /* through the sliver's pieces, from beyond it */
			double u = uniform(), v = uniform();
			if (u + v > 1)
				u = 1 - u, v = 1 - v;
			vec3 x = v3_add(sliver[0], v3_add(v3_scale(v3_sub(sliver[1], sliver[0]), u),
							 v3_scale(v3_sub(sliver[2], sliver[0]), v)));
			ask(a, i, v3_add(lp, v3_scale(v3_sub(x, lp), range(1.05, 4))));
		}
		for (int k = 0; k < 5000; k++) { /* on the cube's edges and along its axes */
			double d = range(0.01, 10), e = range(-1, 1);
			int f = (int)(rng_mix(state++) % 6);
			vec3 u = f < 2 ? v3(d, f ? -d : d, e * d) : f < 4 ? v3(e * d, d, f == 3 ? -d : d) : v3(0, 0, f == 4 ? d : -d);
			ask(a, i, v3_add(lp, u));
		}
	}
	zoom_budget();
	printf("test_lbuf: %ld queries, %ld blocked and %ld lit rays, %ld answers differ\n", asked, blocked, lit,
	       differ);
	CHECK(differ == 0);
	CHECK(blocked > 1000 && lit > 1000);
	accel_free(a);
	scene_free(s);
	TEST_MAIN_END();
}
