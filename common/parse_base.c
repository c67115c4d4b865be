/*
 * parse_base.c - the parser's common ground: error messages ("file:line:col:
 * error: ... near 'tok'"), numbers, vectors and names, the name tables of
 * materials and defines, and transforms. parse.c's conventions hold.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "common/parse_int.h"

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
int parse_vreport(struct parser *P, int level, const struct token *t, int near, const char *fmt, va_list ap)
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

/*
 * The current token does not belong in the block opened by `open` (spelled
 * open_name). Says why as precisely as it can: end of file or a statement
 * keyword (or one of the `closers`, when given) means the block's ';' is
 * missing; `include` is misplaced; anything else is an unknown verb, and
 * the message ends with what the block takes ("; expected ...") when
 * `expected` is given.
 */
int parse_unknown(struct parser *P, const char *what, const struct token *open, const char *open_name,
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

/* Reads the number after keyword kw (the current token is the number). */
int parse_num(struct parser *P, const struct token *kw, double *v, enum range r)
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
int parse_int(struct parser *P, const struct token *kw, int *v, int lo, int hi)
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
int parse_vec(struct parser *P, const struct token *kw, vec3 *v)
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
int parse_name(struct parser *P, const struct token *kw, char **out)
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
static uint32_t names_find(const struct name_table *t, const char *name,
			   const char *(*names)(const struct scene *, uint32_t), const struct scene *s)
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
int parse_names_put(struct name_table *t, uint32_t id, const char *(*names)(const struct scene *, uint32_t),
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


uint32_t parse_find_material(const struct parser *P, const char *name)
{
	return names_find(&P->mat_names, name, mat_name, P->s);
}

uint32_t parse_find_define(const struct parser *P, const char *name)
{
	return names_find(&P->def_names, name, def_name, P->s);
}

/* ---- bookkeeping ------------------------------------------------------------ */

int parse_grow_bytes(unsigned char **arr, uint32_t *cap, uint32_t need)
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
int parse_add_object(struct parser *P, struct scene_object *o, unsigned depth, uint32_t *id,
		      const struct token *at)
{
	TRY(scene_add_object(P->s, o, id, P->err));
	if (parse_grow_bytes(&P->obj_depth, &P->cap_obj_depth, P->s->n_objects) < 0)
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
int parse_transform(struct parser *P, mat34 *xf, bool *has)
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
		TRY(parse_vec(P, &kw, &v));
	else
		TRY(parse_num(P, &kw, &amount, R_ANY));
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
