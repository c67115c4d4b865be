/*
 * accel.c - the scene's objects as a multi-level BVH.
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
 *              the object's space through its inverse transform
 *   instances  (inverse transform as 12 floats, instance object): 52 bytes
 *              each, evaluated in double; the instance's geometry is exactly
 *              the inverse of that float matrix, used consistently for rays,
 *              normals and bounds; a group of ACCEL_PACK_MIN or more
 *              instances and no other bounded reference keeps them in leaf
 *              order without reference words, in leaves of up to
 *              ACCEL_INST_LEAF (issue 3: <= 64 bytes per instance)
 * Unbounded references (planes, CSG with an infinite extent, instances of
 * groups holding those) sit in a list tested for every ray. The BVH is
 * binned SAH (bvh.c) collapsed to 4-wide nodes; traversal is iterative with
 * a fixed stack, nearest child first, and stops at the first hit for
 * accel_occluded. Instances recurse into their define's group (depth
 * bounded by LIM_DEFINE_DEPTH); the closest hit is completed (normal, uv,
 * mp, material) once per group, in the group's space, then carried out
 * through each instance's transform. In the root group, u, v and mp of
 * untransformed spheres (default pole and equator) and of triangles are
 * left to accel_hit_surface (hit.surf_fn), which the shader calls only for
 * materials with a shader; inside instances they are completed at once.
 * The traversal loop exists once per ray octant (bvh_hit's oct), so the
 * node test reads each axis' near and far planes at constant offsets.
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
 */
#include "common/accel.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "common/bvh.h"
#include "common/geom.h"

enum { REF_SPHERE = 0, REF_TRI = 1, REF_XPRIM = 2, REF_INST = 3 };
#define REF_MAKE(k, i) ((uint32_t)(k) << 30 | (uint32_t)(i))
#define REF_KIND(r) ((r) >> 30)
#define REF_IDX(r) ((r) & 0x3fffffffu)
/* references per group: 30 bits of index */
#define ACCEL_MAX_REFS (1u << 30)
/* primitives per BVH leaf */
#define ACCEL_MAX_LEAF 4
/* instances per leaf in a group of at least ACCEL_PACK_MIN instances and
 * nothing else bounded, every subtree this small made a leaf: fewer
 * 128-byte nodes per instance (issue 3's budget of 64 bytes per instance)
 * at the cost of more instance tests, so only where instances are many */
#define ACCEL_INST_LEAF 8
#define ACCEL_PACK_MIN 1024

struct gsphere {
	vec3 c;
	double r2;
	uint32_t obj; /* object index, | GSPH_FRAME when its pole/equator are not the default */
	uint32_t mat; /* the object's material (finish reads no scene object) */
};
/* gsphere.obj flag (object indices are below LIM_OBJECTS = 2^26) */
#define GSPH_FRAME 0x80000000u
_Static_assert(LIM_OBJECTS <= GSPH_FRAME, "object indices leave gsphere.obj's flag bit free");

/* A mesh slot: one raw object or one plain triangle. */
struct gmesh {
	const vec3 *v;      /* vertices in the group's space */
	const vec3 *n;      /* normals in the group's space, or NULL */
	const vec3 *ov;     /* vertices in the object's own space (for mp, uv) */
	const vec3 *fn;     /* a plain triangle's unit face normal (from v, as finish
			       computes it), or NULL (raw meshes: computed per hit) */
	const uint32_t *ix; /* 3 per triangle */
	uint32_t obj;
	uint32_t mat;       /* the object's material (finish reads no scene object) */
};

/* hit.surf_kind: what surface_complete completes */
enum { SURF_SPHERE, SURF_TRI, SURF_XPRIM };

struct gtri {
	uint32_t mesh, tri;
};

struct xprim {
	const struct geom_obj *g;
	uint32_t obj;
};

struct ginst {
	float inv[12]; /* parent -> define space, row-major 3x4 */
	uint32_t obj;  /* the instance object (its define gives the group) */
};

struct group {
	struct bvh bvh;
	uint32_t *refs; /* bounded references in leaf order; NULL in a group of
			   instances only: reference k is then instance k (group_ref) */
	uint32_t n_refs;
	uint32_t *unb;  /* unbounded references */
	uint32_t n_unb;
	struct gsphere *sph;
	uint32_t n_sph;
	struct gmesh *mesh;
	uint32_t n_mesh;
	struct gtri *tri;
	uint32_t n_tri;
	struct xprim *xp;
	uint32_t n_xp;
	struct ginst *inst;
	uint32_t n_inst;
	vec3 *bake;     /* baked vertices and normals (owned) */
	struct geom_box bounds; /* of the bounded references */
	const struct geom_obj *plane1; /* the only unbounded reference when it is an
					  untransformed plane (tested inline), else NULL */
	vec3 center;    /* node bounds are relative to this point */
	size_t bytes;
};

struct accel {
	const struct scene *s;
	struct geom_obj **gobj;   /* per object, built on demand; NULL until needed (owned) */
	struct group **dgroup;    /* per define, built on first use (owned) */
	struct group *root;
	struct accel_stats st;
};

static const uint32_t tri_ix012[3] = { 0, 1, 2 };

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

/*
 * BOX TESTS IN FLOAT, KEPT CONSERVATIVE. Node bounds are floats relative
 * to the group's centre, rounded outward, and every item box is padded by
 * BOX_PAD_REL times the largest coordinate magnitude M about that centre
 * before the build. The ray's origin is taken relative to the centre (in
 * double), its direction scaled exactly by a power of two so that the
 * largest component is in [1, 2) (t scales by the same power), then both
 * are rounded to float. Errors: the origin's rounding moves it by at most
 * 2^-24 |o|: when |o| <= 2M that is below the padding; when |o| > 2M it is
 * at most 2^-23 of the distance to the box, covered by widening every
 * entry/exit distance by BOX_WIDEN relative (which also covers the rounding
 * of the subtraction, of the inverse and of the product, and of tmin/tmax
 * to float). Zero direction components get an inverse of +-1e30 (never
 * inf, so never inf * 0 = NaN); the padding keeps that exact enough.
 * Primitive tests stay in double, so a box test can only let through more,
 * never cull a true hit: BVH and brute force give the same answers
 * (tests/unit/test_bvh.c checks).
 */
#define BOX_PAD_REL 0x1p-19
#define BOX_WIDEN 0x1p-20

struct ray4 {
#if defined(__SSE2__)
	__m128 o[3], inv[3];
#else
	float o[3], inv[3];
#endif
	/* the direction's octant: bit k set when d[k] is negative (its sign
	 * bit, -0 included: the sign of inv[k]); picks the near plane of each
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

static inline void ray4_init(struct ray4 *q, const struct trace *r, vec3 center)
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
		float iv = (float)(fabs(dk) > 1e-30 ? 1.0 / dk : copysign(1e30, dk));
#if defined(__SSE2__)
		q->o[k] = _mm_set1_ps((float)o[k]);
		q->inv[k] = _mm_set1_ps(iv);
#else
		q->o[k] = (float)o[k];
		q->inv[k] = iv;
#endif
	}
}

/*
 * Slab test of the four children of nd against [tmin, tmax] (box space).
 * Returns a mask (bit c: child c may be hit) and the widened entry
 * distances in tn.
 *
 * The near plane of each axis is chosen once per ray by the direction's
 * sign (ray4.near/far). This is exactly the old min/max form: inv is never
 * 0, inf or NaN, and lo <= hi, so (lo - o) * inv and (hi - o) * inv are
 * ordered by inv's sign (rounding is monotonic); min/max would pick the
 * same values (up to the sign of a zero, which no comparison sees). NaN
 * bounds (unused slots) never hit: max returns its second operand when one
 * is NaN, as SSE's does, so t0 becomes NaN and t0 <= t1 fails.
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
		__m128 tnear = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(b + near[k]), q->o[k]), q->inv[k]);
		__m128 tfar = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(b + far[k]), q->o[k]), q->inv[k]);
		t0 = _mm_max_ps(t0, tnear);
		t1 = _mm_min_ps(t1, tfar);
	}
	const __m128 absmask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff)), w = _mm_set1_ps(BOX_WIDEN);
	t0 = _mm_sub_ps(t0, _mm_mul_ps(_mm_and_ps(t0, absmask), w));
	t1 = _mm_add_ps(t1, _mm_mul_ps(_mm_and_ps(t1, absmask), w));
	_mm_storeu_ps(tn, t0);
	return _mm_movemask_ps(_mm_cmple_ps(t0, t1));
#else
	int mask = 0;
	for (int c = 0; c < 4; c++) {
		float t0 = tmin, t1 = tmax;
		for (int k = 0; k < 3; k++) {
			float tnear = (b[near[k] + (uint32_t)c] - q->o[k]) * q->inv[k];
			float tfar = (b[far[k] + (uint32_t)c] - q->o[k]) * q->inv[k];
			t0 = t0 > tnear ? t0 : tnear; /* _mm_max_ps(t0, tnear) */
			t1 = t1 < tfar ? t1 : tfar;   /* _mm_min_ps(t1, tfar) */
		}
		t0 -= fabsf(t0) * BOX_WIDEN;
		t1 += fabsf(t1) * BOX_WIDEN;
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
	double t, b1, b2;
	int part;
	struct hit sub; /* instances and CSG: the finished hit in the group's space */
};

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

static inline const uint32_t *tri_ix(const struct gmesh *m, uint32_t tri) { return m->ix + 3 * (size_t)tri; }

/* The unit face normal of triangle ix of m, from its group-space vertices. */
static inline vec3 tri_normal(const struct gmesh *m, const uint32_t *ix)
{
	vec3 a = m->v[ix[0]], b = m->v[ix[1]], cc = m->v[ix[2]];
	return v3_norm(v3_cross(v3_sub(b, a), v3_sub(cc, a)));
}

static void inst_matrix(const struct ginst *in, mat34 *m)
{
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 4; j++)
			m->m[i][j] = in->inv[4 * i + j];
}

/*
 * Intersects instance `in` with r (parent space); on a hit closer than
 * r->tmax fills *h in the parent space (h->p excepted) and returns true.
 */
static bool inst_hit(const struct accel *A, const struct ginst *in, const struct trace *r, struct hit *h, bool brute)
{
	mat34 inv;
	inst_matrix(in, &inv);
	struct trace lr;
	trace_init(&lr, m34_point(&inv, r->o), m34_dir(&inv, r->d), r->tmin, r->tmax);
	struct hit lh;
	if (!group_hit(A, A->dgroup[A->s->objects[in->obj].u.instance.define], &lr, &lh, brute))
		return false;
	surface_complete(A->s, &lh); /* in the define's space */
	h->t = lh.t;
	h->n = v3_norm(m34_normal(&inv, lh.n));
	h->ng = v3_norm(m34_normal(&inv, lh.ng));
	h->u = lh.u;
	h->v = lh.v;
	h->object = lh.object;
	uint32_t im = A->s->objects[in->obj].material;
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
	mat34 inv;
	inst_matrix(in, &inv);
	struct trace lr;
	trace_init(&lr, m34_point(&inv, r->o), m34_dir(&inv, r->d), r->tmin, r->tmax);
	return group_occluded(A, A->dgroup[A->s->objects[in->obj].u.instance.define], &lr);
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
	if (!geom_intersect(go, o, d, r->tmin, r->tmax, &t, &part))
		return false;
	c->part = part;
	c->ref = ref;
	c->t = t;
	r->tmax = t;
	return true;
}

static __attribute__((noinline)) bool ref_test_slow(const struct accel *A, const struct group *g, uint32_t ref,
						     struct trace *r, struct cand *c, bool brute)
{
	uint32_t i = REF_IDX(ref);
	double t;
	if (REF_KIND(ref) == REF_XPRIM) {
		const struct xprim *x = &g->xp[i];
		if (x->g->kind != PRIM_CSG)
			return xprim_test(x->g, ref, r, c);
		struct hit hh;
		if (!csg_hit(A->s, (struct geom_obj *const *)A->gobj, x->obj, r->o, r->d, r->tmin, r->tmax, &hh))
			return false;
		t = hh.t;
		c->sub = hh;
	} else {
		struct hit hh;
		if (!inst_hit(A, &g->inst[i], r, &hh, brute))
			return false;
		t = hh.t;
		c->sub = hh;
	}
	c->ref = ref;
	c->t = t;
	r->tmax = t;
	return true;
}

/* Tests one reference; on a hit closer than r->tmax records it in *c and
 * shrinks r->tmax. */
static inline __attribute__((always_inline)) bool ref_test(const struct accel *A, const struct group *g,
							    uint32_t ref, struct trace *r, struct cand *c, bool brute)
{
	uint32_t i = REF_IDX(ref);
	double t;
	switch (REF_KIND(ref)) {
	case REF_SPHERE:
		if (!sphere_test(&g->sph[i], r, &t))
			return false;
		break;
	case REF_TRI: {
		const struct gmesh *m = &g->mesh[g->tri[i].mesh];
		const uint32_t *ix = tri_ix(m, g->tri[i].tri);
		double b1, b2;
		if (!geom_tri_hit_p(trace_wray(r), &m->v[ix[0]], &m->v[ix[1]], &m->v[ix[2]], r->tmin, r->tmax, &t, &b1, &b2))
			return false;
		c->b1 = b1;
		c->b2 = b2;
		break;
	}
	case REF_XPRIM: {
		const struct geom_obj *go = g->xp[i].g;
		if (go->kind != PRIM_CSG)
			return xprim_test(go, ref, r, c);
		return ref_test_slow(A, g, ref, r, c, brute);
	}
	default:
		return ref_test_slow(A, g, ref, r, c, brute);
	}
	c->ref = ref;
	c->t = t;
	r->tmax = t;
	return true;
}

/* Any hit in (tmin, tmax) of one reference. */
static inline bool ref_occludes(const struct accel *A, const struct group *g, uint32_t ref, struct trace *r)
{
	uint32_t i = REF_IDX(ref);
	if (REF_KIND(ref) == REF_INST)
		return inst_occluded(A, &g->inst[i], r);
	struct cand c;
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
			/* spheres' and cylinders' mappings (atan2, asin) later, from mp */
			bool lazy = go->kind == PRIM_SPHERE || go->kind == PRIM_CYLINDER;
			if (lazy) {
				n = geom_normal(go, lp, c->part);
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
			h->material = s->objects[h->object].material;
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
		const struct prim_sphere *ps = &s->objects[h->object].u.sphere;
		vec3 q = h->n;
		double phi = atan2(-q.z, q.x);
		if (phi < 0)
			phi += 2 * M_PI;
		h->u = ps->radius * (phi >= 2 * M_PI ? 0 : phi);
		h->v = ps->radius * (asin(q.y > 1 ? 1 : q.y < -1 ? -1 : q.y) + M_PI / 2);
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
		uint32_t ref = g->unb[k];
		const struct geom_obj *go = REF_KIND(ref) == REF_XPRIM ? g->xp[REF_IDX(ref)].g : NULL;
		if (go && go->kind == PRIM_PLANE && !go->has_xform) { /* geom_intersect's plane test, inline */
			double t;
			if (geom_plane_t(go->u.pl.pos, go->u.pl.n, r->o, r->d, &t) && t > r->tmin && t < r->tmax) {
				best->ref = ref;
				best->t = r->tmax = t;
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
		if (sphere_test(&g->sph[k], r, &t)) {
			best->ref = REF_MAKE(REF_SPHERE, k);
			best->t = r->tmax = t;
			found = true;
		}
	}
	for (uint32_t k = 0; k < g->n_tri;) { /* a mesh's triangles are consecutive */
		const struct gmesh *m = &g->mesh[g->tri[k].mesh];
		uint32_t mi = g->tri[k].mesh;
		for (; k < g->n_tri && g->tri[k].mesh == mi; k++) {
			const uint32_t *ix = tri_ix(m, g->tri[k].tri);
			double t, b1, b2;
			if (geom_tri_hit(trace_wray(r), m->v[ix[0]], m->v[ix[1]], m->v[ix[2]], r->tmin, r->tmax, &t, &b1, &b2)) {
				best->ref = REF_MAKE(REF_TRI, k);
				best->t = r->tmax = t;
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

/* The BVH traversal of g's bounded references: nearest child first,
 * subtrees behind the closest hit so far popped and dropped. Same contract
 * as ref_test. */
static inline __attribute__((always_inline)) bool bvh_hit(const struct accel *A, const struct group *g,
							   struct trace *r, struct cand *best, const struct ray4 *qp,
							   const uint32_t oct)
{
	bool found = false;
	const struct bvh4 *nodes = g->bvh.nodes;
	const struct ray4 q = *qp;
	const tspan tmin = tspan_of((float)(r->tmin * q.tscale));
	float tmax = (float)(r->tmax * q.tscale);
	tspan tmax4 = tspan_of(tmax);
	struct {
		uint32_t idx, n;
		float t;
	} stack[3 * BVH_MAX_DEPTH + 4];
	int sp = 0;
	uint32_t idx = 0, n = 0;
	for (;;) {
		if (n) {
			for (uint32_t k = 0; k < n; k++)
				found |= ref_test(A, g, group_ref(g, idx + k), r, best, false);
			tmax = (float)(r->tmax * q.tscale);
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
				int cs[4], k = 0;
				for (int c = 0; c < 4; c++) {
					if (!(m >> c & 1))
						continue;
					int j = k++;
					for (; j > 0 && tn[cs[j - 1]] > tn[c]; j--)
						cs[j] = cs[j - 1];
					cs[j] = c;
				}
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

/* Closest hit in group g; fills *h (group space) only on success. */
static bool group_hit(const struct accel *A, const struct group *g, struct trace *r, struct hit *h, bool brute)
{
	struct cand best;
	bool found = false;
	if (g->plane1) { /* unb_hit's plane test, the common case of one ground plane */
		double t;
		const struct geom_obj *go = g->plane1;
		if (geom_plane_t(go->u.pl.pos, go->u.pl.n, r->o, r->d, &t) && t > r->tmin && t < r->tmax) {
			best.ref = g->unb[0];
			best.t = r->tmax = t;
			best.part = GEOM_PART_MAIN;
			found = true;
		}
	} else if (g->n_unb) {
		found = unb_hit(A, g, r, &best, brute);
	}
	if (brute) {
		found |= brute_hit(A, g, r, &best);
	} else if (g->bvh.root_n) { /* the root is one leaf */
		if (box_hit(g->bvh.root_b, g->center, r))
			for (uint32_t k = 0; k < g->bvh.root_n; k++)
				found |= ref_test(A, g, group_ref(g, g->bvh.root_idx + k), r, &best, false);
	} else if (g->bvh.n_nodes4) {
		struct ray4 q4;
		ray4_init(&q4, r, g->center);
		switch (q4.oct) { /* one copy of the loop per octant: near planes at fixed offsets */
		case 0: found |= bvh_hit(A, g, r, &best, &q4, 0); break;
		case 1: found |= bvh_hit(A, g, r, &best, &q4, 1); break;
		case 2: found |= bvh_hit(A, g, r, &best, &q4, 2); break;
		case 3: found |= bvh_hit(A, g, r, &best, &q4, 3); break;
		case 4: found |= bvh_hit(A, g, r, &best, &q4, 4); break;
		case 5: found |= bvh_hit(A, g, r, &best, &q4, 5); break;
		case 6: found |= bvh_hit(A, g, r, &best, &q4, 6); break;
		default: found |= bvh_hit(A, g, r, &best, &q4, 7); break;
		}
	}
	if (found)
		finish(A, g, r, &best, h);
	return found;
}

static bool group_occluded(const struct accel *A, const struct group *g, struct trace *r)
{
	for (uint32_t k = 0; k < g->n_unb; k++)
		if (ref_occludes(A, g, g->unb[k], r))
			return true;
	if (g->bvh.root_n) {
		if (box_hit(g->bvh.root_b, g->center, r))
			for (uint32_t k = 0; k < g->bvh.root_n; k++)
				if (ref_occludes(A, g, group_ref(g, g->bvh.root_idx + k), r))
					return true;
		return false;
	}
	if (!g->bvh.n_nodes4)
		return false;
	const struct bvh4 *nodes = g->bvh.nodes;
	struct ray4 q;
	ray4_init(&q, r, g->center);
	const tspan tmin = tspan_of((float)(r->tmin * q.tscale)), tmax = tspan_of((float)(r->tmax * q.tscale));
	struct {
		uint32_t idx, n;
	} stack[3 * BVH_MAX_DEPTH + 4];
	int sp = 0;
	uint32_t idx = 0, n = 0;
	for (;;) {
		if (n) {
			for (uint32_t k = 0; k < n; k++)
				if (ref_occludes(A, g, group_ref(g, idx + k), r))
					return true;
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
		if (sp == 0)
			return false;
		sp--;
		idx = stack[sp].idx;
		n = stack[sp].n;
	}
}

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

bool accel_intersect(const struct accel *a, const struct ray *r, struct hit *h)
{
	if (!a->root || !ray_ok(r))
		return false;
	struct trace t;
	trace_init(&t, r->o, r->d, r->tmin, r->tmax);
	return group_hit(a, a->root, &t, h, false);
}

bool accel_intersect_brute(const struct accel *a, const struct ray *r, struct hit *h)
{
	if (!a->root || !ray_ok(r))
		return false;
	struct trace t;
	trace_init(&t, r->o, r->d, r->tmin, r->tmax);
	return group_hit(a, a->root, &t, h, true);
}

bool accel_occluded(const struct accel *a, const struct ray *r)
{
	if (!a->root || !ray_ok(r))
		return false;
	struct trace t;
	trace_init(&t, r->o, r->d, r->tmin, r->tmax);
	return group_occluded(a, a->root, &t);
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

/* ---- building ------------------------------------------------------------------------ */

static void group_free(struct group *g)
{
	if (!g)
		return;
	bvh_free(&g->bvh);
	free(g->refs);
	free(g->unb);
	free(g->sph);
	free(g->mesh);
	free(g->tri);
	free(g->xp);
	free(g->inst);
	free(g->bake);
	free(g);
}

void accel_free(struct accel *a)
{
	if (!a)
		return;
	if (a->gobj) {
		for (uint32_t i = 0; i < a->s->n_objects; i++) {
			geom_obj_clear(a->gobj[i]);
			free(a->gobj[i]);
		}
		free(a->gobj);
	}
	if (a->dgroup) {
		for (uint32_t i = 0; i < a->s->n_defines; i++)
			group_free(a->dgroup[i]);
		free(a->dgroup);
	}
	group_free(a->root);
	free(a);
}

/* The geom_obj of object i, made on first use; NULL when out of memory. */
static struct geom_obj *get_gobj(struct accel *A, uint32_t i)
{
	if (!A->gobj) { /* the table exists only in scenes that need it */
		A->gobj = calloc((size_t)A->s->n_objects + 1, sizeof *A->gobj);
		if (!A->gobj)
			return NULL;
		A->st.bytes += ((size_t)A->s->n_objects + 1) * sizeof *A->gobj;
	}
	if (!A->gobj[i]) {
		struct geom_obj *g = malloc(sizeof *g);
		if (!g)
			return NULL;
		if (geom_obj_init(A->s, i, g) < 0) {
			free(g);
			return NULL;
		}
		A->gobj[i] = g;
		A->st.bytes += sizeof *g;
		if (g->kind == PRIM_POLYGON)
			A->st.bytes += g->u.poly.n_points * 2 * sizeof(double);
	}
	return A->gobj[i];
}

/* Makes the geom_obj of obj and of everything below it (CSG subtrees). */
static int prep_tree(struct accel *A, uint32_t obj)
{
	if (!get_gobj(A, obj))
		return -1;
	const struct scene_object *o = &A->s->objects[obj];
	if (o->kind == PRIM_CSG)
		return prep_tree(A, o->u.csg.operand1) || prep_tree(A, o->u.csg.operand2) ? -1 : 0;
	if (o->kind == PRIM_INSTANCE) {
		const struct scene_define *d = &A->s->defines[o->u.instance.define];
		for (uint32_t k = 0; k < d->n_objects; k++)
			if (prep_tree(A, d->objects[k]))
				return -1;
	}
	return 0;
}

/* Pads a box by a relative epsilon so double rounding never culls a hit. */
static struct geom_box pad_box(struct geom_box b)
{
	double m = fmax(fmax(fabs(b.lo.x), fabs(b.lo.y)), fmax(fabs(b.lo.z), fabs(b.hi.x)));
	m = fmax(m, fmax(fabs(b.hi.y), fabs(b.hi.z)));
	double e = 1e-9 * m + 1e-300;
	vec3 ev = v3(e, e, e);
	b.lo = v3_sub(b.lo, ev);
	b.hi = v3_add(b.hi, ev);
	return b;
}

static struct group *build_group(struct accel *A, const uint32_t *objs, uint32_t n, struct scene_error *err);

/* Bounded references and their boxes while a group is built (grows). */
struct refbuf {
	uint32_t *ref;
	struct geom_box *box;
	uint32_t n, cap;
};

static int refbuf_push(struct refbuf *b, uint32_t ref, struct geom_box box)
{
	if (b->n == b->cap) {
		if (b->cap >= ACCEL_MAX_REFS)
			return -1;
		uint32_t nc = b->cap ? (b->cap > ACCEL_MAX_REFS / 2 ? ACCEL_MAX_REFS : b->cap * 2) : 64;
		uint32_t *nr = realloc(b->ref, (size_t)nc * sizeof *nr);
		if (!nr)
			return -1;
		b->ref = nr;
		struct geom_box *nbx = realloc(b->box, (size_t)nc * sizeof *nbx);
		if (!nbx)
			return -1;
		b->box = nbx;
		b->cap = nc;
	}
	b->ref[b->n] = ref;
	b->box[b->n++] = box;
	return 0;
}

/* Early split clipping: a triangle whose box is SPLIT_RATIO times its own
 * area or more (long diagonal slivers, as ear-clipped gear faces make) is
 * referenced by the boxes of its pieces clipped to halves of its box, down
 * to SPLIT_DEPTH levels. The pieces cover the triangle; a ray meeting it
 * through two pieces tests it twice and keeps the one t. */
#define SPLIT_RATIO 24.0
#define SPLIT_DEPTH 3

/* Clips convex polygon p (n <= 9 + depth vertices) to the side of the plane
 * x[axis] = at given by keep_below; returns the new count (out has room). */
static int clip_half(const vec3 *p, int n, int axis, double at, bool keep_below, vec3 *out)
{
	int m = 0;
	for (int i = 0; i < n; i++) {
		vec3 a = p[i], b = p[(i + 1) % n];
		double da = v3_comp(a, axis) - at, db = v3_comp(b, axis) - at;
		if (!keep_below)
			da = -da, db = -db;
		if (da <= 0)
			out[m++] = a;
		if ((da < 0 && db > 0) || (da > 0 && db < 0)) {
			vec3 x = v3_lerp(a, b, da / (da - db));
			if (axis == 0)
				x.x = at;
			else if (axis == 1)
				x.y = at;
			else
				x.z = at;
			out[m++] = x;
		}
	}
	return m;
}

static int push_pieces(struct refbuf *rb, uint32_t ref, const vec3 *poly, int n, int depth)
{
	struct geom_box bx = geom_box_empty();
	for (int i = 0; i < n; i++)
		bx = geom_box_point(bx, poly[i]);
	vec3 e = v3_sub(bx.hi, bx.lo);
	if (depth == SPLIT_DEPTH || !(e.x > 0 || e.y > 0 || e.z > 0))
		return refbuf_push(rb, ref, pad_box(bx));
	int axis = e.x >= e.y && e.x >= e.z ? 0 : e.y >= e.z ? 1 : 2;
	double at = 0.5 * (v3_comp(bx.lo, axis) + v3_comp(bx.hi, axis));
	vec3 half[16];
	for (int side = 0; side < 2; side++) {
		int m = clip_half(poly, n, axis, at, side == 0, half);
		if (m >= 3 && push_pieces(rb, ref, half, m, depth + 1) < 0)
			return -1;
	}
	return 0;
}

static int push_triangle(struct refbuf *rb, uint32_t ref, vec3 a, vec3 b, vec3 c)
{
	struct geom_box bx = geom_box_point(geom_box_point(geom_box_point(geom_box_empty(), a), b), c);
	vec3 e = v3_sub(bx.hi, bx.lo);
	double box_area = 2 * (e.x * e.y + e.y * e.z + e.z * e.x);
	double tri_area = 0.5 * v3_len(v3_cross(v3_sub(b, a), v3_sub(c, a)));
	if (!(tri_area > 0) || box_area < SPLIT_RATIO * tri_area)
		return refbuf_push(rb, ref, pad_box(bx));
	vec3 p[3] = { a, b, c };
	return push_pieces(rb, ref, p, 3, 0);
}

/* The group of define d, built once. */
static struct group *define_group(struct accel *A, uint32_t d, struct scene_error *err)
{
	if (!A->dgroup[d])
		A->dgroup[d] = build_group(A, A->s->defines[d].objects, A->s->defines[d].n_objects, err);
	return A->dgroup[d];
}

static void float_inverse(const mat34 *inv, struct ginst *gi, mat34 *rounded)
{
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 4; j++) {
			gi->inv[4 * i + j] = (float)inv->m[i][j];
			rounded->m[i][j] = gi->inv[4 * i + j];
		}
}

/*
 * Builds the group over objects objs[0..n). Returns NULL with err filled on
 * failure (out of memory or too many primitives).
 */
static struct group *build_group(struct accel *A, const uint32_t *objs, uint32_t n, struct scene_error *err)
{
	const struct scene *s = A->s;
	struct group *g = calloc(1, sizeof *g);
	struct geom_box *boxes = NULL;
	uint32_t *all = NULL, *perm = NULL;
	struct refbuf rb = { NULL, NULL, 0, 0 };
	if (!g)
		goto oom;
	/* pass 1: counts */
	uint64_t n_sph = 0, n_mesh = 0, n_tri = 0, n_xp = 0, n_inst = 0, n_bake = 0;
	for (uint32_t k = 0; k < n; k++) {
		const struct scene_object *o = &s->objects[objs[k]];
		switch (o->kind) {
		case PRIM_SPHERE:
			if (o->has_xform)
				n_xp++;
			else
				n_sph++;
			break;
		case PRIM_TRIANGLE:
			n_mesh++, n_tri++;
			n_bake += 4 + (o->u.triangle.has_normals ? 3 : 0) + (o->has_xform ? 3 : 0);
			break;
		case PRIM_RAW: {
			const struct scene_mesh *m = &s->meshes[o->u.raw.mesh];
			n_mesh++;
			n_tri += m->n_triangles;
			if (o->has_xform)
				n_bake += (uint64_t)m->n_vertices * (m->normals ? 2 : 1);
			break;
		}
		case PRIM_INSTANCE:
			n_inst++;
			break;
		default:
			n_xp++;
			break;
		}
	}
	uint64_t n_all = n_sph + n_tri + n_xp + n_inst;
	if (n_all >= ACCEL_MAX_REFS) {
		scene_errorf(err, ERRLEVEL_FATAL, "error: too many primitives in one group (%llu)",
			     (unsigned long long)n_all);
		goto fail;
	}
	g->sph = malloc((n_sph ? n_sph : 1) * sizeof *g->sph);
	g->mesh = malloc((n_mesh ? n_mesh : 1) * sizeof *g->mesh);
	g->tri = malloc((n_tri ? n_tri : 1) * sizeof *g->tri);
	g->xp = malloc((n_xp ? n_xp : 1) * sizeof *g->xp);
	g->inst = malloc((n_inst ? n_inst : 1) * sizeof *g->inst);
	g->bake = malloc((n_bake ? n_bake : 1) * sizeof *g->bake);
	if (!g->sph || !g->mesh || !g->tri || !g->xp || !g->inst || !g->bake)
		goto oom;
	g->bytes = sizeof *g + n_sph * sizeof *g->sph + n_mesh * sizeof *g->mesh + n_tri * sizeof *g->tri +
		   n_xp * sizeof *g->xp + n_inst * sizeof *g->inst + n_bake * sizeof *g->bake;

	/* pass 2: fill; bounded references go to all[]/boxes[], the rest to unb */
	uint32_t n_unb = 0;
	uint32_t *unb = malloc((n_all ? n_all : 1) * sizeof *unb);
	if (!unb)
		goto oom;
	g->unb = unb;
	size_t nb = 0;
	for (uint32_t k = 0; k < n; k++) {
		uint32_t oi = objs[k];
		const struct scene_object *o = &s->objects[oi];
		struct geom_box bx;
		uint32_t ref;
		if (o->kind == PRIM_SPHERE && !o->has_xform) {
			struct gsphere *sp = &g->sph[g->n_sph];
			sp->c = o->u.sphere.centre;
			sp->r2 = o->u.sphere.radius * o->u.sphere.radius;
			const struct prim_sphere *ps = &o->u.sphere;
			bool dflt = ps->pole.x == 0 && ps->pole.y == 1 && ps->pole.z == 0 && ps->equator.x == 1 &&
				    ps->equator.y == 0 && ps->equator.z == 0; /* P = +y, E = +x */
			sp->obj = oi | (dflt ? 0 : GSPH_FRAME);
			sp->mat = o->material;
			vec3 rr = v3(o->u.sphere.radius, o->u.sphere.radius, o->u.sphere.radius);
			bx.lo = v3_sub(sp->c, rr);
			bx.hi = v3_add(sp->c, rr);
			if (refbuf_push(&rb, REF_MAKE(REF_SPHERE, g->n_sph++), pad_box(bx)) < 0)
				goto oom;
			continue;
		}
		if (o->kind == PRIM_TRIANGLE || o->kind == PRIM_RAW) {
			struct gmesh *m = &g->mesh[g->n_mesh];
			memset(m, 0, sizeof *m);
			m->obj = oi;
			m->mat = o->material;
			uint32_t ntri;
			mat34 inv;
			if (o->has_xform && !m34_invert(&o->xform, &inv))
				inv = m34_identity();
			if (o->kind == PRIM_TRIANGLE) {
				const struct prim_triangle *t = &o->u.triangle;
				vec3 *v = &g->bake[nb];
				v[0] = t->a, v[1] = t->b, v[2] = t->c;
				nb += 3;
				m->ov = v;
				m->v = v;
				if (o->has_xform) {
					vec3 *w = &g->bake[nb];
					for (int q = 0; q < 3; q++)
						w[q] = m34_point(&o->xform, v[q]);
					nb += 3;
					m->v = w;
				}
				if (t->has_normals) {
					vec3 *nn = &g->bake[nb];
					nn[0] = t->na, nn[1] = t->nb, nn[2] = t->nc;
					if (o->has_xform)
						for (int q = 0; q < 3; q++)
							nn[q] = m34_normal(&inv, nn[q]);
					nb += 3;
					m->n = nn;
				}
				m->ix = tri_ix012;
				vec3 *fn = &g->bake[nb++];
				*fn = tri_normal(m, tri_ix012);
				m->fn = fn;
				ntri = 1;
			} else {
				const struct scene_mesh *sm = &s->meshes[o->u.raw.mesh];
				m->ov = sm->vertices;
				m->v = sm->vertices;
				m->n = sm->normals;
				m->ix = sm->tris;
				if (o->has_xform) {
					vec3 *w = &g->bake[nb];
					for (uint32_t q = 0; q < sm->n_vertices; q++)
						w[q] = m34_point(&o->xform, sm->vertices[q]);
					nb += sm->n_vertices;
					m->v = w;
					if (sm->normals) {
						vec3 *nn = &g->bake[nb];
						for (uint32_t q = 0; q < sm->n_vertices; q++)
							nn[q] = m34_normal(&inv, sm->normals[q]);
						nb += sm->n_vertices;
						m->n = nn;
					}
				}
				ntri = sm->n_triangles;
			}
			for (uint32_t q = 0; q < ntri; q++) {
				const uint32_t *ix = tri_ix(m, q);
				g->tri[g->n_tri].mesh = g->n_mesh;
				g->tri[g->n_tri].tri = q;
				if (push_triangle(&rb, REF_MAKE(REF_TRI, g->n_tri++), m->v[ix[0]], m->v[ix[1]], m->v[ix[2]]) < 0)
					goto oom;
			}
			g->n_mesh++;
			continue;
		}
		if (o->kind == PRIM_INSTANCE) {
			struct group *sub = define_group(A, o->u.instance.define, err);
			if (!sub)
				goto fail;
			if (sub->n_refs == 0 && sub->n_unb == 0)
				continue; /* an empty define draws nothing */
			struct ginst *gi = &g->inst[g->n_inst];
			gi->obj = oi;
			mat34 inv = m34_identity(), rinv, fwd;
			if (o->has_xform && !m34_invert(&o->xform, &inv))
				inv = m34_identity();
			float_inverse(&inv, gi, &rinv);
			if (!m34_invert(&rinv, &fwd)) {
				scene_errorf(err, ERRLEVEL_FATAL, "error: instance transform is singular in single precision");
				goto fail;
			}
			ref = REF_MAKE(REF_INST, g->n_inst++);
			A->st.n_instances++;
			if (sub->n_unb) {
				unb[n_unb++] = ref;
				continue;
			}
			if (refbuf_push(&rb, ref, pad_box(geom_box_xform(&fwd, sub->bounds))) < 0)
				goto oom;
			continue;
		}
		/* xprim */
		if (prep_tree(A, oi) < 0)
			goto oom;
		struct xprim *xp = &g->xp[g->n_xp];
		xp->g = A->gobj[oi];
		xp->obj = oi;
		ref = REF_MAKE(REF_XPRIM, g->n_xp++);
		bx = csg_bounds(s, (struct geom_obj *const *)A->gobj, oi);
		if (bx.lo.x > bx.hi.x || bx.lo.y > bx.hi.y || bx.lo.z > bx.hi.z)
			continue; /* empty: nothing to draw (e.g. disjoint intersect) */
		if (!geom_box_finite(bx)) {
			unb[n_unb++] = ref;
			continue;
		}
		if (refbuf_push(&rb, ref, pad_box(bx)) < 0)
			goto oom;
	}
	uint32_t n_bounded = rb.n;
	all = rb.ref;
	boxes = rb.box;
	rb.ref = NULL;
	rb.box = NULL;
	g->n_unb = n_unb;
	if (n_unb == 1 && REF_KIND(unb[0]) == REF_XPRIM) {
		const struct geom_obj *go = g->xp[REF_IDX(unb[0])].g;
		if (go->kind == PRIM_PLANE && !go->has_xform)
			g->plane1 = go;
	}
	g->n_refs = n_bounded;
	uint32_t *unb_fit = realloc(g->unb, (n_unb ? n_unb : 1) * sizeof *unb_fit);
	if (unb_fit)
		g->unb = unb_fit;
	A->st.n_prims += g->n_sph + g->n_tri + g->n_xp;

	/* pass 3: the BVH over the bounded references */
	/* node bounds are stored relative to the group's centre, padded by
	 * BOX_PAD_REL of the largest coordinate magnitude around it */
	struct geom_box world = geom_box_empty();
	for (uint32_t k = 0; k < n_bounded; k++)
		world = geom_box_union(world, boxes[k]);
	g->center = n_bounded ? v3_scale(v3_add(world.lo, world.hi), 0.5) : v3(0, 0, 0);
	double big = 0;
	for (uint32_t k = 0; k < n_bounded; k++) {
		boxes[k].lo = v3_sub(boxes[k].lo, g->center);
		boxes[k].hi = v3_sub(boxes[k].hi, g->center);
		big = fmax(big, fmax(fmax(fabs(boxes[k].lo.x), fabs(boxes[k].lo.y)), fabs(boxes[k].lo.z)));
		big = fmax(big, fmax(fmax(fabs(boxes[k].hi.x), fabs(boxes[k].hi.y)), fabs(boxes[k].hi.z)));
	}
	vec3 pad = v3(big * BOX_PAD_REL, big * BOX_PAD_REL, big * BOX_PAD_REL);
	for (uint32_t k = 0; k < n_bounded; k++) {
		boxes[k].lo = v3_sub(boxes[k].lo, pad);
		boxes[k].hi = v3_add(boxes[k].hi, pad);
	}
	/* a group whose bounded references are ACCEL_PACK_MIN or more instances
	 * and nothing else keeps its instance records in leaf order instead of a
	 * reference array, and packs its leaves (see ACCEL_INST_LEAF) */
	bool inst_only = n_bounded >= ACCEL_PACK_MIN;
	for (uint32_t k = 0; k < n_bounded && inst_only; k++)
		inst_only = REF_KIND(all[k]) == REF_INST;
	perm = malloc((n_bounded ? n_bounded : 1) * sizeof *perm);
	if (!inst_only)
		g->refs = malloc((n_bounded ? n_bounded : 1) * sizeof *g->refs);
	if (!perm || (!inst_only && !g->refs))
		goto oom;
	if (bvh_build_ex(&g->bvh, boxes, n_bounded, perm, inst_only ? ACCEL_INST_LEAF : ACCEL_MAX_LEAF, inst_only) < 0)
		goto oom;
	g->bounds = geom_box_empty();
	for (uint32_t k = 0; k < n_bounded; k++)
		g->bounds = geom_box_union(g->bounds, boxes[k]);
	if (inst_only) { /* bounded instances in leaf order, then the unbounded ones */
		struct ginst *ord = malloc((size_t)g->n_inst * sizeof *ord);
		if (!ord)
			goto oom;
		for (uint32_t k = 0; k < n_bounded; k++)
			ord[k] = g->inst[REF_IDX(all[perm[k]])];
		uint32_t next = n_bounded;
		for (uint32_t k = 0; k < g->n_unb; k++)
			if (REF_KIND(g->unb[k]) == REF_INST) {
				ord[next] = g->inst[REF_IDX(g->unb[k])];
				g->unb[k] = REF_MAKE(REF_INST, next++);
			}
		free(g->inst);
		g->inst = ord;
	} else {
		for (uint32_t k = 0; k < n_bounded; k++)
			g->refs[k] = all[perm[k]];
	}
	if (n_bounded) { /* back to the group's space, covering the padding */
		g->bounds.lo = v3_add(g->bounds.lo, g->center);
		g->bounds.hi = v3_add(g->bounds.hi, g->center);
		g->bounds = pad_box(g->bounds);
	}
	g->bytes += (size_t)g->bvh.n_nodes4 * sizeof(struct bvh4) +
		    (size_t)((inst_only ? 0 : n_bounded) + n_unb) * sizeof(uint32_t);
	A->st.n_nodes += g->bvh.n_nodes4;
	A->st.bytes += g->bytes;
	free(perm);
	free(all);
	free(boxes);
	return g;
oom:
	scene_errorf(err, ERRLEVEL_FATAL, "error: out of memory building the acceleration structure");
fail:
	free(rb.ref);
	free(rb.box);
	free(perm);
	free(all);
	free(boxes);
	group_free(g);
	return NULL;
}

/*
 * Rejects graphs the tracer's recursion would not survive: CSG nesting over
 * LIM_CSG_DEPTH or define nesting over LIM_DEFINE_DEPTH. Children always
 * have smaller indices, so one forward pass computes every depth.
 */
static int check_depths(const struct scene *s, struct scene_error *err)
{
	uint16_t *cd = calloc((size_t)s->n_objects + 1, sizeof *cd);
	uint16_t *dd = calloc((size_t)s->n_objects + 1, sizeof *dd);
	int32_t *def_cd = malloc(((size_t)s->n_defines + 1) * sizeof *def_cd);
	int32_t *def_dd = malloc(((size_t)s->n_defines + 1) * sizeof *def_dd);
	int rc = 0;
	if (!cd || !dd || !def_cd || !def_dd) {
		rc = scene_errorf(err, ERRLEVEL_FATAL, "error: out of memory building the acceleration structure");
		goto out;
	}
	for (uint32_t i = 0; i < s->n_defines; i++)
		def_cd[i] = def_dd[i] = -1;
	for (uint32_t i = 0; i < s->n_objects; i++) {
		const struct scene_object *o = &s->objects[i];
		unsigned c = 0, d = 0;
		if (o->kind == PRIM_CSG) {
			uint32_t a = o->u.csg.operand1, b = o->u.csg.operand2;
			c = 1u + (cd[a] > cd[b] ? cd[a] : cd[b]);
			d = dd[a] > dd[b] ? dd[a] : dd[b];
		} else if (o->kind == PRIM_INSTANCE) {
			uint32_t df = o->u.instance.define;
			if (def_cd[df] < 0) {
				unsigned mc = 0, md = 0;
				const struct scene_define *D = &s->defines[df];
				for (uint32_t k = 0; k < D->n_objects; k++) {
					uint32_t m = D->objects[k];
					mc = cd[m] > mc ? cd[m] : mc;
					md = dd[m] > md ? dd[m] : md;
				}
				def_cd[df] = (int32_t)mc;
				def_dd[df] = (int32_t)md;
			}
			c = (unsigned)def_cd[df];
			d = 1u + (unsigned)def_dd[df];
		}
		if (c > LIM_CSG_DEPTH || d > LIM_DEFINE_DEPTH) {
			const char *f = o->loc.file ? o->loc.file : "<scene>";
			rc = scene_errorf(err, ERRLEVEL_FATAL, "%s:%d:%d: error: %s nested deeper than %d", f,
					  o->loc.line, o->loc.col, c > LIM_CSG_DEPTH ? "csg" : "definition",
					  c > LIM_CSG_DEPTH ? LIM_CSG_DEPTH : LIM_DEFINE_DEPTH);
			goto out;
		}
		cd[i] = (uint16_t)c;
		dd[i] = (uint16_t)d;
	}
out:
	free(cd);
	free(dd);
	free(def_cd);
	free(def_dd);
	return rc;
}

int accel_build(const struct scene *s, struct accel **out, struct scene_error *err)
{
	struct timespec t0, t1;
	clock_gettime(CLOCK_MONOTONIC, &t0);
	*out = NULL;
	int rc = check_depths(s, err);
	if (rc)
		return rc;
	struct accel *A = calloc(1, sizeof *A);
	if (!A)
		return scene_errorf(err, ERRLEVEL_FATAL, "error: out of memory building the acceleration structure");
	A->s = s;
	A->dgroup = calloc((size_t)s->n_defines + 1, sizeof *A->dgroup);
	if (!A->dgroup) {
		accel_free(A);
		return scene_errorf(err, ERRLEVEL_FATAL, "error: out of memory building the acceleration structure");
	}
	A->st.bytes = sizeof *A + (size_t)s->n_defines * sizeof(void *);
	A->st.instance_bytes = sizeof(struct ginst);
	A->root = build_group(A, s->roots, s->n_roots, err);
	if (!A->root) {
		accel_free(A);
		return err ? err->level : ERRLEVEL_FATAL;
	}
	clock_gettime(CLOCK_MONOTONIC, &t1);
	A->st.build_seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
	*out = A;
	return 0;
}
