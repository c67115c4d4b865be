/*
 * accel_box.h - a single ray's box tests against the BVH's float boxes
 * (BOX TESTS, accel_int.h): its constants (struct ray4), the slab test of a
 * node's four or eight children, and the double test of a root that is one
 * leaf. Shared by the single-ray queries (accel.c) and the shadow
 * crossings (accel_cross.c); private to the accel.
 */
#ifndef PORTRAY_ACCEL_BOX_H
#define PORTRAY_ACCEL_BOX_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "common/accel_int.h"
#include "common/accel_trace.h"

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

/* The offsets of each axis' near and far planes in a node whose bounds
 * are rows of w floats (lo[3][w] then hi[3][w]: lo[k] at w k, hi[k] at
 * w (3 + k)), by the ray's octant: the "sign" trick of slab4. */
static inline __attribute__((always_inline)) void slab_planes(uint32_t w, uint32_t oct, uint32_t near[3], uint32_t far[3])
{
	for (uint32_t k = 0; k < 3; k++) {
		near[k] = k * w + 3 * w * (oct >> k & 1);
		far[k] = k * w + 3 * w * (~oct >> k & 1);
	}
}

/*
 * Slab test of four children against [tmin, tmax] (box space, tmin >= 0):
 * slab4, and node4_hit for a node's. Returns a mask (bit c: child c may be hit) and the widened
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

/* The slab test of four children whose bounds are rows of w floats
 * (lo[3][w] then hi[3][w]) from b: lanes b[0..4) of each row. */
static inline __attribute__((always_inline)) int slab4(const float *b, const uint32_t w, const struct ray4 *q,
							uint32_t oct, tspan tmin, tspan tmax, float tn[4])
{
	uint32_t near[3], far[3];
	slab_planes(w, oct, near, far);
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

static inline __attribute__((always_inline)) int node4_hit(const struct bvh4 *nd, const struct ray4 *q,
							    uint32_t oct, tspan tmin, tspan tmax, float tn[4])
{
	return slab4((const float *)(const void *)nd, 4, q, oct, tmin, tmax, tn);
}

/*
 * node4_hit on a WIDE NODE (bvh.h): the same slab test, eight children in
 * two 4-lane halves; bit c of the mask for child c, entry distances in
 * tn[0..8).
 */
_Static_assert(offsetof(struct bvh8, hi) == 24 * sizeof(float), "bvh8 rows: lo[3][8] then hi[3][8]");

static inline __attribute__((always_inline)) int node8_hit(const struct bvh8 *nd, const struct ray4 *q,
							    uint32_t oct, tspan tmin, tspan tmax, float tn[8])
{
	const float *b = (const float *)(const void *)nd;
	return slab4(b, 8, q, oct, tmin, tmax, tn) | slab4(b + 4, 8, q, oct, tmin, tmax, tn + 4) << 4;
}

/*
 * WIDE NODES IN AVX2. On x86-64 the single ray's closest-hit walk
 * (bvh_hit, accel_hit.h) has a second copy whose node test takes a wide
 * node's eight children in one 256-bit pass instead of node8_hit's two
 * halves, in functions compiled for AVX2 and chosen at run time where the
 * CPU has it (accel_use_avx2). Each lane's arithmetic is node8_hit's:
 * the same float subtraction, product, max and min in the same order, and
 * an ordered <= (no lane sees NaN differently), so the mask and the entry
 * distances are the same bits and both copies walk the same nodes. The
 * build itself needs no -mavx2: only these functions are compiled for it.
 */
#if defined(__x86_64__) && defined(__SSE2__) && (defined(__GNUC__) || defined(__clang__)) && !defined(PORTRAY_NO_AVX2)
#define ACCEL_AVX2 1
#include <immintrin.h>

struct ray8 {
	__m256 o[3], inv_near[3], inv_far[3];
	uint32_t oct;
	double tscale;
};

static inline __attribute__((always_inline, target("avx2"))) void ray8_init(struct ray8 *q, const struct trace *r,
									    vec3 center)
{
	struct ray_box b;
	ray_box_init(&b, r, center);
	q->tscale = b.tscale;
	q->oct = b.oct;
	for (uint32_t k = 0; k < 3; k++) {
		q->o[k] = _mm256_set1_ps(b.o[k]);
		q->inv_near[k] = _mm256_set1_ps(b.inv_near[k]);
		q->inv_far[k] = _mm256_set1_ps(b.inv_far[k]);
	}
}

static inline __attribute__((always_inline, target("avx2"))) __m256 span8_of(float t) { return _mm256_set1_ps(t); }

/* node8_hit in one pass: bit c of the mask for child c, tn[0..8) */
static inline __attribute__((always_inline, target("avx2"))) int node8_hit_avx2(const struct bvh8 *nd,
										const struct ray8 *q, uint32_t oct,
										__m256 tmin, __m256 tmax, float tn[8])
{
	const float *b = (const float *)(const void *)nd;
	uint32_t near[3], far[3];
	slab_planes(8, oct, near, far);
	__m256 t0 = tmin, t1 = tmax;
	for (int k = 0; k < 3; k++) {
		__m256 tnear = _mm256_mul_ps(_mm256_sub_ps(_mm256_loadu_ps(b + near[k]), q->o[k]), q->inv_near[k]);
		__m256 tfar = _mm256_mul_ps(_mm256_sub_ps(_mm256_loadu_ps(b + far[k]), q->o[k]), q->inv_far[k]);
		t0 = _mm256_max_ps(t0, tnear);
		t1 = _mm256_min_ps(t1, tfar);
	}
	_mm256_storeu_ps(tn, t0);
	return _mm256_movemask_ps(_mm256_cmp_ps(t0, t1, _CMP_LE_OQ));
}
#else
#define ACCEL_AVX2 0
#endif

#define SLAB_WIDEN 4.5e-16 /* 1 + 2 gamma(3) for doubles, rounded up (Ize 2013) */

/* The same test in double on one box of six floats (a root that is a leaf). */
static inline bool box_hit(const float b[6], vec3 center, const struct trace *r)
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

#endif
