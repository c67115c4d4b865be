/*
 * test_geom.c - every primitive, analytically: hit distance, normal and
 * (u,v) against hand-computed values; transforms (translate, rotate,
 * stretch, shrink) on simple primitives, baked triangles and planes; polygon
 * holes and notches; watertight shared edges; the secondary-ray offset.
 * Scenes are built with the scene builder directly.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/accel.h"
#include "common/geom.h"
#include "tests/unit/check.h"

#define EPS 1e-9

static struct scene_error err;

static struct scene *scene_one(struct scene_object *o)
{
	struct scene *s = scene_new();
	uint32_t id;
	if (scene_add_object(s, o, &id, &err) || scene_add_root(s, id, &err)) {
		fprintf(stderr, "builder: %s\n", err.msg);
		abort();
	}
	return s;
}

/* Traces one ray; checks BVH, brute force and occlusion agree. */
static bool trace(const struct scene *s, vec3 o, vec3 d, struct hit *h)
{
	struct accel *a;
	if (accel_build(s, &a, &err)) {
		fprintf(stderr, "accel: %s\n", err.msg);
		abort();
	}
	struct ray r = { o, d, 0, INFINITY };
	struct hit hb;
	bool hit = accel_intersect(a, &r, h);
	bool brute = accel_intersect_brute(a, &r, &hb);
	CHECK(hit == brute);
	CHECK(hit == accel_occluded(a, &r));
	if (hit && brute) {
		CHECK(h->t == hb.t && h->object == hb.object);
		/* u, v, mp on demand, the same for both (and twice is harmless) */
		accel_hit_surface(a, h);
		accel_hit_surface(a, &hb);
		struct hit h2 = *h;
		accel_hit_surface(a, &h2);
		CHECK(h->u == hb.u && h->v == hb.v && v3_len(v3_sub(h->mp, hb.mp)) == 0);
		CHECK(h2.u == h->u && h2.v == h->v);
	}
	accel_free(a);
	return hit;
}

static void check_vec(vec3 a, vec3 b, double eps, int line)
{
	if (!(fabs(a.x - b.x) <= eps && fabs(a.y - b.y) <= eps && fabs(a.z - b.z) <= eps)) {
		fprintf(stderr, "line %d: (%.9g %.9g %.9g) != (%.9g %.9g %.9g)\n", line, a.x, a.y, a.z, b.x, b.y, b.z);
		CHECK(!"vectors equal");
	} else {
		CHECK(1);
	}
}
#define CHECK_VEC(a, b) check_vec((a), (b), 1e-9, __LINE__)

static void xf(struct scene_object *o, enum xform_op op, int axis, double amount, vec3 v)
{
	CHECK(scene_xform_op(&o->xform, op, axis, amount, v));
	o->has_xform = true;
}

static void test_sphere(void)
{
	struct scene_object o;
	scene_object_defaults(&o, PRIM_SPHERE);
	o.u.sphere.centre = v3(1, 2, 3);
	o.u.sphere.radius = 2;
	struct scene *s = scene_one(&o);
	struct hit h;
	CHECK(trace(s, v3(1, 2, -10), v3(0, 0, 1), &h));
	CHECK_NEAR(h.t, 11, EPS);
	CHECK_VEC(h.p, v3(1, 2, 1));
	CHECK_VEC(h.n, v3(0, 0, -1));
	CHECK_VEC(h.ng, v3(0, 0, -1));
	/* q = -z; E = +x, W = P x E = -z: longitude 90 degrees, latitude 0 */
	CHECK_NEAR(h.u, 2 * M_PI / 2, EPS);
	CHECK_NEAR(h.v, 2 * M_PI / 2, EPS);
	CHECK(h.object == 0 && h.material == SCENE_NONE);
	CHECK_VEC(h.mp, v3(1, 2, 1));
	/* a direction of length 2 halves t */
	CHECK(trace(s, v3(1, 2, -10), v3(0, 0, 2), &h));
	CHECK_NEAR(h.t, 5.5, EPS);
	/* from the centre: the far side, outward normal */
	CHECK(trace(s, v3(1, 2, 3), v3(1, 0, 0), &h));
	CHECK_NEAR(h.t, 2, EPS);
	CHECK_VEC(h.n, v3(1, 0, 0));
	CHECK_NEAR(h.u, 0, EPS); /* on the equator direction */
	CHECK_NEAR(h.v, M_PI, EPS);
	/* north pole: v = pi r; south pole: v = 0 */
	CHECK(trace(s, v3(1, 10, 3), v3(0, -1, 0), &h));
	CHECK_NEAR(h.t, 6, EPS);
	CHECK_NEAR(h.v, 2 * M_PI, 1e-6);
	CHECK(trace(s, v3(1, -10, 3), v3(0, 1, 0), &h));
	CHECK_NEAR(h.v, 0, 1e-6);
	CHECK(!trace(s, v3(1, 4.01, -10), v3(0, 0, 1), &h));
	CHECK(!trace(s, v3(1, 2, 10), v3(0, 0, 1), &h)); /* behind the origin */
	scene_free(s);

	/* pole +z, equator +y: W = z x y = -x */
	scene_object_defaults(&o, PRIM_SPHERE);
	o.u.sphere.pole = v3(0, 0, 3);
	o.u.sphere.equator = v3(0, 1, 0.5); /* made perpendicular to the pole */
	s = scene_one(&o);
	CHECK(trace(s, v3(-5, 0, 0), v3(1, 0, 0), &h));
	CHECK_NEAR(h.u, M_PI / 2, EPS);
	CHECK_NEAR(h.v, M_PI / 2, EPS);
	CHECK(trace(s, v3(0, 5, 0), v3(0, -1, 0), &h));
	CHECK_NEAR(h.u, 0, EPS);
	scene_free(s);
}

static void test_plane_disk(void)
{
	struct scene_object o;
	scene_object_defaults(&o, PRIM_PLANE);
	struct scene *s = scene_one(&o);
	struct hit h;
	CHECK(trace(s, v3(3, 5, 7), v3(0, -1, 0), &h));
	CHECK_NEAR(h.t, 5, EPS);
	CHECK_VEC(h.n, v3(0, 1, 0));
	CHECK_NEAR(h.u, 3, EPS);  /* X = +x */
	CHECK_NEAR(h.v, -7, EPS); /* Y = N x X = -z */
	CHECK(trace(s, v3(3, -2, 7), v3(0, 1, 0), &h)); /* from behind */
	CHECK_NEAR(h.t, 2, EPS);
	CHECK_VEC(h.n, v3(0, 1, 0)); /* not flipped toward the ray */
	CHECK(!trace(s, v3(3, 5, 7), v3(1, 0, 0), &h));
	scene_free(s);

	scene_object_defaults(&o, PRIM_PLANE);
	o.u.plane.position = v3(0, 1, 0);
	o.u.plane.has_axes = true;
	o.u.plane.x_axis = v3(0, 0, 2);
	o.u.plane.y_axis = v3(1, 0, 0);
	s = scene_one(&o);
	CHECK(trace(s, v3(3, 5, 7), v3(0, -1, 0), &h));
	CHECK_NEAR(h.t, 4, EPS);
	CHECK_NEAR(h.u, 7, EPS);
	CHECK_NEAR(h.v, 3, EPS);
	scene_free(s);

	scene_object_defaults(&o, PRIM_DISK);
	o.u.plane.position = v3(1, 1, 0);
	o.u.plane.normal = v3(0, 0, 1);
	o.u.plane.radius = 1;
	s = scene_one(&o);
	CHECK(trace(s, v3(1.5, 1.5, -5), v3(0, 0, 1), &h));
	CHECK_NEAR(h.t, 5, EPS);
	CHECK_VEC(h.n, v3(0, 0, 1));
	CHECK_NEAR(h.u, 0.5, EPS); /* N = +z: X = +x, Y = z x x = +y */
	CHECK_NEAR(h.v, 0.5, EPS);
	CHECK(trace(s, v3(1.5, 1.5, 5), v3(0, 0, -1), &h)); /* both sides */
	CHECK(!trace(s, v3(1.8, 1.8, -5), v3(0, 0, 1), &h));
	scene_free(s);
}

static void test_cylinder(void)
{
	struct scene_object o;
	scene_object_defaults(&o, PRIM_CYLINDER);
	o.u.cylinder.to = v3(0, 2, 0);
	struct scene *s = scene_one(&o);
	struct hit h;
	CHECK(trace(s, v3(-5, 1, 0), v3(1, 0, 0), &h));
	CHECK_NEAR(h.t, 4, EPS);
	CHECK_VEC(h.n, v3(-1, 0, 0));
	/* A = +y: X = +x, Y = A x X = -z; radial -x: angle pi */
	CHECK_NEAR(h.u, M_PI, EPS);
	CHECK_NEAR(h.v, 1, EPS);
	CHECK(trace(s, v3(0, 1, 0), v3(1, 0, 0), &h)); /* open: inside seen */
	CHECK_NEAR(h.t, 1, EPS);
	CHECK(!trace(s, v3(0, 5, 0.5), v3(0, -1, 0), &h)); /* along the axis: no caps */
	CHECK(!trace(s, v3(-5, 2.5, 0), v3(1, 0, 0), &h));
	/* through the open end to the inside of the far wall */
	CHECK(trace(s, v3(-0.5, 3, 0), v3(1, -1, 0), &h));
	CHECK_NEAR(h.t, 1.5 - 1e-300, 1e-9); /* reaches x = 1 at y = 1.5 */
	CHECK_VEC(h.n, v3(1, 0, 0));
	scene_free(s);

	o.u.cylinder.capped = true;
	s = scene_one(&o);
	CHECK(trace(s, v3(0.5, 5, 0), v3(0, -1, 0), &h));
	CHECK_NEAR(h.t, 3, EPS);
	CHECK_VEC(h.n, v3(0, 1, 0));
	CHECK_NEAR(h.u, 0.5, EPS);
	CHECK(trace(s, v3(0.5, -5, 0.25), v3(0, 1, 0), &h));
	CHECK_NEAR(h.t, 5, EPS);
	CHECK_VEC(h.n, v3(0, -1, 0));
	CHECK(trace(s, v3(0, 1, 0), v3(0, 1, 0), &h)); /* inside: the cap */
	CHECK_NEAR(h.t, 1, EPS);
	scene_free(s);
}

static void test_box(void)
{
	struct scene_object o;
	scene_object_defaults(&o, PRIM_BOX);
	o.u.box.a = v3(1, 1, 1);
	o.u.box.b = v3(-1, -1, -1);
	struct scene *s = scene_one(&o);
	struct hit h;
	CHECK(trace(s, v3(0.5, 0.25, -5), v3(0, 0, 1), &h));
	CHECK_NEAR(h.t, 4, EPS);
	CHECK_VEC(h.n, v3(0, 0, -1));
	CHECK_NEAR(h.u, 1.5, EPS);
	CHECK_NEAR(h.v, 1.25, EPS);
	CHECK(trace(s, v3(0, 0, 0), v3(0, 0, 1), &h));
	CHECK_NEAR(h.t, 1, EPS);
	CHECK_VEC(h.n, v3(0, 0, 1));
	CHECK(trace(s, v3(5, 0.5, 0.25), v3(-1, 0, 0), &h));
	CHECK_VEC(h.n, v3(1, 0, 0));
	CHECK_NEAR(h.u, 1.25, EPS); /* x faces: u = z - lo.z, v = y - lo.y */
	CHECK_NEAR(h.v, 1.5, EPS);
	CHECK(trace(s, v3(0.5, 5, 0.25), v3(0, -1, 0), &h));
	CHECK_VEC(h.n, v3(0, 1, 0));
	CHECK_NEAR(h.u, 1.5, EPS); /* y faces: u = x - lo.x, v = z - lo.z */
	CHECK_NEAR(h.v, 1.25, EPS);
	CHECK(!trace(s, v3(1.5, 0, -5), v3(0, 0, 1), &h));
	/* axis-parallel ray grazing in the face plane: the robust slab test
	 * must not produce NaN; the box is hit (or not) consistently */
	trace(s, v3(1, 0, -5), v3(0, 0, 1), &h);
	scene_free(s);
}

static void test_triangle(void)
{
	struct scene_object o;
	scene_object_defaults(&o, PRIM_TRIANGLE);
	o.u.triangle.a = v3(0, 0, 0);
	o.u.triangle.b = v3(2, 0, 0);
	o.u.triangle.c = v3(0, 2, 0);
	struct scene *s = scene_one(&o);
	struct hit h;
	CHECK(trace(s, v3(0.5, 0.25, 5), v3(0, 0, -1), &h));
	CHECK_NEAR(h.t, 5, EPS);
	CHECK_VEC(h.ng, v3(0, 0, 1));
	CHECK_VEC(h.n, v3(0, 0, 1));
	CHECK_NEAR(h.u, 0.5, EPS);
	CHECK_NEAR(h.v, 0.25, EPS);
	CHECK(trace(s, v3(0.5, 0.25, -5), v3(0, 0, 1), &h)); /* back side */
	CHECK_VEC(h.ng, v3(0, 0, 1));
	CHECK(!trace(s, v3(1.5, 1.5, 5), v3(0, 0, -1), &h));
	scene_free(s);

	o.u.triangle.has_normals = true;
	o.u.triangle.na = v3(0, 0, 1);
	o.u.triangle.nb = v3(1, 0, 1);
	o.u.triangle.nc = v3(0, 1, 1);
	s = scene_one(&o);
	CHECK(trace(s, v3(0.5, 0.5, 5), v3(0, 0, -1), &h));
	/* weights a 0.5, b 0.25, c 0.25 */
	vec3 want = v3_norm(v3_add(v3_add(v3_scale(v3(0, 0, 1), 0.5), v3_scale(v3(1, 0, 1), 0.25)),
				   v3_scale(v3(0, 1, 1), 0.25)));
	CHECK_VEC(h.n, want);
	CHECK_VEC(h.ng, v3(0, 0, 1));
	scene_free(s);
}

/* A mesh of two triangles sharing the diagonal: rays along it never leak. */
static void test_mesh_watertight(void)
{
	struct scene *s = scene_new();
	struct scene_mesh m;
	memset(&m, 0, sizeof m);
	m.file = strdup("quad.raw");
	m.n_vertices = 4;
	m.n_triangles = 2;
	m.vertices = malloc(4 * sizeof *m.vertices);
	m.normals = malloc(4 * sizeof *m.normals);
	m.tris = malloc(6 * sizeof *m.tris);
	m.vertices[0] = v3(0, 0, 0), m.vertices[1] = v3(1, 0, 0);
	m.vertices[2] = v3(1, 1, 0), m.vertices[3] = v3(0, 1, 0);
	for (int i = 0; i < 4; i++)
		m.normals[i] = v3(0, 0, 1);
	m.normals[2] = v3_norm(v3(1, 1, 1));
	uint32_t t[6] = { 0, 1, 2, 0, 2, 3 };
	memcpy(m.tris, t, sizeof t);
	uint32_t mid, id;
	CHECK(scene_add_mesh(s, &m, &mid, &err) == 0);
	struct scene_object o;
	scene_object_defaults(&o, PRIM_RAW);
	o.u.raw.mesh = mid;
	CHECK(scene_add_object(s, &o, &id, &err) == 0);
	CHECK(scene_add_root(s, id, &err) == 0);
	struct accel *a;
	CHECK(accel_build(s, &a, &err) == 0);
	int leaks = 0;
	for (int k = 0; k <= 1000; k++) {
		double f = 0.01 + 0.98 * k / 1000.0; /* stays inside the quad */
		struct ray r = { v3(f, f, 1), v3(0.001 * (k % 7 - 3), 0.001 * (k % 5 - 2), -1), 0, INFINITY };
		struct hit h;
		leaks += !accel_intersect(a, &r, &h);
	}
	CHECK(leaks == 0);
	struct ray r = { v3(0.75, 0.25, 2), v3(0, 0, -1), 0, INFINITY };
	struct hit h;
	CHECK(accel_intersect(a, &r, &h));
	accel_hit_surface(a, &h);
	CHECK_NEAR(h.t, 2, EPS);
	CHECK(h.object == id);
	CHECK_VEC(h.mp, v3(0.75, 0.25, 0));
	/* smooth: weights at (0.75, 0.25) in triangle 0,1,2: v0 .25, v1 .5, v2 .25 */
	vec3 want = v3_norm(v3_add(v3_scale(v3(0, 0, 1), 0.75), v3_scale(v3_norm(v3(1, 1, 1)), 0.25)));
	CHECK_VEC(h.n, want);
	accel_free(a);
	scene_free(s);
}

static struct scene_object polygon(const double (*pts)[2], const uint32_t *counts, uint32_t n_contours)
{
	struct scene_object o;
	scene_object_defaults(&o, PRIM_POLYGON);
	uint32_t n = 0;
	for (uint32_t c = 0; c < n_contours; c++)
		n += counts[c];
	o.u.polygon.n_contours = n_contours;
	o.u.polygon.n_points = n;
	o.u.polygon.contour_start = malloc((n_contours + 1) * sizeof(uint32_t));
	o.u.polygon.points = malloc(n * sizeof(vec3));
	uint32_t k = 0;
	for (uint32_t c = 0; c < n_contours; c++) {
		o.u.polygon.contour_start[c] = k;
		k += counts[c];
	}
	o.u.polygon.contour_start[n_contours] = n;
	for (uint32_t i = 0; i < n; i++)
		o.u.polygon.points[i] = v3(pts[i][0], pts[i][1], 0);
	return o;
}

static void test_polygon(void)
{
	/* a square with a square hole */
	static const double sq[][2] = { { 0, 0 }, { 4, 0 }, { 4, 4 }, { 0, 4 }, { 1, 1 }, { 3, 1 }, { 3, 3 }, { 1, 3 } };
	static const uint32_t sq_n[] = { 4, 4 };
	struct scene_object o = polygon(sq, sq_n, 2);
	struct scene *s = scene_one(&o);
	struct hit h;
	CHECK(!trace(s, v3(2, 2, -1), v3(0, 0, 1), &h)); /* the hole */
	CHECK(!trace(s, v3(1.1, 2.9, -1), v3(0, 0, 1), &h));
	CHECK(trace(s, v3(0.5, 0.25, -1), v3(0, 0, 1), &h));
	CHECK_NEAR(h.t, 1, EPS);
	CHECK_VEC(h.n, v3(0, 0, 1)); /* counter-clockwise seen from +z */
	CHECK_NEAR(h.u, 0.5, EPS);
	CHECK_NEAR(h.v, 0.25, EPS);
	CHECK(trace(s, v3(3.5, 2, 1), v3(0, 0, -1), &h));
	CHECK(!trace(s, v3(4.5, 2, 1), v3(0, 0, -1), &h));
	scene_free(s);

	/* concave: a U whose notch is x in (1, 2), y in (1, 3) */
	static const double u[][2] = { { 0, 0 }, { 3, 0 }, { 3, 3 }, { 2, 3 }, { 2, 1 }, { 1, 1 }, { 1, 3 }, { 0, 3 } };
	static const uint32_t u_n[] = { 8 };
	o = polygon(u, u_n, 1);
	s = scene_one(&o);
	CHECK(!trace(s, v3(1.5, 2, -1), v3(0, 0, 1), &h)); /* the notch */
	CHECK(trace(s, v3(0.5, 2, -1), v3(0, 0, 1), &h));
	CHECK(trace(s, v3(2.5, 2.9, -1), v3(0, 0, 1), &h));
	CHECK(trace(s, v3(1.5, 0.5, -1), v3(0, 0, 1), &h));
	scene_free(s);

	/* two separate contours, and one nested twice (island in a hole) */
	static const double two[][2] = { { 0, 0 }, { 1, 0 }, { 1, 1 }, { 0, 1 }, { 5, 5 }, { 6, 5 }, { 6, 6 }, { 5, 6 },
					  { -10, -10 }, { 10, -10 }, { 10, 10 }, { -10, 10 } };
	static const uint32_t two_n[] = { 4, 4, 4 };
	o = polygon(two, two_n, 3);
	s = scene_one(&o);
	CHECK(!trace(s, v3(0.5, 0.5, -1), v3(0, 0, 1), &h)); /* inside 2 contours: hole */
	CHECK(!trace(s, v3(5.5, 5.5, -1), v3(0, 0, 1), &h));
	CHECK(trace(s, v3(3, 3, -1), v3(0, 0, 1), &h));
	scene_free(s);
}

static void test_transforms(void)
{
	struct hit h;
	/* stretch-x 2 then translate (5 0 0): an ellipsoid */
	struct scene_object o;
	scene_object_defaults(&o, PRIM_SPHERE);
	xf(&o, XF_STRETCH, 0, 2, v3(0, 0, 0));
	xf(&o, XF_TRANSLATE, 0, 0, v3(5, 0, 0));
	struct scene *s = scene_one(&o);
	CHECK(trace(s, v3(0, 0, 0), v3(1, 0, 0), &h));
	CHECK_NEAR(h.t, 3, EPS);
	CHECK_VEC(h.n, v3(-1, 0, 0));
	CHECK_VEC(h.mp, v3(-1, 0, 0)); /* object space */
	double x = sqrt(2), y = 1 / sqrt(2);
	CHECK(trace(s, v3(5 + x, 5, 0), v3(0, -1, 0), &h));
	CHECK_NEAR(h.t, 5 - y, 1e-9);
	CHECK_VEC(h.n, v3_norm(v3(x / 4, y, 0))); /* inverse transpose */
	scene_free(s);

	/* shrink-y 2: y scaled by 1/2 */
	scene_object_defaults(&o, PRIM_SPHERE);
	xf(&o, XF_SHRINK, 1, 2, v3(0, 0, 0));
	s = scene_one(&o);
	CHECK(trace(s, v3(0, 5, 0), v3(0, -1, 0), &h));
	CHECK_NEAR(h.t, 4.5, EPS);
	CHECK_VEC(h.n, v3(0, 1, 0));
	scene_free(s);

	/* z-rotate 90 turns x toward y: box (0 0 0)-(1 2 3) -> x in [-2,0], y in [0,1] */
	scene_object_defaults(&o, PRIM_BOX);
	o.u.box.b = v3(1, 2, 3);
	xf(&o, XF_ROTATE, 2, 90, v3(0, 0, 0));
	s = scene_one(&o);
	CHECK(trace(s, v3(-1, 0.5, -10), v3(0, 0, 1), &h));
	CHECK_NEAR(h.t, 10, EPS);
	CHECK(trace(s, v3(-5, 0.5, 1), v3(1, 0, 0), &h));
	CHECK_NEAR(h.t, 3, 1e-12);
	CHECK_VEC(h.n, v3(-1, 0, 0)); /* was the +y face */
	CHECK(!trace(s, v3(0.5, 0.5, -10), v3(0, 0, 1), &h));
	scene_free(s);

	/* x-rotate 90 turns y toward z: the default plane faces +z */
	scene_object_defaults(&o, PRIM_PLANE);
	xf(&o, XF_ROTATE, 0, 90, v3(0, 0, 0));
	s = scene_one(&o);
	CHECK(trace(s, v3(1, 2, -3), v3(0, 0, 1), &h));
	CHECK_NEAR(h.t, 3, EPS);
	CHECK_VEC(h.n, v3(0, 0, 1));
	CHECK_NEAR(h.u, 1, EPS); /* object space (1, 0, -2): u = x, v = -z */
	CHECK_NEAR(h.v, 2, EPS);
	scene_free(s);

	/* triangles are baked: translate (0 0 5), y-rotate 90 (z toward x) */
	scene_object_defaults(&o, PRIM_TRIANGLE);
	o.u.triangle.a = v3(0, 0, 0);
	o.u.triangle.b = v3(2, 0, 0);
	o.u.triangle.c = v3(0, 2, 0);
	xf(&o, XF_TRANSLATE, 0, 0, v3(0, 0, 5));
	s = scene_one(&o);
	CHECK(trace(s, v3(0.5, 0.5, 0), v3(0, 0, 1), &h));
	CHECK_NEAR(h.t, 5, EPS);
	CHECK_VEC(h.mp, v3(0.5, 0.5, 0));
	CHECK_NEAR(h.u, 0.5, EPS);
	scene_free(s);
	scene_object_defaults(&o, PRIM_TRIANGLE);
	o.u.triangle.a = v3(0, 0, 0);
	o.u.triangle.b = v3(2, 0, 0);
	o.u.triangle.c = v3(0, 2, 0);
	xf(&o, XF_ROTATE, 1, 90, v3(0, 0, 0)); /* +x -> -z, +z -> +x: normal +z -> +x */
	s = scene_one(&o);
	CHECK(trace(s, v3(5, 0.5, -0.5), v3(-1, 0, 0), &h));
	CHECK_NEAR(h.t, 5, 1e-12);
	CHECK_VEC(h.ng, v3(1, 0, 0));
	CHECK_VEC(h.mp, v3(0.5, 0.5, 0));
	scene_free(s);

	/* cylinder under translate + rotate: normals and (u,v) from object space */
	scene_object_defaults(&o, PRIM_CYLINDER);
	o.u.cylinder.to = v3(0, 2, 0);
	xf(&o, XF_ROTATE, 0, 90, v3(0, 0, 0)); /* axis +y -> +z */
	xf(&o, XF_TRANSLATE, 0, 0, v3(10, 0, 0));
	s = scene_one(&o);
	CHECK(trace(s, v3(10, -5, 1), v3(0, 1, 0), &h));
	CHECK_NEAR(h.t, 4, 1e-12);
	CHECK_VEC(h.n, v3(0, -1, 0));
	CHECK_NEAR(h.v, 1, 1e-12);
	scene_free(s);
}

static void test_offset(void)
{
	/* secondary rays from hits on a sphere and a mesh-like triangle fan:
	 * leaving outward must not hit the same surface again */
	struct scene_object o;
	scene_object_defaults(&o, PRIM_SPHERE);
	o.u.sphere.centre = v3(100, 200, 300);
	o.u.sphere.radius = 7;
	struct scene *s = scene_one(&o);
	struct accel *a;
	CHECK(accel_build(s, &a, &err) == 0);
	int acne = 0, misses = 0;
	for (int k = 0; k < 2000; k++) {
		double th = k * 0.61803398875 * 2 * M_PI, z = (k + 0.5) / 2000.0 * 2 - 1;
		vec3 dir = v3(sqrt(1 - z * z) * cos(th), sqrt(1 - z * z) * sin(th), z);
		struct ray r = { v3_add(o.u.sphere.centre, v3_scale(dir, 50)), v3_neg(dir), 0, INFINITY };
		struct hit h;
		if (!accel_intersect(a, &r, &h)) {
			misses++;
			continue;
		}
		/* leave along a grazing direction on the outside */
		vec3 t = v3_norm(v3_cross(h.ng, v3(0.3, 0.7, 0.1)));
		vec3 out = v3_norm(v3_add(t, v3_scale(h.ng, 1e-3)));
		struct ray r2 = { accel_offset_point(h.p, h.ng, out), out, 0, INFINITY };
		acne += accel_occluded(a, &r2);
		/* and go inside (refraction): must find the far side, not the entry */
		vec3 in = v3_neg(h.ng);
		struct ray r3 = { accel_offset_point(h.p, h.ng, in), in, 0, INFINITY };
		struct hit h3;
		CHECK(accel_intersect(a, &r3, &h3));
		acne += !(h3.t > 13.9);
	}
	CHECK(misses == 0);
	CHECK(acne == 0);
	accel_free(a);
	scene_free(s);
}

/* geom_fmin and geom_fmax against the library's fmin and fmax, bit for
 * bit, on signed zeros, infinities, NaN and ordinary values in every order
 * (the values the tracer's roots and offsets have always had). */
static void test_fmin_fmax(void)
{
	/* volatile: the compiler would fold fmin and fmax of constants by its
	 * own rules, not the library's */
	static volatile double v[] = { 0.0, -0.0, 1.0, -1.0, 0.5, 1e-310, -1e-310, 1e300, INFINITY, -INFINITY, NAN, 3.0 };
	const int n = (int)(sizeof v / sizeof v[0]);
	for (int i = 0; i < n; i++)
		for (int j = 0; j < n; j++) {
			double x = v[i], y = v[j];
			double a = geom_fmin(x, y), b = fmin(x, y);
			double c = geom_fmax(x, y), d = fmax(x, y);
			CHECK((a != a && b != b) || memcmp(&a, &b, sizeof a) == 0);
			CHECK((c != c && d != d) || memcmp(&c, &d, sizeof c) == 0);
		}
}


/* A splitmix64 stream for the pre-reject's lines (the test's own). */
static uint64_t tube_state = 0x9e3779b97f4a7c15ull;
static double tube_uniform(void)
{
	uint64_t z = (tube_state += 0x9e3779b97f4a7c15ull);
	z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
	z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
	return (double)((z ^ (z >> 31)) >> 11) * 0x1p-53;
}

/*
 * TUBE PRE-REJECT (geom.h): on lines passing a cylinder's axis at distance
 * r (1 + e), e from -1e-3 to 1e-3 log-uniformly (down to 1e-17) and beyond,
 * at scales from 1e-3 to 1e3, it never says "misses" where
 * geom_sphere_roots finds roots, and it does say so for the misses by ten
 * times its margin.
 */
static void test_tube_pre_reject(void)
{
	long wrong = 0, clear = 0, caught = 0, near = 0;
	for (int i = 0; i < 400000; i++) {
		double scale = pow(10, 6 * tube_uniform() - 3), r = scale * (0.01 + tube_uniform());
		/* the axis along a random unit a; the line's closest point at
		 * distance r (1 + e) along a unit w perpendicular to a */
		vec3 a = v3_norm(v3(tube_uniform() - 0.5, tube_uniform() - 0.5, tube_uniform() - 0.5));
		vec3 w = v3_norm(v3_sub(v3(tube_uniform() - 0.5, tube_uniform() - 0.5, tube_uniform() - 0.5),
					v3_scale(a, 0)));
		w = v3_norm(v3_sub(w, v3_scale(a, v3_dot(w, a))));
		double e = (tube_uniform() < 0.5 ? -1 : 1) * pow(10, -17 + 14 * tube_uniform());
		if (i % 4 == 0)
			e = 4 * tube_uniform() - 1; /* well inside or well outside */
		vec3 dir = v3_norm(v3_add(v3_scale(a, 3 * (tube_uniform() - 0.5)), v3_cross(a, w)));
		vec3 p = v3_add(v3_scale(w, r * (1 + e)), v3_scale(a, scale * (tube_uniform() - 0.5)));
		vec3 o = v3_sub(p, v3_scale(dir, scale * 10 * tube_uniform()));
		vec3 op = v3_sub(o, v3_scale(a, v3_dot(o, a))), dp = v3_sub(dir, v3_scale(a, v3_dot(dir, a)));
		double r2 = r * r, t0, t1;
		bool rej = geom_tube_misses(op, dp, r2);
		wrong += rej && geom_sphere_roots(op, dp, r2, &t0, &t1);
		near += fabs(e) < 1e-6;
		double d2 = r * (1 + e) * r * (1 + e); /* the line's distance, squared */
		if (d2 - r2 > 1e-8 * (v3_dot(op, op) + r2)) { /* ten times the margin */
			clear++;
			caught += rej;
		}
	}
	CHECK(wrong == 0);
	CHECK(near > 100000);
	CHECK(clear > 0 && caught == clear);
}

int main(void)
{
	test_sphere();
	test_plane_disk();
	test_cylinder();
	test_box();
	test_triangle();
	test_mesh_watertight();
	test_polygon();
	test_transforms();
	test_offset();
	test_fmin_fmax();
	test_tube_pre_reject();
	TEST_MAIN_END();
}
