/*
 * camera.h - the pinhole camera and the thin lens: pixel positions to eye rays.
 *
 * Geometry (docs/camera.md): view = look-at - look-from;
 * right = normalize(drop-line x view); down = normalize(view x right).
 * A continuous pixel position (px, py), px in [0, W) from the left and py in
 * [0, H) from the top (pixel (i, j)'s centre is (i + 0.5, j + 0.5)), lies on
 * the film at
 *   look_from + depth*view_unit + (px/W - 0.5)*x_size*right + (py/H - 0.5)*y_size*down
 * and the eye ray runs from look-from through that film point.
 */
#ifndef PORTRAY_CAMERA_H
#define PORTRAY_CAMERA_H

#include <stdint.h>

#include "common/accel.h"
#include "common/scene.h"

struct cam {
	vec3 from;       /* look-from: the pinhole, the lens centre */
	vec3 view;       /* unit view direction */
	vec3 right;      /* unit: the image's rightward direction */
	vec3 down;       /* unit: the image's downward direction */
	double depth;    /* film distance */
	double x_size;   /* film width, spread over w pixels */
	double y_size;   /* film height, spread over h pixels */
	uint32_t w, h;   /* image size in pixels */
	vec3 vd;         /* view * depth: look-from to the film centre */
};

/*
 * Sets up c for camera sc and an image of w x h pixels (both >= 1). Returns 0,
 * or -1 when the camera is degenerate (look-at == look-from, drop-line zero or
 * parallel to the view): the scene builder already refuses those.
 */
int cam_init(struct cam *c, const struct scene_camera *sc, uint32_t w, uint32_t h);

/* The film point of continuous pixel position (px, py). */
vec3 cam_film_point(const struct cam *c, double px, double py);

/* Pinhole eye ray through (px, py): origin look-from, unit direction toward
 * the film point, tmin 0, tmax infinity. */
struct ray cam_ray(const struct cam *c, double px, double py);

/*
 * The two parts of the direction toward the film point of (px, py):
 * cam_col(px) = right * ((px / w - 0.5) * x_size) and cam_row(py) = down *
 * ((py / h - 0.5) * y_size); the direction is vd + (cam_col + cam_row),
 * exactly as cam_ray computes it. A grid of positions shares its columns
 * and rows, so it pays a division per column and per row, not per ray.
 */
vec3 cam_col(const struct cam *c, double px);
vec3 cam_row(const struct cam *c, double py);

/*
 * Pinhole eye rays r[k], k < n <= 4, with directions d[k] (look-from to a
 * film point, not unit) made unit as cam_ray makes them (v3_norm): with
 * d[k] = vd + (cam_col(px) + cam_row(py)), r[k] is cam_ray(c, px, py) bit
 * for bit. The square roots and divisions go two rays at a time (SSE2:
 * packed IEEE operations, the same results as the scalar ones).
 */
void cam_unit4(const struct cam *c, const vec3 d[4], int n, struct ray r[4]);

/* cam_ray of n <= 4 positions (px[k], py[k]) into r[k], bit for bit, with
 * the divisions and square roots two rays at a time (cam_unit4). */
void cam_ray4(const struct cam *c, const double px[4], const double py[4], int n, struct ray r[4]);

/*
 * Thin-lens eye ray through (px, py): the lens is centred on look-from, in the
 * plane of right and down; (lu, lv) is the point on the aperture in world
 * units along right and down. Points at distance focal (measured along the
 * view axis) are in focus: every lens point's ray passes through the point
 * where the pinhole ray meets the plane at distance focal along the view
 * axis. Unit direction, tmin 0, tmax infinity.
 */
struct ray cam_lens_ray(const struct cam *c, double px, double py, double lu, double lv, double focal);

#endif
