/*
 * bench_accel.c - the acceleration structure alone, one thread:
 *   (rates per second of this thread's CPU time)
 *   per SPD scene (tests/data/spd) and mesh (spot from tests/data; teapot,
 *   bunny, dragon from $PORTRAY_SHARED/meshes when present): BVH build time,
 *   Mrays/s for camera primary rays (the preamble's pinhole model, pixel
 *   centres at the scene's image size, one accel_intersect per ray) and for random rays (origins in the
 *   scene bounds, uniform directions), memory held by the accel;
 *   the memory scenario of issue 3: 1,000,000 instances of a 1,000-triangle
 *   object, nested (100 x 100 x 100 through three defines) and flat (one
 *   define level, 1,000,000 instance objects), built and traced, with bytes
 *   per instance and peak RSS (getrusage ru_maxrss).
 * Not a test: prints figures only.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "common/accel.h"
#include "common/parse.h"
#include "common/raw.h"
#include "common/rng.h"
#include "bench/bench_scene.h"

static double peak_rss_mb(void)
{
	struct rusage ru;
	getrusage(RUSAGE_SELF, &ru);
	return (double)ru.ru_maxrss / 1024.0; /* Linux: kilobytes */
}

/* Primary rays through every pixel centre, repeated until ~0.5 s. */
static double primary_mrays(const struct accel *a, const struct scene_camera *c, int W, int H, int *hit_pct)
{
	vec3 view = v3_sub(c->look_at, c->look_from), vu = v3_norm(view);
	vec3 right = v3_norm(v3_cross(c->drop_line, view)), down = v3_norm(v3_cross(view, right));
	long rays = 0, hits = 0;
	double t0 = bs_cpu_now(), dt;
	do {
		for (int j = 0; j < H; j++)
			for (int i = 0; i < W; i++) {
				vec3 f = v3_add(v3_scale(vu, c->depth),
						v3_add(v3_scale(right, ((i + 0.5) / W - 0.5) * c->x_size),
						       v3_scale(down, ((j + 0.5) / H - 0.5) * c->y_size)));
				struct ray r = { c->look_from, f, 0, INFINITY };
				struct hit h;
				hits += accel_intersect(a, &r, &h);
			}
		rays += (long)W * H;
		dt = bs_cpu_now() - t0;
	} while (dt < 0.5);
	*hit_pct = (int)(100 * hits / rays);
	return rays / dt / 1e6;
}

static double random_mrays(const struct accel *a)
{
	vec3 lo, hi;
	if (!accel_bounds(a, &lo, &hi))
		lo = v3(-1, -1, -1), hi = v3(1, 1, 1);
	long rays = 0;
	double t0 = bs_cpu_now(), dt;
	do {
		for (int k = 0; k < 50000; k++, rays++) {
			uint64_t q = (uint64_t)rays * 5;
			vec3 o = v3(lo.x + (hi.x - lo.x) * rng_uniform(3, q), lo.y + (hi.y - lo.y) * rng_uniform(3, q + 1),
				    lo.z + (hi.z - lo.z) * rng_uniform(3, q + 2));
			double z = 2 * rng_uniform(3, q + 3) - 1, ph = 2 * M_PI * rng_uniform(3, q + 4);
			double s = sqrt(fmax(0, 1 - z * z));
			struct ray r = { o, v3(s * cos(ph), s * sin(ph), z), 0, INFINITY };
			struct hit h;
			accel_intersect(a, &r, &h);
		}
		dt = bs_cpu_now() - t0;
	} while (dt < 0.5);
	return rays / dt / 1e6;
}

/* A camera looking at the scene's bounds from the front-left-above. */
static void frame_camera(const struct accel *a, struct scene_camera *c)
{
	vec3 lo, hi;
	scene_camera_defaults(c);
	if (!accel_bounds(a, &lo, &hi))
		return;
	vec3 mid = v3_scale(v3_add(lo, hi), 0.5);
	double diag = v3_len(v3_sub(hi, lo));
	c->look_at = mid;
	c->look_from = v3_add(mid, v3_scale(v3_norm(v3(-0.5, 0.6, -1)), 1.6 * diag));
	c->drop_line = v3(0, -1, 0);
	c->depth = 1;
	c->x_size = 0.8;
	c->y_size = 0.6;
}

static void bench_scene(const char *label, struct scene *s, bool own_camera)
{
	struct accel *a;
	struct scene_error err;
	if (accel_build(s, &a, &err)) {
		printf("%-22s build failed: %s\n", label, err.msg);
		return;
	}
	struct accel_stats st;
	accel_get_stats(a, &st);
	struct scene_camera cam = s->camera;
	if (!own_camera)
		frame_camera(a, &cam);
	int pct;
	double prim = primary_mrays(a, &cam, s->image.xsize, s->image.ysize, &pct);
	double rnd = random_mrays(a);
	printf("%-22s %9llu %9llu %9.2f %8.2f %9.2f (%3d%% hit) %9.2f %9.0f\n", label,
	       (unsigned long long)st.n_prims, (unsigned long long)st.n_nodes, st.build_seconds * 1e3,
	       st.bytes / 1048576.0, prim, pct, rnd, peak_rss_mb());
	fflush(stdout);
	accel_free(a);
}

static void bench_file(const char *path)
{
	struct scene *s;
	struct scene_error err;
	if (access(path, R_OK) != 0) {
		printf("%-22s not found, skipped\n", path);
		return;
	}
	if (parse_files(NULL, path, &s, &err)) {
		printf("%-22s parse failed: %s\n", path, err.msg);
		return;
	}
	const char *base = strrchr(path, '/');
	bench_scene(base ? base + 1 : path, s, true);
	scene_free(s);
}

/* A scene of one RAW object from path. */
static void bench_raw(const char *path)
{
	if (access(path, R_OK) != 0) {
		printf("%-22s not found, skipped\n", path);
		return;
	}
	struct scene *s = scene_new();
	struct scene_mesh m;
	struct scene_error err;
	memset(&m, 0, sizeof m);
	m.file = strdup(path);
	m.weld = 0.00001;
	uint32_t mid, oid;
	if (raw_load(path, &m, &err) || scene_add_mesh(s, &m, &mid, &err)) {
		printf("%-22s load failed: %s\n", path, err.msg);
		scene_free(s);
		return;
	}
	struct scene_object o;
	scene_object_defaults(&o, PRIM_RAW);
	o.u.raw.mesh = mid;
	if (scene_add_object(s, &o, &oid, &err) || scene_add_root(s, oid, &err)) {
		scene_free(s);
		return;
	}
	const char *base = strrchr(path, '/');
	bench_scene(base ? base + 1 : path, s, false);
	scene_free(s);
}

/* 1,000,000 instances of a 1,000-triangle ball: nested 100^3 or flat. */
static void bench_million(bool nested)
{
	double rss0 = peak_rss_mb(), t0 = bs_cpu_now();
	struct scene *s = scene_new();
	bs_million(s, nested ? BS_NESTED : BS_FLAT);
	double t_scene = bs_cpu_now() - t0;
	double rss_scene = peak_rss_mb();
	struct accel *a;
	struct scene_error err;
	if (accel_build(s, &a, &err)) {
		printf("million instances: build failed: %s\n", err.msg);
		scene_free(s);
		return;
	}
	struct accel_stats st;
	accel_get_stats(a, &st);
	struct scene_camera cam;
	frame_camera(a, &cam);
	int pct;
	double prim = primary_mrays(a, &cam, 320, 240, &pct);
	struct scene_stats ss;
	scene_stats(s, &ss);
	printf("1M instances, %s: %llu triangles drawn, %llu instance records, scene built in %.2f s, "
	       "accel built in %.2f s\n",
	       nested ? "nested 100x100x100" : "flat", (unsigned long long)ss.triangles_instanced,
	       (unsigned long long)st.n_instances, t_scene, st.build_seconds);
	printf("  accel %.1f MB = %.1f bytes per drawn instance (instance record %zu bytes + its BVH share); "
	       "primary rays %.2f Mrays/s (%d%% hit)\n",
	       st.bytes / 1048576.0, (double)st.bytes / 1e6, st.instance_bytes, prim, pct);
	printf("  peak RSS %.0f MB (before: %.0f MB; with the scene model: %.0f MB)\n", peak_rss_mb(), rss0,
	       rss_scene);
	fflush(stdout);
	accel_free(a);
	scene_free(s);
}

int main(void)
{
	const char *shared = getenv("PORTRAY_SHARED");
	if (!shared || !*shared)
		shared = "../shared/data";
	printf("%-22s %9s %9s %9s %8s %9s %10s %9s %9s\n", "scene (1 thread)", "prims", "nodes", "build_ms", "accel_MB",
	       "primary", "", "random", "rss_MB");
	printf("%-22s %9s %9s %9s %8s %9s %10s %9s %9s\n", "", "", "", "", "", "Mrays/s", "", "Mrays/s", "");
	printf("# one accel_intersect per ray here; bench_render and bench_primary trace primary rays in 2x2\n"
	       "# packets (accel_intersect4), as the renderer does\n");
	static const char *const spd[] = { "tests/data/spd/balls_s4.sce", "tests/data/spd/gears_s2.sce",
					   "tests/data/spd/rings_s3.sce", "tests/data/spd/tetra_s4.sce",
					   "tests/data/meshes/spot.sce" };
	for (size_t i = 0; i < sizeof spd / sizeof *spd; i++)
		bench_file(spd[i]);
	char path[4096];
	snprintf(path, sizeof path, "%s/meshes/teapot.sce", shared);
	bench_file(path);
	snprintf(path, sizeof path, "%s/meshes/bunny.raw", shared);
	bench_raw(path);
	snprintf(path, sizeof path, "%s/meshes/dragon.raw", shared);
	bench_raw(path);
	bench_million(true);
	bench_million(false);
	return 0;
}
