/*
 * bench_primary.c - the A/B figure for work on the tracing core: primary
 * rays (camera ray + closest hit, no shading) through every pixel centre,
 * one thread, the same frame traced FRAMES times; prints the best frame's
 * rate in Mrays/s of thread CPU time (repeatable to ~0.5% where the
 * wall-clock figures of bench_render wander by ~5%) and a hash of every hit
 * (t, object, normals), which shows whether a change kept each hit bit for
 * bit. docs/performance.md says how to use it.
 *
 *   bench_primary [SCENE [FRAMES [WIDTHxHEIGHT]]]
 *
 * Defaults: tests/data/spd/balls_s4.sce, 15 frames, 1280x960 (the issue 3
 * target's scene and size). Not a test: prints figures only.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "common/accel.h"
#include "common/camera.h"
#include "common/parse.h"

static double cpu_now(void)
{
	struct timespec t;
	clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* FNV-1a over n bytes. */
static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
	const unsigned char *c = p;
	for (size_t i = 0; i < n; i++) {
		h ^= c[i];
		h *= 1099511628211ull;
	}
	return h;
}

/* One frame; the hash of its hits when hash is not NULL. */
static void frame(const struct accel *a, const struct cam *c, uint64_t *hash)
{
	uint64_t h64 = 1469598103934665603ull;
	for (uint32_t y = 0; y < c->h; y++)
		for (uint32_t x = 0; x < c->w; x++) {
			struct ray r = cam_ray(c, x + 0.5, y + 0.5);
			struct hit h;
			bool hit = accel_intersect(a, &r, &h);
			if (!hash)
				continue;
			if (hit) {
				h64 = fnv(h64, &h.t, sizeof h.t);
				h64 = fnv(h64, &h.object, sizeof h.object);
				h64 = fnv(h64, &h.n, sizeof h.n);
				h64 = fnv(h64, &h.ng, sizeof h.ng);
			} else {
				h64 = fnv(h64, "-", 1);
			}
		}
	if (hash)
		*hash = h64;
}

int main(int argc, char **argv)
{
	const char *path = argc > 1 ? argv[1] : "tests/data/spd/balls_s4.sce";
	int frames = argc > 2 ? atoi(argv[2]) : 15;
	unsigned w = 1280, h = 960;
	if (argc > 3 && sscanf(argv[3], "%ux%u", &w, &h) != 2) {
		fprintf(stderr, "usage: bench_primary [SCENE [FRAMES [WIDTHxHEIGHT]]]\n");
		return 64;
	}
	if (frames < 1 || w == 0 || h == 0 || w > 100000 || h > 100000) {
		fprintf(stderr, "bench_primary: bad frame count or size\n");
		return 64;
	}
	struct scene *s;
	struct scene_error err;
	if (parse_files(NULL, path, &s, &err)) {
		printf("%s: %s\n", path, err.msg);
		return 1;
	}
	struct accel *a;
	if (accel_build(s, &a, &err)) {
		printf("%s: %s\n", path, err.msg);
		scene_free(s);
		return 1;
	}
	struct cam c;
	if (cam_init(&c, &s->camera, w, h) < 0) {
		printf("%s: degenerate camera\n", path);
		accel_free(a);
		scene_free(s);
		return 1;
	}
	uint64_t hash = 0;
	frame(a, &c, &hash); /* hashing costs time: a frame of its own, untimed */
	double best = INFINITY;
	for (int i = 0; i < frames; i++) {
		double t0 = cpu_now();
		frame(a, &c, NULL);
		double t = cpu_now() - t0;
		best = t < best ? t : best;
	}
	printf("%s %ux%u: %.2f Mrays/s on 1 thread (best of %d frames, thread CPU time); hits hash %016llx\n", path, w,
	       h, (double)w * h / best * 1e-6, frames, (unsigned long long)hash);
	accel_free(a);
	scene_free(s);
	return 0;
}
