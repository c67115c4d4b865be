/*
 * csg.c - constructive solid geometry by interval combination.
 *
 * For one ray, each operand yields the ordered list of its boundary
 * crossings along the whole line (t from -inf to +inf) and whether t = -inf
 * is inside it. Two lists combine by walking them in t order while tracking
 * "inside A" and "inside B": a solid crossing is a boundary of the result
 * exactly when the result's inside state changes there. Surfaces without an
 * inside (disk, triangle, polygon) pass where the operation keeps them:
 * union: outside the other operand; intersect: inside it; subtract:
 * operand1's outside operand2, operand2's never. An open cylinder is its
 * capped solid for the inside state, but its caps are not drawn. A raw mesh
 * is a closed solid: entering where the ray meets a triangle's front face
 * ((b-a) x (c-a) against the ray), leaving at a back face. An instance
 * operand is the union of its define's members. The closest drawn crossing
 * in (tmin, tmax) of the top node is the hit: exact, not approximate.
 *
 * Every crossing carries its surface data (normal, uv, material, the point
 * in the material owner's space), computed in the leaf's space and carried
 * up through each node's transform, so nested transforms and instances work
 * at any depth.
 *
 * An operand that is a defined object is evaluated member by member, so
 * nested defines make the work exponential in their depth (64): eval and
 * csg_bounds poll the calling thread's cancel flag (cancel.h) at every
 * node, and give up (no crossings; an empty box) once it is seen set.
 */
#include "common/geom.h"

#include <stdlib.h>
#include <string.h>

#include "common/cancel.h"

struct csg_x {
	double t;
	vec3 n, ng, mp;
	double u, v;
	uint32_t material, object;
	int flags; /* GEOM_X_* */
};

struct csg_buf {
	struct csg_x *a;
	size_t n, cap;
	bool heap;
	bool oom;
};

struct csg_env {
	const struct scene *s;
	struct geom_obj *const *gobj;
};

/* Appends x; on out-of-memory sets oom and drops it (the ray then misses). */
static void buf_push(struct csg_buf *b, const struct csg_x *x)
{
	if (b->n == b->cap) {
		size_t nc = b->cap * 2;
		struct csg_x *na = malloc(nc * sizeof *na);
		if (!na) {
			b->oom = true;
			return;
		}
		memcpy(na, b->a, b->n * sizeof *na);
		if (b->heap)
			free(b->a);
		b->a = na;
		b->cap = nc;
		b->heap = true;
	}
	b->a[b->n++] = *x;
}

static bool op_inside(enum csg_op op, bool a, bool b)
{
	switch (op) {
	case CSG_UNION:
		return a || b;
	case CSG_INTERSECT:
		return a && b;
	default:
		return a && !b;
	}
}

/*
 * Combines list A = a[s, m) (inside at -inf: ia) with B = a[m, e) (ib) by op
 * and leaves the result in a[s, ...); returns the result's inside at -inf.
 */
static bool combine(struct csg_buf *b, size_t s, size_t m, size_t e, bool ia, bool ib, enum csg_op op)
{
	size_t i = s, j = m, out0 = e;
	bool in_a = ia, in_b = ib;
	bool state = op_inside(op, in_a, in_b), state0 = state;
	while (i < m || j < e) {
		bool from_a = j >= e || (i < m && b->a[i].t <= b->a[j].t);
		struct csg_x x = b->a[from_a ? i++ : j++];
		if (x.flags & GEOM_X_SURF) {
			bool other = from_a ? in_b : in_a;
			bool keep = op == CSG_UNION ? !other : op == CSG_INTERSECT ? other : (from_a && !in_b);
			if (keep)
				buf_push(b, &x);
			continue;
		}
		if (from_a)
			in_a = (x.flags & GEOM_X_ENTER) != 0;
		else
			in_b = (x.flags & GEOM_X_ENTER) != 0;
		bool ns = op_inside(op, in_a, in_b);
		if (ns == state)
			continue;
		state = ns;
		x.flags = (x.flags & GEOM_X_DRAW) | (ns ? GEOM_X_ENTER : GEOM_X_EXIT);
		if (op == CSG_SUBTRACT && !from_a) { /* B's outside is the result's inside */
			x.n = v3_neg(x.n);
			x.ng = v3_neg(x.ng);
		}
		buf_push(b, &x);
	}
	size_t n_out = b->n - out0;
	memmove(&b->a[s], &b->a[out0], n_out * sizeof *b->a);
	b->n = s + n_out;
	return state0;
}

static int cmp_x(const void *pa, const void *pb)
{
	const struct csg_x *a = pa, *b = pb;
	if (a->t != b->t)
		return a->t < b->t ? -1 : 1;
	return (a->flags & GEOM_X_ENTER) - (b->flags & GEOM_X_ENTER);
}

/* Crossings of a raw mesh (object space ray o + t d), sorted by t. */
static void mesh_crossings(const struct scene *s, uint32_t obj, vec3 o, vec3 d, struct csg_buf *b)
{
	const struct scene_mesh *m = &s->meshes[scene_full_at(s, obj)->u.raw.mesh];
	struct geom_wray w;
	geom_wray_init(&w, o, d);
	size_t start = b->n;
	for (uint32_t k = 0; k < m->n_triangles; k++) {
		if (cancel_poll_every(k)) /* every triangle is tested, with no tree */
			break;
		const uint32_t *ix = &m->tris[3 * (size_t)k];
		vec3 a = m->vertices[ix[0]], bb = m->vertices[ix[1]], c = m->vertices[ix[2]];
		double t, b1, b2;
		if (!geom_tri_hit(&w, a, bb, c, -INFINITY, INFINITY, &t, &b1, &b2))
			continue;
		struct csg_x x;
		memset(&x, 0, sizeof x);
		x.t = t;
		x.ng = v3_norm(v3_cross(v3_sub(bb, a), v3_sub(c, a)));
		x.n = x.ng;
		if (m->normals) {
			vec3 sn = v3_add(v3_add(v3_scale(m->normals[ix[0]], 1 - b1 - b2), v3_scale(m->normals[ix[1]], b1)),
					 v3_scale(m->normals[ix[2]], b2));
			if (v3_len(sn) > 0)
				x.n = v3_norm(sn);
		}
		bool front = v3_dot(d, x.ng) < 0; /* decided by the geometric facing */
		if (v3_dot(x.ng, x.n) < 0)
			x.ng = v3_neg(x.ng);
		x.mp = v3_add(o, v3_scale(d, t));
		geom_tri_uv(a, bb, c, x.mp, &x.u, &x.v);
		x.material = SCENE_NONE;
		x.object = obj;
		x.flags = (front ? GEOM_X_ENTER : GEOM_X_EXIT) | GEOM_X_DRAW;
		buf_push(b, &x);
	}
	if (b->n - start > 1)
		qsort(&b->a[start], b->n - start, sizeof *b->a, cmp_x);
}

/*
 * Appends the crossings of object obj for the ray o + t d given in obj's
 * parent space; returns whether t = -inf is inside. Recursion is bounded by
 * the CSG and define depth limits that accel_build checks.
 */
static bool eval(const struct csg_env *E, uint32_t obj, vec3 o, vec3 d, struct csg_buf *b)
{
	if (cancel_poll())
		return false;
	const struct geom_obj *g = E->gobj[obj];
	struct scene_object tmp;
	const struct scene_object *so = g->so ? g->so : scene_object(E->s, obj, &tmp);
	vec3 lo = o, ld = d;
	if (g->has_xform) {
		lo = m34_point(&g->inv, o);
		ld = m34_dir(&g->inv, d);
	}
	size_t start = b->n;
	bool in0 = false;
	switch (so->kind) {
	case PRIM_CSG: {
		bool ia = eval(E, so->u.csg.operand1, lo, ld, b);
		size_t mid = b->n;
		bool ib = eval(E, so->u.csg.operand2, lo, ld, b);
		in0 = combine(b, start, mid, b->n, ia, ib, so->u.csg.op);
		break;
	}
	case PRIM_INSTANCE: {
		const struct scene_define *df = &E->s->defines[so->u.instance.define];
		for (uint32_t k = 0; k < df->n_objects; k++) {
			size_t mid = b->n;
			bool im = eval(E, df->objects[k], lo, ld, b);
			in0 = k == 0 ? im : combine(b, start, mid, b->n, in0, im, CSG_UNION);
		}
		break;
	}
	case PRIM_RAW:
		mesh_crossings(E->s, obj, lo, ld, b);
		break;
	default: {
		struct geom_cross1 c[2];
		int nc = geom_crossings(g, lo, ld, c, &in0);
		for (int k = 0; k < nc; k++) {
			struct csg_x x;
			memset(&x, 0, sizeof x);
			x.t = c[k].t;
			x.flags = c[k].flags;
			x.mp = v3_add(lo, v3_scale(ld, x.t));
			geom_surface(g, x.mp, c[k].part, &x.n, &x.u, &x.v);
			x.ng = x.n;
			if (g->kind == PRIM_TRIANGLE) {
				x.ng = v3_norm(v3_cross(v3_sub(g->u.tri.b, g->u.tri.a), v3_sub(g->u.tri.c, g->u.tri.a)));
				if (v3_dot(x.ng, x.n) < 0)
					x.ng = v3_neg(x.ng);
			}
			x.material = SCENE_NONE;
			x.object = obj;
			buf_push(b, &x);
		}
		break;
	}
	}
	/* into the parent space; this object's material for crossings without one */
	for (size_t k = start; k < b->n; k++) {
		struct csg_x *x = &b->a[k];
		if (g->has_xform) {
			x->n = v3_norm(m34_normal(&g->inv, x->n));
			x->ng = v3_norm(m34_normal(&g->inv, x->ng));
		}
		if (x->material == SCENE_NONE && so->material != SCENE_NONE) {
			x->material = so->material;
			x->mp = v3_add(lo, v3_scale(ld, x->t));
		}
	}
	return in0;
}

bool csg_hit(const struct scene *s, struct geom_obj *const *gobj, uint32_t obj, vec3 o, vec3 d,
	     double tmin, double tmax, struct hit *h)
{
	struct csg_x stack_buf[CSG_STACK_CROSSINGS];
	struct csg_buf b = { stack_buf, 0, CSG_STACK_CROSSINGS, false, false };
	struct csg_env E = { s, gobj };
	eval(&E, obj, o, d, &b);
	bool found = false;
	if (!b.oom) {
		for (size_t k = 0; k < b.n; k++) {
			const struct csg_x *x = &b.a[k];
			if (!(x->flags & GEOM_X_DRAW) || !(x->t > tmin && x->t < tmax))
				continue;
			h->t = x->t;
			h->n = x->n;
			h->ng = x->ng;
			h->mp = x->mp;
			h->u = x->u;
			h->v = x->v;
			h->material = x->material;
			h->object = x->object;
			found = true;
			break;
		}
	}
	if (b.heap)
		free(b.a);
	return found;
}

static struct geom_box box_isect(struct geom_box a, struct geom_box b)
{
	struct geom_box r = { v3_max(a.lo, b.lo), v3_min(a.hi, b.hi) };
	return r;
}

struct geom_box csg_bounds(const struct scene *s, struct geom_obj *const *gobj, uint32_t obj)
{
	if (cancel_poll())
		return geom_box_empty();
	const struct geom_obj *g = gobj[obj];
	struct scene_object tmp;
	const struct scene_object *so = scene_object(s, obj, &tmp);
	struct geom_box b;
	switch (so->kind) {
	case PRIM_CSG: {
		struct geom_box b1 = csg_bounds(s, gobj, so->u.csg.operand1);
		struct geom_box b2 = csg_bounds(s, gobj, so->u.csg.operand2);
		b = so->u.csg.op == CSG_UNION ? geom_box_union(b1, b2)
		    : so->u.csg.op == CSG_INTERSECT ? box_isect(b1, b2) : b1;
		break;
	}
	case PRIM_INSTANCE: {
		const struct scene_define *df = &s->defines[so->u.instance.define];
		b = geom_box_empty();
		for (uint32_t k = 0; k < df->n_objects; k++)
			b = geom_box_union(b, csg_bounds(s, gobj, df->objects[k]));
		break;
	}
	default:
		b = geom_obj_local_bounds(s, g);
		break;
	}
	return g->has_xform ? geom_box_xform(&g->fwd, b) : b;
}
