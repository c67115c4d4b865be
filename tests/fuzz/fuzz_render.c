/*
 * fuzz_render.c - libFuzzer target for the tracer: a scene from arbitrary
 * bytes (no file access), built and rendered at 8x6 twice, as one tile and
 * as two tiles of other widths (3 and 5 pixels: other 2x2 blocks, so other
 * packets and single rays), and the bytes compared: a difference aborts,
 * as a crash would. A watchdog cancels a scene that takes more than half a
 * second (2^63 instances are legal), so only crashes, sanitizer reports
 * and differences are findings.
 */
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "common/parse.h"
#include "common/render.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

enum { W = 8, H = 6, BUDGET_MS = 500 };

struct watchdog {
	pthread_mutex_t m;
	pthread_cond_t c;
	int done;
	atomic_int cancel;
};

static void *watch(void *arg)
{
	struct watchdog *w = arg;
	struct timespec until;
	clock_gettime(CLOCK_REALTIME, &until);
	until.tv_nsec += (long)BUDGET_MS * 1000000L;
	until.tv_sec += until.tv_nsec / 1000000000L;
	until.tv_nsec %= 1000000000L;
	pthread_mutex_lock(&w->m);
	int rc = 0;
	while (!w->done && rc == 0)
		rc = pthread_cond_timedwait(&w->c, &w->m, &until);
	if (!w->done)
		atomic_store(&w->cancel, 1);
	pthread_mutex_unlock(&w->m);
	return NULL;
}

static void render_both(const struct scene *s, atomic_int *cancel)
{
	struct renderer *r = NULL;
	struct scene_error err;
	if (renderer_new_cancellable(s, &r, &err, cancel) != 0)
		return;
	if (renderer_set_size(r, W, H) == 0) {
		static uint8_t one[W * H * 3], two[W * H * 3], part[W * H * 3];
		struct tile_rect whole = { 0, 0, W, H }, left = { 0, 0, 3, H }, right = { 3, 0, W - 3, H };
		int ok = renderer_tile_cancellable(r, whole, one, cancel);
		ok = ok && renderer_tile_cancellable(r, left, part, cancel);
		for (uint32_t y = 0; ok && y < H; y++)
			memcpy(two + (size_t)y * W * 3, part + (size_t)y * left.w * 3, (size_t)left.w * 3);
		ok = ok && renderer_tile_cancellable(r, right, part, cancel);
		for (uint32_t y = 0; ok && y < H; y++)
			memcpy(two + ((size_t)y * W + right.x) * 3, part + (size_t)y * right.w * 3, (size_t)right.w * 3);
		if (ok && memcmp(one, two, sizeof one) != 0)
			abort(); /* the same pixels whatever the tiles: a finding */
	}
	renderer_free(r);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct scene *s = NULL;
	struct scene_error err;
	if (parse_buffer("fuzz.sce", (const char *)data, size, 0, &s, &err) == 0) {
		struct watchdog w = { PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, 0, 0 };
		pthread_t t;
		int have = pthread_create(&t, NULL, watch, &w) == 0;
		render_both(s, have ? &w.cancel : NULL);
		if (have) {
			pthread_mutex_lock(&w.m);
			w.done = 1;
			pthread_cond_signal(&w.c);
			pthread_mutex_unlock(&w.m);
			pthread_join(t, NULL);
		}
	}
	scene_free(s);
	return 0;
}
