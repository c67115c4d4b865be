/*
 * raw.h - RAW triangle files: nine numbers per triangle, any whitespace.
 */
#ifndef PORTRAY_RAW_H
#define PORTRAY_RAW_H

#include <stddef.h>

#include "common/scene.h"

/*
 * Parses RAW text (buf, len) into mesh (whose options weld/smooth/rotation/at
 * and file are set by the caller beforehand; its arrays are overwritten):
 * welds vertices closer than mesh->weld, rotates (degrees, x then y then z)
 * and then translates by +at (the file's origin lands on the world point AT:
 * v' = Rz Ry Rx v + at; raw.c's top comment gives the reasoning), and builds
 * angle-weighted smoothing normals when mesh->smooth. One non-blank line =
 * exactly nine numbers. On error fills err with "file:line: error: ..."
 * (level 1) and leaves mesh's arrays NULL. Returns 0 or the error level.
 */
int raw_parse(const char *buf, size_t len, struct scene_mesh *mesh, struct scene_error *err);

/* Reads the file at path (bounded by LIM_RAW_BYTES) and calls raw_parse. */
int raw_load(const char *path, struct scene_mesh *mesh, struct scene_error *err);

#endif
