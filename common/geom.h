/*
 * geom.h - internal to the geometry modules (geom.c, bvh.c, csg.c, accel*.c):
 * per-object precomputed shape data and the object-space primitive kernels.
 * Nothing outside common/geom*.c, bvh.c, csg.c and accel*.c includes this.
 *
 * Every kernel works in the object's own space on an unnormalised ray
 * o + t d: t is invariant under affine maps, so a hit distance found in
 * object space is the caller's hit distance too.
 */
#ifndef PORTRAY_GEOM_H
#define PORTRAY_GEOM_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "common/accel.h"

/* Axis-aligned box; an empty box has lo > hi. Infinite components allowed. */
struct geom_box {
	vec3 lo, hi;
};

struct geom_box geom_box_empty(void);
struct geom_box geom_box_union(struct geom_box a, struct geom_box b);
struct geom_box geom_box_point(struct geom_box a, vec3 p);
/* Box of the 8 corners of b mapped by m (infinite boxes stay infinite). */
struct geom_box geom_box_xform(const mat34 *m, struct geom_box b);
bool geom_box_finite(struct geom_box b);

/* Polygon precomputation: the plane, a 2-D projection and the contours. */
struct geom_poly {
	vec3 p0, n;     /* a point on the plane (first vertex) and the unit Newell normal */
	vec3 X, Y;      /* (u,v) axes: X = unit first edge, Y = n x X */
	int ax0, ax1;   /* kept axes of the 2-D projection (the dominant one dropped) */
	double *pts;    /* 2-D points, 2 per vertex (owned) */
	uint32_t *cstart; /* n_contours + 1 offsets (owned) */
	uint32_t n_contours, n_points;
	double lo[2], hi[2]; /* 2-D bounds */
};

/* Per-object data in the object's own space (after its inverse transform). */
struct geom_obj {
	enum prim_kind kind;
	uint32_t obj;      /* scene object index */
	const struct scene_object *so; /* the scene's object; NULL for an instance
					  (read it with scene_object) */
	bool has_xform;
	mat34 inv;         /* parent -> object (identity when !has_xform) */
	mat34 fwd;         /* object -> parent */
	union {
		struct { vec3 c; double r; vec3 P, E, W; } sph;  /* pole, equator, P x E */
		struct { vec3 pos, n, X, Y; double r; } pl;      /* plane and disk */
		struct { vec3 from, a, X, Y; double h, r; bool capped; } cyl; /* a unit axis */
		struct { vec3 lo, hi; } box;
		struct { vec3 a, b, c, na, nb, nc; bool smooth; } tri;
		struct geom_poly poly;
	} u;
};

/*
 * Fills g for scene object obj (any kind; CSG, RAW and instance get only the
 * transform). Polygons allocate g->u.poly arrays: release with geom_obj_clear.
 * Returns 0, or -1 when out of memory.
 */
int geom_obj_init(const struct scene *s, uint32_t obj, struct geom_obj *g);
void geom_obj_clear(struct geom_obj *g);

/* Bounds of the primitive in its own object space (PRIM_PLANE: infinite). */
struct geom_box geom_obj_local_bounds(const struct scene *s, const struct geom_obj *g);

/* The perpendicular axis pair used by planes, disks and cylinders when none is given. */
void geom_frame(vec3 n, vec3 *x, vec3 *y);

/* Parts, for the normal and (u,v) of a hit */
enum { GEOM_PART_MAIN = 0, GEOM_PART_CAP0 = 1, GEOM_PART_CAP1 = 2 };

/*
 * Closest hit of a simple primitive (sphere, plane, disk, cylinder, box,
 * triangle, polygon) with the object-space ray o + t d, tmin < t < tmax,
 * with drawing semantics (open surfaces seen from both sides, an open
 * cylinder's side only). Sets *t and *part.
 */
bool geom_intersect(const struct geom_obj *g, vec3 o, vec3 d, double tmin, double tmax, double *t,
		    int *part);

/* Where the line o + t d crosses the plane through pos with normal n:
 * false when parallel or the distance is not finite. */
static inline bool geom_plane_t(vec3 pos, vec3 n, vec3 o, vec3 d, double *t)
{
	double den = v3_dot(d, n);
	if (den == 0)
		return false;
	*t = v3_dot(v3_sub(pos, o), n) / den;
	return isfinite(*t);
}

/* Unit outward (object-space) normal and (u,v) at object-space point p of part. */
void geom_surface(const struct geom_obj *g, vec3 p, int part, vec3 *n, double *u, double *v);
/* geom_surface's *n alone (the same bits), without the mapping's cost. */
vec3 geom_normal(const struct geom_obj *g, vec3 p, int part);

/* Triangle (u,v) mapping: lengths along unit(b-a) and along n x unit(b-a) from a. */
void geom_tri_uv(vec3 a, vec3 b, vec3 c, vec3 p, double *u, double *v);

/* The same with the unit normal n = v3_norm(v3_cross(b - a, c - a)) already
 * computed (bit-identical results: geom_tri_uv is this after computing n). */
static inline void geom_tri_uv_n(vec3 a, vec3 b, vec3 n, vec3 p, double *u, double *v)
{
	vec3 e = v3_norm(v3_sub(b, a));
	vec3 f = v3_cross(n, e);
	vec3 q = v3_sub(p, a);
	*u = v3_dot(q, e);
	*v = v3_dot(q, f);
}

/*
 * Boundary crossings along the whole line o + t d, for CSG. A solid gives
 * its entering and exiting t (flags GEOM_X_ENTER / GEOM_X_EXIT) and says in
 * *inside0 whether t = -infinity is inside; a surface without inside (disk,
 * triangle, polygon) gives GEOM_X_SURF crossings. GEOM_X_DRAW marks parts
 * that are drawn (not the caps of an open cylinder). At most 2 crossings.
 */
enum { GEOM_X_ENTER = 1, GEOM_X_EXIT = 2, GEOM_X_SURF = 4, GEOM_X_DRAW = 8 };
struct geom_cross1 {
	double t;
	int part;
	int flags;
};
int geom_crossings(const struct geom_obj *g, vec3 o, vec3 d, struct geom_cross1 out[2], bool *inside0);

/*
 * fmin and fmax inline (the library's are calls, even at -O3): the other
 * operand when one is NaN, else x < y ? x : y and x > y ? x : y. That is
 * glibc's x86-64 fmin and fmax (minsd and maxsd behind a NaN test), signed
 * zeros included: tests/unit/test_geom.c compares them on special values.
 * (Other C libraries may order signed zeros differently; these do not
 * depend on the library.)
 */
static inline double geom_fmin(double x, double y) { return x < y || y != y ? x : y; }
static inline double geom_fmax(double x, double y) { return x > y || y != y ? x : y; }

/* ---- quadrics: spheres and cylinders ------------------------------------------- */

/*
 * Roots of |oc + t d|^2 = r2 in a cancellation-resistant form: t0 <= t1;
 * false when the line misses (or d is 0). Inline wherever it is used: a
 * cylinder test made three calls (5% of rings_s3's instructions).
 */
static inline __attribute__((always_inline)) bool geom_sphere_roots(vec3 oc, vec3 d, double r2, double *t0,
								     double *t1)
{
	double a = v3_dot(d, d);
	if (!(a > 0))
		return false;
	double b = v3_dot(oc, d);
	double tc = -b / a;
	vec3 f = v3_add(oc, v3_scale(d, tc)); /* closest point of the line to the centre */
	double h2 = (r2 - v3_dot(f, f)) / a;
	if (h2 < 0)
		return false;
	double h = sqrt(h2);
	double c = v3_dot(oc, oc) - r2;
	double q = tc + (tc >= 0 ? h : -h); /* larger magnitude root */
	double other = q != 0 ? (c / a) / q : 0;
	*t0 = geom_fmin(q, other);
	*t1 = geom_fmax(q, other);
	return true;
}

/*
 * TUBE PRE-REJECT: true only when geom_sphere_roots(op, dp, r2) is
 * certainly false, found without its two divisions and root. With A =
 * dp.dp, B = op.dp, O = op.op (the products it forms), the line misses
 * exactly when A (|f|^2 - r2) = (O - r2) A - B^2 = M > 0. Each rounded
 * product and sum here and there errs by at most about 25 u (O + r2) A
 * in M (u = 2^-53; |f| <= |op| bounds the cancellation in f), so a margin
 * of 1e-9 (O + r2) A leaves the answer the same bit for bit whatever the
 * rounding; below 2^-900 or at infinity it answers false. It ends 31% of
 * rings_s3's cylinder tests (docs/performance.md, round 12).
 */
static inline bool geom_tube_misses(vec3 op, vec3 dp, double r2)
{
	double A = v3_dot(dp, dp), B = v3_dot(op, dp), O = v3_dot(op, op);
	double m = 1e-9 * ((O + r2) * A), M = (O - r2) * A - B * B;
	return M > m && m > 0x1p-900 && M < INFINITY;
}

/*
 * geom_intersect of an open cylinder (PRIM_CYLINDER, not capped: its
 * u.cyl.from, a, r, h), object-space ray: the side between the caps, seen
 * from both sides. Inline here so that the traversals' xprim tests
 * (accel.c) reach it without geom_intersect's call and switch, from a
 * record of their own (OPEN CYLINDERS, accel_int.h); the same arithmetic
 * either way. geom_cyl_open_test without away is the test before AWAY
 * (tests/unit/test_away.c compares them).
 */
static inline __attribute__((always_inline)) bool geom_cyl_open_test(vec3 from, vec3 a, double r, double h,
								      vec3 o, vec3 d, double tmin, double tmax,
								      double *t, int *part, const bool away)
{
	/* one set of dot products, the caps by the axial coordinate */
	vec3 oc = v3_sub(o, from);
	double z0 = v3_dot(oc, a), dz = v3_dot(d, a);
	vec3 op = v3_sub(oc, v3_scale(a, z0)), dp = v3_sub(d, v3_scale(a, dz));
	double r2 = r * r, t0, t1;
	if (geom_tube_misses(op, dp, r2) || v3_dot(dp, dp) <= 1e-30 * v3_dot(d, d))
		return false; /* parallel to the axis: only the (open) ends */
	/* AWAY (sphere_test, accel_trace.h): outside the tube, moving away from
	 * its axis, so both roots <= 0: c = O - r2 >= 0 and tc = -B / A < 0,
	 * B / A >= 2^-900 (A >= 2^-100 keeps A 2^-900 exact) so that tc is not
	 * -0, which would take the other branch of q */
	double A = v3_dot(dp, dp), B = v3_dot(op, dp);
	if (away && tmin >= 0 && v3_dot(op, op) - r2 >= 0 && A >= 0x1p-100 && B >= A * 0x1p-900)
		return false;
	if (!geom_sphere_roots(op, dp, r2, &t0, &t1))
		return false;
	double za = z0 + t0 * dz, zb = z0 + t1 * dz;
	if (za >= 0 && za <= h && t0 > tmin && t0 < tmax) {
		*t = t0, *part = GEOM_PART_MAIN;
		return true;
	}
	if (zb >= 0 && zb <= h && t1 > tmin && t1 < tmax) {
		*t = t1, *part = GEOM_PART_MAIN;
		return true;
	}
	return false;
}

static inline __attribute__((always_inline)) bool geom_cyl_open_hit(vec3 from, vec3 a, double r, double h,
								     vec3 o, vec3 d, double tmin, double tmax,
								     double *t, int *part)
{
	return geom_cyl_open_test(from, a, r, h, o, d, tmin, tmax, t, part, true);
}

/* ---- watertight ray/triangle (Woop, Benthin, Wald 2013) ---------------- */

struct geom_wray {
	double o[3];
	int kx, ky, kz;
	double sx, sy, sz;
	double ox, oy, oz; /* o[kx], o[ky], o[kz] */
};

void geom_wray_init(struct geom_wray *w, vec3 o, vec3 d);

/*
 * Watertight test: true with *t in (tmin, tmax) and barycentric weights
 * *b1 (of b) and *b2 (of c) when the line crosses triangle abc. Seen from
 * both sides; edges shared by two triangles are hit by exactly one of them
 * or both, never neither.
 */
/* Component k (0 x, 1 y, 2 z) of *v, read through its bytes (no array
 * copy of the vertex: one load). */
static inline double geom_comp(const vec3 *v, int k)
{
	double x;
	memcpy(&x, (const char *)v + (size_t)k * sizeof x, sizeof x);
	return x;
}

/* geom_tri_hit with the vertices by address (the same arithmetic). */
static inline bool geom_tri_hit_p(const struct geom_wray *w, const vec3 *a, const vec3 *b, const vec3 *c,
				  double tmin, double tmax, double *t, double *b1, double *b2)
{
	/* vertices relative to the origin, permuted (only the components used) */
	const int kx = w->kx, ky = w->ky, kz = w->kz;
	double Ax = geom_comp(a, kx) - w->ox, Ay = geom_comp(a, ky) - w->oy, Az = geom_comp(a, kz) - w->oz;
	double Bx = geom_comp(b, kx) - w->ox, By = geom_comp(b, ky) - w->oy, Bz = geom_comp(b, kz) - w->oz;
	double Cx = geom_comp(c, kx) - w->ox, Cy = geom_comp(c, ky) - w->oy, Cz = geom_comp(c, kz) - w->oz;
	double ax = Ax - w->sx * Az, ay = Ay - w->sy * Az;
	double bx = Bx - w->sx * Bz, by = By - w->sy * Bz;
	double cx = Cx - w->sx * Cz, cy = Cy - w->sy * Cz;
	double U = cx * by - cy * bx;
	double V = ax * cy - ay * cx;
	double W = bx * ay - by * ax;
	if ((U < 0 || V < 0 || W < 0) && (U > 0 || V > 0 || W > 0))
		return false;
	double det = U + V + W;
	if (det == 0)
		return false;
	double T = U * (w->sz * Az) + V * (w->sz * Bz) + W * (w->sz * Cz);
	double tt = T / det;
	if (!(tt > tmin && tt < tmax))
		return false;
	*t = tt;
	*b1 = V / det;
	*b2 = W / det;
	return true;
}

static inline bool geom_tri_hit(const struct geom_wray *w, vec3 a, vec3 b, vec3 c, double tmin,
				double tmax, double *t, double *b1, double *b2)
{
	return geom_tri_hit_p(w, &a, &b, &c, tmin, tmax, t, b1, b2);
}

/* ---- CSG (csg.c) --------------------------------------------------------- */

/* Crossings kept on the stack per CSG ray before spilling to the heap. */
#define CSG_STACK_CROSSINGS 64

/*
 * Closest drawn boundary of CSG object obj (kind PRIM_CSG) along o + t d,
 * given in obj's PARENT space, with tmin < t < tmax. gobj[] must hold the
 * geom_obj of obj and of every object below it (operands, instance members).
 * On success fills h->t, n, ng (parent space, unit), u, v, mp, material
 * (the operand surface's, else the nearest enclosing node's that has one,
 * else SCENE_NONE) and object (the leaf); h->p is left to the caller.
 * Surfaces with no inside and open cylinders follow docs/language.md.
 * Thread-safe; allocates only when a ray has more than
 * CSG_STACK_CROSSINGS crossings (and then treats out-of-memory as a miss).
 * Once the calling thread's cancel flag is seen set (cancel.h) the result
 * is wrong (crossings left out), to be discarded.
 */
bool csg_hit(const struct scene *s, struct geom_obj *const *gobj, uint32_t obj, vec3 o, vec3 d,
	     double tmin, double tmax, struct hit *h);

/* Bounds of object obj in its parent space (CSG and instances recursively);
 * wrong (parts left out) once the calling thread's cancel flag is seen set
 * (cancel.h), which the caller checks with cancel_seen. */
struct geom_box csg_bounds(const struct scene *s, struct geom_obj *const *gobj, uint32_t obj);

#endif
