/*
 * auth.c - the protocol's uses of SHA-256 (proto/sha256.h): the scene
 * content hash, the handshake's proofs, constant-time comparison.
 */
#include <string.h>

#include "proto/proto.h"
#include "proto/sha256.h"

/* domain separation: a proof for this protocol and nothing else */
#define AUTH_LABEL "portray-auth-v1"

void proto_auth_mac(const uint8_t *secret, size_t secret_len, enum proto_role role,
		    const uint8_t nonce_master[PROTO_NONCE_BYTES], const uint8_t nonce_worker[PROTO_NONCE_BYTES],
		    uint8_t out[PROTO_MAC_BYTES])
{
	uint8_t msg[sizeof AUTH_LABEL - 1 + 1 + 2 * PROTO_NONCE_BYTES];
	size_t n = 0;
	memcpy(msg, AUTH_LABEL, sizeof AUTH_LABEL - 1);
	n += sizeof AUTH_LABEL - 1;
	msg[n++] = (uint8_t)role;
	memcpy(msg + n, nonce_master, PROTO_NONCE_BYTES);
	n += PROTO_NONCE_BYTES;
	memcpy(msg + n, nonce_worker, PROTO_NONCE_BYTES);
	n += PROTO_NONCE_BYTES;
	sha256_hmac(secret, secret_len, msg, n, out);
}

void proto_scene_hash(const uint8_t *p, size_t n, uint8_t out[PROTO_HASH_BYTES]) { sha256(p, n, out); }

bool proto_mac_equal(const uint8_t *a, const uint8_t *b, size_t n) { return sha256_ct_equal(a, b, n) == 1; }
