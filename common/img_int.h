/*
 * img_int.h - what common/img.c (PNG, PPM, files) and common/img_float.c
 * (PFM, OpenEXR, half, sRGB) share; not for use outside the img_ module.
 */
#ifndef PORTRAY_IMG_INT_H
#define PORTRAY_IMG_INT_H

#include <stddef.h>
#include <stdint.h>

#include "common/img.h"

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
