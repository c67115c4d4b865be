/*
 * sha256.h - SHA-256 (FIPS 180-4) and HMAC-SHA256 (RFC 2104), streaming and
 * one-shot, plus a constant-time comparison for MACs. Written in-tree: the
 * farm needs them for scene hashes and the AUTH challenge-response.
 */
#ifndef PORTRAY_SHA256_H
#define PORTRAY_SHA256_H

#include <stddef.h>
#include <stdint.h>

#define SHA256_DIGEST_BYTES 32
#define SHA256_BLOCK_BYTES 64

/* Streaming state: init, any number of updates, final. Plain value, no heap. */
struct sha256 {
	uint32_t h[8];
	uint64_t len;                    /* bytes hashed so far */
	uint8_t buf[SHA256_BLOCK_BYTES]; /* partial block */
	size_t n;                        /* bytes in buf */
};

/* 1 (the default): use the CPU's SHA instructions where it has them (x86
 * SHA-NI); 0: the portable code only. The digest is the same either way;
 * tests set it to compare the two. */
extern int sha256_use_ni;
/* 1 when this build and CPU hash with SHA instructions (sha256_use_ni set). */
int sha256_accelerated(void);

void sha256_init(struct sha256 *c);
void sha256_update(struct sha256 *c, const void *data, size_t n);
/* Writes the digest and wipes the state (init again to reuse it). */
void sha256_final(struct sha256 *c, uint8_t out[SHA256_DIGEST_BYTES]);
/* One-shot: out = SHA-256(data). */
void sha256(const void *data, size_t n, uint8_t out[SHA256_DIGEST_BYTES]);

/* HMAC-SHA256; keys longer than a block are hashed first (RFC 2104). */
struct sha256_hmac {
	struct sha256 inner, outer;
};

void sha256_hmac_init(struct sha256_hmac *m, const void *key, size_t key_len);
void sha256_hmac_update(struct sha256_hmac *m, const void *data, size_t n);
/* Writes the MAC and wipes the state. */
void sha256_hmac_final(struct sha256_hmac *m, uint8_t out[SHA256_DIGEST_BYTES]);
void sha256_hmac(const void *key, size_t key_len, const void *data, size_t n,
		 uint8_t out[SHA256_DIGEST_BYTES]);

/*
 * Compares a[0..n) with b[0..n) in time that depends on n only, never on
 * where they differ (for MACs received off the wire). Returns 1 when equal,
 * 0 otherwise.
 */
int sha256_ct_equal(const void *a, const void *b, size_t n);

#endif
