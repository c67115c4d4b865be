/*
 * tiles.h - the one tiling of an image and the one pool of tracer threads.
 *
 * Every renderer of portray cuts images the same way (tiling_*) and traces
 * tiles on the same pool (tile_pool_*): the local render, the master's own
 * threads beside its workers, and a worker's tracers. They differ only in
 * where tiles come from and where pixels go, which is the tile_source a pool
 * is given. Pixels never depend on the tiling (render.h), so any tile size
 * gives the same image; the tiling only decides the unit of work.
 */
#ifndef PORTRAY_TILES_H
#define PORTRAY_TILES_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "common/render.h"

/* tile side when none is asked for: small enough to balance threads and
 * workers near the end of a render, large enough that the per-tile cost
 * (a message each way on the farm) stays a few percent */
#define TILE_DEFAULT 32u
/* the largest side: a 1024x1024 tile is 3 MiB of RGB8 (12 MiB of RGBF32),
 * one wire frame */
#define TILE_MAX_SIDE 1024u

/* An image cut into square tiles of side `side`, row-major, the last
 * column and row narrower where the image ends. A tiling may cover a
 * region of the image only (--region): its tiles start at (x0, y0) and end
 * at x1, y1; their rectangles stay in the whole image's coordinates. */
struct tiling {
	uint32_t w, h, side;    /* w x h: the whole image */
	uint32_t nx, ny, n;     /* tiles across, down, in all */
	uint32_t x0, y0, x1, y1; /* the region covered (x1, y1 excluded): 0, 0, w, h unless a region */
};

/* Cuts w x h into tiles of side (0: TILE_DEFAULT; clamped to 1..TILE_MAX_SIDE). */
void tiling_init(struct tiling *tg, uint32_t w, uint32_t h, uint32_t side);
/* Cuts the region x0..x1-1, y0..y1-1 of a w x h image (the caller checked it
 * is inside and not empty) into tiles of side, the first at (x0, y0). */
void tiling_init_region(struct tiling *tg, uint32_t w, uint32_t h, uint32_t side, uint32_t x0, uint32_t y0,
			uint32_t x1, uint32_t y1);
/* Rectangle of tile i (i < tg->n). */
struct tile_rect tiling_rect(const struct tiling *tg, uint32_t i);

/* One unit of work handed to a pool thread. */
struct tile_work {
	const struct renderer *r;
	struct tile_rect rect;
	atomic_int *cancel;     /* the tile is abandoned when it becomes non-zero; may be NULL */
	uint64_t id;            /* the source's own: tile index, ... */
	void *ptr;              /* the source's own: job, ... */
	double trace_s;         /* set by the pool before done: wall time spent tracing */
	enum render_pixel px;   /* the pixels wanted (render.h); 0 is RENDER_RGB8 */
};

/* Where a pool's tiles come from and where their pixels go. */
struct tile_source {
	/*
	 * Blocks until there is work: returns 1 with *w filled, or 0 when the
	 * calling thread should end. Called with no lock of the pool's held,
	 * on the pool's thread (so a source may do other slow work here, as
	 * a worker builds scenes).
	 */
	int (*take)(void *ctx, struct tile_work *w);
	/*
	 * After tracing w: ok 1 when *rgb holds the whole tile (w->rect.w *
	 * w->rect.h * render_pixel_bytes(w->px) bytes, rows top to bottom,
	 * kept as bytes whatever the type), 0 when it was abandoned
	 * (cancelled), -1 when no buffer could be allocated. done may keep
	 * the buffer by setting *rgb = NULL (the pool allocates another).
	 */
	void (*done)(void *ctx, const struct tile_work *w, uint8_t **rgb, int ok);
	void *ctx;
};

struct tile_pool;

/*
 * Starts `threads` tracer threads (0: all cores) over src. Returns the pool,
 * or NULL when no thread could be started (fewer than asked is fine: slower,
 * the same pixels). tile_pool_threads says how many run.
 */
struct tile_pool *tile_pool_start(int threads, const struct tile_source *src);
int tile_pool_threads(const struct tile_pool *p);
/* Waits until every thread has ended (its take returned 0), then frees p. */
void tile_pool_join(struct tile_pool *p);

/*
 * Traces on `threads` threads counting the caller (0: all cores) until
 * every take returns 0: tile_pool_start + the caller working + join.
 * Returns the number of threads that worked (at least 1).
 */
int tile_pool_run(int threads, const struct tile_source *src);

#endif
