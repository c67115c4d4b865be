/*
 * rand_vec.h - a test's own reproducible random stream (rng_mix of a
 * counter from RAND_VEC_SEED, which the test defines before including
 * this): uniform doubles in [0, 1) and unit vectors (rejection-sampled, so
 * uniform on the sphere). `state` is the counter; a test may draw from it
 * directly (rng_mix(state++)).
 */
#ifndef PORTRAY_RAND_VEC_H
#define PORTRAY_RAND_VEC_H

#include "common/rng.h"
#include "common/vec.h"

static uint64_t state = RAND_VEC_SEED;
static inline double uniform(void) { return (double)(rng_mix(state++) >> 11) * 0x1p-53; }
static inline vec3 unit(void)
{
	for (;;) {
		vec3 v = v3(2 * uniform() - 1, 2 * uniform() - 1, 2 * uniform() - 1);
		double l = v3_len(v);
		if (l > 0.1 && l <= 1)
			return v3_scale(v, 1 / l);
	}
}

#endif
