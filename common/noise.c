/*
 * noise.c - Perlin's improved gradient noise and its fractal sums.
 *
 * Reference: K. Perlin, "Improving Noise", SIGGRAPH 2002. The permutation
 * table below is the one in Perlin's reference implementation, so values
 * are reproducible and comparable with it.
 */
#include "common/noise.h"

#include <math.h>

static const unsigned char perm[256] = {
	151, 160, 137, 91,  90,  15,  131, 13,  201, 95,  96,  53,  194, 233, 7,   225, 140, 36,
	103, 30,  69,  142, 8,   99,  37,  240, 21,  10,  23,  190, 6,   148, 247, 120, 234, 75,
	0,   26,  197, 62,  94,  252, 219, 203, 117, 35,  11,  32,  57,  177, 33,  88,  237, 149,
	56,  87,  174, 20,  125, 136, 171, 168, 68,  175, 74,  165, 71,  134, 139, 48,  27,  166,
	77,  146, 158, 231, 83,  111, 229, 122, 60,  211, 133, 230, 220, 105, 92,  41,  55,  46,
	245, 40,  244, 102, 143, 54,  65,  25,  63,  161, 1,   216, 80,  73,  209, 76,  132, 187,
	208, 89,  18,  169, 200, 196, 135, 130, 116, 188, 159, 86,  164, 100, 109, 198, 173, 186,
	3,   64,  52,  217, 226, 250, 124, 123, 5,   202, 38,  147, 118, 126, 255, 82,  85,  212,
	207, 206, 59,  227, 47,  16,  58,  17,  182, 189, 28,  42,  223, 183, 170, 213, 119, 248,
	152, 2,   44,  154, 163, 70,  221, 153, 101, 155, 167, 43,  172, 9,   129, 22,  39,  253,
	19,  98,  108, 110, 79,  113, 224, 232, 178, 185, 112, 104, 218, 246, 97,  228, 251, 34,
	242, 193, 238, 210, 144, 12,  191, 179, 162, 241, 81,  51,  145, 235, 249, 14,  239, 107,
	49,  192, 214, 31,  181, 199, 106, 157, 184, 84,  204, 176, 115, 121, 50,  45,  127, 4,
	150, 254, 138, 236, 205, 93,  222, 114, 67,  29,  24,  72,  243, 141, 128, 195, 78,  66,
	215, 61,  156, 180
};

static inline int P(int i) { return perm[i & 255]; }

/* 6t^5 - 15t^4 + 10t^3: zero first and second derivatives at 0 and 1. */
static inline double fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }

static inline double lerp(double t, double a, double b) { return a + t * (b - a); }

/* Dot product of (x, y, z) with one of the 12 cube-edge gradients picked by hash. */
static inline double grad(int hash, double x, double y, double z)
{
	int h = hash & 15;
	double u = h < 8 ? x : y;
	double v = h < 4 ? y : (h == 12 || h == 14) ? x : z;
	return ((h & 1) ? -u : u) + ((h & 2) ? -v : v);
}

/*
 * Splits a finite coordinate into its lattice cell (mod 256) and the
 * fraction within it. Exact for every finite double: floor() of a double is
 * an integer-valued double, and subtracting the multiple of 256 below it is
 * exact.
 */
static inline void cell(double x, int *i, double *f)
{
	double fx = floor(x);
	*i = (int)(fx - 256.0 * floor(fx / 256.0));
	*f = x - fx;
}

double noise_perlin(vec3 p)
{
	if (!v3_finite(p))
		return 0;
	int X, Y, Z;
	double x, y, z;
	cell(p.x, &X, &x);
	cell(p.y, &Y, &y);
	cell(p.z, &Z, &z);
	double u = fade(x), v = fade(y), w = fade(z);
	int A = P(X) + Y, AA = P(A) + Z, AB = P(A + 1) + Z;
	int B = P(X + 1) + Y, BA = P(B) + Z, BB = P(B + 1) + Z;
	return lerp(w,
		    lerp(v, lerp(u, grad(P(AA), x, y, z), grad(P(BA), x - 1, y, z)),
			 lerp(u, grad(P(AB), x, y - 1, z), grad(P(BB), x - 1, y - 1, z))),
		    lerp(v, lerp(u, grad(P(AA + 1), x, y, z - 1), grad(P(BA + 1), x - 1, y, z - 1)),
			 lerp(u, grad(P(AB + 1), x, y - 1, z - 1), grad(P(BB + 1), x - 1, y - 1, z - 1))));
}

double noise_turbulence(vec3 p, int terms)
{
	double sum = 0, scale = 1;
	for (int i = 0; i < terms; i++) {
		sum += fabs(noise_perlin(v3_scale(p, scale))) / scale;
		scale *= 2;
	}
	return sum;
}

double noise_fbm(vec3 p, int terms)
{
	double sum = 0, norm = 0, scale = 1;
	for (int i = 0; i < terms; i++) {
		sum += noise_perlin(v3_scale(p, scale)) / scale;
		norm += 1 / scale;
		scale *= 2;
	}
	return norm > 0 ? sum / norm : 0;
}

vec3 noise_fbm_vec(vec3 p, int terms)
{
	/* fixed, irrational-looking offsets decorrelate the three components */
	return v3(noise_fbm(p, terms), noise_fbm(v3_add(p, v3(31.416, 47.853, 12.793)), terms),
		  noise_fbm(v3_add(p, v3(-53.71, 19.173, 77.29)), terms));
}
