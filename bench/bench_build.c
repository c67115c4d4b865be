/*
 * bench_build.c - the fixed costs of a mesh render before tracing: parse
 * (read the scene, load, weld and smooth the RAW mesh: the scene model) and
 * build (the acceleration structure), for the teapot, bunny and dragon of
 * $PORTRAY_SHARED/meshes, each in teapot.sce's scene. Parse and build on
 * one thread are timed by this thread's CPU time (best of 5); the build
 * on two threads by wall-clock time (best of 5; bvh_set_threads). Target
 * of issue 13: the dragon's parse + build <= 0.15 s on one thread. The
 * PNG encoder's time for a 1280x960 frame is printed too (1 and 2
 * threads; img_set_threads). Not a test: prints figures only.
 */
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "common/accel.h"
#include "common/bvh.h"
#include "common/img.h"
#include "common/parse.h"

#define REPS 5

static double now(clockid_t c)
{
	struct timespec t;
	clock_gettime(c, &t);
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* The whole file, NUL-terminated, or NULL. */
static char *slurp_file(const char *path, size_t *n)
{
	FILE *f = fopen(path, "rb");
	if (!f)
		return NULL;
	char *buf = NULL;
	size_t len = 0, cap = 0;
	for (;;) {
		if (len + 4096 + 1 > cap) {
			cap = cap ? 2 * cap : 65536;
			char *nb = realloc(buf, cap);
			if (!nb) {
				free(buf);
				fclose(f);
				return NULL;
			}
			buf = nb;
		}
		size_t k = fread(buf + len, 1, 4096, f);
		len += k;
		if (k < 4096)
			break;
	}
	fclose(f);
	buf[len] = '\0';
	*n = len;
	return buf;
}

static void bench_mesh(const char *shared, const char *mesh)
{
	char sce[PATH_MAX + 32], raw[PATH_MAX + 32], dir[PATH_MAX];
	/* the mesh's path goes into the scene text, read as relative to the
	 * scene's folder: make it absolute (PORTRAY_SHARED may be relative) */
	if (!realpath(shared, dir))
		snprintf(dir, sizeof dir, "%s", shared);
	snprintf(sce, sizeof sce, "%s/meshes/teapot.sce", dir);
	snprintf(raw, sizeof raw, "%s/meshes/%s.raw", dir, mesh);
	size_t n;
	char *text = slurp_file(sce, &n);
	FILE *probe = fopen(raw, "rb");
	if (!text || !probe) {
		printf("%-7s skipped (%s or %s not found)\n", mesh, sce, raw);
		free(text);
		if (probe)
			fclose(probe);
		return;
	}
	fclose(probe);
	/* teapot.sce with "file teapot.raw" pointing at this mesh */
	const char *at = strstr(text, "file teapot.raw");
	if (at)
		at += strlen("file ");
	if (!at) {
		printf("%-7s skipped (no 'teapot.raw' in %s)\n", mesh, sce);
		free(text);
		return;
	}
	size_t head = (size_t)(at - text), tail = n - head - strlen("teapot.raw");
	char *scene_text = malloc(n + strlen(raw) + 1);
	memcpy(scene_text, text, head);
	memcpy(scene_text + head, raw, strlen(raw));
	memcpy(scene_text + head + strlen(raw), at + strlen("teapot.raw"), tail + 1);
	size_t len = head + strlen(raw) + tail;
	free(text);

	double parse = 1e30, build1 = 1e30, build2 = 1e30;
	uint32_t tris = 0;
	for (int rep = 0; rep < REPS; rep++) {
		struct scene *s;
		struct scene_error err;
		double t0 = now(CLOCK_THREAD_CPUTIME_ID);
		if (parse_buffer(sce, scene_text, len, 1, &s, &err)) {
			printf("%-7s parse failed: %s\n", mesh, err.msg);
			free(scene_text);
			return;
		}
		double t = now(CLOCK_THREAD_CPUTIME_ID) - t0;
		parse = t < parse ? t : parse;
		tris = s->n_meshes ? s->meshes[0].n_triangles : 0;
		for (unsigned th = 1; th <= 2; th++) {
			bvh_set_threads(th);
			clockid_t c = th == 1 ? CLOCK_THREAD_CPUTIME_ID : CLOCK_MONOTONIC;
			struct accel *a;
			t0 = now(c);
			if (accel_build(s, &a, &err)) {
				printf("%-7s build failed: %s\n", mesh, err.msg);
				break;
			}
			t = now(c) - t0;
			if (th == 1)
				build1 = t < build1 ? t : build1;
			else
				build2 = t < build2 ? t : build2;
			accel_free(a);
		}
		scene_free(s);
	}
	bvh_set_threads(0);
	free(scene_text);
	printf("%-7s %7u triangles: parse %6.1f ms + build %6.1f ms = %6.1f ms on one thread (build %5.0f ns per "
	       "triangle); build on 2 threads %6.1f ms wall%s\n",
	       mesh, tris, parse * 1e3, build1 * 1e3, (parse + build1) * 1e3, build1 * 1e9 / (tris ? tris : 1),
	       build2 * 1e3, strcmp(mesh, "dragon") ? "" : (parse + build1 <= 0.15 ? "  [target <= 150 ms: met]" : "  [target <= 150 ms: NOT met]"));
}

/* A 1280x960 frame that looks rendered: shaded gradients, a disc, a little noise. */
static void bench_png(void)
{
	enum { W = 1280, H = 960 };
	uint8_t *px = malloc((size_t)W * H * 3);
	uint32_t x = 12345;
	for (int j = 0; j < H; j++)
		for (int i = 0; i < W; i++) {
			double dx = (i - W / 2.0) / (W / 3.0), dy = (j - H / 2.0) / (H / 3.0), r2 = dx * dx + dy * dy;
			double s = r2 < 1 ? 0.2 + 0.8 * (1 - r2) : 0.1 + 0.3 * j / (double)H;
			for (int c = 0; c < 3; c++) {
				x ^= x << 13, x ^= x >> 17, x ^= x << 5;
				px[3 * ((size_t)j * W + i) + c] = (uint8_t)(s * (180 + 30 * c) + ((i + j) % 7 ? 0 : x & 3));
			}
		}
	for (unsigned th = 1; th <= 2; th++) {
		img_set_threads(th);
		double best = 1e30;
		size_t bytes = 0;
		for (int rep = 0; rep < REPS; rep++) {
			uint8_t *out;
			double t0 = now(CLOCK_MONOTONIC);
			if (img_png_encode(px, W, H, &out, &bytes))
				break;
			double t = now(CLOCK_MONOTONIC) - t0;
			best = t < best ? t : best;
			free(out);
		}
		printf("png 1280x960 render-like frame: %zu bytes in %.1f ms wall on %u thread%s\n", bytes, best * 1e3,
		       th, th > 1 ? "s" : "");
	}
	img_set_threads(0);
	free(px);
}

int main(void)
{
	const char *shared = getenv("PORTRAY_SHARED");
	if (!shared || !*shared)
		shared = "../shared/data";
	static const char *const meshes[] = { "teapot", "bunny", "dragon" };
	for (size_t i = 0; i < sizeof meshes / sizeof *meshes; i++)
		bench_mesh(shared, meshes[i]);
	bench_png();
	return 0;
}
