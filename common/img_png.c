/*
 * img_png.c - the PNG encoder (img.h: img_png_encode, and every PNG that
 * img_encode and the writers in img.c make), with an in-tree deflate.
 *
 *   - Filters: each row takes the filter (None, Sub, Up, Average, Paeth) whose
 *     output has the smallest sum of absolute values (bytes read as signed),
 *     the heuristic the PNG specification recommends for true-colour images
 *     (16-bit rows are filtered as bytes too, a pixel being 6 of them).
 *   - The filtered bytes are deflated in pieces of PNG_PIECE bytes, each
 *     piece on its own (no match reaches back into the piece before; its
 *     blocks follow the last one of that piece), on as many threads as
 *     img_set_threads allows: the pieces are fixed, so the bytes are the
 *     same whatever the number of threads. A piece's task filters the rows
 *     it needs itself.
 *   - Deflate (RFC 1951): LZ77 over a 32 KiB window with hash chains on three
 *     bytes and one-step lazy matching (parameters between zlib's levels 5
 *     and 6: chains of up to 32, 8 when a good match is in hand, stop at 64).
 *     Symbols are gathered into blocks of up to 16 Ki symbols; each block is
 *     written as dynamic Huffman, fixed Huffman or stored, whichever is
 *     smallest. Huffman code lengths are limited (15, and 7 for the code-length
 *     code) by halving the frequencies until the tree fits; every code has at
 *     least two symbols, so all codes are complete.
 *   - zlib wrapper (RFC 1950) with Adler-32; chunks with CRC-32; the IDAT
 *     data is split into chunks of at most 1 MiB.
 *   - With metadata (img_png_emit's plain 0) cHRM, gAMA, sRGB, sBIT (16-bit
 *     from 8-bit values) and tEXt chunks come between IHDR and IDAT; the
 *     IDAT data is the same with or without them.
 */
#include "common/img.h"

#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The SSE2 paths, and (IMG_WORD_COMPARE, below) the word-at-a-time ones:
 * IMG_PORTABLE leaves both out (tests/cli/png_portable.sh builds the
 * encoder so and checks it makes the same bytes). */
#if defined(__SSE2__) && !defined(IMG_PORTABLE)
#define IMG_SSE2 1
#include <emmintrin.h>
#else
#define IMG_SSE2 0
#endif

#include "common/crc32.h"
#include "common/img_int.h"

/* ---- tables ---------------------------------------------------------------- */

static uint8_t len_code[259];   /* match length 3..258 -> code index 0..28 */
static uint8_t dist_code[512];  /* see img_dist_code */
static pthread_once_t tables_once = PTHREAD_ONCE_INIT;

/* base values and extra bits of the 29 length codes and 30 distance codes */
static const uint16_t len_base[29] = { 3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
				       31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258 };
static const uint8_t len_extra[29] = { 0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
				       2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0 };
static const uint16_t dist_base[30] = { 1,   2,   3,   4,   5,    7,    9,    13,   17,   25,
					33,  49,  65,  97,  129,  193,  257,  385,  513,  769,
					1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577 };
static const uint8_t dist_extra[30] = { 0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6,
					6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13 };
/* order in which code-length code lengths are sent */
static const uint8_t cl_order[19] = { 16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15 };

static void tables_init(void)
{
	for (int code = 0; code < 29; code++) {
		int top = code == 28 ? 258 : len_base[code] + (1 << len_extra[code]) - 1;
		if (code == 27)
			top = 257; /* 258 has its own code */
		for (int l = len_base[code]; l <= top; l++)
			len_code[l] = (uint8_t)code;
	}
	/* distances 1..256 directly; 257..32768 by (d-1) >> 7 */
	for (int code = 0; code < 30; code++) {
		int lo = dist_base[code], hi = dist_base[code] + (1 << dist_extra[code]) - 1;
		for (int d = lo; d <= hi; d++) {
			if (d <= 256)
				dist_code[d - 1] = (uint8_t)code;
			else
				dist_code[256 + ((d - 1) >> 7)] = (uint8_t)code;
		}
	}
}

static inline int img_dist_code(unsigned d)
{
	return d <= 256 ? dist_code[d - 1] : dist_code[256 + ((d - 1) >> 7)];
}

/*
 * Adler-32 (RFC 1950). Start with adler = 1; pieces chain like crc32_update.
 * With SSE2, 16 bytes at a time: over a block of 16 bytes v[0..15], a
 * grows by their sum (psadbw) and b by 16 a + sum of (16 - i) v[i]
 * (pmaddwd on the bytes widened to 16 bits); the 16 a terms are gathered
 * as the sum of a's values before each block (ps) and added once per
 * stretch, whose length keeps every lane within 32 bits as zlib's NMAX
 * keeps b.
 */
uint32_t img_adler32(uint32_t adler, const uint8_t *p, size_t n)
{
	uint32_t a = adler & 0xffff, b = adler >> 16;
	while (n > 0) {
		/* 5552 bytes keep b below 2^32 before the reduction (zlib's NMAX) */
		size_t k = n < 5552 ? n : 5552;
		n -= k;
#if IMG_SSE2
		size_t nb = k / 16;
		if (nb > 0) {
			const __m128i z = _mm_setzero_si128();
			const __m128i w_lo = _mm_setr_epi16(16, 15, 14, 13, 12, 11, 10, 9);
			const __m128i w_hi = _mm_setr_epi16(8, 7, 6, 5, 4, 3, 2, 1);
			__m128i s1 = z, ps = z, s2 = z;
			for (size_t i = 0; i < nb; i++) {
				__m128i v = _mm_loadu_si128((const __m128i *)(const void *)(p + 16 * i));
				ps = _mm_add_epi32(ps, s1);
				s1 = _mm_add_epi32(s1, _mm_sad_epu8(v, z));
				s2 = _mm_add_epi32(s2, _mm_madd_epi16(_mm_unpacklo_epi8(v, z), w_lo));
				s2 = _mm_add_epi32(s2, _mm_madd_epi16(_mm_unpackhi_epi8(v, z), w_hi));
			}
			uint32_t l1[4], lp[4], l2[4];
			_mm_storeu_si128((__m128i *)(void *)l1, s1);
			_mm_storeu_si128((__m128i *)(void *)lp, ps);
			_mm_storeu_si128((__m128i *)(void *)l2, s2);
			/* psadbw leaves its sums in lanes 0 and 2 */
			uint64_t sum1 = (uint64_t)l1[0] + l1[2], sump = (uint64_t)lp[0] + lp[2];
			uint64_t sum2 = (uint64_t)l2[0] + l2[1] + l2[2] + l2[3];
			b = (uint32_t)(((uint64_t)b + 16 * (uint64_t)nb * a + 16 * sump + sum2) % 65521);
			a = (uint32_t)(((uint64_t)a + sum1) % 65521);
			p += 16 * nb;
			k -= 16 * nb;
		}
#endif
		while (k--) {
			a += *p++;
			b += a;
		}
		a %= 65521;
		b %= 65521;
	}
	return (b << 16) | a;
}

/* ---- output buffer and bit writer ------------------------------------------- */

struct obuf {
	uint8_t *p;
	size_t n, cap;
	int oom;
	uint64_t bits; /* pending bits, LSB first */
	int nbits;
	int has_stored; /* a stored block was written (it pads to this buffer's bytes) */
};

static void ob_reserve(struct obuf *o, size_t more)
{
	if (o->oom || o->n + more <= o->cap)
		return;
	size_t ncap = o->cap ? o->cap : 4096;
	while (ncap < o->n + more) {
		if (ncap > SIZE_MAX / 2) {
			o->oom = 1;
			return;
		}
		ncap *= 2;
	}
	uint8_t *np = realloc(o->p, ncap);
	if (!np) {
		o->oom = 1;
		return;
	}
	o->p = np;
	o->cap = ncap;
}

static void ob_bytes(struct obuf *o, const void *src, size_t n)
{
	ob_reserve(o, n);
	if (o->oom)
		return;
	memcpy(o->p + o->n, src, n);
	o->n += n;
}

static void ob_be32(struct obuf *o, uint32_t v)
{
	uint8_t b[4] = { (uint8_t)(v >> 24), (uint8_t)(v >> 16), (uint8_t)(v >> 8), (uint8_t)v };
	ob_bytes(o, b, 4);
}

/* Appends n (<= 32) bits of v, least significant first. */
static inline void ob_put(struct obuf *o, uint32_t v, int n)
{
	o->bits |= (uint64_t)v << o->nbits;
	o->nbits += n;
	if (o->nbits >= 32) {
		ob_reserve(o, 4);
		if (!o->oom) {
			uint8_t *d = o->p + o->n;
			d[0] = (uint8_t)o->bits;
			d[1] = (uint8_t)(o->bits >> 8);
			d[2] = (uint8_t)(o->bits >> 16);
			d[3] = (uint8_t)(o->bits >> 24);
			o->n += 4;
		}
		o->bits >>= 32;
		o->nbits -= 32;
	}
}

/* Pads to a byte boundary and writes out the pending bits. */
static void ob_flush_bits(struct obuf *o)
{
	while (o->nbits > 0) {
		uint8_t b = (uint8_t)o->bits;
		ob_bytes(o, &b, 1);
		o->bits >>= 8;
		o->nbits -= 8;
	}
	o->bits = 0;
	o->nbits = 0;
}

/*
 * Appends src's bits (its bytes, then its pending bits) to o's, src being
 * a piece of one deflate stream. A piece with a stored block must start on
 * a byte (the block's padding reaches src's byte boundary): an empty
 * stored block (BFINAL 0, BTYPE 00, padding, LEN 0, NLEN 0xffff) first
 * takes o to one.
 */
static void ob_append_bits(struct obuf *o, const struct obuf *src)
{
	if (src->has_stored && o->nbits % 8) {
		static const uint8_t empty[4] = { 0, 0, 0xff, 0xff };
		ob_put(o, 0, 3);
		ob_flush_bits(o);
		ob_bytes(o, empty, 4);
	}
	if (o->nbits == 0) {
		ob_bytes(o, src->p, src->n);
	} else if (o->nbits % 8 == 0) {
		ob_flush_bits(o);
		ob_bytes(o, src->p, src->n);
	} else {
		const uint8_t *p = src->p;
		size_t i = 0;
		for (; i + 4 <= src->n; i += 4) /* the same bits, 32 at a time */
			ob_put(o, (uint32_t)p[i] | (uint32_t)p[i + 1] << 8 | (uint32_t)p[i + 2] << 16 |
					  (uint32_t)p[i + 3] << 24, 32);
		for (; i < src->n; i++)
			ob_put(o, p[i], 8);
	}
	if (src->nbits)
		ob_put(o, (uint32_t)src->bits, src->nbits);
}

/* ---- Huffman codes ------------------------------------------------------------ */

/*
 * Code lengths for freq[0..n) limited to `limit` bits. Symbols with zero
 * frequency get length 0. At least two symbols always get a code (a zero
 * frequency symbol is promoted when needed), so the code is complete.
 */
static void huff_lengths(const uint32_t *freq_in, int n, int limit, uint8_t *len)
{
	uint32_t freq[288];
	int nz = 0;
	for (int i = 0; i < n; i++) {
		freq[i] = freq_in[i];
		nz += freq[i] != 0;
	}
	for (int i = 0; nz < 2 && i < n; i++) {
		if (!freq[i]) {
			freq[i] = 1;
			nz++;
		}
	}
	for (;;) {
		/* leaves sorted by frequency, ties by symbol: a stable merge sort
		 * of the symbols in order (the same order as an insertion sort) */
		int buf[2][288], m = 0, *sym = buf[0], *other = buf[1];
		for (int i = 0; i < n; i++)
			if (freq[i])
				sym[m++] = i;
		for (int width = 1; width < m; width *= 2) {
			for (int lo = 0; lo < m; lo += 2 * width) {
				int mid = lo + width < m ? lo + width : m, hi = lo + 2 * width < m ? lo + 2 * width : m;
				int a = lo, b = mid, o = lo;
				while (a < mid && b < hi)
					other[o++] = freq[sym[a]] <= freq[sym[b]] ? sym[a++] : sym[b++];
				while (a < mid)
					other[o++] = sym[a++];
				while (b < hi)
					other[o++] = sym[b++];
			}
			int *swap = sym;
			sym = other;
			other = swap;
		}
		/* two-queue Huffman: nodes 0..m-1 leaves, m.. internal */
		uint64_t w[2 * 288];
		int parent[2 * 288];
		for (int i = 0; i < m; i++)
			w[i] = freq[sym[i]];
		int li = 0, ii = m, next = m;
		for (int k = 0; k < m - 1; k++) {
			int pick[2];
			for (int t = 0; t < 2; t++) {
				if (li < m && (ii >= next || w[li] <= w[ii]))
					pick[t] = li++;
				else
					pick[t] = ii++;
			}
			w[next] = w[pick[0]] + w[pick[1]];
			parent[pick[0]] = parent[pick[1]] = next;
			next++;
		}
		/* depths: the root is next-1; parents have larger indices */
		int depth[2 * 288];
		depth[next - 1] = 0;
		for (int i = next - 2; i >= 0; i--)
			depth[i] = depth[parent[i]] + 1;
		int maxd = 0;
		for (int i = 0; i < m; i++)
			maxd = depth[i] > maxd ? depth[i] : maxd;
		if (maxd <= limit) {
			memset(len, 0, (size_t)n);
			for (int i = 0; i < m; i++)
				len[sym[i]] = (uint8_t)depth[i];
			return;
		}
		for (int i = 0; i < n; i++)
			if (freq[i])
				freq[i] = (freq[i] >> 1) | 1;
	}
}

/* Canonical codes from lengths (RFC 1951 3.2.2), bit-reversed for LSB-first output. */
static void huff_codes(const uint8_t *len, int n, uint16_t *code)
{
	int count[16] = { 0 }, next[16];
	for (int i = 0; i < n; i++)
		count[len[i]]++;
	count[0] = 0;
	int c = 0;
	for (int b = 1; b < 16; b++) {
		c = (c + count[b - 1]) << 1;
		next[b] = c;
	}
	for (int i = 0; i < n; i++) {
		if (!len[i]) {
			code[i] = 0;
			continue;
		}
		unsigned v = (unsigned)next[len[i]]++, r = 0;
		for (int k = 0; k < len[i]; k++) {
			r = (r << 1) | (v & 1);
			v >>= 1;
		}
		code[i] = (uint16_t)r;
	}
}

/* ---- deflate ------------------------------------------------------------------- */

#define WSIZE 32768
#define HBITS 15
#define HSIZE (1 << HBITS)
#define MIN_MATCH 3
#define MAX_MATCH 258
/* chains of 128 and NICE_LEN 128 (zlib level 6) made files 1.5-3.5% smaller
 * in 1.6 times the instructions (docs/performance.md, round 4) */
#define MAX_CHAIN 32
#define GOOD_LEN 8     /* with a match this long, search a quarter of the chain */
#define NICE_LEN 64    /* stop searching at a match this long */
#define LAZY_LEN 16    /* do not look for a better match beyond this */
#define BLOCK_SYMS 16384

struct deflate {
	const uint8_t *in;
	size_t n;
	uint32_t *head; /* HSIZE: most recent position + 1 with this hash (0: none) */
	uint32_t *prev; /* WSIZE: previous position + 1 in the chain (an entry is
			 * read only once its position is inserted: not cleared) */
	uint16_t *sym_ll; /* literal (0-255) or length (3-258) */
	uint16_t *sym_d;  /* 0 for a literal, else the distance */
	int nsym;
	/* the pending symbols' frequencies, counted as they are added (where
	 * the kind is known without a branch): literal/length, distance */
	uint32_t lf[286], df[30];
	size_t block_start; /* first input byte of the pending block */
	struct obuf *o;
};

/* Word-at-a-time loads (match comparison, hashing) where the byte order
 * makes them easy. */
#if defined(__GNUC__) && defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__ && \
	!defined(IMG_PORTABLE)
#define IMG_WORD_COMPARE 1
#else
#define IMG_WORD_COMPARE 0
#endif

/*
 * HASH OF FOUR. A position's chain holds the earlier positions whose next
 * four bytes hash alike (zlib's hash three): on a render's filtered rows
 * the three-byte chains were long lists of candidates that fail at the
 * fourth byte, walked to MAX_CHAIN for every position. Hashing four bytes,
 * the SPD renders encode 4-26% faster and, but for balls_s4 (+2.1%: its
 * three-byte matches), into smaller files (docs/performance.md, round 21).
 * The last three positions of the input, which have no four bytes, hash
 * their three. A match of exactly three is still found where four-byte
 * hashes collide; none is looked for otherwise.
 */
static inline uint32_t hash_word(uint32_t v) { return (v * 2654435761u) >> (32 - HBITS); }

static inline uint32_t hash4(const uint8_t *p)
{
	return hash_word((uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24);
}

static inline uint32_t hash3(const uint8_t *p)
{
	return hash_word((uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16);
}

/* The hash of the bytes at pos (pos + 3 <= n): HASH OF FOUR where four
 * are left, with one little-endian load where the byte order allows. */
static inline uint32_t hash_at(const struct deflate *z, size_t pos)
{
	if (pos + 4 <= z->n) {
#if IMG_WORD_COMPARE
		uint32_t v;
		memcpy(&v, z->in + pos, 4);
		return hash_word(v);
#else
		return hash4(z->in + pos);
#endif
	}
	return hash3(z->in + pos);
}

/* insert() of pos whose hash_at is h (pos + MIN_MATCH <= z->n). */
static inline void insert_h(struct deflate *z, size_t pos, uint32_t h)
{
	z->prev[pos & (WSIZE - 1)] = z->head[h];
	z->head[h] = (uint32_t)pos + 1;
}

static inline void insert(struct deflate *z, size_t pos)
{
	if (pos + MIN_MATCH > z->n)
		return;
	insert_h(z, pos, hash_at(z, pos));
}


#if IMG_WORD_COMPARE
/* prev[p] = p (the position before p, plus one) for p in [from, to): the
 * chain of a run of positions that all hash alike. */
static void link_each(uint32_t *prev, size_t from, size_t to)
{
	while (from < to) {
		size_t off = from & (WSIZE - 1), m = WSIZE - off < to - from ? WSIZE - off : to - from;
		uint32_t *d = prev + off, v = (uint32_t)from;
		size_t i = 0;
#if IMG_SSE2
		__m128i x = _mm_add_epi32(_mm_set1_epi32((int)v), _mm_setr_epi32(0, 1, 2, 3));
		const __m128i four = _mm_set1_epi32(4);
		for (; i + 4 <= m; i += 4) {
			_mm_storeu_si128((__m128i *)(void *)(d + i), x);
			x = _mm_add_epi32(x, four);
		}
#endif
		for (; i < m; i++)
			d[i] = v + (uint32_t)i;
		from += m;
	}
}
#endif

/*
 * insert() for every position in [from, to): what a match covers. The
 * chains come out exactly as one insert() at a time would make them:
 *   - four positions from one little-endian 8-byte load, each one's four
 *     bytes being hash4's value (q + 8 <= n: none is in the last three);
 *   - where the 8 bytes are one value repeated (flat areas, the common
 *     case), the run is followed 8 bytes at a time; all its positions
 *     but the last three share one hash, so each one's chain link is simply
 *     the position before it (link_each).
 * Near the end of the input (fewer than 8 bytes to read) insert() itself.
 */
static inline void insert_run(struct deflate *z, size_t from, size_t to)
{
	size_t q = from;
#if IMG_WORD_COMPARE
	const uint8_t *in = z->in;
	uint32_t *head = z->head, *prev = z->prev;
	size_t n = z->n;
	while (q + 4 <= to && q + 8 <= n) {
		uint64_t w;
		memcpy(&w, in + q, 8);
		if (w == (w & 0xff) * 0x0101010101010101ull) {
			/* bytes [q, e) are one value: positions up to e - 4 hash alike */
			size_t e = q + 8;
			while (e + 8 <= n && e < to + 3) {
				uint64_t x;
				memcpy(&x, in + e, 8);
				if (x != w)
					break;
				e += 8;
			}
			size_t stop = e - 3 < to ? e - 3 : to;
			uint32_t h = hash_word((uint32_t)w);
			prev[q & (WSIZE - 1)] = head[h];
			link_each(prev, q + 1, stop);
			head[h] = (uint32_t)stop;
			q = stop;
			continue;
		}
		for (int i = 0; i < 4; i++) {
			uint32_t h = hash_word((uint32_t)(w >> (8 * i)));
			prev[(q + (size_t)i) & (WSIZE - 1)] = head[h];
			head[h] = (uint32_t)(q + (size_t)i) + 1;
		}
		q += 4;
	}
#endif
	for (; q < to; q++)
		insert(z, q);
}

#if IMG_WORD_COMPARE
static inline uint16_t load16(const uint8_t *p)
{
	uint16_t v;
	memcpy(&v, p, 2);
	return v;
}
#endif

/*
 * Longest match for pos (h: hash_at(z, pos)) among earlier positions
 * (inserted already); 0 if < 3. A candidate is compared in full only when the two bytes ending at
 * the current best length and its first two bytes agree (each necessary
 * for a longer match), then 8 bytes at a time: the same candidates win as
 * with a byte-at-a-time comparison.
 */
static int longest_match(const struct deflate *z, size_t pos, uint32_t h, int prev_len, unsigned *dist)
{
	size_t avail = z->n - pos;
	int maxlen = avail < MAX_MATCH ? (int)avail : MAX_MATCH;
	if (maxlen < MIN_MATCH)
		return 0;
	int chain = prev_len >= GOOD_LEN ? MAX_CHAIN / 4 : MAX_CHAIN;
	int best = prev_len > MIN_MATCH - 1 ? prev_len : MIN_MATCH - 1;
	int found = 0;
	if (best >= maxlen)
		return 0;
	const uint8_t *s = z->in + pos;
	/* Every position in the chains is below pos (pos is inserted after
	 * its search), so a chain ends at 0 or at the first position more than
	 * WSIZE back: cand (position + 1) at most lim. Within the window no
	 * link can have been overwritten (position c's slot is reused by
	 * c + WSIZE, not inserted yet), so links only lead back. */
	uint32_t lim = pos > WSIZE ? (uint32_t)(pos - WSIZE) : 0;
	uint32_t cand = z->head[h];
	while (cand > lim && chain-- > 0) {
		size_t c = cand - 1;
		const uint8_t *t = z->in + c;
#if IMG_WORD_COMPARE
		if (load16(t + best - 1) == load16(s + best - 1) && load16(t) == load16(s)) {
			int l = 2;
			while (l + 8 <= maxlen) {
				uint64_t a, b;
				memcpy(&a, t + l, 8);
				memcpy(&b, s + l, 8);
				if (a != b) { /* the lowest differing byte ends the match */
					l += __builtin_ctzll(a ^ b) >> 3;
					goto compared;
				}
				l += 8;
			}
			while (l < maxlen && t[l] == s[l])
				l++;
		compared:
#else
		if (t[best] == s[best] && t[0] == s[0] && t[1] == s[1]) {
			int l = 2;
			while (l < maxlen && t[l] == s[l])
				l++;
#endif
			if (l > best) {
				best = l;
				found = l;
				*dist = (unsigned)(pos - c);
				if (l >= NICE_LEN || l >= maxlen)
					break;
			}
		}
		cand = z->prev[c & (WSIZE - 1)];
	}
	return found >= MIN_MATCH ? found : 0;
}

/* Bits to send freq under lengths len, with the extra bits of lengths/distances. */
static uint64_t block_cost(const uint32_t *lf, const uint8_t *ll, const uint32_t *df, const uint8_t *dl)
{
	uint64_t bits = 0;
	for (int i = 0; i < 286; i++)
		bits += (uint64_t)lf[i] * (ll[i] + (i >= 257 ? len_extra[i - 257] : 0));
	for (int i = 0; i < 30; i++)
		bits += (uint64_t)df[i] * (dl[i] + dist_extra[i]);
	return bits;
}

/* A bit writer into room reserved beforehand: ob_put's bits and bytes
 * without its checks, its state in locals (registers). */
struct bitw {
	uint64_t bits;
	int nbits;
	uint8_t *d;
};

static inline void bw_put(struct bitw *w, uint32_t v, int n)
{
	w->bits |= (uint64_t)v << w->nbits;
	w->nbits += n;
	if (w->nbits >= 32) {
		w->d[0] = (uint8_t)w->bits;
		w->d[1] = (uint8_t)(w->bits >> 8);
		w->d[2] = (uint8_t)(w->bits >> 16);
		w->d[3] = (uint8_t)(w->bits >> 24);
		w->d += 4;
		w->bits >>= 32;
		w->nbits -= 32;
	}
}

/* Writes the symbols of one block with the given codes: at most 48 bits a
 * symbol (length code 15 + 5 extra, distance code 15 + 13 extra) and the
 * end code, so 6 bytes a symbol and 16 more are reserved first. */
static void write_symbols(struct deflate *z, const uint16_t *lc, const uint8_t *ll, const uint16_t *dc,
			  const uint8_t *dl)
{
	struct obuf *o = z->o;
	ob_reserve(o, (size_t)z->nsym * 6 + 16);
	if (o->oom)
		return;
	struct bitw w = { o->bits, o->nbits, o->p + o->n };
	for (int i = 0; i < z->nsym; i++) {
		unsigned v = z->sym_ll[i], d = z->sym_d[i];
		if (!d) {
			bw_put(&w, lc[v], ll[v]);
			continue;
		}
		int c = len_code[v];
		bw_put(&w, lc[257 + c], ll[257 + c]);
		if (len_extra[c])
			bw_put(&w, v - len_base[c], len_extra[c]);
		int dcode = img_dist_code(d);
		bw_put(&w, dc[dcode], dl[dcode]);
		if (dist_extra[dcode])
			bw_put(&w, d - dist_base[dcode], dist_extra[dcode]);
	}
	bw_put(&w, lc[256], ll[256]);
	o->n = (size_t)(w.d - o->p);
	o->bits = w.bits;
	o->nbits = w.nbits;
}

/*
 * Emits the pending symbols, which cover input [block_start, end), as the
 * smallest of a dynamic, fixed or stored block. last marks the final block.
 */
static void flush_block(struct deflate *z, size_t end, int last)
{
	struct obuf *o = z->o;
	uint32_t *lf = z->lf, *df = z->df;
	lf[256] = 1;

	/* dynamic code */
	uint8_t ll[286], dl[30];
	huff_lengths(lf, 286, 15, ll);
	huff_lengths(df, 30, 15, dl);
	int hlit = 286, hdist = 30;
	while (hlit > 257 && !ll[hlit - 1])
		hlit--;
	while (hdist > 1 && !dl[hdist - 1])
		hdist--;
	/* run-length code the lengths with symbols 16 (repeat), 17, 18 (zeros) */
	uint8_t lens[316], rle[316], rle_extra[316];
	int nl = 0, nr = 0;
	for (int i = 0; i < hlit; i++)
		lens[nl++] = ll[i];
	for (int i = 0; i < hdist; i++)
		lens[nl++] = dl[i];
	uint32_t cf[19] = { 0 };
	for (int i = 0; i < nl;) {
		int v = lens[i], run = 1;
		while (i + run < nl && lens[i + run] == v)
			run++;
		if (v == 0 && run >= 3) {
			int r = run > 138 ? 138 : run;
			rle[nr] = r >= 11 ? 18 : 17;
			rle_extra[nr++] = (uint8_t)(r >= 11 ? r - 11 : r - 3);
			i += r;
		} else if (v != 0 && run >= 4) {
			rle[nr] = (uint8_t)v;
			rle_extra[nr++] = 0;
			int r = run - 1 > 6 ? 6 : run - 1;
			rle[nr] = 16;
			rle_extra[nr++] = (uint8_t)(r - 3);
			i += 1 + r;
		} else {
			rle[nr] = (uint8_t)v;
			rle_extra[nr++] = 0;
			i++;
		}
	}
	for (int i = 0; i < nr; i++)
		cf[rle[i]]++;
	uint8_t cl[19];
	huff_lengths(cf, 19, 7, cl);
	int hclen = 19;
	while (hclen > 4 && !cl[cl_order[hclen - 1]])
		hclen--;
	uint64_t dyn = 3 + 5 + 5 + 4 + 3ull * hclen + block_cost(lf, ll, df, dl);
	for (int i = 0; i < 19; i++)
		dyn += (uint64_t)cf[i] * (cl[i] + (i == 16 ? 2 : i == 17 ? 3 : i == 18 ? 7 : 0));

	/* fixed code */
	uint8_t fl[288], fd[30];
	for (int i = 0; i < 288; i++)
		fl[i] = i < 144 ? 8 : i < 256 ? 9 : i < 280 ? 7 : 8;
	memset(fd, 5, sizeof fd);
	uint64_t fix = 3 + block_cost(lf, fl, df, fd);

	/* stored: per 65535-byte piece a 3-bit header, padding, LEN and NLEN */
	size_t raw = end - z->block_start;
	uint64_t pieces = raw ? (raw + 65534) / 65535 : 1;
	uint64_t stored = pieces * (3 + 7 + 32) + 8ull * raw;

	if (stored < dyn && stored < fix) {
		size_t pos = z->block_start;
		do {
			size_t k = end - pos > 65535 ? 65535 : end - pos;
			int fin = last && pos + k == end;
			ob_put(o, (uint32_t)fin, 3); /* BTYPE 00 */
			ob_flush_bits(o);
			o->has_stored = 1;
			uint8_t h[4] = { (uint8_t)k, (uint8_t)(k >> 8), (uint8_t)~k, (uint8_t)(~k >> 8) };
			ob_bytes(o, h, 4);
			ob_bytes(o, z->in + pos, k);
			pos += k;
		} while (pos < end);
	} else if (fix <= dyn) {
		uint16_t lc[288], dc[30];
		huff_codes(fl, 288, lc);
		huff_codes(fd, 30, dc);
		ob_put(o, (uint32_t)last | 1u << 1, 3); /* BTYPE 01 */
		write_symbols(z, lc, fl, dc, fd);
	} else {
		uint16_t lc[286], dc[30], cc[19];
		huff_codes(ll, 286, lc);
		huff_codes(dl, 30, dc);
		huff_codes(cl, 19, cc);
		ob_put(o, (uint32_t)last | 2u << 1, 3); /* BTYPE 10 */
		ob_put(o, (uint32_t)(hlit - 257), 5);
		ob_put(o, (uint32_t)(hdist - 1), 5);
		ob_put(o, (uint32_t)(hclen - 4), 4);
		for (int i = 0; i < hclen; i++)
			ob_put(o, cl[cl_order[i]], 3);
		for (int i = 0; i < nr; i++) {
			ob_put(o, cc[rle[i]], cl[rle[i]]);
			if (rle[i] >= 16)
				ob_put(o, rle_extra[i], rle[i] == 16 ? 2 : rle[i] == 17 ? 3 : 7);
		}
		write_symbols(z, lc, ll, dc, dl);
	}
	z->nsym = 0;
	memset(z->lf, 0, sizeof z->lf);
	memset(z->df, 0, sizeof z->df);
	z->block_start = end;
}

/* Adds literal byte c to the pending symbols. */
static inline void add_lit(struct deflate *z, unsigned c)
{
	z->sym_ll[z->nsym] = (uint16_t)c;
	z->sym_d[z->nsym] = 0;
	z->nsym++;
	z->lf[c]++;
}

/* Adds a match of len (3..258) at distance d (1..32768). */
static inline void add_match(struct deflate *z, unsigned len, unsigned d)
{
	z->sym_ll[z->nsym] = (uint16_t)len;
	z->sym_d[z->nsym] = (uint16_t)d;
	z->nsym++;
	z->lf[257 + len_code[len]]++;
	z->df[img_dist_code(d)]++;
}

/* deflate_raw stays a function of its own: inlined into its caller along
 * with the filters, its match loop ran 7% more instructions (registers) */
#if defined(__GNUC__)
#define IMG_NOINLINE __attribute__((noinline))
#else
#define IMG_NOINLINE
#endif

/* A deflate's tables, kept from one piece to the next by a thread. */
struct deflate_mem {
	uint32_t *head;   /* HSIZE */
	uint32_t *prev;   /* WSIZE */
	uint16_t *sym_ll; /* BLOCK_SYMS */
	uint16_t *sym_d;  /* BLOCK_SYMS */
};

/* Allocates m's tables (m zeroed or freed before); 0 or -1. */
static int deflate_mem_init(struct deflate_mem *m)
{
	m->head = malloc(HSIZE * sizeof *m->head);
	m->prev = malloc(WSIZE * sizeof *m->prev);
	m->sym_ll = malloc(BLOCK_SYMS * sizeof *m->sym_ll);
	m->sym_d = malloc(BLOCK_SYMS * sizeof *m->sym_d);
	return m->head && m->prev && m->sym_ll && m->sym_d ? 0 : -1;
}

static void deflate_mem_free(struct deflate_mem *m)
{
	free(m->head);
	free(m->prev);
	free(m->sym_ll);
	free(m->sym_d);
	memset(m, 0, sizeof *m);
}

/*
 * Compresses in[0..n) as a raw deflate stream appended to o, matches
 * reaching no further back than in, with m's tables (allocated; their
 * contents are set here). last: the final piece of the stream (its last
 * block has BFINAL set); else the next piece's bits follow (its pending
 * bits stay in o->bits). Returns 0, or -1 when out of memory (o->oom).
 */
IMG_NOINLINE static int deflate_raw(const uint8_t *in, size_t n, struct obuf *o, int last, const struct deflate_mem *m)
{
	struct deflate z;
	memset(&z, 0, sizeof z);
	z.in = in;
	z.n = n;
	z.o = o;
	z.head = m->head;
	z.prev = m->prev;
	z.sym_ll = m->sym_ll;
	z.sym_d = m->sym_d;
	memset(z.head, 0, HSIZE * sizeof *z.head);

	/* one-step lazy matching: the byte at pos-1 may be pending (has_prev),
	 * with the match found there (prev_len >= 3) or as a literal (0) */
	size_t pos = 0;
	int has_prev = 0, prev_len = 0;
	unsigned prev_dist = 0;
	/* h: hash_at(pos), made once for its search and its insertion, and
	 * (as hn) one position ahead, so that the chain's head is fetched
	 * under the search before it; 0 where fewer than 3 bytes are left */
	uint32_t h = n >= MIN_MATCH ? hash_at(&z, 0) : 0;
	while (pos < n) {
		unsigned dist = 0;
		int len = 0;
		uint32_t hn = pos + 1 + MIN_MATCH <= n ? hash_at(&z, pos + 1) : 0;
		__builtin_prefetch(&z.head[hn]);
		if (!has_prev || prev_len < LAZY_LEN)
			len = longest_match(&z, pos, h, has_prev ? prev_len : 0, &dist);
		if (has_prev && prev_len >= MIN_MATCH && len <= prev_len) {
			/* the match at pos-1 wins: emit it, insert what it covers */
			add_match(&z, (unsigned)prev_len, prev_dist);
			size_t stop = pos - 1 + (size_t)prev_len;
			insert_run(&z, pos, stop);
			pos = stop;
			h = pos + MIN_MATCH <= n ? hash_at(&z, pos) : 0;
			has_prev = 0;
		} else {
			if (has_prev)
				add_lit(&z, in[pos - 1]);
			if (pos + MIN_MATCH <= n)
				insert_h(&z, pos, h);
			h = hn;
			has_prev = 1;
			prev_len = len;
			prev_dist = dist;
			pos++;
		}
		if (z.nsym >= BLOCK_SYMS - 2)
			flush_block(&z, has_prev ? pos - 1 : pos, 0); /* pending byte: next block */
	}
	if (has_prev)
		add_lit(&z, in[n - 1]); /* no match can start at n-1 */
	flush_block(&z, n, last);
	return o->oom ? -1 : 0;
}

/* ---- PNG ------------------------------------------------------------------------ */

static inline uint8_t paeth(uint8_t a, uint8_t b, uint8_t c)
{
	int p = (int)a + b - c, pa = abs(p - a), pb = abs(p - b), pc = abs(p - c);
	return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

/*
 * Where the PNG's rows come from: the caller's RGB8 rows as they are, or
 * rows converted into buf[y & 1] (so row y - 1 stays valid while row y is
 * made): 8-bit from floats, 16-bit (big-endian samples) from either.
 */
struct png_rows {
	const struct img_desc *d;
	int depth16;
	size_t rb; /* bytes per row: 3w or 6w */
	uint8_t *buf[2];
};

static const uint8_t *png_row(struct png_rows *r, uint32_t y)
{
	const struct img_desc *d = r->d;
	size_t n = 3 * (size_t)d->w;
	if (d->type == IMG_RGB8 && !r->depth16)
		return (const uint8_t *)d->pixels + y * n;
	uint8_t *o = r->buf[y & 1];
	if (d->type == IMG_RGB8) {
		/* v * 257 = v in both bytes: the exact 8-to-16-bit scaling (PNG's
		 * left bit replication; sBIT tells a decoder the high byte is it) */
		const uint8_t *p = (const uint8_t *)d->pixels + y * n;
		for (size_t i = 0; i < n; i++)
			o[2 * i] = o[2 * i + 1] = p[i];
	} else if (!r->depth16) {
		const float *p = (const float *)d->pixels + y * n;
		for (size_t i = 0; i < n; i++)
			o[i] = (uint8_t)img_quantise(p[i], 255.0);
	} else {
		const float *p = (const float *)d->pixels + y * n;
		for (size_t i = 0; i < n; i++) {
			unsigned v = img_quantise(p[i], 65535.0);
			o[2 * i] = (uint8_t)(v >> 8);
			o[2 * i + 1] = (uint8_t)v;
		}
	}
	return o;
}

/* The five filters of bytes [i0, i1) of one row into d[i0..i1) (cur: the
 * row, up: the one above or NULL, k: bytes per pixel; i0 is 0 or at least
 * k), each byte exactly as the PNG specification defines it; one loop per
 * filter, so each vectorises. */
static void filter_none(const uint8_t *cur, const uint8_t *up, size_t k, size_t i0, size_t i1, uint8_t *d)
{
	(void)up, (void)k;
	memcpy(d + i0, cur + i0, i1 - i0);
}

static void filter_sub(const uint8_t *cur, const uint8_t *up, size_t k, size_t i0, size_t i1, uint8_t *d)
{
	(void)up;
	size_t i = i0;
	for (; i < k && i < i1; i++)
		d[i] = cur[i];
	for (; i < i1; i++)
		d[i] = (uint8_t)(cur[i] - cur[i - k]);
}

static void filter_up(const uint8_t *cur, const uint8_t *up, size_t k, size_t i0, size_t i1, uint8_t *d)
{
	(void)k;
	if (!up) {
		memcpy(d + i0, cur + i0, i1 - i0);
		return;
	}
	for (size_t i = i0; i < i1; i++)
		d[i] = (uint8_t)(cur[i] - up[i]);
}

static void filter_avg(const uint8_t *cur, const uint8_t *up, size_t k, size_t i0, size_t i1, uint8_t *d)
{
	size_t i = i0;
	if (!up) {
		for (; i < k && i < i1; i++)
			d[i] = cur[i];
		for (; i < i1; i++)
			d[i] = (uint8_t)(cur[i] - (cur[i - k] >> 1));
		return;
	}
	for (; i < k && i < i1; i++)
		d[i] = (uint8_t)(cur[i] - (up[i] >> 1));
	for (; i < i1; i++)
		d[i] = (uint8_t)(cur[i] - ((cur[i - k] + up[i]) >> 1));
}

#if IMG_SSE2
/*
 * Paeth's predictor for 16 bytes a, b, c (left, up, up-left), in 8-bit
 * lanes. With p = a + b - c: pa = |p - a| = |b - c| and pb = |p - b| =
 * |a - c|, each the OR of the two saturated differences (one is 0); pc =
 * |p - c| = |(a - c) + (b - c)|, which is pa + pb when the two differences
 * have one sign (or one is 0) and |pa - pb| when they have opposite signs.
 * pa + pb saturates at 255, which changes no comparison (pa, pb <= 255).
 * x <= y is x -sat y == 0. The same choice as paeth() for every one of the
 * 2^24 triples (checked exhaustively when written).
 */
static inline __m128i paeth_pred16(__m128i a, __m128i b, __m128i c)
{
	const __m128i z = _mm_setzero_si128();
	__m128i bc = _mm_subs_epu8(b, c), cb = _mm_subs_epu8(c, b);
	__m128i ac = _mm_subs_epu8(a, c), ca = _mm_subs_epu8(c, a);
	__m128i pa = _mm_or_si128(bc, cb), pb = _mm_or_si128(ac, ca);
	__m128i opposite = _mm_or_si128(_mm_min_epu8(bc, ca), _mm_min_epu8(cb, ac)); /* 0: one sign */
	__m128i same = _mm_cmpeq_epi8(opposite, z);
	__m128i sum = _mm_adds_epu8(pa, pb), diff = _mm_or_si128(_mm_subs_epu8(pa, pb), _mm_subs_epu8(pb, pa));
	__m128i pc = _mm_or_si128(_mm_and_si128(same, sum), _mm_andnot_si128(same, diff));
	__m128i use_a = _mm_cmpeq_epi8(_mm_or_si128(_mm_subs_epu8(pa, pb), _mm_subs_epu8(pa, pc)), z);
	__m128i use_b = _mm_cmpeq_epi8(_mm_subs_epu8(pb, pc), z);
	__m128i bcsel = _mm_or_si128(_mm_and_si128(use_b, b), _mm_andnot_si128(use_b, c));
	return _mm_or_si128(_mm_and_si128(use_a, a), _mm_andnot_si128(use_a, bcsel));
}
#endif

static void filter_paeth(const uint8_t *cur, const uint8_t *up, size_t k, size_t i0, size_t i1, uint8_t *d)
{
	if (!up) { /* b = c = 0: the predictor is a, as Sub */
		filter_sub(cur, up, k, i0, i1, d);
		return;
	}
	size_t i = i0;
	for (; i < k && i < i1; i++) /* a = c = 0: the predictor is b */
		d[i] = (uint8_t)(cur[i] - up[i]);
#if IMG_SSE2
	/* 16 bytes a step (paeth_pred16), then 8 */
	for (; i + 16 <= i1; i += 16) {
		__m128i a = _mm_loadu_si128((const __m128i *)(const void *)(cur + i - k));
		__m128i b = _mm_loadu_si128((const __m128i *)(const void *)(up + i));
		__m128i c = _mm_loadu_si128((const __m128i *)(const void *)(up + i - k));
		__m128i x = _mm_loadu_si128((const __m128i *)(const void *)(cur + i));
		_mm_storeu_si128((__m128i *)(void *)(d + i), _mm_sub_epi8(x, paeth_pred16(a, b, c)));
	}
	for (; i + 8 <= i1; i += 8) {
		__m128i a = _mm_loadl_epi64((const __m128i *)(const void *)(cur + i - k));
		__m128i b = _mm_loadl_epi64((const __m128i *)(const void *)(up + i));
		__m128i c = _mm_loadl_epi64((const __m128i *)(const void *)(up + i - k));
		__m128i x = _mm_loadl_epi64((const __m128i *)(const void *)(cur + i));
		_mm_storel_epi64((__m128i *)(void *)(d + i), _mm_sub_epi8(x, paeth_pred16(a, b, c)));
	}
#endif
	for (; i < i1; i++)
		d[i] = (uint8_t)(cur[i] - paeth(cur[i - k], up[i], up[i - k]));
}

void img_png_filter_bytes(int f, const uint8_t *cur, const uint8_t *up, size_t k, size_t i0, size_t i1, uint8_t *d)
{
	static void (*const filt[5])(const uint8_t *, const uint8_t *, size_t, size_t, size_t, uint8_t *) = {
		filter_none, filter_sub, filter_up, filter_avg, filter_paeth
	};
	filt[f](cur, up, k, i0, i1, d);
}

/* Sum of the bytes of d[0..n) read as signed, in absolute value (in
 * pieces of 65536 bytes, whose sums of at most 128 each fit 32 bits). */
static uint64_t filter_cost(const uint8_t *d, size_t n)
{
	uint64_t sum = 0;
#if IMG_SSE2
	/* |v| of a signed byte v is min(v, -v) read unsigned (-128: 128 both
	 * ways); psadbw sums 8 of them into each 64-bit half */
	__m128i acc = _mm_setzero_si128(), z = _mm_setzero_si128();
	size_t j = 0;
	for (; j + 16 <= n; j += 16) {
		__m128i v = _mm_loadu_si128((const __m128i *)(const void *)(d + j));
		acc = _mm_add_epi64(acc, _mm_sad_epu8(_mm_min_epu8(v, _mm_sub_epi8(z, v)), z));
	}
	uint64_t half[2];
	_mm_storeu_si128((__m128i *)(void *)half, acc);
	sum = half[0] + half[1];
	d += j;
	n -= j;
#endif
	for (size_t at = 0; at < n; at += 65536) {
		size_t m = n - at < 65536 ? n - at : 65536;
		uint32_t part = 0;
		for (size_t i = 0; i < m; i++) {
			int v = (int8_t)d[at + i];
			part += (uint32_t)(v < 0 ? -v : v);
		}
		sum += part;
	}
	return sum;
}

/* Bytes of a row filtered and weighed as one step: a filter whose sum is
 * already past the best one's stops there. */
#define PNG_FILTER_STEP 512u

/*
 * Filters rows [y0, y1) into out (row y at out + (y - y0) * (1 + rb)), each row
 * with the filter of least sum of |signed byte|, the lowest-numbered of
 * those that tie; bpp is the bytes of one pixel (3 for 8-bit RGB, 6 for
 * 16-bit). scratch holds 5 rows of rb bytes. A row's choice and bytes
 * depend on it and the row above only, so any split of the rows gives the
 * same bytes.
 *
 * The same choice for less work: the filter that won the row before is
 * tried first, then the others in order, each in steps of
 * PNG_FILTER_STEP bytes; one stops as soon as its partial sum shows it
 * cannot win (sums only grow): at a sum above the best's, or equal to it
 * when it comes after the best in filter order.
 */
static void png_filter(struct png_rows *r, uint32_t y0, uint32_t y1, int bpp, uint8_t *out, uint8_t *scratch)
{
	static void (*const filt[5])(const uint8_t *, const uint8_t *, size_t, size_t, size_t, uint8_t *) = {
		filter_none, filter_sub, filter_up, filter_avg, filter_paeth
	};
	size_t rb = r->rb, k = (size_t)bpp;
	const uint8_t *up = y0 > 0 ? png_row(r, y0 - 1) : NULL;
	int guess = 0;
	for (uint32_t y = y0; y < y1; y++) {
		const uint8_t *cur = png_row(r, y);
		uint64_t best_sum = UINT64_MAX;
		int best = -1;
		for (int t = 0; t < 5; t++) {
			/* guess, then 0..4 without it */
			int f = t == 0 ? guess : t - 1 < guess ? t - 1 : t;
			uint8_t *d = scratch + (size_t)f * rb;
			uint64_t sum = 0;
			int lost = 0;
			for (size_t i0 = 0; i0 < rb && !lost; i0 += PNG_FILTER_STEP) {
				size_t i1 = rb - i0 < PNG_FILTER_STEP ? rb : i0 + PNG_FILTER_STEP;
				filt[f](cur, up, k, i0, i1, d);
				sum += filter_cost(d + i0, i1 - i0);
				lost = best >= 0 && (sum > best_sum || (sum == best_sum && f > best));
			}
			if (!lost && (best < 0 || sum < best_sum || f < best)) {
				best_sum = sum;
				best = f;
			}
		}
		uint8_t *o = out + (size_t)(y - y0) * (rb + 1);
		o[0] = (uint8_t)best;
		memcpy(o + 1, scratch + (size_t)best * rb, rb);
		guess = best;
		up = cur;
	}
}

/* ---- the encoder's threads ----------------------------------------------------- */

/* Filtered bytes per independent deflate piece: the pieces, and so the
 * bytes of a PNG, are the same whatever the number of threads. Large
 * enough that the window lost at each piece's start costs little (well
 * under 1% of the size), small enough that the pieces of a 1280x960
 * image (3.7 MB) keep two threads busy. */
#define PNG_PIECE (256u * 1024u)
/* Most threads an encode uses. */
#define PNG_MAX_THREADS 8u

static atomic_uint png_threads; /* 0: one per online processor */

void img_set_threads(unsigned n) { atomic_store(&png_threads, n); }

/*
 * One task a piece: filter the rows the piece's bytes lie in (the rows
 * that straddle two pieces are filtered by both, the same way), then
 * deflate the piece and take its Adler-32. No buffer holds the whole
 * filtered image, and each thread keeps its buffers (png_ws) from piece
 * to piece, so the encoder touches little fresh memory (page faults were
 * a tenth of a small render's CPU time).
 */
struct piece_job {
	const struct img_desc *d;
	int depth16, bpp;
	size_t rb, raw_n, n_pieces;
	struct obuf *piece;
	uint32_t *adler;
	atomic_size_t next; /* the next piece to take */
};

/* One thread's buffers, made at its first piece. */
struct png_ws {
	struct deflate_mem dm;
	uint8_t *rows; /* the filtered rows of a piece */
	size_t rows_cap;
	uint8_t *scratch; /* 5 rows of rb bytes: the filters' trials */
	uint8_t *conv[2]; /* png_rows' buffers (float or 16-bit rows) */
};

/* ws ready for rows of `need` bytes; 0 or -1. */
static int png_ws_ready(struct png_ws *ws, const struct piece_job *J, size_t need)
{
	if (!ws->scratch) {
		ws->scratch = malloc(5 * J->rb);
		if (!ws->scratch || deflate_mem_init(&ws->dm) < 0)
			return -1;
		if (J->depth16 || J->d->type != IMG_RGB8) {
			ws->conv[0] = malloc(J->rb);
			ws->conv[1] = malloc(J->rb);
			if (!ws->conv[0] || !ws->conv[1])
				return -1;
		}
	}
	if (ws->rows_cap < need) {
		free(ws->rows);
		ws->rows = malloc(need);
		ws->rows_cap = ws->rows ? need : 0;
	}
	return ws->rows ? 0 : -1;
}

static void piece_task(struct piece_job *J, struct png_ws *ws, size_t t)
{
	size_t row = J->rb + 1, off = t * PNG_PIECE, len = J->raw_n - off < PNG_PIECE ? J->raw_n - off : PNG_PIECE;
	uint32_t y0 = (uint32_t)(off / row), y1 = (uint32_t)((off + len - 1) / row + 1);
	if (png_ws_ready(ws, J, (size_t)(y1 - y0) * row) < 0) {
		J->piece[t].oom = 1;
		return;
	}
	struct png_rows rows = { .d = J->d, .depth16 = J->depth16, .rb = J->rb, .buf = { ws->conv[0], ws->conv[1] } };
	png_filter(&rows, y0, y1, J->bpp, ws->rows, ws->scratch);
	const uint8_t *in = ws->rows + (off - (size_t)y0 * row);
	ob_reserve(&J->piece[t], len / 4 + 1024);
	if (deflate_raw(in, len, &J->piece[t], t + 1 == J->n_pieces, &ws->dm) < 0)
		J->piece[t].oom = 1;
	J->adler[t] = img_adler32(1, in, len);
}

static void *piece_thread(void *arg)
{
	struct piece_job *J = arg;
	struct png_ws ws;
	memset(&ws, 0, sizeof ws);
	for (size_t t; (t = atomic_fetch_add(&J->next, 1)) < J->n_pieces;)
		piece_task(J, &ws, t);
	deflate_mem_free(&ws.dm);
	free(ws.rows);
	free(ws.scratch);
	free(ws.conv[0]);
	free(ws.conv[1]);
	return NULL;
}

/* Every piece of J, on up to as many threads as img_set_threads allows
 * (the calling one included), in any order. */
static void pieces_run(struct piece_job *J)
{
	unsigned n = atomic_load(&png_threads);
	if (n == 0) {
		long c = sysconf(_SC_NPROCESSORS_ONLN);
		n = c > 0 ? (unsigned)c : 1;
	}
	if (n > PNG_MAX_THREADS)
		n = PNG_MAX_THREADS;
	if (n > J->n_pieces)
		n = (unsigned)J->n_pieces;
	pthread_t th[PNG_MAX_THREADS];
	unsigned started = 0;
	for (unsigned k = 1; k < n; k++)
		if (pthread_create(&th[started], NULL, piece_thread, J) == 0)
			started++;
	piece_thread(J);
	for (unsigned k = 0; k < started; k++)
		pthread_join(th[k], NULL);
}

/* The Adler-32 of a then b, from theirs and b's length (a's sums carry
 * into b's: each of b's n bytes adds a's byte sum once more to b's
 * second sum). */
static uint32_t adler_cat(uint32_t a, uint32_t b, size_t n)
{
	const uint64_t M = 65521;
	uint64_t a1 = a & 0xffff, b1 = a >> 16, a2 = b & 0xffff, b2 = b >> 16;
	uint64_t s1 = (a1 + a2 + M - 1) % M;
	uint64_t s2 = (b1 + b2 + (n % M) * ((a1 + M - 1) % M)) % M;
	return (uint32_t)(s2 << 16 | s1);
}

static void png_chunk(struct obuf *o, const char *type, const uint8_t *data, size_t n)
{
	ob_be32(o, (uint32_t)n);
	ob_bytes(o, type, 4);
	if (n)
		ob_bytes(o, data, n);
	uint32_t crc = crc32_update(0, (const uint8_t *)type, 4);
	ob_be32(o, crc32_update(crc, data, n));
}

static void put_be32(uint8_t *p, uint32_t v)
{
	p[0] = (uint8_t)(v >> 24);
	p[1] = (uint8_t)(v >> 16);
	p[2] = (uint8_t)(v >> 8);
	p[3] = (uint8_t)v;
}

/*
 * The chunks between IHDR and IDAT (docs/camera.md, "Output formats"):
 * the values are sRGB-encoded, so sRGB (rendering intent 0, perceptual),
 * with the gAMA (1/2.2 as 45455) and cHRM (Rec. 709 primaries, D65 white,
 * times 100000) that the PNG specification asks to go with it for
 * decoders that know no sRGB; sBIT 8 8 8 when 16-bit samples come from
 * 8-bit values; a tEXt chunk per text item.
 */
static void png_meta_chunks(struct obuf *o, const struct img_desc *d, int depth16)
{
	static const uint32_t chrm[8] = { 31270, 32900, 64000, 33000, 30000, 60000, 15000, 6000 };
	uint8_t b[32];
	for (int i = 0; i < 8; i++)
		put_be32(b + 4 * i, chrm[i]);
	png_chunk(o, "cHRM", b, 32);
	put_be32(b, 45455);
	png_chunk(o, "gAMA", b, 4);
	b[0] = 0;
	png_chunk(o, "sRGB", b, 1);
	if (depth16 && d->type == IMG_RGB8) {
		b[0] = b[1] = b[2] = 8;
		png_chunk(o, "sBIT", b, 3);
	}
	for (size_t i = 0; i < d->n_text; i++) {
		char text[IMG_TEXT_KEY_MAX + 1 + IMG_TEXT_VALUE_MAX + 1];
		size_t kn = strlen(d->text[i].key);
		memcpy(text, d->text[i].key, kn + 1); /* keyword, NUL separator */
		size_t vn = img_text_clean(d->text[i].value, text + kn + 1);
		png_chunk(o, "tEXt", (const uint8_t *)text, kn + 1 + vn);
	}
}

/*
 * Encodes d (validated; format IMG_PNG or IMG_PNG16) as a PNG in memory.
 * plain: no chunk but IHDR, IDAT and IEND (img_png_encode's PNG). 0 with
 * *out malloc'd (the caller frees it), or -1 with errno ENOMEM.
 */
int img_png_emit(const struct img_desc *d, int plain, uint8_t **out, size_t *out_len)
{
	*out = NULL;
	*out_len = 0;
	pthread_once(&tables_once, tables_init);
	uint32_t w = d->w, h = d->h;
	int depth16 = d->format == IMG_PNG16, bpp = depth16 ? 6 : 3;
	size_t rb = (size_t)bpp * w, raw_n = (rb + 1) * h;
	struct obuf zs = { 0 }, png = { 0 }, *piece = NULL;
	uint32_t *adler = NULL;
	size_t n_pieces = (raw_n + PNG_PIECE - 1) / PNG_PIECE;

	/* zlib stream: CMF 0x78 (deflate, 32K window), FLG 0x9C (default level,
	 * (CMF*256 + FLG) % 31 == 0), deflate data, Adler-32 big-endian. The
	 * deflate data is the pieces' streams one after the other. */
	piece = calloc(n_pieces, sizeof *piece);
	adler = malloc(n_pieces * sizeof *adler);
	if (!piece || !adler)
		goto oom;
	struct piece_job J = { .d = d, .depth16 = depth16, .bpp = bpp, .rb = rb, .raw_n = raw_n,
			       .n_pieces = n_pieces, .piece = piece, .adler = adler };
	atomic_init(&J.next, 0);
	pieces_run(&J);
	size_t zn = 0;
	for (size_t t = 0; t < n_pieces; t++) {
		if (piece[t].oom)
			goto oom;
		zn += piece[t].n;
	}
	ob_reserve(&zs, zn + 6);
	uint8_t zh[2] = { 0x78, 0x9C };
	ob_bytes(&zs, zh, 2);
	uint32_t ad = 1;
	for (size_t t = 0; t < n_pieces; t++) {
		ob_append_bits(&zs, &piece[t]);
		size_t len = raw_n - t * PNG_PIECE < PNG_PIECE ? raw_n - t * PNG_PIECE : PNG_PIECE;
		ad = adler_cat(ad, adler[t], len);
		free(piece[t].p);
		piece[t].p = NULL;
	}
	ob_flush_bits(&zs);
	ob_be32(&zs, ad);
	free(piece);
	piece = NULL;
	free(adler);
	adler = NULL;
	if (zs.oom)
		goto oom;

	static const uint8_t sig[8] = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n' };
	ob_reserve(&png, zs.n + zs.n / 65536 * 12 + 1024);
	ob_bytes(&png, sig, 8);
	uint8_t ihdr[13] = { 0 };
	put_be32(ihdr, w);
	put_be32(ihdr + 4, h);
	ihdr[8] = depth16 ? 16 : 8; /* bits per sample */
	ihdr[9] = 2;                /* RGB; deflate, adaptive filters, no interlace: 0 0 0 */
	png_chunk(&png, "IHDR", ihdr, sizeof ihdr);
	if (!plain)
		png_meta_chunks(&png, d, depth16);
	const size_t idat_max = 1u << 20;
	for (size_t off = 0; off < zs.n; off += idat_max)
		png_chunk(&png, "IDAT", zs.p + off, zs.n - off < idat_max ? zs.n - off : idat_max);
	png_chunk(&png, "IEND", NULL, 0);
	free(zs.p);
	zs.p = NULL;
	if (png.oom)
		goto oom;
	*out = png.p;
	*out_len = png.n;
	return 0;
oom:
	if (piece)
		for (size_t t = 0; t < n_pieces; t++)
			free(piece[t].p);
	free(piece);
	free(adler);
	free(zs.p);
	free(png.p);
	errno = ENOMEM;
	return -1;
}

/*
 * Encodes w*h RGB8 pixels (rows top to bottom) as a PNG in memory, with no
 * chunk but IHDR, IDAT and IEND. On success *out is malloc'd (the caller
 * frees it) and 0 is returned; on failure -1 with errno EINVAL (size
 * outside LIM_IMAGE_*) or ENOMEM.
 */
int img_png_encode(const uint8_t *rgb, uint32_t w, uint32_t h, uint8_t **out, size_t *out_len)
{
	*out = NULL;
	*out_len = 0;
	if (!img_size_ok(w, h) || !rgb) {
		errno = EINVAL;
		return -1;
	}
	struct img_desc d = { .w = w, .h = h, .type = IMG_RGB8, .pixels = rgb, .format = IMG_PNG };
	return img_png_emit(&d, 1, out, out_len);
}
