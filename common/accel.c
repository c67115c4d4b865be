/*
 * accel.c - the scene's objects as a multi-level BVH: ray queries, one ray
 * at a time, and the completion of their hits. Packets of four rays are in
 * accel_packet.c; what both kinds of query share (a ray's trace state,
 * candidates and CANONICAL TIES, the primitive tests, the TRIANGLE
 * PRE-TEST) in accel_trace.h; building is in accel_build.c; the private
 * structures all of them share are in accel_int.h.
 *
 * A "group" is one BVH over a list of objects: the scene's roots, or the
 * members of one define (built ONCE, however many instances use it). Inside
 * a group every object becomes one or more references (32-bit: 2 bits of
 * kind, 30 bits of index) to:
 *   spheres    untransformed spheres, packed (centre, radius^2, object)
 *   triangles  (mesh slot, triangle): triangles and raw meshes; transformed
 *              ones are baked into the group's space; untransformed raw
 *              meshes use the scene's arrays without a copy; sliver
 *              triangles get several references (early split clipping)
 *   xprims     everything else (transformed spheres, planes, disks,
 *              cylinders, boxes, polygons, CSG nodes): the ray goes into
 *              the object's space through its inverse transform; long
 *              tilted cylinders get several references (LONG CYLINDERS
 *              in accel_build.c)
 *   instances  (the instance object: 4 bytes; the scene holds its define,
 *              material and transform), evaluated in double; the
 *              instance's geometry is exactly the inverse of its inverse
 *              transform rounded to float (inst_inverse, computed on each
 *              visit), used consistently for rays, normals and bounds; a group of ACCEL_PACK_MIN or more
 *              instances and no other bounded reference keeps them in leaf
 *              order without reference words, in leaves of up to
 *              ACCEL_INST_LEAF (issue 3: <= 64 bytes per instance)
 * Unbounded references (planes, CSG with an infinite extent, instances of
 * groups holding those) sit in a list tested for every ray. The BVH is
 * binned SAH (bvh.c) collapsed to 4-wide nodes, which packets walk; single
 * rays walk the same tree widened to 8-wide nodes (WIDE NODES, bvh.h) where
 * the group has them (every group but one of instances only). Traversal is
 * iterative with a fixed stack, nearest child first, and stops at the first
 * hit for accel_occluded. Packets of four rays (accel_intersect4, accel_occluded4,
 * accel_packet.c), and of 16 or 64 from one origin (accel_intersect16,
 * accel_intersect64), share one walk of the root group's tree; a last-blocker hint
 * (accel_occluded_hint) is tested before the tree. A single shadow ray
 * toward a point light may skip the tree for the light's LIGHT BUFFER
 * (accel_occluded_light; accel_int.h, accel_light.c). Instances recurse into their define's group (depth
 * bounded by LIM_DEFINE_DEPTH); the closest hit is completed (normal, uv,
 * mp, material) once per group, in the group's space, then carried out
 * through each instance's transform. In the root group, u, v and mp of
 * untransformed spheres (default pole and equator) and of triangles are
 * left to accel_hit_surface (hit.surf_fn), which the shader calls only for
 * materials with a shader; inside instances they are completed at once.
 * The traversal loop exists once per ray octant (bvh_hit's oct), so the
 * node test reads each axis' near and far planes at constant offsets.
 * Leaves of one to four triangles keep their vertices in float as well
 * (LEAF BLOCKS, accel_int.h): a conservative float pre-test of the ray
 * against the whole leaf (TRIANGLE PRE-TEST, accel_trace.h) picks the triangles the
 * double test then decides.
 *
 * Rays are never normalised when they change space, so t is the same in
 * every space and a hit's t is the caller's t.
 *
 * EPSILON STRATEGY (no self-intersection acne): all intersection arithmetic
 * is double; hits are accepted in the open interval (tmin, tmax). Secondary
 * rays should start at accel_offset_point(p, ng, dir), which moves the hit
 * point off the surface along the geometric normal, toward the side dir
 * leaves by, by ACCEL_OFFSET_REL * (1 + max |p_i|); then tmin = 0 is safe.
 * The offset is ~1e7 times the double rounding error of the tests, and far
 * below any feature size a scene can express in the SPD's units.
 *
 * CANCELLATION. One ray's work has no useful bound: defines nested 64 deep,
 * each two overlapping instances of the one before, make 2^63 instances
 * that a ray meeting them visits one by one. So a query polls the calling
 * thread's cancel flag (cancel.h) wherever the work can grow: on entering
 * an instance, every ACCEL_POLL_POPS subtrees a traversal pops, and every
 * CANCEL_STRIDE unbounded references; a leaf of more than ACCEL_LEAF_CHUNK
 * references (only the builder's depth limit makes one) is tested a chunk
 * at a time, the rest pushed as a subtree, so its pops are counted too (a
 * root group with such a leaf is traced one ray at a time: the packet
 * traversal has no chunks, which cost it 1%).
 * When a poll says true the query gives up and answers "no hit" (or "not
 * occluded") for what it has not seen: wrong, but the caller discards it
 * (cancel_seen). Normal rays pop a few subtrees and never reach a poll
 * outside instances; the counter costs no measurable time
 * (docs/performance.md).
 */
#include "common/accel.h"

#include <stdlib.h>
#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "common/accel_box.h"
#include "common/accel_int.h"
#include "common/accel_trace.h"
#include "common/cancel.h"
#include "common/xmath.h"


/* ---- instances and the rarer kinds --------------------------------------------------- */

static bool group_hit(const struct accel *A, const struct group *g, struct trace *r, struct hit *h, bool brute);
static bool group_occluded(const struct accel *A, const struct group *g, struct trace *r);
static void surface_complete(const struct scene *s, struct hit *h);
static void surface_cb(const struct accel *a, struct hit *h);

/*
 * Intersects instance `in` with r (parent space); on a hit closer than
 * r->tmax fills *h in the parent space (h->p excepted) and returns true.
 */
static bool inst_hit(const struct accel *A, const struct ginst *in, const struct trace *r, struct hit *h, bool brute)
{
	if (cancel_poll()) /* CANCELLATION: nested instances multiply the work */
		return false;
	const struct scene_inst *si = &A->s->insts[in->rec];
	mat34 inv;
	inst_inverse(A, si, &inv);
	struct trace lr;
	trace_init(&lr, m34_point(&inv, r->o), m34_dir(&inv, r->d), r->tmin, r->tmax);
	struct hit lh;
	if (!group_hit(A, A->dgroup[si->define], &lr, &lh, brute))
		return false;
	accel_inst_to_parent(A, si, &inv, &lh, h);
	return true;
}

void accel_inst_to_parent(const struct accel *A, const struct scene_inst *si, const mat34 *inv, struct hit *lh,
			  struct hit *h)
{
	surface_complete(A->s, lh); /* in the define's space */
	h->t = lh->t;
	h->n = v3_norm(m34_normal(inv, lh->n));
	h->ng = v3_norm(m34_normal(inv, lh->ng));
	h->u = lh->u;
	h->v = lh->v;
	h->object = lh->object;
	uint32_t im = si->material;
	if (lh->material == SCENE_NONE && im != SCENE_NONE) {
		h->material = im;
		h->mp = lh->p; /* the instance's own object space is the define's space */
	} else {
		h->material = lh->material;
		h->mp = lh->mp;
	}
}

bool accel_inst_occluded(const struct accel *A, const struct ginst *in, const struct trace *r)
{
	if (cancel_poll()) /* CANCELLATION */
		return false;
	const struct scene_inst *si = &A->s->insts[in->rec];
	mat34 inv;
	inst_inverse(A, si, &inv);
	struct trace lr;
	trace_init(&lr, m34_point(&inv, r->o), m34_dir(&inv, r->d), r->tmin, r->tmax);
	return group_occluded(A, A->dgroup[si->define], &lr);
}

/* The rarer kinds (xprims, CSG, instances), kept out of the traversal loop
 * so the loop keeps the ray in registers. Same contract as ref_test. */
/* A simple primitive other than an untransformed sphere or a triangle (an
 * xprim that is not CSG): a small frame of its own, apart from the CSG and
 * instance paths. Same contract as ref_test. */
static inline __attribute__((always_inline)) bool xprim_hit(const struct xprim *x, const struct trace *r, double *t,
							     int *part)
{
	if (x->r > 0) /* OPEN CYLINDERS */
		return geom_cyl_open_hit(x->from, x->a, x->r, x->h, r->o, r->d, r->tmin, r->tmax, t, part);
	const struct geom_obj *go = x->g;
	vec3 o = r->o, d = r->d;
	if (go->has_xform) {
		o = m34_point(&go->inv, o);
		d = m34_dir(&go->inv, d);
	}
	return geom_intersect(go, o, d, r->tmin, r->tmax, t, part);
}

__attribute__((noinline)) bool accel_xprim_test(const struct xprim *x, uint32_t ref, struct trace *r,
						struct cand *c)
{
	double t;
	int part;
	if (!xprim_hit(x, r, &t, &part) || !cand_better(c, ref, t))
		return false;
	c->part = part;
	cand_take(c, r, ref, t);
	return true;
}

/* ref_occludes of a simple xprim (not CSG): accel_xprim_test's answer
 * without a candidate, kept out of the traversal loops as it is. */
__attribute__((noinline)) bool accel_xprim_occludes(const struct xprim *x, const struct trace *r)
{
	double t;
	int part;
	return xprim_hit(x, r, &t, &part);
}

__attribute__((noinline)) bool accel_ref_test_slow(const struct accel *A, const struct group *g, uint32_t ref,
						   struct trace *r, struct cand *c, bool brute)
{
	uint32_t i = REF_IDX(ref);
	if (REF_KIND(ref) == REF_XPRIM) {
		const struct xprim *x = &g->xp[i];
		if (x->r > 0 || x->g->kind != PRIM_CSG)
			return accel_xprim_test(x, ref, r, c);
		struct hit hh;
		if (!csg_hit(A->s, (struct geom_obj *const *)A->gobj, x->obj, r->o, r->d, r->tmin, r->tmax, &hh) ||
		    !cand_better(c, ref, hh.t))
			return false;
		c->sub = hh;
		cand_take(c, r, ref, hh.t);
		return true;
	}
	struct hit hh;
	if (!inst_hit(A, &g->inst[i], r, &hh, brute))
		return false;
	uint32_t key = REF_MAKE(REF_INST, g->inst[i].rec);
	if (!cand_better(c, key, hh.t))
		return false;
	c->sub = hh;
	cand_take_key(c, r, ref, key, hh.t);
	return true;
}

/* ---- hit completion ----------------------------------------------------------------- */

/* Completes the hit of candidate c in the group's space. */
void accel_finish(const struct accel *A, const struct group *g, const struct trace *r, const struct cand *c,
		  struct hit *h)
{
	const struct scene *s = A->s;
	uint32_t i = REF_IDX(c->ref);
	vec3 p = v3_add(r->o, v3_scale(r->d, c->t));
	switch (REF_KIND(c->ref)) {
	case REF_SPHERE: {
		const struct gsphere *sp = &g->sph[i];
		uint32_t obj = sp->obj & ~GSPH_FRAME;
		vec3 q = v3_norm(v3_sub(p, sp->c));
		h->n = h->ng = q;
		h->mp = p;
		h->u = h->v = 0;
		if (!(sp->obj & GSPH_FRAME)) {
			/* the default frame: u, v from h->n later (surface_complete) */
			h->surf_fn = surface_cb;
			h->surf_kind = SURF_SPHERE;
		} else {
			struct geom_obj go;
			geom_obj_init(s, obj, &go); /* sphere: no allocation */
			geom_surface(&go, p, GEOM_PART_MAIN, &h->n, &h->u, &h->v);
			h->ng = h->n;
			h->surf_fn = NULL;
		}
		h->object = obj;
		h->material = sp->mat;
		break;
	}
	case REF_TRI: {
		const struct gmesh *m = &g->mesh[g->tri[i].mesh];
		const uint32_t *ix = tri_ix(m, g->tri[i].tri);
		double w0 = 1 - c->b1 - c->b2;
		vec3 fn = m->fn ? *m->fn : tri_normal(m, ix);
		h->ng = fn;
		h->n = fn;
		if (m->n) {
			vec3 sn = v3_add(v3_add(v3_scale(m->n[ix[0]], w0), v3_scale(m->n[ix[1]], c->b1)),
					 v3_scale(m->n[ix[2]], c->b2));
			if (v3_len(sn) > 0) {
				h->n = v3_norm(sn);
				if (v3_dot(h->ng, h->n) < 0)
					h->ng = v3_neg(h->ng);
			}
		}
		h->mp = v3(0, 0, 0);
		h->u = h->v = 0;
		h->surf_fn = surface_cb; /* mp, u, v later */
		h->surf_kind = SURF_TRI;
		h->surf = m;
		h->surf_idx = g->tri[i].tri;
		h->surf_b1 = c->b1;
		h->surf_b2 = c->b2;
		h->object = m->obj;
		h->material = m->mat;
		break;
	}
	case REF_XPRIM:
		if (g->xp[i].g->kind == PRIM_CSG) {
			*h = c->sub; /* CSG carries a finished hit */
			h->surf_fn = NULL;
		} else {
			const struct geom_obj *go = g->xp[i].g;
			vec3 lp = go->has_xform ? m34_point(&go->inv, p) : p;
			vec3 n;
			/* spheres' and cylinders' mappings (atan2, asin) later, from mp;
			 * planes', disks' and polygons' too (the ground plane is half
			 * the hits of a mesh scene) */
			bool lazy = go->kind == PRIM_SPHERE || go->kind == PRIM_CYLINDER || go->kind == PRIM_PLANE ||
				    go->kind == PRIM_DISK || go->kind == PRIM_POLYGON;
			if (lazy) {
				/* geom_normal's value; a plane's, the common case, inline */
				n = go->kind == PRIM_PLANE ? go->u.pl.n : geom_normal(go, lp, c->part);
				h->u = h->v = 0;
				h->surf_fn = surface_cb;
				h->surf_kind = SURF_XPRIM;
				h->surf = go;
				h->surf_idx = (uint32_t)c->part;
			} else {
				geom_surface(go, lp, c->part, &n, &h->u, &h->v);
				h->surf_fn = NULL;
			}
			if (go->has_xform)
				n = v3_norm(m34_normal(&go->inv, n));
			h->n = h->ng = n;
			h->mp = lp;
			h->object = g->xp[i].obj;
			h->material = g->xp[i].mat;
		}
		break;
	default:
		*h = c->sub; /* instances complete their hit (inst_hit) */
		h->surf_fn = NULL;
		break;
	}
	h->t = c->t;
	h->p = p;
}

/*
 * The lazy part of accel_finish(): u, v and mp of a sphere in the default frame
 * (from the unit normal accel_finish() stored) or of a triangle (from the
 * barycentrics), in the group's space the hit was finished in, with
 * exactly the arithmetic an eager accel_finish() would use.
 */
static void surface_complete(const struct scene *s, struct hit *h)
{
	if (!h->surf_fn)
		return;
	if (h->surf_kind == SURF_XPRIM) { /* geom_surface's mapping at the object-space point */
		vec3 n;
		geom_surface(h->surf, h->mp, (int)h->surf_idx, &n, &h->u, &h->v);
	} else if (h->surf_kind == SURF_SPHERE) {
		/* the default frame: P = +y, E = +x, W = P x E = -z (as geom_surface) */
		const struct prim_sphere *ps = &scene_full_at(s, h->object)->u.sphere;
		vec3 q = h->n;
		double phi = xm_atan2(-q.z, q.x);
		if (phi < 0)
			phi += 2 * M_PI;
		h->u = ps->radius * (phi >= 2 * M_PI ? 0 : phi);
		h->v = ps->radius * (xm_asin(q.y > 1 ? 1 : q.y < -1 ? -1 : q.y) + M_PI / 2);
		h->mp = h->p;
	} else {
		const struct gmesh *m = h->surf;
		const uint32_t *ix = tri_ix(m, h->surf_idx);
		double b1 = h->surf_b1, b2 = h->surf_b2;
		double w0 = 1 - b1 - b2;
		vec3 oa = m->ov[ix[0]], ob = m->ov[ix[1]], oc = m->ov[ix[2]];
		h->mp = v3_add(v3_add(v3_scale(oa, w0), v3_scale(ob, b1)), v3_scale(oc, b2));
		if (m->ov == m->v) { /* untransformed: geom_tri_uv's normal is the face normal, computed alike */
			vec3 fn = m->fn ? *m->fn : tri_normal(m, ix);
			geom_tri_uv_n(oa, ob, fn, h->mp, &h->u, &h->v);
		} else {
			geom_tri_uv(oa, ob, oc, h->mp, &h->u, &h->v);
		}
	}
	h->surf_fn = NULL;
}

/* hit.surf_fn of a hit awaiting its u, v (and mp) (accel_hit_surface). */
static void surface_cb(const struct accel *a, struct hit *h) { surface_complete(a->s, h); }

/* The unbounded references of g (planes and the like), tested for every
 * ray. Same contract as ref_test. */
__attribute__((noinline)) bool accel_unb_hit(const struct accel *A, const struct group *g, struct trace *r,
					     struct cand *best, bool brute)
{
	bool found = false;
	for (uint32_t k = 0; k < g->n_unb; k++) {
		if (cancel_poll_every(k)) /* CANCELLATION: the list may be long */
			return found;
		uint32_t ref = g->unb[k];
		const struct geom_obj *go = REF_KIND(ref) == REF_XPRIM ? g->xp[REF_IDX(ref)].g : NULL;
		if (go && go->kind == PRIM_PLANE && !go->has_xform) { /* geom_intersect's plane test, inline */
			double t;
			if (geom_plane_t(go->u.pl.pos, go->u.pl.n, r->o, r->d, &t) && t > r->tmin && t < r->tmax &&
			    cand_better(best, ref, t)) {
				cand_take(best, r, ref, t);
				best->part = GEOM_PART_MAIN;
				found = true;
			}
			continue;
		}
		found |= ref_test(A, g, ref, r, best, brute);
	}
	return found;
}

/* Every bounded primitive of g, kind by kind, without the tree (the
 * reference for tests). Same contract as ref_test. */
static __attribute__((noinline)) bool brute_hit(const struct accel *A, const struct group *g, struct trace *r,
						struct cand *best)
{
	bool found = false;
	for (uint32_t k = 0; k < g->n_sph; k++) {
		double t;
		if (sphere_test(&g->sph[k], r, &t) && cand_better(best, REF_MAKE(REF_SPHERE, k), t)) {
			cand_take(best, r, REF_MAKE(REF_SPHERE, k), t);
			found = true;
		}
	}
	for (uint32_t k = 0; k < g->n_tri;) { /* a mesh's triangles are consecutive */
		const struct gmesh *m = &g->mesh[g->tri[k].mesh];
		uint32_t mi = g->tri[k].mesh;
		for (; k < g->n_tri && g->tri[k].mesh == mi; k++) {
			const uint32_t *ix = tri_ix(m, g->tri[k].tri);
			double t, b1, b2;
			if (!tri_flat_behind(g, k, r, &m->v[ix[0]]) && /* FLAT TRIANGLES: part of the test */
			    geom_tri_hit(trace_wray(r), m->v[ix[0]], m->v[ix[1]], m->v[ix[2]], r->tmin, r->tmax, &t, &b1, &b2) &&
			    cand_better(best, REF_MAKE(REF_TRI, k), t)) {
				cand_take(best, r, REF_MAKE(REF_TRI, k), t);
				best->b1 = b1;
				best->b2 = b2;
				found = true;
			}
		}
	}
	for (uint32_t k = 0; k < g->n_refs; k++)
		if (REF_KIND(group_ref(g, k)) >= REF_XPRIM) {
			r->last_x = UINT32_MAX; /* every test made: the reference the MAILBOX is checked against */
			found |= ref_test(A, g, group_ref(g, k), r, best, true);
		}
	return found;
}

/* ---- single-ray traversals ---------------------------------------------------------- */

/* bvh_hit (accel_hit.h) with SSE node tests */
#define BVH_HIT bvh_hit
#define BVH_ATTR
#define BVH_Q struct ray4
#define BVH_SPAN tspan
#define BVH_SPAN_OF tspan_of
#define BVH_NODE(nodes8, nodes, idx, q, oct, tmin, tmax, tn, m, ci, cn)                                          \
	do {                                                                                                    \
		if (nodes8) {                                                                                   \
			const struct bvh8 *nd_ = &(nodes8)[idx];                                                \
			(m) = node8_hit(nd_, q, oct, tmin, tmax, tn);                                           \
			(ci) = nd_->idx, (cn) = nd_->n;                                                         \
		} else {                                                                                        \
			const struct bvh4 *nd_ = &(nodes)[idx];                                                 \
			(m) = node4_hit(nd_, q, oct, tmin, tmax, tn);                                           \
			(ci) = nd_->idx, (cn) = nd_->n;                                                         \
		}                                                                                               \
	} while (0)
#include "common/accel_hit.h"

#if ACCEL_AVX2
/* bvh_hit (accel_hit.h) with AVX2 node tests, on WIDE NODES only */
#define BVH_HIT bvh_hit_avx2
#define BVH_ATTR __attribute__((target("avx2")))
#define BVH_Q struct ray8
#define BVH_SPAN __m256
#define BVH_SPAN_OF span8_of
#define BVH_NODE(nodes8, nodes, idx, q, oct, tmin, tmax, tn, m, ci, cn)                                          \
	do {                                                                                                    \
		const struct bvh8 *nd_ = &(nodes8)[idx];                                                        \
		(void)(nodes);                                                                                  \
		(m) = node8_hit_avx2(nd_, q, oct, tmin, tmax, tn);                                              \
		(ci) = nd_->idx, (cn) = nd_->n;                                                                 \
	} while (0)
#include "common/accel_hit.h"

/* group_hit's tree walk in AVX2 (g->bvh.nodes8, no big leaves): one copy
 * of the loop per octant, as the SSE one; a call of its own, since a
 * function compiled for AVX2 cannot be inlined into one that is not. */
static __attribute__((noinline, target("avx2"))) bool bvh_octants_avx2(const struct accel *A, const struct group *g,
									struct trace *r, struct cand *best)
{
	struct ray8 q8;
	ray8_init(&q8, r, g->center);
	switch (q8.oct) {
	case 0: return bvh_hit_avx2(A, g, r, best, &q8, 0, false);
	case 1: return bvh_hit_avx2(A, g, r, best, &q8, 1, false);
	case 2: return bvh_hit_avx2(A, g, r, best, &q8, 2, false);
	case 3: return bvh_hit_avx2(A, g, r, best, &q8, 3, false);
	case 4: return bvh_hit_avx2(A, g, r, best, &q8, 4, false);
	case 5: return bvh_hit_avx2(A, g, r, best, &q8, 5, false);
	case 6: return bvh_hit_avx2(A, g, r, best, &q8, 6, false);
	default: return bvh_hit_avx2(A, g, r, best, &q8, 7, false);
	}
}
#endif

/* bvh_hit through a tree with big leaves: one copy for every octant (such
 * trees come only from the builder's depth limit). */
static __attribute__((noinline)) bool bvh_hit_chunked(const struct accel *A, const struct group *g,
						       struct trace *r, struct cand *best)
{
	struct ray4 q4;
	ray4_init(&q4, r, g->center);
	return bvh_hit(A, g, r, best, &q4, q4.oct, true);
}


/* Closest hit in group g; fills *h (group space) only on success. */
static bool group_hit(const struct accel *A, const struct group *g, struct trace *r, struct hit *h, bool brute)
{
	struct cand best;
	cand_init(&best);
	bool found = group_hit_unbounded(A, g, r, &best, brute);
	if (brute) {
		found |= brute_hit(A, g, r, &best);
	} else if (g->bvh.root_n) { /* the root is one leaf */
		if (box_hit(g->bvh.root_b, g->center, r))
			for (uint32_t k = 0; k < g->bvh.root_n; k++)
				found |= ref_test(A, g, group_ref(g, g->bvh.root_idx + k), r, &best, false);
	} else if (__builtin_expect(g->big_leaf, 0)) {
		found |= bvh_hit_chunked(A, g, r, &best);
#if ACCEL_AVX2
	} else if (A->avx2 && g->bvh.nodes8) {
		found |= bvh_octants_avx2(A, g, r, &best);
#endif
	} else if (g->bvh.n_nodes4) {
		struct ray4 q4;
		ray4_init(&q4, r, g->center);
		switch (q4.oct) { /* one copy of the loop per octant: near planes at fixed offsets */
		case 0: found |= bvh_hit(A, g, r, &best, &q4, 0, false); break;
		case 1: found |= bvh_hit(A, g, r, &best, &q4, 1, false); break;
		case 2: found |= bvh_hit(A, g, r, &best, &q4, 2, false); break;
		case 3: found |= bvh_hit(A, g, r, &best, &q4, 3, false); break;
		case 4: found |= bvh_hit(A, g, r, &best, &q4, 4, false); break;
		case 5: found |= bvh_hit(A, g, r, &best, &q4, 5, false); break;
		case 6: found |= bvh_hit(A, g, r, &best, &q4, 6, false); break;
		default: found |= bvh_hit(A, g, r, &best, &q4, 7, false); break;
		}
	}
	if (found)
		accel_finish(A, g, r, &best, h);
	return found;
}

/* accel_occluded's query in group g; chunked: g's tree has big leaves,
 * tested ACCEL_LEAF_CHUNK references at a time (CANCELLATION; a constant
 * in each copy, since checking leaves' sizes in the common copy cost 1.5%
 * of a whole render). */
static inline __attribute__((always_inline)) bool group_occluded_t(const struct accel *A, const struct group *g,
								    struct trace *r, const bool chunked, uint32_t *who)
{
	if (unb_any_occludes(A, g, r, who))
		return true;
	if (g->bvh.root_n) {
		if (box_hit(g->bvh.root_b, g->center, r))
			for (uint32_t k = 0; k < g->bvh.root_n; k++)
				if (ref_occludes(A, g, group_ref(g, g->bvh.root_idx + k), r)) {
					*who = group_ref(g, g->bvh.root_idx + k);
					return true;
				}
		return false;
	}
	if (!g->bvh.n_nodes4)
		return false;
	const struct bvh4 *nodes = g->bvh.nodes;
	struct ray4 q;
	ray4_init(&q, r, g->center);
	const tspan tmin = tspan_of(box_tmin(r->tmin * q.tscale)), tmax = tspan_of(box_tmax(r->tmax * q.tscale));
	struct {
		uint32_t idx, n;
	} stack[7 * BVH_MAX_DEPTH + 8]; /* as bvh_hit's */
	int sp = 0;
	uint32_t idx = 0, n = 0;
	uint32_t polls = ACCEL_POLL_POPS;
	struct tri1 q1; /* TRIANGLE PRE-TEST, set up at the first block */
	bool q1_ready = false;
	const struct bvh8 *nodes8 = g->bvh.nodes8; /* WIDE NODES: used when there */
	for (;;) {
		if (n & LEAF_BLOCK) {
			uint32_t ref = block_occluded(g, &g->tblk[idx], n & ~LEAF_BLOCK, r, &q1, &q1_ready);
			if (ref != ACCEL_NO_HINT) {
				*who = ref;
				return true;
			}
		} else if (n) {
			if (chunked && n > ACCEL_LEAF_CHUNK) { /* CANCELLATION, as bvh_hit */
				stack[sp].idx = idx + ACCEL_LEAF_CHUNK;
				stack[sp++].n = n - ACCEL_LEAF_CHUNK;
				n = ACCEL_LEAF_CHUNK;
			}
			for (uint32_t k = 0; k < n; k++)
				if (ref_occludes(A, g, group_ref(g, idx + k), r)) {
					*who = group_ref(g, idx + k);
					return true;
				}
		} else {
			float tn[8];
			int m;
			const uint32_t *ci, *cn; /* the node's idx[] and n[] */
			if (nodes8) {
				const struct bvh8 *nd = &nodes8[idx];
				m = node8_hit(nd, &q, q.oct, tmin, tmax, tn);
				ci = nd->idx, cn = nd->n;
			} else {
				const struct bvh4 *nd = &nodes[idx];
				m = node4_hit(nd, &q, q.oct, tmin, tmax, tn);
				ci = nd->idx, cn = nd->n;
			}
			if (m) { /* the first child in slot order; the others pushed last first */
				int c = __builtin_ctz((unsigned)m);
				for (unsigned mm = (unsigned)m & ((unsigned)m - 1); mm;) {
					int j = 31 - __builtin_clz(mm);
					mm ^= 1u << j;
					stack[sp].idx = ci[j];
					stack[sp++].n = cn[j];
				}
				idx = ci[c];
				n = cn[c];
				continue;
			}
		}
		if (__builtin_expect(--polls == 0, 0)) { /* CANCELLATION, as bvh_hit */
			polls = ACCEL_POLL_POPS;
			if (cancel_poll())
				return false;
		}
		if (sp == 0)
			return false;
		sp--;
		idx = stack[sp].idx;
		n = stack[sp].n;
	}
}

/* Whether anything in g is hit in (r->tmin, r->tmax): group_occluded_t in
 * the copy g's leaves need; on true *who is the reference of g that was hit. */
static bool group_occluded_who(const struct accel *A, const struct group *g, struct trace *r, uint32_t *who)
{
	return g->big_leaf ? group_occluded_t(A, g, r, true, who) : group_occluded_t(A, g, r, false, who);
}

static bool group_occluded(const struct accel *A, const struct group *g, struct trace *r)
{
	uint32_t who;
	return group_occluded_who(A, g, r, &who);
}


/* ---- public queries ----------------------------------------------------------------- */

bool accel_intersect(const struct accel *a, const struct ray *r, struct hit *h)
{
	if (!a->root || !ray_ok(r))
		return false;
	struct trace t;
	trace_init(&t, r->o, r->d, ray_tmin(r), r->tmax);
	return group_hit(a, a->root, &t, h, false);
}

bool accel_intersect_brute(const struct accel *a, const struct ray *r, struct hit *h)
{
	if (!a->root || !ray_ok(r))
		return false;
	struct trace t;
	trace_init(&t, r->o, r->d, ray_tmin(r), r->tmax);
	return group_hit(a, a->root, &t, h, true);
}

bool accel_occluded(const struct accel *a, const struct ray *r)
{
	if (!a->root || !ray_ok(r))
		return false;
	struct trace t;
	trace_init(&t, r->o, r->d, ray_tmin(r), r->tmax);
	return group_occluded(a, a->root, &t);
}

bool accel_occluded_hint(const struct accel *a, const struct ray *r, uint32_t *hint)
{
	if (!a->root || !ray_ok(r))
		return false;
	struct trace t;
	trace_init(&t, r->o, r->d, ray_tmin(r), r->tmax);
	if (hint_occludes(a, a->root, *hint, &t))
		return true;
	if (group_occluded_who(a, a->root, &t, hint))
		return true;
	*hint = ACCEL_NO_HINT; /* a lit neighbour is likely lit too: no test next time */
	return false;
}

/* ref_occludes for the light buffer's loops, with the sphere's and the
 * triangle's tests inline: a call there made its caller (the shading, into
 * which the query is inlined) save and restore its registers around every
 * test. */
static inline __attribute__((always_inline)) bool lbuf_ref_occludes(const struct accel *a, const struct group *g,
								     uint32_t ref, struct trace *t)
{
	double tt;
	switch (REF_KIND(ref)) {
	case REF_SPHERE: return sphere_test_with(&g->sph[REF_IDX(ref)], t, &tt, true); /* sphere_test, inline */
	case REF_TRI: return tri_occludes(g, ref, t);
	default: return ref_occludes(a, g, ref, t);
	}
}

/* The LIGHT BUFFER query (accel_int.h, accel_light.c): after the hint and
 * the unbounded references, the entries of the cell of u = o - lp = -d up
 * to the ray's depth |u_a|; the tree when the ray is not one toward the
 * light (d = lp - o, t within [0, 1]) or starts beyond the buffer's R. */
bool accel_occluded_light(const struct accel *a, uint32_t light, const struct ray *r, uint32_t *hint)
{
	const struct lbuf *lb = a->lbuf && light < a->s->n_lights ? a->lbuf[light] : NULL;
	if (!lb || !a->root || !ray_ok(r))
		return accel_occluded_hint(a, r, hint);
	vec3 d = v3_sub(lb->lp, r->o);
	double ux = -r->d.x, uy = -r->d.y, uz = -r->d.z;
	double ax = fabs(ux), ay = fabs(uy), az = fabs(uz);
	double depth = geom_fmax(ax, geom_fmax(ay, az)); /* fmax, inline */
	if (!(r->tmax <= 1) || d.x != r->d.x || d.y != r->d.y || d.z != r->d.z || !(depth <= lb->R))
		return accel_occluded_hint(a, r, hint); /* not a ray the buffer answers for */
	struct trace t;
	trace_init(&t, r->o, r->d, ray_tmin(r), r->tmax);
	const struct group *g = a->root;
	uint32_t face;
	double p, q;
	if (ax >= ay && ax >= az)
		face = ux < 0, p = uy / ax, q = uz / ax;
	else if (ay >= az)
		face = 2 + (uy < 0), p = ux / ay, q = uz / ay;
	else
		face = 4 + (uz < 0), p = ux / az, q = uy / az;
	uint32_t cell = (face * lb->n + lbuf_cell(lb, face, 1, q)) * lb->n + lbuf_cell(lb, face, 0, p);
	__builtin_prefetch(&lb->start[cell]); /* its load waits on memory: under the hint's test */
	/* the hint as hint_occludes tests it, its sphere or triangle inline */
	if ((*hint != ACCEL_NO_HINT && ref_valid(g, *hint) && lbuf_ref_occludes(a, g, *hint, &t)) ||
	    unb_any_occludes(a, g, &t, hint))
		return true;
	/* FLAT NEAR: the flat triangles first, each decided by its plane
	 * (tri_occludes' first test) unless the ray may reach it; none from an
	 * origin in the box where every one is behind (accel_light.c) */
	const vec3 o = t.o, flo = lb->flat_lo, fhi = lb->flat_hi;
	bool all_behind = o.x >= flo.x && o.x <= fhi.x && o.y >= flo.y && o.y <= fhi.y && o.z >= flo.z && o.z <= fhi.z;
	for (uint32_t k = 0; k < (all_behind ? 0 : lb->n_near_flat); k++) {
		if (cancel_poll_every(k)) /* CANCELLATION, as a leaf's references */
			return false;
		const struct lbuf_near *nr = &lb->near[k];
		if (__builtin_expect(!flat_behind(nr->flat, nr->c, &t), 0) && tri_occludes(g, nr->ref, &t)) {
			*hint = nr->ref;
			return true;
		}
	}
	for (uint32_t k = lb->n_near_flat; k < lb->n_near; k++) {
		if (cancel_poll_every(k))
			return false;
		if (lbuf_ref_occludes(a, g, lb->near[k].ref, &t)) {
			*hint = lb->near[k].ref;
			return true;
		}
	}
	const struct lbuf_ent *e = lb->ent + lb->start[cell], *end = lb->ent + lb->start[cell + 1];
	double lim = depth * (1 + 1e-9);
	for (uint32_t k = 0; e < end && e->dmin <= lim; e++, k++) {
		if (cancel_poll_every(k)) /* CANCELLATION, as a leaf's references */
			return false;
		if (lbuf_ref_occludes(a, g, e->ref, &t)) {
			*hint = e->ref;
			return true;
		}
	}
	*hint = ACCEL_NO_HINT;
	return false;
}

bool accel_light_buffered(const struct accel *a, uint32_t light)
{
	return a->lbuf && a->root && light < a->s->n_lights && a->lbuf[light];
}

bool accel_use_avx2(void)
{
#if ACCEL_AVX2
	const char *e = getenv("PORTRAY_SIMD");
	if (e && strcmp(e, "sse2") == 0)
		return false;
	return __builtin_cpu_supports("avx2");
#else
	return false;
#endif
}

void accel_get_stats(const struct accel *a, struct accel_stats *st) { *st = a->st; }

bool accel_bounds(const struct accel *a, vec3 *lo, vec3 *hi)
{
	if (!a->root || a->root->n_refs == 0)
		return false;
	*lo = a->root->bounds.lo;
	*hi = a->root->bounds.hi;
	return true;
}
