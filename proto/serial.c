/*
 * serial.c - scene encoding and decoding (see serial.h; the layout is in
 * docs/protocol.md, "Scene encoding"). Every multi-byte number is big-endian,
 * doubles travel as their IEEE-754 bit patterns, ints as two's complement
 * 32-bit, booleans as one byte that must be 0 or 1.
 */
#include "proto/serial.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "proto/buf.h"

/* ---- encoder -------------------------------------------------------------- */

static void put_i32(struct proto_wbuf *b, int v) { proto_put_u32(b, (uint32_t)v); }
static void put_bool(struct proto_wbuf *b, bool v) { proto_put_u8(b, v ? 1 : 0); }
static void put_vec(struct proto_wbuf *b, vec3 v)
{
	proto_put_f64(b, v.x);
	proto_put_f64(b, v.y);
	proto_put_f64(b, v.z);
}
static void put_loc(struct proto_wbuf *b, const struct src_loc *l)
{
	put_i32(b, l->line);
	put_i32(b, l->col);
}

static void put_filter(struct proto_wbuf *b, const struct scene_filter *f)
{
	proto_put_u32(b, (uint32_t)f->kind);
	proto_put_f64(b, f->threshold);
	put_i32(b, f->max_depth);
	put_i32(b, f->cache_size);
	proto_put_f64(b, f->relax);
	put_i32(b, f->x_samples);
	put_i32(b, f->y_samples);
	proto_put_f64(b, f->radius);
	put_i32(b, f->samples);
	proto_put_f64(b, f->focal_length);
	put_loc(b, &f->loc);
}

static void put_sphere(struct proto_wbuf *b, const struct prim_sphere *p)
{
	put_vec(b, p->centre);
	proto_put_f64(b, p->radius);
	put_vec(b, p->pole);
	put_vec(b, p->equator);
}

static void put_cylinder(struct proto_wbuf *b, const struct prim_cylinder *p)
{
	put_vec(b, p->from);
	put_vec(b, p->to);
	proto_put_f64(b, p->radius);
	put_bool(b, p->capped);
}

static void put_material(struct proto_wbuf *b, const struct scene_material *m)
{
	put_bool(b, m->name != NULL);
	if (m->name)
		proto_put_str(b, m->name);
	put_vec(b, m->diff_colour);
	put_vec(b, m->spec_colour);
	put_vec(b, m->tran_colour);
	proto_put_f64(b, m->diffuse);
	proto_put_f64(b, m->specular);
	proto_put_f64(b, m->spec_power);
	proto_put_f64(b, m->reflection);
	proto_put_f64(b, m->transparency);
	proto_put_f64(b, m->ior);
	put_loc(b, &m->loc);
	const struct scene_shader *sh = &m->shader;
	proto_put_u32(b, (uint32_t)sh->kind);
	if (sh->kind == SHADER_NONE)
		return;
	proto_put_f64(b, sh->size);
	proto_put_u32(b, sh->mat_a);
	proto_put_u32(b, sh->mat_b);
	proto_put_f64(b, sh->tile_width);
	proto_put_f64(b, sh->grout_width);
	put_i32(b, sh->terms);
	put_vec(b, sh->axis_size);
	proto_put_f64(b, sh->saturation);
	proto_put_f64(b, sh->depth);
	proto_put_f64(b, sh->variance);
	put_vec(b, sh->colour);
	put_vec(b, sh->axis);
	put_bool(b, sh->fades_materials);
	proto_put_u32(b, sh->n_fades);
	for (uint32_t i = 0; i < sh->n_fades; i++) {
		proto_put_f64(b, sh->fades[i].dist);
		put_vec(b, sh->fades[i].colour);
		proto_put_u32(b, sh->fades[i].material);
	}
}

static void put_mesh(struct proto_wbuf *b, const struct scene_mesh *m)
{
	proto_put_str(b, m->file);
	proto_put_u32(b, m->n_vertices);
	proto_put_u32(b, m->n_triangles);
	put_bool(b, m->normals != NULL);
	put_bool(b, m->smooth);
	proto_put_f64(b, m->weld);
	put_vec(b, m->rotation);
	put_vec(b, m->at);
	if (proto_wbuf_reserve(b, (size_t)m->n_vertices * (m->normals ? 48 : 24) + (size_t)m->n_triangles * 12) < 0)
		return;
	for (uint32_t i = 0; i < m->n_vertices; i++)
		put_vec(b, m->vertices[i]);
	if (m->normals)
		for (uint32_t i = 0; i < m->n_vertices; i++)
			put_vec(b, m->normals[i]);
	for (uint64_t i = 0; i < 3ull * m->n_triangles; i++)
		proto_put_u32(b, m->tris[i]);
}

static void put_light(struct proto_wbuf *b, const struct scene_light *l)
{
	put_vec(b, l->colour);
	put_vec(b, l->position);
	proto_put_u32(b, (uint32_t)l->shape);
	put_sphere(b, &l->sphere);
	put_cylinder(b, &l->cylinder);
	put_vec(b, l->box.a);
	put_vec(b, l->box.b);
	put_i32(b, l->samples);
	proto_put_f64(b, l->fall_off);
	put_bool(b, l->no_shadows);
	put_loc(b, &l->loc);
}

/* Transform forms (version 2): a translation alone travels as 3 doubles,
 * not 12 (a million instances of a mesh are 45 bytes each, not 117). */
enum { XF_FORM_NONE = 0, XF_FORM_TRANSLATE = 1, XF_FORM_FULL = 2 };

/* Whether m's 3x3 part is the identity's, bit for bit (-0 is not 0). */
static bool lin_is_identity(const mat34 *m)
{
	mat34 id = m34_identity();
	for (int i = 0; i < 3; i++)
		if (memcmp(m->m[i], id.m[i], 3 * sizeof(double)) != 0)
			return false;
	return true;
}

static void put_object(struct proto_wbuf *b, const struct scene_object *o)
{
	proto_put_u8(b, (uint8_t)o->kind);
	if (!o->has_xform) {
		proto_put_u8(b, XF_FORM_NONE);
	} else if (lin_is_identity(&o->xform)) {
		proto_put_u8(b, XF_FORM_TRANSLATE);
		for (int i = 0; i < 3; i++)
			proto_put_f64(b, o->xform.m[i][3]);
	} else {
		proto_put_u8(b, XF_FORM_FULL);
		for (int i = 0; i < 3; i++)
			for (int j = 0; j < 4; j++)
				proto_put_f64(b, o->xform.m[i][j]);
	}
	proto_put_u32(b, o->material);
	put_loc(b, &o->loc);
	switch (o->kind) {
	case PRIM_SPHERE:
		put_sphere(b, &o->u.sphere);
		break;
	case PRIM_PLANE:
	case PRIM_DISK:
		put_vec(b, o->u.plane.position);
		put_vec(b, o->u.plane.normal);
		put_vec(b, o->u.plane.x_axis);
		put_vec(b, o->u.plane.y_axis);
		put_bool(b, o->u.plane.has_axes);
		proto_put_f64(b, o->u.plane.radius);
		break;
	case PRIM_CYLINDER:
		put_cylinder(b, &o->u.cylinder);
		break;
	case PRIM_BOX:
		put_vec(b, o->u.box.a);
		put_vec(b, o->u.box.b);
		break;
	case PRIM_TRIANGLE:
		put_vec(b, o->u.triangle.a);
		put_vec(b, o->u.triangle.b);
		put_vec(b, o->u.triangle.c);
		put_bool(b, o->u.triangle.has_normals);
		if (o->u.triangle.has_normals) {
			put_vec(b, o->u.triangle.na);
			put_vec(b, o->u.triangle.nb);
			put_vec(b, o->u.triangle.nc);
		}
		break;
	case PRIM_RAW:
		proto_put_u32(b, o->u.raw.mesh);
		break;
	case PRIM_CSG:
		proto_put_u32(b, (uint32_t)o->u.csg.op);
		proto_put_u32(b, o->u.csg.operand1);
		proto_put_u32(b, o->u.csg.operand2);
		break;
	case PRIM_POLYGON: {
		const struct prim_polygon *p = &o->u.polygon;
		proto_put_u32(b, p->n_contours);
		proto_put_u32(b, p->n_points);
		for (uint32_t i = 0; i <= p->n_contours; i++)
			proto_put_u32(b, p->contour_start[i]);
		for (uint32_t i = 0; i < p->n_points; i++)
			put_vec(b, p->points[i]);
		break;
	}
	case PRIM_INSTANCE:
		proto_put_u32(b, o->u.instance.define);
		break;
	default:
		break;
	}
}

int proto_scene_encode(const struct scene *s, uint8_t **out, size_t *len)
{
	struct proto_wbuf b = { 0 };
	proto_put_u32(&b, PROTO_SCENE_MAGIC);
	proto_put_u32(&b, PROTO_SCENE_VERSION);

	const struct scene_camera *c = &s->camera;
	put_bool(&b, c->set);
	put_loc(&b, &c->loc);
	put_vec(&b, c->look_at);
	put_vec(&b, c->drop_line);
	put_vec(&b, c->look_from);
	proto_put_f64(&b, c->depth);
	proto_put_f64(&b, c->x_size);
	proto_put_f64(&b, c->y_size);
	proto_put_u32(&b, (uint32_t)c->n_filters);
	for (int i = 0; i < c->n_filters; i++)
		put_filter(&b, &c->filters[i]);

	const struct scene_image *im = &s->image;
	put_bool(&b, im->set);
	put_loc(&b, &im->loc);
	put_i32(&b, im->xsize);
	put_i32(&b, im->ysize);
	put_bool(&b, im->no_shadows);
	put_bool(&b, im->no_reflections);
	put_bool(&b, im->nonstop);
	put_i32(&b, im->intersect_buffer);

	proto_put_u32(&b, s->n_materials);
	for (uint32_t i = 0; i < s->n_materials; i++)
		put_material(&b, &s->materials[i]);
	proto_put_u32(&b, s->n_meshes);
	for (uint32_t i = 0; i < s->n_meshes; i++)
		put_mesh(&b, &s->meshes[i]);
	proto_put_u32(&b, s->n_lights);
	for (uint32_t i = 0; i < s->n_lights; i++)
		put_light(&b, &s->lights[i]);
	proto_put_u32(&b, s->n_objects);
	for (uint32_t i = 0; i < s->n_objects; i++)
	{
		struct scene_object tmp;
		put_object(&b, scene_object(s, i, &tmp));
	}
	proto_put_u32(&b, s->n_defines);
	for (uint32_t i = 0; i < s->n_defines; i++) {
		const struct scene_define *d = &s->defines[i];
		proto_put_str(&b, d->name);
		put_loc(&b, &d->loc);
		proto_put_u32(&b, d->n_objects);
		for (uint32_t k = 0; k < d->n_objects; k++)
			proto_put_u32(&b, d->objects[k]);
	}
	/* roots as runs of consecutive indices, each as long as it goes (a
	 * million instances written one after another are one run) */
	uint32_t n_runs = 0;
	for (uint32_t i = 0; i < s->n_roots; i++)
		n_runs += i == 0 || s->roots[i] != s->roots[i - 1] + 1;
	proto_put_u32(&b, n_runs);
	for (uint32_t i = 0; i < s->n_roots;) {
		uint32_t j = i + 1;
		while (j < s->n_roots && s->roots[j] == s->roots[j - 1] + 1)
			j++;
		proto_put_u32(&b, s->roots[i]);
		proto_put_u32(&b, j - i);
		i = j;
	}

	if (b.oom) {
		proto_wbuf_free(&b);
		*out = NULL;
		*len = 0;
		return -1;
	}
	*out = b.p;
	*len = b.len;
	return 0;
}

/* ---- decoder -------------------------------------------------------------- */

/* Decoder state: the reader, the scene under construction, the placeholder file. */
struct dec {
	struct proto_rbuf r;
	struct scene *s;
	const char *file;
	const char *why; /* first problem found (static text) */
};

static void bad(struct dec *d, const char *why)
{
	if (!d->why)
		d->why = why;
	d->r.err = 1;
}

static int get_i32(struct dec *d)
{
	uint32_t u = proto_get_u32(&d->r);
	return u <= INT32_MAX ? (int)u : (int)(-(int64_t)(~u) - 1);
}

static bool get_bool(struct dec *d)
{
	uint8_t v = proto_get_u8(&d->r);
	if (v > 1)
		bad(d, "a boolean is neither 0 nor 1");
	return v == 1;
}

static vec3 get_vec(struct dec *d)
{
	vec3 v;
	v.x = proto_get_f64(&d->r);
	v.y = proto_get_f64(&d->r);
	v.z = proto_get_f64(&d->r);
	return v;
}

static void get_loc(struct dec *d, struct src_loc *l)
{
	l->file = d->file;
	l->line = get_i32(d);
	l->col = get_i32(d);
}

/* A count that announces `n` items of at least `min_bytes` each, at most `limit`. */
static uint32_t get_count(struct dec *d, uint32_t limit, size_t min_bytes, const char *what)
{
	uint32_t n = proto_get_u32(&d->r);
	if (d->r.err)
		return 0;
	if (n > limit || (uint64_t)n * min_bytes > proto_rbuf_left(&d->r)) {
		bad(d, what);
		return 0;
	}
	return n;
}

/* A string of at most max bytes with no NUL inside; new heap copy (caller owns), NULL on error. */
static char *get_str(struct dec *d, size_t max)
{
	uint32_t n = proto_get_u32(&d->r);
	if (d->r.err)
		return NULL;
	if (n > max) {
		bad(d, "a name is too long");
		return NULL;
	}
	const uint8_t *p = proto_get_span(&d->r, n);
	if (!p)
		return NULL;
	if (memchr(p, 0, n)) {
		bad(d, "a name holds a NUL byte");
		return NULL;
	}
	char *s = malloc((size_t)n + 1);
	if (!s) {
		bad(d, "out of memory");
		return NULL;
	}
	memcpy(s, p, n);
	s[n] = 0;
	return s;
}

static void get_filter(struct dec *d, struct scene_filter *f)
{
	uint32_t kind = proto_get_u32(&d->r);
	if (kind > FILTER_LENS)
		bad(d, "unknown filter kind");
	scene_filter_defaults(f, d->r.err ? FILTER_STANDARD : (enum filter_kind)kind);
	f->threshold = proto_get_f64(&d->r);
	f->max_depth = get_i32(d);
	f->cache_size = get_i32(d);
	f->relax = proto_get_f64(&d->r);
	f->x_samples = get_i32(d);
	f->y_samples = get_i32(d);
	f->radius = proto_get_f64(&d->r);
	f->samples = get_i32(d);
	f->focal_length = proto_get_f64(&d->r);
	get_loc(d, &f->loc);
}

static void get_sphere(struct dec *d, struct prim_sphere *p)
{
	p->centre = get_vec(d);
	p->radius = proto_get_f64(&d->r);
	p->pole = get_vec(d);
	p->equator = get_vec(d);
}

static void get_cylinder(struct dec *d, struct prim_cylinder *p)
{
	p->from = get_vec(d);
	p->to = get_vec(d);
	p->radius = proto_get_f64(&d->r);
	p->capped = get_bool(d);
}

static int dec_material(struct dec *d, struct scene_error *err)
{
	struct scene_material m;
	scene_material_defaults(&m);
	if (get_bool(d))
		m.name = get_str(d, LIM_TOKEN_LEN);
	m.diff_colour = get_vec(d);
	m.spec_colour = get_vec(d);
	m.tran_colour = get_vec(d);
	m.diffuse = proto_get_f64(&d->r);
	m.specular = proto_get_f64(&d->r);
	m.spec_power = proto_get_f64(&d->r);
	m.reflection = proto_get_f64(&d->r);
	m.transparency = proto_get_f64(&d->r);
	m.ior = proto_get_f64(&d->r);
	get_loc(d, &m.loc);
	uint32_t kind = proto_get_u32(&d->r);
	if (kind > SHADER_TURB3D)
		bad(d, "unknown shader kind");
	if (!d->r.err && kind != SHADER_NONE) {
		struct scene_shader *sh = &m.shader;
		scene_shader_defaults(sh, (enum shader_kind)kind);
		sh->size = proto_get_f64(&d->r);
		sh->mat_a = proto_get_u32(&d->r);
		sh->mat_b = proto_get_u32(&d->r);
		sh->tile_width = proto_get_f64(&d->r);
		sh->grout_width = proto_get_f64(&d->r);
		sh->terms = get_i32(d);
		sh->axis_size = get_vec(d);
		sh->saturation = proto_get_f64(&d->r);
		sh->depth = proto_get_f64(&d->r);
		sh->variance = proto_get_f64(&d->r);
		sh->colour = get_vec(d);
		sh->axis = get_vec(d);
		sh->fades_materials = get_bool(d);
		uint32_t n = get_count(d, LIM_FADES_ENTRIES, 36, "too many fades entries");
		if (n && !d->r.err) {
			sh->fades = calloc(n, sizeof *sh->fades);
			if (!sh->fades)
				bad(d, "out of memory");
			else
				sh->n_fades = n;
		}
		for (uint32_t i = 0; i < sh->n_fades; i++) {
			sh->fades[i].dist = proto_get_f64(&d->r);
			sh->fades[i].colour = get_vec(d);
			sh->fades[i].material = proto_get_u32(&d->r);
		}
	}
	if (d->r.err) {
		free(m.name);
		free(m.shader.fades);
		return 1;
	}
	return scene_add_material(d->s, &m, NULL, err);
}

static int dec_mesh(struct dec *d, struct scene_error *err)
{
	struct scene_mesh m;
	memset(&m, 0, sizeof m);
	m.file = get_str(d, LIM_PATH_LEN);
	uint32_t nv = proto_get_u32(&d->r);
	uint32_t nt = proto_get_u32(&d->r);
	bool has_normals = get_bool(d);
	m.smooth = get_bool(d);
	m.weld = proto_get_f64(&d->r);
	m.rotation = get_vec(d);
	m.at = get_vec(d);
	uint64_t need = (uint64_t)nv * (has_normals ? 48 : 24) + (uint64_t)nt * 12;
	if (!d->r.err && (nt > LIM_MESH_TRIANGLES || nv > 3ull * LIM_MESH_TRIANGLES || need > proto_rbuf_left(&d->r)))
		bad(d, "a mesh is larger than the limits or than the data");
	if (!d->r.err) {
		m.vertices = malloc((size_t)nv * sizeof *m.vertices + 1);
		m.normals = has_normals ? malloc((size_t)nv * sizeof *m.normals + 1) : NULL;
		m.tris = malloc((size_t)nt * 3 * sizeof *m.tris + 1);
		if (!m.vertices || !m.tris || (has_normals && !m.normals))
			bad(d, "out of memory");
	}
	if (!d->r.err) {
		m.n_vertices = nv;
		m.n_triangles = nt;
		for (uint32_t i = 0; i < nv; i++)
			m.vertices[i] = get_vec(d);
		for (uint32_t i = 0; has_normals && i < nv; i++)
			m.normals[i] = get_vec(d);
		for (uint64_t i = 0; i < 3ull * nt; i++)
			m.tris[i] = proto_get_u32(&d->r);
	}
	if (d->r.err) {
		free(m.file);
		free(m.vertices);
		free(m.normals);
		free(m.tris);
		return 1;
	}
	return scene_add_mesh(d->s, &m, NULL, err);
}

static int dec_light(struct dec *d, struct scene_error *err)
{
	struct scene_light l;
	scene_light_defaults(&l);
	l.colour = get_vec(d);
	l.position = get_vec(d);
	uint32_t shape = proto_get_u32(&d->r);
	if (shape > LIGHT_BOX)
		bad(d, "unknown light shape");
	l.shape = d->r.err ? LIGHT_POINT : (enum light_shape)shape;
	get_sphere(d, &l.sphere);
	get_cylinder(d, &l.cylinder);
	l.box.a = get_vec(d);
	l.box.b = get_vec(d);
	l.samples = get_i32(d);
	l.fall_off = proto_get_f64(&d->r);
	l.no_shadows = get_bool(d);
	get_loc(d, &l.loc);
	if (d->r.err)
		return 1;
	return scene_add_light(d->s, &l, err);
}

/* Adds defines until define index `upto` exists (upto = UINT32_MAX: all of them). */
static int flush_defines(struct dec *d, struct scene_define *defs, uint32_t n_defs, uint32_t upto,
			 struct scene_error *err)
{
	while (d->s->n_defines < n_defs && (upto == UINT32_MAX || d->s->n_defines <= upto)) {
		struct scene_define *df = &defs[d->s->n_defines];
		int rc = scene_add_define(d->s, df, NULL, err);
		if (rc)
			return rc;
	}
	return 0;
}

static int dec_object(struct dec *d, struct scene_object *o)
{
	uint32_t kind = proto_get_u8(&d->r);
	memset(o, 0, sizeof *o);
	if (d->r.err || kind >= PRIM_KIND_COUNT) {
		bad(d, "unknown object kind");
		return 1;
	}
	scene_object_defaults(o, (enum prim_kind)kind);
	uint8_t form = proto_get_u8(&d->r);
	o->has_xform = form != XF_FORM_NONE;
	if (form == XF_FORM_TRANSLATE) {
		for (int i = 0; i < 3; i++)
			o->xform.m[i][3] = proto_get_f64(&d->r);
	} else if (form == XF_FORM_FULL) {
		for (int i = 0; i < 3; i++)
			for (int j = 0; j < 4; j++)
				o->xform.m[i][j] = proto_get_f64(&d->r);
		if (lin_is_identity(&o->xform)) /* canonical: that one travels as a translation */
			bad(d, "a full transform whose 3x3 part is the identity");
	} else if (form != XF_FORM_NONE) {
		bad(d, "unknown transform form");
	}
	o->material = proto_get_u32(&d->r);
	get_loc(d, &o->loc);
	switch (o->kind) {
	case PRIM_SPHERE:
		get_sphere(d, &o->u.sphere);
		break;
	case PRIM_PLANE:
	case PRIM_DISK:
		o->u.plane.position = get_vec(d);
		o->u.plane.normal = get_vec(d);
		o->u.plane.x_axis = get_vec(d);
		o->u.plane.y_axis = get_vec(d);
		o->u.plane.has_axes = get_bool(d);
		o->u.plane.radius = proto_get_f64(&d->r);
		break;
	case PRIM_CYLINDER:
		get_cylinder(d, &o->u.cylinder);
		break;
	case PRIM_BOX:
		o->u.box.a = get_vec(d);
		o->u.box.b = get_vec(d);
		break;
	case PRIM_TRIANGLE:
		o->u.triangle.a = get_vec(d);
		o->u.triangle.b = get_vec(d);
		o->u.triangle.c = get_vec(d);
		o->u.triangle.has_normals = get_bool(d);
		if (o->u.triangle.has_normals) {
			o->u.triangle.na = get_vec(d);
			o->u.triangle.nb = get_vec(d);
			o->u.triangle.nc = get_vec(d);
		}
		break;
	case PRIM_RAW:
		o->u.raw.mesh = proto_get_u32(&d->r);
		break;
	case PRIM_CSG: {
		uint32_t op = proto_get_u32(&d->r);
		if (op > CSG_SUBTRACT)
			bad(d, "unknown CSG operation");
		o->u.csg.op = d->r.err ? CSG_UNION : (enum csg_op)op;
		o->u.csg.operand1 = proto_get_u32(&d->r);
		o->u.csg.operand2 = proto_get_u32(&d->r);
		break;
	}
	case PRIM_POLYGON: {
		struct prim_polygon *p = &o->u.polygon;
		uint32_t nc = proto_get_u32(&d->r), np = proto_get_u32(&d->r);
		if (d->r.err)
			return 1;
		if (nc < 1 || nc > LIM_POLY_CONTOURS || np > LIM_POLY_VERTICES ||
		    ((uint64_t)nc + 1) * 4 + (uint64_t)np * 24 > proto_rbuf_left(&d->r)) {
			bad(d, "a polygon is larger than the limits or than the data");
			return 1;
		}
		p->contour_start = malloc(((size_t)nc + 1) * sizeof *p->contour_start);
		p->points = malloc((size_t)np * sizeof *p->points + 1);
		if (!p->contour_start || !p->points) {
			free(p->contour_start);
			free(p->points);
			p->contour_start = NULL;
			p->points = NULL;
			bad(d, "out of memory");
			return 1;
		}
		p->n_contours = nc;
		p->n_points = np;
		for (uint32_t i = 0; i <= nc; i++)
			p->contour_start[i] = proto_get_u32(&d->r);
		for (uint32_t i = 0; i < np; i++)
			p->points[i] = get_vec(d);
		break;
	}
	case PRIM_INSTANCE:
		o->u.instance.define = proto_get_u32(&d->r);
		break;
	default:
		break;
	}
	return d->r.err ? 1 : 0;
}

static void free_object(struct scene_object *o)
{
	if (o->kind == PRIM_POLYGON) {
		free(o->u.polygon.contour_start);
		free(o->u.polygon.points);
		o->u.polygon.contour_start = NULL;
		o->u.polygon.points = NULL;
	}
}

/*
 * Nesting bounds the tracer's recursion: CSG and instance levels together,
 * and shader materials inside shader materials. The parser enforces the
 * individual limits; a peer's bytes are held to their sum (plus slack for
 * how the parser counts), which is what the stack has to survive.
 */
#define DEC_NEST_LIMIT (LIM_CSG_DEPTH + LIM_DEFINE_DEPTH + 2)
#define DEC_SHADER_LIMIT (LIM_SHADER_DEPTH + 1)

static int check_nesting(struct dec *d)
{
	const struct scene *s = d->s;
	int ok = 1;
	uint16_t *od = calloc((size_t)s->n_objects + 1, sizeof *od);
	uint16_t *dd = calloc((size_t)s->n_defines + 1, sizeof *dd);
	uint16_t *md = calloc((size_t)s->n_materials + 1, sizeof *md);
	if (!od || !dd || !md) {
		bad(d, "out of memory");
		ok = 0;
		goto out;
	}
	/* defines only hold objects added before them, so a define's depth is known
	 * once all objects below the first instance using it are done; compute
	 * lazily: objects in order, a define's depth from its members on first use */
	for (uint32_t i = 0; ok && i < s->n_objects; i++) {
		struct scene_object tmp;
		const struct scene_object *o = scene_object(s, i, &tmp);
		uint32_t v = 0;
		if (o->kind == PRIM_CSG) {
			uint32_t a = od[o->u.csg.operand1], b = od[o->u.csg.operand2];
			v = 1 + (a > b ? a : b);
		} else if (o->kind == PRIM_INSTANCE) {
			uint32_t k = o->u.instance.define;
			if (dd[k] == 0) {
				uint32_t m = 0;
				for (uint32_t j = 0; j < s->defines[k].n_objects; j++) {
					uint32_t mo = s->defines[k].objects[j];
					if (mo >= i) { /* members are older than any use */
						ok = 0;
						break;
					}
					if (od[mo] > m)
						m = od[mo];
				}
				dd[k] = (uint16_t)(m + 1 > DEC_NEST_LIMIT + 1 ? DEC_NEST_LIMIT + 1 : m + 1);
			}
			v = 1u + dd[k];
		}
		if (v > DEC_NEST_LIMIT)
			ok = 0;
		od[i] = (uint16_t)v;
	}
	if (!ok) {
		bad(d, "objects nest deeper than the limits");
		goto out;
	}
	for (uint32_t i = 0; ok && i < s->n_materials; i++) {
		const struct scene_shader *sh = &s->materials[i].shader;
		uint32_t v = 0;
		uint32_t refs[2] = { sh->mat_a, sh->mat_b };
		for (int k = 0; k < 2; k++)
			if (sh->kind != SHADER_NONE && refs[k] != SCENE_NONE && md[refs[k]] + 1u > v)
				v = md[refs[k]] + 1u;
		for (uint32_t k = 0; sh->fades_materials && k < sh->n_fades; k++)
			if (md[sh->fades[k].material] + 1u > v)
				v = md[sh->fades[k].material] + 1u;
		if (v > DEC_SHADER_LIMIT)
			ok = 0;
		md[i] = (uint16_t)v;
	}
	if (!ok)
		bad(d, "shader materials nest deeper than the limits");
out:
	free(od);
	free(dd);
	free(md);
	return ok;
}

int proto_scene_decode(const uint8_t *p, size_t len, struct scene **out, struct scene_error *err)
{
	struct dec d = { .r = { .p = p, .len = len } };
	struct scene_define *defs = NULL;
	uint32_t n_defs = 0, n_defs_read = 0;
	struct scene_error dummy;
	int rc = 0;
	*out = NULL;
	if (!err)
		err = &dummy;
	err->msg[0] = 0;
	if (len > LIM_SCENE_BYTES)
		return scene_errorf(err, 1, "scene data: %zu bytes is over the limit", len);
	d.s = scene_new();
	if (!d.s)
		return scene_errorf(err, 1, "scene data: out of memory");
	d.file = scene_intern_file(d.s, PROTO_SCENE_FILE);
	if (!d.file) {
		bad(&d, "out of memory");
		goto fail;
	}
	if (proto_get_u32(&d.r) != PROTO_SCENE_MAGIC) {
		bad(&d, "not a portray scene encoding (bad magic)");
		goto fail;
	}
	uint32_t version = proto_get_u32(&d.r);
	if (version != PROTO_SCENE_VERSION) {
		scene_errorf(err, 1, "scene data: encoding version %u, this build reads version %u", version,
			     PROTO_SCENE_VERSION);
		rc = 1;
		goto fail;
	}

	struct scene_camera cam;
	scene_camera_defaults(&cam);
	cam.set = get_bool(&d);
	get_loc(&d, &cam.loc);
	cam.look_at = get_vec(&d);
	cam.drop_line = get_vec(&d);
	cam.look_from = get_vec(&d);
	cam.depth = proto_get_f64(&d.r);
	cam.x_size = proto_get_f64(&d.r);
	cam.y_size = proto_get_f64(&d.r);
	cam.n_filters = (int)get_count(&d, LIM_FILTERS, 72, "too many filters");
	for (int i = 0; i < cam.n_filters; i++)
		get_filter(&d, &cam.filters[i]);
	if (d.r.err || (rc = scene_set_camera(d.s, &cam, err)) != 0)
		goto fail;

	struct scene_image im;
	scene_image_defaults(&im);
	im.set = get_bool(&d);
	get_loc(&d, &im.loc);
	im.xsize = get_i32(&d);
	im.ysize = get_i32(&d);
	im.no_shadows = get_bool(&d);
	im.no_reflections = get_bool(&d);
	im.nonstop = get_bool(&d);
	im.intersect_buffer = get_i32(&d);
	if (d.r.err || (rc = scene_set_image(d.s, &im, err)) != 0)
		goto fail;

	uint32_t n = get_count(&d, LIM_MATERIALS, 133, "too many materials");
	for (uint32_t i = 0; i < n && !d.r.err; i++)
		if ((rc = dec_material(&d, err)) != 0)
			goto fail;
	n = get_count(&d, LIM_MESHES, 70, "too many meshes");
	for (uint32_t i = 0; i < n && !d.r.err; i++)
		if ((rc = dec_mesh(&d, err)) != 0)
			goto fail;
	n = get_count(&d, LIM_LIGHTS, 250, "too many lights");
	for (uint32_t i = 0; i < n && !d.r.err; i++)
		if ((rc = dec_light(&d, err)) != 0)
			goto fail;

	/* Objects come before defines in the encoding, but the builder wants each
	 * define added after its members and before its first use: read the
	 * defines first (they follow the objects), then interleave. */
	uint32_t n_obj = get_count(&d, LIM_OBJECTS, 14, "too many objects");
	size_t obj_start = d.r.pos;
	{
		/* skip over the objects to reach the defines: decode them into a
		 * throw-away object (cheap) and discard */
		for (uint32_t i = 0; i < n_obj && !d.r.err; i++) {
			struct scene_object o;
			dec_object(&d, &o);
			free_object(&o);
		}
	}
	n_defs = get_count(&d, LIM_DEFINES, 16, "too many definitions");
	if (n_defs && !d.r.err) {
		defs = calloc(n_defs, sizeof *defs);
		if (!defs)
			bad(&d, "out of memory");
	}
	for (uint32_t i = 0; i < n_defs && !d.r.err; i++) {
		struct scene_define *df = &defs[i];
		n_defs_read = i + 1;
		df->name = get_str(&d, LIM_TOKEN_LEN);
		get_loc(&d, &df->loc);
		uint32_t k = get_count(&d, LIM_OBJECTS, 4, "a definition is larger than the data");
		if (d.r.err)
			break;
		df->objects = malloc((size_t)k * sizeof *df->objects + 1);
		if (!df->objects) {
			bad(&d, "out of memory");
			break;
		}
		df->n_objects = k;
		for (uint32_t j = 0; j < k; j++)
			df->objects[j] = proto_get_u32(&d.r);
	}
	size_t roots_start = d.r.pos;
	if (d.r.err)
		goto fail;

	/* now the objects for real, adding defines just in time */
	d.r.pos = obj_start;
	for (uint32_t i = 0; i < n_obj; i++) {
		struct scene_object o;
		if (dec_object(&d, &o)) {
			free_object(&o);
			goto fail;
		}
		if (o.kind == PRIM_INSTANCE && o.u.instance.define < n_defs &&
		    (rc = flush_defines(&d, defs, n_defs, o.u.instance.define, err)) != 0) {
			free_object(&o);
			goto fail;
		}
		if ((rc = scene_add_object(d.s, &o, NULL, err)) != 0)
			goto fail;
	}
	if ((rc = flush_defines(&d, defs, n_defs, UINT32_MAX, err)) != 0)
		goto fail;
	d.r.pos = roots_start;

	n = get_count(&d, LIM_OBJECTS, 8, "too many roots");
	uint64_t n_roots = 0, run_end = UINT64_MAX;
	for (uint32_t i = 0; i < n && !d.r.err; i++) {
		uint32_t first = proto_get_u32(&d.r), cnt = proto_get_u32(&d.r);
		if (d.r.err)
			break;
		n_roots += cnt;
		/* canonical: runs are not empty and as long as they go */
		if (cnt == 0 || first == run_end || (uint64_t)first + cnt > d.s->n_objects || n_roots > LIM_OBJECTS) {
			bad(&d, "a bad run of roots");
			break;
		}
		run_end = (uint64_t)first + cnt;
		for (uint32_t k = 0; k < cnt; k++)
			if ((rc = scene_add_root(d.s, first + k, err)) != 0)
				goto fail;
	}
	if (d.r.err)
		goto fail;
	if (d.r.pos != d.r.len) {
		bad(&d, "trailing bytes after the scene");
		goto fail;
	}
	if (!check_nesting(&d))
		goto fail;
	for (uint32_t i = 0; i < n_defs_read; i++) {
		free(defs[i].name);
		free(defs[i].objects);
	}
	free(defs);
	*out = d.s;
	return 0;

fail:
	if (rc && err->msg[0] && strncmp(err->msg, "scene data:", 11) != 0) {
		char tmp[sizeof err->msg];
		snprintf(tmp, sizeof tmp, "%s", err->msg);
		scene_errorf(err, 1, "scene data: %s", tmp);
	} else if (!rc || !err->msg[0]) {
		scene_errorf(err, 1, "scene data: %s at byte %zu",
			     d.why ? d.why : "truncated", d.r.pos < len ? d.r.pos : len);
	}
	for (uint32_t i = 0; i < n_defs_read; i++) {
		free(defs[i].name);
		free(defs[i].objects);
	}
	free(defs);
	scene_free(d.s);
	return 1;
}
