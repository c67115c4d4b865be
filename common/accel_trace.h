/*
 * accel_trace.h - what the two families of ray queries share: accel.c
 * (one ray at a time) and accel_packet.c (packets of four rays). A ray's
 * trace state and its set-up, the candidate hit and CANONICAL TIES, the
 * primitive tests (spheres, triangles, any reference), the TRIANGLE
 * PRE-TEST against LEAF BLOCKS, the unbounded references and the
 * last-blocker hint, and the accel_ functions one file calls in the other.
 * Private to those two files, like accel_int.h (nothing else includes it);
 * the design is described at the top of accel.c. The pieces are static
 * inline, each file with its own copy: the traversal loops inline them.
 */
#ifndef PORTRAY_ACCEL_TRACE_H
#define PORTRAY_ACCEL_TRACE_H

#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "common/accel_int.h"
#include "common/cancel.h"

/* Subtrees a traversal pops between polls of the cancel flag: each pop
 * follows a leaf (at most ACCEL_LEAF_CHUNK references, instances polling
 * on their own) or a node none of whose children is hit, after at most
 * BVH_MAX_DEPTH nodes with one child hit; 1024 of them are well under a
 * millisecond on any leaf but a CSG, and CSG polls by itself. */
#define ACCEL_POLL_POPS 1024u

/* ---- a ray's trace state ----------------------------------------------------------- */

struct trace {
	vec3 o, d;
	double inv_dd; /* 1 / |d|^2 */
	double tmin, tmax;
	bool w_ready;  /* w is set up (on the first triangle test) */
	uint32_t last_x; /* the xprim reference tested last (MAILBOX), or UINT32_MAX */
	struct geom_wray w;
};

/* The watertight test's ray set-up, made when a triangle is first tested. */
static inline const struct geom_wray *trace_wray(struct trace *r)
{
	if (!r->w_ready) {
		geom_wray_init(&r->w, r->o, r->d);
		r->w_ready = true;
	}
	return &r->w;
}

static inline void trace_init(struct trace *r, vec3 o, vec3 d, double tmin, double tmax)
{
	r->o = o;
	r->d = d;
	double a = v3_dot(d, d);
	r->inv_dd = a > 0 ? 1.0 / a : 0;
	r->w_ready = false;
	r->last_x = UINT32_MAX;
	r->tmin = tmin;
	r->tmax = tmax;
}

/* Bit k set when direction component k has its sign bit set (-0 too):
 * the sign of 1 / (d[k] * s) or of copysign(1e30, d[k]) alike. */
static inline uint32_t ray_octant(vec3 d)
{
	return (signbit(d.x) ? 1u : 0u) | (signbit(d.y) ? 2u : 0u) | (signbit(d.z) ? 4u : 0u);
}

/* Finite origin and direction, non-zero direction, tmin < tmax (false when
 * either is NaN). x - x is 0 for a finite x and NaN for an infinite or NaN
 * one, so one sum tests all six components. */
static inline bool ray_ok(const struct ray *r)
{
	double z = ((r->o.x - r->o.x) + (r->o.y - r->o.y)) + ((r->o.z - r->o.z) + (r->d.x - r->d.x)) +
		   ((r->d.y - r->d.y) + (r->d.z - r->d.z));
	return z == 0 && v3_dot(r->d, r->d) > 0 && r->tmin < r->tmax;
}

/* The ray's tmin, 0 when negative: rays are half-lines (the box tests
 * rely on tmin >= 0). */
static inline double ray_tmin(const struct ray *r) { return r->tmin > 0 ? r->tmin : 0; }

/* ---- candidates -------------------------------------------------------------------- */

struct cand {
	uint32_t ref;
	uint32_t key; /* rank among hits at equal t (CANONICAL TIES) */
	double t, b1, b2;
	int part;
	struct hit sub; /* instances and CSG: the finished hit in the group's space */
};

/*
 * CANONICAL TIES. The closest hit is the least (t, key) pair: at equal t the
 * lower key wins. A reference's key is the reference itself (kind, then
 * index: the order written), except an instance's, which is made of its
 * record's index in scene.insts (in the order of the instances' object
 * indices), since a packed group numbers its instances in leaf order. So the hit never depends on the order in which
 * references are tested, and a traversal may visit the tree in any order
 * (packets, accel_intersect4) and still give every ray the same hit bit for
 * bit. Primitive tests accept t < r->tmax and report a primitive's first
 * hit after tmin whatever tmax is; after a hit at t, r->tmax is the next
 * double above t, so a later hit at the same t still reaches cand_take,
 * which keeps the lower reference.
 */
static inline void cand_init(struct cand *c)
{
	c->ref = c->key = UINT32_MAX;
	c->t = INFINITY;
}

/* The next double above t > 0 (finite): t's bits plus one. */
static inline double next_up(double t)
{
	uint64_t bits;
	memcpy(&bits, &t, sizeof bits);
	bits++;
	memcpy(&t, &bits, sizeof t);
	return t;
}

/* Whether a hit of key at t beats *c (canonical ties). */
static inline bool cand_better(const struct cand *c, uint32_t key, double t)
{
	return t < c->t || (t == c->t && key < c->key);
}

/* Records a hit of ref (of key) at t that beats *c and narrows r to admit
 * its ties. */
static inline void cand_take_key(struct cand *c, struct trace *r, uint32_t ref, uint32_t key, double t)
{
	c->ref = ref;
	c->key = key;
	c->t = t;
	r->tmax = next_up(t);
}

/* The same for a reference whose key is itself (all but instances). */
static inline void cand_take(struct cand *c, struct trace *r, uint32_t ref, double t)
{
	cand_take_key(c, r, ref, ref, t);
}

/* Defined in accel.c, called from both files: accel_xprim_test and
 * accel_ref_test_slow are ref_test's rarer kinds, kept out of the traversal
 * loops; accel_xprim_occludes and accel_inst_occluded are ref_occludes'
 * xprims and instances, accel_unb_hit
 * group_hit_unbounded's list; accel_finish completes the closest hit
 * (group_hit, group_hit4). */
bool accel_xprim_test(const struct xprim *x, uint32_t ref, struct trace *r, struct cand *c);
bool accel_xprim_occludes(const struct xprim *x, const struct trace *r);
bool accel_ref_test_slow(const struct accel *A, const struct group *g, uint32_t ref, struct trace *r,
			 struct cand *c, bool brute);
bool accel_inst_occluded(const struct accel *A, const struct ginst *in, const struct trace *r);
/* The parent-space hit h (but h->p and h->surf_fn) of hit lh (completed
 * here) in the define's group of instance si, whose inverse is inv. */
void accel_inst_to_parent(const struct accel *A, const struct scene_inst *si, const mat34 *inv, struct hit *lh,
			  struct hit *h);
bool accel_unb_hit(const struct accel *A, const struct group *g, struct trace *r, struct cand *best,
		   bool brute);
void accel_finish(const struct accel *A, const struct group *g, const struct trace *r, const struct cand *c,
		  struct hit *h);

/* ---- primitive tests -------------------------------------------------------------- */

/*
 * AWAY: a ray that starts outside (or on) a sphere and moves away from its
 * centre (c >= 0, tc < 0) has both roots at t <= 0, as they are computed
 * here: q = tc - hh < 0 (the rounded difference is at most tc), and the
 * other root c inv_dd / q <= 0 (or NaN, which fails every comparison). For
 * tmin >= 0 that is a miss, found without the root and the division. It is
 * the test of the sphere a secondary or shadow ray leaves (balls_s4: 2.44 M
 * of 7.31 M sphere tests a frame). The same for a cylinder's tube: geom_cyl_open_hit. Without
 * away, the test as it was before (tests/unit/test_away.c compares them).
 */
static inline __attribute__((always_inline)) bool sphere_test_with(const struct gsphere *sp, const struct trace *r,
								    double *t, const bool away)
{
	vec3 oc = v3_sub(r->o, sp->c);
	double b = v3_dot(oc, r->d);
	double tc = -b * r->inv_dd;
	double c = v3_dot(oc, oc) - sp->r2;
	if (away && tc < 0 && c >= 0 && r->tmin >= 0) /* AWAY */
		return false;
	vec3 f = v3_add(oc, v3_scale(r->d, tc));
	double h2 = (sp->r2 - v3_dot(f, f)) * r->inv_dd;
	if (h2 < 0)
		return false;
	double hh = sqrt(h2);
	double q = tc + (tc >= 0 ? hh : -hh);
	double other = q != 0 ? c * r->inv_dd / q : 0;
	double t0 = q < other ? q : other, t1 = q < other ? other : q;
	if (t0 > r->tmin && t0 < r->tmax) {
		*t = t0;
		return true;
	}
	if (t1 > r->tmin && t1 < r->tmax) {
		*t = t1;
		return true;
	}
	return false;
}

static inline bool sphere_test(const struct gsphere *sp, const struct trace *r, double *t)
{
	return sphere_test_with(sp, r, t, true);
}

/* Bounded reference k (in leaf order) of g. */
static inline uint32_t group_ref(const struct group *g, uint32_t k)
{
	return g->refs ? g->refs[k] : REF_MAKE(REF_INST, k);
}

/*
 * FLAT TRIANGLES. A triangle whose three vertices share their coordinate
 * c on axis p bit for bit (g->tri_flat: floors, walls, the faces of
 * boxes) lies in the plane x_p = c exactly. A ray o + t d, t > tmin >= 0,
 * whose origin is on one side (o_p > c) and which does not move toward
 * the plane (d_p >= 0), or which starts in it and leaves it (o_p = c,
 * d_p != 0), never meets that plane at a t the test accepts: that is
 * decided here by exact comparisons of the doubles o_p, d_p and c, with
 * no rounding, and the watertight test is not run. It is the triangle a
 * shadow or secondary ray leaves, and any other in its plane (balls_s4's
 * and rings_s3's floors: most of their exact triangle tests), and the
 * floor under every shadow ray from above it.
 *
 * Where the watertight test runs it would say no hit too, but for
 * rounding: where the ray's dominant axis kz is p (a ray steeper than 45
 * degrees to the plane) its Az, Bz and Cz are one double and its T a sum
 * of terms of one sign, so it agrees bit for bit (docs/rendering.md,
 * "Acne"); for a shallower ray its edge functions are rounded from
 * coordinates far larger than the ray's distance from the plane, and a
 * hit it reported here would be a point the ray does not reach (a speck
 * of acne). Such rays skip the test since RENDER_PIXEL_REV 5
 * (docs/performance.md, round 19).
 */
static inline __attribute__((always_inline)) bool flat_behind(uint32_t p, double c, const struct trace *r)
{
	if (p > 2 || !(r->tmin >= 0))
		return false;
	double op = geom_comp(&r->o, (int)p), dp = geom_comp(&r->d, (int)p);
	if (op > c)
		return dp >= 0;
	if (op < c)
		return dp <= 0;
	return op == c && (dp > 0 || dp < 0);
}

/* flat_behind for triangle i of g, whose first vertex is *a */
static inline __attribute__((always_inline)) bool tri_flat_behind(const struct group *g, uint32_t i,
								   const struct trace *r, const vec3 *a)
{
	uint32_t p = g->tri_flat[i];
	return p <= 2 && flat_behind(p, geom_comp(a, (int)p), r);
}

/* ref_test of triangle reference ref. */
static inline __attribute__((always_inline)) bool tri_test(const struct group *g, uint32_t ref, struct trace *r,
							    struct cand *c)
{
	const struct gtri *gt = &g->tri[REF_IDX(ref)];
	const struct gmesh *m = &g->mesh[gt->mesh];
	const uint32_t *ix = tri_ix(m, gt->tri);
	double t, b1, b2;
	if (tri_flat_behind(g, REF_IDX(ref), r, &m->v[ix[0]]) ||
	    !geom_tri_hit_p(trace_wray(r), &m->v[ix[0]], &m->v[ix[1]], &m->v[ix[2]], r->tmin, r->tmax, &t, &b1,
			    &b2) ||
	    !cand_better(c, ref, t))
		return false;
	c->b1 = b1;
	c->b2 = b2;
	cand_take(c, r, ref, t);
	return true;
}

/* ref_occludes of triangle reference ref. */
static inline __attribute__((always_inline)) bool tri_occludes(const struct group *g, uint32_t ref,
								struct trace *r)
{
	const struct gtri *gt = &g->tri[REF_IDX(ref)];
	const struct gmesh *m = &g->mesh[gt->mesh];
	const uint32_t *ix = tri_ix(m, gt->tri);
	double t, b1, b2;
	return !tri_flat_behind(g, REF_IDX(ref), r, &m->v[ix[0]]) &&
	       geom_tri_hit_p(trace_wray(r), &m->v[ix[0]], &m->v[ix[1]], &m->v[ix[2]], r->tmin, r->tmax, &t, &b1,
			      &b2);
}

/*
 * MAILBOX. A long cylinder is referenced by the boxes of its slices
 * (LONG CYLINDERS, accel_build.c), so a ray that meets two of them tests
 * it twice; the trace keeps the xprim reference it tested last (tests of
 * other kinds between do not clear it), and a test of that reference again
 * is skipped. That changes no answer, for any repeat within a query:
 *   - closest hit: a reference's test reports its first hit after tmin if
 *     it is below tmax, whatever tmax is, and during one query tmin stays
 *     and tmax only falls. So the second test would miss (the first hit
 *     was at or past the old tmax, or there was none) or find the same t,
 *     which the first test then took or found beaten, and which does not
 *     beat itself (CANONICAL TIES);
 *   - any hit: the first test missed, or the query would have ended, and
 *     tmax is fixed.
 * rings_s3: 620,708 of 7.8 M cylinder tests a frame (docs/performance.md,
 * round 14). Only xprims: spheres and triangles have one box each but for
 * split slivers, whose tests in blocks have no room for the check.
 * SHADOW CROSSINGS skip a repeat too: their first test of a reference took
 * every crossing it has on the segment (accel_cross_ref).
 */
static inline bool mailbox_seen(struct trace *r, uint32_t ref)
{
	if (r->last_x == ref)
		return true;
	r->last_x = ref;
	return false;
}

/* Tests one reference; on a hit in (r->tmin, r->tmax) that beats *c
 * (CANONICAL TIES) records it in *c and narrows r->tmax. */
static inline __attribute__((always_inline)) bool ref_test(const struct accel *A, const struct group *g,
							    uint32_t ref, struct trace *r, struct cand *c, bool brute)
{
	uint32_t i = REF_IDX(ref);
	double t;
	switch (REF_KIND(ref)) {
	case REF_SPHERE:
		if (!sphere_test(&g->sph[i], r, &t) || !cand_better(c, ref, t))
			return false;
		break;
	case REF_TRI:
		return tri_test(g, ref, r, c);
	case REF_XPRIM: {
		const struct xprim *x = &g->xp[i];
		if (mailbox_seen(r, ref))
			return false;
		if (x->r > 0 || x->g->kind != PRIM_CSG) /* OPEN CYLINDERS read no geom_obj */
			return accel_xprim_test(x, ref, r, c);
		return accel_ref_test_slow(A, g, ref, r, c, brute);
	}
	default:
		return accel_ref_test_slow(A, g, ref, r, c, brute);
	}
	cand_take(c, r, ref, t);
	return true;
}

/* Any hit in (tmin, tmax) of one reference. */
static inline bool ref_occludes(const struct accel *A, const struct group *g, uint32_t ref, struct trace *r)
{
	uint32_t i = REF_IDX(ref);
	double t;
	switch (REF_KIND(ref)) { /* the common kinds without a candidate */
	case REF_SPHERE:
		return sphere_test(&g->sph[i], r, &t);
	case REF_TRI:
		return tri_occludes(g, ref, r);
	case REF_INST:
		return accel_inst_occluded(A, &g->inst[i], r);
	default: { /* an xprim: accel_xprim_test's answer without a candidate, but CSG */
		const struct xprim *x = &g->xp[i];
		if (x->r <= 0 && x->g->kind == PRIM_CSG) /* OPEN CYLINDERS read no geom_obj */
			break; /* (ref_test's mailbox below) */
		if (mailbox_seen(r, ref))
			return false;
		return accel_xprim_occludes(x, r);
	}
	}
	struct cand c;
	cand_init(&c);
	double tmax = r->tmax;
	bool hit = ref_test(A, g, ref, r, &c, false);
	r->tmax = tmax;
	return hit;
}

/* Whether r meets g's one ground plane (g->plane1) in (tmin, tmax), at
 * *t: geom_intersect's plane case, the same arithmetic, inline. */
static inline bool plane1_hit(const struct group *g, const struct trace *r, double *t)
{
	const struct geom_obj *go = g->plane1;
	return geom_plane_t(go->u.pl.pos, go->u.pl.n, r->o, r->d, t) && *t > r->tmin && *t < r->tmax;
}

/* The unbounded references of g: the start of every closest-hit query.
 * Same contract as ref_test. */
static inline bool group_hit_unbounded(const struct accel *A, const struct group *g, struct trace *r,
				       struct cand *best, bool brute)
{
	if (g->plane1) { /* accel_unb_hit's plane test, the common case of one ground plane */
		double t;
		if (plane1_hit(g, r, &t) && cand_better(best, g->unb[0], t)) {
			cand_take(best, r, g->unb[0], t);
			best->part = GEOM_PART_MAIN;
			return true;
		}
		return false;
	}
	return g->n_unb ? accel_unb_hit(A, g, r, best, brute) : false;
}

/* ref_occludes of g's unbounded reference k; the one ground plane
 * (g->plane1, then k is 0) tested inline, as group_hit_unbounded tests it. */
static inline bool unb_occludes(const struct accel *A, const struct group *g, uint32_t k, struct trace *r)
{
	double t;
	return g->plane1 ? plane1_hit(g, r, &t) : ref_occludes(A, g, g->unb[k], r);
}

/* Whether one of g's unbounded references blocks r (on true *who names
 * it); false too when the render is cancelled (CANCELLATION, as
 * accel_unb_hit). */
static inline bool unb_any_occludes(const struct accel *A, const struct group *g, struct trace *r, uint32_t *who)
{
	for (uint32_t k = 0; k < g->n_unb; k++) {
		if (cancel_poll_every(k))
			return false;
		if (unb_occludes(A, g, k, r)) {
			*who = g->unb[k];
			return true;
		}
	}
	return false;
}

/* Whether ref names a reference of g (kind and index in range): a hint
 * that does may be tested, whatever accel it came from. */
static inline bool ref_valid(const struct group *g, uint32_t ref)
{
	uint32_t i = REF_IDX(ref);
	switch (REF_KIND(ref)) {
	case REF_SPHERE: return i < g->n_sph;
	case REF_TRI: return i < g->n_tri;
	case REF_XPRIM: return i < g->n_xp;
	default: return ref != ACCEL_NO_HINT && i < g->n_inst;
	}
}

/* The last-blocker hint's test (accel_occluded_hint): true when the
 * reference it names blocks r. */
static inline bool hint_occludes(const struct accel *A, const struct group *g, uint32_t hint, struct trace *r)
{
	return hint != ACCEL_NO_HINT && ref_valid(g, hint) && ref_occludes(A, g, hint, r);
}

/* ---- the triangle pre-test and leaf blocks ------------------------------------------ */

/*
 * TRIANGLE PRE-TEST IN FLOAT. A ray and a triangle are first tested in
 * float: the same edge functions U, V, W as geom_tri_hit_p, from the
 * vertices and the ray's origin rounded to float. The ray is rejected only
 * where two of them have opposite signs by more than a margin that bounds
 * the float result's distance from the double one; the double test then
 * rejects too (its first test), so everything not rejected is tested in
 * double exactly as before and the hits stay bit for bit. The margin: with
 * S the largest magnitude of the nine vertex components and the ray's
 * origin (permuted), each of A, B, C minus the origin is within E1 =
 * 2^-21 S of its double value (the roundings to float and the subtraction:
 * 4 u S, u = 2^-24), the sheared a, b, c (|sx|, |sy| <= 1: kz is the
 * dominant axis) within E2 = 2^-19 S (24 u S), and U = cx by - cy bx within
 * E2 (|bx| + |by| + |cx| + |cy|) + 2 E2^2 + 2u (|cx by| + |cy bx|); the
 * margin is twice that (the margin's own rounding and the double's, ~2^-52
 * relative) plus 2^-120 and floors of 2^-140 in E1 and E2 for subnormal
 * floats. One margin M serves U, V and W: with s the largest of |ax| + |ay|,
 * |bx| + |by| and |cx| + |cy|, each edge's two sums add to at most 2s and
 * its two products' magnitudes to at most s^2, so M = 2 [2 E2 s + 2 E2^2 +
 * 2u s^2] + 2^-120 bounds all three (a wider margin only lets more
 * through), and the test is min(U, V, W) < -M and max(U, V, W) > M. An
 * infinite S makes M infinite or NaN, and a NaN among U, V, W drops out of
 * min and max or makes them NaN: neither can make a rejection that two
 * finite edge functions of opposite signs beyond M would not make, and
 * then the double ones have opposite signs too. Each lane is one ray and
 * one triangle, with its own S, so the
 * same bound holds for both uses of the four lanes:
 *   - one ray against a leaf block's up to four triangles (LEAF BLOCKS,
 *     accel_int.h): single rays, closest and any hit, and the closest-hit
 *     packets' leaves met by one ray;
 *   - one triangle against a packet's four rays (tri4_reject): the
 *     closest-hit packets' leaves, and the any-hit packets' in groups of
 *     mostly triangles.
 * The floats are the same either way: a block holds each vertex component
 * rounded to nearest and the lane's largest magnitude, computed at build
 * time as the packets computed them when they gathered the vertices. The
 * scalar path (no SSE2) makes the same operations, lane by lane, in float
 * (a wider evaluation only makes each error smaller).
 */
#if defined(__SSE2__)
static inline __m128 abs4(__m128 x) { return _mm_andnot_ps(_mm_set1_ps(-0.0f), x); }

/* The lanes (bit l) whose ray certainly misses its triangle: v[3j + k] is
 * component k of vertex j, permuted (kx, ky, kz), sv the largest magnitude
 * of the nine, o* and s* the ray's origin (permuted) and shear, so the
 * largest magnitude of its origin, all in float. */
static inline __attribute__((always_inline)) unsigned tri_reject_ps(const __m128 v[9], __m128 sv, __m128 ox,
								    __m128 oy, __m128 oz, __m128 sx, __m128 sy,
								    __m128 so)
{
	__m128 S = _mm_max_ps(so, sv);
	__m128 Az = _mm_sub_ps(v[2], oz), Bz = _mm_sub_ps(v[5], oz), Cz = _mm_sub_ps(v[8], oz);
	__m128 ax = _mm_sub_ps(_mm_sub_ps(v[0], ox), _mm_mul_ps(sx, Az));
	__m128 ay = _mm_sub_ps(_mm_sub_ps(v[1], oy), _mm_mul_ps(sy, Az));
	__m128 bx = _mm_sub_ps(_mm_sub_ps(v[3], ox), _mm_mul_ps(sx, Bz));
	__m128 by = _mm_sub_ps(_mm_sub_ps(v[4], oy), _mm_mul_ps(sy, Bz));
	__m128 cx = _mm_sub_ps(_mm_sub_ps(v[6], ox), _mm_mul_ps(sx, Cz));
	__m128 cy = _mm_sub_ps(_mm_sub_ps(v[7], oy), _mm_mul_ps(sy, Cz));
	__m128 p1 = _mm_mul_ps(cx, by), p2 = _mm_mul_ps(cy, bx); /* U */
	__m128 p3 = _mm_mul_ps(ax, cy), p4 = _mm_mul_ps(ay, cx); /* V */
	__m128 p5 = _mm_mul_ps(bx, ay), p6 = _mm_mul_ps(by, ax); /* W */
	__m128 U = _mm_sub_ps(p1, p2), V = _mm_sub_ps(p3, p4), W = _mm_sub_ps(p5, p6);
	__m128 E2 = _mm_add_ps(_mm_mul_ps(S, _mm_set1_ps(0x1p-19f)), _mm_set1_ps(0x1p-140f));
	__m128 two_e2 = _mm_add_ps(E2, E2), two_e2sq = _mm_mul_ps(two_e2, E2);
	__m128 Aab = _mm_add_ps(abs4(ax), abs4(ay)), Bab = _mm_add_ps(abs4(bx), abs4(by)),
	       Cab = _mm_add_ps(abs4(cx), abs4(cy));
	/* one margin for U, V and W: with s the largest of the three sums,
	 * s1 + s2 <= 2 s and |p| + |q| <= s1 s2 <= s^2, so
	 * 2 [2 E2 s + 2 E2^2 + 2u s^2] + 2^-120 bounds each edge's margin */
	__m128 sm = _mm_max_ps(_mm_max_ps(Aab, Bab), Cab);
	__m128 M = _mm_add_ps(_mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(two_e2, sm), two_e2sq),
						    _mm_mul_ps(_mm_set1_ps(0x1p-23f), _mm_mul_ps(sm, sm))),
					 _mm_set1_ps(2.0f)),
			      _mm_set1_ps(0x1p-120f));
	/* opposite signs beyond the margin; a NaN drops out of min and max
	 * (the second operand is returned), so it never makes a rejection */
	__m128 lo = _mm_min_ps(_mm_min_ps(U, V), W), hi = _mm_max_ps(_mm_max_ps(U, V), W);
	__m128 neg = _mm_cmplt_ps(lo, _mm_sub_ps(_mm_setzero_ps(), M)), pos = _mm_cmpgt_ps(hi, M);
	return (unsigned)_mm_movemask_ps(_mm_and_ps(neg, pos));
}
#else
/* tri_reject_ps for one lane, operation for operation (max(a, b) is
 * a > b ? a : b, as SSE's). */
static inline bool tri_reject_f(const float v[9], float sv, float ox, float oy, float oz, float sx, float sy,
				float so)
{
	float S = so > sv ? so : sv;
	float Az = v[2] - oz, Bz = v[5] - oz, Cz = v[8] - oz;
	float ax = (v[0] - ox) - sx * Az, ay = (v[1] - oy) - sy * Az;
	float bx = (v[3] - ox) - sx * Bz, by = (v[4] - oy) - sy * Bz;
	float cx = (v[6] - ox) - sx * Cz, cy = (v[7] - oy) - sy * Cz;
	float p1 = cx * by, p2 = cy * bx, p3 = ax * cy, p4 = ay * cx, p5 = bx * ay, p6 = by * ax;
	float U = p1 - p2, V = p3 - p4, W = p5 - p6;
	float E2 = S * 0x1p-19f + 0x1p-140f;
	float two_e2 = E2 + E2, two_e2sq = two_e2 * E2;
	float Aab = fabsf(ax) + fabsf(ay), Bab = fabsf(bx) + fabsf(by), Cab = fabsf(cx) + fabsf(cy);
	float sm = Aab > Bab ? Aab : Bab;
	sm = sm > Cab ? sm : Cab;
	float M = ((two_e2 * sm + two_e2sq) + 0x1p-23f * (sm * sm)) * 2.0f + 0x1p-120f;
	float lo = U < V ? U : V, hi = U > V ? U : V; /* minps and maxps */
	lo = lo < W ? lo : W;
	hi = hi > W ? hi : W;
	bool neg = lo < 0.0f - M, pos = hi > M;
	return neg && pos;
}
#endif

/* One ray's side of the pre-test against leaf blocks. */
struct tri1 {
	int rx, ry, rz; /* kx, ky, kz: vertex a's rows in a block (times its width) */
#if defined(__SSE2__)
	__m128 ox, oy, oz, sx, sy, so; /* broadcast to the four lanes */
#else
	float ox, oy, oz, sx, sy, so;
#endif
};

/* From the ray's watertight set-up w (geom_wray_init's). */
static inline void tri1_init(struct tri1 *q, const struct geom_wray *w)
{
	float ox = (float)w->ox, oy = (float)w->oy, oz = (float)w->oz;
	float m = fabsf(ox) > fabsf(oy) ? fabsf(ox) : fabsf(oy);
	float so = m > fabsf(oz) ? m : fabsf(oz);
	q->rx = w->kx, q->ry = w->ky, q->rz = w->kz;
#if defined(__SSE2__)
	q->ox = _mm_set1_ps(ox), q->oy = _mm_set1_ps(oy), q->oz = _mm_set1_ps(oz);
	q->sx = _mm_set1_ps((float)w->sx), q->sy = _mm_set1_ps((float)w->sy), q->so = _mm_set1_ps(so);
#else
	q->ox = ox, q->oy = oy, q->oz = oz;
	q->sx = (float)w->sx, q->sy = (float)w->sy, q->so = so;
#endif
}

/* The lanes (bit l) of block tb's first n that the ray may hit: the
 * others it certainly misses (TRIANGLE PRE-TEST). */
static inline __attribute__((always_inline)) unsigned tri1_pass(const struct tri1 *q, const float *tb, uint32_t n)
{
	const float *x = tb + (uint32_t)q->rx * n, *y = tb + (uint32_t)q->ry * n, *z = tb + (uint32_t)q->rz * n;
	const uint32_t n3 = 3 * n, n6 = 6 * n;
#if defined(__SSE2__)
	const __m128 v[9] = { _mm_loadu_ps(x),      _mm_loadu_ps(y),      _mm_loadu_ps(z),
			      _mm_loadu_ps(x + n3), _mm_loadu_ps(y + n3), _mm_loadu_ps(z + n3),
			      _mm_loadu_ps(x + n6), _mm_loadu_ps(y + n6), _mm_loadu_ps(z + n6) };
	unsigned rej = tri_reject_ps(v, _mm_loadu_ps(blk_row(tb, n, 9)), q->ox, q->oy, q->oz, q->sx, q->sy, q->so);
	return ~rej & ((1u << n) - 1);
#else
	unsigned pass = 0;
	for (uint32_t l = 0; l < n; l++) {
		const float v[9] = { x[l], y[l], z[l], x[n3 + l], y[n3 + l], z[n3 + l], x[n6 + l], y[n6 + l], z[n6 + l] };
		pass |= (unsigned)!tri_reject_f(v, blk_row(tb, n, 9)[l], q->ox, q->oy, q->oz, q->sx, q->sy, q->so) << l;
	}
	return pass;
#endif
}

/* The closest hit among block tb's n triangles (ref_test's contract): the
 * pre-test, then the double test on the lanes it lets through. *q is set
 * up from r on the first block the ray meets (*q_ready). */
static inline __attribute__((always_inline)) bool block_hit(const struct group *g, const float *tb,
							     uint32_t n, struct trace *r, struct cand *best,
							     struct tri1 *q, bool *q_ready)
{
	if (!*q_ready) {
		tri1_init(q, trace_wray(r));
		*q_ready = true;
	}
	bool found = false;
	for (unsigned pass = tri1_pass(q, tb, n); pass; pass &= pass - 1)
		found |= tri_test(g, blk_ref(tb, n, (uint32_t)__builtin_ctz(pass)), r, best);
	return found;
}

/* Any hit among block tb's n triangles: the blocking reference, or
 * ACCEL_NO_HINT. As block_hit. */
static inline __attribute__((always_inline)) uint32_t block_occluded(const struct group *g,
								      const float *tb, uint32_t n,
								      struct trace *r, struct tri1 *q, bool *q_ready)
{
	if (!*q_ready) {
		tri1_init(q, trace_wray(r));
		*q_ready = true;
	}
	for (unsigned pass = tri1_pass(q, tb, n); pass; pass &= pass - 1) {
		uint32_t ref = blk_ref(tb, n, (uint32_t)__builtin_ctz(pass));
		if (tri_occludes(g, ref, r))
			return ref;
	}
	return ACCEL_NO_HINT;
}

/* The children in mask m (bit c: child c, 4 or 8 of them) by entry
 * distance key[c], nearest first, ties in slot order, into cs; returns
 * how many. */
static inline __attribute__((always_inline)) int children_by_entry(int m, const float *key, int *cs)
{
	int k = 0;
	for (unsigned mm = (unsigned)m; mm; mm &= mm - 1) {
		int c = __builtin_ctz(mm);
		int j = k++;
		for (; j > 0 && key[cs[j - 1]] > key[c]; j--)
			cs[j] = cs[j - 1];
		cs[j] = c;
	}
	return k;
}

/* ---- SHADOW CROSSINGS (accel_cross.c, accel_packet.c) ------------------------------- */

/* A query's ray (world space), filter, list and hint (accel_cross,
 * accel_cross4). */
struct cross_query {
	const struct accel *A;
	const struct ray *r;
	const struct accel_cross_filter *f;
	struct accel_crossings *X;
	uint32_t *hint;
};

/* An instance the query went into: its define's group is searched with
 * the ray in the define's space, so a hit found there goes back up the
 * levels to the world (accel_inst_to_parent), and takes its tie key from
 * the references it came through: the instance's at the root (high 32
 * bits), the reference's within the first define (low 32), and below
 * that the first define's reference's alone, which the surfaces of a
 * nested instance share: two of them at one t are settled by the closest
 * hit there (accel_cross_emit). */
struct cross_level {
	const struct cross_level *up; /* NULL: this instance is the root group's */
	const struct trace *pr;       /* the ray in the parent's space */
	const struct scene_inst *si;
	mat34 inv;
	int depth; /* 1: the root group's instance */
	uint64_t key;
};

/* A material known only from the hit (CSG: its operands'). */
#define CROSS_MAT_UNKNOWN (UINT32_MAX - 1)

/* Whether material m (SCENE_NONE or beyond: the default) is opaque everywhere. */
static inline bool cross_opaque(const struct accel_cross_filter *f, uint32_t m)
{
	return f->opaque[m < f->n_materials ? m : f->n_materials] != 0;
}

/* The material of reference ref's hits in g, as accel_finish gives it
 * (SCENE_NONE: the instance's, or the default), or CROSS_MAT_UNKNOWN for a
 * CSG node and an instance, whose hits carry their own. */
static inline uint32_t cross_ref_mat(const struct group *g, uint32_t ref)
{
	uint32_t i = REF_IDX(ref);
	switch (REF_KIND(ref)) {
	case REF_SPHERE: return g->sph[i].mat;
	case REF_TRI: return g->mesh[g->tri[i].mesh].mat;
	case REF_XPRIM: return g->xp[i].r > 0 || g->xp[i].g->kind != PRIM_CSG ? g->xp[i].mat : CROSS_MAT_UNKNOWN;
	default: return CROSS_MAT_UNKNOWN;
	}
}

/* Candidate c (ref, key, t and what accel_finish reads) of group g on r at
 * level lv (NULL: the root group), material mat (SCENE_NONE: the
 * instance's, or at the root the default material; CROSS_MAT_UNKNOWN: the
 * hit's): false when it blocks the segment (opaque, or the list is full),
 * else its entry made. */
bool accel_cross_emit(const struct cross_query *Q, const struct group *g, const struct trace *r,
		      const struct cand *c, uint32_t mat, const struct cross_level *lv);
/* Every crossing of reference ref of g on r: false when one blocks the
 * segment. r's tmin and tmax are as they were; its MAILBOX may name ref (a
 * later test of it is skipped, which is right: every crossing of it was
 * taken here). */
bool accel_cross_ref(const struct cross_query *Q, const struct group *g, uint32_t ref, struct trace *r,
		     const struct cross_level *lv);
/* accel_cross_ref of g's unbounded references: false when one blocks.
 * Inline: most groups have none, and the call cost gears_s2 1.5%. */
static inline bool accel_cross_unb(const struct cross_query *Q, const struct group *g, struct trace *r,
				   const struct cross_level *lv)
{
	for (uint32_t k = 0; k < g->n_unb; k++) {
		if (cancel_poll_every(k)) /* CANCELLATION: the list may be long */
			return true;
		if (!accel_cross_ref(Q, g, g->unb[k], r, lv))
			return false;
	}
	return true;
}
/* X->x in order of t (the entries' t differ). */
void accel_cross_sort(struct accel_crossings *X);

/* accel_cross_ref of a triangle. */
static inline __attribute__((always_inline)) bool cross_tri(const struct cross_query *Q, const struct group *g,
							     uint32_t ref, struct trace *r,
							     const struct cross_level *lv)
{
	const struct gtri *gt = &g->tri[REF_IDX(ref)];
	const struct gmesh *m = &g->mesh[gt->mesh];
	const uint32_t *ix = tri_ix(m, gt->tri);
	struct cand c;
	if (tri_flat_behind(g, REF_IDX(ref), r, &m->v[ix[0]]) ||
	    !geom_tri_hit_p(trace_wray(r), &m->v[ix[0]], &m->v[ix[1]], &m->v[ix[2]], r->tmin, r->tmax, &c.t, &c.b1, &c.b2))
		return true;
	if (!lv && cross_opaque(Q->f, m->mat)) {
		*Q->hint = ref;
		return false;
	}
	c.ref = c.key = ref;
	c.part = GEOM_PART_MAIN;
	return accel_cross_emit(Q, g, r, &c, m->mat, lv);
}

/* Whether the hint, a reference of the root group g whose material is
 * opaque everywhere, blocks r. ref_occludes may leave r's MAILBOX naming an
 * xprim it found no hit of: the traversal then skips a reference without
 * crossings on r. */
static inline bool cross_hint_blocks(const struct cross_query *Q, const struct group *g, struct trace *r)
{
	uint32_t h = *Q->hint;
	if (h == ACCEL_NO_HINT || !ref_valid(g, h))
		return false;
	uint32_t mat = cross_ref_mat(g, h);
	return mat != CROSS_MAT_UNKNOWN && cross_opaque(Q->f, mat) && ref_occludes(Q->A, g, h, r);
}

#endif
