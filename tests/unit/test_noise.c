/*
 * test_noise.c - gradient noise: known values, zeros at lattice points,
 * range, continuity, determinism, and the fractal sums.
 */
#include <stdint.h>

#include "common/noise.h"
#include "common/rng.h"
#include "tests/unit/check.h"

static vec3 rand_point(uint64_t k, double span)
{
	uint64_t s = rng_derive(12345, 7);
	return v3((rng_uniform(s, 3 * k) - 0.5) * span, (rng_uniform(s, 3 * k + 1) - 0.5) * span,
		  (rng_uniform(s, 3 * k + 2) - 0.5) * span);
}

int main(void)
{
	/* Perlin's Java reference gives noise(3.14, 42, 7) = 0.13691995878400012 */
	CHECK_NEAR(noise_perlin(v3(3.14, 42, 7)), 0.13691995878400012, 1e-15);

	/* zero at every lattice point, including negative and far ones */
	for (int x = -3; x <= 3; x++)
		for (int y = -3; y <= 3; y++)
			for (int z = -3; z <= 3; z++)
				CHECK(noise_perlin(v3(x, y, z)) == 0.0);
	CHECK(noise_perlin(v3(1e6, -1e6, 123456789)) == 0.0);
	CHECK(noise_perlin(v3(NAN, 0, 0)) == 0.0);
	CHECK(noise_perlin(v3(INFINITY, 0.5, 0.5)) == 0.0);

	/* range, and the values are not trivially tiny (the noise does vary) */
	double lo = 0, hi = 0;
	int bad_range = 0;
	for (uint64_t k = 0; k < 200000; k++) {
		double n = noise_perlin(rand_point(k, 200));
		if (!(fabs(n) <= NOISE_BOUND))
			bad_range++;
		lo = fmin(lo, n);
		hi = fmax(hi, n);
	}
	CHECK(bad_range == 0);
	CHECK(lo < -0.6 && hi > 0.6);

	/* continuity: a Lipschitz bound (gradient magnitude is well below 4) */
	int jumps = 0;
	for (uint64_t k = 0; k < 50000; k++) {
		vec3 p = rand_point(k, 50);
		vec3 q = v3_add(p, v3(1e-4, -1e-4, 1e-4));
		if (fabs(noise_perlin(p) - noise_perlin(q)) > 4 * 1.8e-4)
			jumps++;
	}
	CHECK(jumps == 0);
	/* continuity across a cell boundary, from both sides */
	CHECK(fabs(noise_perlin(v3(2 - 1e-9, 0.3, 0.7)) - noise_perlin(v3(2 + 1e-9, 0.3, 0.7))) < 1e-8);

	/* determinism: the same point gives the same bits; periodic with period 256 */
	vec3 p = v3(-17.25, 3.5, 101.125);
	double a = noise_perlin(p);
	CHECK(a == noise_perlin(p));
	CHECK(fabs(a - noise_perlin(v3_add(p, v3(256, -512, 256)))) < 1e-12);

	/* turbulence: non-negative, 0 with no terms, bounded by 2*NOISE_BOUND */
	CHECK(noise_turbulence(p, 0) == 0.0);
	CHECK(noise_turbulence(p, 1) == fabs(a));
	int tbad = 0;
	for (uint64_t k = 0; k < 20000; k++) {
		double t = noise_turbulence(rand_point(k, 20), 6);
		if (!(t >= 0 && t < 2 * NOISE_BOUND))
			tbad++;
	}
	CHECK(tbad == 0);

	/* fBm: one term is plain noise; normalised sums stay in range */
	CHECK(noise_fbm(p, 1) == a);
	CHECK(noise_fbm(p, 0) == 0.0);
	int fbad = 0;
	double corr = 0;
	for (uint64_t k = 0; k < 20000; k++) {
		vec3 q = rand_point(k, 20);
		vec3 v = noise_fbm_vec(q, 5);
		if (!(fabs(v.x) <= NOISE_BOUND && fabs(v.y) <= NOISE_BOUND && fabs(v.z) <= NOISE_BOUND))
			fbad++;
		corr += v.x * v.y;
	}
	CHECK(fbad == 0);
	/* components are (nearly) uncorrelated */
	CHECK(fabs(corr / 20000) < 0.01);
	/* many octaves at large coordinates stay finite */
	CHECK(isfinite(noise_fbm(v3(1e12, 3e11, -7e10), 32)));
	TEST_MAIN_END();
}
