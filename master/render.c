/*
 * render.c - portray-master's render command: load the scene, build the
 * renderer, render locally (or on the farm when workers are named), write
 * the image. Log lines and the progress bar go to stderr; stdout stays quiet.
 */
#include <errno.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/filter.h"
#include "common/img.h"
#include "common/parse.h"
#include "common/render.h"
#include "master/farm.h"
#include "master/interrupt.h"
#include "master/master.h"
#include "master/progress.h"
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

int master_render(const struct master_opts *o)
{
	struct scene *s = NULL, *ds = NULL;
	struct renderer *r = NULL;
	uint8_t *enc = NULL;
	size_t enc_len = 0;
	uint8_t *image = NULL;
	char *out_alloc = NULL;
	struct scene_error err;
	memset(&err, 0, sizeof err);
	int rc;
	bool watching = false;
	double t0 = progress_now();

	rc = parse_files(o->camera, o->scene, &s, &err);
	if (rc) {
		fprintf(stderr, "%s\n", err.msg);
		goto done;
	}
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
	rc = proto_scene_decode(enc, enc_len, &ds, &err);
	if (rc) {
		fprintf(stderr, "portray-master: internal error: the scene does not survive its encoding: %s\n", err.msg);
		rc = ERRLEVEL_FATAL;
		goto done;
	}
	rc = renderer_new(ds, &r, &err);
	if (rc) {
		/* the decoded scene names no files: say it with the parsed one's locations */
		struct renderer *r2 = NULL;
		if (renderer_new(s, &r2, &err) == 0)
			snprintf(err.msg, sizeof err.msg, "portray-master: cannot build the scene's acceleration");
		renderer_free(r2);
		fprintf(stderr, "%s\n", err.msg);
		goto done;
	}
	scene_free(s); /* the decoded scene is the one in use from here on */
	s = NULL;
	if (o->width && renderer_set_size(r, o->width, o->height) < 0) {
		fprintf(stderr, "portray-master: --size %ux%u is too large (at most %llu pixels)\n",
			o->width, o->height, (unsigned long long)LIM_IMAGE_PIXELS);
		rc = EXIT_USAGE;
		goto done;
	}
	uint32_t w, h;
	renderer_size(r, &w, &h);
	double t_build = progress_now();

	const char *out = o->out;
	if (!out) {
		out = out_alloc = default_output(o->scene);
		if (!out) {
			fprintf(stderr, "portray-master: out of memory\n");
			rc = ERRLEVEL_FATAL;
			goto done;
		}
	}
	image = calloc((size_t)w * h, 3); /* unfinished pixels stay black */
	if (!image) {
		fprintf(stderr, "portray-master: out of memory for a %ux%u image\n", w, h);
		rc = ERRLEVEL_FATAL;
		goto done;
	}

	atomic_int cancel;
	atomic_init(&cancel, 0);
	interrupt_start(&cancel, !ds->image.nonstop);
	watching = true;
	uint64_t total = render_tile_count(w, h, o->tile), finished = 0;
	int threads = o->threads > 0 ? o->threads : render_ncpus();
	bool farm = o->workers || o->workers_file || o->accept;
	if (farm) {
		rc = farm_render(o, enc, enc_len, t_build - t_parse, r, w, h, image, &cancel);
		if (rc && !atomic_load(&cancel))
			goto done; /* farm_render said why */
		rc = 0;
	} else {
		struct progress prog;
		progress_init(&prog, total, progress_wanted(o->quiet));
		struct render_progress cb = { progress_callback, &prog };
		finished = render_image(r, threads, o->tile, image, &cb, &cancel);
		progress_end(&prog);
	}
	double t_render = progress_now();
	bool partial = farm ? atomic_load(&cancel) != 0 : finished < total;

	if (img_write(out, image, w, h) < 0) {
		fprintf(stderr, "portray-master: cannot write %s: %s\n", out, strerror(errno));
		rc = EXIT_IO;
		goto done;
	}
	if (partial && !atomic_load(&cancel)) {
		/* no interrupt, yet tiles are missing: every render thread failed to get
		 * its tile buffer. Appendix B level 2: unable to allocate heap space. */
		fprintf(stderr, "portray-master: out of memory: %llu of %llu tiles rendered; partial image "
			"written to %s\n", (unsigned long long)finished, (unsigned long long)total, out);
		rc = ERRLEVEL_LEVEL2;
	} else if (partial) {
		const char *why = interrupt_reason() == INTERRUPT_KEY ? "stopped" : "interrupted";
		if (farm)
			fprintf(stderr, "portray-master: %s: partial image written to %s\n", why, out);
		else
			fprintf(stderr, "portray-master: %s: %llu of %llu tiles (%d%%) written to %s\n", why,
				(unsigned long long)finished, (unsigned long long)total,
				(int)(100 * finished / total), out);
		rc = interrupt_reason() == INTERRUPT_SIGNAL ? EXIT_INTERRUPTED : 0;
	} else if (!o->quiet && !farm) {
		double tr = t_render - t_build;
		uint64_t rays = renderer_rays(r);
		fprintf(stderr,
			"portray-master: %s: %ux%u, %d thread%s, %llu tiles, %.3f s (parse %.3f, build %.3f, "
			"trace %.3f), %llu eye rays, %.2f Mrays/s\n",
			out, w, h, threads, threads == 1 ? "" : "s", (unsigned long long)total,
			t_render - t0, t_parse - t0, t_build - t_parse, tr, (unsigned long long)rays,
			tr > 0 ? rays / tr * 1e-6 : 0.0);
	}
done:
	if (watching)
		interrupt_stop();
	free(image);
	free(out_alloc);
	renderer_free(r);
	scene_free(ds);
	scene_free(s);
	free(enc);
	return rc;
}
