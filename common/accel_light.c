/*
 * accel_light.c - LIGHT BUFFERS (accel_int.h): the root group's references
 * sorted into a direction cube around each point light, so that a shadow
 * ray toward the light tests only what lies in its direction.
 *
 * WHY NO CELL MISSES A BLOCKER. The queries answer exactly what the tree
 * answers: "anything hit" is a boolean over the references, each tested by
 * the same function on the same ray, so the buffer must only never leave
 * out a reference the ray can hit. The tree relies on this: a reference's
 * test reports a hit only where the exact ray meets its padded box (the
 * box tests are conservative, accel_int.h). So it is enough that every
 * point X of the exact ray inside a reference's box projects into a cell
 * that lists the reference.
 *
 * The ray is o + t d, d = fl(lp - o), t in [tmin, tmax] within [0, 1].
 * Componentwise d = (lp - o)(1 + e), |e| <= u = 2^-53, so X - lp =
 * U ((1 - t) - t e) with U = o - lp = -d exactly: X lies along U but for a
 * relative error 2u / (1 - t), large only near the light. Let R bound
 * |U|_inf (the farthest box corner from the light; origins beyond it go to
 * the tree) and D = 1e-6 R.
 *   - A box within 3D of the light (|X - lp|_inf, computed) is NEAR: every
 *     query tests it (lbuf.near), in no cell.
 *   - Any other box holds only points X with |X - lp|_inf > 2D (3D less the
 *     rounding of the corners, about 1e-16 R). Such an X has 1 - t > 2D /
 *     |U_a| - u >= 1.9e-6 (a is U's largest axis, the face the query
 *     reads), so X's projection is U's within 2u / 1.9e-6 < 1.2e-10
 *     relative, and its depth on the face is above D. The box clipped to
 *     depths >= D has corners of positive depth, so its projection is the
 *     rectangle of its eight corners' (a central projection maps the
 *     convex box to the convex hull of its corners' images), computed with
 *     relative errors near 1e-16 (corners as (center - lp) + box: errors of
 *     1e-16 R against depths >= D, 1e-10 relative); padded by 1e-8, it
 *     holds X's projection with room to spare, and the cells are found by
 *     the same monotonic rounding (lbuf_cell) the query uses, clamped to
 *     the face's window (ZOOMED FACES, below), which is monotonic too.
 *   - A box whose rectangles would cover more than a 16th of the cube's
 *     faces (LBUF_WIDE: the light is close to it) is WIDE: it joins the
 *     NEAR list instead.
 *   - X's depth is at most |U_a| (1 + u), so entries whose dmin (rounded
 *     down to float) exceeds |U_a| (1 + 1e-9) cannot hold a hit: the
 *     query stops there (entries sorted by dmin).
 * tests/unit/test_lbuf.c compares the answers with the tree's on rays
 * toward the light from everywhere, and near it.
 */
#include "common/accel_int.h"
#include "common/cancel.h"
#include "common/scene.h"

#include <math.h>
#include <stdlib.h>

/* Cells per face side. A light gets no buffer (the tree answers) when its
 * entries would exceed LBUF_REF_ENTRIES a reference plus LBUF_CELL_ENTRIES
 * a cell, or what is left of LBUF_ALL_ENTRIES for all lights (32 MB);
 * at most LBUF_MAX_LIGHTS lights get one (384 KiB of cell starts each). Groups
 * of fewer than LBUF_MIN_REFS references keep the tree alone (a few
 * nodes deep), and so do those of more than LBUF_MAX_REFS. */
#define LBUF_N 128
#define LBUF_CELLS (6 * (uint64_t)LBUF_N * LBUF_N)
#define LBUF_REF_ENTRIES 24
#define LBUF_WIDE 16
#define LBUF_CELL_ENTRIES 2
#define LBUF_ALL_ENTRIES (1u << 22)
#define LBUF_MAX_LIGHTS 16
#define LBUF_MIN_REFS 64
#define LBUF_MAX_REFS (1u << 20)
#define LBUF_NEAR 1e-6
#define LBUF_PAD 1e-8

static double comp(vec3 v, int k) { return k == 0 ? v.x : k == 1 ? v.y : v.z; }

/* A reference's cells on one face: columns i0..i1, rows j0..j1. */
struct lrect {
	uint32_t ref;
	uint16_t face, i0, i1, j0, j1;
	float dmin;
};

static float f_down(double x)
{
	float f = (float)x;
	return (double)f > x ? nextafterf(f, -INFINITY) : f;
}

/* The padded projection of box [lo, hi] (relative to the light) on face
 * f: ext[0..1] its p range, ext[2..3] its q range, *dmin its nearest depth
 * (>= D); false when the box has no point of depth >= D on the face. */
static bool face_proj(vec3 lo, vec3 hi, int f, double D, double ext[4], double *dmin)
{
	int a = f >> 1, b = a == 0 ? 1 : 0, c = a == 2 ? 1 : 2;
	double s = (f & 1) ? -1 : 1;
	double d0 = s > 0 ? comp(lo, a) : -comp(hi, a), d1 = s > 0 ? comp(hi, a) : -comp(lo, a);
	if (!(d1 >= D))
		return false;
	if (d0 < D)
		d0 = D;
	if (comp(lo, b) > 2 * d1 || comp(hi, b) < -2 * d1 || comp(lo, c) > 2 * d1 || comp(hi, c) < -2 * d1)
		return false; /* beside the face (|p| or |q| >= 2 everywhere), known without dividing */
	double pb[2] = { comp(lo, b), comp(hi, b) }, pc[2] = { comp(lo, c), comp(hi, c) }, dd[2] = { d0, d1 };
	double pmin = INFINITY, pmax = -INFINITY, qmin = INFINITY, qmax = -INFINITY;
	for (int k = 0; k < 2; k++)
		for (int m = 0; m < 2; m++) {
			double p = pb[k] / dd[m], q = pc[k] / dd[m];
			pmin = geom_fmin(pmin, p), pmax = geom_fmax(pmax, p);
			qmin = geom_fmin(qmin, q), qmax = geom_fmax(qmax, q);
		}
	pmin -= LBUF_PAD, qmin -= LBUF_PAD;
	pmax += LBUF_PAD, qmax += LBUF_PAD;
	if (pmax < -1 || pmin > 1 || qmax < -1 || qmin > 1) /* beside the face */
		return false;
	ext[0] = pmin, ext[1] = pmax, ext[2] = qmin, ext[3] = qmax;
	*dmin = d0;
	return true;
}

/* The rectangle of box [lo, hi] on face f in cells, into *r (face_proj),
 * and *frac, the part of the whole face it covers. */
static bool face_rect(const struct lbuf *lb, vec3 lo, vec3 hi, int f, double D, struct lrect *r, double *frac)
{
	double ext[4], d0;
	if (!face_proj(lo, hi, f, D, ext, &d0))
		return false;
	*frac = (geom_fmin(ext[1], 1) - geom_fmax(ext[0], -1)) * (geom_fmin(ext[3], 1) - geom_fmax(ext[2], -1)) * 0.25;
	r->face = (uint16_t)f;
	r->i0 = (uint16_t)lbuf_cell(lb, (uint32_t)f, 0, ext[0]), r->i1 = (uint16_t)lbuf_cell(lb, (uint32_t)f, 0, ext[1]);
	r->j0 = (uint16_t)lbuf_cell(lb, (uint32_t)f, 1, ext[2]), r->j1 = (uint16_t)lbuf_cell(lb, (uint32_t)f, 1, ext[3]);
	r->dmin = f_down(d0);
	return true;
}

/*
 * ZOOMED FACES. A light sees the objects within a small part of each face
 * (balls_s4's flake: about 30 x 30 of the 128 x 128 cells, 19 entries a
 * cell), so each face's cells cover only the window where its small
 * references project (those narrower than LBUF_SMALL on both axes), at
 * most LBUF_ZOOM times finer than the whole face; larger ones, and rays,
 * beyond the window fall in its edge cells. Any window gives the tree's
 * answers: lbuf_cell is monotonic, clamping too, so a projection inside a
 * reference's padded rectangle still lands in one of its cells.
 */
#define LBUF_ZOOM 4.0
#define LBUF_SMALL 0.25
#define LBUF_DENSE 0.5 /* small references a cell, at most, that zooming aims for */

/* Every face whole: no zoom. */
static void whole_faces(struct lbuf *lb)
{
	for (int f = 0; f < 6; f++)
		for (int k = 0; k < 2; k++)
			lb->org[f][k] = -1, lb->scale[f][k] = 0.5 * lb->n;
}

static void zoom_faces(struct lbuf *lb, const struct group *g, const struct geom_box *boxes, const uint32_t *perm,
		       vec3 e, double D)
{
	double lo[6][2], hi[6][2];
	uint32_t n_small[6] = { 0, 0, 0, 0, 0, 0 };
	whole_faces(lb);
	for (int f = 0; f < 6; f++)
		for (int k = 0; k < 2; k++)
			lo[f][k] = INFINITY, hi[f][k] = -INFINITY;
	for (uint32_t i = 0; i < g->n_refs; i++) {
		if (cancel_poll_every(i))
			return; /* lbuf_build's loop sees it too */
		const struct geom_box *bx = &boxes[perm[i]];
		vec3 blo = v3_add(e, bx->lo), bhi = v3_add(e, bx->hi);
		for (int f = 0; f < 6; f++) {
			double ext[4], d0;
			if (!face_proj(blo, bhi, f, D, ext, &d0) || !(ext[1] - ext[0] < LBUF_SMALL) ||
			    !(ext[3] - ext[2] < LBUF_SMALL))
				continue;
			for (int k = 0; k < 2; k++) {
				lo[f][k] = geom_fmin(lo[f][k], ext[2 * k]);
				hi[f][k] = geom_fmax(hi[f][k], ext[2 * k + 1]);
			}
			n_small[f]++;
		}
	}
	for (int f = 0; f < 6; f++) {
		/* the zoom that brings the window's small references down to
		 * LBUF_DENSE a cell, 2 to LBUF_ZOOM, or none; an empty window
		 * (NaN or infinite extents) fails the tests below */
		double wa = geom_fmin(hi[f][0], 1) - geom_fmax(lo[f][0], -1), wb = geom_fmin(hi[f][1], 1) - geom_fmax(lo[f][1], -1);
		double cells1 = wa * wb * 0.25 * lb->n * lb->n; /* the window's cells at zoom 1 */
		double z = cells1 > 0 ? sqrt(n_small[f] / (cells1 * LBUF_DENSE)) : 1;
		z = z > LBUF_ZOOM ? LBUF_ZOOM : z;
		/* on each axis at most z finer, and not at all where that would be
		 * less than twice finer (not worth the entries) */
		bool zoom = z >= 2;
		for (int k = 0; k < 2; k++)
			zoom &= geom_fmin(hi[f][k], 1) - geom_fmax(lo[f][k], -1) <= 1;
		if (!zoom) /* nothing small, sparse, or spread over the face */
			continue;
		for (int k = 0; k < 2; k++) {
			double a = geom_fmax(lo[f][k], -1), b = geom_fmin(hi[f][k], 1), w = 2 / z;
			if (b - a < w) { /* centred, z finer, inside [-1, 1] */
				double m = 0.5 * (a + b);
				a = geom_fmin(geom_fmax(m - 0.5 * w, -1), 1 - w);
				b = a + w;
			}
			lb->org[f][k] = a;
			lb->scale[f][k] = lb->n / (b - a);
		}
	}
}

/* Rectangles nearest first (then by reference: the same order every build). */
static int rect_order(const void *x, const void *y)
{
	const struct lrect *a = x, *b = y;
	if (a->dmin != b->dmin)
		return a->dmin < b->dmin ? -1 : 1;
	return (a->ref > b->ref) - (a->ref < b->ref);
}

/* A reference's slot in the stamp array: kinds one after another. */
static uint32_t stamp_slot(const struct group *g, uint32_t ref)
{
	uint32_t i = REF_IDX(ref);
	switch (REF_KIND(ref)) {
	case REF_SPHERE: return i;
	case REF_TRI: return g->n_sph + i;
	case REF_XPRIM: return g->n_sph + g->n_tri + i;
	default: return g->n_sph + g->n_tri + g->n_xp + i;
	}
}

/* NEAR reference ref with its plane where it is a flat triangle (FLAT NEAR:
 * the axis and the first vertex's coordinate, as tri_flat_behind reads them) */
static struct lbuf_near near_entry(const struct group *g, uint32_t ref)
{
	struct lbuf_near e = { 0, ref, 3 };
	if (REF_KIND(ref) == REF_TRI && g->tri_flat[REF_IDX(ref)] <= 2) {
		const struct gtri *gt = &g->tri[REF_IDX(ref)];
		const struct gmesh *m = &g->mesh[gt->mesh];
		e.flat = g->tri_flat[REF_IDX(ref)];
		e.c = geom_comp(&m->v[tri_ix(m, gt->tri)[0]], (int)e.flat);
	}
	return e;
}

/*
 * FLAT NEAR's box: the origins o from which flat_behind holds for every flat
 * NEAR triangle of lb on the ray o + t d, d = lp - o, t >= tmin >= 0 (the
 * queries' rays). For a triangle in the plane x_p = c, the sign of d_p =
 * fl(lp_p - o_p) is that of lp_p - o_p (rounding keeps signs and zeros), so
 * flat_behind holds for c <= o_p <= lp_p when c < lp_p (o on the plane's
 * side of the light or in the plane, the ray not moving toward it) and for
 * lp_p <= o_p <= c when c > lp_p; a plane through the light (c = lp_p,
 * -0 and +0 alike) leaves the box empty. The queries reach the box only
 * with d = lp - o (compared with ==, so a -0 component may stand for +0:
 * flat_behind reads no zero's sign) and tmin >= 0. A NaN c (three vertices
 * with the same NaN coordinate) gives a box flat_behind does not agree
 * with, but such a triangle is never hit (geom_tri_hit_p), so skipping it
 * changes no answer either. tests/unit/test_flatnear.c tests the claim.
 */
static void flat_box(struct lbuf *lb)
{
	double lo[3] = { -INFINITY, -INFINITY, -INFINITY }, hi[3] = { INFINITY, INFINITY, INFINITY };
	for (uint32_t k = 0; k < lb->n_near_flat; k++) {
		int p = (int)lb->near[k].flat;
		double c = lb->near[k].c, l = geom_comp(&lb->lp, p);
		if (c != l) {
			lo[p] = geom_fmax(lo[p], geom_fmin(c, l));
			hi[p] = geom_fmin(hi[p], geom_fmax(c, l));
		} else {
			lo[p] = INFINITY;
			hi[p] = -INFINITY;
		}
	}
	lb->flat_lo = v3(lo[0], lo[1], lo[2]);
	lb->flat_hi = v3(hi[0], hi[1], hi[2]);
}

static void lbuf_free(struct lbuf *lb)
{
	if (!lb)
		return;
	free(lb->start);
	free(lb->ent);
	free(lb->near);
	free(lb);
}

/* Light lp's buffer over g's n references, its faces zoomed or whole;
 * NULL when over budget (the tree answers) or out of memory (*oom set). */
static struct lbuf *lbuf_build(const struct group *g, const struct geom_box *boxes, const uint32_t *perm, vec3 lp,
			       uint64_t left, bool zoom, bool *oom)
{
	uint32_t n = g->n_refs;
	struct lbuf *lb = calloc(1, sizeof *lb);
	struct lrect *rects = malloc((size_t)n * 6 * sizeof *rects);
	uint32_t *cnt = NULL, *stamp = NULL;
	if (!lb || !rects)
		goto oom;
	lb->near = malloc((size_t)n * sizeof *lb->near);
	if (!lb->near)
		goto oom;
	lb->lp = lp;
	lb->n = LBUF_N;
	vec3 e = v3_sub(g->center, lp);
	double R = 0;
	for (uint32_t k = 0; k < n; k++) {
		const struct geom_box *bx = &boxes[perm[k]];
		vec3 lo = v3_add(e, bx->lo), hi = v3_add(e, bx->hi);
		for (int a = 0; a < 3; a++)
			R = geom_fmax(R, geom_fmax(fabs(comp(lo, a)), fabs(comp(hi, a))));
	}
	lb->R = R;
	double D = LBUF_NEAR * R;
	if (zoom)
		zoom_faces(lb, g, boxes, perm, e, D);
	else
		whole_faces(lb);
	uint32_t n_rects = 0;
	uint64_t total = 0;
	const uint64_t cells = LBUF_CELLS;
	uint64_t budget = (uint64_t)n * LBUF_REF_ENTRIES + cells * LBUF_CELL_ENTRIES;
	if (budget > left)
		budget = left;
	for (uint32_t k = 0; k < n; k++) {
		if (cancel_poll_every(k))
			goto over;
		const struct geom_box *bx = &boxes[perm[k]];
		vec3 lo = v3_add(e, bx->lo), hi = v3_add(e, bx->hi);
		double dist = 0; /* |X - lp|_inf over the box */
		for (int a = 0; a < 3; a++) {
			double l = comp(lo, a), h = comp(hi, a);
			dist = geom_fmax(dist, l > 0 ? l : h < 0 ? -h : 0);
		}
		if (dist <= 3 * D) { /* NEAR: every query tests it */
			lb->near[lb->n_near++].ref = g->refs[k];
			continue;
		}
		uint32_t n0 = n_rects;
		uint64_t area = 0;
		double faces = 0; /* how many whole faces its rectangles cover */
		for (int f = 0; f < 6; f++) {
			struct lrect *r = &rects[n_rects];
			double frac;
			if (!face_rect(lb, lo, hi, f, D, r, &frac))
				continue;
			r->ref = g->refs[k];
			area += (uint64_t)(r->i1 - r->i0 + 1) * (uint64_t)(r->j1 - r->j0 + 1);
			faces += frac;
			n_rects++;
		}
		if (faces > 6.0 / LBUF_WIDE) { /* WIDE: tested by every query too */
			n_rects = n0;
			lb->near[lb->n_near++].ref = g->refs[k];
			continue;
		}
		total += area;
		if (total > budget)
			goto over;
	}
	qsort(rects, n_rects, sizeof *rects, rect_order);
	stamp = calloc((size_t)g->n_sph + g->n_tri + g->n_xp + g->n_inst + 1, sizeof *stamp);
	cnt = calloc(cells + 1, sizeof *cnt);
	lb->ent = malloc((total ? total : 1) * sizeof *lb->ent);
	if (!stamp || !cnt || !lb->ent)
		goto oom;
	uint32_t nn = 0; /* NEAR: one entry per reference */
	for (uint32_t k = 0; k < lb->n_near; k++) {
		uint32_t *st = &stamp[stamp_slot(g, lb->near[k].ref)];
		if (!*st) {
			*st = 1;
			lb->near[nn++] = near_entry(g, lb->near[k].ref);
		}
	}
	for (uint32_t k = 0; k < nn; k++)
		stamp[stamp_slot(g, lb->near[k].ref)] = 0;
	lb->n_near = nn;
	/* FLAT NEAR: the flat triangles first (swapped forward; the order
	 * only decides which blocker a query names as its hint) */
	uint32_t nf = 0;
	for (uint32_t k = 0; k < nn; k++)
		if (lb->near[k].flat <= 2) {
			struct lbuf_near x = lb->near[nf];
			lb->near[nf++] = lb->near[k];
			lb->near[k] = x;
		}
	lb->n_near_flat = nf;
	flat_box(lb);
	/* a counting sort in one array: start[k + 1] counts cell k's entries,
	 * then (summed) is cell k's end; the rectangles, filled last first,
	 * move it down to cell k's first entry, each cell nearest first */
	lb->start = cnt;
	cnt = NULL;
	uint32_t *start = lb->start;
	for (uint32_t k = 0; k < n_rects; k++) {
		const struct lrect *r = &rects[k];
		for (uint32_t j = r->j0; j <= r->j1; j++)
			for (uint32_t i = r->i0; i <= r->i1; i++)
				start[((uint64_t)r->face * LBUF_N + j) * LBUF_N + i + 1]++;
	}
	for (uint64_t k = 0; k < cells; k++)
		start[k + 1] += start[k];
	uint32_t all = start[cells];
	for (uint32_t k = n_rects; k-- > 0;) {
		const struct lrect *r = &rects[k];
		for (uint32_t j = r->j0; j <= r->j1; j++)
			for (uint32_t i = r->i0; i <= r->i1; i++)
				lb->ent[--start[((uint64_t)r->face * LBUF_N + j) * LBUF_N + i + 1]] =
					(struct lbuf_ent){ r->dmin, r->ref };
	}
	for (uint64_t k = 0; k < cells; k++) /* start[k + 1] is cell k's first entry now */
		start[k] = start[k + 1];
	start[cells] = all;
	/* each cell nearest first (the rectangles were), one entry per
	 * reference (a sliced cylinder or a split triangle has several boxes):
	 * the first, nearest; stamp[slot] = 1 + the last cell that has it */
	uint32_t out = 0;
	for (uint64_t k = 0; k < cells; k++) {
		uint32_t s0 = lb->start[k], s1 = lb->start[k + 1];
		lb->start[k] = out;
		for (uint32_t m = s0; m < s1; m++) {
			uint32_t *st = &stamp[stamp_slot(g, lb->ent[m].ref)];
			if (*st != (uint32_t)k + 1) {
				*st = (uint32_t)k + 1;
				lb->ent[out++] = lb->ent[m];
			}
		}
	}
	lb->start[cells] = out;
	/* what dedupe left: the arrays at their sizes (shrinking never fails
	 * for good: the old block stays if realloc says no) */
	struct lbuf_ent *ent_fit = realloc(lb->ent, (out ? out : 1) * sizeof *lb->ent);
	if (ent_fit)
		lb->ent = ent_fit;
	struct lbuf_near *near_fit = realloc(lb->near, (lb->n_near ? lb->n_near : 1) * sizeof *lb->near);
	if (near_fit)
		lb->near = near_fit;
	free(rects);
	free(cnt);
	free(stamp);
	return lb;
over:
	free(rects);
	free(cnt);
	free(stamp);
	lbuf_free(lb);
	return NULL;
oom:
	*oom = true;
	goto over;
}

int accel_light_build(struct accel *A, const struct group *g, const struct geom_box *boxes, const uint32_t *perm)
{
	const struct scene *s = A->s;
	if (s->image.no_shadows || g->occ_pretest || g->n_refs < LBUF_MIN_REFS || g->n_refs > LBUF_MAX_REFS || !g->refs ||
	    !s->n_lights)
		return 0;
	A->lbuf = calloc(s->n_lights, sizeof *A->lbuf);
	if (!A->lbuf)
		return -1;
	uint64_t left = LBUF_ALL_ENTRIES;
	for (uint32_t i = 0, made = 0; i < s->n_lights && made < LBUF_MAX_LIGHTS; i++) {
		const struct scene_light *l = &s->lights[i];
		if (l->shape != LIGHT_POINT || l->no_shadows)
			continue;
		bool oom = false;
		struct lbuf *lb = lbuf_build(g, boxes, perm, l->position, left, true, &oom);
		if (!lb && !oom) /* zoomed, the larger references can fill a window's
				    cells beyond the budget: the whole faces, then */
			lb = lbuf_build(g, boxes, perm, l->position, left, false, &oom);
		if (oom)
			return -1;
		if (!lb)
			continue;
		A->lbuf[i] = lb;
		made++;
		left -= lb->start[LBUF_CELLS];
		A->st.bytes += sizeof *lb + (LBUF_CELLS + 1) * sizeof *lb->start +
			       (size_t)lb->start[LBUF_CELLS] * sizeof *lb->ent +
			       (size_t)lb->n_near * sizeof *lb->near;
	}
	return 0;
}

void accel_light_free(struct accel *A)
{
	if (!A->lbuf)
		return;
	for (uint32_t i = 0; i < A->s->n_lights; i++)
		lbuf_free(A->lbuf[i]);
	free(A->lbuf);
	A->lbuf = NULL;
}
