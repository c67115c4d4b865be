/*
 * test_sha256.c - SHA-256 against the FIPS 180-2 / NIST examples, HMAC-SHA256
 * against all seven RFC 4231 test cases (case 5 truncated to 128 bits), the
 * streaming interface against the one-shot one at every split, and the
 * constant-time comparison.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "proto/sha256.h"
#include "tests/unit/check.h"

static void hex(const uint8_t *d, size_t n, char *out)
{
	for (size_t i = 0; i < n; i++)
		sprintf(out + 2 * i, "%02x", d[i]);
}

static int digest_is(const uint8_t *d, size_t n, const char *want)
{
	char h[2 * SHA256_DIGEST_BYTES + 1];
	hex(d, n, h);
	if (strcmp(h, want) != 0) {
		fprintf(stderr, "  got  %s\n  want %s\n", h, want);
		return 0;
	}
	return 1;
}

static void test_sha256_vectors(void)
{
	uint8_t d[32];
	sha256("abc", 3, d);
	CHECK(digest_is(d, 32, "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"));
	sha256("", 0, d);
	CHECK(digest_is(d, 32, "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"));
	/* the 448-bit message: padding spills into a second block */
	const char *m448 = "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";
	sha256(m448, strlen(m448), d);
	CHECK(digest_is(d, 32, "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1"));
	/* the 896-bit message */
	const char *m896 = "abcdefghbcdefghicdefghijdefghijkefghijklfghijklmghijklmnhijklmnoijklmnopjklmnopq"
			   "klmnopqrlmnopqrsmnopqrstnopqrstu";
	sha256(m896, strlen(m896), d);
	CHECK(digest_is(d, 32, "cf5b16a778af8380036ce59e7b0492370b249b11e8f07a51afac45037afee9d1"));
	/* one million 'a', fed in uneven pieces */
	struct sha256 c;
	char a[1024]; /* pieces are at most 1009 bytes */
	memset(a, 'a', sizeof a);
	sha256_init(&c);
	size_t left = 1000000, k = 1;
	while (left) {
		size_t n = k < left ? k : left;
		sha256_update(&c, a, n);
		left -= n;
		k = k % 997 + 13;
	}
	sha256_final(&c, d);
	CHECK(digest_is(d, 32, "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0"));
}

/* Every split of a 200-byte message into two updates gives the one-shot digest;
 * lengths 0..130 cover every padding case (55, 56, 63, 64, 119, 120 ...). */
static void test_streaming(void)
{
	uint8_t msg[200], want[32], got[32];
	for (int i = 0; i < 200; i++)
		msg[i] = (uint8_t)(i * 37 + 11);
	for (size_t len = 0; len <= 130; len++) {
		sha256(msg, len, want);
		int bad = 0;
		for (size_t split = 0; split <= len; split++) {
			struct sha256 c;
			sha256_init(&c);
			sha256_update(&c, msg, split);
			sha256_update(&c, msg + split, len - split);
			sha256_final(&c, got);
			bad += memcmp(got, want, 32) != 0;
		}
		CHECK(bad == 0);
	}
	/* lengths matter: 55 and 56 bytes differ (a broken padding would collide) */
	uint8_t d55[32], d56[32];
	sha256(msg, 55, d55);
	sha256(msg, 56, d56);
	CHECK(memcmp(d55, d56, 32) != 0);
}

static void test_hmac_rfc4231(void)
{
	uint8_t key[131], data[152], mac[32];
	struct {
		size_t klen;
		uint8_t kbyte; /* 0: key bytes 0x01..0x19 (case 4) */
		const char *text;
		size_t dlen;
		uint8_t dbyte;
		const char *want;
	} cases[] = {
		{ 20, 0x0b, "Hi There", 0, 0, "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7" },
		{ 4, 0, "what do ya want for nothing?", 0, 0,
		  "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843" },
		{ 20, 0xaa, NULL, 50, 0xdd, "773ea91e36800e46854db8ebd09181a72959098b3ef8c122d9635514ced565fe" },
		{ 25, 0, NULL, 50, 0xcd, "82558a389a443c0ea4cc819899f2083a85f0faa3e578f8077a2e3ff46729665b" },
		{ 20, 0x0c, "Test With Truncation", 0, 0, "a3b6167473100ee06e0c796c2955552b" },
		{ 131, 0xaa, "Test Using Larger Than Block-Size Key - Hash Key First", 0, 0,
		  "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54" },
		{ 131, 0xaa,
		  "This is a test using a larger than block-size key and a larger than block-size data. "
		  "The key needs to be hashed before being used by the HMAC algorithm.",
		  0, 0, "9b09ffa71b942fcb27635fbcd5b0e944bfdc63644f0713938a7f51535c3a35e2" },
	};
	for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
		size_t klen = cases[i].klen, dlen;
		if (i == 1)
			memcpy(key, "Jefe", 4);
		else if (i == 3)
			for (size_t j = 0; j < 25; j++)
				key[j] = (uint8_t)(j + 1);
		else
			memset(key, cases[i].kbyte, klen);
		if (cases[i].text) {
			dlen = strlen(cases[i].text);
			memcpy(data, cases[i].text, dlen);
		} else {
			dlen = cases[i].dlen;
			memset(data, cases[i].dbyte, dlen);
		}
		sha256_hmac(key, klen, data, dlen, mac);
		size_t n = strlen(cases[i].want) / 2; /* case 5 compares the first 16 bytes */
		CHECK(digest_is(mac, n, cases[i].want));
		if (!digest_is(mac, n, cases[i].want))
			fprintf(stderr, "  RFC 4231 test case %zu\n", i + 1);
		/* streaming in two pieces gives the same MAC */
		struct sha256_hmac m;
		uint8_t mac2[32];
		sha256_hmac_init(&m, key, klen);
		sha256_hmac_update(&m, data, dlen / 3);
		sha256_hmac_update(&m, data + dlen / 3, dlen - dlen / 3);
		sha256_hmac_final(&m, mac2);
		CHECK(memcmp(mac, mac2, 32) == 0);
	}
	/* a 64-byte key is used as is, a 65-byte key is hashed: they differ */
	uint8_t m64[32], m65[32];
	memset(key, 0x42, 65);
	sha256_hmac(key, 64, "x", 1, m64);
	sha256_hmac(key, 65, "x", 1, m65);
	CHECK(memcmp(m64, m65, 32) != 0);
}

static void test_ct_equal(void)
{
	uint8_t a[32], b[32];
	for (int i = 0; i < 32; i++)
		a[i] = b[i] = (uint8_t)(i * 7);
	CHECK(sha256_ct_equal(a, b, 32) == 1);
	CHECK(sha256_ct_equal(a, b, 0) == 1);
	for (int i = 0; i < 32; i++) {
		for (int bit = 0; bit < 8; bit++) {
			b[i] ^= (uint8_t)(1u << bit);
			CHECK(sha256_ct_equal(a, b, 32) == 0);
			b[i] ^= (uint8_t)(1u << bit);
		}
	}
	b[31] = 0xff;
	CHECK(sha256_ct_equal(a, b, 31) == 1); /* only n bytes count */
	CHECK(sha256_ct_equal(a, b, 32) == 0);
}

/* The CPU's SHA instructions (where this machine has them) and the
 * portable code give the same digests, on every length around the block
 * boundaries and on long inputs fed in odd pieces; and every test above
 * passes with the portable code alone. */
static void test_accelerated(void)
{
	static uint8_t msg[70000];
	uint32_t x = 12345;
	for (size_t i = 0; i < sizeof msg; i++) {
		x = x * 1103515245u + 12345u;
		msg[i] = (uint8_t)(x >> 24);
	}
	printf("sha256: %s\n", sha256_accelerated() ? "CPU SHA instructions compared with the portable code"
						      : "no CPU SHA instructions here: portable code only");
	for (size_t n = 0; n < 300; n++) {
		uint8_t a[32], b[32];
		sha256_use_ni = 1;
		sha256(msg, n, a);
		sha256_use_ni = 0;
		sha256(msg, n, b);
		CHECK(memcmp(a, b, 32) == 0);
	}
	uint8_t a[32], b[32];
	for (int ni = 0; ni < 2; ni++) {
		sha256_use_ni = ni;
		struct sha256 c;
		sha256_init(&c);
		for (size_t at = 0, step = 1; at < sizeof msg; at += step, step = step * 7 % 1999 + 1)
			sha256_update(&c, msg + at, at + step <= sizeof msg ? step : sizeof msg - at);
		sha256_final(&c, ni ? a : b);
	}
	CHECK(memcmp(a, b, 32) == 0);
	sha256_use_ni = 0;
	test_sha256_vectors();
	test_streaming();
	test_hmac_rfc4231();
	sha256_use_ni = 1;
}

int main(void)
{
	test_sha256_vectors();
	test_streaming();
	test_hmac_rfc4231();
	test_ct_equal();
	test_accelerated();
	TEST_MAIN_END();
}
