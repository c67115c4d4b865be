/*
 * test_shade_inner.c - shading's internal shortcuts against the real
 * geometry (common/shade.c is included, so its static functions are
 * reachable; the accel is the real one, from the library):
 * - offset() is accel_offset_point, bit for bit (shade.c inlines it);
 * - TWO WAYS AT ONCE: light_ways2's lanes are light_way_at's ways bit for
 *   bit (distance, direction, n.l, lit), light behind, on or beside the
 *   point, at any scale, with special values;
 * - POINT LIGHTS ONLY: the flags are set exactly when every light is a
 *   point light without fall-off (points_only) and when shadows are on and
 *   no light has no-shadows (all_shadows), and then direct_body's folded
 *   copies give the general copy's colours bit for bit, with the eye hits'
 *   shadow packets and without;
 * - DIRECT IN FOURS: direct4's four lanes are direct_body's colours bit
 *   for bit on blocks of one to four eye hits, with the shadow packets'
 *   answers, with some lanes' light ways left to direct4 and with no
 *   answers at all (where the CPU has AVX2);
 * - TRANSPARENT BOXES: a shadow segment that may_cross_transparent says
 *   meets no possibly transparent surface is hit by none (accel_occluded
 *   on a scene of transparent triangles only), for random segments and
 *   for segments that start on a triangle, end on one or graze an edge.
 */
#include "common/shade.c"

#include <string.h>

#include "tests/unit/check.h"

static uint64_t rs = 0x9e3779b97f4a7c15ull;

/* Uniform in [0, 1) (xorshift). */
static double rnd(void)
{
	rs ^= rs << 13;
	rs ^= rs >> 7;
	rs ^= rs << 17;
	return (double)(rs >> 11) * 0x1p-53;
}

static double rnd_in(double lo, double hi) { return lo + (hi - lo) * rnd(); }
static vec3 rnd_v(double lo, double hi) { return v3(rnd_in(lo, hi), rnd_in(lo, hi), rnd_in(lo, hi)); }

/* offset() against accel_offset_point on ordinary and special values. */
static void test_offset(void)
{
	const double special[] = { 0.0, -0.0, 1e-310, -1e-310, 1e300, -1e300, INFINITY, -INFINITY, NAN, 1.0, -3.5 };
	int n_special = (int)(sizeof special / sizeof special[0]);
	int same = 0, total = 0;
	for (int i = 0; i < 20000; i++) {
		vec3 p = rnd_v(-10, 10), ng = v3_norm(rnd_v(-1, 1)), dir = rnd_v(-1, 1);
		if (i % 4 == 1)
			p = v3_scale(p, pow(10, rnd_in(-300, 300)));
		if (i % 4 == 2) { /* special components */
			p.x = special[i / 4 % n_special];
			p.y = special[i / 44 % n_special];
			dir.z = special[i / 7 % n_special];
		}
		if (i % 16 == 3)
			dir = v3(ng.y, -ng.x, 0); /* n.dir may be 0 */
		vec3 a = offset(p, ng, dir), b = accel_offset_point(p, ng, dir);
		total++;
		same += memcmp(&a, &b, sizeof a) == 0;
	}
	CHECK(same == total);
}

/* The fields light_way_at sets (the others are unset when dist is not > 0). */
static bool same_way(const struct light_way *a, const struct light_way *b)
{
	if (memcmp(&a->dist, &b->dist, sizeof a->dist) != 0 || a->lit != b->lit)
		return false;
	if (!(a->dist > 0))
		return true;
	return memcmp(&a->ldir, &b->ldir, sizeof a->ldir) == 0 && memcmp(&a->ndotl, &b->ndotl, sizeof a->ndotl) == 0;
}

/* light_ways2 against light_way_at, lane by lane. */
static void test_ways2(void)
{
	const double special[] = { 0.0, -0.0, 1e-310, 1e300, -1e300, INFINITY, NAN, 1.0 };
	int n_special = (int)(sizeof special / sizeof special[0]);
	int same = 0, total = 0, lit = 0;
	for (int i = 0; i < 40000; i++) {
		vec3 p[2], n[2], lp[2];
		for (int k = 0; k < 2; k++) {
			p[k] = rnd_v(-10, 10);
			n[k] = v3_norm(rnd_v(-1, 1));
			lp[k] = rnd_v(-20, 20);
		}
		if (i % 5 == 1)
			lp[1] = p[1]; /* the light at the point: dist 0 */
		if (i % 5 == 2) {
			double s = pow(10, rnd_in(-150, 150));
			p[0] = v3_scale(p[0], s), lp[0] = v3_scale(lp[0], s);
		}
		if (i % 5 == 3) /* special components */
			lp[i & 1].y = special[i / 5 % n_special];
		struct light_way w[2];
		light_ways2(p, n, lp, w);
		for (int k = 0; k < 2; k++) {
			struct light_way ref = light_way_at(p[k], n[k], lp[k]);
			total++;
			same += same_way(&w[k], &ref);
			lit += ref.lit;
		}
	}
	CHECK(same == total);
	CHECK(lit > total / 4 && lit < total - total / 4); /* both answers, often */
}

/* Adds triangle abc as a root (transformed by xf when given), material mat. */
static void add_tri(struct scene *s, vec3 a, vec3 b, vec3 c, uint32_t mat, const mat34 *xf)
{
	struct scene_object o;
	struct scene_error err;
	uint32_t id;
	scene_object_defaults(&o, PRIM_TRIANGLE);
	o.u.triangle.a = a;
	o.u.triangle.b = b;
	o.u.triangle.c = c;
	o.material = mat;
	if (xf) {
		o.xform = *xf;
		o.has_xform = true;
	}
	CHECK(scene_add_object(s, &o, &id, &err) == 0);
	CHECK(scene_add_root(s, id, &err) == 0);
}

/* A point on triangle t (barycentric u, v), through its transform. */
struct tri {
	vec3 a, b, c;
	bool xf;
};

static void test_tboxes(void)
{
	struct scene *s = scene_new();
	struct scene_error err;
	struct scene_material m;
	uint32_t glass, tint;
	scene_material_defaults(&m);
	m.transparency = 0.5;
	CHECK(scene_add_material(s, &m, &glass, &err) == 0);
	scene_material_defaults(&m);
	m.transparency = 0.9;
	m.tran_colour = v3(1, 0.5, 0.5);
	CHECK(scene_add_material(s, &m, &tint, &err) == 0);
	/* two clusters of small transparent triangles (two boxes), some rotated */
	mat34 rot = m34_identity();
	rot.m[0][0] = 0.6, rot.m[0][1] = -0.8, rot.m[1][0] = 0.8, rot.m[1][1] = 0.6, rot.m[2][3] = 0.25;
	enum { NT = 40 };
	struct tri t[NT];
	for (int i = 0; i < NT; i++) {
		vec3 c = i < NT / 2 ? v3(-2, 0, 1) : v3(3, 1, -1);
		t[i].a = v3_add(c, rnd_v(-0.5, 0.5));
		t[i].b = v3_add(t[i].a, rnd_v(-0.3, 0.3));
		t[i].c = v3_add(t[i].a, rnd_v(-0.3, 0.3));
		t[i].xf = i % 5 == 0;
		add_tri(s, t[i].a, t[i].b, t[i].c, i < NT / 2 ? glass : tint, t[i].xf ? &rot : NULL);
		if (t[i].xf) {
			t[i].a = m34_point(&rot, t[i].a);
			t[i].b = m34_point(&rot, t[i].b);
			t[i].c = m34_point(&rot, t[i].c);
		}
	}
	struct accel *a = NULL;
	CHECK(accel_build(s, &a, &err) == 0);
	struct shade_ctx *c = NULL;
	CHECK(shade_ctx_new(s, a, &c, &err) == 0);
	if (!a || !c)
		goto done;
	CHECK(c->tb.all && c->tb.n == 2);
	int missed = 0, wrong = 0;
	for (int i = 0; i < 200000; i++) {
		struct ray r;
		int kind = i % 4;
		const struct tri *q = &t[(int)(rnd() * NT)];
		double u = rnd(), v = rnd() * (1 - u);
		if (kind == 3) /* on an edge */
			v = 1 - u;
		vec3 on = v3_add(q->a, v3_add(v3_scale(v3_sub(q->b, q->a), u), v3_scale(v3_sub(q->c, q->a), v)));
		vec3 far = rnd_v(-6, 6);
		if (kind == 0) { /* anywhere */
			r.o = rnd_v(-6, 6);
			r.d = v3_sub(far, r.o);
		} else if (kind == 1) { /* from a triangle, just off it, as a shadow ray leaves */
			vec3 ng = v3_norm(v3_cross(v3_sub(q->b, q->a), v3_sub(q->c, q->a)));
			vec3 o = offset(on, ng, v3_sub(far, on));
			r.o = o;
			r.d = v3_sub(far, o);
		} else { /* ending on a triangle or one of its edges, or just past it */
			r.o = far;
			r.d = v3_scale(v3_sub(on, far), 1 + rnd_in(-1e-12, 1e-12));
		}
		r.tmin = 0;
		r.tmax = 1;
		if (may_cross_transparent(c, &r))
			continue;
		missed++;
		wrong += accel_occluded(a, &r);
	}
	CHECK(missed > 10000); /* the test saw the shortcut taken */
	CHECK(wrong == 0);
	if (wrong)
		fprintf(stderr, "%d of %d segments said clear were hit\n", wrong, missed);
done:
	shade_ctx_free(c);
	accel_free(a);
	scene_free(s);
}

/* A cluster of spheres over a floor of two triangles, three lights;
 * variant 0: all point lights; 1: one with fall-off; 2: one a sphere
 * light; 3: one with no-shadows; 4: the image without shadows. */
static struct scene *points_scene(int variant)
{
	struct scene *s = scene_new();
	struct scene_error err;
	struct scene_material m;
	uint32_t mirror, plain;
	scene_material_defaults(&m);
	m.specular = 0.5;
	m.spec_power = 3.0827; /* balls_s4's: every highlight needs its power */
	m.reflection = 0.5;
	m.diff_colour = v3(0.9, 0.6, 0.3);
	CHECK(scene_add_material(s, &m, &mirror, &err) == 0);
	scene_material_defaults(&m);
	m.specular = 0.3;
	m.spec_power = 60; /* POW SKIP's tests */
	m.diffuse = 0.8;
	CHECK(scene_add_material(s, &m, &plain, &err) == 0);
	for (int i = 0; i < 60; i++) {
		struct scene_object o;
		uint32_t id;
		scene_object_defaults(&o, PRIM_SPHERE);
		o.u.sphere.centre = rnd_v(-2, 2);
		o.u.sphere.radius = rnd_in(0.1, 0.5);
		o.material = i % 3 ? mirror : plain;
		CHECK(scene_add_object(s, &o, &id, &err) == 0);
		CHECK(scene_add_root(s, id, &err) == 0);
	}
	add_tri(s, v3(-9, -3, -9), v3(9, -3, -9), v3(9, -3, 9), plain, NULL);
	add_tri(s, v3(-9, -3, -9), v3(9, -3, 9), v3(-9, -3, 9), plain, NULL);
	const vec3 at[3] = { v3(4, 3, 2), v3(1, -2.5, 4), v3(-3, 1, 5) };
	for (int i = 0; i < 3; i++) {
		struct scene_light l;
		scene_light_defaults(&l);
		l.position = at[i];
		l.colour = v3(0.58, 0.58, 0.58);
		if (i == 1 && variant == 1)
			l.fall_off = 1;
		if (i == 2 && variant == 2) {
			l.shape = LIGHT_SPHERE;
			l.sphere.centre = at[i];
			l.sphere.radius = 0.2;
			l.samples = 4;
		}
		if (i == 0 && variant == 3)
			l.no_shadows = true;
		CHECK(scene_add_light(s, &l, &err) == 0);
	}
	s->image.no_shadows = variant == 4;
	return s;
}

/* direct_body's copy for c's flags against the general one on hit sf of
 * ray r (weight w, shadow answers pre or none): 1 when their colours
 * differ in a bit. */
static int copies_differ(const struct shade_ctx *c, const struct ray *r, const struct surf *sf, double w,
			 uint64_t seed, const struct shadow_pre *pre, uint32_t obj)
{
	const struct shader_mat *m = sf->m;
	double kd = m->diffuse * (1 - sf->td);
	vec3 v = v3_neg(r->d);
	vec3 a = c->all_shadows ? direct_body(c, sf->p, sf->n, sf->ng, v, m, kd, w, seed, pre, obj, true, true)
				: direct_body(c, sf->p, sf->n, sf->ng, v, m, kd, w, seed, pre, obj, true, false);
	vec3 b = direct_body(c, sf->p, sf->n, sf->ng, v, m, kd, w, seed, pre, obj, false, false);
	return memcmp(&a, &b, sizeof a) != 0;
}

/* points_scene(variant), its accel and its shading context; false when
 * one could not be made (a failed check) */
static bool points_setup(int variant, struct scene **s, struct accel **a, struct shade_ctx **c)
{
	struct scene_error err;
	*s = points_scene(variant);
	*a = NULL;
	*c = NULL;
	CHECK(accel_build(*s, a, &err) == 0);
	CHECK(shade_ctx_new(*s, *a, c, &err) == 0);
	return *a && *c;
}

static void points_teardown(struct scene *s, struct accel *a, struct shade_ctx *c)
{
	shade_ctx_free(c);
	accel_free(a);
	scene_free(s);
}

static void test_points_only(void)
{
	for (int variant = 0; variant < 5; variant++) {
		struct scene *s;
		struct accel *a;
		struct shade_ctx *c;
		if (!points_setup(variant, &s, &a, &c))
			goto next;
		CHECK(c->points_only == (variant == 0 || variant >= 3));
		CHECK(c->all_shadows == (variant <= 2));
		if (!c->points_only)
			goto next;
		int compared = 0, lit = 0, differ = 0;
		const double weights[4] = { 1.0, 0.5, 1.0 / 40, 1.0 / 900 };
		for (int i = 0; i < 4000; i++) {
			/* four rays from one eye toward neighbouring points, as a 2x2 block */
			vec3 eye = rnd_v(-7, 7), aim = rnd_v(-2, 2);
			struct ray u[4];
			struct surf sf[4];
			bool ok[4];
			for (int k = 0; k < 4; k++) {
				vec3 d = v3_norm(v3_sub(v3_add(aim, rnd_v(-0.05, 0.05)), eye));
				u[k] = (struct ray){ eye, d, 0, INFINITY };
				struct hit h;
				ok[k] = accel_intersect(a, &u[k], &h) && surf_prepare(c, &u[k], &h, &sf[k]);
			}
			struct shadow_pre pre[4];
			shadow_packets(c, sf, ok, 4, pre);
			for (int k = 0; k < 4; k++) {
				if (!ok[k])
					continue;
				double w = weights[(i + k) % 4];
				uint64_t seed = (uint64_t)i * 4 + (uint64_t)k;
				/* as an eye hit (the packets' answers) and as a mirror hit (none) */
				differ += copies_differ(c, &u[k], &sf[k], w, seed, &pre[k], SHADE_HINT_ANY);
				differ += copies_differ(c, &u[k], &sf[k], w, seed, NULL, sf[k].obj);
				vec3 col = direct_body(c, sf[k].p, sf[k].n, sf[k].ng, v3_neg(u[k].d), sf[k].m,
						       sf[k].m->diffuse, 1.0, seed, NULL, sf[k].obj, false, false);
				lit += maxc(col) > 0;
				compared += 2;
			}
		}
		CHECK(compared > 10000);
		CHECK(lit > 1000); /* lights reached, with highlights to power */
		CHECK(differ == 0);
		if (differ)
			fprintf(stderr, "POINT LIGHTS ONLY (variant %d): %d of %d colours differ between the copies\n",
				variant, differ, compared);
	next:
		points_teardown(s, a, c);
	}
}

#if SHADE_DIRECT4
/*
 * DIRECT IN FOURS: direct4's lanes against direct_body (its folded copy
 * for c's flags, weight 1, the eye hit's shadow answers) on blocks of one
 * to four eye hits, some missing; with the packets' answers as made, with
 * some lanes' LIGHT WAYS dropped (direct4 makes those itself, beside the
 * others' given ones) and with no answers at all (every shadow ray traced
 * lane by lane). Returns the number of colours compared.
 */
static int check_direct4(const struct shade_ctx *c, const struct accel *a, int variant, int *lit)
{
	int compared = 0, differ = 0;
	for (int i = 0; i < 3000; i++) {
		vec3 eye = rnd_v(-7, 7), aim = rnd_v(-2, 2);
		struct ray u[4];
		struct surf sf[4];
		bool ok[4];
		int n = 1 + i % 4;
		for (int k = 0; k < 4; k++) {
			vec3 d = v3_norm(v3_sub(v3_add(aim, rnd_v(-0.05, 0.05)), eye));
			u[k] = (struct ray){ eye, d, 0, INFINITY };
			struct hit h;
			ok[k] = k < n && accel_intersect(a, &u[k], &h) && surf_prepare(c, &u[k], &h, &sf[k]);
		}
		struct shadow_pre pre[4];
		shadow_packets(c, sf, ok, n, pre);
		int mode = i % 3;
		for (int k = 0; k < 4; k++) {
			if (mode == 1 && (i / 3 + k) % 2)
				pre[k].wknown = 0; /* this lane's ways: direct4's own */
			if (mode == 2)
				pre[k].known = pre[k].occ = pre[k].wknown = 0; /* nothing known */
		}
		vec3 col[4];
		direct4(c, u, sf, ok, n, pre, col);
		for (int k = 0; k < n; k++) {
			if (!ok[k])
				continue;
			const struct shader_mat *m = sf[k].m;
			double kd = m->diffuse * (1 - sf[k].td);
			uint64_t seed = (uint64_t)i * 4 + (uint64_t)k;
			vec3 v = v3_neg(u[k].d);
			vec3 want = c->all_shadows ? direct_body(c, sf[k].p, sf[k].n, sf[k].ng, v, m, kd, 1.0, seed,
								  &pre[k], SHADE_HINT_ANY, true, true)
						   : direct_body(c, sf[k].p, sf[k].n, sf[k].ng, v, m, kd, 1.0, seed,
								  &pre[k], SHADE_HINT_ANY, true, false);
			differ += memcmp(&want, &col[k], sizeof want) != 0;
			*lit += maxc(want) > 0;
			compared++;
		}
	}
	CHECK(differ == 0);
	if (differ)
		fprintf(stderr, "DIRECT IN FOURS (variant %d): %d of %d colours differ from direct_body's\n", variant,
			differ, compared);
	return compared;
}
#endif

static void test_direct4(void)
{
#if SHADE_DIRECT4
	if (!accel_use_avx2()) {
		printf("DIRECT IN FOURS: not checked (no AVX2 here)\n");
		return;
	}
	int compared = 0, lit = 0;
	for (int variant = 0; variant < 5; variant++) {
		struct scene *s;
		struct accel *a;
		struct shade_ctx *c;
		if (points_setup(variant, &s, &a, &c) && c->points_only) {
			/* taken where some light's ways are not the packets' */
			CHECK(c->direct4 == !c->all_shadows);
			compared += check_direct4(c, a, variant, &lit);
		}
		points_teardown(s, a, c);
	}
	CHECK(compared > 10000);
	CHECK(lit > 5000);
#endif
}

/* The shortcut is off when a possibly transparent surface gets no box. */
static void test_tboxes_off(void)
{
	struct scene *s = scene_new();
	struct scene_error err;
	struct scene_material m;
	uint32_t glass;
	scene_material_defaults(&m);
	m.transparency = 0.5;
	CHECK(scene_add_material(s, &m, &glass, &err) == 0);
	add_tri(s, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0), glass, NULL);
	struct scene_object o;
	uint32_t id;
	scene_object_defaults(&o, PRIM_SPHERE);
	o.material = glass;
	CHECK(scene_add_object(s, &o, &id, &err) == 0);
	CHECK(scene_add_root(s, id, &err) == 0);
	struct accel *a = NULL;
	struct shade_ctx *c = NULL;
	CHECK(accel_build(s, &a, &err) == 0);
	CHECK(shade_ctx_new(s, a, &c, &err) == 0);
	CHECK(c && !c->tb.all);
	struct ray r = { v3(10, 10, 10), v3(1, 0, 0), 0, 1 };
	CHECK(c && may_cross_transparent(c, &r));
	shade_ctx_free(c);
	accel_free(a);
	scene_free(s);
}

int main(void)
{
	test_offset();
	test_ways2();
	test_direct4();
	test_points_only();
	test_tboxes();
	test_tboxes_off();
	TEST_MAIN_END();
}
