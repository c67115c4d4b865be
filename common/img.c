/*
 * img.c - image files: binary PPM, the format names, and writing any format
 * to memory, a file or standard output. The PNG encoder is in img_png.c,
 * the float formats (PFM and OpenEXR) in img_float.c.
 *
 * img_write picks the format by the name: ".png" in any case gives PNG and
 * every other name (".ppm", or anything else) binary PPM (P6, maxval 255);
 * img_write_opts writes the format it is given.
 */
#include "common/img.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/img_int.h"

/* ---- formats, text, sinks ---------------------------------------------------------- */

static const struct {
	const char *name, *ext;
} formats[IMG_N_FORMATS] = {
	[IMG_PNG] = { "png", ".png" }, [IMG_PNG16] = { "png16", ".png" }, [IMG_PPM] = { "ppm", ".ppm" },
	[IMG_PFM] = { "pfm", ".pfm" }, [IMG_EXR] = { "exr", ".exr" },     [IMG_EXR_HALF] = { "exr-half", ".exr" },
};

int img_format_parse(const char *name, enum img_format *f)
{
	for (int i = 0; name && i < IMG_N_FORMATS; i++) {
		if (strcmp(name, formats[i].name) == 0) {
			*f = (enum img_format)i;
			return 0;
		}
	}
	return -1;
}

/* The extension of path's last component ("" when it has none). */
static const char *path_ext(const char *path)
{
	const char *base = strrchr(path, '/');
	base = base ? base + 1 : path;
	const char *dot = strrchr(base, '.');
	return dot && dot != base ? dot : "";
}

int img_format_by_ext(const char *path, enum img_format *f)
{
	const char *ext = path ? path_ext(path) : "";
	for (int i = 0; *ext && i < IMG_N_FORMATS; i++) {
		if (strcasecmp(ext, formats[i].ext) == 0) {
			*f = (enum img_format)i; /* the first format with it: png, exr */
			return 0;
		}
	}
	return -1;
}

int img_format_ext_matches(const char *path, enum img_format f)
{
	return f >= 0 && f < IMG_N_FORMATS && path && strcasecmp(path_ext(path), formats[f].ext) == 0;
}

const char *img_format_name(enum img_format f)
{
	return f >= 0 && f < IMG_N_FORMATS ? formats[f].name : "?";
}

const char *img_format_ext(enum img_format f)
{
	return f >= 0 && f < IMG_N_FORMATS ? formats[f].ext : "";
}

size_t img_text_clean(const char *value, char *out)
{
	size_t n = 0;
	for (; value[n] && n < IMG_TEXT_VALUE_MAX; n++) {
		unsigned char c = (unsigned char)value[n];
		out[n] = (char)((c >= 0x20 && c < 0x7f) || c == '\n' ? c : '?');
	}
	out[n] = 0;
	return n;
}

void img_exr_attr_name(const char *key, char *out)
{
	size_t n = 0;
	int up = 0;
	for (; *key && n < IMG_TEXT_KEY_MAX; key++) {
		if (*key == ' ') {
			up = 1;
			continue;
		}
		char c = *key;
		if (n == 0 && c >= 'A' && c <= 'Z')
			c = (char)(c - 'A' + 'a');
		else if (up && c >= 'a' && c <= 'z')
			c = (char)(c - 'a' + 'A');
		out[n++] = c;
		up = 0;
	}
	out[n] = 0;
}

/* A PNG keyword that is also a sound OpenEXR name: 1..IMG_TEXT_KEY_MAX
 * printable ASCII characters, no space at either end or next to another. */
static int text_key_ok(const char *k)
{
	size_t n = k ? strlen(k) : 0;
	if (n == 0 || n > IMG_TEXT_KEY_MAX || k[0] == ' ' || k[n - 1] == ' ')
		return 0;
	for (size_t i = 0; i < n; i++)
		if (k[i] < 0x20 || k[i] > 0x7e || (k[i] == ' ' && k[i + 1] == ' '))
			return 0;
	return 1;
}

/* d is something the writers can write: size, pixels, format, texts whose
 * OpenEXR names clash with no attribute of ours nor with each other. */
static int desc_ok(const struct img_desc *d)
{
	static const char *taken[] = { "channels",    "chromaticities",   "colorInteropID",     "compression",
				       "dataWindow",  "displayWindow",    "lineOrder",          "pixelAspectRatio",
				       "screenWindowCenter", "screenWindowWidth" };
	if (!d || !d->pixels || !img_size_ok(d->w, d->h) || (d->type != IMG_RGB8 && d->type != IMG_RGBF32) ||
	    d->format < 0 || d->format >= IMG_N_FORMATS || d->n_text > IMG_TEXT_MAX || (d->n_text && !d->text))
		return 0;
	char names[IMG_TEXT_MAX][IMG_TEXT_KEY_MAX + 1];
	for (size_t i = 0; i < d->n_text; i++) {
		if (!text_key_ok(d->text[i].key) || !d->text[i].value)
			return 0;
		img_exr_attr_name(d->text[i].key, names[i]);
		for (size_t t = 0; t < sizeof taken / sizeof taken[0]; t++)
			if (strcmp(names[i], taken[t]) == 0)
				return 0;
		for (size_t j = 0; j < i; j++)
			if (strcmp(names[i], names[j]) == 0)
				return 0;
	}
	return 1;
}

/* Writes all n bytes (short writes and EINTR retried). 0 or -1 with errno. */
static int write_all(int fd, const uint8_t *p, size_t n)
{
	while (n > 0) {
		ssize_t r = write(fd, p, n > (1u << 30) ? (1u << 30) : n);
		if (r < 0 && errno == EINTR)
			continue;
		if (r < 0)
			return -1;
		if (r == 0) {
			errno = EIO;
			return -1;
		}
		p += r;
		n -= (size_t)r;
	}
	return 0;
}

int img_sink_flush(struct img_sink *s)
{
	if (!s->err && s->fd >= 0 && s->n > 0) {
		if (write_all(s->fd, s->p, s->n) < 0)
			s->err = errno ? errno : EIO;
		s->n = 0;
	}
	return s->err ? -1 : 0;
}

void img_sink_bytes(struct img_sink *s, const void *src, size_t n)
{
	const uint8_t *p = src;
	if (s->err || n == 0)
		return;
	if (s->fd < 0) {
		if (s->cap - s->n < n) {
			size_t ncap = s->cap ? s->cap : 4096;
			while (ncap - s->n < n) {
				if (ncap > SIZE_MAX / 2) {
					s->err = ENOMEM;
					return;
				}
				ncap *= 2;
			}
			uint8_t *np = realloc(s->p, ncap);
			if (!np) {
				s->err = ENOMEM;
				return;
			}
			s->p = np;
			s->cap = ncap;
		}
		memcpy(s->p + s->n, p, n);
		s->n += n;
		return;
	}
	if (!s->p) {
		s->p = malloc(IMG_SINK_BUF);
		s->cap = IMG_SINK_BUF;
		if (!s->p) {
			s->err = ENOMEM;
			return;
		}
	}
	if (n >= s->cap) { /* large: straight through */
		if (img_sink_flush(s) == 0 && write_all(s->fd, p, n) < 0)
			s->err = errno ? errno : EIO;
		return;
	}
	while (n > 0 && !s->err) {
		if (s->n == s->cap)
			img_sink_flush(s);
		size_t k = s->cap - s->n < n ? s->cap - s->n : n;
		memcpy(s->p + s->n, p, k);
		s->n += k;
		p += k;
		n -= k;
	}
}

void img_sink_le32(struct img_sink *s, uint32_t v)
{
	uint8_t b[4] = { (uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24) };
	img_sink_bytes(s, b, 4);
}

void img_sink_le64(struct img_sink *s, uint64_t v)
{
	img_sink_le32(s, (uint32_t)v);
	img_sink_le32(s, (uint32_t)(v >> 32));
}

/* Streams the formats that are written as they are made (PPM, PFM, EXR). */
static void emit_stream(const struct img_desc *d, struct img_sink *s)
{
	switch (d->format) {
	case IMG_PFM: img_pfm_emit(d, s); break;
	case IMG_EXR:
	case IMG_EXR_HALF: img_exr_emit(d, s); break;
	default: { /* IMG_PPM */
		char head[64];
		int hn = snprintf(head, sizeof head, "P6\n%u %u\n255\n", (unsigned)d->w, (unsigned)d->h);
		img_sink_bytes(s, head, (size_t)hn);
		size_t n = 3 * (size_t)d->w;
		if (d->type == IMG_RGB8) {
			img_sink_bytes(s, d->pixels, n * d->h);
			break;
		}
		uint8_t *row = malloc(n);
		if (!row) {
			if (!s->err)
				s->err = ENOMEM;
			break;
		}
		for (uint32_t y = 0; y < d->h && !s->err; y++) {
			const float *p = (const float *)d->pixels + y * n;
			for (size_t i = 0; i < n; i++)
				row[i] = (uint8_t)img_quantise(p[i], 255.0);
			img_sink_bytes(s, row, n);
		}
		free(row);
		break;
	}
	}
}

static int is_png_format(enum img_format f)
{
	return f == IMG_PNG || f == IMG_PNG16;
}

int img_encode(const struct img_desc *d, uint8_t **out, size_t *out_len)
{
	*out = NULL;
	*out_len = 0;
	if (!desc_ok(d)) {
		errno = EINVAL;
		return -1;
	}
	if (is_png_format(d->format))
		return img_png_emit(d, 0, out, out_len);
	struct img_sink s = { .fd = -1 };
	emit_stream(d, &s);
	if (s.err) {
		free(s.p);
		errno = s.err;
		return -1;
	}
	*out = s.p ? s.p : malloc(1);
	*out_len = s.n;
	return *out ? 0 : (errno = ENOMEM, -1);
}

/* ---- files ----------------------------------------------------------------------- */

/* Writes d to fd: pre (n bytes) when the image was encoded in memory
 * (PNG), else streamed. 0 or -1 with errno. */
static int write_image(int fd, const uint8_t *pre, size_t n, const struct img_desc *d)
{
	if (pre)
		return write_all(fd, pre, n);
	struct img_sink s = { .fd = fd };
	emit_stream(d, &s);
	img_sink_flush(&s);
	free(s.p);
	if (s.err) {
		errno = s.err;
		return -1;
	}
	return 0;
}

/* "<path>.tmp.<pid>.<n>": the temporary beside path (tmp holds plen + 64). */
static void tmp_name(char *tmp, size_t cap, const char *path)
{
	static unsigned counter;
	unsigned k = __atomic_add_fetch(&counter, 1, __ATOMIC_RELAXED);
	snprintf(tmp, cap, "%s.tmp.%ld.%u", path, (long)getpid(), k);
}

/*
 * Writes d (validated) to path: see img_write for the file handling. plain:
 * a PNG with no chunk beyond IHDR, IDAT, IEND. PNGs are encoded before any
 * file is touched; the streamed formats are made as they are written.
 */
static int write_path(const char *path, const struct img_desc *d, int plain)
{
	uint8_t *data = NULL;
	size_t n = 0;
	if (is_png_format(d->format) && img_png_emit(d, plain, &data, &n) < 0)
		return -1;
	if (strcmp(path, "-") == 0 && !plain) { /* standard output (img_write_opts only) */
		int rc = write_image(STDOUT_FILENO, data, n, d);
		int e = errno;
		free(data);
		errno = e;
		return rc;
	}

	/* a symbolic link is written through: the temporary goes next to its
	 * target and is renamed over the target, and the link stays */
	struct stat st;
	char *real = NULL;
	if (lstat(path, &st) == 0 && S_ISLNK(st.st_mode) && (real = realpath(path, NULL)) != NULL)
		path = real;
	if (stat(path, &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode)) {
		int fd = open(path, O_WRONLY | O_CLOEXEC);
		int rc = fd < 0 ? -1 : write_image(fd, data, n, d);
		int e = errno;
		if (fd >= 0 && close(fd) < 0 && rc == 0)
			e = errno, rc = -1;
		free(data);
		free(real);
		errno = e;
		return rc;
	}

	size_t plen = strlen(path);
	char *tmp = malloc(plen + 64);
	if (!tmp) {
		free(data);
		free(real);
		errno = ENOMEM;
		return -1;
	}
	int fd = -1;
	for (int tries = 0; tries < 100 && fd < 0; tries++) {
		tmp_name(tmp, plen + 64, path);
		fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
		if (fd < 0 && errno != EEXIST)
			break;
	}
	if (fd < 0) {
		int e = errno;
		free(data);
		free(tmp);
		free(real);
		errno = e;
		return -1;
	}
	int rc = write_image(fd, data, n, d);
	if (rc == 0)
		rc = fsync(fd);
	if (close(fd) < 0 && rc == 0)
		rc = -1;
	if (rc == 0)
		rc = rename(tmp, path);
	if (rc != 0) {
		int e = errno;
		unlink(tmp);
		errno = e;
	}
	int e = errno;
	free(data);
	free(tmp);
	free(real);
	errno = e;
	return rc == 0 ? 0 : -1;
}

/* Case-insensitive "ends with .png". */
static int is_png_name(const char *path)
{
	size_t n = strlen(path);
	return n >= 4 && strcasecmp(path + n - 4, ".png") == 0;
}

/*
 * Writes the image to path: PNG when the name ends in ".png" (any case),
 * binary PPM (P6) for any other name. The bytes go to a new temporary file
 * "<path>.tmp.<pid>.<n>" in the same directory (created with mode 0666 less
 * the umask), are fsync'd, and the file is renamed over path, so path holds
 * either its old content or the whole new image. On failure the temporary
 * file is removed and -1 is returned with errno set. A path that exists and
 * is not a regular file (a device such as /dev/null, a FIFO) is written in
 * place instead: renaming over it would replace the device or pipe itself.
 * A symbolic link is followed (its target is replaced, the link stays).
 */
int img_write(const char *path, const uint8_t *rgb, uint32_t w, uint32_t h)
{
	if (!path || !*path || !img_size_ok(w, h) || !rgb) {
		errno = EINVAL;
		return -1;
	}
	struct img_desc d = { .w = w, .h = h, .type = IMG_RGB8, .pixels = rgb,
			      .format = is_png_name(path) ? IMG_PNG : IMG_PPM };
	return write_path(path, &d, 1);
}

int img_write_opts(const char *path, const struct img_desc *d)
{
	if (!path || !*path || !desc_ok(d)) {
		errno = EINVAL;
		return -1;
	}
	return write_path(path, d, 0);
}

/* The directory of path ("." for a bare name) into dir (dir_len > 0). */
static void dir_of(const char *path, char *dir, size_t dir_len)
{
	const char *slash = strrchr(path, '/');
	if (!slash) {
		snprintf(dir, dir_len, ".");
		return;
	}
	while (slash > path && slash[-1] == '/')
		slash--;
	int n = slash == path ? 1 : (int)(slash - path); /* "/x" -> "/" */
	snprintf(dir, dir_len, "%.*s", n, path);
}

int img_output_check(const char *path, char *dir, size_t dir_len)
{
	char scratch[8];
	if (!dir || dir_len == 0) {
		dir = scratch;
		dir_len = sizeof scratch;
	}
	dir[0] = 0;
	if (!path || !*path) {
		errno = EINVAL;
		return -1;
	}
	if (strcmp(path, "-") == 0) {
		/* standard output: open, and not for reading only */
		int fl = fcntl(STDOUT_FILENO, F_GETFL);
		if (fl >= 0 && (fl & O_ACCMODE) != O_RDONLY)
			return 0;
		snprintf(dir, dir_len, "standard output");
		errno = fl < 0 ? EBADF : EACCES;
		return -1;
	}
	/* the file img_write_opts would touch: a link's target */
	struct stat st;
	char *real = NULL;
	if (lstat(path, &st) == 0 && S_ISLNK(st.st_mode) && (real = realpath(path, NULL)) != NULL)
		path = real;
	int rc = 0, e = 0;
	if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
		snprintf(dir, dir_len, "%s", path);
		e = EISDIR;
		rc = -1;
	} else if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
		rc = access(path, W_OK); /* written in place */
		e = errno;
		if (rc)
			snprintf(dir, dir_len, "%s", path);
	} else {
		/* the temporary file the write makes, made and removed now */
		size_t plen = strlen(path);
		char *tmp = malloc(plen + 64);
		int fd = -1;
		e = ENOMEM;
		for (int tries = 0; tmp && tries < 100 && fd < 0; tries++) {
			tmp_name(tmp, plen + 64, path);
			fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
			e = errno;
			if (fd < 0 && errno != EEXIST)
				break;
		}
		if (fd >= 0) {
			close(fd);
			unlink(tmp);
		} else {
			dir_of(path, dir, dir_len);
			rc = -1;
		}
		free(tmp);
	}
	free(real);
	errno = e;
	return rc;
}
