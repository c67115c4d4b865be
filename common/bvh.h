/*
 * bvh.h - a binned-SAH bounding volume hierarchy over boxes, collapsed into
 * arrays of 4-wide nodes (and, on request, 8-wide ones). The builder knows nothing of primitives: it
 * orders item indices; traversal lives with the primitives (accel.c,
 * accel_packet.c).
 */
#ifndef PORTRAY_BVH_H
#define PORTRAY_BVH_H

#include <stdbool.h>
#include <stdint.h>

#include "common/geom.h"

/* Deepest tree the builder makes; traversal stacks are this big. */
#define BVH_MAX_DEPTH 64

/*
 * The builder's node: float bounds rounded outward from the double boxes, so
 * a box test in double on them never culls a true hit. n == 0: interior,
 * children are nodes idx and idx+1; n > 0: leaf of items perm[idx .. idx+n).
 */
struct bvh_node {
	float b[6]; /* min corner x y z, then max corner x y z */
	uint32_t idx, n;
};

/*
 * What traversal reads: a 4-wide node (128 bytes, two cache lines) holding
 * its children's bounds side by side (lo[axis][c], hi[axis][c]), so one
 * 4-wide float SIMD slab test covers all four. Bounds are the builder's
 * (rounded outward to float); unused slots have NaN bounds, which the slab
 * test never reports as hit. Child c: n[c] == 0: interior, idx[c] is its
 * node; else a leaf of items perm[idx[c] .. idx[c]+n[c]).
 */
struct bvh4 {
	float lo[3][4], hi[3][4];
	uint32_t idx[4];
	uint32_t n[4];
};

/*
 * WIDE NODES for single rays: the same tree with each node's children
 * pulled up from its grandchildren until it has up to eight (bvh_make8),
 * so a single ray makes about half the node visits, each one 8-wide slab
 * test. Leaves and unused slots are as in bvh4 (the leaves' idx and n are
 * copied as the 4-wide tree holds them, flags included); an interior
 * child's idx is a bvh8 node. 256 bytes, four cache lines.
 */
struct bvh8 {
	float lo[3][8], hi[3][8];
	uint32_t idx[8];
	uint32_t n[8];
};

struct bvh {
	struct bvh4 *nodes;     /* owned; node 0 is the root unless root_n > 0 */
	uint32_t n_nodes4;
	struct bvh8 *nodes8;    /* owned, or NULL: WIDE NODES of the same tree */
	uint32_t n_nodes8;
	float root_b[6];        /* the root's bounds: min x y z, max x y z */
	uint32_t root_idx, root_n; /* root_n > 0: the root is a leaf (no nodes) */
	uint32_t n_nodes;       /* binary nodes the builder made (statistics) */
};

/* What the builder returns when it gave up (CANCEL_RETURN of cancel.h). */
#define BVH_CANCELLED (-2)
/*
 * Builds over n items with finite boxes. perm (n entries, caller-owned) gets
 * the items in leaf order. max_leaf bounds the items of a leaf unless the
 * depth limit or identical centroids force more. n == 0 gives an empty tree
 * (n_nodes == 0). Returns 0, -1 when out of memory, or BVH_CANCELLED when
 * the calling thread's cancel flag (cancel.h) was seen set (polled every
 * node and every CANCEL_STRIDE items); *b is then empty.
 */
int bvh_build(struct bvh *b, const struct geom_box *boxes, uint32_t n, uint32_t *perm, uint32_t max_leaf);
/* The same; with pack, every subtree of at most max_leaf items is a leaf
 * (fewer, fuller leaves: less memory where items are many and costly to
 * store, such as instances), else the SAH decides as in bvh_build. */
int bvh_build_ex(struct bvh *b, const struct geom_box *boxes, uint32_t n, uint32_t *perm, uint32_t max_leaf,
		 bool pack);
/* An item's usual test cost, which a traversal step costs too, in the
 * units of bvh_build_cost's costs. */
#define BVH_COST_UNIT 4u
/* bvh_build (no packing) with a test cost per item, cost[it] in
 * BVH_COST_UNIT parts of one item's usual test: the SAH weighs each side
 * by its summed cost, so cheap items share leaves and dear ones are split
 * further. NULL: every item costs BVH_COST_UNIT (bvh_build's tree). */
int bvh_build_cost(struct bvh *b, const struct geom_box *boxes, uint32_t n, uint32_t *perm, uint32_t max_leaf,
		   const uint8_t *cost);
/* bvh_build_ex over boxes held as floats (min x y z, then max x y z): the
 * tree bvh_build_ex makes over the same values as doubles, in half the
 * memory (issue 13: a million instances' boxes are 24 MB, not 48). Takes
 * ownership of boxes: they are freed, whatever the result, as soon as the
 * binary tree is built, before its collapse into 4-wide nodes (the build's
 * peak of memory would otherwise hold both). */
int bvh_build_f(struct bvh *b, float (*boxes)[6], uint32_t n, uint32_t *perm, uint32_t max_leaf, bool pack);
void bvh_free(struct bvh *b);
/* WIDE NODES: b->nodes8 from b->nodes as they are now (call it after the
 * leaves' last change). Returns 0, -1 when out of memory, or BVH_CANCELLED
 * (b unchanged then). */
int bvh_make8(struct bvh *b);
/*
 * How many threads a build may use (the calling one included): 0, the
 * default, means one per online processor (at most 8). Builds of fewer
 * than 8192 items use one. The tree is the same whatever the count.
 * Process-wide; set it before building (a render's -j).
 */
void bvh_set_threads(unsigned n);

#endif
