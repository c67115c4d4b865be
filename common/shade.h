/*
 * shade.h - what a ray sees: lights, shadows, the lighting equation,
 * reflection, refraction and the seven shaders (docs/rendering.md).
 */
#ifndef PORTRAY_SHADE_H
#define PORTRAY_SHADE_H

#include <stdint.h>

#include "common/accel.h"

struct shade_ctx;

/* Prepares shading for a scene and its accel (both must outlive it). */
int shade_ctx_new(const struct scene *s, const struct accel *a, struct shade_ctx **out,
		  struct scene_error *err);
void shade_ctx_free(struct shade_ctx *c);

/*
 * Colour seen along an eye ray (linear RGB, not clamped). seed is the
 * (pixel, sample) stream from rng_seed(); every random choice below (area
 * light samples) derives from it, so the result is a pure function of
 * (scene, ray, seed). Thread-safe.
 */
vec3 shade_trace(const struct shade_ctx *c, const struct ray *r, uint64_t seed);

#endif
