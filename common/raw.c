/*
 * raw.c - RAW triangle files: reading, welding, rotation, AT and smoothing.
 *
 * File format (decided; docs/language.md records it):
 *   - Text, one triangle per line: nine numbers Ax Ay Az Bx By Bz Cx Cy Cz.
 *   - "Any whitespace between them": numbers on a line are separated by any
 *     run of spaces, tabs, vertical tabs or form feeds. A line ends at "\n",
 *     "\r\n" or a lone "\r", so Unix, DOS and old Mac files all read.
 *   - Blank lines (nothing but whitespace) are skipped. Every other line must
 *     hold exactly nine numbers; anything else is an error naming file:line
 *     ("dragon.raw:12: error: expected 9 numbers, found 7"). A triangle never
 *     spans lines: that is what every real RAW file does, and it makes a
 *     damaged file fail loudly at the damaged line instead of shifting every
 *     later triangle.
 *   - Numbers: [+-] digits [. digits] [(e|E) [+-] digits] (either side of
 *     the point may be empty, not both). No inf, nan or hex. A number must be
 *     followed by whitespace or the end of the line. Magnitudes above
 *     LIM_RAW_COORD are an error.
 *   - An empty file (no triangles) is an error: a mesh object that draws
 *     nothing is almost surely a wrong file.
 *
 * Degenerate (zero-area) triangles, including those that welding collapses,
 * are KEPT: the triangle count then always equals the number of lines, as
 * the mesh sources' own counts say, and the tracer's triangle test never hits
 * a zero-area triangle anyway. They add nothing to smoothing normals.
 *
 * WELD d: each corner, in file order, is merged into the nearest vertex
 * already kept that lies closer than d (Euclidean distance < d); identical
 * points always merge, so WELD 0 merges exactly equal points only. A kept
 * vertex keeps the position of the first corner that created it (no
 * averaging, no chains: a corner within d of a merged corner but not of its
 * kept vertex makes a new vertex). Welding uses a hash grid with cells a hair
 * larger than 2d, checking the own cell and, per axis, the one neighbour on
 * the side the point is nearer to (at most 8 cells): O(n) expected time.
 * Welding happens on the file's coordinates, before rotation and AT (both
 * preserve distances, so the result is the same, and fewer points are moved).
 *
 * SMOOTH: per-vertex normals are the ANGLE-weighted sum of the unit normals
 * of the faces around the vertex (Thuermer & Wuethrich), normalised. Face
 * normals follow the corner order: (B-A) x (C-A). Angle weighting does not
 * depend on how a surface happens to be split into triangles. A vertex whose
 * sum vanishes (faces of opposite facing cancel) takes the normal of its first
 * non-degenerate face; one with only degenerate faces gets (0 0 1), which is
 * never seen because such faces are never hit.
 *
 * ROTATION and AT. The manual: "X-ROTATION: No of DEGREES to rotate the
 * triangles about the X axis when they are read in" and "AT <vec>: The point
 * in the model world that will be the origin for the triangles." We read AT
 * the way a renderer author would: the RAW file's own origin is placed at the
 * world point AT, i.e. the file's coordinates are relative to AT. So each
 * vertex becomes   v' = Rz * Ry * Rx * v + at
 * (rotations first, about the file's origin, in the order x then y then z,
 * right-handed as in scene_xform_op: x-rotation turns y toward z, and so on;
 * then the translation by +at). A mesh written around its own centre with
 * "at (0 5 0)" therefore sits around (0 5 0) in the world. Normals are
 * rotated with the vertices.
 */
#include "common/raw.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/lex.h"
#include "common/xmath.h"

/* ---- numbers ------------------------------------------------------------ */

static inline int raw_is_blank(char c)
{
	return c == ' ' || c == '\t' || c == '\v' || c == '\f';
}

static inline int raw_is_digit(char c)
{
	return (unsigned char)(c - '0') < 10;
}

enum { RAW_NUM_OK, RAW_NUM_SYNTAX, RAW_NUM_RANGE };

/*
 * Parses one number starting at *pp (bounded by end; the text need not be
 * NUL-terminated) into *out and advances *pp past it. The number must be
 * followed by end, whitespace or a line end. Returns RAW_NUM_OK,
 * RAW_NUM_SYNTAX (not a number; *pp is left at the start of the bad token)
 * or RAW_NUM_RANGE (overflows, or above LIM_RAW_COORD).
 *
 * Fast path: up to 19 significant digits are gathered into a uint64; when the
 * mantissa is <= 2^53 and the decimal exponent is within +-22, the result is
 * one correctly rounded multiplication or division of two exact doubles,
 * hence exactly what strtod returns. Everything else (more digits, huge or
 * tiny exponents) is handed to strtod on a NUL-terminated copy.
 */
static int raw_number(const char **pp, const char *end, double *out)
{
	const char *s = *pp, *p = s;
	int neg = 0;
	if (p < end && (*p == '+' || *p == '-')) {
		neg = *p == '-';
		p++;
	}
	/* the common token first: at most 19 digits in all, with or without a
	 * fraction, no exponent; m then holds every digit exactly, and the
	 * general loop below would find the same m and exponent */
	{
		const char *q = p;
		uint64_t v = 0;
		int nd = 0, frac = 0;
		while (q < end && raw_is_digit(*q))
			v = v * 10 + (unsigned)(*q++ - '0'), nd++;
		if (q < end && *q == '.') {
			q++;
			while (q < end && raw_is_digit(*q))
				v = v * 10 + (unsigned)(*q++ - '0'), frac++;
		}
		if (nd + frac > 0 && nd + frac <= 19 && frac <= 22 && v <= (1ull << 53) &&
		    (q == end || raw_is_blank(*q) || *q == '\n' || *q == '\r')) {
			double x = (double)v;
			x = frac ? x / lex_pow10[frac] : x;
			if (!(x <= LIM_RAW_COORD))
				return RAW_NUM_RANGE;
			*out = neg ? -x : x;
			*pp = q;
			return RAW_NUM_OK;
		}
	}
	uint64_t m = 0;
	int nsig = 0, dropped = 0;
	int64_t ndig = 0, exp10 = 0;
	while (p < end && raw_is_digit(*p)) {
		unsigned d = (unsigned)(*p - '0');
		if (nsig < 19) {
			if (m || d) {
				m = m * 10 + d;
				nsig++;
			}
		} else {
			exp10++;
			dropped |= d != 0;
		}
		ndig++;
		p++;
	}
	if (p < end && *p == '.') {
		p++;
		while (p < end && raw_is_digit(*p)) {
			unsigned d = (unsigned)(*p - '0');
			if (nsig < 19) {
				if (m || d) {
					m = m * 10 + d;
					nsig++;
				}
				exp10--;
			} else {
				dropped |= d != 0;
			}
			ndig++;
			p++;
		}
	}
	if (ndig == 0)
		return RAW_NUM_SYNTAX;
	if (p < end && (*p == 'e' || *p == 'E')) {
		p++;
		int eneg = 0;
		if (p < end && (*p == '+' || *p == '-')) {
			eneg = *p == '-';
			p++;
		}
		if (p >= end || !raw_is_digit(*p))
			return RAW_NUM_SYNTAX;
		int64_t e = 0;
		while (p < end && raw_is_digit(*p)) {
			if (e < 100000000)
				e = e * 10 + (*p - '0');
			p++;
		}
		exp10 += eneg ? -e : e;
	}
	if (p < end && !raw_is_blank(*p) && *p != '\n' && *p != '\r')
		return RAW_NUM_SYNTAX;

	double x;
	if (m == 0) {
		x = 0.0;
	} else if (!dropped && m <= (1ull << 53) && exp10 >= -22 && exp10 <= 22) {
		x = (double)m;
		x = exp10 < 0 ? x / lex_pow10[-exp10] : x * lex_pow10[exp10];
	} else {
		/* unusual input: let the C library round it correctly */
		char tmp[LIM_TOKEN_LEN + 1];
		size_t n = (size_t)(p - s);
		if (n > LIM_TOKEN_LEN)
			return RAW_NUM_RANGE;
		memcpy(tmp, s, n);
		tmp[n] = '\0';
		x = strtod(tmp, NULL);
		x = fabs(x); /* sign applied below, like the fast path */
	}
	if (!(x <= LIM_RAW_COORD))
		return RAW_NUM_RANGE;
	*out = neg ? -x : x;
	*pp = p;
	return RAW_NUM_OK;
}

/* fmax, inline (libm's is a call even at -O3): the other operand when one
 * is NaN, else the larger; raw.c calls it on magnitudes only, so no signed
 * zeros to order */
static inline double raw_fmax(double x, double y) { return x > y || y != y ? x : y; }

/* ---- welding -------------------------------------------------------------- */

/* One occupied grid cell: its key and the first vertex in it (SCENE_NONE ends). */
struct raw_cell {
	double key[3];
	uint32_t head;
};

struct raw_weld {
	double cell;            /* cell size (> d), or 0 for exact welding */
	double d2;              /* d squared */
	struct raw_cell *cells; /* open addressing, cap a power of two */
	size_t cap, used;
	uint32_t *next;         /* per vertex: next vertex in the same cell */
	vec3 *verts;
	uint32_t n, vcap;
};

static inline uint64_t raw_bits(double x)
{
	uint64_t u;
	x += 0.0; /* -0 -> +0 */
	memcpy(&u, &x, sizeof u);
	return u;
}

static inline size_t raw_hash(const double k[3])
{
	uint64_t h = raw_bits(k[0]) * 0x9E3779B97F4A7C15ull;
	h ^= raw_bits(k[1]) + 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
	h ^= raw_bits(k[2]) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
	h ^= h >> 29;
	h *= 0xBF58476D1CE4E5B9ull;
	h ^= h >> 32;
	return (size_t)h;
}

/*
 * The cell key along one axis: floor(x / cell) as a double. When that
 * overflows (tiny cells, big coordinates) distinct coordinates are already
 * far more than d apart, so the coordinate itself is an exact key.
 */
static inline double raw_axis_key(double x, double cell)
{
	if (cell == 0)
		return x + 0.0;
	double q = floor(x / cell);
	return isfinite(q) ? q + 0.0 : x + 0.0;
}

/*
 * Which neighbouring cells along one axis can hold a point closer than d to
 * x: with cells 2d(1 + 1e-9) wide, only the lower one when x sits in the
 * lower half of its cell and only the upper one in the upper half. Near the
 * middle (slack 1e-6, far above the rounding error of x/cell while
 * |x/cell| <= 2^30) both are searched, and so they are far from the origin.
 */
static inline void raw_probe_range(double x, double cell, int *lo, int *hi)
{
	double t = x / cell;
	*lo = -1;
	*hi = 1;
	if (fabs(t) <= 0x1p30) {
		double fr = t - floor(t);
		if (fr >= 0.5 + 1e-6)
			*lo = 0;
		if (fr <= 0.5 - 1e-6)
			*hi = 0;
	}
}

/* Finds the slot of key (an empty slot, head == SCENE_NONE, when absent). */
static size_t raw_slot(const struct raw_weld *w, const double k[3])
{
	size_t mask = w->cap - 1, i = raw_hash(k) & mask;
	for (;;) {
		const struct raw_cell *c = &w->cells[i];
		if (c->head == SCENE_NONE ||
		    (c->key[0] == k[0] && c->key[1] == k[1] && c->key[2] == k[2]))
			return i;
		i = (i + 1) & mask;
	}
}

static int raw_cells_grow(struct raw_weld *w)
{
	size_t ncap = w->cap ? w->cap * 2 : 1024;
	struct raw_cell *old = w->cells;
	size_t ocap = w->cap;
	w->cells = malloc(ncap * sizeof *w->cells);
	if (!w->cells) {
		w->cells = old;
		return -1;
	}
	w->cap = ncap;
	for (size_t i = 0; i < ncap; i++)
		w->cells[i].head = SCENE_NONE;
	for (size_t i = 0; i < ocap; i++)
		if (old[i].head != SCENE_NONE)
			w->cells[raw_slot(w, old[i].key)] = old[i];
	free(old);
	return 0;
}

/*
 * Returns the index of the kept vertex for point p: the nearest existing one
 * closer than d (or identical), else a new one. Returns SCENE_NONE when out
 * of memory.
 */
static uint32_t raw_weld_point(struct raw_weld *w, vec3 p)
{
	double k[3] = { raw_axis_key(p.x, w->cell), raw_axis_key(p.y, w->cell),
			raw_axis_key(p.z, w->cell) };
	uint32_t best = SCENE_NONE;
	double best_d2 = 0;

	/* own cell first: an exact duplicate (the common case) ends the search */
	size_t own = raw_slot(w, k);
	for (uint32_t v = w->cells[own].head; v != SCENE_NONE; v = w->next[v]) {
		vec3 q = w->verts[v];
		double dx = q.x - p.x, dy = q.y - p.y, dz = q.z - p.z;
		double dd = dx * dx + dy * dy + dz * dz;
		if ((dd < w->d2 || dd == 0) &&
		    (best == SCENE_NONE || dd < best_d2 || (dd == best_d2 && v < best))) {
			best = v;
			best_d2 = dd;
			if (dd == 0)
				return v;
		}
	}
	if (w->cell > 0) {
		int lo[3], hi[3];
		raw_probe_range(p.x, w->cell, &lo[0], &hi[0]);
		raw_probe_range(p.y, w->cell, &lo[1], &hi[1]);
		raw_probe_range(p.z, w->cell, &lo[2], &hi[2]);
		for (int dx = lo[0]; dx <= hi[0]; dx++) {
			for (int dy = lo[1]; dy <= hi[1]; dy++) {
				for (int dz = lo[2]; dz <= hi[2]; dz++) {
					if (!dx && !dy && !dz)
						continue;
					double n[3] = { k[0] + dx, k[1] + dy, k[2] + dz };
					/* beyond 2^53, k+-1 may round to k: that cell was
					 * searched already, and there x >= 2^53 * cell makes
					 * distinct coordinates differ by an ulp > d anyway */
					if (n[0] == k[0] && n[1] == k[1] && n[2] == k[2])
						continue;
					size_t s = raw_slot(w, n);
					for (uint32_t v = w->cells[s].head; v != SCENE_NONE; v = w->next[v]) {
						vec3 q = w->verts[v];
						double ex = q.x - p.x, ey = q.y - p.y, ez = q.z - p.z;
						double dd = ex * ex + ey * ey + ez * ez;
						if (dd < w->d2 && (best == SCENE_NONE || dd < best_d2 ||
								   (dd == best_d2 && v < best))) {
							best = v;
							best_d2 = dd;
						}
					}
				}
			}
		}
	}
	if (best != SCENE_NONE)
		return best;

	/* a new vertex */
	if (w->n == w->vcap) {
		uint32_t ncap = w->vcap ? w->vcap * 2 : 1024;
		vec3 *nv = realloc(w->verts, (size_t)ncap * sizeof *nv);
		if (!nv)
			return SCENE_NONE;
		w->verts = nv;
		uint32_t *nn = realloc(w->next, (size_t)ncap * sizeof *nn);
		if (!nn)
			return SCENE_NONE;
		w->next = nn;
		w->vcap = ncap;
	}
	if ((w->used + 1) * 2 > w->cap) {
		if (raw_cells_grow(w) < 0)
			return SCENE_NONE;
		own = raw_slot(w, k);
	}
	uint32_t id = w->n++;
	w->verts[id] = p;
	struct raw_cell *c = &w->cells[own];
	if (c->head == SCENE_NONE) {
		memcpy(c->key, k, sizeof c->key);
		w->used++;
	}
	w->next[id] = c->head;
	c->head = id;
	return id;
}

/* ---- smoothing and transform ------------------------------------------------ */

static vec3 raw_unit_scaled(vec3 a)
{
	double m = raw_fmax(fabs(a.x), raw_fmax(fabs(a.y), fabs(a.z)));
	/* divide (1/m overflows for subnormal m) */
	return m > 0 ? v3_norm(v3(a.x / m, a.y / m, a.z / m)) : a;
}

/*
 * Angle-weighted vertex normals of the (untransformed) mesh. Returns a
 * malloc'd array of n_vertices unit vectors (caller owns), NULL on OOM.
 */
static vec3 *raw_normals(const vec3 *v, uint32_t nv, const uint32_t *t, uint32_t nt)
{
	vec3 *n = calloc(nv ? nv : 1, sizeof *n);
	if (!n)
		return NULL;
	for (uint32_t i = 0; i < nt; i++) {
		const uint32_t *c = t + 3 * (size_t)i;
		vec3 a = v[c[0]], b = v[c[1]], cc = v[c[2]];
		vec3 fn = raw_unit_scaled(v3_cross(raw_unit_scaled(v3_sub(b, a)),
						   raw_unit_scaled(v3_sub(cc, a))));
		if (v3_dot(fn, fn) == 0)
			continue;
		for (int k = 0; k < 3; k++) {
			vec3 p = v[c[k]];
			vec3 e1 = raw_unit_scaled(v3_sub(v[c[(k + 1) % 3]], p));
			vec3 e2 = raw_unit_scaled(v3_sub(v[c[(k + 2) % 3]], p));
			double ang = xm_atan2(v3_len(v3_cross(e1, e2)), v3_dot(e1, e2));
			n[c[k]] = v3_add(n[c[k]], v3_scale(fn, ang));
		}
	}
	for (uint32_t i = 0; i < nv; i++) {
		vec3 u = raw_unit_scaled(n[i]);
		n[i] = v3_dot(u, u) > 0.5 ? u : v3(0, 0, 0);
	}
	/* vanished sums: first non-degenerate face's normal, else (0 0 1) */
	for (uint32_t i = 0; i < nt; i++) {
		const uint32_t *c = t + 3 * (size_t)i;
		if (n[c[0]].x != 0 || n[c[0]].y != 0 || n[c[0]].z != 0) {
			if ((n[c[1]].x != 0 || n[c[1]].y != 0 || n[c[1]].z != 0) &&
			    (n[c[2]].x != 0 || n[c[2]].y != 0 || n[c[2]].z != 0))
				continue;
		}
		vec3 a = v[c[0]];
		vec3 fn = raw_unit_scaled(v3_cross(raw_unit_scaled(v3_sub(v[c[1]], a)),
						   raw_unit_scaled(v3_sub(v[c[2]], a))));
		if (v3_dot(fn, fn) == 0)
			continue;
		for (int k = 0; k < 3; k++) {
			vec3 *q = &n[c[k]];
			if (q->x == 0 && q->y == 0 && q->z == 0)
				*q = fn;
		}
	}
	for (uint32_t i = 0; i < nv; i++)
		if (n[i].x == 0 && n[i].y == 0 && n[i].z == 0)
			n[i] = v3(0, 0, 1);
	return n;
}

/* Rz * Ry * Rx (degrees) followed by +at, exactly as scene_xform_op builds them. */
static mat34 raw_matrix(vec3 rot, vec3 at)
{
	mat34 m = m34_identity();
	double ang[3] = { rot.x, rot.y, rot.z };
	for (int axis = 0; axis < 3; axis++)
		if (ang[axis] != 0)
			scene_xform_op(&m, XF_ROTATE, axis, ang[axis], v3(0, 0, 0)); /* m = R m */
	m.m[0][3] += at.x;
	m.m[1][3] += at.y;
	m.m[2][3] += at.z;
	return m;
}

/* ---- parse ------------------------------------------------------------------ */

static void raw_clear(struct scene_mesh *mesh)
{
	free(mesh->vertices);
	free(mesh->normals);
	free(mesh->tris);
	mesh->vertices = NULL;
	mesh->normals = NULL;
	mesh->tris = NULL;
	mesh->n_vertices = 0;
	mesh->n_triangles = 0;
}

/* Copies up to 32 bytes of the token at p for a message, escaping oddities. */
static void raw_token(char *dst, size_t cap, const char *p, const char *end)
{
	size_t o = 0;
	int k = 0;
	while (p < end && !raw_is_blank(*p) && *p != '\n' && *p != '\r' && k < 32 && o + 5 < cap) {
		unsigned char c = (unsigned char)*p++;
		if (c >= 0x20 && c < 0x7f && c != '\'' && c != '\\')
			dst[o++] = (char)c;
		else
			o += (size_t)snprintf(dst + o, cap - o, "\\x%02x", c);
		k++;
	}
	if (p < end && !raw_is_blank(*p) && *p != '\n' && *p != '\r' && o + 4 < cap) {
		memcpy(dst + o, "...", 3);
		o += 3;
	}
	dst[o] = '\0';
}

/*
 * Parses RAW text; see raw.h and the comment at the top of this file for the
 * exact format and the meaning of the options. The mesh's arrays on entry
 * are ignored (overwritten); on success the mesh owns new arrays, on error
 * they are NULL and err says "file:line: error: ...".
 */
int raw_parse(const char *buf, size_t len, struct scene_mesh *mesh, struct scene_error *err)
{
	const char *file = mesh->file ? mesh->file : "<raw>";
	const char *p = buf, *end = buf + len;
	struct raw_weld w;
	uint32_t *tris = NULL;
	size_t tcap = 0;
	uint32_t nt = 0;
	long line = 0;
	int rc = 0;

	memset(&w, 0, sizeof w);
	mesh->vertices = NULL;
	mesh->normals = NULL;
	mesh->tris = NULL;
	mesh->n_vertices = mesh->n_triangles = 0;

	if (!isfinite(mesh->weld) || mesh->weld < 0 || !v3_finite(mesh->rotation) || !v3_finite(mesh->at))
		return scene_errorf(err, ERRLEVEL_FATAL, "%s: error: invalid weld, rotation or at", file);
	if (mesh->weld > 0) {
		/* cells of 2d (and a hair), so a point is within d of at most one
		 * face of its cell along each axis: see raw_probe_range */
		w.cell = 2 * mesh->weld * (1.0 + 1e-9);
		w.d2 = mesh->weld * mesh->weld;
	}
	if (raw_cells_grow(&w) < 0)
		return scene_errorf(err, ERRLEVEL_FATAL, "%s: error: out of memory reading the mesh", file);
	if (len >= 3 && memcmp(p, "\xEF\xBB\xBF", 3) == 0)
		p += 3; /* a UTF-8 byte-order mark, as the scene lexer skips it */

	while (p < end) {
		double v[9];
		int n = 0;
		line++;
		for (;;) {
			while (p < end && raw_is_blank(*p))
				p++;
			if (p == end || *p == '\n' || *p == '\r')
				break;
			double x;
			const char *tok = p;
			int r = raw_number(&p, end, &x);
			if (r != RAW_NUM_OK) {
				char t[200];
				raw_token(t, sizeof t, tok, end);
				long col = 1;
				for (const char *q = tok; q > buf && q[-1] != '\n' && q[-1] != '\r'; q--)
					col++;
				rc = scene_errorf(err, ERRLEVEL_FATAL, "%s:%ld:%ld: error: %s '%s'", file, line, col,
						  r == RAW_NUM_SYNTAX ? "bad number" : "number out of range", t);
				goto fail;
			}
			if (n < 9)
				v[n] = x;
			n++;
		}
		if (p < end) {
			if (*p == '\r' && p + 1 < end && p[1] == '\n')
				p++;
			p++;
		}
		if (n == 0)
			continue;
		if (n != 9) {
			rc = scene_errorf(err, ERRLEVEL_FATAL, "%s:%ld: error: expected 9 numbers, found %d",
					  file, line, n);
			goto fail;
		}
		if (nt >= LIM_MESH_TRIANGLES) {
			rc = scene_errorf(err, ERRLEVEL_FATAL, "%s:%ld: error: more than %u triangles",
					  file, line, (unsigned)LIM_MESH_TRIANGLES);
			goto fail;
		}
		if (3 * (size_t)nt + 3 > tcap) {
			size_t ncap = tcap ? tcap * 2 : 3 * 1024;
			uint32_t *nb = realloc(tris, ncap * sizeof *nb);
			if (!nb)
				goto oom;
			tris = nb;
			tcap = ncap;
		}
		for (int k = 0; k < 3; k++) {
			uint32_t id = raw_weld_point(&w, v3(v[3 * k], v[3 * k + 1], v[3 * k + 2]));
			if (id == SCENE_NONE)
				goto oom;
			tris[3 * (size_t)nt + k] = id;
		}
		nt++;
	}
	if (nt == 0) {
		rc = scene_errorf(err, ERRLEVEL_FATAL, "%s: error: no triangles in the file", file);
		goto fail;
	}

	vec3 *normals = NULL;
	if (mesh->smooth) {
		normals = raw_normals(w.verts, w.n, tris, nt);
		if (!normals)
			goto oom;
	}
	if (mesh->rotation.x != 0 || mesh->rotation.y != 0 || mesh->rotation.z != 0 ||
	    mesh->at.x != 0 || mesh->at.y != 0 || mesh->at.z != 0) {
		mat34 m = raw_matrix(mesh->rotation, mesh->at);
		for (uint32_t i = 0; i < w.n; i++) {
			w.verts[i] = m34_point(&m, w.verts[i]);
			if (!v3_finite(w.verts[i])) {
				free(normals);
				rc = scene_errorf(err, ERRLEVEL_FATAL,
						  "%s: error: coordinates out of range after rotation and at", file);
				goto fail;
			}
		}
		for (uint32_t i = 0; normals && i < w.n; i++)
			normals[i] = v3_norm(m34_dir(&m, normals[i]));
	}

	free(w.cells);
	free(w.next);
	/* give back the slack of the doubling growth */
	vec3 *vv = realloc(w.verts, (size_t)w.n * sizeof *vv);
	mesh->vertices = vv ? vv : w.verts;
	uint32_t *tt = realloc(tris, 3 * (size_t)nt * sizeof *tt);
	mesh->tris = tt ? tt : tris;
	mesh->normals = normals;
	mesh->n_vertices = w.n;
	mesh->n_triangles = nt;
	return 0;

oom:
	rc = scene_errorf(err, ERRLEVEL_FATAL, "%s:%ld: error: out of memory reading the mesh", file, line);
fail:
	free(w.cells);
	free(w.next);
	free(w.verts);
	free(tris);
	raw_clear(mesh);
	return rc;
}

/*
 * Reads the whole file at path (lex_read_file: bounded by LIM_RAW_BYTES,
 * stopping at a NUL byte) and parses it. Messages name mesh->file when set,
 * else path.
 */
int raw_load(const char *path, struct scene_mesh *mesh, struct scene_error *err)
{
	const char *name = mesh->file ? mesh->file : path;
	char *buf = NULL;
	size_t n = 0;
	unsigned long long dev, ino;
	int nul_line = 0, nul_col = 0;
	int e = lex_read_file(path, LIM_RAW_BYTES, &buf, &n, &dev, &ino, &nul_line, &nul_col);
	if (e == EILSEQ)
		return scene_errorf(err, ERRLEVEL_FATAL, "%s:%d: error: NUL byte (a raw file is text)", name,
				    nul_line);
	if (e == EFBIG)
		return scene_errorf(err, ERRLEVEL_FATAL, "%s: error: raw file larger than %llu bytes", name,
				    (unsigned long long)LIM_RAW_BYTES);
	if (e == ENOMEM)
		return scene_errorf(err, ERRLEVEL_FATAL, "%s: error: out of memory reading the file", name);
	if (e)
		return scene_errorf(err, ERRLEVEL_FATAL, "%s: error: unable to open raw file: %s", name,
				    strerror(e));
	int rc = raw_parse(buf, n, mesh, err);
	free(buf);
	return rc;
}
