/*
 * accel_cross.c - SHADOW CROSSINGS (accel.h): every surface a shadow
 * segment crosses, one ray at a time (accel_cross), and the pieces the
 * packet query (accel_cross4, accel_packet.c) shares with it: a
 * reference's crossings (accel_cross_ref) and a crossing's entry in the
 * list (accel_cross_emit).
 *
 * A shadow ray toward a light through transparent surfaces used to walk:
 * a closest-hit query, a step past the hit (offset along its normal, aimed
 * anew at the light), another query, and so on, three or four queries for
 * a ray through a glass gear. Here one traversal of the segment finds every
 * crossing, in any order, and stops at the first opaque one; the list is
 * kept in order of t, one entry per t. gears_s2 took 22% less time for the
 * same image but one pixel (docs/performance.md, round 17).
 *
 * The traversal needs no order (a crossing is a crossing wherever it is
 * found), so it is the any-hit one's: each node's children that the
 * segment meets, pushed as they come. Each primitive's crossings are its
 * first hit after tmin, then the first after that, and so on (a sphere or
 * a cylinder has two; a triangle one); an instance's are those of its
 * define's group, its ray in the define's space (the same t), each hit
 * brought back to the world as accel_intersect brings it (inst_hit).
 */
#include "common/accel.h"

#include "common/accel_box.h"
#include "common/accel_int.h"
#include "common/accel_trace.h"
#include "common/cancel.h"

/* The entry for t in X: a new one (n, the list grown) or the one there. */
static int cross_slot(struct accel_crossings *X, double t)
{
	int k = 0;
	while (k < X->n && X->x[k].t != t)
		k++;
	return k;
}

/* What the surface the closest hit names at t lets through (false:
 * nothing), for two surfaces of one nested instance at t, whose keys tie
 * (struct cross_level): the query's ray from just below t to just above. */
static bool cross_settle(const struct cross_query *Q, double t, struct accel_pass *p)
{
	struct ray q = *Q->r;
	q.tmin = nextafter(t, 0);
	q.tmax = next_up(t);
	struct hit h;
	if (!accel_intersect(Q->A, &q, &h))
		return true; /* not again (cannot happen): the entry stands */
	return Q->f->pass(Q->f->ctx, &h, p);
}

/* The tie key of a crossing of a reference of key `key` at level lv
 * (struct cross_level), and of the level an instance reference opens. */
static uint64_t cross_key(const struct cross_level *lv, uint32_t key)
{
	return !lv ? (uint64_t)key << 32 : lv->depth == 1 ? lv->key | key : lv->key;
}

bool accel_cross_emit(const struct cross_query *Q, const struct group *g, const struct trace *r,
		      const struct cand *c, uint32_t mat, const struct cross_level *lv)
{
	if (mat != CROSS_MAT_UNKNOWN) {
		for (const struct cross_level *l = lv; mat == SCENE_NONE && l; l = l->up)
			mat = l->si->material; /* inst_hit's: a member without one takes its instance's */
		if (cross_opaque(Q->f, mat)) {
			if (!lv)
				*Q->hint = c->ref;
			return false;
		}
	}
	struct hit h;
	accel_finish(Q->A, g, r, c, &h);
	for (const struct cross_level *l = lv; l; l = l->up) { /* back to the world, as inst_hit */
		struct hit hp;
		accel_inst_to_parent(Q->A, l->si, &l->inv, &h, &hp);
		hp.surf_fn = NULL;
		hp.p = v3_add(l->pr->o, v3_scale(l->pr->d, hp.t));
		h = hp;
	}
	if (cancel_poll()) /* CANCELLATION: shaders may be costly; the answer is dropped */
		return false;
	struct accel_pass p;
	if (!Q->f->pass(Q->f->ctx, &h, &p))
		return false;
	/* one entry per t, the least key's (CANONICAL TIES) */
	struct accel_crossings *X = Q->X;
	uint64_t key = cross_key(lv, c->key);
	int k = cross_slot(X, c->t);
	if (k == X->n) {
		if (X->n >= ACCEL_CROSS_MAX)
			return false; /* too many: blocked */
		X->x[X->n++] = (struct accel_crossing){ c->t, key, p };
	} else if (key < X->x[k].key) {
		X->x[k].key = key;
		X->x[k].p = p;
	} else if (key == X->x[k].key && lv && lv->depth > 1) {
		return cross_settle(Q, c->t, &X->x[k].p);
	}
	return true;
}

static bool group_cross(const struct cross_query *Q, const struct group *g, struct trace *r,
			const struct cross_level *lv);

/* The crossings of instance reference i of g (level lv's group) on r. */
static bool inst_cross(const struct cross_query *Q, const struct group *g, uint32_t i, struct trace *r,
		       const struct cross_level *lv)
{
	if (cancel_poll()) /* CANCELLATION: nested instances multiply the work */
		return true;
	const struct scene_inst *si = &Q->A->s->insts[g->inst[i].rec];
	struct cross_level nl = { lv, r, si, { { { 0 } } }, lv ? lv->depth + 1 : 1,
				  cross_key(lv, REF_MAKE(REF_INST, g->inst[i].rec)) };
	inst_inverse(Q->A, si, &nl.inv);
	struct trace lr;
	trace_init(&lr, m34_point(&nl.inv, r->o), m34_dir(&nl.inv, r->d), r->tmin, r->tmax);
	return group_cross(Q, Q->A->dgroup[si->define], &lr, &nl);
}

bool accel_cross_ref(const struct cross_query *Q, const struct group *g, uint32_t ref, struct trace *r,
		     const struct cross_level *lv)
{
	uint32_t i = REF_IDX(ref);
	struct cand c;
	switch (REF_KIND(ref)) {
	case REF_SPHERE: { /* its first hit after tmin, then the one after that */
		const double tmin = r->tmin;
		double t;
		bool open = true;
		while (open && sphere_test(&g->sph[i], r, &t)) {
			cand_init(&c);
			c.ref = c.key = ref;
			c.t = t;
			c.part = GEOM_PART_MAIN;
			open = accel_cross_emit(Q, g, r, &c, cross_ref_mat(g, ref), lv);
			r->tmin = t;
		}
		r->tmin = tmin;
		return open;
	}
	case REF_TRI:
		return cross_tri(Q, g, ref, r, lv);
	case REF_XPRIM: {
		if (mailbox_seen(r, ref)) /* MAILBOX: every crossing was taken at the first test */
			return true;
		uint32_t mat = cross_ref_mat(g, ref);
		const double tmin = r->tmin, tmax = r->tmax;
		bool open = true;
		for (;;) {
			cand_init(&c);
			bool hit = accel_ref_test_slow(Q->A, g, ref, r, &c, false);
			r->tmax = tmax; /* the test narrowed it */
			if (!hit)
				break;
			if (!(open = accel_cross_emit(Q, g, r, &c, mat, lv)) || !(c.t > r->tmin))
				break;
			r->tmin = c.t;
		}
		r->tmin = tmin;
		return open;
	}
	default:
		return inst_cross(Q, g, i, r, lv);
	}
}

/* The crossings of r in group g (level lv): the unbounded references,
 * then the tree's, any-hit order. False when the segment is blocked. */
static bool group_cross(const struct cross_query *Q, const struct group *g, struct trace *r,
			const struct cross_level *lv)
{
	if (!accel_cross_unb(Q, g, r, lv))
		return false;
	if (g->bvh.root_n) { /* the root is one leaf */
		if (box_hit(g->bvh.root_b, g->center, r))
			for (uint32_t k = 0; k < g->bvh.root_n; k++) {
				if (cancel_poll_every(k))
					return true;
				if (!accel_cross_ref(Q, g, group_ref(g, g->bvh.root_idx + k), r, lv))
					return false;
			}
		return true;
	}
	if (!g->bvh.n_nodes4)
		return true;
	const struct bvh4 *nodes = g->bvh.nodes;
	struct ray4 q;
	ray4_init(&q, r, g->center);
	const tspan tmin = tspan_of(box_tmin(r->tmin * q.tscale)), tmax = tspan_of(box_tmax(r->tmax * q.tscale));
	struct {
		uint32_t idx, n;
	} stack[3 * BVH_MAX_DEPTH + 4];
	int sp = 0;
	uint32_t idx = 0, n = 0, polls = ACCEL_POLL_POPS;
	for (;;) {
		if (n & LEAF_BLOCK) {
			const float *tb = &g->tblk[idx];
			uint32_t nt = n & ~LEAF_BLOCK;
			for (uint32_t k = 0; k < nt; k++)
				if (!cross_tri(Q, g, blk_ref(tb, nt, k), r, lv))
					return false;
		} else if (n) {
			for (uint32_t k = 0; k < n; k++) {
				if (cancel_poll_every(k)) /* CANCELLATION: big leaves */
					return true;
				if (!accel_cross_ref(Q, g, group_ref(g, idx + k), r, lv))
					return false;
			}
		} else {
			const struct bvh4 *nd = &nodes[idx];
			float tn[4];
			int m = node4_hit(nd, &q, q.oct, tmin, tmax, tn);
			if (m) { /* the lowest child next, the others pushed */
				int c = __builtin_ctz((unsigned)m);
				for (int j = 3; j > c; j--)
					if (m >> j & 1) {
						stack[sp].idx = nd->idx[j];
						stack[sp++].n = nd->n[j];
					}
				idx = nd->idx[c];
				n = nd->n[c];
				continue;
			}
		}
		if (__builtin_expect(--polls == 0, 0)) { /* CANCELLATION */
			polls = ACCEL_POLL_POPS;
			if (cancel_poll())
				return true;
		}
		if (sp == 0)
			return true;
		sp--;
		idx = stack[sp].idx;
		n = stack[sp].n;
	}
}

void accel_cross_sort(struct accel_crossings *X)
{
	for (int k = 1; k < X->n; k++) { /* few: insertion */
		struct accel_crossing e = X->x[k];
		int j = k;
		for (; j > 0 && X->x[j - 1].t > e.t; j--)
			X->x[j] = X->x[j - 1];
		X->x[j] = e;
	}
}

bool accel_cross(const struct accel *a, const struct ray *r, const struct accel_cross_filter *f,
		 struct accel_crossings *x, uint32_t *hint)
{
	x->n = 0;
	if (!a->root || !ray_ok(r))
		return true;
	struct trace t;
	trace_init(&t, r->o, r->d, ray_tmin(r), r->tmax);
	const struct cross_query Q = { a, r, f, x, hint };
	if (cross_hint_blocks(&Q, a->root, &t))
		return false;
	if (!group_cross(&Q, a->root, &t, NULL))
		return false;
	accel_cross_sort(x);
	return true;
}
