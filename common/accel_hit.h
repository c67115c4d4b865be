/*
 * accel_hit.h - bvh_hit, the single ray's closest-hit traversal of a
 * group's tree (accel.c), written once and included once per node test
 * (WIDE NODES IN AVX2, accel_box.h): with SSE (struct ray4, node8_hit on
 * WIDE NODES or node4_hit) and, on x86-64, with AVX2 (struct ray8,
 * node8_hit_avx2) in functions compiled for AVX2. The node tests give the
 * same masks and entry distances bit for bit, so both walk the same nodes
 * in the same order. The includer defines, and this file undefines:
 *   BVH_HIT    the function's name;
 *   BVH_ATTR   its attributes beyond always_inline (nothing, or a target);
 *   BVH_Q      the ray's box constants' type, BVH_SPAN a t broadcast to the
 *              node test's lanes and BVH_SPAN_OF(t) one made;
 *   BVH_NODE(nodes8, nodes, idx, q, oct, tmin, tmax, tn, m, ci, cn)  the
 *              test of node idx: its mask into m, the entry distances into
 *              tn[0..8), its idx[] and n[] into ci and cn.
 *
 * The traversal of g's bounded references: nearest child first, subtrees
 * behind the closest hit so far popped and dropped. Same contract as
 * ref_test. chunked: g has big leaves (group.big_leaf), tested
 * ACCEL_LEAF_CHUNK references at a time (CANCELLATION); a constant, so the
 * common copies have no test (it cost 1% of single rays).
 */
static inline __attribute__((always_inline)) BVH_ATTR bool BVH_HIT(const struct accel *A, const struct group *g,
								     struct trace *r, struct cand *best, const BVH_Q *qp,
								     const uint32_t oct, const bool chunked)
{
	bool found = false;
	const struct bvh4 *nodes = g->bvh.nodes;
	const struct bvh8 *nodes8 = g->bvh.nodes8; /* WIDE NODES: used when there */
	const BVH_Q q = *qp;
	const BVH_SPAN tmin = BVH_SPAN_OF(box_tmin(r->tmin * q.tscale));
	float tmax = box_tmax(r->tmax * q.tscale);
	BVH_SPAN tmax4 = BVH_SPAN_OF(tmax);
	struct {
		uint32_t idx, n;
		float t;
	} stack[7 * BVH_MAX_DEPTH + 8]; /* up to 7 children a level (WIDE NODES), and a chunk's rest */
	int sp = 0;
	uint32_t idx = 0, n = 0;
	uint32_t polls = ACCEL_POLL_POPS;
	struct tri1 q1; /* TRIANGLE PRE-TEST, set up at the first block */
	bool q1_ready = false;
	for (;;) {
		if (n) {
			if (n & LEAF_BLOCK) {
				found |= block_hit(g, &g->tblk[idx], n & ~LEAF_BLOCK, r, best, &q1, &q1_ready);
			} else {
				if (chunked && n > ACCEL_LEAF_CHUNK) { /* CANCELLATION: the rest later */
					stack[sp].idx = idx + ACCEL_LEAF_CHUNK;
					stack[sp].n = n - ACCEL_LEAF_CHUNK;
					stack[sp++].t = 0;
					n = ACCEL_LEAF_CHUNK;
				}
				for (uint32_t k = 0; k < n; k++)
					found |= ref_test(A, g, group_ref(g, idx + k), r, best, false);
			}
			tmax = box_tmax(r->tmax * q.tscale);
			tmax4 = BVH_SPAN_OF(tmax);
		} else {
			float tn[8];
			int m;
			const uint32_t *ci, *cn; /* the node's idx[] and n[] */
			BVH_NODE(nodes8, nodes, idx, &q, oct, tmin, tmax4, tn, m, ci, cn);
			/* ONE OR TWO children met take one path (docs/performance.md,
			 * round 22): the second child's entry is written either way
			 * and kept only when there is one. The swap stays a branch:
			 * as masks it put the compare of the reloaded entry distances
			 * on the way to the next node (13% slower). */
			unsigned m2 = (unsigned)m & ((unsigned)m - 1); /* m without its lowest child */
			if (m && !(m2 & (m2 - 1))) {
				int c0 = __builtin_ctz((unsigned)m), c1 = __builtin_ctz(m2 ? m2 : (unsigned)m);
				bool swap = tn[c0] > tn[c1]; /* the nearer first; ties keep slot order */
				int a = swap ? c1 : c0, b = swap ? c0 : c1;
				stack[sp].idx = ci[b]; /* a second child's entry, kept only when there is one */
				stack[sp].n = cn[b];
				stack[sp].t = tn[b];
				sp += m2 != 0;
				idx = ci[a];
				n = cn[a];
				continue;
			}
			if (m) { /* nearest first; the others pushed farthest first */
				int cs[8], k = children_by_entry(m, tn, cs);
				for (int j = k - 1; j >= 1; j--) {
					stack[sp].idx = ci[cs[j]];
					stack[sp].n = cn[cs[j]];
					stack[sp++].t = tn[cs[j]];
				}
				idx = ci[cs[0]];
				n = cn[cs[0]];
				continue;
			}
		}
		if (__builtin_expect(--polls == 0, 0)) { /* CANCELLATION */
			polls = ACCEL_POLL_POPS;
			if (cancel_poll())
				return found;
		}
		/* pop the next subtree still in front of the closest hit */
		for (;;) {
			if (sp == 0)
				return found;
			sp--;
			if (stack[sp].t <= tmax)
				break;
		}
		idx = stack[sp].idx;
		n = stack[sp].n;
	}
}

#undef BVH_HIT
#undef BVH_ATTR
#undef BVH_Q
#undef BVH_SPAN
#undef BVH_SPAN_OF
#undef BVH_NODE
