/*
 * test_flatnear.c - FLAT NEAR (common/accel_light.c) changes no answer.
 * First its box's claim on the doubles themselves: for a plane x_p = c and
 * a light coordinate l != c, every origin coordinate o between c and l
 * (inclusive) makes flat_behind true for d = fl(l - o), on special values
 * (signed zeros, subnormals, the largest doubles) and 2 M random ones, at
 * ordinary and subnormal scales. Then light buffers over scenes of flat
 * triangles built to stress the box: planes on both sides of the light on
 * two axes and two on one side of another; planes on one side only; a plane
 * through the light (an empty box on that axis); signed zeros (a plane at
 * -0 with the light at +0, and the reverse); the light one ulp, and one
 * subnormal, off a plane. Origins are taken on the box's bounds, one ulp
 * either side of them, on the planes and at the light's coordinates, and
 * each ray is asked as shading asks it, with -0 direction components, and
 * with tmin -1 and 0.5; accel_occluded_light must give accel_occluded's
 * answer every time, and some origins must fall in the boxes and some rays
 * be blocked (else nothing was compared).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <float.h>
#include "common/accel_int.h"
#include "common/accel_trace.h"
#include "common/parse.h"
#include "common/scene.h"
#include "tests/unit/check.h"
#include "tests/unit/scene_text.h"
#define RAND_VEC_SEED 0x243f6a8885a308d3ull
#include "tests/unit/rand_vec.h"

static double range(double a, double b) { return a + (b - a) * uniform(); }
static long asked, differ, inbox, blocked;

static void ask_ray(const struct accel *a, uint32_t i, struct ray r)
{
	bool tree = accel_occluded(a, &r);
	uint32_t hints[2] = { ACCEL_NO_HINT, REF_MAKE(REF_SPHERE, 0) };
	for (int k = 0; k < 2; k++) {
		uint32_t h = hints[k];
		bool buf = accel_occluded_light(a, i, &r, &h);
		asked++;
		if (buf != tree && differ++ < 10)
			fprintf(stderr, "light %u o (%.17g %.17g %.17g) d (%g %g %g) tmin %g: tree %d buf %d\n", i, r.o.x, r.o.y, r.o.z,
				r.d.x, r.d.y, r.d.z, r.tmin, tree, buf);
	}
	blocked += tree;
}

static void ask(const struct accel *a, uint32_t i, vec3 o)
{
	const struct lbuf *lb = a->lbuf[i];
	vec3 lp = lb->lp;
	struct ray r = { o, v3_sub(lp, o), 0, 1 };
	if (!(v3_dot(r.d, r.d) > 0))
		return;
	if (o.x >= lb->flat_lo.x && o.x <= lb->flat_hi.x && o.y >= lb->flat_lo.y && o.y <= lb->flat_hi.y &&
	    o.z >= lb->flat_lo.z && o.z <= lb->flat_hi.z)
		inbox++;
	ask_ray(a, i, r);
	/* negative zeros in d, and negative tmin */
	struct ray r2 = r;
	if (r2.d.x == 0) r2.d.x = -0.0;
	if (r2.d.y == 0) r2.d.y = -0.0;
	if (r2.d.z == 0) r2.d.z = -0.0;
	r2.tmin = -1;
	ask_ray(a, i, r2);
	r2.tmin = 0.5; /* tmin > 0 */
	ask_ray(a, i, r2);
}

static double pick(double lo, double hi, double c)
{
	switch (rng_mix(state++) % 8) {
	case 0: return lo;
	case 1: return hi;
	case 2: return nextafter(lo, -INFINITY);
	case 3: return nextafter(hi, INFINITY);
	case 4: return c;
	case 5: return nextafter(c, INFINITY);
	case 6: return nextafter(c, -INFINITY);
	default: return range(isfinite(lo) ? lo - 1 : -10, isfinite(hi) ? hi + 1 : 10);
	}
}

static void scene_run(const char *name, vec3 lp, const char *tris)
{
	struct scene_text st = st_new(1 << 18);
#define PUT(...) st_put(&st, __VA_ARGS__)
	PUT("camera look-from (0 0 10) look-at (0 0 0) ;\nimage xsize 4 ysize 4 ;\n");
	PUT("light position (%.17g %.17g %.17g) ;\n", lp.x, lp.y, lp.z);
	for (int i = 0; i < 100; i++)
		PUT("object sphere centre (%.17g %.17g %.17g) radius %.17g ; ;\n", range(-5, 5), range(-5, 5), range(-5, 5),
		    range(0.01, 0.3));
	PUT("%s", tris);
#undef PUT
	struct scene *s = NULL;
	struct scene_error err = { 0 };
	if (!st.ok || parse_buffer(name, st.t, st.len, 0, &s, &err) != 0) {
		fprintf(stderr, "%s: %s\n", name, st.ok ? err.msg : "scene text too long");
		CHECK(0);
		free(st.t);
		return;
	}
	free(st.t);
	struct accel *a = NULL;
	CHECK(accel_build(s, &a, &err) == 0);
	if (!a || !a->lbuf || !a->lbuf[0]) {
		fprintf(stderr, "%s: no buffer\n", name);
		CHECK(0);
		accel_free(a);
		scene_free(s);
		return;
	}
	const struct lbuf *lb = a->lbuf[0];
	CHECK(lb->n_near_flat > 0); /* the planes are what is tested */
	long d0 = differ, in0 = inbox, a0 = asked, b0 = blocked;
	for (int k = 0; k < 200000; k++) {
		/* pick per axis from a flat near plane or the box */
		vec3 o;
		double cs[3] = { range(-6, 6), range(-6, 6), range(-6, 6) };
		if (lb->n_near_flat) {
			const struct lbuf_near *nr = &lb->near[rng_mix(state++) % lb->n_near_flat];
			cs[nr->flat] = nr->c;
		}
		o.x = pick(lb->flat_lo.x, lb->flat_hi.x, cs[0]);
		o.y = pick(lb->flat_lo.y, lb->flat_hi.y, cs[1]);
		o.z = pick(lb->flat_lo.z, lb->flat_hi.z, cs[2]);
		if (rng_mix(state++) % 4 == 0) { /* exactly the light's coordinate on some axis */
			int p = (int)(rng_mix(state++) % 3);
			if (p == 0) o.x = lp.x; else if (p == 1) o.y = lp.y; else o.z = lp.z;
		}
		if (!(fabs(o.x) < 1e6 && fabs(o.y) < 1e6 && fabs(o.z) < 1e6))
			continue;
		ask(a, 0, o);
	}
	printf("test_flatnear: %s: %ld asked, %ld in the box, %ld blocked, %ld differ\n", name, asked - a0, inbox - in0,
	       blocked - b0, differ - d0);
	accel_free(a);
	scene_free(s);
}

static const char *tri(char *buf, int axis, double c, double lo, double hi)
{
	/* a big right triangle in the plane x_axis = c, covering [lo, hi]^2 on the other axes */
	double p[3][3];
	double u[3] = { lo, 2 * hi - lo, lo }, v[3] = { lo, lo, 2 * hi - lo };
	for (int k = 0; k < 3; k++) {
		int b = axis == 0 ? 1 : 0, cc = axis == 2 ? 1 : 2;
		p[k][axis] = c, p[k][b] = u[k], p[k][cc] = v[k];
	}
	snprintf(buf, 512, "object triangle a (%.17g %.17g %.17g) b (%.17g %.17g %.17g) c (%.17g %.17g %.17g) ; ;\n", p[0][0], p[0][1],
		p[0][2], p[1][0], p[1][1], p[1][2], p[2][0], p[2][1], p[2][2]);
	return buf;
}

int main(void)
{
	/* 1. the claim itself on the doubles: c != l, o_p between c and l inclusive, d = fl(l - o) */
	long bad = 0, n = 0;
	double specials[] = { 0.0, -0.0, DBL_MIN, -DBL_MIN, 4.9e-324, -4.9e-324, 1, -1, 1e308, -1e308, DBL_MAX, -DBL_MAX,
			      INFINITY, -INFINITY, 0.1, 0.3, 1e-300, 3.0, 2.9999999999999996 };
	int ns = sizeof specials / sizeof *specials;
	for (int i = 0; i < ns; i++)
		for (int j = 0; j < ns; j++)
			for (int k = 0; k < ns; k++) {
				double c = specials[i], l = specials[j], op = specials[k];
				if (c == l || !isfinite(l))
					continue;
				double lo = geom_fmin(c, l), hi = geom_fmax(c, l);
				if (!(op >= lo && op <= hi))
					continue;
				double dp = l - op;
				if (!isfinite(dp) || !isfinite(op))
					continue; /* ray_ok refuses */
				struct trace tr;
				trace_init(&tr, v3(op, 0, 0), v3(dp, 1, 0), 0, 1);
				n++;
				if (!flat_behind(0, c, &tr)) {
					bad++;
					printf("claim fails: c %g l %g o %g d %g\n", c, l, op, dp);
				}
			}
	for (long k = 0; k < 2000000; k++) {
		double c = range(-4, 4), l = range(-4, 4);
		if (k & 1) c = ldexp(c, -1070), l = ldexp(l, -1070);
		double lo = geom_fmin(c, l), hi = geom_fmax(c, l);
		double op = k % 3 ? lo + (hi - lo) * uniform() : (k % 2 ? lo : hi);
		if (op < lo) op = lo;
		if (op > hi) op = hi;
		struct trace tr;
		trace_init(&tr, v3(op, 0, 0), v3(l - op, 1, 0), 0, 1);
		n++;
		if (c != l && !flat_behind(0, c, &tr))
			bad++;
	}
	printf("test_flatnear: the box's claim: %ld cases, %ld fail\n", n, bad);
	CHECK(bad == 0);

	char b1[512], b2[512], b3[512], b4[512], b5[512], all[4096];
	/* A: planes on both sides on two axes, and two on one side of one axis */
	snprintf(all, sizeof all, "%s%s%s%s%s", tri(b1, 2, -1, -100, 100), tri(b2, 2, 2, -100, 100), tri(b3, 2, -3, -100, 100),
		 tri(b4, 0, 5, -100, 100), tri(b5, 0, -4, -100, 100));
	scene_run("both_sides", v3(0, 0, 0), all);
	/* B: one side only, two planes on z, one on y */
	snprintf(all, sizeof all, "%s%s%s", tri(b1, 2, -1, -100, 100), tri(b2, 2, -2, -100, 100), tri(b3, 1, 7, -100, 100));
	scene_run("one_side", v3(0.25, 0.5, 3), all);
	/* C: a plane through the light */
	snprintf(all, sizeof all, "%s%s", tri(b1, 2, 0.5, -100, 100), tri(b2, 1, -2, -100, 100));
	scene_run("through_light", v3(0.25, 0.5, 0.5), all);
	/* D: signed zeros: plane z = -0, light at z = 0; plane x = 0, light x = -0 */
	snprintf(all, sizeof all, "%s%s", tri(b1, 2, -0.0, -100, 100), tri(b2, 0, 0.0, -100, 100));
	scene_run("signed_zero", v3(-0.0, 0.5, 0), all);
	/* E: light just off the plane (one ulp) */
	snprintf(all, sizeof all, "%s", tri(b1, 2, 1, -100, 100));
	scene_run("ulp_off", v3(0.5, 0.5, nextafter(1, 2)), all);
	snprintf(all, sizeof all, "%s", tri(b1, 2, 0, -100, 100));
	scene_run("subnormal_off", v3(0.5, 0.5, 4.9e-324), all);
	printf("test_flatnear: %ld queries, %ld from the boxes, %ld blocked, %ld answers differ\n", asked, inbox, blocked,
	       differ);
	CHECK(differ == 0);
	CHECK(inbox > 1000 && blocked > 1000 && asked - blocked > 1000);
	TEST_MAIN_END();
}
