/*
 * shade.c - what a ray sees: lights (point and shaped), shadows through
 * transparent objects, Lambert diffuse, Phong highlights, mirror reflection
 * and refraction. docs/rendering.md states the lighting equation; the code
 * below follows it term by term.
 *
 * A shading point may ask for 65536 lights of 4096 samples, each shadow ray
 * for up to LIM_SHADOW_HITS surfaces, and reflection and refraction branch
 * LIM_TRACE_DEPTH deep: the calling thread's cancel flag (cancel.h) is
 * polled at every light of every shading point (its samples' shadow rays
 * take milliseconds at most: the traversal polls inside any ray that
 * could take longer) and every transparent surface a shadow ray crosses
 * but the first; once it is seen set, shading gives up (black, or what it
 * has so far), a colour the caller discards. Polling at every shadow ray
 * or shading point as well cost 1% on balls_s4.
 */
#include "common/shade.h"

#include <math.h>
#include <stdlib.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "common/cancel.h"
#include "common/rng.h"
#include "common/shade_tbox.h"
#include "common/shader.h"
#include "common/xmath.h"

/* DIRECT IN FOURS (shade_direct4.h): x86-64 with GCC's or clang's vector
 * extensions, AVX2 chosen at run time */
#if defined(__x86_64__) && defined(__SSE2__) && (defined(__GNUC__) || defined(__clang__)) && !defined(PORTRAY_NO_AVX2)
#define SHADE_DIRECT4 1
#else
#define SHADE_DIRECT4 0
#endif

/* Stream tags for rng_derive: one purpose each. */
#define TAG_LIGHT 0x4c49474854000000ull /* + light index */
#define TAG_REFLECT 0x5245464cull
#define TAG_REFRACT 0x52465241ull
/* 1/golden ratio: the second coordinate of the light-sample lattice */
#define GOLDEN_FRAC 0.6180339887498949

struct shade_light {
	const struct scene_light *l;
	/* cylinder: unit axis frame */
	vec3 e1, e2;
	/* box: corner, extents and cumulative face-pair areas */
	vec3 lo, ext;
	double area[3], total_area;
};

#define SHADE_PLAIN 64
struct shade_ctx {
	const struct scene *s;
	const struct accel *a;
	struct shade_light *lights;
	uint32_t n_lights;
	double total_samples; /* light samples per shading point, all lights (>= 1) */
	double cut;           /* SHADE_MIN_WEIGHT / total_samples (direct()) */
	bool any_transparent; /* some material has transparency > 0 */
	/* POINT LIGHTS ONLY (direct()): every light a point light without
	 * fall-off; all_shadows: shadows on, and no light has no-shadows */
	bool points_only, all_shadows;
	/* DIRECT IN FOURS (shade_direct4.h): the eye hits' direct() four at a
	 * time, on AVX2, where points_only and some light's ways are not made
	 * by the shadow packets (a light without shadows, or more lights than
	 * SHADE_PRE_WAYS) */
	bool direct4;
	/* PLAIN MATERIALS: shader_eval's result (but n) for each of the first
	 * SHADE_PLAIN materials without a shader (bit i of plain_ok) and for the
	 * default material, made once: shading points and the surfaces a shadow
	 * ray crosses (cross_pass) point at them */
	uint64_t plain_ok;
	struct shader_mat plain[SHADE_PLAIN], plain_default;
	struct shade_tboxes tb; /* TRANSPARENT BOXES (shade_tbox.h) */
	/* SHADOW CROSSINGS' filter: cross_pass, and the materials without a
	 * shader whose transparency is 0 (opaque[n_materials]: the default) */
	uint8_t *opaque;
	struct accel_cross_filter cross;
};

/*
 * LAST-BLOCKER HINTS (accel_occluded_hint): the blocker a thread's last
 * shadow ray toward a light met, tested first by its next one. The hints
 * sit in two direct-mapped tables of the thread's:
 * - eye hits and shadow packets: one hint per (context, light), since
 *   neighbouring pixels' shadows are cast by the same blockers;
 * - hits of secondary rays: one per (context, light, object hit), since
 *   consecutive reflection hits land anywhere, but a hit on an object
 *   seen before is likely shadowed by what shadowed it then (a sphere of
 *   the sphereflake, a ring's neighbour): balls_s4 -3.2%, rings_s3 -4.0%
 *   (docs/performance.md, round 10).
 * A hint never changes an answer, only what is tested first, so a slot
 * that two keys share, or a stale context at a reused address, costs time
 * at most; the tables live in thread-local storage because shading's
 * context is shared, read-only, by every tracing thread. (One table of
 * 4096 for both kinds cost tetra_s4 8%: its eye hints then sat at the end
 * of a 96 KiB block.)
 */
#define SHADE_HINTS 64
#define SHADE_OBJ_HINTS 4096
#define SHADE_HINT_ANY UINT32_MAX /* the object of an eye hit or a packet */
struct shade_hint {
	const struct shade_ctx *c;
	uint32_t light;
	uint32_t ref;
};
struct shade_obj_hint {
	const struct shade_ctx *c;
	uint32_t light, obj;
	uint32_t ref;
};
static _Thread_local struct shade_hint hints[SHADE_HINTS];
/* secondary rays traced by this thread (shade_take_secondary) */
static _Thread_local uint64_t n_secondary;
static _Thread_local struct shade_obj_hint obj_hints[SHADE_OBJ_HINTS];

/* The calling thread's hint for light i of c from a hit on object obj
 * (SHADE_HINT_ANY: the light's own). */
static uint32_t *light_hint(const struct shade_ctx *c, uint32_t i, uint32_t obj)
{
	if (obj != SHADE_HINT_ANY) {
		struct shade_obj_hint *e = &obj_hints[(obj * 8u + i) % SHADE_OBJ_HINTS];
		if (e->c != c || e->light != i || e->obj != obj) {
			e->c = c;
			e->light = i;
			e->obj = obj;
			e->ref = ACCEL_NO_HINT;
		}
		return &e->ref;
	}
	struct shade_hint *e = &hints[i % SHADE_HINTS];
	if (e->c != c || e->light != i) {
		e->c = c;
		e->light = i;
		e->ref = ACCEL_NO_HINT;
	}
	return &e->ref;
}

/*
 * SHADOW PACKETS. Before a 2x2 block of eye hits is shaded, their shadow
 * rays toward each point light among the first SHADE_PRE_LIGHTS lights
 * are traced together (shadow_packets, accel_occluded4); struct
 * shadow_pre keeps a bit per light. direct() then takes a ray's answer
 * from there instead of tracing it: shadow_packets builds the same ray
 * with direct()'s and transmittance()'s arithmetic, so the same answer.
 * BUFFERED LIGHTS: a light with a light buffer (accel_light_buffered)
 * answers the block's rays one by one from its buffer instead, as it does
 * the mirror hits' (balls_s4 -3.2%; docs/performance.md, round 23): the
 * same answers, and the packet's set-up and walk cost more than the
 * buffer's few entries.
 */
#define SHADE_PRE_LIGHTS 32
/* In scenes with transparent materials, the transmittances of the shadow
 * rays toward the first SHADE_PRE_TLIGHTS point lights, found in packets
 * (cross_packet). */
#define SHADE_PRE_TLIGHTS 8
/* The way from a hit point p (shading normal n) to a point light lp, as
 * direct() finds it: dist = |lp - p|; when dist > 0, the unit direction
 * ldir and ndotl = n . ldir; lit: dist > 0 and !(ndotl <= 0), the light
 * shines on the point's side (light_way_at). */
struct light_way {
	vec3 ldir;
	double dist, ndotl;
	bool lit;
};
#define SHADE_PRE_WAYS 4
/* direct() makes the ways to its first DIRECT_WAYS point lights up front,
 * two at a time, when the shadow packets did not (mirror hits) */
#define DIRECT_WAYS 8
struct shadow_pre {
	uint32_t known; /* bit i: light i's shadow ray from this hit was traced */
	uint32_t occ;   /* bit i: ... and it was blocked */
	uint32_t tknown; /* transparent scenes: bit i: tval[i] is light i's transmittance */
	vec3 *tval;      /* [SHADE_PRE_TLIGHTS] (NULL when tknown is 0) */
	/* LIGHT WAYS: bit i (a point light, i < SHADE_PRE_WAYS): way[i] is
	 * direct()'s way from this hit to light i, made once for the shadow
	 * packet and the shading both */
	uint32_t wknown;
	struct light_way way[SHADE_PRE_WAYS];
};

/* Two unit vectors perpendicular to unit axis a and to each other. */
static void frame(vec3 a, vec3 *e1, vec3 *e2)
{
	vec3 t = fabs(a.x) < 0.9 ? v3(1, 0, 0) : v3(0, 1, 0);
	*e1 = v3_norm(v3_cross(a, t));
	*e2 = v3_cross(a, *e1);
}

/* Largest channel (plain comparisons: fmax is a library call at -O2). */
static inline double max3(double a, double b, double c)
{
	double m = a > b ? a : b;
	return m > c ? m : c;
}
static double maxc(vec3 a) { return max3(a.x, a.y, a.z); }

/* struct light_way from p (normal n) to lp: direct()'s arithmetic. */
static inline struct light_way light_way_at(vec3 p, vec3 n, vec3 lp)
{
	struct light_way w;
	vec3 to = v3_sub(lp, p);
	w.dist = v3_len(to);
	w.lit = false;
	if (!(w.dist > 0))
		return w;
	w.ldir = v3_scale(to, 1 / w.dist);
	w.ndotl = v3_dot(n, w.ldir);
	w.lit = !(w.ndotl <= 0);
	return w;
}

/*
 * TWO WAYS AT ONCE: light_way_at for (p[0], n[0], lp[0]) and (p[1],
 * n[1], lp[1]) in the two lanes of SSE2 doubles: each lane makes the
 * scalar function's operations in its order (subtractions, the products
 * and sums of the dot products left to right, the square root, 1 / dist,
 * the products), each correctly rounded as the scalar one, so the same
 * bits. A way is a chain of a square root, a division and two dot
 * products, on which the eye hits' shading waited (perf annotate), and a
 * shading point makes one per light: two chains in one pass of the units
 * instead of one after the other.
 */
static inline void light_ways2(const vec3 p[2], const vec3 n[2], const vec3 lp[2], struct light_way w[2])
{
#if defined(__SSE2__)
	__m128d tx = _mm_sub_pd(_mm_set_pd(lp[1].x, lp[0].x), _mm_set_pd(p[1].x, p[0].x));
	__m128d ty = _mm_sub_pd(_mm_set_pd(lp[1].y, lp[0].y), _mm_set_pd(p[1].y, p[0].y));
	__m128d tz = _mm_sub_pd(_mm_set_pd(lp[1].z, lp[0].z), _mm_set_pd(p[1].z, p[0].z));
	__m128d dist = _mm_sqrt_pd(
		_mm_add_pd(_mm_add_pd(_mm_mul_pd(tx, tx), _mm_mul_pd(ty, ty)), _mm_mul_pd(tz, tz)));
	__m128d inv = _mm_div_pd(_mm_set1_pd(1.0), dist);
	__m128d lx = _mm_mul_pd(tx, inv), ly = _mm_mul_pd(ty, inv), lz = _mm_mul_pd(tz, inv);
	__m128d nl = _mm_add_pd(_mm_add_pd(_mm_mul_pd(_mm_set_pd(n[1].x, n[0].x), lx),
					   _mm_mul_pd(_mm_set_pd(n[1].y, n[0].y), ly)),
				_mm_mul_pd(_mm_set_pd(n[1].z, n[0].z), lz));
	double d[2], x[2], y[2], z[2], nd[2];
	_mm_storeu_pd(d, dist);
	_mm_storeu_pd(x, lx);
	_mm_storeu_pd(y, ly);
	_mm_storeu_pd(z, lz);
	_mm_storeu_pd(nd, nl);
	for (int k = 0; k < 2; k++) {
		w[k].dist = d[k];
		w[k].ldir = v3(x[k], y[k], z[k]);
		w[k].ndotl = nd[k];
		w[k].lit = d[k] > 0 && !(nd[k] <= 0);
	}
#else
	for (int k = 0; k < 2; k++)
		w[k] = light_way_at(p[k], n[k], lp[k]);
#endif
}

/* The TRANSPARENT BOXES' answer for shadow ray r (shade_tbox.h). */
static inline bool may_cross_transparent(const struct shade_ctx *c, const struct ray *r)
{
	return shade_tboxes_may_cross(&c->tb, r);
}

static int cross_filter_init(struct shade_ctx *c);

int shade_ctx_new(const struct scene *s, const struct accel *a, struct shade_ctx **out,
		  struct scene_error *err)
{
	*out = NULL;
	struct shade_ctx *c = calloc(1, sizeof *c);
	if (!c)
		goto oom;
	c->s = s;
	c->a = a;
	c->n_lights = s->n_lights;
	if (s->n_lights) {
		c->lights = calloc(s->n_lights, sizeof *c->lights);
		if (!c->lights)
			goto oom;
	}
	for (uint32_t i = 0; i < s->n_lights; i++) {
		struct shade_light *L = &c->lights[i];
		const struct scene_light *l = &s->lights[i];
		L->l = l;
		if (l->shape == LIGHT_CYLINDER)
			frame(v3_norm(v3_sub(l->cylinder.to, l->cylinder.from)), &L->e1, &L->e2);
		if (l->shape == LIGHT_BOX) {
			L->lo = v3_min(l->box.a, l->box.b);
			L->ext = v3_sub(v3_max(l->box.a, l->box.b), L->lo);
			L->area[0] = L->ext.y * L->ext.z; /* the two faces normal to x */
			L->area[1] = L->ext.x * L->ext.z;
			L->area[2] = L->ext.x * L->ext.y;
			L->total_area = L->area[0] + L->area[1] + L->area[2];
		}
	}
	c->total_samples = 1;
	for (uint32_t i = 0; i < s->n_lights; i++)
		c->total_samples += s->lights[i].shape == LIGHT_POINT ? 1 : s->lights[i].samples;
	c->cut = SHADE_MIN_WEIGHT / c->total_samples;
	c->points_only = true;
	c->all_shadows = !s->image.no_shadows;
	for (uint32_t i = 0; i < s->n_lights; i++) {
		if (s->lights[i].shape != LIGHT_POINT || s->lights[i].fall_off != 0)
			c->points_only = false;
		if (s->lights[i].no_shadows)
			c->all_shadows = false;
	}
	for (uint32_t i = 0; i < s->n_materials; i++)
		if (s->materials[i].transparency > 0)
			c->any_transparent = true;
#if SHADE_DIRECT4
	c->direct4 = c->points_only && (!c->all_shadows || s->n_lights > SHADE_PRE_WAYS) && accel_use_avx2();
#endif
	const struct shader_point origin = { v3(0, 0, 0), 0, 0, v3(0, 0, 1) }; /* read for n alone */
	for (uint32_t i = 0; i < s->n_materials && i < SHADE_PLAIN; i++)
		if (s->materials[i].shader.kind == SHADER_NONE) {
			shader_eval(s, i, &origin, &c->plain[i]);
			c->plain_ok |= 1ull << i;
		}
	shader_eval(s, SCENE_NONE, &origin, &c->plain_default);
	shade_tboxes_find(s, c->any_transparent, &c->tb);
	if (cross_filter_init(c))
		goto oom;
	*out = c;
	return 0;
oom:
	shade_ctx_free(c);
	return scene_errorf(err, ERRLEVEL_FATAL, "out of memory preparing the lights");
}

void shade_ctx_free(struct shade_ctx *c)
{
	if (!c)
		return;
	free(c->lights);
	free(c->opaque);
	free(c);
}


static double frac(double x) { return x - floor(x); }

/*
 * p moved off the surface with geometric normal ng to the side dir points
 * to, so a secondary ray from there (tmin = 0) cannot hit the surface it
 * starts on (no acne): accel_offset_point (accel.h), bit for bit, inline
 * (a call passes the three vectors through the stack). test_shade_inner
 * compares the two. direct() makes offset_eps once for all its shadow
 * rays, the shadow packets once a hit (block_eps).
 */
static inline double offset_eps(vec3 p)
{
	double ax = fabs(p.x), ay = fabs(p.y), az = fabs(p.z);
	double m = ay > az || az != az ? ay : az; /* fmax, NaN as the library's */
	m = ax > m || m != m ? ax : m;
	return 1e-9 * (1 + m);
}

/* offset with e = offset_eps(p) made already. */
static inline vec3 offset_by(vec3 p, vec3 ng, vec3 dir, double e)
{
	return v3_add(p, v3_scale(ng, v3_dot(dir, ng) < 0 ? -e : e));
}

static inline vec3 offset(vec3 p, vec3 ng, vec3 dir) { return offset_by(p, ng, dir, offset_eps(p)); }

/*
 * Sample k of n on a light: a point light's position, or a point on the
 * shape's surface. (u1, u2) form a randomly shifted lattice: u1 stratified
 * in n strata, u2 a golden-ratio sequence, both shifted by (r1, r2) drawn
 * from the (pixel, sample) stream, so the n points cover the surface evenly.
 */
static vec3 light_point(const struct shade_light *L, int k, int n, double r1, double r2)
{
	const struct scene_light *l = L->l;
	double u1 = frac((k + r1) / n);
	double u2 = frac(k * GOLDEN_FRAC + r2);
	switch (l->shape) {
	case LIGHT_SPHERE: {
		double z = 1 - 2 * u1, rho = sqrt(fmax(0, 1 - z * z)), phi = 2 * M_PI * u2, sn, cs;
		xm_sincos(phi, &sn, &cs);
		vec3 d = v3(rho * cs, rho * sn, z);
		return v3_add(l->sphere.centre, v3_scale(d, l->sphere.radius));
	}
	case LIGHT_CYLINDER: {
		double phi = 2 * M_PI * u2, r = l->cylinder.radius, sn, cs;
		xm_sincos(phi, &sn, &cs);
		vec3 axis = v3_sub(l->cylinder.to, l->cylinder.from);
		vec3 rad = v3_add(v3_scale(L->e1, cs), v3_scale(L->e2, sn));
		if (l->cylinder.capped) { /* u1 picks side or a cap by area */
			double side = 2 * M_PI * r * v3_len(axis), cap = M_PI * r * r;
			double t = u1 * (side + 2 * cap);
			if (t >= side) {
				t -= side;
				int top = t >= cap;
				double f = (t - (top ? cap : 0)) / cap; /* in [0,1): radius^2 fraction */
				vec3 c = top ? l->cylinder.to : l->cylinder.from;
				return v3_add(c, v3_scale(rad, r * sqrt(fmin(f, 1.0))));
			}
			u1 = t / side;
		}
		return v3_add(v3_add(l->cylinder.from, v3_scale(axis, u1)), v3_scale(rad, r));
	}
	case LIGHT_BOX: {
		if (!(L->total_area > 0))
			return v3_add(L->lo, v3_scale(L->ext, 0.5)); /* a point: its centre */
		/* u1 picks a face pair by area, then a side, then a position along it */
		double t = u1 * L->total_area;
		int axis = 0;
		while (axis < 2 && t >= L->area[axis])
			t -= L->area[axis++];
		double f = L->area[axis] > 0 ? t / L->area[axis] : 0; /* in [0,1) */
		int side = f >= 0.5;
		double a1 = side ? 2 * f - 1 : 2 * f;
		double c[3] = { 0, 0, 0 };
		int i1 = (axis + 1) % 3, i2 = (axis + 2) % 3;
		c[axis] = side;
		c[i1] = a1;
		c[i2] = u2;
		return v3(L->lo.x + c[0] * L->ext.x, L->lo.y + c[1] * L->ext.y, L->lo.z + c[2] * L->ext.z);
	}
	case LIGHT_POINT:
	default:
		return l->position;
	}
}

/* The context's evaluation of a material without a shader (PLAIN
 * MATERIALS), or NULL when shader_eval must evaluate it at the point. */
static inline const struct shader_mat *plain_mat(const struct shade_ctx *c, uint32_t material)
{
	if (material >= c->s->n_materials) /* SCENE_NONE too: the default material */
		return &c->plain_default;
	return material < SHADE_PLAIN && (c->plain_ok >> material & 1) ? &c->plain[material] : NULL;
}

/* Whether a hit on material needs its u, v and mp: only shaders read them,
 * and a material without one is evaluated without looking at them
 * (shader_eval). */
static bool surface_needed(const struct shade_ctx *c, uint32_t material)
{
	return material < c->s->n_materials && c->s->materials[material].shader.kind != SHADER_NONE;
}

/* Completes h's u, v and mp (accel_hit_surface) when they are needed. */
static void need_surface(const struct shade_ctx *c, struct hit *h)
{
	if (surface_needed(c, h->material))
		accel_hit_surface(c->a, h);
}

/*
 * A shadow ray's way to its light through transparent surfaces: every
 * surface on the segment, in order (SHADOW CROSSINGS, accel_cross), each
 * letting through transparency x tran-colour of its material there
 * (cross_pass, the filter's callback), or nothing when it is opaque.
 */
_Static_assert(LIM_SHADOW_HITS <= ACCEL_CROSS_MAX, "a list holds every crossing the light may pass");

static bool cross_pass(const void *ctx, struct hit *h, struct accel_pass *p)
{
	const struct shade_ctx *c = ctx;
	struct shader_mat own;
	const struct shader_mat *m = plain_mat(c, h->material); /* PLAIN MATERIALS */
	if (!m) {
		need_surface(c, h);
		struct shader_point pt = { h->mp, h->u, h->v, h->n };
		shader_eval(c->s, h->material, &pt, &own);
		m = &own;
	}
	double td = fmin(m->transparency, 1.0);
	if (!(td > 0))
		return false;
	p->col = v3_max(m->tran_colour, v3(0, 0, 0));
	p->td = td;
	return true;
}

/* c's SHADOW CROSSINGS filter: cross_pass, and the table of the materials
 * it would always find opaque (without a shader, transparency 0; the
 * default at n_materials), so that their hits are not completed. 0, or -1
 * out of memory. */
static int cross_filter_init(struct shade_ctx *c)
{
	const struct scene *s = c->s;
	if (!(c->opaque = calloc((size_t)s->n_materials + 1, 1)))
		return -1;
	for (uint32_t i = 0; i <= s->n_materials; i++) {
		uint32_t mi = i < s->n_materials ? i : SCENE_NONE;
		if (mi != SCENE_NONE && s->materials[mi].shader.kind != SHADER_NONE)
			continue;
		struct shader_mat own;
		const struct shader_mat *m = plain_mat(c, mi);
		if (!m) { /* beyond SHADE_PLAIN */
			const struct shader_point origin = { v3(0, 0, 0), 0, 0, v3(0, 0, 1) };
			shader_eval(s, mi, &origin, &own);
			m = &own;
		}
		c->opaque[i] = !(fmin(m->transparency, 1.0) > 0); /* cross_pass's test */
	}
	c->cross = (struct accel_cross_filter){ c->opaque, s->n_materials, cross_pass, c };
	return 0;
}

const struct accel_cross_filter *shade_cross_filter(const struct shade_ctx *c) { return &c->cross; }

/* The light an open segment's crossings x let through: their product in
 * order along the segment, 0 once it falls below SHADE_MIN_WEIGHT or at
 * the LIM_SHADOW_HITS-th surface. */
static vec3 crossings_light(const struct accel_crossings *x)
{
	vec3 t = v3(1, 1, 1);
	for (int k = 0; k < x->n; k++) {
		t = v3_scale(v3_mul(t, x->x[k].p.col), x->x[k].p.td);
		if (maxc(t) < SHADE_MIN_WEIGHT || k + 1 >= LIM_SHADOW_HITS)
			return v3(0, 0, 0);
	}
	return t;
}

/* The light the crossings of shadow ray r let through. Not inlined: its
 * list (3 KB) stays out of the frames of shading's recursion. */
static __attribute__((noinline)) vec3 cross_one(const struct shade_ctx *c, const struct ray *r, uint32_t *hint)
{
	struct accel_crossings x;
	return accel_cross(c->a, r, &c->cross, &x, hint) ? crossings_light(&x) : v3(0, 0, 0);
}

/*
 * How much light passes from o to the point lp (light i; obj: the object
 * hit, for the hint): (1,1,1) when nothing is in the way, 0 when something
 * opaque is; each transparent surface crossed multiplies it by
 * transparency x tran-colour. pre may know it from a packet's crossings.
 * A segment that meets no transparent surface (TRANSPARENT BOXES) needs
 * only the any-hit query.
 */
static vec3 transmittance(const struct shade_ctx *c, vec3 o, vec3 lp, uint32_t light, const struct shadow_pre *pre,
			  uint32_t obj)
{
	struct ray r = { o, v3_sub(lp, o), 0, 1 };
	if (c->any_transparent && pre && light < SHADE_PRE_TLIGHTS && (pre->tknown >> light & 1))
		return pre->tval[light];
	if (!c->any_transparent || !may_cross_transparent(c, &r))
		return accel_occluded_light(c->a, light, &r, light_hint(c, light, obj)) ? v3(0, 0, 0) : v3(1, 1, 1);
	return cross_one(c, &r, light_hint(c, light, obj));
}

/* The largest |channel|, or NaN when a channel is NaN or infinite (0 * it is NaN). */
static double maxabs_nan(vec3 a) { return v3_maxabs(a) + 0 * (a.x + a.y + a.z); }

/*
 * POW SKIP: whether direct() needs a sample's highlight hl = xm_pow_lite(rv,
 * power) to get its term in (kcd ndotl + kcs hl) to the bit. With ub >= hl
 * (xm_pow_ub) and b = max|kcs| ub >= every channel's |kcs hl| (rounded
 * products and sums of magnitudes are monotonic):
 * -1: the term stays below the cut (v3_maxabs(term) weight < lim) with every
 *     channel at its largest, so direct() skips the sample whatever hl is;
 *  0: b is below an eighth of an ulp of every channel's kcd ndotl (normal
 *     doubles), so each sum rounds to kcd ndotl, as it does with hl = 0;
 *  1: xm_pow_lite must be called.
 * Glass (no diffuse, power 250: examples/exam_004) is mostly -1, diffuse
 * surfaces with high powers often 0. Powers below 32 on surfaces whose
 * diffuse weight kd is above 1/64 (weighted) rarely give either: the tests
 * would cost more than they save, so they are not tried.
 */
static int highlight_needed(double rv, double power, double kd, vec3 in, vec3 kcd, vec3 kcs, double ndotl,
			    double weight, double lim)
{
	if (!(power >= 32 || kd * weight < 1.0 / 64))
		return 1;
	double ub = xm_pow_ub(rv, power);
	double b = maxabs_nan(kcs) * ub, amax = maxabs_nan(kcd) * ndotl;
	if (weight >= 0 && maxabs_nan(in) * (amax + b) * weight < lim)
		return -1;
	double x = fabs(kcd.x), y = fabs(kcd.y), z = fabs(kcd.z); /* finite when amax is */
	double amin = (x < y ? (x < z ? x : z) : (y < z ? y : z)) * ndotl;
	return amax < INFINITY && amin >= 0x1p-960 && b <= amin * 0x1p-56 ? 0 : 1;
}

/* A light sample's term of the lighting equation: in (kcd ndotl + kcs hl). */
static inline vec3 phong_term(vec3 in, vec3 kcd, vec3 kcs, double ndotl, double hl)
{
	return v3_mul(in, v3_add(v3_scale(kcd, ndotl), v3_scale(kcs, hl)));
}

/*
 * POW AFTER SHADOW: whether a sample's term passes direct()'s cut whatever
 * its highlight hl >= 0 is, so that its shadow ray is traced either way and
 * xm_pow_lite can wait for the answer (a blocked ray needs no highlight: balls_s4's
 * single shadow rays are about half blocked). With every factor >= 0 each
 * rounded channel of phong_term is at least its value at hl = 0, computed
 * here with the same function; a NaN or a
 * negative factor answers false (xm_pow_lite first, as before).
 */
static bool passes_without(vec3 in, vec3 kcd, vec3 kcs, double ndotl, double weight, double lim)
{
	if (!(in.x >= 0 && in.y >= 0 && in.z >= 0 && kcd.x >= 0 && kcd.y >= 0 && kcd.z >= 0 && kcs.x >= 0 &&
	      kcs.y >= 0 && kcs.z >= 0 && ndotl >= 0 && weight >= 0))
		return false;
	return v3_maxabs(phong_term(in, kcd, kcs, ndotl, 0.0)) * weight >= lim;
}

/*
 * Direct lighting at p (shading normal n facing the viewer, geometric
 * normal ng on the same side, unit direction to the viewer v) for material
 * m whose diffuse weight is kd (diffuse-reflection x (1 - transparency)):
 * the Lambert and Phong terms of the lighting equation summed over lights
 * and light samples. weight is what the ray contributes to its pixel: a
 * sample whose whole contribution would be below SHADE_MIN_WEIGHT / (all
 * samples of all lights) is skipped without its shadow ray, so the error
 * this makes in a pixel is below SHADE_MIN_WEIGHT. Inlined into its one
 * caller, surf_shade: left to itself gcc stopped inlining it once BLOCK
 * SHADING was added, which cost balls_s4 0.85% (docs/performance.md).
 * points and all_shadows: the context's flags (POINT LIGHTS ONLY, direct()
 * below) as constants, which fold away the tests of other shapes and
 * fall-off, and of no-shadows.
 */
static inline __attribute__((always_inline)) vec3 direct_body(const struct shade_ctx *c, vec3 p, vec3 n, vec3 ng,
							  vec3 v, const struct shader_mat *m, double kd,
							  double weight, uint64_t seed, const struct shadow_pre *pre,
							  uint32_t obj, const bool points, const bool all_shadows)
{
	bool shadows = all_shadows || !c->s->image.no_shadows;
	bool want_spec = m->specular != 0;
	vec3 kcd = v3_scale(m->diff_colour, kd), kcs = v3_scale(m->spec_colour, m->specular);
	double cut = c->cut;
	vec3 col = v3(0, 0, 0);
	/* the ways to the first DIRECT_WAYS lights that are points, two at a
	 * time (TWO WAYS AT ONCE), where no shadow packet made them */
	struct light_way way[DIRECT_WAYS];
	uint32_t n_ways = pre ? 0 : c->n_lights < DIRECT_WAYS ? c->n_lights : DIRECT_WAYS;
	for (uint32_t i = 0; i < n_ways; i += 2) {
		uint32_t j = i + 1 < n_ways ? i + 1 : i;
		light_ways2((vec3[2]){ p, p }, (vec3[2]){ n, n },
			    (vec3[2]){ c->lights[i].l->position, c->lights[j].l->position }, &way[i]);
	}
	const double eps = offset_eps(p); /* the shadow rays' offset, one for all */
	for (uint32_t i = 0; i < c->n_lights; i++) {
		if (cancel_poll()) /* CANCELLATION: a light's samples take milliseconds at most */
			return col;
		const struct shade_light *L = &c->lights[i];
		const struct scene_light *l = L->l;
		bool point = points || l->shape == LIGHT_POINT;
		int n_samples = point ? 1 : l->samples;
		double r1 = 0, r2 = 0;
		if (!point) { /* a point light draws no sample: nothing to derive */
			uint64_t ls = rng_derive(seed, TAG_LIGHT + i);
			r1 = rng_uniform(ls, 0);
			r2 = rng_uniform(ls, 1);
		}
		vec3 sum = v3(0, 0, 0);
		for (int k = 0; k < n_samples; k++) {
			vec3 lp = point ? l->position : light_point(L, k, n_samples, r1, r2);
			struct light_way here; /* the way, where none was made before the loop */
			const struct light_way *w;
			if (point && pre && i < SHADE_PRE_WAYS && (pre->wknown >> i & 1))
				w = &pre->way[i]; /* LIGHT WAYS: made for the shadow packet */
			else if (point && i < n_ways)
				w = &way[i];
			else {
				here = light_way_at(p, n, lp);
				w = &here;
			}
			if (!w->lit)
				continue;
			/* SHADOW PACKETS: a known answer; a blocked ray adds nothing,
			 * so its term (and highlight) are never made */
			bool known = shadows && (all_shadows || !l->no_shadows) && pre && i < SHADE_PRE_LIGHTS &&
				     (pre->known >> i & 1);
			if (known && (pre->occ >> i & 1))
				continue;
			vec3 ldir = w->ldir;
			double dist = w->dist, ndotl = w->ndotl;
			vec3 in = l->colour;
			if (!points && l->fall_off != 0)
				in = v3_scale(in, 1 / xm_pow(dist, l->fall_off));
			double hl = 0, rv = 0; /* (R.V)^power */
			bool traced = shadows && (all_shadows || !l->no_shadows) && !known, later = false;
			if (want_spec) {
				rv = v3_dot(v3_sub(v3_scale(n, 2 * ndotl), ldir), v);
				if (rv > 0) {
					int need = highlight_needed(rv, m->spec_power, kd, in, kcd, kcs, ndotl, weight,
								    cut * n_samples);
					if (need < 0)
						continue;
					if (need && traced && passes_without(in, kcd, kcs, ndotl, weight, cut * n_samples))
						later = true; /* POW AFTER SHADOW */
					else if (need)
						hl = xm_pow_lite(rv, m->spec_power);
				}
			}
			vec3 term = phong_term(in, kcd, kcs, ndotl, hl);
			if (!later && v3_maxabs(term) * weight < cut * n_samples)
				continue;
			if (traced) {
				vec3 t = transmittance(c, offset_by(p, ng, ldir, eps), lp, i, pre, obj);
				if (maxc(t) <= 0)
					continue;
				if (later) {
					term = phong_term(in, kcd, kcs, ndotl, xm_pow_lite(rv, m->spec_power));
				}
				term = v3_mul(term, t);
			}
			sum = v3_add(sum, term);
		}
		/* sum x 1.0 is sum, bit for bit: a point light skips the division */
		col = v3_add(col, point ? sum : v3_scale(sum, 1.0 / n_samples));
	}
	return col;
}

/*
 * POINT LIGHTS ONLY: in a scene whose lights are all point lights without
 * fall-off, direct_body is compiled again with those tests folded to
 * constants, and a third time for such a scene where, besides, every light
 * casts shadows and shadows are on (the SPD scenes; teapot.sce has a light
 * with no-shadows): the same operations on the same values, without the
 * per-light loads and branches that only area lights, fall-off and
 * no-shadows need (balls_s4 3.2% fewer instructions, 0-2.5% faster as
 * the host's load goes; teapot 5.0% fewer, 3.7-5.1% faster;
 * docs/performance.md, round 20).
 */
static inline __attribute__((always_inline)) vec3 direct(const struct shade_ctx *c, vec3 p, vec3 n, vec3 ng,
							  vec3 v, const struct shader_mat *m, double kd,
							  double weight, uint64_t seed, const struct shadow_pre *pre,
							  uint32_t obj)
{
	if (c->points_only && c->all_shadows)
		return direct_body(c, p, n, ng, v, m, kd, weight, seed, pre, obj, true, true);
	if (c->points_only)
		return direct_body(c, p, n, ng, v, m, kd, weight, seed, pre, obj, true, false);
	return direct_body(c, p, n, ng, v, m, kd, weight, seed, pre, obj, false, false);
}

/* d reflected about unit n. */
static vec3 reflect(vec3 d, vec3 n) { return v3_sub(d, v3_scale(n, 2 * v3_dot(d, n))); }

static vec3 trace(const struct shade_ctx *c, const struct ray *r, int depth, double weight, uint64_t seed);
static vec3 trace_hit(const struct shade_ctx *c, const struct ray *r, const struct hit *hp, int depth,
		      double weight, uint64_t seed);

/*
 * The colour seen along ray r (unit direction). weight is the largest
 * channel of what this ray contributes to the pixel; depth counts bounces.
 */
static vec3 trace(const struct shade_ctx *c, const struct ray *r, int depth, double weight, uint64_t seed)
{
	struct hit h;
	if (!accel_intersect(c->a, r, &h))
		return v3(0, 0, 0);
	return trace_hit(c, r, &h, depth, weight, seed);
}

/* A hit made ready for shading: facing the viewer, its material evaluated. */
struct surf {
	vec3 p;              /* the hit point */
	bool entering;       /* the ray meets the geometric normal's front */
	vec3 ng;             /* geometric normal facing the viewer */
	vec3 n;              /* shading normal (the shader's) */
	const struct shader_mat *m; /* the material there: own, or the context's (PLAIN MATERIALS; its n unused) */
	struct shader_mat own;
	double td;           /* transparency clamped to [0, 1] */
	uint32_t obj;        /* the object hit (LAST-BLOCKER HINTS' key) */
};

/* The first half of trace_hit: false when the hit cannot be shaded (black).
 * The hit is read in place, field by field, and copied only when a shader
 * needs its surface completed (need_surface): a copy of the whole struct
 * right after accel filled it in waited on store forwarding (its 16-byte
 * loads span the 8-byte stores that wrote it), 6% of the teapot's render. */
static bool surf_prepare(const struct shade_ctx *c, const struct ray *r, const struct hit *hp, struct surf *sf)
{
	vec3 p = v3_load_split(&hp->p), ng = v3_load_split(&hp->ng), n = v3_load_split(&hp->n);
	if (!v3_finite(p))
		return false;
	sf->p = p;
	sf->obj = hp->object;
	vec3 d = r->d;

	/* face the viewer: the geometric normal decides the side, n follows it */
	sf->entering = v3_dot(ng, d) < 0;
	sf->ng = sf->entering ? ng : v3_neg(ng);
	vec3 n0 = sf->entering ? n : v3_neg(n);
	const struct shader_mat *pm = plain_mat(c, hp->material);
	if (pm) { /* shader_eval's result but n, which it would set to n0 */
		sf->m = pm;
		sf->n = n0;
	} else {
		struct shader_point pt;
		if (surface_needed(c, hp->material)) {
			struct hit h = *hp; /* need_surface's case: mp, u and v completed */
			accel_hit_surface(c->a, &h);
			pt = (struct shader_point){ h.mp, h.u, h.v, n0 };
		} else {
			pt = (struct shader_point){ v3(0, 0, 0), 0, 0, n0 }; /* a plain material reads n alone */
		}
		shader_eval(c->s, hp->material, &pt, &sf->own);
		sf->m = &sf->own;
		sf->n = sf->own.n;
	}
	double tr = sf->m->transparency;
	sf->td = tr < 0 ? 0 : tr > 1 ? 1 : tr;
	return true;
}

static vec3 surf_shade(const struct shade_ctx *c, const struct ray *r, const struct surf *sf, int depth,
		       double weight, uint64_t seed, const struct shadow_pre *pre);

/* trace() given the ray's closest hit *hp. */
static vec3 trace_hit(const struct shade_ctx *c, const struct ray *r, const struct hit *hp, int depth,
		      double weight, uint64_t seed)
{
	struct surf sf;
	if (!surf_prepare(c, r, hp, &sf))
		return v3(0, 0, 0);
	return surf_shade(c, r, &sf, depth, weight, seed, NULL);
}

/*
 * The mirror ray of prepared hit sf of ray r (weight: what r contributes to
 * its pixel), as surf_shade traces it: false when it traces none; else
 * *out is the ray, *w its weight and *k what its colour is multiplied by.
 */
static inline bool reflect_ray(const struct shade_ctx *c, const struct ray *r, const struct surf *sf,
			       double weight, struct ray *out, double *w, vec3 *k)
{
	const struct shader_mat *m = sf->m;
	if (c->s->image.no_reflections || !(m->reflection > 0))
		return false;
	*k = v3_scale(m->spec_colour, m->reflection);
	*w = weight * maxc(*k);
	if (!(*w >= SHADE_MIN_WEIGHT))
		return false;
	vec3 d = r->d, n = sf->n, ng = sf->ng;
	vec3 rd = reflect(d, n);
	if (v3_dot(rd, ng) <= 0) /* a perturbed normal sent it into the surface */
		rd = reflect(d, ng);
	*out = (struct ray){ offset(sf->p, ng, rd), rd, 0, INFINITY };
	return true;
}

/* The same for the transmitted ray: refraction, or total internal
 * reflection (traced only with reflections on). */
static inline bool refract_ray(const struct shade_ctx *c, const struct ray *r, const struct surf *sf,
			       double weight, struct ray *out, double *w, vec3 *k)
{
	const struct shader_mat *m = sf->m;
	double td = sf->td;
	if (!(td > 0))
		return false;
	*k = v3_scale(v3_max(m->tran_colour, v3(0, 0, 0)), td);
	*w = weight * maxc(*k);
	if (!(*w >= SHADE_MIN_WEIGHT))
		return false;
	vec3 d = r->d, n = sf->n, ng = sf->ng;
	double eta = sf->entering ? 1 / m->ior : m->ior;
	double cosi = -v3_dot(n, d);
	double k2 = 1 - eta * eta * (1 - cosi * cosi);
	vec3 nd;
	bool tir = k2 < 0;
	if (tir) {
		nd = reflect(d, n);
	} else {
		nd = v3_norm(v3_add(v3_scale(d, eta), v3_scale(n, eta * cosi - sqrt(k2))));
		if (v3_dot(nd, ng) >= 0) /* perturbed normal: keep it going through */
			nd = d;
	}
	if (tir && c->s->image.no_reflections)
		return false;
	*out = (struct ray){ offset(sf->p, ng, nd), nd, 0, INFINITY };
	return true;
}

/* surf_shade's terms after the direct one (col): reflection, then refraction. */
static inline __attribute__((always_inline)) vec3 surf_secondary(const struct shade_ctx *c, const struct ray *r,
								  const struct surf *sf, int depth, double weight,
								  uint64_t seed, vec3 col)
{
	if (depth >= LIM_TRACE_DEPTH)
		return col;
	struct ray sr;
	double w;
	vec3 k;
	if (reflect_ray(c, r, sf, weight, &sr, &w, &k)) {
		n_secondary++;
		col = v3_add(col, v3_mul(k, trace(c, &sr, depth + 1, w, rng_derive(seed, TAG_REFLECT))));
	}
	if (refract_ray(c, r, sf, weight, &sr, &w, &k)) {
		n_secondary++;
		col = v3_add(col, v3_mul(k, trace(c, &sr, depth + 1, w, rng_derive(seed, TAG_REFRACT))));
	}
	return col;
}

/* The second half of trace_hit, with the shadow answers of pre (NULL: none
 * known) for the hit's own direct lighting: direct + reflection +
 * refraction, summed in that order (block_shade sums the same terms in the
 * same order). */
static vec3 surf_shade(const struct shade_ctx *c, const struct ray *r, const struct surf *sf, int depth,
		       double weight, uint64_t seed, const struct shadow_pre *pre)
{
	const struct shader_mat *m = sf->m;
	vec3 col = direct(c, sf->p, sf->n, sf->ng, v3_neg(r->d), m, m->diffuse * (1 - sf->td), weight, seed, pre,
			  depth ? sf->obj : SHADE_HINT_ANY);
	return surf_secondary(c, r, sf, depth, weight, seed, col);
}

#if SHADE_DIRECT4
#include "common/shade_direct4.h"
#endif

bool shade_eye_ray(const struct ray *r, struct ray *u)
{
	double len = v3_len(r->d);
	if (!(len > 0) || !isfinite(len) || !v3_finite(r->o))
		return false;
	*u = (struct ray){ r->o, v3_scale(r->d, 1 / len), r->tmin * len, r->tmax * len };
	return true;
}

/*
 * shade_eye_ray of e[min(k, n - 1)] into u[k] and ok[k], k < 4 (a ray that
 * cannot be traced is copied as it is, traced for nothing, never shaded).
 * SSE2: when all four lengths and origins pass shade_eye_ray's test, its
 * arithmetic (a square root, a division, four products) two rays at a time,
 * the same IEEE results; any other packet goes through shade_eye_ray. It
 * sits beside shade_eye_ray: a change to one is a change to both.
 */
void shade_eye_rays4(const struct ray e[4], int n, struct ray u[4], bool ok[4])
{
#if defined(__SSE2__)
	const struct ray *q[4];
	for (int k = 0; k < 4; k++)
		q[k] = &e[k < n ? k : n - 1];
	__m128d len[2], inv[2];
	bool good = true;
	for (int h = 0; h < 2; h++) {
		const struct ray *a = q[2 * h], *b = q[2 * h + 1];
		__m128d x = _mm_set_pd(b->d.x, a->d.x), y = _mm_set_pd(b->d.y, a->d.y), z = _mm_set_pd(b->d.z, a->d.z);
		/* v3_len: sqrt((x*x + y*y) + z*z) */
		len[h] = _mm_sqrt_pd(_mm_add_pd(_mm_add_pd(_mm_mul_pd(x, x), _mm_mul_pd(y, y)), _mm_mul_pd(z, z)));
		inv[h] = _mm_div_pd(_mm_set1_pd(1.0), len[h]);
		/* len > 0 and finite: 0 < len < infinity (false for NaN) */
		__m128d fine = _mm_and_pd(_mm_cmpgt_pd(len[h], _mm_setzero_pd()), _mm_cmplt_pd(len[h], _mm_set1_pd(INFINITY)));
		good &= _mm_movemask_pd(fine) == 3 && v3_finite(a->o) && v3_finite(b->o);
	}
	if (good) {
		for (int k = 0; k < 4; k++) {
			double l, i;
			_mm_store_sd(&l, k & 1 ? _mm_unpackhi_pd(len[k >> 1], len[k >> 1]) : len[k >> 1]);
			_mm_store_sd(&i, k & 1 ? _mm_unpackhi_pd(inv[k >> 1], inv[k >> 1]) : inv[k >> 1]);
			u[k] = (struct ray){ q[k]->o, v3_scale(q[k]->d, i), q[k]->tmin * l, q[k]->tmax * l };
			ok[k] = true;
		}
		return;
	}
#endif
	for (int k = 0; k < 4; k++) {
		const struct ray *q1 = &e[k < n ? k : n - 1];
		ok[k] = shade_eye_ray(q1, &u[k]);
		if (!ok[k])
			u[k] = *q1; /* traced for nothing, never shaded */
	}
}

vec3 shade_eye_hit(const struct shade_ctx *c, const struct ray *u, const struct hit *h, uint64_t seed)
{
	return h ? trace_hit(c, u, h, 0, 1.0, seed) : v3(0, 0, 0);
}

/*
 * SHADOW PACKETS: the shadow rays that direct() will trace from each
 * prepared hit (ok[k]) toward each of the first SHADE_PRE_LIGHTS point
 * lights, four at a time, into pre[k]. A ray is built exactly as direct()
 * and transmittance() build it and only where direct() gets as far as
 * tracing it but for its cut-off test (so rarely for nothing). Scenes with
 * transparent materials go through shadow_packets_transparent below.
 */
/* The octant of direction d (its sign bits), as the packets group rays. */
static unsigned octant(vec3 d)
{
	return (unsigned)!!signbit(d.x) | (unsigned)!!signbit(d.y) << 1 | (unsigned)!!signbit(d.z) << 2;
}

/* Lanes m..3 of r repeat ray m - 1 (1 <= m <= 4): a packet of m rays. */
static inline void pad_packet(struct ray r[4], int m)
{
	for (int k = m; k < 4; k++)
		r[k] = r[m - 1];
}

/* The closest hits of rays r[0 .. n-1]: as one packet when packet
 * (pad_packet overwrites lanes n..3; accel_intersect4), else one by one. */
static inline void closest_hits(const struct shade_ctx *c, struct ray r[4], int n, bool packet, struct hit hh[4],
				bool hit[4])
{
	if (packet) {
		pad_packet(r, n);
		accel_intersect4(c->a, r, hh, hit);
		return;
	}
	for (int k = 0; k < n; k++)
		hit[k] = accel_intersect(c->a, &r[k], &hh[k]);
}

/* The shadow rays r[0 .. m-1] toward point light i (at lp) from the
 * prepared hits (ok[k]) that direct() traces, hit who[j] for ray j;
 * returns m. The ways to the light are pre[k]'s when known, and are made
 * here (and kept in pre for direct()) when i < SHADE_PRE_WAYS. */
static inline int block_rays(const struct surf sf[4], const bool ok[4], int n, uint32_t i, vec3 lp,
			     const double eps[4], struct shadow_pre pre[4], struct ray r[4], int who[4])
{
	int m = 0;
	int any = -1; /* a hit to stand in for the others in light_ways2's lanes */
	for (int k = 0; k < n && any < 0; k++)
		any = ok[k] ? k : -1;
	if (any < 0)
		return 0;
	struct light_way ways[4];
	for (int k = 0; k < n; k += 2) { /* direct()'s arithmetic, two at a time */
		int a = ok[k] ? k : any, b = k + 1 < n && ok[k + 1] ? k + 1 : any;
		light_ways2((vec3[2]){ sf[a].p, sf[b].p }, (vec3[2]){ sf[a].n, sf[b].n }, (vec3[2]){ lp, lp }, &ways[k]);
	}
	for (int k = 0; k < n; k++) {
		if (!ok[k])
			continue;
		vec3 p = sf[k].p;
		struct light_way w = ways[k];
		if (i < SHADE_PRE_WAYS) {
			pre[k].way[i] = w;
			pre[k].wknown |= 1u << i;
		}
		if (!w.lit)
			continue;
		vec3 o = offset_by(p, sf[k].ng, w.ldir, eps[k]);
		r[m] = (struct ray){ o, v3_sub(lp, o), 0, 1 }; /* transmittance()'s */
		who[m++] = k;
	}
	return m;
}

/* offset_eps of each prepared hit (ok[k]), once for all of block_rays'
 * lights (eps[k] of any other is 0, unread). */
static inline void block_eps(const struct surf sf[4], const bool ok[4], int n, double eps[4])
{
	for (int k = 0; k < 4; k++)
		eps[k] = k < n && ok[k] ? offset_eps(sf[k].p) : 0;
}

/* The start of both shadow packet paths: pre[]'s bits cleared (its first,
 * the caller's); returns how many of the first lights they look at (0 with
 * shadows off). */
static uint32_t packet_lights(const struct shade_ctx *c, struct shadow_pre pre[4])
{
	for (int k = 0; k < 4; k++)
		pre[k].known = pre[k].occ = pre[k].tknown = pre[k].wknown = 0;
	if (c->s->image.no_shadows)
		return 0;
	return c->n_lights < SHADE_PRE_LIGHTS ? c->n_lights : SHADE_PRE_LIGHTS;
}

/* Light i's shadow rays go as packets: a point light that casts shadows. */
static bool packet_light(const struct shade_ctx *c, uint32_t i)
{
	const struct scene_light *l = c->lights[i].l;
	return l->shape == LIGHT_POINT && !l->no_shadows;
}

/* The m (1..4) shadow rays r[0..m) of hits who[0..m) toward light i as one
 * occlusion packet (lanes past m repeat the last ray), or one by one
 * through light i's buffer where it has one (BUFFERED LIGHTS), their
 * answers into pre. */
static void occlusion_packet(const struct shade_ctx *c, uint32_t i, struct ray r[4], const int who[4], int m,
			     struct shadow_pre pre[4])
{
	bool occ[4];
	uint32_t *hint = light_hint(c, i, SHADE_HINT_ANY); /* the light's, shared by the block's rays */
	if (accel_light_buffered(c->a, i)) {
		for (int j = 0; j < m; j++)
			occ[j] = accel_occluded_light(c->a, i, &r[j], hint);
	} else {
		pad_packet(r, m);
		accel_occluded4(c->a, r, occ, hint);
	}
	for (int j = 0; j < m; j++) {
		pre[who[j]].known |= 1u << i;
		pre[who[j]].occ |= (uint32_t)occ[j] << i;
	}
}

/* always inlined into its caller (as gcc's LTO build does anyway): the
 * hits it reads are only those prepared (ok), which a call would hide */
static inline __attribute__((always_inline)) void shadow_packets(const struct shade_ctx *c, const struct surf sf[4],
								  const bool ok[4], int n, struct shadow_pre pre[4])
{
	for (int k = 0; k < 4; k++)
		pre[k].tval = NULL;
	uint32_t n_lights = packet_lights(c, pre);
	double eps[4];
	block_eps(sf, ok, n, eps);
	for (uint32_t i = 0; i < n_lights; i++) {
		if (!packet_light(c, i))
			continue;
		const struct scene_light *l = c->lights[i].l;
		struct ray r[4];
		int who[4];
		int m = block_rays(sf, ok, n, i, l->position, eps, pre, r, who);
		if (!m)
			continue;
		occlusion_packet(c, i, r, who, m, pre);
	}
}

/* transmittance() of four shadow rays r[j] of one octant toward light i,
 * as one packet of crossings (accel_cross4), into t[j]; obj[j]: the object
 * ray j starts from (the first's names the hint). Not inlined, as
 * cross_one. */
static __attribute__((noinline)) void cross_packet(const struct shade_ctx *c, const struct ray r[4], uint32_t i,
						   const uint32_t obj[4], vec3 t[4])
{
	struct accel_crossings x[4];
	bool open[4];
	accel_cross4(c->a, r, &c->cross, x, open, light_hint(c, i, obj[0]));
	for (int j = 0; j < 4; j++)
		t[j] = open[j] ? crossings_light(&x[j]) : v3(0, 0, 0);
}

/*
 * shadow_packets in a scene with transparent materials (TRANSPARENT
 * BOXES), for hits at any depth (depth: the hits', for the hints): a block
 * whose rays toward a light all miss the boxes is traced as above
 * (occlusion_packet: a packet, or the light's buffer); one where some ray may cross a transparent
 * surface, as one packet of crossings (cross_packet) when it is a whole
 * packet of one octant, and otherwise the rays that miss the boxes alone,
 * the others left to direct(). The crossings are found whether or not
 * direct() will need them (it skips a light whose term is too faint to
 * count); finding them all in packets paid (gears_s2 -8.6% in round 11,
 * when they were walks, docs/performance.md).
 */
static void shadow_packets_transparent(const struct shade_ctx *c, const struct surf sf[4], const bool ok[4], int n,
				       int depth, struct shadow_pre pre[4])
{
	uint32_t n_lights = packet_lights(c, pre);
	double eps[4];
	block_eps(sf, ok, n, eps);
	for (uint32_t i = 0; i < n_lights; i++) {
		if (!packet_light(c, i))
			continue;
		const struct scene_light *l = c->lights[i].l;
		struct ray r[4];
		int who[4];
		int m = block_rays(sf, ok, n, i, l->position, eps, pre, r, who);
		bool cross[4];
		int nc = 0;
		for (int j = 0; j < m; j++)
			nc += cross[j] = may_cross_transparent(c, &r[j]);
		if (nc && m == 4 && i < SHADE_PRE_TLIGHTS && octant(r[1].d) == octant(r[0].d) &&
		    octant(r[2].d) == octant(r[0].d) && octant(r[3].d) == octant(r[0].d)) {
			vec3 t[4];
			uint32_t obj[4];
			for (int j = 0; j < 4; j++)
				obj[j] = depth ? sf[who[j]].obj : SHADE_HINT_ANY;
			cross_packet(c, r, i, obj, t);
			for (int j = 0; j < 4; j++) {
				pre[who[j]].tknown |= 1u << i;
				pre[who[j]].tval[i] = t[j];
			}
			continue;
		}
		int q = 0; /* those that may cross are left to direct() */
		for (int j = 0; j < m; j++)
			if (!cross[j]) {
				r[q] = r[j];
				who[q++] = who[j];
			}
		if (q)
			occlusion_packet(c, i, r, who, q, pre);
	}
}

/*
 * BLOCK SHADING (scenes with transparent materials). The hits of a 2x2
 * block of eye rays are shaded together (shade_eye_hit4); where a block's
 * hits lie on one flat patch (block_flat), their mirror rays and their
 * refracted rays are as coherent as the eye rays were: each kind goes as
 * one packet (block_trace, accel_intersect4) and its hits are shaded as a
 * block in turn, down to LIM_TRACE_DEPTH. Anywhere else a hit is shaded
 * alone (surf_shade) and its rays go one at a time. block_shade sums each
 * ray's terms in surf_shade's order (direct, then reflection, then
 * refraction) with the same functions (surf_shade at the depth limit
 * for the first, reflect_ray, refract_ray), and the random streams are per ray (rng_derive), so every
 * colour is surf_shade's, bit for bit, whatever the order of tracing.
 *
 * Where it pays (docs/performance.md, round 6): refraction through the
 * flat faces of glass (gears_s2). Mirror rays off curved surfaces diverge,
 * so their packets cost as much as single rays (balls_s4, rings_s3); the
 * shadow rays of secondary hits as occlusion packets cost more than they
 * saved; and the block path's overhead made the opaque SPD scenes slower,
 * so opaque scenes keep the per-hit path.
 */
/* Hits whose shading normals have a dot product of at least this with the
 * first one's count as one flat patch (a plane, a polygon, coplanar
 * triangles); neighbouring normals on the SPD spheres differ by more. */
#define SHADE_FLAT_COS 0.99999
/* A packet's rays must be of one octant (accel_intersect4 traces other
 * packets a lane at a time) and within this angle of the first ray. */
#define SHADE_PACKET_COS 0.9

/* Whether the prepared hits sf[k] (ok[k], k < n) are at least two and
 * their shading normals all but parallel (a flat patch). */
static inline bool block_flat(const struct surf sf[4], const bool ok[4], int n)
{
	int first = -1, m = 0;
	for (int k = 0; k < n; k++) {
		if (!ok[k])
			continue;
		m++;
		if (first < 0)
			first = k;
		else if (!(v3_dot(sf[k].n, sf[first].n) >= SHADE_FLAT_COS))
			return false;
	}
	return m >= 2;
}

static void block_trace(const struct shade_ctx *c, struct ray r[4], int n, int depth, const double weight[4],
			const uint64_t seed[4], vec3 out[4]);

/* The secondary rays of one kind (refl: mirror, else transmitted) of the
 * prepared hits sf[k] (ok[k]) of rays r[k], traced together and added to
 * out[k]. */
static inline void block_secondary(const struct shade_ctx *c, const struct ray r[4], const struct surf sf[4],
				   const bool ok[4], int n, int depth, const double weight[4],
				   const uint64_t seed[4], bool refl, vec3 out[4])
{
	struct ray sr[4];
	double w[4];
	vec3 k[4];
	uint64_t ss[4];
	int who[4], m = 0;
	for (int j = 0; j < n; j++) {
		if (!ok[j])
			continue;
		bool any = refl ? reflect_ray(c, &r[j], &sf[j], weight[j], &sr[m], &w[m], &k[m])
				: refract_ray(c, &r[j], &sf[j], weight[j], &sr[m], &w[m], &k[m]);
		if (!any)
			continue;
		ss[m] = rng_derive(seed[j], refl ? TAG_REFLECT : TAG_REFRACT);
		who[m++] = j;
	}
	if (!m)
		return;
	n_secondary += (uint64_t)m;
	vec3 col[4];
	block_trace(c, sr, m, depth + 1, w, ss, col);
	for (int j = 0; j < m; j++)
		out[who[j]] = v3_add(out[who[j]], v3_mul(k[j], col[j]));
}

/* surf_shade of the prepared hits sf[k] (ok[k]; black otherwise) of rays
 * r[k], k < n, into out[k]: as a block on a flat patch, else one by one. */
static void block_shade(const struct shade_ctx *c, const struct ray r[4], const struct surf sf[4], const bool ok[4],
			int n, int depth, const double weight[4], const uint64_t seed[4],
			const struct shadow_pre pre[4], vec3 out[4])
{
	if (depth >= LIM_TRACE_DEPTH || !block_flat(sf, ok, n)) {
		for (int k = 0; k < n; k++)
			out[k] = ok[k] ? surf_shade(c, &r[k], &sf[k], depth, weight[k], seed[k], &pre[k]) : v3(0, 0, 0);
		return;
	}
	for (int k = 0; k < n; k++) /* at the depth limit, surf_shade is the direct term alone */
		out[k] = ok[k] ? surf_shade(c, &r[k], &sf[k], LIM_TRACE_DEPTH, weight[k], seed[k], &pre[k]) : v3(0, 0, 0);
	block_secondary(c, r, sf, ok, n, depth, weight, seed, true, out);
	block_secondary(c, r, sf, ok, n, depth, weight, seed, false, out);
}

/*
 * trace_hit of n <= 4 rays r[k] whose closest hits are h[k] (NULL: a miss,
 * black), into out[k], in a scene with transparent materials. The hits'
 * shadow rays go as packets (shadow_packets_transparent, with room for
 * their transmittances) at every depth: the rays of a block that came through
 * a flat patch of glass are as coherent as the eye rays' (gears_s2 -3.9%
 * against packets for the eye hits alone, docs/performance.md round 11).
 */
static __attribute__((noinline)) void block_hits(const struct shade_ctx *c, const struct ray r[4],
						  const struct hit *h[4], int n, int depth, const double weight[4],
						  const uint64_t seed[4], vec3 out[4])
{
	struct surf sf[4];
	bool ok[4] = { false, false, false, false };
	for (int k = 0; k < n; k++)
		ok[k] = h[k] && surf_prepare(c, &r[k], h[k], &sf[k]);
	struct shadow_pre pre[4];
	vec3 tval[4][SHADE_PRE_TLIGHTS];
	for (int k = 0; k < 4; k++)
		pre[k].tval = tval[k];
	shadow_packets_transparent(c, sf, ok, n, depth, pre);
	block_shade(c, r, sf, ok, n, depth, weight, seed, pre, out);
}

/* trace() of n (1..4) rays r[k], k < n, into out[k]; lanes n..3 of r are
 * overwritten. Two to four rays of one octant, near each other, are one
 * packet (lanes past n repeat the last ray) whose hits are shaded as a
 * block; other rays go through trace() one at a time. */
static void block_trace(const struct shade_ctx *c, struct ray r[4], int n, int depth, const double weight[4],
			const uint64_t seed[4], vec3 out[4])
{
	unsigned oct = octant(r[0].d);
	bool one = n >= 2;
	for (int k = 1; k < n; k++)
		one &= octant(r[k].d) == oct && v3_dot(r[k].d, r[0].d) >= SHADE_PACKET_COS;
	struct hit hh[4];
	bool hit[4];
	closest_hits(c, r, n, one, hh, hit);
	const struct hit *hp[4] = { NULL, NULL, NULL, NULL };
	for (int k = 0; k < n; k++)
		hp[k] = hit[k] ? &hh[k] : NULL;
	block_hits(c, r, hp, n, depth, weight, seed, out);
}

void shade_eye_hit4(const struct shade_ctx *c, const struct ray u[4], const struct hit *h[4],
		    const uint64_t seed[4], int n, vec3 out[4])
{
	if (c->any_transparent) { /* BLOCK SHADING */
		static const double one[4] = { 1.0, 1.0, 1.0, 1.0 };
		block_hits(c, u, h, n, 0, one, seed, out);
		return;
	}
	struct surf sf[4];
	bool ok[4] = { false, false, false, false };
	for (int k = 0; k < n; k++)
		ok[k] = h[k] && surf_prepare(c, &u[k], h[k], &sf[k]);
	struct shadow_pre pre[4];
	shadow_packets(c, sf, ok, n, pre);
	vec3 dc[4] = { v3(0, 0, 0), v3(0, 0, 0), v3(0, 0, 0), v3(0, 0, 0) };
#if SHADE_DIRECT4
	if (c->direct4) /* DIRECT IN FOURS: the direct terms; each hit's secondary rays below */
		direct4(c, u, sf, ok, n, pre, dc);
#endif
	for (int k = 0; k < n; k++) {
		if (!ok[k]) {
			out[k] = v3(0, 0, 0);
			continue;
		}
		vec3 v = c->direct4 ? surf_secondary(c, &u[k], &sf[k], 0, 1.0, seed[k], dc[k])
				    : surf_shade(c, &u[k], &sf[k], 0, 1.0, seed[k], &pre[k]);
		out[k] = v3_load_split(&v); /* returned in memory: read as it was written */
	}
}

vec3 shade_trace(const struct shade_ctx *c, const struct ray *r, uint64_t seed)
{
	struct ray u;
	if (!shade_eye_ray(r, &u))
		return v3(0, 0, 0);
	return trace(c, &u, 0, 1.0, seed);
}

uint64_t shade_take_secondary(void)
{
	uint64_t n = n_secondary;
	n_secondary = 0;
	return n;
}
