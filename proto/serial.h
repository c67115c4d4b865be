/*
 * serial.h - the scene model as bytes: a versioned, byte-order-independent
 * binary form of a complete struct scene, so a worker rebuilds exactly the
 * model the master parsed (docs/protocol.md, "Scene encoding").
 *
 * Decoding trusts nothing: every count is bounded by common/limits.h and by
 * the bytes actually left before anything is allocated, every field is
 * validated, and the scene is rebuilt through the scene_add_* builder, which
 * validates again. File names in src_loc do not travel (a placeholder name is
 * used on the receiving side); line and column numbers do.
 */
#ifndef PORTRAY_PROTO_SERIAL_H
#define PORTRAY_PROTO_SERIAL_H

#include <stddef.h>
#include <stdint.h>

#include "common/scene.h"

/* "PSCN" and the encoding's version: bump the version on any layout change. */
#define PROTO_SCENE_MAGIC 0x5053434eu
#define PROTO_SCENE_VERSION 2u /* 2: transforms travel in three forms (docs/protocol.md) */
/* a serialized scene: 1 GiB, the same bound as a scene file */
#define LIM_SCENE_BYTES (1024ull * 1024 * 1024)
/* a mesh file name as written in the scene (only a label on the worker) */
#define LIM_PATH_LEN 4096
/* the placeholder for src_loc.file in a decoded scene */
#define PROTO_SCENE_FILE "<master>"

/*
 * Encodes s into a new buffer: *out (caller frees with free()) of *len bytes.
 * The same scene always gives the same bytes. Returns 0, or -1 when out of
 * memory (then *out is NULL).
 */
int proto_scene_encode(const struct scene *s, uint8_t **out, size_t *len);

/*
 * Decodes len bytes into a new scene (*out, caller frees with scene_free).
 * Returns 0, or 1 with err filled ("scene data: ...") and *out NULL.
 */
int proto_scene_decode(const uint8_t *p, size_t len, struct scene **out, struct scene_error *err);

#endif
