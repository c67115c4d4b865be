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
#include <stdint.h>

#include "common/scene.h"

struct tile_rect {
	uint32_t x, y, w, h; /* pixels; (0,0) is the top-left of the image */
};

struct renderer;

/* Builds the acceleration and shading state for a scene (which must outlive it). */
int renderer_new(const struct scene *s, struct renderer **out, struct scene_error *err);
void renderer_free(struct renderer *r);

/* Image size as the scene states it (or as overridden with renderer_set_size). */
void renderer_size(const struct renderer *r, uint32_t *w, uint32_t *h);
/* --size WxH overrides the image statement; call before rendering. */
int renderer_set_size(struct renderer *r, uint32_t w, uint32_t h);

/* Renders one tile into rgb (w*h*3 bytes, rows top to bottom). Thread-safe. */
void renderer_tile(const struct renderer *r, struct tile_rect t, uint8_t *rgb);

/* Local thread pool over tiles. */
struct render_progress {
	void (*fn)(void *arg, uint64_t tiles_done, uint64_t tiles_total);
	void *arg;
};
/*
 * Renders the whole image into image (w*h*3) with `threads` threads (0 = all
 * cores) and square tiles of `tile` pixels. Stops early when *cancel becomes
 * non-zero; done[] (one byte per tile, may be NULL) marks finished tiles.
 * Returns the number of tiles finished.
 */
uint64_t render_image(const struct renderer *r, int threads, uint32_t tile, uint8_t *image,
		      const struct render_progress *progress, atomic_int *cancel);

/* Number of online CPUs (at least 1). */
int render_ncpus(void);

#endif
