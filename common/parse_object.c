/*
 * parse_object.c - object statements: primitives and their variables, CSG,
 * defined-object references, transforms on objects, and the material and
 * shader blocks. parse.c's conventions hold.
 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/parse_int.h"
#include "common/raw.h"

/* ---- primitive variables ------------------------------------------------------ */

/* spherevar -> CENTRE vector | RADIUS NUM | POLE vector | EQUATOR vector */
int parse_sphere_var(struct parser *P, struct prim_sphere *sp)
{
	struct token kw = P->tok;
	switch (kw.kw) {
	case KW_CENTRE: next(P); return parse_vec(P, &kw, &sp->centre);
	case KW_RADIUS: next(P); return parse_num(P, &kw, &sp->radius, R_POS);
	case KW_POLE:
		next(P);
		TRY(parse_vec(P, &kw, &sp->pole));
		if (v3_len(sp->pole) == 0)
			return err_at(P, ERRLEVEL_FATAL, &kw, "'pole' must not be (0 0 0)");
		return 0;
	case KW_EQUATOR: next(P); return parse_vec(P, &kw, &sp->equator);
	default: return NOT_MINE;
	}
}

/* cylvar -> FROM vector | TO vector | RADIUS NUM | CAPPED */
int parse_cylinder_var(struct parser *P, struct prim_cylinder *cy)
{
	struct token kw = P->tok;
	switch (kw.kw) {
	case KW_FROM: next(P); return parse_vec(P, &kw, &cy->from);
	case KW_TO: next(P); return parse_vec(P, &kw, &cy->to);
	case KW_RADIUS: next(P); return parse_num(P, &kw, &cy->radius, R_POS);
	case KW_CAPPED: next(P); cy->capped = true; return 0;
	default: return NOT_MINE;
	}
}

/* boxvar -> A vector | B vector */
int parse_box_var(struct parser *P, struct prim_box *bx)
{
	struct token kw = P->tok;
	switch (kw.kw) {
	case KW_A: next(P); return parse_vec(P, &kw, &bx->a);
	case KW_B: next(P); return parse_vec(P, &kw, &bx->b);
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
	case KW_POSITION: next(P); return parse_vec(P, &kw, &pl->position);
	case KW_NORMAL:
		next(P);
		TRY(parse_vec(P, &kw, &pl->normal));
		if (v3_len(pl->normal) == 0)
			return err_at(P, ERRLEVEL_FATAL, &kw, "'normal' must not be (0 0 0)");
		return 0;
	case KW_X_AXIS: next(P); c->axes |= 1; return parse_vec(P, &kw, &pl->x_axis);
	case KW_Y_AXIS: next(P); c->axes |= 2; return parse_vec(P, &kw, &pl->y_axis);
	case KW_RADIUS:
		if (c->o.kind != PRIM_DISK)
			return NOT_MINE;
		next(P);
		return parse_num(P, &kw, &pl->radius, R_POS);
	default: return NOT_MINE;
	}
}

/* trivar -> A vector | B vector | C vector | NORMAL-A vector | NORMAL-B vector | NORMAL-C vector */
static int triangle_var(struct parser *P, struct primctx *c)
{
	struct token kw = P->tok;
	struct prim_triangle *tr = &c->o.u.triangle;
	switch (kw.kw) {
	case KW_A: next(P); return parse_vec(P, &kw, &tr->a);
	case KW_B: next(P); return parse_vec(P, &kw, &tr->b);
	case KW_C: next(P); return parse_vec(P, &kw, &tr->c);
	case KW_NORMAL_A: next(P); c->normals |= 1; return parse_vec(P, &kw, &tr->na);
	case KW_NORMAL_B: next(P); c->normals |= 2; return parse_vec(P, &kw, &tr->nb);
	case KW_NORMAL_C: next(P); c->normals |= 4; return parse_vec(P, &kw, &tr->nc);
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
	case KW_WELD: next(P); return parse_num(P, &kw, &m->weld, R_NONNEG);
	case KW_SMOOTH: next(P); m->smooth = true; return 0;
	case KW_X_ROTATION: next(P); return parse_num(P, &kw, &m->rotation.x, R_ANY);
	case KW_Y_ROTATION: next(P); return parse_num(P, &kw, &m->rotation.y, R_ANY);
	case KW_Z_ROTATION: next(P); return parse_num(P, &kw, &m->rotation.z, R_ANY);
	case KW_AT: next(P); return parse_vec(P, &kw, &m->at);
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
		TRY(parse_vec(P, &kw, &c->pts[c->n_pts]));
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
char *parse_path_relative(const char *from_file, const char *name)
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
	char *path = parse_path_relative(P->file, name);
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
		return parse_unknown(P, "unknown verb in csg", open, "csg", closer_in_prim,
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
			case PRIM_SPHERE: r = parse_sphere_var(P, &c->o.u.sphere); break;
			case PRIM_PLANE: case PRIM_DISK: r = plane_var(P, c); break;
			case PRIM_CYLINDER: r = parse_cylinder_var(P, &c->o.u.cylinder); break;
			case PRIM_BOX: r = parse_box_var(P, &c->o.u.box); break;
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
			return parse_unknown(P, what, &open, name, closer_in_prim, prim_expected(c->o.kind));
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
	uint32_t d = parse_find_define(P, name);
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
			return parse_unknown(P, "unknown verb in complex reference", &open, name, closer_in_prim,
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
int parse_object_body(struct parser *P, const struct token *open, uint32_t *id)
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
			rc = parse_unknown(P, "unknown verb in object", open, "object", NULL,
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
			rc = parse_unknown(P, "unknown verb in object", open, "object", NULL,
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
	rc = parse_add_object(P, &c.o, depth, id, open);
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
		*id = parse_find_material(P, name);
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
		TRY(parse_num(P, kw, &e.dist, R_NONNEG));
		if (materials)
			TRY(parse_matarg(P, kw, &e.material));
		else
			TRY(parse_vec(P, &dtok, &e.colour));
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
				r = parse_num(P, &kw, &sh->size, R_POS);
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
				r = parse_num(P, &kw, w == KW_TILE_WIDTH ? &sh->tile_width : &sh->grout_width,
					     R_NONNEG);
			} else if ((k == SHADER_BUMPY || k == SHADER_TURB3D) && w == KW_TERMS) {
				next(P);
				r = parse_int(P, &kw, &sh->terms, 1, LIM_TERMS);
			} else if (k == SHADER_BUMPY && (w == KW_XSIZE || w == KW_YSIZE || w == KW_ZSIZE)) {
				next(P);
				r = parse_num(P, &kw,
					     w == KW_XSIZE ? &sh->axis_size.x : w == KW_YSIZE ? &sh->axis_size.y
											     : &sh->axis_size.z,
					     R_POS);
			} else if (k == SHADER_BUMPY && w == KW_SATURATION) {
				next(P);
				r = parse_num(P, &kw, &sh->saturation, R_NONNEG);
			} else if ((k == SHADER_BUMPY || k == SHADER_TURB3D) && w == KW_DEPTH) {
				next(P);
				r = parse_num(P, &kw, &sh->depth, R_ANY);
			} else if (k == SHADER_NOISE && w == KW_VARIANCE) {
				next(P);
				r = parse_num(P, &kw, &sh->variance, R_ANY);
			} else if (k == SHADER_NOISE && w == KW_COLOUR) {
				next(P);
				r = parse_vec(P, &kw, &sh->colour);
			} else if (k == SHADER_FADES && w == KW_AXIS) {
				next(P);
				r = parse_vec(P, &kw, &sh->axis);
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
			return parse_unknown(P, what, &open, name, closer_in_shader, shader_expected(k));
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
int parse_material(struct parser *P, const struct token *open, bool need_named, uint32_t *id)
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
			rc = parse_unknown(P, "unknown verb in material", open, "material", closer_in_material,
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
			called = parse_find_material(P, called_name);
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
			rc = parse_name(P, &kw, &m.name);
			break;
		case KW_COLOUR:
			next(P);
			rc = parse_vec(P, &kw, &m.diff_colour);
			m.spec_colour = m.tran_colour = m.diff_colour;
			break;
		case KW_DIFF_COLOUR: next(P); rc = parse_vec(P, &kw, &m.diff_colour); break;
		case KW_SPEC_COLOUR: next(P); rc = parse_vec(P, &kw, &m.spec_colour); break;
		case KW_TRAN_COLOUR: next(P); rc = parse_vec(P, &kw, &m.tran_colour); break;
		case KW_DIFFUSE_REFLECTION: next(P); rc = parse_num(P, &kw, &m.diffuse, R_ANY); break;
		case KW_SPECULAR_REFLECTION: next(P); rc = parse_num(P, &kw, &m.specular, R_ANY); break;
		case KW_SPECULAR_POWER: next(P); rc = parse_num(P, &kw, &m.spec_power, R_NONNEG); break;
		case KW_REFLECTION: next(P); rc = parse_num(P, &kw, &m.reflection, R_ANY); break;
		case KW_TRANSPARENCY: next(P); rc = parse_num(P, &kw, &m.transparency, R_ANY); break;
		case KW_REFRACTIVE_INDEX: next(P); rc = parse_num(P, &kw, &m.ior, R_POS); break;
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
			rc = parse_unknown(P, "unknown verb in material", open, "material", closer_in_material,
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
		if (named && parse_names_put(&P->mat_names, *id, mat_name, P->s) < 0)
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
