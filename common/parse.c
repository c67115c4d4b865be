/*
 * parse.c - the PortRAY scene language parser: a recursive-descent parser over
 * lex.c's tokens that hands every statement to the scene builder (scene.h).
 * docs/language.md is the reference for the language and its decisions.
 *
 * Conventions (as in Lua's lparser.c): P->tok is the current token, not yet
 * consumed; each parse function opens with its grammar rule; every function
 * returns 0 or an Appendix B error level with P->err filled in, and the
 * first error ends the parse. Functions that own memory release it on one
 * cleanup path.
 */
#include "common/parse.h"

#include <errno.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "common/lex.h"
#include "common/parse_int.h"
#include "common/raw.h"

/* ---- statements ---------------------------------------------------------------- */

static bool closer_in_filter(enum keyword kw)
{
	return kw == KW_FILTER || kw == KW_LOOK_AT || kw == KW_LOOK_FROM || kw == KW_DROP_LINE ||
	       kw == KW_X_SIZE || kw == KW_Y_SIZE;
}

/*
 * filter -> FILTER ( STANDARD [';'] | ADAPTIVE { THRESHOLD NUM | MAX-DEPTH INT
 *           | CACHE-SIZE INT | RELAX NUM } ';' | SUPER-SAMPLE { X-SAMPLES INT
 *           | Y-SAMPLES INT } ';' | DISK { RADIUS NUM | SAMPLES INT } ';'
 *           | LENS { RADIUS NUM | SAMPLES INT | FOCAL-LENGTH NUM } ';' )
 * After `standard` a ';' belongs to the filter when the token after it is
 * another ';' or a camera keyword; otherwise it closes the camera.
 */
static int parse_filter(struct parser *P, struct scene_camera *cam, bool *cache_given)
{
	struct token open = P->tok;
	next(P);
	struct token kt = P->tok;
	enum filter_kind k;
	switch (kt.kind == TK_WORD ? kt.kw : KW_NONE) {
	case KW_STANDARD: k = FILTER_STANDARD; break;
	case KW_ADAPTIVE: k = FILTER_ADAPTIVE; break;
	case KW_SUPER_SAMPLE: k = FILTER_SUPERSAMPLE; break;
	case KW_DISK: k = FILTER_DISK; break;
	case KW_LENS: k = FILTER_LENS; break;
	default:
		return err_near(P, &kt, "unrecognised keyword in camera section: filter standard, adaptive, "
					"super-sample, disk or lens expected");
	}
	if (cam->n_filters >= LIM_FILTERS)
		return err_at(P, ERRLEVEL_FATAL, &open, "too many filters (at most %d)", LIM_FILTERS);
	struct scene_filter *f = &cam->filters[cam->n_filters];
	bool *given = &cache_given[cam->n_filters];
	scene_filter_defaults(f, k);
	f->loc = loc_at(P, &open);
	*given = false;
	cam->n_filters++;
	next(P);
	if (k == FILTER_STANDARD) {
		if (P->tok.kind == TK_SEMI) {
			const struct token *nx = peek(P);
			if (nx->kind == TK_SEMI || (nx->kind == TK_WORD && (closer_in_filter(nx->kw) || nx->kw == KW_DEPTH)))
				next(P);
		}
		return 0;
	}
	const char *fname = scene_filter_name(k);
	for (;;) {
		struct token kw = P->tok;
		if (kw.kind == TK_SEMI)
			break;
		int r = NOT_MINE;
		enum keyword w = kw.kind == TK_WORD ? kw.kw : KW_NONE;
		if (k == FILTER_ADAPTIVE) {
			if (w == KW_THRESHOLD)
				next(P), r = parse_num(P, &kw, &f->threshold, R_POS);
			else if (w == KW_MAX_DEPTH)
				next(P), r = parse_int(P, &kw, &f->max_depth, 0, LIM_ADAPTIVE_DEPTH);
			else if (w == KW_CACHE_SIZE)
				next(P), r = parse_int(P, &kw, &f->cache_size, 0, 1 << 30), *given = true;
			else if (w == KW_RELAX)
				next(P), r = parse_num(P, &kw, &f->relax, R_POS);
		} else if (k == FILTER_SUPERSAMPLE) {
			if (w == KW_X_SAMPLES)
				next(P), r = parse_int(P, &kw, &f->x_samples, 1, LIM_SAMPLES);
			else if (w == KW_Y_SAMPLES)
				next(P), r = parse_int(P, &kw, &f->y_samples, 1, LIM_SAMPLES);
		} else {
			if (w == KW_RADIUS)
				next(P), r = parse_num(P, &kw, &f->radius, R_NONNEG);
			else if (w == KW_SAMPLES)
				next(P), r = parse_int(P, &kw, &f->samples, 1, LIM_SAMPLES);
			else if (w == KW_FOCAL_LENGTH && k == FILTER_LENS)
				next(P), r = parse_num(P, &kw, &f->focal_length, R_POS);
		}
		if (r == NOT_MINE) {
			char what[80];
			snprintf(what, sizeof what, "unrecognised keyword in camera section (filter %s)", fname);
			return parse_unknown(P, what, &open, "filter", closer_in_filter,
				       k == FILTER_ADAPTIVE      ? "threshold, max-depth, cache-size, relax or ';'"
				       : k == FILTER_SUPERSAMPLE ? "x-samples, y-samples or ';'"
				       : k == FILTER_DISK        ? "radius, samples or ';'"
								 : "radius, samples, focal-length or ';'");
		}
		if (r)
			return r;
	}
	next(P);
	return 0;
}

/*
 * Applies the rule that standard or adaptive comes first: filters before the
 * first of them are dropped with a warning; with neither, a standard filter
 * is put first (with a warning).
 */
static int order_filters(struct parser *P, struct scene_camera *cam, bool *cache_given, const struct token *open)
{
	int first = -1;
	for (int i = 0; i < cam->n_filters && first < 0; i++)
		if (cam->filters[i].kind == FILTER_STANDARD || cam->filters[i].kind == FILTER_ADAPTIVE)
			first = i;
	if (first > 0) {
		for (int i = 0; i < first; i++) {
			struct token at = { .line = cam->filters[i].loc.line, .col = cam->filters[i].loc.col };
			warn_at(P, &at, "filter %s before the first standard or adaptive filter is ignored",
				scene_filter_name(cam->filters[i].kind));
		}
		memmove(cam->filters, cam->filters + first, (size_t)(cam->n_filters - first) * sizeof cam->filters[0]);
		memmove(cache_given, cache_given + first, (size_t)(cam->n_filters - first) * sizeof cache_given[0]);
		cam->n_filters -= first;
	} else if (first < 0) {
		if (cam->n_filters >= LIM_FILTERS)
			return err_at(P, ERRLEVEL_FATAL, open, "too many filters (at most %d)", LIM_FILTERS);
		if (cam->n_filters > 0)
			warn_at(P, open, "camera has no standard or adaptive filter: 'filter standard' assumed first");
		memmove(cam->filters + 1, cam->filters, (size_t)cam->n_filters * sizeof cam->filters[0]);
		memmove(cache_given + 1, cache_given, (size_t)cam->n_filters * sizeof cache_given[0]);
		scene_filter_defaults(&cam->filters[0], FILTER_STANDARD);
		cam->filters[0].loc = cam->loc;
		cache_given[0] = false;
		cam->n_filters++;
	}
	return 0;
}

/*
 * camera -> CAMERA { LOOK-AT vector | DROP-LINE vector | LOOK-FROM vector
 *           | DEPTH NUM | X-SIZE NUM | Y-SIZE NUM | filter } ';'
 */
static int parse_camera(struct parser *P)
{
	struct token open = P->tok;
	struct scene_camera cam;
	bool cache_given[LIM_FILTERS] = { false };
	scene_camera_defaults(&cam);
	cam.n_filters = 0;
	cam.set = true;
	cam.loc = loc_at(P, &open);
	next(P);
	for (;;) {
		struct token kw = P->tok;
		if (kw.kind == TK_SEMI)
			break;
		int r;
		switch (kw.kind == TK_WORD ? kw.kw : KW_NONE) {
		case KW_LOOK_AT: next(P); r = parse_vec(P, &kw, &cam.look_at); break;
		case KW_DROP_LINE: next(P); r = parse_vec(P, &kw, &cam.drop_line); break;
		case KW_LOOK_FROM: next(P); r = parse_vec(P, &kw, &cam.look_from); break;
		case KW_DEPTH: next(P); r = parse_num(P, &kw, &cam.depth, R_POS); break;
		case KW_X_SIZE: next(P); r = parse_num(P, &kw, &cam.x_size, R_POS); break;
		case KW_Y_SIZE: next(P); r = parse_num(P, &kw, &cam.y_size, R_POS); break;
		case KW_FILTER: r = parse_filter(P, &cam, cache_given); break;
		case KW_XSIZE:
		case KW_YSIZE:
			r = err_near(P, &kw, "unrecognised keyword in camera section (the film size is x-size/y-size; "
					     "xsize/ysize belong in the image statement)");
			break;
		default:
			r = parse_unknown(P, "unrecognised keyword in camera section", &open, "camera", NULL,
				    "look-at, look-from, drop-line, depth, x-size, y-size, filter or ';'");
			break;
		}
		if (r)
			return r;
	}
	TRY(order_filters(P, &cam, cache_given, &open));
	if (P->camera_locked && !P->camera_only) {
		warn_at(P, &open, "camera statement ignored: the camera file's camera is used");
	} else {
		TRY(scene_set_camera(P->s, &cam, P->err));
		memcpy(P->cache_given, cache_given, sizeof cache_given);
		if (P->camera_only)
			P->camera_locked = true;
	}
	next(P);
	return 0;
}

/*
 * image -> IMAGE { XSIZE INT | YSIZE INT | NO-SHADOWS | NO-REFLECTIONS | NONSTOP
 *          | INTERSECT-BUFFER INT } ';'
 */
static int parse_image(struct parser *P)
{
	struct token open = P->tok;
	struct scene_image im;
	scene_image_defaults(&im);
	im.set = true;
	im.loc = loc_at(P, &open);
	next(P);
	for (;;) {
		struct token kw = P->tok;
		if (kw.kind == TK_SEMI)
			break;
		int r;
		switch (kw.kind == TK_WORD ? kw.kw : KW_NONE) {
		case KW_XSIZE: next(P); r = parse_int(P, &kw, &im.xsize, 1, LIM_IMAGE_SIDE); break;
		case KW_YSIZE: next(P); r = parse_int(P, &kw, &im.ysize, 1, LIM_IMAGE_SIDE); break;
		case KW_NO_SHADOWS: next(P); im.no_shadows = true; r = 0; break;
		case KW_NO_REFLECTIONS: next(P); im.no_reflections = true; r = 0; break;
		case KW_NONSTOP: next(P); im.nonstop = true; r = 0; break;
		case KW_INTERSECT_BUFFER: next(P); r = parse_int(P, &kw, &im.intersect_buffer, 0, 1 << 30); break;
		case KW_X_SIZE:
		case KW_Y_SIZE:
			r = err_near(P, &kw, "unrecognised keyword in image section (the pixel size is xsize/ysize; "
					     "x-size/y-size belong in the camera statement)");
			break;
		default:
			r = parse_unknown(P, "unrecognised keyword in image section", &open, "image", NULL,
				    "xsize, ysize, no-shadows, no-reflections, nonstop, intersect-buffer or ';'");
			break;
		}
		if (r)
			return r;
	}
	if (P->image_locked && !P->camera_only) {
		warn_at(P, &open, "image statement ignored: the camera file's image is used");
	} else {
		TRY(scene_set_image(P->s, &im, P->err));
		if (P->camera_only)
			P->image_locked = true;
	}
	next(P);
	return 0;
}

static bool closer_in_light(enum keyword kw)
{
	return kw == KW_COLOUR || kw == KW_POSITION || kw == KW_SHAPE || kw == KW_SAMPLES ||
	       kw == KW_FALL_OFF || kw == KW_NO_SHADOWS;
}

/*
 * light -> LIGHT { COLOUR vector | POSITION vector | SHAPE lightshape
 *          | SAMPLES INT | FALL-OFF NUM | NO-SHADOWS } ';'
 * lightshape -> (SPHERE { spherevar } | CYLINDER { cylvar } | BOX { boxvar }) ';'
 */
static int parse_light(struct parser *P)
{
	struct token open = P->tok, samples_tok = { 0 };
	struct scene_light l;
	bool have_samples = false;
	scene_light_defaults(&l);
	l.loc = loc_at(P, &open);
	next(P);
	for (;;) {
		struct token kw = P->tok;
		if (kw.kind == TK_SEMI)
			break;
		int r;
		switch (kw.kind == TK_WORD ? kw.kw : KW_NONE) {
		case KW_COLOUR: next(P); r = parse_vec(P, &kw, &l.colour); break;
		case KW_POSITION: next(P); r = parse_vec(P, &kw, &l.position); break;
		case KW_SAMPLES:
			samples_tok = kw;
			have_samples = true;
			next(P);
			r = parse_int(P, &kw, &l.samples, 1, LIM_SAMPLES);
			break;
		case KW_FALL_OFF: next(P); r = parse_num(P, &kw, &l.fall_off, R_NONNEG); break;
		case KW_NO_SHADOWS: next(P); l.no_shadows = true; r = 0; break;
		case KW_SHAPE: {
			next(P);
			struct token st = P->tok;
			if (st.kind != TK_WORD || !(st.kw == KW_SPHERE || st.kw == KW_CYLINDER || st.kw == KW_BOX)) {
				if (st.kind == TK_WORD && is_prim_kw(st.kw))
					return err_at(P, ERRLEVEL_FATAL, &st,
						      "a %s cannot be the shape of a light (sphere, cylinder or box)",
						      lex_keyword_name(st.kw));
				return err_near(P, &st, "light shape expected (sphere, cylinder or box)");
			}
			if (l.shape != LIGHT_POINT)
				return err_near(P, &st, "a light takes one shape");
			l.shape = st.kw == KW_SPHERE ? LIGHT_SPHERE : st.kw == KW_CYLINDER ? LIGHT_CYLINDER : LIGHT_BOX;
			const char *sname = lex_keyword_name(st.kw);
			next(P);
			r = 0;
			while (P->tok.kind != TK_SEMI) {
				int v = NOT_MINE;
				if (P->tok.kind == TK_WORD)
					v = l.shape == LIGHT_SPHERE	? parse_sphere_var(P, &l.sphere)
					    : l.shape == LIGHT_CYLINDER ? parse_cylinder_var(P, &l.cylinder)
									: parse_box_var(P, &l.box);
				if (v == NOT_MINE) {
					char what[64];
					snprintf(what, sizeof what, "unknown verb in light (shape %s)", sname);
					return parse_unknown(P, what, &st, sname, closer_in_light,
						       l.shape == LIGHT_SPHERE	   ? "centre, radius, pole, equator or ';'"
						       : l.shape == LIGHT_CYLINDER ? "from, to, radius, capped or ';'"
										   : "a, b or ';'");
				}
				if (v)
					return v;
			}
			if (l.shape == LIGHT_CYLINDER && v3_len(v3_sub(l.cylinder.to, l.cylinder.from)) == 0)
				return err_near(P, &P->tok, "a cylinder's 'from' and 'to' must differ");
			next(P);
			break;
		}
		default:
			r = parse_unknown(P, "unknown verb in light", &open, "light", NULL,
				    "colour, position, shape, samples, fall-off, no-shadows or ';'");
			break;
		}
		if (r)
			return r;
	}
	if (have_samples && l.shape == LIGHT_POINT)
		return err_at(P, ERRLEVEL_LEVEL2, &samples_tok, "'samples' on a light with no shape");
	TRY(scene_add_light(P->s, &l, P->err));
	next(P);
	return 0;
}

/* Object-level keywords cannot name a defined object: they would hide it. */
static bool reserved_define_name(enum keyword kw) { return is_object_kw(kw) || is_transform_kw(kw); }

/*
 * defobject -> { NAME NAME | OBJECT body } ';'   (after DEFINE OBJECT)
 * Exactly one name; any number of member objects.
 */
static int parse_define_object(struct parser *P, const struct token *open)
{
	struct scene_define d = { 0 };
	struct token name_tok = { 0 };
	uint32_t cap = 0;
	unsigned depth = 0;
	int rc = 0;
	d.loc = loc_at(P, open);
	for (;;) {
		struct token kw = P->tok;
		if (kw.kind == TK_SEMI)
			break;
		if (is_kw(P, KW_NAME)) {
			if (d.name) {
				rc = err_near(P, &kw, "a defined object takes one name");
				goto fail;
			}
			next(P);
			name_tok = P->tok;
			if (P->tok.kind == TK_WORD && (reserved_define_name(P->tok.kw) || P->tok.num != NUM_NO)) {
				rc = err_near(P, &P->tok, "a defined object cannot be named by a keyword or number");
				goto fail;
			}
			if ((rc = parse_name(P, &kw, &d.name)) != 0)
				goto fail;
			P->defining = d.name;
			P->defining_line = open->line;
			continue;
		}
		if (is_kw(P, KW_OBJECT)) {
			uint32_t id;
			next(P);
			if ((rc = parse_object_body(P, &kw, &id)) != 0)
				goto fail;
			if (d.n_objects == cap) {
				uint32_t nc = cap ? cap * 2 : 8;
				uint32_t *p = nc > LIM_OBJECTS ? NULL : realloc(d.objects, nc * sizeof *p);
				if (!p) {
					rc = err_at(P, ERRLEVEL_FATAL, &kw, "out of memory");
					goto fail;
				}
				d.objects = p;
				cap = nc;
			}
			d.objects[d.n_objects++] = id;
			if (P->obj_depth[id] > depth)
				depth = P->obj_depth[id];
			continue;
		}
		rc = parse_unknown(P, "unknown verb in definition (name or object expected)", open, "object", NULL, NULL);
		goto fail;
	}
	if (!d.name) {
		rc = err_near(P, &P->tok, "a defined object needs 'name NAME'");
		goto fail;
	}
	if (depth + 1 > LIM_DEFINE_DEPTH) {
		rc = err_at(P, ERRLEVEL_FATAL, &name_tok, "definitions nested more than %d deep", LIM_DEFINE_DEPTH);
		goto fail;
	}
	uint32_t id;
	P->defining = NULL;
	if ((rc = scene_add_define(P->s, &d, &id, P->err)) != 0)
		return rc; /* the scene freed d's arrays */
	if (parse_names_put(&P->def_names, id, def_name, P->s) < 0)
		return err_at(P, ERRLEVEL_FATAL, open, "out of memory");
	if (parse_grow_bytes(&P->def_depth, &P->cap_def_depth, P->s->n_defines) < 0)
		return err_at(P, ERRLEVEL_FATAL, open, "out of memory");
	P->def_depth[id] = (unsigned char)(depth + 1);
	next(P);
	return 0;
fail:
	P->defining = NULL;
	free(d.name);
	free(d.objects);
	return rc;
}

/*
 * define -> DEFINE { OBJECT defobject | MATERIAL material } ';'
 * (a defined material must be named)
 */
static int parse_define(struct parser *P)
{
	struct token open = P->tok;
	next(P);
	for (;;) {
		struct token kw = P->tok;
		if (kw.kind == TK_SEMI)
			break;
		if (is_kw(P, KW_OBJECT)) {
			next(P);
			TRY(parse_define_object(P, &kw));
		} else if (is_kw(P, KW_MATERIAL)) {
			uint32_t id;
			next(P);
			TRY(parse_material(P, &kw, true, &id));
		} else {
			return parse_unknown(P, "unknown verb in definition (object or material expected)", &open, "define",
				       NULL, NULL);
		}
	}
	next(P);
	return 0;
}

static int parse_text(struct parser *P, const char *name, const char *buf, size_t len);

/* Parses the file at path (role names it in messages: "scene", "include"...);
 * at, when not NULL, is the token that asked for it (errors point there). */
static int parse_path(struct parser *P, const char *path, const char *role, const struct token *at)
{
	char *buf = NULL;
	size_t len = 0;
	unsigned long long dev = 0, ino = 0;
	int nul_line = 0, nul_col = 0;
	int e = lex_read_file(path, LIM_FILE_BYTES, &buf, &len, &dev, &ino, &nul_line, &nul_col);
	if (e == EILSEQ)
		return scene_errorf(P->err, ERRLEVEL_FATAL, "%s:%d:%d: error: NUL byte (the %s file is not text)",
				    path, nul_line, nul_col, role);
	if (e) {
		const char *why = e == EFBIG ? "file too large (at most 1 GiB)" : strerror(e);
		if (at)
			return err_at(P, ERRLEVEL_FATAL, at, "unable to open %s file '%s': %s", role, path, why);
		return scene_errorf(P->err, ERRLEVEL_FATAL, "%s: error: unable to open %s file: %s", path, role, why);
	}
	struct inc_id id = { dev, ino };
	for (int i = 0; i < P->n_inc; i++) {
		if (P->inc[i].dev == id.dev && P->inc[i].ino == id.ino) {
			free(buf);
			return err_at(P, ERRLEVEL_FATAL, at, "include cycle: '%s' is already being read", path);
		}
	}
	if (P->n_inc > LIM_INCLUDE_DEPTH) {
		free(buf);
		return err_at(P, ERRLEVEL_FATAL, at, "includes nested more than %d deep", LIM_INCLUDE_DEPTH);
	}
	const char *name = scene_intern_file(P->s, path);
	if (!name) {
		free(buf);
		return scene_errorf(P->err, ERRLEVEL_FATAL, "%s: error: out of memory", path);
	}
	P->inc[P->n_inc++] = id;
	int rc = parse_text(P, name, buf, len);
	P->n_inc--;
	free(buf);
	return rc;
}

/* include -> INCLUDE FILENAME   (between statements only) */
static int parse_include(struct parser *P)
{
	struct token kw = P->tok;
	next(P);
	struct token ft = P->tok;
	if (ft.kind != TK_WORD)
		return err_near(P, &ft, "file name expected after 'include'");
	if (!P->allow_files)
		return err_at(P, ERRLEVEL_FATAL, &kw, "include files cannot be read here");
	char name[LIM_TOKEN_LEN + 1];
	tok_str(&ft, name);
	char *path = parse_path_relative(P->file, name);
	if (!path)
		return err_at(P, ERRLEVEL_FATAL, &ft, "out of memory");
	int rc = parse_path(P, path, "include", &ft);
	free(path);
	if (rc)
		return rc;
	next(P);
	return 0;
}

/*
 * chunk -> { statement } EOF
 * statement -> camera | image | light | object | define | MATERIAL material | include
 * (a camera file: camera, image, light and include only)
 */
static int parse_chunk(struct parser *P)
{
	for (;;) {
		const struct token *t = &P->tok;
		if (t->kind == TK_EOF)
			return 0;
		if (t->kind == TK_ERROR)
			return err_at(P, ERRLEVEL_FATAL, t, "?");
		enum keyword kw = t->kind == TK_WORD ? t->kw : KW_NONE;
		if (P->camera_only && (kw == KW_OBJECT || kw == KW_DEFINE || kw == KW_MATERIAL))
			return err_near(P, t, "unrecognised keyword in camera file (only camera, image, light "
					      "and include)");
		switch (kw) {
		case KW_CAMERA: TRY(parse_camera(P)); break;
		case KW_IMAGE: TRY(parse_image(P)); break;
		case KW_LIGHT: TRY(parse_light(P)); break;
		case KW_INCLUDE: TRY(parse_include(P)); break;
		case KW_DEFINE: TRY(parse_define(P)); break;
		case KW_MATERIAL: {
			struct token open = *t;
			uint32_t id;
			next(P);
			TRY(parse_material(P, &open, true, &id));
			break;
		}
		case KW_OBJECT: {
			struct token open = *t;
			uint32_t id;
			next(P);
			TRY(parse_object_body(P, &open, &id));
			TRY(scene_add_root(P->s, id, P->err));
			break;
		}
		default:
			if (P->camera_only)
				return parse_unknown(P, "unrecognised keyword in camera file", t, "camera file", NULL,
					       "camera, image, light or include");
			return parse_unknown(P, "unknown verb in scene file", t, "scene file", NULL,
				       "camera, image, light, object, define, material or include");
		}
	}
}

/* Parses one file's text (name interned), saving and restoring the lexer
 * state of the including file. */
static int parse_text(struct parser *P, const char *name, const char *buf, size_t len)
{
	struct lexer lx = P->lx;
	struct token tok = P->tok, ahead = P->ahead;
	int has_ahead = P->has_ahead;
	const char *file = P->file;
	if (len > LIM_FILE_BYTES)
		return scene_errorf(P->err, ERRLEVEL_FATAL, "%s: error: file too large", name);
	lex_init(&P->lx, buf, len);
	P->file = name;
	P->has_ahead = 0;
	next(P);
	int rc = parse_chunk(P);
	P->lx = lx;
	P->tok = tok;
	P->ahead = ahead;
	P->has_ahead = has_ahead;
	P->file = file;
	return rc;
}

/* ---- entry points ------------------------------------------------------------------ */

static void parser_free(struct parser *P)
{
	free(P->obj_depth);
	free(P->def_depth);
	for (uint32_t i = 0; i < P->cap_mesh_path; i++)
		free(P->mesh_path[i]);
	free(P->mesh_path);
	free(P->mat_names.slot);
	free(P->def_names.slot);
}

/* After everything is read: the image's intersect-buffer sizes the cache of
 * every adaptive filter that did not give its own cache-size. */
static void finish(struct parser *P)
{
	struct scene_camera *c = &P->s->camera;
	for (int i = 0; i < c->n_filters; i++)
		if (c->filters[i].kind == FILTER_ADAPTIVE && !P->cache_given[i])
			c->filters[i].cache_size = P->s->image.intersect_buffer;
}

static int parser_start(struct parser *P, struct scene_error *err, int allow_files, int warn)
{
	memset(P, 0, sizeof *P);
	P->err = err;
	P->allow_files = allow_files;
	P->warn = warn;
	P->s = scene_new();
	if (!P->s)
		return scene_errorf(err, ERRLEVEL_FATAL, "error: out of memory");
	return 0;
}

static int parser_end(struct parser *P, int rc, struct scene **out)
{
	if (rc == 0) {
		finish(P);
		*out = P->s;
	} else {
		scene_free(P->s);
		*out = NULL;
	}
	parser_free(P);
	return rc;
}

int parse_files(const char *camera_path, const char *scene_path, struct scene **out, struct scene_error *err)
{
	struct parser P;
	struct scene_error dummy;
	if (!err)
		err = &dummy;
	err->level = 0;
	err->msg[0] = '\0';
	*out = NULL;
	int rc = parser_start(&P, err, 1, 1);
	if (rc)
		return rc;
	if (camera_path) {
		P.camera_only = 1;
		rc = parse_path(&P, camera_path, "camera", NULL);
		P.camera_only = 0;
	}
	if (!rc)
		rc = parse_path(&P, scene_path, "scene", NULL);
	return parser_end(&P, rc, out);
}

int parse_buffer(const char *name, const char *text, size_t len, int allow_files, struct scene **out,
		 struct scene_error *err)
{
	struct parser P;
	struct scene_error dummy;
	if (!err)
		err = &dummy;
	err->level = 0;
	err->msg[0] = '\0';
	*out = NULL;
	int rc = parser_start(&P, err, allow_files, 0);
	if (rc)
		return rc;
	const char *iname = scene_intern_file(P.s, name ? name : "<buffer>");
	if (!iname)
		rc = scene_errorf(err, ERRLEVEL_FATAL, "error: out of memory");
	else
		rc = parse_text(&P, iname, text, len);
	return parser_end(&P, rc, out);
}
