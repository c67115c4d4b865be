/*
 * vec.h - small value types for 3-vectors, colours and affine transforms.
 *
 * Everything here is a plain value struct and a static inline function, so the
 * compiler can keep vectors in registers on the hot paths of the tracer.
 * Colours are vec3 with x=r, y=g, z=b.
 */
#ifndef PORTRAY_VEC_H
#define PORTRAY_VEC_H

#include <math.h>

typedef struct vec3 {
	double x, y, z;
} vec3;

/* Affine transform: p' = M p + t, stored row-major as m[row][col], col 3 = t. */
typedef struct mat34 {
	double m[3][4];
} mat34;

static inline vec3 v3(double x, double y, double z)
{
	vec3 r = { x, y, z };
	return r;
}

/*
 * *p read one component at a time (8-byte loads), for a vector that was
 * just stored that way (a hit accel has filled in): gcc would otherwise
 * read x and y with one 16-byte load, which cannot take its data from two
 * 8-byte stores still in the store buffer and waits until they reach the
 * cache (a store-forwarding stall, about a dozen cycles each on x86). The
 * empty asm keeps the three loads apart and costs nothing else.
 */
static inline vec3 v3_load_split(const vec3 *p)
{
	double x = p->x, y = p->y, z = p->z;
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__)) && defined(__SSE2__)
	__asm__("" : "+x"(x), "+x"(y), "+x"(z));
#endif
	return v3(x, y, z);
}
static inline vec3 v3_add(vec3 a, vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline vec3 v3_sub(vec3 a, vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline vec3 v3_mul(vec3 a, vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline vec3 v3_scale(vec3 a, double s) { return v3(a.x * s, a.y * s, a.z * s); }
static inline vec3 v3_neg(vec3 a) { return v3(-a.x, -a.y, -a.z); }
static inline double v3_dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline vec3 v3_cross(vec3 a, vec3 b)
{
	return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double v3_len(vec3 a) { return sqrt(v3_dot(a, a)); }
/* Unit vector along a; a zero vector stays zero (callers validate lengths). */
static inline vec3 v3_norm(vec3 a)
{
	double l = v3_len(a);
	return l > 0 ? v3_scale(a, 1.0 / l) : a;
}
static inline vec3 v3_lerp(vec3 a, vec3 b, double t)
{
	return v3(a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t, a.z + (b.z - a.z) * t);
}
static inline vec3 v3_min(vec3 a, vec3 b) { return v3(fmin(a.x, b.x), fmin(a.y, b.y), fmin(a.z, b.z)); }
static inline vec3 v3_max(vec3 a, vec3 b) { return v3(fmax(a.x, b.x), fmax(a.y, b.y), fmax(a.z, b.z)); }
static inline double v3_comp(vec3 a, int axis) { return axis == 0 ? a.x : axis == 1 ? a.y : a.z; }
/* The largest |component| (plain comparisons, NaN as they order it). */
static inline double v3_maxabs(vec3 a)
{
	double x = fabs(a.x), y = fabs(a.y), z = fabs(a.z);
	double m = x > y ? x : y;
	return m > z ? m : z;
}
static inline int v3_finite(vec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }

static inline mat34 m34_identity(void)
{
	mat34 r = { { { 1, 0, 0, 0 }, { 0, 1, 0, 0 }, { 0, 0, 1, 0 } } };
	return r;
}

/* a * b: apply b first, then a. */
static inline mat34 m34_mul(const mat34 *a, const mat34 *b)
{
	mat34 r;
	for (int i = 0; i < 3; i++) {
		for (int j = 0; j < 4; j++) {
			double s = a->m[i][0] * b->m[0][j] + a->m[i][1] * b->m[1][j] + a->m[i][2] * b->m[2][j];
			r.m[i][j] = s + (j == 3 ? a->m[i][3] : 0.0);
		}
	}
	return r;
}

static inline vec3 m34_point(const mat34 *a, vec3 p)
{
	return v3(a->m[0][0] * p.x + a->m[0][1] * p.y + a->m[0][2] * p.z + a->m[0][3],
		  a->m[1][0] * p.x + a->m[1][1] * p.y + a->m[1][2] * p.z + a->m[1][3],
		  a->m[2][0] * p.x + a->m[2][1] * p.y + a->m[2][2] * p.z + a->m[2][3]);
}

static inline vec3 m34_dir(const mat34 *a, vec3 d)
{
	return v3(a->m[0][0] * d.x + a->m[0][1] * d.y + a->m[0][2] * d.z,
		  a->m[1][0] * d.x + a->m[1][1] * d.y + a->m[1][2] * d.z,
		  a->m[2][0] * d.x + a->m[2][1] * d.y + a->m[2][2] * d.z);
}

/* Normal transform with the inverse-transpose: pass the INVERSE matrix. */
static inline vec3 m34_normal(const mat34 *inv, vec3 n)
{
	return v3(inv->m[0][0] * n.x + inv->m[1][0] * n.y + inv->m[2][0] * n.z,
		  inv->m[0][1] * n.x + inv->m[1][1] * n.y + inv->m[2][1] * n.z,
		  inv->m[0][2] * n.x + inv->m[1][2] * n.y + inv->m[2][2] * n.z);
}

/* Inverse of an affine transform. Returns 0 when singular (det ~ 0). */
static inline int m34_invert(const mat34 *a, mat34 *out)
{
	const double (*m)[4] = a->m;
	double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
	double c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
	double c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
	double det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
	if (!(fabs(det) > 1e-300) || !isfinite(det))
		return 0;
	double id = 1.0 / det;
	mat34 r;
	r.m[0][0] = c00 * id;
	r.m[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * id;
	r.m[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * id;
	r.m[1][0] = c01 * id;
	r.m[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * id;
	r.m[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * id;
	r.m[2][0] = c02 * id;
	r.m[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * id;
	r.m[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * id;
	for (int i = 0; i < 3; i++)
		r.m[i][3] = -(r.m[i][0] * m[0][3] + r.m[i][1] * m[1][3] + r.m[i][2] * m[2][3]);
	*out = r;
	return 1;
}

#endif
