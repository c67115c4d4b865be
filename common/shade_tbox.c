/*
 * shade_tbox.c - TRANSPARENT BOXES (shade_tbox.h): the boxes around the
 * surfaces that may be transparent, found once per shading context.
 */
#include "common/shade_tbox.h"

#include <math.h>

#include "common/limits.h"

/* The largest of three (plain comparisons, as shade.c's max3). */
static double big3(double a, double b, double c)
{
	double m = a > b ? a : b;
	return m > c ? m : c;
}

/* Objects looked at below CSG and instance roots before giving up (the
 * shortcut is then off): bounds shade_ctx_new's time. */
#define TBOX_BUDGET 1000000

/* Whether material index mi (SCENE_NONE or out of range: the default
 * material) may give a transparent surface. */
static bool mat_maybe_transparent(const struct scene *s, uint32_t mi)
{
	const struct scene_material *m = mi < s->n_materials ? &s->materials[mi] : scene_default_material();
	return !(m->transparency <= 0) || m->shader.kind != SHADER_NONE;
}

/*
 * Whether object oi or anything below it (CSG operands, a define's
 * members) names a material that may be transparent; true as well when
 * *budget runs out. Members without a material take their parent's, which
 * the caller has looked at.
 */
static bool subtree_maybe_transparent(const struct scene *s, uint32_t oi, long *budget, int depth)
{
	if (--*budget < 0 || depth > LIM_DEFINE_DEPTH + LIM_CSG_DEPTH || oi >= s->n_objects)
		return true;
	struct scene_object tmp;
	const struct scene_object *o = scene_object(s, oi, &tmp);
	if (o->material != SCENE_NONE && mat_maybe_transparent(s, o->material))
		return true;
	if (o->kind == PRIM_CSG)
		return subtree_maybe_transparent(s, o->u.csg.operand1, budget, depth + 1) ||
		       subtree_maybe_transparent(s, o->u.csg.operand2, budget, depth + 1);
	if (o->kind == PRIM_INSTANCE) {
		if (o->u.instance.define >= s->n_defines)
			return true;
		const struct scene_define *d = &s->defines[o->u.instance.define];
		for (uint32_t k = 0; k < d->n_objects; k++)
			if (subtree_maybe_transparent(s, d->objects[k], budget, depth + 1))
				return true;
	}
	return false;
}

/* Grows box (lo, hi) by vertex p, transformed as accel_build bakes it. */
static void box_add(const struct scene_object *o, vec3 p, vec3 *lo, vec3 *hi)
{
	if (o->has_xform)
		p = m34_point(&o->xform, p);
	*lo = v3(p.x < lo->x ? p.x : lo->x, p.y < lo->y ? p.y : lo->y, p.z < lo->z ? p.z : lo->z);
	*hi = v3(p.x > hi->x ? p.x : hi->x, p.y > hi->y ? p.y : hi->y, p.z > hi->z ? p.z : hi->z);
}

/* World box of root object o, a triangle or RAW mesh, margin included:
 * false when it has none (another kind, or not finite). */
static bool root_box(const struct scene *s, const struct scene_object *o, vec3 *lo, vec3 *hi)
{
	*lo = v3(INFINITY, INFINITY, INFINITY);
	*hi = v3(-INFINITY, -INFINITY, -INFINITY);
	if (o->kind == PRIM_TRIANGLE) {
		box_add(o, o->u.triangle.a, lo, hi);
		box_add(o, o->u.triangle.b, lo, hi);
		box_add(o, o->u.triangle.c, lo, hi);
	} else if (o->kind == PRIM_RAW && o->u.raw.mesh < s->n_meshes) {
		const struct scene_mesh *m = &s->meshes[o->u.raw.mesh];
		for (uint32_t k = 0; k < m->n_vertices; k++)
			box_add(o, m->vertices[k], lo, hi);
	} else {
		return false;
	}
	double big = big3(v3_maxabs(*lo), v3_maxabs(*hi), 0);
	if (!(big < 0x1p900))
		return false; /* infinite, NaN, empty or too large for the margins */
	double e = big * TBOX_MARGIN + 0x1p-900;
	*lo = v3_sub(*lo, v3(e, e, e));
	*hi = v3_add(*hi, v3(e, e, e));
	return true;
}

void shade_tboxes_find(const struct scene *s, bool any_transparent, struct shade_tboxes *t)
{
	t->n = 0;
	t->all = false;
	if (!any_transparent || mat_maybe_transparent(s, SCENE_NONE))
		return;
	vec3 lo[SHADE_TBOXES], hi[SHADE_TBOXES];
	uint32_t mat[SHADE_TBOXES];
	long budget = TBOX_BUDGET;
	for (uint32_t k = 0; k < s->n_roots; k++) {
		uint32_t oi = s->roots[k];
		if (oi >= s->n_objects)
			return;
		struct scene_object tmp;
		const struct scene_object *o = scene_object(s, oi, &tmp);
		if (o->kind == PRIM_CSG || o->kind == PRIM_INSTANCE) {
			if (subtree_maybe_transparent(s, oi, &budget, 0))
				return;
			continue;
		}
		if (!mat_maybe_transparent(s, o->material))
			continue;
		vec3 l, h;
		if (!root_box(s, o, &l, &h))
			return;
		uint32_t j = 0;
		while (j < t->n && mat[j] != o->material && j < SHADE_TBOXES - 1)
			j++;
		if (j == t->n) {
			mat[j] = o->material;
			lo[j] = l;
			hi[j] = h;
			t->n++;
		} else {
			lo[j] = v3_min(lo[j], l);
			hi[j] = v3_max(hi[j], h);
		}
	}
	for (uint32_t j = 0; j < t->n; j++) { /* centre and half-size, rounding covered */
		double big = big3(v3_maxabs(lo[j]), v3_maxabs(hi[j]), 0);
		t->box[j].c = v3_scale(v3_add(lo[j], hi[j]), 0.5);
		t->box[j].e = v3_add(v3_scale(v3_sub(hi[j], lo[j]), 0.5), v3(big * TBOX_DYN, big * TBOX_DYN, big * TBOX_DYN));
	}
	t->all = true;
}
