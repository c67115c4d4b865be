/*
 * bench_png.c - PNG encoder speed: milliseconds per encode (best of 5, one
 * thread) and the file's size, for binary PPM images named on the command
 * line (e.g. renders of tetra_s4 and teapot at 1280x960), or, with none,
 * two made-up 1280x960 images: a render's look (flat background, shaded
 * discs, a little noise) and smooth gradients. Under callgrind (`-n 1`) it
 * counts the encoder's instructions alone.
 *
 *   build/bench/bench_png [-n RUNS] [FILE.ppm...]
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "common/img.h"

static double now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* A binary PPM (maxval 255, no comments) into *w, *h; malloc'd pixels or NULL. */
static uint8_t *read_ppm(const char *path, uint32_t *w, uint32_t *h)
{
	FILE *f = fopen(path, "rb");
	unsigned mw, mh, maxv;
	uint8_t *p = NULL;
	if (f && fscanf(f, "P6 %u %u %u", &mw, &mh, &maxv) == 3 && maxv == 255 && fgetc(f) != EOF && mw && mh &&
	    mw <= 65536 && mh <= 65536) {
		size_t n = 3 * (size_t)mw * mh;
		p = malloc(n);
		if (p && fread(p, 1, n, f) != n) {
			free(p);
			p = NULL;
		}
		*w = mw;
		*h = mh;
	}
	if (f)
		fclose(f);
	return p;
}

static uint8_t *made_up(int smooth, uint32_t w, uint32_t h)
{
	uint8_t *p = malloc(3 * (size_t)w * h);
	uint32_t seed = 1;
	for (size_t i = 0; p && i < 3 * (size_t)w * h; i++) {
		size_t px = i / 3, x = px % w, y = px / w, c = i % 3;
		if (smooth) {
			p[i] = (uint8_t)(x / 3 + y / 2 + 40 * c);
			continue;
		}
		long dx = (long)(x % 200) - 100, dy = (long)(y % 150) - 75, d2 = dx * dx + dy * dy;
		uint8_t v = d2 < 3600 ? (uint8_t)(200 - d2 / 20 + 20 * c) : (uint8_t)(20 + y / 8 + 10 * c);
		seed = seed * 1103515245u + 12345u;
		p[i] = (seed >> 16) % 50 == 0 ? (uint8_t)(v ^ 1) : v;
	}
	return p;
}

static void run(const char *name, const uint8_t *px, uint32_t w, uint32_t h, int runs)
{
	double best = 1e30;
	size_t n = 0;
	for (int r = 0; r < runs; r++) {
		uint8_t *png = NULL;
		double t0 = now();
		if (img_png_encode(px, w, h, &png, &n) < 0) {
			printf("png %s: encode failed\n", name);
			return;
		}
		double t = now() - t0;
		free(png);
		best = t < best ? t : best;
	}
	printf("png %s: %ux%u, %zu bytes, %.1f ms (%.0f MB/s of pixels)\n", name, w, h, n, best * 1e3,
	       3.0 * w * h / best / 1e6);
}

int main(int argc, char **argv)
{
	int runs = 5, i = 1;
	if (argc > 2 && strcmp(argv[1], "-n") == 0) {
		runs = atoi(argv[2]) > 0 ? atoi(argv[2]) : 1;
		i = 3;
	}
	img_set_threads(1);
	if (i >= argc) {
		for (int smooth = 0; smooth < 2; smooth++) {
			uint8_t *p = made_up(smooth, 1280, 960);
			if (p)
				run(smooth ? "gradients" : "render-like", p, 1280, 960, runs);
			free(p);
		}
		return 0;
	}
	for (; i < argc; i++) {
		uint32_t w = 0, h = 0;
		uint8_t *p = read_ppm(argv[i], &w, &h);
		if (!p) {
			printf("png %s: not a binary PPM with maxval 255\n", argv[i]);
			continue;
		}
		run(argv[i], p, w, h, runs);
		free(p);
	}
	return 0;
}
