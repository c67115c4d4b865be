/*
 * test_shade_block.c - BLOCK SHADING against the single-ray path, with the
 * real geometry (common/shade.c is included, so its static functions are
 * reachable; the accel is the real one, from the library).
 *
 * In a scene with transparent materials shade_eye_hit4 shades a 2x2
 * block's hits together and, where they lie on one flat patch, traces
 * their mirror and refracted rays as packets and shades those rays' hits
 * as blocks again, down to LIM_TRACE_DEPTH; shade_trace follows one ray at
 * a time (trace, surf_shade). Every colour must be the same bits, for
 * blocks of neighbouring eye rays (packets at each bounce off the flat
 * mirrors and through the flat glass), for blocks of scattered rays
 * (several octants: one ray at a time), and for blocks of one to three
 * rays. The scenes hold what changes a colour's arithmetic: facing flat
 * mirrors (bounces down to the depth limit), perturbed normals (bumpy),
 * area lights (random samples per ray), lights without shadows, glass
 * (refraction, total internal reflection, tinted shadows) and triangles.
 * The opaque scene (no transparent material: one hit at a time) is
 * checked as well.
 */
#include "common/shade.c"

#include <string.h>

#include "common/parse.h"
#include "tests/unit/check.h"

/* Mirrors: two facing mirror walls, mirror spheres, a bumpy mirror, a
 * reflective triangle pair, a point light without shadows, a sphere light. */
static const char scene_mirrors[] =
	"light colour (1 1 1) position (-4 6 5) ;\n"
	"light colour (0.5 0.4 0.3) position (3 4 -1) no-shadows ;\n"
	"light colour (0.6 0.6 0.6) shape sphere centre (2 5 4) radius 0.8 ; samples 3 ;\n"
	"object plane position (0 -1 0) normal (0 1 0) ;\n"
	"    material chequers size 1\n"
	"        material-a material colour (0.9 0.9 0.9) reflection 0.3 ;\n"
	"        material-b material colour (0.35 0.35 0.4) ;\n"
	"    ; ;\n"
	";\n"
	"object plane position (-4 0 0) normal (1 0 0) ;\n"
	"    material colour (0.8 0.9 1) diffuse-reflection 0.05 reflection 0.95 ;\n"
	";\n"
	"object plane position (4 0 0) normal (-1 0 0) ;\n"
	"    material colour (1 0.9 0.8) diffuse-reflection 0.05 reflection 0.95 ;\n"
	";\n"
	"object sphere centre (0 0 0) radius 1 ;\n"
	"    material colour (0.9 0.9 0.9) diffuse-reflection 0.1 specular-reflection 0.6 specular-power 60"
	" reflection 0.8 ;\n"
	";\n"
	"object sphere centre (-2 0.5 -1) radius 0.7 ;\n"
	"    material colour (0.8 0.8 1) specular-reflection 0.6 specular-power 40 reflection 0.6"
	" bumpy size 0.3 depth 0.05 terms 3 ; ;\n"
	";\n"
	"object sphere centre (2 0.3 -0.5) radius 0.6 ;\n"
	"    material colour (1 0.5 0.4) reflection 0.5 ;\n"
	";\n"
	"object triangle a (-1 -1 -2) b (1 -1 -2) c (0 1.5 -2.5) ;\n"
	"    material colour (0.3 1 0.3) reflection 0.7 ;\n"
	";\n"
	"object triangle a (1 -1 -2) b (2 1.5 -2.5) c (0 1.5 -2.5) ;\n"
	"    material colour (0.3 0.3 1) reflection 0.7 ;\n"
	";\n";

/* What turns BLOCK SHADING on in the mirror scene: transparent materials
 * (a ball, and a pane in front of the mirrors that reflects and refracts). */
static const char glass_pane[] =
	"object sphere centre (1 -0.5 1.5) radius 0.4 ;\n"
	"    material colour (1 1 1) diffuse-reflection 0 transparency 0.8 refractive-index 1.4 ;\n"
	";\n"
	"object box a (-1.5 -1 1.8) b (0.5 1 2) y-rotate 10 ;\n"
	"    material colour (0.9 1 0.9) diffuse-reflection 0.1 transparency 0.6 reflection 0.3"
	" refractive-index 1.5 ;\n"
	";\n";

/* Glass: spheres and a slab that refract (and reflect inside: total
 * internal reflection), a tinted one that colours shadows, mirrors behind. */
static const char scene_glass[] =
	"light colour (1 1 1) position (-4 6 5) ;\n"
	"light colour (0.6 0.6 0.6) shape sphere centre (2 5 4) radius 0.8 ; samples 2 ;\n"
	"object plane position (0 -1 0) normal (0 1 0) ;\n"
	"    material chequers size 1\n"
	"        material-a material colour (0.9 0.9 0.9) ;\n"
	"        material-b material colour (0.35 0.35 0.4) reflection 0.4 ;\n"
	"    ; ;\n"
	";\n"
	"object plane position (0 0 -3) normal (0 0 1) ;\n"
	"    material colour (0.9 0.8 0.2) reflection 0.5 ;\n"
	";\n"
	"object sphere centre (0 0 0) radius 1 ;\n"
	"    material colour (1 1 1) diffuse-reflection 0 specular-reflection 0.8 specular-power 200"
	" reflection 0.1 transparency 0.9 refractive-index 1.5 ;\n"
	";\n"
	"object sphere centre (-2 0.2 0.5) radius 0.6 ;\n"
	"    material colour (1 0.6 0.6) transparency 0.7 refractive-index 1.3 reflection 0.3 ;\n"
	";\n"
	"object box a (1 -0.5 -0.2) b (3 1.5 0.2) x-rotate 35 y-rotate 20 ;\n"
	"    material colour (0.8 1 0.9) diffuse-reflection 0 transparency 1 reflection 0.05"
	" refractive-index 1.6 ;\n"
	";\n"
	"object triangle a (-3 -1 -1) b (-1 -1 -2) c (-2 1.5 -1.5) ;\n"
	"    material colour (0.6 0.6 1) transparency 0.5 reflection 0.3 refractive-index 1.2 ;\n"
	";\n";

static uint64_t rs = 0x2545f4914f6cdd1dull;

/* Uniform in [0, 1) (xorshift). */
static double rnd(void)
{
	rs ^= rs << 13;
	rs ^= rs >> 7;
	rs ^= rs << 17;
	return (double)(rs >> 11) * 0x1p-53;
}

static bool same_colour(vec3 a, vec3 b) { return memcmp(&a, &b, sizeof a) == 0; }

/* One block: eye rays e[0..n) with seeds seed[], through shade_eye_rays4,
 * accel_intersect4 and shade_eye_hit4 as the renderer calls them, against
 * shade_trace of each ray. Returns how many colours differ; *lit counts
 * the colours that are not black. */
static int block_differs(const struct shade_ctx *c, const struct accel *a, const struct ray e[4], int n,
			 const uint64_t seed[4], int *lit)
{
	struct ray u[4];
	bool ok[4], hit[4];
	struct hit h[4];
	shade_eye_rays4(e, n, u, ok);
	accel_intersect4(a, u, h, hit);
	const struct hit *hp[4] = { NULL, NULL, NULL, NULL };
	for (int k = 0; k < n; k++)
		hp[k] = ok[k] && hit[k] ? &h[k] : NULL;
	vec3 out[4];
	shade_eye_hit4(c, u, hp, seed, n, out);
	int bad = 0;
	for (int k = 0; k < n; k++) {
		vec3 want = shade_trace(c, &e[k], seed[k]);
		if (!same_colour(out[k], want)) {
			if (bad == 0)
				fprintf(stderr, "block colour (%.17g %.17g %.17g), single ray (%.17g %.17g %.17g)\n",
					out[k].x, out[k].y, out[k].z, want.x, want.y, want.z);
			bad++;
		}
		*lit += want.x > 0 || want.y > 0 || want.z > 0;
	}
	return bad;
}

/* The scene of text, blocks of eye rays from eye through a grid of 2x2
 * pixel blocks (neighbours), and blocks of scattered rays. */
static void check_scene(const char *name, const char *text, const char *extra, bool no_reflections)
{
	struct scene *s = NULL;
	struct scene_error err;
	char buf[8192];
	int len = snprintf(buf, sizeof buf, "%s%s", text, extra);
	CHECK(len > 0 && len < (int)sizeof buf);
	CHECK(parse_buffer(name, buf, strlen(buf), 0, &s, &err) == 0);
	if (!s)
		return;
	s->image.no_reflections = no_reflections;
	struct accel *a = NULL;
	struct shade_ctx *c = NULL;
	CHECK(accel_build(s, &a, &err) == 0);
	CHECK(a && shade_ctx_new(s, a, &c, &err) == 0);
	if (!a || !c)
		goto done;
	CHECK(c->any_transparent == (strstr(buf, "transparency") != NULL)); /* BLOCK SHADING on or off */
	vec3 eye = v3(0.3, 1.5, 6);
	enum { W = 96, H = 72 };
	int bad = 0, lit = 0, total = 0;
	for (int y = 0; y < H; y += 2) {
		for (int x = 0; x < W; x += 2) {
			struct ray e[4];
			uint64_t seed[4];
			for (int k = 0; k < 4; k++) {
				int px = x + (k & 1), py = y + (k >> 1);
				vec3 d = v3((px - W / 2) * 0.1, (H / 2 - py) * 0.1 - 1.2, -6.5);
				e[k] = (struct ray){ eye, d, 0, INFINITY };
				seed[k] = rng_seed((uint32_t)px, (uint32_t)py, 0);
			}
			int n = 4 - (x / 2 + y / 2) % 4 % 3; /* mostly 4, some blocks of 3 and 2 */
			bad += block_differs(c, a, e, n, seed, &lit);
			total += n;
		}
	}
	for (int i = 0; i < 3000; i++) { /* scattered rays: several octants, from anywhere */
		struct ray e[4];
		uint64_t seed[4];
		for (int k = 0; k < 4; k++) {
			vec3 o = v3(rnd() * 6 - 3, rnd() * 3 - 0.5, rnd() * 4 + 1);
			vec3 d = v3(rnd() * 2 - 1, rnd() * 2 - 1, rnd() * 2 - 1.5);
			e[k] = (struct ray){ o, d, 0, INFINITY };
			seed[k] = rs;
		}
		int n = 1 + i % 4;
		bad += block_differs(c, a, e, n, seed, &lit);
		total += n;
	}
	CHECK(bad == 0);
	CHECK(lit > total / 2); /* the scene is seen */
	if (bad)
		fprintf(stderr, "%s: %d of %d colours differ\n", name, bad, total);
done:
	shade_ctx_free(c);
	accel_free(a);
	scene_free(s);
}

int main(void)
{
	check_scene("mirrors", scene_mirrors, glass_pane, false);
	check_scene("mirrors-noreflect", scene_mirrors, glass_pane, true);
	check_scene("mirrors-opaque", scene_mirrors, "", false);
	check_scene("glass", scene_glass, "", false);
	check_scene("glass-noreflect", scene_glass, "", true);
	TEST_MAIN_END();
}
