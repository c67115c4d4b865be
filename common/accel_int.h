/*
 * accel_int.h - the acceleration structure's private data, shared by the
 * ray queries (accel.c, accel_packet.c, accel_trace.h) and accel_build.c
 * (building). Nothing outside those files includes it; the public interface
 * is accel.h. The design (groups,
 * references, instances, unbounded lists) is described at the top of accel.c.
 */
#ifndef PORTRAY_ACCEL_INT_H
#define PORTRAY_ACCEL_INT_H

#include "common/accel.h"
#include "common/bvh.h"
#include "common/geom.h"

#include <string.h>

enum { REF_SPHERE = 0, REF_TRI = 1, REF_XPRIM = 2, REF_INST = 3 };
#define REF_MAKE(k, i) ((uint32_t)(k) << 30 | (uint32_t)(i))
#define REF_KIND(r) ((r) >> 30)
#define REF_IDX(r) ((r) & 0x3fffffffu)
/* references per group: 30 bits of index */
#define ACCEL_MAX_REFS (1u << 30)
/* an instance's tie key is REF_MAKE(REF_INST, its scene record) (accel_trace.h) */
_Static_assert(LIM_OBJECTS <= ACCEL_MAX_REFS, "object and record indices fit a reference's index bits");
/* primitives per BVH leaf */
#define ACCEL_MAX_LEAF 4
/* instances per leaf in a group of at least ACCEL_PACK_MIN instances and
 * nothing else bounded, every subtree this small made a leaf: fewer
 * 128-byte nodes per instance (issue 3's budget of 64 bytes per instance)
 * at the cost of more instance tests, so only where instances are many */
#define ACCEL_INST_LEAF 8
#define ACCEL_PACK_MIN 1024
/* References of a leaf a traversal tests before it pops again and counts
 * (CANCELLATION in accel.c): leaves are never this big but at the BVH
 * builder's depth limit, which may leave millions of references in one. */
#define ACCEL_LEAF_CHUNK 64u
_Static_assert(ACCEL_MAX_LEAF <= ACCEL_LEAF_CHUNK && ACCEL_INST_LEAF <= ACCEL_LEAF_CHUNK,
	       "ordinary leaves are never split");

struct gsphere {
	vec3 c;
	double r2;
	uint32_t obj; /* object index, | GSPH_FRAME when its pole/equator are not the default */
	uint32_t mat; /* the object's material (accel_finish reads no scene object) */
};
/* gsphere.obj flag (object indices are below LIM_OBJECTS = 2^26) */
#define GSPH_FRAME 0x80000000u
_Static_assert(LIM_OBJECTS <= GSPH_FRAME, "object indices leave gsphere.obj's flag bit free");

/* A mesh slot: one raw object or one plain triangle. */
struct gmesh {
	const vec3 *v;      /* vertices in the group's space */
	const vec3 *n;      /* normals in the group's space, or NULL */
	const vec3 *ov;     /* vertices in the object's own space (for mp, uv) */
	const vec3 *fn;     /* a plain triangle's unit face normal (from v, as
			       accel_finish computes it), or NULL (raw meshes:
			       computed per hit) */
	const uint32_t *ix; /* 3 per triangle */
	uint32_t obj;
	uint32_t mat;       /* the object's material (accel_finish reads no scene object) */
};

/* hit.surf_kind: what surface_complete completes */
enum { SURF_SPHERE, SURF_TRI, SURF_XPRIM };

struct gtri {
	uint32_t mesh, tri;
};

/*
 * OPEN CYLINDERS. An xprim that is an untransformed open cylinder (the
 * SPD rings, 420 of them) carries its axis here, r > 0, and the
 * traversals test it from this record (geom_cyl_open_hit): one record's
 * cache lines instead of the geom_obj's four; r is 0 for every other xprim.
 */
struct xprim {
	vec3 from, a; /* OPEN CYLINDERS: geom_obj.u.cyl's */
	double r, h;
	const struct geom_obj *g;
	uint32_t obj;
	uint32_t mat; /* the object's material (accel_finish reads no scene object) */
};

/* An instance: the index of its record in scene.insts, 4 bytes (issue
 * 13: a million instances in 100 bytes each, the whole process). Its
 * define, material and transform are the scene's; its geometry is exactly
 * the inverse transform rounded to float (inst_inverse), which the build
 * and every ray compute alike. Records are in the order of their object
 * indices, so tie keys made from rec order instances as object indices
 * did (CANONICAL TIES in accel_trace.h). */
struct ginst {
	uint32_t rec;
};

/*
 * LEAF BLOCKS. A leaf of one to ACCEL_MAX_LEAF references that are all
 * triangles gets, at build time, a block of its triangles' vertices in
 * float, one triangle per SIMD lane (struct-of-arrays), so that one ray is
 * tested against the whole leaf in one float pass (the TRIANGLE PRE-TEST,
 * accel_trace.h) and the packets read the floats without gathering them. The
 * node's child then has n = count | LEAF_BLOCK and idx = the block's offset
 * in group.tblk. A block of n triangles is BLK_ROWS rows of n words: row
 * 3j + k holds component k (x, y, z) of vertex j (a, b, c) of each
 * triangle, the double rounded to nearest float; row 9 the largest
 * magnitude of each triangle's nine floats; row 10 the leaf's references
 * (their bits, in leaf order), so the traversal never reads group.refs
 * for it. Rows are n wide, not 4 (44 bytes a triangle, where leaves hold
 * 1.5 triangles on average): a 4-lane load of a row reads the next rows'
 * words into the lanes past n, whose answers are never used, and the
 * array ends with BLK_PAD words of padding so that the last load stays
 * inside it.
 */
#define LEAF_BLOCK 0x80000000u
_Static_assert(ACCEL_MAX_REFS <= LEAF_BLOCK, "leaf sizes leave bvh4.n's flag bit free");
#define BLK_ROWS 11
#define BLK_PAD 3

/* Row r of block b of n triangles. */
static inline const float *blk_row(const float *b, uint32_t n, uint32_t r) { return b + r * n; }

/* The reference of lane l of block b of n triangles. */
static inline uint32_t blk_ref(const float *b, uint32_t n, uint32_t l)
{
	uint32_t ref;
	memcpy(&ref, b + 10 * n + l, sizeof ref);
	return ref;
}

struct group {
	struct bvh bvh;
	uint32_t *refs; /* bounded references in leaf order; NULL in a group of
			   instances only: reference k is then instance k (group_ref) */
	uint32_t n_refs;
	uint32_t *unb;  /* unbounded references */
	uint32_t n_unb;
	struct gsphere *sph;
	uint32_t n_sph;
	struct gmesh *mesh;
	uint32_t n_mesh;
	struct gtri *tri;
	uint8_t *tri_flat; /* per triangle: the axis whose coordinate its three
			      vertices share, bit for bit, or 3 (FLAT TRIANGLES,
			      accel_trace.h) */
	uint32_t n_tri;
	struct xprim *xp;
	uint32_t n_xp;
	struct ginst *inst;
	uint32_t n_inst;
	vec3 *bake;     /* baked vertices and normals (owned) */
	float *tblk;    /* LEAF BLOCKS (owned), n_tblk words */
	uint32_t n_tblk;
	struct geom_box bounds; /* of the bounded references */
	const struct geom_obj *plane1; /* the only unbounded reference when it is an
					  untransformed plane (tested inline), else NULL */
	bool big_leaf;  /* some leaf has more than ACCEL_LEAF_CHUNK references:
			   no packets through this group (accel_packet.c) */
	bool occ_pretest; /* mostly triangles: the any-hit packets' leaf blocks
			     take the TRIANGLE PRE-TEST (bvh_occluded4) */
	vec3 center;    /* node bounds are relative to this point */
	size_t bytes;
};

/*
 * LIGHT BUFFERS (accel_light.c; Haines and Greenberg's light buffer, 1986).
 * For a point light that casts shadows, the root group's bounded
 * references sorted into the cells of a direction cube around the light:
 * 6 faces of n x n cells, face 2a (+a) or 2a + 1 (-a) for the axis a, cell
 * (i, j) of the face the directions whose projections p = u_b / |u_a|, q =
 * u_c / |u_a| (b < c the other axes) fall in column i and row j of the
 * face's window (lbuf_cell; the whole face, [-1, 1]^2, unless ZOOMED
 * FACES in accel_light.c). A shadow ray from o toward the light (d = lp - o, t in [0, 1]) lies
 * along u = o - lp, so only the references of u's cell can block it
 * (accel_occluded_light); each cell's entries are sorted by dmin, the
 * nearest depth |X_a - lp_a| any point X of the reference's box has on the
 * face, and a ray of depth |u_a| stops at the first entry beyond it. Why
 * the cells never miss a reference the ray can hit: accel_light.c.
 */
struct lbuf_ent {
	float dmin;
	uint32_t ref;
};
/* A NEAR reference; FLAT NEAR: a flat triangle's plane (FLAT TRIANGLES,
 * accel_trace.h) kept beside it, flat its axis and c its coordinate (flat
 * 3 for any other reference), so that the queries decide flat_behind
 * without the triangle's loads (balls_s4's floor: two triangles every
 * query tests). */
struct lbuf_near {
	double c;
	uint32_t ref, flat;
};
struct lbuf {
	vec3 lp;         /* the light's position */
	double R;        /* answers for origins with |o - lp|_inf <= R */
	uint32_t n;      /* cells per face side */
	/* ZOOMED FACES: face f's cells cover its window org[f][k] ..
	 * org[f][k] + n / scale[f][k] on axis k (0: p, 1: q), where its small
	 * references lie; projections beyond it go to the edge cells */
	double org[6][2], scale[6][2];
	uint32_t *start; /* cell k's entries: ent[start[k] .. start[k + 1]) */
	struct lbuf_ent *ent;
	struct lbuf_near *near; /* references whose boxes come within 3D of the
				   light, or WIDE, tested by every query (accel_light.c):
				   the flat triangles first, n_near_flat of them */
	uint32_t n_near, n_near_flat;
	/* FLAT NEAR: the origins o (flat_lo <= o <= flat_hi) from which the
	 * ray toward the light is behind every one of those flat triangles
	 * (flat_behind true for each: the loop over them is skipped) */
	vec3 flat_lo, flat_hi;
};

/* The cell column (k 0) or row (k 1) of projection p on face f (both in
 * the build and the queries: the same monotonic rounding). */
static inline uint32_t lbuf_cell(const struct lbuf *lb, uint32_t f, int k, double p)
{
	double x = (p - lb->org[f][k]) * lb->scale[f][k];
	if (!(x > 0))
		return 0;
	return x >= (double)lb->n ? lb->n - 1 : (uint32_t)x;
}

struct accel {
	const struct scene *s;
	struct lbuf **lbuf; /* per scene light: its LIGHT BUFFER, or NULL (owned) */
	struct geom_obj **gobj;   /* per object, built on demand; NULL until needed (owned) */
	struct group **dgroup;    /* per define, built on first use (owned) */
	struct group *root;
	/* the inverses of the scene's instance 3x3 parts (scene.lins), as
	 * m34_invert makes them; m[0][3] NaN: singular (owned) */
	mat34 *lin_inv;
	bool avx2; /* WIDE NODES IN AVX2 (accel_box.h): the CPU has it, PORTRAY_SIMD does not say sse2 */
	struct accel_stats st;
};

/*
 * The inverse transform (parent -> define space) of instance record si,
 * rounded to float and back: what the instance's geometry is, for rays,
 * normals and bounds alike; the build and every visit compute it alike.
 * The values are m34_invert's: its 3x3 part depends on the transform's
 * 3x3 part alone (A->lin_inv, or the identity's, exact), its translation
 * is the same expression. The identity without a transform, and for a
 * singular one (which the scene builder refuses).
 */
static inline void inst_inverse(const struct accel *A, const struct scene_inst *si, mat34 *m)
{
	if (si->lin == SCENE_LIN_NONE) {
		*m = m34_identity();
		return;
	}
	vec3 t = si->t;
	if (si->lin == SCENE_LIN_IDENTITY) {
		/* m34_invert of the identity's 3x3 part is exactly it (+0 off the
		 * diagonal); the translation the same products (0 * y keeps y's
		 * sign), and nothing to round in the 3x3 part */
		*m = m34_identity();
		m->m[0][3] = (float)-(1.0 * t.x + 0.0 * t.y + 0.0 * t.z);
		m->m[1][3] = (float)-(0.0 * t.x + 1.0 * t.y + 0.0 * t.z);
		m->m[2][3] = (float)-(0.0 * t.x + 0.0 * t.y + 1.0 * t.z);
		return;
	}
	*m = A->lin_inv[si->lin];
	if (isnan(m->m[0][3])) {
		*m = m34_identity();
		return;
	}
	const double (*r)[4] = m->m;
	for (int i = 0; i < 3; i++)
		m->m[i][3] = -(r[i][0] * t.x + r[i][1] * t.y + r[i][2] * t.z);
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 4; j++)
			m->m[i][j] = (float)m->m[i][j];
}


static inline const uint32_t *tri_ix(const struct gmesh *m, uint32_t tri) { return m->ix + 3 * (size_t)tri; }

/* The unit face normal of triangle ix of m, from its group-space vertices. */
static inline vec3 tri_normal(const struct gmesh *m, const uint32_t *ix)
{
	vec3 a = m->v[ix[0]], b = m->v[ix[1]], cc = m->v[ix[2]];
	return v3_norm(v3_cross(v3_sub(b, a), v3_sub(cc, a)));
}

/*
 * BOX TESTS IN FLOAT, KEPT CONSERVATIVE. Node bounds are floats relative
 * to the group's centre, rounded outward, and every item box is padded by
 * BOX_PAD_REL times the largest coordinate magnitude M about that centre
 * before the build. The ray's origin is taken relative to the centre (in
 * double), its direction scaled exactly by a power of two so that the
 * largest component is in [1, 2) (t scales by the same power), then both
 * are rounded to float. Errors: the origin's rounding moves each component
 * k by at most 2^-24 |o_k|: when |o_k| <= 2M that is below the padding;
 * when |o_k| > 2M it is at most 2^-23 of the distance to the slab, covered
 * by widening every entry/exit distance by BOX_WIDEN relative (which also
 * covers the rounding of the subtraction, of the inverse and of the
 * product). The widening is folded into the inverses: entry distances use
 * inv * (1 - BOX_WIDEN), exit distances inv * (1 + BOX_WIDEN) (rounded to
 * float: one more 2^-24), which moves an entry distance >= 0 toward 0 and
 * an exit distance >= 0 away from it; rays are half-lines (tmin >= 0), so
 * only those matter. In all about 6 x 2^-24 against BOX_WIDEN's 16 x 2^-24;
 * the packets take their inverses in float (ray_box4, accel_packet.c), two
 * roundings more. The interval's own ends, tmin and tmax, are rounded to
 * float outward. Zero direction components get an inverse of +-1e30 (never
 * inf, so never inf * 0 = NaN); the padding keeps that exact enough.
 * Primitive tests stay in double, so a box test can only let through more,
 * never cull a true hit: BVH and brute force give the same answers
 * (tests/unit/test_bvh.c checks).
 */
#define BOX_PAD_REL 0x1p-19
#define BOX_WIDEN 0x1p-20

/* Makes A->lbuf for the root group g from its references' boxes (boxes[perm[k]]
 * is reference k's, relative to g->center and padded); 0, or -1 out of memory. */
int accel_light_build(struct accel *A, const struct group *g, const struct geom_box *boxes, const uint32_t *perm);
void accel_light_free(struct accel *A);

#endif
