/*
 * bench_render.c - tracing speed per scene: the SPD scenes (tests/data/spd),
 * spot (tests/data/meshes) and, from $PORTRAY_SHARED (default ../shared/data),
 * teapot, bunny and dragon. For each: parse time, BVH build time, primary-ray
 * Mrays/s (camera ray + closest hit, no shading, traced in 8x8 blocks of
 * 2x2 packets as the renderer traces them) on one thread and on all
 * threads, render time (full shading, every filter as written) at 320x240 and
 * 1280x960 on all threads, and the scene's peak RSS (each scene runs in its
 * own process, so getrusage's maximum belongs to it alone).
 * Target (issue 3): >= 10 Mrays/s per core on balls_s4 primary rays.
 * BENCH_ONLY=balls_s4,teapot limits the run to the scenes named.
 */
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "common/accel.h"
#include "common/camera.h"
#include "common/parse.h"
#include "common/render.h"

/* Primary rays are timed over at least this long (repeating the image). */
#define MIN_SECONDS 0.5
/* Size of the primary-ray and large render runs. */
#define BIG_W 1280
#define BIG_H 960

static double now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return ts.tv_sec + ts.tv_nsec * 1e-9;
}

struct prim_job {
	const struct accel *a;
	const struct cam *c;
	atomic_uint next_row;
	atomic_uint_fast64_t hits;
};

static void *prim_rows(void *arg)
{
	struct prim_job *j = arg;
	uint64_t hits = 0;
	for (;;) { /* strips of 8 rows in 8x8 blocks of 2x2 packets, as the renderer traces them */
		unsigned y = 8 * atomic_fetch_add(&j->next_row, 1);
		if (y >= j->c->h)
			break;
		for (uint32_t x = 0; x < j->c->w; x += 8) {
			struct ray r[64];
			struct hit h[64];
			bool hit[64];
			bool in[64];
			for (uint32_t i = 0; i < 64; i++) { /* render.c's order; past the edge: its last pixel */
				uint32_t b = i >> 2, k = i & 3;
				uint32_t px = x + 2 * (b & 1) + 4 * (b >> 2 & 1) + (k & 1);
				uint32_t py = y + 2 * (b >> 1 & 1) + 4 * (b >> 3) + (k >> 1);
				in[i] = px < j->c->w && py < j->c->h;
				r[i] = cam_ray(j->c, (px < j->c->w ? px : j->c->w - 1) + 0.5,
					       (py < j->c->h ? py : j->c->h - 1) + 0.5);
			}
			accel_intersect64(j->a, r, h, hit);
			for (uint32_t i = 0; i < 64; i++)
				hits += hit[i] && in[i];
		}
	}
	atomic_fetch_add(&j->hits, hits);
	return NULL;
}

/* Mrays/s of camera rays + closest hit over a BIG_W x BIG_H image. */
static double primary_mrays(const struct accel *a, const struct cam *c, int threads, double *hit_frac)
{
	uint64_t rays = 0, hits = 0;
	double t0 = now(), t;
	do {
		struct prim_job j = { a, c, 0, 0 };
		pthread_t tid[256];
		int n = threads < 256 ? threads : 256, started = 0;
		for (int i = 1; i < n; i++)
			if (pthread_create(&tid[started], NULL, prim_rows, &j) == 0)
				started++;
		prim_rows(&j);
		for (int i = 0; i < started; i++)
			pthread_join(tid[i], NULL);
		rays += (uint64_t)c->w * c->h;
		hits += atomic_load(&j.hits);
		t = now() - t0;
	} while (t < MIN_SECONDS);
	*hit_frac = (double)hits / rays;
	return rays / t * 1e-6;
}

/* Render the whole image at w x h on all threads; seconds. */
static double render_time(struct renderer *r, uint32_t w, uint32_t h, uint64_t *rays)
{
	if (renderer_set_size(r, w, h) < 0)
		return -1;
	uint8_t *img = malloc((size_t)w * h * 3);
	if (!img)
		return -1;
	uint64_t r0 = renderer_rays(r);
	double t0 = now();
	render_image(r, 0, 32, img, NULL, NULL);
	double t = now() - t0;
	*rays = renderer_rays(r) - r0;
	free(img);
	return t;
}

static int bench_scene(const char *name, const char *path)
{
	struct scene *s = NULL;
	struct scene_error err;
	double t0 = now();
	if (parse_files(NULL, path, &s, &err)) {
		printf("%-9s parse error: %s\n", name, err.msg);
		return 1;
	}
	double t_parse = now() - t0;
	struct accel *a;
	t0 = now();
	if (accel_build(s, &a, &err)) {
		printf("%-9s accel error: %s\n", name, err.msg);
		scene_free(s);
		return 1;
	}
	double t_build = now() - t0;
	struct accel_stats st;
	accel_get_stats(a, &st);
	struct cam c;
	cam_init(&c, &s->camera, BIG_W, BIG_H);
	int ncpu = render_ncpus();
	double hf;
	double m1 = primary_mrays(a, &c, 1, &hf);
	double mn = primary_mrays(a, &c, ncpu, &hf);
	accel_free(a);

	struct renderer *r;
	if (renderer_new(s, &r, &err)) {
		printf("%-9s renderer error: %s\n", name, err.msg);
		scene_free(s);
		return 1;
	}
	uint64_t rays_s, rays_b;
	double ts = render_time(r, 320, 240, &rays_s);
	double tb = render_time(r, BIG_W, BIG_H, &rays_b);
	renderer_free(r);
	scene_free(s);
	struct rusage ru;
	getrusage(RUSAGE_SELF, &ru);
	printf("%-9s %7llu prims  parse %6.3f s  build %6.3f s (%5.1f MB)  primary %6.2f Mrays/s x1, "
	       "%6.2f x%d (hit %3.0f%%)  render 320x240 %6.3f s, %dx%d %6.3f s (%.2f eye Mrays/s)  "
	       "peak RSS %.1f MB\n",
	       name, (unsigned long long)st.n_prims, t_parse, t_build, st.bytes / 1e6, m1, mn, ncpu,
	       hf * 100, ts, BIG_W, BIG_H, tb, tb > 0 ? rays_b / tb * 1e-6 : 0.0, ru.ru_maxrss / 1024.0);
	if (strcmp(name, "balls_s4") == 0)
		printf("%-9s target >= 10 Mrays/s per core on primary rays: %.2f per core, %s\n", name, m1,
		       m1 >= 10 ? "met" : "NOT met");
	fflush(stdout);
	return 0;
}

/* Runs bench_scene in a child process so peak RSS is per scene. Only the
 * scenes named in $BENCH_ONLY (comma-separated substring match) if set. */
static void run(const char *name, const char *path)
{
	const char *only = getenv("BENCH_ONLY");
	if (only && *only && !strstr(only, name))
		return;
	struct stat sb;
	if (stat(path, &sb) != 0) {
		printf("%-9s skipped: %s not found (set PORTRAY_SHARED)\n", name, path);
		return;
	}
	fflush(stdout);
	pid_t pid = fork();
	if (pid == 0)
		_exit(bench_scene(name, path));
	if (pid < 0) {
		bench_scene(name, path);
		return;
	}
	int status;
	waitpid(pid, &status, 0);
	if (!WIFEXITED(status) || WEXITSTATUS(status))
		printf("%-9s failed (status %d)\n", name, status);
}

/* A scene for a bare RAW mesh: the teapot's camera, floor and lights around it. */
static int write_mesh_scene(const char *sce, const char *raw)
{
	FILE *f = fopen(sce, "w");
	if (!f)
		return -1;
	fprintf(f,
		"camera look-from (-1.3 1.5 -2.6) look-at (0 0.6 0) drop-line (0 -1 0)\n"
		"  depth 0.028 x-size 0.032 y-size 0.024 filter standard ; ;\n"
		"image xsize 320 ysize 240 ;\n"
		"light colour (1 1 1) position (-6 10 -8) ;\n"
		"light colour (0.35 0.35 0.4) position (8 6 -6) no-shadows ;\n"
		"object plane position (0 0 0) normal (0 1 0) ; material colour (0.55 0.55 0.55) ; ;\n"
		"object raw file %s smooth ; material colour (0.8 0.7 0.6) specular-reflection 0.3 ; ;\n",
		raw);
	return fclose(f);
}

int main(void)
{
	const char *shared = getenv("PORTRAY_SHARED");
	if (!shared || !*shared)
		shared = "../shared/data";
	printf("# primary = camera ray + closest hit at %dx%d; render = full shading on all %d threads\n",
	       BIG_W, BIG_H, render_ncpus());
	static const char *spd[] = { "balls_s4", "gears_s2", "rings_s3", "tetra_s4" };
	char path[4096], sce[4096];
	for (size_t i = 0; i < sizeof spd / sizeof spd[0]; i++) {
		snprintf(path, sizeof path, "tests/data/spd/%s.sce", spd[i]);
		run(spd[i], path);
	}
	run("spot", "tests/data/meshes/spot.sce");
	snprintf(path, sizeof path, "%s/meshes/teapot.sce", shared);
	run("teapot", path);
	static const char *raws[] = { "bunny", "dragon" };
	for (size_t i = 0; i < 2; i++) {
		snprintf(path, sizeof path, "%s/meshes/%s.raw", shared, raws[i]);
		char *abs = realpath(path, NULL);
		if (!abs) {
			printf("%-9s skipped: %s not found (set PORTRAY_SHARED)\n", raws[i], path);
			continue;
		}
		snprintf(sce, sizeof sce, "/tmp/portray-bench-%d-%s.sce", (int)getpid(), raws[i]);
		if (write_mesh_scene(sce, abs) == 0)
			run(raws[i], sce);
		unlink(sce);
		free(abs);
	}
	return 0;
}
