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

/* Items below this many are built by the thread that reached them; a
 * subtree of more may go to another build thread (bvh_set_threads). */
#define BVH_PAR_GRAIN 4096u
/* Most threads a build uses, whatever the machine says. */
#define BVH_MAX_THREADS 8u
/* Subtrees waiting for a build thread; the thread that finds the stack
 * full builds its subtree itself. */
#define BVH_TASKS 64

/*
 * Four floats, lanes x y z and a spare: an SSE register where there is
 * one, else a plain array (the same values: every operation below is one
 * IEEE single operation per lane, or a min/max that picks an operand).
 */
#ifdef __SSE2__
typedef __m128 f4;
static inline f4 f4_load(const float *p) { return _mm_load_ps(p); }
static inline void f4_store(float *p, f4 a) { _mm_store_ps(p, a); }
static inline f4 f4_set1(float a) { return _mm_set1_ps(a); }
static inline f4 f4_add(f4 a, f4 b) { return _mm_add_ps(a, b); }
static inline f4 f4_sub(f4 a, f4 b) { return _mm_sub_ps(a, b); }
static inline f4 f4_mul(f4 a, f4 b) { return _mm_mul_ps(a, b); }
/* minps/maxps: the second operand unless the first is less / greater */
static inline f4 f4_min(f4 a, f4 b) { return _mm_min_ps(a, b); }
static inline f4 f4_max(f4 a, f4 b) { return _mm_max_ps(a, b); }
/* lane 3 set to 0 (where an item record keeps its index) */
static inline f4 f4_xyz(f4 a) { return _mm_and_ps(a, _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0))); }
/* truncated to int: the lanes are in [0, BVH_BINS - 1] */
static inline void f4_bins(f4 a, int32_t *k) { _mm_store_si128((__m128i *)(void *)k, _mm_cvttps_epi32(a)); }
#else
typedef struct {
	float v[4];
} f4;
static inline f4 f4_load(const float *p) { f4 r; memcpy(r.v, p, sizeof r.v); return r; }
static inline void f4_store(float *p, f4 a) { memcpy(p, a.v, sizeof a.v); }
static inline f4 f4_set1(float a) { return (f4){ { a, a, a, a } }; }
#define F4_OP(name, expr)                                   \
	static inline f4 name(f4 a, f4 b)                   \
	{                                                   \
		f4 r;                                       \
		for (int l = 0; l < 4; l++)                 \
			r.v[l] = expr;                      \
		return r;                                   \
	}
F4_OP(f4_add, a.v[l] + b.v[l])
F4_OP(f4_sub, a.v[l] - b.v[l])
F4_OP(f4_mul, a.v[l] * b.v[l])
F4_OP(f4_min, a.v[l] < b.v[l] ? a.v[l] : b.v[l])
F4_OP(f4_max, a.v[l] > b.v[l] ? a.v[l] : b.v[l])
static inline f4 f4_xyz(f4 a) { a.v[3] = 0; return a; }
static inline void f4_bins(f4 a, int32_t *k) { for (int l = 0; l < 4; l++) k[l] = (int32_t)a.v[l]; }
#endif

/*
 * An item as the builder reads it (32 bytes, kept in leaf order beside
 * perm, so the builder reads and swaps them in place instead of reaching
 * through perm): its box rounded outward to float (a node's float bounds
 * are then the union of its items', the very floats that rounding the
 * union of the double boxes outward gives: rounding is monotonic), the
 * item's index in lo[3] (its bits) and the box's area in hi[3].
 */
struct bvh_rec {
	_Alignas(16) float lo[4];
	float hi[4];
};

/* A node's items' bounds: the union of the boxes (lanes x y z), of the
 * centroids, and the largest box area. */
struct bvh_span {
	f4 blo, bhi, clo, chi;
	float amax;
};

/* A subtree to build: node ni over perm[begin, end). */
struct bvh_task {
	struct bvh_span sp;
	uint32_t ni, begin, end;
	int depth;
};

struct bvh_ctx {
	struct bvh_rec *rec; /* the items, in the order of perm */
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
 * without the call. */
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

static inline float round_down(double x)
{
	float f = (float)x;
	if ((double)f > x)
		f = float_down(f);
	return f;
}

static inline float round_up(double x)
{
	float f = (float)x;
	if ((double)f < x)
		f = -float_down(-f);
	return f;
}

/* The surface area of the box lo..hi (lanes x y z), 0 when empty; in
 * double (the SAH's costs). */
static double f4_area(f4 lo, f4 hi)
{
	float l[4], h[4];
	f4_store(l, lo);
	f4_store(h, hi);
	double ex = (double)h[0] - l[0], ey = (double)h[1] - l[1], ez = (double)h[2] - l[2];
	if (ex < 0 || ey < 0 || ez < 0)
		return 0;
	return 2 * (ex * ey + ey * ez + ez * ex);
}

static inline void span_empty(struct bvh_span *sp)
{
	sp->blo = sp->clo = f4_set1(INFINITY);
	sp->bhi = sp->chi = f4_set1(-INFINITY);
	sp->amax = 0;
}

/* Record r's box (lane 3 zero) and centroid (the halves added: no
 * overflow). */
static inline void rec_get(const struct bvh_rec *r, f4 *lo, f4 *hi, f4 *c)
{
	*lo = f4_xyz(f4_load(r->lo));
	*hi = f4_xyz(f4_load(r->hi));
	f4 half = f4_set1(0.5f);
	*c = f4_add(f4_mul(*lo, half), f4_mul(*hi, half));
}

static inline void span_add(struct bvh_span *sp, const struct bvh_rec *r, f4 lo, f4 hi, f4 c)
{
	sp->blo = f4_min(sp->blo, lo);
	sp->bhi = f4_max(sp->bhi, hi);
	sp->clo = f4_min(sp->clo, c);
	sp->chi = f4_max(sp->chi, c);
	sp->amax = r->hi[3] > sp->amax ? r->hi[3] : sp->amax;
}

/* The bins of centroid c on the three axes, binned from lo at scale
 * (an axis of scale 0 puts everything in bin 0). NaN (inf times 0) goes
 * to bin 0: maxps gives its second operand then. */
static inline void bins_of(f4 c, f4 lo, f4 scale, int32_t *k)
{
	f4 v = f4_mul(f4_sub(c, lo), scale);
	v = f4_min(f4_max(v, f4_set1(0)), f4_set1(BVH_BINS - 1));
	f4_bins(v, k);
}

/* The span of rec[begin, end), item by item. */
static void span_of(const struct bvh_ctx *B, uint32_t begin, uint32_t end, struct bvh_span *sp)
{
	span_empty(sp);
	for (uint32_t i = begin; i < end; i++) {
		if (cancel_poll_every(i))
			return;
		f4 lo, hi, c;
		rec_get(&B->rec[i], &lo, &hi, &c);
		span_add(sp, &B->rec[i], lo, hi, c);
	}
}

/*
 * Partitions rec[begin, end) so that the items whose centroid falls in a
 * bin below split_bin on axis come first (the order a swap from both ends
 * makes); returns the first of the others. The spans of both sides come
 * out in *left and *right. With big > 0 the test is instead "box area
 * above big" (the big items first).
 */
static uint32_t partition(struct bvh_ctx *B, uint32_t begin, uint32_t end, int axis, f4 clo, f4 scale,
			  int split_bin, double big, struct bvh_span *left, struct bvh_span *right)
{
	uint32_t i = begin, j = end;
	struct bvh_rec *rec = B->rec;
	span_empty(left);
	span_empty(right);
	while (i < j) {
		if (cancel_poll_every(i))
			return i;
		f4 lo, hi, c;
		rec_get(&rec[i], &lo, &hi, &c);
		bool first;
		if (big > 0) {
			first = rec[i].hi[3] > big;
		} else {
			_Alignas(16) int32_t k[4];
			bins_of(c, clo, scale, k);
			first = k[axis] < split_bin;
		}
		if (first) {
			span_add(left, &rec[i], lo, hi, c);
			i++;
		} else {
			span_add(right, &rec[i], lo, hi, c);
			j--;
			struct bvh_rec t = rec[i];
			rec[i] = rec[j];
			rec[j] = t;
		}
	}
	return i;
}

/* One bin of one axis: its items' boxes and count. */
struct bvh_bin {
	f4 lo, hi;
	uint32_t n;
};

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
		B->task[B->n_task++] = (struct bvh_task){ *sp, ni, begin, end, depth };
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
static bool best_split(const struct bvh_bin *bn, int nbins, double *best, int *best_bin)
{
	int used[BVH_BINS], nu = 0;
	for (int k = 0; k < nbins; k++)
		if (bn[k].n)
			used[nu++] = k;
	/* right_cost[u]: the bins from used[u] up */
	double right_cost[BVH_BINS];
	f4 alo = f4_set1(INFINITY), ahi = f4_set1(-INFINITY);
	uint32_t cnt = 0;
	for (int u = nu - 1; u > 0; u--) {
		alo = f4_min(alo, bn[used[u]].lo);
		ahi = f4_max(ahi, bn[used[u]].hi);
		cnt += bn[used[u]].n;
		right_cost[u] = f4_area(alo, ahi) * cnt;
	}
	bool better = false;
	alo = f4_set1(INFINITY), ahi = f4_set1(-INFINITY);
	cnt = 0;
	for (int u = 0; u + 1 < nu; u++) { /* split before bin used[u] + 1 */
		alo = f4_min(alo, bn[used[u]].lo);
		ahi = f4_max(ahi, bn[used[u]].hi);
		cnt += bn[used[u]].n;
		double c = f4_area(alo, ahi) * cnt + right_cost[u + 1];
		if (c < *best)
			*best = c, *best_bin = used[u] + 1, better = true;
	}
	return better;
}

/*
 * Builds node ni over rec[begin, end), whose span is *span. Recursion
 * depth < BVH_MAX_DEPTH. Returns at once, leaving garbage, when a cancel
 * poll says true. Every decision depends on the node's items and their
 * order only (which its parent's partition made), never on which thread
 * builds it, so the tree does not depend on the threads.
 */
static void build_node(struct bvh_ctx *B, uint32_t ni, uint32_t begin, uint32_t end, int depth,
		       const struct bvh_span *span)
{
	if (cancel_poll())
		return;
	struct bvh_node *nd = &B->nodes[ni];
	{
		_Alignas(16) float l[4], h[4];
		f4_store(l, span->blo);
		f4_store(h, span->bhi);
		memcpy(nd->b, l, 3 * sizeof(float));
		memcpy(nd->b + 3, h, 3 * sizeof(float));
	}
	uint32_t n = end - begin;
	if (n <= 1 || depth >= BVH_MAX_DEPTH - 1 || (B->pack && n <= B->max_leaf))
		goto leaf;

	/* one pass bins the items on all three axes */
	struct bvh_bin bin[3][BVH_BINS];
	const struct bvh_rec *rec = B->rec;
	_Alignas(16) float clo[4], chi[4], sc[4];
	f4_store(clo, span->clo);
	f4_store(chi, span->chi);
	int live[3], n_live = 0;
	for (int axis = 0; axis < 3; axis++) {
		float ext = chi[axis] - clo[axis];
		sc[axis] = 0;
		if (!(ext > 0))
			continue;
		sc[axis] = BVH_BINS / ext;
		live[n_live++] = axis;
	}
	sc[3] = 0;
	f4 lo4 = span->clo, scale = f4_load(sc);
	for (int a = 0; a < 3; a++)
		for (int k = 0; k < BVH_BINS; k++)
			bin[a][k] = (struct bvh_bin){ f4_set1(INFINITY), f4_set1(-INFINITY), 0 };
	for (uint32_t i = begin; i < end; i++) {
		if (cancel_poll_every(i))
			return;
		f4 lo, hi, c;
		rec_get(&rec[i], &lo, &hi, &c);
		_Alignas(16) int32_t k[4];
		bins_of(c, lo4, scale, k);
		struct bvh_bin *b0 = &bin[0][k[0]], *b1 = &bin[1][k[1]], *b2 = &bin[2][k[2]];
		b0->lo = f4_min(b0->lo, lo), b0->hi = f4_max(b0->hi, hi), b0->n++;
		b1->lo = f4_min(b1->lo, lo), b1->hi = f4_max(b1->hi, hi), b1->n++;
		b2->lo = f4_min(b2->lo, lo), b2->hi = f4_max(b2->hi, hi), b2->n++;
	}
	double best = INFINITY;
	int best_axis = -1, best_bin = 0;
	for (int l = 0; l < n_live; l++)
		if (best_split(bin[live[l]], BVH_BINS, &best, &best_bin))
			best_axis = live[l];
	/* Also try setting the big items apart (a floor under a sphereflake):
	 * centroid bins cannot separate them when their centres sit among the
	 * small ones. Only when some item is big enough for the smallest
	 * fraction (else every try puts all items on one side). */
	static const double big_frac[3] = { 0.5, 0.2, 0.05 };
	int best_big = -1;
	double node_area = f4_area(span->blo, span->bhi);
	if (span->amax > big_frac[2] * node_area) {
		f4 l1[3], h1[3], l2[3], h2[3];
		uint32_t n1[3] = { 0, 0, 0 };
		double thr[3];
		for (int q = 0; q < 3; q++) {
			l1[q] = l2[q] = f4_set1(INFINITY);
			h1[q] = h2[q] = f4_set1(-INFINITY);
			thr[q] = big_frac[q] * node_area;
		}
		for (uint32_t i = begin; i < end; i++) {
			if (cancel_poll_every(i))
				return;
			f4 lo, hi, c;
			rec_get(&rec[i], &lo, &hi, &c);
			double a = rec[i].hi[3];
			for (int q = 0; q < 3; q++) {
				if (a > thr[q])
					l1[q] = f4_min(l1[q], lo), h1[q] = f4_max(h1[q], hi), n1[q]++;
				else
					l2[q] = f4_min(l2[q], lo), h2[q] = f4_max(h2[q], hi);
			}
		}
		for (int q = 0; q < 3; q++) {
			if (n1[q] == 0 || n1[q] == n)
				continue;
			double c = f4_area(l1[q], h1[q]) * n1[q] + f4_area(l2[q], h2[q]) * (n - n1[q]);
			if (c < best)
				best = c, best_big = q;
		}
	}
	uint32_t mid;
	struct bvh_span left, right;
	bool spans = false; /* left and right are the halves' spans */
	if (best_big >= 0) {
		/* partitioned before the leaf test: a leaf keeps this order */
		mid = partition(B, begin, end, 0, lo4, scale, 0, big_frac[best_big] * node_area, &left, &right);
		spans = true;
		double split_cost = BVH_COST_TRAV * node_area + BVH_COST_ISECT * best;
		if (n <= B->max_leaf && BVH_COST_ISECT * node_area * n <= split_cost)
			goto leaf;
	} else if (best_axis < 0) { /* every centroid in one place */
		if (n <= B->max_leaf)
			goto leaf;
		mid = begin + n / 2;
	} else {
		double split_cost = BVH_COST_TRAV * node_area + BVH_COST_ISECT * best;
		double leaf_cost = BVH_COST_ISECT * node_area * n;
		if (n <= B->max_leaf && leaf_cost <= split_cost)
			goto leaf;
		mid = partition(B, begin, end, best_axis, lo4, scale, best_bin, 0, &left, &right);
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
	B->task[0] = (struct bvh_task){ root, 0, 0, n, 0 };
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
			_Alignas(16) float l[4] = { x->b[0], x->b[1], x->b[2], 0 };
			_Alignas(16) float h[4] = { x->b[3], x->b[4], x->b[5], 0 };
			double a = f4_area(f4_load(l), f4_load(h));
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

/* The items' records, in index order (perm the identity); NULL when out
 * of memory, or garbage when a cancel poll said true. */
static struct bvh_rec *make_recs(const struct geom_box *boxes, const float (*fboxes)[6], uint32_t n)
{
	struct bvh_rec *rec = aligned_alloc(16, (size_t)n * sizeof *rec);
	if (!rec)
		return NULL;
	for (uint32_t i = 0; i < n; i++) {
		if (cancel_poll_every(i))
			break;
		struct bvh_rec *r = &rec[i];
		if (boxes) {
			const struct geom_box *g = &boxes[i];
			r->lo[0] = round_down(g->lo.x), r->lo[1] = round_down(g->lo.y), r->lo[2] = round_down(g->lo.z);
			r->hi[0] = round_up(g->hi.x), r->hi[1] = round_up(g->hi.y), r->hi[2] = round_up(g->hi.z);
		} else {
			memcpy(r->lo, fboxes[i], 3 * sizeof(float));
			memcpy(r->hi, fboxes[i] + 3, 3 * sizeof(float));
		}
		r->lo[3] = r->hi[3] = 0;
		r->hi[3] = (float)f4_area(f4_load(r->lo), f4_load(r->hi));
		memcpy(&r->lo[3], &i, sizeof i);
	}
	return rec;
}

static int build(struct bvh *b, const struct geom_box *boxes, float (*fboxes)[6], uint32_t n, uint32_t *perm,
		 uint32_t max_leaf, bool pack)
{
	memset(b, 0, sizeof *b);
	if (n == 0)
		return 0;
	struct bvh_ctx B;
	memset(&B, 0, sizeof B);
	atomic_init(&B.n_nodes, 1);
	atomic_init(&B.gave_up, 0);
	B.max_leaf = max_leaf ? max_leaf : 1;
	B.pack = pack;
	B.rec = make_recs(boxes, (const float(*)[6])fboxes, n);
	free(fboxes); /* bvh_build_f's: the records hold their values now */
	B.nodes = B.rec ? malloc((size_t)2 * n * sizeof *B.nodes) : NULL;
	if (!B.nodes) {
		free(B.rec);
		return -1;
	}
	if (!cancel_seen())
		build_all(&B, n);
	for (uint32_t i = 0; i < n && !cancel_seen(); i++)
		memcpy(&perm[i], &B.rec[i].lo[3], sizeof perm[i]);
	free(B.rec);
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
	return build(b, boxes, NULL, n, perm, max_leaf, pack);
}

int bvh_build_f(struct bvh *b, float (*boxes)[6], uint32_t n, uint32_t *perm, uint32_t max_leaf, bool pack)
{
	if (n == 0) {
		free(boxes);
		memset(b, 0, sizeof *b);
		return 0;
	}
	return build(b, NULL, boxes, n, perm, max_leaf, pack);
}

void bvh_free(struct bvh *b)
{
	if (!b)
		return;
	free(b->nodes);
	memset(b, 0, sizeof *b);
}
