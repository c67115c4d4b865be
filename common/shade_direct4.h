/*
 * shade_direct4.h - DIRECT IN FOURS: direct() of the four eye hits of a
 * 2x2 block at once, in scenes of point lights only (POINT LIGHTS ONLY),
 * included once by shade.c after direct_body, whose per-light loop it
 * follows step by step.
 *
 * The eye hits' shading is mostly arithmetic on doubles in one long chain
 * per light (the way to the light: a square root and a division; the
 * highlight's reflection; the Phong term; the cut-off test), the same
 * operations for the four hits of a block: here each step is one vector
 * operation across the four (GCC's and clang's vector extensions in
 * functions compiled for AVX2, taken where accel_use_avx2 says so), each
 * lane doing exactly what direct_body does for its hit, in the same order
 * with the same roundings (no contraction: -ffp-contract=off, and AVX2
 * has no fused operations), so every colour is direct_body's to the bit.
 * Where direct_body skips a light for a hit (unlit, blocked, below the
 * cut), the lane's term is computed anyway and not added. What is not the
 * same for the four (the highlight's tests and power, a shadow ray the
 * packets did not trace) is done lane by lane with direct_body's own
 * functions. The context takes this path (shade_ctx.direct4) only where
 * some light's ways are not the shadow packets' (docs/performance.md,
 * round 21); tests/unit/test_shade_inner.c compares it with direct_body.
 */

#include <immintrin.h>

#define V4_FN static inline __attribute__((always_inline, target("avx2")))

typedef double v4d __attribute__((vector_size(32)));
typedef int64_t v4m __attribute__((vector_size(32))); /* a lane: all ones or 0 */

struct v4vec {
	v4d x, y, z;
};

V4_FN v4d v4_sel(v4m m, v4d a, v4d b) { return (v4d)(((v4m)a & m) | ((v4m)b & ~m)); }

V4_FN v4d v4_all(double x) { return (v4d){ x, x, x, x }; }

/* v3_dot, lane by lane: (a.x b.x + a.y b.y) + a.z b.z */
V4_FN v4d v4_dot(struct v4vec a, struct v4vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

/* v3_maxabs lane by lane: the same comparisons, NaN as they order it. */
V4_FN v4d v4_maxabs(struct v4vec a)
{
	const v4m abs = (v4m){ INT64_MAX, INT64_MAX, INT64_MAX, INT64_MAX };
	v4d x = (v4d)((v4m)a.x & abs), y = (v4d)((v4m)a.y & abs), z = (v4d)((v4m)a.z & abs);
	v4d m = v4_sel(x > y, x, y);
	return v4_sel(m > z, m, z);
}

/* LANES IN REGISTERS: lanes from four doubles just written, each read on
 * its own (a vector read whole right after its lanes were stored one by
 * one waits on a failed store forwarding, which cost more than the
 * arithmetic saved); masks from four bits by a table. */
V4_FN v4d v4_of(const double a[4])
{
	__m128d lo = _mm_loadh_pd(_mm_load_sd(&a[0]), &a[1]), hi = _mm_loadh_pd(_mm_load_sd(&a[2]), &a[3]);
	return (v4d)_mm256_insertf128_pd(_mm256_castpd128_pd256(lo), hi, 1);
}

static const v4m v4_masks[16] __attribute__((aligned(32))) = {
#define M(b) { -(int64_t)((b) & 1), -(int64_t)((b) >> 1 & 1), -(int64_t)((b) >> 2 & 1), -(int64_t)((b) >> 3 & 1) }
	M(0), M(1), M(2), M(3), M(4), M(5), M(6), M(7), M(8), M(9), M(10), M(11), M(12), M(13), M(14), M(15)
#undef M
};

V4_FN v4m v4_mask(unsigned b) { return v4_masks[b & 15]; }

/*
 * direct(c, p, n, ng, -u[k].d, m, kd, 1.0, seed, &pre[k], SHADE_HINT_ANY)
 * for the prepared hits sf[k] (ok[k], k < n) of eye rays u[k] into col[k],
 * with c->points_only: what surf_shade's direct term is at depth 0.
 * all_shadows: c->all_shadows, folded as in direct_body.
 */
V4_FN void direct4_body(const struct shade_ctx *c, const struct ray u[4], const struct surf sf[4], const bool ok[4],
			 int n, const struct shadow_pre pre[4], vec3 col[4], const bool all_shadows)
{
	const bool shadows = all_shadows || !c->s->image.no_shadows;
	const double cut = c->cut; /* x 1 sample: cut * n_samples is cut */
	int any = -1;
	for (int k = 0; k < n && any < 0; k++)
		any = ok[k] ? k : -1;
	for (int k = 0; k < 4; k++)
		col[k] = v3(0, 0, 0);
	if (any < 0)
		return;
	double power[4];
	bool want_spec[4];
	unsigned live = 0;
	int j[4];
	const struct shader_mat *m[4];
	for (int k = 0; k < 4; k++) {
		j[k] = k < n && ok[k] ? k : any; /* other lanes copy a live one */
		live |= (unsigned)(k < n && ok[k]) << k;
		m[k] = sf[j[k]].m;
		want_spec[k] = m[k]->specular != 0;
		power[k] = m[k]->spec_power;
	}
	/* lanes straight from the hits and materials (LANES IN REGISTERS) */
#define LANES(e) ((v4d){ e(0), e(1), e(2), e(3) })
#define PX(k) sf[j[k]].p.x
#define PY(k) sf[j[k]].p.y
#define PZ(k) sf[j[k]].p.z
#define NX(k) sf[j[k]].n.x
#define NY(k) sf[j[k]].n.y
#define NZ(k) sf[j[k]].n.z
#define VX(k) -u[j[k]].d.x /* v = v3_neg(d), toward the viewer */
#define VY(k) -u[j[k]].d.y
#define VZ(k) -u[j[k]].d.z
#define DIF(k) m[k]->diffuse
#define TD(k) sf[j[k]].td
#define DCX(k) m[k]->diff_colour.x
#define DCY(k) m[k]->diff_colour.y
#define DCZ(k) m[k]->diff_colour.z
#define SCX(k) m[k]->spec_colour.x
#define SCY(k) m[k]->spec_colour.y
#define SCZ(k) m[k]->spec_colour.z
#define SPEC(k) m[k]->specular
	const struct v4vec P = { LANES(PX), LANES(PY), LANES(PZ) }, N = { LANES(NX), LANES(NY), LANES(NZ) },
			   V = { LANES(VX), LANES(VY), LANES(VZ) };
	/* surf_shade's kd = diffuse (1 - td); direct_body's kcd = diff_colour kd, kcs = spec_colour specular */
	const v4d KD = LANES(DIF) * (v4_all(1) - LANES(TD)), SP = LANES(SPEC);
	const struct v4vec KCD = { LANES(DCX) * KD, LANES(DCY) * KD, LANES(DCZ) * KD },
			   KCS = { LANES(SCX) * SP, LANES(SCY) * SP, LANES(SCZ) * SP };
#undef PX
#undef PY
#undef PZ
#undef NX
#undef NY
#undef NZ
#undef VX
#undef VY
#undef VZ
#undef DIF
#undef TD
#undef DCX
#undef DCY
#undef DCZ
#undef SCX
#undef SCY
#undef SCZ
#undef SPEC
	double kd[4];
	vec3 kcd[4], kcs[4]; /* the same, for the lane by lane steps */
	for (int k = 0; k < 4; k++) {
		kd[k] = KD[k];
		kcd[k] = v3(KCD.x[k], KCD.y[k], KCD.z[k]);
		kcs[k] = v3(KCS.x[k], KCS.y[k], KCS.z[k]);
	}
	struct v4vec C = { v4_all(0), v4_all(0), v4_all(0) };
	for (uint32_t i = 0; i < c->n_lights; i++) {
		if (cancel_poll()) /* CANCELLATION: as direct_body (the colours are discarded) */
			break;
		const struct scene_light *l = c->lights[i].l;
		const vec3 lp = l->position;
		/* LIGHT WAYS: the shadow packet's way where it made one, else
		 * light_way_at lane by lane (for all four: one vector op each) */
		unsigned wk = 0;
		for (int k = 0; k < 4; k++)
			wk |= (unsigned)(i < SHADE_PRE_WAYS && (live >> k & 1) && (pre[k].wknown >> i & 1)) << k;
		struct v4vec LD;
		v4d ndotl;
		unsigned lit = 0;
		if (wk != live) {
			struct v4vec TO = { v4_all(lp.x) - P.x, v4_all(lp.y) - P.y, v4_all(lp.z) - P.z };
			v4d dist = (v4d)_mm256_sqrt_pd((__m256d)v4_dot(TO, TO)); /* correctly rounded, as sqrt() */
			v4d inv = v4_all(1) / dist;
			LD = (struct v4vec){ TO.x * inv, TO.y * inv, TO.z * inv };
			ndotl = v4_dot(N, LD);
			v4m lm = (dist > v4_all(0)) & ~(ndotl <= v4_all(0));
			lit = (unsigned)_mm256_movemask_pd((__m256d)lm) & ~wk;
		}
		if (wk) {
			const struct light_way *w[4];
			for (int k = 0; k < 4; k++) {
				w[k] = &pre[wk >> k & 1 ? k : __builtin_ctz(wk)].way[i];
				lit |= (unsigned)((wk >> k & 1) && w[k]->lit) << k;
			}
#define WX(k) w[k]->ldir.x
#define WY(k) w[k]->ldir.y
#define WZ(k) w[k]->ldir.z
#define WN(k) w[k]->ndotl
			struct v4vec LW = { LANES(WX), LANES(WY), LANES(WZ) };
			if (wk == live) {
				LD = LW, ndotl = LANES(WN);
			} else {
				v4m msk = v4_mask(wk);
				LD = (struct v4vec){ v4_sel(msk, LW.x, LD.x), v4_sel(msk, LW.y, LD.y), v4_sel(msk, LW.z, LD.z) };
				ndotl = v4_sel(msk, LANES(WN), ndotl);
			}
#undef WX
#undef WY
#undef WZ
#undef WN
		}
		const bool sh = shadows && (all_shadows || !l->no_shadows);
		unsigned act = live & lit, traced = 0, later = 0;
		for (unsigned b = act; b; b &= b - 1) {
			int k = __builtin_ctz(b);
			bool known = sh && i < SHADE_PRE_LIGHTS && (pre[k].known >> i & 1);
			if (known && (pre[k].occ >> i & 1))
				act &= ~(1u << k); /* SHADOW PACKETS: blocked */
			traced |= (unsigned)(sh && !known) << k;
		}
		if (!act)
			continue; /* every lane adds 0 + nothing: col unchanged */
		const vec3 in = l->colour;
		/* the highlight: (R.V)^power where it counts */
		v4d two_ndotl = v4_all(2) * ndotl;
		struct v4vec RF = { N.x * two_ndotl - LD.x, N.y * two_ndotl - LD.y, N.z * two_ndotl - LD.z };
		v4d rv = v4_dot(RF, V);
		double hs[4] = { 0, 0, 0, 0 };
		for (unsigned b = act; b; b &= b - 1) {
			int k = __builtin_ctz(b);
			if (!want_spec[k] || !(rv[k] > 0))
				continue;
			int need = highlight_needed(rv[k], power[k], kd[k], in, kcd[k], kcs[k], ndotl[k], 1.0, cut);
			if (need < 0)
				act &= ~(1u << k);
			else if (need && (traced >> k & 1) && passes_without(in, kcd[k], kcs[k], ndotl[k], 1.0, cut))
				later |= 1u << k; /* POW AFTER SHADOW */
			else if (need)
				hs[k] = xm_pow_lite(rv[k], power[k]);
		}
		v4d hl = v4_of(hs);
		/* phong_term: in (kcd ndotl + kcs hl) */
		struct v4vec T = { v4_all(in.x) * (KCD.x * ndotl + KCS.x * hl), v4_all(in.y) * (KCD.y * ndotl + KCS.y * hl),
				   v4_all(in.z) * (KCD.z * ndotl + KCS.z * hl) };
		/* the cut (weight 1): not for a POW AFTER SHADOW lane */
		unsigned low = (unsigned)_mm256_movemask_pd((__m256d)(v4_maxabs(T) < v4_all(cut)));
		act &= ~(low & ~later);
		if (act & traced) { /* a shadow ray the packets did not trace */
			double t3[3][4];
			for (int k = 0; k < 4; k++)
				t3[0][k] = T.x[k], t3[1][k] = T.y[k], t3[2][k] = T.z[k];
			for (unsigned b = act & traced; b; b &= b - 1) {
				int k = __builtin_ctz(b);
				vec3 p = sf[k].p, ldir = v3(LD.x[k], LD.y[k], LD.z[k]);
				vec3 t = transmittance(c, offset_by(p, sf[k].ng, ldir, offset_eps(p)), lp, i, &pre[k],
						       SHADE_HINT_ANY);
				if (maxc(t) <= 0) {
					act &= ~(1u << k);
					continue;
				}
				vec3 term = v3(t3[0][k], t3[1][k], t3[2][k]);
				if (later >> k & 1)
					term = phong_term(in, kcd[k], kcs[k], ndotl[k], xm_pow_lite(rv[k], power[k]));
				term = v3_mul(term, t);
				t3[0][k] = term.x, t3[1][k] = term.y, t3[2][k] = term.z;
			}
			T = (struct v4vec){ v4_of(t3[0]), v4_of(t3[1]), v4_of(t3[2]) };
		}
		/* sum = 0 + term (direct_body's sum of one sample), then col + sum */
		v4m am = v4_mask(act);
		C.x += v4_sel(am, v4_all(0) + T.x, v4_all(0));
		C.y += v4_sel(am, v4_all(0) + T.y, v4_all(0));
		C.z += v4_sel(am, v4_all(0) + T.z, v4_all(0));
	}
	double cx[4], cy[4], cz[4];
	for (int k = 0; k < 4; k++)
		cx[k] = C.x[k], cy[k] = C.y[k], cz[k] = C.z[k];
	for (int k = 0; k < n; k++)
		col[k] = ok[k] ? v3(cx[k], cy[k], cz[k]) : v3(0, 0, 0);
#undef LANES
}

/* direct4_body with the context's flag folded (c->points_only holds). */
static __attribute__((target("avx2"))) void direct4(const struct shade_ctx *c, const struct ray u[4],
						    const struct surf sf[4], const bool ok[4], int n,
						    const struct shadow_pre pre[4], vec3 col[4])
{
	if (c->all_shadows)
		direct4_body(c, u, sf, ok, n, pre, col, true);
	else
		direct4_body(c, u, sf, ok, n, pre, col, false);
}

#undef V4_FN
