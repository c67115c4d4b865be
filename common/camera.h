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
 * Thin-lens eye ray through (px, py): the lens is centred on look-from, in the
 * plane of right and down; (lu, lv) is the point on the aperture in world
 * units along right and down. Points at distance focal (measured along the
 * view axis) are in focus: every lens point's ray passes through the point
 * where the pinhole ray meets the plane at distance focal along the view
 * axis. Unit direction, tmin 0, tmax infinity.
 */
struct ray cam_lens_ray(const struct cam *c, double px, double py, double lu, double lv, double focal);

#endif
