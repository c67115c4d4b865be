/*
 * test_bvh_threads.c - the BVH builder makes the same tree whatever the
 * number of build threads (bvh_set_threads): 1, 2, 3 and 8 threads give
 * byte-identical 4-wide nodes, roots and leaf orders, over random boxes
 * of mixed sizes (some big ones, so the big-item split is taken too),
 * over many equal centroids, and with packed leaves. Also the
 * whole acceleration structure of the spot mesh scene: every group's
 * nodes and references are the same with 1 and with 2 threads.
 */
#include <stdlib.h>
#include <string.h>

#include "common/accel_int.h"
#include "common/bvh.h"
#include "common/parse.h"
#include "tests/unit/check.h"

static uint64_t xs = 0x9e3779b97f4a7c15ull;
static double uni(void)
{
	xs ^= xs << 13, xs ^= xs >> 7, xs ^= xs << 17;
	return (double)(xs >> 11) * 0x1p-53;
}

/* n boxes: mostly small, one in 500 big (up to half the scene), and a
 * run of boxes sharing one centroid. */
static struct geom_box *mixed_boxes(uint32_t n)
{
	struct geom_box *b = malloc((size_t)n * sizeof *b);
	for (uint32_t i = 0; b && i < n; i++) {
		vec3 c = v3(uni() * 100, uni() * 20, uni() * 100);
		double r = i % 500 == 7 ? 10 + 40 * uni() : 0.01 + 0.3 * uni();
		if (i % 97 < 5)
			c = v3(50, 10, 50); /* equal centroids */
		b[i].lo = v3_sub(c, v3(r, r * uni(), r));
		b[i].hi = v3_add(c, v3(r, r, r * uni()));
	}
	return b;
}

static bool same_tree(const struct bvh *a, const uint32_t *pa, const struct bvh *b, const uint32_t *pb, uint32_t n)
{
	return a->n_nodes == b->n_nodes && a->n_nodes4 == b->n_nodes4 && a->root_idx == b->root_idx &&
	       a->root_n == b->root_n && !memcmp(a->root_b, b->root_b, sizeof a->root_b) &&
	       (a->n_nodes4 == 0 || !memcmp(a->nodes, b->nodes, (size_t)a->n_nodes4 * sizeof *a->nodes)) &&
	       !memcmp(pa, pb, (size_t)n * sizeof *pa);
}

static void check_boxes(uint32_t n, uint32_t max_leaf, bool pack)
{
	struct geom_box *bx = mixed_boxes(n);
	uint32_t *p1 = malloc((size_t)n * sizeof *p1), *pk = malloc((size_t)n * sizeof *pk);
	CHECK(bx && p1 && pk);
	if (!bx || !p1 || !pk)
		goto out;
	struct bvh b1;
	bvh_set_threads(1);
	CHECK(bvh_build_ex(&b1, bx, n, p1, max_leaf, pack) == 0);
	static const unsigned threads[] = { 2, 3, 8 };
	for (size_t t = 0; t < sizeof threads / sizeof *threads; t++) {
		struct bvh bk;
		bvh_set_threads(threads[t]);
		CHECK(bvh_build_ex(&bk, bx, n, pk, max_leaf, pack) == 0);
		bool same = same_tree(&b1, p1, &bk, pk, n);
		if (!same)
			fprintf(stderr, "%u boxes, %u threads: the tree differs from one thread's\n", n, threads[t]);
		CHECK(same);
		bvh_free(&bk);
	}
	bvh_free(&b1);
out:
	free(bx);
	free(p1);
	free(pk);
}

static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
	const unsigned char *c = p;
	for (size_t i = 0; i < n; i++)
		h = (h ^ c[i]) * 1099511628211ull;
	return h;
}

static uint64_t group_hash(uint64_t h, const struct group *g)
{
	if (!g)
		return h;
	h = fnv(h, &g->bvh.n_nodes4, sizeof g->bvh.n_nodes4);
	h = fnv(h, g->bvh.root_b, sizeof g->bvh.root_b);
	if (g->bvh.nodes)
		h = fnv(h, g->bvh.nodes, (size_t)g->bvh.n_nodes4 * sizeof *g->bvh.nodes);
	if (g->refs)
		h = fnv(h, g->refs, (size_t)g->n_refs * sizeof *g->refs);
	return h;
}

static void check_scene(const char *path)
{
	struct scene *s;
	struct scene_error err;
	if (parse_files(NULL, path, &s, &err)) {
		printf("%s: not parsed (%s): skipped\n", path, err.msg);
		return;
	}
	uint64_t h[2];
	for (int t = 0; t < 2; t++) {
		bvh_set_threads((unsigned)t + 1);
		struct accel *a;
		CHECK(accel_build(s, &a, &err) == 0);
		h[t] = 1469598103934665603ull;
		if (a) {
			h[t] = group_hash(h[t], a->root);
			for (uint32_t d = 0; d < s->n_defines; d++)
				h[t] = group_hash(h[t], a->dgroup[d]);
		}
		accel_free(a);
	}
	CHECK(h[0] == h[1]);
	scene_free(s);
}

int main(void)
{
	check_boxes(3, 4, false);
	check_boxes(20000, 4, false);
	check_boxes(60000, 4, false);
	check_boxes(60000, 8, true);
	check_scene("tests/data/meshes/spot.sce");
	check_scene("tests/data/spd/balls_s4.sce");
	bvh_set_threads(0);
	TEST_MAIN_END();
}
