/*
 * test_img.c - image files: CRC-32 and Adler-32 against published values,
 * the independent decoder (tests/unit/inflate.h) against hand-made and
 * published deflate streams, then our PNGs of many images decoded by it and
 * compared pixel for pixel; PPM output and img_write's file handling.
 *
 * With an argument DIR, also writes a few PNGs and their raw pixels there
 * (DIR/NAME.png, DIR/NAME.rgb, DIR/NAME.size) for tests/cli/png_python.sh.
 */
#include <dirent.h>
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "common/crc32.h"
#include "common/img.h"
#include "common/limits.h"
#include "tests/unit/check.h"
#include "tests/unit/inflate.h"
#include "tests/unit/slurp.h"

static void test_checksums(void)
{
	const uint8_t *d = (const uint8_t *)"123456789";
	CHECK(crc32_update(0, d, 9) == 0xCBF43926u);
	CHECK(crc32_update(crc32_update(0, d, 4), d + 4, 5) == 0xCBF43926u); /* chaining */
	CHECK(crc32_update(0, d, 0) == 0);
	CHECK(crc32_update(0, (const uint8_t *)"The quick brown fox jumps over the lazy dog", 43) == 0x414FA339u);
	CHECK(inf_crc32(d, 9, 0) == 0xCBF43926u); /* the test decoder's own CRC */
	/* eight bytes a step against the decoder's byte-at-a-time CRC: every
	 * length to 40 at every alignment to 8, a long run, chained pieces */
	{
		uint8_t buf[70000];
		uint32_t s = 99;
		for (size_t i = 0; i < sizeof buf; i++) {
			s = s * 1103515245u + 12345u;
			buf[i] = (uint8_t)(s >> 24);
		}
		int same = 1;
		for (size_t len = 0; len <= 40; len++)
			for (size_t off = 0; off < 8; off++)
				same &= crc32_update(0, buf + off, len) == inf_crc32(buf + off, len, 0);
		same &= crc32_update(0, buf + 1, 69999) == inf_crc32(buf + 1, 69999, 0);
		same &= crc32_update(crc32_update(0, buf, 13), buf + 13, 5000) == inf_crc32(buf, 5013, 0);
		CHECK(same);
	}

	CHECK(img_adler32(1, (const uint8_t *)"Wikipedia", 9) == 0x11E60398u);
	CHECK(img_adler32(1, (const uint8_t *)"abc", 3) == 0x024D0127u);
	CHECK(img_adler32(1, d, 0) == 1);
	CHECK(img_adler32(img_adler32(1, (const uint8_t *)"Wiki", 4), (const uint8_t *)"pedia", 5) == 0x11E60398u);
	/* long inputs in closed form: n bytes of 0xff give
	 * a = 1 + 255 n, b = n + 255 n (n + 1) / 2 (mod 65521) */
	size_t n = 1000003;
	uint8_t *ff = malloc(n);
	memset(ff, 0xff, n);
	uint64_t a = (1 + 255ull * n) % 65521, b = (n + 255ull * n * (n + 1) / 2) % 65521;
	CHECK(img_adler32(1, ff, n) == (uint32_t)(b << 16 | a));
	CHECK(inf_adler32(ff, n) == (uint32_t)(b << 16 | a));
	/* the 16-byte path against the test decoder's byte-at-a-time one:
	 * every length to 100 at every alignment to 16, stretch ends near
	 * 5552, and chained pieces starting anywhere */
	uint32_t s = 12345;
	for (size_t i = 0; i < n; i++) {
		s = s * 1103515245u + 12345u;
		ff[i] = (uint8_t)(s >> 23);
	}
	int same = 1;
	for (size_t len = 0; len <= 100; len++)
		for (size_t off = 0; off < 16; off++)
			same &= img_adler32(1, ff + off, len) == inf_adler32(ff + off, len);
	static const size_t lens[] = { 5551, 5552, 5553, 5552 + 16, 11104, 11105, 65536 + 7, 1000000 };
	for (size_t i = 0; i < sizeof lens / sizeof lens[0]; i++)
		same &= img_adler32(1, ff + 3, lens[i]) == inf_adler32(ff + 3, lens[i]);
	same &= img_adler32(img_adler32(1, ff, 777), ff + 777, 70001) == inf_adler32(ff, 777 + 70001);
	CHECK(same);
	free(ff);
}

/* ---- the decoder on streams we did not make ---------------------------------- */

static int from_hex(const char *hex, uint8_t *out)
{
	int n = 0;
	for (; hex[0] && hex[1]; hex += 2) {
		unsigned v;
		sscanf(hex, "%2x", &v);
		out[n++] = (uint8_t)v;
	}
	return n;
}

static void test_decoder(void)
{
	uint8_t in[512], *out = NULL;
	size_t on = 0, used = 0;
	int blocks[3];

	/* a stored block written by hand: BFINAL=1 BTYPE=00, LEN 5, NLEN ~5 */
	int n = from_hex("010500faff68656c6c6f", in);
	CHECK(inf_inflate(in, (size_t)n, &out, &on, &used, blocks) == 0);
	CHECK(on == 5 && out && memcmp(out, "hello", 5) == 0 && blocks[0] == 1);
	free(out);
	/* its NLEN damaged */
	in[3] ^= 1;
	CHECK(inf_inflate(in, (size_t)n, &out, &on, &used, blocks) != 0);

	/* zlib.compress(b"hello"): a fixed-Huffman block (the widely published bytes) */
	n = from_hex("789ccb48cdc9c90700062c0215", in);
	CHECK(inf_zlib(in, (size_t)n, &out, &on, blocks) == 0);
	CHECK(on == 5 && memcmp(out, "hello", 5) == 0 && blocks[1] == 1);
	free(out);
	in[n - 1] ^= 1; /* Adler-32 damaged */
	CHECK(inf_zlib(in, (size_t)n, &out, &on, blocks) != 0);

	/* a dynamic-Huffman block from Python's zlib (level 6) of 300 bytes:
	 * byte i = "abcdefgh"[i % 5 ? (7 i^2 + 3 i) % 8 : i % 3] */
	n = from_hex("789cd58dc10dc04008c36675a228fb6f50f2b821fa42364660133758a48563f758e7cb79fb7cb4"
		     "8e75f3d5267dace7e34dcd33f6bcd6b1bdd729efee677f3f9d6074b1",
		     in);
	CHECK(inf_zlib(in, (size_t)n, &out, &on, blocks) == 0);
	CHECK(on == 300 && blocks[2] == 1);
	int wrong = 0;
	for (int i = 0; out && i < 300 && i < (int)on; i++) {
		int k = i % 5 ? (7 * i * i + 3 * i) % 8 : i % 3;
		wrong += out[i] != "abcdefgh"[k];
	}
	CHECK(wrong == 0);
	free(out);

	/* malformed: reserved block type 3, a distance before the start */
	n = from_hex("07", in); /* BFINAL=1 BTYPE=11 */
	CHECK(inf_inflate(in, (size_t)n, &out, &on, &used, blocks) != 0);
	/* fixed block: length code 257 (len 3), distance code 0 (dist 1) at the
	 * start: bits 1, 10 (BTYPE 01 LSB first), 0000001, 00000, 0000000 (EOB) */
	n = from_hex("030200", in);
	CHECK(inf_inflate(in, (size_t)n, &out, &on, &used, blocks) == -4);
	/* the same with a literal 'a' (00110000+0x61 = 10010001) first is fine:
	 * "aaaa" */
	{
		/* bits: 1,1,0 | 10010001 | 0000001 | 00000 | 0000000 */
		const char *bits = "110" "10010001" "0000001" "00000" "0000000";
		uint8_t b[8] = { 0 };
		int k = 0;
		for (; bits[k]; k++)
			if (bits[k] == '1')
				b[k / 8] |= (uint8_t)(1u << (k % 8));
		CHECK(inf_inflate(b, (size_t)(k + 7) / 8, &out, &on, &used, blocks) == 0);
		CHECK(on == 4 && memcmp(out, "aaaa", 4) == 0 && blocks[1] == 1);
		free(out);
	}
	/* truncated input */
	n = from_hex("789ccb48cdc9", in);
	CHECK(inf_zlib(in, (size_t)n, &out, &on, blocks) != 0);
}

/* ---- our PNGs through the decoder --------------------------------------------------- */

static uint32_t seed = 2024;
static uint32_t rnd(void)
{
	/* xorshift32: the low bits of an LCG repeat too soon to pass for noise */
	seed ^= seed << 13;
	seed ^= seed >> 17;
	seed ^= seed << 5;
	return seed;
}

enum pattern { P_NOISE, P_GRADIENT, P_FLAT, P_CHECKER, P_RENDERLIKE, P_STRIPES };

static uint8_t *make_image(enum pattern p, uint32_t w, uint32_t h)
{
	uint8_t *img = malloc(3 * (size_t)w * h + 1);
	for (uint32_t y = 0; y < h; y++) {
		for (uint32_t x = 0; x < w; x++) {
			uint8_t *px = img + 3 * ((size_t)y * w + x);
			for (int c = 0; c < 3; c++) {
				uint8_t v;
				switch (p) {
				case P_NOISE: v = (uint8_t)rnd(); break;
				case P_GRADIENT: v = (uint8_t)(x * 255 / (w > 1 ? w - 1 : 1) + c * y); break;
				case P_FLAT: v = (uint8_t)(40 + 70 * c); break;
				case P_CHECKER: v = ((x / 7 + y / 5) % 2) ? 230 : (uint8_t)(20 * c); break;
				case P_RENDERLIKE: {
					/* a shaded sphere on a floor with a little noise */
					double dx = (x - w / 2.0) / (w / 3.0 + 1), dy = (y - h / 2.0) / (h / 3.0 + 1);
					double r2 = dx * dx + dy * dy;
					double s = r2 < 1 ? 0.2 + 0.8 * sqrt(1 - r2) : 0.1 + 0.3 * y / (double)h;
					v = (uint8_t)(s * (180 + 30 * c) + (rnd() & 3));
					break;
				}
				default: v = (uint8_t)((x % 3 == 0) * 200 + c); break;
				}
				px[c] = v;
			}
		}
	}
	return img;
}

/* Encodes, decodes with inflate.h, compares. Returns the PNG size (0 on failure). */
static size_t roundtrip(const char *name, const uint8_t *img, uint32_t w, uint32_t h, int blocks_out[3],
			int *idat_out, int filters_out[5])
{
	uint8_t *png = NULL, *back = NULL;
	size_t n = 0;
	int rc = img_png_encode(img, w, h, &png, &n);
	CHECK(rc == 0);
	if (rc)
		return 0;
	uint32_t bw = 0, bh = 0;
	int idat = 0, blocks[3] = { 0 }, filters[5] = { 0 };
	int dr = inf_png(png, n, &back, &bw, &bh, &idat, blocks, filters);
	CHECK(dr == 0);
	if (dr) {
		fprintf(stderr, "%s %ux%u: decoder error %d\n", name, w, h, dr);
		free(png);
		return 0;
	}
	CHECK(bw == w && bh == h);
	int same = bw == w && bh == h && memcmp(back, img, 3 * (size_t)w * h) == 0;
	CHECK(same);
	if (!same)
		fprintf(stderr, "%s %ux%u: pixels differ\n", name, w, h);
	if (blocks_out)
		memcpy(blocks_out, blocks, sizeof blocks);
	if (idat_out)
		*idat_out = idat;
	if (filters_out)
		memcpy(filters_out, filters, sizeof filters);
	free(back);
	free(png);
	return n;
}

static void test_png_roundtrips(void)
{
	static const struct {
		enum pattern p;
		uint32_t w, h;
	} cases[] = {
		{ P_NOISE, 1, 1 },      { P_FLAT, 1, 1 },        { P_NOISE, 1000, 1 },   { P_GRADIENT, 1000, 1 },
		{ P_FLAT, 1, 1000 },    { P_NOISE, 1, 1000 },    { P_NOISE, 2, 2 },      { P_GRADIENT, 17, 13 },
		{ P_NOISE, 200, 120 },  { P_GRADIENT, 320, 240 }, { P_FLAT, 320, 240 },   { P_CHECKER, 333, 211 },
		{ P_RENDERLIKE, 320, 240 }, { P_STRIPES, 257, 99 }, { P_NOISE, 21845, 1 }, /* 65535+1 raw bytes */
		{ P_NOISE, 21844, 1 },  { P_RENDERLIKE, 640, 480 },
	};
	for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
		uint8_t *img = make_image(cases[i].p, cases[i].w, cases[i].h);
		char name[32];
		snprintf(name, sizeof name, "case%zu", i);
		CHECK(roundtrip(name, img, cases[i].w, cases[i].h, NULL, NULL, NULL) > 0);
		free(img);
	}

	/* noise does not compress: stored blocks, several of them (> 65535 bytes),
	 * and more than one IDAT chunk (> 1 MiB) */
	int blocks[3], idat, filters[5];
	uint8_t *img = make_image(P_NOISE, 700, 600);
	size_t n = roundtrip("noise-big", img, 700, 600, blocks, &idat, filters);
	CHECK(blocks[0] >= 2);
	CHECK(idat >= 2);
	CHECK(n < 700 * 600 * 3 + 601 + 2000); /* stored overhead stays small */
	free(img);

	/* a flat image compresses to almost nothing (long matches, fixed or dynamic) */
	img = make_image(P_FLAT, 512, 512);
	n = roundtrip("flat", img, 512, 512, blocks, &idat, filters);
	CHECK(n > 0 && n < 2000);
	CHECK(blocks[0] == 0);
	CHECK(filters[2] == 511); /* every row but the first equals the one above */
	free(img);

	/* a rendered-looking image: dynamic blocks, and a real gain */
	img = make_image(P_RENDERLIKE, 640, 480);
	n = roundtrip("render", img, 640, 480, blocks, &idat, filters);
	CHECK(blocks[2] >= 1);
	CHECK(n > 0 && n < 640 * 480 * 3 / 2);
	free(img);

	/* a horizontal ramp with rows far apart: Sub wins on every row */
	img = malloc(3 * 256 * 16);
	for (int y = 0; y < 16; y++)
		for (int x = 0; x < 256; x++)
			for (int c = 0; c < 3; c++)
				img[3 * (y * 256 + x) + c] = (uint8_t)(x * 3 + y * y * 5 + c);
	n = roundtrip("sub", img, 256, 16, blocks, &idat, filters);
	CHECK(n > 0 && filters[1] == 16);
	free(img);
	/* vertical gradient: each row differs from the one above by a constant:
	 * Up wins from the second row on */
	img = malloc(3 * 64 * 64);
	for (int y = 0; y < 64; y++)
		for (int x = 0; x < 64; x++)
			for (int c = 0; c < 3; c++)
				img[3 * (y * 64 + x) + c] = (uint8_t)((x * 97 + c * 31) % 256);
	n = roundtrip("up", img, 64, 64, blocks, &idat, filters);
	CHECK(filters[2] == 63);
	free(img);

	/* the window edge: rows alternate between two noise rows, so the
	 * filtered data repeats every two rows; with 3w+1 = 16384 that is
	 * exactly the largest distance deflate allows (32768) and must be used;
	 * one pixel wider and nothing can match */
	for (uint32_t w = 5461; w <= 5462; w++) {
		uint32_t h = 8;
		img = malloc(3 * (size_t)w * h);
		for (size_t i = 0; i < 6 * (size_t)w; i++)
			img[i] = (uint8_t)(rnd() >> 16);
		for (uint32_t y = 2; y < h; y++)
			memcpy(img + 3 * (size_t)w * y, img + 3 * (size_t)w * (y % 2), 3 * (size_t)w);
		n = roundtrip("window", img, w, h, blocks, &idat, filters);
		size_t raw = (3 * (size_t)w + 1) * h;
		if (w == 5461)
			CHECK(n > 0 && n < raw / 2);
		else
			CHECK(n > raw * 9 / 10);
		free(img);
	}
	/* rows longer than the window */
	img = make_image(P_FLAT, 11000, 3);
	CHECK(roundtrip("long-rows", img, 11000, 3, NULL, NULL, NULL) > 0);
	free(img);
	img = make_image(P_STRIPES, 10923, 4);
	CHECK(roundtrip("long-rows", img, 10923, 4, NULL, NULL, NULL) > 0);
	free(img);

	/* many sizes around block and window boundaries, each compared exactly */
	for (uint32_t w = 1; w <= 130; w += 43) {
		for (uint32_t h = 1; h <= 300; h += 97) {
			for (int p = 0; p < 6; p++) {
				img = make_image((enum pattern)p, w, h);
				CHECK(roundtrip("sizes", img, w, h, NULL, NULL, NULL) > 0);
				free(img);
			}
		}
	}

	/* invalid sizes */
	uint8_t px[3] = { 1, 2, 3 }, *out = (uint8_t *)px;
	errno = 0;
	CHECK(img_png_encode(px, 0, 1, &out, &n) == -1 && errno == EINVAL && out == NULL);
	CHECK(img_png_encode(px, 1, LIM_IMAGE_SIDE + 1u, &out, &n) == -1 && errno == EINVAL);
}

/* ---- files --------------------------------------------------------------------------- */

static int count_tmp_files(const char *dir)
{
	int k = 0;
	DIR *d = opendir(dir);
	struct dirent *e;
	while (d && (e = readdir(d)) != NULL)
		k += strstr(e->d_name, ".tmp.") != NULL;
	if (d)
		closedir(d);
	return k;
}

static void test_files(void)
{
	char dir[] = "/tmp/test_img_XXXXXX";
	if (!mkdtemp(dir)) {
		CHECK(0);
		return;
	}
	char path[256];
	uint8_t *img = make_image(P_RENDERLIKE, 37, 23), *data;
	size_t n;

	/* .png in any case -> PNG */
	static const char *pngs[] = { "a.png", "b.PNG", "c.PnG" };
	for (int i = 0; i < 3; i++) {
		snprintf(path, sizeof path, "%s/%s", dir, pngs[i]);
		CHECK(img_write(path, img, 37, 23) == 0);
		data = slurp(path, &n);
		uint8_t *back = NULL;
		uint32_t w, h;
		int idat, blocks[3], filters[5];
		CHECK(data && inf_png(data, n, &back, &w, &h, &idat, blocks, filters) == 0);
		CHECK(back && w == 37 && h == 23 && memcmp(back, img, 37 * 23 * 3) == 0);
		free(back);
		free(data);
	}
	/* anything else -> binary PPM */
	static const char *ppms[] = { "d.ppm", "e", "f.png.ppm", "g.pngx" };
	for (int i = 0; i < 4; i++) {
		snprintf(path, sizeof path, "%s/%s", dir, ppms[i]);
		CHECK(img_write(path, img, 37, 23) == 0);
		data = slurp(path, &n);
		static const char head[] = "P6\n37 23\n255\n";
		CHECK(data && n == sizeof head - 1 + 37 * 23 * 3);
		CHECK(data && memcmp(data, head, sizeof head - 1) == 0);
		CHECK(data && n == sizeof head - 1 + 37 * 23 * 3 &&
		      memcmp(data + sizeof head - 1, img, 37 * 23 * 3) == 0);
		free(data);
	}
	/* overwriting replaces the whole file */
	snprintf(path, sizeof path, "%s/d.ppm", dir);
	uint8_t *small = make_image(P_FLAT, 2, 1);
	CHECK(img_write(path, small, 2, 1) == 0);
	data = slurp(path, &n);
	CHECK(data && n == strlen("P6\n2 1\n255\n") + 6);
	free(data);
	free(small);
	CHECK(count_tmp_files(dir) == 0);

	/* errors: a missing directory, a path that is a directory, bad sizes */
	snprintf(path, sizeof path, "%s/nodir/x.png", dir);
	errno = 0;
	CHECK(img_write(path, img, 37, 23) == -1 && errno == ENOENT);
	snprintf(path, sizeof path, "%s/sub.png", dir);
	mkdir(path, 0777);
	CHECK(img_write(path, img, 37, 23) == -1);
	rmdir(path);
	CHECK(count_tmp_files(dir) == 0);
	errno = 0;
	snprintf(path, sizeof path, "%s/z.ppm", dir);
	CHECK(img_write(path, img, 0, 23) == -1 && errno == EINVAL);
	CHECK(access(path, F_OK) != 0);

	/* clean up */
	static const char *all[] = { "a.png", "b.PNG", "c.PnG", "d.ppm", "e", "f.png.ppm", "g.pngx" };
	for (int i = 0; i < 7; i++) {
		snprintf(path, sizeof path, "%s/%s", dir, all[i]);
		unlink(path);
	}
	CHECK(rmdir(dir) == 0);
	free(img);
}

/*
 * An output that exists and is not a regular file (a FIFO here; /dev/null or
 * /dev/stdout in use) is written in place: renaming a temporary over it would
 * replace the device or pipe with a plain file (as root, /dev/null itself).
 */
static void test_special_output(void)
{
	char dir[] = "/tmp/test_img_fifo_XXXXXX";
	if (!mkdtemp(dir)) {
		CHECK(0);
		return;
	}
	char path[256];
	snprintf(path, sizeof path, "%s/out.ppm", dir);
	if (mkfifo(path, 0600) != 0) {
		CHECK(0);
		rmdir(dir);
		return;
	}
	int pfd[2];
	CHECK(pipe(pfd) == 0);
	pid_t pid = fork();
	if (pid == 0) { /* reader: counts the bytes that come through the FIFO */
		close(pfd[0]);
		FILE *f = fopen(path, "rb");
		long k = 0;
		while (f && fgetc(f) != EOF)
			k++;
		(void)!write(pfd[1], &k, sizeof k);
		_exit(0);
	}
	close(pfd[1]);
	uint8_t *img = make_image(P_FLAT, 4, 3);
	int rc = img_write(path, img, 4, 3);
	struct stat st;
	int still_fifo = lstat(path, &st) == 0 && S_ISFIFO(st.st_mode);
	CHECK(rc == 0);
	CHECK(still_fifo);
	long got = -1;
	if (still_fifo && rc == 0) {
		CHECK(read(pfd[0], &got, sizeof got) == (ssize_t)sizeof got);
		CHECK(got == (long)strlen("P6\n4 3\n255\n") + 4 * 3 * 3);
	} else {
		kill(pid, SIGKILL);
	}
	waitpid(pid, NULL, 0);
	close(pfd[0]);
	CHECK(count_tmp_files(dir) == 0);
	unlink(path);
	CHECK(rmdir(dir) == 0);
	free(img);
}

/*
 * An output that is a symbolic link is written through the link: the target
 * gets the image and the link stays (renaming over the link replaced it with
 * a plain file; as root, -o /dev/stdout replaced the /dev/stdout link).
 */
static void test_symlink_output(void)
{
	char dir[] = "/tmp/test_img_link_XXXXXX";
	if (!mkdtemp(dir)) {
		CHECK(0);
		return;
	}
	char target[256], link[256];
	snprintf(target, sizeof target, "%s/real.ppm", dir);
	snprintf(link, sizeof link, "%s/link.ppm", dir);
	FILE *f = fopen(target, "wb");
	CHECK(f != NULL);
	if (f)
		fclose(f);
	CHECK(symlink("real.ppm", link) == 0);
	uint8_t *img = make_image(P_FLAT, 4, 3);
	CHECK(img_write(link, img, 4, 3) == 0);
	struct stat st;
	CHECK(lstat(link, &st) == 0 && S_ISLNK(st.st_mode));
	CHECK(stat(target, &st) == 0 && st.st_size == (off_t)(strlen("P6\n4 3\n255\n") + 4 * 3 * 3));
	CHECK(count_tmp_files(dir) == 0);
	unlink(link);
	unlink(target);
	CHECK(rmdir(dir) == 0);
	free(img);
}

/* Writes sample PNGs and their pixels for tests/cli/png_python.sh. */
static int write_samples(const char *dir)
{
	static const struct {
		const char *name;
		enum pattern p;
		uint32_t w, h;
	} s[] = { { "noise", P_NOISE, 300, 250 }, { "render", P_RENDERLIKE, 320, 240 },
		  { "flat", P_FLAT, 64, 64 },     { "one", P_GRADIENT, 1, 1 },
		  { "wide", P_CHECKER, 1000, 1 },  { "checker", P_CHECKER, 101, 77 } };
	for (size_t i = 0; i < sizeof s / sizeof s[0]; i++) {
		char path[4096];
		uint8_t *img = make_image(s[i].p, s[i].w, s[i].h);
		snprintf(path, sizeof path, "%s/%s.png", dir, s[i].name);
		if (img_write(path, img, s[i].w, s[i].h) != 0)
			return 1;
		snprintf(path, sizeof path, "%s/%s.rgb", dir, s[i].name);
		FILE *f = fopen(path, "wb");
		if (!f || fwrite(img, 3, (size_t)s[i].w * s[i].h, f) != (size_t)s[i].w * s[i].h)
			return 1;
		fclose(f);
		free(img);
	}
	return 0;
}

int main(int argc, char **argv)
{
	if (argc == 2)
		return write_samples(argv[1]);
	test_checksums();
	test_decoder();
	test_png_roundtrips();
	test_files();
	test_special_output();
	test_symlink_output();
	TEST_MAIN_END();
}
