/*
 * accel.h - geometry and acceleration: the scene model's objects turned into
 * intersectable primitives under a multi-level BVH: each define is built
 * once into its own BVH and referenced by instances (a float inverse
 * transform, its 3x3 part shared, and an object index: 20 bytes); defines
 * nest to LIM_DEFINE_DEPTH, CSG to LIM_CSG_DEPTH (accel_build refuses
 * deeper graphs).
 *
 * Owner of the geometry: common/geom*.c, common/bvh.c, common/csg.c,
 * common/accel*.c. Primitive mappings and normals: the comment at the top of
 * common/geom.c; the epsilon strategy: common/accel.c.
 * The accel keeps a pointer to the scene; the scene must outlive it.
 */
#ifndef PORTRAY_ACCEL_H
#define PORTRAY_ACCEL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "common/scene.h"

struct ray {
	vec3 o, d;         /* origin and direction (need not be unit length) */
	double tmin, tmax; /* hits accepted with tmin < t < tmax; a ray is a half-line:
			      a negative tmin counts as 0 */
};

struct accel;

struct hit {
	double t;          /* ray parameter of the hit */
	vec3 p;            /* world-space point */
	vec3 n;            /* world shading normal, unit length (interpolated for smooth
			      triangles); NOT flipped toward the ray */
	vec3 ng;           /* world geometric normal, unit, same side as n */
	vec3 mp;           /* the point in the object space of the object that owns the
			      material (type I shaders: textures move with objects);
			      only after accel_hit_surface */
	double u, v;       /* surface mapping in object-space length units (type II
			      shaders; docs/rendering.md gives each primitive's mapping);
			      only after accel_hit_surface */
	uint32_t material; /* resolved material index, SCENE_NONE = default material */
	uint32_t object;   /* object index of the leaf object hit */
	/* private to accel*.c: how accel_hit_surface completes u, v and mp
	 * (surf_fn == NULL: they are complete). A hit made by hand (a test's
	 * mock accel) must set surf_fn = NULL if shading may ask for them. */
	void (*surf_fn)(const struct accel *a, struct hit *h);
	const void *surf;
	uint32_t surf_kind, surf_idx;
	double surf_b1, surf_b2;
};

struct accel;

struct accel_stats {
	double build_seconds;
	size_t bytes;            /* memory held by the accel */
	uint64_t n_prims;        /* leaf primitives built (triangles count one each) */
	uint64_t n_instances;    /* instance references */
	uint64_t n_nodes;        /* BVH nodes over all levels */
	size_t instance_bytes;   /* size of one instance reference record */
};

/* What accel_build returns when it gave up (CANCEL_RETURN of cancel.h). */
#define ACCEL_CANCELLED (-2)
/*
 * Builds the acceleration for the scene's roots. Returns 0 or an error
 * level; or ACCEL_CANCELLED, with err->msg "cancelled", everything freed and
 * *out NULL, when the calling thread's cancel flag (cancel.h) was seen set:
 * the build polls it in its loops, every few milliseconds of work at most.
 */
int accel_build(const struct scene *s, struct accel **out, struct scene_error *err);
void accel_free(struct accel *a);
void accel_get_stats(const struct accel *a, struct accel_stats *st);
/* Bounds of everything bounded in the scene (infinite planes left out);
 * returns false when nothing is bounded. */
bool accel_bounds(const struct accel *a, vec3 *lo, vec3 *hi);

/* The queries below poll the calling thread's cancel flag (cancel.h) where
 * one ray's work can grow without bound (nested instances, long lists);
 * once a poll has seen it set they answer "no hit" or "not occluded"
 * without looking further, and the caller must discard what it computes
 * from them (cancel_seen). Without a flag, or until it is seen, they are
 * exact. */

/* Closest hit in (r->tmin, r->tmax); fills *h and returns true if any. Thread-safe.
 * h->u, h->v and h->mp may be left 0 until accel_hit_surface(a, h): only
 * shaders read them, and the sphere mapping (atan2, asin) costs as much as
 * the rest of a primary ray. */
bool accel_intersect(const struct accel *a, const struct ray *r, struct hit *h);
/* The closest hits of four rays at once: hit[i] and h[i] are exactly what
 * accel_intersect(a, &r[i], &h[i]) gives, bit for bit (ties are canonical,
 * see accel_trace.h). Faster when the rays are neighbours that visit the
 * same nodes, as the eye rays of a 2x2 block of pixels do. Thread-safe. */
void accel_intersect4(const struct accel *a, const struct ray r[4], struct hit h[4], bool hit[4]);
/* The closest hits of four (sixteen) packets of four rays (r[4 * j ...]:
 * packet j): each what accel_intersect gives, bit for bit. Faster than
 * four accel_intersect4 (accel_intersect16) when the rays share one origin
 * (the same bits), as the eye rays of a 4x4 (8x8) block of a pinhole
 * camera do: the nodes are tested once for all of them, a leaf by each
 * packet that may hit it. Thread-safe. */
void accel_intersect16(const struct accel *a, const struct ray r[16], struct hit h[16], bool hit[16]);
void accel_intersect64(const struct accel *a, const struct ray r[64], struct hit h[64], bool hit[64]);
/* Completes h->u, h->v and h->mp of a hit that accel_intersect or
 * accel_intersect_brute returned with the same accel (the values are those
 * an eager computation gives, bit for bit); does nothing when they are
 * complete already, so calling it twice is harmless. Thread-safe. */
static inline void accel_hit_surface(const struct accel *a, struct hit *h)
{
	if (h->surf_fn) /* inline, so shading links without accel.o (test mocks) */
		h->surf_fn(a, h);
}
/* True if anything is hit in (r->tmin, r->tmax): early exit, for shadow rays. */
bool accel_occluded(const struct accel *a, const struct ray *r);

/* "No blocker remembered" for the hints below. */
#define ACCEL_NO_HINT UINT32_MAX
/*
 * accel_occluded with a last-blocker hint: *hint names an object part of
 * the root level that blocked an earlier ray (ACCEL_NO_HINT: none), which
 * is tested before the tree; on "occluded" *hint names what blocked this
 * ray. The answer is accel_occluded's whatever *hint holds (a hint from
 * another accel only costs a test): anything hit in (tmin, tmax) blocks.
 * Keep one hint per thread and light: neighbouring shadow rays toward one
 * light tend to be blocked by the same object. Thread-safe.
 */
bool accel_occluded_hint(const struct accel *a, const struct ray *r, uint32_t *hint);
/*
 * accel_occluded_hint for a shadow ray toward the scene's point light
 * number light: r->d = (the light's position) - r->o, tmin >= 0, tmax <= 1
 * (the light). The same answer; faster where the accel made a light
 * buffer for that light (LIGHT BUFFERS, accel_int.h). Any other ray gets
 * accel_occluded_hint's answer. Thread-safe.
 */
bool accel_occluded_light(const struct accel *a, uint32_t light, const struct ray *r, uint32_t *hint);
/* Whether point light number light has a light buffer (accel_occluded_light
 * answers its shadow rays from one). */
bool accel_light_buffered(const struct accel *a, uint32_t light);
/*
 * accel_occluded_hint for four rays at once (occ[i] is what
 * accel_occluded(a, &r[i]) gives), sharing one hint: faster when the rays
 * are neighbours, as the shadow rays of a 2x2 block of pixels toward one
 * point light are. Thread-safe.
 */
void accel_occluded4(const struct accel *a, const struct ray r[4], bool occ[4], uint32_t *hint);

/*
 * SHADOW CROSSINGS: the surfaces a shadow segment crosses, for the light
 * that transparent ones let through (docs/rendering.md, Shadows). Every
 * hit in (tmin, tmax) along the ray, each primitive's every one (a sphere
 * crossed is two), counts; hits at one t count once, as the surface of
 * the least key there (CANONICAL TIES, accel_trace.h); an opaque surface
 * anywhere on the segment blocks it, so the query stops at the first one it
 * meets. What a surface lets through is the filter's: f->opaque[m] != 0
 * says material m (m < f->n_materials; the default material at
 * f->n_materials) is opaque everywhere, so its hits need no more; at any
 * other hit, completed as accel_intersect would give it (world space, u,
 * v and mp through accel_hit_surface), f->pass says whether it is opaque
 * there, and if not what it lets through.
 */
#define ACCEL_CROSS_MAX 64
struct accel_pass {
	vec3 col;  /* tran-colour, clamped at 0 */
	double td; /* transparency, in (0, 1] */
};
struct accel_crossings {
	int n; /* in order of t; x[k].key is the surface's tie key */
	struct accel_crossing {
		double t;
		uint64_t key;
		struct accel_pass p;
	} x[ACCEL_CROSS_MAX];
};
struct accel_cross_filter {
	const uint8_t *opaque;
	uint32_t n_materials;
	bool (*pass)(const void *ctx, struct hit *h, struct accel_pass *p);
	const void *ctx;
};
/* The crossings of r's segment into *x, in order of t; false when an
 * opaque surface blocks it or more than ACCEL_CROSS_MAX crossings lie on
 * it (x is then undefined). *hint is as accel_occluded_hint's: a
 * reference that blocked an earlier segment, tested first; on "blocked" it
 * may name the blocker. Once a cancel poll has seen its flag (above), the
 * answer is meaningless. Thread-safe. */
bool accel_cross(const struct accel *a, const struct ray *r, const struct accel_cross_filter *f,
		 struct accel_crossings *x, uint32_t *hint);
/* accel_cross of four rays at once (open[i] and x[i] are what it gives
 * r[i], bit for bit), sharing one hint: faster for neighbours, as the
 * shadow rays of a 2x2 block toward one light are. Thread-safe. */
void accel_cross4(const struct accel *a, const struct ray r[4], const struct accel_cross_filter *f,
		  struct accel_crossings x[4], bool open[4], uint32_t *hint);

/*
 * Start point for a secondary ray leaving a hit at p (geometric normal ng)
 * in direction dir: p moved off the surface along ng, to the side dir
 * leaves by, by 1e-9 * (1 + max |p_i|). Use it with tmin = 0 to avoid
 * self-intersection acne (see the epsilon strategy in accel.c).
 */
vec3 accel_offset_point(vec3 p, vec3 ng, vec3 dir);

/* Brute force reference (no BVH), for tests: same contract as accel_intersect. */
bool accel_intersect_brute(const struct accel *a, const struct ray *r, struct hit *h);

/* Whether the AVX2 paths run: single rays' node tests (WIDE NODES IN AVX2,
 * accel_box.h) and the eye hits' shading (DIRECT IN FOURS, shade.c): the
 * CPU and its OS support AVX2 and the environment's PORTRAY_SIMD is not
 * "sse2" (which keeps the SSE2 ones, to compare them: the two give the
 * same bytes). Asked by each accel_build and shade context. */
bool accel_use_avx2(void);

#endif
