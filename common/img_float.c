/*
 * img_float.c - the floating-point formats: PFM and OpenEXR, with the
 * conversions they need (sRGB decoding to linear, float to half).
 *
 * Values: the writers take the renderer's values as the PNG holds them,
 * display values that the files declare sRGB-encoded (docs/camera.md,
 * "Output formats"), and write them decoded to linear light with sRGB's
 * exact inverse transfer function, the convention for both formats. From
 * RGB8, the value of byte v is v/255 before decoding; encoding a file's
 * value again and rounding to 8 bits gives v back (test_imgfmt). From
 * RGBF32 (what portray-master gives them: the renderer's floats before
 * clamping), each value is decoded as it is, below 0 and above 1 included.
 *
 * PFM: "PF\n<w> <h>\n-1.0\n", then float32 R G B triples, little-endian
 * (the negative scale says so), rows from the bottom of the image up.
 *
 * OpenEXR (single part, scan lines): magic 20000630, version 2 with no
 * flags, a header of attributes (channels B G R of type HALF or FLOAT,
 * chromaticities of Rec. 709 / sRGB with D65 white, colorInteropID
 * "lin_rec709_scene", NO_COMPRESSION, data and display window the image,
 * INCREASING_Y, pixel aspect 1, screen window (0,0) and 1, then the text
 * items as string attributes) ended by a zero byte; the line offset table
 * (one uint64 per scan line, from the start of the file); then one block
 * per scan line: int32 y, int32 byte count, the line's B values, its G
 * values, its R values, little-endian.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/img.h"
#include "common/img_int.h"
#include "common/xmath.h"

/* ---- conversions ------------------------------------------------------------------ */

double img_srgb_to_linear(double v)
{
	if (v != v)
		return 0;
	if (v < 0)
		return -img_srgb_to_linear(-v);
	/* IEC 61966-2-1: the linear segment below 0.04045, the 2.4 power above */
	return v <= 0.04045 ? v / 12.92 : xm_pow((v + 0.055) / 1.055, 2.4);
}

void img_linear_table(float table[256])
{
	for (int v = 0; v < 256; v++)
		table[v] = (float)img_srgb_to_linear(v / 255.0);
}

uint16_t img_half_from_float(float f)
{
	uint32_t x;
	memcpy(&x, &f, sizeof x);
	uint16_t sign = (uint16_t)((x >> 16) & 0x8000);
	uint32_t ax = x & 0x7fffffffu;
	if (ax > 0x7f800000u)
		return sign | 0x7e00; /* NaN: a quiet one */
	if (ax >= 0x477ff000u)
		return sign | 0x7c00; /* 65520 and up (and infinity) round to infinity */
	if (ax >= 0x38800000u) {
		/* normal half (2^-14 and up): rebias the exponent by 127 - 15 and
		 * round the 23-bit fraction to 10 bits, ties to even; a carry out of
		 * the fraction correctly steps the exponent */
		uint32_t r = ax + 0xfffu + ((ax >> 13) & 1);
		return sign | (uint16_t)((r - 0x38000000u) >> 13);
	}
	if (ax <= 0x33000000u)
		return sign; /* 2^-25 and below: zero (2^-25 itself ties to even 0) */
	/* subnormal half: units of 2^-24; the float is m * 2^(e-150) with the
	 * implicit bit in m, so the count is m / 2^(126-e), rounded to even */
	uint32_t e = ax >> 23, m = (ax & 0x7fffffu) | 0x800000u, shift = 126 - e;
	uint32_t q = m >> shift, rest = m & ((1u << shift) - 1), halfway = 1u << (shift - 1);
	if (rest > halfway || (rest == halfway && (q & 1)))
		q++; /* q may reach 0x400, the smallest normal: right */
	return sign | (uint16_t)q;
}

/* ---- rows ------------------------------------------------------------------------- */

/* Row y of d as 3*w linear floats (R G B per pixel). */
static void linear_row(const struct img_desc *d, const float table[256], uint32_t y, float *out)
{
	size_t n = 3 * (size_t)d->w;
	if (d->type == IMG_RGB8) {
		const uint8_t *p = (const uint8_t *)d->pixels + y * n;
		for (size_t i = 0; i < n; i++)
			out[i] = table[p[i]];
	} else {
		const float *p = (const float *)d->pixels + y * n;
		for (size_t i = 0; i < n; i++)
			out[i] = (float)img_srgb_to_linear(p[i]);
	}
}

static void put_le32(uint8_t *p, uint32_t v)
{
	p[0] = (uint8_t)v;
	p[1] = (uint8_t)(v >> 8);
	p[2] = (uint8_t)(v >> 16);
	p[3] = (uint8_t)(v >> 24);
}

static uint32_t float_bits(float f)
{
	uint32_t u;
	memcpy(&u, &f, sizeof u);
	return u;
}

/* ---- PFM ---------------------------------------------------------------------------- */

void img_pfm_emit(const struct img_desc *d, struct img_sink *s)
{
	char head[64];
	int hn = snprintf(head, sizeof head, "PF\n%u %u\n-1.0\n", (unsigned)d->w, (unsigned)d->h);
	img_sink_bytes(s, head, (size_t)hn);
	size_t n = 3 * (size_t)d->w;
	float table[256], *row = malloc(n * sizeof *row);
	uint8_t *bytes = malloc(n * 4);
	if (!row || !bytes) {
		if (!s->err)
			s->err = ENOMEM;
		goto done;
	}
	img_linear_table(table);
	for (uint32_t k = 0; k < d->h && !s->err; k++) {
		linear_row(d, table, d->h - 1 - k, row); /* bottom row first */
		for (size_t i = 0; i < n; i++)
			put_le32(bytes + 4 * i, float_bits(row[i]));
		img_sink_bytes(s, bytes, n * 4);
	}
done:
	free(row);
	free(bytes);
}

/* ---- OpenEXR ------------------------------------------------------------------------ */

/* Attribute header: name, type (both NUL-terminated), int32 value size. */
static void attr(struct img_sink *s, const char *name, const char *type, uint32_t size)
{
	img_sink_bytes(s, name, strlen(name) + 1);
	img_sink_bytes(s, type, strlen(type) + 1);
	img_sink_le32(s, size);
}

static void attr_string(struct img_sink *s, const char *name, const char *v)
{
	uint32_t n = (uint32_t)strlen(v);
	attr(s, name, "string", n);
	img_sink_bytes(s, v, n);
}

static void attr_floats(struct img_sink *s, const char *name, const char *type, const float *v, int n)
{
	attr(s, name, type, 4u * (uint32_t)n);
	for (int i = 0; i < n; i++)
		img_sink_le32(s, float_bits(v[i]));
}

static void attr_box(struct img_sink *s, const char *name, uint32_t w, uint32_t h)
{
	attr(s, name, "box2i", 16);
	img_sink_le32(s, 0);
	img_sink_le32(s, 0);
	img_sink_le32(s, w - 1);
	img_sink_le32(s, h - 1);
}

/* The header (magic, version, attributes, end byte) of d into s. */
static void exr_header(const struct img_desc *d, struct img_sink *s)
{
	static const uint8_t magic_version[8] = { 0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0 };
	img_sink_bytes(s, magic_version, sizeof magic_version);

	/* channels in alphabetical order: name, int32 pixel type (1 HALF,
	 * 2 FLOAT), pLinear 0, three reserved zeros, x and y sampling 1 */
	attr(s, "channels", "chlist", 3 * 18 + 1);
	uint32_t type = d->format == IMG_EXR_HALF ? 1 : 2;
	static const char *names[3] = { "B", "G", "R" };
	for (int c = 0; c < 3; c++) {
		static const uint8_t plinear_reserved[4] = { 0, 0, 0, 0 };
		img_sink_bytes(s, names[c], 2);
		img_sink_le32(s, type);
		img_sink_bytes(s, plinear_reserved, 4);
		img_sink_le32(s, 1);
		img_sink_le32(s, 1);
	}
	img_sink_bytes(s, "", 1);

	/* Rec. 709 primaries (those of sRGB) and D65 white, CIE xy */
	static const float chroma[8] = { 0.64f, 0.33f, 0.30f, 0.60f, 0.15f, 0.06f, 0.3127f, 0.3290f };
	attr_floats(s, "chromaticities", "chromaticities", chroma, 8);
	attr_string(s, "colorInteropID", "lin_rec709_scene");
	attr(s, "compression", "compression", 1);
	img_sink_bytes(s, "", 1); /* NO_COMPRESSION */
	attr_box(s, "dataWindow", d->w, d->h);
	attr_box(s, "displayWindow", d->w, d->h);
	attr(s, "lineOrder", "lineOrder", 1);
	img_sink_bytes(s, "", 1); /* INCREASING_Y */
	static const float one = 1.0f, centre[2] = { 0, 0 };
	attr_floats(s, "pixelAspectRatio", "float", &one, 1);
	attr_floats(s, "screenWindowCenter", "v2f", centre, 2);
	attr_floats(s, "screenWindowWidth", "float", &one, 1);
	for (size_t i = 0; i < d->n_text; i++) {
		char name[IMG_TEXT_KEY_MAX + 1], value[IMG_TEXT_VALUE_MAX + 1];
		img_exr_attr_name(d->text[i].key, name);
		img_text_clean(d->text[i].value, value);
		attr_string(s, name, value);
	}
	img_sink_bytes(s, "", 1); /* end of header */
}

void img_exr_emit(const struct img_desc *d, struct img_sink *s)
{
	size_t bps = d->format == IMG_EXR_HALF ? 2 : 4, w = d->w;
	size_t data = 3 * w * bps, line = 8 + data;
	struct img_sink head = { .fd = -1 };
	float table[256], *row = NULL;
	uint8_t *bytes = NULL;

	exr_header(d, &head);
	if (head.err) {
		if (!s->err)
			s->err = head.err;
		goto done;
	}
	img_sink_bytes(s, head.p, head.n);
	uint64_t first = head.n + 8ull * d->h; /* the first block follows the offset table */
	for (uint32_t y = 0; y < d->h; y++)
		img_sink_le64(s, first + (uint64_t)y * line);

	row = malloc(3 * w * sizeof *row);
	bytes = malloc(line);
	if (!row || !bytes) {
		if (!s->err)
			s->err = ENOMEM;
		goto done;
	}
	img_linear_table(table);
	for (uint32_t y = 0; y < d->h && !s->err; y++) {
		linear_row(d, table, y, row);
		put_le32(bytes, y);
		put_le32(bytes + 4, (uint32_t)data);
		uint8_t *o = bytes + 8;
		for (int c = 2; c >= 0; c--) { /* B, G, R */
			for (size_t x = 0; x < w; x++) {
				float v = row[3 * x + (size_t)c];
				if (bps == 2) {
					uint16_t hv = img_half_from_float(v);
					o[0] = (uint8_t)hv;
					o[1] = (uint8_t)(hv >> 8);
				} else {
					put_le32(o, float_bits(v));
				}
				o += bps;
			}
		}
		img_sink_bytes(s, bytes, line);
	}
done:
	free(head.p);
	free(row);
	free(bytes);
}
