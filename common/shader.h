/*
 * shader.h - the seven shaders: a material evaluated at one surface point
 * gives the effective material there (colours, coefficients) and possibly a
 * perturbed shading normal. docs/rendering.md states each pattern.
 *
 *   type II (surface mapping hit.u, hit.v): bricks, tiles, chequers
 *   type I  (object-space point hit.mp):    bumpy, noise, fades, turb3d
 *
 * Material arguments of a shader are materials of their own and may carry
 * shaders; nesting is bounded by LIM_SHADER_DEPTH (deeper levels are
 * evaluated without their shader).
 */
#ifndef PORTRAY_SHADER_H
#define PORTRAY_SHADER_H

#include <stdint.h>

#include "common/scene.h"

/* The material as seen at one point, every shader applied. */
struct shader_mat {
	vec3 diff_colour, spec_colour, tran_colour;
	double diffuse, specular, spec_power, reflection, transparency, ior;
	vec3 n; /* unit shading normal (the input normal, perturbed by bumpy) */
};

/* Where a material is evaluated. */
struct shader_point {
	vec3 mp;     /* point in the material owner's object space (type I) */
	double u, v; /* surface mapping in object-space length units (type II) */
	vec3 n;      /* unit world shading normal, already facing the viewer */
};

/*
 * Evaluates material `material` (an index into s->materials; SCENE_NONE or
 * an out-of-range index means the default material) at pt and fills *out.
 * Pure function of its arguments; thread-safe.
 */
void shader_eval(const struct scene *s, uint32_t material, const struct shader_point *pt,
		 struct shader_mat *out);

/* The pattern functions, exposed for tests. Each returns 0 or 1 (which material). */
/* bricks: 1 = mortar (mat_a), 0 = brick (mat_b) */
int shader_bricks_is_mortar(double u, double v, double size);
/* tiles: 1 = grout (mat_b), 0 = face (mat_a) */
int shader_tiles_is_grout(double u, double v, double size, double tile_width, double grout_width);
/* chequers: 0 = material-a, 1 = material-b */
int shader_chequers_which(double u, double v, double size);
/* fades: the colour of a colours list at point p (see docs/rendering.md) */
vec3 shader_fades_colour(const struct scene_shader *sh, vec3 p);

#endif
