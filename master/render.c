/*
 * render.c - portray-master's render command: load the scene, build the
 * renderer, render locally (or on the farm when workers are named), write
 * the image. Log lines and the progress bar go to stderr; stdout stays quiet.
 */
#include <errno.h>
#include <limits.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/bvh.h"
#include "common/filter.h"
#include "common/img.h"
#include "common/parse.h"
#include "common/render.h"
#include "common/tiles.h"
#include "master/farm.h"
#include "master/http.h"
#include "master/interrupt.h"
#include "master/journal.h"
#include "master/master.h"
#include "master/progress.h"
#include "proto/proto.h"
#include "proto/serial.h"

/*
 * Default output: the scene file's name without directory and extension,
 * plus ".png", in the current directory. Returns a malloc'd string (caller
 * frees) or NULL on out of memory.
 */
static char *default_output(const char *scene)
{
	const char *base = strrchr(scene, '/');
	base = base ? base + 1 : scene;
	size_t n = strlen(base);
	const char *dot = strrchr(base, '.');
	if (dot && dot != base)
		n = (size_t)(dot - base);
	if (n == 0) {
		base = "portray";
		n = strlen(base);
	}
	char *out = malloc(n + 5);
	if (!out)
		return NULL;
	memcpy(out, base, n);
	memcpy(out + n, ".png", 5);
	return out;
}

/* How the output is named in messages. */
static const char *shown(const char *out)
{
	return strcmp(out, "-") == 0 ? "standard output" : out;
}

/*
 * Settles the output before anything is parsed or traced, so that a
 * render is never lost to a name that cannot be written: *out (the file,
 * "-" for standard output; *out_alloc when made here, the caller frees it)
 * and *fmt (--format, else the extension's format, else PNG for "-").
 * Returns 0, EXIT_USAGE (unknown extension, --format against the
 * extension, a binary image for a terminal) or EXIT_IO (img_output_check
 * failed), having said why.
 */
static int output_plan(const struct master_opts *o, const char **out, char **out_alloc, enum img_format *fmt)
{
	*out = o->out;
	if (!*out) {
		*out = *out_alloc = default_output(o->scene);
		if (!*out) {
			fprintf(stderr, "portray-master: out of memory\n");
			return ERRLEVEL_FATAL;
		}
	}
	bool to_stdout = strcmp(*out, "-") == 0;
	enum img_format by_ext;
	bool known_ext = !to_stdout && img_format_by_ext(*out, &by_ext) == 0;
	if (o->format) {
		if (img_format_parse(o->format, fmt) < 0) {
			fprintf(stderr, "portray-master: unknown --format '%s'\n", o->format);
			return EXIT_USAGE;
		}
		if (known_ext && !img_format_ext_matches(*out, *fmt)) {
			fprintf(stderr, "portray-master: --format %s does not go with the name %s (%s files end in %s)\n",
				o->format, *out, o->format, img_format_ext(*fmt));
			return EXIT_USAGE;
		}
	} else if (to_stdout) {
		*fmt = IMG_PNG;
	} else if (known_ext) {
		*fmt = by_ext;
	} else {
		fprintf(stderr,
			"portray-master: cannot tell the image format of %s from its name: known extensions are\n"
			"portray-master: .png .ppm .pfm .exr (any case); or name one with --format png|png16|ppm|pfm|"
			"exr|exr-half\n",
			*out);
		return EXIT_USAGE;
	}
	if (to_stdout && isatty(STDOUT_FILENO)) {
		fprintf(stderr, "portray-master: -o - would write a binary image to the terminal; redirect standard "
			"output to a file or a pipe\n");
		return EXIT_USAGE;
	}
	char dir[PATH_MAX];
	if (img_output_check(*out, dir, sizeof dir) < 0) {
		int e = errno;
		struct stat st;
		if (e == ENOENT && stat(dir, &st) != 0)
			fprintf(stderr, "portray-master: cannot write %s: no directory %s\n", *out, dir);
		else if (e == EISDIR)
			fprintf(stderr, "portray-master: cannot write %s: it is a directory\n", *out);
		else if (e == ENOTDIR)
			fprintf(stderr, "portray-master: cannot write %s: %s is not a directory\n", *out, dir);
		else if (to_stdout)
			fprintf(stderr, "portray-master: cannot write standard output: %s\n", strerror(e));
		else
			fprintf(stderr, "portray-master: cannot write %s: %s: %s\n", *out, dir, strerror(e));
		return EXIT_IO;
	}
	return 0;
}

/*
 * The assembled image's memory, zeroed (unfinished pixels stay black). Its
 * first touch is the assembly of the tiles, and in 4 KiB pages that is a
 * page fault every 4 KiB (900 for a 1280x960 RGB8 image, about a millisecond
 * of the CPU). Where the system offers transparent huge pages on request
 * (Linux MADV_HUGEPAGE), an image of at least IMAGE_HUGE_MIN bytes gets a
 * mapping of its own, aligned to IMAGE_HUGE_PAGE and so advised; elsewhere,
 * or when the mapping fails, calloc's. image_free takes either.
 */
#define IMAGE_HUGE_PAGE ((size_t)2 << 20) /* x86-64's and aarch64's huge page */
#define IMAGE_HUGE_MIN ((size_t)1 << 20)  /* below this the faults cost little */
struct image_mem {
	uint8_t *p;
	void *map; /* the mapping (map_len bytes), or NULL: p is calloc's */
	size_t map_len;
};

static int image_alloc(struct image_mem *m, size_t n)
{
	memset(m, 0, sizeof *m);
#if defined(MADV_HUGEPAGE) && defined(MAP_ANONYMOUS)
	if (n >= IMAGE_HUGE_MIN && n <= SIZE_MAX - 2 * IMAGE_HUGE_PAGE) {
		size_t len = (n + IMAGE_HUGE_PAGE - 1) / IMAGE_HUGE_PAGE * IMAGE_HUGE_PAGE + IMAGE_HUGE_PAGE;
		void *map = mmap(NULL, len, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
		if (map != MAP_FAILED) {
			uintptr_t a = ((uintptr_t)map + IMAGE_HUGE_PAGE - 1) & ~(uintptr_t)(IMAGE_HUGE_PAGE - 1);
			m->p = (uint8_t *)map + (a - (uintptr_t)map); /* fresh anonymous memory reads as zeros */
			m->map = map;
			m->map_len = len;
			(void)madvise(m->p, len - (a - (uintptr_t)map), MADV_HUGEPAGE); /* advice only */
			return 0;
		}
	}
#endif
	m->p = calloc(n ? n : 1, 1);
	return m->p ? 0 : -1;
}

static void image_free(struct image_mem *m)
{
	if (m->map)
		munmap(m->map, m->map_len);
	else
		free(m->p);
	memset(m, 0, sizeof *m);
}

/*
 * The text items of the image (PNG tEXt chunks, OpenEXR string attributes):
 * Software, Source (the scene's and camera's file names, without their
 * directories), Render time (unless --no-render-time) and, for a partial
 * image, Warning. Strings live in bufs (4 x 512 bytes). Returns the count.
 */
static size_t output_texts(const struct master_opts *o, double seconds, const char *partial,
			   struct img_text *t, char bufs[4][512])
{
	size_t n = 0;
	t[n++] = (struct img_text){ "Software", "portray " PORTRAY_VERSION };
	const char *scene = strrchr(o->scene, '/'), *cam = o->camera ? strrchr(o->camera, '/') : NULL;
	scene = scene ? scene + 1 : o->scene;
	if (o->camera)
		snprintf(bufs[0], 512, "%s (camera file %s)", scene, cam ? cam + 1 : o->camera);
	else
		snprintf(bufs[0], 512, "%s", scene);
	t[n++] = (struct img_text){ "Source", bufs[0] };
	if (!o->no_render_time) {
		snprintf(bufs[1], 512, "%.3f s", seconds);
		t[n++] = (struct img_text){ "Render time", bufs[1] };
	}
	if (partial) {
		snprintf(bufs[2], 512, "partial image: %s", partial);
		t[n++] = (struct img_text){ "Warning", bufs[2] };
	}
	return n;
}

/* The pixels a format wants: the renderer's values before clamping for the
 * formats that can hold more than 8 bits (16-bit PNG, PFM, OpenEXR), its
 * 8-bit bytes for the others. */
static enum render_pixel pixel_for(enum img_format fmt)
{
	return fmt == IMG_PNG || fmt == IMG_PPM ? RENDER_RGB8 : RENDER_RGBF32;
}

static bool host_little_endian(void)
{
	const uint32_t one = 1;
	uint8_t first;
	memcpy(&first, &one, 1);
	return first == 1;
}

/*
 * The pixels the writers get: the image itself, or (--region: a cropped
 * file; RENDER_RGBF32 on a big-endian host: the writers take the host's
 * floats, the image holds little-endian ones) a copy made so, in *copy
 * (the caller frees it). The image stays as assembled: the journal may
 * still read it. NULL when out of memory.
 */
static const uint8_t *output_pixels(const struct master_opts *o, const uint8_t *image, uint32_t w, uint32_t h,
				    enum render_pixel px, uint32_t *ow, uint32_t *oh, uint8_t **copy)
{
	bool swap = px == RENDER_RGBF32 && !host_little_endian();
	uint32_t x0 = o->region ? o->rx0 : 0, y0 = o->region ? o->ry0 : 0;
	*ow = o->region ? o->rx1 - o->rx0 : w;
	*oh = o->region ? o->ry1 - o->ry0 : h;
	*copy = NULL;
	if (!o->region && !swap)
		return image;
	size_t bpp = render_pixel_bytes(px), row = (size_t)*ow * bpp;
	uint8_t *c = malloc(row * *oh);
	if (!c)
		return NULL;
	for (uint32_t y = 0; y < *oh; y++)
		memcpy(c + y * row, image + ((size_t)(y0 + y) * w + x0) * bpp, row);
	if (swap)
		for (uint8_t *p = c, *end = c + row * *oh; p < end; p += 4) {
			uint8_t t = p[0];
			p[0] = p[3];
			p[3] = t;
			t = p[1];
			p[1] = p[2];
			p[2] = t;
		}
	*copy = c;
	return c;
}

/* The render stopped and left its journal beside out. */
static void say_journal(const char *out)
{
	fprintf(stderr, "portray-master: the finished tiles are in %s%s: the same command with --resume traces only "
		"the rest\n", out, JOURNAL_SUFFIX);
}

/* How the render was stopped, for messages. */
static const char *stop_word(void)
{
	if (interrupt_reason() == INTERRUPT_KEY)
		return "stopped";
	switch (interrupt_signal()) {
	case SIGTERM: return "terminated";
	case SIGHUP: return "hung up";
	default: return "interrupted";
	}
}

int master_render(const struct master_opts *o)
{
	struct scene *s = NULL, *ds = NULL;
	struct renderer *r = NULL;
	uint8_t *enc = NULL;
	size_t enc_len = 0;
	uint8_t *image = NULL;
	struct image_mem image_mem = { 0 };
	char *out_alloc = NULL;
	struct scene_error err;
	memset(&err, 0, sizeof err);
	int rc;
	bool watching = false;
	uint8_t *out_copy = NULL; /* the writers' pixels when not the image's (output_pixels) */
	struct journal *jn = NULL;
	bool written = false; /* the whole image is written: the journal can go */
	double t0 = progress_now();
	const char *out;
	enum img_format fmt;

	rc = output_plan(o, &out, &out_alloc, &fmt);
	if (rc)
		goto done;
	/* -j bounds every pool of threads: the tracers, the BVH build, the PNG encoder */
	bvh_set_threads(o->threads > 0 ? (unsigned)o->threads : 0);
	img_set_threads(o->threads > 0 ? (unsigned)o->threads : 0);
	rc = parse_files(o->camera, o->scene, &s, &err);
	if (rc) {
		fprintf(stderr, "%s\n", err.msg);
		goto done;
	}
	master_preview_apply(o, s); /* before the encoding: the workers trace the same */
	master_filter_warnings(&s->camera);
	double t_parse = progress_now();

	/* one road for pixels: the scene is encoded as for the wire and the
	 * renderer built from its decoding, locally as on the farm, so every
	 * pixel comes from what a worker would receive (a serializer defect
	 * shows in any local render, not as a worker "lying") */
	if (proto_scene_encode(s, &enc, &enc_len) < 0) {
		fprintf(stderr, "portray-master: out of memory encoding the scene\n");
		rc = ERRLEVEL_FATAL;
		goto done;
	}
	/* memory (issue 13): the parsed scene, its encoding and the decoded
	 * scene are never all held at once, nor any two of them with the
	 * acceleration's build; a local render keeps no encoding */
	scene_free(s); /* the decoded scene is the one in use from here on */
	s = NULL;
	bool farm = o->workers || o->workers_file || o->accept;
	rc = proto_scene_decode(enc, enc_len, &ds, &err);
	if (rc) {
		fprintf(stderr, "portray-master: internal error: the scene does not survive its encoding: %s\n", err.msg);
		rc = ERRLEVEL_FATAL;
		goto done;
	}
	/* the content hash: the workers' cache key and the journal's scene check
	 * (taken before a local render drops the encoding) */
	uint8_t scene_hash[PROTO_HASH_BYTES];
	proto_scene_hash(enc, enc_len, scene_hash);
	if (!farm && enc_len <= LIM_SCENE_BYTES) { /* farm_render still refuses one over the limit */
		free(enc);
		enc = NULL;
	}
	rc = renderer_new(ds, &r, &err);
	if (rc) {
		/* the decoded scene names no files: say it with the parsed one's
		 * locations (parsed again: errors here are rare, memory is not) */
		struct renderer *r2 = NULL;
		struct scene_error perr;
		renderer_free(r);
		r = NULL;
		scene_free(ds);
		ds = NULL;
		if (parse_files(o->camera, o->scene, &s, &perr) == 0) {
			master_preview_apply(o, s);
			if (renderer_new(s, &r2, &err) == 0)
				snprintf(err.msg, sizeof err.msg, "portray-master: cannot build the scene's acceleration");
		}
		renderer_free(r2);
		fprintf(stderr, "%s\n", err.msg);
		goto done;
	}
	if (o->width && renderer_set_size(r, o->width, o->height) < 0) {
		fprintf(stderr, "portray-master: --size %ux%u is too large (at most %llu pixels)\n",
			o->width, o->height, (unsigned long long)LIM_IMAGE_PIXELS);
		rc = EXIT_USAGE;
		goto done;
	}
	uint32_t w, h;
	renderer_size(r, &w, &h);
	rc = master_region_check(o, w, h);
	if (rc)
		goto done;
	double t_build = progress_now();

	enum render_pixel px = pixel_for(fmt);
	const uint32_t bpp = (uint32_t)render_pixel_bytes(px);
	/* unfinished pixels stay black (0 or 0.0f); w * h * bpp overflows no size_t
	 * of 64 bits (LIM_IMAGE_PIXELS), but may one of 32 */
	if ((size_t)w * h <= SIZE_MAX / bpp && image_alloc(&image_mem, (size_t)w * h * bpp) == 0)
		image = image_mem.p;
	if (!image) {
		fprintf(stderr, "portray-master: out of memory for a %ux%u image\n", w, h);
		rc = ERRLEVEL_FATAL;
		goto done;
	}
	/* the journal: everything that changes a pixel must be in its parameters */
	struct tiling tg; /* as farm_render cuts it */
	if (o->region)
		tiling_init_region(&tg, w, h, o->tile, o->rx0, o->ry0, o->rx1, o->ry1);
	else
		tiling_init(&tg, w, h, o->tile);
	struct journal_params jp = { .width = w, .height = h, .tile = tg.side, .pixel_rev = RENDER_PIXEL_REV,
				     .pixel_type = px == RENDER_RGBF32 ? IMG_RGBF32 : IMG_RGB8, .bpp = bpp };
	if (o->region) {
		jp.region[0] = o->rx0;
		jp.region[1] = o->ry0;
		jp.region[2] = o->rx1;
		jp.region[3] = o->ry1;
	}
	_Static_assert(sizeof jp.scene_hash == sizeof scene_hash, "one scene hash for the wire and the journal");
	memcpy(jp.scene_hash, scene_hash, sizeof scene_hash);
	rc = journal_for_render(o, out, &jp, &jn);
	if (rc)
		goto done;

	atomic_int cancel;
	atomic_init(&cancel, 0);
	interrupt_start(&cancel, !ds->image.nonstop);
	watching = true;
	uint64_t total = tg.n;
	uint32_t finished = 0;
	int threads = o->threads > 0 ? o->threads : render_ncpus();
	/* one loop for every render: without workers it drives the local threads alone */
	rc = farm_render(o, enc, enc_len, scene_hash, t_build - t_parse, r, w, h, image, px, &cancel, &finished, jn);
	if (rc && rc != ERRLEVEL_LEVEL2 && !atomic_load(&cancel))
		goto done; /* farm_render said why */
	rc = 0;
	double t_render = progress_now() - http_lingered(); /* --http-linger is not render time */
	bool partial = finished < total;
	if (jn && journal_loaded(jn) && !o->quiet)
		fprintf(stderr, "portray-master: resumed: %u tiles from the journal, %u traced, %llu in all\n",
			journal_preloaded(jn), finished - journal_preloaded(jn), (unsigned long long)total);
	bool journal_left = false;
	if (jn && partial) { /* the journal first: it is what a resume needs */
		journal_left = journal_close(jn, image, false, o->keep_journal);
		jn = NULL;
	}

	char partial_why[160] = "", bufs[4][512];
	if (partial) {
		const char *how = stop_word();
		if (!atomic_load(&cancel))
			how = "out of memory";
		snprintf(partial_why, sizeof partial_why, "%s, %llu of %llu tiles", how, (unsigned long long)finished,
			 (unsigned long long)total);
	}
	struct img_text texts[4];
	struct img_desc desc = { .type = px == RENDER_RGBF32 ? IMG_RGBF32 : IMG_RGB8, .format = fmt, .text = texts };
	desc.pixels = output_pixels(o, image, w, h, px, &desc.w, &desc.h, &out_copy);
	if (!desc.pixels) {
		fprintf(stderr, "portray-master: out of memory for the output image\n");
		rc = ERRLEVEL_FATAL;
		goto done;
	}
	desc.n_text = output_texts(o, t_render - t0, partial ? partial_why : NULL, texts, bufs);
	if (img_write_opts(out, &desc) < 0) {
		fprintf(stderr, "portray-master: cannot write %s: %s\n", shown(out), strerror(errno));
		rc = EXIT_IO;
		goto done;
	}
	written = !partial;
	if (partial && !atomic_load(&cancel)) {
		/* no interrupt, yet tiles are missing: every render thread failed to get
		 * its tile buffer. Appendix B level 2: unable to allocate heap space. */
		fprintf(stderr, "portray-master: out of memory: %llu of %llu tiles rendered; partial image "
			"written to %s\n", (unsigned long long)finished, (unsigned long long)total, shown(out));
		rc = ERRLEVEL_LEVEL2;
	} else if (partial) {
		fprintf(stderr, "portray-master: %s: %llu of %llu tiles (%d%%) written to %s\n", stop_word(),
			(unsigned long long)finished, (unsigned long long)total, (int)(100 * finished / total),
			shown(out));
		/* 130 for SIGINT, 143 SIGTERM, 129 SIGHUP: the shell's way of telling a signal */
		rc = interrupt_reason() == INTERRUPT_SIGNAL ? 128 + interrupt_signal() : 0;
	} else if (!o->quiet && !farm) {
		double tr = t_render - t_build;
		uint64_t rays = renderer_rays(r);
		char size[96];
		if (o->region)
			snprintf(size, sizeof size, "%ux%u (region %u,%u,%u,%u of %ux%u)", desc.w, desc.h, o->rx0, o->ry0,
				 o->rx1, o->ry1, w, h);
		else
			snprintf(size, sizeof size, "%ux%u", w, h);
		fprintf(stderr,
			"portray-master: %s: %s, %d thread%s, %llu tiles, %.3f s (parse %.3f, build %.3f, "
			"trace %.3f), %llu eye rays, %llu secondary rays, %.2f Mrays/s\n",
			shown(out), size, threads, threads == 1 ? "" : "s", (unsigned long long)total,
			t_render - t0, t_parse - t0, t_build - t_parse, tr, (unsigned long long)rays,
			(unsigned long long)renderer_secondary_rays(r), tr > 0 ? rays / tr * 1e-6 : 0.0);
	}
	if (journal_left)
		say_journal(out);
done:
	/* kept, with the last tiles, unless the image is written (e.g. every worker lost) */
	if (journal_close(jn, image, written, o->keep_journal) && !written)
		say_journal(out);
	if (watching)
		interrupt_stop();
	image_free(&image_mem);
	free(out_copy);
	free(out_alloc);
	renderer_free(r);
	scene_free(ds);
	scene_free(s);
	free(enc);
	return rc;
}
