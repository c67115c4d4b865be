/*
 * lex.h - the PortRAY scene language's lexer (common/lex.c).
 *
 * The text is a sequence of tokens separated by white space and comments:
 *   ;          closes a statement or block
 *   ( and )    around the three numbers of a vector or colour
 *   words      everything else: keywords (any case), names (flat-red,
 *              teapot.raw, ../x/y.inc) and numbers (-1, 2.5, .5e-3)
 * Comments are `~ ... ~` (may span lines) and `//` to the end of the line.
 * A word ends at white space, `;`, `(`, `)`, `~` or `//`.
 *
 * Every token carries its line and column (1-based; a tab counts as one
 * column). The lexer never allocates: token text points into the buffer,
 * which must outlive the lexer. Tokens longer than LIM_TOKEN_LEN, control
 * characters and unfinished comments come back as TK_ERROR with a message.
 */
#ifndef PORTRAY_LEX_H
#define PORTRAY_LEX_H

#include <stddef.h>

enum tok_kind {
	TK_EOF,
	TK_SEMI,
	TK_LPAREN,
	TK_RPAREN,
	TK_WORD,
	TK_ERROR /* lexer->errmsg says why; line/col where the problem starts */
};

/*
 * Keywords. X(id, spelling); spellings are lower case and matched in any
 * case. Aliases (color, center, ...) map to the same id in lex.c.
 */
#define LEX_KEYWORDS(X)                                                                        \
	X(KW_A, "a") X(KW_ADAPTIVE, "adaptive") X(KW_AT, "at") X(KW_AXIS, "axis") X(KW_B, "b")   \
	X(KW_BOX, "box") X(KW_BRICK, "brick") X(KW_BRICKS, "bricks") X(KW_BUMPY, "bumpy")      \
	X(KW_C, "c") X(KW_CACHE_SIZE, "cache-size") X(KW_CALLED, "called")                     \
	X(KW_CAMERA, "camera") X(KW_CAPPED, "capped") X(KW_CENTRE, "centre")                   \
	X(KW_CHEQUERS, "chequers") X(KW_COLOUR, "colour") X(KW_COLOURS, "colours")             \
	X(KW_CONTOUR, "contour") X(KW_CSG, "csg") X(KW_CYLINDER, "cylinder")                   \
	X(KW_DEFINE, "define") X(KW_DEPTH, "depth") X(KW_DIFF_COLOUR, "diff-colour")           \
	X(KW_DIFFUSE_REFLECTION, "diffuse-reflection") X(KW_DISK, "disk")                      \
	X(KW_DROP_LINE, "drop-line") X(KW_EQUATOR, "equator") X(KW_FACE, "face")               \
	X(KW_FADES, "fades") X(KW_FALL_OFF, "fall-off") X(KW_FILE, "file")                     \
	X(KW_FILTER, "filter") X(KW_FOCAL_LENGTH, "focal-length") X(KW_FROM, "from")           \
	X(KW_GROUT, "grout") X(KW_GROUT_WIDTH, "grout-width") X(KW_IMAGE, "image")             \
	X(KW_INCLUDE, "include") X(KW_INTERSECT, "intersect")                                  \
	X(KW_INTERSECT_BUFFER, "intersect-buffer") X(KW_LENS, "lens") X(KW_LIGHT, "light")     \
	X(KW_LOOK_AT, "look-at") X(KW_LOOK_FROM, "look-from") X(KW_MATERIAL, "material")       \
	X(KW_MATERIAL_A, "material-a") X(KW_MATERIAL_B, "material-b")                          \
	X(KW_MATERIALS, "materials") X(KW_MAX_DEPTH, "max-depth") X(KW_MORTAR, "mortar")       \
	X(KW_NAME, "name") X(KW_NAMED, "named") X(KW_NO_REFLECTIONS, "no-reflections")         \
	X(KW_NO_SHADOWS, "no-shadows") X(KW_NOISE, "noise") X(KW_NONSTOP, "nonstop")           \
	X(KW_NORMAL, "normal") X(KW_NORMAL_A, "normal-a") X(KW_NORMAL_B, "normal-b")           \
	X(KW_NORMAL_C, "normal-c") X(KW_OBJECT, "object") X(KW_OPERAND1, "operand1")           \
	X(KW_OPERAND2, "operand2") X(KW_PLANE, "plane") X(KW_POLE, "pole")                     \
	X(KW_POLYGON, "polygon") X(KW_POSITION, "position") X(KW_PRIMITIVE, "primitive")       \
	X(KW_RADIUS, "radius") X(KW_RAW, "raw") X(KW_REFLECTION, "reflection")                 \
	X(KW_REFRACTIVE_INDEX, "refractive-index") X(KW_RELAX, "relax")                        \
	X(KW_SAMPLES, "samples") X(KW_SATURATION, "saturation") X(KW_SHAPE, "shape")           \
	X(KW_SHRINK_X, "shrink-x") X(KW_SHRINK_Y, "shrink-y") X(KW_SHRINK_Z, "shrink-z")       \
	X(KW_SIZE, "size") X(KW_SMOOTH, "smooth") X(KW_SPEC_COLOUR, "spec-colour")             \
	X(KW_SPECULAR_POWER, "specular-power") X(KW_SPECULAR_REFLECTION, "specular-reflection") \
	X(KW_SPHERE, "sphere") X(KW_STANDARD, "standard") X(KW_STRETCH_X, "stretch-x")         \
	X(KW_STRETCH_Y, "stretch-y") X(KW_STRETCH_Z, "stretch-z") X(KW_SUBTRACT, "subtract")   \
	X(KW_SUPER_SAMPLE, "super-sample") X(KW_TERMS, "terms") X(KW_THRESHOLD, "threshold")   \
	X(KW_TILE_WIDTH, "tile-width") X(KW_TILES, "tiles") X(KW_TO, "to")                     \
	X(KW_TRAN_COLOUR, "tran-colour") X(KW_TRANSLATE, "translate")                          \
	X(KW_TRANSPARENCY, "transparency") X(KW_TRIANGLE, "triangle") X(KW_TURB3D, "turb3d")   \
	X(KW_UNION, "union") X(KW_VARIANCE, "variance") X(KW_WELD, "weld")                     \
	X(KW_X_AXIS, "x-axis") X(KW_X_ROTATE, "x-rotate") X(KW_X_ROTATION, "x-rotation")       \
	X(KW_X_SAMPLES, "x-samples") X(KW_X_SIZE, "x-size") X(KW_XSIZE, "xsize")               \
	X(KW_Y_AXIS, "y-axis") X(KW_Y_ROTATE, "y-rotate") X(KW_Y_ROTATION, "y-rotation")       \
	X(KW_Y_SAMPLES, "y-samples") X(KW_Y_SIZE, "y-size") X(KW_YSIZE, "ysize")               \
	X(KW_Z_ROTATE, "z-rotate") X(KW_Z_ROTATION, "z-rotation") X(KW_ZSIZE, "zsize")

enum keyword {
	KW_NONE = 0,
#define LEX_KW_ENUM(id, s) id,
	LEX_KEYWORDS(LEX_KW_ENUM)
#undef LEX_KW_ENUM
	KW_COUNT
};

/* Whether a word is a number: NUM_NO (not number-like), NUM_OK, NUM_BAD
 * (starts like a number but is malformed or out of range, e.g. 1.2.3, 1e999). */
enum { NUM_NO = 0, NUM_OK = 1, NUM_BAD = -1 };

struct token {
	enum tok_kind kind;
	const char *text; /* into the lexer's buffer; not NUL-terminated */
	size_t len;
	int line, col;
	enum keyword kw;  /* TK_WORD: its keyword, or KW_NONE */
	int num;          /* TK_WORD: NUM_NO, NUM_OK or NUM_BAD */
	double value;     /* when num == NUM_OK */
};

struct lexer {
	const char *buf;
	size_t len, pos;
	int line, col;
	const char *errmsg; /* static text, set with a TK_ERROR token */
};

/* Starts lexing buf[0..len) (need not be NUL-terminated; must outlive lx).
 * A UTF-8 byte-order mark at the start is skipped (column 1 follows it). */
void lex_init(struct lexer *lx, const char *buf, size_t len);

/* Reads the next token into *t. After TK_EOF or TK_ERROR it keeps returning
 * the same kind. Never allocates. */
void lex_next(struct lexer *lx, struct token *t);

/* Canonical (lower case) spelling of a keyword; "?" for KW_NONE. */
const char *lex_keyword_name(enum keyword kw);

/* Keyword id of the word w[0..n) in any case (aliases included), KW_NONE if
 * it is not a keyword. */
enum keyword lex_keyword(const char *w, size_t n);

/* Parses w[0..n) as a whole number word: returns NUM_OK with *v set, NUM_BAD
 * (number-like but malformed or not finite) or NUM_NO (not number-like). */
int lex_number(const char *w, size_t n, double *v);

/* 10^0 .. 10^22: all exactly representable doubles (the fast paths of
 * lex_number and raw.c's number reader). */
extern const double lex_pow10[23];

/*
 * Reads the text file at path whole into *buf (malloc'd, caller frees; room
 * for one byte past *len), reading at most limit bytes: the one reader for
 * scene, camera, include and RAW files. On success *dev and *ino identify
 * the file (include cycles). Returns 0 or an errno: EISDIR for a directory,
 * EFBIG past limit, ENOMEM, a read error, or EILSEQ at the first NUL byte:
 * reading stops there (so /dev/zero or a binary file fails at once) with
 * *nul_line and *nul_col its position, counted as the lexer counts. On error
 * nothing is left to free.
 */
int lex_read_file(const char *path, size_t limit, char **buf, size_t *len, unsigned long long *dev,
		  unsigned long long *ino, int *nul_line, int *nul_col);

#endif
