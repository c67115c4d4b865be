/*
 * bench_raw.c - RAW reader speed: MB/s and triangles/s (read + parse + weld
 * with the default distance; once more for dragon with smoothing normals)
 * for the shared meshes dragon, bunny and teapot,
 * from $PORTRAY_SHARED (default ../shared/data). One core; best of 3 runs.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "common/raw.h"

static double now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return ts.tv_sec + ts.tv_nsec * 1e-9;
}

int main(void)
{
	const char *shared = getenv("PORTRAY_SHARED");
	if (!shared || !*shared)
		shared = "../shared/data";
	static const char *names[] = { "dragon.raw", "bunny.raw", "teapot.raw", "dragon.raw" };
	for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
		int smooth = i == 3; /* the last run adds smoothing normals */
		char path[4096];
		snprintf(path, sizeof path, "%s/meshes/%s", shared, names[i]);
		struct stat st;
		if (stat(path, &st) != 0) {
			printf("raw %s: skipped (%s not found; set PORTRAY_SHARED)\n", names[i], path);
			continue;
		}
		double best = 1e30;
		uint32_t nt = 0, nv = 0;
		for (int rep = 0; rep < 3; rep++) {
			struct scene_mesh m;
			struct scene_error err;
			memset(&m, 0, sizeof m);
			m.weld = 0.00001;
			m.smooth = smooth;
			double t0 = now();
			int rc = raw_load(path, &m, &err);
			double t = now() - t0;
			if (rc) {
				printf("raw %s: error: %s\n", names[i], err.msg);
				break;
			}
			nt = m.n_triangles;
			nv = m.n_vertices;
			free(m.vertices);
			free(m.normals);
			free(m.tris);
			if (t < best)
				best = t;
		}
		if (best < 1e30) {
			double mb = st.st_size / 1e6;
			printf("raw %s%s: %.2f MB in %.3f s = %.0f MB/s, %.2f Mtris/s (%u tris, %u verts after weld)\n",
			       names[i], smooth ? " +smooth" : "", mb, best, mb / best, nt / best / 1e6, nt, nv);
		}
	}
	return 0;
}
