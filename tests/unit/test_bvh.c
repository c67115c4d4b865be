/*
 * test_bvh.c - the BVH agrees with brute force: 10,000 random rays per scene
 * (origins uniform in the scene's bounds, directions uniform on the sphere)
 * over every SPD scene, spot, and the teapot when ../shared has it; 100,000
 * with PORTRAY_TEST_FULL=1 (about 10 times as long: the brute force is the
 * cost; the synthetic scenes below scale alike). Same hit
 * or miss, t within 1e-9 relative, the same object (a different object is
 * accepted only at an exact tie in t, and such ties are counted). Also the
 * builder alone: every item lands in exactly one leaf, leaves cover their
 * items' boxes, and degenerate inputs (equal centroids) build; packed
 * leaves; a group of many instances (packed, without a reference array).
 * Packets: accel_intersect4 gives every ray exactly accel_intersect's hit,
 * for four unrelated rays (mostly of different octants) and for four
 * neighbouring rays from one origin (the packet traversal), also with a
 * window (tmin > 0, finite tmax) and along an axis; accel_intersect16 and
 * accel_intersect64 as much for sixteen and sixty-four rays from one
 * origin (four or sixteen such packets), close together and spread wide,
 * with a window, and with one origin moved. The occlusion queries
 * (accel_occluded4, accel_occluded_hint, with hints carried over or made
 * up) answer as accel_occluded for those packets and for four shadow rays
 * toward one point (tmax 1), and for packets whose lanes' directions
 * differ in scale and in components near the inverse's cut-off. The builder's depth
 * limit leaves a leaf of hundreds of items (the traversals test such leaves
 * a chunk at a time: CANCELLATION in accel.c).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <pthread.h>
#include <unistd.h>

#include "common/accel.h"
#include "common/accel_int.h"
#include "common/bvh.h"
#include "common/parse.h"
#include "common/rng.h"
#include "tests/unit/check.h"
#include "tests/unit/same_hit.h"

/* rays per scene: N_RAYS_FULL with PORTRAY_TEST_FULL=1 in the environment */
#define N_RAYS_QUICK 10000
#define N_RAYS_FULL 100000
static int n_rays = N_RAYS_QUICK;

static vec3 unit_dir(uint64_t seed, uint64_t k)
{
	double z = 2 * rng_uniform(seed, 2 * k) - 1, phi = 2 * M_PI * rng_uniform(seed, 2 * k + 1);
	double r = sqrt(fmax(0, 1 - z * z));
	return v3(r * cos(phi), r * sin(phi), z);
}

struct job {
	const struct accel *a;
	vec3 lo, hi;
	uint64_t seed;
	int from, to;
	int mismatch, ties, hits;
	int packets, packet_mismatch;
	uint32_t hint; /* last-blocker hint carried from packet to packet */
};

/* accel_occluded4 and accel_occluded_hint over r[0..4) against
 * accel_occluded, ray by ray, with the hint the job carries (whatever
 * blocked its last rays) or, every fifth packet, an arbitrary one. */
static void occluded_check(struct job *j, const struct ray r[4])
{
	bool occ[4];
	if (j->packets % 5 == 4)
		j->hint = (uint32_t)rng_mix((uint64_t)j->packets);
	accel_occluded4(j->a, r, occ, &j->hint);
	for (int i = 0; i < 4; i++) {
		bool o1 = accel_occluded(j->a, &r[i]);
		if (occ[i] != o1 || accel_occluded_hint(j->a, &r[i], &j->hint) != o1) {
			j->packet_mismatch++;
			return;
		}
	}
}

/* accel_intersect4 over r[0..4) against accel_intersect, ray by ray; the
 * occlusion queries too (occluded_check). */
static void packet_check(struct job *j, const struct ray r[4])
{
	struct hit h[4], h1;
	bool hit[4];
	accel_intersect4(j->a, r, h, hit);
	j->packets++;
	for (int i = 0; i < 4; i++) {
		bool b1 = accel_intersect(j->a, &r[i], &h1);
		if (!same_hit(b1, &h1, hit[i], &h[i])) {
			j->packet_mismatch++;
			return;
		}
	}
	occluded_check(j, r);
}

/* accel_intersect16 (np 4) or accel_intersect64 (np 16) over r[0..4 np)
 * against accel_intersect, ray by ray. */
static void packets_check(struct job *j, const struct ray *r, int np)
{
	struct hit h[64], h1;
	bool hit[64];
	if (np == 16)
		accel_intersect64(j->a, r, h, hit);
	else
		accel_intersect16(j->a, r, h, hit);
	j->packets++;
	for (int i = 0; i < 4 * np; i++) {
		bool b1 = accel_intersect(j->a, &r[i], &h1);
		if (!same_hit(b1, &h1, hit[i], &h[i])) {
			j->packet_mismatch++;
			return;
		}
	}
}

/* 4 np neighbours from o around d (np 4 or 16 packets of four), as a 4x4 or
 * 8x8 block of pixels in 2x2 packets (packet p at (2 (p & 1) + 4 (p >> 2 &
 * 1), 2 (p >> 1 & 1) + 4 (p >> 3)), its ray l at (l & 1, l >> 1), as the
 * renderer orders them), step apart; checked whole, with a window, and with
 * one origin moved (then in smaller packets). */
static void fan_check(struct job *j, vec3 o, vec3 d, double step, int k, int np)
{
	struct ray f[64];
	const double mid = np == 16 ? 3.5 : 1.5;
	for (int i = 0; i < 4 * np; i++) {
		int p = i >> 2, l = i & 3;
		double x = 2 * (p & 1) + 4 * (p >> 2 & 1) + (l & 1), y = 2 * (p >> 1 & 1) + 4 * (p >> 3) + (l >> 1);
		f[i] = (struct ray){ o, v3_norm(v3_add(d, v3(step * (x - mid), step * (y - mid), 0))), 0, INFINITY };
	}
	packets_check(j, f, np);
	for (int i = 0; i < 4 * np; i++) {
		f[i].tmin = 0.3 * rng_uniform(j->seed, 64ull * k + i + 5000000);
		f[i].tmax = f[i].tmin + 0.1 + 3 * rng_uniform(j->seed, 64ull * k + i + 6000000);
	}
	packets_check(j, f, np);
	f[4 * np - 7].o = v3_add(o, v3(1e-9, 0, 0));
	packets_check(j, f, np);
}

/* Rays [from, to): BVH, brute force and occlusion compared. */
static void *run_rays(void *arg)
{
	struct job *j = arg;
	struct ray last[4];
	for (int k = j->from; k < j->to; k++) {
		vec3 o = v3(j->lo.x + (j->hi.x - j->lo.x) * rng_uniform(j->seed, 3ull * k + 1000000),
			    j->lo.y + (j->hi.y - j->lo.y) * rng_uniform(j->seed, 3ull * k + 1000001),
			    j->lo.z + (j->hi.z - j->lo.z) * rng_uniform(j->seed, 3ull * k + 1000002));
		struct ray r = { o, unit_dir(j->seed, (uint64_t)k), 0, INFINITY };
		last[(k - j->from) % 4] = r;
		if ((k - j->from) % 4 == 3) {
			packet_check(j, last); /* four unrelated rays */
			struct ray fan[4]; /* four neighbours from one origin, as a 2x2 block of pixels */
			for (int i = 0; i < 4; i++) {
				vec3 d = v3_add(r.d, v3(2e-3 * (i & 1), 2e-3 * (i >> 1), 0));
				fan[i] = (struct ray){ o, v3_norm(d), 0, INFINITY };
			}
			packet_check(j, fan);
			/* sixteen from one origin: close, wide and wider than an octant */
			fan_check(j, o, r.d, k % 3 == 0 ? 1e-3 : k % 3 == 1 ? 3e-2 : 0.3, k, 4);
			fan_check(j, o, r.d, k % 3 == 0 ? 1e-3 : k % 3 == 1 ? 1e-2 : 0.15, k, 16);
			for (int i = 0; i < 4; i++) { /* the same with a window: tmin > 0, finite tmax */
				fan[i].tmin = 0.3 * rng_uniform(j->seed, 4ull * k + i);
				fan[i].tmax = fan[i].tmin + 0.1 + 3 * rng_uniform(j->seed, 4ull * k + i + 2);
			}
			packet_check(j, fan);
			for (int i = 0; i < 4; i++) /* axis-parallel neighbours (zero components, -0 in z) */
				fan[i] = (struct ray){ o, v3(1e-3 * i, k % 8 < 4 ? 1 : -1, -0.0), 0.01 * i, 2 + i };
			packet_check(j, fan);
			for (int i = 0; i < 4; i++) { /* shadow rays: four origins toward one point (tmax 1) */
				vec3 oi = v3_add(o, v3(1e-2 * (i & 1), 1e-2 * (i >> 1), 0));
				vec3 to = v3_add(o, v3_scale(r.d, 0.5 + 2 * rng_uniform(j->seed, 4ull * k + i + 7)));
				fan[i] = (struct ray){ oi, v3_sub(to, oi), 0, 1 };
			}
			occluded_check(j, fan);
		}
		struct hit h1, h2;
		bool b1 = accel_intersect(j->a, &r, &h1), b2 = accel_intersect_brute(j->a, &r, &h2);
		bool occ = accel_occluded(j->a, &r);
		j->hits += b1;
		if (b1 != b2 || occ != b2) {
			j->mismatch++;
			continue;
		}
		if (!b1)
			continue;
		if (!(fabs(h1.t - h2.t) <= 1e-9 * fabs(h2.t))) {
			j->mismatch++;
			continue;
		}
		if (h1.object != h2.object) {
			if (h1.t == h2.t)
				j->ties++;
			else
				j->mismatch++;
		}
	}
	return NULL;
}

/* run_rays of rays 0..to aimed into the box lo..hi, on this thread. */
static struct job rays_in(const struct accel *a, vec3 lo, vec3 hi, uint64_t seed, int to)
{
	struct job j;
	memset(&j, 0, sizeof j);
	j.a = a;
	j.lo = lo;
	j.hi = hi;
	j.seed = seed;
	j.to = to;
	run_rays(&j);
	return j;
}

static void agree(const char *path)
{
	struct scene *s;
	struct scene_error err;
	if (parse_files(NULL, path, &s, &err)) {
		fprintf(stderr, "%s: %s\n", path, err.msg);
		CHECK(!"scene parses");
		return;
	}
	struct accel *a;
	CHECK(accel_build(s, &a, &err) == 0);
	struct job jobs[2];
	memset(jobs, 0, sizeof jobs);
	for (int i = 0; i < 2; i++) {
		jobs[i].a = a;
		CHECK(accel_bounds(a, &jobs[i].lo, &jobs[i].hi));
		jobs[i].seed = rng_seed(7, 11, (uint32_t)strlen(path));
		jobs[i].from = i * n_rays / 2;
		jobs[i].to = (i + 1) * n_rays / 2;
	}
	pthread_t th;
	bool threaded = pthread_create(&th, NULL, run_rays, &jobs[1]) == 0;
	run_rays(&jobs[0]);
	if (threaded)
		pthread_join(th, NULL);
	else
		run_rays(&jobs[1]);
	int mismatch = jobs[0].mismatch + jobs[1].mismatch, ties = jobs[0].ties + jobs[1].ties;
	int hits = jobs[0].hits + jobs[1].hits;
	int packets = jobs[0].packets + jobs[1].packets, pmis = jobs[0].packet_mismatch + jobs[1].packet_mismatch;
	printf("%s: %d rays, %d hits, %d mismatches, %d exact ties between objects; %d packets, %d unlike single rays\n",
	       path, n_rays, hits, mismatch, ties, packets, pmis);
	CHECK(mismatch == 0);
	CHECK(pmis == 0);
	CHECK(packets >= n_rays);
	CHECK(hits > n_rays / 10);
	CHECK(ties < n_rays / 1000);
	accel_free(a);
	scene_free(s);
}

/* Runs 2 x n_rays/10 rays over an accel and checks agreement (as agree()). */
static void agree_accel(const char *label, const struct accel *a)
{
	struct job jobs[2];
	memset(jobs, 0, sizeof jobs);
	for (int i = 0; i < 2; i++) {
		jobs[i].a = a;
		CHECK(accel_bounds(a, &jobs[i].lo, &jobs[i].hi));
		jobs[i].seed = rng_seed(3, 5, 8);
		jobs[i].from = i * n_rays / 10;
		jobs[i].to = (i + 1) * n_rays / 10;
	}
	run_rays(&jobs[0]);
	run_rays(&jobs[1]);
	int mismatch = jobs[0].mismatch + jobs[1].mismatch, hits = jobs[0].hits + jobs[1].hits;
	int pmis = jobs[0].packet_mismatch + jobs[1].packet_mismatch;
	printf("%s: %d rays, %d hits, %d mismatches, %d packets unlike single rays\n", label, 2 * n_rays / 10, hits,
	       mismatch, pmis);
	CHECK(mismatch == 0);
	CHECK(pmis == 0);
	CHECK(hits > n_rays / 100);
}

/*
 * Small things far from the origin (float node bounds are relative to the
 * group's centre), some through instances, some as sliver triangles.
 */
static void far_away(void)
{
	struct scene *s = scene_new();
	struct scene_error err;
	vec3 at = v3(1e5, -2e5, 3e5);
	uint32_t ids[600];
	for (int i = 0; i < 600; i++) {
		struct scene_object o;
		vec3 p = v3_add(at, v3(rng_uniform(9, 3 * i), rng_uniform(9, 3 * i + 1), rng_uniform(9, 3 * i + 2)));
		if (i % 3 == 0) {
			scene_object_defaults(&o, PRIM_SPHERE);
			o.u.sphere.centre = p;
			o.u.sphere.radius = 0.01 + 0.02 * rng_uniform(10, i);
		} else if (i % 3 == 1) {
			scene_object_defaults(&o, PRIM_TRIANGLE); /* long slivers */
			o.u.triangle.a = p;
			o.u.triangle.b = v3_add(p, v3(0.3, 0.2, 0.25));
			o.u.triangle.c = v3_add(p, v3(0.3, 0.21, 0.25));
		} else {
			scene_object_defaults(&o, PRIM_BOX);
			o.u.box.a = p;
			o.u.box.b = v3_add(p, v3(0.02, 0.03, 0.01));
			scene_xform_op(&o.xform, XF_ROTATE, i % 3, 10.0 * i, v3(0, 0, 0)); /* about the origin! */
			scene_xform_op(&o.xform, XF_ROTATE, i % 3, -10.0 * i, v3(0, 0, 0));
			o.has_xform = true;
		}
		CHECK(scene_add_object(s, &o, &ids[i], &err) == 0);
	}
	struct scene_define d;
	memset(&d, 0, sizeof d);
	d.name = strdup("cluster");
	d.n_objects = 200;
	d.objects = malloc(200 * sizeof *d.objects);
	memcpy(d.objects, ids, 200 * sizeof *ids);
	uint32_t did;
	CHECK(scene_add_define(s, &d, &did, &err) == 0);
	for (int i = 200; i < 600; i++)
		CHECK(scene_add_root(s, ids[i], &err) == 0);
	for (int k = 0; k < 3; k++) {
		struct scene_object o;
		scene_object_defaults(&o, PRIM_INSTANCE);
		o.u.instance.define = did;
		scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0, v3(0.3 * k, 0, 0));
		o.has_xform = true;
		uint32_t id;
		CHECK(scene_add_object(s, &o, &id, &err) == 0);
		CHECK(scene_add_root(s, id, &err) == 0);
	}
	struct accel *a;
	CHECK(accel_build(s, &a, &err) == 0);
	agree_accel("far from the origin", a);
	accel_free(a);
	scene_free(s);
}

/* One random primitive of any simple kind, randomly transformed, at p. */
static uint32_t random_prim(struct scene *s, uint64_t seed, vec3 p, int kind)
{
	struct scene_error err;
	struct scene_object o;
	double r = 0.05 + 0.1 * rng_uniform(seed, 1);
	switch (kind) {
	case 0:
		scene_object_defaults(&o, PRIM_SPHERE);
		o.u.sphere.centre = p;
		o.u.sphere.radius = r;
		break;
	case 1:
		scene_object_defaults(&o, PRIM_BOX);
		o.u.box.a = p;
		o.u.box.b = v3_add(p, v3(r, 2 * r, r * 0.5));
		break;
	case 2:
		scene_object_defaults(&o, PRIM_CYLINDER);
		o.u.cylinder.from = p;
		o.u.cylinder.to = v3_add(p, v3(r, 3 * r, -r));
		o.u.cylinder.radius = r * 0.3;
		o.u.cylinder.capped = rng_uniform(seed, 2) < 0.5;
		break;
	case 3:
		scene_object_defaults(&o, PRIM_DISK);
		o.u.plane.position = p;
		o.u.plane.normal = v3(rng_uniform(seed, 3) - 0.5, 1, rng_uniform(seed, 4) - 0.5);
		o.u.plane.radius = r;
		break;
	case 4: {
		scene_object_defaults(&o, PRIM_POLYGON);
		o.u.polygon.n_contours = 2;
		o.u.polygon.n_points = 8;
		o.u.polygon.contour_start = malloc(3 * sizeof(uint32_t));
		o.u.polygon.points = malloc(8 * sizeof(vec3));
		o.u.polygon.contour_start[0] = 0;
		o.u.polygon.contour_start[1] = 4;
		o.u.polygon.contour_start[2] = 8;
		static const double sq[8][2] = { { 0, 0 }, { 3, 0 }, { 3, 3 }, { 0, 3 }, { 1, 1 }, { 2, 1 }, { 2, 2 }, { 1, 2 } };
		for (int i = 0; i < 8; i++)
			o.u.polygon.points[i] = v3_add(p, v3(sq[i][0] * r, sq[i][1] * r, sq[i][0] * r * 0.3));
		break;
	}
	default:
		scene_object_defaults(&o, PRIM_TRIANGLE);
		o.u.triangle.a = p;
		o.u.triangle.b = v3_add(p, v3(2 * r, 0, r));
		o.u.triangle.c = v3_add(p, v3(0, 2 * r, r));
		break;
	}
	if (rng_uniform(seed, 5) < 0.5) {
		scene_xform_op(&o.xform, XF_STRETCH, (int)(3 * rng_uniform(seed, 6)), 0.5 + rng_uniform(seed, 7), v3(0, 0, 0));
		scene_xform_op(&o.xform, XF_ROTATE, (int)(3 * rng_uniform(seed, 8)), 360 * rng_uniform(seed, 9), v3(0, 0, 0));
		scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0, v3(0.1, -0.2, 0.3));
		o.has_xform = true;
	}
	uint32_t id;
	if (scene_add_object(s, &o, &id, &err))
		abort();
	return id;
}

/* Every kind, transforms, CSG nodes over them, instances two levels deep and
 * an infinite plane, mixed in one scene: BVH, brute force and occlusion agree. */
static void mixed(void)
{
	struct scene *s = scene_new();
	struct scene_error err;
	uint32_t members[60];
	for (int i = 0; i < 60; i++) {
		vec3 p = v3(rng_uniform(11, 3 * i), rng_uniform(11, 3 * i + 1), rng_uniform(11, 3 * i + 2));
		uint32_t a = random_prim(s, rng_seed(1, i, 0), p, i % 6);
		if (i % 4 == 0) { /* a CSG node of two overlapping solids */
			uint32_t b = random_prim(s, rng_seed(2, i, 0), v3_add(p, v3(0.05, 0.05, 0)), (i / 4) % 3);
			struct scene_object o;
			scene_object_defaults(&o, PRIM_CSG);
			o.u.csg.op = (enum csg_op)((i / 4) % 3);
			o.u.csg.operand1 = a;
			o.u.csg.operand2 = b;
			CHECK(scene_add_object(s, &o, &a, &err) == 0);
		}
		members[i] = a;
	}
	struct scene_define d;
	memset(&d, 0, sizeof d);
	d.name = strdup("inner");
	d.n_objects = 30;
	d.objects = malloc(30 * sizeof *d.objects);
	memcpy(d.objects, members, 30 * sizeof *members);
	uint32_t inner;
	CHECK(scene_add_define(s, &d, &inner, &err) == 0);
	uint32_t outer_objs[4];
	for (int k = 0; k < 4; k++) {
		struct scene_object o;
		scene_object_defaults(&o, PRIM_INSTANCE);
		o.u.instance.define = inner;
		scene_xform_op(&o.xform, XF_ROTATE, k % 3, 30.0 * k, v3(0, 0, 0));
		scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0, v3(1.2 * k, 0, 0));
		o.has_xform = true;
		CHECK(scene_add_object(s, &o, &outer_objs[k], &err) == 0);
	}
	memset(&d, 0, sizeof d);
	d.name = strdup("outer");
	d.n_objects = 4;
	d.objects = malloc(4 * sizeof *d.objects);
	memcpy(d.objects, outer_objs, sizeof outer_objs);
	uint32_t outer;
	CHECK(scene_add_define(s, &d, &outer, &err) == 0);
	for (int k = 0; k < 3; k++) {
		struct scene_object o;
		scene_object_defaults(&o, PRIM_INSTANCE);
		o.u.instance.define = outer;
		scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0, v3(0, 1.5 * k, 0.5 * k));
		o.has_xform = true;
		uint32_t id;
		CHECK(scene_add_object(s, &o, &id, &err) == 0);
		CHECK(scene_add_root(s, id, &err) == 0);
	}
	for (int i = 30; i < 60; i++)
		CHECK(scene_add_root(s, members[i], &err) == 0);
	struct scene_object pl;
	scene_object_defaults(&pl, PRIM_PLANE);
	pl.u.plane.position = v3(0, -0.5, 0);
	uint32_t pid;
	CHECK(scene_add_object(s, &pl, &pid, &err) == 0);
	CHECK(scene_add_root(s, pid, &err) == 0);
	struct accel *a;
	CHECK(accel_build(s, &a, &err) == 0);
	agree_accel("every kind, CSG, nested instances, a plane", a);
	accel_free(a);
	scene_free(s);
}

/*
 * Long tilted cylinders, capped and open, some transformed (LONG CYLINDERS
 * in accel_build.c: each referenced by the boxes of up to 8 slices of its
 * axis), near the origin and 1e4 units away: random rays (BVH, brute
 * force, occlusion, packets) and rays aimed at points of the surface at
 * every cut a slicing into 2..8 could make, at the rims and on the caps,
 * exactly and off by 1e-12 to 1e-6 of the length, as packets of four:
 * accel_intersect is brute force's and accel_intersect4's hit, bit for bit,
 * and accel_occluded and accel_occluded4 agree. Checked to fail with
 * slices whose boxes leave out the disk's extent (e = 0) or end a quarter
 * of a slice short of each cut (a tenth is hidden by the disk's extent),
 * and with a MAILBOX (accel_trace.h: a slice's second test in a row
 * skipped; brute force clears it before every test, so it is the check)
 * that skips every xprim after the first (27,018 mismatches) or
 * is not reset for each query (4,186).
 */
#define N_CYL 240
static void long_cylinders(void)
{
	for (int far = 0; far < 2; far++) {
		struct scene *s = scene_new();
		struct scene_error err;
		vec3 at = far ? v3(1e4, -2e4, 3e4) : v3(0, 0, 0);
		struct prim_cylinder cyl[N_CYL];
		bool plain[N_CYL];
		for (int i = 0; i < N_CYL; i++) {
			struct scene_object o;
			scene_object_defaults(&o, PRIM_CYLINDER);
			vec3 p = v3_add(at, v3(4 * rng_uniform(51, 3 * i), 4 * rng_uniform(51, 3 * i + 1), 4 * rng_uniform(51, 3 * i + 2)));
			double len = 0.5 + 2.5 * rng_uniform(52, i);
			o.u.cylinder.from = p;
			o.u.cylinder.to = v3_add(p, v3_scale(unit_dir(53, (uint64_t)i), len));
			o.u.cylinder.radius = len * (0.01 + 0.14 * rng_uniform(54, i));
			o.u.cylinder.capped = i % 2 == 0;
			plain[i] = i % 4 != 3;
			if (!plain[i]) { /* stretched, rotated and moved: slices in the object's space */
				scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0, v3_neg(p)); /* about p */
				scene_xform_op(&o.xform, XF_STRETCH, i % 3, 0.5 + rng_uniform(55, i), v3(0, 0, 0));
				scene_xform_op(&o.xform, XF_ROTATE, (i + 1) % 3, 360 * rng_uniform(56, i), v3(0, 0, 0));
				scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0, v3_add(p, v3(0.2, -0.1, 0.3)));
				o.has_xform = true;
			}
			cyl[i] = o.u.cylinder;
			uint32_t id;
			CHECK(scene_add_object(s, &o, &id, &err) == 0);
			CHECK(scene_add_root(s, id, &err) == 0);
		}
		struct accel *a;
		CHECK(accel_build(s, &a, &err) == 0);
		agree_accel(far ? "long tilted cylinders, 1e4 away" : "long tilted cylinders", a);
		int mismatch = 0, hits = 0;
		static const double offs[] = { 0, 1e-12, -1e-9, 1e-6, -1e-6 };
		for (int k = 0; k < 6000; k++) {
			int i = (int)(rng_uniform(57, 4ull * k) * N_CYL);
			while (!plain[i])
				i = (i + 1) % N_CYL;
			vec3 from = cyl[i].from, ax = v3_sub(cyl[i].to, from);
			vec3 au = v3_norm(ax), X, Y;
			geom_frame(au, &X, &Y);
			int n = 2 + k % 7, c = k % (n + 1); /* cut c of n (0 and n: the ends) */
			double z = (double)c / n + offs[(k / 7) % 5];
			double phi = 2 * M_PI * rng_uniform(57, 4ull * k + 1);
			double rr = cyl[i].radius * ((k / 35) % 4 == 3 ? rng_uniform(57, 4ull * k + 2) : 1); /* some on a cap */
			vec3 target = v3_add(v3_add(from, v3_scale(ax, z)), v3_add(v3_scale(X, rr * cos(phi)), v3_scale(Y, rr * sin(phi))));
			vec3 o = v3_add(target, v3_scale(unit_dir(58, (uint64_t)k), 0.5 + 3 * rng_uniform(57, 4ull * k + 3)));
			struct ray r[4];
			for (int l = 0; l < 4; l++) {
				double e = 1e-7 * cyl[i].radius;
				vec3 tl = v3_add(target, v3_add(v3_scale(X, e * ((l & 1) ? 1 : -1)), v3_scale(au, e * ((l & 2) ? 1 : -1))));
				r[l] = (struct ray){ o, v3_sub(tl, o), 0, k % 5 == 4 ? 1 - 1e-9 : INFINITY };
			}
			struct hit h4[4], h1, hb;
			bool hit4[4], occ4[4];
			uint32_t hint = ACCEL_NO_HINT;
			accel_intersect4(a, r, h4, hit4);
			accel_occluded4(a, r, occ4, &hint);
			for (int l = 0; l < 4; l++) {
				bool b1 = accel_intersect(a, &r[l], &h1), bb = accel_intersect_brute(a, &r[l], &hb);
				mismatch += !same_hit(b1, &h1, hit4[l], &h4[l]) || !same_hit(b1, &h1, bb, &hb);
				mismatch += occ4[l] != bb || accel_occluded(a, &r[l]) != bb;
				hits += b1;
			}
		}
		printf("long tilted cylinders (%s): 24000 rays at their cuts, rims and caps, %d hits, %d mismatches\n",
		       far ? "1e4 away" : "at the origin", hits, mismatch);
		CHECK(mismatch == 0);
		CHECK(hits > 12000);
		accel_free(a);
		scene_free(s);
	}
}

/* A define under a random rotation and translation in the 10-unit cube. */
static uint32_t random_instance(struct scene *s, uint32_t define, uint64_t seed)
{
	struct scene_error err;
	struct scene_object o;
	scene_object_defaults(&o, PRIM_INSTANCE);
	o.u.instance.define = define;
	scene_xform_op(&o.xform, XF_ROTATE, (int)(3 * rng_uniform(seed, 1)), 360 * rng_uniform(seed, 2), v3(0, 0, 0));
	scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0,
		       v3(10 * rng_uniform(seed, 3), 10 * rng_uniform(seed, 4), 10 * rng_uniform(seed, 5)));
	o.has_xform = true;
	uint32_t id;
	CHECK(scene_add_object(s, &o, &id, &err) == 0);
	return id;
}

/* A root group of 1,500 instances and nothing else bounded (kept in leaf
 * order with packed leaves, no reference array) beside unbounded instances
 * (of a define holding a plane) and a plane: BVH, brute force and occlusion
 * agree on 6,000 rays (600 unless PORTRAY_TEST_FULL). */
static void many_instances(void)
{
	struct scene *s = scene_new();
	struct scene_error err;
	uint32_t m[3];
	for (int i = 0; i < 3; i++)
		m[i] = random_prim(s, rng_seed(4, i, 0), v3(0.1 * i, 0, 0), i == 0 ? 0 : i == 1 ? 1 : 5);
	struct scene_define d;
	memset(&d, 0, sizeof d);
	d.name = strdup("small");
	d.n_objects = 3;
	d.objects = malloc(3 * sizeof *d.objects);
	memcpy(d.objects, m, sizeof m);
	uint32_t small;
	CHECK(scene_add_define(s, &d, &small, &err) == 0);
	struct scene_object pl;
	scene_object_defaults(&pl, PRIM_PLANE);
	pl.u.plane.position = v3(0, -3, 0);
	uint32_t pid;
	CHECK(scene_add_object(s, &pl, &pid, &err) == 0);
	memset(&d, 0, sizeof d);
	d.name = strdup("floor");
	d.n_objects = 1;
	d.objects = malloc(sizeof *d.objects);
	d.objects[0] = pid;
	uint32_t floor;
	CHECK(scene_add_define(s, &d, &floor, &err) == 0);
	for (int i = 0; i < 1500; i++) {
		CHECK(scene_add_root(s, random_instance(s, small, rng_seed(5, i, 0)), &err) == 0);
		if (i % 700 == 0)
			CHECK(scene_add_root(s, random_instance(s, floor, rng_seed(6, i, 0)), &err) == 0);
	}
	scene_object_defaults(&pl, PRIM_PLANE);
	pl.u.plane.position = v3(0, 20, 0);
	CHECK(scene_add_object(s, &pl, &pid, &err) == 0);
	CHECK(scene_add_root(s, pid, &err) == 0);
	struct accel *a;
	CHECK(accel_build(s, &a, &err) == 0);
	vec3 lo, hi;
	CHECK(accel_bounds(a, &lo, &hi));
	struct job j = rays_in(a, lo, hi, rng_seed(7, 1, 2), 6 * n_rays / 100);
	printf("1,500 instances in packed leaves, unbounded instances, a plane: %d rays, %d hits, %d mismatches\n",
	       j.to, j.hits, j.mismatch);
	CHECK(j.mismatch == 0);
	CHECK(j.hits > j.to / 2);
	accel_free(a);
	scene_free(s);
}

/* A packed group of instances keeps float boxes (FLOAT BOXES in
 * accel_build.c) until an instance lies beyond float's comfortable range
 * (here at x = 2e31, the 601st of 1,200): the group goes on in doubles,
 * and BVH, brute force and occlusion still agree near the origin. */
static void instances_beyond_floats(void)
{
	struct scene *s = scene_new();
	struct scene_error err;
	uint32_t m[2];
	for (int i = 0; i < 2; i++)
		m[i] = random_prim(s, rng_seed(8, i, 0), v3(0.1 * i, 0, 0), i);
	struct scene_define d;
	memset(&d, 0, sizeof d);
	d.name = strdup("small");
	d.n_objects = 2;
	d.objects = malloc(2 * sizeof *d.objects);
	memcpy(d.objects, m, sizeof m);
	uint32_t small;
	CHECK(scene_add_define(s, &d, &small, &err) == 0);
	for (int i = 0; i < 1200; i++) {
		uint32_t id = random_instance(s, small, rng_seed(9, i, 0));
		if (i == 600) {
			struct scene_object o;
			scene_object_defaults(&o, PRIM_INSTANCE);
			o.u.instance.define = small;
			scene_xform_op(&o.xform, XF_TRANSLATE, 0, 0, v3(2e31, 0, 0));
			o.has_xform = true;
			CHECK(scene_add_object(s, &o, &id, &err) == 0);
		}
		CHECK(scene_add_root(s, id, &err) == 0);
	}
	struct accel *a;
	CHECK(accel_build(s, &a, &err) == 0);
	struct job j = rays_in(a, v3(-2, -2, -2), v3(12, 12, 12), rng_seed(10, 1, 2), 6 * n_rays / 100);
	printf("1,200 instances, one at 2e31: %d rays, %d hits, %d mismatches\n", j.to, j.hits, j.mismatch);
	CHECK(j.mismatch == 0);
	CHECK(j.hits > j.to / 10);
	accel_free(a);
	scene_free(s);
}

/*
 * Child c of a node whose bounds are rows of w floats (lo[3][w] then
 * hi[3][w]), of nn nodes, the node's index ni: the number of broken
 * invariants. An unused slot is all NaN, with nothing used after it and
 * at least two used before; a subtree comes after its parent; a leaf's
 * box holds its items, each counted in seen and covered.
 */
static int check_child(const float *rows, int w, const uint32_t *idx, const uint32_t *cnt, int c, uint32_t ni,
		       uint32_t nn, const uint32_t *perm, const struct geom_box *bx, int *seen, uint32_t *covered)
{
	float lo[3], hi[3];
	for (int a = 0; a < 3; a++) {
		lo[a] = rows[a * w + c];
		hi[a] = rows[(3 + a) * w + c];
	}
	if (isnan(lo[0]))
		return !isnan(hi[2]) || (c < w - 1 && !isnan(rows[c + 1])) || c < 2 || cnt[c];
	if (!cnt[c])
		return idx[c] <= ni || idx[c] >= nn;
	int bad = 0;
	for (uint32_t k = idx[c]; k < idx[c] + cnt[c]; k++) {
		uint32_t it = perm[k];
		seen[it]++;
		(*covered)++;
		bad += !(lo[0] <= bx[it].lo.x && lo[1] <= bx[it].lo.y && lo[2] <= bx[it].lo.z && hi[0] >= bx[it].hi.x &&
			 hi[1] >= bx[it].hi.y && hi[2] >= bx[it].hi.z);
	}
	return bad;
}

/*
 * WIDE NODES (bvh_make8): the 8-wide tree holds the 4-wide tree's leaves,
 * each once, with the same (idx, n) and boxes that hold their items;
 * unused slots are NaN and come last; children follow their parents; and
 * the nodes are wider (fewer of them, more than four children on average).
 */
static void wide_nodes(struct bvh *b, const struct geom_box *bx, const uint32_t *perm, uint32_t n)
{
	CHECK(bvh_make8(b) == 0);
	CHECK(b->nodes8 != NULL && b->n_nodes8 >= 1 && b->n_nodes8 < b->n_nodes4);
	int *seen = calloc(n, sizeof *seen);
	int bad = 0;
	uint32_t covered = 0, slots = 0;
	for (uint32_t ni = 0; ni < b->n_nodes8; ni++) {
		const struct bvh8 *p = &b->nodes8[ni];
		for (int c = 0; c < 8; c++) {
			slots += !isnan(p->lo[0][c]);
			bad += check_child((const float *)(const void *)p, 8, p->idx, p->n, c, ni, b->n_nodes8, perm, bx, seen,
					   &covered);
		}
	}
	for (uint32_t i = 0; i < n; i++)
		bad += seen[i] != 1;
	CHECK(covered == n);
	CHECK(bad == 0);
	CHECK(slots > 4 * b->n_nodes8); /* wider than the 4-wide nodes */
	CHECK(bvh_make8(b) == 0);       /* a second call keeps the tree */
	free(seen);
}

/* Builder invariants on random boxes and on boxes with one centroid. */
static void builder(void)
{
	for (int trial = 0; trial < 2; trial++) {
		uint32_t n = 5000;
		struct geom_box *bx = malloc(n * sizeof *bx);
		uint32_t *perm = malloc(n * sizeof *perm);
		int *seen = calloc(n, sizeof *seen);
		for (uint32_t i = 0; i < n; i++) {
			vec3 c = trial ? v3(1, 2, 3)
				       : v3(rng_uniform(1, 3 * i), rng_uniform(1, 3 * i + 1), rng_uniform(1, 3 * i + 2));
			double e = 0.01 * (1 + rng_uniform(2, i));
			bx[i].lo = v3_sub(c, v3(e, e, e));
			bx[i].hi = v3_add(c, v3(e, e, e));
		}
		struct bvh b;
		CHECK(bvh_build(&b, bx, n, perm, 4) == 0);
		CHECK(b.n_nodes >= 1 && b.n_nodes <= 2 * n);
		CHECK(b.root_n == 0 && b.n_nodes4 >= 1 && b.n_nodes4 <= (b.n_nodes - 1) / 2);
		int bad = 0;
		uint32_t covered = 0;
		for (uint32_t ni = 0; ni < b.n_nodes4; ni++) {
			const struct bvh4 *p = &b.nodes[ni];
			for (int c = 0; c < 4; c++)
				bad += check_child((const float *)(const void *)p, 4, p->idx, p->n, c, ni, b.n_nodes4, perm, bx, seen,
						   &covered);
		}
		for (uint32_t i = 0; i < n; i++)
			bad += seen[i] != 1;
		CHECK(covered == n);
		CHECK(bad == 0);
		wide_nodes(&b, bx, perm, n);
		/* packed: no leaf above 8 items, no interior node over 8 or fewer */
		struct bvh bp;
		CHECK(bvh_build_ex(&bp, bx, n, perm, 8, true) == 0);
		uint32_t packed_items = 0;
		for (uint32_t ni = 0; ni < bp.n_nodes4; ni++)
			for (int c = 0; c < 4; c++) {
				const struct bvh4 *p = &bp.nodes[ni];
				if (!isnan(p->lo[0][c]) && p->n[c]) {
					bad += trial == 0 && p->n[c] > 8;
					packed_items += p->n[c];
				}
			}
		CHECK(packed_items == n);
		CHECK(trial == 1 || bp.n_nodes4 < b.n_nodes4);
		bvh_free(&bp);
		CHECK(bad == 0);
		/* a single item: the root is a leaf */
		struct bvh b1;
		CHECK(bvh_build(&b1, bx, 1, perm, 4) == 0);
		CHECK(b1.n_nodes4 == 0 && b1.root_n == 1 && b1.root_idx == 0);
		bvh_free(&b1);
		bvh_free(&b);
		free(bx);
		free(perm);
		free(seen);
	}
}

/*
 * A leaf far bigger than ACCEL_LEAF_CHUNK (64) from the builder alone:
 * boxes in planes x = c, one at c = -1, a chain at c = 2^-8k (k < 70),
 * each 256 times closer to 0 than the last so that binning peels one off
 * per level, and 300 more at c = i 2^-700, left together in one leaf when
 * the depth limit stops the peeling. Through accel_build the padding of
 * item boxes merges centroids this close (they become one place: median
 * splits, small leaves), so the same triangles there only check extreme
 * coordinates: rays along x through them (closest, occluded, packets) get
 * brute force's hits, bit for bit. The chunked traversal itself was
 * checked by building with ACCEL_LEAF_CHUNK 2 (every tree then has big
 * leaves): this file, test_accel and test_render all agreed.
 */
#define CHAIN 70
#define CLUSTER 300
static void big_leaf(void)
{
	struct scene *s = scene_new();
	struct scene_error err;
	struct geom_box bx[1 + CHAIN + CLUSTER];
	uint32_t perm[1 + CHAIN + CLUSTER];
	for (int i = 0; i < 1 + CHAIN + CLUSTER; i++) {
		double c = i == 0 ? -1 : i <= CHAIN ? ldexp(1, -8 * (i - 1)) : ldexp(i - CHAIN - 1, -700);
		struct scene_object o;
		scene_object_defaults(&o, PRIM_TRIANGLE);
		o.u.triangle.a = v3(c, 0, 0);
		o.u.triangle.b = v3(c, 1e-3, 0);
		o.u.triangle.c = v3(c, 0, 1e-3);
		uint32_t id;
		CHECK(scene_add_object(s, &o, &id, &err) == 0);
		CHECK(scene_add_root(s, id, &err) == 0);
		bx[i].lo = v3(c, 0, 0);
		bx[i].hi = v3(c, 1e-3, 1e-3);
	}
	/* the builder alone makes the big leaf */
	struct bvh b;
	CHECK(bvh_build(&b, bx, 1 + CHAIN + CLUSTER, perm, 4) == 0);
	uint32_t biggest = 0;
	for (uint32_t ni = 0; ni < b.n_nodes4; ni++)
		for (int c = 0; c < 4; c++)
			if (!isnan(b.nodes[ni].lo[0][c]) && b.nodes[ni].n[c] > biggest)
				biggest = b.nodes[ni].n[c];
	printf("big leaf: %u items in the biggest leaf\n", biggest);
	CHECK(biggest > 4 * 64);
	bvh_free(&b);

	struct accel *a;
	CHECK(accel_build(s, &a, &err) == 0);
	int mismatch = 0, hits = 0;
	for (int i = 0; i < 2000; i++) {
		/* from just before the cluster (or from beyond the chain, backward) */
		double y = 4e-4 * rng_uniform(21, 2 * i), z = 4e-4 * rng_uniform(21, 2 * i + 1); /* y + z < 1e-3: inside */
		bool back = i % 4 == 3;
		struct ray r[4];
		for (int k = 0; k < 4; k++) {
			r[k].o = back ? v3(2, y, z) : v3(-1e-300, y, z);
			r[k].d = v3(back ? -1 : 1, 1e-6 * k, -1e-6 * k);
			r[k].tmin = 0;
			r[k].tmax = i % 8 == 1 ? 1e-200 : INFINITY; /* a window ending inside the cluster */
		}
		struct hit h, hb, h4[4];
		bool hit4[4];
		bool f = accel_intersect(a, &r[0], &h), fb = accel_intersect_brute(a, &r[0], &hb);
		mismatch += !same_hit(f, &h, fb, &hb);
		mismatch += accel_occluded(a, &r[0]) != fb;
		bool occ4[4];
		uint32_t hint = ACCEL_NO_HINT;
		accel_occluded4(a, r, occ4, &hint);
		mismatch += occ4[0] != fb;
		accel_intersect4(a, r, h4, hit4);
		mismatch += !same_hit(hit4[0], &h4[0], f, &h);
		hits += f;
	}
	printf("big leaf: 2000 rays, %d hits, %d mismatches\n", hits, mismatch);
	CHECK(mismatch == 0 && hits == 2000);
	accel_free(a);
	scene_free(s);
}

/*
 * The packets' triangle pre-test (TRIANGLE PRE-TEST in accel_trace.h) at its
 * margins: a grid of triangles (near the origin, and 1000 units away,
 * where floats are coarse) and packets of four rays from one origin aimed
 * at the grid's shared vertices and edge midpoints, exactly and off by
 * 1e-15 to 1e-7, and sixteen and sixty-four from one origin
 * (accel_intersect16, accel_intersect64) aimed at 2x2 and 4x4 patches of
 * neighbouring such points: every ray's hit is accel_intersect's, bit for
 * bit.
 */
#define EDGE_GRID 6

/* n rays (4, 16 or 64) from o, in packets of four aimed at target and, h
 * apart, its neighbours (packet p at (p & 1) + 2 (p >> 2 & 1) steps across
 * and (p >> 1 & 1) + 2 (p >> 3) up: the renderer's order of 2x2 blocks),
 * each ray e off its point along a diagonal. */
static void aim_packets(struct ray *r, int n, vec3 o, vec3 target, double h, double e)
{
	for (int l = 0; l < n; l++) {
		int p = l >> 2;
		vec3 tp = v3_add(target, v3(h * ((p & 1) + 2 * (p >> 2 & 1)), h * ((p >> 1 & 1) + 2 * (p >> 3)), 0));
		vec3 tl = v3_add(tp, v3(e * ((l & 1) ? 1 : -1), e * ((l & 2) ? 1 : -1), 0));
		r[l] = (struct ray){ o, v3_sub(tl, o), 0, INFINITY };
	}
}

/* How many of the n packet answers (hit[l], h[l]) differ from
 * accel_intersect's for r[l]; the single rays' hits are added to *hits. */
static int unlike_single(const struct accel *a, const struct ray *r, const struct hit *h, const bool *hit, int n,
			 int *hits)
{
	int mismatch = 0;
	for (int l = 0; l < n; l++) {
		struct hit h1;
		bool b1 = accel_intersect(a, &r[l], &h1);
		mismatch += !same_hit(b1, &h1, hit[l], &h[l]);
		*hits += b1;
	}
	return mismatch;
}

static void tri_margins(void)
{
	for (int far = 0; far < 2; far++) {
		struct scene *s = scene_new();
		struct scene_error err;
		double x0 = far ? 1000 : 0, h = 1.0 / EDGE_GRID;
		for (int j = 0; j < EDGE_GRID; j++)
			for (int i = 0; i < EDGE_GRID; i++)
				for (int t = 0; t < 2; t++) {
					struct scene_object o;
					scene_object_defaults(&o, PRIM_TRIANGLE);
					vec3 p00 = v3(x0 + i * h, j * h, 0.01 * ((i + j) % 3)), p10 = v3(x0 + (i + 1) * h, j * h, 0);
					vec3 p01 = v3(x0 + i * h, (j + 1) * h, 0), p11 = v3(x0 + (i + 1) * h, (j + 1) * h, 0.02);
					o.u.triangle.a = p00;
					o.u.triangle.b = t ? p11 : p10;
					o.u.triangle.c = t ? p01 : p11;
					uint32_t id;
					CHECK(scene_add_object(s, &o, &id, &err) == 0);
					CHECK(scene_add_root(s, id, &err) == 0);
				}
		struct accel *a;
		CHECK(accel_build(s, &a, &err) == 0);
		int mismatch = 0, hits = 0, hits16 = 0, hits64 = 0;
		static const double offs[] = { 0, 1e-15, 1e-12, 1e-9, 1e-7 };
		for (int k = 0; k < 4000; k++) {
			int i = (int)(rng_uniform(31, 3ull * k) * (EDGE_GRID + 1)), j = (int)(rng_uniform(31, 3ull * k + 1) * (EDGE_GRID + 1));
			double half = k % 3 == 1 ? h / 2 : 0; /* a vertex, or an edge's midpoint */
			vec3 target = v3(x0 + i * h + half, j * h + (k % 3 == 2 ? h / 2 : 0), 0);
			vec3 o = v3(x0 + 2 * rng_uniform(31, 3ull * k + 2) - 0.5, 1.5 * rng_uniform(32, k) - 0.25,
				    0.5 + 2 * rng_uniform(33, k));
			double e = offs[k % 5];
			/* four rays at the point, as one accel_intersect4; the same
			 * four and three packets aimed at the neighbouring vertices or
			 * midpoints, as one accel_intersect16; sixteen packets aimed at
			 * a 4x4 patch of such points, as one accel_intersect64 */
			struct ray r[64];
			struct hit hp[64];
			bool hit[64];
			aim_packets(r, 4, o, target, h, e);
			accel_intersect4(a, r, hp, hit);
			mismatch += unlike_single(a, r, hp, hit, 4, &hits);
			aim_packets(r, 16, o, target, h, e);
			accel_intersect16(a, r, hp, hit);
			mismatch += unlike_single(a, r, hp, hit, 16, &hits16);
			aim_packets(r, 64, o, target, h, e);
			accel_intersect64(a, r, hp, hit);
			mismatch += unlike_single(a, r, hp, hit, 64, &hits64);
		}
		printf("triangle pre-test margins (%s): 16000 rays in fours, 64000 in sixteens, 256000 in sixty-fours, %d, %d and %d hits, %d unlike single rays\n",
		       far ? "1000 units away" : "at the origin", hits, hits16, hits64, mismatch);
		CHECK(mismatch == 0);
		CHECK(hits > 8000);
		CHECK(hits16 > 24000);
		CHECK(hits64 > 64000);
		accel_free(a);
		scene_free(s);
	}
}

/*
 * The packets' box set-up (ray_box4 in accel_packet.c) lane by lane: four rays
 * from one origin whose directions differ in scale (2^-500 to 2^60, and
 * beyond the +-1000 exponent clamp), with components at and around the
 * 1e-30 cut-off below which an inverse becomes +-1e30, zero components,
 * so that the two lanes of each divpd take different branches. Every
 * ray's hit and occlusion are accel_intersect's and accel_occluded's.
 */
static void packet_setup(void)
{
	struct scene *s;
	struct scene_error err;
	CHECK(parse_files(NULL, "tests/data/spd/tetra_s4.sce", &s, &err) == 0);
	struct accel *a;
	CHECK(accel_build(s, &a, &err) == 0);
	vec3 lo, hi;
	CHECK(accel_bounds(a, &lo, &hi));
	static const double scale[] = { 1, 0x1p-60, 0x1p60, 0x1p-500, 1e305, 0x1p-3 };
	static const double tiny[] = { 0, 1e-30, 1e-31, 2e-30, 5e-31, 1e-300 };
	int mismatch = 0, hits = 0;
	for (int k = 0; k < 3000; k++) {
		vec3 o = v3_add(hi, v3(1, 1, 1)); /* above a corner: every target ahead */
		vec3 t = v3(lo.x + (hi.x - lo.x) * rng_uniform(41, 3ull * k), lo.y + (hi.y - lo.y) * rng_uniform(41, 3ull * k + 1),
			    lo.z + (hi.z - lo.z) * rng_uniform(41, 3ull * k + 2));
		struct ray r[4];
		for (int l = 0; l < 4; l++) {
			vec3 d = v3_sub(t, o);
			int axis = (k + l) % 3;
			double e = -tiny[(k + 2 * l) % 6]; /* negative as the rest of d: one octant */
			if (k % 4 != 0) /* one axis at or near the cut-off */
				d = axis == 0 ? v3(e, d.y, d.z) : axis == 1 ? v3(d.x, e, d.z) : v3(d.x, d.y, e);
			if (e == 0)
				d = axis == 0 ? v3(-0.0, d.y, d.z) : axis == 1 ? v3(d.x, -0.0, d.z) : v3(d.x, d.y, -0.0);
			d = v3_scale(d, scale[(k + l) % 6]);
			r[l] = (struct ray){ o, d, 0, INFINITY };
		}
		struct hit h4[4], h1;
		bool hit4[4], occ4[4];
		uint32_t hint = ACCEL_NO_HINT;
		accel_intersect4(a, r, h4, hit4);
		accel_occluded4(a, r, occ4, &hint);
		for (int l = 0; l < 4; l++) {
			bool b1 = accel_intersect(a, &r[l], &h1);
			mismatch += !same_hit(b1, &h1, hit4[l], &h4[l]);
			mismatch += occ4[l] != accel_occluded(a, &r[l]);
			hits += b1;
		}
	}
	printf("packet set-up (scales 2^-500 to 1e305, components near 1e-30): 12000 rays, %d hits, %d unlike single rays\n",
	       hits, mismatch);
	CHECK(mismatch == 0);
	CHECK(hits > 500);
	accel_free(a);
	scene_free(s);
}

/* Leaves of b and the items they hold (every item once: the caller checks). */
static uint32_t count_leaves(const struct bvh *b, uint32_t *items)
{
	uint32_t leaves = 0;
	*items = 0;
	for (uint32_t ni = 0; ni < b->n_nodes4; ni++)
		for (int c = 0; c < 4; c++)
			if (!isnan(b->nodes[ni].lo[0][c]) && b->nodes[ni].n[c]) {
				leaves++;
				*items += b->nodes[ni].n[c];
			}
	return leaves;
}

/* COST-WEIGHTED SAH: costs of BVH_COST_UNIT (or none) give bvh_build's tree; cheap
 * items share leaves more than dear ones, and a mix splits the dear ones
 * finer. */
static void costs(void)
{
	uint32_t n = 3000;
	struct geom_box *bx = malloc(n * sizeof *bx);
	uint32_t *perm = malloc(n * sizeof *perm), *perm2 = malloc(n * sizeof *perm2);
	uint8_t *cost = malloc(n);
	for (uint32_t i = 0; i < n; i++) {
		vec3 c = v3(rng_uniform(7, 3 * i), rng_uniform(7, 3 * i + 1), rng_uniform(7, 3 * i + 2));
		double e = 0.02 * (1 + rng_uniform(8, i));
		bx[i].lo = v3_sub(c, v3(e, e, e));
		bx[i].hi = v3_add(c, v3(e, e, e));
	}
	struct bvh b0, b1, b2;
	CHECK(bvh_build(&b0, bx, n, perm, 4) == 0);
	memset(cost, BVH_COST_UNIT, n);
	CHECK(bvh_build_cost(&b1, bx, n, perm2, 4, cost) == 0);
	CHECK(b0.n_nodes4 == b1.n_nodes4 && memcmp(b0.nodes, b1.nodes, b0.n_nodes4 * sizeof *b0.nodes) == 0);
	CHECK(memcmp(perm, perm2, n * sizeof *perm) == 0);
	bvh_free(&b1);
	CHECK(bvh_build_cost(&b1, bx, n, perm2, 4, NULL) == 0);
	CHECK(b0.n_nodes4 == b1.n_nodes4 && memcmp(b0.nodes, b1.nodes, b0.n_nodes4 * sizeof *b0.nodes) == 0);
	bvh_free(&b1);
	uint32_t items0, items1, items2;
	memset(cost, 1, n);
	CHECK(bvh_build_cost(&b1, bx, n, perm2, 4, cost) == 0);
	memset(cost, 32, n);
	CHECK(bvh_build_cost(&b2, bx, n, perm2, 4, cost) == 0);
	uint32_t l0 = count_leaves(&b0, &items0), l1 = count_leaves(&b1, &items1), l2 = count_leaves(&b2, &items2);
	CHECK(items0 == n && items1 == n && items2 == n);
	CHECK(l1 < l0 && l0 < l2); /* cheap: fuller leaves; dear: emptier */
	bvh_free(&b1);
	bvh_free(&b2);
	/* even items cheap, odd ones dear: the dear ones sit in smaller leaves */
	for (uint32_t i = 0; i < n; i++)
		cost[i] = i & 1 ? 32 : 1;
	CHECK(bvh_build_cost(&b1, bx, n, perm2, 4, cost) == 0);
	double sum[2] = { 0, 0 }, cnt[2] = { 0, 0 };
	for (uint32_t ni = 0; ni < b1.n_nodes4; ni++)
		for (int c = 0; c < 4; c++) {
			const struct bvh4 *p = &b1.nodes[ni];
			if (isnan(p->lo[0][c]) || !p->n[c])
				continue;
			for (uint32_t k = p->idx[c]; k < p->idx[c] + p->n[c]; k++) {
				sum[perm2[k] & 1] += p->n[c];
				cnt[perm2[k] & 1]++;
			}
		}
	/* (about 1.0 against 2.4 here; 1.6 each when costs are ignored) */
	CHECK(cnt[0] + cnt[1] == n && sum[1] / cnt[1] < 0.75 * (sum[0] / cnt[0]));
	bvh_free(&b1);
	bvh_free(&b0);
	free(bx);
	free(perm);
	free(perm2);
	free(cost);
}

int main(void)
{
	const char *full = getenv("PORTRAY_TEST_FULL");
	if (full && *full && strcmp(full, "0") != 0)
		n_rays = N_RAYS_FULL;
	builder();
	costs();
	big_leaf();
	tri_margins();
	packet_setup();
	far_away();
	mixed();
	long_cylinders();
	many_instances();
	instances_beyond_floats();
	static const char *const scenes[] = { "tests/data/spd/balls_s4.sce", "tests/data/spd/gears_s2.sce",
					      "tests/data/spd/rings_s3.sce", "tests/data/spd/tetra_s4.sce",
					      "tests/data/meshes/spot.sce" };
	printf("single rays' node tests: %s\n", accel_use_avx2() ? "AVX2 (WIDE NODES IN AVX2)" : "SSE2");
	for (size_t i = 0; i < sizeof scenes / sizeof *scenes; i++)
		agree(scenes[i]);
	/* the SSE2 node tests too, where the AVX2 ones ran above (the same
	 * hits: both agree with brute force, bit for bit) */
	CHECK(setenv("PORTRAY_SIMD", "sse2", 1) == 0);
	CHECK(!accel_use_avx2());
	printf("single rays' node tests: SSE2 (PORTRAY_SIMD=sse2)\n");
	for (size_t i = 0; i < 3; i++)
		agree(scenes[i]);
	CHECK(unsetenv("PORTRAY_SIMD") == 0);
	const char *shared = getenv("PORTRAY_SHARED");
	char teapot[4096];
	snprintf(teapot, sizeof teapot, "%s/meshes/teapot.sce", shared && *shared ? shared : "../shared/data");
	if (access(teapot, R_OK) == 0)
		agree(teapot);
	else
		printf("%s: not found, skipped\n", teapot);
	TEST_MAIN_END();
}
