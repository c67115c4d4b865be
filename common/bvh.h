/*
 * bvh.h - a binned-SAH bounding volume hierarchy over boxes, flattened into
 * an array of 32-byte nodes. The builder knows nothing of primitives: it
 * orders item indices; traversal lives with the primitives (accel.c).
 */
#ifndef PORTRAY_BVH_H
#define PORTRAY_BVH_H

#include <stdint.h>

#include "common/geom.h"

/* Deepest tree the builder makes; traversal stacks are this big. */
#define BVH_MAX_DEPTH 64

/*
 * One node: float bounds rounded outward from the double boxes, so a box test
 * in double on them never culls a true hit. n == 0: interior, children are
 * nodes idx and idx+1 (adjacent: one cache line); n > 0: leaf of items
 * perm[idx .. idx+n).
 */
struct bvh_node {
	float b[6]; /* min corner x y z, then max corner x y z */
	uint32_t idx, n;
};

struct bvh {
	struct bvh_node *nodes; /* owned */
	uint32_t n_nodes;
};

/*
 * Builds over n items with finite boxes. perm (n entries, caller-owned) gets
 * the items in leaf order. max_leaf bounds the items of a leaf unless the
 * depth limit or identical centroids force more. n == 0 gives no nodes.
 * Returns 0, or -1 when out of memory.
 */
int bvh_build(struct bvh *b, const struct geom_box *boxes, uint32_t n, uint32_t *perm, uint32_t max_leaf);
void bvh_free(struct bvh *b);

#endif
