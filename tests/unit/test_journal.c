/*
 * test_journal.c - the checkpoint journal (master/journal.c) alone, with no
 * render: tiles written at checkpoints and read back on resume, undone
 * tiles, the refusal of another render's journal (scene, size, tile side,
 * pixel revision and type), a damaged header, a journal cut at each byte of
 * its header and first records and around every record's end (only whole
 * records survive, each with its own pixels, and the torn tail is cut off
 * the file so appends follow), a flipped byte, the first
 * checkpoint's rename (no file before it, no temporary file after), and the
 * end of a render (removed when finished, kept with the last tiles when not).
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "common/img.h"
#include "common/render.h"
#include "common/tiles.h"
#include "master/journal.h"

/* 5 x 3 tiles of 8, the last column 5 wide and the last row 7 high */
#define IMG_W 37u
#define IMG_H 23u
#define SIDE 8u
#define N_TILES 15u
#define BPP 3u

static char dir[256], path[300];

/* A pixel byte of tile id as variant v: depends on place, tile and variant. */
static uint8_t pat(uint32_t id, uint32_t x, uint32_t y, uint32_t c, uint32_t v)
{
	return (uint8_t)(id * 41u + x * 7u + y * 13u + c * 101u + v * 59u + 1u);
}

static const struct tiling *tg_(void)
{
	static struct tiling tg;
	tiling_init(&tg, IMG_W, IMG_H, SIDE);
	return &tg;
}

static void fill(uint32_t id, uint32_t v, uint8_t *out)
{
	struct tile_rect r = tiling_rect(tg_(), id);
	for (uint32_t y = 0; y < r.h; y++)
		for (uint32_t x = 0; x < r.w; x++)
			for (uint32_t c = 0; c < BPP; c++)
				out[((size_t)y * r.w + x) * BPP + c] = pat(id, r.x + x, r.y + y, c, v);
}

/* the test's render: which tiles are done, as which variant */
static int variant[N_TILES]; /* -1: not done */

static bool px(void *arg, uint32_t id, uint8_t *out)
{
	(void)arg;
	if (variant[id] < 0)
		return false;
	fill(id, (uint32_t)variant[id], out);
	return true;
}

static struct journal_params params(void)
{
	struct journal_params p = { .width = IMG_W, .height = IMG_H, .tile = SIDE, .pixel_rev = RENDER_PIXEL_REV,
				    .pixel_type = IMG_RGB8, .bpp = BPP };
	for (int i = 0; i < JOURNAL_HASH_BYTES; i++)
		p.scene_hash[i] = (uint8_t)(i * 3 + 1);
	return p;
}

static bool exists(const char *p)
{
	struct stat st;
	return stat(p, &st) == 0;
}

static long file_size(const char *p)
{
	struct stat st;
	return stat(p, &st) == 0 ? (long)st.st_size : -1;
}

static enum journal_status open_j(const struct journal_params *p, bool resume, struct journal **j)
{
	char err[600];
	err[0] = 0;
	enum journal_status s = journal_open(path, p, resume, 0, j, err, sizeof err);
	if (s != JOURNAL_OK && !err[0])
		fprintf(stderr, "journal_open failed without a message\n");
	return s;
}

/* Every journalled tile of j reads back as its variant in want (-1: must be absent). */
static bool tiles_are(struct journal *j, const int *want)
{
	uint8_t got[SIDE * SIDE * BPP], exp[SIDE * SIDE * BPP];
	for (uint32_t id = 0; id < N_TILES; id++) {
		if (want[id] < 0) {
			if (journal_has(j, id))
				return false;
			continue;
		}
		struct tile_rect r = tiling_rect(tg_(), id);
		fill(id, (uint32_t)want[id], exp);
		if (!journal_has(j, id) || journal_read_tile(j, id, got) < 0 ||
		    memcmp(got, exp, (size_t)r.w * r.h * BPP) != 0)
			return false;
	}
	return true;
}

static void copy_file(const char *from, const char *to, long n)
{
	FILE *a = fopen(from, "rb"), *b = fopen(to, "wb");
	for (long i = 0; a && b && i < n; i++) {
		int ch = getc(a);
		if (ch == EOF)
			break;
		putc(ch, b);
	}
	if (a)
		fclose(a);
	if (b)
		fclose(b);
}

/* A fresh journal: checkpoints write what changed; resume reads it back. */
static void test_write_read(void)
{
	struct journal_params p = params();
	struct journal *j;
	unlink(path);
	CHECK(open_j(&p, true, &j) == JOURNAL_OK); /* --resume with no journal: an empty one */
	CHECK(!journal_loaded(j) && journal_tiles(j) == 0);
	for (uint32_t i = 0; i < N_TILES; i++)
		variant[i] = -1;
	/* nothing done: a checkpoint creates no file */
	journal_note(j, 3, false);
	CHECK(journal_checkpoint(j, px, NULL) == 0);
	CHECK(!exists(path));
	variant[0] = variant[4] = variant[14] = 0;
	journal_note(j, 0, true);
	journal_note(j, 4, true);
	journal_note(j, 14, true);
	CHECK(journal_checkpoint(j, px, NULL) == 0);
	CHECK(exists(path));
	char tmp[320];
	snprintf(tmp, sizeof tmp, "%s.tmp", path);
	CHECK(!exists(tmp));
	CHECK(journal_tiles(j) == 3);
	/* a second checkpoint appends; noting a tile twice writes it once */
	variant[7] = 0;
	journal_note(j, 7, true);
	journal_note(j, 7, true);
	long before = file_size(path);
	CHECK(journal_checkpoint(j, px, NULL) == 0);
	CHECK(file_size(path) == before + 12 + 8 * 8 * 3 + 16);
	/* nothing changed: nothing written */
	before = file_size(path);
	CHECK(journal_checkpoint(j, px, NULL) == 0);
	CHECK(file_size(path) == before);
	CHECK(!journal_close(j, NULL, true, false)); /* finished: removed */
	CHECK(!exists(path));

	/* again, and read it back */
	CHECK(open_j(&p, false, &j) == JOURNAL_OK);
	for (uint32_t i = 0; i < N_TILES; i++)
		journal_note(j, i, variant[i] >= 0);
	CHECK(journal_checkpoint(j, px, NULL) == 0);
	CHECK(journal_close(j, NULL, false, false)); /* not finished: kept */
	CHECK(open_j(&p, true, &j) == JOURNAL_OK);
	CHECK(journal_loaded(j) && journal_tiles(j) == 4 && journal_dropped(j) == 0);
	CHECK(tiles_are(j, variant));
	journal_close(j, NULL, false, false);
}

/* A tile undone (its worker caught lying) and redone with other pixels. */
static void test_undo(void)
{
	struct journal_params p = params();
	struct journal *j;
	unlink(path);
	for (uint32_t i = 0; i < N_TILES; i++)
		variant[i] = (int)(i % 3 == 0 ? 1 : -1); /* 0 3 6 9 12 as the liar's variant 1 */
	CHECK(open_j(&p, false, &j) == JOURNAL_OK);
	for (uint32_t i = 0; i < N_TILES; i++)
		journal_note(j, i, variant[i] >= 0);
	CHECK(journal_checkpoint(j, px, NULL) == 0);
	variant[3] = variant[6] = -1; /* undone */
	journal_note(j, 3, false);
	journal_note(j, 6, false);
	journal_note(j, 5, false); /* never journalled: no record */
	long before = file_size(path);
	CHECK(journal_checkpoint(j, px, NULL) == 0);
	CHECK(file_size(path) == before + 2 * (12 + 16));
	CHECK(journal_tiles(j) == 3);
	variant[6] = 0; /* redone right */
	journal_note(j, 6, true);
	CHECK(journal_checkpoint(j, px, NULL) == 0);
	journal_close(j, NULL, false, false);
	CHECK(open_j(&p, true, &j) == JOURNAL_OK);
	CHECK(journal_tiles(j) == 4);
	CHECK(tiles_are(j, variant));
	journal_close(j, NULL, false, false);
}

/* Another render's journal is refused, naming what differs. */
static void test_mismatch(void)
{
	struct journal_params p = params(), q;
	struct journal *j;
	CHECK(exists(path));
	q = p;
	q.scene_hash[5] ^= 1;
	CHECK(open_j(&q, true, &j) == JOURNAL_MISMATCH);
	q = p;
	q.width = IMG_W + 1;
	CHECK(open_j(&q, true, &j) == JOURNAL_MISMATCH);
	q = p;
	q.height = IMG_H - 1;
	CHECK(open_j(&q, true, &j) == JOURNAL_MISMATCH);
	q = p;
	q.tile = SIDE * 2;
	CHECK(open_j(&q, true, &j) == JOURNAL_MISMATCH);
	q = p;
	q.pixel_rev = RENDER_PIXEL_REV + 1;
	CHECK(open_j(&q, true, &j) == JOURNAL_MISMATCH);
	q = p;
	q.pixel_type = IMG_RGBF32;
	q.bpp = 12;
	CHECK(open_j(&q, true, &j) == JOURNAL_MISMATCH);
	char err[600];
	/* a --region render's journal (its tiles are cut from the region's corner) */
	q = p;
	q.region[0] = 3, q.region[1] = 2, q.region[2] = 30, q.region[3] = 20;
	CHECK(journal_open(path, &q, true, 0, &j, err, sizeof err) == JOURNAL_MISMATCH);
	CHECK(strstr(err, "--region") != NULL);
	q = p;
	q.tile = SIDE * 2;
	CHECK(journal_open(path, &q, true, 0, &j, err, sizeof err) == JOURNAL_MISMATCH);
	CHECK(strstr(err, "tiles of 8") && strstr(err, "16"));
	/* without --resume the old journal is no obstacle */
	CHECK(open_j(&q, false, &j) == JOURNAL_OK);
	journal_close(j, NULL, false, false);
	/* a damaged header */
	copy_file(path, "hdr.bak", 1L << 30);
	FILE *f = fopen(path, "r+b");
	fseek(f, 50, SEEK_SET);
	putc(0x5a, f);
	fclose(f);
	CHECK(journal_open(path, &p, true, 0, &j, err, sizeof err) == JOURNAL_DAMAGED);
	CHECK(strstr(err, "damaged") != NULL);
	f = fopen(path, "wb");
	fputs("hello\n", f);
	fclose(f);
	CHECK(open_j(&p, true, &j) == JOURNAL_DAMAGED);
	rename("hdr.bak", path);
	CHECK(open_j(&p, true, &j) == JOURNAL_OK);
	journal_close(j, NULL, false, false);
}

/*
 * The journal cut short (a crash mid-append): the header survives
 * whole or the journal is refused; of the records only whole ones count,
 * each with its own pixels; the torn tail is cut off, so that the next
 * checkpoint's records are read back too.
 */
static void test_cut(void)
{
	struct journal_params p = params();
	struct journal *j;
	unlink(path);
	for (uint32_t i = 0; i < N_TILES; i++)
		variant[i] = -1;
	CHECK(open_j(&p, false, &j) == JOURNAL_OK);
	/* one tile per checkpoint: record k ends at ends[k] */
	long ends[N_TILES + 1];
	for (uint32_t i = 0; i < N_TILES; i++) {
		variant[i] = 2;
		journal_note(j, i, true);
		CHECK(journal_checkpoint(j, px, NULL) == 0);
		ends[i] = file_size(path);
	}
	journal_close(j, NULL, false, false);
	long full = file_size(path);
	CHECK(full == ends[N_TILES - 1]);
	copy_file(path, "full.bak", full);
	int bad = 0, tried = 0;
	for (long cut = 0; cut <= full; cut++) {
		/* every byte of the header and the first records, then around
		 * each record's end and a stride (files are slow to open here) */
		bool near_end = false;
		for (uint32_t k = 0; k < N_TILES; k++)
			near_end |= cut >= ends[k] - 2 && cut <= ends[k] + 2;
		if (cut > ends[1] && !near_end && cut % 13 != 0 && cut != full - 5)
			continue;
		tried++;
		copy_file("full.bak", path, cut);
		enum journal_status s = open_j(&p, true, &j);
		if (cut < 112) {
			bad += s != JOURNAL_DAMAGED;
			continue;
		}
		if (s != JOURNAL_OK) {
			bad++;
			continue;
		}
		uint32_t whole = 0;
		while (whole < N_TILES && ends[whole] <= cut)
			whole++;
		int want[N_TILES];
		for (uint32_t i = 0; i < N_TILES; i++)
			want[i] = i < whole ? 2 : -1;
		bad += journal_tiles(j) != whole || !tiles_are(j, want);
		bad += (long)journal_dropped(j) != cut - (whole ? ends[whole - 1] : 112);
		bad += file_size(path) != (whole ? ends[whole - 1] : 112); /* the tail is cut off */
		if (cut == full - 5) {
			/* append after the cut: the last tile again, then read back */
			journal_note(j, N_TILES - 1, true);
			CHECK(journal_checkpoint(j, px, NULL) == 0);
			journal_close(j, NULL, false, false);
			CHECK(open_j(&p, true, &j) == JOURNAL_OK);
			CHECK(journal_tiles(j) == N_TILES && journal_dropped(j) == 0);
			CHECK(tiles_are(j, variant));
		}
		journal_close(j, NULL, false, false);
	}
	CHECK(bad == 0);
	CHECK(tried > 300);
	/* a byte flipped in the middle of record 6's pixels: it and the rest are dropped */
	copy_file("full.bak", path, full);
	FILE *f = fopen(path, "r+b");
	fseek(f, ends[5] + 12 + 20, SEEK_SET);
	int ch = getc(f);
	fseek(f, ends[5] + 12 + 20, SEEK_SET);
	putc(ch ^ 0x10, f);
	fclose(f);
	CHECK(open_j(&p, true, &j) == JOURNAL_OK);
	int want[N_TILES];
	for (uint32_t i = 0; i < N_TILES; i++)
		want[i] = i < 6 ? 2 : -1;
	CHECK(journal_tiles(j) == 6 && tiles_are(j, want));
	CHECK((long)journal_dropped(j) == full - ends[5]);
	journal_close(j, NULL, false, false);
	unlink("full.bak");
}

/* The end of a render: kept with the tiles finished since the last
 * checkpoint (read from the image), or removed; --keep-journal keeps it. */
static void test_close(void)
{
	struct journal_params p = params();
	struct journal *j;
	unlink(path);
	static uint8_t image[IMG_W * IMG_H * BPP];
	memset(image, 0, sizeof image);
	for (uint32_t i = 0; i < N_TILES; i++) {
		variant[i] = (int)(i & 1) ? 0 : -1;
		if (variant[i] < 0)
			continue;
		uint8_t t[SIDE * SIDE * BPP];
		fill(i, 0, t);
		struct tile_rect r = tiling_rect(tg_(), i);
		for (uint32_t y = 0; y < r.h; y++)
			memcpy(image + ((size_t)(r.y + y) * IMG_W + r.x) * BPP, t + (size_t)y * r.w * BPP, r.w * BPP);
	}
	CHECK(open_j(&p, false, &j) == JOURNAL_OK);
	for (uint32_t i = 0; i < N_TILES; i++)
		journal_note(j, i, variant[i] >= 0);
	CHECK(journal_close(j, image, false, false));
	CHECK(open_j(&p, true, &j) == JOURNAL_OK);
	CHECK(journal_tiles(j) == 7 && tiles_are(j, variant));
	CHECK(journal_close(j, image, true, true)); /* finished, --keep-journal */
	CHECK(exists(path));
	CHECK(open_j(&p, true, &j) == JOURNAL_OK);
	CHECK(!journal_close(j, image, true, false));
	CHECK(!exists(path));
}

int main(void)
{
	snprintf(dir, sizeof dir, "%s/portray-journal.XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
	if (!mkdtemp(dir)) {
		perror("mkdtemp");
		return 1;
	}
	if (chdir(dir) < 0)
		return 1;
	snprintf(path, sizeof path, "%s/out.png.journal", dir);
	test_write_read();
	test_undo();
	test_mismatch();
	test_cut();
	test_close();
	unlink(path);
	char tmp[320];
	snprintf(tmp, sizeof tmp, "%s.tmp", path);
	unlink(tmp);
	rmdir(dir);
	TEST_MAIN_END();
}
