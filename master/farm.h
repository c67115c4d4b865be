/*
 * farm.h - rendering on a farm of portray-worker daemons (master/farm.c).
 */
#ifndef PORTRAY_FARM_H
#define PORTRAY_FARM_H

#include <stdatomic.h>
#include <stdint.h>

#include "common/render.h"
#include "common/scene.h"
#include "master/master.h"

/*
 * Renders scene s at w x h into image (w*h*3 bytes, RGB8, rows top to bottom)
 * on the workers named in o (-w, --workers-file), with local threads (o->threads,
 * using renderer r, which must be built for w x h) joining in unless o->no_local.
 * Every pixel is the same as a local render's: worker tiles are audited
 * (o->audit: each worker's first few and a sampled fraction re-rendered with r
 * on the local threads, or on one audit-only thread with o->no_local) and a
 * worker caught returning wrong pixels is dropped with every tile it delivered
 * rendered again; a worker holding tiles without results far past its usual
 * tile time is dropped as hung. Stops early when *cancel becomes
 * non-zero (unfinished tiles stay as they were in image). Progress and a summary
 * go to stderr unless o->quiet. Returns 0 on success, or an exit code
 * (EXIT_NO_WORKERS when --no-local and every worker is lost, EXIT_USAGE for a
 * bad worker list or secret file) after printing a message on stderr.
 */
int farm_render(const struct master_opts *o, const struct scene *s, struct renderer *r, uint32_t w,
		uint32_t h, uint8_t *image, atomic_int *cancel);

#endif
