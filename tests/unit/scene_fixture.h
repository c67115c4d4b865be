/*
 * scene_fixture.h - a hand-built scene holding every primitive, every shader,
 * every filter and every light shape, for the serializer and protocol tests
 * (and for generating fuzz corpora). Static so each test binary gets a copy.
 */
#ifndef PORTRAY_SCENE_FIXTURE_H
#define PORTRAY_SCENE_FIXTURE_H

#include <stdlib.h>
#include <string.h>

#include "common/scene.h"

static uint32_t fx_material(struct scene *s, const char *name, enum shader_kind kind, uint32_t a, uint32_t b)
{
	struct scene_material m;
	struct scene_error err;
	uint32_t id = SCENE_NONE;
	scene_material_defaults(&m);
	m.name = name ? strdup(name) : NULL;
	m.diff_colour = v3(0.8, 0.3, 0.1);
	m.specular = 0.25;
	m.loc.line = 7;
	scene_shader_defaults(&m.shader, kind);
	m.shader.mat_a = a;
	m.shader.mat_b = b;
	if (kind == SHADER_FADES) {
		m.shader.n_fades = 3;
		m.shader.fades = calloc(3, sizeof *m.shader.fades);
		m.shader.fades_materials = a != SCENE_NONE;
		m.shader.mat_a = m.shader.mat_b = SCENE_NONE;
		for (uint32_t i = 0; i < 3; i++) {
			m.shader.fades[i].dist = i == 2 ? 0 : 1.5 + i;
			m.shader.fades[i].colour = v3(i * 0.3, 0.5, 1 - i * 0.3);
			m.shader.fades[i].material = a != SCENE_NONE ? (i & 1 ? a : b) : SCENE_NONE;
		}
	}
	if (scene_add_material(s, &m, &id, &err))
		abort();
	return id;
}

static uint32_t fx_object(struct scene *s, struct scene_object *o)
{
	struct scene_error err;
	uint32_t id;
	if (scene_add_object(s, o, &id, &err)) {
		fprintf(stderr, "fixture: %s\n", err.msg);
		abort();
	}
	return id;
}

static uint32_t fx_mesh(struct scene *s, int normals)
{
	struct scene_mesh m;
	struct scene_error err;
	uint32_t id;
	memset(&m, 0, sizeof m);
	m.file = strdup(normals ? "smooth.raw" : "flat.raw");
	m.n_vertices = 4;
	m.n_triangles = 2;
	m.vertices = malloc(4 * sizeof *m.vertices);
	m.tris = malloc(6 * sizeof *m.tris);
	m.vertices[0] = v3(0, 0, 0), m.vertices[1] = v3(1, 0, 0);
	m.vertices[2] = v3(1, 1, 0), m.vertices[3] = v3(0, 1, 0.5);
	uint32_t t[6] = { 0, 1, 2, 0, 2, 3 };
	memcpy(m.tris, t, sizeof t);
	if (normals) {
		m.normals = malloc(4 * sizeof *m.normals);
		for (int i = 0; i < 4; i++)
			m.normals[i] = v3(0, 0.1 * i, 1);
		m.smooth = true;
	}
	m.weld = 0.001;
	m.rotation = v3(10, 20, 30);
	m.at = v3(0.5, 0, -1);
	if (scene_add_mesh(s, &m, &id, &err))
		abort();
	return id;
}

/* Every primitive, shader, filter and light shape; caller frees with scene_free. */
static struct scene *fx_scene(void)
{
	struct scene *s = scene_new();
	struct scene_error err;
	struct scene_camera cam;
	scene_camera_defaults(&cam);
	cam.look_from = v3(1, 2, 12);
	cam.look_at = v3(0, 0.5, 0);
	cam.set = true;
	cam.loc.line = 1, cam.loc.col = 1;
	enum filter_kind fk[5] = { FILTER_STANDARD, FILTER_ADAPTIVE, FILTER_SUPERSAMPLE, FILTER_DISK, FILTER_LENS };
	for (int i = 0; i < 5; i++) {
		scene_filter_defaults(&cam.filters[i], fk[i]);
		cam.filters[i].loc.line = 2 + i;
	}
	cam.filters[2].x_samples = 3;
	cam.n_filters = 5;
	if (scene_set_camera(s, &cam, &err))
		abort();
	struct scene_image im;
	scene_image_defaults(&im);
	im.xsize = 64, im.ysize = 48, im.set = true, im.no_reflections = true;
	if (scene_set_image(s, &im, &err))
		abort();

	uint32_t red = fx_material(s, "red", SHADER_NONE, SCENE_NONE, SCENE_NONE);
	uint32_t brick = fx_material(s, "wall", SHADER_BRICKS, red, SCENE_NONE);
	uint32_t tiles = fx_material(s, NULL, SHADER_TILES, SCENE_NONE, red);
	uint32_t cheq = fx_material(s, "cheq", SHADER_CHEQUERS, red, brick);
	uint32_t bumpy = fx_material(s, NULL, SHADER_BUMPY, cheq, SCENE_NONE);
	uint32_t noise = fx_material(s, "noisy", SHADER_NOISE, SCENE_NONE, SCENE_NONE);
	uint32_t fadec = fx_material(s, NULL, SHADER_FADES, SCENE_NONE, SCENE_NONE);
	uint32_t fadem = fx_material(s, "fm", SHADER_FADES, red, tiles);
	uint32_t turb = fx_material(s, "wood", SHADER_TURB3D, noise, SCENE_NONE);

	uint32_t mesh_s = fx_mesh(s, 1), mesh_f = fx_mesh(s, 0);

	enum light_shape shapes[4] = { LIGHT_POINT, LIGHT_SPHERE, LIGHT_CYLINDER, LIGHT_BOX };
	for (int i = 0; i < 4; i++) {
		struct scene_light l;
		scene_light_defaults(&l);
		l.shape = shapes[i];
		l.position = v3(i, 5, -3);
		l.samples = i ? 4 : 1;
		l.fall_off = i * 0.5;
		l.no_shadows = i == 3;
		if (scene_add_light(s, &l, &err))
			abort();
	}

	struct scene_object o;
	uint32_t ids[32];
	int n = 0;
	scene_object_defaults(&o, PRIM_SPHERE);
	o.u.sphere.radius = 0.75;
	o.material = brick;
	scene_xform_op(&o.xform, XF_ROTATE, 1, 30, v3(0, 0, 0));
	scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0, v3(-2, 0.75, 0));
	o.has_xform = true;
	ids[n++] = fx_object(s, &o);
	scene_object_defaults(&o, PRIM_PLANE);
	o.material = cheq;
	ids[n++] = fx_object(s, &o);
	scene_object_defaults(&o, PRIM_CYLINDER);
	o.u.cylinder.capped = true;
	o.u.cylinder.radius = 0.3;
	o.material = tiles;
	ids[n++] = fx_object(s, &o);
	scene_object_defaults(&o, PRIM_BOX);
	o.u.box.a = v3(1, 0, 1);
	o.material = bumpy;
	ids[n++] = fx_object(s, &o);
	scene_object_defaults(&o, PRIM_TRIANGLE);
	o.u.triangle.has_normals = true;
	o.u.triangle.na = v3(0, 0, 1), o.u.triangle.nb = v3(0, 0.2, 1), o.u.triangle.nc = v3(0.2, 0, 1);
	o.material = noise;
	ids[n++] = fx_object(s, &o);
	scene_object_defaults(&o, PRIM_TRIANGLE);
	o.u.triangle.a = v3(-1, 2, 0);
	ids[n++] = fx_object(s, &o);
	scene_object_defaults(&o, PRIM_RAW);
	o.u.raw.mesh = mesh_s;
	o.material = fadec;
	ids[n++] = fx_object(s, &o);
	scene_object_defaults(&o, PRIM_RAW);
	o.u.raw.mesh = mesh_f;
	o.material = fadem;
	ids[n++] = fx_object(s, &o);
	scene_object_defaults(&o, PRIM_DISK);
	o.u.plane.radius = 0.5;
	o.u.plane.position = v3(2, 1, 0);
	o.u.plane.normal = v3(0, 0, 1);
	o.u.plane.x_axis = v3(1, 0, 0);
	o.u.plane.y_axis = v3(0, 1, 0);
	o.u.plane.has_axes = true;
	o.material = turb;
	ids[n++] = fx_object(s, &o);
	scene_object_defaults(&o, PRIM_POLYGON);
	o.u.polygon.n_contours = 2;
	o.u.polygon.n_points = 7;
	o.u.polygon.contour_start = malloc(3 * sizeof(uint32_t));
	o.u.polygon.points = malloc(7 * sizeof(vec3));
	o.u.polygon.contour_start[0] = 0, o.u.polygon.contour_start[1] = 4, o.u.polygon.contour_start[2] = 7;
	vec3 pts[7] = { { 0, 0, 3 }, { 2, 0, 3 }, { 2, 2, 3 }, { 0, 2, 3 }, { 0.5, 0.5, 3 }, { 1.5, 0.5, 3 }, { 1, 1.5, 3 } };
	memcpy(o.u.polygon.points, pts, sizeof pts);
	ids[n++] = fx_object(s, &o);
	/* csg of two fresh solids */
	scene_object_defaults(&o, PRIM_SPHERE);
	uint32_t a = fx_object(s, &o);
	scene_object_defaults(&o, PRIM_BOX);
	uint32_t b = fx_object(s, &o);
	scene_object_defaults(&o, PRIM_CSG);
	o.u.csg.op = CSG_SUBTRACT;
	o.u.csg.operand1 = a, o.u.csg.operand2 = b;
	o.material = red;
	ids[n++] = fx_object(s, &o);
	/* a define of two objects, and a define holding an instance of it */
	scene_object_defaults(&o, PRIM_SPHERE);
	o.u.sphere.radius = 0.2;
	uint32_t m1 = fx_object(s, &o);
	scene_object_defaults(&o, PRIM_CYLINDER);
	uint32_t m2 = fx_object(s, &o);
	struct scene_define d = { .name = strdup("Block"), .n_objects = 2 };
	d.objects = malloc(2 * sizeof *d.objects);
	d.objects[0] = m1, d.objects[1] = m2;
	uint32_t blk;
	if (scene_add_define(s, &d, &blk, &err))
		abort();
	scene_object_defaults(&o, PRIM_INSTANCE);
	o.u.instance.define = blk;
	scene_xform_op(&o.xform, XF_STRETCH, 2, 3, v3(0, 0, 0));
	o.has_xform = true;
	uint32_t inst1 = fx_object(s, &o);
	struct scene_define d2 = { .name = strdup("wall"), .n_objects = 1 };
	d2.objects = malloc(sizeof *d2.objects);
	d2.objects[0] = inst1;
	uint32_t wall;
	if (scene_add_define(s, &d2, &wall, &err))
		abort();
	scene_object_defaults(&o, PRIM_INSTANCE);
	o.u.instance.define = wall;
	o.material = red;
	ids[n++] = fx_object(s, &o);
	scene_object_defaults(&o, PRIM_INSTANCE);
	o.u.instance.define = blk;
	scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0, v3(0, 3, 0));
	o.has_xform = true;
	uint32_t inst3 = fx_object(s, &o);
	scene_object_defaults(&o, PRIM_CSG);
	o.u.csg.op = CSG_UNION;
	o.u.csg.operand1 = inst3, o.u.csg.operand2 = ids[0];
	ids[n++] = fx_object(s, &o);
	for (int i = 0; i < n; i++)
		if (scene_add_root(s, ids[i], &err))
			abort();
	return s;
}

#endif
