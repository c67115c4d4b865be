/*
 * parse_int.h - what the parser's files share (parse.c: statements, files
 * and entry points; parse_object.c: objects, primitives, materials and
 * shaders; parse_base.c: messages, values, names, transforms). Internal to
 * them: nothing else includes it.
 */
#ifndef PORTRAY_PARSE_INT_H
#define PORTRAY_PARSE_INT_H

#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "common/lex.h"
#include "common/scene.h"

/* returned by the *_var helpers when the current word is not theirs */
#define NOT_MINE (-1)
/* longest token text quoted in a message ("near '...'") */
#define NEAR_MAX 40
/* room for " near '" + NEAR_MAX bytes, each possibly shown as \xNN, + "...'" */
#define NEAR_BUF (16 + 4 * NEAR_MAX)
/* a contour's points must lie within this fraction of the polygon's size of
 * the first contour's plane (rounding in written decimals, nothing more) */
#define POLY_PLANE_TOL 1e-6

#define TRY(x)                         \
	do {                           \
		int try_rc_ = (x);     \
		if (try_rc_)           \
			return try_rc_; \
	} while (0)

struct inc_id {
	unsigned long long dev, ino;
};

/*
 * Case-insensitive name -> index table (open addressing, linear probing),
 * so that `called NAME` and defined-object uses cost O(1) even in scenes
 * with many names. Keys are the scene's own name strings; a name defined
 * again points at its latest index, as scene_find_* would answer.
 */
struct name_table {
	uint32_t *slot; /* index + 1, 0 = empty */
	uint32_t cap, n; /* cap is a power of two */
};

struct parser {
	struct scene *s;
	struct scene_error *err;
	struct lexer lx;
	const char *file;     /* current file's name (interned in the scene) */
	struct token tok;     /* current token */
	struct token ahead;   /* one token of lookahead, valid when has_ahead */
	int has_ahead;
	int allow_files;      /* includes and raw files may be read */
	int camera_only;      /* camera file: camera, image and light only */
	int warn;             /* print warnings on stderr */
	/* files being read, outermost first, for cycles and depth */
	struct inc_id inc[LIM_INCLUDE_DEPTH + 2];
	int n_inc;
	/* the camera file's camera/image win over the scene file's */
	bool camera_locked, image_locked;
	bool cache_given[LIM_FILTERS]; /* adaptive cache-size written, per filter */
	/* per object: define nesting depth below it; per define: its depth */
	unsigned char *obj_depth;
	uint32_t cap_obj_depth;
	unsigned char *def_depth;
	uint32_t cap_def_depth;
	/* per mesh: the resolved path it was read from, for reuse */
	char **mesh_path;
	uint32_t cap_mesh_path;
	int csg_depth, shader_depth;
	/* the defined object being read (its name once written), for messages */
	const char *defining;
	int defining_line;
	/* name -> latest index, for materials and defines (case-insensitive) */
	struct name_table mat_names, def_names;
};

/* ---- messages (parse_base.c) ------------------------------------------------- */

int parse_vreport(struct parser *P, int level, const struct token *t, int near, const char *fmt, va_list ap);
int parse_unknown(struct parser *P, const char *what, const struct token *open, const char *open_name,
		  bool (*closer)(enum keyword), const char *expected);

static inline int err_near(struct parser *P, const struct token *t, const char *fmt, ...)
	__attribute__((format(printf, 3, 4)));
static inline int err_near(struct parser *P, const struct token *t, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	int r = parse_vreport(P, ERRLEVEL_FATAL, t, 1, fmt, ap);
	va_end(ap);
	return r;
}

static inline int err_at(struct parser *P, int level, const struct token *t, const char *fmt, ...)
	__attribute__((format(printf, 4, 5)));
static inline int err_at(struct parser *P, int level, const struct token *t, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	int r = parse_vreport(P, level, t, 0, fmt, ap);
	va_end(ap);
	return r;
}

static inline void warn_at(struct parser *P, const struct token *t, const char *fmt, ...)
	__attribute__((format(printf, 3, 4)));
static inline void warn_at(struct parser *P, const struct token *t, const char *fmt, ...)
{
	if (!P->warn)
		return;
	va_list ap;
	va_start(ap, fmt);
	fprintf(stderr, "%s:%d:%d: warning: ", P->file, t->line, t->col);
	vfprintf(stderr, fmt, ap);
	fputc('\n', stderr);
	va_end(ap);
}

/* Where token t stands in the current file, for the scene model. */
static inline struct src_loc loc_at(const struct parser *P, const struct token *t)
{
	struct src_loc l = { P->file, t->line, t->col };
	return l;
}

/* ---- tokens ------------------------------------------------------------------ */

static inline void next(struct parser *P)
{
	if (P->has_ahead) {
		P->tok = P->ahead;
		P->has_ahead = 0;
	} else {
		lex_next(&P->lx, &P->tok);
	}
}

static inline const struct token *peek(struct parser *P)
{
	if (!P->has_ahead) {
		lex_next(&P->lx, &P->ahead);
		P->has_ahead = 1;
	}
	return &P->ahead;
}

static inline bool is_kw(const struct parser *P, enum keyword kw)
{
	return P->tok.kind == TK_WORD && P->tok.kw == kw;
}

/* Statement keywords: inside any block they mean a ';' is missing. */
static inline bool is_statement_kw(enum keyword kw)
{
	return kw == KW_CAMERA || kw == KW_IMAGE || kw == KW_LIGHT || kw == KW_OBJECT || kw == KW_DEFINE;
}

static inline bool is_prim_kw(enum keyword kw)
{
	switch (kw) {
	case KW_SPHERE: case KW_PLANE: case KW_CYLINDER: case KW_BOX: case KW_TRIANGLE:
	case KW_RAW: case KW_CSG: case KW_DISK: case KW_POLYGON:
		return true;
	default:
		return false;
	}
}

static inline bool is_transform_kw(enum keyword kw)
{
	switch (kw) {
	case KW_SHRINK_X: case KW_SHRINK_Y: case KW_SHRINK_Z: case KW_STRETCH_X: case KW_STRETCH_Y:
	case KW_STRETCH_Z: case KW_TRANSLATE: case KW_X_ROTATE: case KW_Y_ROTATE: case KW_Z_ROTATE:
		return true;
	default:
		return false;
	}
}

/* Words that belong to an object but not inside a primitive's block. */
static inline bool is_object_kw(enum keyword kw)
{
	return is_prim_kw(kw) || kw == KW_MATERIAL || kw == KW_PRIMITIVE;
}

/* ---- values, names, bookkeeping, transforms (parse_base.c) -------------------- */

enum range { R_ANY, R_POS, R_NONNEG };

int parse_num(struct parser *P, const struct token *kw, double *v, enum range r);
int parse_int(struct parser *P, const struct token *kw, int *v, int lo, int hi);
int parse_vec(struct parser *P, const struct token *kw, vec3 *v);
int parse_name(struct parser *P, const struct token *kw, char **out);

/* Copies token text into buf (NUL-terminated; LIM_TOKEN_LEN + 1 bytes). */
static inline void tok_str(const struct token *t, char *buf)
{
	memcpy(buf, t->text, t->len);
	buf[t->len] = '\0';
}

int parse_names_put(struct name_table *t, uint32_t id, const char *(*names)(const struct scene *, uint32_t),
		    const struct scene *s);
static inline const char *mat_name(const struct scene *s, uint32_t i) { return s->materials[i].name; }
static inline const char *def_name(const struct scene *s, uint32_t i) { return s->defines[i].name; }
uint32_t parse_find_material(const struct parser *P, const char *name);
uint32_t parse_find_define(const struct parser *P, const char *name);
int parse_grow_bytes(unsigned char **arr, uint32_t *cap, uint32_t need);
int parse_add_object(struct parser *P, struct scene_object *o, unsigned depth, uint32_t *id,
		     const struct token *at);
int parse_transform(struct parser *P, mat34 *xf, bool *has);

/* ---- objects and materials (parse_object.c) ------------------------------------ */

int parse_sphere_var(struct parser *P, struct prim_sphere *sp);
int parse_cylinder_var(struct parser *P, struct prim_cylinder *cy);
int parse_box_var(struct parser *P, struct prim_box *bx);
char *parse_path_relative(const char *from_file, const char *name);
int parse_object_body(struct parser *P, const struct token *open, uint32_t *id);
int parse_material(struct parser *P, const struct token *open, bool need_named, uint32_t *id);

#endif
