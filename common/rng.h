/*
 * rng.h - counter-based randomness: every random number is a pure function of
 * (pixel, sample, purpose), never of a thread or of the order of work, so an
 * image is byte-identical for any thread count, tile size or set of workers.
 */
#ifndef PORTRAY_RNG_H
#define PORTRAY_RNG_H

#include <stdint.h>

/* splitmix64 finaliser: a strong 64-bit mixing function. */
static inline uint64_t rng_mix(uint64_t z)
{
	z += 0x9e3779b97f4a7c15ull;
	z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
	z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
	return z ^ (z >> 31);
}

/* rng_seed in two steps: the sample index's part, rng_seed_s(s), which a
 * caller may keep for the samples of many pixels, and rng_seed_at(x, y,
 * rng_seed_s(s)) == rng_seed(x, y, s). */
static inline uint64_t rng_seed_s(uint32_t s) { return rng_mix((uint64_t)s + 0x632be59bd9b4e019ull); }
static inline uint64_t rng_seed_at(uint32_t x, uint32_t y, uint64_t ms)
{
	return rng_mix(((uint64_t)x << 32 | y) ^ ms);
}

/* Seed for one pixel sample: pixel (x, y), sample index s. */
static inline uint64_t rng_seed(uint32_t x, uint32_t y, uint32_t s) { return rng_seed_at(x, y, rng_seed_s(s)); }

/* Derive an independent stream from a seed and a purpose tag. */
static inline uint64_t rng_derive(uint64_t seed, uint64_t tag) { return rng_mix(seed ^ rng_mix(tag)); }

/* The k-th uniform double in [0,1) of stream seed. */
static inline double rng_uniform(uint64_t seed, uint64_t k)
{
	return (double)(rng_mix(seed + k * 0xd1b54a32d192ed03ull) >> 11) * 0x1.0p-53;
}

#endif
