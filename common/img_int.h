/*
 * img_int.h - what common/img.c (PPM, formats, files), common/img_png.c
 * (PNG, deflate) and common/img_float.c (PFM, OpenEXR, half, sRGB) share;
 * not for use outside the img_ module.
 */
#ifndef PORTRAY_IMG_INT_H
#define PORTRAY_IMG_INT_H

#include <stddef.h>
#include <stdint.h>

#include "common/img.h"
#include "common/limits.h"

/* w x h within LIM_IMAGE_SIDE and LIM_IMAGE_PIXELS (and not empty). */
static inline int img_size_ok(uint32_t w, uint32_t h)
{
	return w > 0 && h > 0 && w <= LIM_IMAGE_SIDE && h <= LIM_IMAGE_SIDE &&
	       (uint64_t)w * h <= LIM_IMAGE_PIXELS;
}

/* The renderer's own rounding (filter_quantise): clamp to [0,1], then the
 * nearest of 2^bits - 1 steps (top = 255 or 65535); NaN counts as 0. */
static inline unsigned img_quantise(float c, double top)
{
	double v = c > 0 ? (c < 1 ? c : 1) : 0;
	return (unsigned)(v * top + 0.5);
}

/*
 * Encodes d (validated; format IMG_PNG or IMG_PNG16) as a PNG in memory
 * (img_png.c). plain: no chunk but IHDR, IDAT and IEND (img_png_encode's
 * PNG). 0 with *out malloc'd (the caller frees it), or -1 with errno ENOMEM.
 */
int img_png_emit(const struct img_desc *d, int plain, uint8_t **out, size_t *out_len);

/* For tests: PNG filter f (0 None, 1 Sub, 2 Up, 3 Average, 4 Paeth) of
 * bytes [i0, i1) of row cur (up: the row above, or NULL for the first; k
 * bytes a pixel; i0 is 0 or at least k) into d[i0..i1), as the encoder
 * filters. */
void img_png_filter_bytes(int f, const uint8_t *cur, const uint8_t *up, size_t k, size_t i0, size_t i1, uint8_t *d);

/*
 * Where encoded bytes go: memory (fd < 0: p grows to hold everything) or a
 * file descriptor (p is a buffer of IMG_SINK_BUF bytes, written out when
 * full and by sink_flush). err keeps the first failure's errno; once set,
 * every later call does nothing, so an encoder checks it once at the end.
 */
struct img_sink {
	int fd;
	uint8_t *p;
	size_t n, cap;
	int err;
};
#define IMG_SINK_BUF (1u << 16)

void img_sink_bytes(struct img_sink *s, const void *p, size_t n);
void img_sink_le32(struct img_sink *s, uint32_t v);
void img_sink_le64(struct img_sink *s, uint64_t v);
int img_sink_flush(struct img_sink *s); /* fd sinks: write what is pending; 0 or -1 (err set) */

/* Text for a tEXt chunk or a string attribute: value with every byte
 * other than printable ASCII and '\n' replaced by '?', cut at
 * IMG_TEXT_VALUE_MAX bytes. Writes a NUL-terminated string to out
 * (IMG_TEXT_VALUE_MAX + 1 bytes). Returns its length. */
size_t img_text_clean(const char *value, char *out);
/* OpenEXR attribute name for a text key ("Render time" -> "renderTime");
 * out holds IMG_TEXT_KEY_MAX + 1 bytes. */
void img_exr_attr_name(const char *key, char *out);

/* RGB8 value v (0..255) as the float pipeline's value v/255, decoded to
 * linear: table[v] (filled by img_linear_table). */
void img_linear_table(float table[256]);

/* Streams a PFM or an OpenEXR of d (already validated) into s. */
void img_pfm_emit(const struct img_desc *d, struct img_sink *s);
void img_exr_emit(const struct img_desc *d, struct img_sink *s);

#endif
