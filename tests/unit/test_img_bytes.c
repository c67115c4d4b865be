/*
 * test_img_bytes.c - the PNG encoder's exact bytes. Speed work on the
 * encoder (match search, hashing, Adler-32, filters, bit writer) must not
 * move a byte, so each image below, made from a fixed recipe, must encode
 * to the length and CRC-32 recorded here (taken from the encoder as it was
 * before round 6's speed work). The recipes reach every path: stored,
 * fixed and dynamic blocks, code lengths cut to 15 and 7 bits, matches of
 * every length and distance class, several deflate pieces, 16-bit rows,
 * float pixels and the metadata chunks.
 *
 * The five row filters are checked byte for byte against the PNG
 * specification's definitions on random rows (the SIMD paths against the
 * formula), whole and in pieces.
 *
 * `test_img_bytes --print` prints the table for the encoder it is linked
 * with (to record it again, after a change that means to move bytes).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/crc32.h"
#include "common/img.h"
#include "common/img_int.h"
#include "tests/unit/check.h"

static uint32_t seed;
static uint32_t rnd(void)
{
	seed ^= seed << 13;
	seed ^= seed >> 17;
	seed ^= seed << 5;
	return seed;
}

enum recipe {
	R_NOISE,     /* every byte random: stored blocks */
	R_FLAT,      /* one colour: runs of MAX_MATCH */
	R_SMOOTH,    /* gradients: filters Sub/Up/Avg/Paeth win, short codes */
	R_BANDS,     /* noise and smooth bands of 17 rows: stored between compressed */
	R_FEW,       /* 4 values: literals and short matches */
	R_GEOMETRIC, /* byte k with probability 2^-(k+1): codes longer than 15 bits cut */
	R_TILED,     /* a tile of noise repeated: distances of every class, to 32 KiB */
	R_SCENE,     /* a render's look: flat sky, shaded discs, a little noise */
	R_N
};

/* Pixel bytes (3 per pixel) for recipe r; malloc'd. */
static uint8_t *make(enum recipe r, uint32_t w, uint32_t h, uint32_t s)
{
	size_t n = 3 * (size_t)w * h;
	uint8_t *p = malloc(n ? n : 1);
	seed = s;
	for (size_t i = 0; p && i < n; i++) {
		size_t px = i / 3, x = px % w, y = px / w, c = i % 3;
		uint8_t v = 0;
		switch (r) {
		case R_NOISE: v = (uint8_t)rnd(); break;
		case R_FLAT: v = (uint8_t)(60 + 50 * c); break;
		case R_SMOOTH: v = (uint8_t)(x / 3 + y / 2 + 40 * c); break;
		case R_BANDS: v = (y / 17) % 2 ? (uint8_t)rnd() : (uint8_t)(x * 2 + y + 30 * c); break;
		case R_FEW: v = (uint8_t)(rnd() % 4 * 64); break;
		case R_GEOMETRIC: {
			uint32_t b = rnd() | 1u << 24, k = 0;
			while (!(b & 1)) {
				b >>= 1;
				k++;
			}
			v = (uint8_t)(k * 7);
			break;
		}
		case R_TILED: {
			size_t tw = 1 + (s % 4000);
			seed = (uint32_t)(((y % 61) * tw + x % tw) * 2654435761u + c + 1);
			v = (uint8_t)rnd();
			break;
		}
		case R_SCENE: {
			long dx = (long)(x % 200) - 100, dy = (long)(y % 150) - 75;
			long d2 = dx * dx + dy * dy;
			if (d2 < 60 * 60)
				v = (uint8_t)(200 - d2 / 20 + 20 * c);
			else
				v = (uint8_t)(20 + y / 8 + 10 * c);
			if (rnd() % 50 == 0)
				v ^= 1;
			break;
		}
		default: break;
		}
		p[i] = v;
	}
	return p;
}

struct kase {
	enum recipe r;
	uint32_t w, h, s;
	enum img_format f;
	int floats; /* pixels given as floats (v / 255, and every 7th a little off) */
	int text;   /* with two text items */
	size_t len; /* expected */
	uint32_t crc;
};

static struct kase cases[] = {
	/* clang-format off */
	{ R_NOISE, 1, 1, 1, IMG_PNG, 0, 0, 142, 0x789f0be4 },
	{ R_NOISE, 3, 5, 2, IMG_PNG, 0, 0, 190, 0x8008828b },
	{ R_FLAT, 7, 300, 3, IMG_PNG, 0, 0, 179, 0x3e908924 },
	{ R_SMOOTH, 300, 7, 4, IMG_PNG, 0, 0, 196, 0x23d21f2b },
	{ R_NOISE, 512, 512, 5, IMG_PNG, 0, 0, 787348, 0xf6b8ecc8 },
	{ R_FLAT, 1500, 1100, 6, IMG_PNG, 0, 0, 7895, 0xdad16ba4 },
	{ R_SMOOTH, 640, 480, 7, IMG_PNG, 0, 0, 2863, 0x63f745ec },
	{ R_BANDS, 700, 400, 8, IMG_PNG, 0, 0, 415202, 0xa0a01454 },
	{ R_FEW, 401, 333, 9, IMG_PNG, 0, 0, 137239, 0x3228fd31 },
	{ R_GEOMETRIC, 500, 300, 10, IMG_PNG, 0, 0, 144282, 0x2bf9e2f1 },
	{ R_TILED, 800, 300, 11, IMG_PNG, 0, 0, 15225, 0x21d07b22 },
	{ R_TILED, 1200, 200, 3000, IMG_PNG, 0, 0, 690304, 0x0868335a },
	{ R_TILED, 900, 200, 255, IMG_PNG, 0, 0, 153942, 0xb17c28e2 },
	{ R_SCENE, 1280, 960, 12, IMG_PNG, 0, 0, 321735, 0x3e97b55f },
	{ R_SCENE, 320, 240, 13, IMG_PNG, 0, 1, 24284, 0xe57a907a },
	{ R_SCENE, 320, 240, 14, IMG_PNG16, 0, 0, 32909, 0xdaa1ad23 },
	{ R_BANDS, 200, 150, 15, IMG_PNG16, 1, 1, 85435, 0x8e25bae6 },
	{ R_SMOOTH, 333, 111, 16, IMG_PNG, 1, 0, 1613, 0x57b7abdd },
	{ R_NOISE, 100, 100, 17, IMG_PNG16, 0, 0, 54004, 0x1b694849 },
	/* clang-format on */
};

/* Encodes case k; 0 with *out (malloc'd) or -1. */
static int encode(const struct kase *k, uint8_t **out, size_t *n)
{
	uint8_t *px = make(k->r, k->w, k->h, k->s);
	float *fl = NULL;
	size_t np = 3 * (size_t)k->w * k->h;
	if (k->floats) {
		fl = malloc(np * sizeof *fl);
		for (size_t i = 0; fl && i < np; i++)
			fl[i] = px[i] / 255.0f + (i % 7 == 0 ? 0.0013f * (float)(i % 5) - 0.003f : 0.0f);
	}
	static const struct img_text text[2] = { { "Software", "portray" }, { "Comment", "bytes\tunder\ntest" } };
	struct img_desc d = { .w = k->w,
			      .h = k->h,
			      .type = fl ? IMG_RGBF32 : IMG_RGB8,
			      .pixels = fl ? (const void *)fl : (const void *)px,
			      .format = k->f,
			      .text = k->text ? text : NULL,
			      .n_text = k->text ? 2 : 0 };
	int rc = px && (fl || !k->floats) ? img_encode(&d, out, n) : -1;
	free(px);
	free(fl);
	return rc;
}

/* The specification's filter f of byte i (a left, b up, c up-left; 0
 * outside the image). */
static uint8_t spec_filter(int f, const uint8_t *cur, const uint8_t *up, size_t k, size_t i)
{
	int x = cur[i], a = i >= k ? cur[i - k] : 0, b = up ? up[i] : 0, c = up && i >= k ? up[i - k] : 0;
	int p = a + b - c, pa = abs(p - a), pb = abs(p - b), pc = abs(p - c);
	int pred[5] = { 0, a, b, (a + b) / 2, pa <= pb && pa <= pc ? a : pb <= pc ? b : c };
	return (uint8_t)(x - pred[f]);
}

static void test_filters(void)
{
	enum { N = 4099 };
	static uint8_t cur[N], up[N], d[N];
	int same = 1;
	for (int round = 0; round < 40; round++) {
		seed = 1000u + (uint32_t)round;
		for (size_t i = 0; i < N; i++) {
			/* random bytes, near-flat bytes and the extremes: every sign case */
			uint32_t r = rnd();
			cur[i] = round % 4 == 0 ? (uint8_t)r : round % 4 == 1 ? (uint8_t)(128 + r % 5) : (r & 1 ? 255 : 0);
			up[i] = round % 4 == 3 ? (uint8_t)(r >> 8) : (uint8_t)(cur[i] + (r >> 16) % 7 - 3);
		}
		size_t k = round % 2 ? 6 : 3, n = round < 20 ? N : 1 + (size_t)round * 3;
		for (int f = 0; f < 5; f++) {
			for (int has_up = 0; has_up < 2; has_up++) {
				const uint8_t *u = has_up ? up : NULL;
				memset(d, 0xAA, N);
				img_png_filter_bytes(f, cur, u, k, 0, n, d);
				for (size_t i = 0; i < n; i++)
					same &= d[i] == spec_filter(f, cur, u, k, i);
				/* in pieces, as the encoder's steps (the first piece holds the first pixel) */
				memset(d, 0xAA, N);
				size_t cut1 = n > 2 * k ? k + rnd() % (n - 2 * k) : n, cut2 = cut1 + (n - cut1) / 2;
				img_png_filter_bytes(f, cur, u, k, 0, cut1, d);
				img_png_filter_bytes(f, cur, u, k, cut1, cut2, d);
				img_png_filter_bytes(f, cur, u, k, cut2, n, d);
				for (size_t i = 0; i < n; i++)
					same &= d[i] == spec_filter(f, cur, u, k, i);
			}
		}
	}
	CHECK(same);
}

int main(int argc, char **argv)
{
	int print = argc > 1 && strcmp(argv[1], "--print") == 0;
	size_t nk = sizeof cases / sizeof cases[0];
	if (!print)
		test_filters();
	for (unsigned threads = 1; threads <= 2; threads++) {
		img_set_threads(threads);
		for (size_t i = 0; i < nk; i++) {
			uint8_t *png = NULL;
			size_t n = 0;
			CHECK(encode(&cases[i], &png, &n) == 0);
			uint32_t crc = png ? crc32_update(0, png, n) : 0;
			free(png);
			if (print && threads == 1) {
				printf("case %zu: %zu, 0x%08x\n", i, n, crc);
				continue;
			}
			if (n != cases[i].len || crc != cases[i].crc)
				fprintf(stderr, "case %zu (%u threads): %zu bytes, crc 0x%08x; want %zu, 0x%08x\n", i,
					threads, n, crc, cases[i].len, cases[i].crc);
			CHECK(n == cases[i].len && crc == cases[i].crc);
		}
	}
	TEST_MAIN_END();
}
