/* test_camera.c - the pinhole camera and thin lens (common/camera.c). */
#include <math.h>
#include <string.h>

#include "common/camera.h"
#include "tests/unit/check.h"

static struct scene_camera spd_camera(void)
{
	struct scene_camera c;
	scene_camera_defaults(&c);
	c.look_from = v3(2.1, 1.3, 1.7);
	c.look_at = v3(0.5, -0.25, 0.1);
	c.drop_line = v3(0.3, -1.0, 0.2); /* not perpendicular to the view */
	c.depth = 1.0;
	c.x_size = 0.8;
	c.y_size = 0.5;
	return c;
}

static double angle_between(vec3 a, vec3 b)
{
	double c = v3_dot(v3_norm(a), v3_norm(b));
	return acos(fmin(1.0, fmax(-1.0, c)));
}

int main(void)
{
	/* manual defaults: from +z looking at the origin, drop-line -y */
	struct scene_camera sc;
	scene_camera_defaults(&sc);
	struct cam c;
	CHECK(cam_init(&c, &sc, 320, 240) == 0);
	CHECK_NEAR(c.right.x, 1, 1e-12); /* right = drop x view = +x: not mirrored */
	CHECK_NEAR(c.down.y, -1, 1e-12); /* down = -y */
	CHECK_NEAR(c.view.z, -1, 1e-12);
	struct ray r = cam_ray(&c, 0.5, 0.5); /* top-left pixel: left (-x) and up (+y) */
	CHECK(r.d.x < 0 && r.d.y > 0);
	CHECK_NEAR(v3_len(r.d), 1, 1e-12);
	CHECK(r.o.z == 10 && r.tmin == 0 && isinf(r.tmax));

	/* a general camera with a drop-line not perpendicular to the view */
	sc = spd_camera();
	uint32_t W = 321, H = 241; /* odd: pixel (160,120) is the image centre */
	CHECK(cam_init(&c, &sc, W, H) == 0);
	vec3 view = v3_sub(sc.look_at, sc.look_from);
	vec3 right = v3_norm(v3_cross(sc.drop_line, view));
	vec3 vu = v3_norm(view);
	vec3 down = v3_norm(v3_sub(sc.drop_line, v3_scale(vu, v3_dot(sc.drop_line, vu))));
	CHECK_NEAR(v3_dot(c.right, right), 1, 1e-12);
	CHECK_NEAR(v3_dot(c.down, down), 1, 1e-12);
	CHECK_NEAR(v3_dot(c.down, c.view), 0, 1e-12);

	/* the centre pixel's ray points at look-at */
	r = cam_ray(&c, W / 2 + 0.5, H / 2 + 0.5);
	CHECK(angle_between(r.d, view) < 1e-9);
	CHECK_NEAR(v3_len(v3_sub(r.o, sc.look_from)), 0, 0);

	/* right half looks toward drop x view, left half away; top rows opposite
	 * to the drop-line, bottom rows along it */
	for (uint32_t j = 0; j < H; j += 40) {
		for (uint32_t i = 0; i < W; i += 40) {
			r = cam_ray(&c, i + 0.5, j + 0.5);
			double side = v3_dot(r.d, right), vert = v3_dot(r.d, down);
			CHECK(i > W / 2 ? side > 0 : i < W / 2 ? side < 0 : fabs(side) < 1e-12);
			CHECK(j > H / 2 ? vert > 0 : j < H / 2 ? vert < 0 : fabs(vert) < 1e-12);
		}
	}
	r = cam_ray(&c, W / 2 + 0.5, 0.5);
	vec3 rc = cam_ray(&c, W / 2 + 0.5, H / 2 + 0.5).d;
	CHECK(v3_dot(r.d, sc.drop_line) < v3_dot(rc, sc.drop_line));

	/* x-size spans the width and y-size the height, independently */
	r = cam_ray(&c, 0, H / 2 + 0.5); /* left edge of the film */
	CHECK_NEAR(tan(angle_between(r.d, view)), sc.x_size / 2 / sc.depth, 1e-12);
	r = cam_ray(&c, W, H / 2 + 0.5);
	CHECK_NEAR(tan(angle_between(r.d, view)), sc.x_size / 2 / sc.depth, 1e-12);
	r = cam_ray(&c, W / 2 + 0.5, 0); /* top edge */
	CHECK_NEAR(tan(angle_between(r.d, view)), sc.y_size / 2 / sc.depth, 1e-12);
	struct cam c2;
	CHECK(cam_init(&c2, &sc, 100, 700) == 0); /* other pixel aspect: same film edges */
	CHECK_NEAR(tan(angle_between(cam_ray(&c2, 0, 350).d, view)), sc.x_size / 2 / sc.depth, 1e-12);
	CHECK_NEAR(tan(angle_between(cam_ray(&c2, 50, 0).d, view)), sc.y_size / 2 / sc.depth, 1e-12);
	/* film point formula */
	vec3 fp = cam_film_point(&c, 10.25, 30.5);
	vec3 want = v3_add(v3_add(sc.look_from, v3_scale(vu, sc.depth)),
			   v3_add(v3_scale(right, (10.25 / W - 0.5) * sc.x_size),
				  v3_scale(down, (30.5 / H - 0.5) * sc.y_size)));
	CHECK_NEAR(v3_len(v3_sub(fp, want)), 0, 1e-12);
	/* ray through the film point */
	r = cam_ray(&c, 10.25, 30.5);
	CHECK(angle_between(r.d, v3_sub(fp, sc.look_from)) < 1e-9);

	/* thin lens: a zero aperture is the pinhole; every aperture point's ray
	 * passes through the pinhole ray's point at the focal distance */
	struct ray p = cam_ray(&c, 37.5, 12.5);
	r = cam_lens_ray(&c, 37.5, 12.5, 0, 0, 7.0);
	CHECK_NEAR(v3_len(v3_sub(r.d, p.d)), 0, 1e-12);
	double focal = 7.0;
	vec3 focus = v3_add(p.o, v3_scale(p.d, focal / v3_dot(p.d, c.view)));
	for (int k = 0; k < 8; k++) {
		double lu = 0.1 * cos(k), lv = 0.1 * sin(k);
		r = cam_lens_ray(&c, 37.5, 12.5, lu, lv, focal);
		CHECK_NEAR(v3_dot(v3_sub(r.o, sc.look_from), c.view), 0, 1e-12); /* on the lens plane */
		CHECK_NEAR(v3_len(v3_sub(r.o, sc.look_from)), 0.1, 1e-12);
		double t = v3_dot(v3_sub(focus, r.o), r.d);
		CHECK_NEAR(v3_len(v3_sub(v3_add(r.o, v3_scale(r.d, t)), focus)), 0, 1e-9);
		CHECK_NEAR(v3_len(r.d), 1, 1e-12);
	}

	/* cam_ray4 and cam_unit4 over cam_col and cam_row (the SSE2 paths) give
	 * cam_ray's rays bit for bit, for n = 1..4 and positions anywhere: on
	 * and off the film, at its edges, huge; with depth 0 the film centre's
	 * direction is zero and stays zero, as v3_norm leaves it */
	const double pos[] = { 0.5, 0, 1e-300, 320.75, 321, -17.25, 1e6, -3e300, 160.5, 120.5, 0.1, 240.999 };
	const int n_pos = (int)(sizeof pos / sizeof pos[0]);
	for (int depth0 = 0; depth0 < 2; depth0++) {
		sc = spd_camera();
		if (depth0)
			sc.depth = 0;
		CHECK(cam_init(&c, &sc, W, H) == 0);
		for (int n = 1; n <= 4; n++)
			for (int i = 0; i < n_pos; i++) {
				double px[4], py[4];
				vec3 d[4];
				struct ray r4[4], u4[4];
				for (int k = 0; k < n; k++) {
					px[k] = pos[(i + k) % n_pos];
					py[k] = pos[(i + 3 * k + 1) % n_pos];
					d[k] = v3_add(c.vd, v3_add(cam_col(&c, px[k]), cam_row(&c, py[k])));
				}
				cam_ray4(&c, px, py, n, r4);
				cam_unit4(&c, d, n, u4);
				for (int k = 0; k < n; k++) {
					struct ray one = cam_ray(&c, px[k], py[k]);
					CHECK(memcmp(&one, &r4[k], sizeof one) == 0);
					CHECK(memcmp(&one, &u4[k], sizeof one) == 0);
				}
			}
		/* the film centre with depth 0: a zero direction */
		double cx[4] = { W / 2.0 }, cy[4] = { H / 2.0 };
		struct ray z[4];
		cam_ray4(&c, cx, cy, 1, z);
		CHECK(depth0 ? z[0].d.x == 0 && z[0].d.y == 0 && z[0].d.z == 0 : fabs(v3_len(z[0].d) - 1) < 1e-15);
	}
	/* a NaN position: NaN directions, both ways */
	sc = spd_camera();
	CHECK(cam_init(&c, &sc, W, H) == 0);
	double nx[4] = { NAN, 3.5 }, ny[4] = { 2.5, NAN };
	struct ray nr[4];
	cam_ray4(&c, nx, ny, 2, nr);
	for (int k = 0; k < 2; k++) {
		struct ray one = cam_ray(&c, nx[k], ny[k]);
		CHECK(isnan(one.d.x) && isnan(nr[k].d.x) && isnan(nr[k].d.y) && isnan(nr[k].d.z));
		CHECK(memcmp(&one.o, &nr[k].o, sizeof one.o) == 0 && nr[k].tmin == 0 && isinf(nr[k].tmax));
	}

	/* degenerate cameras are refused */
	sc.drop_line = v3_scale(view, 2);
	CHECK(cam_init(&c, &sc, 10, 10) < 0);
	sc = spd_camera();
	sc.look_at = sc.look_from;
	CHECK(cam_init(&c, &sc, 10, 10) < 0);
	TEST_MAIN_END();
}
