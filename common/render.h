/*
 * render.h - camera, filters and the tile renderer: the one renderer used
 * both by the master (locally) and by workers.
 *
 * A pixel's value is a function of the scene and the pixel alone, so a tile
 * rendered anywhere (any thread, any tile size, any worker) has the same bytes.
 */
#ifndef PORTRAY_RENDER_H
#define PORTRAY_RENDER_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "common/scene.h"

struct tile_rect {
	uint32_t x, y, w, h; /* pixels; (0,0) is the top-left of the image */
};

struct renderer;

/*
 * Builds the acceleration and shading state for a scene (which must outlive
 * it). Returns 0, or an error level (ERRLEVEL_*) with err filled in.
 */
int renderer_new(const struct scene *s, struct renderer **out, struct scene_error *err);

/* What renderer_new_cancellable returns when it gave up: distinct from
 * every error level (those are positive). */
#define RENDERER_CANCELLED (-2)
/*
 * renderer_new, giving up when *cancel (may be NULL: never) becomes
 * non-zero: the acceleration build polls it in its loops (a few
 * milliseconds of work apart at most, whatever the scene), and then
 * everything built so far is freed, *out is NULL, err holds "cancelled"
 * (level ERRLEVEL_FATAL, for callers that print it) and the return value is
 * RENDERER_CANCELLED. A build that finished is used even if the flag is set
 * afterwards.
 */
int renderer_new_cancellable(const struct scene *s, struct renderer **out, struct scene_error *err,
			     atomic_int *cancel);
void renderer_free(struct renderer *r);

/* Image size as the scene states it (or as overridden with renderer_set_size). */
void renderer_size(const struct renderer *r, uint32_t *w, uint32_t *h);
/* --size WxH overrides the image statement; call before rendering. */
int renderer_set_size(struct renderer *r, uint32_t w, uint32_t h);

/*
 * The pixels' revision: raised by every change that makes some scene's
 * pixels differ, so that the farm's build check (proto_build_id) keeps
 * builds that draw different pixels apart even at one version number.
 * 2: canonical ties between coincident surfaces (docs/language.md).
 * 3: shadow rays through transparent surfaces take every surface on the
 *    straight segment to the light (SHADOW CROSSINGS, accel.h), where they
 *    stepped from hit to hit, each step offset and aimed anew.
 * 4: the Phong highlight's power is xm_pow_lite (LITE POW, docs/maths.md),
 *    within a few ulps of xm_pow's value instead of the same bits.
 * 5: a ray that leaves the plane of a flat triangle, or never reaches it,
 *    skips that triangle's test whatever its direction (FLAT TRIANGLES,
 *    accel_trace.h), where only rays steeper than 45 degrees to the plane
 *    did; a shallower one could get a rounding hit (acne) from a triangle
 *    about 10^6 times larger than its distance.
 */
#define RENDER_PIXEL_REV 5

/*
 * What a tile's pixels are: chosen per render from the output format (the
 * master's) and carried by the farm's wire as they are, so a pixel's bytes
 * are the same on every host, thread, tile size and worker.
 *   RENDER_RGB8:   3 bytes, the filter's colour clamped and rounded
 *                  (filter_quantise): what 8-bit PNG and PPM hold.
 *   RENDER_RGBF32: 12 bytes, the filter's colour before clamping, each
 *                  channel converted once from double to float (nearest)
 *                  and stored little-endian whatever the host: for 16-bit
 *                  PNG, PFM and OpenEXR (values below 0 and above 1 kept).
 */
enum render_pixel { RENDER_RGB8 = 0, RENDER_RGBF32 = 1 };
#define RENDER_PIXEL_MAX_BYTES 12
static inline uint32_t render_pixel_bytes(enum render_pixel px) { return px == RENDER_RGBF32 ? 12u : 3u; }

/*
 * Renders one tile into rgb (t.w*t.h*3 bytes, rows top to bottom). Pixels of
 * the rectangle outside the image are written black. Thread-safe.
 */
void renderer_tile(const struct renderer *r, struct tile_rect t, uint8_t *rgb);
/*
 * As renderer_tile, but gives up when *cancel (may be NULL: never) becomes
 * non-zero, within a few milliseconds of work whatever the scene: the flag
 * is polled per four pixels of a row (per 2x2 block for filter standard),
 * per filter sample or packet of four, per light of a shading point, and
 * inside the traversal of a ray, so one ray through 2^63 nested instances
 * is abandoned too (common/cancel.h). Returns 1 when the whole tile is in
 * rgb, exactly as renderer_tile gives it; 0 when it gave up (rgb then holds
 * a partial, partly wrong tile: do not use it).
 */
int renderer_tile_cancellable(const struct renderer *r, struct tile_rect t, uint8_t *rgb,
			      atomic_int *cancel);
/* renderer_tile_cancellable with pixels of type px: out holds t.w * t.h *
 * render_pixel_bytes(px) bytes (black is all zero bytes in either type). */
int renderer_tile_px(const struct renderer *r, struct tile_rect t, enum render_pixel px, uint8_t *out,
		     atomic_int *cancel);

/* Eye rays traced by this renderer so far, over all threads (for Mrays/s). */
uint64_t renderer_rays(const struct renderer *r);
/* Mirror and transmitted rays traced by this renderer so far, at every
 * depth, over all threads (shadow rays not counted; shade_take_secondary). */
uint64_t renderer_secondary_rays(const struct renderer *r);
/* Number of filters ignored and their warnings (see filter_warnings): the
 * master prints them once. buf is NUL-terminated, truncated to n. */
int renderer_warnings(const struct renderer *r, char *buf, size_t n);

/* Local thread pool over tiles. fn is called after every finished tile, by
 * the thread that finished it, one call at a time (under a mutex). */
struct render_progress {
	void (*fn)(void *arg, uint64_t tiles_done, uint64_t tiles_total);
	void *arg;
};
/*
 * Renders the whole image into image (w*h*3, renderer_size) with `threads`
 * threads (0 = all cores) and square tiles of `tile` pixels (0 = TILE_DEFAULT;
 * tiles.h: the pool and the tiling every renderer shares), handed out in
 * row-major order. Stops early when *cancel (may be NULL) becomes
 * non-zero: tiles not finished are left untouched in image (callers start
 * from black). progress may be NULL. Returns the number of tiles finished.
 */
uint64_t render_image(const struct renderer *r, int threads, uint32_t tile, uint8_t *image,
		      const struct render_progress *progress, atomic_int *cancel);

/* Number of tiles render_image uses for a w x h image with tiles of side tile. */
uint64_t render_tile_count(uint32_t w, uint32_t h, uint32_t tile);

/* Number of online CPUs (at least 1). */
int render_ncpus(void);

#endif
