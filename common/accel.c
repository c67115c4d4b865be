/*
 * accel.c - the scene's objects as a multi-level BVH: ray queries. Building
 * is in accel_build.c; the private structures both share are in accel_int.h.
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
 * binned SAH (bvh.c) collapsed to 4-wide nodes; traversal is iterative with
 * a fixed stack, nearest child first, and stops at the first hit for
 * accel_occluded. Packets of four rays (accel_intersect4, accel_occluded4)
 * share one walk of the root group's tree; a last-blocker hint
 * (accel_occluded_hint) is tested before the tree. Instances recurse into their define's group (depth
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
 * against the whole leaf (TRIANGLE PRE-TEST) picks the triangles the
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

#include "common/accel_int.h"
#include "common/cancel.h"
#include "common/xmath.h"

/* Subtrees a traversal pops between polls of the cancel flag: each pop
 * follows a leaf (at most ACCEL_LEAF_CHUNK references, instances polling
 * on their own) or a node none of whose children is hit, after at most
 * BVH_MAX_DEPTH nodes with one child hit; 1024 of them are well under a
 * millisecond on any leaf but a CSG, and CSG polls by itself. */
#define ACCEL_POLL_POPS 1024u

/* ---- rays ------------------------------------------------------------------------ */

struct trace {
	vec3 o, d;
	double inv_dd; /* 1 / |d|^2 */
	double tmin, tmax;
	bool w_ready;  /* w is set up (on the first triangle test) */
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

static void trace_init(struct trace *r, vec3 o, vec3 d, double tmin, double tmax)
{
	r->o = o;
	r->d = d;
	double a = v3_dot(d, d);
	r->inv_dd = a > 0 ? 1.0 / a : 0;
	r->w_ready = false;
	r->tmin = tmin;
	r->tmax = tmax;
}

struct ray4 {
#if defined(__SSE2__)
	__m128 o[3], inv_near[3], inv_far[3];
#else
	float o[3], inv_near[3], inv_far[3];
#endif
	/* the direction's octant: bit k set when d[k] is negative (its sign
	 * bit, -0 included: the sign of the inverses); picks the near plane of each
	 * axis (hi[k] for a negative direction, lo[k] else), the "sign" trick */
	uint32_t oct;
	double tscale; /* box-space t = ray t * tscale */
};

_Static_assert(offsetof(struct bvh4, hi) == 12 * sizeof(float), "bvh4 rows: lo[3][4] then hi[3][4]");

/* Bit k set when direction component k has its sign bit set (-0 too):
 * the sign of 1 / (d[k] * s) or of copysign(1e30, d[k]) alike. */
static inline uint32_t ray_octant(vec3 d)
{
	return (signbit(d.x) ? 1u : 0u) | (signbit(d.y) ? 2u : 0u) | (signbit(d.z) ? 4u : 0u);
}

/* 2^e for an integer e in [-1022, 1023], exactly. */
static inline double pow2(int e)
{
	uint64_t bits = (uint64_t)(e + 1023) << 52;
	double x;
	memcpy(&x, &bits, sizeof x);
	return x;
}

/* A ray's box-test constants in float (BOX TESTS, accel_int.h): the origin
 * relative to the group's centre and the widened inverses of the scaled
 * direction; tscale and the octant as in struct ray4. */
struct ray_box {
	float o[3], inv_near[3], inv_far[3];
	double tscale;
	uint32_t oct;
};

static inline void ray_box_init(struct ray_box *q, const struct trace *r, vec3 center)
{
	double ax = fabs(r->d.x), ay = fabs(r->d.y), az = fabs(r->d.z);
	double m = ax > ay ? ax : ay;
	m = m > az ? m : az;
	uint64_t bits;
	memcpy(&bits, &m, sizeof bits);
	int e = (int)(bits >> 52 & 0x7ff) - 1023; /* floor(log2 m) for normal m */
	if (e < -1000 || e > 1000)
		e = 0; /* absurd scales: left unscaled (the +-1e30 rule still holds) */
	double s = pow2(-e);
	q->tscale = pow2(e);
	q->oct = ray_octant(r->d);
	double o[3] = { r->o.x - center.x, r->o.y - center.y, r->o.z - center.z };
	double d[3] = { r->d.x, r->d.y, r->d.z };
	for (uint32_t k = 0; k < 3; k++) {
		double dk = d[k] * s;
		double iv = fabs(dk) > 1e-30 ? 1.0 / dk : copysign(1e30, dk);
		/* the widening, folded into the inverse (BOX TESTS, accel_int.h) */
		q->inv_near[k] = (float)(iv * (1 - BOX_WIDEN));
		q->inv_far[k] = (float)(iv * (1 + BOX_WIDEN));
		q->o[k] = (float)o[k];
	}
}

static inline void ray4_init(struct ray4 *q, const struct trace *r, vec3 center)
{
	struct ray_box b;
	ray_box_init(&b, r, center);
	q->tscale = b.tscale;
	q->oct = b.oct;
	for (uint32_t k = 0; k < 3; k++) {
#if defined(__SSE2__)
		q->o[k] = _mm_set1_ps(b.o[k]);
		q->inv_near[k] = _mm_set1_ps(b.inv_near[k]);
		q->inv_far[k] = _mm_set1_ps(b.inv_far[k]);
#else
		q->o[k] = b.o[k];
		q->inv_near[k] = b.inv_near[k];
		q->inv_far[k] = b.inv_far[k];
#endif
	}
}

/*
 * The box tests' tmin and tmax: x >= 0 rounded to a float, down for tmin
 * and up for tmax, without a branch (tmax changes at every leaf that hits,
 * and a data-dependent branch there costs more than the box test). The
 * factor covers float rounding's relative error (2^-24) of normal values
 * and the tiny term its absolute error (2^-150) of subnormal ones; inf
 * stays inf. A tmin below 0 by the tiny term only lets a box through.
 */
static inline float box_tmin(double x) { return (float)(x * (1 - 0x1p-22) - 0x1p-140); }
static inline float box_tmax(double x) { return (float)(x * (1 + 0x1p-22) + 0x1p-140); }

/*
 * Slab test of the four children of nd against [tmin, tmax] (box space,
 * tmin >= 0). Returns a mask (bit c: child c may be hit) and the widened
 * entry distances in tn.
 *
 * The near plane of each axis is chosen once per ray by the direction's
 * sign (the "sign" trick): inv is never 0, inf or NaN, and lo <= hi, so
 * (lo - o) * inv and (hi - o) * inv are ordered by inv's sign (rounding is
 * monotonic). Each entry distance is multiplied by 1 - BOX_WIDEN and each
 * exit distance by 1 + BOX_WIDEN through the inverses (ray4_init): an
 * entry distance that matters is >= tmin >= 0, so that moves it toward 0,
 * and an exit distance that matters is >= 0, so that moves it away; a
 * negative one belongs to a box behind the origin by more than the
 * padding. NaN bounds (unused slots) never hit: max returns its second
 * operand when one is NaN, as SSE's does, so t0 becomes NaN and t0 <= t1
 * fails.
 */
#if defined(__SSE2__)
typedef __m128 tspan; /* tmin or tmax broadcast to the four lanes */
static inline tspan tspan_of(float t) { return _mm_set1_ps(t); }
#else
typedef float tspan;
static inline tspan tspan_of(float t) { return t; }
#endif

static inline __attribute__((always_inline)) int node4_hit(const struct bvh4 *nd, const struct ray4 *q,
							    uint32_t oct, tspan tmin, tspan tmax, float tn[4])
{
	const float *b = (const float *)(const void *)nd; /* lo[3][4] then hi[3][4] */
	/* rows of bvh4: lo[k] at 4k, hi[k] at 12 + 4k */
	const uint32_t near[3] = { 12 * (oct & 1), 4 + 12 * (oct >> 1 & 1), 8 + 12 * (oct >> 2 & 1) };
	const uint32_t far[3] = { 12 * (~oct & 1), 4 + 12 * (~oct >> 1 & 1), 8 + 12 * (~oct >> 2 & 1) };
#if defined(__SSE2__)
	__m128 t0 = tmin, t1 = tmax;
	for (int k = 0; k < 3; k++) {
		__m128 tnear = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(b + near[k]), q->o[k]), q->inv_near[k]);
		__m128 tfar = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(b + far[k]), q->o[k]), q->inv_far[k]);
		t0 = _mm_max_ps(t0, tnear);
		t1 = _mm_min_ps(t1, tfar);
	}
	_mm_storeu_ps(tn, t0);
	return _mm_movemask_ps(_mm_cmple_ps(t0, t1));
#else
	int mask = 0;
	for (int c = 0; c < 4; c++) {
		float t0 = tmin, t1 = tmax;
		for (int k = 0; k < 3; k++) {
			float tnear = (b[near[k] + (uint32_t)c] - q->o[k]) * q->inv_near[k];
			float tfar = (b[far[k] + (uint32_t)c] - q->o[k]) * q->inv_far[k];
			t0 = t0 > tnear ? t0 : tnear; /* _mm_max_ps(t0, tnear) */
			t1 = t1 < tfar ? t1 : tfar;   /* _mm_min_ps(t1, tfar) */
		}
		tn[c] = t0;
		mask |= (t0 <= t1) << c;
	}
	return mask;
#endif
}

#define SLAB_WIDEN 4.5e-16 /* 1 + 2 gamma(3) for doubles, rounded up (Ize 2013) */

/* The same test in double on one box of six floats (a root that is a leaf). */
static bool box_hit(const float b[6], vec3 center, const struct trace *r)
{
	double o[3] = { r->o.x - center.x, r->o.y - center.y, r->o.z - center.z };
	double d[3] = { r->d.x, r->d.y, r->d.z };
	double t0 = r->tmin, t1 = r->tmax;
	for (int k = 0; k < 3; k++) {
		double inv = fabs(d[k]) > 1e-300 ? 1.0 / d[k] : copysign(1e300, d[k]);
		double a = ((double)b[k] - o[k]) * inv, c = ((double)b[k + 3] - o[k]) * inv;
		double lo = a < c ? a : c, hi = a < c ? c : a;
		t0 = lo > t0 ? lo : t0;
		t1 = hi < t1 ? hi : t1;
	}
	t1 += fabs(t1) * SLAB_WIDEN;
	return t0 <= t1;
}

/* ---- candidates and hits ---------------------------------------------------------- */

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

static bool group_hit(const struct accel *A, const struct group *g, struct trace *r, struct hit *h, bool brute);
static bool group_occluded(const struct accel *A, const struct group *g, struct trace *r);
static void surface_complete(const struct scene *s, struct hit *h);
static void surface_cb(const struct accel *a, struct hit *h);

static inline bool sphere_test(const struct gsphere *sp, const struct trace *r, double *t)
{
	vec3 oc = v3_sub(r->o, sp->c);
	double b = v3_dot(oc, r->d);
	double tc = -b * r->inv_dd;
	vec3 f = v3_add(oc, v3_scale(r->d, tc));
	double h2 = (sp->r2 - v3_dot(f, f)) * r->inv_dd;
	if (h2 < 0)
		return false;
	double hh = sqrt(h2);
	double q = tc + (tc >= 0 ? hh : -hh);
	double c = v3_dot(oc, oc) - sp->r2;
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

/* Bounded reference k (in leaf order) of g. */
static inline uint32_t group_ref(const struct group *g, uint32_t k)
{
	return g->refs ? g->refs[k] : REF_MAKE(REF_INST, k);
}



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
	surface_complete(A->s, &lh); /* in the define's space */
	h->t = lh.t;
	h->n = v3_norm(m34_normal(&inv, lh.n));
	h->ng = v3_norm(m34_normal(&inv, lh.ng));
	h->u = lh.u;
	h->v = lh.v;
	h->object = lh.object;
	uint32_t im = si->material;
	if (lh.material == SCENE_NONE && im != SCENE_NONE) {
		h->material = im;
		h->mp = lh.p; /* the instance's own object space is the define's space */
	} else {
		h->material = lh.material;
		h->mp = lh.mp;
	}
	return true;
}

static bool inst_occluded(const struct accel *A, const struct ginst *in, const struct trace *r)
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
static __attribute__((noinline)) bool xprim_test(const struct geom_obj *go, uint32_t ref, struct trace *r,
						 struct cand *c)
{
	vec3 o = r->o, d = r->d;
	if (go->has_xform) {
		o = m34_point(&go->inv, o);
		d = m34_dir(&go->inv, d);
	}
	double t;
	int part;
	if (!geom_intersect(go, o, d, r->tmin, r->tmax, &t, &part) || !cand_better(c, ref, t))
		return false;
	c->part = part;
	cand_take(c, r, ref, t);
	return true;
}

static __attribute__((noinline)) bool ref_test_slow(const struct accel *A, const struct group *g, uint32_t ref,
						     struct trace *r, struct cand *c, bool brute)
{
	uint32_t i = REF_IDX(ref);
	if (REF_KIND(ref) == REF_XPRIM) {
		const struct xprim *x = &g->xp[i];
		if (x->g->kind != PRIM_CSG)
			return xprim_test(x->g, ref, r, c);
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

/* ref_test of triangle reference ref. */
static inline __attribute__((always_inline)) bool tri_test(const struct group *g, uint32_t ref, struct trace *r,
							    struct cand *c)
{
	const struct gtri *gt = &g->tri[REF_IDX(ref)];
	const struct gmesh *m = &g->mesh[gt->mesh];
	const uint32_t *ix = tri_ix(m, gt->tri);
	double t, b1, b2;
	if (!geom_tri_hit_p(trace_wray(r), &m->v[ix[0]], &m->v[ix[1]], &m->v[ix[2]], r->tmin, r->tmax, &t, &b1, &b2) ||
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
	return geom_tri_hit_p(trace_wray(r), &m->v[ix[0]], &m->v[ix[1]], &m->v[ix[2]], r->tmin, r->tmax, &t, &b1,
			      &b2);
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
		const struct geom_obj *go = g->xp[i].g;
		if (go->kind != PRIM_CSG)
			return xprim_test(go, ref, r, c);
		return ref_test_slow(A, g, ref, r, c, brute);
	}
	default:
		return ref_test_slow(A, g, ref, r, c, brute);
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
		return inst_occluded(A, &g->inst[i], r);
	default: { /* an xprim: xprim_test's answer without a candidate, but CSG */
		const struct geom_obj *go = g->xp[i].g;
		if (go->kind == PRIM_CSG)
			break;
		vec3 o = r->o, d = r->d;
		if (go->has_xform) {
			o = m34_point(&go->inv, o);
			d = m34_dir(&go->inv, d);
		}
		int part;
		return geom_intersect(go, o, d, r->tmin, r->tmax, &t, &part);
	}
	}
	struct cand c;
	cand_init(&c);
	double tmax = r->tmax;
	bool hit = ref_test(A, g, ref, r, &c, false);
	r->tmax = tmax;
	return hit;
}

/* Completes the hit of candidate c in the group's space. */
static void finish(const struct accel *A, const struct group *g, const struct trace *r, const struct cand *c,
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
			h->material = scene_full_at(s, h->object)->material; /* an xprim: not an instance */
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
 * The lazy part of finish(): u, v and mp of a sphere in the default frame
 * (from the unit normal finish() stored) or of a triangle (from the
 * barycentrics), in the group's space the hit was finished in, with
 * exactly the arithmetic an eager finish() would use.
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
static __attribute__((noinline)) bool unb_hit(const struct accel *A, const struct group *g, struct trace *r,
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
			if (geom_tri_hit(trace_wray(r), m->v[ix[0]], m->v[ix[1]], m->v[ix[2]], r->tmin, r->tmax, &t, &b1, &b2) &&
			    cand_better(best, REF_MAKE(REF_TRI, k), t)) {
				cand_take(best, r, REF_MAKE(REF_TRI, k), t);
				best->b1 = b1;
				best->b2 = b2;
				found = true;
			}
		}
	}
	for (uint32_t k = 0; k < g->n_refs; k++)
		if (REF_KIND(group_ref(g, k)) >= REF_XPRIM)
			found |= ref_test(A, g, group_ref(g, k), r, best, true);
	return found;
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
 *     accel_int.h): single rays, closest and any hit, and the packets'
 *     leaves met by one ray or traced for any hit;
 *   - one triangle against a packet's four rays (tri4_reject).
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

/* The children in mask m (bit c: child c) by entry distance key[c],
 * nearest first, ties in slot order, into cs; returns how many. */
static inline __attribute__((always_inline)) int children_by_entry(int m, const float key[4], int cs[4])
{
	int k = 0;
	for (int c = 0; c < 4; c++) {
		if (!(m >> c & 1))
			continue;
		int j = k++;
		for (; j > 0 && key[cs[j - 1]] > key[c]; j--)
			cs[j] = cs[j - 1];
		cs[j] = c;
	}
	return k;
}

/* The BVH traversal of g's bounded references: nearest child first,
 * subtrees behind the closest hit so far popped and dropped. Same contract
 * as ref_test. chunked: g has big leaves (group.big_leaf), tested
 * ACCEL_LEAF_CHUNK references at a time (CANCELLATION); a constant, so the
 * common copies have no test (it cost 1% of single rays). */
static inline __attribute__((always_inline)) bool bvh_hit(const struct accel *A, const struct group *g,
							   struct trace *r, struct cand *best, const struct ray4 *qp,
							   const uint32_t oct, const bool chunked)
{
	bool found = false;
	const struct bvh4 *nodes = g->bvh.nodes;
	const struct ray4 q = *qp;
	const tspan tmin = tspan_of(box_tmin(r->tmin * q.tscale));
	float tmax = box_tmax(r->tmax * q.tscale);
	tspan tmax4 = tspan_of(tmax);
	struct {
		uint32_t idx, n;
		float t;
	} stack[3 * BVH_MAX_DEPTH + 4];
	int sp = 0;
	uint32_t idx = 0, n = 0;
	uint32_t polls = ACCEL_POLL_POPS;
	struct tri1 q1; /* TRIANGLE PRE-TEST, set up at the first block */
	bool q1_ready = false;
	for (;;) {
		if (n) {
			if (n & LEAF_BLOCK) {
				found |= block_hit(g, &g->tblk[idx], n & ~LEAF_BLOCK, r, best, &q1, &q1_ready);
			} else {
				if (chunked && n > ACCEL_LEAF_CHUNK) { /* CANCELLATION: the rest later */
					stack[sp].idx = idx + ACCEL_LEAF_CHUNK;
					stack[sp].n = n - ACCEL_LEAF_CHUNK;
					stack[sp++].t = 0;
					n = ACCEL_LEAF_CHUNK;
				}
				for (uint32_t k = 0; k < n; k++)
					found |= ref_test(A, g, group_ref(g, idx + k), r, best, false);
			}
			tmax = box_tmax(r->tmax * q.tscale);
			tmax4 = tspan_of(tmax);
		} else {
			const struct bvh4 *nd = &nodes[idx];
			float tn[4];
			int m = node4_hit(nd, &q, oct, tmin, tmax4, tn);
			if (m && !(m & (m - 1))) { /* one child */
				int c = __builtin_ctz((unsigned)m);
				idx = nd->idx[c];
				n = nd->n[c];
				continue;
			}
			int m2 = m & (m - 1); /* m without its lowest child */
			if (m2 && !(m2 & (m2 - 1))) { /* two children */
				int c0 = __builtin_ctz((unsigned)m), c1 = __builtin_ctz((unsigned)m2);
				if (tn[c0] > tn[c1]) { /* the nearer first; ties keep slot order */
					int tc = c0;
					c0 = c1, c1 = tc;
				}
				stack[sp].idx = nd->idx[c1];
				stack[sp].n = nd->n[c1];
				stack[sp++].t = tn[c1];
				idx = nd->idx[c0];
				n = nd->n[c0];
				continue;
			}
			if (m) { /* nearest first; the others pushed farthest first */
				int cs[4], k = children_by_entry(m, tn, cs);
				for (int j = k - 1; j >= 1; j--) {
					stack[sp].idx = nd->idx[cs[j]];
					stack[sp].n = nd->n[cs[j]];
					stack[sp++].t = tn[cs[j]];
				}
				idx = nd->idx[cs[0]];
				n = nd->n[cs[0]];
				continue;
			}
		}
		if (__builtin_expect(--polls == 0, 0)) { /* CANCELLATION */
			polls = ACCEL_POLL_POPS;
			if (cancel_poll())
				return found;
		}
		/* pop the next subtree still in front of the closest hit */
		for (;;) {
			if (sp == 0)
				return found;
			sp--;
			if (stack[sp].t <= tmax)
				break;
		}
		idx = stack[sp].idx;
		n = stack[sp].n;
	}
}

/* bvh_hit through a tree with big leaves: one copy for every octant (such
 * trees come only from the builder's depth limit). */
static __attribute__((noinline)) bool bvh_hit_chunked(const struct accel *A, const struct group *g,
						       struct trace *r, struct cand *best)
{
	struct ray4 q4;
	ray4_init(&q4, r, g->center);
	return bvh_hit(A, g, r, best, &q4, q4.oct, true);
}

/* The unbounded references of g: the start of every closest-hit query.
 * Same contract as ref_test. */
static inline bool group_hit_unbounded(const struct accel *A, const struct group *g, struct trace *r,
				       struct cand *best, bool brute)
{
	if (g->plane1) { /* unb_hit's plane test, the common case of one ground plane */
		double t;
		const struct geom_obj *go = g->plane1;
		if (geom_plane_t(go->u.pl.pos, go->u.pl.n, r->o, r->d, &t) && t > r->tmin && t < r->tmax &&
		    cand_better(best, g->unb[0], t)) {
			cand_take(best, r, g->unb[0], t);
			best->part = GEOM_PART_MAIN;
			return true;
		}
		return false;
	}
	return g->n_unb ? unb_hit(A, g, r, best, brute) : false;
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
		finish(A, g, r, &best, h);
	return found;
}

/* accel_occluded's query in group g; chunked: g's tree has big leaves,
 * tested ACCEL_LEAF_CHUNK references at a time (CANCELLATION; a constant
 * in each copy, since checking leaves' sizes in the common copy cost 1.5%
 * of a whole render). */
static inline __attribute__((always_inline)) bool group_occluded_t(const struct accel *A, const struct group *g,
								    struct trace *r, const bool chunked, uint32_t *who)
{
	for (uint32_t k = 0; k < g->n_unb; k++) {
		if (cancel_poll_every(k)) /* CANCELLATION, as unb_hit */
			return false;
		if (ref_occludes(A, g, g->unb[k], r)) {
			*who = g->unb[k];
			return true;
		}
	}
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
	} stack[3 * BVH_MAX_DEPTH + 4];
	int sp = 0;
	uint32_t idx = 0, n = 0;
	uint32_t polls = ACCEL_POLL_POPS;
	struct tri1 q1; /* TRIANGLE PRE-TEST, set up at the first block */
	bool q1_ready = false;
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
			const struct bvh4 *nd = &nodes[idx];
			float tn[4];
			int m = node4_hit(nd, &q, q.oct, tmin, tmax, tn);
			if (m) {
				int c = __builtin_ctz((unsigned)m);
				for (int j = 3; j > c; j--) {
					if (m >> j & 1) {
						stack[sp].idx = nd->idx[j];
						stack[sp++].n = nd->n[j];
					}
				}
				idx = nd->idx[c];
				n = nd->n[c];
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

/* ---- packets of four rays ------------------------------------------------------------ */

#if defined(__SSE2__)
/*
 * Four rays of one octant, one per SIMD lane (lane i: ray i), for the
 * packet traversal: where bvh_hit tests one ray against a node's four
 * children at once, bvh_hit4 tests each child against four rays at once.
 * Neighbouring camera rays visit nearly the same nodes, so the packet
 * shares the node loads, the ordering and the stack among them. The box
 * arithmetic is bvh_hit's (the same constants, from ray_box_init), so a
 * lane's box test passes exactly when bvh_hit's would with that ray's tmax.
 */
struct ray4x {
	__m128 o[3], inv_near[3], inv_far[3];
	/* lane i's o, inv_near and inv_far broadcast to four lanes (one per
	 * child): bvh_hit4 tests a node ray by ray, the four children at once */
	__m128 lo[4][3], lnear[4][3], lfar[4][3];
	double tscale[4];
};

/* The lanes (bit i: ray i) whose entry distance t into a subtree is finite
 * (the ray meets its box: a miss is +inf) and not behind the ray's closest
 * hit so far. The first test matters while a ray has no hit: its tmax is
 * +inf too. */
static inline unsigned lanes_in_front(__m128 t, __m128 tmax4, __m128 inf4)
{
	return (unsigned)_mm_movemask_ps(_mm_and_ps(_mm_cmplt_ps(t, inf4), _mm_cmple_ps(t, tmax4)));
}

/* The smallest of the four lanes. */
static inline float lanes_min(__m128 v)
{
	v = _mm_min_ps(v, _mm_shuffle_ps(v, v, _MM_SHUFFLE(2, 3, 0, 1)));
	v = _mm_min_ps(v, _mm_shuffle_ps(v, v, _MM_SHUFFLE(1, 0, 3, 2)));
	return _mm_cvtss_f32(v);
}

/* box_tmin and box_tmax of the four rays' tmin and tmax (times their
 * tscale) as lanes, two at a time in registers: the same floats, without
 * the four scalar stores that a 16-byte load would wait on. */
static inline __m128 lanes_box_tmin(const struct trace tr[4], const double tscale[4])
{
	const __m128d f = _mm_set1_pd(1 - 0x1p-22), a = _mm_set1_pd(0x1p-140);
	__m128d x0 = _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(&tr[0].tmin), &tr[1].tmin), _mm_loadu_pd(tscale));
	__m128d x1 = _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(&tr[2].tmin), &tr[3].tmin), _mm_loadu_pd(tscale + 2));
	return _mm_movelh_ps(_mm_cvtpd_ps(_mm_sub_pd(_mm_mul_pd(x0, f), a)),
			     _mm_cvtpd_ps(_mm_sub_pd(_mm_mul_pd(x1, f), a)));
}

static inline __m128 lanes_box_tmax(const struct trace tr[4], const double tscale[4])
{
	const __m128d f = _mm_set1_pd(1 + 0x1p-22), a = _mm_set1_pd(0x1p-140);
	__m128d x0 = _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(&tr[0].tmax), &tr[1].tmax), _mm_loadu_pd(tscale));
	__m128d x1 = _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(&tr[2].tmax), &tr[3].tmax), _mm_loadu_pd(tscale + 2));
	return _mm_movelh_ps(_mm_cvtpd_ps(_mm_add_pd(_mm_mul_pd(x0, f), a)),
			     _mm_cvtpd_ps(_mm_add_pd(_mm_mul_pd(x1, f), a)));
}

/*
 * ray_box_init for four rays at once, into P's rows (lane i: ray i): the
 * same operations two rays at a time, so the same floats bit for bit
 * (divpd and mulpd round as divsd and mulsd do, cvtpd2ps as cvtsd2ss, and
 * maxpd picks what the scalar comparisons pick for finite directions). The
 * scale's power of two comes from the exponent bits: 2^e is m's exponent
 * field alone and 2^-e has the field 2046 - E. Everything stays in
 * registers: building the pairs through arrays on the stack (8-byte
 * stores read back by 16-byte loads) stalled store forwarding and made
 * the set-up a tenth of tetra_s4's render.
 */
static void ray_box4(const struct trace tr[4], vec3 center, struct ray4x *P)
{
	const __m128d one = _mm_set1_pd(1.0), tiny = _mm_set1_pd(1e-30), big = _mm_set1_pd(1e30);
	const __m128d sign = _mm_set1_pd(-0.0), wn = _mm_set1_pd(1 - BOX_WIDEN), wf = _mm_set1_pd(1 + BOX_WIDEN);
	const __m128d expo = _mm_castsi128_pd(_mm_set1_epi64x(0x7ff0000000000000LL));
	const __m128i two046 = _mm_set1_epi64x(0x7fe0000000000000LL);
	const __m128d lo_e = _mm_set1_pd(0x1p-1000), hi_e = _mm_set1_pd(0x1p1001);
	const __m128d c[3] = { _mm_set1_pd(center.x), _mm_set1_pd(center.y), _mm_set1_pd(center.z) };
	__m128 o[3][2], in[3][2], fa[3][2];
	for (int h = 0; h < 2; h++) {
		const struct trace *a = &tr[2 * h], *b = &tr[2 * h + 1];
		/* lane pairs loaded 8 bytes at a time: the rays were just stored that way */
		__m128d d[3] = { _mm_loadh_pd(_mm_load_sd(&a->d.x), &b->d.x), _mm_loadh_pd(_mm_load_sd(&a->d.y), &b->d.y),
				 _mm_loadh_pd(_mm_load_sd(&a->d.z), &b->d.z) };
		__m128d oo[3] = { _mm_loadh_pd(_mm_load_sd(&a->o.x), &b->o.x), _mm_loadh_pd(_mm_load_sd(&a->o.y), &b->o.y),
				  _mm_loadh_pd(_mm_load_sd(&a->o.z), &b->o.z) };
		__m128d m = _mm_max_pd(_mm_max_pd(_mm_andnot_pd(sign, d[0]), _mm_andnot_pd(sign, d[1])),
				       _mm_andnot_pd(sign, d[2]));
		/* e outside [-1000, 1000] (m < 2^-1000 or m >= 2^1001): unscaled, as ray_box_init */
		__m128d clamp = _mm_or_pd(_mm_cmplt_pd(m, lo_e), _mm_cmpge_pd(m, hi_e));
		__m128d ts = _mm_and_pd(m, expo);                                        /* 2^e */
		__m128d sc = _mm_castsi128_pd(_mm_sub_epi64(two046, _mm_castpd_si128(ts))); /* 2^-e */
		ts = _mm_or_pd(_mm_and_pd(clamp, one), _mm_andnot_pd(clamp, ts));
		sc = _mm_or_pd(_mm_and_pd(clamp, one), _mm_andnot_pd(clamp, sc));
		_mm_storeu_pd(&P->tscale[2 * h], ts);
		for (int k = 0; k < 3; k++) {
			__m128d dk = _mm_mul_pd(d[k], sc);
			__m128d iv = _mm_div_pd(one, dk);
			/* fabs(dk) > 1e-30 ? 1 / dk : copysign(1e30, dk) */
			__m128d ok = _mm_cmpgt_pd(_mm_andnot_pd(sign, dk), tiny);
			__m128d alt = _mm_or_pd(_mm_and_pd(sign, dk), big);
			iv = _mm_or_pd(_mm_and_pd(ok, iv), _mm_andnot_pd(ok, alt));
			in[k][h] = _mm_cvtpd_ps(_mm_mul_pd(iv, wn));
			fa[k][h] = _mm_cvtpd_ps(_mm_mul_pd(iv, wf));
			o[k][h] = _mm_cvtpd_ps(_mm_sub_pd(oo[k], c[k]));
		}
	}
	for (int k = 0; k < 3; k++) {
		P->o[k] = _mm_movelh_ps(o[k][0], o[k][1]);
		P->inv_near[k] = _mm_movelh_ps(in[k][0], in[k][1]);
		P->inv_far[k] = _mm_movelh_ps(fa[k][0], fa[k][1]);
	}
}

/* The packet's side of the TRIANGLE PRE-TEST: one triangle against the
 * four rays, where they share kx, ky, kz (neighbouring rays do). */
struct tri4 {
	bool ok;   /* set up, and the four rays share kx, ky, kz */
	int kx, ky, kz;
	__m128 ox, oy, oz, sx, sy, so; /* per ray: origin, shear, max |origin| */
};

/* Sets up the pre-test for the packet (the rays' watertight set-up too). */
static void tri4_init(struct tri4 *q, struct trace tr[4])
{
	float ox[4], oy[4], oz[4], sx[4], sy[4], so[4];
	const struct geom_wray *w0 = trace_wray(&tr[0]);
	q->ok = true;
	q->kx = w0->kx, q->ky = w0->ky, q->kz = w0->kz;
	for (int i = 0; i < 4; i++) {
		const struct geom_wray *w = trace_wray(&tr[i]);
		q->ok &= w->kx == q->kx && w->ky == q->ky && w->kz == q->kz;
		ox[i] = (float)w->ox, oy[i] = (float)w->oy, oz[i] = (float)w->oz;
		sx[i] = (float)w->sx, sy[i] = (float)w->sy;
		float m = fabsf(ox[i]) > fabsf(oy[i]) ? fabsf(ox[i]) : fabsf(oy[i]);
		so[i] = m > fabsf(oz[i]) ? m : fabsf(oz[i]);
	}
	q->ox = _mm_loadu_ps(ox), q->oy = _mm_loadu_ps(oy), q->oz = _mm_loadu_ps(oz);
	q->sx = _mm_loadu_ps(sx), q->sy = _mm_loadu_ps(sy), q->so = _mm_loadu_ps(so);
}

/* The rays (bit i: ray i) that lane l's triangle of block tb certainly
 * misses (TRIANGLE PRE-TEST); q->ok must hold. The block's floats are the
 * vertices rounded as the packets once rounded them when they gathered
 * them, and its s the same largest magnitude. */
static inline unsigned tri4_reject(const struct tri4 *q, const float *tb, uint32_t n, uint32_t l)
{
	const float *x = tb + (uint32_t)q->kx * n + l, *y = tb + (uint32_t)q->ky * n + l,
		    *z = tb + (uint32_t)q->kz * n + l;
	const uint32_t n3 = 3 * n, n6 = 6 * n;
	const __m128 v[9] = { _mm_set1_ps(x[0]),  _mm_set1_ps(y[0]),  _mm_set1_ps(z[0]),
			      _mm_set1_ps(x[n3]), _mm_set1_ps(y[n3]), _mm_set1_ps(z[n3]),
			      _mm_set1_ps(x[n6]), _mm_set1_ps(y[n6]), _mm_set1_ps(z[n6]) };
	return tri_reject_ps(v, _mm_set1_ps(blk_row(tb, n, 9)[l]), q->ox, q->oy, q->oz, q->sx, q->sy, q->so);
}

/* The same for a triangle of a leaf without a block (mixed leaves): its
 * floats gathered and rounded here, as make_blocks rounds them. */
static inline unsigned tri4_reject_v(const struct tri4 *q, const vec3 *a, const vec3 *b, const vec3 *c)
{
	const int kx = q->kx, ky = q->ky, kz = q->kz;
	float f[9] = { (float)geom_comp(a, kx), (float)geom_comp(a, ky), (float)geom_comp(a, kz),
		       (float)geom_comp(b, kx), (float)geom_comp(b, ky), (float)geom_comp(b, kz),
		       (float)geom_comp(c, kx), (float)geom_comp(c, ky), (float)geom_comp(c, kz) };
	float sv = 0;
	for (int k = 0; k < 9; k++)
		sv = fabsf(f[k]) > sv ? fabsf(f[k]) : sv; /* NaN: left out, but NaN below rejects nothing */
	__m128 v[9];
	for (int k = 0; k < 9; k++)
		v[k] = _mm_set1_ps(f[k]);
	return tri_reject_ps(v, _mm_set1_ps(sv), q->ox, q->oy, q->oz, q->sx, q->sy, q->so);
}

/* A leaf of n references from idx tested for the rays in lanes (two or
 * more), reference by reference: triangles through the pre-test when the
 * rays share their permutation (set up on the packet's first such leaf). */
static inline __attribute__((always_inline)) void leaf4(const struct accel *A, const struct group *g,
							struct trace tr[4], struct cand best[4], bool found[4],
							uint32_t idx, uint32_t n, unsigned lanes, struct tri4 *q,
							bool *q_ready)
{
	for (uint32_t k = 0; k < n; k++) {
		uint32_t ref = group_ref(g, idx + k);
		unsigned test = lanes;
		if (REF_KIND(ref) == REF_TRI) {
			if (!*q_ready) {
				tri4_init(q, tr);
				*q_ready = true;
			}
			if (q->ok) {
				const struct gmesh *m = &g->mesh[g->tri[REF_IDX(ref)].mesh];
				const uint32_t *ix = tri_ix(m, g->tri[REF_IDX(ref)].tri);
				test &= ~tri4_reject_v(q, &m->v[ix[0]], &m->v[ix[1]], &m->v[ix[2]]);
			}
		}
		for (; test; test &= test - 1) {
			int i = __builtin_ctz(test);
			found[i] |= ref_test(A, g, ref, &tr[i], &best[i], false);
		}
	}
}

/* leaf4 for a leaf block of n triangles: each triangle's pre-test against
 * the rays in lanes (two or more) reads the block. */
static inline __attribute__((always_inline)) void leaf4_block(const struct group *g, struct trace tr[4],
							      struct cand best[4], bool found[4],
							      const float *tb, uint32_t n, unsigned lanes,
							      struct tri4 *q, bool *q_ready)
{
	if (!*q_ready) {
		tri4_init(q, tr);
		*q_ready = true;
	}
	for (uint32_t l = 0; l < n; l++) {
		unsigned test = lanes;
		if (q->ok)
			test &= ~tri4_reject(q, tb, n, l);
		for (; test; test &= test - 1) {
			int i = __builtin_ctz(test);
			found[i] |= tri_test(g, blk_ref(tb, n, l), &tr[i], &best[i]);
		}
	}
}

/*
 * The packet traversal of g's bounded references. A subtree is visited
 * when any ray may hit it, nearest (smallest entry over the rays) first;
 * each stack entry keeps every ray's entry distance (+inf for a ray that
 * misses it), so a subtree is popped only for the rays that meet it and are
 * still in front of their closest hit, and a leaf is tested only for those. Every ray thus
 * tests every reference bvh_hit would let it test, perhaps more and in
 * another order: CANONICAL TIES make its hit the same. found[i], best[i]
 * and tr[i] are ray i's, as group_hit's.
 */
static inline __attribute__((always_inline)) void bvh_hit4(const struct accel *A, const struct group *g,
							   struct trace tr[4], struct cand best[4], bool found[4],
							   const struct ray4x *P, const uint32_t oct)
{
	const struct bvh4 *nodes = g->bvh.nodes;
	const uint32_t near[3] = { 12 * (oct & 1), 4 + 12 * (oct >> 1 & 1), 8 + 12 * (oct >> 2 & 1) };
	const uint32_t far[3] = { 12 * (~oct & 1), 4 + 12 * (~oct >> 1 & 1), 8 + 12 * (~oct >> 2 & 1) };
	const __m128 tmin4 = lanes_box_tmin(tr, P->tscale), inf4 = _mm_set1_ps(INFINITY);
	__m128 tmax4 = lanes_box_tmax(tr, P->tscale);
	struct {
		__m128 t; /* each ray's entry distance, +inf where it misses */
		uint32_t idx, n;
	} stack[3 * BVH_MAX_DEPTH + 4];
	int sp = 0;
	uint32_t idx = 0, n = 0;
	__m128 tcur = tmin4; /* the entry distances of the subtree at hand */
	uint32_t polls = ACCEL_POLL_POPS;
	struct tri4 q; /* TRIANGLE PRE-TEST, set up at the first leaf that needs it */
	bool q_ready = false;
	for (;;) {
		if (n) {
			/* the rays that meet the leaf, in front of their closest hit */
			unsigned lanes = lanes_in_front(tcur, tmax4, inf4);
			if (n & LEAF_BLOCK) {
				const float *tb = &g->tblk[idx];
				uint32_t nt = n & ~LEAF_BLOCK;
				if (lanes & (lanes - 1)) {
					leaf4_block(g, tr, best, found, tb, nt, lanes, &q, &q_ready);
				} else if (lanes) {
					int i = __builtin_ctz(lanes);
					struct tri1 q1;
					bool q1_ready = false;
					found[i] |= block_hit(g, tb, nt, &tr[i], &best[i], &q1, &q1_ready);
				}
			} else if (lanes & (lanes - 1)) { /* two or more: the triangle pre-test pays */
				leaf4(A, g, tr, best, found, idx, n, lanes, &q, &q_ready);
			} else if (lanes) {
				int i = __builtin_ctz(lanes);
				for (uint32_t k = 0; k < n; k++)
					found[i] |= ref_test(A, g, group_ref(g, idx + k), &tr[i], &best[i], false);
			}
			tmax4 = lanes_box_tmax(tr, P->tscale); /* the tested lanes' changed */
		} else {
			const struct bvh4 *nd = &nodes[idx];
			const float *b = (const float *)(const void *)nd; /* rows as in node4_hit */
			/* ray by ray, the four children in the lanes (node4_hit's
			 * arithmetic, operand for operand), then transposed: e[c] is
			 * child c's entry distance for each ray, +inf where it misses */
			const __m128 nr[3] = { _mm_loadu_ps(b + near[0]), _mm_loadu_ps(b + near[1]),
					       _mm_loadu_ps(b + near[2]) };
			const __m128 fr[3] = { _mm_loadu_ps(b + far[0]), _mm_loadu_ps(b + far[1]),
					       _mm_loadu_ps(b + far[2]) };
			__m128 e[4];
			int m = 0;
#define RAY_NODE(i)                                                                                      \
	do {                                                                                             \
		__m128 t0 = _mm_shuffle_ps(tmin4, tmin4, _MM_SHUFFLE(i, i, i, i));                       \
		__m128 t1 = _mm_shuffle_ps(tmax4, tmax4, _MM_SHUFFLE(i, i, i, i));                       \
		for (int k = 0; k < 3; k++) {                                                            \
			__m128 tn = _mm_mul_ps(_mm_sub_ps(nr[k], P->lo[i][k]), P->lnear[i][k]);          \
			__m128 tf = _mm_mul_ps(_mm_sub_ps(fr[k], P->lo[i][k]), P->lfar[i][k]);           \
			t0 = _mm_max_ps(t0, tn);                                                         \
			t1 = _mm_min_ps(t1, tf);                                                         \
		}                                                                                        \
		__m128 hit = _mm_cmple_ps(t0, t1);                                                       \
		e[i] = _mm_or_ps(_mm_and_ps(hit, t0), _mm_andnot_ps(hit, inf4));                         \
		m |= _mm_movemask_ps(hit);                                                               \
	} while (0)
			RAY_NODE(0);
			RAY_NODE(1);
			RAY_NODE(2);
			RAY_NODE(3);
#undef RAY_NODE
			float key[4]; /* each child's nearest entry over the rays */
			_mm_storeu_ps(key, _mm_min_ps(_mm_min_ps(e[0], e[1]), _mm_min_ps(e[2], e[3])));
			_MM_TRANSPOSE4_PS(e[0], e[1], e[2], e[3]);
			if (m) { /* nearest first; the others pushed farthest first */
				int cs[4], k = 0;
				for (int c = 0; c < 4; c++) {
					if (!(m >> c & 1))
						continue;
					int j = k++;
					for (; j > 0 && key[cs[j - 1]] > key[c]; j--)
						cs[j] = cs[j - 1];
					cs[j] = c;
				}
				for (int j = k - 1; j >= 1; j--) {
					stack[sp].idx = nd->idx[cs[j]];
					stack[sp].n = nd->n[cs[j]];
					stack[sp++].t = e[cs[j]];
				}
				idx = nd->idx[cs[0]];
				n = nd->n[cs[0]];
				tcur = e[cs[0]];
				continue;
			}
		}
		if (__builtin_expect(--polls == 0, 0)) { /* CANCELLATION, as bvh_hit */
			polls = ACCEL_POLL_POPS;
			if (cancel_poll())
				return;
		}
		/* pop the next subtree still in front of some ray's closest hit */
		for (;;) {
			if (sp == 0)
				return;
			sp--;
			if (lanes_in_front(stack[sp].t, tmax4, inf4))
				break;
		}
		idx = stack[sp].idx;
		n = stack[sp].n;
		tcur = stack[sp].t;
	}
}

/*
 * bvh_hit4 for four rays from one origin (the same floats in P->o's lanes):
 * each node's children are tested against the packet as a whole, with the
 * interval of the rays' inverses per axis. The plane less the origin, d,
 * is the same float for every ray, and fl(d * x) is monotonic in x, so the
 * smaller of d times the least and d times the greatest inverse is the
 * least entry distance over the rays on that axis, exactly, and the larger
 * of the far products the greatest exit; with the least tmin and greatest
 * tmax over the rays, a child that any ray's own test (RAY_NODE) lets
 * through passes. Leaves are tested for all four rays (the triangle
 * pre-test and the exact tests decide), a subtree popped while its entry
 * is within some ray's tmax.
 */
static inline __attribute__((always_inline)) void bvh_hit4o(const struct accel *A, const struct group *g,
							    struct trace tr[4], struct cand best[4], bool found[4],
							    const struct ray4x *P, const uint32_t oct)
{
	const struct bvh4 *nodes = g->bvh.nodes;
	const uint32_t near[3] = { 12 * (oct & 1), 4 + 12 * (oct >> 1 & 1), 8 + 12 * (oct >> 2 & 1) };
	const uint32_t far[3] = { 12 * (~oct & 1), 4 + 12 * (~oct >> 1 & 1), 8 + 12 * (~oct >> 2 & 1) };
	__m128 o[3], nlo[3], nhi[3], flo[3], fhi[3];
	for (int k = 0; k < 3; k++) {
		o[k] = _mm_shuffle_ps(P->o[k], P->o[k], 0); /* the shared origin */
		__m128 a = P->inv_near[k], b = P->inv_far[k];
		__m128 a2 = _mm_shuffle_ps(a, a, _MM_SHUFFLE(1, 0, 3, 2)), b2 = _mm_shuffle_ps(b, b, _MM_SHUFFLE(1, 0, 3, 2));
		__m128 amin = _mm_min_ps(a, a2), amax = _mm_max_ps(a, a2);
		__m128 bmin = _mm_min_ps(b, b2), bmax = _mm_max_ps(b, b2);
		nlo[k] = _mm_min_ps(amin, _mm_shuffle_ps(amin, amin, _MM_SHUFFLE(2, 3, 0, 1)));
		nhi[k] = _mm_max_ps(amax, _mm_shuffle_ps(amax, amax, _MM_SHUFFLE(2, 3, 0, 1)));
		flo[k] = _mm_min_ps(bmin, _mm_shuffle_ps(bmin, bmin, _MM_SHUFFLE(2, 3, 0, 1)));
		fhi[k] = _mm_max_ps(bmax, _mm_shuffle_ps(bmax, bmax, _MM_SHUFFLE(2, 3, 0, 1)));
	}
	const __m128 tmin1 = _mm_set1_ps(lanes_min(lanes_box_tmin(tr, P->tscale)));
	float tmax = -lanes_min(_mm_sub_ps(_mm_setzero_ps(), lanes_box_tmax(tr, P->tscale))); /* the greatest */
	struct {
		float t; /* the packet's least entry distance */
		uint32_t idx, n;
	} stack[3 * BVH_MAX_DEPTH + 4];
	int sp = 0;
	uint32_t idx = 0, n = 0;
	uint32_t polls = ACCEL_POLL_POPS;
	struct tri4 q; /* TRIANGLE PRE-TEST, set up at the first leaf that needs it */
	bool q_ready = false;
	for (;;) {
		if (n) {
			if (n & LEAF_BLOCK)
				leaf4_block(g, tr, best, found, &g->tblk[idx], n & ~LEAF_BLOCK, 15, &q, &q_ready);
			else
				leaf4(A, g, tr, best, found, idx, n, 15, &q, &q_ready);
			tmax = -lanes_min(_mm_sub_ps(_mm_setzero_ps(), lanes_box_tmax(tr, P->tscale)));
		} else {
			const struct bvh4 *nd = &nodes[idx];
			const float *b = (const float *)(const void *)nd; /* rows as in node4_hit */
			__m128 t0 = tmin1, t1 = _mm_set1_ps(tmax);
			for (int k = 0; k < 3; k++) {
				__m128 dn = _mm_sub_ps(_mm_loadu_ps(b + near[k]), o[k]);
				__m128 df = _mm_sub_ps(_mm_loadu_ps(b + far[k]), o[k]);
				t0 = _mm_max_ps(t0, _mm_min_ps(_mm_mul_ps(dn, nlo[k]), _mm_mul_ps(dn, nhi[k])));
				t1 = _mm_min_ps(t1, _mm_max_ps(_mm_mul_ps(df, flo[k]), _mm_mul_ps(df, fhi[k])));
			}
			int m = _mm_movemask_ps(_mm_cmple_ps(t0, t1));
			if (m) {
				float key[4];
				_mm_storeu_ps(key, t0);
				int cs[4], k = children_by_entry(m, key, cs);
				for (int j = k - 1; j >= 1; j--) {
					stack[sp].idx = nd->idx[cs[j]];
					stack[sp].n = nd->n[cs[j]];
					stack[sp++].t = key[cs[j]];
				}
				idx = nd->idx[cs[0]];
				n = nd->n[cs[0]];
				continue;
			}
		}
		if (__builtin_expect(--polls == 0, 0)) { /* CANCELLATION, as bvh_hit */
			polls = ACCEL_POLL_POPS;
			if (cancel_poll())
				return;
		}
		/* pop the next subtree still in front of some ray's closest hit */
		for (;;) {
			if (sp == 0)
				return;
			sp--;
			if (stack[sp].t <= tmax)
				break;
		}
		idx = stack[sp].idx;
		n = stack[sp].n;
	}
}

/* bvh_hit4o, one copy per octant. */
static __attribute__((noinline)) void group_hit4o(const struct accel *A, const struct group *g, struct trace tr[4],
						  struct cand best[4], bool found[4], const struct ray4x *P, uint32_t oct)
{
	switch (oct) {
	case 0: bvh_hit4o(A, g, tr, best, found, P, 0); break;
	case 1: bvh_hit4o(A, g, tr, best, found, P, 1); break;
	case 2: bvh_hit4o(A, g, tr, best, found, P, 2); break;
	case 3: bvh_hit4o(A, g, tr, best, found, P, 3); break;
	case 4: bvh_hit4o(A, g, tr, best, found, P, 4); break;
	case 5: bvh_hit4o(A, g, tr, best, found, P, 5); break;
	case 6: bvh_hit4o(A, g, tr, best, found, P, 6); break;
	default: bvh_hit4o(A, g, tr, best, found, P, 7); break;
	}
}

/* group_hit for four rays of one octant through g's tree (g->bvh.n_nodes4). */
static void group_hit4(const struct accel *A, const struct group *g, struct trace tr[4], uint32_t oct,
		       struct hit h[4], bool hit[4])
{
	struct cand best[4];
	bool found[4];
	struct ray4x P;
	for (int i = 0; i < 4; i++) {
		cand_init(&best[i]);
		found[i] = group_hit_unbounded(A, g, &tr[i], &best[i], false);
	}
	ray_box4(tr, g->center, &P);
	/* one origin, the same floats in every lane (eye rays of a pinhole
	 * camera): the whole-packet node test, which needs no rows per ray */
	__m128i same = _mm_set1_epi32(-1);
	for (int k = 0; k < 3; k++) {
		__m128i ok = _mm_castps_si128(P.o[k]);
		same = _mm_and_si128(same, _mm_cmpeq_epi32(ok, _mm_shuffle_epi32(ok, 0)));
	}
	if (_mm_movemask_epi8(same) == 0xffff) {
		group_hit4o(A, g, tr, best, found, &P, oct);
	} else {
		for (int k = 0; k < 3; k++) {
			__m128 a = P.o[k], b = P.inv_near[k], f = P.inv_far[k];
			P.lo[0][k] = _mm_shuffle_ps(a, a, 0x00), P.lo[1][k] = _mm_shuffle_ps(a, a, 0x55);
			P.lo[2][k] = _mm_shuffle_ps(a, a, 0xaa), P.lo[3][k] = _mm_shuffle_ps(a, a, 0xff);
			P.lnear[0][k] = _mm_shuffle_ps(b, b, 0x00), P.lnear[1][k] = _mm_shuffle_ps(b, b, 0x55);
			P.lnear[2][k] = _mm_shuffle_ps(b, b, 0xaa), P.lnear[3][k] = _mm_shuffle_ps(b, b, 0xff);
			P.lfar[0][k] = _mm_shuffle_ps(f, f, 0x00), P.lfar[1][k] = _mm_shuffle_ps(f, f, 0x55);
			P.lfar[2][k] = _mm_shuffle_ps(f, f, 0xaa), P.lfar[3][k] = _mm_shuffle_ps(f, f, 0xff);
		}
		switch (oct) { /* one copy of the loop per octant, as group_hit */
		case 0: bvh_hit4(A, g, tr, best, found, &P, 0); break;
		case 1: bvh_hit4(A, g, tr, best, found, &P, 1); break;
		case 2: bvh_hit4(A, g, tr, best, found, &P, 2); break;
		case 3: bvh_hit4(A, g, tr, best, found, &P, 3); break;
		case 4: bvh_hit4(A, g, tr, best, found, &P, 4); break;
		case 5: bvh_hit4(A, g, tr, best, found, &P, 5); break;
		case 6: bvh_hit4(A, g, tr, best, found, &P, 6); break;
		default: bvh_hit4(A, g, tr, best, found, &P, 7); break;
		}
	}
	for (int i = 0; i < 4; i++) {
		hit[i] = found[i];
		if (found[i])
			finish(A, g, &tr[i], &best[i], &h[i]);
	}
}

/*
 * The any-hit packet traversal of g's bounded references for the rays
 * (lanes) in *active: a subtree is visited when an active ray may hit it
 * (children in slot order, as group_occluded_t), each stack entry keeps
 * the lanes that met its box, and a leaf's references are each tested
 * against those of its lanes still active. A ray leaves *active at its
 * first blocker (*hint then names it); the walk ends when no ray is left.
 * Every ray tests what group_occluded_t would let it test, perhaps more:
 * anything hit blocks, so its answer is the same.
 */
static inline __attribute__((always_inline)) void bvh_occluded4(const struct accel *A, const struct group *g,
								struct trace tr[4], unsigned *active, uint32_t *hint,
								const struct ray4x *P, const uint32_t oct)
{
	const struct bvh4 *nodes = g->bvh.nodes;
	const uint32_t near[3] = { 12 * (oct & 1), 4 + 12 * (oct >> 1 & 1), 8 + 12 * (oct >> 2 & 1) };
	const uint32_t far[3] = { 12 * (~oct & 1), 4 + 12 * (~oct >> 1 & 1), 8 + 12 * (~oct >> 2 & 1) };
	const __m128 tmin4 = lanes_box_tmin(tr, P->tscale), tmax4 = lanes_box_tmax(tr, P->tscale);
	struct {
		uint32_t idx, n;
		unsigned lanes; /* the rays that met the subtree's box */
	} stack[3 * BVH_MAX_DEPTH + 4];
	int sp = 0;
	unsigned act = *active, lanes = act;
	uint32_t idx = 0, n = 0;
	uint32_t polls = ACCEL_POLL_POPS;
	for (;;) {
		if (n & LEAF_BLOCK) { /* the block's references; no pre-test (it did not pay here) */
			const float *tb = &g->tblk[idx];
			uint32_t nt = n & ~LEAF_BLOCK;
			for (uint32_t k = 0; k < nt && (lanes &= act); k++) {
				uint32_t ref = blk_ref(tb, nt, k);
				for (unsigned l = lanes; l; l &= l - 1) {
					int i = __builtin_ctz(l);
					if (tri_occludes(g, ref, &tr[i])) {
						act &= ~(1u << i);
						*hint = ref;
					}
				}
			}
			if (!act)
				break;
		} else if (n) {
			for (uint32_t k = 0; k < n && (lanes &= act); k++) {
				uint32_t ref = group_ref(g, idx + k);
				for (unsigned l = lanes; l; l &= l - 1) {
					int i = __builtin_ctz(l);
					if (ref_occludes(A, g, ref, &tr[i])) {
						act &= ~(1u << i);
						*hint = ref;
					}
				}
			}
			if (!act)
				break;
		} else {
			const struct bvh4 *nd = &nodes[idx];
			const float *b = (const float *)(const void *)nd; /* rows as in node4_hit */
			unsigned m[4];
			for (int c = 0; c < 4; c++) {
				__m128 t0 = tmin4, t1 = tmax4;
				for (int k = 0; k < 3; k++) {
					__m128 tn = _mm_mul_ps(_mm_sub_ps(_mm_set1_ps(b[near[k] + (uint32_t)c]), P->o[k]),
							       P->inv_near[k]);
					__m128 tf = _mm_mul_ps(_mm_sub_ps(_mm_set1_ps(b[far[k] + (uint32_t)c]), P->o[k]),
							       P->inv_far[k]);
					t0 = _mm_max_ps(t0, tn);
					t1 = _mm_min_ps(t1, tf);
				}
				m[c] = (unsigned)_mm_movemask_ps(_mm_cmple_ps(t0, t1)) & act;
			}
			int first = -1;
			for (int c = 3; c >= 0; c--) {
				if (!m[c])
					continue;
				if (first >= 0) {
					stack[sp].idx = nd->idx[first];
					stack[sp].n = nd->n[first];
					stack[sp++].lanes = m[first];
				}
				first = c;
			}
			if (first >= 0) {
				idx = nd->idx[first];
				n = nd->n[first];
				lanes = m[first];
				continue;
			}
		}
		if (__builtin_expect(--polls == 0, 0)) { /* CANCELLATION, as bvh_hit */
			polls = ACCEL_POLL_POPS;
			if (cancel_poll())
				break;
		}
		/* pop the next subtree some active ray meets */
		for (;;) {
			if (sp == 0)
				goto out;
			sp--;
			if (stack[sp].lanes & act)
				break;
		}
		idx = stack[sp].idx;
		n = stack[sp].n;
		lanes = stack[sp].lanes;
	}
out:
	*active = act;
}

/* The four rays' box constants (struct ray4x) in group g's frame. */
static void ray4x_init(struct ray4x *P, const struct trace tr[4], const struct group *g)
{
	ray_box4(tr, g->center, P);
}

/* accel_occluded4's packet query in g (g->bvh.n_nodes4, no big leaves) for
 * four rays of one octant: unbounded references and the hint ray by ray,
 * then the tree for the rays not yet blocked. */
static void group_occluded4(const struct accel *A, const struct group *g, struct trace tr[4], uint32_t oct,
			    bool occ[4], uint32_t *hint)
{
	unsigned active = 0;
	for (int i = 0; i < 4; i++) {
		bool blocked = false;
		for (uint32_t k = 0; k < g->n_unb && !blocked; k++) {
			if (cancel_poll_every(k)) /* CANCELLATION, as unb_hit */
				break;
			if (ref_occludes(A, g, g->unb[k], &tr[i])) {
				blocked = true;
				*hint = g->unb[k];
			}
		}
		if (!blocked)
			blocked = hint_occludes(A, g, *hint, &tr[i]);
		active |= (unsigned)!blocked << i;
	}
	if (active) {
		struct ray4x P;
		ray4x_init(&P, tr, g);
		switch (oct) { /* one copy of the loop per octant, as group_hit */
		case 0: bvh_occluded4(A, g, tr, &active, hint, &P, 0); break;
		case 1: bvh_occluded4(A, g, tr, &active, hint, &P, 1); break;
		case 2: bvh_occluded4(A, g, tr, &active, hint, &P, 2); break;
		case 3: bvh_occluded4(A, g, tr, &active, hint, &P, 3); break;
		case 4: bvh_occluded4(A, g, tr, &active, hint, &P, 4); break;
		case 5: bvh_occluded4(A, g, tr, &active, hint, &P, 5); break;
		case 6: bvh_occluded4(A, g, tr, &active, hint, &P, 6); break;
		default: bvh_occluded4(A, g, tr, &active, hint, &P, 7); break;
		}
	}
	for (int i = 0; i < 4; i++)
		occ[i] = !(active >> i & 1);
	if (active == 15)
		*hint = ACCEL_NO_HINT; /* as accel_occluded_hint */
}
#endif

/* ---- public queries ----------------------------------------------------------------- */

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

bool accel_intersect(const struct accel *a, const struct ray *r, struct hit *h)
{
	if (!a->root || !ray_ok(r))
		return false;
	struct trace t;
	trace_init(&t, r->o, r->d, ray_tmin(r), r->tmax);
	return group_hit(a, a->root, &t, h, false);
}

#if defined(__SSE2__)
/* Whether the four rays can be traced as a packet through the root's tree
 * (all valid, one octant, a 4-wide tree): then tr and *oct are set up. */
static inline bool packet_start(const struct accel *a, const struct ray r[4], struct trace tr[4], uint32_t *oct)
{
	const struct group *g = a->root;
	if (!g || g->bvh.root_n || !g->bvh.n_nodes4 || g->big_leaf)
		return false;
	*oct = ray_octant(r[0].d);
	for (int i = 0; i < 4; i++)
		if (!ray_ok(&r[i]) || ray_octant(r[i].d) != *oct)
			return false;
	for (int i = 0; i < 4; i++)
		trace_init(&tr[i], r[i].o, r[i].d, ray_tmin(&r[i]), r[i].tmax);
	return true;
}
#endif

void accel_intersect4(const struct accel *a, const struct ray r[4], struct hit h[4], bool hit[4])
{
#if defined(__SSE2__)
	struct trace tr[4];
	uint32_t oct;
	if (packet_start(a, r, tr, &oct)) {
		group_hit4(a, a->root, tr, oct, h, hit);
		return;
	}
#endif
	for (int i = 0; i < 4; i++) /* rays of different octants, a root without a tree */
		hit[i] = accel_intersect(a, &r[i], &h[i]);
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

void accel_occluded4(const struct accel *a, const struct ray r[4], bool occ[4], uint32_t *hint)
{
#if defined(__SSE2__)
	struct trace tr[4];
	uint32_t oct;
	if (packet_start(a, r, tr, &oct)) {
		group_occluded4(a, a->root, tr, oct, occ, hint);
		return;
	}
#endif
	for (int i = 0; i < 4; i++) /* rays of different octants, a root without a tree */
		occ[i] = accel_occluded_hint(a, &r[i], hint);
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
