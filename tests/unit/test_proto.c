/*
 * test_proto.c - frames and messages over a socketpair: every message round
 * trips; short reads (1 byte at a time), EOF mid-frame, oversized and
 * malformed frames, other protocol versions; CRC-32, auth proofs, the scene
 * hash; address parsing and secret files.
 */
#include <fcntl.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/probe.h"
#include "common/render.h"
#include "check.h"
#include "common/render.h"
#include "proto/net.h"
#include "proto/proto.h"
#include "proto/serial.h"
#include "proto/sha256.h"

static struct proto_conn *A, *B;
static int sv[2];

static void pair(void)
{
	CHECK(socketpair(AF_UNIX, SOCK_STREAM, 0, sv) == 0);
	for (int i = 0; i < 2; i++)
		fcntl(sv[i], F_SETFL, fcntl(sv[i], F_GETFL) | O_NONBLOCK);
	A = proto_conn_new(sv[0]);
	B = proto_conn_new(sv[1]);
}

static void unpair(void)
{
	proto_conn_free(A);
	proto_conn_free(B);
}

/* Flushes A and reads one message on B; returns proto_conn_next's result. */
static int xfer(struct proto_msg *m, int *code, const char **why)
{
	CHECK(proto_conn_flush(A) == 0);
	const char *w;
	while (proto_conn_read(B, &w) > 0)
		;
	return proto_conn_next(B, m, code, why);
}

static int same_tile(const struct proto_tile *a, const struct proto_tile *b)
{
	return a->id == b->id && a->x == b->x && a->y == b->y && a->w == b->w && a->h == b->h && a->px == b->px;
}

static void test_round_trips(void)
{
	pair();
	struct proto_msg m;
	int code;
	const char *why;
	struct proto_hello h;
	memset(&h, 0, sizeof h);
	h.version = PROTO_VERSION;
	h.role = ROLE_MASTER;
	h.secret = 1;
	h.threads = 7;
	h.heartbeat_ms = 2500;
	memset(h.nonce, 0x42, sizeof h.nonce);
	strcpy(h.build, proto_build_id());
	proto_send_hello(A, &h);
	CHECK(xfer(&m, &code, &why) == 1 && m.type == MSG_HELLO);
	CHECK(m.u.hello.threads == 7 && m.u.hello.heartbeat_ms == 2500 && m.u.hello.secret == 1);
	CHECK(memcmp(m.u.hello.nonce, h.nonce, PROTO_NONCE_BYTES) == 0 && strcmp(m.u.hello.build, h.build) == 0);

	uint8_t hash[PROTO_HASH_BYTES];
	for (int i = 0; i < PROTO_HASH_BYTES; i++)
		hash[i] = (uint8_t)(i * 7);
	proto_send_offer(A, hash, 123456, 640, 480);
	CHECK(xfer(&m, &code, &why) == 1 && m.type == MSG_SCENE_OFFER && m.u.offer.size == 123456 &&
	      m.u.offer.width == 640 && m.u.offer.height == 480 && memcmp(m.u.offer.hash, hash, 32) == 0);
	proto_send_hash(A, MSG_SCENE_NEED, hash);
	CHECK(xfer(&m, &code, &why) == 1 && m.type == MSG_SCENE_NEED && memcmp(m.u.hash, hash, 32) == 0);
	uint8_t chunk[1000];
	for (int i = 0; i < 1000; i++)
		chunk[i] = (uint8_t)(i ^ 0x55);
	proto_send_data(A, 1ull << 33, chunk, sizeof chunk);
	CHECK(xfer(&m, &code, &why) == 1 && m.type == MSG_SCENE_DATA && m.u.data.offset == 1ull << 33 &&
	      m.u.data.n == 1000 && memcmp(m.u.data.bytes, chunk, 1000) == 0);
	proto_send_ready(A, hash, true, 99);
	CHECK(xfer(&m, &code, &why) == 1 && m.u.ready.cached == 1 && m.u.ready.build_ms == 99);
	struct proto_tile t = { 17, 32, 64, 10, 3, RENDER_RGB8 };
	proto_send_tile(A, &t);
	CHECK(xfer(&m, &code, &why) == 1 && m.type == MSG_TILE && same_tile(&m.u.tile, &t));
	uint8_t px[360];
	for (int i = 0; i < 360; i++)
		px[i] = (uint8_t)i;
	CHECK(proto_tile_bytes(&t) == 90);
	proto_send_result(A, &t, px, crc32_update(0, px, 90));
	CHECK(xfer(&m, &code, &why) == 1 && m.type == MSG_TILE_RESULT && same_tile(&m.u.result.tile, &t) &&
	      m.u.result.crc == crc32_update(0, px, 90) && memcmp(m.u.result.pixels, px, 90) == 0);
	/* the float pixel type: 12 bytes a pixel, named in TILE and TILE_RESULT */
	t.px = RENDER_RGBF32;
	CHECK(proto_tile_bytes(&t) == 360);
	proto_send_tile(A, &t);
	CHECK(xfer(&m, &code, &why) == 1 && m.type == MSG_TILE && same_tile(&m.u.tile, &t));
	proto_send_result_timed(A, &t, px, crc32_update(0, px, 360), 5);
	CHECK(xfer(&m, &code, &why) == 1 && m.type == MSG_TILE_RESULT && same_tile(&m.u.result.tile, &t) &&
	      m.u.result.trace_us == 5 && memcmp(m.u.result.pixels, px, 360) == 0);
	proto_send_heartbeat(A, 5, 6);
	CHECK(xfer(&m, &code, &why) == 1 && m.u.heartbeat.done == 5 && m.u.heartbeat.queued == 6);
	proto_send_cancel(A, PROTO_CANCEL_ALL);
	CHECK(xfer(&m, &code, &why) == 1 && m.u.cancel_id == PROTO_CANCEL_ALL);
	proto_send_error(A, PERR_AUTH, "bad %s\x01", "secret");
	CHECK(xfer(&m, &code, &why) == 1 && m.u.error.code == PERR_AUTH && strcmp(m.u.error.text, "bad secret?") == 0);
	proto_send_bye(A);
	CHECK(xfer(&m, &code, &why) == 1 && m.type == MSG_BYE);
	CHECK(proto_conn_next(B, &m, &code, &why) == 0 && proto_conn_pending(B) == 0);
	CHECK(proto_conn_bytes_out(A) == proto_conn_bytes_in(B));
	unpair();
}

/* A frame delivered one byte at a time, then EOF in the middle of the next. */
static void test_short_reads(void)
{
	pair();
	struct proto_tile t = { 1, 0, 0, 4, 4, RENDER_RGB8 };
	uint8_t px[48] = { 0 };
	proto_send_result(A, &t, px, crc32_update(0, px, 48));
	proto_send_bye(A);
	CHECK(proto_conn_flush(A) == 0);
	uint8_t all[256];
	ssize_t n = recv(sv[1], all, sizeof all, 0);
	CHECK(n == 12 + 29 + 48 + 12);
	/* feed it back through a fresh pair one byte at a time */
	int p2[2];
	CHECK(socketpair(AF_UNIX, SOCK_STREAM, 0, p2) == 0);
	fcntl(p2[1], F_SETFL, fcntl(p2[1], F_GETFL) | O_NONBLOCK);
	struct proto_conn *r = proto_conn_new(p2[1]);
	struct proto_msg m;
	int code, got = 0, early = 0;
	const char *why;
	for (ssize_t i = 0; i < n - 5; i++) {
		CHECK(write(p2[0], all + i, 1) == 1);
		CHECK(proto_conn_read(r, &why) == 1);
		int k = proto_conn_next(r, &m, &code, &why);
		if (k == 1)
			got++, early += i != 12 + 29 + 48 - 1;
		CHECK(k >= 0);
	}
	CHECK(got == 1 && early == 0);
	CHECK(proto_conn_read(r, &why) == 0); /* nothing more yet: not an error */
	close(p2[0]);                          /* EOF with 7 of BYE's 12 bytes sent */
	CHECK(proto_conn_read(r, &why) == -1 && strstr(why, "middle of a frame") != NULL);
	proto_conn_free(r);
	unpair();
}

static void put_header(uint8_t *h, uint32_t magic, uint16_t ver, uint16_t type, uint32_t len)
{
	proto_wr32(h, magic);
	proto_wr16(h + 4, ver);
	proto_wr16(h + 6, type);
	proto_wr32(h + 8, len);
}

static int raw_frame(const uint8_t *p, size_t n, struct proto_msg *m, int *code, const char **why)
{
	pair();
	CHECK(write(sv[0], p, n) == (ssize_t)n);
	const char *w;
	proto_conn_read(B, &w);
	int k = proto_conn_next(B, m, code, why);
	unpair();
	return k;
}

static void test_bad_frames(void)
{
	uint8_t f[128] = { 0 };
	struct proto_msg m;
	int code = 0;
	const char *why = "";
	put_header(f, 0x47455420, PROTO_VERSION, MSG_BYE, 0); /* "GET " */
	CHECK(raw_frame(f, 12, &m, &code, &why) == -1 && code == PERR_PROTOCOL && strstr(why, "magic"));
	put_header(f, PROTO_MAGIC, PROTO_VERSION, MSG_SCENE_DATA, LIM_FRAME_PAYLOAD + 1);
	CHECK(raw_frame(f, 12, &m, &code, &why) == -1 && code == PERR_LIMIT);
	put_header(f, PROTO_MAGIC, PROTO_VERSION, 99, 0);
	CHECK(raw_frame(f, 12, &m, &code, &why) == -1 && strstr(why, "unknown message type"));
	/* a frame of another version: only HELLO and ERROR are decoded */
	put_header(f, PROTO_MAGIC, PROTO_VERSION + 1, MSG_BYE, 0);
	CHECK(raw_frame(f, 12, &m, &code, &why) == -1 && code == PERR_VERSION);
	put_header(f, PROTO_MAGIC, PROTO_VERSION + 1, MSG_ERROR, 2 + 4 + 2);
	proto_wr16(f + 12, PERR_VERSION);
	proto_wr32(f + 14, 2);
	f[18] = 'h', f[19] = 'i';
	CHECK(raw_frame(f, 20, &m, &code, &why) == 1 && m.type == MSG_ERROR && m.frame_version == PROTO_VERSION + 1 &&
	      strcmp(m.u.error.text, "hi") == 0);
	/* wrong payload sizes */
	put_header(f, PROTO_MAGIC, PROTO_VERSION, MSG_BYE, 1);
	CHECK(raw_frame(f, 13, &m, &code, &why) == -1 && strstr(why, "longer"));
	put_header(f, PROTO_MAGIC, PROTO_VERSION, MSG_CANCEL, 3);
	CHECK(raw_frame(f, 15, &m, &code, &why) == -1 && strstr(why, "shorter"));
	/* a tile result whose pixel bytes do not match its rectangle */
	put_header(f, PROTO_MAGIC, PROTO_VERSION, MSG_TILE_RESULT, 29 + 11);
	memset(f + 12, 0, 29 + 11);
	proto_wr32(f + 12 + 12, 2), proto_wr32(f + 12 + 16, 2); /* 2x2: 12 bytes */
	CHECK(raw_frame(f, 12 + 40, &m, &code, &why) == -1 && strstr(why, "pixel bytes"));
	put_header(f, PROTO_MAGIC, PROTO_VERSION, MSG_TILE_RESULT, 29 + 12);
	memset(f + 12, 0, 29 + 12);
	proto_wr32(f + 12 + 12, 2), proto_wr32(f + 12 + 16, 2);
	CHECK(raw_frame(f, 12 + 41, &m, &code, &why) == 1 && m.u.result.tile.px == RENDER_RGB8);
	f[12 + 20] = RENDER_RGBF32; /* 2x2 floats: 48 bytes, not 12 */
	CHECK(raw_frame(f, 12 + 41, &m, &code, &why) == -1 && strstr(why, "pixel bytes"));
	f[12 + 20] = 2; /* no such type */
	CHECK(raw_frame(f, 12 + 41, &m, &code, &why) == -1 && strstr(why, "unknown pixel type"));
	put_header(f, PROTO_MAGIC, PROTO_VERSION, MSG_TILE_RESULT, 29 + 48);
	memset(f + 12, 0, 29 + 48);
	proto_wr32(f + 12 + 12, 2), proto_wr32(f + 12 + 16, 2);
	f[12 + 20] = RENDER_RGBF32;
	CHECK(raw_frame(f, 12 + 29 + 48, &m, &code, &why) == 1 && m.u.result.tile.px == RENDER_RGBF32);
	/* a tile larger than the limit; a tile of an unknown pixel type */
	put_header(f, PROTO_MAGIC, PROTO_VERSION, MSG_TILE, 21);
	memset(f + 12, 0, 21);
	proto_wr32(f + 12 + 12, 2048), proto_wr32(f + 12 + 16, 2048);
	CHECK(raw_frame(f, 33, &m, &code, &why) == -1 && strstr(why, "tile size"));
	proto_wr32(f + 12 + 12, 8), proto_wr32(f + 12 + 16, 8);
	f[12 + 20] = RENDER_RGBF32;
	CHECK(raw_frame(f, 33, &m, &code, &why) == 1 && m.u.tile.px == RENDER_RGBF32);
	f[12 + 20] = 7;
	CHECK(raw_frame(f, 33, &m, &code, &why) == -1 && strstr(why, "unknown pixel type"));
	/* an error text longer than the limit */
	put_header(f, PROTO_MAGIC, PROTO_VERSION, MSG_ERROR, 6);
	proto_wr16(f + 12, 1);
	proto_wr32(f + 14, LIM_ERROR_TEXT + 1);
	CHECK(raw_frame(f, 18, &m, &code, &why) == -1);
	/* a scene offer of 0 bytes or too big an image */
	put_header(f, PROTO_MAGIC, PROTO_VERSION, MSG_SCENE_OFFER, 48);
	memset(f + 12, 0, 48);
	proto_wr32(f + 12 + 40, 10), proto_wr32(f + 12 + 44, 10);
	CHECK(raw_frame(f, 60, &m, &code, &why) == -1 && strstr(why, "scene size"));
	/* a declared length is never allocated up front: a 13 MiB frame that
	 * never arrives costs only what did arrive */
	pair();
	put_header(f, PROTO_MAGIC, PROTO_VERSION, MSG_SCENE_DATA, LIM_FRAME_PAYLOAD);
	CHECK(write(sv[0], f, 12) == 12);
	const char *w;
	CHECK(proto_conn_read(B, &w) == 1);
	CHECK(proto_conn_next(B, &m, &code, &why) == 0);
	unpair();
}

/* A connection's own frame limit (the handshake's): a longer declared frame
 * is refused from its header alone, and the buffer stays at header + limit. */
static void test_conn_limit(void)
{
	uint8_t f[12];
	struct proto_msg m;
	int code = 0;
	const char *why = "", *w;
	pair();
	proto_conn_set_limit(B, LIM_HANDSHAKE_PAYLOAD);
	put_header(f, PROTO_MAGIC, PROTO_VERSION, MSG_HELLO, LIM_HANDSHAKE_PAYLOAD + 1);
	CHECK(write(sv[0], f, 12) == 12);
	CHECK(proto_conn_read(B, &w) == 1);
	CHECK(proto_conn_next(B, &m, &code, &why) == -1 && code == PERR_LIMIT);
	unpair();
	/* at the limit: waits for the bytes, reading never buffers past one frame */
	pair();
	proto_conn_set_limit(B, LIM_HANDSHAKE_PAYLOAD);
	uint8_t big[4096] = { 0 };
	size_t one = PROTO_HEADER_BYTES + LIM_HANDSHAKE_PAYLOAD;
	put_header(big, PROTO_MAGIC, PROTO_VERSION, MSG_SCENE_DATA, LIM_HANDSHAKE_PAYLOAD);
	put_header(big + one, PROTO_MAGIC, PROTO_VERSION, MSG_BYE, 0); /* and a second frame behind it */
	CHECK(write(sv[0], big, one + 12) == (ssize_t)(one + 12));
	while (proto_conn_read(B, &w) > 0)
		;
	CHECK(proto_conn_pending(B) == one);
	CHECK(proto_conn_next(B, &m, &code, &why) == 1 && m.type == MSG_SCENE_DATA);
	CHECK(proto_conn_read(B, &w) == 1);
	CHECK(proto_conn_next(B, &m, &code, &why) == 1 && m.type == MSG_BYE);
	/* raised again (authenticated): longer frames pass */
	proto_conn_set_limit(B, LIM_FRAME_PAYLOAD);
	proto_send_data(A, 0, big, sizeof big);
	CHECK(xfer(&m, &code, &why) == 1 && m.type == MSG_SCENE_DATA && m.u.data.n == sizeof big);
	unpair();
}

/* Several threads computing CRCs at once (run under SAN=thread: the lazily
 * filled table was a data race). */
static void *crc_thread(void *arg)
{
	uint32_t *out = arg;
	*out = crc32_update(0, (const uint8_t *)"123456789", 9);
	return NULL;
}

static void test_crc_threads(void)
{
	pthread_t t[4];
	uint32_t v[4] = { 0 };
	for (int i = 0; i < 4; i++)
		CHECK(pthread_create(&t[i], NULL, crc_thread, &v[i]) == 0);
	for (int i = 0; i < 4; i++) {
		pthread_join(t[i], NULL);
		CHECK(v[i] == 0xcbf43926u);
	}
}

static void test_crypto_glue(void)
{
	CHECK(crc32_update(0, (const uint8_t *)"123456789", 9) == 0xcbf43926u);
	CHECK(crc32_update(crc32_update(0, (const uint8_t *)"1234", 4), (const uint8_t *)"56789", 5) == 0xcbf43926u);
	uint8_t nm[32], nw[32], a[32], b[32], c[32];
	memset(nm, 1, 32);
	memset(nw, 2, 32);
	proto_auth_mac((const uint8_t *)"k", 1, ROLE_MASTER, nm, nw, a);
	proto_auth_mac((const uint8_t *)"k", 1, ROLE_WORKER, nm, nw, b);
	CHECK(!proto_mac_equal(a, b, 32)); /* a proof cannot be reflected */
	proto_auth_mac((const uint8_t *)"k", 1, ROLE_MASTER, nw, nm, c);
	CHECK(!proto_mac_equal(a, c, 32)); /* nonces are ordered */
	proto_auth_mac((const uint8_t *)"K", 1, ROLE_MASTER, nm, nw, c);
	CHECK(!proto_mac_equal(a, c, 32));
	proto_auth_mac((const uint8_t *)"k", 1, ROLE_MASTER, nm, nw, c);
	CHECK(proto_mac_equal(a, c, 32));
	uint8_t h1[32], h2[32];
	proto_scene_hash((const uint8_t *)"abc", 3, h1);
	sha256("abc", 3, h2);
	CHECK(memcmp(h1, h2, 32) == 0 && h1[0] == 0xba && h1[31] == 0xad);
}

static void test_net_and_secret(void)
{
	char host[NET_HOST_LEN], port[NET_PORT_LEN], err[300];
	CHECK(net_parse_hostport("127.0.0.1:7411", host, port, err, sizeof err) == 0 && strcmp(host, "127.0.0.1") == 0 &&
	      strcmp(port, "7411") == 0);
	CHECK(net_parse_hostport("[::1]:0", host, port, err, sizeof err) == 0 && strcmp(host, "::1") == 0);
	CHECK(net_parse_hostport("render-3.lan:80", host, port, err, sizeof err) == 0);
	CHECK(net_parse_hostport("127.0.0.1", host, port, err, sizeof err) < 0);
	CHECK(net_parse_hostport("127.0.0.1:65536", host, port, err, sizeof err) < 0);
	CHECK(net_parse_hostport(":80", host, port, err, sizeof err) < 0);
	CHECK(net_parse_hostport("::1:80", host, port, err, sizeof err) < 0);
	CHECK(net_parse_hostport("h:8x", host, port, err, sizeof err) < 0);

	char path[] = "/tmp/portray-secret-XXXXXX";
	int fd = mkstemp(path);
	CHECK(fd >= 0);
	CHECK(write(fd, "s3cret\n\n", 8) == 8);
	close(fd);
	uint8_t *s;
	size_t n;
	char warn[300];
	CHECK(chmod(path, 0600) == 0);
	CHECK(proto_read_secret(path, &s, &n, err, sizeof err, warn, sizeof warn) == 0 && n == 6 && memcmp(s, "s3cret", 6) == 0);
	CHECK(warn[0] == 0);
	free(s);
	/* readable by others: still read, with a warning */
	CHECK(chmod(path, 0644) == 0);
	CHECK(proto_read_secret(path, &s, &n, err, sizeof err, warn, sizeof warn) == 0 && strstr(warn, "other users"));
	free(s);
	fd = open(path, O_WRONLY | O_TRUNC);
	CHECK(write(fd, "\n", 1) == 1);
	close(fd);
	CHECK(proto_read_secret(path, &s, &n, err, sizeof err, warn, sizeof warn) < 0 && strstr(err, "empty"));
	unlink(path);
	CHECK(proto_read_secret(path, &s, &n, err, sizeof err, warn, sizeof warn) < 0);
	/* a FIFO (or a device) is refused, not read: it could block for ever */
	CHECK(mkfifo(path, 0600) == 0);
	CHECK(proto_read_secret(path, &s, &n, err, sizeof err, warn, sizeof warn) < 0 && strstr(err, "regular"));
	unlink(path);

	/* listen on an OS-chosen port and connect to it */
	int l = net_listen("127.0.0.1", "0", err, sizeof err);
	CHECK(l >= 0);
	int p = net_local_port(l);
	CHECK(p > 0);
	char ps[16];
	snprintf(ps, sizeof ps, "%d", p);
	int c = net_connect_start("127.0.0.1", ps, err, sizeof err);
	CHECK(c >= 0);
	char peer[96];
	int a = -1;
	for (int i = 0; i < 200 && a < 0; i++) {
		a = net_accept(l, peer, sizeof peer);
		if (a < 0)
			usleep(1000);
	}
	CHECK(a >= 0 && strncmp(peer, "127.0.0.1:", 10) == 0);
	CHECK(net_connect_finish(c, err, sizeof err) == 0);
	close(a);
	close(c);
	close(l);
}

/* The build id is the compatibility part and the probe's fingerprint, no
 * compiler or architecture; proto_hello_check names which part differs. */
static void test_hello_build(void)
{
	const char *id = proto_build_id();
	char want[80];
	snprintf(want, sizeof want, "proto-%u/scene-%u/pixels-%d/probe-%016llx", PROTO_VERSION, PROTO_SCENE_VERSION,
		 RENDER_PIXEL_REV, (unsigned long long)probe_hash());
	CHECK(strcmp(id, want) == 0);
	CHECK(probe_hash() != 0 && probe_compute() == probe_hash()); /* the probe is deterministic */
	CHECK(strstr(id, "gcc") == NULL && strstr(id, "clang") == NULL && strstr(id, "x86") == NULL);
	struct proto_msg m;
	memset(&m, 0, sizeof m);
	m.type = MSG_HELLO;
	m.frame_version = PROTO_VERSION;
	m.u.hello.version = PROTO_VERSION;
	m.u.hello.role = ROLE_WORKER;
	char why[LIM_ERROR_TEXT + 1];
	snprintf(m.u.hello.build, sizeof m.u.hello.build, "%s", id);
	CHECK(proto_hello_check(&m, ROLE_WORKER, false, PROTO_VERSION, why, sizeof why) == 0);
	/* another probe: refused, and the message says it is the pixels */
	m.u.hello.build[strlen(id) - 1] = id[strlen(id) - 1] == 'f' ? 'e' : 'f';
	CHECK(proto_hello_check(&m, ROLE_WORKER, false, PROTO_VERSION, why, sizeof why) == PERR_BUILD);
	CHECK(strstr(why, "pixel probe mismatch: the worker's probe image hashes to ") == why);
	CHECK(strstr(why, id + strlen(id) - 16) != NULL);
	/* another pixel revision: a core build mismatch */
	snprintf(m.u.hello.build, sizeof m.u.hello.build, "proto-%u/scene-%u/pixels-%d/probe-%s", PROTO_VERSION,
		 PROTO_SCENE_VERSION, RENDER_PIXEL_REV + 1, id + strlen(id) - 16);
	CHECK(proto_hello_check(&m, ROLE_WORKER, false, PROTO_VERSION, why, sizeof why) == PERR_BUILD);
	CHECK(strstr(why, "core build mismatch: the worker runs 'proto-") == why);
	/* an old-style build string */
	snprintf(m.u.hello.build, sizeof m.u.hello.build, "portray-0.11.0/proto-2/scene-1/pixels-2/gcc-12.2.0/x86_64");
	CHECK(proto_hello_check(&m, ROLE_WORKER, false, PROTO_VERSION, why, sizeof why) == PERR_BUILD);
	CHECK(strstr(why, "core build mismatch") == why);
}

int main(void)
{
	test_crc_threads(); /* first: nothing else has filled the CRC table yet */
	test_conn_limit();
	test_round_trips();
	test_hello_build();
	test_short_reads();
	test_bad_frames();
	test_crypto_glue();
	test_net_and_secret();
	TEST_MAIN_END();
}
