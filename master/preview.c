/*
 * preview.c - the quick-look switches (--no-aa, --no-shadows,
 * --no-reflections, --preview for all three) and --region's check.
 *
 * The switches change the parsed scene model, before master/render.c
 * encodes it for the wire: the workers receive the changed scene and trace
 * exactly what the master traces (one road: text -> scene model -> wire ->
 * acceleration). They use fields the model has already: the image
 * statement's no-shadows and no-reflections flags, and a filter list of one
 * standard filter.
 */
#include <stdio.h>

#include "common/scene.h"
#include "master/master.h"

void master_preview_apply(const struct master_opts *o, struct scene *s)
{
	if (o->no_shadows)
		s->image.no_shadows = true;
	if (o->no_reflections)
		s->image.no_reflections = true;
	if (o->no_aa) {
		/* one sample at each pixel's centre: no adaptive subdivision, no
		 * super-sampling, no disk or lens jitter */
		struct src_loc loc = s->camera.n_filters > 0 ? s->camera.filters[0].loc : s->camera.loc;
		scene_filter_defaults(&s->camera.filters[0], FILTER_STANDARD);
		s->camera.filters[0].loc = loc;
		s->camera.n_filters = 1;
	}
}

int master_region_check(const struct master_opts *o, uint32_t w, uint32_t h)
{
	if (!o->region)
		return 0;
	if (o->rx1 > w || o->ry1 > h) {
		fprintf(stderr,
			"portray-master: --region %u,%u,%u,%u is not inside the %ux%u image (X1 at most %u, Y1 at most "
			"%u)\n",
			o->rx0, o->ry0, o->rx1, o->ry1, w, h, w, h);
		return EXIT_USAGE;
	}
	return 0;
}
