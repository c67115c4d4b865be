/*
 * inflate.h - a small, independent inflate (RFC 1951), zlib (RFC 1950) and
 * PNG (RGB, 8 or 16 bits, all five filters) decoder, used only by the tests to check the
 * encoder in common/img.c. It shares no code with img.c: its own bitwise
 * CRC-32 and plain Adler-32, its own Huffman decoding (canonical codes walked
 * one bit at a time). Strict: incomplete or over-subscribed codes are
 * rejected (except the one-code distance tree RFC 1951 allows), and so are
 * bad CRCs, bad Adler-32, distances before the start, and trailing garbage.
 * Header-only: include it in exactly one test file.
 */
#ifndef PORTRAY_TEST_INFLATE_H
#define PORTRAY_TEST_INFLATE_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

struct inf {
	const uint8_t *in;
	size_t n, pos;     /* next input byte */
	uint32_t bitbuf;
	int bitcnt;
	uint8_t *out;
	size_t olen, ocap;
	int err;
	int blocks[3];     /* blocks seen by type: stored, fixed, dynamic */
};

struct inf_huff {
	uint16_t count[16];  /* codes of each length */
	uint16_t symbol[320]; /* symbols ordered by code */
};

static uint32_t inf_bits(struct inf *s, int need)
{
	uint32_t v = s->bitbuf;
	while (s->bitcnt < need) {
		if (s->pos >= s->n) {
			s->err = -1; /* ran out of input */
			return 0;
		}
		v |= (uint32_t)s->in[s->pos++] << s->bitcnt;
		s->bitcnt += 8;
	}
	s->bitbuf = need == 32 ? 0 : v >> need;
	s->bitcnt -= need;
	return need == 32 ? v : v & ((1u << need) - 1);
}

static void inf_put(struct inf *s, uint8_t b)
{
	if (s->olen == s->ocap) {
		size_t nc = s->ocap ? s->ocap * 2 : 1024;
		uint8_t *p = realloc(s->out, nc);
		if (!p) {
			s->err = -9;
			return;
		}
		s->out = p;
		s->ocap = nc;
	}
	s->out[s->olen++] = b;
}

/* Builds the decoding table; returns 0 complete, 1 incomplete, -1 over-subscribed. */
static int inf_build(struct inf_huff *h, const uint8_t *len, int n)
{
	uint16_t offs[16];
	memset(h->count, 0, sizeof h->count);
	for (int i = 0; i < n; i++)
		h->count[len[i]]++;
	if (h->count[0] == n)
		return 1;
	int left = 1;
	for (int b = 1; b < 16; b++) {
		left <<= 1;
		left -= h->count[b];
		if (left < 0)
			return -1;
	}
	offs[1] = 0;
	for (int b = 1; b < 15; b++)
		offs[b + 1] = (uint16_t)(offs[b] + h->count[b]);
	for (int i = 0; i < n; i++)
		if (len[i])
			h->symbol[offs[len[i]]++] = (uint16_t)i;
	return left > 0;
}

/* Decodes one symbol, reading the code MSB-first one bit at a time. */
static int inf_decode(struct inf *s, const struct inf_huff *h)
{
	int code = 0, first = 0, index = 0;
	for (int b = 1; b < 16; b++) {
		code |= (int)inf_bits(s, 1);
		if (s->err)
			return -1;
		int cnt = h->count[b];
		if (code - first < cnt)
			return h->symbol[index + code - first];
		index += cnt;
		first = (first + cnt) << 1;
		code <<= 1;
	}
	s->err = -2; /* no such code */
	return -1;
}

static const uint16_t inf_lbase[29] = { 3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
					31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258 };
static const uint8_t inf_lext[29] = { 0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
				      2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0 };
static const uint16_t inf_dbase[30] = { 1,    2,    3,    4,    5,    7,    9,    13,    17,    25,
					33,   49,   65,   97,   129,  193,  257,  385,   513,   769,
					1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577 };
static const uint8_t inf_dext[30] = { 0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6,
				      6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13 };

static void inf_codes(struct inf *s, const struct inf_huff *lh, const struct inf_huff *dh)
{
	for (;;) {
		int sym = inf_decode(s, lh);
		if (s->err)
			return;
		if (sym < 256) {
			inf_put(s, (uint8_t)sym);
		} else if (sym == 256) {
			return;
		} else {
			sym -= 257;
			if (sym >= 29) {
				s->err = -3;
				return;
			}
			size_t len = inf_lbase[sym] + inf_bits(s, inf_lext[sym]);
			int ds = inf_decode(s, dh);
			if (s->err)
				return;
			if (ds >= 30) {
				s->err = -3;
				return;
			}
			size_t dist = inf_dbase[ds] + inf_bits(s, inf_dext[ds]);
			if (s->err)
				return;
			if (dist > s->olen) {
				s->err = -4; /* before the start of the output */
				return;
			}
			while (len-- && !s->err)
				inf_put(s, s->out[s->olen - dist]);
		}
		if (s->err)
			return;
	}
}

static void inf_stored(struct inf *s)
{
	s->bitbuf = 0;
	s->bitcnt = 0; /* drop to the byte boundary */
	if (s->n - s->pos < 4) {
		s->err = -1;
		return;
	}
	unsigned len = s->in[s->pos] | s->in[s->pos + 1] << 8;
	unsigned nlen = s->in[s->pos + 2] | s->in[s->pos + 3] << 8;
	s->pos += 4;
	if (len != (~nlen & 0xffff)) {
		s->err = -5;
		return;
	}
	if (s->n - s->pos < len) {
		s->err = -1;
		return;
	}
	for (unsigned i = 0; i < len; i++)
		inf_put(s, s->in[s->pos + i]);
	s->pos += len;
}

static void inf_fixed(struct inf *s)
{
	uint8_t l[288], d[30];
	struct inf_huff lh, dh;
	for (int i = 0; i < 288; i++)
		l[i] = i < 144 ? 8 : i < 256 ? 9 : i < 280 ? 7 : 8;
	memset(d, 5, sizeof d);
	inf_build(&lh, l, 288);
	inf_build(&dh, d, 30);
	inf_codes(s, &lh, &dh);
}

static void inf_dynamic(struct inf *s)
{
	static const uint8_t order[19] = { 16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15 };
	int nlen = (int)inf_bits(s, 5) + 257, ndist = (int)inf_bits(s, 5) + 1, ncode = (int)inf_bits(s, 4) + 4;
	if (s->err)
		return;
	if (nlen > 286 || ndist > 30) {
		s->err = -6;
		return;
	}
	uint8_t cl[19] = { 0 }, len[316];
	for (int i = 0; i < ncode; i++)
		cl[order[i]] = (uint8_t)inf_bits(s, 3);
	struct inf_huff ch, lh, dh;
	if (s->err || inf_build(&ch, cl, 19) != 0) {
		s->err = s->err ? s->err : -7;
		return;
	}
	for (int i = 0; i < nlen + ndist;) {
		int sym = inf_decode(s, &ch);
		if (s->err)
			return;
		if (sym < 16) {
			len[i++] = (uint8_t)sym;
			continue;
		}
		int rep, v = 0;
		if (sym == 16) {
			if (i == 0) {
				s->err = -8;
				return;
			}
			v = len[i - 1];
			rep = 3 + (int)inf_bits(s, 2);
		} else if (sym == 17) {
			rep = 3 + (int)inf_bits(s, 3);
		} else {
			rep = 11 + (int)inf_bits(s, 7);
		}
		if (s->err || i + rep > nlen + ndist) {
			s->err = s->err ? s->err : -8;
			return;
		}
		while (rep--)
			len[i++] = (uint8_t)v;
	}
	if (len[256] == 0) {
		s->err = -8; /* no end-of-block code */
		return;
	}
	if (inf_build(&lh, len, nlen) != 0) {
		s->err = -7;
		return;
	}
	int dr = inf_build(&dh, len + nlen, ndist);
	/* RFC 1951 allows an incomplete distance code only when it has no code
	 * at all or a single one-bit code */
	int nd = ndist - dh.count[0];
	if (dr < 0 || (dr > 0 && !(nd == 0 || (nd == 1 && dh.count[1] == 1)))) {
		s->err = -7;
		return;
	}
	inf_codes(s, &lh, &dh);
}

/*
 * Inflates a raw deflate stream at in[0..n). On success returns 0, *out is
 * malloc'd (caller frees) and *used is the number of input bytes consumed.
 */
static int inf_inflate(const uint8_t *in, size_t n, uint8_t **out, size_t *out_len, size_t *used,
		       int blocks[3])
{
	struct inf s;
	memset(&s, 0, sizeof s);
	s.in = in;
	s.n = n;
	int last;
	do {
		last = (int)inf_bits(&s, 1);
		int type = (int)inf_bits(&s, 2);
		if (s.err)
			break;
		if (type == 3) {
			s.err = -10;
			break;
		}
		s.blocks[type]++;
		if (type == 0)
			inf_stored(&s);
		else if (type == 1)
			inf_fixed(&s);
		else
			inf_dynamic(&s);
	} while (!last && !s.err);
	if (s.err) {
		free(s.out);
		return s.err;
	}
	*out = s.out ? s.out : malloc(1);
	*out_len = s.olen;
	*used = s.pos; /* the last partial byte is counted: the rest is padding */
	if (blocks)
		memcpy(blocks, s.blocks, sizeof s.blocks);
	return 0;
}

static uint32_t inf_crc32(const uint8_t *p, size_t n, uint32_t crc)
{
	crc = ~crc;
	for (size_t i = 0; i < n; i++) {
		crc ^= p[i];
		for (int k = 0; k < 8; k++)
			crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1)));
	}
	return ~crc;
}

static uint32_t inf_adler32(const uint8_t *p, size_t n)
{
	uint32_t a = 1, b = 0;
	for (size_t i = 0; i < n; i++) {
		a = (a + p[i]) % 65521;
		b = (b + a) % 65521;
	}
	return b << 16 | a;
}

static uint32_t inf_be32(const uint8_t *p)
{
	return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* Decodes a zlib stream that must fill in[0..n) exactly. 0 or a negative error. */
static int inf_zlib(const uint8_t *in, size_t n, uint8_t **out, size_t *out_len, int blocks[3])
{
	if (n < 6 || (in[0] & 0x0f) != 8 || (in[0] >> 4) > 7 || (in[0] * 256u + in[1]) % 31 != 0 ||
	    (in[1] & 0x20))
		return -20;
	size_t used;
	int rc = inf_inflate(in + 2, n - 6, out, out_len, &used, blocks);
	if (rc)
		return rc;
	if (used != n - 6 || inf_be32(in + n - 4) != inf_adler32(*out, *out_len)) {
		free(*out);
		return -21;
	}
	return 0;
}

static uint8_t inf_paeth(int a, int b, int c)
{
	int p = a + b - c, pa = abs(p - a), pb = abs(p - b), pc = abs(p - c);
	return (uint8_t)(pa <= pb && pa <= pc ? a : pb <= pc ? b : c);
}

/*
 * Decodes an 8- or 16-bit RGB, non-interlaced PNG. On success returns 0 with
 * *samples malloc'd (w*h*3 samples of *depth bits, 16-bit ones big-endian
 * as in the file; caller frees). *n_idat counts IDAT chunks, blocks the
 * deflate block types, filters[5] how often each row filter was used.
 * Chunks other than IHDR, IDAT and IEND must be ancillary; they are skipped.
 */
static int inf_png_any(const uint8_t *p, size_t n, uint8_t **samples, uint32_t *w, uint32_t *h, int *depth,
		       int *n_idat, int blocks[3], int filters[5])
{
	static const uint8_t sig[8] = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n' };
	if (n < 8 || memcmp(p, sig, 8) != 0)
		return -30;
	size_t pos = 8, zn = 0;
	uint8_t *z = NULL;
	int seen_ihdr = 0, seen_iend = 0;
	*n_idat = 0;
	while (pos < n && !seen_iend) {
		if (n - pos < 12)
			goto bad;
		uint32_t len = inf_be32(p + pos);
		if (len > n - pos - 12)
			goto bad;
		const uint8_t *type = p + pos + 4, *data = p + pos + 8;
		if (inf_crc32(type, 4 + (size_t)len, 0) != inf_be32(data + len))
			goto bad;
		if (!memcmp(type, "IHDR", 4)) {
			if (seen_ihdr || pos != 8 || len != 13 || (data[8] != 8 && data[8] != 16) || data[9] != 2 ||
			    data[10] || data[11] || data[12])
				goto bad;
			*w = inf_be32(data);
			*h = inf_be32(data + 4);
			*depth = data[8];
			seen_ihdr = 1;
		} else if (!memcmp(type, "IDAT", 4)) {
			if (!seen_ihdr)
				goto bad;
			uint8_t *nz = realloc(z, zn + len + 1);
			if (!nz)
				goto bad;
			z = nz;
			memcpy(z + zn, data, len);
			zn += len;
			(*n_idat)++;
		} else if (!memcmp(type, "IEND", 4)) {
			if (len)
				goto bad;
			seen_iend = 1;
		} else if (!(type[0] & 0x20)) {
			goto bad; /* unknown critical chunk */
		}
		pos += 12 + (size_t)len;
	}
	if (!seen_iend || pos != n || !*n_idat || !*w || !*h)
		goto bad;
	uint8_t *raw;
	size_t rn;
	if (inf_zlib(z, zn, &raw, &rn, blocks) != 0)
		goto bad;
	free(z);
	z = NULL;
	size_t bpp = (size_t)(*depth / 8) * 3, rb = bpp * *w;
	if (rn != (rb + 1) * *h) {
		free(raw);
		return -31;
	}
	size_t img_n = rb * *h;
	uint8_t *img = malloc(img_n ? img_n : 1);
	if (!img) {
		free(raw);
		return -32;
	}
	for (int f = 0; f < 5; f++)
		filters[f] = 0;
	for (uint32_t y = 0; y < *h; y++) {
		const uint8_t *src = raw + y * (rb + 1);
		uint8_t *row = img + y * rb, *up = y ? row - rb : NULL;
		int f = src[0];
		if (f > 4) {
			free(raw);
			free(img);
			return -33;
		}
		filters[f]++;
		for (size_t i = 0; i < rb; i++) {
			int a = i >= bpp ? row[i - bpp] : 0, b = up ? up[i] : 0, c = i >= bpp && up ? up[i - bpp] : 0;
			int pred = f == 0 ? 0 : f == 1 ? a : f == 2 ? b : f == 3 ? (a + b) / 2 : inf_paeth(a, b, c);
			row[i] = (uint8_t)(src[1 + i] + pred);
		}
	}
	free(raw);
	*samples = img;
	return 0;
bad:
	free(z);
	return -34;
}

/* inf_png_any for 8-bit PNGs only: *rgb holds w*h*3 bytes. */
static int inf_png(const uint8_t *p, size_t n, uint8_t **rgb, uint32_t *w, uint32_t *h, int *n_idat,
		   int blocks[3], int filters[5])
{
	int depth = 0;
	int rc = inf_png_any(p, n, rgb, w, h, &depth, n_idat, blocks, filters);
	if (rc == 0 && depth != 8) {
		free(*rgb);
		*rgb = NULL;
		return -35;
	}
	return rc;
}

#endif
