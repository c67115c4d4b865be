/*
 * sha256.c - SHA-256 (FIPS 180-4 section 6.2) and HMAC-SHA256 (RFC 2104).
 */
#include "proto/sha256.h"

#include <stdatomic.h>
#include <string.h>

#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__))
#define SHA256_X86_NI 1
#include <cpuid.h>
#include <immintrin.h>
#else
#define SHA256_X86_NI 0
#endif

/* first 32 bits of the fractional parts of the cube roots of the first 64 primes */
static const uint32_t sha256_k[64] = {
	0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5,
	0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174,
	0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da,
	0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967,
	0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
	0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070,
	0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
	0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2,
};

/* sha256.h: 0 keeps the portable code whatever the CPU (tests compare the two) */
int sha256_use_ni = 1;

static inline uint32_t rotr(uint32_t x, int n)
{
	return (x >> n) | (x << (32 - n));
}

/* Processes one 64-byte block. */
static void sha256_block(uint32_t h[8], const uint8_t *p)
{
	uint32_t w[64];
	for (int i = 0; i < 16; i++)
		w[i] = (uint32_t)p[4 * i] << 24 | (uint32_t)p[4 * i + 1] << 16 | (uint32_t)p[4 * i + 2] << 8 |
		       p[4 * i + 3];
	for (int i = 16; i < 64; i++) {
		uint32_t s0 = rotr(w[i - 15], 7) ^ rotr(w[i - 15], 18) ^ (w[i - 15] >> 3);
		uint32_t s1 = rotr(w[i - 2], 17) ^ rotr(w[i - 2], 19) ^ (w[i - 2] >> 10);
		w[i] = w[i - 16] + s0 + w[i - 7] + s1;
	}
	uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4], f = h[5], g = h[6], hh = h[7];
	for (int i = 0; i < 64; i++) {
		uint32_t t1 = hh + (rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25)) + ((e & f) ^ (~e & g)) + sha256_k[i] + w[i];
		uint32_t t2 = (rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
		hh = g;
		g = f;
		f = e;
		e = d + t1;
		d = c;
		c = b;
		b = a;
		a = t1 + t2;
	}
	h[0] += a;
	h[1] += b;
	h[2] += c;
	h[3] += d;
	h[4] += e;
	h[5] += f;
	h[6] += g;
	h[7] += hh;
}

#if SHA256_X86_NI
/*
 * The same compression with the x86 SHA extensions (SHA-NI), for CPUs that
 * have them (cpuid leaf 7, EBX bit 29; with SSSE3 and SSE4.1, which every
 * such CPU has): a scene of a few MB is hashed by the master and by each
 * worker, and the portable code took 10% of a render of the dragon (227 M
 * instructions for its 3.6 MB encoding).
 *
 * The instructions keep the state as two vectors, ABEF and CDGH (A in the
 * highest lane); sha256rnds2 does two rounds, taking its two words of
 * W + K from the low half of its third operand. The schedule for words
 * 16..63 four at a time: W[t..t+3] = msg2(msg1(W[t-16..t-13], W[t-12..t-9])
 * + W[t-7..t-4], W[t-4..t-1]), where msg1 adds sigma0 and msg2 the sigma1
 * terms (FIPS 180-4 6.2.2 step 1, as sha256_block).
 */
__attribute__((target("sha,sse4.1,ssse3"))) static void sha256_blocks_ni(uint32_t h[8], const uint8_t *p,
									   size_t nblocks)
{
	/* big-endian words: reverse the bytes of each 32-bit lane */
	const __m128i bswap = _mm_set_epi8(12, 13, 14, 15, 8, 9, 10, 11, 4, 5, 6, 7, 0, 1, 2, 3);
	__m128i dcba = _mm_loadu_si128((const __m128i *)(const void *)&h[0]);
	__m128i hgfe = _mm_loadu_si128((const __m128i *)(const void *)&h[4]);
	__m128i cdab = _mm_shuffle_epi32(dcba, 0xB1);
	__m128i efgh = _mm_shuffle_epi32(hgfe, 0x1B);
	__m128i abef = _mm_alignr_epi8(cdab, efgh, 8);
	__m128i cdgh = _mm_blend_epi16(efgh, cdab, 0xF0);
	for (; nblocks; nblocks--, p += SHA256_BLOCK_BYTES) {
		__m128i abef0 = abef, cdgh0 = cdgh, w[4];
		for (int g = 0; g < 16; g++) {
			__m128i x;
			if (g < 4) {
				x = _mm_shuffle_epi8(_mm_loadu_si128((const __m128i *)(const void *)(p + 16 * g)), bswap);
			} else {
				__m128i t = _mm_add_epi32(_mm_sha256msg1_epu32(w[g & 3], w[(g + 1) & 3]),
							  _mm_alignr_epi8(w[(g + 3) & 3], w[(g + 2) & 3], 4));
				x = _mm_sha256msg2_epu32(t, w[(g + 3) & 3]);
			}
			w[g & 3] = x;
			__m128i wk = _mm_add_epi32(x, _mm_loadu_si128((const __m128i *)(const void *)&sha256_k[4 * g]));
			cdgh = _mm_sha256rnds2_epu32(cdgh, abef, wk);
			abef = _mm_sha256rnds2_epu32(abef, cdgh, _mm_shuffle_epi32(wk, 0x0E));
		}
		abef = _mm_add_epi32(abef, abef0);
		cdgh = _mm_add_epi32(cdgh, cdgh0);
	}
	__m128i feba = _mm_shuffle_epi32(abef, 0x1B);
	__m128i dchg = _mm_shuffle_epi32(cdgh, 0xB1);
	_mm_storeu_si128((__m128i *)(void *)&h[0], _mm_blend_epi16(feba, dchg, 0xF0));
	_mm_storeu_si128((__m128i *)(void *)&h[4], _mm_alignr_epi8(dchg, feba, 8));
}

/* 1: the CPU has SHA-NI (and the SSSE3 and SSE4.1 it comes with), 0: not. */
static int sha256_have_ni(void)
{
	static atomic_int have = -1; /* a race only computes the same answer twice */
	if (atomic_load_explicit(&have, memory_order_relaxed) < 0) {
		unsigned a, b, c, d;
		int ni = 0;
		if (__get_cpuid_max(0, NULL) >= 7 && __get_cpuid(1, &a, &b, &c, &d) && (c & bit_SSSE3) &&
		    (c & bit_SSE4_1)) {
			__cpuid_count(7, 0, a, b, c, d);
			ni = (b >> 29) & 1;
		}
		atomic_store_explicit(&have, ni, memory_order_relaxed);
	}
	return atomic_load_explicit(&have, memory_order_relaxed);
}
#endif

/* Processes nblocks 64-byte blocks. */
static void sha256_blocks(uint32_t h[8], const uint8_t *p, size_t nblocks)
{
#if SHA256_X86_NI
	if (sha256_use_ni && sha256_have_ni()) {
		sha256_blocks_ni(h, p, nblocks);
		return;
	}
#endif
	for (; nblocks; nblocks--, p += SHA256_BLOCK_BYTES)
		sha256_block(h, p);
}

void sha256_init(struct sha256 *c)
{
	static const uint32_t iv[8] = { 0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
					0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19 };
	memcpy(c->h, iv, sizeof iv);
	c->len = 0;
	c->n = 0;
}

void sha256_update(struct sha256 *c, const void *data, size_t n)
{
	const uint8_t *p = data;
	c->len += n;
	if (c->n) {
		size_t k = SHA256_BLOCK_BYTES - c->n;
		if (k > n)
			k = n;
		memcpy(c->buf + c->n, p, k);
		c->n += k;
		p += k;
		n -= k;
		if (c->n < SHA256_BLOCK_BYTES)
			return;
		sha256_blocks(c->h, c->buf, 1);
		c->n = 0;
	}
	size_t nb = n / SHA256_BLOCK_BYTES;
	sha256_blocks(c->h, p, nb);
	p += nb * SHA256_BLOCK_BYTES;
	n -= nb * SHA256_BLOCK_BYTES;
	memcpy(c->buf, p, n);
	c->n = n;
}

/* Wipes memory the compiler may not optimise away (a secret may live there). */
static void sha256_wipe(void *p, size_t n)
{
	volatile uint8_t *v = p;
	while (n--)
		*v++ = 0;
}

void sha256_final(struct sha256 *c, uint8_t out[SHA256_DIGEST_BYTES])
{
	uint64_t bits = c->len * 8;
	/* padding: 0x80, zeros to 56 mod 64, the length in bits big-endian */
	c->buf[c->n++] = 0x80;
	if (c->n > 56) {
		memset(c->buf + c->n, 0, SHA256_BLOCK_BYTES - c->n);
		sha256_blocks(c->h, c->buf, 1);
		c->n = 0;
	}
	memset(c->buf + c->n, 0, 56 - c->n);
	for (int i = 0; i < 8; i++)
		c->buf[56 + i] = (uint8_t)(bits >> (56 - 8 * i));
	sha256_blocks(c->h, c->buf, 1);
	for (int i = 0; i < 8; i++) {
		out[4 * i] = (uint8_t)(c->h[i] >> 24);
		out[4 * i + 1] = (uint8_t)(c->h[i] >> 16);
		out[4 * i + 2] = (uint8_t)(c->h[i] >> 8);
		out[4 * i + 3] = (uint8_t)c->h[i];
	}
	sha256_wipe(c, sizeof *c);
}

void sha256(const void *data, size_t n, uint8_t out[SHA256_DIGEST_BYTES])
{
	struct sha256 c;
	sha256_init(&c);
	sha256_update(&c, data, n);
	sha256_final(&c, out);
}

/*
 * HMAC(K, m) = H((K' ^ opad) | H((K' ^ ipad) | m)), K' the key zero-padded
 * to a block (hashed first when longer than a block).
 */
void sha256_hmac_init(struct sha256_hmac *m, const void *key, size_t key_len)
{
	uint8_t k[SHA256_BLOCK_BYTES], pad[SHA256_BLOCK_BYTES];
	memset(k, 0, sizeof k);
	if (key_len > SHA256_BLOCK_BYTES)
		sha256(key, key_len, k);
	else if (key_len)
		memcpy(k, key, key_len);
	for (int i = 0; i < SHA256_BLOCK_BYTES; i++)
		pad[i] = k[i] ^ 0x36;
	sha256_init(&m->inner);
	sha256_update(&m->inner, pad, sizeof pad);
	for (int i = 0; i < SHA256_BLOCK_BYTES; i++)
		pad[i] = k[i] ^ 0x5c;
	sha256_init(&m->outer);
	sha256_update(&m->outer, pad, sizeof pad);
	sha256_wipe(k, sizeof k);
	sha256_wipe(pad, sizeof pad);
}

void sha256_hmac_update(struct sha256_hmac *m, const void *data, size_t n)
{
	sha256_update(&m->inner, data, n);
}

void sha256_hmac_final(struct sha256_hmac *m, uint8_t out[SHA256_DIGEST_BYTES])
{
	uint8_t ih[SHA256_DIGEST_BYTES];
	sha256_final(&m->inner, ih);
	sha256_update(&m->outer, ih, sizeof ih);
	sha256_final(&m->outer, out);
	sha256_wipe(ih, sizeof ih);
}

void sha256_hmac(const void *key, size_t key_len, const void *data, size_t n,
		 uint8_t out[SHA256_DIGEST_BYTES])
{
	struct sha256_hmac m;
	sha256_hmac_init(&m, key, key_len);
	sha256_hmac_update(&m, data, n);
	sha256_hmac_final(&m, out);
}

int sha256_ct_equal(const void *a, const void *b, size_t n)
{
	const volatile uint8_t *x = a, *y = b;
	uint8_t d = 0;
	for (size_t i = 0; i < n; i++)
		d |= x[i] ^ y[i];
	/* 1 when d == 0, without a data-dependent branch */
	return (int)(1 & (((uint32_t)d - 1) >> 8));
}

int sha256_accelerated(void)
{
#if SHA256_X86_NI
	return sha256_use_ni && sha256_have_ni();
#else
	return 0;
#endif
}
