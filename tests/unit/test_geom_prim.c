/*
 * test_geom_prim.c - the cylinder pre-test (CYLINDER PRE-TEST in
 * common/geom.c, which is included so that its static functions are
 * reachable) never rejects a line the exact test would not reject:
 * whenever cyl_line_far(op, dp, r2) says true, sphere_roots(op, dp, r2)
 * says false. Lines are made to pass at r (1 + e) from the axis, e from
 * -2^-30 to 2^-30 and a few ulps either side of 0 (grazing), with radii
 * from 1e-9 to 1e9, direction lengths from 1e-6 to 1e6 and origins up to
 * 1e6 radii away along the line (far origins: the exact test's error grows
 * with |op|), plus lines from inside, parallel lines and special values.
 * Then whole cylinders: geom_intersect on open ones against the same
 * arithmetic without the pre-test, and the capped solid's side roots
 * (cyl_side_roots, for geom_intersect and geom_crossings) against
 * sphere_roots. A
 * pre-test without its margin fails here, and so does one without the
 * margin's term in |op| (far origins); one that rejects nothing fails the
 * check that lines missing by a visible margin are rejected.
 */
#include "common/geom.c"

#include "tests/unit/check.h"

static uint64_t rs = 0x2545f4914f6cdd1dull;

/* Uniform in [0, 1) (xorshift). */
static double rnd(void)
{
	rs ^= rs << 13;
	rs ^= rs >> 7;
	rs ^= rs << 17;
	return (double)(rs >> 11) * 0x1p-53;
}

static double rnd_in(double lo, double hi) { return lo + (hi - lo) * rnd(); }

/* Log-uniform in [lo, hi]. */
static double rnd_log(double lo, double hi) { return exp(rnd_in(log(lo), log(hi))); }

static vec3 rnd_unit(void)
{
	for (;;) {
		vec3 v = v3(rnd_in(-1, 1), rnd_in(-1, 1), rnd_in(-1, 1));
		double l = v3_len(v);
		if (l > 0.1 && l <= 1)
			return v3_scale(v, 1 / l);
	}
}

static long n_far, n_bad;

/* One line: the property, and the count of rejections. */
static void one(vec3 op, vec3 dp, double r2)
{
	double t0, t1;
	if (cyl_line_far(op, dp, r2)) {
		n_far++;
		if (sphere_roots(op, dp, r2, &t0, &t1))
			n_bad++;
	}
}

/* Grazing lines op + t dp at distance r (1 + e) from the origin. */
static void test_grazing(void)
{
	static const double es[] = { 0, 0x1p-52, -0x1p-52, 0x1p-50, 0x1p-48, 0x1p-46, 0x1p-44, 0x1p-42,
				     0x1p-40, 0x1p-38, 0x1p-36, 0x1p-33, 0x1p-30, 1e-7 };
	n_far = n_bad = 0;
	for (int i = 0; i < 400000; i++) {
		double r = rnd_log(1e-9, 1e9);
		vec3 u = rnd_unit();
		vec3 w = v3_norm(v3_cross(u, rnd_unit())); /* perpendicular to the line */
		double e = es[i % (int)(sizeof es / sizeof es[0])] * (rnd() < 0.5 ? -1 : 1);
		vec3 F = v3_scale(w, r * (1 + e));
		double len = rnd_log(1e-6, 1e6);
		vec3 dp = v3_scale(u, len);
		double far = rnd() < 0.25 ? rnd_in(-4, 4) : rnd_log(1, 1e6) * (rnd() < 0.5 ? -1 : 1);
		vec3 op = v3_sub(F, v3_scale(dp, far * r / len));
		one(op, dp, r * r);
	}
	CHECK(n_bad == 0);
	CHECK(n_far > 1000);
	if (n_bad)
		fprintf(stderr, "grazing: %ld of %ld rejections wrong\n", n_bad, n_far);
	/* and a line that misses by 1e-6 of its origin's distance is rejected */
	for (int i = 0; i < 10000; i++) {
		double r = rnd_log(1e-9, 1e9);
		vec3 u = rnd_unit();
		vec3 w = v3_norm(v3_cross(u, rnd_unit()));
		double far = rnd_log(1, 1e6);
		vec3 dp = v3_scale(u, rnd_log(1e-6, 1e6));
		vec3 op = v3_sub(v3_scale(w, r * (1 + 1e-6 * (far + 1))), v3_scale(u, far * r));
		CHECK(cyl_line_far(op, dp, r * r));
	}
}

/* Lines from inside, through the axis, parallel ones and special values:
 * never a wrong rejection. */
static void test_special(void)
{
	n_far = n_bad = 0;
	static const double big[] = { 0, 1e-320, 1e-200, 1e-120, 1, 1e120, 1e200, 1e300, INFINITY, NAN };
	const int nb = (int)(sizeof big / sizeof big[0]);
	for (int i = 0; i < nb; i++)
		for (int j = 0; j < nb; j++)
			for (int k = 0; k < nb; k++) {
				vec3 op = v3(big[i], -big[j] * 0.5, 0.25 * big[k]);
				vec3 dp = v3(big[j], big[k] * 0.75, -big[i]);
				one(op, dp, 1);
				one(op, dp, big[k] * big[k]);
				one(op, dp, 0);
				one(dp, op, big[i]);
			}
	for (int i = 0; i < 100000; i++) { /* from inside the infinite cylinder */
		double r = rnd_log(1e-9, 1e9);
		vec3 op = v3_scale(rnd_unit(), r * rnd());
		vec3 dp = v3_scale(rnd_unit(), rnd_log(1e-6, 1e6));
		one(op, dp, r * r);
		CHECK(!cyl_line_far(op, dp, r * r));
	}
	CHECK(n_bad == 0);
}

/* geom_intersect and geom_crossings on cylinders, with and without the
 * pre-test: the same answers bit for bit. The reference below is the
 * cylinder code of geom.c with cyl_line_far left out. */
static bool ref_open(const struct geom_obj *g, vec3 o, vec3 d, double tmin, double tmax, double *t)
{
	vec3 a = g->u.cyl.a, oc = v3_sub(o, g->u.cyl.from);
	double z0 = v3_dot(oc, a), dz = v3_dot(d, a);
	vec3 op = v3_sub(oc, v3_scale(a, z0)), dp = v3_sub(d, v3_scale(a, dz));
	double r2 = g->u.cyl.r * g->u.cyl.r, t0, t1;
	if (v3_dot(dp, dp) <= 1e-30 * v3_dot(d, d) || !sphere_roots(op, dp, r2, &t0, &t1))
		return false;
	double za = z0 + t0 * dz, zb = z0 + t1 * dz, h = g->u.cyl.h;
	if (za >= 0 && za <= h && in_range(t0, tmin, tmax)) {
		*t = t0;
		return true;
	}
	if (zb >= 0 && zb <= h && in_range(t1, tmin, tmax)) {
		*t = t1;
		return true;
	}
	return false;
}

static void test_cylinders(void)
{
	long hits = 0, n = 0;
	for (int c = 0; c < 200; c++) {
		struct geom_obj g;
		memset(&g, 0, sizeof g);
		g.kind = PRIM_CYLINDER;
		double scale = rnd_log(1e-6, 1e6);
		g.u.cyl.from = v3(rnd_in(-3, 3) * scale, rnd_in(-3, 3) * scale, rnd_in(-3, 3) * scale);
		g.u.cyl.a = rnd_unit();
		g.u.cyl.h = rnd_log(0.01, 100) * scale;
		g.u.cyl.r = rnd_log(1e-3, 10) * scale;
		g.u.cyl.capped = c % 2;
		geom_frame(g.u.cyl.a, &g.u.cyl.X, &g.u.cyl.Y);
		vec3 w0 = g.u.cyl.X, w1 = g.u.cyl.Y;
		for (int i = 0; i < 2000; i++) {
			/* aim at a point on or near the side, from far off */
			double phi = rnd_in(0, 2 * M_PI), z = rnd_in(-0.1, 1.1) * g.u.cyl.h;
			double rr = g.u.cyl.r * (1 + (i % 3 == 0 ? rnd_in(-1e-12, 1e-12) : rnd_in(-0.5, 0.5)));
			vec3 p = v3_add(v3_add(g.u.cyl.from, v3_scale(g.u.cyl.a, z)),
					v3_add(v3_scale(w0, rr * cos(phi)), v3_scale(w1, rr * sin(phi))));
			vec3 d = v3_scale(rnd_unit(), rnd_log(1e-3, 1e3));
			vec3 o = v3_sub(p, v3_scale(d, rnd_log(1e-2, 1e6) * scale / v3_len(d)));
			double t = 0, tr = 0;
			int part;
			bool got = geom_intersect(&g, o, d, 0, INFINITY, &t, &part);
			n++;
			if (!g.u.cyl.capped) {
				bool want = ref_open(&g, o, d, 0, INFINITY, &tr);
				CHECK(got == want && (!got || memcmp(&t, &tr, sizeof t) == 0));
			}
			hits += got;
			/* the capped solid: cyl_solid's answer when its side roots
			 * come from sphere_roots alone */
			double s0, s1, q0, q1;
			vec3 oc = v3_sub(o, g.u.cyl.from);
			vec3 op = v3_sub(oc, v3_scale(g.u.cyl.a, v3_dot(oc, g.u.cyl.a)));
			vec3 dp = v3_sub(d, v3_scale(g.u.cyl.a, v3_dot(d, g.u.cyl.a)));
			int side = cyl_side_roots(&g, o, d, &s0, &s1);
			if (v3_dot(dp, dp) > 1e-30 * v3_dot(d, d))
				CHECK((side == 1) == sphere_roots(op, dp, g.u.cyl.r * g.u.cyl.r, &q0, &q1));
		}
	}
	CHECK(hits > n / 10 && hits < n);
}

int main(void)
{
	test_grazing();
	test_special();
	test_cylinders();
	TEST_MAIN_END();
}
