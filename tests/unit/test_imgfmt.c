/*
 * test_imgfmt.c - the output formats beyond the plain PNG and PPM: format
 * names and extensions; float to half and sRGB decoding against hand-checked
 * values (and every half); the PNG chunks (cHRM, gAMA, sRGB, sBIT, tEXt)
 * byte for byte, with the IDAT data unchanged from the plain PNG; 16-bit
 * PNGs decoded by tests/unit/inflate.h; PFM and OpenEXR parsed field by
 * field (header attributes, offset table, scan lines) and read back;
 * img_write_opts to files and standard output; img_output_check.
 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "common/img.h"
#include "common/limits.h"
#include "tests/unit/check.h"
#include "tests/unit/inflate.h"
#include "tests/unit/slurp.h"

static uint32_t seed = 77;
static uint32_t rnd(void)
{
	seed ^= seed << 13;
	seed ^= seed >> 17;
	seed ^= seed << 5;
	return seed;
}

/* w*h RGB8 pixels: noise over a gradient, every byte value present in big ones */
static uint8_t *make_rgb(uint32_t w, uint32_t h)
{
	uint8_t *p = malloc(3 * (size_t)w * h);
	for (size_t i = 0; i < 3 * (size_t)w * h; i++)
		p[i] = (uint8_t)(i % 7 == 0 ? rnd() >> 24 : (i / 3) % 256);
	return p;
}

static uint32_t le32(const uint8_t *p)
{
	return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float lef(const uint8_t *p)
{
	uint32_t u = le32(p);
	float f;
	memcpy(&f, &u, 4);
	return f;
}

/* binary16 to float, written apart from the encoder: sign, exponent, fraction */
static float half_to_float(uint16_t h)
{
	int s = h >> 15, e = (h >> 10) & 31, m = h & 1023;
	double v;
	if (e == 0)
		v = ldexp(m, -24);
	else if (e == 31)
		v = m ? NAN : INFINITY;
	else
		v = ldexp(1024 + m, e - 25);
	return (float)(s ? -v : v);
}

/* The independent sRGB encoding (IEC 61966-2-1), for round trips. */
static double srgb_encode(double l)
{
	return l <= 0.0031308 ? l * 12.92 : 1.055 * pow(l, 1 / 2.4) - 0.055;
}

/* ---- names ------------------------------------------------------------------------ */

static void test_names(void)
{
	enum img_format f;
	static const char *names[] = { "png", "png16", "ppm", "pfm", "exr", "exr-half" };
	for (int i = 0; i < 6; i++) {
		CHECK(img_format_parse(names[i], &f) == 0 && (int)f == i);
		CHECK(strcmp(img_format_name(f), names[i]) == 0);
	}
	CHECK(img_format_parse("PNG", &f) == -1);
	CHECK(img_format_parse("exr16", &f) == -1);
	CHECK(img_format_parse("", &f) == -1);

	CHECK(img_format_by_ext("a.png", &f) == 0 && f == IMG_PNG);
	CHECK(img_format_by_ext("dir.d/a.PnG", &f) == 0 && f == IMG_PNG);
	CHECK(img_format_by_ext("a.ppm", &f) == 0 && f == IMG_PPM);
	CHECK(img_format_by_ext("/x/a.b.PFM", &f) == 0 && f == IMG_PFM);
	CHECK(img_format_by_ext("a.exr", &f) == 0 && f == IMG_EXR);
	CHECK(img_format_by_ext("a.tif", &f) == -1);
	CHECK(img_format_by_ext("a", &f) == -1);
	CHECK(img_format_by_ext("dir.png/a", &f) == -1);
	CHECK(img_format_by_ext(".png", &f) == -1); /* a hidden file with no extension */
	CHECK(img_format_by_ext("a.png.", &f) == -1);
	CHECK(img_format_by_ext("-", &f) == -1);

	CHECK(img_format_ext_matches("a.PNG", IMG_PNG16));
	CHECK(img_format_ext_matches("a.exr", IMG_EXR_HALF));
	CHECK(!img_format_ext_matches("a.exr", IMG_PFM));
	CHECK(!img_format_ext_matches("a", IMG_PPM));
	CHECK(strcmp(img_format_ext(IMG_EXR_HALF), ".exr") == 0);
}

/* ---- conversions ------------------------------------------------------------------ */

static void test_half(void)
{
	static const struct {
		float f;
		uint16_t h;
	} cases[] = {
		{ 0.0f, 0x0000 },           { -0.0f, 0x8000 },       { 1.0f, 0x3c00 },       { -2.0f, 0xc000 },
		{ 0.5f, 0x3800 },           { 65504.0f, 0x7bff },    { 65519.99f, 0x7bff },  { 65520.0f, 0x7c00 },
		{ 1e10f, 0x7c00 },          { -1e10f, 0xfc00 },      { 0x1p-14f, 0x0400 },   { 0x1p-24f, 0x0001 },
		{ 0x1p-25f, 0x0000 },       { 0x1.8p-25f, 0x0001 },  { 0x1.8p-24f, 0x0002 }, /* 1.5 units: tie, to even 2 */
		{ 0x1.4p-24f, 0x0001 },     { 0x1.002p+0f, 0x3c00 }, /* 1 + 2^-11: tie, to even */
		{ 0x1.006p+0f, 0x3c02 },    /* 1 + 3*2^-11: tie, to even (up) */
		{ 0x1.0021p+0f, 0x3c01 },   /* just past the tie */
		{ 0x1.004p+0f, 0x3c01 },    /* 1 + 2^-10: exact */
		{ 0.1f, 0x2e66 },           { 1.0f / 3, 0x3555 },    { 0x1.ffcp-15f, 0x0400 }, /* rounds up into the normals */
		{ 0x1.ff8p-15f, 0x03ff },   { 0.0003035269835488375f, 0x0cf9 },
		{ 0.21586050011389926f, 0x32e8 }, { 0.5028864580325687f, 0x3806 },
	};
	for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
		uint16_t h = img_half_from_float(cases[i].f);
		CHECK(h == cases[i].h);
		if (h != cases[i].h)
			fprintf(stderr, "half(%a) = %04x, want %04x\n", cases[i].f, h, cases[i].h);
	}
	CHECK(img_half_from_float(INFINITY) == 0x7c00);
	CHECK(img_half_from_float(-INFINITY) == 0xfc00);
	CHECK((img_half_from_float(NAN) & 0x7c00) == 0x7c00 && (img_half_from_float(NAN) & 0x3ff) != 0);

	/* every finite half comes back as itself, and the point halfway to the
	 * next goes to the one with an even fraction */
	int bad = 0;
	for (uint32_t h = 0; h < 0x7c00; h++) {
		float f = half_to_float((uint16_t)h);
		bad += img_half_from_float(f) != h || img_half_from_float(-f) != (h | 0x8000);
		if (h + 1 < 0x7c00) {
			float mid = (float)(((double)f + half_to_float((uint16_t)(h + 1))) / 2);
			uint16_t even = (h & 1) ? (uint16_t)(h + 1) : (uint16_t)h;
			bad += img_half_from_float(mid) != even;
			bad += img_half_from_float(nextafterf(mid, INFINITY)) != h + 1;
			bad += img_half_from_float(nextafterf(mid, 0)) != h;
		}
	}
	CHECK(bad == 0);
}

static void test_srgb(void)
{
	CHECK(img_srgb_to_linear(0) == 0);
	CHECK(img_srgb_to_linear(1) == 1);
	CHECK_NEAR(img_srgb_to_linear(0.04045), 0.04045 / 12.92, 1e-15);
	CHECK_NEAR(img_srgb_to_linear(0.5), 0.21404114048223255, 1e-15);
	CHECK_NEAR(img_srgb_to_linear(128 / 255.0), 0.21586050011389926, 1e-15);
	CHECK_NEAR(img_srgb_to_linear(-0.5), -0.21404114048223255, 1e-15);
	CHECK_NEAR(img_srgb_to_linear(2.0), pow(2.055 / 1.055, 2.4), 1e-12);
	CHECK(img_srgb_to_linear(NAN) == 0);
	/* monotonic across the join of the two pieces */
	CHECK(img_srgb_to_linear(0.04045) < img_srgb_to_linear(0.040451));

	/* every byte survives float and half: encode the linear value again,
	 * round to 8 bits, get the byte back */
	int bad = 0;
	for (int v = 0; v < 256; v++) {
		float l = (float)img_srgb_to_linear(v / 255.0);
		float lh = half_to_float(img_half_from_float(l));
		bad += (int)floor(srgb_encode(l) * 255 + 0.5) != v;
		bad += (int)floor(srgb_encode(lh) * 255 + 0.5) != v;
	}
	CHECK(bad == 0);
}

/* ---- PNG ---------------------------------------------------------------------------- */

struct chunk {
	char type[5];
	const uint8_t *data;
	uint32_t len;
};

/* Splits a PNG into its chunks (CRCs checked); returns the count or -1. */
static int png_chunks(const uint8_t *p, size_t n, struct chunk *c, int max)
{
	size_t pos = 8;
	int k = 0;
	while (pos + 12 <= n && k < max) {
		uint32_t len = inf_be32(p + pos);
		if (len > n - pos - 12 || inf_crc32(p + pos + 4, 4 + (size_t)len, 0) != inf_be32(p + pos + 8 + len))
			return -1;
		memcpy(c[k].type, p + pos + 4, 4);
		c[k].type[4] = 0;
		c[k].data = p + pos + 8;
		c[k].len = len;
		k++;
		pos += 12 + (size_t)len;
	}
	return pos == n ? k : -1;
}

/* The PNG with every chunk but IHDR, IDAT and IEND taken out. */
static uint8_t *strip_ancillary(const uint8_t *p, size_t n, size_t *out_n)
{
	uint8_t *o = malloc(n);
	memcpy(o, p, 8);
	size_t on = 8, pos = 8;
	while (pos + 12 <= n) {
		uint32_t len = inf_be32(p + pos);
		if (len > n - pos - 12)
			break;
		if (!(p[pos + 4] & 0x20)) { /* critical */
			memcpy(o + on, p + pos, 12 + (size_t)len);
			on += 12 + (size_t)len;
		}
		pos += 12 + (size_t)len;
	}
	*out_n = on;
	return o;
}

static const struct img_text texts[] = {
	{ "Software", "portray 0.11.0" },
	{ "Source", "sc\xe9ne\tone.sce\nline two" },
	{ "Render time", "1.250 s" },
};

static void test_png8(void)
{
	static const uint32_t sizes[][2] = { { 1, 1 }, { 37, 23 }, { 320, 240 }, { 700, 600 } };
	for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
		uint32_t w = sizes[s][0], h = sizes[s][1];
		uint8_t *rgb = make_rgb(w, h), *plain = NULL, *png = NULL;
		size_t pn = 0, n = 0;
		CHECK(img_png_encode(rgb, w, h, &plain, &pn) == 0);
		struct img_desc d = { .w = w, .h = h, .type = IMG_RGB8, .pixels = rgb, .format = IMG_PNG,
				      .text = texts, .n_text = 3 };
		CHECK(img_encode(&d, &png, &n) == 0);
		/* the plain PNG is this one without its new chunks, byte for byte:
		 * IHDR and the IDAT stream unchanged */
		size_t sn;
		uint8_t *stripped = strip_ancillary(png, n, &sn);
		CHECK(sn == pn && memcmp(stripped, plain, pn) == 0);
		free(stripped);

		struct chunk c[64];
		int k = png_chunks(png, n, c, 64);
		CHECK(k >= 9);
		if (k >= 9) {
			static const char *order[] = { "IHDR", "cHRM", "gAMA", "sRGB", "tEXt", "tEXt", "tEXt", "IDAT" };
			for (int i = 0; i < 8; i++)
				CHECK(strcmp(c[i].type, order[i]) == 0);
			CHECK(strcmp(c[k - 1].type, "IEND") == 0);
			CHECK(c[0].data[8] == 8 && c[0].data[9] == 2);
			static const uint8_t chrm[32] = { 0, 0, 0x7a, 0x26, 0, 0, 0x80, 0x84, 0, 0, 0xfa, 0,    0, 0, 0x80, 0xe8,
							  0, 0, 0x75, 0x30, 0, 0, 0xea, 0x60, 0, 0, 0x3a, 0x98, 0, 0, 0x17, 0x70 };
			CHECK(c[1].len == 32 && memcmp(c[1].data, chrm, 32) == 0);
			static const uint8_t gama[4] = { 0, 0, 0xb1, 0x8f }; /* 45455 */
			CHECK(c[2].len == 4 && memcmp(c[2].data, gama, 4) == 0);
			CHECK(c[3].len == 1 && c[3].data[0] == 0); /* perceptual */
			static const char t0[] = "Software\0portray 0.11.0";
			static const char t1[] = "Source\0sc?ne?one.sce\nline two";
			static const char t2[] = "Render time\0" "1.250 s";
			CHECK(c[4].len == sizeof t0 - 1 && memcmp(c[4].data, t0, sizeof t0 - 1) == 0);
			CHECK(c[5].len == sizeof t1 - 1 && memcmp(c[5].data, t1, sizeof t1 - 1) == 0);
			CHECK(c[6].len == sizeof t2 - 1 && memcmp(c[6].data, t2, sizeof t2 - 1) == 0);
			for (int i = 0; i < k; i++)
				CHECK(strcmp(c[i].type, "sBIT") != 0); /* 8 bits of 8: nothing to say */
		}
		uint8_t *back = NULL;
		uint32_t bw = 0, bh = 0;
		int idat, blocks[3], filters[5];
		CHECK(inf_png(png, n, &back, &bw, &bh, &idat, blocks, filters) == 0);
		CHECK(back && bw == w && bh == h && memcmp(back, rgb, 3 * (size_t)w * h) == 0);

		/* the same values as floats v/255 give the same file */
		float *fl = malloc(3 * sizeof *fl * w * h);
		for (size_t i = 0; i < 3 * (size_t)w * h; i++)
			fl[i] = rgb[i] / 255.0f;
		struct img_desc df = d;
		df.type = IMG_RGBF32;
		df.pixels = fl;
		uint8_t *pf = NULL;
		size_t nf = 0;
		CHECK(img_encode(&df, &pf, &nf) == 0 && nf == n && memcmp(pf, png, n) == 0);
		free(pf);
		free(fl);
		free(back);
		free(png);
		free(plain);
		free(rgb);
	}

	/* floats are clamped as the renderer clamps: below 0 and NaN to 0, above 1 to 255 */
	float fl[12] = { -1, 0.5f, 2, NAN, 1e30f, -0.0f, 0.25f, 0.75f, 1.0f / 255, 0.6f / 255, 0.4f / 255, 254.6f / 255 };
	struct img_desc d = { .w = 4, .h = 1, .type = IMG_RGBF32, .pixels = fl, .format = IMG_PNG };
	uint8_t *png = NULL, *back = NULL;
	size_t n = 0;
	uint32_t bw, bh;
	int idat, blocks[3], filters[5];
	CHECK(img_encode(&d, &png, &n) == 0);
	CHECK(inf_png(png, n, &back, &bw, &bh, &idat, blocks, filters) == 0);
	static const uint8_t want[12] = { 0, 128, 255, 0, 255, 0, 64, 191, 1, 1, 0, 255 };
	CHECK(back && memcmp(back, want, 12) == 0);
	free(back);
	free(png);
}

static void test_png16(void)
{
	uint32_t w = 300, h = 200;
	uint8_t *rgb = make_rgb(w, h), *png = NULL, *back = NULL;
	size_t n = 0;
	struct img_desc d = { .w = w, .h = h, .type = IMG_RGB8, .pixels = rgb, .format = IMG_PNG16,
			      .text = texts, .n_text = 1 };
	CHECK(img_encode(&d, &png, &n) == 0);
	struct chunk c[64];
	int k = png_chunks(png, n, c, 64);
	CHECK(k >= 8);
	if (k >= 8) {
		static const char *order[] = { "IHDR", "cHRM", "gAMA", "sRGB", "sBIT", "tEXt", "IDAT" };
		for (int i = 0; i < 7; i++)
			CHECK(strcmp(c[i].type, order[i]) == 0);
		CHECK(c[0].data[8] == 16 && c[0].data[9] == 2);
		CHECK(c[4].len == 3 && c[4].data[0] == 8 && c[4].data[1] == 8 && c[4].data[2] == 8);
	}
	uint32_t bw = 0, bh = 0;
	int depth = 0, idat, blocks[3], filters[5];
	CHECK(inf_png_any(png, n, &back, &bw, &bh, &depth, &idat, blocks, filters) == 0);
	CHECK(depth == 16 && bw == w && bh == h);
	int bad = 0;
	for (size_t i = 0; back && i < 3 * (size_t)w * h; i++)
		bad += (back[2 * i] << 8 | back[2 * i + 1]) != rgb[i] * 257;
	CHECK(back && bad == 0);
	CHECK(filters[1] + filters[2] + filters[3] + filters[4] > 0); /* filters at work on 6-byte pixels */
	free(back);
	free(png);

	/* from floats: the nearest of 65535 steps, and no sBIT */
	float fl[6] = { 0.5f, 1.0f / 65535, 0.25f, -3, 7, 0.123456f };
	struct img_desc df = { .w = 2, .h = 1, .type = IMG_RGBF32, .pixels = fl, .format = IMG_PNG16 };
	CHECK(img_encode(&df, &png, &n) == 0);
	k = png_chunks(png, n, c, 64);
	for (int i = 0; i < k; i++)
		CHECK(strcmp(c[i].type, "sBIT") != 0);
	CHECK(inf_png_any(png, n, &back, &bw, &bh, &depth, &idat, blocks, filters) == 0);
	static const unsigned want[6] = { 32768, 1, 16384, 0, 65535, 8091 };
	for (int i = 0; back && i < 6; i++)
		CHECK((unsigned)(back[2 * i] << 8 | back[2 * i + 1]) == want[i]);
	free(back);
	free(png);
	free(rgb);
}

/* ---- PPM and PFM -------------------------------------------------------------------- */

static void test_ppm_pfm(void)
{
	uint8_t rgb[6 * 3] = { 0, 1, 10, 11, 128, 188, 255, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9 };
	struct img_desc d = { .w = 3, .h = 2, .type = IMG_RGB8, .pixels = rgb, .format = IMG_PPM,
			      .text = texts, .n_text = 3 };
	uint8_t *out = NULL;
	size_t n = 0;
	CHECK(img_encode(&d, &out, &n) == 0);
	static const char ph[] = "P6\n3 2\n255\n";
	CHECK(n == sizeof ph - 1 + 18 && memcmp(out, ph, sizeof ph - 1) == 0 && memcmp(out + sizeof ph - 1, rgb, 18) == 0);
	free(out);

	d.format = IMG_PFM;
	CHECK(img_encode(&d, &out, &n) == 0);
	static const char fh[] = "PF\n3 2\n-1.0\n";
	CHECK(n == sizeof fh - 1 + 6 * 12 && memcmp(out, fh, sizeof fh - 1) == 0);
	/* hand-checked: bytes 0 1 10 | 11 128 188 of the top row, decoded from
	 * sRGB, as little-endian float32; the top row comes last */
	static const uint8_t top[3 * 12] = {
		0x00, 0x00, 0x00, 0x00, 0xb4, 0x22, 0x9f, 0x39, 0x61, 0xeb, 0x46, 0x3b, /* 0, 1, 10 */
		0x8e, 0x51, 0x5b, 0x3b, 0x89, 0x0a, 0x5d, 0x3e, 0x2b, 0xbd, 0x00, 0x3f, /* 11, 128, 188 */
		0x00, 0x00, 0x80, 0x3f, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, /* 255, 0, 0 */
	};
	CHECK(n >= sizeof fh - 1 + 72 && memcmp(out + sizeof fh - 1 + 36, top, 36) == 0);
	/* parse it back: bottom row first */
	int bad = 0;
	for (int row = 0; row < 2; row++) {
		for (int i = 0; i < 9; i++) {
			float v = lef(out + sizeof fh - 1 + 4 * (size_t)(row * 9 + i));
			int y = 1 - row;
			bad += v != (float)img_srgb_to_linear(rgb[y * 9 + i] / 255.0);
		}
	}
	CHECK(bad == 0);
	free(out);

	/* floats: unclamped values survive, decoded */
	float fl[3] = { 2.0f, -0.5f, 0.5f };
	struct img_desc df = { .w = 1, .h = 1, .type = IMG_RGBF32, .pixels = fl, .format = IMG_PFM };
	CHECK(img_encode(&df, &out, &n) == 0);
	CHECK(n == strlen("PF\n1 1\n-1.0\n") + 12);
	CHECK(lef(out + n - 12) == (float)img_srgb_to_linear(2.0) && lef(out + n - 12) > 1);
	CHECK(lef(out + n - 8) == (float)-img_srgb_to_linear(0.5));
	free(out);
	df.format = IMG_PPM;
	CHECK(img_encode(&df, &out, &n) == 0);
	CHECK(n == strlen("P6\n1 1\n255\n") + 3 && out[n - 3] == 255 && out[n - 2] == 0 && out[n - 1] == 128);
	free(out);
}

/* ---- OpenEXR ------------------------------------------------------------------------ */

struct exr_attr {
	char name[32], type[32];
	const uint8_t *v;
	uint32_t size;
};

/*
 * Parses an uncompressed single-part scan-line OpenEXR with channels B G R of
 * one type, checking every structural rule met on the way; fills the
 * attributes (up to 32), the image (w*h*3 floats, R G B, caller frees) and
 * the pixel type (1 half, 2 float). 0 or the number of the rule broken.
 */
static int exr_parse(const uint8_t *p, size_t n, struct exr_attr *a, int *n_attr, float **img, uint32_t *w,
		     uint32_t *h, int *ptype)
{
	if (n < 8 || le32(p) != 20000630 || le32(p + 4) != 2)
		return 1;
	size_t pos = 8;
	*n_attr = 0;
	int have_ch = 0, comp = -1, order = -1;
	int32_t dw[4] = { 0 };
	while (pos < n && p[pos]) {
		if (*n_attr == 32)
			return 2;
		struct exr_attr *t = &a[(*n_attr)++];
		size_t ln = strnlen((const char *)p + pos, n - pos);
		if (ln == 0 || ln > 31 || pos + ln >= n)
			return 3;
		memcpy(t->name, p + pos, ln + 1);
		pos += ln + 1;
		ln = strnlen((const char *)p + pos, n - pos);
		if (ln == 0 || ln > 31 || pos + ln + 4 >= n)
			return 4;
		memcpy(t->type, p + pos, ln + 1);
		pos += ln + 1;
		t->size = le32(p + pos);
		pos += 4;
		if (t->size > n - pos)
			return 5;
		t->v = p + pos;
		pos += t->size;
		for (int j = 0; j < *n_attr - 1; j++)
			if (strcmp(a[j].name, t->name) == 0)
				return 6; /* twice */
		if (!strcmp(t->name, "channels")) {
			/* B, G, R: name, int32 type, pLinear, 3 reserved, sampling 1 1 */
			static const char *want[3] = { "B", "G", "R" };
			if (strcmp(t->type, "chlist") || t->size != 55 || t->v[54] != 0)
				return 7;
			for (int c = 0; c < 3; c++) {
				const uint8_t *q = t->v + 18 * c;
				if (memcmp(q, want[c], 2) || le32(q + 2) < 1 || le32(q + 2) > 2 ||
				    le32(q + 2) != le32(t->v + 2) || q[6] || q[7] || q[8] || q[9] || le32(q + 10) != 1 ||
				    le32(q + 14) != 1)
					return 8;
			}
			*ptype = (int)le32(t->v + 2);
			have_ch = 1;
		} else if (!strcmp(t->name, "compression")) {
			if (strcmp(t->type, "compression") || t->size != 1)
				return 9;
			comp = t->v[0];
		} else if (!strcmp(t->name, "lineOrder")) {
			if (strcmp(t->type, "lineOrder") || t->size != 1)
				return 10;
			order = t->v[0];
		} else if (!strcmp(t->name, "dataWindow") || !strcmp(t->name, "displayWindow")) {
			if (strcmp(t->type, "box2i") || t->size != 16)
				return 11;
			int32_t b[4];
			for (int i = 0; i < 4; i++)
				b[i] = (int32_t)le32(t->v + 4 * i);
			if (!strcmp(t->name, "dataWindow"))
				memcpy(dw, b, sizeof dw);
			else if (memcmp(dw, b, sizeof b)) /* displayWindow comes after dataWindow and equals it */
				return 12;
		} else if (!strcmp(t->name, "pixelAspectRatio") || !strcmp(t->name, "screenWindowWidth")) {
			if (strcmp(t->type, "float") || t->size != 4 || lef(t->v) != 1.0f)
				return 13;
		} else if (!strcmp(t->name, "screenWindowCenter")) {
			if (strcmp(t->type, "v2f") || t->size != 8 || lef(t->v) != 0 || lef(t->v + 4) != 0)
				return 14;
		}
	}
	if (pos >= n)
		return 15;
	pos++; /* the end of the header */
	static const char *required[] = { "channels",   "compression", "dataWindow",        "displayWindow",
					  "lineOrder",  "pixelAspectRatio", "screenWindowCenter", "screenWindowWidth" };
	for (size_t r = 0; r < 8; r++) {
		int found = 0;
		for (int j = 0; j < *n_attr; j++)
			found |= !strcmp(a[j].name, required[r]);
		if (!found)
			return 16;
	}
	if (!have_ch || comp != 0 || order != 0 || dw[0] != 0 || dw[1] != 0 || dw[2] < 0 || dw[3] < 0)
		return 17;
	*w = (uint32_t)dw[2] + 1;
	*h = (uint32_t)dw[3] + 1;
	size_t bps = *ptype == 1 ? 2 : 4, data = 3 * bps * *w;
	if (n - pos < 8ull * *h)
		return 18;
	const uint8_t *table = p + pos;
	size_t expect = pos + 8ull * *h;
	*img = malloc(3 * sizeof **img * *w * *h);
	for (uint32_t y = 0; y < *h; y++) {
		uint64_t off = (uint64_t)le32(table + 8 * y) | (uint64_t)le32(table + 8 * y + 4) << 32;
		if (off != expect || n - off < 8 + data || le32(p + off) != y || le32(p + off + 4) != data) {
			free(*img);
			*img = NULL;
			return 19;
		}
		const uint8_t *q = p + off + 8;
		for (int c = 2; c >= 0; c--) { /* B G R */
			for (uint32_t x = 0; x < *w; x++, q += bps)
				(*img)[3 * ((size_t)y * *w + x) + (size_t)c] =
					bps == 2 ? half_to_float((uint16_t)(q[0] | q[1] << 8)) : lef(q);
		}
		expect = off + 8 + data;
	}
	if (expect != n) {
		free(*img);
		*img = NULL;
		return 20; /* trailing bytes */
	}
	return 0;
}

static const struct exr_attr *find_attr(const struct exr_attr *a, int n, const char *name)
{
	for (int i = 0; i < n; i++)
		if (!strcmp(a[i].name, name))
			return &a[i];
	return NULL;
}

static void test_exr(void)
{
	/* the first bytes, by hand: magic, version 2 with no flags, the
	 * channels attribute's name, type and size (3 x 18 + 1) and the B channel */
	uint8_t px[3] = { 255, 128, 0 };
	struct img_desc d = { .w = 1, .h = 1, .type = IMG_RGB8, .pixels = px, .format = IMG_EXR_HALF };
	uint8_t *out = NULL;
	size_t n = 0;
	CHECK(img_encode(&d, &out, &n) == 0);
	static const uint8_t head[] = { 0x76, 0x2f, 0x31, 0x01, 0x02, 0x00, 0x00, 0x00, 'c', 'h', 'a', 'n', 'n', 'e',
					'l',  's',  0,    'c',  'h',  'l',  'i',  's',  't',  0,   55,  0,   0,   0,
					'B',  0,    1,    0,    0,    0,    0,    0,    0,    0,   1,   0,   0,   0,
					1,    0,    0,    0,    'G',  0 };
	CHECK(n > sizeof head && memcmp(out, head, sizeof head) == 0);
	/* the last line block, by hand: y 0, 6 bytes, B G R as halves of 0, 0.2159, 1 */
	static const uint8_t block[] = { 0, 0, 0, 0, 6, 0, 0, 0, 0x00, 0x00, 0xe8, 0x32, 0x00, 0x3c };
	CHECK(n > sizeof block && memcmp(out + n - sizeof block, block, sizeof block) == 0);
	/* and the offset table's one entry points at it */
	size_t off = n - sizeof block;
	CHECK(le32(out + off - 8) == off && le32(out + off - 4) == 0);
	free(out);

	static const uint32_t sizes[][2] = { { 1, 1 }, { 5, 3 }, { 64, 48 }, { 301, 7 } };
	for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
		for (int half = 0; half < 2; half++) {
			uint32_t w = sizes[s][0], h = sizes[s][1];
			uint8_t *rgb = make_rgb(w, h);
			struct img_desc e = { .w = w, .h = h, .type = IMG_RGB8, .pixels = rgb,
					      .format = half ? IMG_EXR_HALF : IMG_EXR, .text = texts, .n_text = 3 };
			CHECK(img_encode(&e, &out, &n) == 0);
			struct exr_attr a[32];
			int na = 0, ptype = 0;
			float *img = NULL;
			uint32_t bw = 0, bh = 0;
			int rc = exr_parse(out, n, a, &na, &img, &bw, &bh, &ptype);
			CHECK(rc == 0);
			if (rc) {
				fprintf(stderr, "exr %ux%u half %d: rule %d broken\n", w, h, half, rc);
				free(out);
				free(rgb);
				continue;
			}
			CHECK(bw == w && bh == h && ptype == (half ? 1 : 2));
			int bad = 0;
			for (size_t i = 0; i < 3 * (size_t)w * h; i++) {
				float l = (float)img_srgb_to_linear(rgb[i] / 255.0);
				bad += img[i] != (half ? half_to_float(img_half_from_float(l)) : l);
				bad += (int)floor(srgb_encode(img[i]) * 255 + 0.5) != rgb[i];
			}
			CHECK(bad == 0);
			const struct exr_attr *t = find_attr(a, na, "chromaticities");
			static const float chroma[8] = { 0.64f, 0.33f, 0.30f, 0.60f, 0.15f, 0.06f, 0.3127f, 0.3290f };
			CHECK(t && !strcmp(t->type, "chromaticities") && t->size == 32);
			for (int i = 0; t && i < 8; i++)
				CHECK(lef(t->v + 4 * i) == chroma[i]);
			t = find_attr(a, na, "colorInteropID");
			CHECK(t && !strcmp(t->type, "string") && t->size == 16 && !memcmp(t->v, "lin_rec709_scene", 16));
			t = find_attr(a, na, "software");
			CHECK(t && !strcmp(t->type, "string") && t->size == 14 && !memcmp(t->v, "portray 0.11.0", 14));
			t = find_attr(a, na, "source");
			CHECK(t && t->size == 22 && !memcmp(t->v, "sc?ne?one.sce\nline two", 22));
			t = find_attr(a, na, "renderTime");
			CHECK(t && t->size == 7 && !memcmp(t->v, "1.250 s", 7));
			CHECK(na == 13);
			free(img);
			free(out);
			free(rgb);
		}
	}

	/* floats: unclamped, decoded, and halves overflow to infinity */
	float fl[6] = { 2.0f, -0.25f, 1e6f, 0.5f, 0, 1 };
	struct img_desc df = { .w = 2, .h = 1, .type = IMG_RGBF32, .pixels = fl, .format = IMG_EXR };
	for (int half = 0; half < 2; half++) {
		df.format = half ? IMG_EXR_HALF : IMG_EXR;
		CHECK(img_encode(&df, &out, &n) == 0);
		struct exr_attr a[32];
		int na, ptype;
		float *img = NULL;
		uint32_t bw, bh;
		CHECK(exr_parse(out, n, a, &na, &img, &bw, &bh, &ptype) == 0);
		for (int i = 0; img && i < 6; i++) {
			float l = (float)img_srgb_to_linear(fl[i]);
			CHECK(img[i] == (half ? half_to_float(img_half_from_float(l)) : l));
		}
		CHECK(img && img[0] > 1 && img[1] < 0);
		CHECK(img && (half ? isinf(img[2]) : img[2] > 1e13f));
		free(img);
		free(out);
	}
}

/* ---- what is refused ---------------------------------------------------------------- */

static void test_invalid(void)
{
	uint8_t px[3] = { 1, 2, 3 }, *out = (uint8_t *)px;
	size_t n = 5;
	struct img_desc d = { .w = 1, .h = 1, .type = IMG_RGB8, .pixels = px, .format = IMG_EXR };
	CHECK(img_encode(&d, &out, &n) == 0);
	free(out);
	static const char *bad_keys[] = { "", " Lead", "Trail ", "Two  spaces", "Tab\tkey",
					  "A key that is far too long for an OpenEXR name", "Channels", "Compression",
					  "Data window", "color interop ID" };
	for (size_t i = 0; i < sizeof bad_keys / sizeof bad_keys[0]; i++) {
		struct img_text t = { bad_keys[i], "v" };
		d.text = &t;
		d.n_text = 1;
		errno = 0;
		out = px;
		CHECK(img_encode(&d, &out, &n) == -1 && errno == EINVAL && out == NULL);
	}
	struct img_text two[2] = { { "Render time", "1" }, { "render Time", "2" } }; /* both renderTime */
	d.text = two;
	d.n_text = 2;
	CHECK(img_encode(&d, &out, &n) == -1 && errno == EINVAL);
	two[1].key = "Comment";
	two[1].value = NULL;
	CHECK(img_encode(&d, &out, &n) == -1 && errno == EINVAL);
	two[1].value = "fine";
	CHECK(img_encode(&d, &out, &n) == 0);
	free(out);
	d.n_text = IMG_TEXT_MAX + 1;
	CHECK(img_encode(&d, &out, &n) == -1 && errno == EINVAL);
	d.n_text = 0;
	d.text = NULL;
	d.w = 0;
	CHECK(img_encode(&d, &out, &n) == -1 && errno == EINVAL);
	d.w = LIM_IMAGE_SIDE + 1u;
	CHECK(img_encode(&d, &out, &n) == -1 && errno == EINVAL);
	d.w = 1;
	d.pixels = NULL;
	CHECK(img_encode(&d, &out, &n) == -1 && errno == EINVAL);
	d.pixels = px;
	d.format = IMG_N_FORMATS;
	CHECK(img_encode(&d, &out, &n) == -1 && errno == EINVAL);
	d.format = IMG_PNG;
	CHECK(img_write_opts(NULL, &d) == -1 && errno == EINVAL);
	CHECK(img_write_opts("", &d) == -1 && errno == EINVAL);

	/* a long value is cut, not refused */
	char *longv = malloc(IMG_TEXT_VALUE_MAX + 100);
	memset(longv, 'x', IMG_TEXT_VALUE_MAX + 99);
	longv[IMG_TEXT_VALUE_MAX + 99] = 0;
	struct img_text lt = { "Comment", longv };
	d.text = &lt;
	d.n_text = 1;
	CHECK(img_encode(&d, &out, &n) == 0);
	struct chunk c[16];
	int k = png_chunks(out, n, c, 16);
	CHECK(k > 4 && !strcmp(c[4].type, "tEXt") && c[4].len == 8 + IMG_TEXT_VALUE_MAX);
	free(out);
	free(longv);
}

/* ---- files and standard output ------------------------------------------------------ */

/* What img_write_opts(path "-") puts on standard output, read through a pipe. */
static uint8_t *via_stdout(const struct img_desc *d, size_t *n, int *rc)
{
	int pfd[2];
	if (pipe(pfd) != 0)
		return NULL;
	pid_t pid = fork();
	if (pid == 0) {
		close(pfd[0]);
		dup2(pfd[1], STDOUT_FILENO);
		close(pfd[1]);
		_exit(img_write_opts("-", d) == 0 ? 0 : 1);
	}
	close(pfd[1]);
	size_t cap = 1 << 16, len = 0;
	uint8_t *b = malloc(cap);
	ssize_t r;
	while ((r = read(pfd[0], b + len, cap - len)) > 0) {
		len += (size_t)r;
		if (len == cap)
			b = realloc(b, cap *= 2);
	}
	close(pfd[0]);
	int st = 0;
	waitpid(pid, &st, 0);
	*rc = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
	*n = len;
	return b;
}

static void test_write(void)
{
	char dir[] = "/tmp/test_imgfmt_XXXXXX";
	if (!mkdtemp(dir)) {
		CHECK(0);
		return;
	}
	uint32_t w = 150, h = 90; /* PFM and EXR go through the sink's buffer several times */
	uint8_t *rgb = make_rgb(w, h);
	char path[300];
	for (int f = 0; f < IMG_N_FORMATS; f++) {
		struct img_desc d = { .w = w, .h = h, .type = IMG_RGB8, .pixels = rgb, .format = (enum img_format)f,
				      .text = texts, .n_text = 3 };
		uint8_t *want = NULL;
		size_t wn = 0;
		CHECK(img_encode(&d, &want, &wn) == 0);
		snprintf(path, sizeof path, "%s/out%d%s", dir, f, img_format_ext(d.format));
		CHECK(img_write_opts(path, &d) == 0);
		size_t n = 0;
		uint8_t *got = slurp(path, &n);
		CHECK(got && n == wn && memcmp(got, want, n) == 0);
		free(got);
		int rc = -1;
		got = via_stdout(&d, &n, &rc);
		CHECK(rc == 0 && got && n == wn && memcmp(got, want, n) == 0);
		free(got);
		unlink(path);
		free(want);
	}
	/* "-" is a file name to the plain writer, as it always was */
	char cwd[4096];
	CHECK(getcwd(cwd, sizeof cwd) != NULL);
	CHECK(chdir(dir) == 0);
	CHECK(img_write("-", rgb, w, h) == 0);
	struct stat st;
	CHECK(stat("-", &st) == 0 && S_ISREG(st.st_mode));
	unlink("-");
	CHECK(chdir(cwd) == 0);
	CHECK(rmdir(dir) == 0);
	free(rgb);
}

static int count_entries(const char *dir)
{
	char cmd[400];
	snprintf(cmd, sizeof cmd, "ls -A '%s' | wc -l", dir);
	FILE *p = popen(cmd, "r");
	int k = -1;
	if (p) {
		if (fscanf(p, "%d", &k) != 1)
			k = -1;
		pclose(p);
	}
	return k;
}

static void test_output_check(void)
{
	char dir[] = "/tmp/test_imgchk_XXXXXX";
	if (!mkdtemp(dir)) {
		CHECK(0);
		return;
	}
	char path[400], got[400];
	CHECK(img_output_check("-", got, sizeof got) == 0);
	/* standard output closed, or open for reading only: refused */
	pid_t pid = fork();
	if (pid == 0) {
		close(STDOUT_FILENO);
		int closed = img_output_check("-", NULL, 0) == -1 && errno == EBADF;
		int fd = open("/dev/null", O_RDONLY); /* takes descriptor 1 */
		int rdonly = fd == STDOUT_FILENO && img_output_check("-", got, sizeof got) == -1 && errno == EACCES &&
			     strcmp(got, "standard output") == 0;
		_exit(closed && rdonly ? 0 : 1);
	}
	int st = -1;
	waitpid(pid, &st, 0);
	CHECK(WIFEXITED(st) && WEXITSTATUS(st) == 0);
	snprintf(path, sizeof path, "%s/new.png", dir);
	CHECK(img_output_check(path, got, sizeof got) == 0);
	CHECK(count_entries(dir) == 0); /* the probe is gone */
	CHECK(img_output_check("/dev/null", got, sizeof got) == 0);

	snprintf(path, sizeof path, "%s/no/such/x.png", dir);
	errno = 0;
	CHECK(img_output_check(path, got, sizeof got) == -1 && errno == ENOENT);
	char want[400];
	snprintf(want, sizeof want, "%s/no/such", dir);
	CHECK(strcmp(got, want) == 0);

	CHECK(img_output_check(dir, got, sizeof got) == -1 && errno == EISDIR && strcmp(got, dir) == 0);
	snprintf(path, sizeof path, "%s/", dir);
	CHECK(img_output_check(path, got, sizeof got) == -1 && errno == EISDIR);

	snprintf(path, sizeof path, "%s/file", dir);
	FILE *f = fopen(path, "w");
	CHECK(f != NULL);
	if (f)
		fclose(f);
	snprintf(path, sizeof path, "%s/file/x.png", dir);
	CHECK(img_output_check(path, got, sizeof got) == -1 && errno == ENOTDIR);

	/* a link is judged by its target's directory */
	snprintf(path, sizeof path, "%s/sub", dir);
	CHECK(mkdir(path, 0755) == 0);
	snprintf(path, sizeof path, "%s/link.png", dir);
	CHECK(symlink("sub/real.png", path) == 0 || errno == EEXIST);
	char target[400];
	snprintf(target, sizeof target, "%s/sub/real.png", dir);
	f = fopen(target, "w");
	if (f)
		fclose(f);
	CHECK(img_output_check(path, got, sizeof got) == 0);

	/* a directory that refuses files; root is refused nothing by mode bits */
	snprintf(path, sizeof path, "%s/sub", dir);
	chmod(path, 0555);
	snprintf(path, sizeof path, "%s/sub/x.png", dir);
	if (geteuid() != 0) {
		CHECK(img_output_check(path, got, sizeof got) == -1 && errno == EACCES);
		snprintf(want, sizeof want, "%s/sub", dir);
		CHECK(strcmp(got, want) == 0);
	}
	/* whatever the directory refuses, the probe leaves nothing behind */
	snprintf(path, sizeof path, "%s/sub", dir);
	chmod(path, 0755);
	CHECK(count_entries(path) == 1);

	unlink(target);
	snprintf(path, sizeof path, "%s/link.png", dir);
	unlink(path);
	snprintf(path, sizeof path, "%s/sub", dir);
	rmdir(path);
	snprintf(path, sizeof path, "%s/file", dir);
	unlink(path);
	CHECK(rmdir(dir) == 0);
	CHECK(img_output_check(NULL, NULL, 0) == -1 && errno == EINVAL);
	CHECK(img_output_check("", NULL, 0) == -1 && errno == EINVAL);
}

int main(void)
{
	test_names();
	test_half();
	test_srgb();
	test_png8();
	test_png16();
	test_ppm_pfm();
	test_exr();
	test_invalid();
	test_write();
	test_output_check();
	TEST_MAIN_END();
}
