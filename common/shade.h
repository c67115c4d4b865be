/*
 * shade.h - what a ray sees: lights, shadows, the lighting equation,
 * reflection, refraction and the seven shaders (docs/rendering.md).
 */
#ifndef PORTRAY_SHADE_H
#define PORTRAY_SHADE_H

#include <stdbool.h>
#include <stdint.h>

#include "common/accel.h"

struct shade_ctx;

/* A ray whose contribution to the pixel would be below this is not traced:
 * 1/512 is a quarter of one 8-bit step at full brightness. */
#define SHADE_MIN_WEIGHT (1.0 / 512.0)

/* Prepares shading for a scene and its accel (both must outlive it). */
int shade_ctx_new(const struct scene *s, const struct accel *a, struct shade_ctx **out,
		  struct scene_error *err);
void shade_ctx_free(struct shade_ctx *c);
/* The SHADOW CROSSINGS filter (accel.h) shading queries accel_cross with:
 * a material's transparency x tran-colour at a hit (shaders evaluated
 * there), its table of materials opaque everywhere. For benchmarks and
 * tests that ask what shading asks; it lives as long as c. */
const struct accel_cross_filter *shade_cross_filter(const struct shade_ctx *c);

/*
 * Colour seen along an eye ray (linear RGB, not clamped). seed is the
 * (pixel, sample) stream from rng_seed(); every random choice below (area
 * light samples) derives from it, so the result is a pure function of
 * (scene, ray, seed). Thread-safe. Polls the calling thread's cancel flag
 * (cancel.h): once it is seen set, the colour is wrong (work skipped).
 */
vec3 shade_trace(const struct shade_ctx *c, const struct ray *r, uint64_t seed);

/*
 * shade_trace in two halves, for callers that find the closest hits of
 * several eye rays at once (accel_intersect4): shade_eye_ray makes the ray
 * shade_trace traces for r (unit direction, tmin and tmax scaled to match),
 * false when r cannot be traced (shade_trace's colour is then black);
 * shade_eye_hit is the colour given that ray's closest hit, h (NULL for a
 * miss) from accel_intersect or accel_intersect4 with the context's accel.
 * Together they give shade_trace's colour, bit for bit.
 */
bool shade_eye_ray(const struct ray *r, struct ray *u);
/* shade_eye_ray of n <= 4 rays e[0..n) at once into u and ok (lanes from n
 * on repeat e[n-1]), bit for bit. */
void shade_eye_rays4(const struct ray e[4], int n, struct ray u[4], bool ok[4]);
vec3 shade_eye_hit(const struct shade_ctx *c, const struct ray *u, const struct hit *h, uint64_t seed);
/*
 * shade_eye_hit of n <= 4 neighbouring eye rays (a 2x2 block): out[k] is
 * shade_eye_hit(c, &u[k], h[k], seed[k]) bit for bit; their hits' shadow
 * rays toward each point light are traced together (accel_occluded4). In
 * a scene with transparent materials, the mirror and refracted rays of
 * hits on one flat patch go as packets too (accel_intersect4), down to
 * LIM_TRACE_DEPTH (BLOCK SHADING in shade.c).
 */
void shade_eye_hit4(const struct shade_ctx *c, const struct ray u[4], const struct hit *h[4],
		    const uint64_t seed[4], int n, vec3 out[4]);

/*
 * The secondary rays (mirror and transmitted rays, at every depth) the
 * calling thread has traced since its last call: statistics for the
 * render summary and bench/povray.sh's like-for-like counts. Shadow rays
 * are not counted.
 */
uint64_t shade_take_secondary(void);

#endif
