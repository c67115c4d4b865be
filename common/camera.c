/*
 * camera.c - the pinhole camera and the thin lens (camera.h, docs/camera.md).
 */
#include "common/camera.h"

#include <math.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

int cam_init(struct cam *c, const struct scene_camera *sc, uint32_t w, uint32_t h)
{
	vec3 view = v3_sub(sc->look_at, sc->look_from);
	vec3 right = v3_cross(sc->drop_line, view);
	if (!(v3_len(view) > 0) || !(v3_len(right) > 0) || w == 0 || h == 0)
		return -1;
	c->from = sc->look_from;
	c->view = v3_norm(view);
	c->right = v3_norm(right);
	c->down = v3_norm(v3_cross(view, c->right));
	c->depth = sc->depth;
	c->x_size = sc->x_size;
	c->y_size = sc->y_size;
	c->w = w;
	c->h = h;
	c->vd = v3_scale(c->view, c->depth);
	return 0;
}

vec3 cam_col(const struct cam *c, double px) { return v3_scale(c->right, (px / c->w - 0.5) * c->x_size); }

vec3 cam_row(const struct cam *c, double py) { return v3_scale(c->down, (py / c->h - 0.5) * c->y_size); }

/* Direction from look-from to the film point of (px, py) (not unit). */
static vec3 cam_dir(const struct cam *c, double px, double py)
{
	return v3_add(c->vd, v3_add(cam_col(c, px), cam_row(c, py)));
}

vec3 cam_film_point(const struct cam *c, double px, double py) { return v3_add(c->from, cam_dir(c, px, py)); }

struct ray cam_ray(const struct cam *c, double px, double py)
{
	struct ray r;
	r.o = c->from;
	r.d = v3_norm(cam_dir(c, px, py));
	r.tmin = 0.0;
	r.tmax = INFINITY;
	return r;
}

/* The fields of an eye ray but its direction. */
static void cam_eye(const struct cam *c, struct ray *r)
{
	r->o = c->from;
	r->tmin = 0.0;
	r->tmax = INFINITY;
}

#if defined(__SSE2__)
/* v3_norm of two directions, lane by lane: l = sqrt((x*x + y*y) + z*z),
 * then d * (1 / l) where l > 0 and d unchanged where not (zero or NaN). */
static void unit2(__m128d *x, __m128d *y, __m128d *z)
{
	__m128d l = _mm_sqrt_pd(_mm_add_pd(_mm_add_pd(_mm_mul_pd(*x, *x), _mm_mul_pd(*y, *y)), _mm_mul_pd(*z, *z)));
	__m128d inv = _mm_div_pd(_mm_set1_pd(1.0), l);
	__m128d pos = _mm_cmpgt_pd(l, _mm_setzero_pd());
	*x = _mm_or_pd(_mm_and_pd(pos, _mm_mul_pd(*x, inv)), _mm_andnot_pd(pos, *x));
	*y = _mm_or_pd(_mm_and_pd(pos, _mm_mul_pd(*y, inv)), _mm_andnot_pd(pos, *y));
	*z = _mm_or_pd(_mm_and_pd(pos, _mm_mul_pd(*z, inv)), _mm_andnot_pd(pos, *z));
}

/* Stores lane 0 of (x, y, z) into r[0].d and, when two, lane 1 into r[1].d. */
static void store2(__m128d x, __m128d y, __m128d z, struct ray *r, int two)
{
	_mm_storel_pd(&r[0].d.x, x);
	_mm_storel_pd(&r[0].d.y, y);
	_mm_storel_pd(&r[0].d.z, z);
	if (two) {
		_mm_storeh_pd(&r[1].d.x, x);
		_mm_storeh_pd(&r[1].d.y, y);
		_mm_storeh_pd(&r[1].d.z, z);
	}
}
#endif

void cam_unit4(const struct cam *c, const vec3 d[4], int n, struct ray r[4])
{
	for (int k = 0; k < n; k++)
		cam_eye(c, &r[k]);
#if defined(__SSE2__)
	for (int k = 0; k < n; k += 2) {
		int k1 = k + 1 < n ? k + 1 : k; /* one ray left: both lanes the same */
		__m128d x = _mm_set_pd(d[k1].x, d[k].x), y = _mm_set_pd(d[k1].y, d[k].y);
		__m128d z = _mm_set_pd(d[k1].z, d[k].z);
		unit2(&x, &y, &z);
		store2(x, y, z, &r[k], k1 != k);
	}
#else
	for (int k = 0; k < n; k++)
		r[k].d = v3_norm(d[k]);
#endif
}

void cam_ray4(const struct cam *c, const double px[4], const double py[4], int n, struct ray r[4])
{
#if defined(__SSE2__)
	for (int k = 0; k < n; k++)
		cam_eye(c, &r[k]);
	const __m128d w = _mm_set1_pd((double)c->w), h = _mm_set1_pd((double)c->h), half = _mm_set1_pd(0.5);
	const __m128d xs = _mm_set1_pd(c->x_size), ys = _mm_set1_pd(c->y_size);
	for (int k = 0; k < n; k += 2) {
		int k1 = k + 1 < n ? k + 1 : k;
		/* cam_col and cam_row: (p / w - 0.5) * size along right and down */
		__m128d fx = _mm_mul_pd(_mm_sub_pd(_mm_div_pd(_mm_set_pd(px[k1], px[k]), w), half), xs);
		__m128d fy = _mm_mul_pd(_mm_sub_pd(_mm_div_pd(_mm_set_pd(py[k1], py[k]), h), half), ys);
		/* cam_dir: vd + (right * fx + down * fy) */
		__m128d x = _mm_add_pd(_mm_set1_pd(c->vd.x), _mm_add_pd(_mm_mul_pd(_mm_set1_pd(c->right.x), fx),
									_mm_mul_pd(_mm_set1_pd(c->down.x), fy)));
		__m128d y = _mm_add_pd(_mm_set1_pd(c->vd.y), _mm_add_pd(_mm_mul_pd(_mm_set1_pd(c->right.y), fx),
									_mm_mul_pd(_mm_set1_pd(c->down.y), fy)));
		__m128d z = _mm_add_pd(_mm_set1_pd(c->vd.z), _mm_add_pd(_mm_mul_pd(_mm_set1_pd(c->right.z), fx),
									_mm_mul_pd(_mm_set1_pd(c->down.z), fy)));
		unit2(&x, &y, &z);
		store2(x, y, z, &r[k], k1 != k);
	}
#else
	for (int k = 0; k < n; k++)
		r[k] = cam_ray(c, px[k], py[k]);
#endif
}

struct ray cam_lens_ray(const struct cam *c, double px, double py, double lu, double lv, double focal)
{
	vec3 d = cam_dir(c, px, py);
	/* the pinhole ray meets the focal plane at from + d * (focal / depth) */
	vec3 focus = v3_add(c->from, v3_scale(d, focal / c->depth));
	vec3 lens = v3_add(c->from, v3_add(v3_scale(c->right, lu), v3_scale(c->down, lv)));
	struct ray r;
	r.o = lens;
	r.d = v3_norm(v3_sub(focus, lens));
	r.tmin = 0.0;
	r.tmax = INFINITY;
	return r;
}
