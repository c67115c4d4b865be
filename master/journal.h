/*
 * journal.h - checkpoint and resume (master/journal.c): the master keeps a
 * journal of finished tiles beside the output image (OUT.journal) and
 * `--resume` continues from it, tracing only the tiles it lacks.
 *
 * The file is an append-only log. A header, written once with the first
 * records into OUT.journal.tmp, fsync'd and renamed over OUT.journal, says
 * what render the tiles belong to: the scene's content hash (the encoded
 * scene: includes, RAW data and the camera file with it), the image size,
 * the tile side, the pixel revision (RENDER_PIXEL_REV), the pixel type and
 * bytes a pixel. Records follow: a finished tile (its id and pixels) or an
 * undone one (its worker was caught lying after it was journalled), each
 * closed by a checksum over the whole record. Checkpoints append and fsync;
 * a record torn by a crash or damaged later fails its checksum and it and
 * everything after it are dropped on resume (those tiles are traced again),
 * so a journal never gives a wrong pixel. The layout is in journal.c and
 * docs/resume.md.
 */
#ifndef PORTRAY_JOURNAL_H
#define PORTRAY_JOURNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "master/master.h"

#define JOURNAL_HASH_BYTES 32
/* the journal's name: the output's plus this */
#define JOURNAL_SUFFIX ".journal"
/* default --checkpoint: seconds between checkpoints during a render */
#define JOURNAL_INTERVAL_DEFAULT 30.0

/* What a journal's tiles belong to: anything that changes a pixel. */
struct journal_params {
	uint8_t scene_hash[JOURNAL_HASH_BYTES]; /* proto_scene_hash of the encoded scene */
	uint32_t width, height;
	uint32_t tile;       /* tile side as cut (tiling_init's side, never 0) */
	uint32_t pixel_rev;  /* RENDER_PIXEL_REV */
	uint32_t pixel_type; /* enum img_pixel_type of the tiles */
	uint32_t bpp;        /* bytes a pixel of the tiles */
	uint32_t region[4];  /* --region x0, y0, x1, y1 (x1, y1 excluded); all 0: the whole image */
};

struct tiling;
/* The tiling of a render with parameters p (the farm's: tiling_init_region with a region). */
void journal_tiling(const struct journal_params *p, struct tiling *tg);

/* What journal_open found wrong (besides 0). */
enum journal_status {
	JOURNAL_OK = 0,
	JOURNAL_MISMATCH, /* another render's journal: err says what differs */
	JOURNAL_DAMAGED,  /* not a journal, or its header is damaged */
	JOURNAL_IO,       /* cannot read or open it (errno) */
	JOURNAL_NOMEM
};

struct journal;
struct farm;

/*
 * A journal at path for a render with parameters p (p->tile the side as
 * cut). resume: load path when it exists (it must match p; its torn or
 * damaged tail is dropped and cut off the file); otherwise any old file at
 * path is replaced at the first checkpoint. interval: seconds between
 * checkpoints while attached to a render (0: only when it ends). *out gets
 * the journal (caller frees with journal_close) unless an error is
 * returned, with err (errlen bytes) saying why.
 */
enum journal_status journal_open(const char *path, const struct journal_params *p, bool resume, double interval,
				 struct journal **out, char *err, size_t errlen);
/* Whether a journal file was loaded, and how many tiles it holds. */
bool journal_loaded(const struct journal *j);
uint32_t journal_tiles(const struct journal *j);
/* Bytes of a damaged tail dropped when loading (0: none). */
uint64_t journal_dropped(const struct journal *j);
/* Whether tile id is in the journal (loaded, or written since). */
bool journal_has(const struct journal *j, uint32_t id);
/* Reads the pixels of journalled tile id (its rectangle, rows top to bottom,
 * bpp bytes a pixel) into out. 0, or -1 (not journalled, read error). */
int journal_read_tile(struct journal *j, uint32_t id, uint8_t *out);

/*
 * Where checkpoints read a tile's pixels: true with the pixels in out when
 * the tile is done, false when it is not.
 */
typedef bool (*journal_pixels_fn)(void *arg, uint32_t id, uint8_t *out);
/* Tile id was stored (done) or undone (!done) since the last checkpoint. */
void journal_note(struct journal *j, uint32_t id, bool done);
/*
 * Writes what changed since the last checkpoint (finished tiles, and
 * undone ones that were journalled), reading pixels with px, and makes it
 * durable (the first one creates the file: temporary file, fsync, rename).
 * Nothing to write and no file yet: nothing is created. 0, or -1 when the
 * journal could not be written (said once on stderr; journalling stops,
 * what was written stays valid).
 */
int journal_checkpoint(struct journal *j, journal_pixels_fn px, void *arg);

/*
 * The render's side (farm.c): preloads every journalled tile into the
 * scheduler, observes what is stored or undone from then on and arms the
 * checkpoint timer on the loop. Call after the other observers, before any
 * tile is taken. 0, or -1 with a message printed.
 */
int journal_attach(struct journal *j, struct farm *f);
/* The farm ends: no more checkpoints from its loop or scheduler. */
void journal_detach(struct journal *j);
/* Tiles preloaded from the journal by journal_attach. */
uint32_t journal_preloaded(const struct journal *j);

/*
 * Ends the journal with the render (image: the whole image, w*h*bpp, as
 * assembled; nothing traces any more). finished: the render is complete and
 * its image written: the journal is removed (unless keep). Otherwise (or
 * with keep) the last changes are written from image and the file stays.
 * Frees j (NULL: nothing). Returns whether a journal file is left.
 */
bool journal_close(struct journal *j, const uint8_t *image, bool finished, bool keep);
/* The journal's file name (for messages). */
const char *journal_path(const struct journal *j);

/*
 * render.c's side: the journal for a render to out (NULL, with 0 returned,
 * for standard output, "-"), with its notes and errors printed. Returns 0 or
 * an exit code: EXIT_USAGE (--resume with -o -), EXIT_JOURNAL (a journal
 * that does not match or is damaged), EXIT_IO (unreadable), ERRLEVEL_FATAL
 * (out of memory).
 */
int journal_for_render(const struct master_opts *o, const char *out, const struct journal_params *p,
		       struct journal **out_j);

#endif
