/*
 * bench_primary.c - the A/B figure for work on the tracing core: primary
 * rays (camera ray + closest hit, no shading) through every pixel centre,
 * made and traced as the renderer makes and traces them (8x8 blocks of
 * pixels as sixteen 2x2 blocks, their rays from filter_eye_block when the
 * scene's filter is standard, through accel_intersect64; --4x4: 4x4 blocks
 * through accel_intersect16; --2x2: each 2x2 block through
 * accel_intersect4; without filter_eye_block, or a size not a multiple of
 * the block's, 2x2 blocks; --single: cam_ray and one accel_intersect per
 * ray), one thread, the
 * same frame traced FRAMES times; prints the best frame's
 * rate in Mrays/s of thread CPU time (repeatable to ~0.5% where the
 * wall-clock figures of bench_render wander by ~5%) and a hash of every hit
 * (t, object, normals), which shows whether a change kept each hit bit for
 * bit; it also checks that both ways give that same hash. docs/performance.md
 * says how to use it.
 *
 *   bench_primary [--single | --4x4 | --2x2] [SCENE [FRAMES [WIDTHxHEIGHT]]]
 *
 * Defaults: tests/data/spd/balls_s4.sce, 15 frames, 1280x960 (the issue 3
 * target's scene and size). Not a test: prints figures only.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/accel.h"
#include "common/camera.h"
#include "common/filter.h"
#include "bench/bench_scene.h"

/* One frame of single rays; the hash of its hits (row by row) when hash is
 * not NULL. */
static void frame_single(const struct accel *a, const struct cam *c, uint64_t *hash)
{
	uint64_t h64 = 1469598103934665603ull;
	for (uint32_t y = 0; y < c->h; y++)
		for (uint32_t x = 0; x < c->w; x++) {
			struct ray r = cam_ray(c, x + 0.5, y + 0.5);
			struct hit h;
			bool hit = accel_intersect(a, &r, &h);
			if (hash)
				h64 = bs_hash_hit(h64, hit, &h);
		}
	if (hash)
		*hash = h64;
}

/* The same frame in 2x2 blocks, as the renderer traces it: a whole
 * block's rays from filter_eye_block when fc is not NULL (a
 * filter_single_ray chain: the same rays as cam_ray bit for bit), else
 * from cam_ray (a block past the image's edge repeats its last row or
 * column); the same hash. */
static void frame_packets(const struct accel *a, const struct cam *c, const struct filter_chain *fc, uint64_t *hash,
			  struct hit *row2, bool *hit2)
{
	uint64_t h64 = 1469598103934665603ull;
	for (uint32_t y = 0; y < c->h; y += 2) {
		for (uint32_t x = 0; x < c->w; x += 2) {
			struct ray r[4];
			struct hit h[4];
			bool hit[4];
			if (fc && x + 1 < c->w && y + 1 < c->h) {
				uint64_t seed[4];
				filter_eye_block(fc, x, y, r, seed);
				accel_intersect4(a, r, h, hit);
			} else {
				bs_block_hits(a, c, x, y, r, h, hit);
			}
			if (!hash)
				continue;
			for (uint32_t i = 0; i < 4; i++) {
				size_t k = (size_t)(i >> 1) * c->w + x + (i & 1);
				if (x + (i & 1) < c->w) {
					row2[k] = h[i];
					hit2[k] = hit[i];
				}
			}
		}
		if (!hash)
			continue;
		for (uint32_t j = 0; j < 2 && y + j < c->h; j++)
			for (uint32_t x = 0; x < c->w; x++)
				h64 = bs_hash_hit(h64, hit2[(size_t)j * c->w + x], &row2[(size_t)j * c->w + x]);
	}
	if (hash)
		*hash = h64;
}

/* The same frame in side x side blocks (4: accel_intersect16, 8:
 * accel_intersect64) of 2x2 blocks from filter_eye_block, in the
 * renderer's order (render.c: 2x2 block b at (2 (b & 1) + 4 (b >> 2 & 1),
 * 2 (b >> 1 & 1) + 4 (b >> 3))); the image's size a multiple of side; the
 * same hash. */
static void frame_big(const struct accel *a, const struct cam *c, const struct filter_chain *fc, uint32_t side,
		      uint64_t *hash, struct hit *rows, bool *hits)
{
	uint64_t h64 = 1469598103934665603ull;
	const int nb = (int)(side * side / 4);
	for (uint32_t y = 0; y + side - 1 < c->h; y += side) {
		for (uint32_t x = 0; x + side - 1 < c->w; x += side) {
			struct ray r[64];
			struct hit h[64];
			bool hit[64];
			uint64_t seed[64];
			for (int b = 0; b < nb; b++) {
				uint32_t bx = 2 * (b & 1) + 4 * (b >> 2 & 1), by = 2 * (b >> 1 & 1) + 4 * (b >> 3);
				filter_eye_block(fc, x + bx, y + by, r + 4 * b, seed + 4 * b);
			}
			if (side == 8)
				accel_intersect64(a, r, h, hit);
			else
				accel_intersect16(a, r, h, hit);
			if (!hash)
				continue;
			for (int i = 0; i < 4 * nb; i++) {
				int b = i >> 2, k = i & 3;
				uint32_t px = 2 * (b & 1) + 4 * (b >> 2 & 1) + (k & 1);
				uint32_t py = 2 * (b >> 1 & 1) + 4 * (b >> 3) + (k >> 1);
				size_t at = (size_t)py * c->w + x + px;
				rows[at] = h[i];
				hits[at] = hit[i];
			}
		}
		if (!hash)
			continue;
		for (size_t k = 0; k < side * (size_t)c->w; k++)
			h64 = bs_hash_hit(h64, hits[k], &rows[k]);
	}
	if (hash)
		*hash = h64;
}

int main(int argc, char **argv)
{
	uint32_t side = 8; /* --4x4, --2x2: smaller blocks */
	if (argc > 1 && (strcmp(argv[1], "--4x4") == 0 || strcmp(argv[1], "--2x2") == 0)) {
		side = argv[1][2] == '4' ? 4 : 2;
		argc--;
		argv++;
	}
	bool single = argc > 1 && strcmp(argv[1], "--single") == 0;
	if (single) {
		argc--;
		argv++;
	}
	struct bs_bench b;
	int rc = bs_start(argc, argv, 15, "bench_primary [--single | --4x4 | --2x2] [SCENE [FRAMES [WIDTHxHEIGHT]]]",
			  &b);
	if (rc)
		return rc;
	/* the renderer's eye rays when it makes them by filter_eye_block */
	struct filter_chain *fc = malloc(sizeof *fc);
	if (fc && (filter_chain_init(fc, &b.s->camera, &b.s->image, b.w, b.h) < 0 || !filter_single_ray(fc))) {
		free(fc);
		fc = NULL;
	}
	struct hit *row2 = malloc(8 * (size_t)b.w * sizeof *row2);
	bool *hit2 = malloc(8 * (size_t)b.w * sizeof *hit2);
	if (!row2 || !hit2) {
		fprintf(stderr, "bench_primary: out of memory\n");
		return 1;
	}
	/* hashing costs time: frames of their own, untimed */
	uint64_t hash = 0, hash_p = 0;
	frame_single(b.a, &b.c, &hash);
	if (!fc || b.w % side || b.h % side)
		side = 2;
	if (side > 2)
		frame_big(b.a, &b.c, fc, side, &hash_p, row2, hit2);
	else
		frame_packets(b.a, &b.c, fc, &hash_p, row2, hit2);
	double best = INFINITY;
	for (int i = 0; i < b.frames; i++) {
		double t0 = bs_cpu_now();
		if (single)
			frame_single(b.a, &b.c, NULL);
		else if (side > 2)
			frame_big(b.a, &b.c, fc, side, NULL, NULL, NULL);
		else
			frame_packets(b.a, &b.c, fc, NULL, NULL, NULL);
		double t = bs_cpu_now() - t0;
		best = t < best ? t : best;
	}
	printf("%s %ux%u: %.2f Mrays/s on 1 thread, %s (best of %d frames, thread CPU time); hits hash %016llx%s\n",
	       b.path, b.w, b.h, (double)b.w * b.h / best * 1e-6,
	       single ? "single rays"
	       : side == 8 ? "8x8 blocks of 2x2 packets, filter_eye_block"
	       : side == 4 ? "4x4 blocks of 2x2 packets, filter_eye_block"
	       : fc   ? "2x2 packets, filter_eye_block"
		      : "2x2 packets, cam_ray",
	       b.frames,
	       (unsigned long long)hash, hash == hash_p ? "" : " MISMATCH: packets and single rays differ");
	free(fc);
	free(row2);
	free(hit2);
	accel_free(b.a);
	scene_free(b.s);
	return 0;
}
