/*
 * check.c - `portray-master --check [-c CAMERA] SCENE`: parse everything,
 * print a short summary on stdout (errors on stderr) and return the
 * Appendix B error level (EXIT_IO when the summary cannot be written).
 */
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "common/filter.h"
#include "common/parse.h"
#include "master/master.h"

/* Room for the filter warnings of a camera (LIM_FILTERS lines). */
#define WARN_BUF 4096

void master_filter_warnings(const struct scene_camera *c)
{
	char warn[WARN_BUF];
	if (filter_warnings(c, warn, sizeof warn))
		fputs(warn, stderr);
}

/* Prints the filters as "standard, lens (samples 10, radius 0.1, focal-length 30)". */
static void print_filters(const struct scene_camera *c)
{
	printf("filters: ");
	for (int i = 0; i < c->n_filters; i++) {
		const struct scene_filter *f = &c->filters[i];
		printf("%s%s", i ? ", " : "", scene_filter_name(f->kind));
		switch (f->kind) {
		case FILTER_ADAPTIVE:
			printf(" (threshold %g, max-depth %d, cache-size %d, relax %g)", f->threshold, f->max_depth,
			       f->cache_size, f->relax);
			break;
		case FILTER_SUPERSAMPLE:
			printf(" (%d x %d)", f->x_samples, f->y_samples);
			break;
		case FILTER_DISK:
			printf(" (samples %d, radius %g)", f->samples, f->radius);
			break;
		case FILTER_LENS:
			printf(" (samples %d, radius %g, focal-length %g)", f->samples, f->radius, f->focal_length);
			break;
		default:
			break;
		}
	}
	printf("\n");
}

/*
 * Summary lines (stable, tests grep them):
 *   image: WxH
 *   filters: ...
 *   lights: N (P point, S shaped)
 *   objects: N (K kind, ...)
 *   primitives: S spheres, C cylinders, T triangles; L lights; M materials
 *   triangles: T stored (D drawn, counting every instance)
 *   primitive instances: N   (or "at least 18446744073709551615")
 *   meshes: N
 *   definitions: N
 *   instances: N
 *   materials: M (N named, A inline)
 * "primitives:" uses the wording of the SPD files' header comments.
 * "primitive instances:" is scene_stats' prims_instanced: every primitive
 * as drawn, through every instance (docs/language.md, Decisions); it is
 * exact below 2^64 and saturates there, hence "at least".
 */
int master_check(const struct master_opts *o)
{
	struct scene *s = NULL;
	struct scene_error err = { 0 };
	int rc = parse_files(o->camera, o->scene, &s, &err);
	if (rc) {
		fprintf(stderr, "%s\n", err.msg);
		return rc;
	}
	master_filter_warnings(&s->camera);
	struct scene_stats st;
	scene_stats(s, &st);
	uint32_t shaped = 0;
	for (uint32_t i = 0; i < s->n_lights; i++)
		shaped += s->lights[i].shape != LIGHT_POINT;
	printf("scene: %s%s%s\n", o->scene, o->camera ? ", camera: " : "", o->camera ? o->camera : "");
	printf("image: %dx%d\n", s->image.xsize, s->image.ysize);
	print_filters(&s->camera);
	printf("lights: %u (%u point, %u shaped)\n", s->n_lights, s->n_lights - shaped, shaped);
	printf("objects: %u (", s->n_objects);
	int first = 1;
	for (int k = 0; k < PRIM_KIND_COUNT; k++) {
		if (!st.by_kind[k])
			continue;
		printf("%s%u %s", first ? "" : ", ", st.by_kind[k], scene_prim_name((enum prim_kind)k));
		first = 0;
	}
	printf(")\n");
	printf("primitives: %u spheres, %u cylinders, %llu triangles; %u lights; %u materials\n",
	       st.by_kind[PRIM_SPHERE], st.by_kind[PRIM_CYLINDER], (unsigned long long)st.triangles, s->n_lights,
	       s->n_materials);
	printf("triangles: %llu stored, %llu drawn (every instance counted)\n", (unsigned long long)st.triangles,
	       (unsigned long long)st.triangles_instanced);
	if (st.prims_instanced == UINT64_MAX)
		printf("primitive instances: at least %llu\n", (unsigned long long)UINT64_MAX);
	else
		printf("primitive instances: %llu\n", (unsigned long long)st.prims_instanced);
	printf("meshes: %u\n", s->n_meshes);
	printf("definitions: %u\n", s->n_defines);
	printf("instances: %u\n", st.by_kind[PRIM_INSTANCE]);
	printf("materials: %u (%u named, %u inline)\n", s->n_materials, st.materials_named, st.materials_anon);
	scene_free(s);
	if (fflush(stdout) != 0 || ferror(stdout)) {
		fprintf(stderr, "portray-master: cannot write the summary: %s\n", strerror(errno));
		return EXIT_IO;
	}
	return 0;
}
