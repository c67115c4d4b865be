/*
 * test_accel.c - instancing and the accel's contract: a define used through
 * (nested) instances gives the same hits as the same objects written inline
 * with the composed transforms (instances keep their inverse as floats:
 * positions agree to 1e-6 of the coordinates), with the right leaf object
 * and inherited materials; mp in the material owner's space; unbounded members; empty defines; the
 * define depth limit; tmin/tmax; bad rays; stats; coincident surfaces (the
 * first written wins, whatever the traversal, single rays and packets alike).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/accel.h"
#include "common/rng.h"
#include "tests/unit/build_util.h"
#include "tests/unit/check.h"

static struct scene_error err;


#define N_MEMBERS 8

/*
 * Adds the block's members, each with transform pre (applied after the
 * member's own transform) and returns their indices in ids[]. Members 0, 2
 * and 5 have their own material mat_own; the rest none.
 */
static void add_members(struct scene *s, const mat34 *pre, uint32_t mesh, uint32_t mat_own, uint32_t *ids)
{
	struct scene_object o[N_MEMBERS];
	scene_object_defaults(&o[0], PRIM_SPHERE);
	o[0].u.sphere.centre = v3(0.2, 0.3, 0.1);
	o[0].u.sphere.radius = 0.3;
	scene_object_defaults(&o[1], PRIM_BOX);
	o[1].u.box.a = v3(0.5, 0, 0);
	o[1].u.box.b = v3(1, 0.5, 0.25);
	scene_xform_op(&o[1].xform, XF_ROTATE, 1, 20, v3(0, 0, 0));
	o[1].has_xform = true;
	scene_object_defaults(&o[2], PRIM_TRIANGLE);
	o[2].u.triangle.a = v3(0, 0.6, 0);
	o[2].u.triangle.b = v3(1, 0.6, 0);
	o[2].u.triangle.c = v3(0, 0.9, 0.5);
	scene_object_defaults(&o[3], PRIM_CYLINDER);
	o[3].u.cylinder.from = v3(0.1, 0, 0.5);
	o[3].u.cylinder.to = v3(0.9, 0.2, 0.5);
	o[3].u.cylinder.radius = 0.1;
	o[3].u.cylinder.capped = true;
	scene_object_defaults(&o[4], PRIM_DISK);
	o[4].u.plane.position = v3(0.5, 0.5, 0.8);
	o[4].u.plane.normal = v3(0, 1, 1);
	o[4].u.plane.radius = 0.2;
	scene_object_defaults(&o[5], PRIM_RAW);
	o[5].u.raw.mesh = mesh;
	scene_xform_op(&o[5].xform, XF_STRETCH, 2, 1.5, v3(0, 0, 0));
	o[5].has_xform = true;
	scene_object_defaults(&o[6], PRIM_SPHERE); /* transformed sphere: an ellipsoid */
	o[6].u.sphere.centre = v3(0.8, 0.8, 0.2);
	o[6].u.sphere.radius = 0.1;
	scene_xform_op(&o[6].xform, XF_STRETCH, 0, 1.7, v3(0, 0, 0));
	o[6].has_xform = true;
	scene_object_defaults(&o[7], PRIM_POLYGON);
	o[7].u.polygon.n_contours = 1;
	o[7].u.polygon.n_points = 4;
	o[7].u.polygon.contour_start = malloc(2 * sizeof(uint32_t));
	o[7].u.polygon.points = malloc(4 * sizeof(vec3));
	o[7].u.polygon.contour_start[0] = 0;
	o[7].u.polygon.contour_start[1] = 4;
	o[7].u.polygon.points[0] = v3(0, 0, 1);
	o[7].u.polygon.points[1] = v3(0.3, 0, 1);
	o[7].u.polygon.points[2] = v3(0.1, 0.1, 1); /* concave dart */
	o[7].u.polygon.points[3] = v3(0, 0.3, 1);
	for (int i = 0; i < N_MEMBERS; i++) {
		if (i == 0 || i == 2 || i == 5)
			o[i].material = mat_own;
		if (pre) {
			o[i].xform = m34_mul(pre, &o[i].xform);
			o[i].has_xform = true;
		}
		ids[i] = bu_add(s, &o[i]);
	}
}

static uint32_t small_mesh(struct scene *s)
{
	struct scene_mesh m;
	memset(&m, 0, sizeof m);
	m.file = strdup("tet.raw");
	m.n_vertices = 4;
	m.n_triangles = 4;
	m.vertices = malloc(4 * sizeof *m.vertices);
	m.tris = malloc(12 * sizeof *m.tris);
	m.vertices[0] = v3(0.4, 0.1, 0.3), m.vertices[1] = v3(0.7, 0.1, 0.3);
	m.vertices[2] = v3(0.5, 0.4, 0.3), m.vertices[3] = v3(0.5, 0.2, 0.6);
	uint32_t t[12] = { 0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3 };
	memcpy(m.tris, t, sizeof t);
	uint32_t id;
	if (scene_add_mesh(s, &m, &id, &err))
		abort();
	return id;
}

static mat34 xform3(double rot, int axis, vec3 tr, double stretch)
{
	mat34 m = m34_identity();
	scene_xform_op(&m, XF_STRETCH, axis, stretch, v3(0, 0, 0));
	scene_xform_op(&m, XF_ROTATE, (axis + 1) % 3, rot, v3(0, 0, 0));
	scene_xform_op(&m, XF_TRANSLATE, 0, 0, tr);
	return m;
}

static uint32_t define(struct scene *s, const char *name, const uint32_t *objs, uint32_t n)
{
	struct scene_define d;
	memset(&d, 0, sizeof d);
	d.name = strdup(name);
	d.n_objects = n;
	d.objects = malloc(n * sizeof *d.objects);
	memcpy(d.objects, objs, n * sizeof *objs);
	uint32_t id;
	if (scene_add_define(s, &d, &id, &err))
		abort();
	return id;
}

static uint32_t instance(struct scene *s, uint32_t def, const mat34 *m, uint32_t mat)
{
	struct scene_object o;
	scene_object_defaults(&o, PRIM_INSTANCE);
	o.u.instance.define = def;
	o.xform = *m;
	o.has_xform = true;
	o.material = mat;
	return bu_add(s, &o);
}

/* A wall: 2 walls of 3 rows of 3 blocks, through nested defines and inline. */
static void instanced_equals_inline(void)
{
	struct scene *si = scene_new(), *sl = scene_new();
	uint32_t mi_own = bu_material(si, 0.1), mi_inst = bu_material(si, 0.2), mi_row = bu_material(si, 0.3);
	uint32_t ml_own = bu_material(sl, 0.1), ml_inst = bu_material(sl, 0.2), ml_row = bu_material(sl, 0.3);
	uint32_t mesh_i = small_mesh(si), mesh_l = small_mesh(sl);
	uint32_t block[N_MEMBERS];
	add_members(si, NULL, mesh_i, mi_own, block);
	uint32_t d_block = define(si, "block", block, N_MEMBERS);
	mat34 bx[3], rx[3], wx[2];
	for (int i = 0; i < 3; i++) {
		bx[i] = xform3(15.0 * i, i, v3(1.3 * i, 0.1 * i, 0), 1 + 0.2 * i);
		rx[i] = xform3(-10.0 * i, 2 - i, v3(0, 1.5 * i, 0.3 * i), 1);
	}
	wx[0] = m34_identity();
	wx[1] = xform3(90, 0, v3(0, 0, 5), 0.5);
	/* instanced: blocks 0 and 1 carry material mi_inst, 2 none; rows 0 carry mi_row */
	uint32_t row_objs[3], wall_objs[3], roots[2];
	for (int i = 0; i < 3; i++)
		row_objs[i] = instance(si, d_block, &bx[i], i < 2 ? mi_inst : SCENE_NONE);
	uint32_t d_row = define(si, "row", row_objs, 3);
	for (int i = 0; i < 3; i++)
		wall_objs[i] = instance(si, d_row, &rx[i], i == 0 ? mi_row : SCENE_NONE);
	uint32_t d_wall = define(si, "wall", wall_objs, 3);
	for (int i = 0; i < 2; i++) {
		roots[i] = instance(si, d_wall, &wx[i], SCENE_NONE);
		CHECK(scene_add_root(si, roots[i], &err) == 0);
	}
	/* inline: member k of block (w, r, b) with the expected material */
	uint32_t map[2 * 3 * 3 * N_MEMBERS];
	uint32_t want_mat[2 * 3 * 3 * N_MEMBERS];
	uint32_t n_inline = 0;
	uint32_t first_inline = sl->n_objects;
	for (int w = 0; w < 2; w++)
		for (int r = 0; r < 3; r++)
			for (int b = 0; b < 3; b++) {
				mat34 t = m34_mul(&rx[r], &bx[b]);
				t = m34_mul(&wx[w], &t);
				uint32_t ids[N_MEMBERS];
				add_members(sl, &t, mesh_l, ml_own, ids);
				for (int k = 0; k < N_MEMBERS; k++) {
					CHECK(scene_add_root(sl, ids[k], &err) == 0);
					map[n_inline] = block[k];
					bool own = k == 0 || k == 2 || k == 5;
					want_mat[n_inline] = own ? mi_own : b < 2 ? mi_inst : r == 0 ? mi_row : SCENE_NONE;
					n_inline++;
				}
			}
	(void)ml_inst;
	(void)ml_row;
	struct accel *ai, *al;
	CHECK(accel_build(si, &ai, &err) == 0);
	CHECK(accel_build(sl, &al, &err) == 0);
	struct accel_stats st;
	accel_get_stats(ai, &st);
	CHECK(st.n_instances == 3 + 3 + 2); /* references, not copies */
	CHECK(st.n_prims == N_MEMBERS - 1 + 4); /* the mesh counts its 4 triangles */
	vec3 lo, hi;
	CHECK(accel_bounds(al, &lo, &hi));
	int bad_hit = 0, bad_t = 0, bad_obj = 0, bad_mat = 0, bad_n = 0, bad_mp = 0, hits = 0;
	for (int k = 0; k < 20000; k++) {
		vec3 o = v3(lo.x - 1 + (hi.x - lo.x + 2) * rng_uniform(5, 6ull * k),
			    lo.y - 1 + (hi.y - lo.y + 2) * rng_uniform(5, 6ull * k + 1),
			    lo.z - 1 + (hi.z - lo.z + 2) * rng_uniform(5, 6ull * k + 2));
		vec3 d = v3(rng_uniform(5, 6ull * k + 3) - 0.5, rng_uniform(5, 6ull * k + 4) - 0.5,
			    rng_uniform(5, 6ull * k + 5) - 0.5);
		struct ray r = { o, d, 0, INFINITY };
		struct hit h1, h2, hb;
		bool b1 = accel_intersect(ai, &r, &h1), b2 = accel_intersect(al, &r, &h2);
		bool bb = accel_intersect_brute(ai, &r, &hb);
		if (b1 != b2 || bb != b1) {
			bad_hit++;
			continue;
		}
		if (!b1)
			continue;
		accel_hit_surface(ai, &h1);
		accel_hit_surface(al, &h2);
		hits++;
		/* float inverses: positions agree to ~1e-7 of the coordinates */
		if (!(fabs(h1.t - h2.t) * v3_len(d) <= 1e-6 * (1 + v3_len(h2.p))) || hb.t != h1.t) {
			if (bad_t < 5)
				fprintf(stderr, "t %.12g inline %.12g brute %.12g\n", h1.t, h2.t, hb.t);
			bad_t++;
		}
		uint32_t li = h2.object - first_inline;
		/* the inline scene adds materials and the mesh first: object indices
		 * of the inline members are dense from first_inline on */
		if (li >= n_inline) {
			bad_obj++;
			continue;
		}
		bad_obj += h1.object != map[li];
		bad_mat += h1.material != want_mat[li];
		bad_n += v3_len(v3_sub(h1.n, h2.n)) > 1e-4 || v3_len(v3_sub(h1.ng, h2.ng)) > 1e-4;
		bad_n += fabs(v3_len(h1.n) - 1) > 1e-9;
		/* members with their own material: mp is in the member's own space,
		 * the same in both scenes up to the float inverse */
		if (want_mat[li] == mi_own)
			bad_mp += v3_len(v3_sub(h1.mp, h2.mp)) > 1e-4 * (1 + v3_len(h2.mp));
	}
	printf("instanced vs inline: %d hits; bad hit %d t %d object %d material %d normal %d mp %d\n", hits,
	       bad_hit, bad_t, bad_obj, bad_mat, bad_n, bad_mp);
	CHECK(hits > 1000);
	CHECK(bad_hit == 0 && bad_t == 0 && bad_obj == 0 && bad_mat == 0 && bad_n == 0 && bad_mp == 0);
	accel_free(ai);
	accel_free(al);
	scene_free(si);
	scene_free(sl);
}

/* mp follows the material's owner: the instance's own space for inherited ones. */
static void mp_owner(void)
{
	struct scene *s = scene_new();
	uint32_t m = bu_material(s, 0.5);
	struct scene_object o;
	scene_object_defaults(&o, PRIM_SPHERE);
	scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0, v3(1, 0, 0)); /* member: sphere at x=1 */
	o.has_xform = true;
	uint32_t sp = bu_add(s, &o);
	uint32_t d = define(s, "ball", &sp, 1);
	mat34 t = m34_identity();
	scene_xform_op(&t, XF_TRANSLATE, 0, 0, v3(10, 0, 0));
	uint32_t inst = instance(s, d, &t, m);
	CHECK(scene_add_root(s, inst, &err) == 0);
	struct accel *a;
	CHECK(accel_build(s, &a, &err) == 0);
	struct ray r = { v3(11, 0, -5), v3(0, 0, 1), 0, INFINITY };
	struct hit h;
	CHECK(accel_intersect(a, &r, &h));
	accel_hit_surface(a, &h);
	CHECK_NEAR(h.t, 4, 1e-6);
	CHECK(h.material == m && h.object == sp);
	CHECK_NEAR(h.mp.x, 1, 1e-6); /* define space: the member's centre is at x = 1 */
	CHECK_NEAR(h.mp.z, -1, 1e-6);
	CHECK_NEAR(h.p.x, 11, 1e-6);
	/* tmax and tmin bound the hits */
	struct ray r2 = { v3(11, 0, -5), v3(0, 0, 1), 0, 3.9 };
	CHECK(!accel_intersect(a, &r2, &h) && !accel_occluded(a, &r2));
	struct ray r3 = { v3(11, 0, -5), v3(0, 0, 1), 4.5, INFINITY };
	CHECK(accel_intersect(a, &r3, &h));
	CHECK_NEAR(h.t, 6, 1e-6);
	CHECK_NEAR(h.n.z, 1, 1e-6);
	/* a ray is a half-line: a negative tmin counts as 0 (nothing behind) */
	struct ray r4 = { v3(11, 0, 5), v3(0, 0, 1), -100, INFINITY };
	CHECK(!accel_intersect(a, &r4, &h) && !accel_occluded(a, &r4) && !accel_intersect_brute(a, &r4, &h));
	struct ray r5 = { v3(11, 0, -5), v3(0, 0, 1), -100, INFINITY };
	CHECK(accel_intersect(a, &r5, &h));
	CHECK_NEAR(h.t, 4, 1e-6);
	/* bad rays never hit */
	struct ray bad1 = { v3(11, 0, -5), v3(0, 0, 0), 0, INFINITY };
	struct ray bad2 = { v3(NAN, 0, -5), v3(0, 0, 1), 0, INFINITY };
	struct ray bad3 = { v3(11, 0, -5), v3(0, 0, 1), 5, 1 };
	CHECK(!accel_intersect(a, &bad1, &h) && !accel_intersect(a, &bad2, &h) && !accel_intersect(a, &bad3, &h));
	CHECK(!accel_occluded(a, &bad1) && !accel_occluded(a, &bad2));
	accel_free(a);
	scene_free(s);
}

/* A plane inside a define makes its instances unbounded; empty defines draw nothing. */
static void unbounded_and_empty(void)
{
	struct scene *s = scene_new();
	struct scene_object o;
	scene_object_defaults(&o, PRIM_PLANE);
	uint32_t pl = bu_add(s, &o);
	uint32_t d = define(s, "floor", &pl, 1);
	struct scene_define e;
	memset(&e, 0, sizeof e);
	e.name = strdup("empty");
	uint32_t de;
	CHECK(scene_add_define(s, &e, &de, &err) == 0);
	mat34 t = m34_identity();
	scene_xform_op(&t, XF_TRANSLATE, 0, 0, v3(0, -2, 0));
	CHECK(scene_add_root(s, instance(s, d, &t, SCENE_NONE), &err) == 0);
	CHECK(scene_add_root(s, instance(s, de, &t, SCENE_NONE), &err) == 0);
	struct accel *a;
	CHECK(accel_build(s, &a, &err) == 0);
	vec3 lo, hi;
	CHECK(!accel_bounds(a, &lo, &hi));
	struct ray r = { v3(1000, 5, -3000), v3(0.1, -1, 0.2), 0, INFINITY };
	struct hit h;
	CHECK(accel_intersect(a, &r, &h));
	CHECK_NEAR(h.t, 7, 1e-6);
	CHECK(h.object == pl);
	accel_free(a);
	scene_free(s);

	/* an empty scene */
	s = scene_new();
	CHECK(accel_build(s, &a, &err) == 0);
	CHECK(!accel_intersect(a, &r, &h) && !accel_occluded(a, &r));
	accel_free(a);
	scene_free(s);
}

/* LIM_DEFINE_DEPTH nested defines work; one more is refused. */
static void define_depth(void)
{
	for (int extra = 0; extra < 2; extra++) {
		struct scene *s = scene_new();
		struct scene_object o;
		scene_object_defaults(&o, PRIM_SPHERE);
		uint32_t cur = bu_add(s, &o);
		mat34 t = m34_identity();
		scene_xform_op(&t, XF_TRANSLATE, 0, 0, v3(0.01, 0, 0));
		for (int i = 0; i < LIM_DEFINE_DEPTH + extra; i++) {
			char name[32];
			snprintf(name, sizeof name, "d%d", i);
			uint32_t d = define(s, name, &cur, 1);
			cur = instance(s, d, &t, SCENE_NONE);
		}
		CHECK(scene_add_root(s, cur, &err) == 0);
		struct accel *a = NULL;
		int rc = accel_build(s, &a, &err);
		if (extra) {
			CHECK(rc != 0 && a == NULL && strstr(err.msg, "definition nested deeper"));
		} else {
			CHECK(rc == 0);
			struct ray r = { v3(-5, 0, 0), v3(1, 0, 0), 0, INFINITY };
			struct hit h;
			CHECK(a && accel_intersect(a, &r, &h));
			CHECK_NEAR(h.t, 4 + 0.01 * LIM_DEFINE_DEPTH, 1e-5);
		}
		accel_free(a);
		scene_free(s);
	}
}

/*
 * Coincident surfaces: 24 boxes of different sizes share the face x = -1
 * (each box's test computes the same t there), so a ray through that face
 * meets all of them at one t. The first box written must win, for single
 * rays and for packets, however the tree orders the boxes.
 */
static void coincident_surfaces(void)
{
	struct scene *s = scene_new();
	uint32_t first = 0;
	for (int k = 0; k < 24; k++) {
		struct scene_object o;
		scene_object_defaults(&o, PRIM_BOX);
		double e = 1 + 0.37 * ((k * 7 + 23) % 24); /* sizes in scrambled order, the first the largest */
		o.u.box.a = v3(-1, -1, -1);
		o.u.box.b = v3(e, e, e);
		uint32_t id = bu_add(s, &o);
		CHECK(scene_add_root(s, id, &err) == 0);
		if (k == 0)
			first = id;
	}
	struct accel *a;
	CHECK(accel_build(s, &a, &err) == 0);
	int n = 0, wrong = 0;
	for (int k = 0; k < 400; k++) {
		struct ray r[4];
		struct hit h[4], h1;
		bool hit[4];
		vec3 o = v3(-5 - rng_uniform(5, 3 * k), 1.8 * rng_uniform(5, 3 * k + 1) - 0.9,
			    1.8 * rng_uniform(5, 3 * k + 2) - 0.9);
		for (int i = 0; i < 4; i++) /* aimed at the shared face, near (-1, o.y, o.z) */
			r[i] = (struct ray){ o, v3(1, 0.01 * (i & 1) - 0.005, 0.01 * (i >> 1) - 0.005), 0, INFINITY };
		accel_intersect4(a, r, h, hit);
		for (int i = 0; i < 4; i++) {
			n++;
			if (!accel_intersect(a, &r[i], &h1) || !hit[i] || h1.object != first || h[i].object != first ||
			    h1.t != h[i].t)
				wrong++;
		}
	}
	printf("coincident faces of 24 boxes: %d rays, %d not on the first box written\n", n, wrong);
	CHECK(wrong == 0);
	accel_free(a);
	scene_free(s);

	/* the same through 1,100 instances of one box, stretched and moved in
	 * y and z only, so that all share the face x = -1: a group this big
	 * keeps its instances in leaf order (ACCEL_PACK_MIN), yet the first
	 * written, the only red one, must win */
	s = scene_new();
	struct scene_object o;
	scene_object_defaults(&o, PRIM_BOX);
	o.u.box.a = v3(-1, -1, -1);
	o.u.box.b = v3(1, 1, 1);
	uint32_t box = bu_add(s, &o), red = bu_material(s, 1), d = define(s, "slab", &box, 1);
	for (int k = 0; k < 1100; k++) {
		mat34 t = m34_identity();
		scene_xform_op(&t, XF_STRETCH, 1, 5, v3(0, 0, 0));
		scene_xform_op(&t, XF_STRETCH, 2, 5, v3(0, 0, 0));
		scene_xform_op(&t, XF_TRANSLATE, 0, 0, v3(0, 4 * rng_uniform(7, 2 * k) - 2, 4 * rng_uniform(7, 2 * k + 1) - 2));
		CHECK(scene_add_root(s, instance(s, d, &t, k == 0 ? red : SCENE_NONE), &err) == 0);
	}
	CHECK(accel_build(s, &a, &err) == 0);
	n = wrong = 0;
	for (int k = 0; k < 100; k++) {
		struct ray r[4];
		struct hit h[4], h1;
		bool hit[4];
		vec3 org = v3(-5 - rng_uniform(6, 3 * k), 1.8 * rng_uniform(6, 3 * k + 1) - 0.9,
			      1.8 * rng_uniform(6, 3 * k + 2) - 0.9);
		for (int i = 0; i < 4; i++)
			r[i] = (struct ray){ org, v3(1, 0.01 * (i & 1) - 0.005, 0.01 * (i >> 1) - 0.005), 0, INFINITY };
		accel_intersect4(a, r, h, hit);
		for (int i = 0; i < 4; i++) {
			n++;
			if (!accel_intersect(a, &r[i], &h1) || !hit[i] || h1.material != red || h[i].material != red ||
			    h1.t != h[i].t)
				wrong++;
		}
	}
	printf("coincident faces of 1,100 instances: %d rays, %d not on the first instance written\n", n, wrong);
	CHECK(wrong == 0);
	accel_free(a);
	scene_free(s);
}

int main(void)
{
	coincident_surfaces();
	instanced_equals_inline();
	mp_owner();
	unbounded_and_empty();
	define_depth();
	TEST_MAIN_END();
}
