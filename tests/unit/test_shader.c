/*
 * test_shader.c - the seven shaders: pattern functions at known points, and
 * shader_eval on materials built with the scene builder (defaults, nesting,
 * the nesting bound, normals from bumpy).
 */
#include <stdlib.h>
#include <string.h>

#include "common/noise.h"
#include "common/shader.h"
#include "tests/unit/check.h"

static int near3(vec3 a, vec3 b, double eps)
{
	return fabs(a.x - b.x) <= eps && fabs(a.y - b.y) <= eps && fabs(a.z - b.z) <= eps;
}

static uint32_t add(struct scene *s, struct scene_material *m)
{
	uint32_t id = SCENE_NONE;
	struct scene_error err;
	int rc = scene_add_material(s, m, &id, &err);
	CHECK(rc == 0);
	if (rc)
		fprintf(stderr, "%s\n", err.msg);
	return id;
}

static uint32_t colour_mat(struct scene *s, vec3 c)
{
	struct scene_material m;
	scene_material_defaults(&m);
	m.diff_colour = m.spec_colour = m.tran_colour = c;
	return add(s, &m);
}

static struct shader_mat eval_at(const struct scene *s, uint32_t id, vec3 mp, double u, double v)
{
	struct shader_point pt = { mp, u, v, v3(0, 0, 1) };
	struct shader_mat m;
	shader_eval(s, id, &pt, &m);
	return m;
}

static void test_patterns(void)
{
	/* chequers */
	CHECK(shader_chequers_which(0.5, 0.5, 1) == 0);
	CHECK(shader_chequers_which(1.5, 0.5, 1) == 1);
	CHECK(shader_chequers_which(-0.5, 0.5, 1) == 1);
	CHECK(shader_chequers_which(-0.5, -0.5, 1) == 0);
	CHECK(shader_chequers_which(2.5, 0.5, 2) == 1);
	CHECK(shader_chequers_which(3.9, 0.1, 2) == 1);
	CHECK(shader_chequers_which(4.1, 0.1, 2) == 0);

	/* tiles: size 9 with 8 + 1 units: grout in the last unit of each period */
	CHECK(shader_tiles_is_grout(7.9, 4, 9, 8, 1) == 0);
	CHECK(shader_tiles_is_grout(8.5, 4, 9, 8, 1) == 1);
	CHECK(shader_tiles_is_grout(4, 8.5, 9, 8, 1) == 1);
	CHECK(shader_tiles_is_grout(-0.5, 4, 9, 8, 1) == 1);
	CHECK(shader_tiles_is_grout(9.5, 4, 9, 8, 1) == 0);
	CHECK(shader_tiles_is_grout(8.5, 8.5, 9, 8, 0) == 0); /* no grout */
	/* grout area fraction: 1 - (8/9)^2 */
	int g = 0, n = 0;
	for (int i = 0; i < 300; i++)
		for (int j = 0; j < 300; j++, n++)
			g += shader_tiles_is_grout((i + 0.5) * 0.03, (j + 0.5) * 0.03, 1, 8, 1);
	CHECK_NEAR((double)g / n, 1 - 64.0 / 81.0, 0.01);

	/* bricks: size 1, courses 1/3 high, mortar 0.045, odd courses shifted by 1/2 */
	CHECK(shader_bricks_is_mortar(0.5, 0.2, 1) == 0);
	CHECK(shader_bricks_is_mortar(0.02, 0.2, 1) == 1);
	CHECK(shader_bricks_is_mortar(0.02, 0.5, 1) == 0);
	CHECK(shader_bricks_is_mortar(0.52, 0.5, 1) == 1);
	CHECK(shader_bricks_is_mortar(0.5, 0.34, 1) == 1);
	CHECK(shader_bricks_is_mortar(0.2, 2.2, 10) == 1);  /* scales with size */
	CHECK(shader_bricks_is_mortar(5.5, 2.5, 10) == 0);
	CHECK(shader_bricks_is_mortar(-0.98, 0.2, 1) == 1); /* negative u: periodic */
	g = n = 0;
	for (int i = 0; i < 300; i++)
		for (int j = 0; j < 300; j++, n++)
			g += shader_bricks_is_mortar((i + 0.5) / 100.0, (j + 0.5) / 100.0, 1);
	CHECK_NEAR((double)g / n, 1 - (1 - 0.045) * (1 - 0.135), 0.01);

	/* fades: the manual's example: 0.1 (0 0 0), 2.0 (0 0 1), 0.0 (0 0 0) along (1 1 1) */
	struct scene_shader sh;
	scene_shader_defaults(&sh, SHADER_FADES);
	struct fades_entry e[3] = { { 0.1, { 0, 0, 0 }, SCENE_NONE },
				    { 2.0, { 0, 0, 1 }, SCENE_NONE },
				    { 0.0, { 0, 0, 0 }, SCENE_NONE } };
	sh.fades = e;
	sh.n_fades = 3;
	sh.axis = v3(1, 1, 1);
	vec3 a = v3_norm(sh.axis);
	CHECK(near3(shader_fades_colour(&sh, v3_scale(a, 0.05)), v3(0, 0, 0.5), 1e-12));
	CHECK(near3(shader_fades_colour(&sh, v3_scale(a, 0.1)), v3(0, 0, 1), 1e-12));
	CHECK(near3(shader_fades_colour(&sh, v3_scale(a, 1.1)), v3(0, 0, 0.5), 1e-12));
	CHECK(near3(shader_fades_colour(&sh, v3_scale(a, 2.1 + 0.05)), v3(0, 0, 0.5), 1e-9));
	CHECK(near3(shader_fades_colour(&sh, v3_scale(a, -2.05)), v3(0, 0, 0.5), 1e-9));
	/* perpendicular to the axis nothing changes */
	CHECK(near3(shader_fades_colour(&sh, v3_add(v3_scale(a, 0.05), v3(1, -1, 0))), v3(0, 0, 0.5), 1e-9));
	sh.n_fades = 1; /* one entry: constant */
	CHECK(near3(shader_fades_colour(&sh, v3(5, 6, 7)), v3(0, 0, 0), 0));
}

static void test_eval(void)
{
	struct scene *s = scene_new();
	/* default material: white, matt */
	struct shader_mat d = eval_at(s, SCENE_NONE, v3(0, 0, 0), 0, 0);
	CHECK(near3(d.diff_colour, v3(1, 1, 1), 0) && d.diffuse == 1 && d.specular == 0 && d.ior == 1);
	CHECK(near3(d.n, v3(0, 0, 1), 0));

	uint32_t red = colour_mat(s, v3(1, 0, 0));
	uint32_t blue = colour_mat(s, v3(0, 0, 1));

	/* chequers with one argument absent: material-b = matt black */
	struct scene_material m;
	scene_material_defaults(&m);
	m.shader.kind = SHADER_CHEQUERS;
	m.shader.mat_a = red;
	m.shader.size = 2;
	uint32_t chq = add(s, &m);
	CHECK(near3(eval_at(s, chq, v3(0, 0, 0), 1, 1).diff_colour, v3(1, 0, 0), 0));
	CHECK(near3(eval_at(s, chq, v3(0, 0, 0), 3, 1).diff_colour, v3(0, 0, 0), 0));

	/* bricks defaults: brick (0.6 0.25 0.15), mortar (0.85 0.85 0.8) */
	scene_material_defaults(&m);
	m.shader.kind = SHADER_BRICKS;
	uint32_t bricks = add(s, &m);
	CHECK(near3(eval_at(s, bricks, v3(0, 0, 0), 0.5, 0.2).diff_colour, v3(0.6, 0.25, 0.15), 0));
	CHECK(near3(eval_at(s, bricks, v3(0, 0, 0), 0.01, 0.2).diff_colour, v3(0.85, 0.85, 0.8), 0));

	/* tiles defaults: face white, grout (0.3 0.3 0.3); face given as blue */
	scene_material_defaults(&m);
	m.shader.kind = SHADER_TILES;
	m.shader.mat_a = blue;
	m.shader.size = 9;
	uint32_t tiles = add(s, &m);
	CHECK(near3(eval_at(s, tiles, v3(0, 0, 0), 4, 4).diff_colour, v3(0, 0, 1), 0));
	CHECK(near3(eval_at(s, tiles, v3(0, 0, 0), 8.5, 4).diff_colour, v3(0.3, 0.3, 0.3), 0));

	/* nesting: chequers whose material-a is the bricks material */
	scene_material_defaults(&m);
	m.shader.kind = SHADER_CHEQUERS;
	m.shader.mat_a = bricks;
	m.shader.mat_b = tiles;
	m.shader.size = 100;
	uint32_t nest = add(s, &m);
	CHECK(near3(eval_at(s, nest, v3(0, 0, 0), 0.5, 0.2).diff_colour, v3(0.6, 0.25, 0.15), 0));
	CHECK(near3(eval_at(s, nest, v3(0, 0, 0), 104, 8.5).diff_colour, v3(0.3, 0.3, 0.3), 0));

	/* noise: diff = material x max(0, colour + variance * noise) */
	scene_material_defaults(&m);
	m.diff_colour = v3(1, 0.5, 1);
	m.specular = 0.25;
	m.shader.kind = SHADER_NOISE;
	m.shader.colour = v3(0.5, 0.5, 0.5);
	m.shader.variance = 0.4;
	m.shader.size = 0.5;
	uint32_t noisy = add(s, &m);
	vec3 p = v3(0.3, 1.7, -2.2);
	double nv = noise_perlin(v3_scale(p, 2));
	struct shader_mat r = eval_at(s, noisy, p, 0, 0);
	CHECK(near3(r.diff_colour, v3(0.5 + 0.4 * nv, 0.5 * (0.5 + 0.4 * nv), 0.5 + 0.4 * nv), 1e-12));
	CHECK(r.specular == 0.25); /* the rest is the material's own */
	CHECK(fabs(nv) > 0.01);   /* the point is not degenerate */
	/* at a lattice point of p/size the noise is 0: the base colour */
	CHECK(near3(eval_at(s, noisy, v3(1, 1.5, -2), 0, 0).diff_colour, v3(0.5, 0.25, 0.5), 1e-12));

	/* fades with a materials list: every coefficient interpolated */
	struct scene_material a, b;
	scene_material_defaults(&a);
	a.diff_colour = v3(1, 0, 0);
	a.reflection = 0;
	scene_material_defaults(&b);
	b.diff_colour = v3(0, 0, 1);
	b.reflection = 1;
	uint32_t ma = add(s, &a), mb = add(s, &b);
	scene_material_defaults(&m);
	m.shader.kind = SHADER_FADES;
	m.shader.axis = v3(0, 2, 0);
	m.shader.fades_materials = true;
	m.shader.n_fades = 3;
	m.shader.fades = calloc(3, sizeof *m.shader.fades);
	m.shader.fades[0] = (struct fades_entry){ 1.0, v3(0, 0, 0), ma };
	m.shader.fades[1] = (struct fades_entry){ 1.0, v3(0, 0, 0), mb };
	m.shader.fades[2] = (struct fades_entry){ 0.0, v3(0, 0, 0), ma };
	uint32_t fm = add(s, &m);
	r = eval_at(s, fm, v3(7, 0.25, 3), 0, 0);
	CHECK(near3(r.diff_colour, v3(0.75, 0, 0.25), 1e-12));
	CHECK_NEAR(r.reflection, 0.25, 1e-12);
	r = eval_at(s, fm, v3(0, 1.5, 0), 0, 0);
	CHECK(near3(r.diff_colour, v3(0.5, 0, 0.5), 1e-12));

	/* turb3d: depth 0 changes nothing; otherwise moves the point the fades sees */
	scene_material_defaults(&m);
	m.shader.kind = SHADER_TURB3D;
	m.shader.mat_a = fm;
	m.shader.depth = 0;
	uint32_t t0 = add(s, &m);
	scene_material_defaults(&m);
	m.shader.kind = SHADER_TURB3D;
	m.shader.mat_a = fm;
	m.shader.depth = 0.3;
	m.shader.terms = 5;
	uint32_t t1 = add(s, &m);
	int differ = 0, same0 = 1;
	for (int i = 0; i < 100; i++) {
		vec3 q = v3(i * 0.173, i * 0.0291, i * -0.07);
		vec3 c0 = eval_at(s, fm, q, 0, 0).diff_colour;
		if (!near3(eval_at(s, t0, q, 0, 0).diff_colour, c0, 0))
			same0 = 0;
		if (!near3(eval_at(s, t1, q, 0, 0).diff_colour, c0, 1e-6))
			differ++;
		/* the displacement is at most depth along the axis: colour change bounded */
		vec3 c1 = eval_at(s, t1, q, 0, 0).diff_colour;
		CHECK(fabs(c1.x - c0.x) <= 0.3 * 1.04 + 1e-9);
	}
	CHECK(same0);
	CHECK(differ > 80);

	/* bumpy: unit normals, tilted; saturation 0 or depth 0 leave the normal alone */
	scene_material_defaults(&m);
	m.shader.kind = SHADER_BUMPY;
	m.shader.mat_a = red;
	m.shader.size = 0.5;
	m.shader.depth = 0.1;
	uint32_t bump = add(s, &m);
	scene_material_defaults(&m);
	m.shader.kind = SHADER_BUMPY;
	m.shader.saturation = 0;
	uint32_t flat = add(s, &m);
	scene_material_defaults(&m);
	m.shader.kind = SHADER_BUMPY;
	m.shader.saturation = 1.0; /* part of the surface only */
	m.shader.size = 0.5;
	uint32_t part = add(s, &m);
	double tilt = 0;
	int unit = 1, facing = 1, flat_ok = 1, n_bumped = 0;
	for (int i = 0; i < 400; i++) {
		vec3 q = v3(i * 0.0173, i * 0.031, i * 0.011);
		struct shader_mat bm = eval_at(s, bump, q, 0, 0);
		if (fabs(v3_len(bm.n) - 1) > 1e-12)
			unit = 0;
		if (bm.n.z <= 0)
			facing = 0;
		tilt += 1 - bm.n.z;
		if (!near3(eval_at(s, flat, q, 0, 0).n, v3(0, 0, 1), 0))
			flat_ok = 0;
		if (!near3(eval_at(s, part, q, 0, 0).n, v3(0, 0, 1), 0))
			n_bumped++;
		CHECK(near3(bm.diff_colour, v3(1, 0, 0), 0)); /* the material underneath */
	}
	CHECK(unit && facing && flat_ok);
	CHECK(tilt / 400 > 0.005);
	CHECK(n_bumped > 20 && n_bumped < 380);

	/* the nesting bound: a chain of 20 turb3d materials over red stops at depth 16 */
	uint32_t prev = red;
	uint32_t chain[20];
	for (int i = 0; i < 20; i++) {
		scene_material_defaults(&m);
		m.shader.kind = SHADER_TURB3D;
		m.shader.mat_a = prev;
		chain[i] = prev = add(s, &m);
	}
	CHECK(near3(eval_at(s, chain[9], v3(0.5, 0.5, 0.5), 0, 0).diff_colour, v3(1, 0, 0), 0));
	CHECK(near3(eval_at(s, chain[19], v3(0.5, 0.5, 0.5), 0, 0).diff_colour, v3(1, 1, 1), 0));

	/* determinism */
	struct shader_mat r1 = eval_at(s, t1, v3(1.1, 2.2, 3.3), 0, 0);
	struct shader_mat r2 = eval_at(s, t1, v3(1.1, 2.2, 3.3), 0, 0);
	CHECK(memcmp(&r1, &r2, sizeof r1) == 0);
	scene_free(s);
}

int main(void)
{
	test_patterns();
	test_eval();
	TEST_MAIN_END();
}
