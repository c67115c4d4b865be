/*
 * test_shade.c - the lighting equation, term by term, on hand-made geometry.
 *
 * This test supplies its own accel_intersect, accel_occluded, accel_cross
 * and accel_offset_point over a few analytic spheres and planes (so the linker
 * never pulls in the real accel), records every ray the shader casts, and checks the colours and
 * the rays against values computed by hand from docs/rendering.md.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/accel.h"
#include "common/shade.h"
#include "tests/unit/check.h"

/* ---- a mock accel ------------------------------------------------------------ */

enum { MOCK_SPHERE, MOCK_PLANE };

struct mock_prim {
	int kind;
	vec3 c;      /* sphere centre or a point on the plane */
	double r;    /* sphere radius */
	vec3 n;      /* plane normal (unit) */
	uint32_t material;
};

#define MOCK_MAX 16
#define LOG_MAX 4096

struct accel {
	struct mock_prim p[MOCK_MAX];
	int n;
};

static struct ray ray_log[LOG_MAX];
static int n_log;

static bool prim_hit(const struct mock_prim *m, const struct ray *r, struct hit *h)
{
	double t;
	if (m->kind == MOCK_SPHERE) {
		vec3 oc = v3_sub(r->o, m->c);
		double a = v3_dot(r->d, r->d), b = v3_dot(oc, r->d), cc = v3_dot(oc, oc) - m->r * m->r;
		double disc = b * b - a * cc;
		if (disc < 0)
			return false;
		double sq = sqrt(disc);
		t = (-b - sq) / a;
		if (!(t > r->tmin && t < r->tmax)) {
			t = (-b + sq) / a;
			if (!(t > r->tmin && t < r->tmax))
				return false;
		}
		h->p = v3_add(r->o, v3_scale(r->d, t));
		h->n = v3_norm(v3_sub(h->p, m->c));
		h->mp = v3_sub(h->p, m->c);
		h->u = h->mp.x;
		h->v = h->mp.y;
	} else {
		double dn = v3_dot(r->d, m->n);
		if (dn == 0)
			return false;
		t = v3_dot(v3_sub(m->c, r->o), m->n) / dn;
		if (!(t > r->tmin && t < r->tmax))
			return false;
		h->p = v3_add(r->o, v3_scale(r->d, t));
		h->n = m->n;
		h->mp = v3_sub(h->p, m->c);
		h->u = h->mp.x;
		h->v = h->mp.z;
	}
	h->t = t;
	h->ng = h->n;
	h->material = m->material;
	h->object = 0;
	return true;
}

bool accel_intersect(const struct accel *a, const struct ray *r, struct hit *h)
{
	if (n_log < LOG_MAX)
		ray_log[n_log++] = *r;
	bool any = false;
	struct ray rr = *r;
	for (int i = 0; i < a->n; i++) {
		struct hit t;
		if (prim_hit(&a->p[i], &rr, &t)) {
			*h = t;
			rr.tmax = t.t;
			any = true;
		}
	}
	return any;
}

bool accel_occluded(const struct accel *a, const struct ray *r)
{
	struct hit h;
	for (int i = 0; i < a->n; i++)
		if (prim_hit(&a->p[i], r, &h))
			return true;
	return false;
}

/* As the library's (accel.c): the AVX2 paths, shading's DIRECT IN FOURS
 * among them, where the CPU has AVX2, so the mock renders take them too. */
bool accel_use_avx2(void)
{
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
	return __builtin_cpu_supports("avx2");
#else
	return false;
#endif
}

/* The hint changes no answer (accel.h): the mock ignores it. */
bool accel_occluded_hint(const struct accel *a, const struct ray *r, uint32_t *hint)
{
	(void)hint;
	return accel_occluded(a, r);
}

/* So does the light's buffer (accel.h): the same answer. */
bool accel_occluded_light(const struct accel *a, uint32_t light, const struct ray *r, uint32_t *hint)
{
	(void)light;
	return accel_occluded_hint(a, r, hint);
}

/* BUFFERED LIGHTS (shade.c): the odd lights "have a buffer", so the eye
 * hits' shadow rays take both ways, ray by ray and as packets, with the
 * same answers. */
bool accel_light_buffered(const struct accel *a, uint32_t light)
{
	(void)a;
	return light % 2 == 1;
}

void accel_occluded4(const struct accel *a, const struct ray r[4], bool occ[4], uint32_t *hint)
{
	for (int i = 0; i < 4; i++)
		occ[i] = accel_occluded_hint(a, &r[i], hint);
}

/* Four closest hits, one by one (accel.h: the same as accel_intersect). */
void accel_intersect4(const struct accel *a, const struct ray r[4], struct hit h[4], bool hit[4])
{
	for (int i = 0; i < 4; i++)
		hit[i] = accel_intersect(a, &r[i], &h[i]);
}

/* Every crossing of r's segment (accel.h, SHADOW CROSSINGS): each
 * primitive's hits in turn (a sphere's two), one entry per t, in order of t;
 * the mock's key is the primitive's index. */
bool accel_cross(const struct accel *a, const struct ray *r, const struct accel_cross_filter *f,
		 struct accel_crossings *x, uint32_t *hint)
{
	(void)hint;
	x->n = 0;
	for (int i = 0; i < a->n; i++) {
		struct ray rr = *r;
		struct hit h;
		while (prim_hit(&a->p[i], &rr, &h)) {
			struct accel_pass p;
			uint32_t m = h.material;
			if (f->opaque[m < f->n_materials ? m : f->n_materials] || !f->pass(f->ctx, &h, &p))
				return false;
			int k = 0;
			while (k < x->n && x->x[k].t != h.t)
				k++;
			if (k == x->n) {
				if (x->n == ACCEL_CROSS_MAX)
					return false;
				x->x[x->n++] = (struct accel_crossing){ h.t, (uint64_t)i, p };
			}
			rr.tmin = h.t;
		}
	}
	for (int k = 1; k < x->n; k++)
		for (int j = k; j > 0 && x->x[j - 1].t > x->x[j].t; j--) {
			struct accel_crossing e = x->x[j];
			x->x[j] = x->x[j - 1];
			x->x[j - 1] = e;
		}
	return true;
}

void accel_cross4(const struct accel *a, const struct ray r[4], const struct accel_cross_filter *f,
		  struct accel_crossings x[4], bool open[4], uint32_t *hint)
{
	for (int i = 0; i < 4; i++)
		open[i] = accel_cross(a, &r[i], f, &x[i], hint);
}

/* The same offset as the real accel's (accel.h). */
vec3 accel_offset_point(vec3 p, vec3 ng, vec3 dir)
{
	double eps = 1e-9 * (1 + fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z))));
	return v3_add(p, v3_scale(ng, v3_dot(ng, dir) >= 0 ? eps : -eps));
}

/* ---- helpers ----------------------------------------------------------------- */

static struct accel A;
static struct scene *cur; /* the scene new_scene made last */

/* The mock's primitive as a root object of the scene as well: shading
 * reads the scene's objects (shade_tbox.c, TRANSPARENT BOXES), which must be
 * what its accel was built from. */
static void add_root(enum prim_kind kind, vec3 c, double r, vec3 n, uint32_t mat)
{
	struct scene_object o;
	struct scene_error err;
	uint32_t id;
	scene_object_defaults(&o, kind);
	if (kind == PRIM_SPHERE) {
		o.u.sphere.centre = c;
		o.u.sphere.radius = r;
	} else {
		o.u.plane.position = c;
		o.u.plane.normal = n;
	}
	o.material = mat;
	CHECK(scene_add_object(cur, &o, &id, &err) == 0);
	CHECK(scene_add_root(cur, id, &err) == 0);
}

static void add_sphere(vec3 c, double r, uint32_t mat)
{
	A.p[A.n++] = (struct mock_prim){ MOCK_SPHERE, c, r, v3(0, 0, 0), mat };
	add_root(PRIM_SPHERE, c, r, v3(0, 0, 0), mat);
}

static void add_plane(vec3 c, vec3 n, uint32_t mat)
{
	A.p[A.n++] = (struct mock_prim){ MOCK_PLANE, c, 0, v3_norm(n), mat };
	add_root(PRIM_PLANE, c, 0, n, mat);
}

static struct scene *new_scene(void)
{
	A.n = 0;
	cur = scene_new();
	return cur;
}

static uint32_t add_mat(struct scene *s, struct scene_material *m)
{
	uint32_t id;
	struct scene_error err;
	int rc = scene_add_material(s, m, &id, &err);
	CHECK(rc == 0);
	return id;
}

static void add_point_light(struct scene *s, vec3 pos, vec3 colour, double fall_off, bool no_shadows)
{
	struct scene_light l;
	scene_light_defaults(&l);
	l.position = pos;
	l.colour = colour;
	l.fall_off = fall_off;
	l.no_shadows = no_shadows;
	struct scene_error err;
	CHECK(scene_add_light(s, &l, &err) == 0);
}

/* Colour seen along the ray o + t d with pixel sample seed. */
static vec3 shoot(const struct scene *s, vec3 o, vec3 d, uint64_t seed)
{
	struct shade_ctx *c;
	struct scene_error err;
	CHECK(shade_ctx_new(s, &A, &c, &err) == 0);
	struct ray r = { o, d, 0, INFINITY };
	n_log = 0;
	vec3 col = shade_trace(c, &r, seed);
	shade_ctx_free(c);
	return col;
}

static int near3(vec3 a, vec3 b, double eps)
{
	return fabs(a.x - b.x) <= eps && fabs(a.y - b.y) <= eps && fabs(a.z - b.z) <= eps;
}

/* ---- tests -------------------------------------------------------------------- */

/* Lambert: a unit sphere at the origin seen from +z, light along the view. */
static void test_diffuse(void)
{
	struct scene *s = new_scene();
	add_sphere(v3(0, 0, 0), 1, SCENE_NONE); /* default material: white, diffuse 1 */
	add_point_light(s, v3(0, 0, 10), v3(1, 1, 1), 0, false);
	vec3 c = shoot(s, v3(0, 0, 5), v3(0, 0, -1), 1);
	CHECK(near3(c, v3(1, 1, 1), 1e-9));
	/* no light, no ambient: black; a miss: black */
	CHECK(near3(shoot(s, v3(0, 0, 5), v3(0, 1, 0), 1), v3(0, 0, 0), 0));
	scene_free(s);

	/* light at 60 degrees from the normal: N.L = 0.5; coloured light and material */
	s = new_scene();
	struct scene_material m;
	scene_material_defaults(&m);
	m.diff_colour = v3(1, 0.5, 0.25);
	m.diffuse = 0.8;
	uint32_t id = add_mat(s, &m);
	add_sphere(v3(0, 0, 0), 1, id);
	add_point_light(s, v3(0, 100 * sin(M_PI / 3), 1 + 100 * cos(M_PI / 3)), v3(1, 1, 0.5), 0, false);
	c = shoot(s, v3(0, 0, 5), v3(0, 0, -1), 1);
	CHECK(near3(c, v3(0.8 * 0.5, 0.8 * 0.5 * 0.5, 0.8 * 0.25 * 0.5 * 0.5), 1e-9));
	scene_free(s);
}

/* Fall-off: colour / d^fall_off. */
static void test_fall_off(void)
{
	struct scene *s = new_scene();
	add_sphere(v3(0, 0, 0), 1, SCENE_NONE);
	add_point_light(s, v3(0, 0, 3), v3(1, 1, 1), 2, false); /* d = 2 from the hit (0,0,1) */
	CHECK(near3(shoot(s, v3(0, 0, 5), v3(0, 0, -1), 1), v3(0.25, 0.25, 0.25), 1e-9));
	scene_free(s);
	s = new_scene();
	add_sphere(v3(0, 0, 0), 1, SCENE_NONE);
	add_point_light(s, v3(0, 0, 5), v3(1, 1, 1), 1.5, false); /* d = 4 */
	CHECK(near3(shoot(s, v3(0, 0, 5), v3(0, 0, -1), 1), v3(0.125, 0.125, 0.125), 1e-9));
	scene_free(s);
}

/* Shadows: a blocker between the light and the point; no-shadows switches. */
static void test_shadows(void)
{
	struct scene *s = new_scene();
	add_plane(v3(0, 0, 0), v3(0, 0, 1), SCENE_NONE);
	add_sphere(v3(0, 0, 5), 1, SCENE_NONE); /* blocker between the floor point and light */
	add_point_light(s, v3(0, 0, 10), v3(1, 1, 1), 0, false);
	/* look at the floor point (0,0,0) from the side (so the blocker is not in the way) */
	vec3 o = v3(3, 0, 3), d = v3(-1, 0, -1);
	CHECK(near3(shoot(s, o, d, 1), v3(0, 0, 0), 0));
	/* image no-shadows */
	s->image.no_shadows = true;
	CHECK(near3(shoot(s, o, d, 1), v3(1, 1, 1), 1e-9));
	s->image.no_shadows = false;
	/* light no-shadows: the same picture as image no-shadows (one light) */
	s->lights[0].no_shadows = true;
	CHECK(near3(shoot(s, o, d, 1), v3(1, 1, 1), 1e-9));
	scene_free(s);

	/* no acne: a lit sphere with tmin = 0 everywhere on its lit half */
	s = new_scene();
	add_sphere(v3(0.3, -0.2, 0.1), 1.7, SCENE_NONE);
	add_point_light(s, v3(0.3, -0.2, 100), v3(1, 1, 1), 0, false);
	int dark = 0;
	for (int i = 0; i < 400; i++) {
		double x = 0.3 + (i % 20 - 9.5) * 0.08, y = -0.2 + (i / 20 - 9.5) * 0.08;
		vec3 c = shoot(s, v3(x, y, 10), v3(0, 0, -1), (uint64_t)i);
		if (!(c.x > 0.3))
			dark++;
	}
	CHECK(dark == 0);
	scene_free(s);
}

/* Phong highlight: specular x spec-colour x light x (R.V)^power. */
static void test_specular(void)
{
	struct scene *s = new_scene();
	struct scene_material m;
	scene_material_defaults(&m);
	m.diffuse = 0;
	m.specular = 0.7;
	m.spec_power = 10;
	m.spec_colour = v3(1, 0.5, 1);
	uint32_t id = add_mat(s, &m);
	add_plane(v3(0, 0, 0), v3(0, 0, 1), id);
	/* light at 30 degrees on one side, viewer at 40 degrees on the other */
	double a = M_PI / 6, b = 2 * M_PI / 9;
	add_point_light(s, v3(-10 * sin(a), 0, 10 * cos(a)), v3(1, 1, 1), 0, false);
	vec3 o = v3(5 * sin(b), 0, 5 * cos(b));
	vec3 c = shoot(s, o, v3_neg(o), 1);
	/* R = mirror of L: at 30 degrees on the viewer's side; R.V = cos(40-30 deg) */
	double e = 0.7 * pow(cos(b - a), 10);
	CHECK(near3(c, v3(e, 0.5 * e, e), 1e-9));
	/* the viewer on the light's side, away from the mirror direction: R.V < 0 */
	vec3 o2 = v3(-5 * sin(7 * M_PI / 18), 0, 5 * cos(7 * M_PI / 18)); /* 70 deg */
	CHECK(near3(shoot(s, o2, v3_neg(o2), 1), v3(0, 0, 0), 0));
	scene_free(s);
}

/* Mirror reflection: reflection x spec-colour x trace(reflected). */
static void test_reflection(void)
{
	struct scene *s = new_scene();
	struct scene_material m;
	scene_material_defaults(&m);
	m.diffuse = 0;
	m.reflection = 0.5;
	m.spec_colour = v3(1, 0.8, 0.6);
	uint32_t mirror = add_mat(s, &m);
	add_plane(v3(0, 0, 0), v3(0, 1, 0), mirror);       /* floor mirror y = 0 */
	add_sphere(v3(0, 3, -5), 1, SCENE_NONE);             /* white ball above it */
	add_point_light(s, v3(0, 3, 100), v3(1, 1, 1), 0, false);
	/* eye at (0,3,5) looking down at (0,0,0): the reflected ray goes to (0,3,-5) */
	vec3 c = shoot(s, v3(0, 3, 5), v3(0, -3, -5), 1);
	/* the reflected ray travels along (0,3,-5) straight at the ball's centre and
	 * hits the point of the ball that faces the origin */
	vec3 rd = v3_norm(v3(0, 3, -5));
	/* ball front point along rd from the origin: solve |t rd - (0,3,-5)| = 1 */
	double bb = v3_dot(rd, v3(0, 3, -5)), t = bb - sqrt(bb * bb - (34 - 1));
	vec3 p = v3_scale(rd, t);
	vec3 nrm = v3_norm(v3_sub(p, v3(0, 3, -5)));
	double ndl = v3_dot(nrm, v3_norm(v3_sub(v3(0, 3, 100), p)));
	CHECK(near3(c, v3(0.5 * ndl, 0.4 * ndl, 0.3 * ndl), 1e-6));
	/* two rays: eye ray and reflected ray */
	CHECK(n_log == 2);

	/* no-reflections == reflection 0 */
	s->image.no_reflections = true;
	vec3 c1 = shoot(s, v3(0, 3, 5), v3(0, -3, -5), 1);
	s->image.no_reflections = false;
	s->materials[mirror].reflection = 0;
	vec3 c2 = shoot(s, v3(0, 3, 5), v3(0, -3, -5), 1);
	CHECK(near3(c1, c2, 0) && near3(c1, v3(0, 0, 0), 0));
	scene_free(s);

	/* two facing perfect mirrors: recursion stops at LIM_TRACE_DEPTH */
	s = new_scene();
	scene_material_defaults(&m);
	m.diffuse = 0;
	m.reflection = 1;
	mirror = add_mat(s, &m);
	add_plane(v3(0, 0, 0), v3(0, 1, 0), mirror);
	add_plane(v3(0, 1, 0), v3(0, -1, 0), mirror);
	(void)shoot(s, v3(0, 0.5, 0), v3(0.1, 1, 0), 1);
	CHECK(n_log == LIM_TRACE_DEPTH + 1);
	/* a weaker mirror: the weight cut-off (1/512) stops it first: 0.5^9 < 1/512 */
	s->materials[mirror].reflection = 0.5;
	(void)shoot(s, v3(0, 0.5, 0), v3(0.1, 1, 0), 1);
	CHECK(n_log == 10);
	scene_free(s);
}

/* Transparency: thin sheets tint per crossing; refraction obeys Snell; TIR reflects. */
static void test_transparency(void)
{
	struct scene *s = new_scene();
	struct scene_material m;
	scene_material_defaults(&m);
	m.diffuse = 1;
	m.transparency = 0.5;
	m.tran_colour = v3(1, 0.5, 0.25);
	m.diff_colour = v3(0, 1, 0);
	uint32_t glass = add_mat(s, &m); /* ior 1: no bending */
	add_plane(v3(0, 0, 2), v3(0, 0, 1), glass); /* pane at z = 2 */
	add_plane(v3(0, 0, 0), v3(0, 0, 1), SCENE_NONE); /* white wall at z = 0 */
	add_point_light(s, v3(0, 0, 10), v3(1, 1, 1), 0, true);   /* no shadows: wall fully lit */
	vec3 c = shoot(s, v3(0, 0, 5), v3(0, 0, -1), 1);
	/* pane: (1-t) diffuse green + t tran-colour x wall(1) */
	CHECK(near3(c, v3(0.5, 0.5 + 0.25, 0.125), 1e-9));

	/* shadow through the pane: tinted by tran-colour x transparency */
	s->lights[0].no_shadows = false;
	/* eye straight down: the pane (lit directly) plus the wall, lit through the pane */
	c = shoot(s, v3(0, 0, 5), v3(0, 0, -1), 1);
	vec3 wall = v3(0.5, 0.25, 0.125); /* light through the pane: t x tran-colour */
	CHECK(near3(c, v3(0.5 * wall.x, 0.5 + 0.25 * wall.y, 0.125 * wall.z), 1e-9));
	scene_free(s);

	/* refraction at a flat interface, ior 1.5: sin(t) = sin(i) / 1.5 */
	s = new_scene();
	scene_material_defaults(&m);
	m.diffuse = 0;
	m.transparency = 1;
	m.ior = 1.5;
	glass = add_mat(s, &m);
	add_plane(v3(0, 0, 0), v3(0, 0, 1), glass);
	vec3 d = v3_norm(v3(sin(0.6), 0, -cos(0.6)));
	(void)shoot(s, v3(0, 0, 1), d, 1);
	CHECK(n_log == 2);
	vec3 t = v3_norm(ray_log[1].d);
	CHECK_NEAR(t.x, sin(0.6) / 1.5, 1e-12);
	CHECK(t.z < 0);
	/* the refracted ray starts just below the surface (no self-hit) */
	CHECK(ray_log[1].o.z < 0 && ray_log[1].o.z > -1e-6);
	/* leaving glass (ray from inside, against the normal): TIR beyond asin(1/1.5) */
	d = v3_norm(v3(sin(0.9), 0, cos(0.9))); /* 0.9 rad > 0.7297 critical */
	(void)shoot(s, v3(0, 0, -1), d, 1);
	CHECK(n_log == 2);
	t = v3_norm(ray_log[1].d);
	CHECK_NEAR(t.x, sin(0.9), 1e-12);
	CHECK_NEAR(t.z, -cos(0.9), 1e-12); /* reflected back inside */
	/* below the critical angle it leaves, bent away from the normal */
	d = v3_norm(v3(sin(0.4), 0, cos(0.4)));
	(void)shoot(s, v3(0, 0, -1), d, 1);
	t = v3_norm(ray_log[1].d);
	CHECK_NEAR(t.x, sin(0.4) * 1.5, 1e-12);
	CHECK(t.z > 0);
	scene_free(s);

	/* a glass ball: a ray through its centre goes straight through, 3 rays */
	s = new_scene();
	glass = add_mat(s, &m);
	add_sphere(v3(0, 0, 0), 1, glass);
	(void)shoot(s, v3(0, 0, 5), v3(0, 0, -1), 1);
	CHECK(n_log == 3);
	CHECK(near3(v3_norm(ray_log[2].d), v3(0, 0, -1), 1e-12));
	scene_free(s);
}

/* Shaped lights: a tiny sphere light ~ a point light; soft shadows in between. */
static void test_shaped_lights(void)
{
	struct scene *s = new_scene();
	add_plane(v3(0, 0, 0), v3(0, 0, 1), SCENE_NONE);
	struct scene_light l;
	scene_light_defaults(&l);
	l.shape = LIGHT_SPHERE;
	l.sphere.centre = v3(0, 0, 10);
	l.sphere.radius = 1e-6;
	l.samples = 16;
	struct scene_error err;
	CHECK(scene_add_light(s, &l, &err) == 0);
	vec3 o = v3(2, 0, 3), d = v3(-2, 0, -3); /* sees the floor origin */
	vec3 c_sphere = shoot(s, o, d, 7);
	s->lights[0].shape = LIGHT_POINT;
	s->lights[0].position = v3(0, 0, 10);
	vec3 c_point = shoot(s, o, d, 7);
	CHECK(near3(c_sphere, c_point, 1e-6));

	/* a big sphere light half hidden by a wall edge gives a penumbra value */
	s->lights[0].shape = LIGHT_SPHERE;
	s->lights[0].sphere.radius = 2;
	s->lights[0].samples = 64;
	/* occluder: a huge ball whose surface passes through the light's centre line */
	add_sphere(v3(-1000, 0, 5), 1000, SCENE_NONE);
	vec3 c1 = shoot(s, o, d, 7);
	CHECK(c1.x > 0.2 && c1.x < 0.8);
	/* deterministic: same seed, same bits; another seed, another (close) value */
	vec3 c2 = shoot(s, o, d, 7);
	CHECK(c1.x == c2.x);
	vec3 c3 = shoot(s, o, d, 8);
	CHECK(fabs(c3.x - c1.x) < 0.1);
	scene_free(s);

	/* cylinder and box lights: all samples lie on the surface */
	s = new_scene();
	add_plane(v3(0, 0, 0), v3(0, 0, 1), SCENE_NONE);
	scene_light_defaults(&l);
	l.shape = LIGHT_BOX;
	l.box.a = v3(-1, -1, 9.999999);
	l.box.b = v3(1, 1, 10); /* a thin panel */
	l.samples = 25;
	CHECK(scene_add_light(s, &l, &err) == 0);
	vec3 cb = shoot(s, v3(0, 0, 3), v3(0, 0, -1), 3);
	/* the panel seen from the origin: N.L averages a little below 1 */
	CHECK(cb.x > 0.98 && cb.x <= 1.0);
	s->lights[0].shape = LIGHT_CYLINDER;
	s->lights[0].cylinder.from = v3(-5, 0, 10);
	s->lights[0].cylinder.to = v3(5, 0, 10);
	s->lights[0].cylinder.radius = 0.5;
	vec3 cc = shoot(s, v3(0, 0, 3), v3(0, 0, -1), 3);
	/* N.L of points along a 10-long tube at height 10: mean of 10/sqrt(100+x^2) */
	double expect = 0;
	for (int i = 0; i < 10000; i++) {
		double x = -5 + 10 * (i + 0.5) / 10000;
		expect += 10 / sqrt(100 + x * x) / 10000;
	}
	CHECK(fabs(cc.x - expect) < 0.01);
	/* a capped cylinder light also samples its end discs (by area): a short,
	 * wide one is nearly a disc, whose samples lie nearer the axis */
	s->lights[0].cylinder.from = v3(0, 0, 10);
	s->lights[0].cylinder.to = v3(0, 0, 10.001);
	s->lights[0].cylinder.radius = 2;
	s->lights[0].samples = 64;
	vec3 side_only = shoot(s, v3(0, 0, 3), v3(0, 0, -1), 3);
	CHECK_NEAR(side_only.x, 10 / sqrt(104), 1e-3);
	s->lights[0].cylinder.capped = true;
	vec3 with_caps = shoot(s, v3(0, 0, 3), v3(0, 0, -1), 3);
	CHECK(with_caps.x > 0.986 && with_caps.x < 0.9925); /* disc mean ~ 1 - E[r^2]/200 = 0.99 */
	s->lights[0].cylinder.from = v3(-5, 0, 10);
	s->lights[0].cylinder.to = v3(5, 0, 10);
	s->lights[0].cylinder.radius = 0.5;
	s->lights[0].cylinder.capped = false;
	s->lights[0].samples = 25;
	/* light fall-off with a shape: every sample attenuated */
	s->lights[0].fall_off = 1;
	vec3 cf = shoot(s, v3(0, 0, 3), v3(0, 0, -1), 3);
	CHECK(cf.x < cc.x / 9.0 && cf.x > cc.x / 12.0);
	scene_free(s);
}

/* shade_eye_rays4 is shade_eye_ray four at a time, bit for bit, with the
 * lanes past n repeating the last ray, untraceable rays (zero, infinite or
 * NaN directions, infinite origins) included. */
static bool same_bits(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

static void test_eye_rays4(void)
{
	uint64_t x = 88172645463325252ull;
	double odd[] = { 0.0, -0.0, INFINITY, NAN, 1e-310, 1e300 };
	int bad = 0;
	for (int round = 0; round < 20000; round++) {
		struct ray e[4];
		for (int k = 0; k < 4; k++) {
			double v[7];
			for (int j = 0; j < 7; j++) {
				x ^= x << 13, x ^= x >> 7, x ^= x << 17;
				v[j] = ((double)(x >> 11) / 9007199254740992.0 - 0.5) * 8;
				if ((x & 255) < 3)
					v[j] = odd[(x >> 8) % 6];
			}
			e[k] = (struct ray){ v3(v[0], v[1], v[2]), v3(v[3], v[4], v[5]), fabs(v[6]) * 0.01, INFINITY };
		}
		int n = 1 + round % 4;
		struct ray u[4];
		bool ok[4];
		shade_eye_rays4(e, n, u, ok);
		for (int k = 0; k < 4; k++) {
			struct ray w;
			const struct ray *q = &e[k < n ? k : n - 1];
			bool okw = shade_eye_ray(q, &w);
			if (okw != ok[k]) {
				bad++;
				continue;
			}
			if (!okw)
				w = *q;
			bad += !(same_bits(u[k].o.x, w.o.x) && same_bits(u[k].o.y, w.o.y) && same_bits(u[k].o.z, w.o.z) &&
				 same_bits(u[k].d.x, w.d.x) && same_bits(u[k].d.y, w.d.y) && same_bits(u[k].d.z, w.d.z) &&
				 same_bits(u[k].tmin, w.tmin) && same_bits(u[k].tmax, w.tmax));
		}
	}
	CHECK(bad == 0);
}

int main(void)
{
	test_eye_rays4();
	test_diffuse();
	test_fall_off();
	test_shadows();
	test_specular();
	test_reflection();
	test_transparency();
	test_shaped_lights();
	TEST_MAIN_END();
}
