/*
 * test_cross.c - SHADOW CROSSINGS (accel_cross, accel_cross4): every
 * surface a segment crosses, in order, one entry per t, blocked by any
 * opaque one.
 *
 * - Against a reference walk along the same ray (accel_intersect, then
 *   again from the hit's t, and so on), on random segments through a scene
 *   of every primitive kind in glass: spheres (two crossings each),
 *   triangles, a box, cylinders, a disk, a polygon, CSG, a glass plane (an
 *   unbounded reference), instances of a define (members inheriting the
 *   instance's material, one nested a level deeper), a chequered sphere
 *   whose squares are glass and opaque (the filter's callback decides),
 *   and opaque spheres, through shading's filter (shade_cross_filter);
 *   once with its table of opaque materials, once with the callback
 *   answering for them.
 * - Packets (accel_cross4) give every ray what accel_cross gives it, bit
 *   for bit, keys included.
 * - The list's bounds: 64 crossings fit, a 65th blocks; surfaces at one t
 *   count once, the first written's; an opaque one there blocks.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/accel.h"
#include "common/parse.h"
#include "common/rng.h"
#include "common/shade.h"
#include "tests/unit/check.h"

static const char SCENE[] =
	"define material named ga colour (1 0.8 0.6) transparency 0.9 ; ;\n"
	"define material named gb colour (0.5 1 0.7) transparency 0.6 ; ;\n"
	"define material named dark colour (0.3 0.3 0.3) ; ;\n"
	"define material named chq chequers size 0.25\n"
	"    material-a material colour (1 1 0.5) transparency 0.8 ; material-b material colour (0 0 1) ; ; ; ;\n"
	"define object name lens\n"
	"    object sphere radius 0.4 ; material called gb ; ;\n"
	"    object box a (-0.2 -0.2 -0.2) b (0.2 0.2 0.2) ; translate (0.6 0 0) ;\n"
	"    object triangle a (0 0 0) b (0.5 0 0) c (0 0.5 0.2) ; ;\n"
	"; ;\n"
	"define object name pair object lens ; ; object lens ; y-rotate 90 translate (0 0.9 0) ; ; ;\n"
	"object sphere centre (-1 0 0) radius 0.7 ; material called ga ; ;\n"
	"object sphere centre (1.2 0.4 -0.5) radius 0.5 ; material called gb ; ;\n"
	"object sphere centre (0 1.5 0.5) radius 0.3 ; x-rotate 30 stretch-y 1.5 material called ga ; ;\n"
	"object sphere centre (0.3 -1.2 0.8) radius 0.45 ; material called chq ; ;\n"
	"object sphere centre (1.5 -1.5 -1) radius 0.3 ; material called dark ; ;\n"
	"object sphere centre (-1.6 1.4 -0.8) radius 0.35 ; ;\n"
	"object triangle a (-2 -2 1.5) b (2 -2 1.6) c (0 2 1.4) ; material called gb ; ;\n"
	"object triangle a (-2 2 -1.5) b (2 2 -1.6) c (0 -2 -1.4) ; material called ga ; ;\n"
	"object box a (0.5 0.5 0.5) b (1.2 1.1 0.9) ; z-rotate 20 material called ga ; ;\n"
	"object cylinder from (-1.5 -1 -1) to (1.5 -0.5 0.2) radius 0.2 capped ; material called gb ; ;\n"
	"object cylinder from (-0.5 -2 0.5) to (-0.3 2 0.4) radius 0.25 ; material called ga ; ;\n"
	"object disk position (0.8 -0.6 0) normal (1 1 0.3) radius 0.5 ; material called gb ; ;\n"
	"object polygon contour (-1 0 -1.2) (0 0.3 -1.2) (-0.3 0.6 -1.2) (-1 1 -1.2) ; ; material called ga ; ;\n"
	"object csg operand1 object sphere centre (0 0 -0.6) radius 0.6 ; ;\n"
	"    operand2 object box a (-0.4 -0.4 -1.4) b (0.4 0.4 -0.2) ; ; intersect ; material called gb ; ;\n"
	"object plane position (0 -2.6 0) normal (0 1 0.1) ; material called ga ; ;\n"
	"object lens ; translate (-0.5 0.2 0.9) material called ga ; ;\n"
	"object pair ; x-rotate 40 translate (1.4 -0.2 1) material called gb ; ;\n"
	"object lens ; z-rotate 70 translate (-1.2 -1.1 0.3) ;\n";

/* The filter shading queries with (shade_cross_filter), for scene s and
 * accel a: its context in *ctx (to free); with table none (n_materials + 1
 * zeros) every hit goes through the callback. */
static struct accel_cross_filter filter_of(const struct scene *s, const struct accel *a, struct shade_ctx **ctx,
					   const uint8_t *none)
{
	struct scene_error err;
	if (shade_ctx_new(s, a, ctx, &err)) {
		fprintf(stderr, "shading: %s\n", err.msg);
		abort();
	}
	struct accel_cross_filter f = *shade_cross_filter(*ctx);
	if (none)
		f.opaque = none;
	return f;
}

/* The reference: closest hit after closest hit along the same ray. */
static bool walk(const struct accel *a, const struct ray *r, const struct accel_cross_filter *f,
		 struct accel_crossings *x)
{
	struct ray q = *r;
	x->n = 0;
	struct hit h;
	while (accel_intersect(a, &q, &h)) {
		struct accel_pass p;
		if (!f->pass(f->ctx, &h, &p) || x->n == ACCEL_CROSS_MAX)
			return false;
		x->x[x->n++] = (struct accel_crossing){ h.t, 0, p };
		q.tmin = h.t;
	}
	return true;
}

static bool same_pass(const struct accel_pass *a, const struct accel_pass *b)
{
	return memcmp(&a->col, &b->col, sizeof a->col) == 0 && memcmp(&a->td, &b->td, sizeof a->td) == 0;
}

/* x and y alike; with keys too when keys. */
static bool same_list(bool oa, const struct accel_crossings *x, bool ob, const struct accel_crossings *y, bool keys)
{
	if (oa != ob)
		return false;
	if (!oa)
		return true;
	if (x->n != y->n)
		return false;
	for (int k = 0; k < x->n; k++)
		if (x->x[k].t != y->x[k].t || !same_pass(&x->x[k].p, &y->x[k].p) || (keys && x->x[k].key != y->x[k].key))
			return false;
	return true;
}

static vec3 rand_point(uint64_t seed, uint64_t k, double ext)
{
	return v3(ext * (2 * rng_uniform(seed, 3 * k) - 1), ext * (2 * rng_uniform(seed, 3 * k + 1) - 1),
		  ext * (2 * rng_uniform(seed, 3 * k + 2) - 1));
}

static void against_walk(const struct accel *a, const struct accel_cross_filter *f, uint64_t seed)
{
	int n = 4000, bad = 0, bad4 = 0, open = 0, many = 0;
	static struct accel_crossings x, y, x4[4];
	for (int k = 0; k < n; k++) {
		/* four neighbouring segments toward one light point */
		vec3 o = rand_point(seed, 2 * (uint64_t)k, 3), lp = rand_point(seed, 2 * (uint64_t)k + 1, 4);
		struct ray r[4];
		for (int j = 0; j < 4; j++) {
			vec3 oj = v3_add(o, v3(0.01 * (j & 1), 0.01 * (j >> 1), 0.003 * j));
			r[j] = (struct ray){ oj, v3_sub(lp, oj), 0, 1 };
		}
		uint32_t hint = ACCEL_NO_HINT, hint4 = ACCEL_NO_HINT;
		bool o4[4];
		accel_cross4(a, r, f, x4, o4, &hint4);
		for (int j = 0; j < 4; j++) {
			bool oc = accel_cross(a, &r[j], f, &x, &hint);
			bool ow = walk(a, &r[j], f, &y);
			bad += !same_list(oc, &x, ow, &y, false);
			bad4 += !same_list(o4[j], &x4[j], oc, &x, true);
			open += oc;
			many += oc && x.n >= 3;
		}
	}
	printf("  %d segments: %d open, %d of them through 3 or more surfaces\n", 4 * n, open, many);
	CHECK(bad == 0);
	CHECK(bad4 == 0);
	/* the scene does what it is for: some segments pass, some through several */
	CHECK(open > 400 && many > 100);
	CHECK(4 * n - open > 400);
}

/* A stack of n glass squares (two triangles each) across z in (0, 1). */
static struct accel *stack_of(int n, struct scene **sp)
{
	size_t cap = 256 + (size_t)n * 400;
	char *t = malloc(cap);
	size_t len = (size_t)snprintf(t, cap, "define material named g colour (1 1 1) transparency 1 ; ;\n");
	for (int i = 0; i < n; i++) {
		double z = (i + 0.5) / n;
		len += (size_t)snprintf(t + len, cap - len,
					"object triangle a (-1 -1 %.17g) b (1 -1 %.17g) c (1 1 %.17g) ; material called g ; ;\n"
					"object triangle a (-1 -1 %.17g) b (1 1 %.17g) c (-1 1 %.17g) ; material called g ; ;\n",
					z, z, z, z, z, z);
	}
	struct scene_error err;
	struct accel *a = NULL;
	if (parse_buffer("stack", t, len, 0, sp, &err) || accel_build(*sp, &a, &err)) {
		fprintf(stderr, "stack: %s\n", err.msg);
		abort();
	}
	free(t);
	return a;
}

static void bounds(void)
{
	static const uint8_t none[2] = { 0, 0 };
	static struct accel_crossings x, x4[4];
	for (int n = 63; n <= 65; n++) {
		struct scene *s;
		struct accel *a = stack_of(n, &s);
		struct shade_ctx *sc;
		struct accel_cross_filter f = filter_of(s, a, &sc, none);
		struct ray r[4];
		for (int j = 0; j < 4; j++) /* off the diagonal edge */
			r[j] = (struct ray){ v3(0.3 + 0.01 * j, -0.2, -1), v3(0, 0, 3), 0, 1 };
		uint32_t hint = ACCEL_NO_HINT;
		bool open = accel_cross(a, &r[0], &f, &x, &hint), o4[4];
		accel_cross4(a, r, &f, x4, o4, &hint);
		CHECK(open == (n <= ACCEL_CROSS_MAX));
		for (int j = 0; j < 4; j++) {
			CHECK(o4[j] == open);
			if (open)
				CHECK(x4[j].n == n);
		}
		if (open)
			CHECK(x.n == n);
		/* the diagonal edge of each square: one crossing per square */
		struct ray e = { v3(0.25, 0.25, -1), v3(0, 0, 3), 0, 1 };
		open = accel_cross(a, &e, &f, &x, &hint);
		CHECK(open == (n <= ACCEL_CROSS_MAX));
		if (open)
			CHECK(x.n == n);
		shade_ctx_free(sc);
		accel_free(a);
		scene_free(s);
	}
}

/* Scene text t, padded with 40 small opaque spheres far from the rays so
 * that the root is a tree and accel_cross4 takes the packet path. */
static struct accel *tie_scene(const char *t, struct scene **sp)
{
	char buf[8192];
	size_t len = (size_t)snprintf(buf, sizeof buf, "%s", t);
	for (int i = 0; i < 40; i++)
		len += (size_t)snprintf(buf + len, sizeof buf - len,
					"object sphere centre (%d 9 %d) radius 0.1 ; ;\n", 8 + i % 5, i / 5);
	struct scene_error err;
	struct accel *a = NULL;
	if (len >= sizeof buf || parse_buffer("ties", buf, len, 0, sp, &err) || accel_build(*sp, &a, &err)) {
		fprintf(stderr, "ties: %s\n", len >= sizeof buf ? "too long" : err.msg);
		abort();
	}
	return a;
}

/* Four rays from near (0 0 -1) to z = z1 through scene t: each lane's
 * crossings, single and packet alike, and as the walk says when `walks`;
 * returns lane 0's (open, *x). */
static bool tie_rays(const char *t, double z1, bool walks, struct accel_crossings *x)
{
	struct scene *s;
	struct accel *a = tie_scene(t, &s);
	static const uint8_t none[8] = { 0 };
	struct shade_ctx *sc;
	struct accel_cross_filter f = filter_of(s, a, &sc, none);
	static struct accel_crossings x4[4], y;
	uint32_t hint = ACCEL_NO_HINT;
	struct ray r[4];
	for (int j = 0; j < 4; j++)
		r[j] = (struct ray){ v3(0.01 * j, 0.02 * (j >> 1), -1), v3(0, 0, z1 + 1), 0, 1 };
	bool o4[4], open0 = false;
	accel_cross4(a, r, &f, x4, o4, &hint);
	for (int j = 0; j < 4; j++) {
		bool open = accel_cross(a, &r[j], &f, x, &hint);
		CHECK(same_list(o4[j], &x4[j], open, x, true));
		CHECK(!walks || same_list(open, x, walk(a, &r[j], &f, &y), &y, false));
		if (j == 0)
			open0 = open;
	}
	accel_cross(a, &r[0], &f, x, &hint);
	shade_ctx_free(sc);
	accel_free(a);
	scene_free(s);
	return open0;
}

static void ties(void)
{
#define MATS                                                                                                   \
	"define material named ga colour (1 0.5 0.5) transparency 0.5 ; ;\n"                                   \
	"define material named gb colour (0.5 1 0.5) transparency 0.7 ; ;\n"
	static struct accel_crossings x;
	static const char T[] = MATS "object triangle a (-1 -1 0) b (1 -1 0) c (0 1 0) ; material called ga ; ;\n"
				     "object triangle a (-1 -1 0) b (1 -1 0) c (0 1 0) ; material called gb ; ;\n"
				     "object triangle a (-1 -1 0.5) b (1 -1 0.5) c (0 1 0.5) ; material called gb ; ;\n"
				     "object triangle a (-1 -1 0.5) b (1 -1 0.5) c (0 1 0.5) ; ;\n";
	/* two surfaces at one t: once, as the first written (ga) */
	CHECK(tie_rays(T, 0.2, true, &x) && x.n == 1 && x.x[0].p.td == 0.5 && x.x[0].p.col.y == 0.5);
	/* to z = 1: the opaque (default) triangle written after gb's, at its t,
	 * blocks, where the closest hit there is gb's (a walk would pass) */
	CHECK(!tie_rays(T, 1, false, &x));
	/* an instance's surface and a root triangle at one t: the triangle's key is
	 * the lower (CANONICAL TIES) whatever the order written */
	static const char U[] = MATS "define object name t object triangle a (-1 -1 0) b (1 -1 0) c (0 1 0) ;"
				     " material called gb ; ; ; ;\n"
				     "object t ; ;\n"
				     "object triangle a (-1 -1 0) b (1 -1 0) c (0 1 0) ; material called ga ; ;\n";
	CHECK(tie_rays(U, 1, true, &x) && x.n == 1 && x.x[0].p.td == 0.5);
	/* two surfaces of an instance within an instance: the first member
	 * written (ga's triangle), as the closest hit takes it */
#define INNER                                                                                                  \
	MATS "define object name inner\n"                                                                      \
	     "  object triangle a (-5 -5 0) b (5 -5 0) c (0 5 0) ; material called ga ; ;\n"                    \
	     "  object plane position (0 0 0) normal (0 0 1) ; material called gb ; ;\n"                         \
	     "; ;\n"
	static const char V[] = INNER "define object name mid object inner ; ; ; ;\n"
				      "object mid ; ;\n";
	CHECK(tie_rays(V, 1, true, &x) && x.n == 1 && x.x[0].p.td == 0.5);
	/* the same a level less deep */
	static const char W[] = INNER "object inner ; ;\n";
	CHECK(tie_rays(W, 1, true, &x) && x.n == 1 && x.x[0].p.td == 0.5);
#undef INNER
#undef MATS
}

int main(void)
{
	struct scene *s;
	struct scene_error err;
	struct accel *a = NULL;
	if (parse_buffer("cross", SCENE, sizeof SCENE - 1, 0, &s, &err) || accel_build(s, &a, &err)) {
		fprintf(stderr, "scene: %s\n", err.msg);
		return 1;
	}
	uint8_t *none = calloc(s->n_materials + 1, 1);
	struct shade_ctx *sc1, *sc2;
	struct accel_cross_filter f1 = filter_of(s, a, &sc1, NULL), f2 = filter_of(s, a, &sc2, none);
	/* shading's table knows dark and the default as opaque, not the chequers */
	CHECK(f1.opaque[2] && f1.opaque[s->n_materials] && !f1.opaque[0] && !f1.opaque[3]);
	printf("opaque materials in the table:\n");
	against_walk(a, &f1, 11);
	printf("every material through the callback:\n");
	against_walk(a, &f2, 12);
	shade_ctx_free(sc1);
	shade_ctx_free(sc2);
	accel_free(a);
	scene_free(s);
	free(none);
	bounds();
	ties();
	TEST_MAIN_END();
}
