/*
 * accel_build.c - building the multi-level BVH: one group for the scene's
 * roots and one per define (built once, on first use), every object turned
 * into references (accel.c's header describes them), sliver triangles split
 * into several boxes and long tilted cylinders sliced, instance transforms rounded to the float inverse the
 * traversal uses, and the nesting depths checked before anything is built.
 *
 * The build polls the calling thread's cancel flag (cancel.h) in every loop
 * whose length the scene decides (objects, triangles, references, the BVH
 * builder's) and in the recursions over CSG and instances, and gives up
 * with ACCEL_CANCELLED when a poll says so; accel_build also checks
 * cancel_seen at the end, so a build some poll gave up in (csg_bounds
 * returns an empty box then) is never used.
 */
#include <assert.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "common/accel_int.h"
#include "common/cancel.h"

_Static_assert(ACCEL_CANCELLED == CANCEL_RETURN, "accel_build gives up with the core's value");

static const uint32_t tri_ix012[3] = { 0, 1, 2 };

/* ---- building ------------------------------------------------------------------------ */

static void group_free(struct group *g)
{
	if (!g)
		return;
	bvh_free(&g->bvh);
	free(g->refs);
	free(g->unb);
	free(g->sph);
	free(g->mesh);
	free(g->tri);
	free(g->tri_flat);
	free(g->xp);
	free(g->inst);
	free(g->bake);
	free(g->tblk);
	free(g);
}

void accel_free(struct accel *a)
{
	if (!a)
		return;
	if (a->gobj) {
		for (uint32_t i = 0; i < a->s->n_objects; i++) {
			geom_obj_clear(a->gobj[i]);
			free(a->gobj[i]);
		}
		free(a->gobj);
	}
	if (a->dgroup) {
		for (uint32_t i = 0; i < a->s->n_defines; i++)
			group_free(a->dgroup[i]);
		free(a->dgroup);
	}
	group_free(a->root);
	accel_light_free(a);
	free(a->lin_inv);
	free(a);
}

/* The geom_obj of object i, made on first use; NULL when out of memory. */
static struct geom_obj *get_gobj(struct accel *A, uint32_t i)
{
	if (!A->gobj) { /* the table exists only in scenes that need it */
		A->gobj = calloc((size_t)A->s->n_objects + 1, sizeof *A->gobj);
		if (!A->gobj)
			return NULL;
		A->st.bytes += ((size_t)A->s->n_objects + 1) * sizeof *A->gobj;
	}
	if (!A->gobj[i]) {
		struct geom_obj *g = malloc(sizeof *g);
		if (!g)
			return NULL;
		if (geom_obj_init(A->s, i, g) < 0) {
			free(g);
			return NULL;
		}
		A->gobj[i] = g;
		A->st.bytes += sizeof *g;
		if (g->kind == PRIM_POLYGON)
			A->st.bytes += g->u.poly.n_points * 2 * sizeof(double);
	}
	return A->gobj[i];
}

/*
 * Makes the geom_obj of obj and of everything below it (CSG subtrees).
 * Returns 0, -1 when out of memory, or ACCEL_CANCELLED. The recursion walks
 * every path through shared defines (exponential in their nesting), so it
 * polls the cancel flag at each object.
 */
static int prep_tree(struct accel *A, uint32_t obj)
{
	if (cancel_poll())
		return ACCEL_CANCELLED;
	if (!get_gobj(A, obj))
		return -1;
	struct scene_object tmp;
	const struct scene_object *o = scene_object(A->s, obj, &tmp);
	int rc = 0;
	if (o->kind == PRIM_CSG) {
		rc = prep_tree(A, o->u.csg.operand1);
		if (!rc)
			rc = prep_tree(A, o->u.csg.operand2);
	} else if (o->kind == PRIM_INSTANCE) {
		const struct scene_define *d = &A->s->defines[o->u.instance.define];
		for (uint32_t k = 0; k < d->n_objects && !rc; k++)
			rc = prep_tree(A, d->objects[k]);
	}
	return rc;
}

/* Pads a box by a relative epsilon so double rounding never culls a hit. */
static struct geom_box pad_box(struct geom_box b)
{
	double m = geom_fmax(geom_fmax(fabs(b.lo.x), fabs(b.lo.y)), geom_fmax(fabs(b.lo.z), fabs(b.hi.x)));
	m = geom_fmax(m, geom_fmax(fabs(b.hi.y), fabs(b.hi.z)));
	double e = 1e-9 * m + 1e-300;
	vec3 ev = v3(e, e, e);
	b.lo = v3_sub(b.lo, ev);
	b.hi = v3_add(b.hi, ev);
	return b;
}

static struct group *build_group(struct accel *A, const uint32_t *objs, uint32_t n, struct scene_error *err);

/*
 * Bounded references and their boxes while a group is built (grows). The
 * boxes are doubles (box), or, in a group of ACCEL_PACK_MIN instances or
 * more and no sphere or triangle (FLOAT BOXES), floats rounded outward
 * (fbox): half the build's biggest array. fbox is NULL in double mode.
 */
struct refbuf {
	uint32_t *ref;
	struct geom_box *box;
	float (*fbox)[6];
	uint32_t n, cap;
};

/* FLOAT BOXES. A box rounded outward to float still holds its item, so
 * the tree is as conservative as before (no hit is culled: pixels cannot
 * move) though its splits may differ from a double build's. Coordinates
 * beyond FBOX_MAX (where float loses the range) switch the group to
 * doubles (refbuf_to_double). */
#define FBOX_MAX 1e30

static float f_down(double x)
{
	float f = (float)x;
	return (double)f > x ? nextafterf(f, -INFINITY) : f;
}

static float f_up(double x)
{
	float f = (float)x;
	return (double)f < x ? nextafterf(f, INFINITY) : f;
}

/* Grows the arrays to cap nc. */
static int refbuf_grow(struct refbuf *b, uint32_t nc)
{
	uint32_t *nr = realloc(b->ref, (size_t)nc * sizeof *nr);
	if (!nr)
		return -1;
	b->ref = nr;
	if (b->fbox) {
		float(*nf)[6] = realloc(b->fbox, (size_t)nc * sizeof *nf);
		if (!nf)
			return -1;
		b->fbox = nf;
	} else {
		struct geom_box *nbx = realloc(b->box, (size_t)nc * sizeof *nbx);
		if (!nbx)
			return -1;
		b->box = nbx;
	}
	b->cap = nc;
	return 0;
}

/* Room for n references (n < ACCEL_MAX_REFS); floats when fl. */
static int refbuf_reserve(struct refbuf *b, uint32_t n, bool fl)
{
	if (fl && !b->fbox && !b->box) {
		b->fbox = malloc(sizeof *b->fbox); /* marks float mode; grown below */
		if (!b->fbox)
			return -1;
	}
	return n <= b->cap ? 0 : refbuf_grow(b, n);
}

/* Float mode to double mode: the boxes so far as doubles (rare: a group
 * with coordinates beyond FBOX_MAX). */
static int refbuf_to_double(struct refbuf *b)
{
	struct geom_box *nbx = malloc((size_t)(b->cap ? b->cap : 1) * sizeof *nbx);
	if (!nbx)
		return -1;
	for (uint32_t k = 0; k < b->n; k++) {
		const float *f = b->fbox[k];
		nbx[k].lo = v3(f[0], f[1], f[2]);
		nbx[k].hi = v3(f[3], f[4], f[5]);
	}
	free(b->fbox);
	b->fbox = NULL;
	b->box = nbx;
	return 0;
}

/* Box k of the bounded references: boxes[k], or fboxes[k] as doubles. */
static struct geom_box ref_box(const struct geom_box *boxes, const float (*fboxes)[6], uint32_t k)
{
	if (boxes)
		return boxes[k];
	struct geom_box b = { v3(fboxes[k][0], fboxes[k][1], fboxes[k][2]), v3(fboxes[k][3], fboxes[k][4], fboxes[k][5]) };
	return b;
}

static int refbuf_push(struct refbuf *b, uint32_t ref, struct geom_box box)
{
	if (b->n == b->cap) {
		if (b->cap >= ACCEL_MAX_REFS)
			return -1;
		uint32_t nc = b->cap ? (b->cap > ACCEL_MAX_REFS / 2 ? ACCEL_MAX_REFS : b->cap * 2) : 64;
		if (refbuf_grow(b, nc) < 0)
			return -1;
	}
	if (b->fbox) {
		double m = geom_fmax(geom_fmax(geom_fmax(fabs(box.lo.x), fabs(box.lo.y)), fabs(box.lo.z)),
				geom_fmax(geom_fmax(fabs(box.hi.x), fabs(box.hi.y)), fabs(box.hi.z)));
		if (!(m <= FBOX_MAX) && refbuf_to_double(b) < 0)
			return -1;
	}
	b->ref[b->n] = ref;
	if (b->fbox) {
		float *f = b->fbox[b->n++];
		f[0] = f_down(box.lo.x), f[1] = f_down(box.lo.y), f[2] = f_down(box.lo.z);
		f[3] = f_up(box.hi.x), f[4] = f_up(box.hi.y), f[5] = f_up(box.hi.z);
		return 0;
	}
	b->box[b->n++] = box;
	return 0;
}

/* Early split clipping: a triangle whose box is SPLIT_RATIO times its own
 * area or more (long diagonal slivers, as ear-clipped gear faces make) is
 * referenced by the boxes of its pieces clipped to halves of its box, down
 * to SPLIT_DEPTH levels. The pieces cover the triangle; a ray meeting it
 * through two pieces tests it twice and keeps the one t. */
#define SPLIT_RATIO 24.0
#define SPLIT_DEPTH 3

/* Clips convex polygon p (n <= 9 + depth vertices) to the side of the plane
 * x[axis] = at given by keep_below; returns the new count (out has room). */
static int clip_half(const vec3 *p, int n, int axis, double at, bool keep_below, vec3 *out)
{
	int m = 0;
	for (int i = 0; i < n; i++) {
		vec3 a = p[i], b = p[(i + 1) % n];
		double da = v3_comp(a, axis) - at, db = v3_comp(b, axis) - at;
		if (!keep_below)
			da = -da, db = -db;
		if (da <= 0)
			out[m++] = a;
		if ((da < 0 && db > 0) || (da > 0 && db < 0)) {
			vec3 x = v3_lerp(a, b, da / (da - db));
			if (axis == 0)
				x.x = at;
			else if (axis == 1)
				x.y = at;
			else
				x.z = at;
			out[m++] = x;
		}
	}
	return m;
}

static int push_pieces(struct refbuf *rb, uint32_t ref, const vec3 *poly, int n, int depth)
{
	struct geom_box bx = geom_box_empty();
	for (int i = 0; i < n; i++)
		bx = geom_box_point(bx, poly[i]);
	vec3 e = v3_sub(bx.hi, bx.lo);
	if (depth == SPLIT_DEPTH || !(e.x > 0 || e.y > 0 || e.z > 0))
		return refbuf_push(rb, ref, pad_box(bx));
	int axis = e.x >= e.y && e.x >= e.z ? 0 : e.y >= e.z ? 1 : 2;
	double at = 0.5 * (v3_comp(bx.lo, axis) + v3_comp(bx.hi, axis));
	vec3 half[16];
	for (int side = 0; side < 2; side++) {
		int m = clip_half(poly, n, axis, at, side == 0, half);
		if (m >= 3 && push_pieces(rb, ref, half, m, depth + 1) < 0)
			return -1;
	}
	return 0;
}

/* FLAT TRIANGLES (accel_trace.h): the axis whose coordinate a, b and c
 * share bit for bit (the lowest), or 3. */
static uint8_t flat_axis(const vec3 *a, const vec3 *b, const vec3 *c)
{
	for (int k = 0; k < 3; k++) {
		double x = geom_comp(a, k), y = geom_comp(b, k), z = geom_comp(c, k);
		if (memcmp(&x, &y, sizeof x) == 0 && memcmp(&x, &z, sizeof x) == 0)
			return (uint8_t)k;
	}
	return 3;
}

static int push_triangle(struct refbuf *rb, uint32_t ref, vec3 a, vec3 b, vec3 c)
{
	struct geom_box bx = geom_box_point(geom_box_point(geom_box_point(geom_box_empty(), a), b), c);
	vec3 e = v3_sub(bx.hi, bx.lo);
	double box_area = 2 * (e.x * e.y + e.y * e.z + e.z * e.x);
	double tri_area = 0.5 * v3_len(v3_cross(v3_sub(b, a), v3_sub(c, a)));
	if (!(tri_area > 0) || box_area < SPLIT_RATIO * tri_area)
		return refbuf_push(rb, ref, pad_box(bx));
	vec3 p[3] = { a, b, c };
	return push_pieces(rb, ref, p, 3, 0);
}

/*
 * LONG CYLINDERS. A tilted cylinder's box is mostly empty (in rings_s3 its
 * surface area is 4.4 times the cylinder's): a cylinder, capped or open,
 * is referenced by the boxes of n <= CYL_SLICES_MAX slices of its axis
 * segment, each grown by the extent of a disk across the axis, where that
 * makes the boxes' total area at most CYL_SPLIT_GAIN of the one box's. By
 * Cauchy's formula the area is proportional to how many boxes a random
 * line meets, so to the cylinder tests. The slice between two cuts holds
 * every disk across the axis there (the caps are the end disks); the cuts
 * are points of the one axis, each computed once for both its slices, and
 * pad_box covers their rounding as it covers that of the ends (`to` below
 * is geom_obj_local_bounds' expression). Every reference tests the whole
 * cylinder: a ray meeting two slices tests it twice and finds the same t
 * (geom_intersect reports the first root after tmin, if it is below tmax,
 * whatever tmax is), which does not beat itself (CANONICAL TIES in
 * accel_trace.h): the hits are the one box's, bit for bit.
 */
#define CYL_SLICES_MAX 8
#define CYL_SPLIT_GAIN 0.9

static double surf_area(struct geom_box b)
{
	vec3 e = v3_sub(b.hi, b.lo);
	return 2 * (e.x * e.y + e.y * e.z + e.z * e.x);
}

/* Slice k of n of cylinder go: its box in the parent's space, unpadded. */
static struct geom_box cyl_slice(const struct geom_obj *go, vec3 e, uint32_t k, uint32_t n)
{
	vec3 from = go->u.cyl.from, a = go->u.cyl.a;
	double h = go->u.cyl.h;
	vec3 p = k == 0 ? from : v3_add(from, v3_scale(a, h * k / n));
	vec3 q = k + 1 == n ? v3_add(from, v3_scale(a, h)) : v3_add(from, v3_scale(a, h * (k + 1) / n));
	struct geom_box b = { v3_sub(v3_min(p, q), e), v3_add(v3_max(p, q), e) };
	return go->has_xform ? geom_box_xform(&go->fwd, b) : b;
}

/* An xprim's references: one of box bx, or a long cylinder's slices. */
static int push_xprim(struct refbuf *rb, uint32_t ref, const struct geom_obj *go, struct geom_box bx)
{
	if (go->kind != PRIM_CYLINDER)
		return refbuf_push(rb, ref, pad_box(bx));
	vec3 a = go->u.cyl.a;
	double r = go->u.cyl.r; /* geom.c's disk_extent */
	vec3 e = v3(r * sqrt(fmax(0, 1 - a.x * a.x)), r * sqrt(fmax(0, 1 - a.y * a.y)), r * sqrt(fmax(0, 1 - a.z * a.z)));
	double best = CYL_SPLIT_GAIN * surf_area(bx);
	uint32_t n_best = 1;
	for (uint32_t n = 2; n <= CYL_SLICES_MAX; n++) {
		double sum = 0;
		for (uint32_t k = 0; k < n; k++)
			sum += surf_area(cyl_slice(go, e, k, n));
		if (sum < best)
			best = sum, n_best = n;
	}
	if (n_best == 1)
		return refbuf_push(rb, ref, pad_box(bx));
	for (uint32_t k = 0; k < n_best; k++)
		if (refbuf_push(rb, ref, pad_box(cyl_slice(go, e, k, n_best))) < 0)
			return -1;
	return 0;
}

/* Whether child c of node nd is a leaf of one to ACCEL_MAX_LEAF
 * triangles (LEAF BLOCKS). */
static bool tri_leaf(const struct group *g, const struct bvh4 *nd, int c)
{
	uint32_t n = nd->n[c];
	if (n == 0 || n > ACCEL_MAX_LEAF || isnan(nd->lo[0][c]))
		return false;
	for (uint32_t k = 0; k < n; k++)
		if (REF_KIND(g->refs[nd->idx[c] + k]) != REF_TRI)
			return false;
	return true;
}


/*
 * COST-WEIGHTED SAH: a reference's test cost for the builder (bvh_build_cost),
 * in quarters of a traversal step (BVH_COST_UNIT = 4), measured
 * (docs/performance.md, round 8): a triangle in a SIMD block is cheaper
 * than a step, a sphere a little dearer, a cylinder (its caps and the
 * exact quadratic) about three steps.
 * The tree changes, never a hit: the closest hit is chosen by (t, key)
 * whatever the order of the tests (cand_better).
 */
static uint8_t ref_cost(const struct group *g, uint32_t ref)
{
	switch (REF_KIND(ref)) {
	case REF_TRI: return 3;
	case REF_SPHERE: return 5;
	case REF_XPRIM: return g->xp[REF_IDX(ref)].g->kind == PRIM_CYLINDER ? 12 : BVH_COST_UNIT;
	default: return BVH_COST_UNIT; /* instances: as before */
	}
}

/*
 * LEAF BLOCKS (accel_int.h): every leaf of g's tree that is one to
 * ACCEL_MAX_LEAF triangles gets its block, and its node child the
 * block's offset in g->tblk and the LEAF_BLOCK flag. A group whose blocks
 * would not fit 32-bit offsets gets none (its leaves are tested as
 * before, with the same hits). Returns 0, -1 when out of memory, or
 * ACCEL_CANCELLED.
 */
static int make_blocks(struct group *g)
{
	uint64_t words = 0;
	for (uint32_t k = 0; k < g->bvh.n_nodes4; k++) {
		if (cancel_poll_every(k))
			return ACCEL_CANCELLED;
		for (int c = 0; c < 4; c++)
			if (tri_leaf(g, &g->bvh.nodes[k], c))
				words += BLK_ROWS * (uint64_t)g->bvh.nodes[k].n[c];
	}
	if (!words || words + BLK_PAD > UINT32_MAX)
		return 0; /* no blocks: the leaves as they are (the same hits) */
	g->tblk = calloc(words + BLK_PAD, sizeof *g->tblk);
	if (!g->tblk)
		return -1;
	g->n_tblk = (uint32_t)(words + BLK_PAD);
	g->bytes += (size_t)g->n_tblk * sizeof *g->tblk;
	uint32_t at = 0;
	for (uint32_t k = 0; k < g->bvh.n_nodes4; k++) {
		if (cancel_poll_every(k))
			return ACCEL_CANCELLED;
		struct bvh4 *nd = &g->bvh.nodes[k];
		for (int c = 0; c < 4; c++) {
			if (!tri_leaf(g, nd, c))
				continue;
			uint32_t n = nd->n[c];
			float *b = &g->tblk[at];
			for (uint32_t l = 0; l < n; l++) {
				uint32_t ref = g->refs[nd->idx[c] + l];
				const struct gtri *t = &g->tri[REF_IDX(ref)];
				const struct gmesh *m = &g->mesh[t->mesh];
				const uint32_t *ix = tri_ix(m, t->tri);
				float sv = 0;
				for (uint32_t j = 0; j < 3; j++)
					for (uint32_t q = 0; q < 3; q++) {
						float f = (float)geom_comp(&m->v[ix[j]], (int)q);
						b[(3 * j + q) * n + l] = f;
						/* as tri4_init's and the packets' once: a NaN is
						 * left out (it makes every comparison false) */
						sv = fabsf(f) > sv ? fabsf(f) : sv;
					}
				b[9 * n + l] = sv;
				memcpy(&b[10 * n + l], &ref, sizeof ref);
			}
			nd->n[c] |= LEAF_BLOCK;
			nd->idx[c] = at;
			at += BLK_ROWS * n;
		}
	}
	return 0;
}

/* The group of define d, built once. */
static struct group *define_group(struct accel *A, uint32_t d, struct scene_error *err)
{
	if (!A->dgroup[d])
		A->dgroup[d] = build_group(A, A->s->defines[d].objects, A->s->defines[d].n_objects, err);
	return A->dgroup[d];
}

/*
 * Puts g's instance records in leaf order: first the bounded ones, record k
 * being the one of reference all[perm[k]] (all NULL: reference j is
 * instance j), then the unbounded ones in
 * g->unb's order (their references renumbered). In place, cycle by cycle,
 * with a 4-byte index per record (a copy of the records would hold the
 * group's biggest array twice at the build's peak). Every record has one
 * reference, bounded or not. Returns 0, -1 when out of memory, or
 * ACCEL_CANCELLED when a cancel poll said true.
 */
static int order_instances(struct group *g, const uint32_t *all, const uint32_t *perm, uint32_t n_bounded)
{
	const uint32_t placed = 1u << 31; /* records number below 2^28 (ACCEL_MAX_REFS) */
	uint32_t *src = malloc(((size_t)g->n_inst + 1) * sizeof *src); /* slot j takes record src[j] */
	if (!src)
		return -1;
	for (uint32_t k = 0; k < n_bounded; k++)
		src[k] = all ? REF_IDX(all[perm[k]]) : perm[k];
	uint32_t next = n_bounded;
	for (uint32_t k = 0; k < g->n_unb; k++)
		if (REF_KIND(g->unb[k]) == REF_INST) {
			src[next] = REF_IDX(g->unb[k]);
			g->unb[k] = REF_MAKE(REF_INST, next++);
		}
	assert(next == g->n_inst);
	for (uint32_t k = 0; k < g->n_inst; k++) {
		if (cancel_poll_every(k)) {
			free(src);
			return ACCEL_CANCELLED;
		}
		if (src[k] & placed)
			continue;
		struct ginst first = g->inst[k];
		uint32_t j = k;
		while ((src[j] & ~placed) != k) {
			uint32_t from = src[j] & ~placed;
			g->inst[j] = g->inst[from];
			src[j] |= placed;
			j = from;
		}
		g->inst[j] = first;
		src[j] |= placed;
	}
	free(src);
	return 0;
}

/*
 * Builds the group over objects objs[0..n). Returns NULL with err filled on
 * failure (out of memory or too many primitives).
 */
static struct group *build_group(struct accel *A, const uint32_t *objs, uint32_t n, struct scene_error *err)
{
	const struct scene *s = A->s;
	struct group *g = calloc(1, sizeof *g);
	struct geom_box *boxes = NULL;
	float(*fboxes)[6] = NULL;
	uint32_t *all = NULL, *perm = NULL;
	struct refbuf rb = { NULL, NULL, NULL, 0, 0 };
	if (!g)
		goto oom;
	/* pass 1: counts */
	uint64_t n_sph = 0, n_mesh = 0, n_tri = 0, n_xp = 0, n_inst = 0, n_bake = 0;
	for (uint32_t k = 0; k < n; k++) {
		struct scene_object tmp;
		const struct scene_object *o = scene_object(s, objs[k], &tmp);
		switch (o->kind) {
		case PRIM_SPHERE:
			if (o->has_xform)
				n_xp++;
			else
				n_sph++;
			break;
		case PRIM_TRIANGLE:
			n_mesh++, n_tri++;
			n_bake += 4 + (o->u.triangle.has_normals ? 3 : 0) + (o->has_xform ? 3 : 0);
			break;
		case PRIM_RAW: {
			const struct scene_mesh *m = &s->meshes[o->u.raw.mesh];
			n_mesh++;
			n_tri += m->n_triangles;
			if (o->has_xform)
				n_bake += (uint64_t)m->n_vertices * (m->normals ? 2 : 1);
			break;
		}
		case PRIM_INSTANCE:
			n_inst++;
			break;
		default:
			n_xp++;
			break;
		}
	}
	uint64_t n_all = n_sph + n_tri + n_xp + n_inst;
	if (n_all >= ACCEL_MAX_REFS) {
		scene_errorf(err, ERRLEVEL_FATAL, "error: too many primitives in one group (%llu)",
			     (unsigned long long)n_all);
		goto fail;
	}
	g->sph = malloc((n_sph ? n_sph : 1) * sizeof *g->sph);
	g->mesh = malloc((n_mesh ? n_mesh : 1) * sizeof *g->mesh);
	g->tri = malloc((n_tri ? n_tri : 1) * sizeof *g->tri);
	g->tri_flat = malloc(n_tri ? n_tri : 1);
	g->xp = malloc((n_xp ? n_xp : 1) * sizeof *g->xp);
	g->inst = malloc((n_inst ? n_inst : 1) * sizeof *g->inst);
	g->bake = malloc((n_bake ? n_bake : 1) * sizeof *g->bake);
	if (!g->sph || !g->mesh || !g->tri || !g->tri_flat || !g->xp || !g->inst || !g->bake)
		goto oom;
	g->bytes = sizeof *g + n_sph * sizeof *g->sph + n_mesh * sizeof *g->mesh + n_tri * (sizeof *g->tri + 1) +
		   n_xp * sizeof *g->xp + n_inst * sizeof *g->inst + n_bake * sizeof *g->bake;

	/* pass 2: fill; bounded references go to all[]/boxes[], the rest to unb
	 * (room for one each; only split triangles make more) */
	if (refbuf_reserve(&rb, (uint32_t)n_all, n_sph == 0 && n_tri == 0 && n_inst >= ACCEL_PACK_MIN) < 0)
		goto oom;
	uint32_t n_unb = 0;
	uint32_t *unb = malloc((n_all ? n_all : 1) * sizeof *unb);
	if (!unb)
		goto oom;
	g->unb = unb;
	size_t nb = 0;
	for (uint32_t k = 0; k < n; k++) {
		if (cancel_poll_every(k))
			goto cancelled;
		uint32_t oi = objs[k];
		struct scene_object tmp;
		const struct scene_object *o = scene_object(s, oi, &tmp);
		struct geom_box bx;
		uint32_t ref;
		if (o->kind == PRIM_SPHERE && !o->has_xform) {
			struct gsphere *sp = &g->sph[g->n_sph];
			sp->c = o->u.sphere.centre;
			sp->r2 = o->u.sphere.radius * o->u.sphere.radius;
			const struct prim_sphere *ps = &o->u.sphere;
			bool dflt = ps->pole.x == 0 && ps->pole.y == 1 && ps->pole.z == 0 && ps->equator.x == 1 &&
				    ps->equator.y == 0 && ps->equator.z == 0; /* P = +y, E = +x */
			sp->obj = oi | (dflt ? 0 : GSPH_FRAME);
			sp->mat = o->material;
			vec3 rr = v3(o->u.sphere.radius, o->u.sphere.radius, o->u.sphere.radius);
			bx.lo = v3_sub(sp->c, rr);
			bx.hi = v3_add(sp->c, rr);
			if (refbuf_push(&rb, REF_MAKE(REF_SPHERE, g->n_sph++), pad_box(bx)) < 0)
				goto oom;
			continue;
		}
		if (o->kind == PRIM_TRIANGLE || o->kind == PRIM_RAW) {
			struct gmesh *m = &g->mesh[g->n_mesh];
			memset(m, 0, sizeof *m);
			m->obj = oi;
			m->mat = o->material;
			uint32_t ntri;
			mat34 inv;
			if (o->has_xform && !m34_invert(&o->xform, &inv))
				inv = m34_identity();
			if (o->kind == PRIM_TRIANGLE) {
				const struct prim_triangle *t = &o->u.triangle;
				vec3 *v = &g->bake[nb];
				v[0] = t->a, v[1] = t->b, v[2] = t->c;
				nb += 3;
				m->ov = v;
				m->v = v;
				if (o->has_xform) {
					vec3 *w = &g->bake[nb];
					for (int q = 0; q < 3; q++)
						w[q] = m34_point(&o->xform, v[q]);
					nb += 3;
					m->v = w;
				}
				if (t->has_normals) {
					vec3 *nn = &g->bake[nb];
					nn[0] = t->na, nn[1] = t->nb, nn[2] = t->nc;
					if (o->has_xform)
						for (int q = 0; q < 3; q++)
							nn[q] = m34_normal(&inv, nn[q]);
					nb += 3;
					m->n = nn;
				}
				m->ix = tri_ix012;
				vec3 *fn = &g->bake[nb++];
				*fn = tri_normal(m, tri_ix012);
				m->fn = fn;
				ntri = 1;
			} else {
				const struct scene_mesh *sm = &s->meshes[o->u.raw.mesh];
				m->ov = sm->vertices;
				m->v = sm->vertices;
				m->n = sm->normals;
				m->ix = sm->tris;
				if (o->has_xform) {
					vec3 *w = &g->bake[nb];
					for (uint32_t q = 0; q < sm->n_vertices; q++)
						w[q] = m34_point(&o->xform, sm->vertices[q]);
					nb += sm->n_vertices;
					m->v = w;
					if (sm->normals) {
						vec3 *nn = &g->bake[nb];
						for (uint32_t q = 0; q < sm->n_vertices; q++)
							nn[q] = m34_normal(&inv, sm->normals[q]);
						nb += sm->n_vertices;
						m->n = nn;
					}
				}
				ntri = sm->n_triangles;
			}
			for (uint32_t q = 0; q < ntri; q++) {
				if (cancel_poll_every(q))
					goto cancelled;
				const uint32_t *ix = tri_ix(m, q);
				g->tri[g->n_tri].mesh = g->n_mesh;
				g->tri[g->n_tri].tri = q;
				g->tri_flat[g->n_tri] = flat_axis(&m->v[ix[0]], &m->v[ix[1]], &m->v[ix[2]]);
				if (push_triangle(&rb, REF_MAKE(REF_TRI, g->n_tri++), m->v[ix[0]], m->v[ix[1]], m->v[ix[2]]) < 0)
					goto oom;
			}
			g->n_mesh++;
			continue;
		}
		if (o->kind == PRIM_INSTANCE) {
			struct group *sub = define_group(A, o->u.instance.define, err);
			if (!sub)
				goto fail;
			if (sub->n_refs == 0 && sub->n_unb == 0)
				continue; /* an empty define draws nothing */
			struct ginst *gi = &g->inst[g->n_inst];
			gi->rec = scene_inst_rank(s, oi);
			mat34 rinv, fwd;
			inst_inverse(A, scene_inst_at(s, oi), &rinv);
			if (!m34_invert(&rinv, &fwd)) {
				scene_errorf(err, ERRLEVEL_FATAL, "error: instance transform is singular in single precision");
				goto fail;
			}
			ref = REF_MAKE(REF_INST, g->n_inst++);
			A->st.n_instances++;
			if (sub->n_unb) {
				unb[n_unb++] = ref;
				continue;
			}
			if (refbuf_push(&rb, ref, pad_box(geom_box_xform(&fwd, sub->bounds))) < 0)
				goto oom;
			continue;
		}
		/* xprim */
		int prc = prep_tree(A, oi);
		if (prc == ACCEL_CANCELLED)
			goto cancelled;
		if (prc < 0)
			goto oom;
		struct xprim *xp = &g->xp[g->n_xp];
		*xp = (struct xprim){ .g = A->gobj[oi] };
		if (xp->g->kind == PRIM_CYLINDER && !xp->g->u.cyl.capped && !xp->g->has_xform &&
		    xp->g->u.cyl.r > 0) { /* OPEN CYLINDERS */
			xp->from = xp->g->u.cyl.from;
			xp->a = xp->g->u.cyl.a;
			xp->r = xp->g->u.cyl.r;
			xp->h = xp->g->u.cyl.h;
		}
		xp->obj = oi;
		xp->mat = scene_full_at(s, oi)->material; /* an xprim: not an instance */
		ref = REF_MAKE(REF_XPRIM, g->n_xp++);
		bx = csg_bounds(s, (struct geom_obj *const *)A->gobj, oi);
		if (cancel_seen()) /* csg_bounds polls too (nested instances in CSG) */
			goto cancelled;
		if (bx.lo.x > bx.hi.x || bx.lo.y > bx.hi.y || bx.lo.z > bx.hi.z)
			continue; /* empty: nothing to draw (e.g. disjoint intersect) */
		if (!geom_box_finite(bx)) {
			unb[n_unb++] = ref;
			continue;
		}
		if (push_xprim(&rb, ref, xp->g, bx) < 0)
			goto oom;
	}
	uint32_t n_bounded = rb.n;
	all = rb.ref;
	boxes = rb.box;
	fboxes = rb.fbox;
	rb.ref = NULL;
	rb.box = NULL;
	rb.fbox = NULL;
	g->n_unb = n_unb;
	if (n_unb == 1 && REF_KIND(unb[0]) == REF_XPRIM) {
		const struct geom_obj *go = g->xp[REF_IDX(unb[0])].g;
		if (go->kind == PRIM_PLANE && !go->has_xform)
			g->plane1 = go;
	}
	g->n_refs = n_bounded;
	uint32_t *unb_fit = realloc(g->unb, (n_unb ? n_unb : 1) * sizeof *unb_fit);
	if (unb_fit)
		g->unb = unb_fit;
	A->st.n_prims += g->n_sph + g->n_tri + g->n_xp;

	/* pass 3: the BVH over the bounded references */
	/* node bounds are stored relative to the group's centre, padded by
	 * BOX_PAD_REL of the largest coordinate magnitude around it */
	struct geom_box world = geom_box_empty();
	for (uint32_t k = 0; k < n_bounded; k++) {
		if (cancel_poll_every(k))
			goto cancelled;
		world = geom_box_union(world, ref_box(boxes, fboxes, k));
	}
	g->center = n_bounded ? v3_scale(v3_add(world.lo, world.hi), 0.5) : v3(0, 0, 0);
	double big = 0;
	for (uint32_t k = 0; k < n_bounded; k++) {
		if (cancel_poll_every(k))
			goto cancelled;
		struct geom_box b = ref_box(boxes, fboxes, k);
		b.lo = v3_sub(b.lo, g->center);
		b.hi = v3_sub(b.hi, g->center);
		if (boxes)
			boxes[k] = b;
		big = geom_fmax(big, geom_fmax(geom_fmax(fabs(b.lo.x), fabs(b.lo.y)), fabs(b.lo.z)));
		big = geom_fmax(big, geom_fmax(geom_fmax(fabs(b.hi.x), fabs(b.hi.y)), fabs(b.hi.z)));
	}
	vec3 pad = v3(big * BOX_PAD_REL, big * BOX_PAD_REL, big * BOX_PAD_REL);
	for (uint32_t k = 0; k < n_bounded; k++) {
		if (cancel_poll_every(k))
			goto cancelled;
		if (boxes) {
			boxes[k].lo = v3_sub(boxes[k].lo, pad);
			boxes[k].hi = v3_add(boxes[k].hi, pad);
			continue;
		}
		/* the same steps in double, then outward to float (FLOAT BOXES) */
		float *f = fboxes[k];
		vec3 lo = v3_sub(v3_sub(v3(f[0], f[1], f[2]), g->center), pad);
		vec3 hi = v3_add(v3_sub(v3(f[3], f[4], f[5]), g->center), pad);
		f[0] = f_down(lo.x), f[1] = f_down(lo.y), f[2] = f_down(lo.z);
		f[3] = f_up(hi.x), f[4] = f_up(hi.y), f[5] = f_up(hi.z);
	}
	/* a group whose bounded references are ACCEL_PACK_MIN or more instances
	 * and nothing else keeps its instance records in leaf order instead of a
	 * reference array, and packs its leaves (see ACCEL_INST_LEAF) */
	bool inst_only = n_bounded >= ACCEL_PACK_MIN;
	for (uint32_t k = 0; k < n_bounded && inst_only; k++)
		inst_only = REF_KIND(all[k]) == REF_INST;
	if (inst_only) { /* all[] is often instance k at k: then it goes before the build's peak */
		bool ident = true;
		for (uint32_t k = 0; k < n_bounded && ident; k++)
			ident = all[k] == REF_MAKE(REF_INST, k);
		if (ident) {
			free(all);
			all = NULL;
		}
	}
	/* before the build: bvh_build_f frees the float boxes */
	g->bounds = geom_box_empty();
	for (uint32_t k = 0; k < n_bounded; k++) {
		if (cancel_poll_every(k))
			goto cancelled;
		g->bounds = geom_box_union(g->bounds, ref_box(boxes, fboxes, k));
	}
	perm = malloc((n_bounded ? n_bounded : 1) * sizeof *perm);
	if (!inst_only)
		g->refs = malloc((n_bounded ? n_bounded : 1) * sizeof *g->refs);
	if (!perm || (!inst_only && !g->refs))
		goto oom;
	uint32_t max_leaf = inst_only ? ACCEL_INST_LEAF : ACCEL_MAX_LEAF;
	uint8_t *cost = NULL;
	if (boxes && !inst_only) {
		cost = malloc(n_bounded ? n_bounded : 1);
		if (!cost)
			goto oom;
		for (uint32_t k = 0; k < n_bounded; k++)
			cost[k] = ref_cost(g, all[k]);
	}
	int brc = !boxes ? bvh_build_f(&g->bvh, fboxes, n_bounded, perm, max_leaf, inst_only)
		  : inst_only ? bvh_build_ex(&g->bvh, boxes, n_bounded, perm, max_leaf, true)
			      : bvh_build_cost(&g->bvh, boxes, n_bounded, perm, max_leaf, cost);
	free(cost);
	fboxes = NULL; /* bvh_build_f freed them */
	if (brc == BVH_CANCELLED)
		goto cancelled;
	if (brc < 0)
		goto oom;
	/* leaves too big to test without polling (only the builder's depth
	 * limit makes them; a root that is a leaf has at most max_leaf) */
	for (uint32_t k = 0; k < g->bvh.n_nodes4; k++)
		for (int c = 0; c < 4; c++)
			g->big_leaf |= g->bvh.nodes[k].n[c] > ACCEL_LEAF_CHUNK;
	/* a few triangles among other primitives are mostly a floor, which
	 * every shadow ray of a hit on it meets and no pre-test rejects
	 * (docs/performance.md, round 11) */
	g->occ_pretest = g->n_tri >= 3 * ((uint64_t)g->n_sph + g->n_xp + g->n_inst);
	if (inst_only) { /* bounded instances in leaf order, then the unbounded ones */
		int orc = order_instances(g, all, perm, n_bounded);
		if (orc == ACCEL_CANCELLED)
			goto cancelled;
		if (orc < 0)
			goto oom;
	} else {
		for (uint32_t k = 0; k < n_bounded; k++) {
			if (cancel_poll_every(k))
				goto cancelled;
			g->refs[k] = all[perm[k]];
		}
		if (boxes && objs == A->s->roots && accel_light_build(A, g, boxes, perm) < 0) /* LIGHT BUFFERS */
			goto oom;
		int mrc = make_blocks(g);
		if (mrc == ACCEL_CANCELLED)
			goto cancelled;
		if (mrc < 0)
			goto oom;
		int wrc = bvh_make8(&g->bvh); /* WIDE NODES (bvh.h), after the blocks */
		if (wrc == BVH_CANCELLED)
			goto cancelled;
		if (wrc < 0)
			goto oom;
		g->bytes += (size_t)g->bvh.n_nodes8 * sizeof(struct bvh8);
	}
	if (n_bounded) { /* back to the group's space, covering the padding */
		g->bounds.lo = v3_add(g->bounds.lo, g->center);
		g->bounds.hi = v3_add(g->bounds.hi, g->center);
		g->bounds = pad_box(g->bounds);
	}
	g->bytes += (size_t)g->bvh.n_nodes4 * sizeof(struct bvh4) +
		    (size_t)((inst_only ? 0 : n_bounded) + n_unb) * sizeof(uint32_t);
	A->st.n_nodes += g->bvh.n_nodes4;
	A->st.bytes += g->bytes;
	free(perm);
	free(all);
	free(boxes);
	free(fboxes);
	return g;
cancelled:
	scene_errorf(err, ERRLEVEL_FATAL, "cancelled");
	goto fail;
oom:
	scene_errorf(err, ERRLEVEL_FATAL, "error: out of memory building the acceleration structure");
fail:
	free(rb.ref);
	free(rb.box);
	free(rb.fbox);
	free(perm);
	free(all);
	free(boxes);
	free(fboxes);
	group_free(g);
	return NULL;
}

/*
 * Rejects graphs the tracer's recursion would not survive: CSG nesting over
 * LIM_CSG_DEPTH or define nesting over LIM_DEFINE_DEPTH. Children always
 * have smaller indices, so one forward pass computes every depth.
 */
static int check_depths(const struct scene *s, struct scene_error *err)
{
	uint16_t *cd = calloc((size_t)s->n_objects + 1, sizeof *cd);
	uint16_t *dd = calloc((size_t)s->n_objects + 1, sizeof *dd);
	int32_t *def_cd = malloc(((size_t)s->n_defines + 1) * sizeof *def_cd);
	int32_t *def_dd = malloc(((size_t)s->n_defines + 1) * sizeof *def_dd);
	int rc = 0;
	if (!cd || !dd || !def_cd || !def_dd) {
		rc = scene_errorf(err, ERRLEVEL_FATAL, "error: out of memory building the acceleration structure");
		goto out;
	}
	for (uint32_t i = 0; i < s->n_defines; i++)
		def_cd[i] = def_dd[i] = -1;
	for (uint32_t i = 0; i < s->n_objects; i++) {
		if (cancel_poll_every(i)) {
			rc = scene_errorf(err, ERRLEVEL_FATAL, "cancelled");
			goto out;
		}
		struct scene_object tmp;
		const struct scene_object *o = scene_object(s, i, &tmp);
		unsigned c = 0, d = 0;
		if (o->kind == PRIM_CSG) {
			uint32_t a = o->u.csg.operand1, b = o->u.csg.operand2;
			c = 1u + (cd[a] > cd[b] ? cd[a] : cd[b]);
			d = dd[a] > dd[b] ? dd[a] : dd[b];
		} else if (o->kind == PRIM_INSTANCE) {
			uint32_t df = o->u.instance.define;
			if (def_cd[df] < 0) {
				unsigned mc = 0, md = 0;
				const struct scene_define *D = &s->defines[df];
				for (uint32_t k = 0; k < D->n_objects; k++) {
					uint32_t m = D->objects[k];
					mc = cd[m] > mc ? cd[m] : mc;
					md = dd[m] > md ? dd[m] : md;
				}
				def_cd[df] = (int32_t)mc;
				def_dd[df] = (int32_t)md;
			}
			c = (unsigned)def_cd[df];
			d = 1u + (unsigned)def_dd[df];
		}
		if (c > LIM_CSG_DEPTH || d > LIM_DEFINE_DEPTH) {
			const char *f = o->loc.file ? o->loc.file : "<scene>";
			rc = scene_errorf(err, ERRLEVEL_FATAL, "%s:%d:%d: error: %s nested deeper than %d", f,
					  o->loc.line, o->loc.col, c > LIM_CSG_DEPTH ? "csg" : "definition",
					  c > LIM_CSG_DEPTH ? LIM_CSG_DEPTH : LIM_DEFINE_DEPTH);
			goto out;
		}
		cd[i] = (uint16_t)c;
		dd[i] = (uint16_t)d;
	}
out:
	free(cd);
	free(dd);
	free(def_cd);
	free(def_dd);
	return rc;
}

int accel_build(const struct scene *s, struct accel **out, struct scene_error *err)
{
	struct timespec t0, t1;
	clock_gettime(CLOCK_MONOTONIC, &t0);
	*out = NULL;
	int rc = check_depths(s, err);
	if (rc)
		return cancel_seen() ? ACCEL_CANCELLED : rc;
	struct accel *A = calloc(1, sizeof *A);
	if (!A)
		return scene_errorf(err, ERRLEVEL_FATAL, "error: out of memory building the acceleration structure");
	A->s = s;
	A->avx2 = accel_use_avx2();
	A->dgroup = calloc((size_t)s->n_defines + 1, sizeof *A->dgroup);
	if (!A->dgroup) {
		accel_free(A);
		return scene_errorf(err, ERRLEVEL_FATAL, "error: out of memory building the acceleration structure");
	}
	A->st.bytes = sizeof *A + (size_t)s->n_defines * sizeof(void *);
	if (s->n_lins) { /* inst_inverse's 3x3 parts, one per distinct one */
		A->lin_inv = malloc((size_t)s->n_lins * sizeof *A->lin_inv);
		if (!A->lin_inv) {
			accel_free(A);
			return scene_errorf(err, ERRLEVEL_FATAL, "error: out of memory building the acceleration structure");
		}
		for (uint32_t k = 0; k < s->n_lins; k++)
			if (!m34_invert(&s->lins[k], &A->lin_inv[k]))
				A->lin_inv[k].m[0][3] = NAN;
		A->st.bytes += (size_t)s->n_lins * sizeof *A->lin_inv;
	}
	A->st.instance_bytes = sizeof(struct ginst);
	A->root = build_group(A, s->roots, s->n_roots, err);
	if (!A->root || cancel_seen()) {
		accel_free(A);
		if (!cancel_seen())
			return err ? err->level : ERRLEVEL_FATAL;
		scene_errorf(err, ERRLEVEL_FATAL, "cancelled");
		return ACCEL_CANCELLED;
	}
	clock_gettime(CLOCK_MONOTONIC, &t1);
	A->st.build_seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
	*out = A;
	return 0;
}
