/*
 * shader.c - the seven shaders (bricks, tiles, chequers, bumpy, noise,
 * fades, turb3d) evaluated at a surface point. The patterns are described
 * in docs/rendering.md; the constants below are the ones it quotes.
 */
#include "common/shader.h"

#include <math.h>

#include "common/noise.h"

/* Bricks: course height and mortar width as fractions of the brick length
 * (size). A real brick with its joint is about 225 x 75 mm with 10 mm mortar. */
#define BRICK_COURSE 0.3333333333333333
#define BRICK_MORTAR 0.045
/* Bumpy: finite-difference step for the gradient, as a fraction of a feature */
#define BUMP_STEP 1e-3
/* Bumpy: width of the soft edge of the saturation mask, in radians */
#define BUMP_RAMP (0.05 * M_PI)
/* Offset decorrelating the bumpy saturation mask from the bump heights */
#define BUMP_MASK_OFFSET 71.17

/* The material's own settings, its shader ignored. */
static void base(const struct scene_material *m, vec3 n, struct shader_mat *o)
{
	o->diff_colour = m->diff_colour;
	o->spec_colour = m->spec_colour;
	o->tran_colour = m->tran_colour;
	o->diffuse = m->diffuse;
	o->specular = m->specular;
	o->spec_power = m->spec_power;
	o->reflection = m->reflection;
	o->transparency = m->transparency;
	o->ior = m->ior;
	o->n = n;
}

/* Default materials of shader arguments that are absent (docs/language.md):
 * the default material (white and matt) with `colour colour`. */
static void matt(struct shader_mat *o, vec3 colour, vec3 n)
{
	base(scene_default_material(), n, o);
	o->diff_colour = o->spec_colour = o->tran_colour = colour;
}

/* x mod m in [0, m) for m > 0, also for negative x. */
static double fmod_pos(double x, double m)
{
	double r = x - m * floor(x / m);
	return r >= m ? 0 : r < 0 ? 0 : r;
}

int shader_bricks_is_mortar(double u, double v, double size)
{
	double course = size * BRICK_COURSE, mortar = size * BRICK_MORTAR;
	double row = floor(v / course);
	double shift = fmod_pos(row, 2.0) >= 1.0 ? 0.5 * size : 0.0;
	double bu = fmod_pos(u + shift, size);
	double bv = v - row * course;
	return bu < mortar || bv < mortar;
}

int shader_tiles_is_grout(double u, double v, double size, double tile_width, double grout_width)
{
	double units = tile_width + grout_width;
	if (!(units > 0) || !(grout_width > 0))
		return 0;
	double fu = fmod_pos(u / size, 1.0) * units;
	double fv = fmod_pos(v / size, 1.0) * units;
	return fu >= tile_width || fv >= tile_width;
}

int shader_chequers_which(double u, double v, double size)
{
	double k = floor(u / size) + floor(v / size);
	return fmod_pos(k, 2.0) >= 1.0;
}

/*
 * Where p lies in a fades list: entry *i and the fraction *f of the way
 * from entry i to entry i+1 (*f = 0 and *i = 0 when the list is constant).
 */
static void fades_locate(const struct scene_shader *sh, vec3 p, uint32_t *i, double *f)
{
	*i = 0;
	*f = 0;
	if (sh->n_fades < 2)
		return;
	double total = 0;
	for (uint32_t k = 0; k + 1 < sh->n_fades; k++)
		total += sh->fades[k].dist;
	if (!(total > 0) || !isfinite(total))
		return;
	double t = fmod_pos(v3_dot(p, v3_norm(sh->axis)), total);
	for (uint32_t k = 0; k + 1 < sh->n_fades; k++) {
		double d = sh->fades[k].dist;
		if (t < d) {
			*i = k;
			*f = t / d;
			return;
		}
		t -= d;
	}
	*i = sh->n_fades - 2; /* rounding at the very end of the period */
	*f = 1;
}

vec3 shader_fades_colour(const struct scene_shader *sh, vec3 p)
{
	if (sh->n_fades == 0)
		return v3(1, 1, 1);
	uint32_t i;
	double f;
	fades_locate(sh, p, &i, &f);
	if (f == 0)
		return sh->fades[i].colour;
	return v3_lerp(sh->fades[i].colour, sh->fades[i + 1].colour, f);
}

static void mat_lerp(struct shader_mat *o, const struct shader_mat *a, const struct shader_mat *b, double f)
{
	o->diff_colour = v3_lerp(a->diff_colour, b->diff_colour, f);
	o->spec_colour = v3_lerp(a->spec_colour, b->spec_colour, f);
	o->tran_colour = v3_lerp(a->tran_colour, b->tran_colour, f);
	o->diffuse = a->diffuse + (b->diffuse - a->diffuse) * f;
	o->specular = a->specular + (b->specular - a->specular) * f;
	o->spec_power = a->spec_power + (b->spec_power - a->spec_power) * f;
	o->reflection = a->reflection + (b->reflection - a->reflection) * f;
	o->transparency = a->transparency + (b->transparency - a->transparency) * f;
	o->ior = a->ior + (b->ior - a->ior) * f;
	vec3 n = v3_norm(v3_lerp(a->n, b->n, f));
	o->n = v3_len(n) > 0 ? n : a->n;
}

static void eval(const struct scene *s, uint32_t id, const struct shader_point *pt, int depth, struct shader_mat *o);

/* Evaluates a shader argument: the material, or the given default when absent. */
static void eval_arg(const struct scene *s, uint32_t id, vec3 def, const struct shader_point *pt, int depth,
		     struct shader_mat *o)
{
	if (id == SCENE_NONE || id >= s->n_materials)
		matt(o, def, pt->n);
	else
		eval(s, id, pt, depth + 1, o);
}

/* Evaluates the "material" argument of bumpy/noise/turb3d: absent = the owner without its shader. */
static void eval_own(const struct scene *s, const struct scene_material *m, const struct shader_point *pt,
		     int depth, struct shader_mat *o)
{
	if (m->shader.mat_a == SCENE_NONE || m->shader.mat_a >= s->n_materials)
		base(m, pt->n, o);
	else
		eval(s, m->shader.mat_a, pt, depth + 1, o);
}

/* Bump height field: depth x fBm over the scaled point. */
static double bump_height(const struct scene_shader *sh, vec3 p)
{
	vec3 q = v3(p.x / (sh->size * sh->axis_size.x), p.y / (sh->size * sh->axis_size.y),
		    p.z / (sh->size * sh->axis_size.z));
	return noise_fbm(q, sh->terms);
}

/*
 * Bumpy: the normal tilts against the gradient of a height field
 * h(p) = depth * w(p) * fbm(q), q = p / (size * (xsize, ysize, zsize)),
 * w = the saturation mask (1 where bumped). See docs/rendering.md.
 */
static vec3 bump_normal(const struct scene_shader *sh, vec3 p, vec3 n)
{
	if (sh->terms <= 0 || sh->depth == 0 || sh->saturation <= 0)
		return n;
	double w = 1;
	if (sh->saturation < M_PI) {
		vec3 q = v3(p.x / (sh->size * sh->axis_size.x), p.y / (sh->size * sh->axis_size.y),
			    p.z / (sh->size * sh->axis_size.z));
		double s = fabs(noise_perlin(v3_add(q, v3(BUMP_MASK_OFFSET, 0, 0))));
		double phase = M_PI * fmin(1.0, s / NOISE_BOUND);
		w = (sh->saturation - phase) / BUMP_RAMP;
		w = w < 0 ? 0 : w > 1 ? 1 : w;
		if (w == 0)
			return n;
	}
	double h = BUMP_STEP * sh->size * fmin(sh->axis_size.x, fmin(sh->axis_size.y, sh->axis_size.z));
	double h0 = bump_height(sh, p);
	vec3 g = v3((bump_height(sh, v3(p.x + h, p.y, p.z)) - h0) / h,
		    (bump_height(sh, v3(p.x, p.y + h, p.z)) - h0) / h,
		    (bump_height(sh, v3(p.x, p.y, p.z + h)) - h0) / h);
	g = v3_scale(g, sh->depth * w);
	vec3 gt = v3_sub(g, v3_scale(n, v3_dot(g, n))); /* tangential part */
	vec3 nn = v3_norm(v3_sub(n, gt));
	return v3_finite(nn) && v3_len(nn) > 0 ? nn : n;
}

static void eval(const struct scene *s, uint32_t id, const struct shader_point *pt, int depth, struct shader_mat *o)
{
	if (id == SCENE_NONE || id >= s->n_materials) {
		base(scene_default_material(), pt->n, o);
		return;
	}
	const struct scene_material *m = &s->materials[id];
	const struct scene_shader *sh = &m->shader;
	if (sh->kind == SHADER_NONE || depth >= LIM_SHADER_DEPTH) {
		base(m, pt->n, o);
		return;
	}
	switch (sh->kind) {
	case SHADER_BRICKS:
		if (shader_bricks_is_mortar(pt->u, pt->v, sh->size))
			eval_arg(s, sh->mat_a, v3(0.85, 0.85, 0.8), pt, depth, o);
		else
			eval_arg(s, sh->mat_b, v3(0.6, 0.25, 0.15), pt, depth, o);
		return;
	case SHADER_TILES:
		if (shader_tiles_is_grout(pt->u, pt->v, sh->size, sh->tile_width, sh->grout_width))
			eval_arg(s, sh->mat_b, v3(0.3, 0.3, 0.3), pt, depth, o);
		else
			eval_arg(s, sh->mat_a, v3(1, 1, 1), pt, depth, o);
		return;
	case SHADER_CHEQUERS:
		if (shader_chequers_which(pt->u, pt->v, sh->size))
			eval_arg(s, sh->mat_b, v3(0, 0, 0), pt, depth, o);
		else
			eval_arg(s, sh->mat_a, v3(1, 1, 1), pt, depth, o);
		return;
	case SHADER_BUMPY:
		eval_own(s, m, pt, depth, o);
		o->n = bump_normal(sh, pt->mp, o->n);
		return;
	case SHADER_NOISE: {
		eval_own(s, m, pt, depth, o);
		double nv = noise_perlin(v3_scale(pt->mp, 1.0 / sh->size));
		vec3 f = v3_max(v3_add(sh->colour, v3(sh->variance * nv, sh->variance * nv, sh->variance * nv)),
				v3(0, 0, 0));
		o->diff_colour = v3_mul(o->diff_colour, f);
		return;
	}
	case SHADER_FADES: {
		if (!sh->fades_materials) {
			base(m, pt->n, o);
			o->diff_colour = shader_fades_colour(sh, pt->mp);
			return;
		}
		uint32_t i;
		double f;
		if (sh->n_fades == 0) {
			base(m, pt->n, o);
			return;
		}
		fades_locate(sh, pt->mp, &i, &f);
		eval_arg(s, sh->fades[i].material, v3(1, 1, 1), pt, depth, o);
		if (f > 0) {
			struct shader_mat b;
			eval_arg(s, sh->fades[i + 1].material, v3(1, 1, 1), pt, depth, &b);
			struct shader_mat a = *o;
			mat_lerp(o, &a, &b, f);
		}
		return;
	}
	case SHADER_TURB3D: {
		vec3 d = noise_fbm_vec(v3_scale(pt->mp, 1.0 / sh->size), sh->terms);
		struct shader_point q = *pt;
		q.mp = v3_add(q.mp, v3_scale(d, sh->depth));
		eval_own(s, m, &q, depth, o);
		return;
	}
	default:
		base(m, pt->n, o);
		return;
	}
}

void shader_eval(const struct scene *s, uint32_t material, const struct shader_point *pt,
		 struct shader_mat *out)
{
	eval(s, material, pt, 0, out);
}
