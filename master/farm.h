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

struct journal;

/*
 * Renders the encoded scene (scene_len bytes, proto_scene_encode, whose
 * proto_scene_hash is scene_hash: hashed once per render; scene is NULL for
 * a local render, which keeps no encoding) at w x h
 * into image (w*h*render_pixel_bytes(px) bytes, pixels of type px as
 * render.h states them, rows top to bottom; with o->region only the
 * region's pixels are traced and written, the rest left as they were) on
 * the workers named in
 * o (-w, --workers-file, --accept), with local threads (o->threads) joining
 * in unless o->no_local. With no workers named and no --accept it is the
 * local render: the same loop, scheduler and tile pool with the local
 * threads alone (never a second renderer). *finished: the tiles stored. r must be built from the decoding of those very bytes (one
 * road for pixels: what the master traces is what the workers trace), for w
 * x h; build_s is how long that build took (the workers' build deadline
 * follows it). Every pixel is the same as a local render's: worker tiles are
 * audited (o->audit: each worker's first few and a sampled fraction
 * re-rendered with r on the local threads, or on one audit-only thread with
 * o->no_local) and a worker caught returning wrong pixels is dropped with
 * every tile it delivered rendered again; a worker silent, stalled in any
 * step of its handshake, transfer or build past its deadline, or holding
 * tiles without results far past its usual tile time is dropped. Stops early
 * when *cancel becomes non-zero (unfinished tiles stay as they were in
 * image). Farm faults go to stderr always; progress and a summary unless
 * o->quiet. Returns 0 on success, ERRLEVEL_LEVEL2 when the local threads
 * found no memory for their tiles (what was done is in image), or an exit code (EXIT_TOO_FEW when
 * fewer than o->min_workers workers joined, EXIT_NO_WORKERS when
 * --no-local and every worker is lost, EXIT_USAGE for a bad worker list or
 * secret file) after printing a message on stderr. jn (may be NULL): the
 * journal (master/journal.h): its tiles are taken as done before anything
 * is traced, and what is stored from then on is checkpointed into it.
 */
int farm_render(const struct master_opts *o, const uint8_t *scene, size_t scene_len, const uint8_t *scene_hash,
		double build_s, const struct renderer *r, uint32_t w, uint32_t h, uint8_t *image, enum render_pixel px,
		atomic_int *cancel, uint32_t *finished, struct journal *jn);

#endif
