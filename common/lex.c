/*
 * lex.c - the PortRAY scene language's lexer. See lex.h for the token rules.
 *
 * Keywords are found through a small open-addressing hash table of their
 * lower-case spellings, built once (pthread_once) on first use.
 */
#include "common/lex.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/limits.h"

#define LEX_STR_(x) #x
#define LEX_STR(x) LEX_STR_(x)

/* longest keyword spelling we look up; longer words are never keywords */
#define KW_MAX_LEN 32
/* hash table slots: a power of two well above the ~130 spellings */
#define KW_SLOTS 512

static const char *const kw_names[KW_COUNT] = {
	"?",
#define LEX_KW_NAME(id, s) s,
	LEX_KEYWORDS(LEX_KW_NAME)
#undef LEX_KW_NAME
};

/* Alternative spellings accepted for a keyword (docs/language.md). */
static const struct {
	const char *name;
	enum keyword kw;
} kw_aliases[] = {
	{ "color", KW_COLOUR },
	{ "colors", KW_COLOURS },
	{ "diff-color", KW_DIFF_COLOUR },
	{ "spec-color", KW_SPEC_COLOUR },
	{ "tran-color", KW_TRAN_COLOUR },
	{ "center", KW_CENTRE },
	{ "varience", KW_VARIANCE }, /* the manual's spelling */
	{ "diffuse-relection", KW_DIFFUSE_REFLECTION }, /* the manual's material text */
	{ "supersample", KW_SUPER_SAMPLE },
	{ "checkers", KW_CHEQUERS },
};

static struct {
	const char *name;
	unsigned char len;
	unsigned char kw;
} kw_table[KW_SLOTS];
static pthread_once_t kw_once = PTHREAD_ONCE_INIT;

static uint32_t kw_hash(const char *s, size_t n)
{
	uint32_t h = 2166136261u;
	for (size_t i = 0; i < n; i++)
		h = (h ^ (unsigned char)s[i]) * 16777619u;
	return h;
}

static void kw_insert(const char *name, enum keyword kw)
{
	size_t n = strlen(name);
	uint32_t h = kw_hash(name, n) & (KW_SLOTS - 1);
	while (kw_table[h].name)
		h = (h + 1) & (KW_SLOTS - 1);
	kw_table[h].name = name;
	kw_table[h].len = (unsigned char)n;
	kw_table[h].kw = (unsigned char)kw;
}

static void kw_build(void)
{
	for (int k = 1; k < KW_COUNT; k++)
		kw_insert(kw_names[k], (enum keyword)k);
	for (size_t i = 0; i < sizeof kw_aliases / sizeof kw_aliases[0]; i++)
		kw_insert(kw_aliases[i].name, kw_aliases[i].kw);
}

enum keyword lex_keyword(const char *w, size_t n)
{
	char low[KW_MAX_LEN];
	if (n == 0 || n > KW_MAX_LEN)
		return KW_NONE;
	for (size_t i = 0; i < n; i++) {
		char c = w[i];
		low[i] = (c >= 'A' && c <= 'Z') ? (char)(c + ('a' - 'A')) : c;
	}
	pthread_once(&kw_once, kw_build);
	uint32_t h = kw_hash(low, n) & (KW_SLOTS - 1);
	while (kw_table[h].name) {
		if (kw_table[h].len == n && memcmp(kw_table[h].name, low, n) == 0)
			return (enum keyword)kw_table[h].kw;
		h = (h + 1) & (KW_SLOTS - 1);
	}
	return KW_NONE;
}

const char *lex_keyword_name(enum keyword kw)
{
	return (unsigned)kw < KW_COUNT ? kw_names[kw] : "?";
}

static int is_digit(char c) { return c >= '0' && c <= '9'; }

const double lex_pow10[23] = {
	1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
	1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
};

/*
 * The digits are gathered as they are checked: m holds the first 19
 * significant ones and e10 the power of ten that scales them. When m fits
 * in 53 bits, no digit was dropped and |e10| <= 22, m and 10^|e10| are
 * exact doubles and one IEEE product or quotient is the correctly rounded
 * value, which is strtod's (Clinger's fast path); anything else goes to
 * strtod.
 */
int lex_number(const char *w, size_t n, double *v)
{
	size_t i = 0, digits = 0;
	/* number-like: [+-]? then a digit, or [+-]? '.' digit */
	size_t j = (n > 0 && (w[0] == '+' || w[0] == '-')) ? 1 : 0;
	if (!(j < n && (is_digit(w[j]) || (w[j] == '.' && j + 1 < n && is_digit(w[j + 1])))))
		return NUM_NO;
	uint64_t m = 0;
	int nsig = 0;
	long e10 = 0;
	bool dropped = false;
	i = j;
	for (; i < n && is_digit(w[i]); i++, digits++) {
		unsigned d = (unsigned)(w[i] - '0');
		if (nsig < 19) {
			m = m * 10 + d;
			nsig += m != 0;
		} else {
			e10++;
			dropped |= d != 0;
		}
	}
	if (i < n && w[i] == '.') {
		for (i++; i < n && is_digit(w[i]); i++, digits++) {
			unsigned d = (unsigned)(w[i] - '0');
			if (nsig < 19) {
				m = m * 10 + d;
				nsig += m != 0;
				e10--;
			} else {
				dropped |= d != 0;
			}
		}
	}
	if (digits == 0)
		return NUM_BAD;
	if (i < n && (w[i] == 'e' || w[i] == 'E')) {
		i++;
		bool eneg = false;
		if (i < n && (w[i] == '+' || w[i] == '-'))
			eneg = w[i++] == '-';
		size_t ed = 0;
		long e = 0;
		for (; i < n && is_digit(w[i]); i++, ed++)
			if (e < 100000000)
				e = e * 10 + (w[i] - '0');
		if (ed == 0)
			return NUM_BAD;
		e10 += eneg ? -e : e;
	}
	if (i != n || n > LIM_TOKEN_LEN)
		return NUM_BAD;
	double d;
	if (!dropped && m <= (1ull << 53) && e10 >= -22 && e10 <= 22) {
		d = (double)m;
		d = e10 < 0 ? d / lex_pow10[-e10] : d * lex_pow10[e10];
		if (w[0] == '-')
			d = -d;
	} else {
		/* the grammar above is a subset of strtod's, so strtod reads it
		 * all and rounds correctly; copy to terminate it */
		char tmp[LIM_TOKEN_LEN + 1];
		memcpy(tmp, w, n);
		tmp[n] = '\0';
		d = strtod(tmp, NULL);
	}
	if (!isfinite(d))
		return NUM_BAD;
	*v = d;
	return NUM_OK;
}

/* UTF-8 byte-order mark, written at the start of a file by some editors */
#define LEX_BOM "\xEF\xBB\xBF"

void lex_init(struct lexer *lx, const char *buf, size_t len)
{
	lx->buf = buf;
	lx->len = len;
	/* a leading byte-order mark is no part of the first word */
	lx->pos = len >= 3 && memcmp(buf, LEX_BOM, 3) == 0 ? 3 : 0;
	lx->line = 1;
	lx->col = 1;
	lx->errmsg = NULL;
}

/* characters that end a word (besides white space and "//") */
static int is_delim(unsigned char c)
{
	return c <= ' ' || c == ';' || c == '(' || c == ')' || c == '~' || c == 0x7f;
}

static void tok_at(struct lexer *lx, struct token *t, enum tok_kind k)
{
	t->kind = k;
	t->text = lx->buf + lx->pos;
	t->len = 0;
	t->line = lx->line;
	t->col = lx->col;
	t->kw = KW_NONE;
	t->num = NUM_NO;
	t->value = 0;
}

static void lex_fail(struct lexer *lx, struct token *t, const char *msg)
{
	t->kind = TK_ERROR;
	lx->errmsg = msg;
	lx->pos = lx->len; /* stay at the end: further calls give EOF-like errors */
}

void lex_next(struct lexer *lx, struct token *t)
{
	const char *b = lx->buf;
	size_t n = lx->len;
	if (lx->errmsg) { /* sticky */
		tok_at(lx, t, TK_ERROR);
		return;
	}
	for (;;) {
		if (lx->pos >= n) {
			tok_at(lx, t, TK_EOF);
			return;
		}
		unsigned char c = (unsigned char)b[lx->pos];
		if (c == '\n') {
			lx->pos++;
			lx->line++;
			lx->col = 1;
		} else if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
			lx->pos++;
			lx->col++;
		} else if (c == '~') {
			tok_at(lx, t, TK_ERROR); /* position of the comment, if unfinished */
			lx->pos++;
			lx->col++;
			while (lx->pos < n && b[lx->pos] != '~') {
				if (b[lx->pos] == '\n') {
					lx->line++;
					lx->col = 1;
				} else {
					lx->col++;
				}
				lx->pos++;
			}
			if (lx->pos >= n) {
				lex_fail(lx, t, "unfinished '~' comment");
				return;
			}
			lx->pos++;
			lx->col++;
		} else if (c == '/' && lx->pos + 1 < n && b[lx->pos + 1] == '/') {
			while (lx->pos < n && b[lx->pos] != '\n')
				lx->pos++, lx->col++;
		} else {
			break;
		}
	}
	unsigned char c = (unsigned char)b[lx->pos];
	if (c == ';' || c == '(' || c == ')') {
		tok_at(lx, t, c == ';' ? TK_SEMI : c == '(' ? TK_LPAREN : TK_RPAREN);
		t->len = 1;
		lx->pos++;
		lx->col++;
		return;
	}
	if (c < ' ' || c == 0x7f) {
		tok_at(lx, t, TK_ERROR);
		lex_fail(lx, t, "invalid control character");
		return;
	}
	tok_at(lx, t, TK_WORD);
	size_t start = lx->pos, i = start;
	while (i < n && !is_delim((unsigned char)b[i]) && !(b[i] == '/' && i + 1 < n && b[i + 1] == '/'))
		i++;
	size_t len = i - start;
	if (len > LIM_TOKEN_LEN) {
		lex_fail(lx, t, "token too long (more than " LEX_STR(LIM_TOKEN_LEN) " bytes)");
		return;
	}
	lx->pos = i;
	lx->col += (int)len;
	t->len = len;
	t->num = lex_number(t->text, len, &t->value);
	if (t->num == NUM_NO)
		t->kw = lex_keyword(t->text, len);
}

/* Initial buffer for a file whose size fstat cannot tell (a pipe, a device). */
#define LEX_READ_CHUNK 65536

int lex_read_file(const char *path, size_t limit, char **buf, size_t *len, unsigned long long *dev,
		  unsigned long long *ino, int *nul_line, int *nul_col)
{
	int fd = open(path, O_RDONLY | O_CLOEXEC);
	if (fd < 0)
		return errno;
	struct stat st;
	if (fstat(fd, &st) < 0) {
		int e = errno;
		close(fd);
		return e;
	}
	if (S_ISDIR(st.st_mode)) {
		close(fd);
		return EISDIR;
	}
	*dev = (unsigned long long)st.st_dev;
	*ino = (unsigned long long)st.st_ino;
	/* one byte more than the limit, so that a file over it is seen */
	const size_t most = limit + 1;
	size_t cap = S_ISREG(st.st_mode) && st.st_size > 0 && (unsigned long long)st.st_size < most
			     ? (size_t)st.st_size + 1
			     : LEX_READ_CHUNK;
	size_t n = 0;
	char *b = malloc(cap);
	int e = b ? 0 : ENOMEM;
	while (!e) {
		if (n == cap) {
			if (cap >= most) {
				e = EFBIG;
				break;
			}
			size_t nc = cap > most / 2 ? most : cap * 2;
			char *nb = realloc(b, nc);
			if (!nb) {
				e = ENOMEM;
				break;
			}
			b = nb;
			cap = nc;
		}
		ssize_t r = read(fd, b + n, cap - n);
		if (r < 0) {
			if (errno != EINTR)
				e = errno;
			continue;
		}
		if (r == 0)
			break;
		const char *z = memchr(b + n, '\0', (size_t)r);
		n += (size_t)r;
		if (z) { /* its line and column, counted as the lexer counts */
			*nul_line = 1;
			*nul_col = 1;
			for (const char *q = b; q < z; q++) {
				if (*q == '\n')
					++*nul_line, *nul_col = 1;
				else
					++*nul_col;
			}
			e = EILSEQ;
		}
	}
	close(fd);
	if (!e && n > limit)
		e = EFBIG;
	if (!e && n == cap) { /* keep the promised byte past the end */
		char *nb = realloc(b, n + 1);
		if (!nb)
			e = ENOMEM;
		else
			b = nb;
	}
	if (e) {
		free(b);
		return e;
	}
	*buf = b;
	*len = n;
	return 0;
}
