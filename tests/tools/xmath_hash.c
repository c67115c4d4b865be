/*
 * xmath_hash.c - prints, per function of common/xmath.h, a 64-bit hash of
 * its results over N fixed arguments (default 2^20: the same spread as
 * test_xmath, from a fixed seed). Two builds (another compiler, flags or
 * CPU) must print the same lines: tests/e2e/cross_*.sh compare them.
 *   xmath_hash [N]
 */
#include <math.h> /* floor */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/xmath.h"

static uint64_t s = 0x243f6a8885a308d3ull;
static uint64_t rnd64(void)
{
	s ^= s >> 12;
	s ^= s << 25;
	s ^= s >> 27;
	return s * 0x2545f4914f6cdd1dull;
}

/* an argument: random bits, or a random value in a useful range */
static double arg(long i)
{
	uint64_t u = rnd64();
	double d;
	switch (i % 4) {
	case 0: memcpy(&d, &u, sizeof d); return d;
	case 1: return ((double)(u >> 11) * 0x1p-53 - 0.5) * 20;
	case 2: return (double)(u >> 11) * 0x1p-53 * 2 - 1;
	default: return ((double)(u >> 11) * 0x1p-53 - 0.5) * 1500;
	}
}

static uint64_t mix(uint64_t h, double d)
{
	uint64_t u;
	memcpy(&u, &d, sizeof u);
	if (d != d)
		u = 0x7ff8000000000000ull; /* any NaN: its payload is not ours to promise */
	for (int i = 0; i < 8; i++) {
		h ^= (u >> (8 * i)) & 0xff;
		h *= 0x100000001b3ull;
	}
	return h;
}

int main(int argc, char **argv)
{
	long n = argc > 1 ? atol(argv[1]) : 1L << 20;
	static const char *const names[] = { "sin", "cos", "tan", "atan", "asin", "acos", "exp", "log", "atan2", "pow" };
	for (int f = 0; f < 10; f++) {
		uint64_t h = 0xcbf29ce484222325ull;
		s = 0x243f6a8885a308d3ull + (uint64_t)f;
		for (long i = 0; i < n; i++) {
			double x = arg(i), y = arg(i + 1), r;
			switch (f) {
			case 0: r = xm_sin(x); break;
			case 1: r = xm_cos(x); break;
			case 2: r = xm_tan(x); break;
			case 3: r = xm_atan(x); break;
			case 4: r = xm_asin(x); break;
			case 5: r = xm_acos(x); break;
			case 6: r = xm_exp(x); break;
			case 7: r = xm_log(x < 0 ? -x : x); break;
			case 8: r = xm_atan2(x, y); break;
			default: r = xm_pow(x < 0 && i % 3 ? -x : x, i % 5 ? y / 8 : floor(y / 8)); break; /* integers too */
			}
			h = mix(h, r);
		}
		printf("%-6s %ld %016llx\n", names[f], n, (unsigned long long)h);
	}
	return 0;
}
