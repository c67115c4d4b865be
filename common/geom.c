/*
 * geom.c - primitive shapes in their own object space: precomputation,
 * intersection, normals and (u,v) surface mappings.
 *
 * (u,v) MAPPINGS, in object-space length units (docs/rendering.md copies this):
 *
 *   sphere    P = unit pole; E = equator made perpendicular to P, unit (when the
 *             equator is parallel to the pole, E is the plane rule's x-axis for
 *             normal P); W = P x E. For a point with unit direction q from the
 *             centre: longitude phi = atan2(q.W, q.E) in [0, 2 pi), latitude
 *             lat = asin(q.P) in [-pi/2, pi/2].
 *               u = radius * phi           (arc length along the equator from E,
 *                                            turning right-handed about the pole)
 *               v = radius * (lat + pi/2)  (arc length from the south pole)
 *   plane     X = x-axis and Y = y-axis when written (X made perpendicular to the
 *             normal N and unit; Y unit, or N x X when zero); otherwise derived:
 *             X = unit(x^ - N.x N) if |N.x| < 0.9 else unit(z^ - N.z N), Y = N x X
 *             (default plane, N = +y: X = +x, Y = -z).
 *               u = (p - position).X,  v = (p - position).Y
 *   disk      as the plane, about its centre (position).
 *   cylinder  A = unit(to - from); X, Y = the plane rule's axes for normal A.
 *             side: u = radius * atan2(q.Y, q.X) in [0, 2 pi radius), q = the
 *                   radial offset of p from the axis; v = (p - from).A (0 at
 *                   `from`, the length at `to`).
 *             caps (capped only): u = (p - c).X, v = (p - c).Y, c the cap centre.
 *   box       lo/hi = min/max corners. Faces facing +-x: u = z - lo.z, v = y - lo.y;
 *             +-y: u = x - lo.x, v = z - lo.z; +-z: u = x - lo.x, v = y - lo.y.
 *   triangle  e = unit(b - a), N = unit((b - a) x (c - a)), f = N x e:
 *               u = (p - a).e,  v = (p - a).f   (mesh triangles: the same with
 *               their own vertices, in the mesh's object space)
 *   polygon   p0 = first vertex, X = unit(second - first vertex), N = Newell
 *             normal of the first contour, Y = N x X:
 *               u = (p - p0).X,  v = (p - p0).Y
 *
 * NORMALS: outward for solids (sphere, box, cylinder side and caps); plane,
 * disk and polygon: their normal; triangles: unit((b-a) x (c-a)), or the
 * interpolated normal-a/b/c. Open surfaces are hit from both sides; normals
 * are never flipped toward the ray (the shader does that).
 */
#include "common/geom.h"

#include <stdlib.h>
#include <string.h>

#include "common/xmath.h"

/* ---- boxes ---------------------------------------------------------------- */

struct geom_box geom_box_empty(void)
{
	struct geom_box b = { v3(INFINITY, INFINITY, INFINITY), v3(-INFINITY, -INFINITY, -INFINITY) };
	return b;
}

static inline double mn(double a, double b) { return a < b ? a : b; }
static inline double mx(double a, double b) { return a > b ? a : b; }

struct geom_box geom_box_union(struct geom_box a, struct geom_box b)
{
	struct geom_box r = { v3(mn(a.lo.x, b.lo.x), mn(a.lo.y, b.lo.y), mn(a.lo.z, b.lo.z)),
			      v3(mx(a.hi.x, b.hi.x), mx(a.hi.y, b.hi.y), mx(a.hi.z, b.hi.z)) };
	return r;
}

struct geom_box geom_box_point(struct geom_box a, vec3 p)
{
	struct geom_box r = { v3(mn(a.lo.x, p.x), mn(a.lo.y, p.y), mn(a.lo.z, p.z)),
			      v3(mx(a.hi.x, p.x), mx(a.hi.y, p.y), mx(a.hi.z, p.z)) };
	return r;
}

bool geom_box_finite(struct geom_box b) { return v3_finite(b.lo) && v3_finite(b.hi); }

struct geom_box geom_box_xform(const mat34 *m, struct geom_box b)
{
	if (b.lo.x > b.hi.x || b.lo.y > b.hi.y || b.lo.z > b.hi.z)
		return geom_box_empty();
	if (!geom_box_finite(b)) {
		struct geom_box inf = { v3(-INFINITY, -INFINITY, -INFINITY), v3(INFINITY, INFINITY, INFINITY) };
		return inf;
	}
	struct geom_box r = geom_box_empty();
	for (int i = 0; i < 8; i++) {
		vec3 p = v3(i & 1 ? b.hi.x : b.lo.x, i & 2 ? b.hi.y : b.lo.y, i & 4 ? b.hi.z : b.lo.z);
		r = geom_box_point(r, m34_point(m, p));
	}
	return r;
}

/* ---- frames --------------------------------------------------------------- */

void geom_frame(vec3 n, vec3 *x, vec3 *y)
{
	n = v3_norm(n);
	vec3 e = fabs(n.x) < 0.9 ? v3(1, 0, 0) : v3(0, 0, 1);
	*x = v3_norm(v3_sub(e, v3_scale(n, v3_dot(e, n))));
	*y = v3_cross(n, *x);
}

/* Angle of (a, b) in [0, 2 pi). */
static double angle_2pi(double b, double a)
{
	double phi = xm_atan2(b, a);
	if (phi < 0)
		phi += 2 * M_PI;
	if (phi >= 2 * M_PI)
		phi = 0;
	return phi;
}

/* ---- polygon precomputation ---------------------------------------------------- */

static int poly_init(const struct prim_polygon *p, struct geom_poly *g)
{
	memset(g, 0, sizeof *g);
	uint32_t n0 = p->contour_start[1];
	vec3 nw = v3(0, 0, 0);
	for (uint32_t i = 0; i < n0; i++) { /* Newell normal of the first contour */
		vec3 a = p->points[i], b = p->points[(i + 1) % n0];
		nw.x += (a.y - b.y) * (a.z + b.z);
		nw.y += (a.z - b.z) * (a.x + b.x);
		nw.z += (a.x - b.x) * (a.y + b.y);
	}
	g->n = v3_norm(nw);
	g->p0 = p->points[0];
	vec3 e = v3_sub(p->points[1], p->points[0]);
	e = v3_sub(e, v3_scale(g->n, v3_dot(e, g->n)));
	if (v3_len(e) > 0) {
		g->X = v3_norm(e);
		g->Y = v3_cross(g->n, g->X);
	} else {
		geom_frame(g->n, &g->X, &g->Y);
	}
	double an[3] = { fabs(g->n.x), fabs(g->n.y), fabs(g->n.z) };
	int drop = an[0] >= an[1] && an[0] >= an[2] ? 0 : an[1] >= an[2] ? 1 : 2;
	g->ax0 = (drop + 1) % 3;
	g->ax1 = (drop + 2) % 3;
	g->n_contours = p->n_contours;
	g->n_points = p->n_points;
	g->pts = malloc((size_t)p->n_points * 2 * sizeof *g->pts);
	g->cstart = malloc(((size_t)p->n_contours + 1) * sizeof *g->cstart);
	if (!g->pts || !g->cstart) {
		free(g->pts);
		free(g->cstart);
		g->pts = NULL;
		g->cstart = NULL;
		return -1;
	}
	memcpy(g->cstart, p->contour_start, ((size_t)p->n_contours + 1) * sizeof *g->cstart);
	g->lo[0] = g->lo[1] = INFINITY;
	g->hi[0] = g->hi[1] = -INFINITY;
	for (uint32_t i = 0; i < p->n_points; i++) {
		double x = v3_comp(p->points[i], g->ax0), y = v3_comp(p->points[i], g->ax1);
		g->pts[2 * i] = x;
		g->pts[2 * i + 1] = y;
		g->lo[0] = fmin(g->lo[0], x);
		g->lo[1] = fmin(g->lo[1], y);
		g->hi[0] = fmax(g->hi[0], x);
		g->hi[1] = fmax(g->hi[1], y);
	}
	return 0;
}

/* Even-odd rule over every edge of every contour (crossing number). */
static bool poly_inside(const struct geom_poly *g, double x, double y)
{
	if (x < g->lo[0] || x > g->hi[0] || y < g->lo[1] || y > g->hi[1])
		return false;
	bool in = false;
	for (uint32_t c = 0; c < g->n_contours; c++) {
		uint32_t s = g->cstart[c], e = g->cstart[c + 1];
		for (uint32_t i = s, j = e - 1; i < e; j = i++) {
			double xi = g->pts[2 * i], yi = g->pts[2 * i + 1];
			double xj = g->pts[2 * j], yj = g->pts[2 * j + 1];
			if ((yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi)
				in = !in;
		}
	}
	return in;
}

/* ---- per-object data -------------------------------------------------------------- */

/* Plane axes as scene.h and the mapping comment above define them. */
static void plane_axes(const struct prim_plane *p, vec3 n, vec3 *X, vec3 *Y)
{
	if (p->has_axes) {
		vec3 x = v3_sub(p->x_axis, v3_scale(n, v3_dot(p->x_axis, n)));
		if (v3_len(x) > 0) {
			*X = v3_norm(x);
			*Y = v3_len(p->y_axis) > 0 ? v3_norm(p->y_axis) : v3_cross(n, *X);
			return;
		}
	}
	geom_frame(n, X, Y);
}

int geom_obj_init(const struct scene *s, uint32_t obj, struct geom_obj *g)
{
	struct scene_object tmp;
	const struct scene_object *o = scene_object(s, obj, &tmp);
	memset(g, 0, sizeof *g);
	g->kind = o->kind;
	g->obj = obj;
	g->so = o == &tmp ? NULL : o;
	g->has_xform = o->has_xform;
	g->fwd = o->has_xform ? o->xform : m34_identity();
	if (!o->has_xform || !m34_invert(&g->fwd, &g->inv)) {
		g->inv = m34_identity(); /* the builder rejects singular transforms */
		g->fwd = m34_identity();
		g->has_xform = false;
	}
	switch (o->kind) {
	case PRIM_SPHERE: {
		const struct prim_sphere *p = &o->u.sphere;
		g->u.sph.c = p->centre;
		g->u.sph.r = p->radius;
		vec3 P = v3_norm(p->pole);
		vec3 E = v3_sub(p->equator, v3_scale(P, v3_dot(p->equator, P)));
		if (v3_len(E) > 1e-12 * (v3_len(p->equator) + 1e-300)) {
			E = v3_norm(E);
		} else {
			vec3 y;
			geom_frame(P, &E, &y);
		}
		g->u.sph.P = P;
		g->u.sph.E = E;
		g->u.sph.W = v3_cross(P, E);
		break;
	}
	case PRIM_PLANE:
	case PRIM_DISK: {
		const struct prim_plane *p = &o->u.plane;
		g->u.pl.pos = p->position;
		g->u.pl.n = v3_norm(p->normal);
		g->u.pl.r = p->radius;
		plane_axes(p, g->u.pl.n, &g->u.pl.X, &g->u.pl.Y);
		break;
	}
	case PRIM_CYLINDER: {
		const struct prim_cylinder *p = &o->u.cylinder;
		vec3 ax = v3_sub(p->to, p->from);
		g->u.cyl.from = p->from;
		g->u.cyl.h = v3_len(ax);
		g->u.cyl.a = v3_norm(ax);
		g->u.cyl.r = p->radius;
		g->u.cyl.capped = p->capped;
		geom_frame(g->u.cyl.a, &g->u.cyl.X, &g->u.cyl.Y);
		break;
	}
	case PRIM_BOX:
		g->u.box.lo = v3_min(o->u.box.a, o->u.box.b);
		g->u.box.hi = v3_max(o->u.box.a, o->u.box.b);
		break;
	case PRIM_TRIANGLE: {
		const struct prim_triangle *p = &o->u.triangle;
		g->u.tri.a = p->a;
		g->u.tri.b = p->b;
		g->u.tri.c = p->c;
		g->u.tri.smooth = p->has_normals;
		g->u.tri.na = p->na;
		g->u.tri.nb = p->nb;
		g->u.tri.nc = p->nc;
		break;
	}
	case PRIM_POLYGON:
		if (poly_init(&o->u.polygon, &g->u.poly) < 0)
			return -1;
		break;
	default: /* CSG, RAW, instance: the transform only */
		break;
	}
	return 0;
}

void geom_obj_clear(struct geom_obj *g)
{
	if (g && g->kind == PRIM_POLYGON) {
		free(g->u.poly.pts);
		free(g->u.poly.cstart);
		g->u.poly.pts = NULL;
		g->u.poly.cstart = NULL;
	}
}

/* Half-extent of a disk of radius r with unit normal n, per axis. */
static vec3 disk_extent(vec3 n, double r)
{
	return v3(r * sqrt(fmax(0, 1 - n.x * n.x)), r * sqrt(fmax(0, 1 - n.y * n.y)),
		  r * sqrt(fmax(0, 1 - n.z * n.z)));
}

struct geom_box geom_obj_local_bounds(const struct scene *s, const struct geom_obj *g)
{
	struct geom_box b = geom_box_empty();
	struct scene_object tmp;
	const struct scene_object *o = scene_object(s, g->obj, &tmp);
	switch (g->kind) {
	case PRIM_SPHERE: {
		vec3 r = v3(g->u.sph.r, g->u.sph.r, g->u.sph.r);
		b.lo = v3_sub(g->u.sph.c, r);
		b.hi = v3_add(g->u.sph.c, r);
		break;
	}
	case PRIM_PLANE:
		b.lo = v3(-INFINITY, -INFINITY, -INFINITY);
		b.hi = v3(INFINITY, INFINITY, INFINITY);
		break;
	case PRIM_DISK: {
		vec3 e = disk_extent(g->u.pl.n, g->u.pl.r);
		b.lo = v3_sub(g->u.pl.pos, e);
		b.hi = v3_add(g->u.pl.pos, e);
		break;
	}
	case PRIM_CYLINDER: {
		vec3 e = disk_extent(g->u.cyl.a, g->u.cyl.r);
		vec3 to = v3_add(g->u.cyl.from, v3_scale(g->u.cyl.a, g->u.cyl.h));
		b.lo = v3_sub(v3_min(g->u.cyl.from, to), e);
		b.hi = v3_add(v3_max(g->u.cyl.from, to), e);
		break;
	}
	case PRIM_BOX:
		b.lo = g->u.box.lo;
		b.hi = g->u.box.hi;
		break;
	case PRIM_TRIANGLE:
		b = geom_box_point(geom_box_point(geom_box_point(b, g->u.tri.a), g->u.tri.b), g->u.tri.c);
		break;
	case PRIM_POLYGON:
		for (uint32_t i = 0; i < o->u.polygon.n_points; i++)
			b = geom_box_point(b, o->u.polygon.points[i]);
		break;
	case PRIM_RAW: {
		const struct scene_mesh *m = &s->meshes[o->u.raw.mesh];
		for (uint64_t i = 0; i < 3ull * m->n_triangles; i++)
			b = geom_box_point(b, m->vertices[m->tris[i]]);
		break;
	}
	default:
		break;
	}
	return b;
}

/* ---- quadric and slab helpers ------------------------------------------------------ */

/* Infinite cylinder side roots (axis through `from` along unit a). Returns
 * 0 miss, 1 roots in t0 <= t1, 2 the whole line is inside (parallel ray). */
static inline __attribute__((always_inline)) int cyl_side_roots(const struct geom_obj *g, vec3 o, vec3 d, double *t0,
								 double *t1)
{
	vec3 a = g->u.cyl.a;
	vec3 oc = v3_sub(o, g->u.cyl.from);
	vec3 op = v3_sub(oc, v3_scale(a, v3_dot(oc, a)));
	vec3 dp = v3_sub(d, v3_scale(a, v3_dot(d, a)));
	double r2 = g->u.cyl.r * g->u.cyl.r;
	if (geom_tube_misses(op, dp, r2)) /* TUBE PRE-REJECT: side 0, as below */
		return 0;
	if (v3_dot(dp, dp) <= 1e-30 * v3_dot(d, d))
		return v3_dot(op, op) <= r2 ? 2 : 0;
	return geom_sphere_roots(op, dp, r2, t0, t1) ? 1 : 0;
}

/* Slab 0 <= (p - from).a <= h: 0 miss, 1 [t0, t1] with parts, 2 whole line. */
static inline __attribute__((always_inline)) int cyl_slab(const struct geom_obj *g, vec3 o, vec3 d, double *t0,
							   double *t1, int *p0, int *p1)
{
	double z0 = v3_dot(v3_sub(o, g->u.cyl.from), g->u.cyl.a), dz = v3_dot(d, g->u.cyl.a);
	if (dz == 0)
		return z0 >= 0 && z0 <= g->u.cyl.h ? 2 : 0;
	double ta = -z0 / dz, tb = (g->u.cyl.h - z0) / dz;
	if (ta <= tb) {
		*t0 = ta, *p0 = GEOM_PART_CAP0, *t1 = tb, *p1 = GEOM_PART_CAP1;
	} else {
		*t0 = tb, *p0 = GEOM_PART_CAP1, *t1 = ta, *p1 = GEOM_PART_CAP0;
	}
	return 1;
}

/* The capped solid's interval along the line; parts say side or which cap. */
static inline __attribute__((always_inline)) bool cyl_solid(const struct geom_obj *g, vec3 o, vec3 d, double *t0,
							     double *t1, int *p0, int *p1)
{
	double s0 = -INFINITY, s1 = INFINITY, c0 = -INFINITY, c1 = INFINITY;
	int q0 = GEOM_PART_CAP0, q1 = GEOM_PART_CAP1;
	int side = cyl_side_roots(g, o, d, &s0, &s1);
	if (side == 0)
		return false;
	if (side == 2)
		s0 = -INFINITY, s1 = INFINITY;
	int slab = cyl_slab(g, o, d, &c0, &c1, &q0, &q1);
	if (slab == 0)
		return false;
	if (slab == 2)
		c0 = -INFINITY, c1 = INFINITY;
	if (s0 >= c0)
		*t0 = s0, *p0 = GEOM_PART_MAIN;
	else
		*t0 = c0, *p0 = q0;
	if (s1 <= c1)
		*t1 = s1, *p1 = GEOM_PART_MAIN;
	else
		*t1 = c1, *p1 = q1;
	return *t0 <= *t1 && isfinite(*t0) && isfinite(*t1);
}

/* Box slab test over the whole line: parts are 2*axis + (1 for the hi face). */
static bool box_solid(const struct geom_obj *g, vec3 o, vec3 d, double *t0, double *t1, int *p0, int *p1)
{
	double lo[3] = { g->u.box.lo.x, g->u.box.lo.y, g->u.box.lo.z };
	double hi[3] = { g->u.box.hi.x, g->u.box.hi.y, g->u.box.hi.z };
	double oo[3] = { o.x, o.y, o.z }, dd[3] = { d.x, d.y, d.z };
	double tn = -INFINITY, tf = INFINITY;
	int pn = 0, pf = 1;
	for (int k = 0; k < 3; k++) {
		if (dd[k] == 0) {
			if (oo[k] < lo[k] || oo[k] > hi[k])
				return false;
			continue;
		}
		double ta = (lo[k] - oo[k]) / dd[k], tb = (hi[k] - oo[k]) / dd[k];
		int pa = 2 * k, pb = 2 * k + 1;
		if (ta > tb) {
			double tt = ta;
			ta = tb, tb = tt;
			int pp = pa;
			pa = pb, pb = pp;
		}
		if (ta > tn)
			tn = ta, pn = pa;
		if (tb < tf)
			tf = tb, pf = pb;
	}
	if (!(tn <= tf) || !isfinite(tn) || !isfinite(tf))
		return false;
	*t0 = tn, *t1 = tf, *p0 = pn, *p1 = pf;
	return true;
}

/* Line meets the plane (pos, n): t, or false when parallel. */
static bool plane_t(vec3 pos, vec3 n, vec3 o, vec3 d, double *t) { return geom_plane_t(pos, n, o, d, t); }

static bool tri_line(const struct geom_obj *g, vec3 o, vec3 d, double tmin, double tmax, double *t)
{
	struct geom_wray w;
	geom_wray_init(&w, o, d);
	double b1, b2;
	return geom_tri_hit(&w, g->u.tri.a, g->u.tri.b, g->u.tri.c, tmin, tmax, t, &b1, &b2);
}

/* Planar shapes (disk, polygon): does the plane point at t lie on the shape? */
static bool planar_on(const struct geom_obj *g, vec3 p)
{
	if (g->kind == PRIM_DISK) {
		vec3 q = v3_sub(p, g->u.pl.pos);
		return v3_dot(q, q) <= g->u.pl.r * g->u.pl.r;
	}
	return poly_inside(&g->u.poly, v3_comp(p, g->u.poly.ax0), v3_comp(p, g->u.poly.ax1));
}

static bool planar_t(const struct geom_obj *g, vec3 o, vec3 d, double *t)
{
	if (g->kind == PRIM_POLYGON)
		return v3_len(g->u.poly.n) > 0 && plane_t(g->u.poly.p0, g->u.poly.n, o, d, t);
	return plane_t(g->u.pl.pos, g->u.pl.n, o, d, t);
}

static bool in_range(double t, double tmin, double tmax) { return t > tmin && t < tmax; }

/* ---- closest hit ------------------------------------------------------------------------- */

bool geom_intersect(const struct geom_obj *g, vec3 o, vec3 d, double tmin, double tmax, double *t, int *part)
{
	double t0, t1;
	int p0 = GEOM_PART_MAIN, p1 = GEOM_PART_MAIN;
	switch (g->kind) {
	case PRIM_SPHERE: {
		double r = g->u.sph.r;
		if (!geom_sphere_roots(v3_sub(o, g->u.sph.c), d, r * r, &t0, &t1))
			return false;
		break;
	}
	case PRIM_PLANE:
		if (!plane_t(g->u.pl.pos, g->u.pl.n, o, d, &t0) || !in_range(t0, tmin, tmax))
			return false;
		*t = t0;
		*part = GEOM_PART_MAIN;
		return true;
	case PRIM_DISK:
	case PRIM_POLYGON:
		if (!planar_t(g, o, d, &t0) || !in_range(t0, tmin, tmax))
			return false;
		if (!planar_on(g, v3_add(o, v3_scale(d, t0))))
			return false;
		*t = t0;
		*part = GEOM_PART_MAIN;
		return true;
	case PRIM_TRIANGLE:
		if (!tri_line(g, o, d, tmin, tmax, t))
			return false;
		*part = GEOM_PART_MAIN;
		return true;
	case PRIM_BOX:
		if (!box_solid(g, o, d, &t0, &t1, &p0, &p1))
			return false;
		break;
	case PRIM_CYLINDER:
		if (g->u.cyl.capped) {
			if (!cyl_solid(g, o, d, &t0, &t1, &p0, &p1))
				return false;
		} else {
			return geom_cyl_open_hit(g->u.cyl.from, g->u.cyl.a, g->u.cyl.r, g->u.cyl.h, o, d, tmin, tmax, t, part);
		}
		break;
	default:
		return false;
	}
	if (in_range(t0, tmin, tmax)) {
		*t = t0, *part = p0;
		return true;
	}
	if (in_range(t1, tmin, tmax)) {
		*t = t1, *part = p1;
		return true;
	}
	return false;
}

/* ---- crossings for CSG ------------------------------------------------------------------------ */

int geom_crossings(const struct geom_obj *g, vec3 o, vec3 d, struct geom_cross1 out[2], bool *inside0)
{
	double t0, t1;
	int p0 = GEOM_PART_MAIN, p1 = GEOM_PART_MAIN;
	*inside0 = false;
	switch (g->kind) {
	case PRIM_SPHERE: {
		double r = g->u.sph.r;
		if (!geom_sphere_roots(v3_sub(o, g->u.sph.c), d, r * r, &t0, &t1))
			return 0;
		break;
	}
	case PRIM_BOX:
		if (!box_solid(g, o, d, &t0, &t1, &p0, &p1))
			return 0;
		break;
	case PRIM_CYLINDER: {
		if (!cyl_solid(g, o, d, &t0, &t1, &p0, &p1))
			return 0;
		bool cap = g->u.cyl.capped;
		out[0] = (struct geom_cross1){ t0, p0, GEOM_X_ENTER | (cap || p0 == GEOM_PART_MAIN ? GEOM_X_DRAW : 0) };
		out[1] = (struct geom_cross1){ t1, p1, GEOM_X_EXIT | (cap || p1 == GEOM_PART_MAIN ? GEOM_X_DRAW : 0) };
		return 2;
	}
	case PRIM_PLANE: { /* the half-space behind the normal: (p - pos).n < 0 */
		double den = v3_dot(d, g->u.pl.n);
		double s0 = v3_dot(v3_sub(o, g->u.pl.pos), g->u.pl.n);
		if (den == 0 || !plane_t(g->u.pl.pos, g->u.pl.n, o, d, &t0)) {
			*inside0 = s0 < 0;
			return 0;
		}
		*inside0 = den > 0;
		out[0] = (struct geom_cross1){ t0, GEOM_PART_MAIN, (den > 0 ? GEOM_X_EXIT : GEOM_X_ENTER) | GEOM_X_DRAW };
		return 1;
	}
	case PRIM_DISK:
	case PRIM_POLYGON:
		if (!planar_t(g, o, d, &t0) || !planar_on(g, v3_add(o, v3_scale(d, t0))))
			return 0;
		out[0] = (struct geom_cross1){ t0, GEOM_PART_MAIN, GEOM_X_SURF | GEOM_X_DRAW };
		return 1;
	case PRIM_TRIANGLE:
		if (!tri_line(g, o, d, -INFINITY, INFINITY, &t0))
			return 0;
		out[0] = (struct geom_cross1){ t0, GEOM_PART_MAIN, GEOM_X_SURF | GEOM_X_DRAW };
		return 1;
	default:
		return 0;
	}
	out[0] = (struct geom_cross1){ t0, p0, GEOM_X_ENTER | GEOM_X_DRAW };
	out[1] = (struct geom_cross1){ t1, p1, GEOM_X_EXIT | GEOM_X_DRAW };
	return 2;
}

/* ---- normals and (u,v) ------------------------------------------------------------------------- */

void geom_tri_uv(vec3 a, vec3 b, vec3 c, vec3 p, double *u, double *v)
{
	geom_tri_uv_n(a, b, v3_norm(v3_cross(v3_sub(b, a), v3_sub(c, a))), p, u, v);
}

/* geom_surface and geom_normal: uv false skips the mapping (u, v are then
 * scratch), never changing *n. */
static inline __attribute__((always_inline)) void surface(const struct geom_obj *g, vec3 p, int part, vec3 *n,
							  double *u, double *v, const bool uv)
{
	*u = *v = 0;
	switch (g->kind) {
	case PRIM_SPHERE: {
		vec3 q = v3_norm(v3_sub(p, g->u.sph.c));
		double r = g->u.sph.r;
		*n = q;
		if (!uv)
			break;
		*u = r * angle_2pi(v3_dot(q, g->u.sph.W), v3_dot(q, g->u.sph.E));
		double s = v3_dot(q, g->u.sph.P);
		s = s > 1 ? 1 : s < -1 ? -1 : s;
		*v = r * (xm_asin(s) + M_PI / 2);
		break;
	}
	case PRIM_PLANE:
	case PRIM_DISK: {
		*n = g->u.pl.n;
		if (!uv)
			break;
		vec3 q = v3_sub(p, g->u.pl.pos);
		*u = v3_dot(q, g->u.pl.X);
		*v = v3_dot(q, g->u.pl.Y);
		break;
	}
	case PRIM_CYLINDER: {
		vec3 q = v3_sub(p, g->u.cyl.from);
		double z = v3_dot(q, g->u.cyl.a);
		if (part == GEOM_PART_MAIN) {
			vec3 rad = v3_sub(q, v3_scale(g->u.cyl.a, z));
			*n = v3_norm(rad);
			if (uv)
				*u = g->u.cyl.r * angle_2pi(v3_dot(rad, g->u.cyl.Y), v3_dot(rad, g->u.cyl.X));
			*v = z;
		} else {
			vec3 c = part == GEOM_PART_CAP0 ? g->u.cyl.from
							: v3_add(g->u.cyl.from, v3_scale(g->u.cyl.a, g->u.cyl.h));
			vec3 qc = v3_sub(p, c);
			*n = part == GEOM_PART_CAP0 ? v3_neg(g->u.cyl.a) : g->u.cyl.a;
			*u = v3_dot(qc, g->u.cyl.X);
			*v = v3_dot(qc, g->u.cyl.Y);
		}
		break;
	}
	case PRIM_BOX: {
		int axis = part / 2;
		double sgn = part & 1 ? 1 : -1;
		vec3 q = v3_sub(p, g->u.box.lo);
		*n = v3(axis == 0 ? sgn : 0, axis == 1 ? sgn : 0, axis == 2 ? sgn : 0);
		if (axis == 0)
			*u = q.z, *v = q.y;
		else if (axis == 1)
			*u = q.x, *v = q.z;
		else
			*u = q.x, *v = q.y;
		break;
	}
	case PRIM_TRIANGLE: {
		vec3 a = g->u.tri.a, b = g->u.tri.b, c = g->u.tri.c;
		vec3 cr = v3_cross(v3_sub(b, a), v3_sub(c, a));
		vec3 ng = v3_norm(cr);
		*n = ng;
		if (g->u.tri.smooth) {
			double den = v3_dot(cr, cr);
			double w1 = den > 0 ? v3_dot(v3_cross(v3_sub(p, a), v3_sub(c, a)), cr) / den : 0;
			double w2 = den > 0 ? v3_dot(v3_cross(v3_sub(b, a), v3_sub(p, a)), cr) / den : 0;
			vec3 sn = v3_add(v3_add(v3_scale(g->u.tri.na, 1 - w1 - w2), v3_scale(g->u.tri.nb, w1)),
					 v3_scale(g->u.tri.nc, w2));
			if (v3_len(sn) > 0)
				*n = v3_norm(sn);
		}
		if (uv)
			geom_tri_uv(a, b, c, p, u, v);
		break;
	}
	case PRIM_POLYGON: {
		*n = g->u.poly.n;
		if (!uv)
			break;
		vec3 q = v3_sub(p, g->u.poly.p0);
		*u = v3_dot(q, g->u.poly.X);
		*v = v3_dot(q, g->u.poly.Y);
		break;
	}
	default:
		*n = v3(0, 1, 0);
		break;
	}
}

void geom_surface(const struct geom_obj *g, vec3 p, int part, vec3 *n, double *u, double *v)
{
	surface(g, p, part, n, u, v, true);
}

vec3 geom_normal(const struct geom_obj *g, vec3 p, int part)
{
	vec3 n;
	double u, v;
	surface(g, p, part, &n, &u, &v, false);
	return n;
}

/* ---- watertight ray set-up ---------------------------------------------------------------------------- */

void geom_wray_init(struct geom_wray *w, vec3 o, vec3 d)
{
	double dd[3] = { d.x, d.y, d.z };
	w->o[0] = o.x, w->o[1] = o.y, w->o[2] = o.z;
	double ax = fabs(d.x), ay = fabs(d.y), az = fabs(d.z);
	int kz = ax >= ay && ax >= az ? 0 : ay >= az ? 1 : 2;
	static const int next[3] = { 1, 2, 0 };
	int kx = next[kz], ky = next[kx];
	if (dd[kz] < 0) {
		int tmp = kx;
		kx = ky, ky = tmp;
	}
	w->kx = kx, w->ky = ky, w->kz = kz;
	w->ox = w->o[kx], w->oy = w->o[ky], w->oz = w->o[kz];
	double inv = dd[kz] != 0 ? 1.0 / dd[kz] : 0;
	w->sx = dd[kx] * inv;
	w->sy = dd[ky] * inv;
	w->sz = inv;
}

/* ---- secondary ray origins (declared in accel.h; here so that a test's own
 * accel_intersect does not collide with accel.o) ----------------------------- */

/* relative epsilon of accel_offset_point: see the strategy in accel.c */
#define ACCEL_OFFSET_REL 1e-9

vec3 accel_offset_point(vec3 p, vec3 ng, vec3 dir)
{
	double m = geom_fmax(fabs(p.x), geom_fmax(fabs(p.y), fabs(p.z)));
	double e = ACCEL_OFFSET_REL * (1 + m);
	return v3_add(p, v3_scale(ng, v3_dot(dir, ng) < 0 ? -e : e));
}
