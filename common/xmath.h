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

#endif
