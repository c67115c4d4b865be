/*
 * bench_xmath.c - the highlight's pow: nanoseconds a call of xm_pow and
 * xm_pow_lite (LITE POW, docs/maths.md) on what direct() gives them, R.V
 * in [0.2, 1) and the SPD scenes' specular power 3.0827 (and 20, the
 * language's default), best of 7 passes of thread CPU time, interleaved.
 * It also prints the largest difference between the two in ulps of
 * xm_pow's result over those arguments. Not a test: prints figures only.
 *
 *   build/bench/bench_xmath [-n PASSES]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench/bench_scene.h"
#include "common/xmath.h"

enum { N_ARGS = 1024, REPS = 2000 };

typedef double (*powfn)(double, double);

/* One pass: every argument REPS times; the sum keeps the calls. */
static double pass(powfn f, const double *x, double y, double *sum)
{
	double s = 0, t0 = bs_cpu_now();
	for (int r = 0; r < REPS; r++)
		for (int i = 0; i < N_ARGS; i++)
			s += f(x[i], y);
	*sum += s;
	return bs_cpu_now() - t0;
}

int main(int argc, char **argv)
{
	int passes = 7;
	if (argc == 3 && strcmp(argv[1], "-n") == 0)
		passes = atoi(argv[2]);
	if (passes < 1 || (argc != 1 && argc != 3)) {
		fprintf(stderr, "usage: bench_xmath [-n PASSES]\n");
		return 2;
	}
	double x[N_ARGS];
	for (int i = 0; i < N_ARGS; i++)
		x[i] = 0.2 + 0.79 * i / N_ARGS;
	static const double powers[] = { 3.0827, 20 };
	double sum = 0;
	for (size_t p = 0; p < sizeof powers / sizeof powers[0]; p++) {
		double y = powers[p], best[2] = { 1e300, 1e300 }, ulps = 0;
		for (int k = 0; k < passes; k++) {
			double t = pass(xm_pow, x, y, &sum);
			best[0] = t < best[0] ? t : best[0];
			t = pass(xm_pow_lite, x, y, &sum);
			best[1] = t < best[1] ? t : best[1];
		}
		for (int i = 0; i < N_ARGS; i++) {
			double a = xm_pow(x[i], y), b = xm_pow_lite(x[i], y);
			double u = fabs(a - b) / (nextafter(a, INFINITY) - a);
			ulps = u > ulps ? u : ulps;
		}
		double calls = (double)N_ARGS * REPS;
		printf("pow x^%g, x in [0.2, 1): xm_pow %.1f ns, xm_pow_lite %.1f ns a call (%.2fx); at most %.0f ulps apart\n",
		       y, best[0] / calls * 1e9, best[1] / calls * 1e9, best[0] / best[1], ulps);
	}
	return sum == 42 ? 1 : 0; /* never: the sum only keeps the calls */
}
