/* test_filter.c - layered filters (common/filter.c) on synthetic scenes. */
#include <math.h>
#include <string.h>

#include "common/filter.h"
#include "common/rng.h"
#include "tests/unit/check.h"

/* A constant colour everywhere. */
static vec3 trace_const(void *arg, const struct ray *r, uint64_t seed)
{
	(void)r;
	(void)seed;
	return *(const vec3 *)arg;
}

/* A colour that depends on the ray and on the seed (like an area light). */
static vec3 trace_noisy(void *arg, const struct ray *r, uint64_t seed)
{
	(void)arg;
	return v3(0.5 + 0.5 * r->d.x, rng_uniform(seed, 7), 0.5 + 0.4 * sin(40 * r->d.y));
}

/* Half-space edge: white where the ray points right of a slanted line. */
static vec3 trace_edge(void *arg, const struct ray *r, uint64_t seed)
{
	(void)arg;
	(void)seed;
	return r->d.x + 0.37 * r->d.y > 0.013 ? v3(1, 1, 1) : v3(0, 0, 0);
}

/* Records the last ray. */
static struct ray last_ray;
static vec3 trace_record(void *arg, const struct ray *r, uint64_t seed)
{
	(void)arg;
	(void)seed;
	last_ray = *r;
	return v3(0, 0, 0);
}

/* trace_noisy four rays at a time (filter_trace4_fn), counting packets. */
static int n_packets;
static void trace_noisy4(void *arg, const struct ray r[4], const uint64_t seed[4], int n, vec3 out[4])
{
	CHECK(n >= 1 && n <= 4);
	n_packets++;
	for (int k = 0; k < n; k++)
		out[k] = trace_noisy(arg, &r[k], seed[k]);
}

/* trace_noisy four at a time, recording every ray and seed in order (rec_n of them). */
#define REC_MAX 1024
static struct ray rec_ray[REC_MAX];
static uint64_t rec_seed[REC_MAX];
static int rec_n;
static void trace_rec4(void *arg, const struct ray r[4], const uint64_t seed[4], int n, vec3 out[4])
{
	for (int k = 0; k < n; k++) {
		if (rec_n < REC_MAX) {
			rec_ray[rec_n] = r[k];
			rec_seed[rec_n] = seed[k];
		}
		rec_n++;
		out[k] = trace_noisy(arg, &r[k], seed[k]);
	}
}

/* filter_pixel4 over every pixel of a w x h chain (scratch per row when
 * cache) gives filter_pixel's colours bit for bit and its ray count;
 * returns the packets traced. */
static int packets_agree(const struct filter_chain *fc, uint32_t w, uint32_t h, bool cache)
{
	n_packets = 0;
	for (uint32_t y = 0; y < h; y++) {
		struct filter_scratch *s1 = cache ? filter_scratch_new(fc) : NULL;
		struct filter_scratch *s4 = cache ? filter_scratch_new(fc) : NULL;
		for (uint32_t x = 0; x < w; x++) {
			uint64_t r1 = 0, r4 = 0;
			vec3 v1 = filter_pixel(fc, s1, x, y, trace_noisy, NULL, &r1);
			vec3 v4 = filter_pixel4(fc, s4, x, y, trace_noisy, trace_noisy4, NULL, &r4);
			CHECK(memcmp(&v1, &v4, sizeof v1) == 0);
			CHECK(r1 == r4);
		}
		filter_scratch_free(s1);
		filter_scratch_free(s4);
	}
	return n_packets;
}

static struct scene_camera base_camera(void)
{
	struct scene_camera c;
	scene_camera_defaults(&c);
	c.look_from = v3(0, 0, 5);
	c.depth = 1;
	c.x_size = 1;
	c.y_size = 0.75;
	c.n_filters = 0;
	return c;
}

static void add(struct scene_camera *c, enum filter_kind k)
{
	scene_filter_defaults(&c->filters[c->n_filters], k);
	c->filters[c->n_filters].loc.line = c->n_filters + 1;
	c->n_filters++;
}

static struct scene_image img;

static void chain(struct filter_chain *fc, const struct scene_camera *c, uint32_t w, uint32_t h)
{
	int rc = filter_chain_init(fc, c, &img, w, h);
	CHECK(rc == 0);
}

/* Renders w x h through tiles of side t, fresh scratch per tile, into out. */
static uint64_t render_tiles(const struct filter_chain *fc, uint32_t w, uint32_t h, uint32_t t,
			     filter_trace_fn fn, vec3 *out)
{
	uint64_t rays = 0;
	for (uint32_t ty = 0; ty < h; ty += t)
		for (uint32_t tx = 0; tx < w; tx += t) {
			struct filter_scratch *s = filter_scratch_new(fc);
			CHECK(s != NULL);
			for (uint32_t y = ty; y < ty + t && y < h; y++)
				for (uint32_t x = tx; x < tx + t && x < w; x++)
					out[y * w + x] = filter_pixel(fc, s, x, y, fn, NULL, &rays);
			filter_scratch_free(s);
		}
	return rays;
}

/* Film position of a ray (inverse of the camera), in continuous pixels. */
static void ray_to_pixel(const struct cam *c, const struct ray *r, double *px, double *py)
{
	double t = c->depth / v3_dot(r->d, c->view);
	vec3 p = v3_add(r->o, v3_scale(r->d, t));
	vec3 centre = v3_add(c->from, v3_scale(c->view, c->depth));
	*px = (v3_dot(v3_sub(p, centre), c->right) / c->x_size + 0.5) * c->w;
	*py = (v3_dot(v3_sub(p, centre), c->down) / c->y_size + 0.5) * c->h;
}

int main(void)
{
	scene_image_defaults(&img);
	struct filter_chain fc, fc2;
	struct scene_camera c;
	uint64_t rays;
	char warn[1024];

	/* no filter, or standard: one ray through the pixel centre */
	c = base_camera();
	chain(&fc, &c, 40, 30);
	CHECK(fc.base.kind == FILTER_STANDARD && fc.n_layers == 0);
	rays = 0;
	filter_pixel(&fc, NULL, 3, 4, trace_record, NULL, &rays);
	CHECK(rays == 1);
	struct ray want = cam_ray(&fc.cam, 3.5, 4.5);
	CHECK(memcmp(&want.d, &last_ray.d, sizeof want.d) == 0);

	/* the manual's example: 10 x 3 x 3 x 10 = 900 rays per pixel */
	c = base_camera();
	add(&c, FILTER_STANDARD);
	add(&c, FILTER_LENS);
	c.filters[1].samples = 10;
	c.filters[1].focal_length = 30;
	add(&c, FILTER_SUPERSAMPLE);
	c.filters[2].x_samples = 3;
	c.filters[2].y_samples = 3;
	add(&c, FILTER_DISK);
	c.filters[3].samples = 10;
	chain(&fc, &c, 8, 6);
	CHECK(filter_rays_per_sample(&fc) == 900);
	rays = 0;
	vec3 v1 = filter_pixel(&fc, NULL, 2, 3, trace_noisy, NULL, &rays);
	CHECK(rays == 900);
	CHECK(filter_warnings(&c, warn, sizeof warn) == 0 && warn[0] == '\0');
	/* deterministic: the same pixel twice gives the same colour */
	vec3 v2 = filter_pixel(&fc, NULL, 2, 3, trace_noisy, NULL, NULL);
	CHECK(memcmp(&v1, &v2, sizeof v1) == 0);

	/* a flat-colour scene looks the same under every filter */
	vec3 grey = v3(0.31, 0.62, 0.93); /* away from the x.5/255 rounding edges */
	uint8_t q0[3], q1[3];
	filter_quantise(grey, q0);
	for (int k = 0; k <= FILTER_LENS; k++) {
		c = base_camera();
		add(&c, k == FILTER_ADAPTIVE ? FILTER_ADAPTIVE : FILTER_STANDARD);
		if (k != FILTER_STANDARD && k != FILTER_ADAPTIVE)
			add(&c, (enum filter_kind)k);
		chain(&fc, &c, 8, 6);
		struct filter_scratch *s = filter_scratch_new(&fc);
		for (uint32_t y = 0; y < 6; y++)
			for (uint32_t x = 0; x < 8; x++) {
				filter_quantise(filter_pixel(&fc, s, x, y, trace_const, &grey, NULL), q1);
				CHECK(memcmp(q0, q1, 3) == 0);
			}
		filter_scratch_free(s);
	}

	/* super-sample 1x1 == standard, bit for bit, even with seed-dependent colour */
	c = base_camera();
	add(&c, FILTER_STANDARD);
	chain(&fc, &c, 16, 12);
	add(&c, FILTER_SUPERSAMPLE);
	c.filters[1].x_samples = c.filters[1].y_samples = 1;
	chain(&fc2, &c, 16, 12);
	for (uint32_t y = 0; y < 12; y++)
		for (uint32_t x = 0; x < 16; x++) {
			v1 = filter_pixel(&fc, NULL, x, y, trace_noisy, NULL, NULL);
			v2 = filter_pixel(&fc2, NULL, x, y, trace_noisy, NULL, NULL);
			CHECK(memcmp(&v1, &v2, sizeof v1) == 0);
		}
	/* super-sample 2x3 puts its rays on the centres of a grid of cells */
	c.filters[1].x_samples = 2;
	c.filters[1].y_samples = 3;
	chain(&fc2, &c, 16, 12);
	CHECK(filter_rays_per_sample(&fc2) == 6);

	/* filters before the first standard/adaptive are ignored, with a warning */
	c = base_camera();
	add(&c, FILTER_DISK);
	add(&c, FILTER_STANDARD);
	chain(&fc2, &c, 16, 12);
	CHECK(fc2.n_layers == 0 && filter_rays_per_sample(&fc2) == 1);
	CHECK(filter_warnings(&c, warn, sizeof warn) == 1);
	CHECK(strstr(warn, ":1:0: warning: filter disk ignored") != NULL);
	v1 = filter_pixel(&fc, NULL, 5, 5, trace_noisy, NULL, NULL);
	v2 = filter_pixel(&fc2, NULL, 5, 5, trace_noisy, NULL, NULL);
	CHECK(memcmp(&v1, &v2, sizeof v1) == 0);
	/* only filters before: all ignored, standard used */
	c = base_camera();
	add(&c, FILTER_LENS);
	chain(&fc2, &c, 16, 12);
	CHECK(fc2.base.kind == FILTER_STANDARD && fc2.n_layers == 0);
	CHECK(filter_warnings(&c, warn, sizeof warn) == 1 && strstr(warn, "using filter standard"));
	/* a later standard changes nothing */
	c = base_camera();
	add(&c, FILTER_STANDARD);
	add(&c, FILTER_STANDARD);
	chain(&fc2, &c, 16, 12);
	CHECK(filter_warnings(&c, warn, sizeof warn) == 0 && filter_rays_per_sample(&fc2) == 1);

	/* disk: offsets within the radius, different per pixel and sample */
	c = base_camera();
	add(&c, FILTER_STANDARD);
	add(&c, FILTER_DISK);
	c.filters[1].samples = 1;
	c.filters[1].radius = 0.9;
	chain(&fc, &c, 40, 30);
	double px, py, maxr = 0, minr = 1, lastpx = -1;
	int same = 0;
	for (uint32_t i = 0; i < 200; i++) {
		filter_pixel(&fc, NULL, i % 40, i / 40, trace_record, NULL, NULL);
		ray_to_pixel(&fc.cam, &last_ray, &px, &py);
		double dx = px - (i % 40 + 0.5), dy = py - (i / 40 + 0.5), rr = sqrt(dx * dx + dy * dy);
		maxr = fmax(maxr, rr);
		minr = fmin(minr, rr);
		same += fabs(dx - lastpx) < 1e-12;
		lastpx = dx;
	}
	CHECK(maxr <= 0.9 + 1e-9 && maxr > 0.7 && minr < 0.2 && same == 0);
	/* tent weight: a sample's weight is 1 - r/R; with one sample per pixel the
	 * weighted mean is that sample's colour (weights normalised) */
	v1 = filter_pixel(&fc, NULL, 7, 7, trace_const, &grey, NULL);
	CHECK_NEAR(v1.y, 0.62, 1e-12);

	/* lens: all rays of a pixel meet at the focal distance; aperture radius kept */
	c = base_camera();
	add(&c, FILTER_STANDARD);
	add(&c, FILTER_LENS);
	c.filters[1].samples = 1;
	c.filters[1].radius = 0.25;
	c.filters[1].focal_length = 3.0;
	chain(&fc, &c, 40, 30);
	struct ray pin = cam_ray(&fc.cam, 11.5, 6.5);
	vec3 focus = v3_add(pin.o, v3_scale(pin.d, 3.0 / v3_dot(pin.d, fc.cam.view)));
	double maxa = 0;
	for (uint32_t i = 0; i < 50; i++) {
		struct filter_chain f2 = fc;
		f2.layers[0].samples = (int)i + 1; /* different sample indices */
		filter_pixel(&f2, NULL, 11, 6, trace_record, NULL, NULL);
		double t = v3_dot(v3_sub(focus, last_ray.o), last_ray.d);
		CHECK_NEAR(v3_len(v3_sub(v3_add(last_ray.o, v3_scale(last_ray.d, t)), focus)), 0, 1e-9);
		double a = v3_len(v3_sub(last_ray.o, fc.cam.from));
		CHECK(a <= 0.25 + 1e-12);
		maxa = fmax(maxa, a);
	}
	CHECK(maxa > 0.15);

	/* adaptive, threshold huge: the mean of the four corners, 4 rays alone,
	 * 2 more per pixel along a row when the cache shares corners */
	c = base_camera();
	add(&c, FILTER_ADAPTIVE);
	c.filters[0].threshold = 1e9;
	chain(&fc, &c, 16, 12);
	uint32_t g = 1u << fc.base.max_depth;
	for (uint32_t y = 0; y < 12; y += 3)
		for (uint32_t x = 0; x < 16; x += 5) {
			rays = 0;
			v1 = filter_pixel(&fc, NULL, x, y, trace_noisy, NULL, &rays);
			CHECK(rays == 4);
			vec3 tl = filter_point(&fc, x, y, x * g, y * g, trace_noisy, NULL, NULL);
			vec3 tr = filter_point(&fc, x + 1, y, (x + 1) * g, y * g, trace_noisy, NULL, NULL);
			vec3 bl = filter_point(&fc, x, y + 1, x * g, (y + 1) * g, trace_noisy, NULL, NULL);
			vec3 br = filter_point(&fc, x + 1, y + 1, (x + 1) * g, (y + 1) * g, trace_noisy, NULL, NULL);
			v2 = v3_scale(v3_add(v3_add(tl, tr), v3_add(bl, br)), 0.25);
			CHECK(memcmp(&v1, &v2, sizeof v1) == 0);
		}
	struct filter_scratch *s = filter_scratch_new(&fc);
	rays = 0;
	for (uint32_t x = 0; x < 4; x++)
		filter_pixel(&fc, s, x, 0, trace_const, &grey, &rays);
	CHECK(rays == 4 + 3 * 2);
	filter_scratch_free(s);

	/* adaptive on an edge: subdivides, estimates coverage, and the image does
	 * not depend on the tile size or the cache size */
	c = base_camera();
	add(&c, FILTER_ADAPTIVE);
	c.filters[0].threshold = 0.1;
	c.filters[0].max_depth = 3;
	c.filters[0].cache_size = 7;
	add(&c, FILTER_DISK); /* random layer under adaptive: corners seeded by position */
	c.filters[1].samples = 2;
	chain(&fc, &c, 24, 18);
	static vec3 a1[24 * 18], a2[24 * 18], a3[24 * 18];
	uint64_t r1 = render_tiles(&fc, 24, 18, 24, trace_edge, a1);
	render_tiles(&fc, 24, 18, 5, trace_edge, a2);
	fc.cache_size = 1000;
	uint64_t r3 = render_tiles(&fc, 24, 18, 7, trace_edge, a3);
	CHECK(memcmp(a1, a2, sizeof a1) == 0);
	CHECK(memcmp(a1, a3, sizeof a1) == 0);
	CHECK(r3 < r1);                 /* the bigger cache traces fewer rays */
	CHECK(r1 > 24 * 18 * 4 * 2 / 4); /* subdivision happened somewhere */
	int partial = 0;
	for (int i = 0; i < 24 * 18; i++)
		partial += a1[i].x > 0.05 && a1[i].x < 0.95;
	CHECK(partial >= 10);
	/* without the disk layer, coverage of an edge pixel is estimated on the
	 * 1/8 grid: compare with the exact area by fine sampling */
	c.n_filters = 1;
	chain(&fc, &c, 24, 18);
	render_tiles(&fc, 24, 18, 24, trace_edge, a1);
	double worst = 0;
	for (uint32_t y = 0; y < 18; y++)
		for (uint32_t x = 0; x < 24; x++) {
			double cov = 0;
			for (int k = 0; k < 64 * 64; k++) {
				struct ray rr = cam_ray(&fc.cam, x + (k % 64 + 0.5) / 64, y + (k / 64 + 0.5) / 64);
				cov += trace_edge(NULL, &rr, 0).x;
			}
			worst = fmax(worst, fabs(cov / 4096 - a1[y * 24 + x].x));
		}
	CHECK(worst < 0.15);

	/* quantisation: clamp, round to nearest, no gamma */
	uint8_t q[3];
	filter_quantise(v3(0.5, 1.7, -0.2), q);
	CHECK(q[0] == 128 && q[1] == 255 && q[2] == 0);
	filter_quantise(v3(NAN, 1.0 / 255, 0.4 / 255), q);
	CHECK(q[0] == 0 && q[1] == 1 && q[2] == 0);
	/* packets (filter_pixel4): a last super-sample grid four samples a
	 * packet (3 x 3: 4, 4, 1), alone, after a lens, under adaptive;
	 * adaptive's corners four at a time, with and without the cache, and
	 * with a cache of one slot (corners of one batch share it) */
	c = base_camera();
	add(&c, FILTER_STANDARD);
	add(&c, FILTER_SUPERSAMPLE);
	c.filters[1].x_samples = 3;
	c.filters[1].y_samples = 3;
	chain(&fc, &c, 9, 7);
	CHECK(packets_agree(&fc, 9, 7, false) == 9 * 7 * 3);
	c = base_camera();
	add(&c, FILTER_STANDARD);
	add(&c, FILTER_LENS);
	c.filters[1].samples = 3;
	add(&c, FILTER_SUPERSAMPLE);
	c.filters[2].x_samples = 2;
	c.filters[2].y_samples = 3;
	chain(&fc, &c, 5, 4);
	CHECK(packets_agree(&fc, 5, 4, false) == 5 * 4 * 3 * 2);
	for (int size = 0; size < 3; size++) {
		c = base_camera();
		add(&c, FILTER_ADAPTIVE);
		c.filters[0].threshold = 0.05;
		c.filters[0].max_depth = 3;
		c.filters[0].cache_size = size == 2 ? 1 : 64;
		chain(&fc, &c, 12, 9);
		CHECK(packets_agree(&fc, 12, 9, size > 0) > 12 * 9);
	}
	c = base_camera();
	add(&c, FILTER_ADAPTIVE);
	c.filters[0].threshold = 0.05;
	add(&c, FILTER_SUPERSAMPLE);
	c.filters[1].x_samples = 2;
	c.filters[1].y_samples = 2;
	chain(&fc, &c, 6, 5);
	CHECK(packets_agree(&fc, 6, 5, true) > 6 * 5);

	/* the packet paths against the scalar expressions they replace, bit for
	 * bit: sample k of an xs x ys grid from pixel (x, y)'s centre is
	 * cam_ray at (x + 0.5 + ((k % xs + 0.5) / xs - 0.5), y + 0.5 + ((k / xs +
	 * 0.5) / ys - 0.5)) seeded rng_seed(x, y, k); the chain keeps each
	 * offset as that expression gives it; grids wider than its table
	 * (FILTER_GRID_TAB) compute them sample by sample */
	static const int grids[][2] = { { 3, 3 }, { 2, 5 }, { 1, 1 }, { 4, 1 }, { 16, 16 }, { 17, 2 }, { 3, 40 } };
	for (size_t gi = 0; gi < sizeof grids / sizeof grids[0]; gi++) {
		int xs = grids[gi][0], ys = grids[gi][1];
		c = base_camera();
		add(&c, FILTER_STANDARD);
		add(&c, FILTER_SUPERSAMPLE);
		c.filters[1].x_samples = xs;
		c.filters[1].y_samples = ys;
		chain(&fc, &c, 9, 7);
		for (int a = 0; a < xs && a < FILTER_GRID_TAB; a++) {
			double want_dx = ((double)(uint64_t)a + 0.5) / xs - 0.5;
			CHECK(memcmp(&want_dx, &fc.grid_dx[0][a], sizeof want_dx) == 0);
		}
		for (int b = 0; b < ys && b < FILTER_GRID_TAB; b++) {
			double want_dy = ((double)(uint64_t)b + 0.5) / ys - 0.5;
			CHECK(memcmp(&want_dy, &fc.grid_dy[0][b], sizeof want_dy) == 0);
		}
		for (uint32_t y = 0; y < 7; y += 3)
			for (uint32_t x = 0; x < 9; x += 4) {
				rec_n = 0;
				rays = 0;
				filter_pixel4(&fc, NULL, x, y, trace_noisy, trace_rec4, NULL, &rays);
				CHECK(rec_n == xs * ys && rays == (uint64_t)(xs * ys) && rec_n <= REC_MAX);
				for (int k = 0; k < rec_n && k < REC_MAX; k++) {
					uint64_t a = (uint64_t)k % (uint64_t)xs, b = (uint64_t)k / (uint64_t)xs;
					double sx = x + 0.5, sy = y + 0.5;
					sx += ((double)a + 0.5) / xs - 0.5;
					sy += ((double)b + 0.5) / ys - 0.5;
					struct ray rk = cam_ray(&fc.cam, sx, sy);
					CHECK(memcmp(&rk, &rec_ray[k], sizeof rk) == 0);
					CHECK(rec_seed[k] == rng_seed(x, y, (uint32_t)k));
				}
			}
	}
	/* adaptive's corners traced four at a time: each is cam_ray at the
	 * corner (cx / 2^depth, cy / 2^depth) seeded rng_seed(cx, cy, 0) */
	c = base_camera();
	add(&c, FILTER_ADAPTIVE);
	c.filters[0].threshold = 0.01;
	c.filters[0].max_depth = 3;
	chain(&fc, &c, 12, 9);
	int found = 0;
	for (uint32_t y = 2; y < 9; y += 3)
		for (uint32_t x = 1; x < 12; x += 5) {
			rec_n = 0;
			filter_pixel4(&fc, NULL, x, y, trace_noisy, trace_rec4, NULL, NULL);
			CHECK(rec_n >= 4 && rec_n <= REC_MAX);
			for (int k = 0; k < rec_n && k < REC_MAX; k++) {
				bool ok = false;
				for (uint32_t cy = y * 8; cy <= y * 8 + 8 && !ok; cy++)
					for (uint32_t cx = x * 8; cx <= x * 8 + 8 && !ok; cx++) {
						if (rec_seed[k] != rng_seed(cx, cy, 0))
							continue;
						struct ray rk = cam_ray(&fc.cam, (double)cx / 8, (double)cy / 8);
						ok = memcmp(&rk, &rec_ray[k], sizeof rk) == 0;
					}
				CHECK(ok);
				found += ok;
			}
		}
	CHECK(found > 9 * 4); /* some pixels subdivided */
	/* filter_pixels4: n = 1..4 pixels of a row, each filter_pixel's colour
	 * bit for bit and the same rays; a grid's rays in packets of four
	 * across the pixels (3 x 3 over 4 pixels: 9 packets), other chains
	 * pixel by pixel */
	for (int kind = 0; kind < 9; kind++) {
		static const int pg[][2] = { { 3, 3 }, { 2, 2 }, { 1, 1 }, { 5, 3 }, { 16, 1 }, { 17, 2 } };
		c = base_camera();
		add(&c, kind == 8 ? FILTER_ADAPTIVE : FILTER_STANDARD);
		if (kind == 6) {
			add(&c, FILTER_LENS);
			c.filters[1].samples = 2;
		}
		if (kind < 7) {
			add(&c, FILTER_SUPERSAMPLE);
			c.filters[c.n_filters - 1].x_samples = pg[kind % 6][0];
			c.filters[c.n_filters - 1].y_samples = pg[kind % 6][1];
		}
		if (kind == 8)
			c.filters[0].threshold = 0.05;
		chain(&fc, &c, 11, 5);
		for (uint32_t y = 0; y < 5; y += 2)
			for (int n = 1; n <= 4; n++)
				for (uint32_t x = 0; x + (uint32_t)n <= 11; x += 3) {
					vec3 out[4];
					uint64_t ra = 0, rb = 0;
					n_packets = 0;
					filter_pixels4(&fc, NULL, x, y, n, trace_noisy, trace_noisy4, NULL, &rb, out);
					if (kind == 0)
						CHECK(n_packets == (9 * n + 3) / 4);
					for (int p = 0; p < n; p++) {
						vec3 one = filter_pixel(&fc, NULL, x + (uint32_t)p, y, trace_noisy, NULL, &ra);
						CHECK(memcmp(&one, &out[p], sizeof one) == 0);
					}
					CHECK(ra == rb);
				}
	}
	/* filter_eye_block: filter_eye_ray's rays and seeds of a 2x2 block */
	c = base_camera();
	chain(&fc, &c, 41, 31);
	for (uint32_t y = 0; y + 1 < 31; y += 3)
		for (uint32_t x = 0; x + 1 < 41; x += 5) {
			struct ray rb[4];
			uint64_t sb[4];
			filter_eye_block(&fc, x, y, rb, sb);
			for (uint32_t k = 0; k < 4; k++) {
				struct ray e1;
				uint64_t s1;
				filter_eye_ray(&fc, x + (k & 1), y + (k >> 1), &e1, &s1);
				CHECK(memcmp(&e1, &rb[k], sizeof e1) == 0 && s1 == sb[k]);
			}
		}
	/* filter_eye_ray4: filter_eye_ray's rays and seeds, n = 1..4 */
	c = base_camera();
	chain(&fc, &c, 40, 30);
	for (int n = 1; n <= 4; n++)
		for (uint32_t y = 0; y < 30; y += 7) {
			uint32_t ex[4], ey[4];
			struct ray r4[4];
			uint64_t s4[4];
			for (int k = 0; k < n; k++) {
				ex[k] = (y * 3 + (uint32_t)k * 11) % 40;
				ey[k] = (y + (uint32_t)k) % 30;
			}
			filter_eye_ray4(&fc, ex, ey, n, r4, s4);
			for (int k = 0; k < n; k++) {
				struct ray e1;
				uint64_t s1;
				filter_eye_ray(&fc, ex[k], ey[k], &e1, &s1);
				CHECK(memcmp(&e1, &r4[k], sizeof e1) == 0 && s1 == s4[k]);
			}
		}

	TEST_MAIN_END();
}
