/*
 * test_parse.c - the parser: every keyword of the manual, the model fields
 * and defaults it produces, the decisions of docs/language.md, and error
 * messages with their positions and levels.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "common/parse.h"
#include "tests/unit/check.h"

#define EPS 1e-12

static struct scene *ok(const char *text)
{
	struct scene *s = NULL;
	struct scene_error err = { 0 };
	int rc = parse_buffer("t.sce", text, strlen(text), 0, &s, &err);
	if (rc) {
		fprintf(stderr, "unexpected error %d: %s\n  in: %s\n", rc, err.msg, text);
		return NULL;
	}
	return s;
}

/* Parses text expecting failure at level with msg containing want. */
static int fails(const char *text, int level, const char *want)
{
	struct scene *s = NULL;
	struct scene_error err = { 0 };
	int rc = parse_buffer("t.sce", text, strlen(text), 0, &s, &err);
	if (rc != level || !strstr(err.msg, want) || s != NULL) {
		fprintf(stderr, "want level %d '%s', got %d '%s'\n  in: %s\n", level, want, rc, err.msg, text);
		scene_free(s);
		return 0;
	}
	return 1;
}

static int veq(vec3 a, double x, double y, double z)
{
	return fabs(a.x - x) < EPS && fabs(a.y - y) < EPS && fabs(a.z - z) < EPS;
}

static void test_camera_image(void)
{
	struct scene *s = ok("CAMERA look-at (1 2 3) drop-line (0 0 -1) look-from (4 5 6) depth 0.5 "
			     "x-size 0.04 y-size 0.03 ; "
			     "Image xsize 640 ysize 480 no-shadows no-reflections nonstop intersect-buffer 77 ;");
	CHECK(s != NULL);
	if (!s)
		return;
	const struct scene_camera *c = &s->camera;
	CHECK(c->set && veq(c->look_at, 1, 2, 3) && veq(c->drop_line, 0, 0, -1) && veq(c->look_from, 4, 5, 6));
	CHECK(c->depth == 0.5 && c->x_size == 0.04 && c->y_size == 0.03);
	CHECK(c->n_filters == 1 && c->filters[0].kind == FILTER_STANDARD);
	CHECK(c->loc.line == 1 && c->loc.col == 1);
	CHECK(s->image.set && s->image.xsize == 640 && s->image.ysize == 480 && s->image.no_shadows &&
	      s->image.no_reflections && s->image.nonstop && s->image.intersect_buffer == 77);
	scene_free(s);

	/* defaults */
	s = ok("camera ; image ;");
	CHECK(s && s->camera.depth == 0.028 && s->camera.x_size == 0.032 && s->camera.y_size == 0.024);
	CHECK(s && veq(s->camera.drop_line, 0, -1, 0) && veq(s->camera.look_at, 0, 0, 0));
	CHECK(s && s->image.xsize == 320 && s->image.ysize == 240 && !s->image.no_shadows &&
	      s->image.intersect_buffer == 1000);
	scene_free(s);
	s = ok("");
	CHECK(s && !s->camera.set && !s->image.set && s->n_objects == 0);
	scene_free(s);
}

static void test_filters(void)
{
	struct scene *s = ok("camera filter standard filter adaptive threshold 0.1 max-depth 4 cache-size 50 "
			     "relax 1.5 ; filter super-sample x-samples 3 y-samples 5 ; filter disk samples 10 "
			     "radius 0.5 ; filter lens samples 7 radius 0.2 focal-length 30 ; ;");
	CHECK(s != NULL);
	if (!s)
		return;
	const struct scene_camera *c = &s->camera;
	CHECK(c->n_filters == 5);
	CHECK(c->filters[0].kind == FILTER_STANDARD);
	CHECK(c->filters[1].kind == FILTER_ADAPTIVE && c->filters[1].threshold == 0.1 &&
	      c->filters[1].max_depth == 4 && c->filters[1].cache_size == 50 && c->filters[1].relax == 1.5);
	CHECK(c->filters[2].kind == FILTER_SUPERSAMPLE && c->filters[2].x_samples == 3 && c->filters[2].y_samples == 5);
	CHECK(c->filters[3].kind == FILTER_DISK && c->filters[3].samples == 10 && c->filters[3].radius == 0.5);
	CHECK(c->filters[4].kind == FILTER_LENS && c->filters[4].samples == 7 && c->filters[4].radius == 0.2 &&
	      c->filters[4].focal_length == 30);
	scene_free(s);

	/* filter defaults; `filter standard` with and without ';' */
	s = ok("camera filter adaptive ; filter disk ; filter lens ; filter super-sample ; ;");
	CHECK(s && s->camera.n_filters == 4);
	if (s) {
		const struct scene_filter *f = s->camera.filters;
		CHECK(f[0].threshold == 0.2 && f[0].max_depth == 3 && f[0].cache_size == 1000 && f[0].relax == 1.2);
		CHECK(f[1].samples == 4 && f[1].radius == 0.707);
		CHECK(f[2].samples == 4 && f[2].radius == 0.1 && f[2].focal_length == 1000.0);
		CHECK(f[3].x_samples == 2 && f[3].y_samples == 2);
	}
	scene_free(s);
	s = ok("camera filter standard ; ; image ;");
	CHECK(s && s->camera.n_filters == 1 && s->image.set);
	scene_free(s);
	s = ok("camera filter standard ; image ;");
	CHECK(s && s->camera.n_filters == 1 && s->image.set);
	scene_free(s);
	s = ok("camera filter standard ; look-at (0 0 1) ;");
	CHECK(s && veq(s->camera.look_at, 0, 0, 1));
	scene_free(s);
	s = ok("camera filter standard filter lens ; depth 1 ;");
	CHECK(s && s->camera.n_filters == 2 && s->camera.depth == 1);
	scene_free(s);

	/* filters before standard/adaptive are dropped; none: standard first */
	s = ok("camera filter lens ; filter disk ; filter adaptive ; filter super-sample ; ;");
	CHECK(s && s->camera.n_filters == 2 && s->camera.filters[0].kind == FILTER_ADAPTIVE &&
	      s->camera.filters[1].kind == FILTER_SUPERSAMPLE);
	scene_free(s);
	s = ok("camera filter lens ; ;");
	CHECK(s && s->camera.n_filters == 2 && s->camera.filters[0].kind == FILTER_STANDARD &&
	      s->camera.filters[1].kind == FILTER_LENS);
	scene_free(s);

	/* intersect-buffer sizes the adaptive cache unless cache-size is given */
	s = ok("image intersect-buffer 123 ; camera filter adaptive ; ;");
	CHECK(s && s->camera.filters[0].cache_size == 123);
	scene_free(s);
	s = ok("camera filter adaptive cache-size 9 ; ; image intersect-buffer 123 ;");
	CHECK(s && s->camera.filters[0].cache_size == 9);
	scene_free(s);

	CHECK(fails("camera filter fancy ; ;", 1, "t.sce:1:15: error: unrecognised keyword in camera section"));
	CHECK(fails("camera filter lens threshold 1 ; ;", 1, "1:20: error: unrecognised keyword in camera section"));
	CHECK(fails("camera filter adaptive filter lens ; ;", 1, "';' expected (to close 'filter' at line 1) near 'filter'"));
	CHECK(fails("camera filter super-sample x-samples 0 ; ;", 1, "'x-samples' must be between 1 and"));
	CHECK(fails("camera filter disk samples 2.5 ; ;", 1, "whole number expected after 'samples'"));
}

static void test_camera_errors(void)
{
	CHECK(fails("camera\n  zoom 3 ;", 1, "t.sce:2:3: error: unrecognised keyword in camera section near 'zoom'"));
	/* an unknown word is followed by what the block takes */
	CHECK(fails("camera zoom 3 ;", 1,
		    "near 'zoom'; expected look-at, look-from, drop-line, depth, x-size, y-size, filter or ';'"));
	CHECK(fails("light shape box radius 1 ; ;", 1, "(shape box) near 'radius'; expected a, b or ';'"));
	CHECK(fails("object sphere ; material noise grout 1 ; ; ;", 1,
		    "(noise shader) near 'grout'; expected size, material, variance, colour or ';'"));
	CHECK(fails("camera xsize 3 ;", 1, "unrecognised keyword in camera section"));
	CHECK(fails("image\n x-size 3 ;", 1, "t.sce:2:2: error: unrecognised keyword in image section"));
	CHECK(fails("image bogus ;", 1, "unrecognised keyword in image section near 'bogus'"));
	CHECK(fails("camera look-at (0 0 0) look-from (0 0 0) ;", 1, "look-at equals look-from"));
	CHECK(fails("camera depth -1 ;", 1, "'depth' must be greater than 0"));
	CHECK(fails("image xsize 0 ;", 1, "'xsize' must be between 1 and"));
	CHECK(fails("camera look-at (1 2) ;", 1, "t.sce:1:20: error: number expected (3 in the vector after 'look-at') near ')'"));
	CHECK(fails("camera look-at 1 2 3 ;", 1, "'(' expected (a vector after 'look-at') near '1'"));
	CHECK(fails("camera look-at (1 2 3 4) ;", 1, "')' expected (to close '(' at line 1) near '4'"));
}

static void test_light(void)
{
	struct scene *s = ok("light colour (0.5 0.6 0.7) position (1 2 3) fall-off 1.5 no-shadows ; "
			     "light shape sphere centre (1 1 1) radius 2.6 pole (0 0 1) equator (0 1 0) ; samples 20 ; "
			     "light shape cylinder from (0 0 0) to (0 3 0) radius 0.5 ; ; "
			     "light samples 3 shape box a (-1 -1 -1) b (1 2 3) ; ; "
			     "light ;");
	CHECK(s && s->n_lights == 5);
	if (!s)
		return;
	const struct scene_light *l = s->lights;
	CHECK(veq(l[0].colour, 0.5, 0.6, 0.7) && veq(l[0].position, 1, 2, 3) && l[0].fall_off == 1.5 &&
	      l[0].no_shadows && l[0].shape == LIGHT_POINT && l[0].samples == 1);
	CHECK(l[1].shape == LIGHT_SPHERE && veq(l[1].sphere.centre, 1, 1, 1) && l[1].sphere.radius == 2.6 &&
	      veq(l[1].sphere.pole, 0, 0, 1) && veq(l[1].sphere.equator, 0, 1, 0) && l[1].samples == 20);
	CHECK(l[2].shape == LIGHT_CYLINDER && veq(l[2].cylinder.to, 0, 3, 0) && l[2].cylinder.radius == 0.5);
	CHECK(l[3].shape == LIGHT_BOX && veq(l[3].box.a, -1, -1, -1) && veq(l[3].box.b, 1, 2, 3) && l[3].samples == 3);
	CHECK(veq(l[4].colour, 1, 1, 1) && l[4].fall_off == 0 && !l[4].no_shadows && l[4].samples == 1);
	scene_free(s);

	CHECK(fails("light\n  samples 4 ;", 2, "t.sce:2:3: error: 'samples' on a light with no shape"));
	CHECK(fails("light shape plane ; ;", 1, "t.sce:1:13: error: a plane cannot be the shape of a light"));
	CHECK(fails("light shape triangle ; ;", 1, "cannot be the shape of a light"));
	CHECK(fails("light glow 3 ;", 1, "t.sce:1:7: error: unknown verb in light near 'glow'"));
	CHECK(fails("light shape sphere capped ; ;", 1, "unknown verb in light (shape sphere) near 'capped'"));
	CHECK(fails("light shape sphere radius 1 samples 3 ;", 1, "';' expected (to close 'sphere' at line 1) near 'samples'"));
	CHECK(fails("light fall-off -1 ;", 1, "'fall-off' must not be negative"));
}

static void test_primitives(void)
{
	struct scene *s = ok(
		"object Sphere centre (1 2 3) radius 4 pole (0 0 1) equator (0 1 0) ; ; "
		"object sphere center (5 6 7) ; ; "
		"object plane position (0 -10 0) normal (0 0 1) x-axis (1 0 0) y-axis (0 1 0) ; ; "
		"object cylinder from (10 0 0) to (-10 0 0) radius 1 capped ; ; "
		"object box a (0 0 0) b (1 2 3) ; ; "
		"object triangle a (0 0 10) b (-5 0 0) c (5 0 0) ; ; "
		"object triangle a (0 0 0) b (1 0 0) c (0 1 0) normal-a (0 0 1) normal-b (0 0.1 1) normal-c (0.1 0 1) ; ; "
		"object disk position (1 1 1) normal (0 1 0) radius 2.5 ; ; "
		"object primitive sphere ; ; "
		"object plane x-axis (1 0 0) ; ;");
	CHECK(s && s->n_objects == 10 && s->n_roots == 10);
	if (!s)
		return;
	const struct scene_object *o = s->objs; /* no instances here: objs[] is every object */
	CHECK(o[0].kind == PRIM_SPHERE && veq(o[0].u.sphere.centre, 1, 2, 3) && o[0].u.sphere.radius == 4 &&
	      veq(o[0].u.sphere.pole, 0, 0, 1) && veq(o[0].u.sphere.equator, 0, 1, 0));
	CHECK(o[0].material == SCENE_NONE && !o[0].has_xform && o[0].loc.line == 1 && o[0].loc.col == 8);
	CHECK(veq(o[1].u.sphere.centre, 5, 6, 7) && o[1].u.sphere.radius == 1);
	CHECK(o[2].kind == PRIM_PLANE && veq(o[2].u.plane.position, 0, -10, 0) && veq(o[2].u.plane.normal, 0, 0, 1) &&
	      o[2].u.plane.has_axes && veq(o[2].u.plane.x_axis, 1, 0, 0) && veq(o[2].u.plane.y_axis, 0, 1, 0));
	CHECK(o[3].kind == PRIM_CYLINDER && veq(o[3].u.cylinder.from, 10, 0, 0) && veq(o[3].u.cylinder.to, -10, 0, 0) &&
	      o[3].u.cylinder.radius == 1 && o[3].u.cylinder.capped);
	CHECK(o[4].kind == PRIM_BOX && veq(o[4].u.box.a, 0, 0, 0) && veq(o[4].u.box.b, 1, 2, 3));
	CHECK(o[5].kind == PRIM_TRIANGLE && veq(o[5].u.triangle.a, 0, 0, 10) && veq(o[5].u.triangle.c, 5, 0, 0) &&
	      !o[5].u.triangle.has_normals);
	CHECK(o[6].u.triangle.has_normals && veq(o[6].u.triangle.nb, 0, 0.1, 1) && veq(o[6].u.triangle.nc, 0.1, 0, 1));
	CHECK(o[7].kind == PRIM_DISK && o[7].u.plane.radius == 2.5 && veq(o[7].u.plane.position, 1, 1, 1));
	CHECK(o[8].kind == PRIM_SPHERE && veq(o[8].u.sphere.centre, 0, 0, 0) && o[8].u.sphere.radius == 1);
	/* only x-axis written: y-axis = normal x x-axis */
	CHECK(o[9].u.plane.has_axes && veq(o[9].u.plane.y_axis, 0, 0, -1));
	scene_free(s);

	/* defaults of every primitive */
	s = ok("object plane ; ; object cylinder ; ; object box ; ; object triangle ; ; object disk ; ;");
	CHECK(s && s->n_objects == 5);
	if (s) {
		o = s->objs; /* no instances here: objs[] is every object */
		CHECK(veq(o[0].u.plane.normal, 0, 1, 0) && !o[0].u.plane.has_axes);
		CHECK(veq(o[1].u.cylinder.from, 0, 0, 0) && veq(o[1].u.cylinder.to, 0, 1, 0) && !o[1].u.cylinder.capped);
		CHECK(veq(o[2].u.box.b, 1, 1, 1));
		CHECK(veq(o[3].u.triangle.b, 1, 0, 0) && veq(o[3].u.triangle.c, 0, 1, 0));
		CHECK(o[4].u.plane.radius == 1);
	}
	scene_free(s);

	CHECK(fails("object\n sphere radius 1 ;\n sphere ; ;", 1,
		    "t.sce:3:2: error: ';' expected (to close 'object' at line 1) near 'sphere'"));
	CHECK(fails("object sphere radius 1 material ; ;", 1, "';' expected (to close 'sphere' at line 1) near 'material'"));
	CHECK(fails("object sphere bogus 1 ; ;", 1, "t.sce:1:15: error: unknown verb in object (sphere) near 'bogus'"));
	CHECK(fails("object plane radius 1 ; ;", 1, "unknown verb in object (plane) near 'radius'"));
	CHECK(fails("object colour (1 1 1) ;", 1, "t.sce:1:8: error: unknown verb in object"));
	CHECK(fails("object ;", 1, "an object needs a primitive"));
	CHECK(fails("object sphere radius 0 ; ;", 1, "'radius' must be greater than 0"));
	CHECK(fails("object sphere radius 1x ; ;", 1, "t.sce:1:22: error: malformed number near '1x'"));
	CHECK(fails("object sphere radius big ; ;", 1, "number expected after 'radius' near 'big'"));
	CHECK(fails("object cylinder from (1 1 1) to (1 1 1) ; ;", 1, "'from' and 'to' must differ"));
	CHECK(fails("object triangle normal-a (0 0 1) ; ;", 1, "needs all of normal-a, normal-b and normal-c"));
	CHECK(fails("object plane normal (0 0 0) ; ;", 1, "'normal' must not be (0 0 0)"));
	CHECK(fails("object plane normal (0 0 1) x-axis (1 0 0) y-axis (2 0 0) ; ;", 1, "must not lie in one plane"));
	CHECK(fails("object sphere ;", 1, "t.sce:1:16: error: ';' expected (to close 'object' at line 1) near end of file"));
	CHECK(fails("object sphere ; ; object\n sphere\n", 1, "t.sce:3:1: error: ';' expected (to close 'sphere' at line 2) near end of file"));
	CHECK(fails("object raw file x.raw ; ;", 1, "raw files cannot be read here"));
	CHECK(fails("object raw smooth ; ;", 1, "a raw object needs 'file NAME'"));
	CHECK(fails("object raw weld 0.1 x-rotation 90 y-rotation 1 z-rotation 2 at (1 2 3) file m.raw ; ;", 1,
		    "t.sce:1:77: error: raw files cannot be read here"));
}

static void test_polygon(void)
{
	struct scene *s = ok("object polygon contour (0 0 0) (4 0 0) (4 4 0) (0 4 0) ; "
			     "contour (1 1 0) (2 1 0) (2 2 0) ; ; ;");
	CHECK(s && s->n_objects == 1);
	if (s) {
		const struct prim_polygon *p = &scene_object(s, 0, &(struct scene_object){ 0 })->u.polygon;
		CHECK((*scene_object(s, 0, &(struct scene_object){ 0 })).kind == PRIM_POLYGON && p->n_contours == 2 && p->n_points == 7);
		CHECK(p->contour_start[0] == 0 && p->contour_start[1] == 4 && p->contour_start[2] == 7);
		CHECK(veq(p->points[5], 2, 1, 0));
	}
	scene_free(s);
	CHECK(fails("object polygon contour (0 0 0) (1 0 0) ; ; ;", 1, "a contour needs at least 3 vertices"));
	CHECK(fails("object polygon ; ;", 1, "a polygon needs at least one 'contour'"));
	CHECK(fails("object polygon contour (0 0 0) (1 0 0) (0 1 0) ; contour (0 0 1) (1 0 1) (0 1 2) ; ; ;", 1,
		    "not in one plane"));
	CHECK(fails("object polygon contour (0 0 0) (1 0 0) (2 0 0) ; ; ;", 1, "has no area"));
	CHECK(fails("object polygon contour (0 0 0) (1 0 0) (0 1 0) x ; ; ;", 1, "vertex '(x y z)' or ';' expected"));
}

static void test_transforms(void)
{
	struct scene *s = ok("object translate (1 0 0) sphere ; z-rotate 90 ; "
			     "object sphere ; shrink-x 2 stretch-y 3 shrink-y 3 stretch-z 4 shrink-z 2 stretch-x 5 "
			     "x-rotate 10 x-rotate -10 y-rotate 20 y-rotate -20 ; "
			     "object sphere translate (0 0 5) ; ;");
	CHECK(s && s->n_objects == 3);
	if (!s)
		return;
	/* translate first, then rotate: (0 0 0) -> (1 0 0) -> (0 1 0) */
	vec3 p = m34_point(&scene_object(s, 0, &(struct scene_object){ 0 })->xform, v3(0, 0, 0));
	CHECK((*scene_object(s, 0, &(struct scene_object){ 0 })).has_xform);
	CHECK_NEAR(p.x, 0, 1e-12);
	CHECK_NEAR(p.y, 1, 1e-12);
	p = m34_point(&scene_object(s, 1, &(struct scene_object){ 0 })->xform, v3(1, 1, 1));
	CHECK_NEAR(p.x, 2.5, 1e-12);
	CHECK_NEAR(p.y, 1, 1e-12);
	CHECK_NEAR(p.z, 2, 1e-12);
	p = m34_point(&scene_object(s, 2, &(struct scene_object){ 0 })->xform, v3(0, 0, 0));
	CHECK_NEAR(p.z, 5, 1e-12);
	scene_free(s);
	CHECK(fails("object sphere ; shrink-x 0 ;", 1, "t.sce:1:17: error: 'shrink-x' by 0"));
	/* rotation sense: x-rotate turns y toward z, y-rotate z toward x, z-rotate x toward y */
	s = ok("object sphere ; x-rotate 90 ; object sphere ; y-rotate 90 ; object sphere ; z-rotate 90 ;");
	CHECK(s && s->n_objects == 3);
	if (s) {
		p = m34_point(&scene_object(s, 0, &(struct scene_object){ 0 })->xform, v3(0, 1, 0));
		CHECK(fabs(p.z - 1) < 1e-12);
		p = m34_point(&scene_object(s, 1, &(struct scene_object){ 0 })->xform, v3(0, 0, 1));
		CHECK(fabs(p.x - 1) < 1e-12);
		p = m34_point(&scene_object(s, 2, &(struct scene_object){ 0 })->xform, v3(1, 0, 0));
		CHECK(fabs(p.y - 1) < 1e-12);
	}
	scene_free(s);
}

static void test_csg(void)
{
	struct scene *s = ok("object csg operand1 object sphere ; ; operand2 object box ; material colour (1 0 0) ; ; "
			     "subtract ; translate (1 1 1) ; "
			     "object csg union operand2 object sphere ; ; operand1 object csg operand1 object box ; ; "
			     "operand2 object cylinder ; ; intersect ; ; ; ;");
	CHECK(s != NULL);
	if (!s)
		return;
	CHECK(s->n_roots == 2 && s->n_objects == 8);
	const struct scene_object *c = scene_object(s, s->roots[0], &(struct scene_object){ 0 });
	CHECK(c->kind == PRIM_CSG && c->u.csg.op == CSG_SUBTRACT && c->has_xform);
	CHECK((*scene_object(s, c->u.csg.operand1, &(struct scene_object){ 0 })).kind == PRIM_SPHERE && (*scene_object(s, c->u.csg.operand2, &(struct scene_object){ 0 })).kind == PRIM_BOX);
	CHECK((*scene_object(s, c->u.csg.operand2, &(struct scene_object){ 0 })).material != SCENE_NONE);
	c = scene_object(s, s->roots[1], &(struct scene_object){ 0 });
	CHECK(c->u.csg.op == CSG_UNION && (*scene_object(s, c->u.csg.operand1, &(struct scene_object){ 0 })).kind == PRIM_CSG &&
	      (*scene_object(s, (*scene_object(s, c->u.csg.operand1, &(struct scene_object){ 0 })).u.csg.operand1, &(struct scene_object){ 0 })).kind == PRIM_BOX &&
	      (*scene_object(s, c->u.csg.operand1, &(struct scene_object){ 0 })).u.csg.op == CSG_INTERSECT);
	scene_free(s);
	CHECK(fails("object csg operand1 object sphere ; ; union ; ;", 1, "a csg needs 'operand1 object"));
	CHECK(fails("object csg operand1 sphere ; ;", 1, "'object' expected after 'operand1'"));
	CHECK(fails("object csg union intersect ; ;", 1, "a csg takes one operation"));
	CHECK(fails("object csg operand1 object sphere ; ; operand1 object sphere ; ; ; ;", 1, "'operand1' given twice"));
	CHECK(fails("object csg mix ; ;", 1, "unknown verb in csg"));
	/* nesting is bounded */
	char buf[8192] = "";
	for (int i = 0; i < LIM_CSG_DEPTH + 1; i++)
		strcat(buf, "object csg union operand1 ");
	strcat(buf, "object sphere ; ;");
	CHECK(fails(buf, 1, "csg nested more than"));
}

static void test_materials(void)
{
	struct scene *s = ok(
		"define material named Wood colour (0.5 0.3 0.1) ; ; "
		"material named glass diff-colour (0.1 0.2 0.3) spec-colour (0.4 0.5 0.6) tran-colour (0.7 0.8 0.9) "
		"diffuse-reflection 0.2 specular-reflection 0.7 specular-power 100 reflection 0.3 "
		"transparency 0.9 refractive-index 1.5 ; "
		"object sphere ; material called WOOD ; ; "
		"object sphere ; material color (1 0 0) ; ; "
		"object sphere ; material named red2 colour (1 0 0) ; ; "
		"object sphere ; material called glass ; ; "
		"object sphere ; ;");
	CHECK(s != NULL);
	if (!s)
		return;
	CHECK(s->n_materials == 4);
	const struct scene_material *m = &s->materials[0];
	CHECK(strcmp(m->name, "Wood") == 0 && veq(m->diff_colour, 0.5, 0.3, 0.1) && veq(m->spec_colour, 0.5, 0.3, 0.1) &&
	      veq(m->tran_colour, 0.5, 0.3, 0.1));
	CHECK(m->diffuse == 1.0 && m->specular == 0 && m->spec_power == 20 && m->reflection == 0 &&
	      m->transparency == 0 && m->ior == 1 && m->shader.kind == SHADER_NONE);
	m = &s->materials[1];
	CHECK(strcmp(m->name, "glass") == 0 && veq(m->diff_colour, 0.1, 0.2, 0.3) && veq(m->spec_colour, 0.4, 0.5, 0.6) &&
	      veq(m->tran_colour, 0.7, 0.8, 0.9) && m->diffuse == 0.2 && m->specular == 0.7 && m->spec_power == 100 &&
	      m->reflection == 0.3 && m->transparency == 0.9 && m->ior == 1.5);
	CHECK((*scene_object(s, 0, &(struct scene_object){ 0 })).material == 0);
	CHECK((*scene_object(s, 1, &(struct scene_object){ 0 })).material == 2 && s->materials[2].name == NULL && veq(s->materials[2].spec_colour, 1, 0, 0));
	CHECK((*scene_object(s, 2, &(struct scene_object){ 0 })).material == 3 && strcmp(s->materials[3].name, "red2") == 0);
	CHECK((*scene_object(s, 3, &(struct scene_object){ 0 })).material == 1);
	CHECK((*scene_object(s, 4, &(struct scene_object){ 0 })).material == SCENE_NONE);
	CHECK(scene_find_material(s, "RED2") == 3);
	scene_free(s);

	CHECK(fails("object sphere ; material called nothing ; ;", 1, "t.sce:1:33: error: undefined material 'nothing'"));
	CHECK(fails("material named m ; object sphere ; material called m colour (1 1 1) ; ;", 1,
		    "t.sce:1:54: error: attempt to alter the named material 'm'"));
	CHECK(fails("material named m ; object sphere ; material colour (1 1 1) called m ; ;", 1,
		    "t.sce:1:60: error: attempt to overlay a material with the named material 'm'"));
	CHECK(fails("object sphere ; material shiny ; ;", 1, "t.sce:1:26: error: unknown verb in material near 'shiny'"));
	CHECK(fails("object sphere ; material ; material ; ;", 1, "an object takes one material"));
	CHECK(fails("define material colour (1 1 1) ; ;", 1, "a defined material needs 'named NAME'"));
	CHECK(fails("material colour (1 1 1) ;", 1, "a defined material needs 'named NAME'"));
	CHECK(fails("object sphere ; material refractive-index 0 ; ;", 1, "'refractive-index' must be greater than 0"));
	CHECK(fails("object sphere ; material named a named b ; ;", 1, "a material takes one name"));
}

static void test_shaders(void)
{
	struct scene *s = ok(
		"define material named grey colour (0.5 0.5 0.5) ; ; "
		"material named b1 bricks mortar material colour (1 1 1) ; brick called grey size 2 ; ; "
		"material named t1 tiles face called grey grout material colour (0 0 0) ; tile-width 6 grout-width 2 size 3 ; ; "
		"material named c1 chequers material-a called grey material-b called b1 size 0.5 ; ; "
		"material named u1 bumpy size 2 terms 5 xsize 1 ysize 2 zsize 3 material called grey saturation 1.5 depth 0.3 ; ; "
		"material named n1 noise size 4 material called grey variance 0.25 colour (0.1 0.2 0.3) ; ; "
		"material named n2 noise varience 0.75 ; ; "
		"material named f1 fades axis (1 1 1) colours 0.1 (0 0 0) 2.0 (0 0 1) 0.0 (0 0 0) ; ; "
		"material named f2 fades materials 1 called grey 2 material colour (1 0 0) ; 0 called grey ; ; "
		"material named r1 turb3d terms 6 depth 0.5 size 2 material called f1 ; ; "
		"material named d1 bricks ; ; material named d2 tiles ; ; material named d3 chequers ; ; "
		"material named d4 bumpy ; ; material named d5 turb3d ; ;");
	CHECK(s != NULL);
	if (!s)
		return;
	uint32_t grey = scene_find_material(s, "grey");
	const struct scene_material *m = &s->materials[scene_find_material(s, "b1")];
	CHECK(m->shader.kind == SHADER_BRICKS && m->shader.size == 2 && m->shader.mat_b == grey &&
	      m->shader.mat_a != SCENE_NONE && s->materials[m->shader.mat_a].name == NULL);
	m = &s->materials[scene_find_material(s, "t1")];
	CHECK(m->shader.kind == SHADER_TILES && m->shader.mat_a == grey && m->shader.tile_width == 6 &&
	      m->shader.grout_width == 2 && m->shader.size == 3 && veq(s->materials[m->shader.mat_b].diff_colour, 0, 0, 0));
	m = &s->materials[scene_find_material(s, "c1")];
	CHECK(m->shader.kind == SHADER_CHEQUERS && m->shader.mat_a == grey &&
	      m->shader.mat_b == scene_find_material(s, "b1") && m->shader.size == 0.5);
	m = &s->materials[scene_find_material(s, "u1")];
	CHECK(m->shader.kind == SHADER_BUMPY && m->shader.size == 2 && m->shader.terms == 5 &&
	      veq(m->shader.axis_size, 1, 2, 3) && m->shader.mat_a == grey && m->shader.saturation == 1.5 &&
	      m->shader.depth == 0.3);
	m = &s->materials[scene_find_material(s, "n1")];
	CHECK(m->shader.kind == SHADER_NOISE && m->shader.size == 4 && m->shader.mat_a == grey &&
	      m->shader.variance == 0.25 && veq(m->shader.colour, 0.1, 0.2, 0.3));
	CHECK(s->materials[scene_find_material(s, "n2")].shader.variance == 0.75);
	m = &s->materials[scene_find_material(s, "f1")];
	CHECK(m->shader.kind == SHADER_FADES && veq(m->shader.axis, 1, 1, 1) && !m->shader.fades_materials &&
	      m->shader.n_fades == 3 && m->shader.fades[0].dist == 0.1 && veq(m->shader.fades[1].colour, 0, 0, 1) &&
	      m->shader.fades[2].dist == 0 && m->shader.fades[0].material == SCENE_NONE);
	m = &s->materials[scene_find_material(s, "f2")];
	CHECK(m->shader.fades_materials && m->shader.n_fades == 3 && m->shader.fades[0].material == grey &&
	      m->shader.fades[1].dist == 2 && m->shader.fades[1].material != SCENE_NONE && m->shader.fades[2].material == grey);
	m = &s->materials[scene_find_material(s, "r1")];
	CHECK(m->shader.kind == SHADER_TURB3D && m->shader.terms == 6 && m->shader.depth == 0.5 && m->shader.size == 2 &&
	      m->shader.mat_a == scene_find_material(s, "f1"));
	/* shader defaults: scene_shader_defaults */
	struct scene_shader def;
	for (int k = 1; k <= 5; k++) {
		char nm[4] = { 'd', (char)('0' + k), 0, 0 };
		m = &s->materials[scene_find_material(s, nm)];
		scene_shader_defaults(&def, m->shader.kind);
		CHECK(m->shader.kind != SHADER_NONE && m->shader.size == def.size && m->shader.mat_a == SCENE_NONE &&
		      m->shader.mat_b == SCENE_NONE && m->shader.terms == def.terms && m->shader.depth == def.depth &&
		      m->shader.tile_width == def.tile_width);
	}
	scene_free(s);

	CHECK(fails("material named x fades colours 1 (0 0 0) 0 (1 1 1) materials 0 called x ; ;", 1,
		    "never both"));
	CHECK(fails("material named x fades axis (1 0 0) ; ;", 1, "a fades needs a 'colours' or 'materials' list"));
	CHECK(fails("material named x fades colours 0 (0 0 0) ; ;", 1, "positive distance"));
	CHECK(fails("material named x bricks tile-width 3 ; ;", 1, "unknown verb in material (bricks shader) near 'tile-width'"));
	CHECK(fails("material named x bricks mortar colour (1 1 1) ; ;", 1, "'material ... ;' or 'called NAME' expected after 'mortar'"));
	CHECK(fails("material named x bricks ; tiles ; ;", 1, "a material takes one shader"));
	CHECK(fails("material named x bricks size 2 colour (1 1 1) ; ;", 1, "';' expected (to close 'bricks' at line 1) near 'colour'"));
	CHECK(fails("material named x bumpy terms 0 ; ;", 1, "'terms' must be between 1 and"));
	CHECK(fails("material named x noise material called nope ; ;", 1, "undefined material 'nope'"));
	char buf[8192] = "material named x ";
	for (int i = 0; i < LIM_SHADER_DEPTH + 1; i++)
		strcat(buf, "bumpy material material ");
	CHECK(fails(buf, 1, "materials nested in shaders more than"));
}

static void test_define(void)
{
	struct scene *s = ok("define object name athing object sphere ; ; object box ; material colour (1 0 0) ; ; ; "
			     "material named m2 colour (0 1 0) ; ; "
			     "define object name wall object AThing ; ; object athing translate (2 0 0) ; ; ; ; "
			     "object translate (0 0 1) athing ; ; "
			     "object primitive wall x-rotate 90 material called m2 ; ; ; "
			     "object wall ; material called m2 ; ;");
	CHECK(s != NULL);
	if (!s)
		return;
	CHECK(s->n_defines == 2 && s->n_roots == 3);
	const struct scene_define *d = &s->defines[0];
	CHECK(strcmp(d->name, "athing") == 0 && d->n_objects == 2 && (*scene_object(s, d->objects[0], &(struct scene_object){ 0 })).kind == PRIM_SPHERE &&
	      (*scene_object(s, d->objects[1], &(struct scene_object){ 0 })).kind == PRIM_BOX);
	d = &s->defines[1];
	CHECK(d->n_objects == 2 && (*scene_object(s, d->objects[0], &(struct scene_object){ 0 })).kind == PRIM_INSTANCE &&
	      (*scene_object(s, d->objects[0], &(struct scene_object){ 0 })).u.instance.define == 0 && (*scene_object(s, d->objects[1], &(struct scene_object){ 0 })).has_xform);
	const struct scene_object *o = scene_object(s, s->roots[0], &(struct scene_object){ 0 });
	CHECK(o->kind == PRIM_INSTANCE && o->u.instance.define == 0 && o->has_xform);
	o = scene_object(s, s->roots[1], &(struct scene_object){ 0 });
	CHECK(o->kind == PRIM_INSTANCE && o->u.instance.define == 1 && o->has_xform &&
	      o->material == scene_find_material(s, "m2"));
	o = scene_object(s, s->roots[2], &(struct scene_object){ 0 });
	CHECK(o->u.instance.define == 1 && o->material == scene_find_material(s, "m2"));
	struct scene_stats st;
	scene_stats(s, &st);
	CHECK(st.by_kind[PRIM_INSTANCE] == 5);
	scene_free(s);

	CHECK(fails("object\n  athing ; ;", 1, "t.sce:2:3: error: undefined complex object 'athing'"));
	CHECK(fails("define object name a object sphere ; ; ; ; object a spin 3 ; ;", 1,
		    "t.sce:1:53: error: unknown verb in complex reference near 'spin'"));
	CHECK(fails("define light ;", 1, "t.sce:1:8: error: ';' expected (to close 'define' at line 1) near 'light'"));
	CHECK(fails("define thing ;", 1, "t.sce:1:8: error: unknown verb in definition"));
	CHECK(fails("define object object sphere ; ; ; ;", 1, "a defined object needs 'name NAME'"));
	CHECK(fails("define object name sphere ; ;", 1, "cannot be named by a keyword"));
	CHECK(fails("define object name a colour ; ;", 1, "unknown verb in definition (name or object expected)"));
	/* nesting is bounded */
	size_t cap = 65536;
	char *buf = malloc(cap);
	int n = snprintf(buf, cap, "define object name d0 object sphere ; ; ; ;\n");
	for (int i = 1; i <= LIM_DEFINE_DEPTH; i++)
		n += snprintf(buf + n, cap - (size_t)n, "define object name d%d object d%d ; ; ; ;\n", i, i - 1);
	CHECK(fails(buf, 1, "definitions nested more than"));
	free(buf);
}

static void test_scene_level(void)
{
	CHECK(fails("camera ; object sphere ; ;\n  teapot ;", 1, "t.sce:2:3: error: unknown verb in scene file near 'teapot'"));
	CHECK(fails("object sphere ; include x.inc ;", 1,
		    "t.sce:1:17: error: 'include' inside a statement ('object' at line 1)"));
	CHECK(fails("light include x ;", 1, "'include' inside a statement ('light' at line 1)"));
	CHECK(fails("include x.inc", 1, "t.sce:1:1: error: include files cannot be read here"));
	CHECK(fails("object sphere ; ;\n~ unfinished", 1, "t.sce:2:1: error: unfinished '~' comment"));
	CHECK(fails("light colour (1 1 1) object sphere ; ;", 1, "';' expected (to close 'light' at line 1) near 'object'"));
	CHECK(fails("object sphere ; ; ;", 1, "unknown verb in scene file near ';'"));
	/* comments and case everywhere */
	struct scene *s = ok("~ header ~ OBJECT // comment\n SPHERE RADIUS 2 ~ inline ~ ; MATERIAL COLOUR (1 0 0) ; ;");
	CHECK(s && s->n_objects == 1 && (*scene_object(s, 0, &(struct scene_object){ 0 })).u.sphere.radius == 2);
	scene_free(s);
	/* a long name is quoted shortened */
	char name[200];
	memset(name, 'q', sizeof name - 1);
	name[sizeof name - 1] = '\0';
	char text[300];
	snprintf(text, sizeof text, "%s ;", name);
	CHECK(fails(text, 1, "...'"));
	/* parse_buffer without a name; NUL bytes are rejected */
	struct scene *s2 = NULL;
	struct scene_error err;
	CHECK(parse_buffer(NULL, "object\0 sphere", 14, 0, &s2, &err) == 1 && s2 == NULL &&
	      strstr(err.msg, "<buffer>:1:7: error: invalid control character"));
}

/* Many objects parse quickly (a speed check lives in bench/, this one only
 * guards against quadratic behaviour: 20000 objects must take < 2 s). */
static void test_many(void)
{
	size_t cap = 20000 * 80 + 200, n = 0;
	char *buf = malloc(cap);
	n += (size_t)snprintf(buf + n, cap - n, "define material named m colour (1 1 1) ; ;\n");
	for (int i = 0; i < 20000; i++)
		n += (size_t)snprintf(buf + n, cap - n, "object sphere centre (%d 0 0) radius 0.5 ; material called m ; ;\n", i);
	clock_t t0 = clock();
	struct scene *s = ok(buf);
	double secs = (double)(clock() - t0) / CLOCKS_PER_SEC;
	CHECK(s && s->n_objects == 20000 && s->n_materials == 1);
	CHECK(secs < 2.0);
	scene_free(s);
	/* many names: lookups must not be linear (20000 x 20000 would take seconds) */
	n = 0;
	for (int i = 0; i < 20000; i++)
		n += (size_t)snprintf(buf + n, cap - n, "material named m%d ;\n", i);
	for (int i = 0; i < 20000 && n + 60 < cap; i++)
		n += (size_t)snprintf(buf + n, cap - n, "object sphere ; material called M%d ; ;\n", i);
	t0 = clock();
	s = ok(buf);
	secs = (double)(clock() - t0) / CLOCKS_PER_SEC;
	CHECK(s && s->n_materials == 20000 && s->n_objects > 10000 && (*scene_object(s, 123, &(struct scene_object){ 0 })).material == 123);
	CHECK(secs < 2.0);
	scene_free(s);
	free(buf);
	/* a redefined name: the latest wins */
	s = ok("material named a colour (1 0 0) ; material named A colour (0 1 0) ; object sphere ; material called a ; ; "
	       "define object name d object sphere ; ; ; ; define object name D object box ; ; ; ; object d ; ;");
	CHECK(s && (*scene_object(s, 0, &(struct scene_object){ 0 })).material == 1 && (*scene_object(s, s->roots[1], &(struct scene_object){ 0 })).u.instance.define == 1);
	scene_free(s);
}

static char tmpdir[64];

/* Writes tmpdir/name with text. */
static void put(const char *name, const char *text)
{
	char path[256];
	snprintf(path, sizeof path, "%s/%s", tmpdir, name);
	FILE *f = fopen(path, "w");
	CHECK(f != NULL);
	if (f) {
		fputs(text, f);
		fclose(f);
	}
}

static int files(const char *cam, const char *scene, struct scene **s, struct scene_error *err)
{
	char cp[256], sp[256];
	snprintf(cp, sizeof cp, "%s/%s", tmpdir, cam ? cam : "");
	snprintf(sp, sizeof sp, "%s/%s", tmpdir, scene);
	return parse_files(cam ? cp : NULL, sp, s, err);
}

/* Includes, raw files, camera files: parse_files on files in a temporary directory. */
static void test_files(void)
{
	snprintf(tmpdir, sizeof tmpdir, "/tmp/portray-test-parse-XXXXXX");
	if (!mkdtemp(tmpdir)) {
		CHECK(0);
		return;
	}
	char cmd[128];
	snprintf(cmd, sizeof cmd, "mkdir -p %s/sub/deeper", tmpdir);
	CHECK(system(cmd) == 0);
	put("sub/two.raw", "0 0 0 1 0 0 0 1 0\n1 0 0 1 1 0 0 1 0\n");
	put("sub/mats.inc", "define material named inc-red colour (1 0 0) ; ;\ninclude deeper/more.inc\n");
	put("sub/deeper/more.inc", "light position (1 2 3) ;\n");
	put("main.sce", "include sub/mats.inc\n"
			"object raw file sub/two.raw weld 0.001 smooth x-rotation 90 y-rotation 0 z-rotation 0 "
			"at (0 0 0) ; material called inc-red ; ;\n"
			"object raw file sub/two.raw weld 0.001 smooth x-rotation 90 y-rotation 0 z-rotation 0 ; ;\n"
			"object raw file sub/two.raw ; ;\n"
			"camera depth 2 ; image xsize 10 ;\n");
	put("cam.cam", "camera depth 5 ; image xsize 99 ; light ;");
	struct scene *s = NULL;
	struct scene_error err = { 0 };
	int rc = files(NULL, "main.sce", &s, &err);
	CHECK(rc == 0);
	if (rc)
		fprintf(stderr, "%s\n", err.msg);
	if (s) {
		CHECK(s->n_lights == 1 && veq(s->lights[0].position, 1, 2, 3));
		CHECK(s->n_objects == 3 && s->n_meshes == 2); /* same file and options: one mesh */
		CHECK((*scene_object(s, 0, &(struct scene_object){ 0 })).u.raw.mesh == (*scene_object(s, 1, &(struct scene_object){ 0 })).u.raw.mesh);
		CHECK((*scene_object(s, 0, &(struct scene_object){ 0 })).material == scene_find_material(s, "INC-RED"));
		const struct scene_mesh *m = &s->meshes[(*scene_object(s, 0, &(struct scene_object){ 0 })).u.raw.mesh];
		CHECK(m->n_triangles == 2 && m->n_vertices == 4 && m->smooth && m->weld == 0.001 && m->rotation.x == 90);
		CHECK(s->meshes[1].weld == 0.00001 && !s->meshes[1].smooth);
		CHECK(s->camera.depth == 2 && s->image.xsize == 10);
		scene_free(s);
	}
	/* the camera file's camera and image win; lights add up */
	rc = files("cam.cam", "main.sce", &s, &err);
	CHECK(rc == 0 && s && s->camera.depth == 5 && s->image.xsize == 99 && s->n_lights == 2);
	scene_free(s);
	/* errors with file names relative to the including file */
	put("bad1.sce", "object sphere ; ;\ninclude sub/nothing.inc\n");
	rc = files(NULL, "bad1.sce", &s, &err);
	CHECK(rc == 1 && s == NULL && strstr(err.msg, "bad1.sce:2:9: error: unable to open include file '") &&
	      strstr(err.msg, "sub/nothing.inc'"));
	put("bad2.sce", "object raw\n file missing.raw ; ;\n");
	rc = files(NULL, "bad2.sce", &s, &err);
	CHECK(rc == 1 && strstr(err.msg, "bad2.sce:2:7: error: unable to open raw file 'missing.raw'"));
	put("sub/bad.inc", "object sphere radius -1 ; ;\n");
	put("bad3.sce", "include sub/bad.inc\n");
	rc = files(NULL, "bad3.sce", &s, &err);
	CHECK(rc == 1 && strstr(err.msg, "sub/bad.inc:1:22: error: 'radius' must be greater than 0"));
	put("cycle.sce", "include sub/c1.inc\n");
	put("sub/c1.inc", "include c2.inc\n");
	put("sub/c2.inc", "light ;\ninclude c1.inc\n");
	rc = files(NULL, "cycle.sce", &s, &err);
	CHECK(rc == 1 && strstr(err.msg, "sub/c2.inc:2:9: error: include cycle"));
	put("self.sce", "include self.sce\n");
	rc = files(NULL, "self.sce", &s, &err);
	CHECK(rc == 1 && strstr(err.msg, "self.sce:1:9: error: include cycle"));
	/* depth: d0 includes d1 ... d33 (33 levels of nesting) */
	for (int i = 0; i <= 34; i++) {
		char n[32], t[64];
		snprintf(n, sizeof n, "d%d.inc", i);
		snprintf(t, sizeof t, i < 34 ? "include d%d.inc\n" : "light ;\n", i + 1);
		put(n, t);
	}
	rc = files(NULL, "d2.inc", &s, &err); /* 32 levels: fine */
	CHECK(rc == 0 && s && s->n_lights == 1);
	scene_free(s);
	rc = files(NULL, "d1.inc", &s, &err); /* 33 levels: too deep */
	CHECK(rc == 1 && strstr(err.msg, "d33.inc:1:9: error: includes nested more than 32 deep"));
	/* camera files hold camera, image and light only */
	put("objcam.cam", "camera ;\nobject sphere ; ;\n");
	rc = files("objcam.cam", "main.sce", &s, &err);
	CHECK(rc == 1 && strstr(err.msg, "objcam.cam:2:1: error: unrecognised keyword in camera file"));
	rc = files("nope.cam", "main.sce", &s, &err);
	CHECK(rc == 1 && strstr(err.msg, "nope.cam: error: unable to open camera file: No such file"));
	rc = files(NULL, "nope.sce", &s, &err);
	CHECK(rc == 1 && strstr(err.msg, "nope.sce: error: unable to open scene file: No such file"));
	rc = files(NULL, "sub", &s, &err);
	CHECK(rc == 1 && strstr(err.msg, "unable to open scene file: Is a directory"));
	snprintf(cmd, sizeof cmd, "rm -rf %s", tmpdir);
	CHECK(system(cmd) == 0);
}

int main(void)
{
	test_files();
	test_camera_image();
	test_filters();
	test_camera_errors();
	test_light();
	test_primitives();
	test_polygon();
	test_transforms();
	test_csg();
	test_materials();
	test_shaders();
	test_define();
	test_scene_level();
	test_many();
	TEST_MAIN_END();
}
