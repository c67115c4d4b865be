/*
 * bvh.c - binned SAH builder (16 bins on each axis over centroid bounds),
 * children stored adjacently, bounds rounded outward to float.
 *
 * The builder polls the calling thread's cancel flag (cancel.h) at every
 * node and every CANCEL_STRIDE items of a node's loops; once a poll says
 * true every function returns at once, leaving garbage, and bvh_build_ex
 * frees it and returns BVH_CANCELLED.
 */
#include "common/bvh.h"

#include <stdlib.h>
#include <string.h>

#include "common/cancel.h"

_Static_assert(BVH_CANCELLED == CANCEL_RETURN, "the builder gives up with the core's value");

#define BVH_BINS 16
/* SAH constants relative to one primitive test */
#define BVH_COST_TRAV 1.0
#define BVH_COST_ISECT 1.0

struct bvh_ctx {
	const struct geom_box *boxes;
	vec3 *cent;
	uint32_t *perm;
	struct bvh_node *nodes;
	uint32_t n_nodes;
	uint32_t max_leaf;
	bool pack;
};

static float round_down(double x)
{
	float f = (float)x;
	if ((double)f > x)
		f = nextafterf(f, -INFINITY);
	return f;
}

static float round_up(double x)
{
	float f = (float)x;
	if ((double)f < x)
		f = nextafterf(f, INFINITY);
	return f;
}

static double box_area(struct geom_box b)
{
	vec3 e = v3_sub(b.hi, b.lo);
	if (e.x < 0 || e.y < 0 || e.z < 0)
		return 0;
	return 2 * (e.x * e.y + e.y * e.z + e.z * e.x);
}

/* Partitions perm[begin, end) so that items with pred true come first. */
static uint32_t partition(struct bvh_ctx *B, uint32_t begin, uint32_t end, int axis, double lo,
			  double scale, int split_bin)
{
	uint32_t i = begin, j = end;
	while (i < j) {
		if (cancel_poll_every(i))
			return i;
		double c = v3_comp(B->cent[B->perm[i]], axis);
		int k = (int)((c - lo) * scale);
		k = k < 0 ? 0 : k >= BVH_BINS ? BVH_BINS - 1 : k;
		if (k < split_bin) {
			i++;
		} else {
			j--;
			uint32_t t = B->perm[i];
			B->perm[i] = B->perm[j];
			B->perm[j] = t;
		}
	}
	return i;
}

/* Builds node ni over perm[begin, end). Recursion depth < BVH_MAX_DEPTH.
 * Returns at once, leaving garbage, when a cancel poll says true. */
static void build_node(struct bvh_ctx *B, uint32_t ni, uint32_t begin, uint32_t end, int depth)
{
	if (cancel_poll())
		return;
	struct geom_box bb = geom_box_empty(), cb = geom_box_empty();
	for (uint32_t i = begin; i < end; i++) {
		if (cancel_poll_every(i))
			return;
		bb = geom_box_union(bb, B->boxes[B->perm[i]]);
		cb = geom_box_point(cb, B->cent[B->perm[i]]);
	}
	struct bvh_node *nd = &B->nodes[ni];
	nd->b[0] = round_down(bb.lo.x), nd->b[1] = round_down(bb.lo.y), nd->b[2] = round_down(bb.lo.z);
	nd->b[3] = round_up(bb.hi.x), nd->b[4] = round_up(bb.hi.y), nd->b[5] = round_up(bb.hi.z);
	uint32_t n = end - begin;
	if (n <= 1 || depth >= BVH_MAX_DEPTH - 1 || (B->pack && n <= B->max_leaf))
		goto leaf;

	double best = INFINITY;
	int best_axis = -1, best_bin = 0;
	for (int axis = 0; axis < 3; axis++) {
		double lo = v3_comp(cb.lo, axis), ext = v3_comp(cb.hi, axis) - lo;
		if (!(ext > 0))
			continue;
		double scale = BVH_BINS / ext;
		struct geom_box bin_box[BVH_BINS];
		uint32_t bin_n[BVH_BINS] = { 0 };
		for (int k = 0; k < BVH_BINS; k++)
			bin_box[k] = geom_box_empty();
		for (uint32_t i = begin; i < end; i++) {
			if (cancel_poll_every(i))
				return;
			uint32_t it = B->perm[i];
			int k = (int)((v3_comp(B->cent[it], axis) - lo) * scale);
			k = k < 0 ? 0 : k >= BVH_BINS ? BVH_BINS - 1 : k;
			bin_n[k]++;
			bin_box[k] = geom_box_union(bin_box[k], B->boxes[it]);
		}
		double right_cost[BVH_BINS];
		struct geom_box acc = geom_box_empty();
		uint32_t cnt = 0;
		for (int k = BVH_BINS - 1; k > 0; k--) {
			acc = geom_box_union(acc, bin_box[k]);
			cnt += bin_n[k];
			right_cost[k] = box_area(acc) * cnt;
		}
		acc = geom_box_empty();
		cnt = 0;
		for (int k = 1; k < BVH_BINS; k++) { /* split before bin k */
			acc = geom_box_union(acc, bin_box[k - 1]);
			cnt += bin_n[k - 1];
			if (cnt == 0 || cnt == n)
				continue;
			double c = box_area(acc) * cnt + right_cost[k];
			if (c < best)
				best = c, best_axis = axis, best_bin = k;
		}
	}
	/* Also try setting the big items apart (a floor under a sphereflake):
	 * centroid bins cannot separate them when their centres sit among the
	 * small ones. */
	static const double big_frac[3] = { 0.5, 0.2, 0.05 };
	int best_big = -1;
	double node_area = box_area(bb);
	for (int q = 0; q < 3; q++) {
		struct geom_box b1 = geom_box_empty(), b2 = geom_box_empty();
		uint32_t n1 = 0;
		for (uint32_t i = begin; i < end; i++) {
			if (cancel_poll_every(i))
				return;
			const struct geom_box *ib = &B->boxes[B->perm[i]];
			if (box_area(*ib) > big_frac[q] * node_area)
				b1 = geom_box_union(b1, *ib), n1++;
			else
				b2 = geom_box_union(b2, *ib);
		}
		if (n1 == 0 || n1 == n)
			continue;
		double c = box_area(b1) * n1 + box_area(b2) * (n - n1);
		if (c < best)
			best = c, best_big = q;
	}
	uint32_t mid;
	if (best_big >= 0) {
		uint32_t i = begin, j = end;
		while (i < j) {
			if (cancel_poll_every(i))
				return;
			if (box_area(B->boxes[B->perm[i]]) > big_frac[best_big] * node_area) {
				i++;
			} else {
				j--;
				uint32_t t = B->perm[i];
				B->perm[i] = B->perm[j];
				B->perm[j] = t;
			}
		}
		mid = i;
		double split_cost = BVH_COST_TRAV * node_area + BVH_COST_ISECT * best;
		if (n <= B->max_leaf && BVH_COST_ISECT * node_area * n <= split_cost)
			goto leaf;
	} else if (best_axis < 0) { /* every centroid in one place */
		if (n <= B->max_leaf)
			goto leaf;
		mid = begin + n / 2;
	} else {
		double area = box_area(bb);
		double split_cost = BVH_COST_TRAV * area + BVH_COST_ISECT * best;
		double leaf_cost = BVH_COST_ISECT * area * n;
		if (n <= B->max_leaf && leaf_cost <= split_cost)
			goto leaf;
		double lo = v3_comp(cb.lo, best_axis), ext = v3_comp(cb.hi, best_axis) - lo;
		mid = partition(B, begin, end, best_axis, lo, BVH_BINS / ext, best_bin);
		if (cancel_seen())
			return;
		if (mid == begin || mid == end)
			mid = begin + n / 2;
	}
	uint32_t c = B->n_nodes;
	B->n_nodes += 2;
	nd->idx = c;
	nd->n = 0;
	build_node(B, c, begin, mid, depth + 1);
	build_node(B, c + 1, mid, end, depth + 1);
	return;
leaf:
	nd->idx = begin;
	nd->n = n;
}

/*
 * Collapses binary node ni (interior) into 4-wide node *next, opening the
 * largest interior child until four children or only leaves remain;
 * children's nodes follow in depth-first order. Returns its index (garbage
 * when a cancel poll says true).
 */
static uint32_t collapse(const struct bvh_node *nodes, uint32_t ni, struct bvh4 *out, uint32_t *next)
{
	uint32_t me = (*next)++;
	if (cancel_seen() || cancel_poll_every(me)) /* seen: the other subtrees too */
		return me;
	uint32_t ch[4] = { nodes[ni].idx, nodes[ni].idx + 1, 0, 0 };
	int nc = 2;
	while (nc < 4) {
		int best = -1;
		double best_area = -1;
		for (int c = 0; c < nc; c++) {
			const struct bvh_node *x = &nodes[ch[c]];
			if (x->n)
				continue;
			struct geom_box bx = { v3(x->b[0], x->b[1], x->b[2]), v3(x->b[3], x->b[4], x->b[5]) };
			double a = box_area(bx);
			if (a > best_area)
				best_area = a, best = c;
		}
		if (best < 0)
			break;
		uint32_t x = ch[best];
		ch[best] = nodes[x].idx;
		ch[nc++] = nodes[x].idx + 1;
	}
	struct bvh4 nd;
	for (int c = 0; c < 4; c++) {
		if (c >= nc) {
			for (int k = 0; k < 3; k++)
				nd.lo[k][c] = nd.hi[k][c] = NAN;
			nd.idx[c] = 0;
			nd.n[c] = 0;
			continue;
		}
		const struct bvh_node *x = &nodes[ch[c]];
		for (int k = 0; k < 3; k++) {
			nd.lo[k][c] = x->b[k];
			nd.hi[k][c] = x->b[k + 3];
		}
		nd.n[c] = x->n;
		nd.idx[c] = x->n ? x->idx : collapse(nodes, ch[c], out, next);
	}
	out[me] = nd;
	return me;
}

int bvh_build(struct bvh *b, const struct geom_box *boxes, uint32_t n, uint32_t *perm, uint32_t max_leaf)
{
	return bvh_build_ex(b, boxes, n, perm, max_leaf, false);
}

int bvh_build_ex(struct bvh *b, const struct geom_box *boxes, uint32_t n, uint32_t *perm, uint32_t max_leaf,
		 bool pack)
{
	memset(b, 0, sizeof *b);
	if (n == 0)
		return 0;
	struct bvh_ctx B = { boxes, NULL, perm, NULL, 1, max_leaf ? max_leaf : 1, pack };
	B.cent = malloc((size_t)n * sizeof *B.cent);
	B.nodes = malloc((size_t)2 * n * sizeof *B.nodes);
	if (!B.cent || !B.nodes) {
		free(B.cent);
		free(B.nodes);
		return -1;
	}
	for (uint32_t i = 0; i < n; i++) {
		perm[i] = i;
		B.cent[i] = v3_scale(v3_add(boxes[i].lo, boxes[i].hi), 0.5);
	}
	build_node(&B, 0, 0, n, 0);
	free(B.cent);
	if (cancel_seen()) {
		free(B.nodes);
		return BVH_CANCELLED;
	}
	b->n_nodes = B.n_nodes;
	memcpy(b->root_b, B.nodes[0].b, sizeof b->root_b);
	b->root_idx = B.nodes[0].idx;
	b->root_n = B.nodes[0].n;
	if (!b->root_n) {
		uint32_t cap = (B.n_nodes - 1) / 2; /* interior binary nodes bound the 4-wide ones */
		b->nodes = malloc((size_t)cap * sizeof *b->nodes);
		if (!b->nodes) {
			free(B.nodes);
			return -1;
		}
		uint32_t next = 0;
		collapse(B.nodes, 0, b->nodes, &next);
		if (cancel_seen()) {
			free(B.nodes);
			bvh_free(b);
			return BVH_CANCELLED;
		}
		b->n_nodes4 = next;
		struct bvh4 *fit = realloc(b->nodes, (size_t)next * sizeof *fit);
		if (fit)
			b->nodes = fit;
		b->root_idx = 0;
	}
	free(B.nodes);
	return 0;
}

void bvh_free(struct bvh *b)
{
	if (!b)
		return;
	free(b->nodes);
	memset(b, 0, sizeof *b);
}
