/*
 * bench_parse.c - scene parser speed: MB/s and ms per file (read + lex +
 * parse + build the scene model) for the SPD scenes in tests/data/spd (and
 * $PORTRAY_SHARED/spd when present). One core; best of 5 runs. Target:
 * balls_s4.sce (700 KB) well under 100 ms.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "common/parse.h"

static double now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return ts.tv_sec + ts.tv_nsec * 1e-9;
}

int main(void)
{
	static const char *names[] = { "balls_s4.sce", "gears_s2.sce", "rings_s3.sce", "tetra_s4.sce" };
	for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
		char path[4096];
		snprintf(path, sizeof path, "tests/data/spd/%s", names[i]);
		struct stat st;
		if (stat(path, &st) != 0) {
			printf("parse %s: skipped (%s not found)\n", names[i], path);
			continue;
		}
		double best = 1e30;
		uint32_t nobj = 0;
		for (int rep = 0; rep < 5; rep++) {
			struct scene *s = NULL;
			struct scene_error err;
			double t0 = now();
			int rc = parse_files(NULL, path, &s, &err);
			double t = now() - t0;
			if (rc) {
				printf("parse %s: error: %s\n", names[i], err.msg);
				break;
			}
			nobj = s->n_objects;
			scene_free(s);
			if (t < best)
				best = t;
		}
		if (best < 1e30)
			printf("parse %s: %.0f KB in %.2f ms = %.0f MB/s (%u objects)\n", names[i], st.st_size / 1e3,
			       best * 1e3, st.st_size / 1e6 / best, nobj);
	}
	return 0;
}
