/*
 * test_scene.c - the scene model: defaults, builder validation, ownership,
 * transform composition and rotation sense.
 */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/scene.h"
#include "tests/unit/check.h"

static void test_defaults(void)
{
	struct scene *s = scene_new();
	CHECK(s != NULL);
	CHECK(s->image.xsize == 320 && s->image.ysize == 240);
	CHECK(s->camera.n_filters == 1 && s->camera.filters[0].kind == FILTER_STANDARD);
	const struct scene_material *m = scene_default_material();
	CHECK(m->diffuse == 1.0 && m->specular == 0.0 && m->transparency == 0.0);
	CHECK(m->diff_colour.x == 1 && m->diff_colour.y == 1 && m->diff_colour.z == 1);
	struct scene_filter f;
	scene_filter_defaults(&f, FILTER_LENS);
	CHECK(f.radius == 0.1 && f.focal_length == 1000.0 && f.samples == 4);
	scene_filter_defaults(&f, FILTER_DISK);
	CHECK(f.radius == 0.707 && f.samples == 4);
	scene_filter_defaults(&f, FILTER_ADAPTIVE);
	CHECK(f.threshold == 0.2 && f.max_depth == 3 && f.cache_size == 1000 && f.relax == 1.2);
	scene_free(s);
}

static void test_xform(void)
{
	mat34 m = m34_identity();
	/* z-rotate 90 turns x toward y */
	CHECK(scene_xform_op(&m, XF_ROTATE, 2, 90, v3(0, 0, 0)));
	vec3 p = m34_point(&m, v3(1, 0, 0));
	CHECK_NEAR(p.x, 0, 1e-12);
	CHECK_NEAR(p.y, 1, 1e-12);
	/* then translate: applied after the rotation (written order) */
	CHECK(scene_xform_op(&m, XF_TRANSLATE, 0, 0, v3(5, 0, 0)));
	p = m34_point(&m, v3(1, 0, 0));
	CHECK_NEAR(p.x, 5, 1e-12);
	CHECK_NEAR(p.y, 1, 1e-12);
	/* x-rotate turns y toward z, y-rotate turns z toward x */
	mat34 a = m34_identity();
	CHECK(scene_xform_op(&a, XF_ROTATE, 0, 90, v3(0, 0, 0)));
	p = m34_point(&a, v3(0, 1, 0));
	CHECK_NEAR(p.z, 1, 1e-12);
	mat34 b = m34_identity();
	CHECK(scene_xform_op(&b, XF_ROTATE, 1, 90, v3(0, 0, 0)));
	p = m34_point(&b, v3(0, 0, 1));
	CHECK_NEAR(p.x, 1, 1e-12);
	/* shrink divides, stretch multiplies; 0 is refused */
	mat34 c = m34_identity();
	CHECK(scene_xform_op(&c, XF_SHRINK, 0, 4, v3(0, 0, 0)));
	CHECK(scene_xform_op(&c, XF_STRETCH, 1, 3, v3(0, 0, 0)));
	p = m34_point(&c, v3(1, 1, 1));
	CHECK_NEAR(p.x, 0.25, 1e-15);
	CHECK_NEAR(p.y, 3, 1e-15);
	CHECK(!scene_xform_op(&c, XF_SHRINK, 0, 0, v3(0, 0, 0)));
	/* inverse */
	mat34 inv;
	CHECK(m34_invert(&m, &inv));
	vec3 q = m34_point(&inv, m34_point(&m, v3(0.3, -2, 7)));
	CHECK_NEAR(q.x, 0.3, 1e-12);
	CHECK_NEAR(q.y, -2, 1e-12);
	CHECK_NEAR(q.z, 7, 1e-12);
}

static void test_builder(void)
{
	struct scene *s = scene_new();
	struct scene_error err;
	struct scene_material m;
	uint32_t mid, a, b, c, d;
	scene_material_defaults(&m);
	m.name = strdup("Flat-Red");
	CHECK(scene_add_material(s, &m, &mid, &err) == 0);
	CHECK(scene_find_material(s, "flat-red") == mid);
	CHECK(scene_find_material(s, "nothing") == SCENE_NONE);

	/* a shader referencing a material not yet defined is refused (acyclic) */
	scene_material_defaults(&m);
	scene_shader_defaults(&m.shader, SHADER_CHEQUERS);
	m.shader.mat_a = 5;
	CHECK(scene_add_material(s, &m, NULL, &err) == 1);

	struct scene_object o;
	scene_object_defaults(&o, PRIM_SPHERE);
	CHECK(scene_add_object(s, &o, &a, &err) == 0);
	scene_object_defaults(&o, PRIM_BOX);
	o.material = mid;
	CHECK(scene_add_object(s, &o, &b, &err) == 0);
	scene_object_defaults(&o, PRIM_CSG);
	o.u.csg.operand1 = a;
	o.u.csg.operand2 = b;
	CHECK(scene_add_object(s, &o, &c, &err) == 0);
	/* forward references are refused */
	o.u.csg.operand2 = c + 1;
	CHECK(scene_add_object(s, &o, NULL, &err) == 1);
	/* negative radius refused, message names the location */
	scene_object_defaults(&o, PRIM_SPHERE);
	o.u.sphere.radius = -1;
	o.loc.file = "x.sce";
	o.loc.line = 3;
	o.loc.col = 5;
	CHECK(scene_add_object(s, &o, NULL, &err) == 1);
	CHECK(strstr(err.msg, "x.sce:3:5: error:") != NULL);

	struct scene_define def = { 0 };
	def.name = strdup("athing");
	def.objects = malloc(sizeof *def.objects);
	def.objects[0] = c;
	def.n_objects = 1;
	CHECK(scene_add_define(s, &def, &d, &err) == 0);
	CHECK(def.name == NULL && def.objects == NULL); /* ownership moved */
	CHECK(scene_find_define(s, "ATHING") == d);
	scene_object_defaults(&o, PRIM_INSTANCE);
	o.u.instance.define = d;
	uint32_t inst;
	CHECK(scene_add_object(s, &o, &inst, &err) == 0);
	CHECK(scene_add_root(s, inst, &err) == 0);
	CHECK(scene_add_root(s, inst, &err) == 0);
	CHECK(scene_add_root(s, 999, &err) == 1);

	/* polygon ownership: moved on success, freed on failure */
	scene_object_defaults(&o, PRIM_POLYGON);
	o.u.polygon.n_contours = 1;
	o.u.polygon.n_points = 2; /* too few: refused, arrays freed by the builder */
	o.u.polygon.contour_start = calloc(2, sizeof(uint32_t));
	o.u.polygon.contour_start[1] = 2;
	o.u.polygon.points = calloc(2, sizeof(vec3));
	CHECK(scene_add_object(s, &o, NULL, &err) == 1);

	struct scene_stats st;
	scene_stats(s, &st);
	CHECK(st.by_kind[PRIM_SPHERE] == 1 && st.by_kind[PRIM_CSG] == 1 && st.by_kind[PRIM_INSTANCE] == 1);
	CHECK(st.prims_instanced == 4); /* the instance twice: a csg of sphere and box */
	CHECK(st.materials_named == 1);
	scene_free(s);
	scene_free(NULL);
}

static void test_mesh_stats(void)
{
	struct scene *s = scene_new();
	struct scene_error err;
	struct scene_mesh mesh = { 0 };
	mesh.file = strdup("t.raw");
	mesh.n_vertices = 3;
	mesh.n_triangles = 1;
	mesh.vertices = calloc(3, sizeof(vec3));
	mesh.tris = calloc(3, sizeof(uint32_t));
	mesh.tris[1] = 1;
	mesh.tris[2] = 2;
	uint32_t id, obj, def, inst;
	CHECK(scene_add_mesh(s, &mesh, &id, &err) == 0);
	struct scene_object o;
	scene_object_defaults(&o, PRIM_RAW);
	o.u.raw.mesh = id;
	CHECK(scene_add_object(s, &o, &obj, &err) == 0);
	struct scene_define d = { 0 };
	d.name = strdup("tri");
	d.objects = malloc(sizeof(uint32_t));
	d.objects[0] = obj;
	d.n_objects = 1;
	CHECK(scene_add_define(s, &d, &def, &err) == 0);
	for (int i = 0; i < 5; i++) {
		scene_object_defaults(&o, PRIM_INSTANCE);
		o.u.instance.define = def;
		CHECK(scene_add_object(s, &o, &inst, &err) == 0);
		CHECK(scene_add_root(s, inst, &err) == 0);
	}
	struct scene_stats st;
	scene_stats(s, &st);
	CHECK(st.triangles == 1);
	CHECK(st.triangles_instanced == 5);
	CHECK(st.prims_instanced == 5); /* a raw mesh is one primitive */
	/* a mesh index out of range is refused */
	struct scene_mesh bad = { 0 };
	bad.n_vertices = 1;
	bad.n_triangles = 1;
	bad.vertices = calloc(1, sizeof(vec3));
	bad.tris = calloc(3, sizeof(uint32_t));
	bad.tris[2] = 7;
	CHECK(scene_add_mesh(s, &bad, NULL, &err) == 1);
	scene_free(s);
}

/*
 * Triangles drawn through instances saturate instead of wrapping: 64 levels
 * of defines, each drawing the one below twice, draw 2^64 triangles; 128
 * levels must not take 2^64 steps either (a saturated count stays known).
 */
static void test_stats_saturate(void)
{
	struct scene *s = scene_new();
	struct scene_error err;
	struct scene_object o;
	uint32_t obj, def;
	scene_object_defaults(&o, PRIM_TRIANGLE);
	CHECK(scene_add_object(s, &o, &obj, &err) == 0);
	for (int level = 0; level <= 128; level++) {
		struct scene_define d = { 0 };
		char name[16];
		snprintf(name, sizeof name, "d%d", level);
		d.name = strdup(name);
		d.objects = malloc(2 * sizeof(uint32_t));
		d.n_objects = level == 0 ? 1 : 2;
		for (uint32_t k = 0; k < d.n_objects; k++) {
			if (level == 0) {
				d.objects[k] = obj;
				continue;
			}
			scene_object_defaults(&o, PRIM_INSTANCE);
			o.u.instance.define = def;
			CHECK(scene_add_object(s, &o, &d.objects[k], &err) == 0);
		}
		CHECK(scene_add_define(s, &d, &def, &err) == 0);
	}
	scene_object_defaults(&o, PRIM_INSTANCE);
	o.u.instance.define = def;
	CHECK(scene_add_object(s, &o, &obj, &err) == 0);
	CHECK(scene_add_root(s, obj, &err) == 0);
	struct scene_stats st;
	scene_stats(s, &st);
	CHECK(st.triangles == 1);
	CHECK(st.triangles_instanced == UINT64_MAX);
	CHECK(st.prims_instanced == UINT64_MAX);
	scene_free(s);
}

/* The default material is set up once however many threads ask first
 * (a plain flag was a data race: run under -fsanitize=thread to see it). */
static void *default_material_thread(void *arg)
{
	(void)arg;
	const struct scene_material *m = scene_default_material();
	return (void *)(m->diffuse == 1.0 && m->diff_colour.x == 1 ? m : NULL);
}

static void test_default_material_threads(void)
{
	pthread_t t[4];
	void *got[4];
	for (int i = 0; i < 4; i++)
		CHECK(pthread_create(&t[i], NULL, default_material_thread, NULL) == 0);
	for (int i = 0; i < 4; i++) {
		pthread_join(t[i], &got[i]);
		CHECK(got[i] != NULL && got[i] == got[0]);
	}
}

/* Adds an instance of define 0 with transform m (has: has_xform) and
 * material mat; returns its object index. */
static uint32_t add_inst(struct scene *s, const mat34 *m, bool has, uint32_t mat, int line)
{
	struct scene_object o;
	scene_object_defaults(&o, PRIM_INSTANCE);
	o.u.instance.define = 0;
	o.xform = *m;
	o.has_xform = has;
	o.material = mat;
	o.loc.file = scene_intern_file(s, line % 2 ? "a.sce" : "b.sce");
	o.loc.line = line;
	o.loc.col = 70000 + line;
	uint32_t id = SCENE_NONE;
	struct scene_error err;
	CHECK(scene_add_object(s, &o, &id, &err) == 0);
	return id;
}

/* Instances are stored as compact records (INSTANCES in scene.h) and read
 * back bit for bit: translations, shared 3x3 parts, -0 in a 3x3 part, no
 * transform, material, define and location. */
static void test_compact_instances(void)
{
	struct scene *s = scene_new();
	struct scene_error err;
	struct scene_object sph;
	scene_object_defaults(&sph, PRIM_SPHERE);
	uint32_t sid;
	CHECK(scene_add_object(s, &sph, &sid, &err) == 0);
	struct scene_define d = { 0 };
	d.name = strdup("ball");
	d.objects = malloc(sizeof *d.objects);
	d.objects[0] = sid;
	d.n_objects = 1;
	CHECK(scene_add_define(s, &d, NULL, &err) == 0);
	struct scene_material mat;
	scene_material_defaults(&mat);
	CHECK(scene_add_material(s, &mat, NULL, &err) == 0);

	mat34 m[7];
	m[0] = m34_identity();                                   /* no transform */
	m[1] = m34_identity();
	scene_xform_op(&m[1], XF_TRANSLATE, 0, 0, v3(1.5, -0.0, 1e-300)); /* a translation, -0 kept */
	m[2] = m34_identity();
	scene_xform_op(&m[2], XF_ROTATE, 1, 30, v3(0, 0, 0));
	scene_xform_op(&m[2], XF_TRANSLATE, 0, 0, v3(0.1, 0.2, 0.3));
	m[3] = m[2];                                             /* the same rotation: shared */
	m[3].m[0][3] = 7;
	m[4] = m34_identity();
	m[4].m[0][1] = -0.0; /* equal to the identity, but not its bits: kept as written */
	m[5] = m34_identity();                                   /* has_xform with the identity */
	m[6] = m[1];
	bool has[7] = { false, true, true, true, true, true, true };
	uint32_t mats[7] = { SCENE_NONE, 0, SCENE_NONE, 0, 0, SCENE_NONE, 0 };
	uint32_t id[7];
	for (int k = 0; k < 7; k++)
		id[k] = add_inst(s, &m[k], has[k], mats[k], k + 1);
	CHECK(s->n_objects == 8 && s->n_insts == 7 && s->n_objs == 1);
	CHECK(s->n_lins == 2); /* m[2] and m[3] share one; m[4] has its own */
	for (int k = 0; k < 7; k++) {
		struct scene_object o = scene_object_at(s, id[k]);
		CHECK(scene_is_inst(s, id[k]) && scene_kind(s, id[k]) == PRIM_INSTANCE);
		CHECK(o.kind == PRIM_INSTANCE && o.u.instance.define == 0 && o.material == mats[k]);
		CHECK(o.has_xform == has[k] && memcmp(&o.xform, &m[k], sizeof(mat34)) == 0);
		CHECK(o.loc.line == k + 1 && o.loc.col == 70001 + k && strcmp(o.loc.file, (k + 1) % 2 ? "a.sce" : "b.sce") == 0);
	}
	CHECK(!scene_is_inst(s, sid) && scene_kind(s, sid) == PRIM_SPHERE);
	struct scene_stats st;
	scene_stats(s, &st);
	CHECK(st.by_kind[PRIM_INSTANCE] == 7 && st.by_kind[PRIM_SPHERE] == 1 && st.prims_instanced == 0);
	/* an instance whose file the scene did not intern gets its own copy */
	struct scene_object o;
	scene_object_defaults(&o, PRIM_INSTANCE);
	o.u.instance.define = 0;
	o.loc.file = "elsewhere.sce";
	uint32_t eid;
	CHECK(scene_add_object(s, &o, &eid, &err) == 0);
	struct scene_object back = scene_object_at(s, eid);
	CHECK(back.loc.file != o.loc.file && strcmp(back.loc.file, "elsewhere.sce") == 0);
	/* an undefined define is refused as before */
	o.u.instance.define = 5;
	CHECK(scene_add_object(s, &o, &eid, &err) != 0 && s->n_objects == 9);
	scene_free(s);
}

int main(void)
{
	test_default_material_threads(); /* first: the first use is what races */
	test_defaults();
	test_xform();
	test_builder();
	test_mesh_stats();
	test_stats_saturate();
	test_compact_instances();
	TEST_MAIN_END();
}
