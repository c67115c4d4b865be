/*
 * img.h - image files: PNG (with in-tree deflate) and binary PPM (P6).
 */
#ifndef PORTRAY_IMG_H
#define PORTRAY_IMG_H

#include <stddef.h>
#include <stdint.h>

/* Encodes w*h RGB8 pixels as a PNG in memory; *out is malloc'd (caller frees). */
int img_png_encode(const uint8_t *rgb, uint32_t w, uint32_t h, uint8_t **out, size_t *out_len);

/*
 * Writes rgb to path, PNG when the name ends in .png (any case), binary PPM
 * otherwise (.ppm). Writes a temporary file beside it and renames, so a
 * reader never sees a half-written image. Returns 0, or -1 with errno set.
 */
int img_write(const char *path, const uint8_t *rgb, uint32_t w, uint32_t h);

/* CRC-32 (PNG/zlib polynomial) and Adler-32, exported for tests. */
uint32_t img_adler32(uint32_t adler, const uint8_t *p, size_t n);

#endif
