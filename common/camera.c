/*
 * camera.c - the pinhole camera and the thin lens (camera.h, docs/camera.md).
 */
#include "common/camera.h"

#include <math.h>

int cam_init(struct cam *c, const struct scene_camera *sc, uint32_t w, uint32_t h)
{
	vec3 view = v3_sub(sc->look_at, sc->look_from);
	vec3 right = v3_cross(sc->drop_line, view);
	if (!(v3_len(view) > 0) || !(v3_len(right) > 0) || w == 0 || h == 0)
		return -1;
	c->from = sc->look_from;
	c->view = v3_norm(view);
	c->right = v3_norm(right);
	c->down = v3_norm(v3_cross(view, c->right));
	c->depth = sc->depth;
	c->x_size = sc->x_size;
	c->y_size = sc->y_size;
	c->w = w;
	c->h = h;
	return 0;
}

/* Direction from look-from to the film point of (px, py) (not unit). */
static vec3 cam_dir(const struct cam *c, double px, double py)
{
	double fx = (px / c->w - 0.5) * c->x_size;
	double fy = (py / c->h - 0.5) * c->y_size;
	return v3_add(v3_scale(c->view, c->depth), v3_add(v3_scale(c->right, fx), v3_scale(c->down, fy)));
}

vec3 cam_film_point(const struct cam *c, double px, double py) { return v3_add(c->from, cam_dir(c, px, py)); }

struct ray cam_ray(const struct cam *c, double px, double py)
{
	struct ray r;
	r.o = c->from;
	r.d = v3_norm(cam_dir(c, px, py));
	r.tmin = 0.0;
	r.tmax = INFINITY;
	return r;
}

struct ray cam_lens_ray(const struct cam *c, double px, double py, double lu, double lv, double focal)
{
	vec3 d = cam_dir(c, px, py);
	/* the pinhole ray meets the focal plane at from + d * (focal / depth) */
	vec3 focus = v3_add(c->from, v3_scale(d, focal / c->depth));
	vec3 lens = v3_add(c->from, v3_add(v3_scale(c->right, lu), v3_scale(c->down, lv)));
	struct ray r;
	r.o = lens;
	r.d = v3_norm(v3_sub(focus, lens));
	r.tmin = 0.0;
	r.tmax = INFINITY;
	return r;
}
