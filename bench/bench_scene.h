/*
 * bench_scene.h - what the benchmarks share: thread CPU time, loading a
 * scene file with its acceleration structure, and the million-instance
 * scene of issues 3 and 13 built through the builder calls (bench_accel,
 * bench_rss). Builder refusals abort: a benchmark scene that fails to build
 * is a bug in the benchmark. Static inline so each binary takes what it uses.
 */
#ifndef PORTRAY_BENCH_SCENE_H
#define PORTRAY_BENCH_SCENE_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "common/accel.h"
#include "common/camera.h"
#include "common/parse.h"
#include "common/scene.h"
#include "tests/unit/build_util.h"

/* This thread's CPU time in seconds: rates measured with it hold on a
 * machine shared with other work (wall-clock rates would measure the
 * neighbours). */
static inline double bs_cpu_now(void)
{
	struct timespec t;
	clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* The A/B benchmarks' arguments, [SCENE [FRAMES [WIDTHxHEIGHT]]]: SCENE
 * defaults to tests/data/spd/balls_s4.sce, FRAMES to def_frames, the size
 * to 1280x960. Returns -1 (the caller prints its usage) on a size that
 * does not parse, fewer than one frame, or a side of 0 or over 100,000. */
static inline int bs_args(int argc, char **argv, int def_frames, const char **path, int *frames, unsigned *w,
			  unsigned *h)
{
	*path = argc > 1 ? argv[1] : "tests/data/spd/balls_s4.sce";
	*frames = argc > 2 ? atoi(argv[2]) : def_frames;
	*w = 1280, *h = 960;
	if (argc > 3 && sscanf(argv[3], "%ux%u", w, h) != 2)
		return -1;
	return *frames < 1 || *w == 0 || *h == 0 || *w > 100000 || *h > 100000 ? -1 : 0;
}

/* Parses path and builds its acceleration structure into *s and *a (the
 * caller frees both); on failure prints "path: message", frees what it
 * made and returns 1. */
static inline int bs_load(const char *path, struct scene **s, struct accel **a)
{
	struct scene_error err;
	if (parse_files(NULL, path, s, &err)) {
		printf("%s: %s\n", path, err.msg);
		return 1;
	}
	if (accel_build(*s, a, &err)) {
		printf("%s: %s\n", path, err.msg);
		scene_free(*s);
		return 1;
	}
	return 0;
}

/* What an A/B benchmark starts from (bs_start). */
struct bs_bench {
	const char *path; /* the scene file */
	int frames;
	unsigned w, h;
	struct scene *s;
	struct accel *a;
	struct cam c; /* the camera at w x h */
};

/* The A/B benchmarks' start, [SCENE [FRAMES [WIDTHxHEIGHT]]] (bs_args),
 * the scene and its tree (bs_load) and the camera into *b. Returns 0, or
 * the status to exit with: 64 after printing usage (the rest of a "usage: "
 * line) on a bad argument, 1 when the scene or the camera fails (said on
 * stdout, nothing left allocated). */
static inline int bs_start(int argc, char **argv, int def_frames, const char *usage, struct bs_bench *b)
{
	if (bs_args(argc, argv, def_frames, &b->path, &b->frames, &b->w, &b->h)) {
		fprintf(stderr, "usage: %s\n", usage);
		return 64;
	}
	if (bs_load(b->path, &b->s, &b->a))
		return 1;
	if (cam_init(&b->c, &b->s->camera, b->w, b->h) < 0) {
		printf("%s: degenerate camera\n", b->path);
		accel_free(b->a);
		scene_free(b->s);
		return 1;
	}
	return 0;
}

/* Room for element n of the growable array p of *cap elements of elem
 * bytes (the capacity doubles, from first, until it holds n): p, or the
 * array moved, or NULL when out of memory or past SIZE_MAX bytes (p is
 * then still the caller's). */
static inline void *bs_grow(void *p, size_t *cap, size_t n, size_t elem, size_t first)
{
	if (n < *cap)
		return p;
	size_t c = *cap ? *cap : first;
	while (c <= n) {
		if (c > SIZE_MAX / 2)
			return NULL;
		c *= 2;
	}
	if (c > SIZE_MAX / elem)
		return NULL;
	void *np = realloc(p, c * elem);
	if (np)
		*cap = c;
	return np;
}

/* FNV-1a over n bytes, from h (1469598103934665603 to start). */
static inline uint64_t bs_fnv(uint64_t h, const void *p, size_t n)
{
	const unsigned char *b = p;
	for (size_t i = 0; i < n; i++) {
		h ^= b[i];
		h *= 1099511628211ull;
	}
	return h;
}

/* h64 extended by one query's answer: "-" for no hit, else the hit's t,
 * object and normals (what shows whether a change kept a hit bit for bit). */
static inline uint64_t bs_hash_hit(uint64_t h64, bool hit, const struct hit *h)
{
	if (!hit)
		return bs_fnv(h64, "-", 1);
	h64 = bs_fnv(h64, &h->t, sizeof h->t);
	h64 = bs_fnv(h64, &h->object, sizeof h->object);
	h64 = bs_fnv(h64, &h->n, sizeof h->n);
	return bs_fnv(h64, &h->ng, sizeof h->ng);
}

/* The camera rays of the 2x2 pixel block at (x, y) into r, as the renderer
 * makes them (a block past the image's edge repeats its last row or
 * column), traced by one accel_intersect4 into h and hit. */
static inline void bs_block_hits(const struct accel *a, const struct cam *c, uint32_t x, uint32_t y, struct ray r[4],
				 struct hit h[4], bool hit[4])
{
	for (uint32_t i = 0; i < 4; i++) {
		uint32_t px = x + (i & 1), py = y + (i >> 1);
		r[i] = cam_ray(c, (px < c->w ? px : c->w - 1) + 0.5, (py < c->h ? py : c->h - 1) + 0.5);
	}
	accel_intersect4(a, r, h, hit);
}

/* A closed 1,000-triangle mesh: a 20 x 25 latitude-longitude sphere of
 * radius r; returns its mesh index. */
static inline uint32_t bs_mesh_1000(struct scene *s, double r)
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

/* define NAME over objs[0..n) (ownership of objs moves to the scene);
 * returns its index. */
static inline uint32_t bs_add_define(struct scene *s, const char *name, uint32_t *objs, uint32_t n)
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

/* An instance of define def translated to at; returns its object index. */
static inline uint32_t bs_add_instance(struct scene *s, uint32_t def, vec3 at)
{
	struct scene_object o;
	scene_object_defaults(&o, PRIM_INSTANCE);
	o.u.instance.define = def;
	scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0, at);
	o.has_xform = true;
	return bu_add(s, &o);
}

static inline void bs_root(struct scene *s, uint32_t obj)
{
	struct scene_error err;
	if (scene_add_root(s, obj, &err))
		abort();
}

#define BS_SIDE 100 /* 100^3 = 1,000,000 instances */

enum bs_million { BS_NONE, BS_FLAT, BS_NESTED };

/* Adds a define "ball" holding one bs_mesh_1000 of radius 0.4 and, unless
 * kind is BS_NONE, 1,000,000 instances of it on a unit grid as roots:
 * BS_FLAT, 1,000,000 root instances of the ball (each its own
 * translation); BS_NESTED, the same million drawn through three levels of
 * 100 instances (defines "row" and "wall"). */
static inline void bs_million(struct scene *s, enum bs_million kind)
{
	struct scene_object o;
	scene_object_defaults(&o, PRIM_RAW);
	o.u.raw.mesh = bs_mesh_1000(s, 0.4);
	uint32_t *one = malloc(sizeof *one);
	if (!one)
		abort();
	*one = bu_add(s, &o);
	uint32_t d_ball = bs_add_define(s, "ball", one, 1);
	if (kind == BS_NESTED) {
		uint32_t *row = malloc(BS_SIDE * sizeof *row), *wall = malloc(BS_SIDE * sizeof *wall);
		if (!row || !wall)
			abort();
		for (int i = 0; i < BS_SIDE; i++)
			row[i] = bs_add_instance(s, d_ball, v3(i, 0, 0));
		uint32_t d_row = bs_add_define(s, "row", row, BS_SIDE);
		for (int i = 0; i < BS_SIDE; i++)
			wall[i] = bs_add_instance(s, d_row, v3(0, i, 0));
		uint32_t d_wall = bs_add_define(s, "wall", wall, BS_SIDE);
		for (int i = 0; i < BS_SIDE; i++)
			bs_root(s, bs_add_instance(s, d_wall, v3(0, 0, i)));
	} else if (kind == BS_FLAT) {
		for (int k = 0; k < BS_SIDE * BS_SIDE * BS_SIDE; k++)
			bs_root(s, bs_add_instance(s, d_ball,
						   v3(k % BS_SIDE, (k / BS_SIDE) % BS_SIDE, k / (BS_SIDE * BS_SIDE))));
	}
}

#endif
