/* test_render.c - the tile renderer and its thread pool (common/render.c):
 * determinism over threads and tile sizes with every filter on, cancellation,
 * progress, sizes, ray counts, flat scenes. Scenes built with the builder. */
#include <stdlib.h>
#include <string.h>

#include "common/render.h"
#include "tests/unit/check.h"

#define W 37
#define H 23

static void add_filter(struct scene_camera *c, enum filter_kind k)
{
	scene_filter_defaults(&c->filters[c->n_filters++], k);
}

/* A few spheres over a plane, lit by a sphere light (random samples) and a
 * point light; camera filters as given. Half the spheres are red, with
 * the given reflection and transparency; when either is above 0 the plane
 * is red too (a flat mirror or pane: BLOCK SHADING's packets). */
static struct scene *make_scene_red(const struct scene_camera *cam, int with_objects, double red_reflection,
				    double red_transparency)
{
	struct scene_error err;
	struct scene *s = scene_new();
	CHECK(s != NULL);
	CHECK(scene_set_camera(s, cam, &err) == 0);
	struct scene_image im;
	scene_image_defaults(&im);
	im.xsize = W;
	im.ysize = H;
	CHECK(scene_set_image(s, &im, &err) == 0);
	if (!with_objects)
		return s;
	struct scene_light l;
	scene_light_defaults(&l);
	l.position = v3(3, 5, 4);
	l.shape = LIGHT_SPHERE;
	l.sphere.centre = v3(3, 5, 4);
	l.sphere.radius = 1;
	l.samples = 3;
	CHECK(scene_add_light(s, &l, &err) == 0);
	scene_light_defaults(&l);
	l.position = v3(-4, 3, 2);
	l.colour = v3(0.3, 0.3, 0.5);
	CHECK(scene_add_light(s, &l, &err) == 0);
	struct scene_material m;
	scene_material_defaults(&m);
	m.diff_colour = v3(0.9, 0.3, 0.2);
	m.specular = 0.5;
	m.reflection = red_reflection;
	m.transparency = red_transparency;
	uint32_t red;
	CHECK(scene_add_material(s, &m, &red, &err) == 0);
	for (int i = 0; i < 4; i++) {
		struct scene_object o;
		uint32_t id;
		scene_object_defaults(&o, PRIM_SPHERE);
		o.u.sphere.centre = v3(-2.4 + 1.6 * i, 0.2 * i, -0.5 * i);
		o.u.sphere.radius = 0.7;
		o.material = i % 2 ? red : SCENE_NONE;
		CHECK(scene_add_object(s, &o, &id, &err) == 0);
		CHECK(scene_add_root(s, id, &err) == 0);
	}
	struct scene_object o;
	uint32_t id;
	scene_object_defaults(&o, PRIM_PLANE);
	o.u.plane.position = v3(0, -1, 0);
	if (red_reflection > 0 || red_transparency > 0)
		o.material = red;
	CHECK(scene_add_object(s, &o, &id, &err) == 0);
	CHECK(scene_add_root(s, id, &err) == 0);
	return s;
}

/* make_scene_red with a plain red (neither mirror nor glass). */
static struct scene *make_scene(const struct scene_camera *cam, int with_objects)
{
	return make_scene_red(cam, with_objects, 0, 0);
}

static struct scene_camera base_camera(void)
{
	struct scene_camera c;
	scene_camera_defaults(&c);
	c.look_from = v3(0, 2, 9);
	c.look_at = v3(0, 0, 0);
	c.depth = 1;
	c.x_size = 0.8;
	c.y_size = 0.6;
	c.n_filters = 0;
	return c;
}

/* base_camera with filter standard: the eye rays in packets and 2x2
 * shading blocks; single: with super-sample 1x1 after it, the same image
 * traced one ray at a time (filter_pixel) */
static struct scene_camera packets_or_single(int single)
{
	struct scene_camera c = base_camera();
	add_filter(&c, FILTER_STANDARD);
	if (single) {
		add_filter(&c, FILTER_SUPERSAMPLE);
		c.filters[1].x_samples = c.filters[1].y_samples = 1;
	}
	return c;
}

/* A scene of mirrors (reflection 1, white spec-colour: every mirror ray
 * keeps weight 1) across base_camera's view: one plane through the origin
 * facing the camera, and with facing, a second one parallel to it behind
 * the camera. Every eye ray meets the first; its mirror ray goes back to
 * the sky (one secondary ray a pixel) or, with facing, between the two
 * until LIM_TRACE_DEPTH (that many a pixel). */
static struct scene *mirror_scene(const struct scene_camera *cam, int facing)
{
	struct scene_error err;
	struct scene *s = make_scene(cam, 0);
	struct scene_light l;
	scene_light_defaults(&l);
	l.position = v3(1, 3, 5);
	CHECK(scene_add_light(s, &l, &err) == 0);
	struct scene_material m;
	scene_material_defaults(&m);
	m.reflection = 1;
	uint32_t mirror;
	CHECK(scene_add_material(s, &m, &mirror, &err) == 0);
	for (int k = 0; k <= facing; k++) {
		struct scene_object o;
		uint32_t id;
		scene_object_defaults(&o, PRIM_PLANE);
		o.u.plane.normal = v3(0, 2, 9); /* toward the camera at (0 2 9) */
		o.u.plane.position = k ? v3(0, 4, 18) : v3(0, 0, 0);
		o.material = mirror;
		CHECK(scene_add_object(s, &o, &id, &err) == 0);
		CHECK(scene_add_root(s, id, &err) == 0);
	}
	return s;
}

static uint64_t calls;
static uint64_t last_done;
static void count_progress(void *arg, uint64_t done, uint64_t total)
{
	(void)arg;
	CHECK(done == last_done + 1 && done <= total);
	last_done = done;
	calls++;
}

static uint8_t *render(const struct renderer *r, int threads, uint32_t tile)
{
	uint8_t *img = calloc(W * H, 3);
	uint64_t n = render_image(r, threads, tile, img, NULL, NULL);
	CHECK(n == render_tile_count(W, H, tile));
	return img;
}

/* The float pixels of r (RENDER_RGBF32): one tile of the whole image equals
 * the same image traced in tiles of 5 (a corner tile's outside pixels all
 * zero bytes), and each value clamped and rounded to 8 bits is the RGB8
 * pixel of rgb (within 1: the float is the double rounded once). */
static void check_float_tiles(const struct renderer *r, const uint8_t *rgb)
{
	uint8_t *whole = malloc(W * H * 12), *parts = malloc(W * H * 12), tile[5 * 5 * 12];
	CHECK(whole && parts);
	if (!whole || !parts)
		goto out;
	CHECK(renderer_tile_px(r, (struct tile_rect){ 0, 0, W, H }, RENDER_RGBF32, whole, NULL) == 1);
	for (uint32_t y = 0; y < H; y += 5)
		for (uint32_t x = 0; x < W; x += 5) {
			memset(tile, 0x55, sizeof tile);
			CHECK(renderer_tile_px(r, (struct tile_rect){ x, y, 5, 5 }, RENDER_RGBF32, tile, NULL) == 1);
			for (uint32_t j = 0; j < 5; j++)
				for (uint32_t i = 0; i < 5; i++) {
					const uint8_t *p = tile + (j * 5 + i) * 12;
					if (x + i < W && y + j < H)
						memcpy(parts + ((y + j) * W + x + i) * 12, p, 12);
					else
						for (int k = 0; k < 12; k++)
							CHECK(p[k] == 0);
				}
		}
	CHECK(memcmp(whole, parts, W * H * 12) == 0);
	int off = 0, far = 0;
	for (int i = 0; i < W * H * 3; i++) {
		const uint8_t *p = whole + 4 * i;
		uint32_t u = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
		float f;
		memcpy(&f, &u, sizeof f);
		double v = f < 0 ? 0 : f > 1 ? 1 : f;
		int q = (int)(v * 255.0 + 0.5), d = q - rgb[i];
		off += d != 0;
		far += d < -1 || d > 1;
	}
	CHECK(far == 0 && off <= W * H * 3 / 100);
out:
	free(whole);
	free(parts);
}

int main(void)
{
	struct scene_error err;
	struct renderer *r;

	/* every filter on: adaptive, lens, super-sample, disk */
	struct scene_camera c = base_camera();
	add_filter(&c, FILTER_ADAPTIVE);
	c.filters[0].threshold = 0.05;
	c.filters[0].max_depth = 2;
	c.filters[0].cache_size = 50;
	add_filter(&c, FILTER_LENS);
	c.filters[1].samples = 2;
	c.filters[1].radius = 0.05;
	c.filters[1].focal_length = 9;
	add_filter(&c, FILTER_SUPERSAMPLE);
	add_filter(&c, FILTER_DISK);
	c.filters[3].samples = 2;
	struct scene *s = make_scene(&c, 1);
	CHECK(renderer_new(s, &r, &err) == 0);
	uint32_t w, h;
	renderer_size(r, &w, &h);
	CHECK(w == W && h == H);
	uint8_t *a = render(r, 1, 7);
	uint8_t *b = render(r, 2, 16);
	uint8_t *d = render(r, 2, 64);
	uint8_t *e = render(r, 3, 1);
	CHECK(memcmp(a, b, W * H * 3) == 0);
	CHECK(memcmp(a, d, W * H * 3) == 0);
	CHECK(memcmp(a, e, W * H * 3) == 0);
	check_float_tiles(r, a); /* pixel by pixel (filter_pixel) */
	/* the picture is not blank and not flat */
	int lit = 0, distinct = 0;
	for (int i = 0; i < W * H * 3; i++) {
		lit += a[i] > 0;
		distinct += i >= 3 && a[i] != a[i - 3];
	}
	CHECK(lit > W * H / 2 && distinct > W * H / 4);
	/* an odd rectangle through renderer_tile matches the image */
	uint8_t tilebuf[9 * 5 * 3];
	struct tile_rect t = { 13, 11, 9, 5 };
	renderer_tile(r, t, tilebuf);
	for (uint32_t j = 0; j < t.h; j++)
		CHECK(memcmp(tilebuf + j * t.w * 3, a + ((t.y + j) * W + t.x) * 3, t.w * 3) == 0);
	/* pixels outside the image come back black */
	struct tile_rect edge = { W - 2, H - 1, 4, 3 };
	uint8_t eb[4 * 3 * 3];
	memset(eb, 0x55, sizeof eb);
	renderer_tile(r, edge, eb);
	CHECK(memcmp(eb, a + ((H - 1) * W + W - 2) * 3, 6) == 0);
	CHECK(eb[6] == 0 && eb[4 * 3 * 3 - 1] == 0);

	/* progress: one call per tile, in order; cancellation before the start */
	calls = last_done = 0;
	struct render_progress pr = { count_progress, NULL };
	memset(b, 0, W * H * 3);
	uint64_t n = render_image(r, 2, 8, b, &pr, NULL);
	CHECK(n == render_tile_count(W, H, 8) && calls == n && n == 5 * 3);
	atomic_int cancel;
	atomic_init(&cancel, 1);
	memset(b, 0, W * H * 3);
	CHECK(render_image(r, 2, 8, b, NULL, &cancel) == 0);
	int any = 0;
	for (int i = 0; i < W * H * 3; i++)
		any |= b[i];
	CHECK(any == 0);
	t = (struct tile_rect){ 0, 0, 8, 8 };
	uint8_t big[8 * 8 * 3];
	CHECK(renderer_tile_cancellable(r, t, big, &cancel) == 0);
	atomic_store(&cancel, 0);
	CHECK(renderer_tile_cancellable(r, t, big, &cancel) == 1);
	CHECK(memcmp(big, a, 8 * 3) == 0);

	/* --size: a new size, refused when absurd */
	CHECK(renderer_set_size(r, 0, 5) < 0);
	CHECK(renderer_set_size(r, LIM_IMAGE_SIDE + 1, 5) < 0);
	CHECK(renderer_set_size(r, 10, 7) == 0);
	renderer_size(r, &w, &h);
	CHECK(w == 10 && h == 7);
	renderer_free(r);
	scene_free(s);
	free(a);
	free(b);
	free(d);
	free(e);

	/* standard: exactly one eye ray per pixel; super-sample 1x1 (traced pixel
	 * by pixel through filter_pixel) is the same image as standard's blocks
	 * (render.c: with 16-pixel tiles over 37x23, whole 8x8 blocks through
	 * accel_intersect64, whole 4x4 ones of cut blocks through
	 * accel_intersect16, the rest in 2x2 packets) */
	c = base_camera();
	add_filter(&c, FILTER_STANDARD);
	s = make_scene(&c, 1);
	CHECK(renderer_new(s, &r, &err) == 0);
	a = render(r, 2, 16);
	CHECK(renderer_rays(r) == W * H);
	check_float_tiles(r, a); /* the blocks */
	/* blocks (render.c): odd tiles and -j give the same image; a tile over
	 * the image's corner has its outside pixels black */
	uint8_t *o = render(r, 1, 3), *o2 = render(r, 3, 5);
	CHECK(memcmp(a, o, W * H * 3) == 0 && memcmp(a, o2, W * H * 3) == 0);
	free(o);
	free(o2);
	struct tile_rect corner = { W - 3, H - 1, 5, 3 };
	uint8_t cb[5 * 3 * 3];
	memset(cb, 0x55, sizeof cb);
	renderer_tile(r, corner, cb);
	CHECK(memcmp(cb, a + ((H - 1) * W + W - 3) * 3, 9) == 0);
	for (int i = 9; i < (int)sizeof cb; i++)
		CHECK(cb[i] == 0);
	renderer_free(r);
	scene_free(s);
	add_filter(&c, FILTER_SUPERSAMPLE);
	c.filters[1].x_samples = c.filters[1].y_samples = 1;
	s = make_scene(&c, 1);
	CHECK(renderer_new(s, &r, &err) == 0);
	b = render(r, 2, 5);
	CHECK(memcmp(a, b, W * H * 3) == 0);
	renderer_free(r);
	scene_free(s);
	free(a);
	free(b);

	/* shadow packets (shade_eye_hit4 over 2x2 blocks) against single rays
	 * (super-sample 1x1 traces one ray at a time): 40 dim point lights,
	 * more than the packets take (SHADE_PRE_LIGHTS in shade.c), every
	 * fifth without shadows, besides make_scene's sphere and point light */
	for (int k = 0; k < 2; k++) {
		uint8_t *img[2];
		for (int v = 0; v < 2; v++) {
			c = packets_or_single(v);
			s = make_scene(&c, 1);
			for (int i = 0; i < 40 * k; i++) {
				struct scene_light l;
				scene_light_defaults(&l);
				l.position = v3(-6 + 0.3 * i, 2 + 0.1 * (i % 7), 3 - 0.2 * (i % 5));
				l.colour = v3(0.02, 0.025, 0.03);
				l.no_shadows = i % 5 == 4;
				CHECK(scene_add_light(s, &l, &err) == 0);
			}
			CHECK(renderer_new(s, &r, &err) == 0);
			img[v] = render(r, 2, 16);
			renderer_free(r);
			scene_free(s);
		}
		CHECK(memcmp(img[0], img[1], W * H * 3) == 0);
		free(img[0]);
		free(img[1]);
	}

	/* a flat scene (nothing but the black background) is black under every filter */
	for (int k = FILTER_STANDARD; k <= FILTER_LENS; k++) {
		c = base_camera();
		add_filter(&c, k == FILTER_ADAPTIVE ? FILTER_ADAPTIVE : FILTER_STANDARD);
		if (k > FILTER_ADAPTIVE)
			add_filter(&c, (enum filter_kind)k);
		s = make_scene(&c, 0);
		CHECK(renderer_new(s, &r, &err) == 0);
		a = render(r, 2, 16);
		any = 0;
		for (int i = 0; i < W * H * 3; i++)
			any |= a[i];
		CHECK(any == 0);
		CHECK(renderer_rays(r) >= W * H);
		free(a);
		renderer_free(r);
		scene_free(s);
	}
	/* secondary rays (renderer_secondary_rays): none without mirrors or
	 * glass; with them, the same count whatever the threads and tiles, and
	 * the same through the packets and blocks (standard) as through single
	 * rays (super-sample 1x1), opaque (surf_shade) and transparent
	 * (BLOCK SHADING) */
	for (int k = 0; k < 3; k++) {
		uint64_t cnt[2];
		for (int v = 0; v < 2; v++) {
			c = packets_or_single(v);
			s = make_scene_red(&c, 1, k ? 0.5 : 0, k == 2 ? 0.6 : 0);
			CHECK(renderer_new(s, &r, &err) == 0);
			free(render(r, 1, 16));
			cnt[v] = renderer_secondary_rays(r);
			free(render(r, 2, 5));
			CHECK(renderer_secondary_rays(r) == 2 * cnt[v]);
			renderer_free(r);
			scene_free(s);
		}
		CHECK(cnt[0] == cnt[1]);
		CHECK(k ? cnt[0] > 0 : cnt[0] == 0);
		if (k == 2) /* glass adds transmitted rays to the mirror rays */
			CHECK(cnt[0] > W * H / 8);
	}
	/* exact counts: one mirror ray a pixel off one mirror, LIM_TRACE_DEPTH
	 * between two facing ones, through packets and single rays alike */
	for (int facing = 0; facing < 2; facing++)
		for (int v = 0; v < 2; v++) {
			c = packets_or_single(v);
			s = mirror_scene(&c, facing);
			CHECK(renderer_new(s, &r, &err) == 0);
			free(render(r, 2, 16));
			CHECK(renderer_secondary_rays(r) == (uint64_t)W * H * (facing ? LIM_TRACE_DEPTH : 1));
			renderer_free(r);
			scene_free(s);
		}
	CHECK(render_ncpus() >= 1);
	CHECK(render_tile_count(64, 64, 32) == 4 && render_tile_count(65, 64, 32) == 6);
	TEST_MAIN_END();
}
