/*
 * test_progress.c - the progress line (master/progress.c) on a fake clock:
 * the line fits any width (a 50-column terminal with six workers included),
 * the ETA follows the recent tile rate rather than elapsed/done, and the
 * region tiling (common/tiles.c) covers a region's pixels once each.
 */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "common/tiles.h"
#include "master/progress.h"

static const char *names[6] = {
	"render-node-01.example.com:7070", "render-node-02.example.com:7070", "10.0.0.3:7070",
	"[2001:db8::4]:7070",              "render-node-05.example.com:7070", "127.0.0.1:40123",
};

static void fits_everywhere(void)
{
	struct progress p;
	progress_init(&p, 12345, PROGRESS_BAR, 0, 100.0);
	for (int k = 1; k <= 40; k++)
		progress_sample(&p, (uint64_t)k * 100, 100.0 + k * 0.5);
	struct progress_peer peers[6];
	for (int i = 0; i < 6; i++)
		peers[i] = (struct progress_peer){ names[i], 12.5 + i, i != 2, i == 4 };
	struct progress_farm farm = { 33.3, peers, 6 };
	char line[PROGRESS_LINE_MAX];
	for (int cols = 1; cols <= 300; cols++) {
		for (int f = 0; f < 2; f++) {
			size_t n = progress_format(&p, 121.0, cols, f ? &farm : NULL, line, sizeof line);
			CHECK(n == strlen(line));
			CHECK(n <= (size_t)cols);
			CHECK(strchr(line, '\n') == NULL);
			if (cols >= 20)
				CHECK(strstr(line, "ETA ") != NULL); /* the ETA survives every abbreviation */
			if (cols >= 20)
				CHECK(strstr(line, "32%") != NULL);
		}
	}
	/* a 50-column terminal (49 used) with six workers: summed up, on one line */
	size_t n = progress_format(&p, 121.0, 49, &farm, line, sizeof line);
	CHECK(n <= 49);
	CHECK(strstr(line, "4/6") != NULL); /* four working (one dropped, one not ready) */
	/* a wide one: every worker by its whole name, and a bar */
	progress_format(&p, 121.0, 400, &farm, line, sizeof line);
	for (int i = 0; i < 6; i++)
		CHECK(strstr(line, names[i]) != NULL);
	CHECK(strstr(line, "(dropped)") != NULL);
	CHECK(strchr(line, '[') != NULL);
	/* 160 columns (where the old line wrapped): each worker's rate, in order */
	n = progress_format(&p, 121.0, 159, &farm, line, sizeof line);
	CHECK(n <= 159);
	CHECK(strstr(line, "| w 12.5 13.5 14.5- 15.5 x 17.5") != NULL);
	/* 200 columns: names without domains, cut to their last characters */
	n = progress_format(&p, 121.0, 199, &farm, line, sizeof line);
	CHECK(n <= 199);
	CHECK(strstr(line, "| ~-node-01:7070 12.5 |") != NULL);
	CHECK(strstr(line, "| 10.0.0.3:7070 14.5- |") != NULL);
	CHECK(strstr(line, "| ~-node-05:7070 x |") != NULL);
	/* a local render at 80 columns: the whole words and a bar */
	n = progress_format(&p, 121.0, 79, NULL, line, sizeof line);
	CHECK(n <= 79);
	CHECK(strstr(line, "4000/12345 tiles") != NULL);
	CHECK(strstr(line, "elapsed") != NULL);
	CHECK(strstr(line, "[###") != NULL);
	/* no width limit (lines off a terminal): the richest layout */
	n = progress_format(&p, 121.0, 0, &farm, line, sizeof line);
	CHECK(strstr(line, names[0]) != NULL && strstr(line, "elapsed") != NULL);
}

static void eta(void)
{
	struct progress p;
	double t0 = 50.0;
	progress_init(&p, 1000, PROGRESS_OFF, 0, t0);
	CHECK(progress_eta(&p, t0) < 0);
	progress_sample(&p, 0, t0 + 0.5);
	CHECK(progress_eta(&p, t0 + 0.5) < 0); /* no tile yet */
	/* a steady 20 tiles/s: the ETA is the truth once there are samples */
	double t = t0 + 0.5;
	uint64_t done = 0;
	for (int i = 0; i < 4; i++) {
		t += 0.25;
		done += 5;
		progress_sample(&p, done, t);
	}
	CHECK(progress_eta(&p, t) < 0); /* under PROGRESS_ETA_AFTER_S of samples */
	for (int i = 0; i < 40; i++) {
		t += 0.25;
		done += 5;
		progress_sample(&p, done, t);
	}
	CHECK_NEAR(progress_eta(&p, t), (1000.0 - done) / 20, 1.5);

	/* the issue's render: the first part of the image is cheap (sky), the
	 * rest five times dearer. elapsed/done then promises far too little;
	 * the smoothed rate catches up within seconds */
	progress_init(&p, 1000, PROGRESS_OFF, 0, 0);
	t = 0;
	done = 0;
	while (done < 300) { /* 100 tiles/s for 3 s */
		t += 0.2;
		done += 20;
		progress_sample(&p, done, t);
	}
	while (t < 3 + 10.0) { /* then 20 tiles/s, for 10 s */
		t += 0.2;
		done += 4;
		progress_sample(&p, done, t);
	}
	double truth = (1000.0 - done) / 20, naive = t * (1000.0 - done) / done;
	double e = progress_eta(&p, t);
	CHECK(e > 0);
	CHECK(fabs(e - truth) < 0.12 * truth);
	CHECK(fabs(naive - truth) > 0.3 * truth); /* what the old bar said */
	/* merged samples: many calls within PROGRESS_SAMPLE_S do not disturb the rate */
	double before = p.rate;
	progress_sample(&p, done + 1, t + 0.01);
	progress_sample(&p, done + 2, t + 0.02);
	CHECK_NEAR(p.rate, before, 1e-12);
	CHECK(p.done == done + 2);
	/* the end */
	progress_sample(&p, 1000, t + 1);
	CHECK(progress_eta(&p, t + 1) == 0);
	char line[PROGRESS_LINE_MAX];
	progress_format(&p, t + 1, 0, NULL, line, sizeof line);
	CHECK(strstr(line, "100% ") != NULL && strstr(line, "ETA 0:00") != NULL);
}

static void times(void)
{
	struct progress p;
	char line[PROGRESS_LINE_MAX];
	progress_init(&p, 10, PROGRESS_OFF, 0, 0);
	progress_sample(&p, 1, 3725.2);
	progress_format(&p, 3725.2, 0, NULL, line, sizeof line);
	CHECK(strstr(line, "1:02:05 elapsed") != NULL);
	CHECK(strstr(line, "ETA -:--") != NULL);
	CHECK(strncmp(line, " 10% ", 5) == 0);
}

/* a region's tiles cover its pixels once each, none outside, rectangles in
 * the whole image's coordinates */
static void region_tiling(void)
{
	const uint32_t W = 53, H = 41;
	uint8_t *seen = calloc(W * H, 1);
	struct tiling tg;
	tiling_init_region(&tg, W, H, 8, 5, 7, 50, 30);
	CHECK(tg.w == W && tg.h == H);
	CHECK(tg.nx == 6 && tg.ny == 3 && tg.n == 18);
	for (uint32_t i = 0; i < tg.n; i++) {
		struct tile_rect r = tiling_rect(&tg, i);
		CHECK(r.w > 0 && r.h > 0 && r.w <= 8 && r.h <= 8);
		for (uint32_t y = r.y; y < r.y + r.h; y++)
			for (uint32_t x = r.x; x < r.x + r.w; x++)
				seen[y * W + x]++;
	}
	int bad = 0;
	for (uint32_t y = 0; y < H; y++)
		for (uint32_t x = 0; x < W; x++)
			bad += seen[y * W + x] != (x >= 5 && x < 50 && y >= 7 && y < 30);
	CHECK(bad == 0);
	struct tile_rect r0 = tiling_rect(&tg, 0), rl = tiling_rect(&tg, tg.n - 1);
	CHECK(r0.x == 5 && r0.y == 7);
	CHECK(rl.x + rl.w == 50 && rl.y + rl.h == 30);
	/* the whole image is the region 0, 0, w, h */
	struct tiling a, b;
	tiling_init(&a, W, H, 16);
	tiling_init_region(&b, W, H, 16, 0, 0, W, H);
	CHECK(memcmp(&a, &b, sizeof a) == 0);
	free(seen);
}

int main(void)
{
	fits_everywhere();
	eta();
	times();
	region_tiling();
	TEST_MAIN_END();
}
