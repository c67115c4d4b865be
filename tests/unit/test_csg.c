/*
 * test_csg.c - CSG truth tables: for each operation, rays through known
 * regions of two overlapping spheres and boxes hit or miss at the right t
 * with the right material and outward normal; planes as half-spaces; open
 * surfaces (disk, open cylinder) per docs/language.md; raw meshes as closed
 * solids; instances as operands; transforms on operands and nodes; nesting
 * at the depth limit, and one over it refused.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/accel.h"
#include "tests/unit/build_util.h"
#include "tests/unit/check.h"

#define EPS 1e-9

static struct scene_error err;


static uint32_t sphere(struct scene *s, vec3 c, double r, uint32_t mat)
{
	struct scene_object o;
	scene_object_defaults(&o, PRIM_SPHERE);
	o.u.sphere.centre = c;
	o.u.sphere.radius = r;
	o.material = mat;
	return bu_add(s, &o);
}

static uint32_t box(struct scene *s, vec3 a, vec3 b, uint32_t mat)
{
	struct scene_object o;
	scene_object_defaults(&o, PRIM_BOX);
	o.u.box.a = a;
	o.u.box.b = b;
	o.material = mat;
	return bu_add(s, &o);
}

static uint32_t csg(struct scene *s, enum csg_op op, uint32_t a, uint32_t b, uint32_t mat)
{
	struct scene_object o;
	scene_object_defaults(&o, PRIM_CSG);
	o.u.csg.op = op;
	o.u.csg.operand1 = a;
	o.u.csg.operand2 = b;
	o.material = mat;
	return bu_add(s, &o);
}

struct expect {
	vec3 o, d;
	bool hit;
	double t;
	uint32_t material;
	vec3 n;
};

/* Builds the accel over root and checks every expectation (and brute force). */
static void run(struct scene *s, uint32_t root, const struct expect *e, int n, int line)
{
	CHECK(scene_add_root(s, root, &err) == 0);
	struct accel *a;
	if (accel_build(s, &a, &err)) {
		fprintf(stderr, "accel: %s\n", err.msg);
		CHECK(!"accel builds");
		return;
	}
	for (int i = 0; i < n; i++) {
		struct ray r = { e[i].o, e[i].d, 0, INFINITY };
		struct hit h, hb;
		bool got = accel_intersect(a, &r, &h);
		bool gotb = accel_intersect_brute(a, &r, &hb);
		bool ok = got == e[i].hit && gotb == got && accel_occluded(a, &r) == got;
		if (ok && got) {
			ok = fabs(h.t - e[i].t) <= EPS && h.material == e[i].material && hb.t == h.t &&
			     v3_len(v3_sub(h.n, e[i].n)) <= 1e-9 && v3_len(v3_sub(h.ng, e[i].n)) <= 1e-9;
		}
		if (!ok) {
			fprintf(stderr, "line %d case %d: expected %s t=%g mat=%u n=(%g %g %g); got %s t=%g mat=%u n=(%g %g %g)\n",
				line, i, e[i].hit ? "hit" : "miss", e[i].t, e[i].material, e[i].n.x, e[i].n.y, e[i].n.z,
				got ? "hit" : "miss", got ? h.t : 0, got ? h.material : 0, got ? h.n.x : 0,
				got ? h.n.y : 0, got ? h.n.z : 0);
		}
		CHECK(ok);
	}
	accel_free(a);
}

#define RUN(s, root, e) run((s), (root), (e), (int)(sizeof(e) / sizeof *(e)), __LINE__)
#define X v3(1, 0, 0)
#define NX v3(-1, 0, 0)

/* Spheres A (centre -0.5, material 0) and B (centre +0.5, material 1), r = 1:
 * A spans x in [-1.5, 0.5], B [-0.5, 1.5] on the axis. */
static void spheres(void)
{
	for (int op = CSG_UNION; op <= CSG_SUBTRACT; op++) {
		for (int swap = 0; swap < 2; swap++) {
			struct scene *s = scene_new();
			uint32_t ma = bu_material(s, 0.1), mb = bu_material(s, 0.2);
			uint32_t a = sphere(s, v3(-0.5, 0, 0), 1, ma), b = sphere(s, v3(0.5, 0, 0), 1, mb);
			uint32_t root = swap ? csg(s, (enum csg_op)op, b, a, SCENE_NONE) : csg(s, (enum csg_op)op, a, b, SCENE_NONE);
			/* at y = 0.9: A spans [-0.936, -0.064], B [0.064, 0.936] */
			double e9 = sqrt(1 - 0.81);
			struct expect e[4];
			vec3 from_left = v3(-5, 0, 0), from_right = v3(5, 0, 0), high_left = v3(-5, 0.9, 0);
			if (op == CSG_UNION) {
				e[0] = (struct expect){ from_left, X, true, 3.5, ma, NX };
				e[1] = (struct expect){ from_right, NX, true, 3.5, mb, X };
				e[2] = (struct expect){ high_left, X, true, 5 - 0.5 - e9, ma, v3_norm(v3(-e9, 0.9, 0)) };
				e[3] = (struct expect){ v3(0, 0, 0), X, true, 1.5, mb, X }; /* from inside both */
			} else if (op == CSG_INTERSECT) {
				e[0] = (struct expect){ from_left, X, true, 4.5, mb, NX };
				e[1] = (struct expect){ from_right, NX, true, 4.5, ma, X };
				e[2] = (struct expect){ high_left, X, false, 0, 0, X };
				e[3] = (struct expect){ v3(0, 0, 0), X, true, 0.5, ma, X };
			} else if (!swap) { /* A - B: x in [-1.5, -0.5] */
				e[0] = (struct expect){ from_left, X, true, 3.5, ma, NX };
				e[1] = (struct expect){ from_right, NX, true, 5.5, mb, X }; /* B's face, flipped */
				e[2] = (struct expect){ high_left, X, true, 5 - 0.5 - e9, ma, v3_norm(v3(-e9, 0.9, 0)) };
				e[3] = (struct expect){ v3(-1, 0, 0), X, true, 0.5, mb, X }; /* leaving through B */
			} else { /* B - A: x in [0.5, 1.5] */
				e[0] = (struct expect){ from_left, X, true, 5.5, ma, NX };
				e[1] = (struct expect){ from_right, NX, true, 3.5, mb, X };
				/* from x = 0 at y = 0.9: B spans [0.064, 0.936] there, A is behind */
				e[2] = (struct expect){ v3(0, 0.9, 0), X, true, 0.5 - e9, mb, v3_norm(v3(-e9, 0.9, 0)) };
				/* from inside both: the result starts where A ends (A's face, flipped) */
				e[3] = (struct expect){ v3(0, 0, 0), X, true, 0.5, ma, NX };
			}
			RUN(s, root, e);
			scene_free(s);
		}
	}
}

/* Boxes A = [0,2]^3 (material 0), B = [1,3]^3 (material 1); rays along x at y = z = 1.5. */
static void boxes(void)
{
	for (int op = CSG_UNION; op <= CSG_SUBTRACT; op++) {
		struct scene *s = scene_new();
		uint32_t ma = bu_material(s, 0.1), mb = bu_material(s, 0.2), mn = bu_material(s, 0.3);
		uint32_t a = box(s, v3(0, 0, 0), v3(2, 2, 2), ma), b = box(s, v3(3, 3, 3), v3(1, 1, 1), SCENE_NONE);
		uint32_t root = csg(s, (enum csg_op)op, a, b, mn); /* B inherits the node's */
		(void)mb;
		vec3 l = v3(-5, 1.5, 1.5), r = v3(5, 1.5, 1.5), low = v3(-5, 0.5, 0.5);
		struct expect e[3];
		if (op == CSG_UNION) {
			e[0] = (struct expect){ l, X, true, 5, ma, NX };
			e[1] = (struct expect){ r, NX, true, 2, mn, X };
			e[2] = (struct expect){ low, X, true, 5, ma, NX };
		} else if (op == CSG_INTERSECT) {
			e[0] = (struct expect){ l, X, true, 6, mn, NX };
			e[1] = (struct expect){ r, NX, true, 3, ma, X };
			e[2] = (struct expect){ low, X, false, 0, 0, X };
		} else {
			e[0] = (struct expect){ l, X, true, 5, ma, NX };
			e[1] = (struct expect){ r, NX, true, 4, mn, X }; /* B's x=1 face, flipped */
			e[2] = (struct expect){ v3(0.5, 1.5, 1.5), X, true, 0.5, mn, X };
		}
		RUN(s, root, e);
		scene_free(s);
	}
}

/* Planes are half-spaces behind their normal; disks have no inside. */
static void planes_and_surfaces(void)
{
	struct scene *s = scene_new();
	uint32_t ms = bu_material(s, 0.1), mp = bu_material(s, 0.2);
	uint32_t sp = sphere(s, v3(0, 0, 0), 1, ms);
	struct scene_object o;
	scene_object_defaults(&o, PRIM_PLANE); /* y = 0, normal +y: keeps y < 0 */
	o.material = mp;
	uint32_t pl = bu_add(s, &o);
	uint32_t root = csg(s, CSG_INTERSECT, sp, pl, SCENE_NONE);
	struct expect e1[] = {
		{ v3(0, 5, 0), v3(0, -1, 0), true, 5, mp, v3(0, 1, 0) },
		{ v3(0, -5, 0), v3(0, 1, 0), true, 4, ms, v3(0, -1, 0) },
		{ v3(0.5, 0.5, -5), v3(0, 0, 1), false, 0, 0, X },
		{ v3(3, 5, 0), v3(0, -1, 0), false, 0, 0, X },
	};
	RUN(s, root, e1);
	scene_free(s);

	/* a disk (z = 0, radius 2) with a unit sphere, each operation */
	for (int op = CSG_UNION; op <= CSG_SUBTRACT + 1; op++) {
		s = scene_new();
		ms = bu_material(s, 0.1);
		uint32_t md = bu_material(s, 0.2);
		sp = sphere(s, v3(0, 0, 0), 1, ms);
		scene_object_defaults(&o, PRIM_DISK);
		o.u.plane.normal = v3(0, 0, 1);
		o.u.plane.radius = 2;
		o.material = md;
		uint32_t dk = bu_add(s, &o);
		/* op 3: sphere - disk (the disk's parts are never drawn) */
		root = op <= CSG_SUBTRACT ? csg(s, (enum csg_op)op, dk, sp, SCENE_NONE) : csg(s, CSG_SUBTRACT, sp, dk, SCENE_NONE);
		vec3 c = v3(0, 0, -5), side = v3(1.5, 0, -5), z = v3(0, 0, 1), nz = v3(0, 0, -1);
		struct expect e[2];
		if (op == CSG_UNION) {
			e[0] = (struct expect){ c, z, true, 4, ms, nz };
			e[1] = (struct expect){ side, z, true, 5, md, z };
		} else if (op == CSG_INTERSECT) {
			e[0] = (struct expect){ c, z, true, 5, md, z };
			e[1] = (struct expect){ side, z, false, 0, 0, z };
		} else if (op == CSG_SUBTRACT) {
			e[0] = (struct expect){ c, z, false, 0, 0, z };
			e[1] = (struct expect){ side, z, true, 5, md, z };
		} else {
			e[0] = (struct expect){ c, z, true, 4, ms, nz };
			e[1] = (struct expect){ side, z, false, 0, 0, z };
		}
		RUN(s, root, e);
		scene_free(s);
	}

	/* an open cylinder is its capped solid inside, but its caps are not drawn */
	s = scene_new();
	ms = bu_material(s, 0.1);
	scene_object_defaults(&o, PRIM_CYLINDER);
	o.u.cylinder.from = v3(0, -1, 0);
	o.u.cylinder.to = v3(0, 1, 0);
	uint32_t cy = bu_add(s, &o);
	sp = sphere(s, v3(0, 0, 0), 5, ms);
	uint32_t in = csg(s, CSG_INTERSECT, cy, sp, SCENE_NONE);
	struct expect e2[] = {
		{ v3(0, -5, 0.5), v3(0, 1, 0), false, 0, 0, X }, /* neither cap is drawn */
		{ v3(-5, 0, 0), X, true, 4, SCENE_NONE, NX },     /* the side is */
	};
	RUN(s, in, e2);
	scene_free(s);

	s = scene_new();
	ms = bu_material(s, 0.1);
	cy = bu_add(s, &o);
	sp = sphere(s, v3(0, 0, 0), 5, ms);
	uint32_t big = sphere(s, v3(0, 10, 0), 9.5, ms); /* cuts the cylinder above y = 0.5 */
	in = csg(s, CSG_INTERSECT, cy, sp, SCENE_NONE);
	root = csg(s, CSG_SUBTRACT, in, big, SCENE_NONE);
	struct expect e3[] = {
		{ v3(0, 0, 0), v3(0, 1, 0), true, 0.5, ms, v3(0, 1, 0) }, /* the cut, facing out of the result */
		{ v3(0, -5, 0), v3(0, 1, 0), true, 5.5, ms, v3(0, 1, 0) }, /* seen through the open bottom */
	};
	RUN(s, root, e3);
	scene_free(s);
}

/* A raw mesh cube [-1,1]^3 with outward triangles, minus a sphere at (1 0 0). */
static void mesh_solid(void)
{
	struct scene *s = scene_new();
	uint32_t mm = bu_material(s, 0.1), ms = bu_material(s, 0.2);
	struct scene_mesh m;
	memset(&m, 0, sizeof m);
	m.file = strdup("cube.raw");
	m.n_vertices = 8;
	m.n_triangles = 12;
	m.vertices = malloc(8 * sizeof *m.vertices);
	m.tris = malloc(36 * sizeof *m.tris);
	for (int i = 0; i < 8; i++)
		m.vertices[i] = v3(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1);
	int nt = 0;
	for (int k = 0; k < 3; k++) {
		for (int sgn = 0; sgn < 2; sgn++) {
			int bit = 1 << k, u = 1 << ((k + 1) % 3), v = 1 << ((k + 2) % 3);
			int base = sgn ? bit : 0;
			int q[4] = { base, base | u, base | u | v, base | v };
			vec3 out = v3(k == 0 ? (sgn ? 1 : -1) : 0, k == 1 ? (sgn ? 1 : -1) : 0, k == 2 ? (sgn ? 1 : -1) : 0);
			for (int t = 0; t < 2; t++) {
				int a = q[0], b = q[1 + t], c = q[2 + t];
				vec3 n = v3_cross(v3_sub(m.vertices[b], m.vertices[a]), v3_sub(m.vertices[c], m.vertices[a]));
				if (v3_dot(n, out) < 0) {
					int tmp = b;
					b = c, c = tmp;
				}
				m.tris[3 * nt] = (uint32_t)a, m.tris[3 * nt + 1] = (uint32_t)b, m.tris[3 * nt + 2] = (uint32_t)c;
				nt++;
			}
		}
	}
	uint32_t mid;
	CHECK(scene_add_mesh(s, &m, &mid, &err) == 0);
	struct scene_object o;
	scene_object_defaults(&o, PRIM_RAW);
	o.u.raw.mesh = mid;
	o.material = mm;
	uint32_t cube = bu_add(s, &o);
	uint32_t sp = sphere(s, v3(1, 0, 0), 0.5, ms);
	uint32_t root = csg(s, CSG_SUBTRACT, cube, sp, SCENE_NONE);
	struct expect e[] = {
		{ v3(5, 0, 0), NX, true, 4.5, ms, X },           /* the cube's face is cut away */
		{ v3(5, 0.9, 0), NX, true, 4, mm, X },           /* outside the sphere: the face */
		{ v3(-5, 0, 0), X, true, 4, mm, NX },
		{ v3(0, 0, 0), X, true, 0.5, ms, X },            /* inside: the sphere, flipped */
		{ v3(0, 5, 0), v3(0, -1, 0), true, 4, mm, v3(0, 1, 0) },
	};
	RUN(s, root, e);
	scene_free(s);
}

/* Instances as operands, transforms on operands and on the node. */
static void instances_and_transforms(void)
{
	struct scene *s = scene_new();
	uint32_t ma = bu_material(s, 0.1), mb = bu_material(s, 0.2), mi = bu_material(s, 0.3);
	uint32_t a = sphere(s, v3(0, 0, 0), 1, SCENE_NONE); /* member without a material */
	struct scene_define d;
	memset(&d, 0, sizeof d);
	d.name = strdup("ball");
	d.n_objects = 1;
	d.objects = malloc(sizeof *d.objects);
	d.objects[0] = a;
	uint32_t did;
	CHECK(scene_add_define(s, &d, &did, &err) == 0);
	struct scene_object o;
	scene_object_defaults(&o, PRIM_INSTANCE);
	o.u.instance.define = did;
	o.material = mi;
	CHECK(scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0, v3(-0.5, 0, 0)));
	o.has_xform = true;
	uint32_t ia = bu_add(s, &o);
	uint32_t b = sphere(s, v3(0.5, 0, 0), 1, mb);
	scene_object_defaults(&o, PRIM_CSG);
	o.u.csg.op = CSG_INTERSECT;
	o.u.csg.operand1 = ia;
	o.u.csg.operand2 = b;
	o.material = ma;
	CHECK(scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0, v3(0, 10, 0)));
	o.has_xform = true;
	uint32_t root = bu_add(s, &o);
	struct expect e[] = {
		{ v3(-5, 10, 0), X, true, 4.5, mb, NX },
		{ v3(5, 10, 0), NX, true, 4.5, mi, X }, /* instance's material over the node's */
		{ v3(-5, 0, 0), X, false, 0, 0, X },
	};
	RUN(s, root, e);
	/* mp is in the instance's own space for the instance's material */
	struct accel *acc;
	CHECK(accel_build(s, &acc, &err) == 0);
	struct ray r = { v3(5, 10, 0), NX, 0, INFINITY };
	struct hit h;
	CHECK(accel_intersect(acc, &r, &h));
	accel_hit_surface(acc, &h);
	CHECK_NEAR(h.mp.x, 1, EPS); /* world x 0.5 = define x 1 */
	CHECK_NEAR(h.mp.y, 0, EPS);
	CHECK(h.object == a);
	accel_free(acc);
	scene_free(s);
}

/* LIM_CSG_DEPTH nested nodes work; one more is refused. */
static void depth(void)
{
	for (int extra = 0; extra < 2; extra++) {
		struct scene *s = scene_new();
		uint32_t cur = sphere(s, v3(0, 0, 0), 1, SCENE_NONE);
		for (int i = 0; i < LIM_CSG_DEPTH + extra; i++) {
			uint32_t other = sphere(s, v3(0.01 * (i + 1), 0, 0), 1, SCENE_NONE);
			cur = csg(s, i % 2 ? CSG_UNION : CSG_INTERSECT, cur, other, SCENE_NONE);
		}
		CHECK(scene_add_root(s, cur, &err) == 0);
		struct accel *a = NULL;
		int rc = accel_build(s, &a, &err);
		if (extra) {
			CHECK(rc != 0 && a == NULL);
			CHECK(strstr(err.msg, "csg nested deeper") != NULL);
		} else {
			CHECK(rc == 0);
			struct ray r = { v3(-5, 0, 0), X, 0, INFINITY };
			struct hit h;
			CHECK(a && accel_intersect(a, &r, &h));
		}
		accel_free(a);
		scene_free(s);
	}
}

int main(void)
{
	spheres();
	boxes();
	planes_and_surfaces();
	mesh_solid();
	instances_and_transforms();
	depth();
	TEST_MAIN_END();
}
