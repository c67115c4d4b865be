/*
 * test_sched.c - the master's tile scheduler (master/sched.c) with no socket:
 * the test plays the event loop (workers taking, releasing, delivering, some
 * lying) and the local threads (some on real pthreads), and checks the queue
 * order, requeues, duplicates at the tail, image assembly, the local threads'
 * blocking take, audits and distrust, a dropped worker, and a random mix of
 * all of them that must end with the exact image.
 */
#include <pthread.h>
#include <sched.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "check.h"
#include "master/sched.h"

/* the odd image most sections use: 5 x 3 tiles of 8, the last column 5
 * wide and the last row 7 high */
#define IMG_W 37u
#define IMG_H 23u
#define SIDE 8u
#define N_TILES 15u
#define SENTINEL 0xee

/* how long a thread the scheduler should let go may take to return (only
 * a broken scheduler makes the test wait this long; a thread that should
 * stay blocked is watched for BLOCKED_MS) */
#define PATIENCE_MS 5000
#define BLOCKED_MS 30

/* the variant a worker lying about its pixels delivers */
#define LIE 7

/* A pixel of tile id as variant v renders it (0: the true image). Depends on
 * the pixel's place in the image and on the tile, so a tile written at the
 * wrong place, with the wrong stride or from another tile shows. */
static uint8_t pat(uint32_t id, uint32_t x, uint32_t y, uint32_t c, uint32_t v)
{
	return (uint8_t)(id * 41u + x * 7u + y * 13u + c * 101u + v * 59u + 1u);
}

/* Fills rgb (the tile's rows, top to bottom) with tile id as variant v. */
static void fill(const struct sched *s, uint32_t id, uint32_t v, uint8_t *rgb)
{
	struct tile_rect r = sched_rect(s, id);
	for (uint32_t y = 0; y < r.h; y++)
		for (uint32_t x = 0; x < r.w; x++)
			for (uint32_t c = 0; c < 3; c++)
				rgb[((size_t)y * r.w + x) * 3 + c] = pat(id, r.x + x, r.y + y, c, v);
}

/* Writes tile id as variant v into an image of tg (what the scheduler should do). */
static void paint(const struct tiling *tg, uint8_t *img, uint32_t id, uint32_t v)
{
	struct tile_rect r = tiling_rect(tg, id);
	for (uint32_t y = r.y; y < r.y + r.h; y++)
		for (uint32_t x = r.x; x < r.x + r.w; x++)
			for (uint32_t c = 0; c < 3; c++)
				img[((size_t)y * tg->w + x) * 3 + c] = pat(id, x, y, c, v);
}

/* Whether tile id of img is variant v. */
static bool rect_is(const struct tiling *tg, const uint8_t *img, uint32_t id, uint32_t v)
{
	struct tile_rect r = tiling_rect(tg, id);
	for (uint32_t y = r.y; y < r.y + r.h; y++)
		for (uint32_t x = r.x; x < r.x + r.w; x++)
			for (uint32_t c = 0; c < 3; c++)
				if (img[((size_t)y * tg->w + x) * 3 + c] != pat(id, x, y, c, v))
					return false;
	return true;
}

/* Whether tile id of img still holds the sentinel everywhere. */
static bool rect_blank(const struct tiling *tg, const uint8_t *img, uint32_t id)
{
	struct tile_rect r = tiling_rect(tg, id);
	for (uint32_t y = r.y; y < r.y + r.h; y++)
		for (uint32_t x = r.x; x < r.x + r.w; x++)
			for (uint32_t c = 0; c < 3; c++)
				if (img[((size_t)y * tg->w + x) * 3 + c] != SENTINEL)
					return false;
	return true;
}

/* An image of tg full of the sentinel (caller frees). */
static uint8_t *blank_image(const struct tiling *tg)
{
	size_t n = (size_t)tg->w * tg->h * 3;
	uint8_t *img = malloc(n);
	if (img)
		memset(img, SENTINEL, n);
	return img;
}

static void wake_count(void *arg) { atomic_fetch_add((atomic_int *)arg, 1); }

static struct sched_stats stats_of(struct sched *s)
{
	struct sched_stats st;
	sched_stats(s, &st);
	return st;
}

/* Worker who delivers tile id as variant v; the outcome, *cancel the other holder. */
static enum sched_outcome deliver(struct sched *s, uint32_t id, uint16_t who, uint32_t v, bool audit,
				  uint16_t *cancel)
{
	uint8_t rgb[SIDE * SIDE * 3];
	fill(s, id, v, rgb);
	return sched_result(s, id, who, rgb, audit, cancel);
}

/* A local thread finishing (ok) or abandoning tile id, its pixels variant v. */
static void local_done(struct sched *s, uint32_t id, bool audit, uint32_t v, bool ok)
{
	uint8_t rgb[SIDE * SIDE * 3];
	fill(s, id, v, rgb);
	sched_local_done(s, id, audit, rgb, ok);
}

static void sleep_ms(int ms)
{
	struct timespec ts = { ms / 1000, (long)(ms % 1000) * 1000000L };
	nanosleep(&ts, NULL);
}

/* ---- one sched_local_take on its own thread ---- */

struct taker {
	pthread_t th;
	struct sched *s;
	bool audit_only;
	atomic_int returned;
	int ret;
	uint32_t id;
	bool audit;
};

static void *taker_main(void *arg)
{
	struct taker *t = arg;
	t->ret = sched_local_take(t->s, t->audit_only, &t->id, &t->audit);
	atomic_store(&t->returned, 1);
	return NULL;
}

static bool taker_start(struct taker *t, struct sched *s, bool audit_only)
{
	memset(t, 0, sizeof *t);
	t->s = s;
	t->audit_only = audit_only;
	atomic_init(&t->returned, 0);
	return pthread_create(&t->th, NULL, taker_main, t) == 0;
}

/* Whether t's take returned within ms milliseconds. */
static bool taker_returned(struct taker *t, int ms)
{
	for (int i = 0; i < ms && !atomic_load(&t->returned); i++)
		sleep_ms(1);
	return atomic_load(&t->returned);
}

/* A local thread that even sched_stop does not free: the scheduler is
 * broken beyond testing further (and s cannot be freed under it). */
static void give_up(const char *why)
{
	check_failed++;
	fprintf(stderr, "test_sched: %s: giving up\n", why);
	printf("%d checks, %d failed\n", check_total, check_failed);
	exit(1);
}

/* Joins t; one stuck (a broken scheduler) is freed by sched_stop. */
static void taker_join(struct taker *t)
{
	if (!taker_returned(t, PATIENCE_MS)) {
		sched_stop(t->s);
		if (!taker_returned(t, PATIENCE_MS))
			give_up("a local thread stays blocked after sched_stop");
	}
	pthread_join(t->th, NULL);
}

/* sched_local_take, run on a thread so that one blocking where it should
 * not fails a check instead of hanging the test (the scheduler is then
 * stopped to free it). */
static int local_take(struct sched *s, bool audit_only, uint32_t *id, bool *audit)
{
	struct taker t;
	if (!taker_start(&t, s, audit_only))
		give_up("no thread");
	bool returned = taker_returned(&t, PATIENCE_MS);
	CHECK(returned);
	taker_join(&t);
	*id = t.id;
	*audit = t.audit;
	return returned ? t.ret : -1;
}

/* ---- take ---- */

/* One taker gets the tiles in row-major order, each once; an empty queue
 * gives SCHED_NO_TILE without dup_ok and never the taker's own tile with it;
 * after sched_stop nothing is taken by anyone. */
static void test_take(void)
{
	struct tiling tg, none;
	tiling_init(&tg, IMG_W, IMG_H, SIDE);
	tiling_init(&none, 0, 0, SIDE);
	uint8_t *img = blank_image(&tg);
	CHECK(tg.n == N_TILES);
	CHECK(sched_new(&tg, 3, SCHED_MAX_WORKERS + 1, img, 0, 1, NULL, NULL) == NULL);
	CHECK(sched_new(&none, 3, 1, img, 0, 1, NULL, NULL) == NULL);

	struct sched *s = sched_new(&tg, 3, 2, img, 0, 1, NULL, NULL);
	CHECK(s != NULL);
	struct sched_stats st = stats_of(s);
	CHECK(st.n == N_TILES && st.done == 0 && st.redispatched == 0 && st.duplicates == 0);
	struct tile_rect last = sched_rect(s, N_TILES - 1);
	CHECK(last.x == 32 && last.y == 16 && last.w == 5 && last.h == 7);

	bool in_order = true;
	for (uint32_t i = 0; i < N_TILES; i++)
		if (sched_take(s, 0, false, 1.0 + i) != i)
			in_order = false;
	CHECK(in_order);
	CHECK(sched_take(s, 0, false, 20) == SCHED_NO_TILE);
	CHECK(sched_take(s, 1, false, 20) == SCHED_NO_TILE);
	/* every tile is worker 0's alone: no duplicate of its own for it */
	CHECK(sched_take(s, 0, true, 20) == SCHED_NO_TILE);
	st = stats_of(s);
	CHECK(st.duplicates == 0 && st.redispatched == 0);
	/* worker 1 may duplicate (the oldest: tile 0), worker 0 still not */
	CHECK(sched_take(s, 1, true, 21) == 0);
	CHECK(sched_take(s, 0, true, 21) == SCHED_NO_TILE);
	sched_free(s);

	s = sched_new(&tg, 3, 2, img, 0, 1, NULL, NULL);
	CHECK(sched_take(s, 0, false, 1) == 0);
	CHECK(atomic_load(sched_stop_flag(s)) == 0);
	sched_stop(s);
	CHECK(atomic_load(sched_stop_flag(s)) != 0);
	CHECK(sched_take(s, 0, false, 2) == SCHED_NO_TILE);
	CHECK(sched_take(s, 1, false, 2) == SCHED_NO_TILE);
	CHECK(sched_take(s, 1, true, 2) == SCHED_NO_TILE);
	uint32_t id = 0;
	bool audit = false;
	CHECK(local_take(s, false, &id, &audit) == 0); /* stopped: does not block */
	CHECK(!sched_finished(s));
	CHECK(stats_of(s).done == 0);
	sched_free(s);
	free(img);
}

/* ---- requeue / release ---- */

/* A released tile goes to the front of the queue and counts as redispatched
 * when taken again; a tile someone else still holds, or a done one, is not
 * requeued; releasing twice queues once. */
static void test_requeue(void)
{
	struct tiling tg;
	tiling_init(&tg, IMG_W, IMG_H, SIDE);
	uint8_t *img = blank_image(&tg);
	struct sched *s = sched_new(&tg, 3, 3, img, 0, 1, NULL, NULL);
	CHECK(sched_take(s, 0, false, 1) == 0);
	CHECK(sched_take(s, 0, false, 2) == 1);
	CHECK(sched_take(s, 0, false, 3) == 2);
	sched_release(s, 1, 0);
	CHECK(stats_of(s).redispatched == 0);
	CHECK(sched_take(s, 1, false, 4) == 1); /* the front, not tile 3 */
	CHECK(stats_of(s).redispatched == 1);
	/* released in the order 1, 0: the last released is the first taken */
	sched_release(s, 1, 1);
	sched_release(s, 0, 0);
	CHECK(sched_take(s, 2, false, 5) == 0);
	CHECK(sched_take(s, 2, false, 6) == 1);
	CHECK(sched_take(s, 2, false, 7) == 3);
	CHECK(stats_of(s).redispatched == 3);
	/* a release by one who does not hold the tile changes nothing */
	sched_release(s, 2, 1);
	CHECK(sched_take(s, 1, false, 8) == 4);
	sched_free(s);

	/* two tiles: a held duplicate keeps its tile out of the queue */
	tiling_init(&tg, 16, 8, SIDE);
	s = sched_new(&tg, 3, 3, img, 0, 1, NULL, NULL);
	CHECK(sched_take(s, 0, false, 1) == 0);
	CHECK(sched_take(s, 0, false, 2) == 1);
	CHECK(sched_take(s, 1, true, 3) == 0); /* the oldest */
	sched_release(s, 0, 1);
	CHECK(sched_take(s, 2, false, 4) == SCHED_NO_TILE); /* worker 0 still holds 0 */
	sched_release(s, 0, 0);
	sched_release(s, 0, 0); /* twice: queued once */
	CHECK(sched_take(s, 2, false, 5) == 0);
	CHECK(sched_take(s, 1, false, 6) == SCHED_NO_TILE);
	/* a done tile stays done: releases by its former holders requeue nothing */
	CHECK(sched_take(s, 1, true, 7) == 0);
	uint16_t cancel;
	CHECK(deliver(s, 0, 2, 0, false, &cancel) == SCHED_USED);
	CHECK(cancel == 1);
	sched_release(s, 0, 1);
	sched_release(s, 0, 2);
	CHECK(sched_take(s, 1, false, 8) == SCHED_NO_TILE);
	CHECK(sched_take(s, 2, true, 9) == 1); /* the only tile left to duplicate */
	CHECK(stats_of(s).done == 1);
	sched_free(s);
	free(img);
}

/* ---- duplicates ---- */

/* With the queue empty an idle taker duplicates the oldest outstanding tile
 * (by the time it was handed out) held by one other taker: never its own,
 * never one with two holders or a claim. The first result wins and cancels
 * the other holder; the second is wasted. */
static void test_duplicate(void)
{
	struct tiling tg;
	tiling_init(&tg, 24, 8, SIDE); /* 3 tiles */
	uint8_t *img = blank_image(&tg);
	struct sched *s = sched_new(&tg, 3, 5, img, 0, 1, NULL, NULL);
	/* handed out at times 3, 2, 1: tile 2 is the oldest, tile 0 the newest */
	CHECK(sched_take(s, 0, false, 3) == 0);
	CHECK(sched_take(s, 1, false, 2) == 1);
	CHECK(sched_take(s, 1, false, 1) == 2);
	CHECK(sched_take(s, 1, false, 4) == SCHED_NO_TILE);
	CHECK(sched_take(s, 1, true, 4) == 0);  /* its own 2 and 1 are older */
	CHECK(sched_take(s, 2, true, 5) == 2);  /* the oldest held by one */
	CHECK(sched_take(s, 3, true, 6) == 1);  /* 0 and 2 have two holders */
	CHECK(sched_take(s, 4, true, 7) == SCHED_NO_TILE);
	CHECK(sched_take(s, 2, true, 8) == SCHED_NO_TILE);
	struct sched_stats st = stats_of(s);
	CHECK(st.duplicates == 3 && st.redispatched == 0);

	uint16_t cancel = 0;
	CHECK(deliver(s, 2, 2, 2, false, &cancel) == SCHED_USED);
	CHECK(cancel == 1);
	CHECK(rect_is(&tg, img, 2, 2));
	CHECK(deliver(s, 2, 1, 1, false, &cancel) == SCHED_WASTED);
	CHECK(cancel == SCHED_NONE);
	CHECK(rect_is(&tg, img, 2, 2)); /* the first one's pixels stay */
	st = stats_of(s);
	CHECK(st.dup_wasted == 1 && st.done == 1);
	/* the other way round: the duplicate's holder loses */
	CHECK(deliver(s, 0, 0, 0, false, &cancel) == SCHED_USED);
	CHECK(cancel == 1);
	CHECK(deliver(s, 0, 1, 1, false, &cancel) == SCHED_WASTED);
	CHECK(rect_is(&tg, img, 0, 0));
	CHECK(deliver(s, 1, 3, 3, false, &cancel) == SCHED_USED);
	CHECK(cancel == 1);
	st = stats_of(s);
	CHECK(st.dup_wasted == 2 && st.done == 3);
	CHECK(sched_finished(s));
	sched_free(s);

	/* a claim awaiting its audit is never duplicated, even with one holder
	 * left (the local thread that traces it anyway) */
	memset(img, SENTINEL, (size_t)tg.w * tg.h * 3);
	s = sched_new(&tg, 3, 3, img, 1.0, 1, NULL, NULL);
	uint32_t id = SCHED_NO_TILE;
	bool audit = true;
	CHECK(local_take(s, false, &id, &audit) == 1);
	CHECK(id == 0 && !audit);
	CHECK(sched_take(s, 0, false, 1) == 1);
	CHECK(sched_take(s, 1, false, 2) == 2);
	CHECK(sched_take(s, 0, true, 3) == 0); /* a duplicate of the local thread's */
	CHECK(deliver(s, 0, 0, 0, true, &cancel) == SCHED_USED);
	CHECK(cancel == SCHED_NONE); /* the local thread is no worker to cancel */
	CHECK(rect_blank(&tg, img, 0));
	CHECK(sched_take(s, 2, true, 4) == 1); /* not 0, though the oldest */
	CHECK(sched_take(s, 2, true, 5) == 2);
	CHECK(sched_take(s, 2, true, 6) == SCHED_NO_TILE);
	local_done(s, 0, false, 0, true); /* settles the claim */
	st = stats_of(s);
	CHECK(st.audits == 1 && st.done == 1 && st.local_done == 1);
	CHECK(rect_is(&tg, img, 0, 0));
	sched_free(s);

	/* a local thread's tile is as old as when it took it: one a worker
	 * had before is older */
	tiling_init(&tg, 16, 8, SIDE); /* 2 tiles */
	s = sched_new(&tg, 3, 2, img, 0, 1, NULL, NULL);
	CHECK(sched_take(s, 0, false, 10) == 0);
	CHECK(local_take(s, false, &id, &audit) == 1);
	CHECK(id == 1 && !audit);
	CHECK(sched_take(s, 1, true, 11) == 0);
	sched_free(s);
	free(img);
}

/* ---- image assembly ---- */

/* Each result writes exactly its rectangle; the render is finished (and
 * the loop woken, and a blocked local thread let go) only after the last. */
static void test_image(void)
{
	struct tiling tg;
	tiling_init(&tg, IMG_W, IMG_H, SIDE);
	uint8_t *img = blank_image(&tg), *want = blank_image(&tg);
	atomic_int wakes;
	atomic_init(&wakes, 0);
	struct sched *s = sched_new(&tg, 3, 2, img, 0, 1, wake_count, &wakes);
	for (uint32_t i = 0; i < N_TILES; i++)
		CHECK(sched_take(s, (uint16_t)(i % 2), false, 1.0 + i) == i);
	struct taker t;
	bool started = false;
	bool exact = true, early = false;
	for (uint32_t k = 0; k < N_TILES; k++) {
		uint32_t id = (k * 7u + 3u) % N_TILES; /* a scrambled order, the corner tile included */
		if (k == N_TILES - 1) {
			started = taker_start(&t, s, true);
			CHECK(started);
			CHECK(!taker_returned(&t, BLOCKED_MS));
		}
		uint16_t cancel;
		if (deliver(s, id, (uint16_t)(id % 2), 0, false, &cancel) != SCHED_USED)
			exact = false;
		paint(&tg, want, id, 0);
		if (memcmp(img, want, (size_t)tg.w * tg.h * 3) != 0)
			exact = false;
		if (k < N_TILES - 1 && (sched_finished(s) || atomic_load(&wakes) != 0))
			early = true;
	}
	CHECK(exact);
	CHECK(!early);
	CHECK(sched_finished(s));
	CHECK(atomic_load(&wakes) == 1);
	if (started) {
		CHECK(taker_returned(&t, PATIENCE_MS));
		taker_join(&t);
		CHECK(t.ret == 0);
	}
	struct sched_stats st = stats_of(s);
	CHECK(st.done == N_TILES && st.local_done == 0 && st.dup_wasted == 0);
	CHECK(sched_take(s, 0, true, 99) == SCHED_NO_TILE);
	sched_free(s);
	free(img);
	free(want);
}

/* ---- local threads ---- */

/* Audits come before ordinary tiles; an audit-only thread waits for an
 * audit; a blocked thread is let go by sched_stop or a new audit; a tile a
 * local thread abandons goes back to the queue, an abandoned audit back to
 * the audits. */
static void test_local(void)
{
	struct tiling tg;
	tiling_init(&tg, 32, 8, SIDE); /* 4 tiles */
	uint8_t *img = blank_image(&tg);
	struct sched *s = sched_new(&tg, 3, 2, img, 1.0, 1, NULL, NULL);
	uint32_t id = SCHED_NO_TILE;
	bool audit = false;
	uint16_t cancel;
	CHECK(sched_take(s, 0, false, 1) == 0);
	CHECK(deliver(s, 0, 0, 0, true, &cancel) == SCHED_USED);
	CHECK(local_take(s, false, &id, &audit) == 1);
	CHECK(id == 0 && audit);
	CHECK(local_take(s, false, &id, &audit) == 1);
	CHECK(id == 1 && !audit);
	/* an abandoned audit is audited again */
	local_done(s, 0, true, 0, false);
	CHECK(stats_of(s).audits == 0);
	CHECK(rect_blank(&tg, img, 0));
	CHECK(local_take(s, false, &id, &audit) == 1);
	CHECK(id == 0 && audit);
	local_done(s, 0, true, 0, true);
	CHECK(stats_of(s).audits == 1 && stats_of(s).done == 1);
	/* an abandoned ordinary tile goes back to the front of the queue */
	local_done(s, 1, false, 0, false);
	CHECK(stats_of(s).done == 1);
	CHECK(sched_take(s, 1, false, 2) == 1);
	CHECK(stats_of(s).redispatched == 1);

	/* tiles 2 and 3 wait, but an audit-only thread wants an audit */
	struct taker t;
	CHECK(taker_start(&t, s, true));
	CHECK(!taker_returned(&t, BLOCKED_MS));
	CHECK(sched_take(s, 0, false, 3) == 2);
	CHECK(deliver(s, 2, 0, 0, true, &cancel) == SCHED_USED); /* a new audit */
	CHECK(taker_returned(&t, PATIENCE_MS));
	taker_join(&t);
	CHECK(t.ret == 1 && t.id == 2 && t.audit);
	local_done(s, 2, true, 0, true);
	/* one with nothing to do is let go by sched_stop */
	CHECK(taker_start(&t, s, true));
	CHECK(!taker_returned(&t, BLOCKED_MS));
	sched_stop(s);
	CHECK(taker_returned(&t, PATIENCE_MS));
	taker_join(&t);
	CHECK(t.ret == 0);
	sched_free(s);

	/* an ordinary (non-audit-only) thread blocks too when all is held */
	tiling_init(&tg, 8, 8, SIDE);
	s = sched_new(&tg, 3, 1, img, 0, 1, NULL, NULL);
	CHECK(local_take(s, false, &id, &audit) == 1);
	CHECK(id == 0 && !audit);
	CHECK(taker_start(&t, s, false));
	CHECK(!taker_returned(&t, BLOCKED_MS));
	sched_stop(s);
	CHECK(taker_returned(&t, PATIENCE_MS));
	taker_join(&t);
	CHECK(t.ret == 0);
	sched_free(s);

	/*
	 * A claim on a tile a local thread traces anyway skips its audit (the
	 * local result settles it); if that thread abandons the tile, the
	 * claim must get its audit after all, or the render never ends.
	 */
	tiling_init(&tg, 24, 8, SIDE); /* 3 tiles */
	memset(img, SENTINEL, (size_t)tg.w * tg.h * 3);
	s = sched_new(&tg, 3, 2, img, 1.0, 1, NULL, NULL);
	CHECK(local_take(s, false, &id, &audit) == 1);
	CHECK(id == 0 && !audit);
	CHECK(sched_take(s, 0, false, 1) == 1);
	CHECK(sched_take(s, 1, false, 2) == 2);
	CHECK(sched_take(s, 0, true, 3) == 0);
	CHECK(deliver(s, 0, 0, 0, true, &cancel) == SCHED_USED); /* a claim; the local thread holds 0 */
	sched_release(s, 2, 1);
	CHECK(local_take(s, false, &id, &audit) == 1); /* passes over the audit of 0 */
	CHECK(id == 2 && !audit);
	local_done(s, 0, false, 0, false);
	CHECK(local_take(s, false, &id, &audit) == 1);
	CHECK(id == 0 && audit);
	local_done(s, 0, audit, 0, true);
	CHECK(stats_of(s).audits == 1 && rect_is(&tg, img, 0, 0));
	sched_free(s);
	free(img);
}

/* ---- audits ---- */

/* Counts the ids below n that sched_audit_due samples for who after delivered results. */
static uint32_t count_due(const struct sched *s, uint16_t who, uint32_t delivered, uint32_t n)
{
	uint32_t k = 0;
	for (uint32_t id = 0; id < n; id++)
		k += sched_audit_due(s, who, delivered, id);
	return k;
}

/* Probation, then a salted sample of about the asked fraction; none with audit 0. */
static void test_audit_due(void)
{
	struct tiling tg;
	tiling_init(&tg, IMG_W, IMG_H, SIDE);
	uint8_t *img = blank_image(&tg);
	struct sched *a = sched_new(&tg, 3, 4, img, 0.25, 0x1234, NULL, NULL);
	struct sched *b = sched_new(&tg, 3, 4, img, 0.25, 0x1234, NULL, NULL);
	struct sched *c = sched_new(&tg, 3, 4, img, 0.25, 0x5678, NULL, NULL);
	struct sched *z = sched_new(&tg, 3, 4, img, 0, 0x1234, NULL, NULL);
	bool probation = true;
	for (uint32_t d = 0; d < SCHED_AUDIT_PROBATION; d++)
		if (count_due(a, 1, d, 1000) != 1000)
			probation = false;
	CHECK(probation);
	uint32_t k = count_due(a, 1, SCHED_AUDIT_PROBATION, 10000);
	CHECK(k >= 2000 && k <= 3000);
	k = count_due(a, 2, 500, 10000);
	CHECK(k >= 2000 && k <= 3000);
	CHECK(count_due(z, 1, 0, 10000) == 0);
	CHECK(count_due(z, 1, 500, 10000) == 0);
	uint32_t same = 0, differ = 0, other_worker = 0;
	for (uint32_t id = 0; id < 10000; id++) {
		bool x = sched_audit_due(a, 1, 100, id);
		same += x != sched_audit_due(b, 1, 100, id);
		differ += x != sched_audit_due(c, 1, 100, id);
		other_worker += x != sched_audit_due(a, 2, 100, id);
	}
	CHECK(same == 0);       /* a function of salt, worker and tile alone */
	CHECK(differ > 1000);   /* about 2 * 0.25 * 0.75 of them */
	CHECK(other_worker > 1000);
	sched_free(a);
	sched_free(b);
	sched_free(c);
	sched_free(z);
	free(img);
}

/*
 * A claim is not in the image until a local thread renders the same pixels.
 * A claim the local render contradicts distrusts its worker: every tile it
 * delivered is undone and requeued, its other claims discarded, it gets and
 * delivers nothing more, and the loop hears of it once.
 */
static void test_audit(void)
{
	struct tiling tg;
	tiling_init(&tg, IMG_W, IMG_H, SIDE);
	uint8_t *img = blank_image(&tg);
	atomic_int wakes;
	atomic_init(&wakes, 0);
	struct sched *s = sched_new(&tg, 3, 3, img, 1.0, 1, wake_count, &wakes);
	uint16_t cancel;
	uint32_t id = SCHED_NO_TILE;
	bool audit = false, first = true;
	struct sched_trust tr;

	/* an honest claim */
	CHECK(sched_take(s, 0, false, 1) == 0);
	CHECK(deliver(s, 0, 0, 0, true, &cancel) == SCHED_USED);
	CHECK(rect_blank(&tg, img, 0));
	CHECK(stats_of(s).done == 0 && !sched_finished(s));
	CHECK(local_take(s, true, &id, &audit) == 1);
	CHECK(id == 0 && audit);
	local_done(s, 0, true, 0, true);
	struct sched_stats st = stats_of(s);
	CHECK(st.audits == 1 && st.audit_failed == 0 && st.done == 1 && st.local_done == 0);
	CHECK(rect_is(&tg, img, 0, 0));
	CHECK(!sched_caught(s, 0, &tr, &first));
	CHECK(!tr.caught && !first);
	CHECK(atomic_load(&wakes) == 0);

	/* worker 1 lies: 1-3 stored, 4, 5 and 8 claimed, 6 in hand; worker 0
	 * stores 7 */
	for (uint32_t i = 1; i <= 6; i++)
		CHECK(sched_take(s, 1, false, 1.0 + i) == i);
	CHECK(sched_take(s, 0, false, 8) == 7);
	CHECK(sched_take(s, 1, false, 9) == 8);
	for (uint32_t i = 1; i <= 3; i++)
		CHECK(deliver(s, i, 1, LIE, false, &cancel) == SCHED_USED);
	CHECK(deliver(s, 7, 0, 0, false, &cancel) == SCHED_USED);
	CHECK(deliver(s, 4, 1, LIE, true, &cancel) == SCHED_USED);
	CHECK(deliver(s, 5, 1, LIE, true, &cancel) == SCHED_USED);
	CHECK(deliver(s, 8, 1, LIE, true, &cancel) == SCHED_USED);
	CHECK(stats_of(s).done == 5);
	CHECK(rect_is(&tg, img, 1, LIE) && rect_blank(&tg, img, 4));
	CHECK(local_take(s, true, &id, &audit) == 1);
	CHECK(id == 4 && audit);
	uint32_t id5 = SCHED_NO_TILE;
	CHECK(local_take(s, true, &id5, &audit) == 1); /* in progress while 4 fails */
	CHECK(id5 == 5 && audit);
	local_done(s, 4, true, 0, true);

	st = stats_of(s);
	CHECK(st.audits == 2 && st.audit_failed == 1);
	CHECK(st.done == 3); /* 0, 7, and 4 with the local pixels */
	CHECK(rect_is(&tg, img, 4, 0));
	CHECK(atomic_load(&wakes) >= 1);
	CHECK(sched_caught(s, 1, &tr, &first));
	CHECK(first && tr.caught && tr.tile == 4);
	CHECK(tr.requeued == 6); /* 4 itself, 1-3 undone, the claims on 5 and 8 */
	CHECK(sched_caught(s, 1, &tr, &first));
	CHECK(!first && tr.caught);
	CHECK(!sched_caught(s, 0, &tr, &first));
	CHECK(!first);
	/* the discarded claim on 5 is no audit: its local render just stores it */
	local_done(s, 5, true, 0, true);
	st = stats_of(s);
	CHECK(st.audits == 2 && st.audit_failed == 1 && st.done == 4);
	CHECK(rect_is(&tg, img, 5, 0));

	/* nothing more for the liar, and nothing from it is used */
	CHECK(sched_take(s, 1, false, 20) == SCHED_NO_TILE);
	CHECK(sched_take(s, 1, true, 20) == SCHED_NO_TILE);
	CHECK(deliver(s, 6, 1, LIE, false, &cancel) == SCHED_WASTED);
	CHECK(deliver(s, 6, 1, LIE, true, &cancel) == SCHED_WASTED);
	CHECK(rect_blank(&tg, img, 6) && stats_of(s).done == 4);

	/* its tiles are at the front, then the untouched ones: 5 is done
	 * though it was requeued, so it is skipped */
	uint32_t seen = 0;
	for (int i = 0; i < 5; i++) {
		uint32_t t = sched_take(s, 0, false, 30.0 + i);
		if (t < 32)
			seen |= 1u << t;
	}
	CHECK(seen == ((1u << 1) | (1u << 2) | (1u << 3) | (1u << 6) | (1u << 8)));
	CHECK(sched_take(s, 0, false, 40) == 9);
	CHECK(stats_of(s).redispatched == 5);
	/* the discarded claim on 8 left no audit behind */
	CHECK(local_take(s, false, &id, &audit) == 1);
	CHECK(id == 10 && !audit);
	sched_free(s);
	free(img);
}

/* ---- a dropped worker ---- */

/* A lost connection releases the worker's tiles: the next taker gets
 * exactly those, then the untouched ones. */
static void test_drop(void)
{
	struct tiling tg;
	tiling_init(&tg, IMG_W, IMG_H, SIDE);
	uint8_t *img = blank_image(&tg);
	struct sched *s = sched_new(&tg, 3, 3, img, 0, 1, NULL, NULL);
	uint32_t held[5];
	for (uint32_t i = 0; i < 5; i++)
		held[i] = sched_take(s, 0, false, 1.0 + i);
	CHECK(sched_take(s, 1, false, 6) == 5);
	CHECK(sched_take(s, 1, false, 7) == 6);
	for (uint32_t i = 0; i < 5; i++)
		sched_release(s, held[i], 0);
	uint32_t seen = 0;
	for (int i = 0; i < 5; i++) {
		uint32_t t = sched_take(s, 2, false, 10.0 + i);
		if (t < 32)
			seen |= 1u << t;
	}
	CHECK(seen == 0x1fu);
	CHECK(sched_take(s, 2, false, 20) == 7);
	CHECK(stats_of(s).redispatched == 5);
	sched_free(s);
	free(img);
}

/* ---- stress ---- */

#define ST_W 61u
#define ST_H 47u
#define ST_SIDE 4u
#define ST_LOCALS 3
#define ST_WORKERS 3
#define ST_LIAR 2
#define ST_DEPTH 3

/* xorshift32: a small deterministic generator per thread */
static uint32_t rnd(uint32_t *x)
{
	*x ^= *x << 13;
	*x ^= *x >> 17;
	*x ^= *x << 5;
	return *x;
}

struct st_local {
	pthread_t th;
	struct sched *s;
	uint32_t seed;
	uint32_t n;
	atomic_int exited;
};

/* A local thread: renders the true pixels, abandons one tile in eight
 * (and any when the render stops meanwhile). */
static void *st_local_main(void *arg)
{
	struct st_local *L = arg;
	uint8_t rgb[ST_SIDE * ST_SIDE * 3];
	uint32_t id;
	bool audit;
	while (sched_local_take(L->s, false, &id, &audit)) {
		struct tile_rect r = sched_rect(L->s, id);
		for (uint32_t y = 0; y < r.h; y++)
			for (uint32_t x = 0; x < r.w; x++)
				for (uint32_t c = 0; c < 3; c++)
					rgb[((size_t)y * r.w + x) * 3 + c] = pat(id, r.x + x, r.y + y, c, 0);
		if (rnd(&L->seed) % 4 == 0)
			sched_yield();
		bool ok = rnd(&L->seed) % 8 != 0 && !atomic_load(sched_stop_flag(L->s));
		sched_local_done(L->s, id, audit, rgb, ok);
		L->n++;
	}
	atomic_store(&L->exited, 1);
	return NULL;
}

struct st_worker {
	uint32_t held[ST_DEPTH];
	int n;
	uint32_t delivered;
	bool gone;
};

static void held_remove(struct st_worker *w, int k) { w->held[k] = w->held[--w->n]; }

static void held_drop_id(struct st_worker *w, uint32_t id)
{
	for (int k = 0; k < w->n; k++)
		if (w->held[k] == id) {
			held_remove(w, k);
			return;
		}
}

/* how a worker of the stress test makes up its pixels */
enum st_mode {
	ST_HONEST,
	ST_SNEAKY,      /* lies when the result is not audited */
	ST_BOLD,        /* lies when it is */
	ST_SOMETIMES,   /* lies one time in three */
};
/* what st_deliver did */
#define ST_USED 1
#define ST_LIED 2       /* a lie, and used */
#define ST_DUE 4

/* Worker k delivers its j-th held tile as the event loop would (audited
 * when due, the other holder cancelled). ST_* flags. */
static int st_deliver(struct sched *s, struct st_worker *w, uint16_t k, int j, enum st_mode mode, uint32_t *seed)
{
	struct st_worker *wk = &w[k];
	uint32_t id = wk->held[j];
	held_remove(wk, j);
	bool due = sched_audit_due(s, k, wk->delivered, id);
	bool lie = (mode == ST_SNEAKY && !due) || (mode == ST_BOLD && due) ||
		   (mode == ST_SOMETIMES && rnd(seed) % 3 == 0);
	uint8_t rgb[ST_SIDE * ST_SIDE * 3];
	fill(s, id, lie ? LIE : 0, rgb);
	uint16_t cancel;
	if (sched_result(s, id, k, rgb, due, &cancel) != SCHED_USED)
		return due ? ST_DUE : 0;
	wk->delivered++;
	if (cancel != SCHED_NONE && cancel < ST_WORKERS)
		held_drop_id(&w[cancel], id);
	return ST_USED | (lie ? ST_LIED : 0) | (due ? ST_DUE : 0);
}

/* Local threads and three workers (one of them lying) at random until the
 * render is finished: the image is the true one, every tile done, the liar
 * caught and reported once. */
static void test_stress(void)
{
	struct tiling tg;
	tiling_init(&tg, ST_W, ST_H, ST_SIDE);
	uint8_t *img = blank_image(&tg), *want = blank_image(&tg);
	for (uint32_t i = 0; i < tg.n; i++)
		paint(&tg, want, i, 0);
	atomic_int wakes;
	atomic_init(&wakes, 0);
	struct sched *s = sched_new(&tg, 3, ST_WORKERS, img, 0.3, 0xfeed, wake_count, &wakes);
	struct st_worker w[ST_WORKERS];
	memset(w, 0, sizeof w);
	uint32_t seed = 0x9e3779b9u;
	double now = 1;
	/*
	 * Before any local thread runs (so no claim is settled yet): the
	 * workers take their tiles, and the liar delivers honestly through its
	 * probation, then slips in two lies that are not audited (stored),
	 * then lies on an audited one (a claim that will unmask it). Without
	 * this the local threads may finish the render before the liar lies.
	 */
	for (uint16_t k = 0; k < ST_WORKERS; k++)
		while (w[k].n < ST_DEPTH)
			w[k].held[w[k].n++] = sched_take(s, k, false, now++);
	uint32_t stored_lies = 0, claimed_lies = 0;
	struct st_worker *liar = &w[ST_LIAR];
	for (uint32_t i = 0; i < tg.n / 2 && !claimed_lies; i++) {
		if (liar->n == 0)
			liar->held[liar->n++] = sched_take(s, ST_LIAR, false, now++);
		int r = st_deliver(s, w, ST_LIAR, 0, stored_lies < 2 ? ST_SNEAKY : ST_BOLD, &seed);
		if (r & ST_LIED)
			*((r & ST_DUE) ? &claimed_lies : &stored_lies) += 1;
	}
	CHECK(stored_lies == 2 && claimed_lies == 1);
	CHECK(st_deliver(s, w, 0, 0, ST_HONEST, &seed) == (ST_USED | ST_DUE));
	CHECK(st_deliver(s, w, 1, 0, ST_HONEST, &seed) == (ST_USED | ST_DUE));
	struct sched_trust tr;
	bool first;
	CHECK(!sched_caught(s, ST_LIAR, &tr, &first));
	struct st_local L[ST_LOCALS];
	int n_locals = 0;
	for (int i = 0; i < ST_LOCALS; i++) {
		L[i].s = s;
		L[i].seed = 0x1234567u * (uint32_t)(i + 1);
		L[i].n = 0;
		atomic_init(&L[i].exited, 0);
		if (pthread_create(&L[i].th, NULL, st_local_main, &L[i]) != 0)
			break;
		n_locals++;
	}
	CHECK(n_locals >= 2);

	uint32_t caught_first = 0;
	struct timespec t0, t1;
	clock_gettime(CLOCK_MONOTONIC, &t0);
	bool timed_out = false;
	for (uint32_t iter = 0; !sched_finished(s); iter++) {
		if (iter % 1024 == 0) {
			clock_gettime(CLOCK_MONOTONIC, &t1);
			if (t1.tv_sec - t0.tv_sec > 20) {
				timed_out = true;
				break;
			}
		}
		now += 1;
		uint16_t k = (uint16_t)(rnd(&seed) % ST_WORKERS);
		struct st_worker *wk = &w[k];
		if (wk->gone)
			continue;
		if (sched_caught(s, k, &tr, &first)) { /* the loop drops it */
			caught_first += first;
			for (int j = 0; j < wk->n; j++)
				sched_release(s, wk->held[j], k);
			wk->n = 0;
			wk->gone = true;
			continue;
		}
		uint32_t a = rnd(&seed) % 20;
		if (a < 8) {
			if (wk->n < ST_DEPTH) {
				uint32_t id = sched_take(s, k, wk->n == 0, now);
				if (id != SCHED_NO_TILE)
					wk->held[wk->n++] = id;
			}
		} else if (a < 9 && wk->n) { /* a refused tile */
			int j = (int)(rnd(&seed) % (uint32_t)wk->n);
			sched_release(s, wk->held[j], k);
			held_remove(wk, j);
		} else if (a < 10) { /* a lost connection, then back */
			for (int j = 0; j < wk->n; j++)
				sched_release(s, wk->held[j], k);
			wk->n = 0;
		} else if (wk->n) {
			st_deliver(s, w, k, (int)(rnd(&seed) % (uint32_t)wk->n),
				   k == ST_LIAR ? ST_SOMETIMES : ST_HONEST, &seed);
		} else {
			sched_yield();
		}
	}
	CHECK(!timed_out);
	if (timed_out)
		sched_stop(s);
	/* the end of the render lets every local thread go */
	int exited = 0;
	for (int ms = 0; ms < PATIENCE_MS && exited < n_locals; ms++) {
		exited = 0;
		for (int i = 0; i < n_locals; i++)
			exited += atomic_load(&L[i].exited);
		if (exited < n_locals)
			sleep_ms(1);
	}
	CHECK(exited == n_locals);
	if (exited < n_locals) {
		sched_stop(s);
		sleep_ms(PATIENCE_MS);
		for (int i = 0; i < n_locals; i++)
			if (!atomic_load(&L[i].exited))
				give_up("a local thread stays blocked after sched_stop");
	}
	uint32_t local_n = 0;
	for (int i = 0; i < n_locals; i++) {
		pthread_join(L[i].th, NULL);
		local_n += L[i].n;
	}
	struct sched_stats st = stats_of(s);
	CHECK(memcmp(img, want, (size_t)tg.w * tg.h * 3) == 0);
	CHECK(st.done == tg.n && st.n == tg.n);
	/* caught and reported once: to the loop, or here when the render
	 * ended first; its two stored lies were undone (the image is true) */
	CHECK(sched_caught(s, ST_LIAR, &tr, &first));
	CHECK(caught_first + (uint32_t)first == 1);
	CHECK(tr.requeued >= 1 + stored_lies);
	CHECK(st.audit_failed == 1 && st.audits >= 2);
	CHECK(!sched_caught(s, 0, &tr, &first) && !sched_caught(s, 1, &tr, &first));
	CHECK(atomic_load(&wakes) >= 1);
	CHECK(local_n > 0);
	sched_free(s);
	free(img);
	free(want);
}

/* ---- observers and resume ---- */

/* The change list names every tile stored or undone, once however often it
 * changed, and wakes the loop only when it turns non-empty; pixels read
 * back are the stored ones; preloaded tiles are never handed out, and
 * preloading them all finishes the render. */
static void test_observe(void)
{
	struct tiling tg;
	tiling_init(&tg, IMG_W, IMG_H, SIDE);
	uint8_t *img = blank_image(&tg);
	atomic_int wakes;
	atomic_init(&wakes, 0);
	struct sched *s = sched_new(&tg, 3, 2, img, 1.0, 1, wake_count, &wakes);
	uint32_t ids[N_TILES + 1];
	uint8_t px[SIDE * SIDE * 3], want[SIDE * SIDE * 3];
	uint16_t cancel;
	CHECK(sched_changes(s, ids, N_TILES) == 0);
	CHECK(sched_observe(s) == 0);
	CHECK(sched_observe(s) == 0); /* twice is once */

	/* preload 3 and 9: out of the queue, stored, listed */
	fill(s, 3, 0, px);
	CHECK(sched_preload(s, 3, px) == 0);
	fill(s, 9, 0, px);
	CHECK(sched_preload(s, 9, px) == 0);
	CHECK(sched_preload(s, 9, px) == -1); /* done already */
	CHECK(atomic_load(&wakes) == 1);
	CHECK(sched_changes(s, ids, N_TILES) == 2 && ids[0] == 3 && ids[1] == 9);
	CHECK(sched_changes(s, ids, N_TILES) == 0);
	CHECK(stats_of(s).done == 2 && rect_is(&tg, img, 3, 0) && rect_is(&tg, img, 9, 0));
	struct tile_rect r9 = sched_rect(s, 9); /* 5 wide: the last column */
	fill(s, 9, 0, want);
	memset(px, 0, sizeof px);
	CHECK(sched_tile_pixels(s, 9, px) && memcmp(px, want, (size_t)r9.w * r9.h * 3) == 0);
	CHECK(!sched_tile_pixels(s, 0, px));

	/* worker 1 lies on 0 (stored: its probation is over for the test's
	 * purpose only if audits say so, so deliver unaudited), worker 0
	 * delivers 1 with an audit claim */
	uint32_t taken[N_TILES], n_taken = 0, id;
	while ((id = sched_take(s, 1, false, 1.0 + n_taken)) != SCHED_NO_TILE)
		taken[n_taken++] = id;
	CHECK(n_taken == N_TILES - 2);
	bool skipped = true;
	for (uint32_t i = 0; i < n_taken; i++)
		skipped &= taken[i] != 3 && taken[i] != 9;
	CHECK(skipped);
	CHECK(deliver(s, 0, 1, LIE, false, &cancel) == SCHED_USED);
	CHECK(deliver(s, 1, 1, LIE, false, &cancel) == SCHED_USED);
	CHECK(deliver(s, 2, 1, LIE, true, &cancel) == SCHED_USED); /* a claim: not stored, not listed */
	int w0 = atomic_load(&wakes);
	CHECK(sched_changes(s, ids, 1) == 1 && ids[0] == 0); /* max respected */
	CHECK(sched_changes(s, ids, N_TILES) == 1 && ids[0] == 1);
	/* the audit of 2 catches worker 1: 0 and 1 come undone and are listed again */
	uint32_t aid = SCHED_NO_TILE;
	bool audit = false;
	CHECK(local_take(s, true, &aid, &audit) == 1 && aid == 2 && audit);
	local_done(s, 2, true, 0, true);
	CHECK(atomic_load(&wakes) > w0);
	uint32_t n = sched_changes(s, ids, N_TILES);
	bool has0 = false, has1 = false, has2 = false;
	for (uint32_t i = 0; i < n; i++) {
		has0 |= ids[i] == 0;
		has1 |= ids[i] == 1;
		has2 |= ids[i] == 2;
	}
	CHECK(n == 3 && has0 && has1 && has2);
	CHECK(!sched_tile_pixels(s, 0, px) && !sched_tile_pixels(s, 1, px) && sched_tile_pixels(s, 2, px));
	sched_free(s);
	free(img);

	/* a render whose every tile is preloaded is finished */
	img = blank_image(&tg);
	s = sched_new(&tg, 3, 0, img, 0, 1, NULL, NULL);
	for (uint32_t i = 0; i < N_TILES; i++) {
		fill(s, i, 0, px);
		CHECK(sched_preload(s, i, px) == 0);
	}
	CHECK(sched_finished(s) && stats_of(s).done == N_TILES);
	CHECK(sched_take(s, 0, true, 1) == SCHED_NO_TILE);
	sched_free(s);
	free(img);
}

/* ---- pixels of 12 bytes (RGBF32) ---- */

/* Tile id of a 12-byte-pixel image as variant v: floats of the pixel's
 * place, stored as little-endian bytes (the scheduler only moves bytes). */
static void fill_f32(const struct tiling *tg, uint32_t id, uint32_t v, uint8_t *px)
{
	struct tile_rect r = tiling_rect(tg, id);
	for (uint32_t y = 0; y < r.h; y++)
		for (uint32_t x = 0; x < r.w; x++)
			for (uint32_t c = 0; c < 3; c++) {
				float f = (float)(r.x + x) * 0.25f + (float)(r.y + y) * 1.5f + (float)c * 3.0f +
					  (float)v * 0.001f - 2.0f; /* some negative, some far above 1 */
				uint32_t u;
				memcpy(&u, &f, sizeof u);
				uint8_t *o = px + ((size_t)y * r.w + x) * 12 + c * 4;
				o[0] = (uint8_t)u, o[1] = (uint8_t)(u >> 8), o[2] = (uint8_t)(u >> 16), o[3] = (uint8_t)(u >> 24);
			}
}

/* sched_new with bpp 12: sched_bpp says so; tiles land at 12 bytes a pixel;
 * sched_tile_pixels and sched_preload move 12 bytes a pixel; an audit that
 * finds one bit of one float changed catches the worker, and an identical
 * one passes. */
static void test_float_pixels(void)
{
	struct tiling tg;
	tiling_init(&tg, IMG_W, IMG_H, SIDE);
	size_t n = (size_t)tg.w * tg.h * 12;
	uint8_t *img = malloc(n), *want = malloc(n);
	uint8_t px[SIDE * SIDE * 12], out[SIDE * SIDE * 12];
	CHECK(img && want);
	if (!img || !want)
		return;
	memset(img, SENTINEL, n);
	CHECK(sched_new(&tg, 0, 1, img, 0, 1, NULL, NULL) == NULL);
	struct sched *s = sched_new(&tg, 12, 2, img, 1.0, 1, NULL, NULL);
	CHECK(s != NULL && sched_bpp(s) == 12);
	CHECK(sched_observe(s) == 0);
	/* tile 0 preloaded; the rest: worker 0 honest, worker 1 lies about one bit */
	fill_f32(&tg, 0, 0, px);
	CHECK(sched_preload(s, 0, px) == 0);
	uint16_t cancel;
	uint32_t id;
	bool audit;
	CHECK(sched_take(s, 0, false, 1) == 1);
	fill_f32(&tg, 1, 0, px);
	CHECK(sched_result(s, 1, 0, px, true, &cancel) == SCHED_USED);
	CHECK(local_take(s, true, &id, &audit) == 1 && id == 1 && audit);
	sched_local_done(s, 1, true, px, true); /* the same bytes: passes */
	CHECK(stats_of(s).audit_failed == 0 && stats_of(s).done == 2);
	CHECK(sched_take(s, 1, false, 2) == 2);
	fill_f32(&tg, 2, 0, px);
	px[5 * 12 + 4] ^= 1; /* the lowest bit of one green value */
	CHECK(sched_result(s, 2, 1, px, true, &cancel) == SCHED_USED);
	CHECK(local_take(s, true, &id, &audit) == 1 && id == 2 && audit);
	fill_f32(&tg, 2, 0, px);
	sched_local_done(s, 2, true, px, true);
	struct sched_trust tr;
	bool first;
	CHECK(stats_of(s).audit_failed == 1 && sched_caught(s, 1, &tr, &first) && tr.tile == 2);
	/* the rest by the local threads */
	while (local_take(s, false, &id, &audit) == 1) {
		fill_f32(&tg, id, 0, px);
		sched_local_done(s, id, audit, px, true);
		if (sched_finished(s))
			break;
	}
	CHECK(sched_finished(s));
	for (uint32_t t = 0; t < tg.n; t++) {
		struct tile_rect r = tiling_rect(&tg, t);
		fill_f32(&tg, t, 0, px);
		for (uint32_t y = 0; y < r.h; y++)
			memcpy(want + (((size_t)(r.y + y) * tg.w) + r.x) * 12, px + (size_t)y * r.w * 12, (size_t)r.w * 12);
		CHECK(sched_tile_pixels(s, t, out) && memcmp(out, px, (size_t)r.w * r.h * 12) == 0);
	}
	CHECK(memcmp(img, want, n) == 0);
	sched_free(s);
	free(img);
	free(want);
}

int main(void)
{
	test_take();
	test_requeue();
	test_duplicate();
	test_image();
	test_local();
	test_audit_due();
	test_audit();
	test_drop();
	test_stress();
	test_observe();
	test_float_pixels();
	TEST_MAIN_END();
}
