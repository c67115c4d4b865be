/*
 * bvh.c - binned SAH builder (16 bins on each axis over centroid bounds;
 * items may carry test costs, bvh_build_cost),
 * children stored adjacently, bounds rounded outward to float.
 *
 * The builder polls the calling thread's cancel flag (cancel.h) at every
 * node and every CANCEL_STRIDE items of a node's loops; once a poll says
 * true every function returns at once, leaving garbage, and bvh_build_ex
 * frees it and returns BVH_CANCELLED.
 */
#include "common/bvh.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "common/cancel.h"

_Static_assert(BVH_CANCELLED == CANCEL_RETURN, "the builder gives up with the core's value");

#define BVH_BINS 16
/* SAH constants relative to one primitive test */
#define BVH_COST_TRAV 1.0
#define BVH_COST_ISECT 1.0
/* item costs (bvh_build_cost) are in BVH_COST_UNIT parts of BVH_COST_ISECT */

/* Items below this many are built by the thread that reached them; a
 * subtree of more may go to another build thread (bvh_set_threads). */
#define BVH_PAR_GRAIN 4096u
/* Most threads a build uses, whatever the machine says. */
#define BVH_MAX_THREADS 8u
/* Subtrees waiting for a build thread; the thread that finds the stack
 * full builds its subtree itself. */
#define BVH_TASKS 64

/* A node's items' bounds, as the binning of its parent found them: the
 * union of the boxes, of the centroids, and the largest box area. */
struct bvh_span {
	struct geom_box bb, cb;
	double amax;
};

/* A subtree to build: node ni over perm[begin, end). */
struct bvh_task {
	uint32_t ni, begin, end;
	int depth;
	struct bvh_span sp;
};

struct bvh_ctx {
	const struct geom_box *boxes; /* the items' boxes; or NULL and fboxes */
	const float (*fboxes)[6];
	const uint8_t *cost; /* the items' test costs (item_cost); or NULL */
	uint32_t *perm;
	struct bvh_node *nodes;
	atomic_uint n_nodes; /* nodes handed out (any thread) */
	uint32_t max_leaf;
	bool pack;
	/* build threads: a stack of subtrees, the count of threads at work */
	unsigned n_threads;
	pthread_mutex_t mu;
	pthread_cond_t cv;
	struct bvh_task task[BVH_TASKS];
	int n_task, busy;
	atomic_int gave_up; /* some build thread saw its cancel poll say true */
	atomic_int *flag;   /* the calling thread's cancel flag, for the others */
};

/* The float one step below f (not NaN, not -inf): nextafterf(f, -INFINITY)
 * without the call (a node's bounds make six). */
static inline float float_down(float f)
{
	uint32_t u;
	memcpy(&u, &f, sizeof u);
	if (f > 0)
		u--;
	else if (f < 0)
		u++;
	else
		u = 0x80000001u; /* -0 and +0: the negative subnormal */
	memcpy(&f, &u, sizeof f);
	return f;
}

static float round_down(double x)
{
	float f = (float)x;
	if ((double)f > x)
		f = float_down(f);
	return f;
}

static float round_up(double x)
{
	float f = (float)x;
	if ((double)f < x)
		f = -float_down(-f);
	return f;
}

static double box_area(struct geom_box b)
{
	vec3 e = v3_sub(b.hi, b.lo);
	if (e.x < 0 || e.y < 0 || e.z < 0)
		return 0;
	return 2 * (e.x * e.y + e.y * e.z + e.z * e.x);
}

/* geom_box_empty, geom_box_union and geom_box_point, inline (the same
 * values and comparisons) */
#define EMPTY_BOX ((struct geom_box){ { INFINITY, INFINITY, INFINITY }, { -INFINITY, -INFINITY, -INFINITY } })
static inline double mn(double a, double b) { return a < b ? a : b; }
static inline double mx(double a, double b) { return a > b ? a : b; }
#ifdef __SSE2__
/* minpd/maxpd return their second operand unless the first is less /
 * greater: mn and mx exactly */
static inline void box_grow(struct geom_box *r, const struct geom_box *b)
{
	const double *pr = &r->lo.x, *pb = &b->lo.x;
	__m128d lo = _mm_min_pd(_mm_loadu_pd(pr), _mm_loadu_pd(pb));
	__m128d mid = _mm_loadu_pd(pr + 2), bmid = _mm_loadu_pd(pb + 2);
	__m128d mlo = _mm_min_pd(mid, bmid), mhi = _mm_max_pd(mid, bmid);
	__m128d hi = _mm_max_pd(_mm_loadu_pd(pr + 4), _mm_loadu_pd(pb + 4));
	_mm_storeu_pd(&r->lo.x, lo);
	_mm_storeu_pd(&r->lo.z, _mm_move_sd(mhi, mlo)); /* lo.z from the min, hi.x from the max */
	_mm_storeu_pd(&r->hi.y, hi);
}
#else
static inline void box_grow(struct geom_box *r, const struct geom_box *b)
{
	r->lo.x = mn(r->lo.x, b->lo.x), r->lo.y = mn(r->lo.y, b->lo.y), r->lo.z = mn(r->lo.z, b->lo.z);
	r->hi.x = mx(r->hi.x, b->hi.x), r->hi.y = mx(r->hi.y, b->hi.y), r->hi.z = mx(r->hi.z, b->hi.z);
}
#endif
#ifdef __SSE2__
static inline void box_grow_pt(struct geom_box *r, vec3 p)
{
	double *pr = &r->lo.x;
	__m128d pxy = _mm_loadu_pd(&p.x), pz = _mm_set1_pd(p.z);
	__m128d mid = _mm_loadu_pd(pr + 2); /* lo.z, hi.x */
	_mm_storeu_pd(pr, _mm_min_pd(_mm_loadu_pd(pr), pxy));
	__m128d zx = _mm_move_sd(_mm_max_pd(mid, _mm_unpacklo_pd(pz, pxy)), _mm_min_pd(mid, pz));
	_mm_storeu_pd(pr + 2, zx); /* lo.z from the min, hi.x from the max */
	_mm_storeu_pd(pr + 4, _mm_max_pd(_mm_loadu_pd(pr + 4), _mm_unpackhi_pd(pxy, pz)));
}
#else
static inline void box_grow_pt(struct geom_box *r, vec3 p)
{
	r->lo.x = mn(r->lo.x, p.x), r->lo.y = mn(r->lo.y, p.y), r->lo.z = mn(r->lo.z, p.z);
	r->hi.x = mx(r->hi.x, p.x), r->hi.y = mx(r->hi.y, p.y), r->hi.z = mx(r->hi.z, p.z);
}
#endif

/* An item's centroid (recomputed where needed: an array of them would
 * be 24 bytes per item more at the build's peak). */
static inline vec3 cent_of(const struct geom_box *b) { return v3_scale(v3_add(b->lo, b->hi), 0.5); }

/* The bin of centroid coordinate c on an axis binned from lo at scale. */
static inline int bin_of(double c, double lo, double scale)
{
	int k = (int)((c - lo) * scale);
	return k < 0 ? 0 : k >= BVH_BINS ? BVH_BINS - 1 : k;
}

/* Item it's box: a pointer into the doubles, or its float box in *tmp. */
static inline const struct geom_box *item_box(const struct bvh_ctx *B, uint32_t it, struct geom_box *tmp)
{
	if (B->boxes)
		return &B->boxes[it];
	const float *f = B->fboxes[it];
	tmp->lo = v3(f[0], f[1], f[2]);
	tmp->hi = v3(f[3], f[4], f[5]);
	return tmp;
}

/* The span of perm[begin, end), item by item. */
static void span_of(const struct bvh_ctx *B, uint32_t begin, uint32_t end, struct bvh_span *sp)
{
	sp->bb = EMPTY_BOX;
	sp->cb = EMPTY_BOX;
	sp->amax = 0;
	for (uint32_t i = begin; i < end; i++) {
		if (cancel_poll_every(i))
			return;
		struct geom_box tmp;
		const struct geom_box *ib = item_box(B, B->perm[i], &tmp);
		box_grow(&sp->bb, ib);
		box_grow_pt(&sp->cb, cent_of(ib));
		sp->amax = mx(sp->amax, box_area(*ib));
	}
}

/* Adds item it to span *sp. */
static inline void span_add(const struct bvh_ctx *B, struct bvh_span *sp, uint32_t it)
{
	struct geom_box tmp;
	const struct geom_box *ib = item_box(B, it, &tmp);
	box_grow(&sp->bb, ib);
	box_grow_pt(&sp->cb, cent_of(ib));
	sp->amax = mx(sp->amax, box_area(*ib));
}

/*
 * Partitions perm[begin, end) so that the items whose centroid falls in a
 * bin below split_bin on axis come first (the order a swap from both ends
 * makes); returns the first of the others. The spans of both sides come
 * out in *left and *right. With big > 0 the test is instead "box area
 * above big" (the big items first).
 */
static uint32_t partition(struct bvh_ctx *B, uint32_t begin, uint32_t end, int axis, double lo,
			  double scale, int split_bin, double big, struct bvh_span *left, struct bvh_span *right)
{
	uint32_t i = begin, j = end;
	left->bb = left->cb = right->bb = right->cb = EMPTY_BOX;
	left->amax = right->amax = 0;
	while (i < j) {
		if (cancel_poll_every(i))
			return i;
		uint32_t it = B->perm[i];
		struct geom_box tmp;
		const struct geom_box *ib = item_box(B, it, &tmp);
		bool first = big > 0 ? box_area(*ib) > big : bin_of(v3_comp(cent_of(ib), axis), lo, scale) < split_bin;
		if (first) {
			span_add(B, left, it);
			i++;
		} else {
			span_add(B, right, it);
			j--;
			B->perm[i] = B->perm[j];
			B->perm[j] = it;
		}
	}
	return i;
}

/* One bin of one axis: its items' boxes, count and summed cost (64 bits:
 * exact for any count of items at any cost up to 255). */
struct bvh_bin {
	struct geom_box b;
	uint32_t n;
	uint64_t c;
};

/* Item it's test cost in BVH_COST_UNIT parts of BVH_COST_ISECT (the unit itself without costs). */
static inline uint32_t item_cost(const struct bvh_ctx *B, uint32_t it)
{
	return B->cost ? B->cost[it] : BVH_COST_UNIT;
}

static void build_node(struct bvh_ctx *B, uint32_t ni, uint32_t begin, uint32_t end, int depth,
		       const struct bvh_span *span);

/* Hands the subtree to another build thread when one may take it; false:
 * the caller builds it. */
static bool offer(struct bvh_ctx *B, uint32_t ni, uint32_t begin, uint32_t end, int depth,
		  const struct bvh_span *sp)
{
	if (B->n_threads < 2 || end - begin < BVH_PAR_GRAIN)
		return false;
	bool taken = false;
	pthread_mutex_lock(&B->mu);
	if (B->n_task < BVH_TASKS && B->n_task + B->busy < (int)B->n_threads + 1) {
		B->task[B->n_task++] = (struct bvh_task){ ni, begin, end, depth, *sp };
		pthread_cond_signal(&B->cv);
		taken = true;
	}
	pthread_mutex_unlock(&B->mu);
	return taken;
}

/*
 * The best centroid split of one axis' bins (split before bin k: bins
 * below k on the left): lowers *best and sets *best_bin when a split
 * costs less, and then says true. Only splits right after a non-empty
 * bin are priced: a split after an empty bin has the same two sides, and
 * so the same cost, as the one before that bin, which comes first and
 * wins the tie (the costs are compared with <).
 */
static bool best_split(const struct bvh_bin *bn, double *best, int *best_bin)
{
	int used[BVH_BINS], nu = 0;
	for (int k = 0; k < BVH_BINS; k++)
		if (bn[k].n)
			used[nu++] = k;
	/* right_cost[u]: the bins from used[u] up */
	double right_cost[BVH_BINS];
	struct geom_box acc = EMPTY_BOX;
	uint64_t cnt = 0;
	for (int u = nu - 1; u > 0; u--) {
		box_grow(&acc, &bn[used[u]].b);
		cnt += bn[used[u]].c;
		right_cost[u] = box_area(acc) * cnt;
	}
	bool better = false;
	acc = EMPTY_BOX;
	cnt = 0;
	for (int u = 0; u + 1 < nu; u++) { /* split before bin used[u] + 1 */
		box_grow(&acc, &bn[used[u]].b);
		cnt += bn[used[u]].c;
		double c = box_area(acc) * cnt + right_cost[u + 1];
		if (c < *best)
			*best = c, *best_bin = used[u] + 1, better = true;
	}
	return better;
}

/*
 * Builds node ni over perm[begin, end), whose span is *span. Recursion
 * depth < BVH_MAX_DEPTH. Returns at once, leaving garbage, when a cancel
 * poll says true. Every decision is the one the item-by-item builder of
 * before made (the bins, spans and costs are the same doubles: min and
 * max are exact in any order), so the tree does not depend on the threads.
 */
static void build_node(struct bvh_ctx *B, uint32_t ni, uint32_t begin, uint32_t end, int depth,
		       const struct bvh_span *span)
{
	if (cancel_poll())
		return;
	struct geom_box bb = span->bb, cb = span->cb;
	struct bvh_node *nd = &B->nodes[ni];
	nd->b[0] = round_down(bb.lo.x), nd->b[1] = round_down(bb.lo.y), nd->b[2] = round_down(bb.lo.z);
	nd->b[3] = round_up(bb.hi.x), nd->b[4] = round_up(bb.hi.y), nd->b[5] = round_up(bb.hi.z);
	uint32_t n = end - begin;
	if (n <= 1 || depth >= BVH_MAX_DEPTH - 1 || (B->pack && n <= B->max_leaf))
		goto leaf;

	/* one pass bins the items on every axis their centroids spread along */
	static const struct bvh_bin empty_bin = { { { INFINITY, INFINITY, INFINITY }, { -INFINITY, -INFINITY, -INFINITY } },
						  0, 0 };
	struct bvh_bin bin[3][BVH_BINS];
	double lo3[3], scale3[3];
	int live[3], n_live = 0;
	for (int axis = 0; axis < 3; axis++) {
		double lo = v3_comp(cb.lo, axis), ext = v3_comp(cb.hi, axis) - lo;
		if (!(ext > 0))
			continue;
		lo3[axis] = lo;
		scale3[axis] = BVH_BINS / ext;
		live[n_live++] = axis;
		for (int k = 0; k < BVH_BINS; k++)
			bin[axis][k] = empty_bin;
	}
	uint64_t ctot = 0; /* the items' summed cost (exact: integers, in any order) */
	for (uint32_t i = begin; i < end; i++) {
		if (cancel_poll_every(i))
			return;
		uint32_t it = B->perm[i], ci = item_cost(B, it);
		struct geom_box tmp;
		const struct geom_box *ib = item_box(B, it, &tmp);
		vec3 c = cent_of(ib);
		ctot += ci;
		for (int l = 0; l < n_live; l++) {
			int axis = live[l];
			struct bvh_bin *bk = &bin[axis][bin_of(v3_comp(c, axis), lo3[axis], scale3[axis])];
			bk->n++;
			bk->c += ci;
			box_grow(&bk->b, ib);
		}
	}
	double best = INFINITY;
	int best_axis = -1, best_bin = 0;
	for (int l = 0; l < n_live; l++)
		if (best_split(bin[live[l]], &best, &best_bin))
			best_axis = live[l];
	/* Also try setting the big items apart (a floor under a sphereflake):
	 * centroid bins cannot separate them when their centres sit among the
	 * small ones. Only when some item is big enough for the smallest
	 * fraction (else every try puts all items on one side). */
	static const double big_frac[3] = { 0.5, 0.2, 0.05 };
	int best_big = -1;
	double node_area = box_area(bb);
	if (span->amax > big_frac[2] * node_area) {
		struct geom_box b1[3], b2[3];
		uint32_t n1[3] = { 0, 0, 0 };
		uint64_t c1[3] = { 0, 0, 0 };
		double thr[3];
		for (int q = 0; q < 3; q++) {
			b1[q] = b2[q] = EMPTY_BOX;
			thr[q] = big_frac[q] * node_area;
		}
		for (uint32_t i = begin; i < end; i++) {
			if (cancel_poll_every(i))
				return;
			uint32_t it = B->perm[i];
			struct geom_box tmp;
			const struct geom_box *ib = item_box(B, it, &tmp);
			double a = box_area(*ib);
			uint32_t ci = item_cost(B, it);
			for (int q = 0; q < 3; q++) {
				if (a > thr[q])
					box_grow(&b1[q], ib), n1[q]++, c1[q] += ci;
				else
					box_grow(&b2[q], ib);
			}
		}
		for (int q = 0; q < 3; q++) {
			if (n1[q] == 0 || n1[q] == n)
				continue;
			double c = box_area(b1[q]) * c1[q] + box_area(b2[q]) * (ctot - c1[q]);
			if (c < best)
				best = c, best_big = q;
		}
	}
	uint32_t mid;
	struct bvh_span left, right;
	bool spans = false; /* left and right are the halves' spans */
	if (best_big >= 0) {
		/* partitioned before the leaf test: a leaf keeps this order */
		mid = partition(B, begin, end, 0, 0, 0, 0, big_frac[best_big] * node_area, &left, &right);
		spans = true;
		double split_cost = BVH_COST_TRAV * node_area + BVH_COST_ISECT * best / BVH_COST_UNIT;
		if (n <= B->max_leaf && BVH_COST_ISECT * node_area * ctot / BVH_COST_UNIT <= split_cost)
			goto leaf;
	} else if (best_axis < 0) { /* every centroid in one place */
		if (n <= B->max_leaf)
			goto leaf;
		mid = begin + n / 2;
	} else {
		double area = box_area(bb);
		double split_cost = BVH_COST_TRAV * area + BVH_COST_ISECT * best / BVH_COST_UNIT;
		double leaf_cost = BVH_COST_ISECT * area * ctot / BVH_COST_UNIT;
		if (n <= B->max_leaf && leaf_cost <= split_cost)
			goto leaf;
		mid = partition(B, begin, end, best_axis, lo3[best_axis], scale3[best_axis], best_bin, 0, &left,
				&right);
		spans = true;
		if (mid == begin || mid == end) {
			mid = begin + n / 2;
			spans = false;
		}
	}
	if (cancel_seen())
		return;
	if (!spans) {
		span_of(B, begin, mid, &left);
		span_of(B, mid, end, &right);
		if (cancel_seen())
			return;
	}
	uint32_t c = atomic_fetch_add_explicit(&B->n_nodes, 2, memory_order_relaxed);
	nd->idx = c;
	nd->n = 0;
	if (!offer(B, c, begin, mid, depth + 1, &left))
		build_node(B, c, begin, mid, depth + 1, &left);
	build_node(B, c + 1, mid, end, depth + 1, &right);
	return;
leaf:
	nd->idx = begin;
	nd->n = n;
}

/* A build thread: takes subtrees off the stack until none is left and no
 * thread is at work (which could offer more). */
static void *build_thread(void *arg)
{
	struct bvh_ctx *B = arg;
	struct cancel_scope saved;
	cancel_enter(B->flag, &saved);
	pthread_mutex_lock(&B->mu);
	for (;;) {
		while (B->n_task == 0 && B->busy > 0)
			pthread_cond_wait(&B->cv, &B->mu);
		if (B->n_task == 0)
			break;
		struct bvh_task t = B->task[--B->n_task];
		B->busy++;
		pthread_mutex_unlock(&B->mu);
		build_node(B, t.ni, t.begin, t.end, t.depth, &t.sp);
		if (cancel_seen())
			atomic_store(&B->gave_up, 1);
		pthread_mutex_lock(&B->mu);
		B->busy--;
		if (B->busy == 0 && B->n_task == 0)
			pthread_cond_broadcast(&B->cv);
	}
	pthread_cond_broadcast(&B->cv);
	pthread_mutex_unlock(&B->mu);
	cancel_leave(&saved);
	return NULL;
}

static atomic_uint build_threads; /* 0: one per online processor */

void bvh_set_threads(unsigned n) { atomic_store(&build_threads, n); }

static unsigned threads_to_use(void)
{
	unsigned n = atomic_load(&build_threads);
	if (n == 0) {
		long c = sysconf(_SC_NPROCESSORS_ONLN);
		n = c > 0 ? (unsigned)c : 1;
	}
	return n > BVH_MAX_THREADS ? BVH_MAX_THREADS : n;
}

/* Builds the whole tree from the root over B->perm, on as many threads as
 * there are and the tree's size makes worth it. */
static void build_all(struct bvh_ctx *B, uint32_t n)
{
	struct bvh_span root;
	span_of(B, 0, n, &root);
	if (cancel_seen())
		return;
	B->n_threads = n >= 2 * BVH_PAR_GRAIN ? threads_to_use() : 1;
	if (B->n_threads < 2) {
		build_node(B, 0, 0, n, 0, &root);
		return;
	}
	pthread_mutex_init(&B->mu, NULL);
	pthread_cond_init(&B->cv, NULL);
	B->flag = cancel_cur.flag;
	B->n_task = 1;
	B->busy = 0;
	B->task[0] = (struct bvh_task){ 0, 0, n, 0, root };
	pthread_t th[BVH_MAX_THREADS];
	unsigned started = 0;
	for (unsigned k = 1; k < B->n_threads; k++)
		if (pthread_create(&th[started], NULL, build_thread, B) == 0)
			started++;
	build_thread(B); /* this thread builds too (alone, if none started) */
	for (unsigned k = 0; k < started; k++)
		pthread_join(th[k], NULL);
	if (atomic_load(&B->gave_up) && !cancel_seen())
		cancel_note(); /* another thread saw the flag: so does this one */
	pthread_cond_destroy(&B->cv);
	pthread_mutex_destroy(&B->mu);
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

static int build(struct bvh *b, const struct geom_box *boxes, float (*fboxes)[6], uint32_t n, uint32_t *perm,
		 uint32_t max_leaf, bool pack, const uint8_t *cost)
{
	memset(b, 0, sizeof *b);
	if (n == 0)
		return 0;
	struct bvh_ctx B;
	memset(&B, 0, sizeof B);
	B.boxes = boxes;
	B.fboxes = fboxes;
	B.cost = cost;
	B.perm = perm;
	atomic_init(&B.n_nodes, 1);
	atomic_init(&B.gave_up, 0);
	B.max_leaf = max_leaf ? max_leaf : 1;
	B.pack = pack;
	B.nodes = malloc((size_t)2 * n * sizeof *B.nodes);
	if (!B.nodes) {
		free(fboxes);
		return -1;
	}
	for (uint32_t i = 0; i < n; i++)
		perm[i] = i;
	build_all(&B, n);
	free(fboxes); /* bvh_build_f's: the collapse below reads the binary nodes only */
	if (cancel_seen()) {
		free(B.nodes);
		return BVH_CANCELLED;
	}
	b->n_nodes = atomic_load(&B.n_nodes);
	memcpy(b->root_b, B.nodes[0].b, sizeof b->root_b);
	b->root_idx = B.nodes[0].idx;
	b->root_n = B.nodes[0].n;
	if (!b->root_n) {
		uint32_t cap = (b->n_nodes - 1) / 2; /* interior binary nodes bound the 4-wide ones */
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

int bvh_build_ex(struct bvh *b, const struct geom_box *boxes, uint32_t n, uint32_t *perm, uint32_t max_leaf,
		 bool pack)
{
	return build(b, boxes, NULL, n, perm, max_leaf, pack, NULL);
}

int bvh_build_cost(struct bvh *b, const struct geom_box *boxes, uint32_t n, uint32_t *perm, uint32_t max_leaf,
		   const uint8_t *cost)
{
	return build(b, boxes, NULL, n, perm, max_leaf, false, cost);
}

int bvh_build_f(struct bvh *b, float (*boxes)[6], uint32_t n, uint32_t *perm, uint32_t max_leaf, bool pack)
{
	if (n == 0) {
		free(boxes);
		memset(b, 0, sizeof *b);
		return 0;
	}
	return build(b, NULL, boxes, n, perm, max_leaf, pack, NULL);
}

/* A child slot of a bvh4 or bvh8 node, while bvh_make8 gathers them. */
struct slot8 {
	float lo[3], hi[3];
	uint32_t idx, n;
};

/* Child c of nd is used (a leaf or a subtree): unused slots are NaN. */
static bool used4(const struct bvh4 *nd, int c) { return nd->lo[0][c] == nd->lo[0][c]; }

static int count4(const struct bvh4 *nd)
{
	int k = 0;
	for (int c = 0; c < 4; c++)
		k += used4(nd, c);
	return k;
}

/* nd's used children into s; returns how many. */
static int slots4(const struct bvh4 *nd, struct slot8 *s)
{
	int k = 0;
	for (int c = 0; c < 4; c++) {
		if (!used4(nd, c))
			continue;
		for (int a = 0; a < 3; a++) {
			s[k].lo[a] = nd->lo[a][c];
			s[k].hi[a] = nd->hi[a][c];
		}
		s[k].idx = nd->idx[c];
		s[k++].n = nd->n[c];
	}
	return k;
}

/*
 * Node of bvh4 node ni and its subtree, into out from *next. The children
 * of ni are taken, then the subtree child of largest area is replaced by
 * its own children while they fit in eight (collapse()'s rule, one level
 * up). The order of the slots does not matter to a hit (CANONICAL TIES).
 */
static uint32_t widen8(const struct bvh4 *in, uint32_t ni, struct bvh8 *out, uint32_t *next)
{
	uint32_t me = (*next)++;
	if (cancel_seen() || cancel_poll_every(me)) /* as collapse(): the caller checks cancel_seen */
		return me;
	struct slot8 s[8 + 4];
	int k = slots4(&in[ni], s);
	for (;;) {
		int best = -1;
		double best_area = -1;
		for (int c = 0; c < k; c++) {
			if (s[c].n)
				continue;
			if (k - 1 + count4(&in[s[c].idx]) > 8)
				continue;
			struct geom_box bx = { v3(s[c].lo[0], s[c].lo[1], s[c].lo[2]),
					       v3(s[c].hi[0], s[c].hi[1], s[c].hi[2]) };
			double a = box_area(bx);
			if (a > best_area)
				best_area = a, best = c;
		}
		if (best < 0)
			break;
		struct slot8 sub[4];
		int ns = slots4(&in[s[best].idx], sub);
		s[best] = sub[0];
		for (int j = 1; j < ns; j++)
			s[k++] = sub[j];
	}
	struct bvh8 nd;
	for (int c = k; c < 8; c++) { /* unused */
		for (int a = 0; a < 3; a++)
			nd.lo[a][c] = nd.hi[a][c] = NAN;
		nd.idx[c] = 0;
		nd.n[c] = 0;
	}
	for (int c = 0; c < k; c++) {
		for (int a = 0; a < 3; a++) {
			nd.lo[a][c] = s[c].lo[a];
			nd.hi[a][c] = s[c].hi[a];
		}
		nd.n[c] = s[c].n;
		nd.idx[c] = s[c].n ? s[c].idx : widen8(in, s[c].idx, out, next);
	}
	out[me] = nd;
	return me;
}

int bvh_make8(struct bvh *b)
{
	if (!b->n_nodes4 || b->nodes8)
		return 0;
	struct bvh8 *out = malloc((size_t)b->n_nodes4 * sizeof *out);
	if (!out)
		return -1;
	uint32_t next = 0;
	widen8(b->nodes, 0, out, &next);
	if (cancel_seen()) {
		free(out);
		return BVH_CANCELLED;
	}
	struct bvh8 *fit = realloc(out, (size_t)next * sizeof *fit);
	b->nodes8 = fit ? fit : out;
	b->n_nodes8 = next;
	return 0;
}

void bvh_free(struct bvh *b)
{
	if (!b)
		return;
	free(b->nodes);
	free(b->nodes8);
	memset(b, 0, sizeof *b);
}
