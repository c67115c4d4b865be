/*
 * scene.c - the scene model's defaults, builder and lookups.
 */
#include "common/scene.h"

#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "common/xmath.h"

int scene_errorf(struct scene_error *err, int level, const char *fmt, ...)
{
	if (err) {
		va_list ap;
		va_start(ap, fmt);
		vsnprintf(err->msg, sizeof err->msg, fmt, ap);
		va_end(ap);
		err->level = level;
	}
	return level;
}

/* ---- defaults ------------------------------------------------------------ */

void scene_filter_defaults(struct scene_filter *f, enum filter_kind kind)
{
	memset(f, 0, sizeof *f);
	f->kind = kind;
	f->threshold = 0.2;
	f->max_depth = 3;
	f->cache_size = 1000;
	f->relax = 1.2;
	f->x_samples = 2;
	f->y_samples = 2;
	f->radius = kind == FILTER_LENS ? 0.1 : 0.707;
	f->samples = 4;
	f->focal_length = 1000.0;
}

void scene_camera_defaults(struct scene_camera *c)
{
	memset(c, 0, sizeof *c);
	c->look_at = v3(0, 0, 0);
	c->drop_line = v3(0, -1, 0);
	c->look_from = v3(0, 0, 10);
	c->depth = 0.028;
	c->x_size = 0.032;
	c->y_size = 0.024;
	scene_filter_defaults(&c->filters[0], FILTER_STANDARD);
	c->n_filters = 1;
}

void scene_image_defaults(struct scene_image *im)
{
	memset(im, 0, sizeof *im);
	im->xsize = 320;
	im->ysize = 240;
	im->intersect_buffer = 1000;
}

void scene_light_defaults(struct scene_light *l)
{
	memset(l, 0, sizeof *l);
	l->colour = v3(1, 1, 1);
	l->shape = LIGHT_POINT;
	l->sphere.radius = 1;
	l->sphere.pole = v3(0, 1, 0);
	l->sphere.equator = v3(1, 0, 0);
	l->cylinder.to = v3(0, 1, 0);
	l->cylinder.radius = 1;
	l->box.b = v3(1, 1, 1);
	l->samples = 1;
	l->fall_off = 0;
}

void scene_shader_defaults(struct scene_shader *s, enum shader_kind kind)
{
	memset(s, 0, sizeof *s);
	s->kind = kind;
	s->size = 1.0;
	s->mat_a = SCENE_NONE;
	s->mat_b = SCENE_NONE;
	s->tile_width = 8;
	s->grout_width = 1;
	s->terms = 4;
	s->axis_size = v3(1, 1, 1);
	s->saturation = 3.1416;
	s->depth = kind == SHADER_TURB3D ? 1.0 : 0.2;
	s->variance = 0.5;
	s->colour = v3(0.5, 0.5, 0.5);
	s->axis = v3(0, 1, 0);
}

void scene_material_defaults(struct scene_material *m)
{
	memset(m, 0, sizeof *m);
	m->diff_colour = v3(1, 1, 1);
	m->spec_colour = v3(1, 1, 1);
	m->tran_colour = v3(1, 1, 1);
	m->diffuse = 1.0;
	m->specular = 0.0;
	m->spec_power = 20.0;
	m->reflection = 0.0;
	m->transparency = 0.0;
	m->ior = 1.0;
	scene_shader_defaults(&m->shader, SHADER_NONE);
}

static struct scene_material default_material;
static pthread_once_t default_material_once = PTHREAD_ONCE_INIT;

static void default_material_init(void) { scene_material_defaults(&default_material); }

/* Render threads call this at once: pthread_once, not an unsynchronised
 * "initialised" flag (a data race, even if every thread wrote the same bytes). */
const struct scene_material *scene_default_material(void)
{
	pthread_once(&default_material_once, default_material_init);
	return &default_material;
}

void scene_object_defaults(struct scene_object *o, enum prim_kind kind)
{
	memset(o, 0, sizeof *o);
	o->kind = kind;
	o->xform = m34_identity();
	o->material = SCENE_NONE;
	switch (kind) {
	case PRIM_SPHERE:
		o->u.sphere.radius = 1;
		o->u.sphere.pole = v3(0, 1, 0);
		o->u.sphere.equator = v3(1, 0, 0);
		break;
	case PRIM_PLANE:
	case PRIM_DISK:
		o->u.plane.normal = v3(0, 1, 0);
		o->u.plane.radius = 1;
		break;
	case PRIM_CYLINDER:
		o->u.cylinder.to = v3(0, 1, 0);
		o->u.cylinder.radius = 1;
		break;
	case PRIM_BOX:
		o->u.box.b = v3(1, 1, 1);
		break;
	case PRIM_TRIANGLE:
		o->u.triangle.b = v3(1, 0, 0);
		o->u.triangle.c = v3(0, 1, 0);
		break;
	case PRIM_CSG:
		o->u.csg.operand1 = SCENE_NONE;
		o->u.csg.operand2 = SCENE_NONE;
		break;
	case PRIM_RAW:
		o->u.raw.mesh = SCENE_NONE;
		break;
	case PRIM_INSTANCE:
		o->u.instance.define = SCENE_NONE;
		break;
	default:
		break;
	}
}

/* ---- lifetime -------------------------------------------------------------- */

struct scene *scene_new(void)
{
	struct scene *s = calloc(1, sizeof *s);
	if (!s)
		return NULL;
	scene_camera_defaults(&s->camera);
	scene_image_defaults(&s->image);
	return s;
}

static void object_free_owned(struct scene_object *o)
{
	if (o->kind == PRIM_POLYGON) {
		free(o->u.polygon.contour_start);
		free(o->u.polygon.points);
		o->u.polygon.contour_start = NULL;
		o->u.polygon.points = NULL;
	}
}

static void mesh_free_owned(struct scene_mesh *m)
{
	free(m->file);
	free(m->vertices);
	free(m->normals);
	free(m->tris);
	memset(m, 0, sizeof *m);
}

void scene_free(struct scene *s)
{
	if (!s)
		return;
	for (uint32_t i = 0; i < s->n_materials; i++) {
		free(s->materials[i].name);
		free(s->materials[i].shader.fades);
	}
	for (uint32_t i = 0; i < s->n_meshes; i++)
		mesh_free_owned(&s->meshes[i]);
	for (uint32_t i = 0; i < s->n_objs; i++)
		object_free_owned(&s->objs[i]);
	for (uint32_t i = 0; i < s->n_defines; i++) {
		free(s->defines[i].name);
		free(s->defines[i].objects);
	}
	for (uint32_t i = 0; i < s->n_files; i++)
		free(s->files[i]);
	free(s->lights);
	free(s->materials);
	free(s->meshes);
	free(s->inst_bits);
	free(s->inst_rank);
	free(s->objs);
	free(s->insts);
	free(s->lins);
	free(s->defines);
	free(s->roots);
	free(s->files);
	free(s);
}

/*
 * Grows *arr (elements of size elem) so that one more fits below limit.
 * Returns 0 on success, -1 when the limit is reached or memory runs out.
 */
static int grow(void **arr, uint32_t n, uint32_t *cap, size_t elem, uint32_t limit)
{
	if (n < *cap)
		return 0;
	if (n >= limit)
		return -1;
	uint64_t nc = *cap ? (uint64_t)*cap * 2 : 16;
	if (nc > limit)
		nc = limit;
	void *p = realloc(*arr, (size_t)nc * elem);
	if (!p)
		return -1;
	*arr = p;
	*cap = (uint32_t)nc;
	return 0;
}

const char *scene_intern_file(struct scene *s, const char *name)
{
	for (uint32_t i = 0; i < s->n_files; i++)
		if (strcmp(s->files[i], name) == 0)
			return s->files[i];
	if (grow((void **)&s->files, s->n_files, &s->cap_files, sizeof *s->files, 1u << 20) < 0)
		return NULL;
	char *dup = strdup(name);
	if (!dup)
		return NULL;
	s->files[s->n_files++] = dup;
	return dup;
}

/* ---- validation helpers -------------------------------------------------------- */

static const char *loc_file(const struct src_loc *l) { return l->file ? l->file : "<scene>"; }

#define LOCFMT "%s:%d:%d: error: "
#define LOCARGS(l) loc_file(l), (l)->line, (l)->col

static int finite_pos(double v) { return isfinite(v) && v > 0; }
static int finite_nonneg(double v) { return isfinite(v) && v >= 0; }

static int check_filter(const struct scene_filter *f, struct scene_error *err)
{
	if (!(finite_pos(f->threshold) && f->max_depth >= 0 && f->max_depth <= LIM_ADAPTIVE_DEPTH &&
	      f->cache_size >= 0 && finite_pos(f->relax) && f->x_samples >= 1 &&
	      f->x_samples <= LIM_SAMPLES && f->y_samples >= 1 && f->y_samples <= LIM_SAMPLES &&
	      finite_nonneg(f->radius) && f->samples >= 1 && f->samples <= LIM_SAMPLES &&
	      finite_pos(f->focal_length) && (int)f->kind >= 0 && f->kind <= FILTER_LENS))
		return scene_errorf(err, ERRLEVEL_FATAL, LOCFMT "filter %s has a value out of range",
				    LOCARGS(&f->loc), scene_filter_name(f->kind));
	return 0;
}

int scene_set_camera(struct scene *s, const struct scene_camera *c, struct scene_error *err)
{
	if (!v3_finite(c->look_at) || !v3_finite(c->look_from) || !v3_finite(c->drop_line))
		return scene_errorf(err, 1, LOCFMT "camera vectors must be finite", LOCARGS(&c->loc));
	if (!finite_pos(c->depth) || !finite_pos(c->x_size) || !finite_pos(c->y_size))
		return scene_errorf(err, 1, LOCFMT "camera depth, x-size and y-size must be positive",
				    LOCARGS(&c->loc));
	vec3 view = v3_sub(c->look_at, c->look_from);
	if (!isfinite(v3_len(view)) || !isfinite(v3_len(c->drop_line)))
		return scene_errorf(err, 1, LOCFMT "camera vectors too large (look-at - look-from or drop-line "
					     "has no finite length)", LOCARGS(&c->loc));
	if (v3_len(view) == 0)
		return scene_errorf(err, 1, LOCFMT "camera look-at equals look-from", LOCARGS(&c->loc));
	if (v3_len(v3_cross(view, c->drop_line)) <= 1e-12 * v3_len(view) * v3_len(c->drop_line))
		return scene_errorf(err, 1, LOCFMT "camera drop-line is zero or parallel to the view direction",
				    LOCARGS(&c->loc));
	if (c->n_filters < 0 || c->n_filters > LIM_FILTERS)
		return scene_errorf(err, 1, LOCFMT "too many filters", LOCARGS(&c->loc));
	uint64_t rays = 1; /* every multiplying filter counted, ignored ones too */
	for (int i = 0; i < c->n_filters; i++) {
		const struct scene_filter *f = &c->filters[i];
		if (check_filter(f, err))
			return err->level;
		if (f->kind == FILTER_SUPERSAMPLE)
			rays *= (uint64_t)f->x_samples * (uint64_t)f->y_samples;
		else if (f->kind == FILTER_DISK || f->kind == FILTER_LENS)
			rays *= (uint64_t)f->samples;
		if (rays > LIM_RAYS_PER_SAMPLE)
			return scene_errorf(err, 1, LOCFMT "filter %s: the filters so far trace %llu rays per "
						     "sample (at most %u)",
					    LOCARGS(&f->loc), scene_filter_name(f->kind), (unsigned long long)rays,
					    LIM_RAYS_PER_SAMPLE);
	}
	s->camera = *c;
	return 0;
}

int scene_set_image(struct scene *s, const struct scene_image *im, struct scene_error *err)
{
	if (im->xsize < 1 || im->ysize < 1 || im->xsize > LIM_IMAGE_SIDE || im->ysize > LIM_IMAGE_SIDE ||
	    (uint64_t)im->xsize * (uint64_t)im->ysize > LIM_IMAGE_PIXELS)
		return scene_errorf(err, 1, LOCFMT "image size %dx%d out of range (1..%d per side, at most %llu pixels)",
				    LOCARGS(&im->loc), im->xsize, im->ysize, LIM_IMAGE_SIDE,
				    (unsigned long long)LIM_IMAGE_PIXELS);
	if (im->intersect_buffer < 0)
		return scene_errorf(err, 1, LOCFMT "intersect-buffer must not be negative", LOCARGS(&im->loc));
	s->image = *im;
	return 0;
}

static int check_sphere(const struct prim_sphere *p)
{
	return v3_finite(p->centre) && finite_pos(p->radius) && v3_finite(p->pole) &&
	       v3_finite(p->equator) && v3_len(p->pole) > 0;
}

static int check_cylinder(const struct prim_cylinder *p)
{
	return v3_finite(p->from) && v3_finite(p->to) && finite_pos(p->radius) &&
	       v3_len(v3_sub(p->to, p->from)) > 0;
}

static int check_box(const struct prim_box *p) { return v3_finite(p->a) && v3_finite(p->b); }

int scene_add_light(struct scene *s, const struct scene_light *l, struct scene_error *err)
{
	int ok = v3_finite(l->colour) && v3_finite(l->position) && finite_nonneg(l->fall_off) &&
		 l->samples >= 1 && l->samples <= LIM_SAMPLES && (int)l->shape >= 0 && l->shape <= LIGHT_BOX;
	if (ok && l->shape == LIGHT_SPHERE)
		ok = check_sphere(&l->sphere);
	if (ok && l->shape == LIGHT_CYLINDER)
		ok = check_cylinder(&l->cylinder);
	if (ok && l->shape == LIGHT_BOX)
		ok = check_box(&l->box);
	if (!ok)
		return scene_errorf(err, 1, LOCFMT "light has a value out of range", LOCARGS(&l->loc));
	if (grow((void **)&s->lights, s->n_lights, &s->cap_lights, sizeof *s->lights, LIM_LIGHTS) < 0)
		return scene_errorf(err, 1, LOCFMT "too many lights or out of memory", LOCARGS(&l->loc));
	s->lights[s->n_lights++] = *l;
	return 0;
}

static int check_mat_ref(uint32_t ref, uint32_t self, int may_be_none)
{
	if (ref == SCENE_NONE)
		return may_be_none;
	return ref < self;
}

static int check_shader(const struct scene_shader *sh, uint32_t self)
{
	if ((int)sh->kind < 0 || sh->kind > SHADER_TURB3D)
		return 0;
	if (sh->kind == SHADER_NONE)
		return sh->n_fades == 0;
	if (!finite_pos(sh->size) || !check_mat_ref(sh->mat_a, self, 1) || !check_mat_ref(sh->mat_b, self, 1))
		return 0;
	if (!finite_nonneg(sh->tile_width) || !finite_nonneg(sh->grout_width) || sh->terms < 0 ||
	    sh->terms > LIM_TERMS || !v3_finite(sh->axis_size) || !finite_nonneg(sh->saturation) ||
	    !isfinite(sh->depth) || !isfinite(sh->variance) || !v3_finite(sh->colour) || !v3_finite(sh->axis))
		return 0;
	if (sh->axis_size.x <= 0 || sh->axis_size.y <= 0 || sh->axis_size.z <= 0)
		return 0;
	if (sh->kind == SHADER_FADES && v3_len(sh->axis) == 0)
		return 0;
	if (sh->n_fades > LIM_FADES_ENTRIES || (sh->n_fades && !sh->fades))
		return 0;
	for (uint32_t i = 0; i < sh->n_fades; i++) {
		const struct fades_entry *e = &sh->fades[i];
		if (!finite_nonneg(e->dist) || !v3_finite(e->colour))
			return 0;
		if (sh->fades_materials ? !check_mat_ref(e->material, self, 0) : e->material != SCENE_NONE)
			return 0;
	}
	return 1;
}

int scene_add_material(struct scene *s, struct scene_material *m, uint32_t *id, struct scene_error *err)
{
	uint32_t self = s->n_materials;
	int ok = v3_finite(m->diff_colour) && v3_finite(m->spec_colour) && v3_finite(m->tran_colour) &&
		 isfinite(m->diffuse) && isfinite(m->specular) && finite_nonneg(m->spec_power) &&
		 isfinite(m->reflection) && isfinite(m->transparency) && finite_pos(m->ior) &&
		 check_shader(&m->shader, self);
	if (!ok) {
		scene_errorf(err, 1, LOCFMT "material has a value out of range", LOCARGS(&m->loc));
		goto fail;
	}
	if (grow((void **)&s->materials, s->n_materials, &s->cap_materials, sizeof *s->materials,
		 LIM_MATERIALS) < 0) {
		scene_errorf(err, 1, LOCFMT "too many materials or out of memory", LOCARGS(&m->loc));
		goto fail;
	}
	s->materials[s->n_materials++] = *m;
	if (id)
		*id = self;
	return 0;
fail:
	free(m->name);
	free(m->shader.fades);
	m->name = NULL;
	m->shader.fades = NULL;
	return err ? err->level : 1;
}

int scene_add_mesh(struct scene *s, struct scene_mesh *mesh, uint32_t *id, struct scene_error *err)
{
	int ok = mesh->n_triangles <= LIM_MESH_TRIANGLES && (mesh->n_vertices == 0 || mesh->vertices) &&
		 (mesh->n_triangles == 0 || mesh->tris) && isfinite(mesh->weld) && mesh->weld >= 0 &&
		 v3_finite(mesh->rotation) && v3_finite(mesh->at);
	for (uint64_t i = 0; ok && i < 3ull * mesh->n_triangles; i++)
		ok = mesh->tris[i] < mesh->n_vertices;
	for (uint32_t i = 0; ok && i < mesh->n_vertices; i++)
		ok = v3_finite(mesh->vertices[i]) && (!mesh->normals || v3_finite(mesh->normals[i]));
	if (!ok) {
		scene_errorf(err, 1, "%s: error: invalid mesh data", mesh->file ? mesh->file : "<mesh>");
		goto fail;
	}
	if (grow((void **)&s->meshes, s->n_meshes, &s->cap_meshes, sizeof *s->meshes, LIM_MESHES) < 0) {
		scene_errorf(err, 1, "%s: error: too many meshes or out of memory",
			     mesh->file ? mesh->file : "<mesh>");
		goto fail;
	}
	if (id)
		*id = s->n_meshes;
	s->meshes[s->n_meshes++] = *mesh;
	memset(mesh, 0, sizeof *mesh);
	return 0;
fail:
	mesh_free_owned(mesh);
	return err ? err->level : 1;
}

static int check_xform(const struct scene_object *o)
{
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 4; j++)
			if (!isfinite(o->xform.m[i][j]))
				return 0;
	mat34 inv;
	return m34_invert(&o->xform, &inv);
}

static int check_polygon(const struct prim_polygon *p)
{
	if (p->n_contours < 1 || p->n_contours > LIM_POLY_CONTOURS || p->n_points > LIM_POLY_VERTICES ||
	    !p->contour_start || !p->points)
		return 0;
	if (p->contour_start[0] != 0 || p->contour_start[p->n_contours] != p->n_points)
		return 0;
	for (uint32_t i = 0; i < p->n_contours; i++)
		if (p->contour_start[i + 1] < p->contour_start[i] + 3)
			return 0;
	for (uint32_t i = 0; i < p->n_points; i++)
		if (!v3_finite(p->points[i]))
			return 0;
	return 1;
}

/* Room in inst_bits and inst_rank for object n_objects (its word is
 * started: no bit set, the rank of the instances so far). 0 or -1. */
static int grow_bits(struct scene *s)
{
	uint32_t w = s->n_objects >> 6;
	if (w >= s->cap_words) {
		uint32_t nc = s->cap_words ? s->cap_words * 2 : 4;
		uint64_t *nb = realloc(s->inst_bits, (size_t)nc * sizeof *nb);
		if (!nb)
			return -1;
		s->inst_bits = nb;
		uint32_t *nr = realloc(s->inst_rank, (size_t)nc * sizeof *nr);
		if (!nr)
			return -1;
		s->inst_rank = nr;
		s->cap_words = nc;
	}
	if ((s->n_objects & 63) == 0) {
		s->inst_bits[w] = 0;
		s->inst_rank[w] = s->n_insts;
	}
	return 0;
}

/* Appends o (not an instance) to objs[] as object n_objects. 0 or -1. */
static int add_full(struct scene *s, const struct scene_object *o)
{
	if (grow((void **)&s->objs, s->n_objs, &s->cap_objs, sizeof *s->objs, LIM_OBJECTS) < 0)
		return -1;
	s->objs[s->n_objs++] = *o;
	return 0;
}

/* The files[] index of interned name f (SCENE_NONE for NULL or a name the
 * scene did not intern: decoders' placeholders). */
static uint32_t file_index(struct scene *s, const char *f)
{
	if (!f)
		return SCENE_NONE;
	if (s->last_file < s->n_files && s->files[s->last_file] == f)
		return s->last_file;
	for (uint32_t k = 0; k < s->n_files; k++)
		if (s->files[k] == f)
			return s->last_file = k;
	return SCENE_NONE;
}

/* Appends instance o as a compact record (INSTANCES in scene.h), object
 * n_objects. Returns 0 or -1. */
static int add_inst(struct scene *s, const struct scene_object *o)
{
	struct scene_inst in;
	memset(&in, 0, sizeof in);
	in.define = o->u.instance.define;
	in.material = o->material;
	in.line = o->loc.line;
	in.col = o->loc.col;
	in.file = file_index(s, o->loc.file);
	if (o->loc.file && in.file == SCENE_NONE) {
		/* not interned here: intern it, so the record can name it */
		const char *f = scene_intern_file(s, o->loc.file);
		if (!f)
			return -1;
		in.file = file_index(s, f);
	}
	in.lin = SCENE_LIN_NONE;
	if (o->has_xform) {
		mat34 lin = o->xform;
		in.t = v3(lin.m[0][3], lin.m[1][3], lin.m[2][3]);
		lin.m[0][3] = lin.m[1][3] = lin.m[2][3] = 0;
		mat34 id = m34_identity();
		if (memcmp(&lin, &id, sizeof lin) == 0) { /* bit for bit: -0 is not 0 here */
			in.lin = SCENE_LIN_IDENTITY;
		} else if (s->n_lins && memcmp(&lin, &s->lins[s->n_lins - 1], sizeof lin) == 0) {
			in.lin = s->n_lins - 1; /* the same rotation as the instance before */
		} else {
			if (grow((void **)&s->lins, s->n_lins, &s->cap_lins, sizeof *s->lins, LIM_OBJECTS) < 0)
				return -1;
			in.lin = s->n_lins;
			s->lins[s->n_lins++] = lin;
		}
	}
	if (grow((void **)&s->insts, s->n_insts, &s->cap_insts, sizeof *s->insts, LIM_OBJECTS) < 0)
		return -1;
	s->inst_bits[s->n_objects >> 6] |= UINT64_C(1) << (s->n_objects & 63);
	s->insts[s->n_insts++] = in;
	return 0;
}

void scene_inst_xform(const struct scene *s, const struct scene_inst *in, mat34 *m)
{
	if (in->lin == SCENE_LIN_NONE) {
		*m = m34_identity();
		return;
	}
	*m = in->lin == SCENE_LIN_IDENTITY ? m34_identity() : s->lins[in->lin];
	m->m[0][3] = in->t.x;
	m->m[1][3] = in->t.y;
	m->m[2][3] = in->t.z;
}

void scene_inst_expand(const struct scene *s, const struct scene_inst *in, struct scene_object *o)
{
	scene_object_defaults(o, PRIM_INSTANCE);
	o->u.instance.define = in->define;
	o->material = in->material;
	o->has_xform = in->lin != SCENE_LIN_NONE;
	scene_inst_xform(s, in, &o->xform);
	o->loc.file = in->file == SCENE_NONE ? NULL : s->files[in->file];
	o->loc.line = in->line;
	o->loc.col = in->col;
}

struct scene_object scene_object_at(const struct scene *s, uint32_t i)
{
	struct scene_object tmp;
	return *scene_object(s, i, &tmp);
}

int scene_add_object(struct scene *s, struct scene_object *o, uint32_t *id, struct scene_error *err)
{
	uint32_t self = s->n_objects;
	int ok = (int)o->kind >= 0 && o->kind < PRIM_KIND_COUNT && check_xform(o) &&
		 (o->material == SCENE_NONE || o->material < s->n_materials);
	const char *why = "a value out of range";
	if (ok) {
		switch (o->kind) {
		case PRIM_SPHERE:
			ok = check_sphere(&o->u.sphere);
			break;
		case PRIM_PLANE:
		case PRIM_DISK:
			ok = v3_finite(o->u.plane.position) && v3_finite(o->u.plane.normal) &&
			     v3_len(o->u.plane.normal) > 0 && v3_finite(o->u.plane.x_axis) &&
			     v3_finite(o->u.plane.y_axis) && (o->kind == PRIM_PLANE || finite_pos(o->u.plane.radius));
			break;
		case PRIM_CYLINDER:
			ok = check_cylinder(&o->u.cylinder);
			break;
		case PRIM_BOX:
			ok = check_box(&o->u.box);
			break;
		case PRIM_TRIANGLE: {
			const struct prim_triangle *t = &o->u.triangle;
			ok = v3_finite(t->a) && v3_finite(t->b) && v3_finite(t->c) &&
			     (!t->has_normals || (v3_finite(t->na) && v3_finite(t->nb) && v3_finite(t->nc)));
			break;
		}
		case PRIM_RAW:
			ok = o->u.raw.mesh < s->n_meshes;
			why = "an unknown mesh";
			break;
		case PRIM_CSG:
			ok = o->u.csg.operand1 < self && o->u.csg.operand2 < self &&
			     o->u.csg.operand1 != o->u.csg.operand2 && (int)o->u.csg.op >= 0 &&
			     o->u.csg.op <= CSG_SUBTRACT;
			why = "invalid operands";
			break;
		case PRIM_POLYGON:
			ok = check_polygon(&o->u.polygon);
			why = "an invalid contour list (each contour needs 3 or more points)";
			break;
		case PRIM_INSTANCE:
			ok = o->u.instance.define < s->n_defines;
			why = "an undefined complex object";
			break;
		default:
			ok = 0;
		}
	}
	if (!ok) {
		scene_errorf(err, 1, LOCFMT "%s object has %s", LOCARGS(&o->loc), scene_prim_name(o->kind), why);
		goto fail;
	}
	if (s->n_objects >= LIM_OBJECTS || grow_bits(s) < 0 ||
	    (o->kind == PRIM_INSTANCE ? add_inst(s, o) : add_full(s, o)) < 0) {
		scene_errorf(err, 1, LOCFMT "too many objects or out of memory", LOCARGS(&o->loc));
		goto fail;
	}
	s->n_objects++;
	if (o->kind == PRIM_POLYGON)
		o->u.polygon.points = NULL, o->u.polygon.contour_start = NULL;
	if (id)
		*id = self;
	return 0;
fail:
	object_free_owned(o);
	return err ? err->level : 1;
}

int scene_add_define(struct scene *s, struct scene_define *d, uint32_t *id, struct scene_error *err)
{
	int ok = d->name && d->name[0] && (d->n_objects == 0 || d->objects);
	for (uint32_t i = 0; ok && i < d->n_objects; i++)
		ok = d->objects[i] < s->n_objects;
	if (!ok) {
		scene_errorf(err, 1, LOCFMT "invalid definition", LOCARGS(&d->loc));
		goto fail;
	}
	if (grow((void **)&s->defines, s->n_defines, &s->cap_defines, sizeof *s->defines, LIM_DEFINES) < 0) {
		scene_errorf(err, 1, LOCFMT "too many definitions or out of memory", LOCARGS(&d->loc));
		goto fail;
	}
	if (id)
		*id = s->n_defines;
	s->defines[s->n_defines++] = *d;
	d->name = NULL;
	d->objects = NULL;
	return 0;
fail:
	free(d->name);
	free(d->objects);
	d->name = NULL;
	d->objects = NULL;
	return err ? err->level : 1;
}

int scene_add_root(struct scene *s, uint32_t object, struct scene_error *err)
{
	if (object >= s->n_objects)
		return scene_errorf(err, 1, "error: root object %u does not exist", object);
	if (grow((void **)&s->roots, s->n_roots, &s->cap_roots, sizeof *s->roots, LIM_OBJECTS) < 0)
		return scene_errorf(err, 1, "error: too many objects or out of memory");
	s->roots[s->n_roots++] = object;
	return 0;
}

uint32_t scene_find_material(const struct scene *s, const char *name)
{
	for (uint32_t i = s->n_materials; i-- > 0;)
		if (s->materials[i].name && strcasecmp(s->materials[i].name, name) == 0)
			return i;
	return SCENE_NONE;
}

uint32_t scene_find_define(const struct scene *s, const char *name)
{
	for (uint32_t i = s->n_defines; i-- > 0;)
		if (strcasecmp(s->defines[i].name, name) == 0)
			return i;
	return SCENE_NONE;
}

/* ---- statistics and names ------------------------------------------------------- */

/* a + b, saturating at UINT64_MAX: nested instances multiply counts quickly */
static uint64_t sat_add(uint64_t a, uint64_t b) { return a > UINT64_MAX - b ? UINT64_MAX : a + b; }

/* What an object draws, through every instance: triangles (a raw mesh
 * counts its own) and primitives (a raw mesh counts one), each saturating
 * at UINT64_MAX. */
struct drawn {
	uint64_t tris, prims;
};

/* Per define: what it draws, once known (for object_drawn). */
struct drawn_memo {
	struct drawn n;
	bool known;
};

static struct drawn drawn_add(struct drawn a, struct drawn b)
{
	return (struct drawn){ sat_add(a.tris, b.tris), sat_add(a.prims, b.prims) };
}

/* What object i draws (struct drawn); memo caches per-define counts, so
 * each define is counted once however often it is used (nested64.sce's
 * 2^63 spheres take 64 steps). CSG nodes are not cached: the parser makes
 * every operand an object of its own, so only defines are shared. */
static struct drawn object_drawn(const struct scene *s, uint32_t i, struct drawn_memo *memo)
{
	if (scene_is_inst(s, i)) {
		uint32_t d = scene_inst_at(s, i)->define;
		if (!memo[d].known) {
			struct drawn n = { 0, 0 };
			for (uint32_t k = 0; k < s->defines[d].n_objects; k++)
				n = drawn_add(n, object_drawn(s, s->defines[d].objects[k], memo));
			memo[d].n = n;
			memo[d].known = true;
		}
		return memo[d].n;
	}
	const struct scene_object *o = scene_full_at(s, i);
	switch (o->kind) {
	case PRIM_TRIANGLE:
		return (struct drawn){ 1, 1 };
	case PRIM_RAW:
		return (struct drawn){ s->meshes[o->u.raw.mesh].n_triangles, 1 };
	case PRIM_CSG:
		return drawn_add(object_drawn(s, o->u.csg.operand1, memo), object_drawn(s, o->u.csg.operand2, memo));
	default: /* sphere, plane, cylinder, box, disk, polygon */
		return (struct drawn){ 0, 1 };
	}
}

void scene_stats(const struct scene *s, struct scene_stats *st)
{
	memset(st, 0, sizeof *st);
	for (uint32_t i = 0; i < s->n_objs; i++)
		st->by_kind[s->objs[i].kind]++;
	st->by_kind[PRIM_INSTANCE] += s->n_insts;
	for (uint32_t i = 0; i < s->n_meshes; i++)
		st->triangles += s->meshes[i].n_triangles;
	st->triangles += st->by_kind[PRIM_TRIANGLE];
	for (uint32_t i = 0; i < s->n_materials; i++) {
		if (s->materials[i].name)
			st->materials_named++;
		else
			st->materials_anon++;
	}
	struct drawn_memo *memo = calloc(s->n_defines ? s->n_defines : 1, sizeof *memo);
	if (memo) {
		struct drawn n = { 0, 0 };
		for (uint32_t i = 0; i < s->n_roots; i++)
			n = drawn_add(n, object_drawn(s, s->roots[i], memo));
		st->triangles_instanced = n.tris;
		st->prims_instanced = n.prims;
		free(memo);
	}
}

const char *scene_prim_name(enum prim_kind k)
{
	static const char *const names[] = { "sphere", "plane", "cylinder", "box", "triangle",
					     "raw", "csg", "disk", "polygon", "instance" };
	return (unsigned)k < PRIM_KIND_COUNT ? names[k] : "?";
}

const char *scene_filter_name(enum filter_kind k)
{
	static const char *const names[] = { "standard", "adaptive", "super-sample", "disk", "lens" };
	return (unsigned)k <= FILTER_LENS ? names[k] : "?";
}

const char *scene_shader_name(enum shader_kind k)
{
	static const char *const names[] = { "none", "bricks", "tiles", "chequers",
					     "bumpy", "noise", "fades", "turb3d" };
	return (unsigned)k <= SHADER_TURB3D ? names[k] : "?";
}

int scene_xform_op(mat34 *m, enum xform_op op, int axis, double amount, vec3 v)
{
	mat34 t = m34_identity();
	switch (op) {
	case XF_SHRINK:
	case XF_STRETCH: {
		if (!isfinite(amount) || amount == 0 || axis < 0 || axis > 2)
			return 0;
		double f = op == XF_STRETCH ? amount : 1.0 / amount;
		t.m[axis][axis] = f;
		break;
	}
	case XF_TRANSLATE:
		if (!v3_finite(v))
			return 0;
		t.m[0][3] = v.x;
		t.m[1][3] = v.y;
		t.m[2][3] = v.z;
		break;
	case XF_ROTATE: {
		if (!isfinite(amount) || axis < 0 || axis > 2)
			return 0;
		/* right-handed: positive angles turn y toward z (x-rotate), z toward x
		 * (y-rotate), x toward y (z-rotate) */
		double a = amount * (M_PI / 180.0), c = xm_cos(a), sn = xm_sin(a);
		int i = (axis + 1) % 3, j = (axis + 2) % 3;
		t.m[i][i] = c;
		t.m[i][j] = -sn;
		t.m[j][i] = sn;
		t.m[j][j] = c;
		break;
	}
	default:
		return 0;
	}
	*m = m34_mul(&t, m); /* written order: the new op applies after the earlier ones */
	return 1;
}
