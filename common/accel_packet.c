/*
 * accel_packet.c - packets of rays through the root group's tree
 * (accel_intersect4, accel_intersect16, accel_intersect64,
 * accel_occluded4): the closest-hit traversals bvh_hit4 (four rays from
 * anywhere) and bvh_hit_o (4, 16 or 64 rays from one origin), the any-hit
 * traversal bvh_occluded4, and their set-up. Each ray of a packet gets
 * exactly the answer accel_intersect or accel_occluded gives it
 * (CANONICAL TIES, accel_trace.h); the single-ray queries, the hits'
 * completion and the design are in accel.c, what both share in
 * accel_trace.h. Without SSE2 the packet queries trace their rays one at a
 * time.
 */
#include "common/accel.h"

#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "common/accel_int.h"
#include "common/accel_trace.h"
#include "common/cancel.h"

/* ---- packets of four rays ------------------------------------------------------------ */

#if defined(__SSE2__)
/*
 * Four rays of one octant, one per SIMD lane (lane i: ray i), for the
 * packet traversal: where bvh_hit tests one ray against a node's four
 * children at once, bvh_hit4 tests each child against four rays at once.
 * Neighbouring camera rays visit nearly the same nodes, so the packet
 * shares the node loads, the ordering and the stack among them. The box
 * arithmetic is bvh_hit's, but for the inverses, which ray_box4 takes in
 * float: a lane's box test may pass where bvh_hit's would not, or fail at
 * a box bvh_hit's passes without a hit in it, never at one holding the
 * ray's hit (BOX TESTS, accel_int.h), and CANONICAL TIES make the hit the
 * same.
 */
struct ray4x {
	__m128 o[3], inv_near[3], inv_far[3];
	/* lane i's o, inv_near and inv_far broadcast to four lanes (one per
	 * child): bvh_hit4 tests a node ray by ray, the four children at once */
	__m128 lo[4][3], lnear[4][3], lfar[4][3];
	double tscale[4];
};

/* The lanes (bit i: ray i) whose entry distance t into a subtree is finite
 * (the ray meets its box: a miss is +inf) and not behind the ray's closest
 * hit so far. The first test matters while a ray has no hit: its tmax is
 * +inf too. */
static inline unsigned lanes_in_front(__m128 t, __m128 tmax4, __m128 inf4)
{
	return (unsigned)_mm_movemask_ps(_mm_and_ps(_mm_cmplt_ps(t, inf4), _mm_cmple_ps(t, tmax4)));
}

/* The smallest of the four lanes. */
static inline float lanes_min(__m128 v)
{
	v = _mm_min_ps(v, _mm_shuffle_ps(v, v, _MM_SHUFFLE(2, 3, 0, 1)));
	v = _mm_min_ps(v, _mm_shuffle_ps(v, v, _MM_SHUFFLE(1, 0, 3, 2)));
	return _mm_cvtss_f32(v);
}

/* box_tmin and box_tmax of the four rays' tmin and tmax (times their
 * tscale) as lanes, two at a time in registers: the same floats, without
 * the four scalar stores that a 16-byte load would wait on. */
static inline __m128 lanes_box_tmin(const struct trace tr[4], const double tscale[4])
{
	const __m128d f = _mm_set1_pd(1 - 0x1p-22), a = _mm_set1_pd(0x1p-140);
	__m128d x0 = _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(&tr[0].tmin), &tr[1].tmin), _mm_loadu_pd(tscale));
	__m128d x1 = _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(&tr[2].tmin), &tr[3].tmin), _mm_loadu_pd(tscale + 2));
	return _mm_movelh_ps(_mm_cvtpd_ps(_mm_sub_pd(_mm_mul_pd(x0, f), a)),
			     _mm_cvtpd_ps(_mm_sub_pd(_mm_mul_pd(x1, f), a)));
}

static inline __m128 lanes_box_tmax(const struct trace tr[4], const double tscale[4])
{
	const __m128d f = _mm_set1_pd(1 + 0x1p-22), a = _mm_set1_pd(0x1p-140);
	__m128d x0 = _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(&tr[0].tmax), &tr[1].tmax), _mm_loadu_pd(tscale));
	__m128d x1 = _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(&tr[2].tmax), &tr[3].tmax), _mm_loadu_pd(tscale + 2));
	return _mm_movelh_ps(_mm_cvtpd_ps(_mm_add_pd(_mm_mul_pd(x0, f), a)),
			     _mm_cvtpd_ps(_mm_add_pd(_mm_mul_pd(x1, f), a)));
}

/*
 * ray_box_init for four rays at once, into P's rows (lane i: ray i). The
 * origins, the scale and the scaled directions are ray_box_init's, two
 * rays at a time (mulpd and subpd round as mulsd and subsd do, cvtpd2ps
 * as cvtsd2ss, and maxpd picks what the scalar comparisons pick for
 * finite directions); the scale's power of two comes from the exponent
 * bits: 2^e is m's exponent field alone and 2^-e has the field 2046 - E.
 * The inverses are taken in float, four at a time (one divps where
 * ray_box_init makes three divisions a ray): the scaled direction rounded
 * to float, its inverse and the widening's product each add a rounding
 * (2^-24) where ray_box_init's double path has one, two more in all,
 * which BOX_WIDEN covers with room (accel_int.h: the budget is 2^-20, the
 * errors about 2^-21 with these). The +-1e30 rule is the same, tested on
 * the float. Everything stays in registers: building the pairs through
 * arrays on the stack (8-byte stores read back by 16-byte loads) stalled
 * store forwarding and made the set-up a tenth of tetra_s4's render.
 */
static void ray_box4(const struct trace tr[4], vec3 center, struct ray4x *P)
{
	const __m128d one = _mm_set1_pd(1.0), sign = _mm_set1_pd(-0.0);
	const __m128d expo = _mm_castsi128_pd(_mm_set1_epi64x(0x7ff0000000000000LL));
	const __m128i two046 = _mm_set1_epi64x(0x7fe0000000000000LL);
	const __m128d lo_e = _mm_set1_pd(0x1p-1000), hi_e = _mm_set1_pd(0x1p1001);
	const __m128d c[3] = { _mm_set1_pd(center.x), _mm_set1_pd(center.y), _mm_set1_pd(center.z) };
	__m128 o[3][2], dks[3][2];
	for (int h = 0; h < 2; h++) {
		const struct trace *a = &tr[2 * h], *b = &tr[2 * h + 1];
		/* lane pairs loaded 8 bytes at a time: the rays were just stored that way */
		__m128d d[3] = { _mm_loadh_pd(_mm_load_sd(&a->d.x), &b->d.x), _mm_loadh_pd(_mm_load_sd(&a->d.y), &b->d.y),
				 _mm_loadh_pd(_mm_load_sd(&a->d.z), &b->d.z) };
		__m128d oo[3] = { _mm_loadh_pd(_mm_load_sd(&a->o.x), &b->o.x), _mm_loadh_pd(_mm_load_sd(&a->o.y), &b->o.y),
				  _mm_loadh_pd(_mm_load_sd(&a->o.z), &b->o.z) };
		__m128d m = _mm_max_pd(_mm_max_pd(_mm_andnot_pd(sign, d[0]), _mm_andnot_pd(sign, d[1])),
				       _mm_andnot_pd(sign, d[2]));
		/* e outside [-1000, 1000] (m < 2^-1000 or m >= 2^1001): unscaled, as ray_box_init */
		__m128d clamp = _mm_or_pd(_mm_cmplt_pd(m, lo_e), _mm_cmpge_pd(m, hi_e));
		__m128d ts = _mm_and_pd(m, expo);                                        /* 2^e */
		__m128d sc = _mm_castsi128_pd(_mm_sub_epi64(two046, _mm_castpd_si128(ts))); /* 2^-e */
		ts = _mm_or_pd(_mm_and_pd(clamp, one), _mm_andnot_pd(clamp, ts));
		sc = _mm_or_pd(_mm_and_pd(clamp, one), _mm_andnot_pd(clamp, sc));
		_mm_storeu_pd(&P->tscale[2 * h], ts);
		for (int k = 0; k < 3; k++) {
			dks[k][h] = _mm_cvtpd_ps(_mm_mul_pd(d[k], sc));
			o[k][h] = _mm_cvtpd_ps(_mm_sub_pd(oo[k], c[k]));
		}
	}
	const __m128 onef = _mm_set1_ps(1.0f), tinyf = _mm_set1_ps(1e-30f), bigf = _mm_set1_ps(1e30f);
	const __m128 signf = _mm_set1_ps(-0.0f), wnf = _mm_set1_ps(1 - BOX_WIDEN), wff = _mm_set1_ps(1 + BOX_WIDEN);
	for (int k = 0; k < 3; k++) {
		__m128 dk = _mm_movelh_ps(dks[k][0], dks[k][1]);
		__m128 iv = _mm_div_ps(onef, dk);
		/* fabsf(dk) > 1e-30 ? 1 / dk : copysignf(1e30, dk) */
		__m128 ok = _mm_cmpgt_ps(_mm_andnot_ps(signf, dk), tinyf);
		__m128 alt = _mm_or_ps(_mm_and_ps(signf, dk), bigf);
		iv = _mm_or_ps(_mm_and_ps(ok, iv), _mm_andnot_ps(ok, alt));
		P->o[k] = _mm_movelh_ps(o[k][0], o[k][1]);
		P->inv_near[k] = _mm_mul_ps(iv, wnf);
		P->inv_far[k] = _mm_mul_ps(iv, wff);
	}
}

/* The packet's side of the TRIANGLE PRE-TEST: one triangle against the
 * four rays, where they share kx, ky, kz (neighbouring rays do). */
struct tri4 {
	bool ok;   /* set up, and the four rays share kx, ky, kz */
	int kx, ky, kz;
	__m128 ox, oy, oz, sx, sy, so; /* per ray: origin, shear, max |origin| */
};

/* Sets up the pre-test for the packet (the rays' watertight set-up too). */
/* Field f (a double) of the four rays' set-ups, each rounded to float,
 * into one vector: two conversions of pairs loaded as doubles, not four
 * scalar stores that one vector load would have to wait for (store
 * forwarding fails across them). */
#define TRI4_LANES(w, f) \
	_mm_movelh_ps(_mm_cvtpd_ps(_mm_set_pd((w)[1]->f, (w)[0]->f)), _mm_cvtpd_ps(_mm_set_pd((w)[3]->f, (w)[2]->f)))

static void tri4_init(struct tri4 *q, struct trace tr[4])
{
	const struct geom_wray *w[4];
	for (int i = 0; i < 4; i++)
		w[i] = trace_wray(&tr[i]);
	q->kx = w[0]->kx, q->ky = w[0]->ky, q->kz = w[0]->kz;
	q->ok = true;
	for (int i = 1; i < 4; i++)
		q->ok &= w[i]->kx == q->kx && w[i]->ky == q->ky && w[i]->kz == q->kz;
	q->ox = TRI4_LANES(w, ox), q->oy = TRI4_LANES(w, oy), q->oz = TRI4_LANES(w, oz);
	q->sx = TRI4_LANES(w, sx), q->sy = TRI4_LANES(w, sy);
	/* max(|ox|, |oy|, |oz|) as `a > b ? a : b` in float, which maxps is */
	q->so = _mm_max_ps(_mm_max_ps(abs4(q->ox), abs4(q->oy)), abs4(q->oz));
}

/* The rays (bit i: ray i) that lane l's triangle of block tb certainly
 * misses (TRIANGLE PRE-TEST); q->ok must hold. The block's floats are the
 * vertices rounded as the packets once rounded them when they gathered
 * them, and its s the same largest magnitude. */
static inline unsigned tri4_reject(const struct tri4 *q, const float *tb, uint32_t n, uint32_t l)
{
	const float *x = tb + (uint32_t)q->kx * n + l, *y = tb + (uint32_t)q->ky * n + l,
		    *z = tb + (uint32_t)q->kz * n + l;
	const uint32_t n3 = 3 * n, n6 = 6 * n;
	const __m128 v[9] = { _mm_set1_ps(x[0]),  _mm_set1_ps(y[0]),  _mm_set1_ps(z[0]),
			      _mm_set1_ps(x[n3]), _mm_set1_ps(y[n3]), _mm_set1_ps(z[n3]),
			      _mm_set1_ps(x[n6]), _mm_set1_ps(y[n6]), _mm_set1_ps(z[n6]) };
	return tri_reject_ps(v, _mm_set1_ps(blk_row(tb, n, 9)[l]), q->ox, q->oy, q->oz, q->sx, q->sy, q->so);
}

/* The same for a triangle of a leaf without a block (mixed leaves): its
 * floats gathered and rounded here, as make_blocks rounds them. */
static inline unsigned tri4_reject_v(const struct tri4 *q, const vec3 *a, const vec3 *b, const vec3 *c)
{
	const int kx = q->kx, ky = q->ky, kz = q->kz;
	float f[9] = { (float)geom_comp(a, kx), (float)geom_comp(a, ky), (float)geom_comp(a, kz),
		       (float)geom_comp(b, kx), (float)geom_comp(b, ky), (float)geom_comp(b, kz),
		       (float)geom_comp(c, kx), (float)geom_comp(c, ky), (float)geom_comp(c, kz) };
	float sv = 0;
	for (int k = 0; k < 9; k++)
		sv = fabsf(f[k]) > sv ? fabsf(f[k]) : sv; /* NaN: left out, but NaN below rejects nothing */
	__m128 v[9];
	for (int k = 0; k < 9; k++)
		v[k] = _mm_set1_ps(f[k]);
	return tri_reject_ps(v, _mm_set1_ps(sv), q->ox, q->oy, q->oz, q->sx, q->sy, q->so);
}

/* A leaf of n references from idx tested for the rays in lanes (two or
 * more), reference by reference: triangles through the pre-test when the
 * rays share their permutation (set up on the packet's first such leaf). */
static inline __attribute__((always_inline)) void leaf4(const struct accel *A, const struct group *g,
							struct trace tr[4], struct cand best[4], bool found[4],
							uint32_t idx, uint32_t n, unsigned lanes, struct tri4 *q,
							bool *q_ready)
{
	for (uint32_t k = 0; k < n; k++) {
		uint32_t ref = group_ref(g, idx + k);
		unsigned test = lanes;
		if (REF_KIND(ref) == REF_TRI) {
			if (!*q_ready) {
				tri4_init(q, tr);
				*q_ready = true;
			}
			if (q->ok) {
				const struct gmesh *m = &g->mesh[g->tri[REF_IDX(ref)].mesh];
				const uint32_t *ix = tri_ix(m, g->tri[REF_IDX(ref)].tri);
				test &= ~tri4_reject_v(q, &m->v[ix[0]], &m->v[ix[1]], &m->v[ix[2]]);
			}
		}
		for (; test; test &= test - 1) {
			int i = __builtin_ctz(test);
			found[i] |= ref_test(A, g, ref, &tr[i], &best[i], false);
		}
	}
}

/* leaf4 for a leaf block of n triangles: each triangle's pre-test against
 * the rays in lanes (two or more) reads the block. */
static inline __attribute__((always_inline)) void leaf4_block(const struct group *g, struct trace tr[4],
							      struct cand best[4], bool found[4],
							      const float *tb, uint32_t n, unsigned lanes,
							      struct tri4 *q, bool *q_ready)
{
	if (!*q_ready) {
		tri4_init(q, tr);
		*q_ready = true;
	}
	for (uint32_t l = 0; l < n; l++) {
		unsigned test = lanes;
		if (q->ok)
			test &= ~tri4_reject(q, tb, n, l);
		for (; test; test &= test - 1) {
			int i = __builtin_ctz(test);
			found[i] |= tri_test(g, blk_ref(tb, n, l), &tr[i], &best[i]);
		}
	}
}

/*
 * The packet traversal of g's bounded references. A subtree is visited
 * when any ray may hit it, nearest (smallest entry over the rays) first;
 * each stack entry keeps every ray's entry distance (+inf for a ray that
 * misses it), so a subtree is popped only for the rays that meet it and are
 * still in front of their closest hit, and a leaf is tested only for those. Every ray thus
 * tests every reference bvh_hit would let it test, perhaps more and in
 * another order: CANONICAL TIES make its hit the same. found[i], best[i]
 * and tr[i] are ray i's, as group_hit's.
 */
static inline __attribute__((always_inline)) void bvh_hit4(const struct accel *A, const struct group *g,
							   struct trace tr[4], struct cand best[4], bool found[4],
							   const struct ray4x *P, const uint32_t oct)
{
	const struct bvh4 *nodes = g->bvh.nodes;
	const uint32_t near[3] = { 12 * (oct & 1), 4 + 12 * (oct >> 1 & 1), 8 + 12 * (oct >> 2 & 1) };
	const uint32_t far[3] = { 12 * (~oct & 1), 4 + 12 * (~oct >> 1 & 1), 8 + 12 * (~oct >> 2 & 1) };
	const __m128 tmin4 = lanes_box_tmin(tr, P->tscale), inf4 = _mm_set1_ps(INFINITY);
	__m128 tmax4 = lanes_box_tmax(tr, P->tscale);
	struct {
		__m128 t; /* each ray's entry distance, +inf where it misses */
		uint32_t idx, n;
	} stack[3 * BVH_MAX_DEPTH + 4];
	int sp = 0;
	uint32_t idx = 0, n = 0;
	__m128 tcur = tmin4; /* the entry distances of the subtree at hand */
	uint32_t polls = ACCEL_POLL_POPS;
	struct tri4 q; /* TRIANGLE PRE-TEST, set up at the first leaf that needs it */
	bool q_ready = false;
	for (;;) {
		if (n) {
			/* the rays that meet the leaf, in front of their closest hit */
			unsigned lanes = lanes_in_front(tcur, tmax4, inf4);
			if (n & LEAF_BLOCK) {
				const float *tb = &g->tblk[idx];
				uint32_t nt = n & ~LEAF_BLOCK;
				if (lanes & (lanes - 1)) {
					leaf4_block(g, tr, best, found, tb, nt, lanes, &q, &q_ready);
				} else if (lanes) {
					int i = __builtin_ctz(lanes);
					struct tri1 q1;
					bool q1_ready = false;
					found[i] |= block_hit(g, tb, nt, &tr[i], &best[i], &q1, &q1_ready);
				}
			} else if (lanes & (lanes - 1)) { /* two or more: the triangle pre-test pays */
				leaf4(A, g, tr, best, found, idx, n, lanes, &q, &q_ready);
			} else if (lanes) {
				int i = __builtin_ctz(lanes);
				for (uint32_t k = 0; k < n; k++)
					found[i] |= ref_test(A, g, group_ref(g, idx + k), &tr[i], &best[i], false);
			}
			tmax4 = lanes_box_tmax(tr, P->tscale); /* the tested lanes' changed */
		} else {
			const struct bvh4 *nd = &nodes[idx];
			const float *b = (const float *)(const void *)nd; /* rows as in node4_hit */
			/* ray by ray, the four children in the lanes (node4_hit's
			 * arithmetic, operand for operand), then transposed: e[c] is
			 * child c's entry distance for each ray, +inf where it misses */
			const __m128 nr[3] = { _mm_loadu_ps(b + near[0]), _mm_loadu_ps(b + near[1]),
					       _mm_loadu_ps(b + near[2]) };
			const __m128 fr[3] = { _mm_loadu_ps(b + far[0]), _mm_loadu_ps(b + far[1]),
					       _mm_loadu_ps(b + far[2]) };
			__m128 e[4];
			int m = 0;
#define RAY_NODE(i)                                                                                      \
	do {                                                                                             \
		__m128 t0 = _mm_shuffle_ps(tmin4, tmin4, _MM_SHUFFLE(i, i, i, i));                       \
		__m128 t1 = _mm_shuffle_ps(tmax4, tmax4, _MM_SHUFFLE(i, i, i, i));                       \
		for (int k = 0; k < 3; k++) {                                                            \
			__m128 tn = _mm_mul_ps(_mm_sub_ps(nr[k], P->lo[i][k]), P->lnear[i][k]);          \
			__m128 tf = _mm_mul_ps(_mm_sub_ps(fr[k], P->lo[i][k]), P->lfar[i][k]);           \
			t0 = _mm_max_ps(t0, tn);                                                         \
			t1 = _mm_min_ps(t1, tf);                                                         \
		}                                                                                        \
		__m128 hit = _mm_cmple_ps(t0, t1);                                                       \
		e[i] = _mm_or_ps(_mm_and_ps(hit, t0), _mm_andnot_ps(hit, inf4));                         \
		m |= _mm_movemask_ps(hit);                                                               \
	} while (0)
			RAY_NODE(0);
			RAY_NODE(1);
			RAY_NODE(2);
			RAY_NODE(3);
#undef RAY_NODE
			float key[4]; /* each child's nearest entry over the rays */
			_mm_storeu_ps(key, _mm_min_ps(_mm_min_ps(e[0], e[1]), _mm_min_ps(e[2], e[3])));
			_MM_TRANSPOSE4_PS(e[0], e[1], e[2], e[3]);
			if (m) { /* nearest first; the others pushed farthest first */
				/* children_by_entry's sort written out: the call cost gears_s2
				 * +0.65% instructions here (group_hit4 +5.8%, gcc's inlining) */
				int cs[4], k = 0;
				for (int c = 0; c < 4; c++) {
					if (!(m >> c & 1))
						continue;
					int j = k++;
					for (; j > 0 && key[cs[j - 1]] > key[c]; j--)
						cs[j] = cs[j - 1];
					cs[j] = c;
				}
				for (int j = k - 1; j >= 1; j--) {
					stack[sp].idx = nd->idx[cs[j]];
					stack[sp].n = nd->n[cs[j]];
					stack[sp++].t = e[cs[j]];
				}
				idx = nd->idx[cs[0]];
				n = nd->n[cs[0]];
				tcur = e[cs[0]];
				continue;
			}
		}
		if (__builtin_expect(--polls == 0, 0)) { /* CANCELLATION, as bvh_hit */
			polls = ACCEL_POLL_POPS;
			if (cancel_poll())
				return;
		}
		/* pop the next subtree still in front of some ray's closest hit */
		for (;;) {
			if (sp == 0)
				return;
			sp--;
			if (lanes_in_front(stack[sp].t, tmax4, inf4))
				break;
		}
		idx = stack[sp].idx;
		n = stack[sp].n;
		tcur = stack[sp].t;
	}
}

/*
 * bvh_hit4 for 4 * ng rays from one origin (the same floats in every P[j]->o
 * lane), ng packets of four (ng 1, 4 or 16): each node's children are
 * tested against the rays as a whole, with the interval of the rays'
 * inverses per axis. The plane less the origin, d, is the same float for
 * every ray, and fl(d * x) is monotonic in x, so the smaller of d times the
 * least and d times the greatest inverse is the least entry distance over
 * the rays on that axis, exactly, and the larger of the far products the
 * greatest exit; with the least tmin and greatest tmax over the rays, a
 * child that any ray's own test (RAY_NODE) lets through passes. A subtree
 * is popped while its entry is within some ray's tmax. At a leaf each
 * packet of four whose own interval (the same test, in SIMD over four
 * packets at a time) meets the leaf's box, in its parent node, is tested
 * whole (the triangle pre-test and the exact tests decide); with ng 1 that
 * test is the node's, so it is not repeated.
 */
static inline __attribute__((always_inline)) void bvh_hit_o(const struct accel *A, const struct group *g,
							    struct trace *tr, struct cand *best, bool *found,
							    const struct ray4x *P, const uint32_t oct, const int ng)
{
	enum { NSMAX = 4 };
	const int ns = ng / 4; /* groups of four packets (ng > 1) */
	const struct bvh4 *nodes = g->bvh.nodes;
	const uint32_t near[3] = { 12 * (oct & 1), 4 + 12 * (oct >> 1 & 1), 8 + 12 * (oct >> 2 & 1) };
	const uint32_t far[3] = { 12 * (~oct & 1), 4 + 12 * (~oct >> 1 & 1), 8 + 12 * (~oct >> 2 & 1) };
	__m128 o[3], nlo[3], nhi[3], flo[3], fhi[3];
	/* ng > 1, from the first leaf: lane j of group s packet 4 s + j's least
	 * and greatest inverses, tmin and tmax */
	__m128 snlo[NSMAX][3], snhi[NSMAX][3], sflo[NSMAX][3], sfhi[NSMAX][3], stmin[NSMAX], stmax[NSMAX];
	for (int k = 0; k < 3; k++) {
		o[k] = _mm_shuffle_ps(P[0].o[k], P[0].o[k], 0); /* the shared origin */
		__m128 a = P[0].inv_near[k], a_ = a, b = P[0].inv_far[k], b_ = b;
		for (int j = 1; j < ng; j++) {
			a = _mm_min_ps(a, P[j].inv_near[k]), a_ = _mm_max_ps(a_, P[j].inv_near[k]);
			b = _mm_min_ps(b, P[j].inv_far[k]), b_ = _mm_max_ps(b_, P[j].inv_far[k]);
		}
		__m128 amin = _mm_min_ps(a, _mm_shuffle_ps(a, a, _MM_SHUFFLE(1, 0, 3, 2)));
		__m128 amax = _mm_max_ps(a_, _mm_shuffle_ps(a_, a_, _MM_SHUFFLE(1, 0, 3, 2)));
		__m128 bmin = _mm_min_ps(b, _mm_shuffle_ps(b, b, _MM_SHUFFLE(1, 0, 3, 2)));
		__m128 bmax = _mm_max_ps(b_, _mm_shuffle_ps(b_, b_, _MM_SHUFFLE(1, 0, 3, 2)));
		nlo[k] = _mm_min_ps(amin, _mm_shuffle_ps(amin, amin, _MM_SHUFFLE(2, 3, 0, 1)));
		nhi[k] = _mm_max_ps(amax, _mm_shuffle_ps(amax, amax, _MM_SHUFFLE(2, 3, 0, 1)));
		flo[k] = _mm_min_ps(bmin, _mm_shuffle_ps(bmin, bmin, _MM_SHUFFLE(2, 3, 0, 1)));
		fhi[k] = _mm_max_ps(bmax, _mm_shuffle_ps(bmax, bmax, _MM_SHUFFLE(2, 3, 0, 1)));
	}
	/* the least tmin and greatest tmax of all the rays */
	__m128 gtmin = lanes_box_tmin(tr, P[0].tscale), gtmax = lanes_box_tmax(tr, P[0].tscale);
	for (int j = 1; j < ng; j++) {
		gtmin = _mm_min_ps(gtmin, lanes_box_tmin(tr + 4 * j, P[j].tscale));
		gtmax = _mm_max_ps(gtmax, lanes_box_tmax(tr + 4 * j, P[j].tscale));
	}
	bool sub = false;
#define PACKET_TMAX()                                                                                      \
	do {                                                                                               \
		if (ng == 1) {                                                                             \
			gtmax = lanes_box_tmax(tr, P[0].tscale);                                           \
		} else {                                                                                   \
			for (int s_ = 0; s_ < ns; s_++) {                                                  \
				const int j_ = 4 * s_;                                                     \
				__m128 u0 = lanes_box_tmax(tr + 4 * j_, P[j_].tscale),                     \
				       u1 = lanes_box_tmax(tr + 4 * j_ + 4, P[j_ + 1].tscale),             \
				       u2 = lanes_box_tmax(tr + 4 * j_ + 8, P[j_ + 2].tscale),             \
				       u3 = lanes_box_tmax(tr + 4 * j_ + 12, P[j_ + 3].tscale);            \
				_MM_TRANSPOSE4_PS(u0, u1, u2, u3);                                         \
				stmax[s_] = _mm_max_ps(_mm_max_ps(u0, u1), _mm_max_ps(u2, u3));            \
				gtmax = s_ ? _mm_max_ps(gtmax, stmax[s_]) : stmax[s_];                     \
			}                                                                                  \
		}                                                                                          \
	} while (0)
#define SUB_SETUP()                                                                                        \
	do {                                                                                               \
		for (int s_ = 0; s_ < ns; s_++) {                                                          \
			const struct ray4x *Q = P + 4 * s_;                                                \
			for (int k = 0; k < 3; k++) {                                                      \
				__m128 a0 = Q[0].inv_near[k], a1 = Q[1].inv_near[k], a2 = Q[2].inv_near[k], \
				       a3 = Q[3].inv_near[k];                                              \
				__m128 b0 = Q[0].inv_far[k], b1 = Q[1].inv_far[k], b2 = Q[2].inv_far[k],   \
				       b3 = Q[3].inv_far[k];                                               \
				_MM_TRANSPOSE4_PS(a0, a1, a2, a3); /* lane j: packet j's ray 0..3 */        \
				_MM_TRANSPOSE4_PS(b0, b1, b2, b3);                                         \
				snlo[s_][k] = _mm_min_ps(_mm_min_ps(a0, a1), _mm_min_ps(a2, a3));          \
				snhi[s_][k] = _mm_max_ps(_mm_max_ps(a0, a1), _mm_max_ps(a2, a3));          \
				sflo[s_][k] = _mm_min_ps(_mm_min_ps(b0, b1), _mm_min_ps(b2, b3));          \
				sfhi[s_][k] = _mm_max_ps(_mm_max_ps(b0, b1), _mm_max_ps(b2, b3));          \
			}                                                                                  \
			const struct trace *T = tr + 16 * s_;                                              \
			__m128 t0 = lanes_box_tmin(T, Q[0].tscale), t1 = lanes_box_tmin(T + 4, Q[1].tscale), \
			       t2 = lanes_box_tmin(T + 8, Q[2].tscale), t3 = lanes_box_tmin(T + 12, Q[3].tscale); \
			_MM_TRANSPOSE4_PS(t0, t1, t2, t3);                                                 \
			stmin[s_] = _mm_min_ps(_mm_min_ps(t0, t1), _mm_min_ps(t2, t3));                    \
		}                                                                                          \
		PACKET_TMAX();                                                                             \
		sub = true;                                                                                \
	} while (0)
	const __m128 tmin1 = _mm_set1_ps(lanes_min(gtmin));
	float tmax = -lanes_min(_mm_sub_ps(_mm_setzero_ps(), gtmax)); /* the greatest */
	struct {
		float t; /* the rays' least entry distance */
		uint32_t idx, n;
		uint32_t from; /* ng > 1: the parent node's index * 4 + the child's slot */
	} stack[3 * BVH_MAX_DEPTH + 4];
	int sp = 0;
	uint32_t idx = 0, n = 0, from = 0;
	uint32_t polls = ACCEL_POLL_POPS;
	struct tri4 q[16]; /* TRIANGLE PRE-TEST per packet, set up at the first leaf that needs it */
	uint32_t q_ready = 0; /* bit j: q[j] */
	for (;;) {
		if (n) {
			unsigned gm = 1;
			if (ng > 1) { /* the packets whose interval meets the leaf's box */
				if (!sub)
					SUB_SETUP();
				const float *b = (const float *)(const void *)&nodes[from >> 2];
				const uint32_t c = from & 3;
				__m128 dn[3], df[3];
				for (int k = 0; k < 3; k++) {
					dn[k] = _mm_sub_ps(_mm_set1_ps(b[near[k] + c]), o[k]);
					df[k] = _mm_sub_ps(_mm_set1_ps(b[far[k] + c]), o[k]);
				}
				gm = 0;
				for (int s_ = 0; s_ < ns; s_++) {
					__m128 t0 = stmin[s_], t1 = stmax[s_];
					for (int k = 0; k < 3; k++) {
						t0 = _mm_max_ps(t0, _mm_min_ps(_mm_mul_ps(dn[k], snlo[s_][k]),
									       _mm_mul_ps(dn[k], snhi[s_][k])));
						t1 = _mm_min_ps(t1, _mm_max_ps(_mm_mul_ps(df[k], sflo[s_][k]),
									       _mm_mul_ps(df[k], sfhi[s_][k])));
					}
					gm |= (unsigned)_mm_movemask_ps(_mm_cmple_ps(t0, t1)) << (4 * s_);
				}
			}
			for (; gm; gm &= gm - 1) {
				int j = __builtin_ctz(gm);
				bool qr = q_ready >> j & 1;
				if (n & LEAF_BLOCK)
					leaf4_block(g, tr + 4 * j, best + 4 * j, found + 4 * j, &g->tblk[idx],
						    n & ~LEAF_BLOCK, 15, &q[j], &qr);
				else
					leaf4(A, g, tr + 4 * j, best + 4 * j, found + 4 * j, idx, n, 15, &q[j], &qr);
				q_ready |= (uint32_t)qr << j;
			}
			PACKET_TMAX();
			tmax = -lanes_min(_mm_sub_ps(_mm_setzero_ps(), gtmax));
		} else {
			const struct bvh4 *nd = &nodes[idx];
			const float *b = (const float *)(const void *)nd; /* rows as in node4_hit */
			__m128 t0 = tmin1, t1 = _mm_set1_ps(tmax);
			for (int k = 0; k < 3; k++) {
				__m128 dn = _mm_sub_ps(_mm_loadu_ps(b + near[k]), o[k]);
				__m128 df = _mm_sub_ps(_mm_loadu_ps(b + far[k]), o[k]);
				t0 = _mm_max_ps(t0, _mm_min_ps(_mm_mul_ps(dn, nlo[k]), _mm_mul_ps(dn, nhi[k])));
				t1 = _mm_min_ps(t1, _mm_max_ps(_mm_mul_ps(df, flo[k]), _mm_mul_ps(df, fhi[k])));
			}
			int m = _mm_movemask_ps(_mm_cmple_ps(t0, t1));
			if (m) {
				float key[4];
				_mm_storeu_ps(key, t0);
				int cs[4], k = children_by_entry(m, key, cs);
				for (int j = k - 1; j >= 1; j--) {
					stack[sp].idx = nd->idx[cs[j]];
					stack[sp].n = nd->n[cs[j]];
					if (ng > 1)
						stack[sp].from = idx * 4 + (uint32_t)cs[j];
					stack[sp++].t = key[cs[j]];
				}
				if (ng > 1)
					from = idx * 4 + (uint32_t)cs[0];
				n = nd->n[cs[0]];
				idx = nd->idx[cs[0]];
				continue;
			}
		}
		if (__builtin_expect(--polls == 0, 0)) { /* CANCELLATION, as bvh_hit */
			polls = ACCEL_POLL_POPS;
			if (cancel_poll())
				return;
		}
		/* pop the next subtree still in front of some ray's closest hit */
		for (;;) {
			if (sp == 0)
				return;
			sp--;
			if (stack[sp].t <= tmax)
				break;
		}
		idx = stack[sp].idx;
		n = stack[sp].n;
		if (ng > 1)
			from = stack[sp].from;
	}
#undef PACKET_TMAX
#undef SUB_SETUP
}

/* bvh_hit_o for ng packets (1, 4 or 16), one copy per octant. */
static inline __attribute__((always_inline)) void hit_o_octants(const struct accel *A, const struct group *g,
								 struct trace *tr, struct cand *best, bool *found,
								 const struct ray4x *P, uint32_t oct, const int ng)
{
	switch (oct) {
	case 0: bvh_hit_o(A, g, tr, best, found, P, 0, ng); break;
	case 1: bvh_hit_o(A, g, tr, best, found, P, 1, ng); break;
	case 2: bvh_hit_o(A, g, tr, best, found, P, 2, ng); break;
	case 3: bvh_hit_o(A, g, tr, best, found, P, 3, ng); break;
	case 4: bvh_hit_o(A, g, tr, best, found, P, 4, ng); break;
	case 5: bvh_hit_o(A, g, tr, best, found, P, 5, ng); break;
	case 6: bvh_hit_o(A, g, tr, best, found, P, 6, ng); break;
	default: bvh_hit_o(A, g, tr, best, found, P, 7, ng); break;
	}
}

static __attribute__((noinline)) void group_hit4o(const struct accel *A, const struct group *g, struct trace tr[4],
						  struct cand best[4], bool found[4], const struct ray4x *P, uint32_t oct)
{
	hit_o_octants(A, g, tr, best, found, P, oct, 1);
}

static __attribute__((noinline)) void group_hit16o(const struct accel *A, const struct group *g, struct trace tr[16],
						   struct cand best[16], bool found[16], const struct ray4x P[4],
						   uint32_t oct)
{
	hit_o_octants(A, g, tr, best, found, P, oct, 4);
}

static __attribute__((noinline)) void group_hit64o(const struct accel *A, const struct group *g, struct trace tr[64],
						   struct cand best[64], bool found[64], const struct ray4x P[16],
						   uint32_t oct)
{
	hit_o_octants(A, g, tr, best, found, P, oct, 16);
}

/* group_hit for four rays of one octant through g's tree (g->bvh.n_nodes4). */
static void group_hit4(const struct accel *A, const struct group *g, struct trace tr[4], uint32_t oct,
		       struct hit h[4], bool hit[4])
{
	struct cand best[4];
	bool found[4];
	struct ray4x P;
	for (int i = 0; i < 4; i++) {
		cand_init(&best[i]);
		found[i] = group_hit_unbounded(A, g, &tr[i], &best[i], false);
	}
	ray_box4(tr, g->center, &P);
	/* one origin, the same floats in every lane (eye rays of a pinhole
	 * camera): the whole-packet node test, which needs no rows per ray */
	__m128i same = _mm_set1_epi32(-1);
	for (int k = 0; k < 3; k++) {
		__m128i ok = _mm_castps_si128(P.o[k]);
		same = _mm_and_si128(same, _mm_cmpeq_epi32(ok, _mm_shuffle_epi32(ok, 0)));
	}
	if (_mm_movemask_epi8(same) == 0xffff) {
		group_hit4o(A, g, tr, best, found, &P, oct);
	} else {
		for (int k = 0; k < 3; k++) {
			__m128 a = P.o[k], b = P.inv_near[k], f = P.inv_far[k];
			P.lo[0][k] = _mm_shuffle_ps(a, a, 0x00), P.lo[1][k] = _mm_shuffle_ps(a, a, 0x55);
			P.lo[2][k] = _mm_shuffle_ps(a, a, 0xaa), P.lo[3][k] = _mm_shuffle_ps(a, a, 0xff);
			P.lnear[0][k] = _mm_shuffle_ps(b, b, 0x00), P.lnear[1][k] = _mm_shuffle_ps(b, b, 0x55);
			P.lnear[2][k] = _mm_shuffle_ps(b, b, 0xaa), P.lnear[3][k] = _mm_shuffle_ps(b, b, 0xff);
			P.lfar[0][k] = _mm_shuffle_ps(f, f, 0x00), P.lfar[1][k] = _mm_shuffle_ps(f, f, 0x55);
			P.lfar[2][k] = _mm_shuffle_ps(f, f, 0xaa), P.lfar[3][k] = _mm_shuffle_ps(f, f, 0xff);
		}
		switch (oct) { /* one copy of the loop per octant, as group_hit */
		case 0: bvh_hit4(A, g, tr, best, found, &P, 0); break;
		case 1: bvh_hit4(A, g, tr, best, found, &P, 1); break;
		case 2: bvh_hit4(A, g, tr, best, found, &P, 2); break;
		case 3: bvh_hit4(A, g, tr, best, found, &P, 3); break;
		case 4: bvh_hit4(A, g, tr, best, found, &P, 4); break;
		case 5: bvh_hit4(A, g, tr, best, found, &P, 5); break;
		case 6: bvh_hit4(A, g, tr, best, found, &P, 6); break;
		default: bvh_hit4(A, g, tr, best, found, &P, 7); break;
		}
	}
	for (int i = 0; i < 4; i++) {
		hit[i] = found[i];
		if (found[i])
			accel_finish(A, g, &tr[i], &best[i], &h[i]);
	}
}

/* group_hit for np packets of four rays (np 4 or 16; tr[4 * j ...]: packet
 * j) from one origin and of one octant through g's tree (g->bvh.n_nodes4). */
static void group_hit_block(const struct accel *A, const struct group *g, struct trace *tr, uint32_t oct, int np,
			    struct hit *h, bool *hit)
{
	struct cand best[64];
	bool found[64];
	struct ray4x P[16];
	for (int i = 0; i < 4 * np; i++) {
		cand_init(&best[i]);
		found[i] = group_hit_unbounded(A, g, &tr[i], &best[i], false);
	}
	for (int j = 0; j < np; j++)
		ray_box4(tr + 4 * j, g->center, &P[j]);
	if (np == 16)
		group_hit64o(A, g, tr, best, found, P, oct);
	else
		group_hit16o(A, g, tr, best, found, P, oct);
	for (int i = 0; i < 4 * np; i++) {
		hit[i] = found[i];
		if (found[i])
			accel_finish(A, g, &tr[i], &best[i], &h[i]);
	}
}

/* A subtree on the any-hit packet walks' stack (bvh_occluded4, bvh_cross4). */
struct lanes_entry {
	uint32_t idx, n;
	unsigned lanes; /* the rays that met the subtree's box */
};

/* The any-hit packet walks' next subtree some ray in act met, popped into
 * *idx, *n and *lanes; false when the stack is empty. */
static inline bool any_pop(const struct lanes_entry *stack, int *sp, unsigned act, uint32_t *idx, uint32_t *n,
			   unsigned *lanes)
{
	do {
		if (*sp == 0)
			return false;
		--*sp;
	} while (!(stack[*sp].lanes & act));
	*idx = stack[*sp].idx;
	*n = stack[*sp].n;
	*lanes = stack[*sp].lanes;
	return true;
}

/* The any-hit packet walks' visit of node nd: each child against the four
 * rays (lane i: ray i) still in act; the lowest child some ray meets into
 * *idx, *n and *lanes, the others pushed; false when none is met. */
static inline __attribute__((always_inline)) bool any_node4(const struct bvh4 *nd, const uint32_t near[3],
							   const uint32_t far[3], __m128 tmin4, __m128 tmax4,
							   const struct ray4x *P, unsigned act,
							   struct lanes_entry *stack, int *sp, uint32_t *idx,
							   uint32_t *n, unsigned *lanes)
{
	const float *b = (const float *)(const void *)nd; /* rows as in node4_hit */
	unsigned m[4];
	for (int c = 0; c < 4; c++) {
		__m128 t0 = tmin4, t1 = tmax4;
		for (int k = 0; k < 3; k++) {
			__m128 tn = _mm_mul_ps(_mm_sub_ps(_mm_set1_ps(b[near[k] + (uint32_t)c]), P->o[k]), P->inv_near[k]);
			__m128 tf = _mm_mul_ps(_mm_sub_ps(_mm_set1_ps(b[far[k] + (uint32_t)c]), P->o[k]), P->inv_far[k]);
			t0 = _mm_max_ps(t0, tn);
			t1 = _mm_min_ps(t1, tf);
		}
		m[c] = (unsigned)_mm_movemask_ps(_mm_cmple_ps(t0, t1)) & act;
	}
	int first = -1;
	for (int c = 3; c >= 0; c--) {
		if (!m[c])
			continue;
		if (first >= 0) {
			stack[*sp].idx = nd->idx[first];
			stack[*sp].n = nd->n[first];
			stack[(*sp)++].lanes = m[first];
		}
		first = c;
	}
	if (first < 0)
		return false;
	*idx = nd->idx[first];
	*n = nd->n[first];
	*lanes = m[first];
	return true;
}

/*
 * The any-hit packet traversal of g's bounded references for the rays
 * (lanes) in *active: a subtree is visited when an active ray may hit it
 * (children in slot order, as group_occluded_t), each stack entry keeps
 * the lanes that met its box, and a leaf's references are each tested
 * against those of its lanes still active. A ray leaves *active at its
 * first blocker (*hint then names it); the walk ends when no ray is left.
 * Every ray tests what group_occluded_t would let it test, perhaps more:
 * anything hit blocks, so its answer is the same.
 */
static inline __attribute__((always_inline)) void bvh_occluded4(const struct accel *A, const struct group *g,
								struct trace tr[4], unsigned *active, uint32_t *hint,
								const struct ray4x *P, const uint32_t oct)
{
	const struct bvh4 *nodes = g->bvh.nodes;
	const uint32_t near[3] = { 12 * (oct & 1), 4 + 12 * (oct >> 1 & 1), 8 + 12 * (oct >> 2 & 1) };
	const uint32_t far[3] = { 12 * (~oct & 1), 4 + 12 * (~oct >> 1 & 1), 8 + 12 * (~oct >> 2 & 1) };
	const __m128 tmin4 = lanes_box_tmin(tr, P->tscale), tmax4 = lanes_box_tmax(tr, P->tscale);
	struct lanes_entry stack[3 * BVH_MAX_DEPTH + 4];
	int sp = 0;
	unsigned act = *active, lanes = act;
	uint32_t idx = 0, n = 0;
	uint32_t polls = ACCEL_POLL_POPS;
	/* TRIANGLE PRE-TEST where g->occ_pretest, set up at the first block two
	 * rays meet */
	struct tri4 q;
	bool q_ready = false;
	for (;;) {
		if (n & LEAF_BLOCK) {
			const float *tb = &g->tblk[idx];
			uint32_t nt = n & ~LEAF_BLOCK;
			for (uint32_t k = 0; k < nt && (lanes &= act); k++) {
				uint32_t ref = blk_ref(tb, nt, k);
				unsigned test = lanes;
				if (g->occ_pretest && (test & (test - 1))) {
					if (!q_ready) {
						tri4_init(&q, tr);
						q_ready = true;
					}
					if (q.ok)
						test &= ~tri4_reject(&q, tb, nt, k);
				}
				for (unsigned l = test; l; l &= l - 1) {
					int i = __builtin_ctz(l);
					if (tri_occludes(g, ref, &tr[i])) {
						act &= ~(1u << i);
						*hint = ref;
					}
				}
			}
			if (!act)
				break;
		} else if (n) {
			for (uint32_t k = 0; k < n && (lanes &= act); k++) {
				uint32_t ref = group_ref(g, idx + k);
				for (unsigned l = lanes; l; l &= l - 1) {
					int i = __builtin_ctz(l);
					if (ref_occludes(A, g, ref, &tr[i])) {
						act &= ~(1u << i);
						*hint = ref;
					}
				}
			}
			if (!act)
				break;
		} else {
			if (any_node4(&nodes[idx], near, far, tmin4, tmax4, P, act, stack, &sp, &idx, &n, &lanes))
				continue;
		}
		if (__builtin_expect(--polls == 0, 0)) { /* CANCELLATION, as bvh_hit */
			polls = ACCEL_POLL_POPS;
			if (cancel_poll())
				break;
		}
		if (!any_pop(stack, &sp, act, &idx, &n, &lanes))
			break;
	}
	*active = act;
}

/* The four rays' box constants (struct ray4x) in group g's frame. */
static void ray4x_init(struct ray4x *P, const struct trace tr[4], const struct group *g)
{
	ray_box4(tr, g->center, P);
}

/* accel_occluded4's packet query in g (g->bvh.n_nodes4, no big leaves) for
 * four rays of one octant: unbounded references and the hint ray by ray,
 * then the tree for the rays not yet blocked. */
static void group_occluded4(const struct accel *A, const struct group *g, struct trace tr[4], uint32_t oct,
			    bool occ[4], uint32_t *hint)
{
	unsigned active = 0;
	for (int i = 0; i < 4; i++) {
		bool blocked = unb_any_occludes(A, g, &tr[i], hint) || hint_occludes(A, g, *hint, &tr[i]);
		active |= (unsigned)!blocked << i;
	}
	if (active) {
		struct ray4x P;
		ray4x_init(&P, tr, g);
		switch (oct) { /* one copy of the loop per octant, as group_hit */
		case 0: bvh_occluded4(A, g, tr, &active, hint, &P, 0); break;
		case 1: bvh_occluded4(A, g, tr, &active, hint, &P, 1); break;
		case 2: bvh_occluded4(A, g, tr, &active, hint, &P, 2); break;
		case 3: bvh_occluded4(A, g, tr, &active, hint, &P, 3); break;
		case 4: bvh_occluded4(A, g, tr, &active, hint, &P, 4); break;
		case 5: bvh_occluded4(A, g, tr, &active, hint, &P, 5); break;
		case 6: bvh_occluded4(A, g, tr, &active, hint, &P, 6); break;
		default: bvh_occluded4(A, g, tr, &active, hint, &P, 7); break;
		}
	}
	for (int i = 0; i < 4; i++)
		occ[i] = !(active >> i & 1);
	if (active == 15)
		*hint = ACCEL_NO_HINT; /* as accel_occluded_hint */
}

/*
 * accel_cross4's traversal (SHADOW CROSSINGS, accel_cross.c): the tree as
 * bvh_occluded4 walks it, each ray tested for what it meets, with
 * accel_cross's tests (a leaf block's triangles through the TRIANGLE
 * PRE-TEST wherever two rays meet it); a ray is dropped (its bit cleared
 * from *active) when it is blocked. Q[i] is ray i's query.
 */
static inline __attribute__((always_inline)) void bvh_cross4(const struct group *g, struct trace tr[4],
							     unsigned *active, const struct ray4x *P,
							     const uint32_t oct, const struct cross_query Q[4])
{
	const struct bvh4 *nodes = g->bvh.nodes;
	const uint32_t near[3] = { 12 * (oct & 1), 4 + 12 * (oct >> 1 & 1), 8 + 12 * (oct >> 2 & 1) };
	const uint32_t far[3] = { 12 * (~oct & 1), 4 + 12 * (~oct >> 1 & 1), 8 + 12 * (~oct >> 2 & 1) };
	const __m128 tmin4 = lanes_box_tmin(tr, P->tscale), tmax4 = lanes_box_tmax(tr, P->tscale);
	struct lanes_entry stack[3 * BVH_MAX_DEPTH + 4];
	int sp = 0;
	unsigned act = *active, lanes = act;
	uint32_t idx = 0, n = 0;
	uint32_t polls = ACCEL_POLL_POPS;
	struct tri4 q; /* TRIANGLE PRE-TEST, set up at the first block two rays meet */
	bool q_ready = false;
	for (;;) {
		if (n & LEAF_BLOCK) {
			const float *tb = &g->tblk[idx];
			uint32_t nt = n & ~LEAF_BLOCK;
			for (uint32_t k = 0; k < nt && (lanes &= act); k++) {
				uint32_t ref = blk_ref(tb, nt, k);
				unsigned test = lanes;
				if (test & (test - 1)) {
					if (!q_ready) {
						tri4_init(&q, tr);
						q_ready = true;
					}
					if (q.ok)
						test &= ~tri4_reject(&q, tb, nt, k);
				}
				for (unsigned l = test; l; l &= l - 1) {
					int i = __builtin_ctz(l);
					if (!cross_tri(&Q[i], g, ref, &tr[i], NULL))
						act &= ~(1u << i);
				}
			}
			if (!act)
				break;
		} else if (n) {
			for (uint32_t k = 0; k < n && (lanes &= act); k++) {
				uint32_t ref = group_ref(g, idx + k);
				for (unsigned l = lanes; l; l &= l - 1) {
					int i = __builtin_ctz(l);
					if (!accel_cross_ref(&Q[i], g, ref, &tr[i], NULL))
						act &= ~(1u << i);
				}
			}
			if (!act)
				break;
		} else {
			if (any_node4(&nodes[idx], near, far, tmin4, tmax4, P, act, stack, &sp, &idx, &n, &lanes))
				continue;
		}
		if (__builtin_expect(--polls == 0, 0)) { /* CANCELLATION, as bvh_hit */
			polls = ACCEL_POLL_POPS;
			if (cancel_poll())
				break;
		}
		if (!any_pop(stack, &sp, act, &idx, &n, &lanes))
			break;
	}
	*active = act;
}

/* accel_cross4's packet query in g for four rays of one octant: the hint
 * and the unbounded references ray by ray, then the tree for the rays
 * still open. */
static void group_cross4(const struct group *g, struct trace tr[4], uint32_t oct, const struct cross_query Q[4],
			 bool open[4])
{
	unsigned active = 0;
	for (int i = 0; i < 4; i++) {
		bool blocked = cross_hint_blocks(&Q[i], g, &tr[i]) || !accel_cross_unb(&Q[i], g, &tr[i], NULL);
		active |= (unsigned)!blocked << i;
	}
	if (active) {
		struct ray4x P;
		ray4x_init(&P, tr, g);
		switch (oct) { /* one copy of the loop per octant, as group_hit */
		case 0: bvh_cross4(g, tr, &active, &P, 0, Q); break;
		case 1: bvh_cross4(g, tr, &active, &P, 1, Q); break;
		case 2: bvh_cross4(g, tr, &active, &P, 2, Q); break;
		case 3: bvh_cross4(g, tr, &active, &P, 3, Q); break;
		case 4: bvh_cross4(g, tr, &active, &P, 4, Q); break;
		case 5: bvh_cross4(g, tr, &active, &P, 5, Q); break;
		case 6: bvh_cross4(g, tr, &active, &P, 6, Q); break;
		default: bvh_cross4(g, tr, &active, &P, 7, Q); break;
		}
	}
	for (int i = 0; i < 4; i++) {
		open[i] = active >> i & 1;
		if (open[i])
			accel_cross_sort(Q[i].X);
	}
}
#endif

/* ---- public queries ----------------------------------------------------------------- */

#if defined(__SSE2__)
/* Whether the four rays can be traced as a packet through the root's tree
 * (all valid, one octant, a 4-wide tree): then tr and *oct are set up. */
static inline bool packet_start(const struct accel *a, const struct ray r[4], struct trace tr[4], uint32_t *oct)
{
	const struct group *g = a->root;
	if (!g || g->bvh.root_n || !g->bvh.n_nodes4 || g->big_leaf)
		return false;
	*oct = ray_octant(r[0].d);
	for (int i = 0; i < 4; i++)
		if (!ray_ok(&r[i]) || ray_octant(r[i].d) != *oct)
			return false;
	for (int i = 0; i < 4; i++)
		trace_init(&tr[i], r[i].o, r[i].d, ray_tmin(&r[i]), r[i].tmax);
	return true;
}
#endif

void accel_intersect4(const struct accel *a, const struct ray r[4], struct hit h[4], bool hit[4])
{
#if defined(__SSE2__)
	struct trace tr[4];
	uint32_t oct;
	if (packet_start(a, r, tr, &oct)) {
		group_hit4(a, a->root, tr, oct, h, hit);
		return;
	}
#endif
	for (int i = 0; i < 4; i++) /* rays of different octants, a root without a tree */
		hit[i] = accel_intersect(a, &r[i], &h[i]);
}

/* accel_intersect16 (np 4) and accel_intersect64 (np 16). */
static void intersect_block(const struct accel *a, const struct ray *r, int np, struct hit *h, bool *hit)
{
#if defined(__SSE2__)
	struct trace tr[64];
	uint32_t oct[16];
	bool one = true; /* one origin (the same bits), one octant: the whole-block traversal */
	for (int i = 1; i < 4 * np && one; i++)
		one = memcmp(&r[i].o, &r[0].o, sizeof r[0].o) == 0;
	for (int j = 0; j < np && one; j++)
		one = packet_start(a, r + 4 * j, tr + 4 * j, &oct[j]) && oct[j] == oct[0];
	if (one) {
		group_hit_block(a, a->root, tr, oct[0], np, h, hit);
		return;
	}
#endif
	for (int j = 0; j < 4; j++) /* four smaller blocks */
		if (np == 16)
			intersect_block(a, r + 16 * j, 4, h + 16 * j, hit + 16 * j);
		else
			accel_intersect4(a, r + 4 * j, h + 4 * j, hit + 4 * j);
}

void accel_intersect16(const struct accel *a, const struct ray r[16], struct hit h[16], bool hit[16])
{
	intersect_block(a, r, 4, h, hit);
}

void accel_intersect64(const struct accel *a, const struct ray r[64], struct hit h[64], bool hit[64])
{
	intersect_block(a, r, 16, h, hit);
}

void accel_occluded4(const struct accel *a, const struct ray r[4], bool occ[4], uint32_t *hint)
{
#if defined(__SSE2__)
	struct trace tr[4];
	uint32_t oct;
	if (packet_start(a, r, tr, &oct)) {
		group_occluded4(a, a->root, tr, oct, occ, hint);
		return;
	}
#endif
	for (int i = 0; i < 4; i++) /* rays of different octants, a root without a tree */
		occ[i] = accel_occluded_hint(a, &r[i], hint);
}

void accel_cross4(const struct accel *a, const struct ray r[4], const struct accel_cross_filter *f,
		  struct accel_crossings x[4], bool open[4], uint32_t *hint)
{
#if defined(__SSE2__)
	struct trace tr[4];
	uint32_t oct;
	if (packet_start(a, r, tr, &oct)) {
		const struct cross_query Q[4] = { { a, &r[0], f, &x[0], hint }, { a, &r[1], f, &x[1], hint },
						  { a, &r[2], f, &x[2], hint }, { a, &r[3], f, &x[3], hint } };
		for (int i = 0; i < 4; i++)
			x[i].n = 0;
		group_cross4(a->root, tr, oct, Q, open);
		return;
	}
#endif
	for (int i = 0; i < 4; i++) /* rays of different octants, a root without a tree */
		open[i] = accel_cross(a, &r[i], f, &x[i], hint);
}
