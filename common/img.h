/*
 * img.h - image files: PNG (8 or 16 bits, in-tree deflate), binary PPM (P6),
 * PFM and OpenEXR (half or float, uncompressed). What the values in each
 * format mean is stated in docs/camera.md, "Output formats".
 */
#ifndef PORTRAY_IMG_H
#define PORTRAY_IMG_H

#include <stddef.h>
#include <stdint.h>

/* Encodes w*h RGB8 pixels as a PNG in memory, with no chunk beyond IHDR,
 * IDAT and IEND; *out is malloc'd (caller frees). */
int img_png_encode(const uint8_t *rgb, uint32_t w, uint32_t h, uint8_t **out, size_t *out_len);

/*
 * Writes rgb to path, PNG when the name ends in .png (any case), binary PPM
 * otherwise (.ppm). Writes a temporary file beside it and renames, so a
 * reader never sees a half-written image. Returns 0, or -1 with errno set.
 * (The plain writer of old: no chunks, no metadata. img_write_opts is the
 * one with every format.)
 */
int img_write(const char *path, const uint8_t *rgb, uint32_t w, uint32_t h);

/*
 * How many threads a PNG encode may use (the calling one included): 0, the
 * default, means one per online processor (at most 8). The bytes are the
 * same whatever the count. Process-wide.
 */
void img_set_threads(unsigned n);

/* CRC-32 (PNG/zlib polynomial) and Adler-32, exported for tests. */
uint32_t img_adler32(uint32_t adler, const uint8_t *p, size_t n);

/* ---- every format ------------------------------------------------------------ */

/*
 * What the pixels given to the writers are. Both hold the renderer's values
 * on one scale: 1.0 is the 8-bit 255, and the values are the ones the
 * renderer sends to the display without a curve, which the files declare
 * as sRGB-encoded (docs/camera.md, "Output formats").
 *   IMG_RGB8:   3 bytes a pixel, the renderer's clamped and rounded bytes.
 *   IMG_RGBF32: 3 floats a pixel (the host's), unclamped: the renderer's
 *               RENDER_RGBF32 pixels (common/render.h), which
 *               portray-master renders for png16, PFM and OpenEXR.
 */
enum img_pixel_type { IMG_RGB8, IMG_RGBF32 };

enum img_format {
	IMG_PNG,      /* 8 bits a channel, sRGB chunks, text */
	IMG_PNG16,    /* 16 bits a channel: floats in 65535 steps; 8-bit values times 257, sBIT 8 */
	IMG_PPM,      /* binary P6, maxval 255, no metadata */
	IMG_PFM,      /* PF, little-endian float32, rows bottom to top, linear */
	IMG_EXR,      /* OpenEXR, scan lines, FLOAT channels, no compression, linear */
	IMG_EXR_HALF, /* the same with HALF channels */
	IMG_N_FORMATS
};

/* A text item: PNG tEXt chunk (key = keyword), OpenEXR string attribute
 * (key with its spaces removed and the next letter capitalised, first
 * letter lower case: "Render time" -> "renderTime"). PPM and PFM carry none. */
struct img_text {
	const char *key;   /* 1 to IMG_TEXT_KEY_MAX printable ASCII characters */
	const char *value; /* bytes other than printable ASCII and '\n' are written as '?' */
};
#define IMG_TEXT_KEY_MAX 31    /* OpenEXR's short-name limit (PNG allows 79) */
#define IMG_TEXT_VALUE_MAX 4096 /* longer values are cut: metadata, not payload */
#define IMG_TEXT_MAX 16         /* text items per image */

struct img_desc {
	uint32_t w, h;
	enum img_pixel_type type;
	const void *pixels; /* w*h pixels, rows top to bottom, R G B */
	enum img_format format;
	const struct img_text *text; /* n_text items, may be NULL when n_text is 0 */
	size_t n_text;
};

/* --format name ("png", "png16", "ppm", "pfm", "exr", "exr-half") to format;
 * 0, or -1 for an unknown name. */
int img_format_parse(const char *name, enum img_format *f);
/* The format a file name's extension names (.png .ppm .pfm .exr, any case;
 * .png is IMG_PNG and .exr IMG_EXR); 0, or -1 when it names none. */
int img_format_by_ext(const char *path, enum img_format *f);
/* Whether path's extension suits f (.png for both PNGs, .exr for both EXRs). */
int img_format_ext_matches(const char *path, enum img_format f);
const char *img_format_name(enum img_format f); /* "png16" */
const char *img_format_ext(enum img_format f);  /* ".png" */

/*
 * Encodes d in memory. 0 with *out malloc'd (caller frees), or -1 with
 * errno EINVAL (size outside LIM_IMAGE_*, no pixels, a bad text key, too
 * many texts) or ENOMEM.
 */
int img_encode(const struct img_desc *d, uint8_t **out, size_t *out_len);

/*
 * Writes d to path in d->format, as img_write does (temporary file, fsync,
 * rename; special files written in place; symbolic links written through),
 * or to standard output when path is "-" (in place; no fsync). 0, or -1
 * with errno set.
 */
int img_write_opts(const char *path, const struct img_desc *d);

/*
 * Checks, before any work is done, that img_write_opts could write path:
 * "-" passes when standard output is open for writing (else EBADF, or
 * EACCES when open for reading only); a directory fails (EISDIR); an existing file that is
 * not a regular one (device, FIFO) must be writable (access W_OK); for any
 * other name a temporary file is created and removed in the directory the
 * image would go to (that of a symbolic link's target), which catches a
 * missing directory (ENOENT), a non-directory (ENOTDIR), and one that
 * refuses files (EACCES, EROFS, ...), root's read-only mounts included.
 * 0, or -1 with errno set and dir (dir_len bytes, may be NULL) holding the
 * directory that failed, or path itself for EISDIR and special files.
 */
int img_output_check(const char *path, char *dir, size_t dir_len);

/* ---- exported for tests ------------------------------------------------------- */

/* IEEE 754 binary16 nearest to f (ties to even; overflow to infinity; NaN stays NaN). */
uint16_t img_half_from_float(float f);
/* sRGB's decoding (IEC 61966-2-1) extended to all reals: odd-symmetric, and
 * the power law continued above 1. NaN gives 0. */
double img_srgb_to_linear(double v);

#endif
