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
#include <fcntl.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/lex.h"
#include "common/raw.h"

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

/* ---- messages --------------------------------------------------------------- */

/* Length of the valid UTF-8 sequence at s[0..n) (1 to 4), or 0 if invalid. */
static size_t utf8_len(const unsigned char *s, size_t n)
{
	size_t k = s[0] < 0x80 ? 1 : s[0] >= 0xc2 && s[0] <= 0xdf ? 2 : s[0] >= 0xe0 && s[0] <= 0xef ? 3
		   : s[0] >= 0xf0 && s[0] <= 0xf4 ? 4 : 0;
	if (k == 0 || k > n)
		return 0;
	for (size_t i = 1; i < k; i++)
		if ((s[i] & 0xc0) != 0x80)
			return 0;
	return k;
}

/*
 * Formats "near 'tok'" (or "near end of file") into buf (n >= NEAR_BUF).
 * At most NEAR_MAX bytes of the word are quoted; bytes that are not valid
 * UTF-8 (binary junk) are shown as \xNN so a message never sends raw bytes
 * to the terminal.
 */
static void near_text(const struct token *t, char *buf, size_t n)
{
	switch (t->kind) {
	case TK_EOF:
		snprintf(buf, n, " near end of file");
		break;
	case TK_WORD: {
		const unsigned char *w = (const unsigned char *)t->text;
		size_t m = t->len < NEAR_MAX ? t->len : NEAR_MAX, o = 0;
		o += (size_t)snprintf(buf + o, n - o, " near '");
		for (size_t i = 0; i < m && o + 8 < n;) {
			size_t k = utf8_len(w + i, t->len - i);
			if (k == 0) {
				o += (size_t)snprintf(buf + o, n - o, "\\x%02x", w[i]);
				i++;
			} else {
				memcpy(buf + o, w + i, k);
				o += k;
				i += k;
			}
		}
		snprintf(buf + o, n - o, "%s'", t->len > m ? "..." : "");
		break;
	}
	case TK_SEMI:
	case TK_LPAREN:
	case TK_RPAREN:
		snprintf(buf, n, " near '%c'", t->text[0]);
		break;
	default:
		buf[0] = '\0';
	}
}

/*
 * Reports an error at token t: "file:line:col: error: MSG near 'tok'"; with
 * near == 0 the "near" part is left out. A lexer error token reports the
 * lexer's message instead. Returns level.
 */
static int vreport(struct parser *P, int level, const struct token *t, int near, const char *fmt, va_list ap)
{
	char msg[600], nt[NEAR_BUF];
	if (t->kind == TK_ERROR) {
		snprintf(msg, sizeof msg, "%s", P->lx.errmsg ? P->lx.errmsg : "invalid input");
		near = 0;
	} else {
		vsnprintf(msg, sizeof msg, fmt, ap);
	}
	nt[0] = '\0';
	if (near)
		near_text(t, nt, sizeof nt);
	return scene_errorf(P->err, level, "%s:%d:%d: error: %s%s", P->file, t->line, t->col, msg, nt);
}

static int err_near(struct parser *P, const struct token *t, const char *fmt, ...)
	__attribute__((format(printf, 3, 4)));
static int err_near(struct parser *P, const struct token *t, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	int r = vreport(P, ERRLEVEL_FATAL, t, 1, fmt, ap);
	va_end(ap);
	return r;
}

static int err_at(struct parser *P, int level, const struct token *t, const char *fmt, ...)
	__attribute__((format(printf, 4, 5)));
static int err_at(struct parser *P, int level, const struct token *t, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	int r = vreport(P, level, t, 0, fmt, ap);
	va_end(ap);
	return r;
}

static void warn_at(struct parser *P, const struct token *t, const char *fmt, ...)
	__attribute__((format(printf, 3, 4)));
static void warn_at(struct parser *P, const struct token *t, const char *fmt, ...)
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
static struct src_loc loc_at(const struct parser *P, const struct token *t)
{
	struct src_loc l = { P->file, t->line, t->col };
	return l;
}

/* ---- tokens ------------------------------------------------------------------ */

static void next(struct parser *P)
{
	if (P->has_ahead) {
		P->tok = P->ahead;
		P->has_ahead = 0;
	} else {
		lex_next(&P->lx, &P->tok);
	}
}

static const struct token *peek(struct parser *P)
{
	if (!P->has_ahead) {
		lex_next(&P->lx, &P->ahead);
		P->has_ahead = 1;
	}
	return &P->ahead;
}

static bool is_kw(const struct parser *P, enum keyword kw)
{
	return P->tok.kind == TK_WORD && P->tok.kw == kw;
}

/* Statement keywords: inside any block they mean a ';' is missing. */
static bool is_statement_kw(enum keyword kw)
{
	return kw == KW_CAMERA || kw == KW_IMAGE || kw == KW_LIGHT || kw == KW_OBJECT || kw == KW_DEFINE;
}

static bool is_prim_kw(enum keyword kw)
{
	switch (kw) {
	case KW_SPHERE: case KW_PLANE: case KW_CYLINDER: case KW_BOX: case KW_TRIANGLE:
	case KW_RAW: case KW_CSG: case KW_DISK: case KW_POLYGON:
		return true;
	default:
		return false;
	}
}

static bool is_transform_kw(enum keyword kw)
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
static bool is_object_kw(enum keyword kw)
{
	return is_prim_kw(kw) || kw == KW_MATERIAL || kw == KW_PRIMITIVE;
}

/*
 * The current token does not belong in the block opened by `open` (spelled
 * open_name). Says why as precisely as it can: end of file or a statement
 * keyword (or one of the `closers`, when given) means the block's ';' is
 * missing; `include` is misplaced; anything else is an unknown verb, and
 * the message ends with what the block takes ("; expected ...") when
 * `expected` is given.
 */
static int unknown(struct parser *P, const char *what, const struct token *open, const char *open_name,
		   bool (*closer)(enum keyword), const char *expected)
{
	const struct token *t = &P->tok;
	if (t->kind == TK_ERROR)
		return err_at(P, ERRLEVEL_FATAL, t, "?");
	if (t->kind == TK_EOF || (t->kind == TK_WORD && (is_statement_kw(t->kw) || (closer && closer(t->kw)))))
		return err_near(P, t, "';' expected (to close '%s' at line %d)", open_name, open->line);
	if (t->kind == TK_WORD && t->kw == KW_INCLUDE)
		return err_at(P, ERRLEVEL_FATAL, t,
			      "'include' inside a statement ('%s' at line %d): only allowed between statements",
			      open_name, open->line);
	if (!expected)
		return err_near(P, t, "%s", what);
	char nt[NEAR_BUF];
	near_text(t, nt, sizeof nt);
	return err_at(P, ERRLEVEL_FATAL, t, "%s%s; expected %s", what, nt, expected);
}

/* ---- values ------------------------------------------------------------------ */

enum range { R_ANY, R_POS, R_NONNEG };

/* Reads the number after keyword kw (the current token is the number). */
static int read_num(struct parser *P, const struct token *kw, double *v, enum range r)
{
	const struct token *t = &P->tok;
	if (t->kind == TK_WORD && t->num == NUM_BAD)
		return err_near(P, t, "malformed number");
	if (t->kind != TK_WORD || t->num != NUM_OK)
		return err_near(P, t, "number expected after '%.*s'", (int)kw->len, kw->text);
	if (r == R_POS && !(t->value > 0))
		return err_near(P, t, "'%.*s' must be greater than 0", (int)kw->len, kw->text);
	if (r == R_NONNEG && !(t->value >= 0))
		return err_near(P, t, "'%.*s' must not be negative", (int)kw->len, kw->text);
	*v = t->value;
	next(P);
	return 0;
}

/* Reads a whole number in [lo, hi] after keyword kw. */
static int read_int(struct parser *P, const struct token *kw, int *v, int lo, int hi)
{
	const struct token *t = &P->tok;
	if (t->kind == TK_WORD && t->num == NUM_BAD)
		return err_near(P, t, "malformed number");
	if (t->kind != TK_WORD || t->num != NUM_OK || fabs(t->value) > 2e9 || t->value != floor(t->value))
		return err_near(P, t, "whole number expected after '%.*s'", (int)kw->len, kw->text);
	if (t->value < lo || t->value > hi)
		return err_near(P, t, "'%.*s' must be between %d and %d", (int)kw->len, kw->text, lo, hi);
	*v = (int)t->value;
	next(P);
	return 0;
}

/* vector -> '(' NUM NUM NUM ')' */
static int read_vec(struct parser *P, const struct token *kw, vec3 *v)
{
	double c[3];
	if (P->tok.kind != TK_LPAREN)
		return err_near(P, &P->tok, "'(' expected (a vector after '%.*s')", (int)kw->len, kw->text);
	struct token open = P->tok;
	next(P);
	for (int i = 0; i < 3; i++) {
		const struct token *t = &P->tok;
		if (t->kind == TK_WORD && t->num == NUM_BAD)
			return err_near(P, t, "malformed number");
		if (t->kind != TK_WORD || t->num != NUM_OK)
			return err_near(P, t, "number expected (3 in the vector after '%.*s')", (int)kw->len,
					kw->text);
		c[i] = t->value;
		next(P);
	}
	if (P->tok.kind != TK_RPAREN)
		return err_near(P, &P->tok, "')' expected (to close '(' at line %d)", open.line);
	next(P);
	*v = v3(c[0], c[1], c[2]);
	return 0;
}

/* Reads a name (any word) after keyword kw into *out (malloc'd: caller frees). */
static int read_name(struct parser *P, const struct token *kw, char **out)
{
	if (P->tok.kind != TK_WORD)
		return err_near(P, &P->tok, "name expected after '%.*s'", (int)kw->len, kw->text);
	char *s = malloc(P->tok.len + 1);
	if (!s)
		return err_at(P, ERRLEVEL_FATAL, &P->tok, "out of memory");
	memcpy(s, P->tok.text, P->tok.len);
	s[P->tok.len] = '\0';
	*out = s;
	next(P);
	return 0;
}

/* Copies token text into buf (NUL-terminated; LIM_TOKEN_LEN + 1 bytes). */
static void tok_str(const struct token *t, char *buf)
{
	memcpy(buf, t->text, t->len);
	buf[t->len] = '\0';
}

/* ---- names -------------------------------------------------------------------- */

static uint32_t name_hash(const char *k)
{
	uint32_t h = 2166136261u;
	for (; *k; k++) {
		unsigned char c = (unsigned char)*k;
		if (c >= 'A' && c <= 'Z')
			c = (unsigned char)(c + ('a' - 'A'));
		h = (h ^ c) * 16777619u;
	}
	return h;
}

/* Looks name up; names(i) gives the name of index i. SCENE_NONE when absent. */
static uint32_t names_find(const struct name_table *t, const char *name, const char *(*names)(const struct scene *, uint32_t),
			   const struct scene *s)
{
	if (!t->cap)
		return SCENE_NONE;
	for (uint32_t h = name_hash(name) & (t->cap - 1);; h = (h + 1) & (t->cap - 1)) {
		uint32_t v = t->slot[h];
		if (!v)
			return SCENE_NONE;
		if (strcasecmp(names(s, v - 1), name) == 0)
			return v - 1;
	}
}

/* Records index id under its name (replacing an older entry). 0 or -1 (OOM). */
static int names_put(struct name_table *t, uint32_t id, const char *(*names)(const struct scene *, uint32_t),
		     const struct scene *s)
{
	if ((t->n + 1) * 2 > t->cap) {
		uint32_t nc = t->cap ? t->cap * 2 : 64;
		uint32_t *ns = calloc(nc, sizeof *ns);
		if (!ns)
			return -1;
		for (uint32_t i = 0; i < t->cap; i++) {
			uint32_t v = t->slot[i];
			if (!v)
				continue;
			uint32_t h = name_hash(names(s, v - 1)) & (nc - 1);
			while (ns[h])
				h = (h + 1) & (nc - 1);
			ns[h] = v;
		}
		free(t->slot);
		t->slot = ns;
		t->cap = nc;
	}
	const char *name = names(s, id);
	uint32_t h = name_hash(name) & (t->cap - 1);
	while (t->slot[h] && strcasecmp(names(s, t->slot[h] - 1), name) != 0)
		h = (h + 1) & (t->cap - 1);
	if (!t->slot[h])
		t->n++;
	t->slot[h] = id + 1;
	return 0;
}

static const char *mat_name(const struct scene *s, uint32_t i) { return s->materials[i].name; }
static const char *def_name(const struct scene *s, uint32_t i) { return s->defines[i].name; }

static uint32_t find_material(const struct parser *P, const char *name)
{
	return names_find(&P->mat_names, name, mat_name, P->s);
}

static uint32_t find_define(const struct parser *P, const char *name)
{
	return names_find(&P->def_names, name, def_name, P->s);
}

/* ---- bookkeeping ------------------------------------------------------------ */

static int grow_bytes(unsigned char **arr, uint32_t *cap, uint32_t need)
{
	if (need <= *cap)
		return 0;
	uint32_t nc = *cap ? *cap : 64;
	while (nc < need)
		nc = nc > UINT32_MAX / 2 ? need : nc * 2;
	unsigned char *p = realloc(*arr, nc);
	if (!p)
		return -1;
	memset(p + *cap, 0, nc - *cap);
	*arr = p;
	*cap = nc;
	return 0;
}

/* Adds object o (see scene_add_object for ownership) and records its define depth. */
static int add_object(struct parser *P, struct scene_object *o, unsigned depth, uint32_t *id,
		      const struct token *at)
{
	TRY(scene_add_object(P->s, o, id, P->err));
	if (grow_bytes(&P->obj_depth, &P->cap_obj_depth, P->s->n_objects) < 0)
		return err_at(P, ERRLEVEL_FATAL, at, "out of memory");
	P->obj_depth[*id] = (unsigned char)depth;
	return 0;
}

/* ---- transforms ------------------------------------------------------------ */

/*
 * transform -> (SHRINK-X | SHRINK-Y | SHRINK-Z | STRETCH-X | STRETCH-Y | STRETCH-Z
 *               | X-ROTATE | Y-ROTATE | Z-ROTATE) NUM | TRANSLATE vector
 * Composes onto *xf in written order. NOT_MINE when the word is no transform.
 */
static int parse_transform(struct parser *P, mat34 *xf, bool *has)
{
	if (P->tok.kind != TK_WORD || !is_transform_kw(P->tok.kw))
		return NOT_MINE;
	struct token kw = P->tok;
	enum xform_op op;
	int axis = 0;
	double amount = 0;
	vec3 v = v3(0, 0, 0);
	next(P);
	switch (kw.kw) {
	case KW_SHRINK_X: case KW_SHRINK_Y: case KW_SHRINK_Z:
		op = XF_SHRINK;
		axis = kw.kw - KW_SHRINK_X;
		break;
	case KW_STRETCH_X: case KW_STRETCH_Y: case KW_STRETCH_Z:
		op = XF_STRETCH;
		axis = kw.kw - KW_STRETCH_X;
		break;
	case KW_X_ROTATE:
		op = XF_ROTATE, axis = 0;
		break;
	case KW_Y_ROTATE:
		op = XF_ROTATE, axis = 1;
		break;
	case KW_Z_ROTATE:
		op = XF_ROTATE, axis = 2;
		break;
	default:
		op = XF_TRANSLATE;
		break;
	}
	if (op == XF_TRANSLATE)
		TRY(read_vec(P, &kw, &v));
	else
		TRY(read_num(P, &kw, &amount, R_ANY));
	if (!scene_xform_op(xf, op, axis, amount, v))
		return err_at(P, ERRLEVEL_FATAL, &kw, "'%s' by 0 would flatten the object",
			      lex_keyword_name(kw.kw));
	/* the composed transform must stay finite and invertible (the builder
	 * checks it too, but here the message can name the transform) */
	mat34 inv;
	bool finite = true;
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 4; j++)
			finite = finite && isfinite(xf->m[i][j]);
	if (!finite || !m34_invert(xf, &inv))
		return err_at(P, ERRLEVEL_FATAL, &kw, "'%s' makes the object's transform overflow or collapse",
			      lex_keyword_name(kw.kw));
	*has = true;
	return 0;
}

/* ---- primitive variables ------------------------------------------------------ */

/* spherevar -> CENTRE vector | RADIUS NUM | POLE vector | EQUATOR vector */
static int sphere_var(struct parser *P, struct prim_sphere *sp)
{
	struct token kw = P->tok;
	switch (kw.kw) {
	case KW_CENTRE: next(P); return read_vec(P, &kw, &sp->centre);
	case KW_RADIUS: next(P); return read_num(P, &kw, &sp->radius, R_POS);
	case KW_POLE:
		next(P);
		TRY(read_vec(P, &kw, &sp->pole));
		if (v3_len(sp->pole) == 0)
			return err_at(P, ERRLEVEL_FATAL, &kw, "'pole' must not be (0 0 0)");
		return 0;
	case KW_EQUATOR: next(P); return read_vec(P, &kw, &sp->equator);
	default: return NOT_MINE;
	}
}

/* cylvar -> FROM vector | TO vector | RADIUS NUM | CAPPED */
static int cylinder_var(struct parser *P, struct prim_cylinder *cy)
{
	struct token kw = P->tok;
	switch (kw.kw) {
	case KW_FROM: next(P); return read_vec(P, &kw, &cy->from);
	case KW_TO: next(P); return read_vec(P, &kw, &cy->to);
	case KW_RADIUS: next(P); return read_num(P, &kw, &cy->radius, R_POS);
	case KW_CAPPED: next(P); cy->capped = true; return 0;
	default: return NOT_MINE;
	}
}

/* boxvar -> A vector | B vector */
static int box_var(struct parser *P, struct prim_box *bx)
{
	struct token kw = P->tok;
	switch (kw.kw) {
	case KW_A: next(P); return read_vec(P, &kw, &bx->a);
	case KW_B: next(P); return read_vec(P, &kw, &bx->b);
	default: return NOT_MINE;
	}
}

/* Everything one primitive block collects before the object is built. */
struct primctx {
	struct scene_object o;
	unsigned axes;             /* plane: 1 = x-axis written, 2 = y-axis written */
	unsigned normals;          /* triangle: bit per normal-a/b/c written */
	struct token file_tok;     /* raw: the file name token */
	bool have_file;
	struct scene_mesh mesh;    /* raw: options (weld, smooth, rotation, at) */
	vec3 *pts;                 /* polygon: all points so far (owned) */
	uint32_t n_pts, cap_pts;
	uint32_t *starts;          /* polygon: contour starts so far (owned) */
	uint32_t n_contours, cap_contours;
};

static void primctx_free(struct primctx *c)
{
	free(c->pts);
	free(c->starts);
	c->pts = NULL;
	c->starts = NULL;
	if (c->o.kind == PRIM_POLYGON) {
		free(c->o.u.polygon.points);
		free(c->o.u.polygon.contour_start);
		c->o.u.polygon.points = NULL;
		c->o.u.polygon.contour_start = NULL;
	}
}

/* planevar -> POSITION vector | NORMAL vector | X-AXIS vector | Y-AXIS vector
 *           | RADIUS NUM (disk only) */
static int plane_var(struct parser *P, struct primctx *c)
{
	struct token kw = P->tok;
	struct prim_plane *pl = &c->o.u.plane;
	switch (kw.kw) {
	case KW_POSITION: next(P); return read_vec(P, &kw, &pl->position);
	case KW_NORMAL:
		next(P);
		TRY(read_vec(P, &kw, &pl->normal));
		if (v3_len(pl->normal) == 0)
			return err_at(P, ERRLEVEL_FATAL, &kw, "'normal' must not be (0 0 0)");
		return 0;
	case KW_X_AXIS: next(P); c->axes |= 1; return read_vec(P, &kw, &pl->x_axis);
	case KW_Y_AXIS: next(P); c->axes |= 2; return read_vec(P, &kw, &pl->y_axis);
	case KW_RADIUS:
		if (c->o.kind != PRIM_DISK)
			return NOT_MINE;
		next(P);
		return read_num(P, &kw, &pl->radius, R_POS);
	default: return NOT_MINE;
	}
}

/* trivar -> A vector | B vector | C vector | NORMAL-A vector | NORMAL-B vector | NORMAL-C vector */
static int triangle_var(struct parser *P, struct primctx *c)
{
	struct token kw = P->tok;
	struct prim_triangle *tr = &c->o.u.triangle;
	switch (kw.kw) {
	case KW_A: next(P); return read_vec(P, &kw, &tr->a);
	case KW_B: next(P); return read_vec(P, &kw, &tr->b);
	case KW_C: next(P); return read_vec(P, &kw, &tr->c);
	case KW_NORMAL_A: next(P); c->normals |= 1; return read_vec(P, &kw, &tr->na);
	case KW_NORMAL_B: next(P); c->normals |= 2; return read_vec(P, &kw, &tr->nb);
	case KW_NORMAL_C: next(P); c->normals |= 4; return read_vec(P, &kw, &tr->nc);
	default: return NOT_MINE;
	}
}

/* rawvar -> FILE NAME | WELD NUM | SMOOTH | X-ROTATION NUM | Y-ROTATION NUM
 *         | Z-ROTATION NUM | AT vector */
static int raw_var(struct parser *P, struct primctx *c)
{
	struct token kw = P->tok;
	struct scene_mesh *m = &c->mesh;
	switch (kw.kw) {
	case KW_FILE:
		next(P);
		if (P->tok.kind != TK_WORD)
			return err_near(P, &P->tok, "file name expected after 'file'");
		c->file_tok = P->tok;
		c->have_file = true;
		next(P);
		return 0;
	case KW_WELD: next(P); return read_num(P, &kw, &m->weld, R_NONNEG);
	case KW_SMOOTH: next(P); m->smooth = true; return 0;
	case KW_X_ROTATION: next(P); return read_num(P, &kw, &m->rotation.x, R_ANY);
	case KW_Y_ROTATION: next(P); return read_num(P, &kw, &m->rotation.y, R_ANY);
	case KW_Z_ROTATION: next(P); return read_num(P, &kw, &m->rotation.z, R_ANY);
	case KW_AT: next(P); return read_vec(P, &kw, &m->at);
	default: return NOT_MINE;
	}
}

/* contour -> CONTOUR vector vector vector { vector } ';' */
static int polygon_var(struct parser *P, struct primctx *c)
{
	if (!is_kw(P, KW_CONTOUR))
		return NOT_MINE;
	struct token kw = P->tok;
	next(P);
	if (c->n_contours >= LIM_POLY_CONTOURS)
		return err_at(P, ERRLEVEL_FATAL, &kw, "too many contours (at most %u)", LIM_POLY_CONTOURS);
	if (c->n_contours + 2 > c->cap_contours) {
		uint32_t nc = c->cap_contours ? c->cap_contours * 2 : 8;
		uint32_t *p = realloc(c->starts, nc * sizeof *p);
		if (!p)
			return err_at(P, ERRLEVEL_FATAL, &kw, "out of memory");
		c->starts = p;
		c->cap_contours = nc;
	}
	uint32_t first = c->n_pts;
	while (P->tok.kind == TK_LPAREN) {
		if (c->n_pts >= LIM_POLY_VERTICES)
			return err_near(P, &P->tok, "too many polygon vertices (at most %u)", LIM_POLY_VERTICES);
		if (c->n_pts == c->cap_pts) {
			uint32_t nc = c->cap_pts ? c->cap_pts * 2 : 16;
			vec3 *p = realloc(c->pts, nc * sizeof *p);
			if (!p)
				return err_at(P, ERRLEVEL_FATAL, &kw, "out of memory");
			c->pts = p;
			c->cap_pts = nc;
		}
		TRY(read_vec(P, &kw, &c->pts[c->n_pts]));
		c->n_pts++;
	}
	if (P->tok.kind != TK_SEMI)
		return err_near(P, &P->tok, "vertex '(x y z)' or ';' expected (to close 'contour' at line %d)",
				kw.line);
	if (c->n_pts - first < 3)
		return err_near(P, &P->tok, "a contour needs at least 3 vertices (this one has %u)",
				c->n_pts - first);
	next(P);
	c->starts[c->n_contours++] = first;
	return 0;
}

/* Moves the collected contours into the polygon; checks they are coplanar. */
static int polygon_finish(struct parser *P, struct primctx *c, const struct token *at)
{
	if (c->n_contours == 0)
		return err_near(P, at, "a polygon needs at least one 'contour'");
	c->starts[c->n_contours] = c->n_pts;
	/* Newell normal of the first contour, then every point's distance to its plane */
	vec3 nrm = v3(0, 0, 0), lo = c->pts[0], hi = c->pts[0];
	for (uint32_t i = c->starts[0]; i < c->starts[1]; i++) {
		vec3 a = c->pts[i], b = c->pts[i + 1 < c->starts[1] ? i + 1 : c->starts[0]];
		nrm.x += (a.y - b.y) * (a.z + b.z);
		nrm.y += (a.z - b.z) * (a.x + b.x);
		nrm.z += (a.x - b.x) * (a.y + b.y);
	}
	for (uint32_t i = 0; i < c->n_pts; i++) {
		if (!v3_finite(c->pts[i]))
			return err_near(P, at, "polygon vertex out of range");
		lo = v3_min(lo, c->pts[i]);
		hi = v3_max(hi, c->pts[i]);
	}
	double ext = v3_len(v3_sub(hi, lo)), nl = v3_len(nrm);
	if (!(nl > 0) || !(nl > 1e-12 * ext * ext))
		return err_near(P, at, "the polygon's first contour has no area");
	nrm = v3_scale(nrm, 1.0 / nl);
	double d0 = v3_dot(nrm, c->pts[0]);
	for (uint32_t i = 0; i < c->n_pts; i++)
		if (fabs(v3_dot(nrm, c->pts[i]) - d0) > POLY_PLANE_TOL * ext)
			return err_near(P, at, "polygon contours are not in one plane");
	c->o.u.polygon.n_contours = c->n_contours;
	c->o.u.polygon.n_points = c->n_pts;
	c->o.u.polygon.contour_start = c->starts;
	c->o.u.polygon.points = c->pts;
	c->starts = NULL;
	c->pts = NULL;
	return 0;
}

/* Joins a name written in the current file to that file's directory. */
static char *path_relative(const char *from_file, const char *name)
{
	const char *slash = strrchr(from_file, '/');
	if (name[0] == '/' || !slash) {
		char *r = strdup(name);
		return r;
	}
	size_t dl = (size_t)(slash - from_file) + 1, nl = strlen(name);
	char *r = malloc(dl + nl + 1);
	if (!r)
		return NULL;
	memcpy(r, from_file, dl);
	memcpy(r + dl, name, nl + 1);
	return r;
}

/* Loads the raw mesh the block named (once per file and options) into o. */
static int raw_finish(struct parser *P, struct primctx *c, const struct token *at)
{
	char name[LIM_TOKEN_LEN + 1];
	if (!c->have_file)
		return err_near(P, at, "a raw object needs 'file NAME'");
	if (!P->allow_files)
		return err_at(P, ERRLEVEL_FATAL, &c->file_tok, "raw files cannot be read here");
	tok_str(&c->file_tok, name);
	char *path = path_relative(P->file, name);
	if (!path)
		return err_at(P, ERRLEVEL_FATAL, &c->file_tok, "out of memory");
	struct scene_mesh *m = &c->mesh;
	for (uint32_t i = 0; i < P->s->n_meshes; i++) {
		const struct scene_mesh *e = &P->s->meshes[i];
		if (P->mesh_path[i] && strcmp(P->mesh_path[i], path) == 0 && e->weld == m->weld &&
		    e->smooth == m->smooth && e->rotation.x == m->rotation.x && e->rotation.y == m->rotation.y &&
		    e->rotation.z == m->rotation.z && e->at.x == m->at.x && e->at.y == m->at.y &&
		    e->at.z == m->at.z) {
			free(path);
			c->o.u.raw.mesh = i;
			return 0;
		}
	}
	int fd = open(path, O_RDONLY);
	if (fd < 0) {
		int e = errno;
		free(path);
		return err_at(P, ERRLEVEL_FATAL, &c->file_tok, "unable to open raw file '%s': %s", name,
			      strerror(e));
	}
	close(fd);
	m->file = path; /* messages from raw_load name the file as found */
	if (raw_load(path, m, P->err)) {
		free(m->file);
		m->file = NULL;
		return P->err->level ? P->err->level : ERRLEVEL_FATAL;
	}
	uint32_t id;
	if (scene_add_mesh(P->s, m, &id, P->err)) /* the scene owns m's arrays either way */
		return P->err->level;
	char *keep = strdup(path); /* path itself is the mesh's file name now */
	if (!keep)
		return err_at(P, ERRLEVEL_FATAL, &c->file_tok, "out of memory");
	if (P->s->n_meshes > P->cap_mesh_path) {
		uint32_t nc = P->cap_mesh_path ? P->cap_mesh_path * 2 : 16;
		char **np = realloc(P->mesh_path, nc * sizeof *np);
		if (!np) {
			free(keep);
			return err_at(P, ERRLEVEL_FATAL, &c->file_tok, "out of memory");
		}
		for (uint32_t i = P->cap_mesh_path; i < nc; i++)
			np[i] = NULL;
		P->mesh_path = np;
		P->cap_mesh_path = nc;
	}
	P->mesh_path[id] = keep;
	c->o.u.raw.mesh = id;
	return 0;
}

/* ---- objects ------------------------------------------------------------------- */

static int parse_object_body(struct parser *P, const struct token *open, uint32_t *id);
static int parse_material(struct parser *P, const struct token *open, bool need_named, uint32_t *id);

static bool closer_in_prim(enum keyword kw) { return is_object_kw(kw); }

/* What a primitive's block takes, for messages. */
static const char *prim_expected(enum prim_kind k)
{
	switch (k) {
	case PRIM_SPHERE: return "centre, radius, pole, equator, a transform or ';'";
	case PRIM_PLANE: return "position, normal, x-axis, y-axis, a transform or ';'";
	case PRIM_DISK: return "position, normal, x-axis, y-axis, radius, a transform or ';'";
	case PRIM_CYLINDER: return "from, to, radius, capped, a transform or ';'";
	case PRIM_BOX: return "a, b, a transform or ';'";
	case PRIM_TRIANGLE: return "a, b, c, normal-a, normal-b, normal-c, a transform or ';'";
	case PRIM_RAW: return "file, weld, smooth, x-rotation, y-rotation, z-rotation, at, a transform or ';'";
	case PRIM_POLYGON: return "contour, a transform or ';'";
	default: return NULL;
	}
}

/*
 * csg -> CSG { OPERAND1 OBJECT body | OPERAND2 OBJECT body
 *            | UNION | INTERSECT | SUBTRACT } ';'
 * (body is an object's body with its own closing ';'). Each once; all three
 * required. Fills c->o (kind PRIM_CSG) and *depth.
 */
static int parse_csg(struct parser *P, struct primctx *c, const struct token *open, unsigned *depth)
{
	struct prim_csg *g = &c->o.u.csg;
	struct token optok = { 0 };
	bool have_op = false;
	if (++P->csg_depth > LIM_CSG_DEPTH)
		return err_at(P, ERRLEVEL_FATAL, open, "csg nested more than %d deep", LIM_CSG_DEPTH);
	next(P);
	for (;;) {
		struct token kw = P->tok;
		if (kw.kind == TK_SEMI)
			break;
		if (kw.kind == TK_WORD && (kw.kw == KW_OPERAND1 || kw.kw == KW_OPERAND2)) {
			uint32_t *slot = kw.kw == KW_OPERAND1 ? &g->operand1 : &g->operand2;
			if (*slot != SCENE_NONE)
				return err_near(P, &kw, "'%s' given twice in one csg", lex_keyword_name(kw.kw));
			next(P);
			if (!is_kw(P, KW_OBJECT))
				return err_near(P, &P->tok, "'object' expected after '%s'", lex_keyword_name(kw.kw));
			struct token obj = P->tok;
			next(P);
			TRY(parse_object_body(P, &obj, slot));
			if (P->obj_depth[*slot] > *depth)
				*depth = P->obj_depth[*slot];
			continue;
		}
		if (kw.kind == TK_WORD && (kw.kw == KW_UNION || kw.kw == KW_INTERSECT || kw.kw == KW_SUBTRACT)) {
			if (have_op)
				return err_near(P, &kw, "a csg takes one operation ('%s' at line %d)",
						lex_keyword_name(optok.kw), optok.line);
			optok = kw;
			have_op = true;
			g->op = kw.kw == KW_UNION ? CSG_UNION : kw.kw == KW_INTERSECT ? CSG_INTERSECT : CSG_SUBTRACT;
			next(P);
			continue;
		}
		return unknown(P, "unknown verb in csg", open, "csg", closer_in_prim,
			       "operand1, operand2, union, intersect, subtract or ';'");
	}
	if (g->operand1 == SCENE_NONE || g->operand2 == SCENE_NONE || !have_op)
		return err_near(P, &P->tok, "a csg needs 'operand1 object ... ;', 'operand2 object ... ;' and "
					    "one of union, intersect, subtract");
	next(P);
	P->csg_depth--;
	return 0;
}

/*
 * prim -> SPHERE { spherevar | transform } ';' | PLANE { planevar | transform } ';'
 *       | CYLINDER ... | BOX ... | TRIANGLE ... | RAW ... | DISK ... | POLYGON { contour } ';'
 *       | csg
 * Current token: the primitive's keyword. Fills c->o.
 */
static int parse_prim(struct parser *P, struct primctx *c, mat34 *xf, bool *has_xf, unsigned *depth)
{
	struct token open = P->tok;
	const char *name = lex_keyword_name(open.kw);
	static const enum prim_kind kinds[] = {
		[KW_SPHERE] = PRIM_SPHERE, [KW_PLANE] = PRIM_PLANE, [KW_CYLINDER] = PRIM_CYLINDER,
		[KW_BOX] = PRIM_BOX, [KW_TRIANGLE] = PRIM_TRIANGLE, [KW_RAW] = PRIM_RAW,
		[KW_CSG] = PRIM_CSG, [KW_DISK] = PRIM_DISK, [KW_POLYGON] = PRIM_POLYGON,
	};
	scene_object_defaults(&c->o, kinds[open.kw]);
	c->o.loc = loc_at(P, &open);
	if (c->o.kind == PRIM_CSG)
		return parse_csg(P, c, &open, depth);
	if (c->o.kind == PRIM_RAW) {
		memset(&c->mesh, 0, sizeof c->mesh);
		c->mesh.weld = 0.00001;
	}
	next(P);
	for (;;) {
		if (P->tok.kind == TK_SEMI)
			break;
		int r = NOT_MINE;
		if (P->tok.kind == TK_WORD) {
			switch (c->o.kind) {
			case PRIM_SPHERE: r = sphere_var(P, &c->o.u.sphere); break;
			case PRIM_PLANE: case PRIM_DISK: r = plane_var(P, c); break;
			case PRIM_CYLINDER: r = cylinder_var(P, &c->o.u.cylinder); break;
			case PRIM_BOX: r = box_var(P, &c->o.u.box); break;
			case PRIM_TRIANGLE: r = triangle_var(P, c); break;
			case PRIM_RAW: r = raw_var(P, c); break;
			case PRIM_POLYGON: r = polygon_var(P, c); break;
			default: break;
			}
			if (r == NOT_MINE)
				r = parse_transform(P, xf, has_xf);
		}
		if (r == NOT_MINE) {
			char what[64];
			snprintf(what, sizeof what, "unknown verb in object (%s)", name);
			return unknown(P, what, &open, name, closer_in_prim, prim_expected(c->o.kind));
		}
		if (r)
			return r;
	}
	struct token semi = P->tok;
	switch (c->o.kind) {
	case PRIM_PLANE:
	case PRIM_DISK: {
		struct prim_plane *pl = &c->o.u.plane;
		if (c->axes == 1)
			pl->y_axis = v3_cross(pl->normal, pl->x_axis);
		else if (c->axes == 2)
			pl->x_axis = v3_cross(pl->y_axis, pl->normal);
		pl->has_axes = c->axes != 0;
		if (pl->has_axes && !(fabs(v3_dot(v3_cross(pl->x_axis, pl->y_axis), pl->normal)) > 0))
			return err_near(P, &semi, "x-axis, y-axis and normal of a %s must not lie in one plane", name);
		break;
	}
	case PRIM_CYLINDER:
		if (v3_len(v3_sub(c->o.u.cylinder.to, c->o.u.cylinder.from)) == 0)
			return err_near(P, &semi, "a cylinder's 'from' and 'to' must differ");
		break;
	case PRIM_TRIANGLE:
		if (c->normals != 0 && c->normals != 7)
			return err_near(P, &semi, "a rounded triangle needs all of normal-a, normal-b and normal-c");
		c->o.u.triangle.has_normals = c->normals == 7;
		break;
	case PRIM_POLYGON:
		TRY(polygon_finish(P, c, &semi));
		break;
	case PRIM_RAW:
		TRY(raw_finish(P, c, &semi));
		break;
	default:
		break;
	}
	next(P);
	return 0;
}

/*
 * reference -> NAME { transform | MATERIAL material } ';'
 * A use of a defined object (a "complex reference"). Current token: NAME.
 */
static int parse_reference(struct parser *P, struct primctx *c, mat34 *xf, bool *has_xf, unsigned *depth,
			   uint32_t *mat, struct token *mat_tok)
{
	struct token open = P->tok;
	char name[LIM_TOKEN_LEN + 1];
	tok_str(&open, name);
	uint32_t d = find_define(P, name);
	if (d == SCENE_NONE) {
		if (P->defining && strcasecmp(P->defining, name) == 0)
			return err_at(P, ERRLEVEL_FATAL, &open,
				      "undefined complex object '%s': its definition (line %d) is not closed "
				      "yet (';' missing?)", name, P->defining_line);
		const struct token *nx = peek(P);
		if (nx->kind == TK_SEMI || (nx->kind == TK_WORD && (is_transform_kw(nx->kw) || nx->kw == KW_MATERIAL)))
			return err_at(P, ERRLEVEL_FATAL, &open, "undefined complex object '%s'", name);
		return err_near(P, &open, "unknown verb in object (not a primitive or a defined object)");
	}
	scene_object_defaults(&c->o, PRIM_INSTANCE);
	c->o.u.instance.define = d;
	c->o.loc = loc_at(P, &open);
	*depth = P->def_depth[d];
	next(P);
	for (;;) {
		if (P->tok.kind == TK_SEMI)
			break;
		int r = NOT_MINE;
		if (is_kw(P, KW_MATERIAL)) {
			if (*mat != SCENE_NONE)
				return err_near(P, &P->tok, "an object takes one material (the first is at line %d)",
						mat_tok->line);
			*mat_tok = P->tok;
			next(P);
			r = parse_material(P, mat_tok, false, mat);
		} else if (P->tok.kind == TK_WORD) {
			r = parse_transform(P, xf, has_xf);
		}
		if (r == NOT_MINE)
			return unknown(P, "unknown verb in complex reference", &open, name, closer_in_prim,
				       "a transform, material or ';'");
		if (r)
			return r;
	}
	next(P);
	return 0;
}

/*
 * object -> OBJECT body
 * body -> { [PRIMITIVE] (prim | reference) | transform | MATERIAL material } ';'
 * One primitive (or reference) and at most one material per object. Current
 * token: the first after OBJECT (open is the OBJECT token). Adds the object
 * (not as a root) and returns its index in *id.
 */
static int parse_object_body(struct parser *P, const struct token *open, uint32_t *id)
{
	struct primctx c;
	memset(&c, 0, sizeof c);
	mat34 xf = m34_identity();
	bool has_xf = false, have_prim = false;
	uint32_t mat = SCENE_NONE;
	struct token mat_tok = { 0 }, prim_tok = { 0 };
	unsigned depth = 0;
	int rc = 0;
	for (;;) {
		const struct token *t = &P->tok;
		if (t->kind == TK_SEMI)
			break;
		if (t->kind != TK_WORD) {
			rc = unknown(P, "unknown verb in object", open, "object", NULL,
				     have_prim ? "a transform, material or ';'"
					       : "a primitive, a defined object's name, a transform, material or ';'");
			goto fail;
		}
		if (t->kw == KW_PRIMITIVE) {
			if (have_prim) {
				rc = err_near(P, t, "';' expected (to close 'object' at line %d)", open->line);
				goto fail;
			}
			next(P);
			if (P->tok.kind != TK_WORD || (P->tok.kw != KW_NONE && !is_prim_kw(P->tok.kw))) {
				rc = err_near(P, &P->tok, "primitive or defined object expected after 'primitive'");
				goto fail;
			}
			continue;
		}
		if (is_prim_kw(t->kw) || (!have_prim && t->num == NUM_NO && !is_object_kw(t->kw) &&
					  !is_transform_kw(t->kw))) {
			if (have_prim) {
				rc = err_near(P, t, "';' expected (to close 'object' at line %d)", open->line);
				goto fail;
			}
			prim_tok = *t;
			have_prim = true;
			if (!is_prim_kw(t->kw))
				rc = parse_reference(P, &c, &xf, &has_xf, &depth, &mat, &mat_tok);
			else
				rc = parse_prim(P, &c, &xf, &has_xf, &depth);
			if (rc)
				goto fail;
			continue;
		}
		if (t->kw == KW_MATERIAL) {
			if (mat != SCENE_NONE) {
				rc = err_near(P, t, "an object takes one material (the first is at line %d)", mat_tok.line);
				goto fail;
			}
			mat_tok = *t;
			next(P);
			if ((rc = parse_material(P, &mat_tok, false, &mat)) != 0)
				goto fail;
			continue;
		}
		rc = parse_transform(P, &xf, &has_xf);
		if (rc == NOT_MINE) {
			rc = unknown(P, "unknown verb in object", open, "object", NULL,
				     have_prim ? "a transform, material or ';'"
					       : "a primitive, a defined object's name, a transform, material or ';'");
			goto fail;
		}
		if (rc)
			goto fail;
	}
	if (!have_prim) {
		rc = err_near(P, &P->tok, "an object needs a primitive (sphere, plane, cylinder, box, triangle, "
					  "raw, csg, disk, polygon) or a defined object's name");
		goto fail;
	}
	(void)prim_tok;
	c.o.xform = xf;
	c.o.has_xform = has_xf;
	c.o.material = mat;
	rc = add_object(P, &c.o, depth, id, open);
	memset(&c.o, 0, sizeof c.o); /* the scene owns the polygon arrays now, or freed them */
	primctx_free(&c);
	if (rc)
		return rc;
	next(P);
	return 0;
fail:
	primctx_free(&c);
	return rc;
}

/* ---- materials and shaders --------------------------------------------------------- */

/* matarg -> CALLED NAME | MATERIAL material   (a shader's material argument) */
static int parse_matarg(struct parser *P, const struct token *kw, uint32_t *id)
{
	if (is_kw(P, KW_CALLED)) {
		struct token called = P->tok;
		next(P);
		if (P->tok.kind != TK_WORD)
			return err_near(P, &P->tok, "material name expected after 'called'");
		char name[LIM_TOKEN_LEN + 1];
		tok_str(&P->tok, name);
		*id = find_material(P, name);
		if (*id == SCENE_NONE)
			return err_at(P, ERRLEVEL_FATAL, &P->tok, "undefined material '%s'", name);
		(void)called;
		next(P);
		return 0;
	}
	if (is_kw(P, KW_MATERIAL)) {
		struct token open = P->tok;
		next(P);
		return parse_material(P, &open, false, id);
	}
	return err_near(P, &P->tok, "'material ... ;' or 'called NAME' expected after '%.*s'", (int)kw->len,
			kw->text);
}

/*
 * fadelist -> { NUM (vector | matarg) } ending with the entry whose NUM is 0
 * Current token: the first distance. Appends to sh->fades (owned by sh).
 */
static int parse_fades_list(struct parser *P, const struct token *kw, struct scene_shader *sh, bool materials)
{
	double total = 0;
	for (;;) {
		if (sh->n_fades >= LIM_FADES_ENTRIES)
			return err_near(P, &P->tok, "too many fades entries (at most %d)", LIM_FADES_ENTRIES);
		struct fades_entry e = { 0, v3(0, 0, 0), SCENE_NONE };
		struct token dtok = P->tok;
		if (dtok.kind != TK_WORD || dtok.num == NUM_NO)
			return err_near(P, &dtok, "distance expected in the '%.*s' list (it ends with an entry "
						  "whose distance is 0)", (int)kw->len, kw->text);
		TRY(read_num(P, kw, &e.dist, R_NONNEG));
		if (materials)
			TRY(parse_matarg(P, kw, &e.material));
		else
			TRY(read_vec(P, &dtok, &e.colour));
		struct fades_entry *nf = realloc(sh->fades, (sh->n_fades + 1) * sizeof *nf);
		if (!nf)
			return err_at(P, ERRLEVEL_FATAL, &dtok, "out of memory");
		sh->fades = nf;
		sh->fades[sh->n_fades++] = e;
		total += e.dist;
		if (e.dist == 0)
			break;
	}
	if (!(total > 0) || !isfinite(total))
		return err_at(P, ERRLEVEL_FATAL, kw, "a fades list needs a positive distance before its closing 0");
	return 0;
}

/* What a shader's block takes, for messages. */
static const char *shader_expected(enum shader_kind k)
{
	switch (k) {
	case SHADER_BRICKS: return "mortar, brick, size or ';'";
	case SHADER_TILES: return "face, grout, tile-width, grout-width, size or ';'";
	case SHADER_CHEQUERS: return "material-a, material-b, size or ';'";
	case SHADER_BUMPY: return "size, terms, xsize, ysize, zsize, material, saturation, depth or ';'";
	case SHADER_NOISE: return "size, material, variance, colour or ';'";
	case SHADER_FADES: return "axis, colours, materials or ';'";
	case SHADER_TURB3D: return "terms, depth, size, material or ';'";
	default: return NULL;
	}
}

/* What a material block takes, for messages. */
#define MATERIAL_EXPECTED                                                                          \
	"called, named, colour, diff-colour, spec-colour, tran-colour, diffuse-reflection, "       \
	"specular-reflection, specular-power, reflection, transparency, refractive-index, a shader " \
	"(bricks, tiles, chequers, bumpy, noise, fades, turb3d) or ';'"

static bool closer_in_shader(enum keyword kw)
{
	switch (kw) {
	case KW_BRICKS: case KW_TILES: case KW_CHEQUERS: case KW_BUMPY: case KW_NOISE: case KW_FADES:
	case KW_TURB3D: case KW_CALLED: case KW_NAMED: case KW_COLOUR: case KW_DIFF_COLOUR: case KW_SPEC_COLOUR:
	case KW_TRAN_COLOUR: case KW_DIFFUSE_REFLECTION: case KW_SPECULAR_REFLECTION:
	case KW_SPECULAR_POWER: case KW_REFLECTION: case KW_TRANSPARENCY: case KW_REFRACTIVE_INDEX:
		return true;
	default:
		return false;
	}
}

/*
 * shader -> BRICKS { MORTAR matarg | BRICK matarg | SIZE NUM } ';'
 *         | TILES { FACE matarg | GROUT matarg | TILE-WIDTH NUM | GROUT-WIDTH NUM | SIZE NUM } ';'
 *         | CHEQUERS { MATERIAL-A matarg | MATERIAL-B matarg | SIZE NUM } ';'
 *         | BUMPY { SIZE NUM | TERMS INT | XSIZE NUM | YSIZE NUM | ZSIZE NUM
 *                 | MATERIAL matarg | SATURATION NUM | DEPTH NUM } ';'
 *         | NOISE { SIZE NUM | MATERIAL matarg | VARIANCE NUM | COLOUR vector } ';'
 *         | FADES { AXIS vector | MATERIALS fadelist | COLOURS fadelist } ';'
 *         | TURB3D { TERMS INT | DEPTH NUM | SIZE NUM | MATERIAL matarg } ';'
 * Current token: the shader's keyword. Fills *sh (which owns its fades list).
 */
static int parse_shader(struct parser *P, struct scene_shader *sh)
{
	struct token open = P->tok;
	static const enum shader_kind kinds[] = {
		[KW_BRICKS] = SHADER_BRICKS, [KW_TILES] = SHADER_TILES, [KW_CHEQUERS] = SHADER_CHEQUERS,
		[KW_BUMPY] = SHADER_BUMPY, [KW_NOISE] = SHADER_NOISE, [KW_FADES] = SHADER_FADES,
		[KW_TURB3D] = SHADER_TURB3D,
	};
	enum shader_kind k = kinds[open.kw];
	const char *name = lex_keyword_name(open.kw);
	bool have_list = false;
	scene_shader_defaults(sh, k);
	next(P);
	for (;;) {
		struct token kw = P->tok;
		if (kw.kind == TK_SEMI)
			break;
		int r = NOT_MINE;
		if (kw.kind == TK_WORD) {
			enum keyword w = kw.kw;
			if (w == KW_SIZE) {
				next(P);
				r = read_num(P, &kw, &sh->size, R_POS);
			} else if ((k == SHADER_BRICKS && w == KW_MORTAR) || (k == SHADER_TILES && w == KW_FACE) ||
				   (k == SHADER_CHEQUERS && w == KW_MATERIAL_A) ||
				   ((k == SHADER_BUMPY || k == SHADER_NOISE || k == SHADER_TURB3D) && w == KW_MATERIAL)) {
				next(P);
				r = parse_matarg(P, &kw, &sh->mat_a);
			} else if ((k == SHADER_BRICKS && w == KW_BRICK) || (k == SHADER_TILES && w == KW_GROUT) ||
				   (k == SHADER_CHEQUERS && w == KW_MATERIAL_B)) {
				next(P);
				r = parse_matarg(P, &kw, &sh->mat_b);
			} else if (k == SHADER_TILES && (w == KW_TILE_WIDTH || w == KW_GROUT_WIDTH)) {
				next(P);
				r = read_num(P, &kw, w == KW_TILE_WIDTH ? &sh->tile_width : &sh->grout_width,
					     R_NONNEG);
			} else if ((k == SHADER_BUMPY || k == SHADER_TURB3D) && w == KW_TERMS) {
				next(P);
				r = read_int(P, &kw, &sh->terms, 1, LIM_TERMS);
			} else if (k == SHADER_BUMPY && (w == KW_XSIZE || w == KW_YSIZE || w == KW_ZSIZE)) {
				next(P);
				r = read_num(P, &kw,
					     w == KW_XSIZE ? &sh->axis_size.x : w == KW_YSIZE ? &sh->axis_size.y
											     : &sh->axis_size.z,
					     R_POS);
			} else if (k == SHADER_BUMPY && w == KW_SATURATION) {
				next(P);
				r = read_num(P, &kw, &sh->saturation, R_NONNEG);
			} else if ((k == SHADER_BUMPY || k == SHADER_TURB3D) && w == KW_DEPTH) {
				next(P);
				r = read_num(P, &kw, &sh->depth, R_ANY);
			} else if (k == SHADER_NOISE && w == KW_VARIANCE) {
				next(P);
				r = read_num(P, &kw, &sh->variance, R_ANY);
			} else if (k == SHADER_NOISE && w == KW_COLOUR) {
				next(P);
				r = read_vec(P, &kw, &sh->colour);
			} else if (k == SHADER_FADES && w == KW_AXIS) {
				next(P);
				r = read_vec(P, &kw, &sh->axis);
				if (!r && v3_len(sh->axis) == 0)
					r = err_at(P, ERRLEVEL_FATAL, &kw, "the fades 'axis' must not be (0 0 0)");
			} else if (k == SHADER_FADES && (w == KW_MATERIALS || w == KW_COLOURS)) {
				if (have_list)
					return err_near(P, &kw, "a fades takes one list: 'materials' or 'colours', never both");
				have_list = true;
				sh->fades_materials = w == KW_MATERIALS;
				next(P);
				r = parse_fades_list(P, &kw, sh, w == KW_MATERIALS);
			}
		}
		if (r == NOT_MINE) {
			char what[64];
			snprintf(what, sizeof what, "unknown verb in material (%s shader)", name);
			return unknown(P, what, &open, name, closer_in_shader, shader_expected(k));
		}
		if (r)
			return r;
	}
	if (k == SHADER_FADES && !have_list)
		return err_near(P, &P->tok, "a fades needs a 'colours' or 'materials' list");
	next(P);
	return 0;
}

static bool closer_in_material(enum keyword kw)
{
	return is_prim_kw(kw) || is_transform_kw(kw) || kw == KW_MATERIAL || kw == KW_PRIMITIVE;
}

/*
 * material -> MATERIAL { CALLED NAME | NAMED NAME | COLOUR vector | DIFF-COLOUR vector
 *            | SPEC-COLOUR vector | TRAN-COLOUR vector | DIFFUSE-REFLECTION NUM
 *            | SPECULAR-REFLECTION NUM | SPECULAR-POWER NUM | REFLECTION NUM
 *            | TRANSPARENCY NUM | REFRACTIVE-INDEX NUM | shader } ';'
 * `called NAME` stands alone: settings after it alter a named material and
 * settings before it overlay one, both errors. Current token: the first after
 * MATERIAL. *id is the material used: the called one or the new one.
 */
static int parse_material(struct parser *P, const struct token *open, bool need_named, uint32_t *id)
{
	struct scene_material m;
	scene_material_defaults(&m);
	m.loc = loc_at(P, open);
	uint32_t called = SCENE_NONE;
	char called_name[LIM_TOKEN_LEN + 1] = "";
	struct token first_setting = { 0 }, shader_tok = { 0 };
	bool have_setting = false;
	int rc = 0;
	if (++P->shader_depth > LIM_SHADER_DEPTH) {
		rc = err_at(P, ERRLEVEL_FATAL, open, "materials nested in shaders more than %d deep", LIM_SHADER_DEPTH);
		goto fail;
	}
	for (;;) {
		struct token kw = P->tok;
		if (kw.kind == TK_SEMI)
			break;
		if (kw.kind != TK_WORD) {
			rc = unknown(P, "unknown verb in material", open, "material", closer_in_material,
				     MATERIAL_EXPECTED);
			goto fail;
		}
		if (kw.kw == KW_CALLED) {
			next(P);
			if (P->tok.kind != TK_WORD) {
				rc = err_near(P, &P->tok, "material name expected after 'called'");
				goto fail;
			}
			tok_str(&P->tok, called_name);
			if (called != SCENE_NONE) {
				rc = err_at(P, ERRLEVEL_FATAL, &kw, "a material can call one named material");
				goto fail;
			}
			if (have_setting) {
				rc = err_at(P, ERRLEVEL_FATAL, &kw,
					    "attempt to overlay a material with the named material '%s' "
					    "(settings at line %d come before 'called')",
					    called_name, first_setting.line);
				goto fail;
			}
			called = find_material(P, called_name);
			if (called == SCENE_NONE) {
				rc = err_at(P, ERRLEVEL_FATAL, &P->tok, "undefined material '%s'", called_name);
				goto fail;
			}
			next(P);
			continue;
		}
		if (called != SCENE_NONE) {
			rc = err_near(P, &kw, "attempt to alter the named material '%s' (only 'called NAME ;' may "
					      "follow 'called')", called_name);
			goto fail;
		}
		if (!have_setting)
			first_setting = kw;
		have_setting = true;
		switch (kw.kw) {
		case KW_NAMED:
			if (m.name) {
				rc = err_near(P, &kw, "a material takes one name");
				goto fail;
			}
			next(P);
			rc = read_name(P, &kw, &m.name);
			break;
		case KW_COLOUR:
			next(P);
			rc = read_vec(P, &kw, &m.diff_colour);
			m.spec_colour = m.tran_colour = m.diff_colour;
			break;
		case KW_DIFF_COLOUR: next(P); rc = read_vec(P, &kw, &m.diff_colour); break;
		case KW_SPEC_COLOUR: next(P); rc = read_vec(P, &kw, &m.spec_colour); break;
		case KW_TRAN_COLOUR: next(P); rc = read_vec(P, &kw, &m.tran_colour); break;
		case KW_DIFFUSE_REFLECTION: next(P); rc = read_num(P, &kw, &m.diffuse, R_ANY); break;
		case KW_SPECULAR_REFLECTION: next(P); rc = read_num(P, &kw, &m.specular, R_ANY); break;
		case KW_SPECULAR_POWER: next(P); rc = read_num(P, &kw, &m.spec_power, R_NONNEG); break;
		case KW_REFLECTION: next(P); rc = read_num(P, &kw, &m.reflection, R_ANY); break;
		case KW_TRANSPARENCY: next(P); rc = read_num(P, &kw, &m.transparency, R_ANY); break;
		case KW_REFRACTIVE_INDEX: next(P); rc = read_num(P, &kw, &m.ior, R_POS); break;
		case KW_BRICKS: case KW_TILES: case KW_CHEQUERS: case KW_BUMPY: case KW_NOISE: case KW_FADES:
		case KW_TURB3D:
			if (m.shader.kind != SHADER_NONE) {
				rc = err_near(P, &kw, "a material takes one shader ('%s' at line %d)",
					      lex_keyword_name(shader_tok.kw), shader_tok.line);
				goto fail;
			}
			shader_tok = kw;
			rc = parse_shader(P, &m.shader);
			break;
		default:
			rc = unknown(P, "unknown verb in material", open, "material", closer_in_material,
				     MATERIAL_EXPECTED);
			break;
		}
		if (rc)
			goto fail;
	}
	if (called != SCENE_NONE) {
		*id = called;
	} else {
		if (need_named && !m.name) {
			rc = err_near(P, &P->tok, "a defined material needs 'named NAME'");
			goto fail;
		}
		bool named = m.name != NULL;
		if ((rc = scene_add_material(P->s, &m, id, P->err)) != 0)
			goto out; /* the scene freed m's name and fades */
		if (named && names_put(&P->mat_names, *id, mat_name, P->s) < 0)
			return err_at(P, ERRLEVEL_FATAL, open, "out of memory");
	}
	next(P);
	P->shader_depth--;
	return 0;
fail:
	free(m.name);
	free(m.shader.fades);
out:
	return rc;
}

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
				next(P), r = read_num(P, &kw, &f->threshold, R_POS);
			else if (w == KW_MAX_DEPTH)
				next(P), r = read_int(P, &kw, &f->max_depth, 0, LIM_ADAPTIVE_DEPTH);
			else if (w == KW_CACHE_SIZE)
				next(P), r = read_int(P, &kw, &f->cache_size, 0, 1 << 30), *given = true;
			else if (w == KW_RELAX)
				next(P), r = read_num(P, &kw, &f->relax, R_POS);
		} else if (k == FILTER_SUPERSAMPLE) {
			if (w == KW_X_SAMPLES)
				next(P), r = read_int(P, &kw, &f->x_samples, 1, LIM_SAMPLES);
			else if (w == KW_Y_SAMPLES)
				next(P), r = read_int(P, &kw, &f->y_samples, 1, LIM_SAMPLES);
		} else {
			if (w == KW_RADIUS)
				next(P), r = read_num(P, &kw, &f->radius, R_NONNEG);
			else if (w == KW_SAMPLES)
				next(P), r = read_int(P, &kw, &f->samples, 1, LIM_SAMPLES);
			else if (w == KW_FOCAL_LENGTH && k == FILTER_LENS)
				next(P), r = read_num(P, &kw, &f->focal_length, R_POS);
		}
		if (r == NOT_MINE) {
			char what[80];
			snprintf(what, sizeof what, "unrecognised keyword in camera section (filter %s)", fname);
			return unknown(P, what, &open, "filter", closer_in_filter,
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
		case KW_LOOK_AT: next(P); r = read_vec(P, &kw, &cam.look_at); break;
		case KW_DROP_LINE: next(P); r = read_vec(P, &kw, &cam.drop_line); break;
		case KW_LOOK_FROM: next(P); r = read_vec(P, &kw, &cam.look_from); break;
		case KW_DEPTH: next(P); r = read_num(P, &kw, &cam.depth, R_POS); break;
		case KW_X_SIZE: next(P); r = read_num(P, &kw, &cam.x_size, R_POS); break;
		case KW_Y_SIZE: next(P); r = read_num(P, &kw, &cam.y_size, R_POS); break;
		case KW_FILTER: r = parse_filter(P, &cam, cache_given); break;
		case KW_XSIZE:
		case KW_YSIZE:
			r = err_near(P, &kw, "unrecognised keyword in camera section (the film size is x-size/y-size; "
					     "xsize/ysize belong in the image statement)");
			break;
		default:
			r = unknown(P, "unrecognised keyword in camera section", &open, "camera", NULL,
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
		case KW_XSIZE: next(P); r = read_int(P, &kw, &im.xsize, 1, LIM_IMAGE_SIDE); break;
		case KW_YSIZE: next(P); r = read_int(P, &kw, &im.ysize, 1, LIM_IMAGE_SIDE); break;
		case KW_NO_SHADOWS: next(P); im.no_shadows = true; r = 0; break;
		case KW_NO_REFLECTIONS: next(P); im.no_reflections = true; r = 0; break;
		case KW_NONSTOP: next(P); im.nonstop = true; r = 0; break;
		case KW_INTERSECT_BUFFER: next(P); r = read_int(P, &kw, &im.intersect_buffer, 0, 1 << 30); break;
		case KW_X_SIZE:
		case KW_Y_SIZE:
			r = err_near(P, &kw, "unrecognised keyword in image section (the pixel size is xsize/ysize; "
					     "x-size/y-size belong in the camera statement)");
			break;
		default:
			r = unknown(P, "unrecognised keyword in image section", &open, "image", NULL,
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
		case KW_COLOUR: next(P); r = read_vec(P, &kw, &l.colour); break;
		case KW_POSITION: next(P); r = read_vec(P, &kw, &l.position); break;
		case KW_SAMPLES:
			samples_tok = kw;
			have_samples = true;
			next(P);
			r = read_int(P, &kw, &l.samples, 1, LIM_SAMPLES);
			break;
		case KW_FALL_OFF: next(P); r = read_num(P, &kw, &l.fall_off, R_NONNEG); break;
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
					v = l.shape == LIGHT_SPHERE	? sphere_var(P, &l.sphere)
					    : l.shape == LIGHT_CYLINDER ? cylinder_var(P, &l.cylinder)
									: box_var(P, &l.box);
				if (v == NOT_MINE) {
					char what[64];
					snprintf(what, sizeof what, "unknown verb in light (shape %s)", sname);
					return unknown(P, what, &st, sname, closer_in_light,
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
			r = unknown(P, "unknown verb in light", &open, "light", NULL,
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
			if ((rc = read_name(P, &kw, &d.name)) != 0)
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
		rc = unknown(P, "unknown verb in definition (name or object expected)", open, "object", NULL, NULL);
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
	if (names_put(&P->def_names, id, def_name, P->s) < 0)
		return err_at(P, ERRLEVEL_FATAL, open, "out of memory");
	if (grow_bytes(&P->def_depth, &P->cap_def_depth, P->s->n_defines) < 0)
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
			return unknown(P, "unknown verb in definition (object or material expected)", &open, "define",
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
	char *path = path_relative(P->file, name);
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
				return unknown(P, "unrecognised keyword in camera file", t, "camera file", NULL,
					       "camera, image, light or include");
			return unknown(P, "unknown verb in scene file", t, "scene file", NULL,
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
