/*
 * test_raw.c - the RAW reader: parsing, whitespace, errors with line numbers,
 * welding (against a brute-force reference), smoothing normals, rotation and
 * AT, and the hand-written number parser against strtod.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "common/raw.h"
#include "tests/unit/check.h"

static void mesh_init(struct scene_mesh *m, const char *file)
{
	memset(m, 0, sizeof *m);
	m->file = (char *)file; /* not owned here: never freed by these tests */
	m->weld = 0.00001;
}

static void mesh_done(struct scene_mesh *m)
{
	free(m->vertices);
	free(m->normals);
	free(m->tris);
	m->vertices = m->normals = NULL;
	m->tris = NULL;
}

static int parse(const char *text, struct scene_mesh *m, struct scene_error *e)
{
	return raw_parse(text, strlen(text), m, e);
}

/* corner k of triangle t */
static vec3 corner(const struct scene_mesh *m, uint32_t t, int k)
{
	return m->vertices[m->tris[3 * t + k]];
}

static int veq(vec3 a, vec3 b, double eps)
{
	return fabs(a.x - b.x) <= eps && fabs(a.y - b.y) <= eps && fabs(a.z - b.z) <= eps;
}

static void test_basic(void)
{
	struct scene_mesh m;
	struct scene_error e;
	mesh_init(&m, "t.raw");
	CHECK(parse("0 0 0 1 0 0 0 1 0\n1 0 0 1 1 0 0 1 0\n", &m, &e) == 0);
	CHECK(m.n_triangles == 2);
	CHECK(m.n_vertices == 4);
	CHECK(m.normals == NULL);
	if (m.n_triangles == 2) {
		CHECK(veq(corner(&m, 0, 0), v3(0, 0, 0), 0));
		CHECK(veq(corner(&m, 0, 1), v3(1, 0, 0), 0));
		CHECK(veq(corner(&m, 0, 2), v3(0, 1, 0), 0));
		CHECK(veq(corner(&m, 1, 1), v3(1, 1, 0), 0));
		CHECK(m.tris[3] == m.tris[1]); /* shared corner (1 0 0) */
		CHECK(m.tris[5] == m.tris[2]); /* shared corner (0 1 0) */
	}
	mesh_done(&m);

	/* number forms */
	mesh_init(&m, "t.raw");
	CHECK(parse("-1.5 +2 .25 3. 1e2 -2E-1 0.000 -0 1e+1\n", &m, &e) == 0);
	if (m.n_triangles == 1) {
		CHECK(veq(corner(&m, 0, 0), v3(-1.5, 2, 0.25), 0));
		CHECK(veq(corner(&m, 0, 1), v3(3, 100, -0.2), 0));
		CHECK(veq(corner(&m, 0, 2), v3(0, 0, 10), 0));
	}
	mesh_done(&m);

	/* degenerate triangles are kept: the count equals the lines */
	mesh_init(&m, "t.raw");
	CHECK(parse("0 0 0 0 0 0 0 0 0\n0 0 0 1 0 0 2 0 0\n", &m, &e) == 0);
	CHECK(m.n_triangles == 2);
	CHECK(m.n_vertices == 3);
	mesh_done(&m);
}

/* Every whitespace variant of the same two triangles gives the same mesh. */
static void test_whitespace(void)
{
	static const char *variants[] = {
		"0 0 0 1 0 0 0 1 0\n1 0 0 1 1 0 0 1 0\n",
		"0 0 0 1 0 0 0 1 0\n1 0 0 1 1 0 0 1 0",          /* no final newline */
		"0\t0\t0\t1\t0\t0\t0\t1\t0\n1 0 0\t\t1 1 0   0 1 0\n", /* tabs, runs */
		"0 0 0 1 0 0 0 1 0\r\n1 0 0 1 1 0 0 1 0\r\n",    /* CRLF */
		"0 0 0 1 0 0 0 1 0\r1 0 0 1 1 0 0 1 0\r",        /* old Mac CR */
		"\n\n   \n0 0 0 1 0 0 0 1 0   \n \t \n  1 0 0 1 1 0 0 1 0\n\n\n", /* blanks */
		"\f0 0 0 1 0 0 0 1 0\v\n1 0 0 1 1 0 0 1 0\r\n\r\n",
		("\xEF\xBB\xBF" "0 0 0 1 0 0 0 1 0\r\n1 0 0 1 1 0 0 1 0\r\n"), /* UTF-8 byte-order mark */
	};
	for (size_t i = 0; i < sizeof variants / sizeof variants[0]; i++) {
		struct scene_mesh m;
		struct scene_error e;
		mesh_init(&m, "w.raw");
		int rc = parse(variants[i], &m, &e);
		CHECK(rc == 0);
		if (rc)
			fprintf(stderr, "variant %zu: %s\n", i, e.msg);
		CHECK(m.n_triangles == 2 && m.n_vertices == 4);
		if (m.n_triangles == 2) {
			CHECK(veq(corner(&m, 1, 1), v3(1, 1, 0), 0));
			CHECK(veq(corner(&m, 0, 2), v3(0, 1, 0), 0));
		}
		mesh_done(&m);
	}
}

static void expect_error(const char *text, const char *msg)
{
	struct scene_mesh m;
	struct scene_error e;
	mesh_init(&m, "dragon.raw");
	memset(&e, 0, sizeof e);
	int rc = parse(text, &m, &e);
	CHECK(rc == 1);
	CHECK(e.level == 1);
	CHECK(strstr(e.msg, msg) != NULL);
	if (!strstr(e.msg, msg))
		fprintf(stderr, "  wanted '%s', got '%s'\n", msg, e.msg);
	CHECK(m.vertices == NULL && m.tris == NULL && m.normals == NULL);
	CHECK(m.n_triangles == 0 && m.n_vertices == 0);
}

static void test_errors(void)
{
	const char *ok = "0 0 0 1 0 0 0 1 0\n";
	char buf[256];
	snprintf(buf, sizeof buf, "%s\n%s1 2 3 4 5 6 7\n", ok, ok);
	expect_error(buf, "dragon.raw:4: error: expected 9 numbers, found 7");
	snprintf(buf, sizeof buf, "%s1 2 3 4 5 6 7 8 9 10\n", ok);
	expect_error(buf, "dragon.raw:2: error: expected 9 numbers, found 10");
	expect_error("Object1\n0 0 0 1 0 0 0 1 0\n", "dragon.raw:1:1: error: bad number 'Object1'");
	expect_error("0 0 0 1 0 0 0 1 0\r\n0 0 0 1 0 0 0 1.5x 0\r\n", "dragon.raw:2:15: error: bad number '1.5x'");
	expect_error("0 0 0 1 0 0 0 1 0\r0 0 0 1 0 0 0 1 0\r1 2\r", "dragon.raw:3: error: expected 9 numbers, found 2");
	expect_error("0 0 0 1 0 0 0 1 inf\n", "bad number 'inf'");
	expect_error("0 0 0 1 0 0 0 1 nan\n", "bad number 'nan'");
	expect_error("0 0 0 1 0 0 0 1 0x10\n", "bad number '0x10'");
	expect_error("0 0 0 1 0 0 0 1 1e\n", "bad number '1e'");
	expect_error("0 0 0 1 0 0 0 1 1e+\n", "bad number '1e+'");
	expect_error("0 0 0 1 0 0 0 1 .\n", "bad number '.'");
	expect_error("0 0 0 1 0 0 0 1 -\n", "bad number '-'");
	expect_error("0 0 0 1 0 0 0 1 e5\n", "bad number 'e5'");
	expect_error("0 0 0 1 0 0 0 1 1,5\n", "bad number '1,5'");
	expect_error("0 0 0 1 0 0 0 1 --1\n", "bad number '--1'");
	expect_error("0 0 0 1 0 0 0 1 1e999\n", "dragon.raw:1:17: error: number out of range '1e999'");
	expect_error("0 0 0 1 0 0 0 1 1e101\n", "number out of range");
	expect_error("", "dragon.raw: error: no triangles");
	expect_error("\n \n\t\r\n", "dragon.raw: error: no triangles");
	/* a NUL byte inside the text */
	{
		struct scene_mesh m;
		struct scene_error e;
		mesh_init(&m, "z.raw");
		static const char nul[] = "0 0 0 1 0 0 0 1 0\n0 0 0 1 0 0\0 0 1 0\n";
		CHECK(raw_parse(nul, sizeof nul - 1, &m, &e) == 1);
		CHECK(strstr(e.msg, "z.raw:2:11: error: bad number '0\\x00'") != NULL);
		CHECK(m.tris == NULL);
	}
	/* bad options */
	{
		struct scene_mesh m;
		struct scene_error e;
		mesh_init(&m, "o.raw");
		m.weld = -1;
		CHECK(parse(ok, &m, &e) == 1);
		mesh_init(&m, "o.raw");
		m.at.x = INFINITY;
		CHECK(parse(ok, &m, &e) == 1);
	}
	/* an absurdly long number goes to the slow path and is rejected, not read past */
	{
		size_t n = 5000;
		char *big = malloc(n + 64);
		memset(big, '1', n);
		big[0] = '0';
		big[1] = '.';
		strcpy(big + n, " 0 0 1 0 0 0 1 0\n");
		struct scene_mesh m;
		struct scene_error e;
		mesh_init(&m, "long.raw");
		CHECK(parse(big, &m, &e) == 1);
		CHECK(strstr(e.msg, "long.raw:1:1: error: number out of range '0.111111") != NULL);
		free(big);
	}
}

/* ---- weld ---------------------------------------------------------------- */

/* The 12 triangles of the unit cube, outward facing. */
static const char cube_raw[] =
	"0 0 0 0 1 0 1 1 0\n0 0 0 1 1 0 1 0 0\n" /* z = 0, normal -z */
	"0 0 1 1 0 1 1 1 1\n0 0 1 1 1 1 0 1 1\n" /* z = 1, normal +z */
	"0 0 0 1 0 0 1 0 1\n0 0 0 1 0 1 0 0 1\n" /* y = 0, normal -y */
	"0 1 0 0 1 1 1 1 1\n0 1 0 1 1 1 1 1 0\n" /* y = 1, normal +y */
	"0 0 0 0 0 1 0 1 1\n0 0 0 0 1 1 0 1 0\n" /* x = 0, normal -x */
	"1 0 0 1 1 0 1 1 1\n1 0 0 1 1 1 1 0 1\n"; /* x = 1, normal +x */

static void test_weld_cube(void)
{
	struct scene_mesh m;
	struct scene_error e;
	mesh_init(&m, "cube.raw");
	CHECK(parse(cube_raw, &m, &e) == 0);
	CHECK(m.n_triangles == 12);
	CHECK(m.n_vertices == 8);
	/* every face normal (B-A)x(C-A) points away from the centre */
	for (uint32_t t = 0; t < m.n_triangles; t++) {
		vec3 a = corner(&m, t, 0), b = corner(&m, t, 1), c = corner(&m, t, 2);
		vec3 n = v3_cross(v3_sub(b, a), v3_sub(c, a));
		vec3 ctr = v3_scale(v3_add(v3_add(a, b), c), 1.0 / 3);
		CHECK(v3_dot(n, v3_sub(ctr, v3(0.5, 0.5, 0.5))) > 0);
	}
	mesh_done(&m);

	/* a cube whose corners are jittered by less than the weld distance */
	char buf[2048];
	size_t o = 0;
	uint32_t seed = 7;
	for (const char *p = cube_raw; *p; p++) {
		if (*p == '0' || *p == '1') {
			seed = seed * 1664525u + 1013904223u;
			double j = ((seed >> 8) / 16777216.0 - 0.5) * 0.4e-5; /* |j| <= 2e-6 */
			o += (size_t)snprintf(buf + o, sizeof buf - o, "%.9f", (*p - '0') + j);
		} else {
			buf[o++] = *p;
		}
	}
	buf[o] = '\0';
	mesh_init(&m, "jcube.raw");
	CHECK(parse(buf, &m, &e) == 0);
	CHECK(m.n_vertices == 8);
	mesh_done(&m);
	/* with weld 0 the jittered corners stay apart: 36 corners */
	mesh_init(&m, "jcube.raw");
	m.weld = 0;
	CHECK(parse(buf, &m, &e) == 0);
	CHECK(m.n_vertices == 36);
	mesh_done(&m);
	/* weld 0 still merges identical points */
	mesh_init(&m, "cube.raw");
	m.weld = 0;
	CHECK(parse(cube_raw, &m, &e) == 0);
	CHECK(m.n_vertices == 8);
	mesh_done(&m);
	/* a weld larger than the cube merges everything into one point */
	mesh_init(&m, "cube.raw");
	m.weld = 10;
	CHECK(parse(cube_raw, &m, &e) == 0);
	CHECK(m.n_vertices == 1 && m.n_triangles == 12);
	mesh_done(&m);
	/* exactly at the distance: not closer than d, so not merged */
	mesh_init(&m, "d.raw");
	m.weld = 0.5;
	CHECK(parse("0 0 0 1 0 0 0 1 0\n0.5 0 0 1 0 0 0 1 0\n", &m, &e) == 0);
	CHECK(m.n_vertices == 4);
	mesh_done(&m);
	mesh_init(&m, "d.raw");
	m.weld = 0.5;
	CHECK(parse("0 0 0 1 0 0 0 1 0\n0.49 0 0 1 0 0 0 1 0\n", &m, &e) == 0);
	CHECK(m.n_vertices == 3);
	mesh_done(&m);
}

/* The weld rule, by brute force: nearest kept vertex closer than d (ties: lowest index). */
static uint32_t brute_weld(vec3 *kept, uint32_t *nk, vec3 p, double d)
{
	uint32_t best = UINT32_MAX;
	double bd = 0;
	for (uint32_t i = 0; i < *nk; i++) {
		vec3 q = v3_sub(kept[i], p);
		double dd = v3_dot(q, q);
		if ((dd < d * d || dd == 0) && (best == UINT32_MAX || dd < bd)) {
			best = i;
			bd = dd;
		}
	}
	if (best != UINT32_MAX)
		return best;
	kept[*nk] = p;
	return (*nk)++;
}

static void test_weld_random(void)
{
	/* points on a coarse lattice plus small noise, so that many pairs sit
	 * near the weld distance and straddle grid cells in every direction */
	enum { NT = 600 };
	static double pts[NT * 9];
	static vec3 kept[NT * 3];
	uint32_t seed = 12345;
	/* (d, offset): far from the origin the grid keys pass 2^52 and 2^53,
	 * where doubles are spaced by about d */
	static const double rounds[][2] = { { 0.01, 0 },     { 0.003, 0 },    { 1e-5, 0 },  { 0.25, 0 },
					    { 1e-5, 3e10 },  { 1e-5, 6e10 },  { 1e-4, 1e12 }, { 3e-4, 1e12 },
					    { 0.01, -7e13 } };
	for (size_t round = 0; round < sizeof rounds / sizeof rounds[0]; round++) {
		double d = rounds[round][0], base = rounds[round][1];
		char *text = malloc(NT * 9 * 32);
		CHECK(text != NULL);
		if (!text)
			break;
		size_t o = 0;
		for (int i = 0; i < NT * 9; i++) {
			seed = seed * 1664525u + 1013904223u;
			int lat = (int)((seed >> 16) % 5);
			seed = seed * 1664525u + 1013904223u;
			double noise = ((seed >> 8) / 16777216.0 - 0.5) * 3 * d;
			char num[40];
			snprintf(num, sizeof num, "%.17g", base ? base + lat * 2 * d + noise : lat * 0.02 + noise - 0.04);
			pts[i] = strtod(num, NULL);
			o += (size_t)sprintf(text + o, "%s%c", num, i % 9 == 8 ? '\n' : ' ');
		}
		struct scene_mesh m;
		struct scene_error e;
		mesh_init(&m, "rand.raw");
		m.weld = d;
		CHECK(raw_parse(text, o, &m, &e) == 0);
		uint32_t nk = 0, mismatches = 0;
		for (int c = 0; c < NT * 3; c++) {
			uint32_t id = brute_weld(kept, &nk, v3(pts[3 * c], pts[3 * c + 1], pts[3 * c + 2]), d);
			if (!m.tris || m.tris[c] != id)
				mismatches++;
		}
		CHECK(mismatches == 0);
		if (mismatches)
			fprintf(stderr, "weld round %zu: %u mismatches\n", round, mismatches);
		CHECK(m.n_vertices == nk);
		CHECK(nk > 1 && nk < NT * 3); /* the case is not trivial */
		if (getenv("TEST_RAW_VERBOSE"))
			fprintf(stderr, "weld round %zu: %u vertices of %d\n", round, nk, NT * 3);
		mesh_done(&m);
		free(text);
	}
}

/* ---- smoothing ------------------------------------------------------------- */

static void test_smooth(void)
{
	struct scene_mesh m;
	struct scene_error e;

	/* cube: each corner touches one or two triangles per face; angle
	 * weighting gives every face 90 degrees, so the normal is the diagonal */
	mesh_init(&m, "cube.raw");
	m.smooth = true;
	CHECK(parse(cube_raw, &m, &e) == 0);
	CHECK(m.normals != NULL);
	for (uint32_t i = 0; m.normals && i < m.n_vertices; i++) {
		vec3 dir = v3_norm(v3_sub(m.vertices[i], v3(0.5, 0.5, 0.5)));
		CHECK(veq(m.normals[i], dir, 1e-12));
	}
	mesh_done(&m);

	/* octahedron: normals are the unit positions */
	static const char octa[] = "1 0 0 0 1 0 0 0 1\n0 1 0 -1 0 0 0 0 1\n-1 0 0 0 -1 0 0 0 1\n"
				   "0 -1 0 1 0 0 0 0 1\n0 1 0 1 0 0 0 0 -1\n-1 0 0 0 1 0 0 0 -1\n"
				   "0 -1 0 -1 0 0 0 0 -1\n1 0 0 0 -1 0 0 0 -1\n";
	mesh_init(&m, "octa.raw");
	m.smooth = true;
	CHECK(parse(octa, &m, &e) == 0);
	CHECK(m.n_vertices == 6 && m.n_triangles == 8);
	for (uint32_t i = 0; m.normals && i < m.n_vertices; i++)
		CHECK(veq(m.normals[i], m.vertices[i], 1e-12));
	mesh_done(&m);

	/* a vertex shared by a 90-degree face (normal +z) and a 45-degree face
	 * (normal +y): angle weights 2:1 (area weights would be 1:1 here) */
	mesh_init(&m, "w.raw");
	m.smooth = true;
	CHECK(parse("0 0 0 1 0 0 0 1 0\n0 0 0 0 0 1 1 0 1\n", &m, &e) == 0);
	if (m.normals) {
		vec3 want = v3_norm(v3(0, M_PI / 4, M_PI / 2));
		CHECK(veq(m.normals[m.tris[0]], want, 1e-12));
		/* (0 1 0) touches only the first face */
		CHECK(veq(m.normals[m.tris[2]], v3(0, 0, 1), 1e-12));
	}
	mesh_done(&m);

	/* subnormal edge lengths still give unit normals (found by fuzz_raw) */
	mesh_init(&m, "s.raw");
	m.smooth = true;
	m.weld = 0;
	CHECK(parse("9e-324 1 0 0 1 1 0 1 0\n", &m, &e) == 0);
	for (uint32_t i = 0; m.normals && i < m.n_vertices; i++)
		CHECK(fabs(v3_len(m.normals[i]) - 1) < 1e-12);
	mesh_done(&m);

	/* cancelling faces (one triangle both ways round) and degenerate ones */
	mesh_init(&m, "c.raw");
	m.smooth = true;
	CHECK(parse("0 0 0 1 0 0 0 1 0\n0 0 0 0 1 0 1 0 0\n5 5 5 5 5 5 6 6 6\n", &m, &e) == 0);
	for (uint32_t i = 0; m.normals && i < m.n_vertices; i++) {
		CHECK(fabs(v3_len(m.normals[i]) - 1) < 1e-12);
		if (i < 3)
			CHECK(veq(m.normals[i], v3(0, 0, 1), 1e-12));
	}
	mesh_done(&m);
}

/* ---- rotation and AT -------------------------------------------------------- */

static void test_rotation_at(void)
{
	struct scene_mesh m;
	struct scene_error e;
	const char *tri = "1 0 0 0 1 0 0 0 1\n";

	/* z-rotation turns x toward y */
	mesh_init(&m, "r.raw");
	m.rotation = v3(0, 0, 90);
	CHECK(parse(tri, &m, &e) == 0);
	CHECK(veq(corner(&m, 0, 0), v3(0, 1, 0), 1e-15));
	CHECK(veq(corner(&m, 0, 1), v3(-1, 0, 0), 1e-15));
	CHECK(veq(corner(&m, 0, 2), v3(0, 0, 1), 1e-15));
	mesh_done(&m);

	/* x-rotation turns y toward z; y-rotation turns z toward x */
	mesh_init(&m, "r.raw");
	m.rotation = v3(90, 0, 0);
	CHECK(parse(tri, &m, &e) == 0);
	CHECK(veq(corner(&m, 0, 1), v3(0, 0, 1), 1e-15));
	mesh_done(&m);
	mesh_init(&m, "r.raw");
	m.rotation = v3(0, 90, 0);
	CHECK(parse(tri, &m, &e) == 0);
	CHECK(veq(corner(&m, 0, 2), v3(1, 0, 0), 1e-15));
	mesh_done(&m);

	/* order: x first, then y: (0 1 0) -x-> (0 0 1) -y-> (1 0 0)
	 * (y first would give (0 0 1)) */
	mesh_init(&m, "r.raw");
	m.rotation = v3(90, 90, 0);
	CHECK(parse(tri, &m, &e) == 0);
	CHECK(veq(corner(&m, 0, 1), v3(1, 0, 0), 1e-15));
	mesh_done(&m);
	/* and y before z: (0 0 1) -y-> (1 0 0) -z-> (0 1 0) */
	mesh_init(&m, "r.raw");
	m.rotation = v3(0, 90, 90);
	CHECK(parse(tri, &m, &e) == 0);
	CHECK(veq(corner(&m, 0, 2), v3(0, 1, 0), 1e-15));
	mesh_done(&m);

	/* AT: the file's origin lands on the world point AT, after rotation */
	mesh_init(&m, "a.raw");
	m.rotation = v3(0, 0, 90);
	m.at = v3(10, 20, 30);
	CHECK(parse(tri, &m, &e) == 0);
	CHECK(veq(corner(&m, 0, 0), v3(10, 21, 30), 1e-13));
	CHECK(veq(corner(&m, 0, 1), v3(9, 20, 30), 1e-13));
	CHECK(veq(corner(&m, 0, 2), v3(10, 20, 31), 1e-13));
	mesh_done(&m);

	/* normals rotate with the mesh and ignore AT */
	mesh_init(&m, "cube.raw");
	m.smooth = true;
	m.rotation = v3(30, 45, 60);
	m.at = v3(-3, 4, 5);
	CHECK(parse(cube_raw, &m, &e) == 0);
	if (m.normals) {
		/* the cube's centre moved to R*(0.5 0.5 0.5)+at: recover it as the mean */
		vec3 ctr = v3(0, 0, 0);
		for (uint32_t i = 0; i < m.n_vertices; i++)
			ctr = v3_add(ctr, m.vertices[i]);
		ctr = v3_scale(ctr, 1.0 / m.n_vertices);
		for (uint32_t i = 0; i < m.n_vertices; i++)
			CHECK(veq(m.normals[i], v3_norm(v3_sub(m.vertices[i], ctr)), 1e-12));
	}
	mesh_done(&m);

	/* AT pushing coordinates out of range is an error, not infinities */
	mesh_init(&m, "big.raw");
	m.at = v3(1e308, 0, 0);
	CHECK(parse("1e100 0 0 0 1 0 0 0 1\n", &m, &e) == 0 || strstr(e.msg, "out of range"));
	if (m.vertices)
		for (uint32_t i = 0; i < m.n_vertices; i++)
			CHECK(v3_finite(m.vertices[i]));
	mesh_done(&m);
	mesh_init(&m, "big.raw");
	m.at = v3(1.7e308, 0, 0);
	m.rotation = v3(0, 0, 0);
	CHECK(parse("1e100 0 0 0 1 0 0 0 1\n", &m, &e) == 0);
	mesh_done(&m);
}

/* ---- numbers vs strtod ----------------------------------------------------- */

static uint32_t rng_state = 99;
static uint32_t rnd(void)
{
	rng_state ^= rng_state << 13;
	rng_state ^= rng_state >> 17;
	rng_state ^= rng_state << 5;
	return rng_state;
}

/* A random number text: sign, 0-25 integer digits, optional point and 0-25
 * fraction digits, optional exponent in [-130, 110]; at least one digit. */
static void random_number(char *s)
{
	size_t o = 0;
	uint32_t r = rnd();
	if (r % 3 == 0)
		s[o++] = '-';
	else if (r % 7 == 0)
		s[o++] = '+';
	int ni = (int)(rnd() % 26), nf = (int)(rnd() % 26);
	if (rnd() % 2)
		ni = (int)(rnd() % 4), nf = (int)(rnd() % 10); /* common short shapes */
	int lead0 = rnd() % 4 == 0;
	for (int i = 0; i < ni; i++)
		s[o++] = (char)('0' + (lead0 && i < 3 ? 0 : rnd() % 10));
	if (nf || !ni || rnd() % 4 == 0) {
		s[o++] = '.';
		for (int i = 0; i < nf; i++)
			s[o++] = (char)('0' + rnd() % 10);
	}
	if (!ni && !nf)
		s[o++] = '5';
	if (rnd() % 3 == 0) {
		s[o++] = rnd() % 2 ? 'e' : 'E';
		int ex = (int)(rnd() % 241) - 130;
		o += (size_t)sprintf(s + o, rnd() % 2 && ex >= 0 ? "+%d" : "%d", ex);
	}
	s[o] = '\0';
}

static void test_numbers(void)
{
	enum { N = 9 * 4000 };
	static double want[N];
	char *text = malloc((size_t)N * 80);
	size_t o = 0;
	int n = 0;
	while (n < N) {
		char s[80];
		if (n % 3 == 0)
			snprintf(s, sizeof s, "%.*g", 1 + (int)(rnd() % 19),
				 (rnd() / 4294967296.0 - 0.5) * pow(10, (int)(rnd() % 40) - 20));
		else
			random_number(s);
		double x = strtod(s, NULL);
		if (!(fabs(x) <= 1e100))
			continue;
		want[n] = x;
		o += (size_t)sprintf(text + o, "%s%c", s, n % 9 == 8 ? '\n' : ' ');
		n++;
	}
	struct scene_mesh m;
	struct scene_error e;
	mesh_init(&m, "num.raw");
	m.weld = 0;
	int rc = raw_parse(text, o, &m, &e);
	CHECK(rc == 0);
	if (rc)
		fprintf(stderr, "%s\n", e.msg);
	int bad = 0, inexact = 0;
	for (int i = 0; rc == 0 && i < N; i++) {
		vec3 v = m.vertices[m.tris[i / 3]];
		double got = v3_comp(v, i % 3);
		double rel = want[i] == 0 ? fabs(got) : fabs(got - want[i]) / fabs(want[i]);
		if (!(rel < 1e-15))
			bad++;
		if (got != want[i] && !(got == 0 && want[i] == 0))
			inexact++;
	}
	CHECK(bad == 0);
	/* the fast path is correctly rounded and the rest is strtod: all exact */
	CHECK(inexact == 0);
	if (bad || inexact)
		fprintf(stderr, "numbers: %d beyond 1e-15, %d not bit-exact\n", bad, inexact);
	mesh_done(&m);
	free(text);

	/* hand-picked edges */
	static const char *edge[] = { "9007199254740993", "9007199254740992", "1e22", "1e23",
				      "1e-22", "1e-23", "0.1", "0.3", "123456789012345678901234567890",
				      "0.0000000000000000000000000000001234567", "4.9e-324", "2.2250738585072011e-308",
				      "1.00000000000000011102230246251565404236316680908203125",
				      "1.00000000000000011102230246251565404236316680908203124",
				      "99999999999999999999e-20", "1e100", "-1e100", "00000000000000000000000001.5" };
	for (size_t i = 0; i < sizeof edge / sizeof edge[0]; i++) {
		char line[256];
		snprintf(line, sizeof line, "%s 0 0 0 0 0 0 0 0\n", edge[i]);
		mesh_init(&m, "edge.raw");
		m.weld = 0;
		CHECK(parse(line, &m, &e) == 0);
		if (m.vertices) {
			CHECK(m.vertices[m.tris[0]].x == strtod(edge[i], NULL));
			if (m.vertices[m.tris[0]].x != strtod(edge[i], NULL))
				fprintf(stderr, "edge %s: %.17g\n", edge[i], m.vertices[m.tris[0]].x);
		}
		mesh_done(&m);
	}
}

/* ---- raw_load ------------------------------------------------------------------ */

static void test_load(void)
{
	char path[] = "/tmp/test_raw_XXXXXX";
	int fd = mkstemp(path);
	CHECK(fd >= 0);
	if (fd < 0)
		return;
	CHECK(write(fd, cube_raw, sizeof cube_raw - 1) == (ssize_t)(sizeof cube_raw - 1));
	close(fd);
	struct scene_mesh m;
	struct scene_error e;
	mesh_init(&m, NULL);
	CHECK(raw_load(path, &m, &e) == 0);
	CHECK(m.n_triangles == 12 && m.n_vertices == 8);
	mesh_done(&m);
	unlink(path);

	/* a real mesh (run from the repository root, as make test does):
	 * 5856 triangles, 2930 distinct corners (counted with Python) */
	mesh_init(&m, "spot.raw");
	m.weld = 0;
	m.smooth = true;
	if (raw_load("tests/data/meshes/spot.raw", &m, &e) == 0) {
		CHECK(m.n_triangles == 5856);
		CHECK(m.n_vertices == 2930);
		CHECK(m.normals != NULL);
		mesh_done(&m);
	} else {
		fprintf(stderr, "spot.raw: %s\n", e.msg);
		CHECK(0);
	}

	mesh_init(&m, "missing.raw");
	CHECK(raw_load("/nonexistent/missing.raw", &m, &e) == 1);
	CHECK(strstr(e.msg, "missing.raw: error: unable to open raw file") != NULL);
	CHECK(m.tris == NULL);
	mesh_init(&m, "dir.raw");
	CHECK(raw_load("/tmp", &m, &e) == 1);
	CHECK(strstr(e.msg, "dir.raw: error: unable to open raw file") != NULL);
}

int main(void)
{
	test_basic();
	test_whitespace();
	test_errors();
	test_weld_cube();
	test_weld_random();
	test_smooth();
	test_rotation_at();
	test_numbers();
	test_load();
	TEST_MAIN_END();
}
