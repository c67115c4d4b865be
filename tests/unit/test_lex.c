/*
 * test_lex.c - the lexer: token kinds, positions, comments, numbers,
 * keywords in any case and their aliases, limits and errors.
 */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/lex.h"
#include "common/limits.h"
#include "tests/unit/check.h"

/* Lexes text and returns the n-th token (0-based). */
static struct token nth(const char *text, int n)
{
	static struct lexer lx;
	struct token t;
	lex_init(&lx, text, strlen(text));
	for (int i = 0; i <= n; i++)
		lex_next(&lx, &t);
	return t;
}

static int tok_is(const struct token *t, const char *s)
{
	return t->len == strlen(s) && memcmp(t->text, s, t->len) == 0;
}

static void test_kinds_positions(void)
{
	const char *src = "object\n  Sphere centre (1 -2.5 3e2) ;\n\t;";
	struct lexer lx;
	struct token t;
	lex_init(&lx, src, strlen(src));
	lex_next(&lx, &t);
	CHECK(t.kind == TK_WORD && t.kw == KW_OBJECT && t.line == 1 && t.col == 1);
	lex_next(&lx, &t);
	CHECK(t.kind == TK_WORD && t.kw == KW_SPHERE && t.line == 2 && t.col == 3 && tok_is(&t, "Sphere"));
	lex_next(&lx, &t);
	CHECK(t.kw == KW_CENTRE && t.col == 10);
	lex_next(&lx, &t);
	CHECK(t.kind == TK_LPAREN && t.col == 17);
	lex_next(&lx, &t);
	CHECK(t.num == NUM_OK && t.value == 1 && t.col == 18);
	lex_next(&lx, &t);
	CHECK(t.num == NUM_OK && t.value == -2.5);
	lex_next(&lx, &t);
	CHECK(t.num == NUM_OK && t.value == 300 && t.kw == KW_NONE);
	lex_next(&lx, &t);
	CHECK(t.kind == TK_RPAREN && t.col == 28);
	lex_next(&lx, &t);
	CHECK(t.kind == TK_SEMI && t.line == 2 && t.col == 30);
	lex_next(&lx, &t);
	CHECK(t.kind == TK_SEMI && t.line == 3 && t.col == 2);
	lex_next(&lx, &t);
	CHECK(t.kind == TK_EOF && t.line == 3 && t.col == 3);
	lex_next(&lx, &t);
	CHECK(t.kind == TK_EOF);
}

static void test_comments(void)
{
	struct token t = nth("~ a comment\nover ~two~ lines ~ camera", 0);
	CHECK(tok_is(&t, "two") && t.line == 2 && t.col == 7);
	t = nth("~ a comment\nover ~two~ lines ~ camera", 1);
	CHECK(t.kw == KW_CAMERA && t.line == 2 && t.col == 20);
	t = nth("// all of this\n  light // and this ;\nimage", 1);
	CHECK(t.kw == KW_IMAGE && t.line == 3 && t.col == 1);
	t = nth("file ../x/y.inc//comment", 1);
	CHECK(t.kind == TK_WORD && tok_is(&t, "../x/y.inc"));
	t = nth("file ../x/y.inc//comment", 2);
	CHECK(t.kind == TK_EOF);
	t = nth("a~b~c", 1);
	CHECK(tok_is(&t, "c"));
	struct lexer lx;
	const char *bad = "camera\n  ~ never closed\n";
	lex_init(&lx, bad, strlen(bad));
	lex_next(&lx, &t);
	lex_next(&lx, &t);
	CHECK(t.kind == TK_ERROR && t.line == 2 && t.col == 3 && strstr(lx.errmsg, "unfinished"));
	lex_next(&lx, &t);
	CHECK(t.kind == TK_ERROR); /* sticky */
}

static void test_numbers(void)
{
	double v = 0;
	CHECK(lex_number("42", 2, &v) == NUM_OK && v == 42);
	CHECK(lex_number("+4.5", 4, &v) == NUM_OK && v == 4.5);
	CHECK(lex_number("-.5", 3, &v) == NUM_OK && v == -0.5);
	CHECK(lex_number("5.", 2, &v) == NUM_OK && v == 5);
	CHECK(lex_number("1.5E-3", 6, &v) == NUM_OK && v == 1.5e-3);
	CHECK(lex_number("2e+2", 4, &v) == NUM_OK && v == 200);
	CHECK(lex_number("1.2.3", 5, &v) == NUM_BAD);
	CHECK(lex_number("1e", 2, &v) == NUM_BAD);
	CHECK(lex_number("1e999", 5, &v) == NUM_BAD);
	CHECK(lex_number("3abc", 4, &v) == NUM_BAD);
	CHECK(lex_number("-", 1, &v) == NUM_NO);
	CHECK(lex_number("-x", 2, &v) == NUM_NO);
	CHECK(lex_number(".", 1, &v) == NUM_NO);
	CHECK(lex_number("flat-red", 8, &v) == NUM_NO);
	CHECK(lex_number("0x10", 4, &v) == NUM_BAD);
	CHECK(lex_number("nan", 3, &v) == NUM_NO);
	struct token t = nth("(1 2 3)", 3);
	CHECK(t.num == NUM_OK && t.value == 3);
	t = nth("radius 2;", 1);
	CHECK(t.num == NUM_OK && t.value == 2 && t.len == 1);
}

/* A tiny deterministic generator for the strtod comparison. */
static uint64_t num_rng = 0x9e3779b97f4a7c15ull;
static unsigned num_next(unsigned n)
{
	num_rng ^= num_rng << 13, num_rng ^= num_rng >> 7, num_rng ^= num_rng << 17;
	return (unsigned)(num_rng % n);
}

/*
 * lex_number's fast path (Clinger's: m < 2^53 exactly, |e10| <= 22) and
 * its strtod fallback give strtod's value, sign of zero included, for
 * numbers of every shape the grammar allows: leading and trailing zeros,
 * up to 25 digits (more than 19 significant ones are dropped into e10),
 * exponents from -330 to 330, halfway cases such as 9007199254740993.
 */
static void test_numbers_vs_strtod(void)
{
	const char *fixed[] = { "9007199254740992", "9007199254740993", "9007199254740994", "0.1", "-0", "-0.0e5",
				"1e22", "1e23", "1e-22", "1e-23", "123456789012345678901234", "0.000000000000000000001",
				"4.9406564584124654e-324", "2.2250738585072011e-308", "1.7976931348623157e308",
				"00000000000000000000001.5", "1234567890123456789", "12345678901234567890" };
	char buf[64];
	int bad = 0;
	for (int k = 0; k < 20000 + (int)(sizeof fixed / sizeof fixed[0]); k++) {
		size_t n = 0;
		if (k < (int)(sizeof fixed / sizeof fixed[0])) {
			n = strlen(fixed[k]);
			memcpy(buf, fixed[k], n + 1);
		} else {
			if (num_next(3) == 0)
				buf[n++] = num_next(2) ? '-' : '+';
			unsigned ip = num_next(12), fp = num_next(3) ? num_next(14) : 0;
			for (unsigned i = 0; i < ip; i++)
				buf[n++] = (char)('0' + (num_next(4) ? num_next(10) : 0));
			if (fp || ip == 0) {
				buf[n++] = '.';
				for (unsigned i = 0; i < fp + (ip == 0); i++)
					buf[n++] = (char)('0' + num_next(10));
			}
			if (num_next(3) == 0)
				n += (size_t)snprintf(buf + n, sizeof buf - n, "e%d", (int)num_next(661) - 330);
			buf[n] = '\0';
		}
		double v = 12345, want = strtod(buf, NULL);
		int r = lex_number(buf, n, &v);
		if (!isfinite(want))
			bad += r != NUM_BAD;
		else
			bad += r != NUM_OK || memcmp(&v, &want, sizeof v) != 0;
	}
	CHECK(bad == 0);
}

static void test_keywords(void)
{
	CHECK(lex_keyword("OBJECT", 6) == KW_OBJECT);
	CHECK(lex_keyword("Look-From", 9) == KW_LOOK_FROM);
	CHECK(lex_keyword("color", 5) == KW_COLOUR);
	CHECK(lex_keyword("Colour", 6) == KW_COLOUR);
	CHECK(lex_keyword("center", 6) == KW_CENTRE);
	CHECK(lex_keyword("VARIENCE", 8) == KW_VARIANCE);
	CHECK(lex_keyword("diff-color", 10) == KW_DIFF_COLOUR);
	CHECK(lex_keyword("Diffuse-Relection", 17) == KW_DIFFUSE_REFLECTION); /* the manual's 8.x text */
	CHECK(lex_keyword("flat-red", 8) == KW_NONE);
	CHECK(lex_keyword("", 0) == KW_NONE);
	/* every keyword finds itself, in upper case too */
	for (int k = 1; k < KW_COUNT; k++) {
		const char *n = lex_keyword_name((enum keyword)k);
		char up[64];
		size_t len = strlen(n);
		CHECK(len < sizeof up);
		for (size_t i = 0; i <= len; i++)
			up[i] = (n[i] >= 'a' && n[i] <= 'z') ? (char)(n[i] - 32) : n[i];
		CHECK(lex_keyword(n, len) == (enum keyword)k);
		CHECK(lex_keyword(up, len) == (enum keyword)k);
	}
	CHECK(strcmp(lex_keyword_name(KW_NONE), "?") == 0);
}

static void test_limits_and_errors(void)
{
	size_t n = LIM_TOKEN_LEN + 1;
	char *big = malloc(n + 8);
	memset(big, 'x', n);
	big[n] = '\0';
	struct lexer lx;
	struct token t;
	lex_init(&lx, big, n);
	lex_next(&lx, &t);
	CHECK(t.kind == TK_ERROR && strstr(lx.errmsg, "too long"));
	lex_init(&lx, big, LIM_TOKEN_LEN);
	lex_next(&lx, &t);
	CHECK(t.kind == TK_WORD && t.len == LIM_TOKEN_LEN);
	free(big);
	const char ctl[] = "light \x01";
	lex_init(&lx, ctl, sizeof ctl - 1);
	lex_next(&lx, &t);
	lex_next(&lx, &t);
	CHECK(t.kind == TK_ERROR && t.col == 7);
	/* not NUL-terminated: the lexer stops at len */
	const char part[] = "cameraXYZ";
	lex_init(&lx, part, 6);
	lex_next(&lx, &t);
	CHECK(t.kw == KW_CAMERA && t.len == 6);
	lex_next(&lx, &t);
	CHECK(t.kind == TK_EOF);
	/* UTF-8 in names is fine */
	t = nth("named caf\xc3\xa9", 1);
	CHECK(t.kind == TK_WORD && t.len == 5);
}

/* A UTF-8 byte-order mark (Windows editors write one) is not part of the
 * first word; elsewhere it is an ordinary part of a word. */
static void test_bom(void)
{
	const char *src = "\xEF\xBB\xBFobject a\xEF\xBB\xBF";
	struct lexer lx;
	struct token t;
	lex_init(&lx, src, strlen(src));
	lex_next(&lx, &t);
	CHECK(t.kind == TK_WORD && t.kw == KW_OBJECT && t.line == 1 && t.col == 1);
	lex_next(&lx, &t);
	CHECK(t.kind == TK_WORD && t.len == 4 && t.col == 8);
	lex_next(&lx, &t);
	CHECK(t.kind == TK_EOF);
}

/* lex_read_file: whole files, the limit, directories, and a NUL byte. */
static void test_read_file(void)
{
	char dir[] = "/tmp/test_lex_XXXXXX", path[128];
	if (!mkdtemp(dir)) {
		CHECK(0);
		return;
	}
	snprintf(path, sizeof path, "%s/a.sce", dir);
	FILE *f = fopen(path, "wb");
	static const char text[] = "object\n\tsphere ;\nab\0cd\n";
	fwrite(text, 1, sizeof text - 1, f);
	fclose(f);
	char *buf = NULL;
	size_t len = 0;
	unsigned long long dev = 0, ino = 0;
	int line = 0, col = 0;
	CHECK(lex_read_file(path, 1000, &buf, &len, &dev, &ino, &line, &col) == EILSEQ);
	CHECK(line == 3 && col == 3);
	f = fopen(path, "wb");
	fwrite(text, 1, 18, f); /* up to "ab" */
	fclose(f);
	CHECK(lex_read_file(path, 1000, &buf, &len, &dev, &ino, &line, &col) == 0);
	CHECK(buf && len == 18 && memcmp(buf, text, 18) == 0);
	struct stat st;
	CHECK(stat(path, &st) == 0 && dev == (unsigned long long)st.st_dev && ino == (unsigned long long)st.st_ino);
	free(buf);
	buf = NULL;
	CHECK(lex_read_file(path, 18, &buf, &len, &dev, &ino, &line, &col) == 0); /* exactly the limit */
	free(buf);
	buf = NULL;
	CHECK(lex_read_file(path, 17, &buf, &len, &dev, &ino, &line, &col) == EFBIG);
	CHECK(lex_read_file(dir, 1000, &buf, &len, &dev, &ino, &line, &col) == EISDIR);
	/* a device that never ends stops at its first byte, not at the limit */
	if (access("/dev/zero", R_OK) == 0) {
		CHECK(lex_read_file("/dev/zero", 1000000, &buf, &len, &dev, &ino, &line, &col) == EILSEQ);
		CHECK(line == 1 && col == 1);
	}
	snprintf(path, sizeof path, "%s/none", dir);
	CHECK(lex_read_file(path, 1000, &buf, &len, &dev, &ino, &line, &col) == ENOENT);
	snprintf(path, sizeof path, "%s/a.sce", dir);
	unlink(path);
	CHECK(rmdir(dir) == 0);
}

int main(void)
{
	test_kinds_positions();
	test_comments();
	test_numbers();
	test_numbers_vs_strtod();
	test_keywords();
	test_limits_and_errors();
	test_read_file();
	test_bom();
	TEST_MAIN_END();
}
