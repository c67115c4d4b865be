/*
 * journal.c - checkpoint and resume (journal.h).
 *
 * Layout, every number little-endian:
 *
 *   header (JN_HDR_BYTES = 112)
 *     0  magic "PORTRAYJ"           8
 *     8  version (1)                4
 *    12  header bytes (112)         4
 *    16  scene content hash        32
 *    48  width, height, tile side, pixel revision, pixel type, bytes a
 *        pixel, tiles in all, region x0, y0, x1, y1 (all 0: the whole
 *        image), 0                12 x 4
 *    96  SHA-256 of bytes 0..95, its first 16 bytes
 *   records, one after another
 *     0  kind: 1 tile finished, 2 tile undone
 *     4  tile id
 *     8  payload bytes: the tile's pixels (rows top to bottom), or 0 (undone)
 *    12  payload
 *     .  SHA-256 of the record's bytes before it, its first 16 bytes
 *
 * A tile's latest record says what it is. Reading stops at the first record
 * that is short, unknown, about an unknown tile, of the wrong size or fails
 * its checksum: that record and the rest are dropped (and cut off the file
 * before anything is appended).
 */
#include "master/journal.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/tiles.h"
#include "master/farm_int.h"
#include "proto/net.h"
#include "proto/sha256.h"

#define JN_MAGIC "PORTRAYJ"
#define JN_VERSION 1u
#define JN_HDR_BYTES 112u
#define JN_HDR_SUMMED 96u
#define JN_SUM_BYTES 16u
#define JN_REC_HEAD 12u
#define JN_TILE 1u
#define JN_UNDO 2u
/* bytes gathered before a write(2) during a checkpoint */
#define JN_WBUF_BYTES (1u << 20)

/* per-tile flags */
enum {
	F_IN = 1,    /* the journal's latest record for it is a finished tile */
	F_DIRTY = 2, /* changed since the last checkpoint (in j->dirty) */
	F_PRE = 4,   /* preloaded: its one change report is ours, not news */
	F_DONE = 8,  /* done when last reported (journal_note) */
};

struct journal {
	char *path, *tmp;
	struct journal_params p;
	struct tiling tg;
	int fd;                /* the journal (once it exists), or -1 */
	uint64_t good;         /* bytes of the file known good (appends go here) */
	bool loaded;
	uint64_t dropped;
	bool broken;           /* a write failed: no more checkpoints */
	double interval;
	uint8_t *flags;        /* per tile */
	uint64_t *off;         /* per tile: its latest finished record's payload */
	uint32_t n_in;         /* tiles with F_IN */
	uint32_t *dirty;       /* ids with F_DIRTY */
	uint32_t n_dirty;
	uint8_t *tile;         /* one tile's pixels */
	size_t tile_bytes;     /* its size: side * side * bpp */
	uint8_t *wbuf;         /* records waiting for write(2) */
	size_t wlen;
	/* attached to a render */
	struct farm *f;
	struct ev_timer tm;
	uint32_t preloaded;
};

static void put32(uint8_t *p, uint32_t v)
{
	p[0] = (uint8_t)v;
	p[1] = (uint8_t)(v >> 8);
	p[2] = (uint8_t)(v >> 16);
	p[3] = (uint8_t)(v >> 24);
}

static uint32_t get32(const uint8_t *p)
{
	return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

void journal_tiling(const struct journal_params *p, struct tiling *tg)
{
	if (p->region[2] > p->region[0])
		tiling_init_region(tg, p->width, p->height, p->tile, p->region[0], p->region[1], p->region[2],
				   p->region[3]);
	else
		tiling_init(tg, p->width, p->height, p->tile);
}

/* The header for p and tg (JN_HDR_BYTES into h). */
static void header_make(const struct journal_params *p, const struct tiling *tg, uint8_t *h)
{
	memset(h, 0, JN_HDR_BYTES);
	memcpy(h, JN_MAGIC, 8);
	put32(h + 8, JN_VERSION);
	put32(h + 12, JN_HDR_BYTES);
	memcpy(h + 16, p->scene_hash, JOURNAL_HASH_BYTES);
	const uint32_t v[12] = { p->width,     p->height,    p->tile,      p->pixel_rev,
				 p->pixel_type, p->bpp,      tg->n,        p->region[0],
				 p->region[1],  p->region[2], p->region[3], 0 };
	for (int i = 0; i < 12; i++)
		put32(h + 48 + 4 * i, v[i]);
	uint8_t sum[SHA256_DIGEST_BYTES];
	sha256(h, JN_HDR_SUMMED, sum);
	memcpy(h + JN_HDR_SUMMED, sum, JN_SUM_BYTES);
}

/* Bytes of tile id's pixels. */
static size_t tile_size(const struct journal *j, uint32_t id)
{
	struct tile_rect r = tiling_rect(&j->tg, id);
	return (size_t)r.w * r.h * j->p.bpp;
}

/* ---- reading ---- */

/* Reads exactly n bytes at the file's position: n, fewer at end of file, or -1. */
static ssize_t read_full(int fd, uint8_t *buf, size_t n)
{
	size_t got = 0;
	while (got < n) {
		ssize_t k = read(fd, buf + got, n - got);
		if (k < 0 && errno == EINTR)
			continue;
		if (k < 0)
			return -1;
		if (k == 0)
			break;
		got += (size_t)k;
	}
	return (ssize_t)got;
}

/* Compares the header h with j's parameters; JOURNAL_OK or a status with err. */
static enum journal_status header_check(const struct journal *j, const uint8_t *h, char *err, size_t errlen)
{
	uint8_t sum[SHA256_DIGEST_BYTES];
	sha256(h, JN_HDR_SUMMED, sum);
	if (memcmp(h, JN_MAGIC, 8) != 0 || get32(h + 12) != JN_HDR_BYTES ||
	    memcmp(h + JN_HDR_SUMMED, sum, JN_SUM_BYTES) != 0) {
		snprintf(err, errlen, "%s is not a portray journal, or its header is damaged", j->path);
		return JOURNAL_DAMAGED;
	}
	if (get32(h + 8) != JN_VERSION) {
		snprintf(err, errlen, "%s is a journal of version %u; this portray reads version %u", j->path,
			 get32(h + 8), JN_VERSION);
		return JOURNAL_MISMATCH;
	}
	const uint8_t *v = h + 48;
	uint32_t w = get32(v), hh = get32(v + 4), tile = get32(v + 8), rev = get32(v + 12), type = get32(v + 16),
		 bpp = get32(v + 20);
	if (memcmp(h + 16, j->p.scene_hash, JOURNAL_HASH_BYTES) != 0)
		snprintf(err, errlen,
			 "%s belongs to another scene (its content hash differs: the scene, a file it includes, its "
			 "RAW data or the camera file changed)",
			 j->path);
	else if (w != j->p.width || hh != j->p.height)
		snprintf(err, errlen, "%s is for a %ux%u image; this render is %ux%u", j->path, w, hh, j->p.width,
			 j->p.height);
	else if (tile != j->p.tile)
		snprintf(err, errlen, "%s is for tiles of %u pixels; this render cuts tiles of %u (--tile)", j->path,
			 tile, j->p.tile);
	else if (rev != j->p.pixel_rev)
		snprintf(err, errlen,
			 "%s was written by a portray whose pixels differ (pixel revision %u; this one is %u)",
			 j->path, rev, j->p.pixel_rev);
	else if (type != j->p.pixel_type || bpp != j->p.bpp)
		snprintf(err, errlen,
			 "%s holds pixels of another type (type %u, %u bytes a pixel; this output wants type %u, %u "
			 "bytes: --format or the extension changed)",
			 j->path, type, bpp, j->p.pixel_type, j->p.bpp);
	else if (get32(v + 28) != j->p.region[0] || get32(v + 32) != j->p.region[1] ||
		 get32(v + 36) != j->p.region[2] || get32(v + 40) != j->p.region[3])
		snprintf(err, errlen, "%s is for another --region (%u,%u,%u,%u; all 0: the whole image)", j->path,
			 get32(v + 28), get32(v + 32), get32(v + 36), get32(v + 40));
	else if (get32(v + 24) != j->tg.n)
		snprintf(err, errlen, "%s is damaged (%u tiles, not %u)", j->path, get32(v + 24), j->tg.n);
	else
		return JOURNAL_OK;
	return JOURNAL_MISMATCH;
}

/*
 * Reads the records after the header from fd (positioned there): sets the
 * tiles' F_IN and off, j->good to the end of the last good record. Stops at
 * the first bad one. 0, or -1 on a read error.
 */
static int records_load(struct journal *j, int fd)
{
	uint64_t pos = JN_HDR_BYTES;
	uint8_t head[JN_REC_HEAD], sum[SHA256_DIGEST_BYTES], want[JN_SUM_BYTES];
	for (;;) {
		j->good = pos;
		ssize_t k = read_full(fd, head, sizeof head);
		if (k < 0)
			return -1;
		if (k < (ssize_t)sizeof head)
			return 0;
		uint32_t kind = get32(head), id = get32(head + 4), len = get32(head + 8);
		if ((kind != JN_TILE && kind != JN_UNDO) || id >= j->tg.n ||
		    len != (kind == JN_TILE ? tile_size(j, id) : 0))
			return 0;
		struct sha256 c;
		sha256_init(&c);
		sha256_update(&c, head, sizeof head);
		if (len && ((k = read_full(fd, j->tile, len)) < 0 || (size_t)k < len))
			return k < 0 ? -1 : 0;
		if (len)
			sha256_update(&c, j->tile, len);
		sha256_final(&c, sum);
		if ((k = read_full(fd, want, sizeof want)) < 0)
			return -1;
		if ((size_t)k < sizeof want || memcmp(sum, want, JN_SUM_BYTES) != 0)
			return 0;
		bool was_in = j->flags[id] & F_IN;
		if (kind == JN_TILE) {
			j->flags[id] |= F_IN;
			j->off[id] = pos + JN_REC_HEAD;
			j->n_in += !was_in;
		} else {
			j->flags[id] &= (uint8_t)~F_IN;
			j->n_in -= was_in;
		}
		pos += JN_REC_HEAD + len + JN_SUM_BYTES;
	}
}

/* Loads the journal at j->path; JOURNAL_OK (also when there is none), or an error with err. */
static enum journal_status journal_load(struct journal *j, char *err, size_t errlen)
{
	int fd = open(j->path, O_RDWR | O_CLOEXEC);
	if (fd < 0) {
		if (errno == ENOENT)
			return JOURNAL_OK;
		snprintf(err, errlen, "cannot open %s: %s", j->path, strerror(errno));
		return JOURNAL_IO;
	}
	struct stat st;
	uint8_t h[JN_HDR_BYTES];
	ssize_t k = fstat(fd, &st) == 0 ? read_full(fd, h, sizeof h) : -1;
	enum journal_status rc = JOURNAL_IO;
	if (k < 0) {
		snprintf(err, errlen, "cannot read %s: %s", j->path, strerror(errno));
		goto fail;
	}
	if (k < (ssize_t)sizeof h) {
		snprintf(err, errlen, "%s is not a portray journal, or its header is damaged (%zd bytes)", j->path, k);
		rc = JOURNAL_DAMAGED;
		goto fail;
	}
	if ((rc = header_check(j, h, err, errlen)) != JOURNAL_OK)
		goto fail;
	if (records_load(j, fd) < 0) {
		snprintf(err, errlen, "cannot read %s: %s", j->path, strerror(errno));
		rc = JOURNAL_IO;
		goto fail;
	}
	j->dropped = (uint64_t)st.st_size - j->good;
	/* cut a damaged tail off, so that appends follow the last good record */
	if (j->dropped && ftruncate(fd, (off_t)j->good) < 0) {
		snprintf(err, errlen, "cannot cut the damaged tail off %s: %s", j->path, strerror(errno));
		rc = JOURNAL_IO;
		goto fail;
	}
	j->fd = fd;
	j->loaded = true;
	return JOURNAL_OK;
fail:
	close(fd);
	return rc;
}

/* ---- the journal ---- */

static void journal_free(struct journal *j)
{
	if (!j)
		return;
	if (j->fd >= 0)
		close(j->fd);
	free(j->path);
	free(j->tmp);
	free(j->flags);
	free(j->off);
	free(j->dirty);
	free(j->tile);
	free(j->wbuf);
	free(j);
}

enum journal_status journal_open(const char *path, const struct journal_params *p, bool resume, double interval,
				 struct journal **out, char *err, size_t errlen)
{
	*out = NULL;
	struct journal *j = calloc(1, sizeof *j);
	if (!j)
		goto nomem;
	j->fd = -1;
	j->p = *p;
	j->interval = interval;
	journal_tiling(p, &j->tg);
	size_t n = strlen(path);
	j->path = strdup(path);
	j->tmp = malloc(n + 5);
	j->tile_bytes = (size_t)j->tg.side * j->tg.side * p->bpp;
	j->flags = calloc(j->tg.n, 1);
	j->off = calloc(j->tg.n, sizeof *j->off);
	j->dirty = calloc(j->tg.n, sizeof *j->dirty);
	j->tile = malloc(j->tile_bytes);
	if (!j->path || !j->tmp || !j->flags || !j->off || !j->dirty || !j->tile)
		goto nomem;
	memcpy(j->tmp, path, n);
	memcpy(j->tmp + n, ".tmp", 5);
	if (resume) {
		enum journal_status rc = journal_load(j, err, errlen);
		if (rc != JOURNAL_OK) {
			journal_free(j);
			return rc;
		}
	}
	*out = j;
	return JOURNAL_OK;
nomem:
	journal_free(j);
	snprintf(err, errlen, "out of memory for the journal");
	return JOURNAL_NOMEM;
}

bool journal_loaded(const struct journal *j) { return j->loaded; }
uint32_t journal_tiles(const struct journal *j) { return j->n_in; }
uint64_t journal_dropped(const struct journal *j) { return j->dropped; }
bool journal_has(const struct journal *j, uint32_t id) { return id < j->tg.n && (j->flags[id] & F_IN); }
const char *journal_path(const struct journal *j) { return j->path; }
uint32_t journal_preloaded(const struct journal *j) { return j->preloaded; }

int journal_read_tile(struct journal *j, uint32_t id, uint8_t *out)
{
	if (!journal_has(j, id) || j->fd < 0)
		return -1;
	size_t len = tile_size(j, id), got = 0;
	while (got < len) {
		ssize_t k = pread(j->fd, out + got, len - got, (off_t)(j->off[id] + got));
		if (k < 0 && errno == EINTR)
			continue;
		if (k <= 0)
			return -1;
		got += (size_t)k;
	}
	return 0;
}

void journal_note(struct journal *j, uint32_t id, bool done)
{
	if (id >= j->tg.n)
		return;
	if (done)
		j->flags[id] |= F_DONE;
	else
		j->flags[id] &= (uint8_t)~F_DONE;
	if (!(j->flags[id] & F_DIRTY)) {
		j->flags[id] |= F_DIRTY;
		j->dirty[j->n_dirty++] = id;
	}
}

/* ---- writing ---- */

static int write_full(int fd, const uint8_t *p, size_t n)
{
	while (n > 0) {
		ssize_t k = write(fd, p, n);
		if (k < 0 && errno == EINTR)
			continue;
		if (k <= 0)
			return -1;
		p += k;
		n -= (size_t)k;
	}
	return 0;
}

/* Writes the gathered records (j->wbuf) at the end of fd. */
static int wflush(struct journal *j, int fd)
{
	int rc = write_full(fd, j->wbuf, j->wlen);
	j->wlen = 0;
	return rc;
}

/* Gathers one record (payload len bytes, may be 0), flushing to fd when the buffer fills. */
static int record_put(struct journal *j, int fd, uint32_t kind, uint32_t id, const uint8_t *payload, size_t len)
{
	uint8_t head[JN_REC_HEAD], sum[SHA256_DIGEST_BYTES];
	put32(head, kind);
	put32(head + 4, id);
	put32(head + 8, (uint32_t)len);
	struct sha256 c;
	sha256_init(&c);
	sha256_update(&c, head, sizeof head);
	if (len)
		sha256_update(&c, payload, len);
	sha256_final(&c, sum);
	size_t need = JN_REC_HEAD + len + JN_SUM_BYTES;
	if (j->wlen + need > JN_WBUF_BYTES && j->wlen && wflush(j, fd) < 0)
		return -1;
	if (need > JN_WBUF_BYTES) { /* a tile larger than the buffer: straight out */
		return write_full(fd, head, sizeof head) < 0 || write_full(fd, payload, len) < 0 ||
		       write_full(fd, sum, JN_SUM_BYTES) < 0 ? -1 : 0;
	}
	memcpy(j->wbuf + j->wlen, head, sizeof head);
	if (len)
		memcpy(j->wbuf + j->wlen + sizeof head, payload, len);
	memcpy(j->wbuf + j->wlen + sizeof head + len, sum, JN_SUM_BYTES);
	j->wlen += need;
	return 0;
}

/* fsyncs the directory holding path (so that a rename in it is durable). */
static void dir_sync(const char *path)
{
	const char *slash = strrchr(path, '/');
	char dir[4096];
	if (!slash)
		snprintf(dir, sizeof dir, ".");
	else if (slash == path)
		snprintf(dir, sizeof dir, "/");
	else
		snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
	int fd = open(dir, O_RDONLY | O_CLOEXEC);
	if (fd >= 0) {
		(void)fsync(fd);
		close(fd);
	}
}

int journal_checkpoint(struct journal *j, journal_pixels_fn px, void *arg)
{
	if (j->broken || j->n_dirty == 0)
		return j->broken ? -1 : 0;
	if (!j->wbuf && !(j->wbuf = malloc(JN_WBUF_BYTES))) {
		fprintf(stderr, "portray-master: warning: out of memory for the journal: no more checkpoints\n");
		j->broken = true;
		return -1;
	}
	bool fresh = j->fd < 0;
	int fd = j->fd;
	const char *what = j->path;
	if (fresh) {
		/* the first checkpoint: header and records in a temporary file, renamed over path */
		what = j->tmp;
		fd = open(j->tmp, O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
		if (fd < 0)
			goto fail;
		header_make(&j->p, &j->tg, j->wbuf);
		j->wlen = JN_HDR_BYTES;
		j->good = JN_HDR_BYTES;
	} else if (lseek(fd, (off_t)j->good, SEEK_SET) < 0) {
		goto fail;
	}
	uint64_t pos = j->good;
	uint32_t n_in = j->n_in;
	for (uint32_t i = 0; i < j->n_dirty; i++) {
		uint32_t id = j->dirty[i];
		bool in = j->flags[id] & F_IN;
		size_t len = tile_size(j, id);
		if (px(arg, id, j->tile)) {
			if (record_put(j, fd, JN_TILE, id, j->tile, len) < 0)
				goto fail;
			j->off[id] = pos + JN_REC_HEAD; /* takes effect with F_IN below, once durable */
			pos += JN_REC_HEAD + len + JN_SUM_BYTES;
			n_in += !in;
			j->flags[id] |= F_IN;
		} else if (in) {
			if (record_put(j, fd, JN_UNDO, id, NULL, 0) < 0)
				goto fail;
			pos += JN_REC_HEAD + JN_SUM_BYTES;
			n_in--;
			j->flags[id] &= (uint8_t)~F_IN;
		}
	}
	if (fresh && pos == JN_HDR_BYTES) { /* nothing to keep yet: no file */
		close(fd);
		unlink(j->tmp);
		j->wlen = 0;
		goto clean;
	}
	if (wflush(j, fd) < 0 || fsync(fd) < 0)
		goto fail;
	if (fresh) {
		if (rename(j->tmp, j->path) < 0)
			goto fail;
		dir_sync(j->path);
		j->fd = fd;
	}
	j->good = pos;
	j->n_in = n_in;
clean:
	for (uint32_t i = 0; i < j->n_dirty; i++)
		j->flags[j->dirty[i]] &= (uint8_t)~F_DIRTY;
	j->n_dirty = 0;
	return 0;
fail:
	fprintf(stderr, "portray-master: warning: cannot write the journal %s: %s; no more checkpoints\n", what,
		strerror(errno));
	j->broken = true;
	j->wlen = 0;
	if (fresh) {
		if (fd >= 0)
			close(fd);
		unlink(j->tmp);
	} else if (ftruncate(fd, (off_t)j->good) < 0) {
		/* what was appended may be torn: a resume drops it by its checksum */
	}
	return -1;
}

/* ---- attached to a render ---- */

/* journal_pixels_fn over the scheduler (during the render) */
static bool sched_px(void *arg, uint32_t id, uint8_t *out) { return sched_tile_pixels(arg, id, out); }

/* the farm's observer: tiles stored or undone */
static void on_tiles(void *arg, struct farm *f, const uint32_t *ids, uint32_t n)
{
	struct journal *j = arg;
	for (uint32_t i = 0; i < n; i++) {
		uint32_t id = ids[i];
		if (id < j->tg.n && (j->flags[id] & F_PRE)) { /* its preload reported back */
			j->flags[id] &= (uint8_t)~F_PRE;
			continue;
		}
		journal_note(j, id, sched_tile_pixels(f->s, id, j->tile));
	}
}

static void on_timer(struct ev_loop *l, void *arg)
{
	struct journal *j = arg;
	journal_checkpoint(j, sched_px, j->f->s);
	if (!j->broken)
		ev_timer_arm(l, &j->tm, net_now() + j->interval);
}

int journal_attach(struct journal *j, struct farm *f)
{
	if (sched_bpp(f->s) != j->p.bpp || f->tg.n != j->tg.n || f->tg.side != j->tg.side) {
		fprintf(stderr, "portray-master: internal error: the journal's tiles (%u of %u px, %u bytes a pixel) are "
			"not the render's (%u of %u px, %u bytes)\n", j->tg.n, j->tg.side, j->p.bpp, f->tg.n, f->tg.side,
			sched_bpp(f->s));
		return -1;
	}
	if (farm_observe(f, &(struct farm_observer){ on_tiles, j }) < 0) {
		fprintf(stderr, "portray-master: out of memory for the journal\n");
		return -1;
	}
	j->f = f;
	for (uint32_t id = 0; id < j->tg.n; id++) {
		if (!(j->flags[id] & F_IN))
			continue;
		if (journal_read_tile(j, id, j->tile) < 0) {
			fprintf(stderr, "portray-master: cannot read %s: %s\n", j->path, strerror(errno));
			return -1;
		}
		if (sched_preload(f->s, id, j->tile) == 0) {
			j->flags[id] |= F_PRE | F_DONE;
			j->preloaded++;
		}
	}
	if (j->interval > 0) {
		ev_timer_init(&j->tm, on_timer, j);
		ev_timer_arm(f->loop, &j->tm, net_now() + j->interval);
	}
	return 0;
}

void journal_detach(struct journal *j)
{
	if (!j || !j->f)
		return;
	if (j->f->loop)
		ev_timer_stop(j->f->loop, &j->tm);
	j->f = NULL;
}

/* journal_pixels_fn over the finished image (nothing traces any more) */
struct image_src {
	const struct journal *j;
	const uint8_t *image;
};

static bool image_px(void *arg, uint32_t id, uint8_t *out)
{
	const struct image_src *src = arg;
	const struct journal *j = src->j;
	if (!(j->flags[id] & F_DONE))
		return false;
	struct tile_rect r = tiling_rect(&j->tg, id);
	size_t row = (size_t)r.w * j->p.bpp;
	for (uint32_t y = 0; y < r.h; y++)
		memcpy(out + y * row, src->image + ((size_t)(r.y + y) * j->tg.w + r.x) * j->p.bpp, row);
	return true;
}

bool journal_close(struct journal *j, const uint8_t *image, bool finished, bool keep)
{
	if (!j)
		return false;
	journal_detach(j);
	bool left = false;
	if (finished && !keep) {
		if (unlink(j->path) < 0 && errno != ENOENT)
			fprintf(stderr, "portray-master: warning: cannot remove %s: %s\n", j->path, strerror(errno));
		unlink(j->tmp);
	} else {
		if (image) {
			struct image_src src = { j, image };
			journal_checkpoint(j, image_px, &src);
		}
		left = j->fd >= 0;
	}
	journal_free(j);
	return left;
}

/* ---- render.c's side ---- */

int journal_for_render(const struct master_opts *o, const char *out, const struct journal_params *p,
		       struct journal **out_j)
{
	*out_j = NULL;
	if (strcmp(out, "-") == 0) {
		if (o->resume) {
			fprintf(stderr, "portray-master: --resume needs an output file (-o FILE): its journal lives "
				"beside it, and standard output has none\n");
			return EXIT_USAGE;
		}
		return 0;
	}
	size_t n = strlen(out);
	char *path = malloc(n + sizeof JOURNAL_SUFFIX);
	if (!path) {
		fprintf(stderr, "portray-master: out of memory\n");
		return ERRLEVEL_FATAL;
	}
	memcpy(path, out, n);
	memcpy(path + n, JOURNAL_SUFFIX, sizeof JOURNAL_SUFFIX);
	char err[600];
	struct stat st;
	bool exists = stat(path, &st) == 0;
	enum journal_status s = journal_open(path, p, o->resume, o->checkpoint_s, out_j, err, sizeof err);
	int rc = 0;
	switch (s) {
	case JOURNAL_OK:
		break;
	case JOURNAL_MISMATCH:
	case JOURNAL_DAMAGED:
		fprintf(stderr,
			"portray-master: cannot resume: %s\n"
			"portray-master: render without --resume to start afresh (the journal is then replaced), or "
			"remove it\n",
			err);
		rc = EXIT_JOURNAL;
		break;
	case JOURNAL_IO:
		fprintf(stderr, "portray-master: %s\n", err);
		rc = EXIT_IO;
		break;
	case JOURNAL_NOMEM:
		fprintf(stderr, "portray-master: %s\n", err);
		rc = ERRLEVEL_FATAL;
		break;
	}
	if (rc == 0) {
		struct journal *j = *out_j;
		struct tiling tg;
		journal_tiling(p, &tg);
		if (o->resume && journal_loaded(j)) {
			fprintf(stderr, "portray-master: resuming from %s: %u of %u tiles done, %u to trace\n", path,
				journal_tiles(j), tg.n, tg.n - journal_tiles(j));
			if (journal_dropped(j))
				fprintf(stderr,
					"portray-master: %s: a damaged or torn tail of %llu bytes dropped (its tiles are "
					"traced again)\n",
					path, (unsigned long long)journal_dropped(j));
		} else if (o->resume) {
			fprintf(stderr, "portray-master: --resume: no journal %s: rendering from the start\n", path);
		} else if (exists) {
			fprintf(stderr,
				"portray-master: note: the journal %s of an earlier render will be replaced (--resume "
				"continues it)\n",
				path);
		}
	}
	free(path);
	return rc;
}
