/*
 * xmath.h - the transcendental functions of the pixel path, computed in the
 * tree from plain IEEE-754 double arithmetic (+ - * / and sqrt, all
 * correctly rounded), so that every compiler, C library and CPU gives the
 * same bits (docs/maths.md: the algorithms and their error bounds).
 *
 * Each function follows C99 Annex F for its special values (zeros, NaN,
 * infinities); errno is never set.
 */
#ifndef PORTRAY_XMATH_H
#define PORTRAY_XMATH_H

#include <float.h>
#include <math.h>
#include <stdint.h>

/*
 * Flags that change the value of double arithmetic would make this build's
 * pixels differ from every other build's: refuse them here (each pixel-path
 * file includes this header). -fno-math-errno and -fno-trapping-math change
 * no value and are allowed. Contraction (a*b+c fused) has no macro: the
 * Makefile passes -ffp-contract=off and the start-up probe (common/probe.h)
 * catches a build that overrides it.
 */
#if defined(__FAST_MATH__)
#error "portray must not be built with -ffast-math: it changes pixels (docs/maths.md)"
#endif
#if defined(__FINITE_MATH_ONLY__) && __FINITE_MATH_ONLY__
#error "portray must not be built with -ffinite-math-only: the tracer relies on infinities"
#endif
#if defined(__ASSOCIATIVE_MATH__) || defined(__RECIPROCAL_MATH__) || defined(__NO_SIGNED_ZEROS__)
#error "portray must not be built with -fassociative-math, -freciprocal-math or -fno-signed-zeros: they change pixels"
#endif
#if !defined(FLT_EVAL_METHOD) || FLT_EVAL_METHOD != 0
#error "portray needs FLT_EVAL_METHOD == 0 (doubles evaluated as doubles: SSE2 on x86, not x87)"
#endif

double xm_sin(double x);
double xm_cos(double x);
/* sin and cos of one angle with one argument reduction */
void xm_sincos(double x, double *s, double *c);
double xm_tan(double x);
double xm_atan(double x);
double xm_atan2(double y, double x);
double xm_asin(double x);
double xm_acos(double x);
double xm_exp(double x);
double xm_log(double x);
double xm_pow(double x, double y);
/*
 * x^y as exp(y log x) with the logarithm and the product in plain doubles
 * (LITE POW, docs/maths.md): within 4 + 6|y log x| ulps of x^y
 * instead of xm_pow's one, in about 60% of its time (bench_xmath); xm_pow itself
 * beyond |y| < 2^20 and near the ends of the range. For the Phong
 * highlight, whose value is scaled and summed into a colour.
 */
double xm_pow_lite(double x, double y);
/*
 * A cheap upper bound on xm_pow(x, y) for 0 < x < 1 and 0 <= y < 2^64: a
 * power of two, at most 4 e^(y w^3 / (3 (1 - w))) times x^y (w = 1 - x:
 * tight near x = 1, where highlights are); INFINITY for any other argument.
 * A caller that needs x^y only when it can matter skips xm_pow with it
 * (common/shade.c; docs/maths.md). Inline: it is called where xm_pow was.
 *
 * log x = log(1 - w) = -(w + w^2/2 + w^3/3 + ...) <= -(w + w^2/2), so x^y
 * <= 2^-t, t = y (w + w^2/2) / ln 2. The computed t has 6 roundings of
 * positive terms (the constant's included: relative error below 2^-50), so
 * tl = t (1 - 2^-48) is below the exact t, and with n = floor(tl), x^y <=
 * 2^-n. 2^(1-n) then bounds any result within 2^51 ulps of x^y (xm_pow is
 * within 1) and any subnormal one (n < 1000).
 */
static inline double xm_pow_ub(double x, double y)
{
	if (!(x > 0 && x < 1 && y >= 0 && y < 0x1p64))
		return INFINITY;
	double w = 1 - x;
	double t = y * (w + 0.5 * (w * w)) * 0x1.71547652b82fep+0; /* 1/ln 2 rounded */
	double tl = t * (1 - 0x1p-48);
	if (tl >= 1000)
		return 0x1p-999;
	union { uint64_t u; double d; } b = { (uint64_t)(1023 + 1 - (int)tl) << 52 }; /* (int): floor, tl >= 0 */
	return b.d;
}

#endif
