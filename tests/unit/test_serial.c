/*
 * test_serial.c - scene encoding: round trips are byte-identical, decoding
 * survives truncation and corruption, and hostile counts and nesting are
 * refused before anything large is allocated.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "common/parse.h"
#include "proto/serial.h"
#include "scene_fixture.h"

/* encode -> decode -> encode must give the same bytes; returns the first encoding. */
static uint8_t *round_trip(const struct scene *s, size_t *len_out)
{
	uint8_t *a = NULL, *b = NULL;
	size_t la = 0, lb = 0;
	*len_out = 0;
	struct scene *t = NULL;
	struct scene_error err;
	CHECK(proto_scene_encode(s, &a, &la) == 0);
	CHECK(proto_scene_decode(a, la, &t, &err) == 0);
	if (!t) {
		fprintf(stderr, "decode: %s\n", err.msg);
		free(a);
		return NULL;
	}
	CHECK(proto_scene_encode(t, &b, &lb) == 0);
	CHECK(la == lb && memcmp(a, b, la) == 0);
	CHECK(t->n_objects == s->n_objects && t->n_defines == s->n_defines && t->n_roots == s->n_roots &&
	      t->n_materials == s->n_materials && t->n_meshes == s->n_meshes && t->n_lights == s->n_lights);
	scene_free(t);
	free(b);
	*len_out = la;
	return a;
}

static void test_fixture(void)
{
	struct scene *s = fx_scene();
	size_t len;
	uint8_t *a = round_trip(s, &len);
	CHECK(a != NULL);
	struct scene *t = NULL;
	struct scene_error err;
	CHECK(proto_scene_decode(a, len, &t, &err) == 0);
	if (t) {
		/* spot checks of content, not only of bytes */
		CHECK(t->camera.n_filters == 5 && t->camera.filters[2].x_samples == 3);
		CHECK(t->camera.filters[4].kind == FILTER_LENS);
		CHECK(t->image.xsize == 64 && t->image.no_reflections && !t->image.no_shadows);
		CHECK(strcmp(t->materials[0].name, "red") == 0 && t->materials[2].name == NULL);
		CHECK(t->materials[7].shader.kind == SHADER_FADES && t->materials[7].shader.fades_materials);
		CHECK(t->materials[7].shader.fades[1].material == 0);
		CHECK(t->meshes[0].normals != NULL && t->meshes[1].normals == NULL);
		CHECK(strcmp(t->meshes[0].file, "smooth.raw") == 0);
		CHECK(t->lights[2].shape == LIGHT_CYLINDER && t->lights[3].no_shadows);
		uint32_t poly = s->roots[9];
		CHECK((*scene_object(t, poly, &(struct scene_object){ 0 })).kind == PRIM_POLYGON && (*scene_object(t, poly, &(struct scene_object){ 0 })).u.polygon.n_points == 7 &&
		      (*scene_object(t, poly, &(struct scene_object){ 0 })).u.polygon.contour_start[1] == 4);
		CHECK(memcmp(&scene_object(t, 0, &(struct scene_object){ 0 })->xform, &scene_object(s, 0, &(struct scene_object){ 0 })->xform, sizeof(mat34)) == 0);
		CHECK(strcmp(t->defines[1].name, "wall") == 0 && t->defines[0].n_objects == 2);
		CHECK(strcmp((*scene_object(t, 0, &(struct scene_object){ 0 })).loc.file, PROTO_SCENE_FILE) == 0);
		struct scene_stats st1, st2;
		scene_stats(s, &st1);
		scene_stats(t, &st2);
		CHECK(memcmp(&st1, &st2, sizeof st1) == 0);
		scene_free(t);
	}

	/* every truncation fails cleanly */
	int bad_ok = 1;
	for (size_t n = 0; n < len; n++) {
		struct scene *u = NULL;
		if (proto_scene_decode(a, n, &u, &err) == 0 || u != NULL)
			bad_ok = 0;
		scene_free(u);
	}
	CHECK(bad_ok);
	/* a byte too many fails */
	uint8_t *c = malloc(len + 1);
	memcpy(c, a, len);
	c[len] = 0;
	t = NULL;
	CHECK(proto_scene_decode(c, len + 1, &t, &err) == 1 && t == NULL);
	CHECK(strstr(err.msg, "trailing") != NULL);

	/* bit flips: decoding either fails or gives a scene that round-trips */
	int flips_ok = 1, accepted = 0;
	for (size_t i = 0; i < len; i++) {
		memcpy(c, a, len);
		c[i] ^= (uint8_t)(1u << (i % 8));
		struct scene *u = NULL;
		if (proto_scene_decode(c, len, &u, &err) == 0) {
			accepted++;
			uint8_t *e = NULL;
			size_t le = 0;
			struct scene *v = NULL;
			if (proto_scene_encode(u, &e, &le) || proto_scene_decode(e, le, &v, &err))
				flips_ok = 0;
			scene_free(v);
			free(e);
		}
		scene_free(u);
	}
	CHECK(flips_ok);
	CHECK(accepted > 0); /* most flips land in doubles and stay valid */

	/* wrong version is named in the message */
	memcpy(c, a, len);
	c[7] = 99;
	CHECK(proto_scene_decode(c, len, &t, &err) == 1 && strstr(err.msg, "version 99") != NULL);
	free(c);
	free(a);
	scene_free(s);
}

/* A count far beyond the bytes present is refused without a huge allocation. */
static void test_hostile_counts(void)
{
	struct scene *s = scene_new();
	uint8_t *a;
	size_t len;
	CHECK(proto_scene_encode(s, &a, &len) == 0);
	/* layout ends with 6 u32 counts (materials meshes lights objects defines roots) = 0 */
	CHECK(len > 24);
	uint8_t *c = malloc(len);
	for (int k = 0; k < 6; k++) {
		memcpy(c, a, len);
		size_t at = len - 24 + 4 * (size_t)k;
		c[at] = 0x7f, c[at + 1] = 0xff, c[at + 2] = 0xff, c[at + 3] = 0xff;
		struct scene *t = NULL;
		struct scene_error err;
		CHECK(proto_scene_decode(c, len, &t, &err) == 1 && t == NULL);
	}
	/* the unmodified empty scene decodes */
	memcpy(c, a, len);
	struct scene *t = NULL;
	struct scene_error err;
	CHECK(proto_scene_decode(c, len, &t, &err) == 0);
	scene_free(t);
	free(c);
	free(a);
	scene_free(s);
}

/* A CSG chain deeper than the limits is refused (it would blow the tracer's stack). */
static void test_deep_nesting(void)
{
	struct scene *s = scene_new();
	struct scene_object o;
	struct scene_error err;
	uint32_t prev, leaf;
	scene_object_defaults(&o, PRIM_SPHERE);
	scene_add_object(s, &o, &prev, &err);
	for (int i = 0; i < LIM_CSG_DEPTH + LIM_DEFINE_DEPTH + 10; i++) {
		scene_object_defaults(&o, PRIM_SPHERE);
		scene_add_object(s, &o, &leaf, &err);
		scene_object_defaults(&o, PRIM_CSG);
		o.u.csg.operand1 = prev, o.u.csg.operand2 = leaf;
		scene_add_object(s, &o, &prev, &err);
	}
	scene_add_root(s, prev, &err);
	uint8_t *a;
	size_t len;
	CHECK(proto_scene_encode(s, &a, &len) == 0);
	struct scene *t = NULL;
	CHECK(proto_scene_decode(a, len, &t, &err) == 1 && strstr(err.msg, "nest") != NULL);
	free(a);
	scene_free(s);

	/* shader materials nested too deep */
	s = scene_new();
	uint32_t m = SCENE_NONE;
	for (int i = 0; i < LIM_SHADER_DEPTH + 5; i++) {
		struct scene_material mat;
		scene_material_defaults(&mat);
		if (i)
			scene_shader_defaults(&mat.shader, SHADER_BUMPY), mat.shader.mat_a = m;
		scene_add_material(s, &mat, &m, &err);
	}
	CHECK(proto_scene_encode(s, &a, &len) == 0);
	CHECK(proto_scene_decode(a, len, &t, &err) == 1 && strstr(err.msg, "nest") != NULL);
	free(a);
	scene_free(s);
}

/* Parsed scenes (every SPD scene, a mesh scene, the farm's test scene) round-trip. */
static void test_parsed(void)
{
	const char *files[] = { "tests/data/spd/balls_s4.sce", "tests/data/spd/gears_s2.sce",
				"tests/data/spd/rings_s3.sce", "tests/data/spd/tetra_s4.sce",
				"tests/data/meshes/spot.sce", "tests/e2e/farm_scene.sce" };
	for (size_t i = 0; i < sizeof files / sizeof *files; i++) {
		struct scene *s = NULL;
		struct scene_error err;
		if (parse_files(NULL, files[i], &s, &err) != 0) {
			fprintf(stderr, "%s\n", err.msg);
			CHECK(!"parse failed");
			continue;
		}
		size_t len;
		uint8_t *a = round_trip(s, &len);
		CHECK(a != NULL && len > 0);
		free(a);
		scene_free(s);
	}
}

/* Offset of the only occurrence of the 8 bytes of big-endian double v in
 * a[0..len), or -1 (none or several). */
static long find_f64(const uint8_t *a, size_t len, double v)
{
	uint64_t u;
	memcpy(&u, &v, sizeof u);
	uint8_t be[8];
	for (int i = 0; i < 8; i++)
		be[i] = (uint8_t)(u >> (56 - 8 * i));
	long at = -1;
	for (size_t i = 0; i + 8 <= len; i++)
		if (memcmp(a + i, be, 8) == 0) {
			if (at >= 0)
				return -1;
			at = (long)i;
		}
	return at;
}

/* Version 2's transform forms: none, a translation (3 doubles), or 12
 * doubles, each round trip exact (a -0 in the 3x3 part travels in full);
 * a full form whose 3x3 part is the identity's bits, and an unknown form,
 * are refused (the encoding stays canonical). */
static void test_xform_forms(void)
{
	struct scene *s = scene_new();
	struct scene_error err;
	struct scene_object o;
	uint32_t id[4];
	for (int k = 0; k < 4; k++) {
		scene_object_defaults(&o, PRIM_SPHERE);
		if (k == 1)
			scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0, v3(1.25, -0.0, 3));
		if (k == 2)
			o.xform.m[0][1] = -0.0;
		if (k == 3)
			o.xform.m[1][1] = 2.75; /* a stretch: found and patched below */
		o.has_xform = k > 0;
		CHECK(scene_add_object(s, &o, &id[k], &err) == 0);
		CHECK(scene_add_root(s, id[k], &err) == 0);
	}
	size_t len = 0;
	uint8_t *a = round_trip(s, &len);
	CHECK(a != NULL);
	struct scene *t = NULL;
	if (a && proto_scene_decode(a, len, &t, &err) == 0) {
		for (int k = 0; k < 4; k++) {
			struct scene_object x = scene_object_at(s, id[k]), y = scene_object_at(t, id[k]);
			CHECK(x.has_xform == y.has_xform && memcmp(&x.xform, &y.xform, sizeof(mat34)) == 0);
		}
		scene_free(t);
		t = NULL;
		/* 2.75 -> 1.0: a full transform with the identity's 3x3 part */
		long at = find_f64(a, len, 2.75);
		CHECK(at > 0);
		if (at > 0) {
			uint8_t one[8] = { 0x3f, 0xf0, 0, 0, 0, 0, 0, 0 };
			memcpy(a + at, one, 8);
			CHECK(proto_scene_decode(a, len, &t, &err) != 0 && t == NULL);
			CHECK(strstr(err.msg, "identity") != NULL);
			/* the form byte before the 12 doubles (material and the
			 * 3x3 part's first row: 4 doubles before 2.75): form 3 */
			long form = at - 5 * 8 - 1;
			CHECK(a[form] == 2);
			a[form] = 3;
			CHECK(proto_scene_decode(a, len, &t, &err) != 0 && t == NULL);
			CHECK(strstr(err.msg, "transform form") != NULL);
		}
	}
	free(a);
	scene_free(s);
}

/* Roots travel as runs of consecutive indices: any order round trips; an
 * empty run, a run past the objects and a run that continues the one
 * before (not canonical) are refused. */
static void test_root_runs(void)
{
	struct scene *s = scene_new();
	struct scene_error err;
	for (int k = 0; k < 6; k++) {
		struct scene_object o;
		scene_object_defaults(&o, PRIM_SPHERE);
		CHECK(scene_add_object(s, &o, NULL, &err) == 0);
	}
	static const uint32_t roots[] = { 0, 1, 2, 5, 3, 3, 4 }; /* runs (0,3) (5,1) (3,1) (3,2) */
	for (size_t k = 0; k < sizeof roots / sizeof *roots; k++)
		CHECK(scene_add_root(s, roots[k], &err) == 0);
	size_t len = 0;
	uint8_t *a = round_trip(s, &len);
	struct scene *t = NULL;
	CHECK(a != NULL && proto_scene_decode(a, len, &t, &err) == 0);
	if (t) {
		CHECK(t->n_roots == 7 && memcmp(t->roots, roots, sizeof roots) == 0);
		scene_free(t);
		t = NULL;
	}
	if (a && len > 40) {
		uint8_t *tail = a + len - 8; /* the last run: (3, 2) */
		CHECK(tail[3] == 3 && tail[7] == 2);
		tail[7] = 0; /* empty */
		CHECK(proto_scene_decode(a, len, &t, &err) != 0 && strstr(err.msg, "run of roots") != NULL);
		tail[7] = 4; /* 3 + 4 > 6 objects */
		CHECK(proto_scene_decode(a, len, &t, &err) != 0 && strstr(err.msg, "run of roots") != NULL);
		tail[7] = 1;
		tail[3] = 4; /* (3,1) then (4,1): one run written as two */
		CHECK(proto_scene_decode(a, len, &t, &err) != 0 && strstr(err.msg, "run of roots") != NULL);
		tail[3] = 0; /* (0,1): fine */
		int rc = proto_scene_decode(a, len, &t, &err);
		if (rc)
			fprintf(stderr, "%s\n", err.msg);
		CHECK(rc == 0 && t && t->n_roots == 6 && t->roots[5] == 0);
		scene_free(t);
	}
	free(a);
	scene_free(s);
}

int main(void)
{
	test_parsed();
	test_xform_forms();
	test_root_runs();
	test_fixture();
	test_hostile_counts();
	test_deep_nesting();
	TEST_MAIN_END();
}
