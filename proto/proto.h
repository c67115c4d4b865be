/*
 * proto.h - portray's wire protocol: frames, messages and a buffered,
 * non-blocking connection (docs/protocol.md is the reference).
 *
 * Frame = 12-byte header + payload, all numbers big-endian:
 *   u32 magic "PRAY" | u16 protocol version | u16 type | u32 payload length
 * The header layout and the HELLO and ERROR payloads never change between
 * protocol versions, so a peer of another version is always told why it is
 * refused. Every other frame must carry the connection's version.
 *
 * Untrusted bytes: a declared length is checked against LIM_FRAME_PAYLOAD
 * before anything is read, the input buffer grows only as bytes arrive, and
 * every decoded field is validated (exact payload sizes, string bounds, tile
 * sizes). A bad frame yields an error code and text for the ERROR reply.
 */
#ifndef PORTRAY_PROTO_H
#define PORTRAY_PROTO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "common/crc32.h" /* tile checksums: crc32_update */
#include "proto/buf.h"

#define PROTO_MAGIC 0x50524159u /* "PRAY" */
/* 2: heartbeat interval agreed at the handshake (no clamp), the master's
 * OFFER pipelined behind its HELLO or AUTH, TILE and CANCEL accepted while
 * the worker builds
 * 3: TILE and TILE_RESULT name the pixel type (RGB8, or RGBF32 for the
 * float outputs) after the rectangle */
#define PROTO_VERSION 3u
#define PROTO_HEADER_BYTES 12
#define PROTO_DEFAULT_PORT 7411
#define PROTO_NONCE_BYTES 32
#define PROTO_HASH_BYTES 32 /* SHA-256 */
#define PROTO_MAC_BYTES 32  /* HMAC-SHA256 */

/* ---- limits (each with its reason; docs/protocol.md lists them) ---- */
/* one frame's payload: a 1024x1024 tile result of floats (12 MiB) plus its
 * header fits */
#define LIM_FRAME_PAYLOAD (13u * 1024 * 1024)
/* scene bytes per SCENE_DATA frame: small enough to interleave heartbeats */
#define PROTO_CHUNK_BYTES (256u * 1024)
/* pixels in one tile on the wire: keeps a TILE_RESULT under LIM_FRAME_PAYLOAD */
#define LIM_TILE_PIXELS (1024u * 1024)
/* texts in ERROR messages and build ids: short by design */
#define LIM_ERROR_TEXT 256
#define LIM_BUILD_ID 64
/* tiles a master may have queued on one connection: bounds a worker's memory */
#define LIM_TILES_QUEUED 1024
/* a shared secret file */
#define LIM_SECRET_BYTES 4096
/* a frame before the handshake is done: HELLO (112 B), AUTH (32 B) and ERROR
 * (262 B) fit; an unauthenticated peer never makes us buffer more than this */
#define LIM_HANDSHAKE_PAYLOAD 1024u
/* the longest frame a master sends: a full SCENE_DATA (u64 offset + chunk) */
#define PROTO_MASTER_FRAME_MAX (8u + PROTO_CHUNK_BYTES)
/*
 * Heartbeats. The master's HELLO names the interval at which both sides send
 * them: a quarter of its --heartbeat-timeout, so any timeout works with
 * tiles and builds of any length. The master drops a worker silent for the
 * timeout (4 intervals); a worker drops a master silent for
 * proto_hb_deadline(interval), more patient since losing a master ends its
 * job while keeping one costs nothing. A HELLO outside these bounds is refused.
 */
#define PROTO_HB_MIN_MS 50u
#define PROTO_HB_MAX_MS (6u * 3600 * 1000)
static inline double proto_hb_deadline(double interval_s)
{
	double d = 6 * interval_s + 5;
	return d < 30 ? 30 : d;
}
/* bytes a connection may have waiting to be sent before the sender pauses */
#define PROTO_OUT_HIGH_WATER (4u * 1024 * 1024)

enum proto_type {
	MSG_HELLO = 1,
	MSG_AUTH = 2,
	MSG_SCENE_OFFER = 3,
	MSG_SCENE_HAVE = 4,
	MSG_SCENE_NEED = 5,
	MSG_SCENE_DATA = 6,
	MSG_SCENE_READY = 7,
	MSG_TILE = 8,
	MSG_TILE_RESULT = 9,
	MSG_HEARTBEAT = 10,
	MSG_CANCEL = 11,
	MSG_ERROR = 12,
	MSG_BYE = 13,
	MSG_TYPE_MAX = 13
};

enum proto_err {
	PERR_PROTOCOL = 1, /* malformed frame or message, or one not allowed now */
	PERR_VERSION = 2,  /* protocol version mismatch */
	PERR_AUTH = 3,     /* secret missing or wrong */
	PERR_BUILD = 4,    /* core build differs: pixels could differ */
	PERR_SCENE = 5,    /* scene bytes rejected (hash, decoding, renderer) */
	PERR_LIMIT = 6,    /* a limit was exceeded (size, queue, cache) */
	PERR_TIMEOUT = 7,  /* peer too slow */
	PERR_INTERNAL = 8, /* out of memory or similar on the sender's side */
	PERR_SHUTDOWN = 9  /* the sender is shutting down */
};

enum proto_role { ROLE_MASTER = 1, ROLE_WORKER = 2 };

struct proto_hello {
	uint32_t version;       /* protocol version the sender speaks */
	uint8_t role;           /* enum proto_role */
	uint8_t secret;         /* 1: the sender has a shared secret configured */
	uint16_t threads;       /* worker: tracing threads; master: 0 */
	uint32_t heartbeat_ms;  /* master: the interval it wants; worker: 0 */
	uint8_t nonce[PROTO_NONCE_BYTES];
	char build[LIM_BUILD_ID + 1]; /* core build id */
};

struct proto_tile {
	uint32_t id, x, y, w, h;
	uint8_t px; /* pixel type: enum render_pixel (common/render.h), 0 RGB8 or 1 RGBF32 */
};
/* Bytes of t's pixels: w * h * 3 (RGB8) or w * h * 12 (RGBF32). */
size_t proto_tile_bytes(const struct proto_tile *t);

/* One decoded message. Pointers point into the connection's input buffer
 * and stay valid until the next proto_conn_next call. */
struct proto_msg {
	enum proto_type type;
	uint16_t frame_version;
	union {
		struct proto_hello hello;
		uint8_t mac[PROTO_MAC_BYTES];
		struct {
			uint8_t hash[PROTO_HASH_BYTES];
			uint64_t size;
			uint32_t width, height;
		} offer;
		uint8_t hash[PROTO_HASH_BYTES]; /* HAVE, NEED */
		struct {
			uint64_t offset;
			const uint8_t *bytes;
			uint32_t n;
		} data;
		struct {
			uint8_t hash[PROTO_HASH_BYTES];
			uint8_t cached;
			uint32_t build_ms;
		} ready;
		struct proto_tile tile;
		struct {
			struct proto_tile tile;
			uint32_t crc;
			uint32_t trace_us;     /* the worker's time tracing it (0: not measured) */
			const uint8_t *pixels; /* proto_tile_bytes(&tile) bytes */
		} result;
		struct {
			uint32_t done, queued;
		} heartbeat;
		uint32_t cancel_id; /* PROTO_CANCEL_ALL: every queued tile */
		struct {
			uint16_t code;
			char text[LIM_ERROR_TEXT + 1];
		} error;
	} u;
};
#define PROTO_CANCEL_ALL UINT32_MAX

/* ---- pure functions (no I/O): also the fuzz targets' entry points ---- */

/*
 * Parses a frame header from len bytes. Returns 0 and fills type, version
 * and payload length; or -1 with code and why set when the header is invalid
 * (bad magic, length over LIM_FRAME_PAYLOAD, unknown type).
 */
int proto_header_parse(const uint8_t *p, size_t len, uint16_t *type, uint16_t *version, uint32_t *plen,
		       int *code, const char **why);
/*
 * Decodes one payload of the given type into m (pointers into p). Returns 0,
 * or -1 with why set (static text). Checks exact sizes and field ranges.
 */
int proto_msg_decode(uint16_t type, const uint8_t *p, uint32_t len, struct proto_msg *m, const char **why);

/*
 * The build id HELLO carries: "proto-N/scene-N/pixels-N/probe-HHHHHHHHHHHHHHHH",
 * what decides compatibility (protocol, scene encoding, pixel revision) and
 * the 64-bit fingerprint of the pixel probe (common/probe.h), rendered at the
 * first call (a few milliseconds; thread-safe). A peer must match both:
 * proto_hello_check says which one differs.
 */
const char *proto_build_id(void);
/*
 * The one HELLO check, both sides: m is the peer's HELLO; `want` the role the
 * peer must have; have_secret whether this side holds a shared secret;
 * my_version the version this side speaks (PROTO_VERSION but for a test
 * hook). Checks the frame's and the payload's versions, the role, the build
 * id, that both sides agree on having a secret and (from a master) the
 * heartbeat interval. Returns 0, or a PERR_ code with a message in why that
 * names both sides' views, for the ERROR reply and the log.
 */
int proto_hello_check(const struct proto_msg *m, enum proto_role want, bool have_secret, uint32_t my_version,
		      char *why, size_t whylen);
/* Name of a message type and of an error code, for logs. */
const char *proto_type_name(int type);
const char *proto_err_name(int code);
/* Fills n bytes from the OS's random source (getrandom, else /dev/urandom); 0 or -1. */
int proto_random(uint8_t *p, size_t n);

/* ---- a buffered non-blocking connection ---- */

struct proto_conn;

/* Wraps a connected non-blocking socket (the conn owns and closes it). NULL on OOM. */
struct proto_conn *proto_conn_new(int fd);
void proto_conn_free(struct proto_conn *c);
int proto_conn_fd(const struct proto_conn *c);

/*
 * Reads what the socket has (non-blocking; EINTR retried). Returns 1 if bytes
 * arrived, 0 if none were ready, -1 on EOF or error (errno-style text in why).
 */
int proto_conn_read(struct proto_conn *c, const char **why);
/*
 * Takes the next complete frame from the input buffer and decodes it.
 * Returns 1 (m filled), 0 (need more bytes) or -1 (protocol error: *code and
 * *why say what to put in the ERROR reply; the connection should close).
 * Frames other than HELLO and ERROR must carry PROTO_VERSION.
 */
int proto_conn_next(struct proto_conn *c, struct proto_msg *m, int *code, const char **why);
/* Bytes in the input buffer not yet consumed (for tests). */
size_t proto_conn_pending(const struct proto_conn *c);

/* Writes queued output; returns 0 (maybe partially sent) or -1 (peer gone). */
int proto_conn_flush(struct proto_conn *c);
/* Bytes queued and not yet written. */
size_t proto_conn_outq(const struct proto_conn *c);
/* Total bytes written and read so far. */
uint64_t proto_conn_bytes_out(const struct proto_conn *c);
uint64_t proto_conn_bytes_in(const struct proto_conn *c);

/* Queue one message (not sent until proto_conn_flush). 0, or -1 when out of memory. */
int proto_send_hello(struct proto_conn *c, const struct proto_hello *h);
int proto_send_auth(struct proto_conn *c, const uint8_t mac[PROTO_MAC_BYTES]);
int proto_send_offer(struct proto_conn *c, const uint8_t hash[PROTO_HASH_BYTES], uint64_t size, uint32_t w,
		     uint32_t h);
int proto_send_hash(struct proto_conn *c, enum proto_type type, const uint8_t hash[PROTO_HASH_BYTES]);
int proto_send_data(struct proto_conn *c, uint64_t offset, const uint8_t *p, uint32_t n);
int proto_send_ready(struct proto_conn *c, const uint8_t hash[PROTO_HASH_BYTES], bool cached, uint32_t build_ms);
int proto_send_tile(struct proto_conn *c, const struct proto_tile *t);
int proto_send_result(struct proto_conn *c, const struct proto_tile *t, const uint8_t *pixels, uint32_t crc);
/* With the time the tile took to trace, microseconds (the master sizes its
 * window of tiles in flight from it); proto_send_result sends 0, unknown. */
int proto_send_result_timed(struct proto_conn *c, const struct proto_tile *t, const uint8_t *pixels, uint32_t crc,
			    uint32_t trace_us);
int proto_send_heartbeat(struct proto_conn *c, uint32_t done, uint32_t queued);
int proto_send_cancel(struct proto_conn *c, uint32_t id);
int proto_send_error(struct proto_conn *c, int code, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
int proto_send_bye(struct proto_conn *c);
/*
 * Largest payload accepted from now on (at most LIM_FRAME_PAYLOAD; the
 * default). A longer declared frame is an ERROR(limit) before any of its
 * bytes are buffered, and the input buffer never grows past header + limit.
 */
void proto_conn_set_limit(struct proto_conn *c, uint32_t max_payload);
/* Test hook: the version written into frame headers by this connection. */
void proto_conn_set_version(struct proto_conn *c, uint16_t version);

/*
 * Authentication proof: HMAC-SHA256(secret, "portray-auth-v1" | role |
 * master nonce | worker nonce). role is the prover's role, so a proof can
 * not be reflected back. Returns 0, or -1 if the crypto module is missing.
 */
void proto_auth_mac(const uint8_t *secret, size_t secret_len, enum proto_role role,
		    const uint8_t nonce_master[PROTO_NONCE_BYTES], const uint8_t nonce_worker[PROTO_NONCE_BYTES],
		    uint8_t out[PROTO_MAC_BYTES]);
/* Scene content hash: SHA-256 of the encoded scene. */
void proto_scene_hash(const uint8_t *p, size_t n, uint8_t out[PROTO_HASH_BYTES]);
/* Constant-time equality of n bytes. */
bool proto_mac_equal(const uint8_t *a, const uint8_t *b, size_t n);
/*
 * Reads a shared secret file (a regular file of at most LIM_SECRET_BYTES,
 * trailing newlines dropped, not empty). Returns 0 with *out (caller frees)
 * and *len, or -1 with a message in err. warn gets a warning ("" if none)
 * when the file is readable by group or others.
 */
int proto_read_secret(const char *path, uint8_t **out, size_t *len, char *err, size_t errlen, char *warn,
		      size_t warnlen);

#endif
