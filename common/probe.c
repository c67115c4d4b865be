/*
 * probe.c - the pixel probe (probe.h).
 *
 * The scene below is rendered PROBE_W x PROBE_H with filter standard and
 * PROBE_SMALL_W x PROBE_SMALL_H with each other filter (576 pixels). Every
 * primitive is in view (a RAW mesh is added from text here, as parse_buffer
 * reads no files), every shader, all four light shapes, fall-off and
 * specular powers (xm_pow_lite), rotations (xm_sin, xm_cos), mapped spheres
 * (xm_asin, xm_atan2), mirror reflection, refraction through a glass sphere
 * and tinted shadows.
 *
 * 8-bit pixels hide most differences of a last bit, so the fingerprint also
 * takes the exact bits of what the pixels are made of: camera rays, noise,
 * and the xmath functions over a spread of arguments. A build whose
 * arithmetic differs anywhere there (contraction, another libm, excess
 * precision) gets another fingerprint even when the probe's pixels agree.
 */
#include "common/probe.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/camera.h"
#include "common/noise.h"
#include "common/parse.h"
#include "common/raw.h"
#include "common/render.h"
#include "common/xmath.h"

/* %s: the filter, %d %d: the image size */
static const char probe_scene[] =
	"camera look-from (0 3 9) look-at (0 0.6 0) drop-line (0 -1 0) %s ;\n"
	"image xsize %d ysize %d ;\n"
	"light colour (0.7 0.7 0.7) position (-5 8 6) fall-off 0.3 ;\n"
	"light colour (0.5 0.4 0.3) shape sphere centre (4 6 5) radius 0.8 ; samples 2 ;\n"
	"light colour (0.3 0.4 0.5) shape cylinder from (-3 5 -1) to (3 5 -1) radius 0.3 ; samples 2 fall-off 0.5 ;\n"
	"light colour (0.3 0.3 0.3) shape box a (-1 7 2) b (1 7.5 3) ; samples 2 ;\n"
	"define\n"
	" material named red colour (0.9 0.2 0.15) specular-reflection 0.5 specular-power 30 ;\n"
	" object name pair\n"
	"  object sphere radius 0.3 ; ;\n"
	"  object box a (0.4 -0.3 -0.3) b (1 0.3 0.3) ; z-rotate 25 ;\n"
	" ;\n"
	";\n"
	"object plane position (0 -1 0) normal (0 1 0) ;\n"
	" material chequers size 1 material-a material colour (0.9 0.9 0.9) ;\n"
	"  material-b material colour (0.3 0.3 0.35) reflection 0.3 ; ; ;\n"
	";\n"
	"object box a (-5 -1 -3.5) b (5 3.5 -3) ; material bricks size 0.6 ; ; ;\n"
	"object sphere centre (-2.3 0 0) radius 0.8 pole (0 1 0.3) ; x-rotate 15\n"
	" material colour (0.4 0.7 0.3) specular-reflection 0.6 specular-power 40\n"
	"  bumpy size 0.3 terms 3 depth 0.3 ; ;\n"
	";\n"
	"object sphere centre (0 -0.2 1.2) radius 0.7 ;\n"
	" material colour (1 1 1) diffuse-reflection 0 specular-reflection 0.8 specular-power 200\n"
	"  reflection 0.1 transparency 0.9 refractive-index 1.5 tran-colour (0.8 1 0.9) ;\n"
	";\n"
	"object cylinder from (2.3 -1 0) to (2.3 0.8 0) radius 0.6 capped ; z-rotate 8\n"
	" material tiles size 0.25 ; ;\n"
	";\n"
	"object disk position (-3 1.8 -2.9) normal (0.2 0 1) radius 0.7 ;\n"
	" material noise size 0.2 colour (0.2 0.6 0.9) variance 0.6 ; ; ;\n"
	"object triangle a (1.2 1.4 -2.9) b (3.4 1.4 -2.9) c (2.3 3.2 -2.9)\n"
	"  normal-a (-0.3 0 1) normal-b (0.3 0 1) normal-c (0 0.3 1) ;\n"
	" material turb3d size 0.5 terms 3 depth 0.6 material material colour (0.9 0.6 0.2) ; ; ;\n"
	";\n"
	"object polygon contour (-1.6 1.2 -2.9) (0.4 1.2 -2.9) (0.4 3 -2.9) (-1.6 3 -2.9) ;\n"
	"  contour (-1 1.7 -2.9) (-0.2 1.7 -2.9) (-0.6 2.5 -2.9) ; ;\n"
	" material fades axis (1 1 0) colours 0.4 (1 0.9 0.1) 0.4 (0.8 0.1 0.1) 0 (1 0.9 0.1) ; ;\n"
	";\n"
	"object csg operand1 object sphere radius 0.75 ; ;\n"
	"  operand2 object box a (-0.5 -0.5 -1) b (0.5 0.5 1) ; y-rotate 30 ; subtract ;\n"
	" translate (0 0.9 -1.2) material colour (0.8 0.8 0.9) reflection 0.6 ;\n"
	";\n"
	"object pair ; stretch-x 1.3 shrink-y 1.2 y-rotate -30 translate (-1.2 -0.6 2.2) material called red ; ;\n"
	"object pair ; x-rotate 40 translate (0.9 -0.5 2.6) ;\n";

/* a tetrahedron, smoothed (angle-weighted normals: xm_atan2) */
static const char probe_raw[] = "0 0 0 1 0 0 0 1 0\n0 0 0 0 1 0 0 0 1\n0 0 0 0 0 1 1 0 0\n1 0 0 0 1 0 0 0 1\n";

static const char *const probe_filters[] = {
	"filter standard ;",
	"filter adaptive threshold 0.05 max-depth 2 ;",
	"filter super-sample x-samples 2 y-samples 2 ;",
	"filter disk radius 0.6 samples 3 ;",
	"filter lens radius 0.2 samples 3 focal-length 9 ;",
};
#define N_PROBE_FILTERS (sizeof probe_filters / sizeof probe_filters[0])

/* FNV-1a, 64 bits */
#define FNV_OFFSET 0xcbf29ce484222325ull
static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
	const unsigned char *b = p;
	for (size_t i = 0; i < n; i++) {
		h ^= b[i];
		h *= 0x100000001b3ull;
	}
	return h;
}

static uint64_t fnv_d(uint64_t h, double d)
{
	return fnv(h, &d, sizeof d);
}

/* the RAW mesh as a root object; 0 or an error level */
static int add_raw(struct scene *s, struct scene_error *err)
{
	struct scene_mesh m;
	memset(&m, 0, sizeof m);
	m.weld = 0.00001;
	m.smooth = true;
	m.rotation = v3(30, 0, 10);
	m.at = v3(-3.4, -1, 2);
	m.file = strdup("<probe>");
	if (!m.file)
		return ERRLEVEL_FATAL;
	if (raw_parse(probe_raw, sizeof probe_raw - 1, &m, err)) {
		free(m.file);
		return err->level ? err->level : ERRLEVEL_FATAL;
	}
	uint32_t mesh, obj;
	if (scene_add_mesh(s, &m, &mesh, err))
		return err->level;
	struct scene_object o;
	scene_object_defaults(&o, PRIM_RAW);
	o.u.raw.mesh = mesh;
	if (scene_add_object(s, &o, &obj, err) || scene_add_root(s, obj, err))
		return err->level;
	return 0;
}

/* one probe image hashed into *h: 0, or -1 */
static int render_one(const char *filter, int w, int hgt, uint64_t *h)
{
	char text[sizeof probe_scene + 128];
	int n = snprintf(text, sizeof text, probe_scene, filter, w, hgt);
	if (n < 0 || (size_t)n >= sizeof text)
		return -1;
	struct scene *s = NULL;
	struct renderer *r = NULL;
	struct scene_error err;
	memset(&err, 0, sizeof err);
	uint8_t *rgb = malloc((size_t)w * hgt * 3);
	int rc = -1;
	if (!rgb || parse_buffer("<probe>", text, (size_t)n, 0, &s, &err) || add_raw(s, &err) ||
	    renderer_new(s, &r, &err))
		goto done;
	renderer_tile(r, (struct tile_rect){ 0, 0, (uint32_t)w, (uint32_t)hgt }, rgb);
	*h = fnv(*h, rgb, (size_t)w * hgt * 3);
	/* the camera's rays over the image, exactly */
	struct cam c;
	if (cam_init(&c, &s->camera, (uint32_t)w, (uint32_t)hgt) == 0)
		for (int y = 0; y < hgt; y += 3)
			for (int x = 0; x < w; x += 3) {
				struct ray ray = cam_ray(&c, x + 0.5, y + 0.5);
				*h = fnv(*h, &ray.o, sizeof ray.o);
				*h = fnv(*h, &ray.d, sizeof ray.d);
			}
	rc = 0;
done:
	renderer_free(r);
	scene_free(s);
	free(rgb);
	return rc;
}

/* the building blocks' doubles: noise and the xmath functions */
static uint64_t hash_blocks(uint64_t h)
{
	for (int i = 0; i < 64; i++) {
		double t = (i - 31.5) * 0.377;
		vec3 p = v3(t, 0.61 * t + 0.3, 1.7 - 0.29 * t);
		h = fnv_d(h, noise_perlin(p));
		h = fnv_d(h, noise_turbulence(p, 4));
		vec3 f = noise_fbm_vec(p, 3);
		h = fnv(h, &f, sizeof f);
		double s, c;
		xm_sincos(t * 3.1, &s, &c);
		h = fnv_d(h, s);
		h = fnv_d(h, c);
		h = fnv_d(h, xm_sin(t * 1e5));
		h = fnv_d(h, xm_tan(t));
		h = fnv_d(h, xm_atan2(t, 0.7 - t));
		h = fnv_d(h, xm_atan(t * t * t));
		h = fnv_d(h, xm_asin(t / 12.5));
		h = fnv_d(h, xm_acos(t / 12.5));
		h = fnv_d(h, xm_exp(t * 20));
		h = fnv_d(h, xm_log(t * t + 1e-3));
		h = fnv_d(h, xm_pow(t * t, t));
		h = fnv_d(h, xm_pow_lite(t * t * 0.08, 1 + t * 7));
	}
	return h;
}

uint64_t probe_compute(void)
{
	uint64_t h = FNV_OFFSET;
	for (size_t i = 0; i < N_PROBE_FILTERS; i++) {
		int big = i == 0;
		if (render_one(probe_filters[i], big ? PROBE_W : PROBE_SMALL_W, big ? PROBE_H : PROBE_SMALL_H, &h))
			return 0;
	}
	h = hash_blocks(h);
	return h ? h : 1; /* 0 means "failed" */
}

static pthread_once_t probe_once = PTHREAD_ONCE_INIT;
static uint64_t probe_value;

static void probe_init(void)
{
	probe_value = probe_compute();
}

uint64_t probe_hash(void)
{
	pthread_once(&probe_once, probe_init);
	return probe_value;
}
