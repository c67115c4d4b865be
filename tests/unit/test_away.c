/*
 * test_away.c - AWAY, the early miss of a ray that leaves a sphere or an
 * open cylinder's tube (sphere_test in common/accel_trace.h,
 * geom_cyl_open_hit in common/geom.h), changes no answer. Each is compared
 * with the same test without it (sphere_test_with and geom_cyl_open_test,
 * away false), on rays from points on
 * the surface, just outside and just inside it (by 1e-9 of the radius and
 * the coordinates, as shading offsets a ray's start, and by more), in every
 * direction, with tmin 0, tiny or negative and tmax infinite or finite, at
 * scales from 1e-3 to 1e3 and centres up to 1e3 away: the same hit or
 * miss, and the same t bit for bit. And FLAT TRIANGLES (flat_triangles
 * below): the rule is right, and moves no hit of a ray that starts off
 * the plane.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "common/accel_trace.h"
#include "common/rng.h"
#include "tests/unit/check.h"
#define RAND_VEC_SEED 0x243f6a8885a308d3ull
#include "tests/unit/rand_vec.h"

#define N_RAYS 400000

/* A start at distance rad (1 + e) from a centre (or axis) along n: on the
 * surface, 1e-9 out or in (relative, and as shade.c's offset: of the
 * coordinates), or well away. */
static double start_e(const vec3 c)
{
	double m = fmax(fabs(c.x), fmax(fabs(c.y), fabs(c.z)));
	switch ((int)(uniform() * 6)) {
	case 0: return 0;
	case 1: return 1e-9;
	case 2: return -1e-9;
	case 3: return 1e-9 * (1 + m);
	case 4: return 4 * uniform() - 2;
	default: return (uniform() - 0.5) * 1e-6;
	}
}

static void limits(double *tmin, double *tmax)
{
	double u = uniform();
	*tmin = u < 0.6 ? 0 : u < 0.8 ? 1e-12 : -1;
	*tmax = uniform() < 0.5 ? INFINITY : 10 * uniform();
}

/*
 * FLAT TRIANGLES (tri_flat_behind in common/accel_trace.h): a triangle
 * whose vertices share the coordinate of one axis bit for bit, and rays
 * from points on it (inside and beyond its edges), on its plane, 1e-9 off
 * it either side (of the coordinates, as shading offsets them) or well
 * away, steep and grazing. Wherever tri_flat_behind says "no hit":
 *   - the ray does not reach the plane: its origin's distance from it,
 *     o_p - c, is 0 or of d_p's sign, or d_p is 0 (computed apart, in
 *     long double, as a check of the rule's exact comparisons);
 *   - geom_tri_hit_p says "no hit" too for every ray that starts off the
 *     plane (*bad counts those it hits: none, so the rule moves no pixel
 *     of a ray that shading starts), and its rounding hits of rays that
 *     start in the plane (*on_plane) lie within 1e-9 of the origin.
 * Returns how often it said so.
 */
static long flat_triangles(long *bad, long *hits, long *on_plane)
{
	uint8_t flat[1];
	struct group g;
	memset(&g, 0, sizeof g);
	g.tri_flat = flat;
	long behind_n = 0;
	for (int i = 0; i < N_RAYS; i++) {
		int ax = i % 3;
		flat[0] = (uint8_t)ax;
		double scale = pow(10, 6 * uniform() - 3);
		vec3 c = v3_scale(unit(), uniform() < 0.5 ? 0 : 1e3 * uniform());
		vec3 v[3];
		for (int k = 0; k < 3; k++) {
			v[k] = v3_add(c, v3_scale(unit(), scale));
			double *q = ax == 0 ? &v[k].x : ax == 1 ? &v[k].y : &v[k].z;
			*q = ax == 0 ? c.x : ax == 1 ? c.y : c.z; /* one plane, bit for bit */
		}
		double u = 1.4 * uniform() - 0.2, w = (1 - u) * (1.4 * uniform() - 0.2);
		vec3 p = v3_add(v[0], v3_add(v3_scale(v3_sub(v[1], v[0]), u), v3_scale(v3_sub(v[2], v[0]), w)));
		double m = fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z)));
		double e = (int)(uniform() * 4) == 0 ? 0 : (uniform() < 0.5 ? -1 : 1) * 1e-9 * (1 + m) * (uniform() < 0.8 ? 1 : 1e3);
		vec3 o = p;
		double *oq = ax == 0 ? &o.x : ax == 1 ? &o.y : &o.z;
		*oq += e;
		vec3 d = unit();
		if (uniform() < 0.5) { /* steep: the plane's axis the largest */
			double *dq = ax == 0 ? &d.x : ax == 1 ? &d.y : &d.z;
			*dq = (*dq < 0 ? -1 : 1) * (1 + 2 * uniform());
		}
		d = v3_scale(d, uniform() < 0.5 ? 1 : 3 * scale * uniform() + 1e-3);
		double tmin, tmax, t = 0, b1, b2;
		limits(&tmin, &tmax);
		struct trace r;
		trace_init(&r, o, d, tmin, tmax);
		bool behind = tri_flat_behind(&g, 0, &r, &v[0]);
		bool hit = geom_tri_hit_p(trace_wray(&r), &v[0], &v[1], &v[2], tmin, tmax, &t, &b1, &b2);
		behind_n += behind;
		*hits += hit;
		if (!behind)
			continue;
		long double h = (long double)geom_comp(&o, ax) - geom_comp(&v[0], ax), dp = geom_comp(&d, ax);
		*bad += !(tmin >= 0) || h * dp < 0; /* the rule's claim, computed apart */
		if (hit && h != 0)
			(*bad)++;
		if (hit && h == 0) {
			(*on_plane)++;
			*bad += !(t * sqrt(v3_dot(d, d)) <= 1e-9 * (1 + m));
		}
	}
	return behind_n;
}

int main(void)
{
	long away_s = 0, away_c = 0, hits_s = 0, hits_c = 0, bad_s = 0, bad_c = 0;
	for (int i = 0; i < N_RAYS; i++) {
		double scale = pow(10, 6 * uniform() - 3);
		vec3 c = v3_scale(unit(), uniform() < 0.5 ? 0 : 1e3 * uniform());
		double rad = scale * (0.05 + uniform());
		vec3 n = unit(), d = v3_scale(unit(), uniform() < 0.5 ? 1 : 3 * scale * uniform() + 1e-3);
		double tmin, tmax, ta = 0, tb = 0;
		limits(&tmin, &tmax);

		/* a sphere */
		struct gsphere sp = { c, rad * rad, 0, 0 };
		struct trace r;
		trace_init(&r, v3_add(c, v3_scale(n, rad * (1 + start_e(c)))), d, tmin, tmax);
		bool ha = sphere_test(&sp, &r, &ta), hb = sphere_test_with(&sp, &r, &tb, false);
		bad_s += ha != hb || (ha && memcmp(&ta, &tb, sizeof ta) != 0);
		hits_s += hb;
		vec3 oc = v3_sub(r.o, c);
		away_s += -v3_dot(oc, d) * r.inv_dd < 0 && v3_dot(oc, oc) - sp.r2 >= 0 && tmin >= 0;

		/* an open cylinder along a, the start beside its axis at height z */
		vec3 a = unit();
		double h = scale * (0.1 + 3 * uniform()), z = h * (1.4 * uniform() - 0.2);
		vec3 side = v3_norm(v3_sub(n, v3_scale(a, v3_dot(n, a))));
		vec3 o = v3_add(v3_add(c, v3_scale(a, z)), v3_scale(side, rad * (1 + start_e(c))));
		ha = geom_cyl_open_hit(c, a, rad, h, o, d, tmin, tmax, &ta, &(int){ 0 });
		hb = geom_cyl_open_test(c, a, rad, h, o, d, tmin, tmax, &tb, &(int){ 0 }, false);
		bad_c += ha != hb || (ha && memcmp(&ta, &tb, sizeof ta) != 0);
		hits_c += hb;
		vec3 op = v3_sub(v3_sub(o, c), v3_scale(a, v3_dot(v3_sub(o, c), a)));
		vec3 dp = v3_sub(d, v3_scale(a, v3_dot(d, a)));
		away_c += v3_dot(op, dp) > 0 && v3_dot(op, op) - rad * rad >= 0 && tmin >= 0;
	}
	printf("spheres: %ld hits, %ld away; cylinders: %ld hits, %ld away\n", hits_s, away_s, hits_c, away_c);
	CHECK(bad_s == 0);
	CHECK(bad_c == 0);
	/* the cases the early miss is for, and hits, are many */
	CHECK(away_s > N_RAYS / 8 && hits_s > N_RAYS / 8);
	CHECK(away_c > N_RAYS / 8 && hits_c > N_RAYS / 10);
	long bad_f = 0, hits_f = 0, on_f = 0, behind_f = flat_triangles(&bad_f, &hits_f, &on_f);
	printf("flat triangles: %ld hits, %ld behind, %ld of them rounding hits from the plane, %ld wrong\n", hits_f,
	       behind_f, on_f, bad_f);
	CHECK(bad_f == 0);
	CHECK(behind_f > N_RAYS / 8 && hits_f > N_RAYS / 20);
	TEST_MAIN_END();
}
