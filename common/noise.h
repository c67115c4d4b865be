/*
 * noise.h - gradient noise (Ken Perlin's "improved noise", 2002, with its
 * fixed permutation table) and the fractal sums built on it. Everything is a
 * pure function of its arguments: no state, no randomness, thread-safe, and
 * the same bits on every machine with IEEE doubles.
 */
#ifndef PORTRAY_NOISE_H
#define PORTRAY_NOISE_H

#include "common/vec.h"

/* Largest |noise_perlin| can reach: every observed value is below 1.04. */
#define NOISE_BOUND 1.04

/*
 * Gradient noise at p: a smooth (C2) function with value 0 at every integer
 * lattice point, values in [-NOISE_BOUND, NOISE_BOUND], and features of size
 * about 1. Non-finite coordinates give 0.
 */
double noise_perlin(vec3 p);

/*
 * Fractal sum of `terms` octaves of |noise|: sum_{i<terms} |noise(p 2^i)| / 2^i.
 * terms <= 0 gives 0. Result in [0, 2 NOISE_BOUND).
 */
double noise_turbulence(vec3 p, int terms);

/*
 * Signed fractal sum (fBm): sum_{i<terms} noise(p 2^i) / 2^i, divided by the
 * sum of the weights so that the result stays in [-NOISE_BOUND, NOISE_BOUND].
 */
double noise_fbm(vec3 p, int terms);

/*
 * A vector field of three independent noise_fbm components (each sampled at
 * a fixed offset of p, so they are uncorrelated). Each component lies in
 * [-NOISE_BOUND, NOISE_BOUND].
 */
vec3 noise_fbm_vec(vec3 p, int terms);

#endif
