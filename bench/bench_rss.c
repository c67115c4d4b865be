/*
 * bench_rss.c - whole-process peak memory for a million instances of a
 * defined mesh (issue 13: at most 100 bytes per instance, 100 MB). Each
 * scenario runs in a child process of its own, which builds the scene
 * model through the builder calls (as the parser and the scene
 * deserializer do), builds the renderer (the acceleration structure) and
 * renders a 160x120 image; the parent reports the child's peak resident
 * set (wait4's ru_maxrss) and the child's high-water mark after each stage
 * (VmHWM). Scenarios: "flat", 1,000,000 root instances (each its own
 * translation) of one define holding a 1,000-triangle RAW mesh; "nested",
 * the same million drawn through three levels of 100 instances; "empty",
 * the same process with the mesh and no instance (the floor under the
 * figures). Not a test: prints figures only.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "common/render.h"
#include "common/scene.h"
#include "common/tiles.h"

#define N_SIDE 100 /* 100^3 = 1,000,000 instances */

/* The calling process's high-water mark of resident memory in KiB (Linux
 * /proc), or -1. */
static long hwm_kib(void)
{
	char line[256];
	FILE *f = fopen("/proc/self/status", "r");
	if (!f)
		return -1;
	long kib = -1;
	while (fgets(line, sizeof line, f))
		if (sscanf(line, "VmHWM: %ld", &kib) == 1)
			break;
	fclose(f);
	return kib;
}

static void stage(const char *what) { printf("    %-34s VmHWM %7.1f MB\n", what, hwm_kib() / 1024.0); }

/* A closed 1,000-triangle mesh: a 20 x 25 latitude-longitude sphere of radius r. */
static uint32_t mesh_1000(struct scene *s, double r)
{
	enum { NU = 25, NV = 20 };
	struct scene_mesh m;
	struct scene_error err;
	memset(&m, 0, sizeof m);
	m.file = strdup("ball1000.raw");
	m.weld = 0.00001;
	m.n_vertices = (NV + 1) * NU;
	m.n_triangles = NV * NU * 2;
	m.vertices = malloc(m.n_vertices * sizeof *m.vertices);
	m.tris = malloc(3 * (size_t)m.n_triangles * sizeof *m.tris);
	if (!m.file || !m.vertices || !m.tris)
		abort();
	for (int j = 0; j <= NV; j++)
		for (int i = 0; i < NU; i++) {
			double th = M_PI * j / NV, ph = 2 * M_PI * i / NU;
			m.vertices[j * NU + i] = v3(r * sin(th) * cos(ph), r * cos(th), r * sin(th) * sin(ph));
		}
	uint32_t k = 0;
	for (int j = 0; j < NV; j++)
		for (int i = 0; i < NU; i++) {
			uint32_t a = j * NU + i, b = j * NU + (i + 1) % NU, c = a + NU, d = b + NU;
			uint32_t t[6] = { a, c, b, b, c, d };
			memcpy(&m.tris[k], t, sizeof t);
			k += 6;
		}
	uint32_t id;
	if (scene_add_mesh(s, &m, &id, &err))
		abort();
	return id;
}

static uint32_t add_obj(struct scene *s, struct scene_object *o)
{
	struct scene_error err;
	uint32_t id;
	if (scene_add_object(s, o, &id, &err)) {
		fprintf(stderr, "%s\n", err.msg);
		abort();
	}
	return id;
}

/* define NAME over objs[0..n) (ownership of objs moves to the scene) */
static uint32_t add_define(struct scene *s, const char *name, uint32_t *objs, uint32_t n)
{
	struct scene_define d;
	struct scene_error err;
	memset(&d, 0, sizeof d);
	d.name = strdup(name);
	d.n_objects = n;
	d.objects = objs;
	uint32_t id;
	if (scene_add_define(s, &d, &id, &err))
		abort();
	return id;
}

static uint32_t add_instance(struct scene *s, uint32_t def, vec3 at)
{
	struct scene_object o;
	scene_object_defaults(&o, PRIM_INSTANCE);
	o.u.instance.define = def;
	scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0, at);
	o.has_xform = true;
	return add_obj(s, &o);
}

static void root(struct scene *s, uint32_t obj)
{
	struct scene_error err;
	if (scene_add_root(s, obj, &err))
		abort();
}

/* The child's work: scene, renderer, a 160x120 image. */
static int run(const char *kind)
{
	struct scene *s = scene_new();
	if (!s)
		return 1;
	struct scene_camera cam;
	scene_camera_defaults(&cam);
	cam.look_from = v3(-60, 150, -120);
	cam.look_at = v3(50, 50, 50);
	struct scene_error err;
	if (scene_set_camera(s, &cam, &err))
		return 1;
	struct scene_light l;
	scene_light_defaults(&l);
	l.position = v3(-100, 300, -200);
	if (scene_add_light(s, &l, &err))
		return 1;
	struct scene_object o;
	scene_object_defaults(&o, PRIM_RAW);
	o.u.raw.mesh = mesh_1000(s, 0.4);
	uint32_t ball = add_obj(s, &o);
	uint32_t *one = malloc(sizeof *one);
	*one = ball;
	uint32_t d_ball = add_define(s, "ball", one, 1);
	if (!strcmp(kind, "nested")) {
		uint32_t *row = malloc(N_SIDE * sizeof *row), *wall = malloc(N_SIDE * sizeof *wall);
		for (int i = 0; i < N_SIDE; i++)
			row[i] = add_instance(s, d_ball, v3(i, 0, 0));
		uint32_t d_row = add_define(s, "row", row, N_SIDE);
		for (int i = 0; i < N_SIDE; i++)
			wall[i] = add_instance(s, d_row, v3(0, i, 0));
		uint32_t d_wall = add_define(s, "wall", wall, N_SIDE);
		for (int i = 0; i < N_SIDE; i++)
			root(s, add_instance(s, d_wall, v3(0, 0, i)));
	} else if (!strcmp(kind, "flat")) {
		for (int k = 0; k < N_SIDE * N_SIDE * N_SIDE; k++)
			root(s, add_instance(s, d_ball, v3(k % N_SIDE, (k / N_SIDE) % N_SIDE, k / (N_SIDE * N_SIDE))));
	}
	stage("scene model built");
	struct renderer *r;
	if (renderer_new(s, &r, &err)) {
		fprintf(stderr, "%s\n", err.msg);
		return 1;
	}
	stage("acceleration built");
	enum { W = 160, H = 120 };
	if (renderer_set_size(r, W, H))
		return 1;
	static uint8_t rgb[W * H * 3];
	struct tile_rect t = { 0, 0, W, H };
	renderer_tile(r, t, rgb);
	unsigned long sum = 0;
	for (size_t i = 0; i < sizeof rgb; i++)
		sum += rgb[i];
	stage("160x120 rendered");
	printf("    (pixel sum %lu)\n", sum);
	renderer_free(r);
	scene_free(s);
	return 0;
}

int main(int argc, char **argv)
{
	if (argc == 2)
		return run(argv[1]);
	static const char *const kinds[] = { "empty", "flat", "nested" };
	double floor_mb = 0;
	for (size_t i = 0; i < sizeof kinds / sizeof *kinds; i++) {
		printf("%s:\n", kinds[i]);
		fflush(stdout);
		pid_t pid = fork();
		if (pid < 0)
			return 1;
		if (pid == 0) {
			execl("/proc/self/exe", argv[0], kinds[i], (char *)NULL);
			_exit(127);
		}
		int st;
		struct rusage ru;
		if (wait4(pid, &st, 0, &ru) < 0 || !WIFEXITED(st) || WEXITSTATUS(st)) {
			printf("  failed\n");
			continue;
		}
		double mb = ru.ru_maxrss / 1024.0;
		if (i == 0) {
			floor_mb = mb;
			printf("  peak RSS %.1f MB (the process without instances)\n", mb);
		} else {
			printf("  peak RSS %.1f MB = %.0f bytes per instance (%.0f above the empty process); target "
			       "<= 100 MB\n",
			       mb, mb * 1048576.0 / 1e6, (mb - floor_mb) * 1048576.0 / 1e6);
		}
		fflush(stdout);
	}
	return 0;
}
