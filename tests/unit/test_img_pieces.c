/*
 * test_img_pieces.c - the PNG encoder deflates its filtered rows in fixed
 * pieces on several threads (img_set_threads): the bytes are the same for
 * 1, 2, 3 and 8 threads, and every PNG decodes (tests/unit/inflate.h, an
 * independent strict decoder) to the pixels encoded. Images mix rows that
 * compress (the pieces end anywhere in a byte) with noise (stored blocks,
 * which must start on a byte of the whole stream), in both orders, and
 * sizes of less than one piece, exactly one, and several.
 */
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/img.h"
#include "tests/unit/check.h"
#include "tests/unit/inflate.h"

static uint32_t seed = 77;
static uint32_t rnd(void)
{
	seed ^= seed << 13;
	seed ^= seed >> 17;
	seed ^= seed << 5;
	return seed;
}

/* w x h pixels: bands of noise_rows noisy rows between bands of smooth ones
 * (noise_first: the noise first). */
static uint8_t *mixed(uint32_t w, uint32_t h, uint32_t band, int noise_first)
{
	uint8_t *img = malloc(3 * (size_t)w * h);
	for (uint32_t y = 0; img && y < h; y++) {
		int noisy = ((y / band) % 2 == 0) == (noise_first != 0);
		for (uint32_t x = 0; x < w; x++)
			for (int c = 0; c < 3; c++)
				img[3 * ((size_t)y * w + x) + c] =
					noisy ? (uint8_t)rnd() : (uint8_t)(x / 3 + y / 2 + 40 * c);
	}
	return img;
}

static void check_image(const char *name, const uint8_t *img, uint32_t w, uint32_t h)
{
	static const unsigned threads[] = { 1, 2, 3, 8 };
	uint8_t *first = NULL;
	size_t first_n = 0;
	for (size_t t = 0; t < sizeof threads / sizeof *threads; t++) {
		img_set_threads(threads[t]);
		uint8_t *png = NULL;
		size_t n = 0;
		CHECK(img_png_encode(img, w, h, &png, &n) == 0);
		if (!png)
			continue;
		if (!first) {
			uint8_t *back = NULL;
			uint32_t bw = 0, bh = 0;
			int idat = 0, blocks[3] = { 0 }, filters[5] = { 0 };
			int dr = inf_png(png, n, &back, &bw, &bh, &idat, blocks, filters);
			if (dr)
				fprintf(stderr, "%s: decoder error %d\n", name, dr);
			CHECK(dr == 0);
			CHECK(dr || (bw == w && bh == h && !memcmp(back, img, 3 * (size_t)w * h)));
			free(back);
			first = png;
			first_n = n;
			continue;
		}
		bool same = n == first_n && !memcmp(png, first, n);
		if (!same)
			fprintf(stderr, "%s: %u threads give other bytes than one\n", name, threads[t]);
		CHECK(same);
		free(png);
	}
	free(first);
}

int main(void)
{
	static const struct {
		uint32_t w, h, band;
	} cases[] = {
		{ 100, 50, 7 },      /* well under one piece */
		{ 512, 170, 40 },    /* (1 + 1536) * 170 = 261,290: just under one piece (262,144) */
		{ 700, 600, 90 },    /* several pieces */
		{ 1280, 960, 333 },  /* a render's size */
		{ 640, 480, 1 },     /* noise every other row */
	};
	for (size_t i = 0; i < sizeof cases / sizeof *cases; i++)
		for (int nf = 0; nf < 2; nf++) {
			char name[64];
			snprintf(name, sizeof name, "%ux%u band %u%s", cases[i].w, cases[i].h, cases[i].band,
				 nf ? " noise first" : "");
			uint8_t *img = mixed(cases[i].w, cases[i].h, cases[i].band, nf);
			CHECK(img != NULL);
			if (img)
				check_image(name, img, cases[i].w, cases[i].h);
			free(img);
		}
	img_set_threads(0);
	TEST_MAIN_END();
}
