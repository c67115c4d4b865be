/*
 * shade_tbox.h - TRANSPARENT BOXES. In a scene with transparent materials a
 * shadow ray needs its closest hit (shade.c's transmittance): a transparent
 * surface in front lets light through, an opaque one does not. But a
 * segment that meets no surface whose material may be transparent has
 * only opaque hits, so its closest hit, if any, is opaque: its
 * transmittance is then 0 exactly when accel_occluded says "occluded"
 * (anything hit in (tmin, tmax) blocks), and what came through so far
 * otherwise: the answer of the cheaper any-hit query, or of a packet.
 *
 * shade_tboxes_find puts a box around the root objects whose resolved
 * material may be transparent (transparency > 0 or NaN, or a shader, whose
 * pattern may pick or blend in a transparent material): one box per
 * material, SHADE_TBOXES at most. Only triangles and RAW meshes get a box:
 * their watertight test accepts a line only within a few rounding errors of
 * the triangle, relative to the vertices' and the origin's coordinates, and
 * the boxes' margins (TBOX_MARGIN of the box's largest coordinate,
 * TBOX_DYN of the ray's origin and direction, added at each test) are far
 * above that. A root that may show a transparent surface but gets no box
 * (another primitive, a plane, CSG or an instance holding a possibly
 * transparent material) turns the shortcut off (all false). The margins are
 * below accel_offset_point's 1e-9, so that a ray leaving a transparent mesh
 * through its outer face gets out of its box.
 */
#ifndef PORTRAY_SHADE_TBOX_H
#define PORTRAY_SHADE_TBOX_H

#include <stdbool.h>
#include <stdint.h>

#include "common/accel.h"
#include "common/scene.h"
#include "common/vec.h"

/* at most this many boxes, one per material, the last one taking the rest */
#define SHADE_TBOXES 8
#define TBOX_MARGIN 0x1p-32
#define TBOX_DYN 0x1p-40

struct shade_tboxes {
	/* when all, every surface whose material may be transparent lies
	 * inside one of box[0 .. n-1] */
	bool all;
	uint32_t n;
	struct {
		vec3 c, e; /* centre and half-size */
	} box[SHADE_TBOXES];
};

/* Fills *t for scene s, which has a material with transparency > 0 when
 * any_transparent (none: the shortcut is off, no scene is looked at). */
void shade_tboxes_find(const struct scene *s, bool any_transparent, struct shade_tboxes *t);

/*
 * Whether the segment of shadow ray r (t in [0, 1]) may meet a surface
 * whose material may be transparent: false only when it provably does
 * not. The separating-axis test of a segment and a box (the box's three
 * axes, and the segment's direction crossed with each), with r's rounding
 * margin added to the boxes. Inline: it runs for every shadow ray of a
 * scene with transparent materials.
 */
static inline bool shade_tboxes_may_cross(const struct shade_tboxes *t, const struct ray *r)
{
	if (!t->all)
		return true;
	vec3 h = v3_scale(r->d, 0.5), q = v3_add(r->o, h); /* half the segment, its middle */
	double ax = fabs(h.x), ay = fabs(h.y), az = fabs(h.z);
	double mu = TBOX_DYN * (v3_maxabs(r->o) + 2 * v3_maxabs(h)) + 0x1p-900;
	if (!(mu < 0x1p-60 * 0x1p900))
		return true; /* NaN, infinite, or large enough to overflow below */
	for (uint32_t j = 0; j < t->n; j++) {
		vec3 m = v3_sub(q, t->box[j].c);
		double ex = t->box[j].e.x + mu, ey = t->box[j].e.y + mu, ez = t->box[j].e.z + mu;
		if (fabs(m.x) > ex + ax || fabs(m.y) > ey + ay || fabs(m.z) > ez + az)
			continue;
		if (fabs(m.y * h.z - m.z * h.y) > ey * az + ez * ay)
			continue;
		if (fabs(m.z * h.x - m.x * h.z) > ex * az + ez * ax)
			continue;
		if (fabs(m.x * h.y - m.y * h.x) > ex * ay + ey * ax)
			continue;
		return true;
	}
	return false;
}

#endif
