/*
 * fuzz_frame.c - libFuzzer target: the frame header parser and every message
 * decoder on arbitrary bytes, as they would arrive on a socket. The input is
 * read as a stream of frames; each complete one is decoded, and a decoded
 * message is re-encoded and decoded again to check that the codec agrees
 * with itself. `make fuzz` runs it with libFuzzer; the replay main runs the
 * checked-in corpus in `make test`.
 */
#include <fcntl.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "proto/proto.h"

/* Sends m through a socketpair-backed connection and decodes it again. */
static void reencode(const struct proto_msg *m)
{
	int sv[2];
	if (socketpair(AF_UNIX, SOCK_STREAM, 0, sv) < 0)
		return;
	for (int i = 0; i < 2; i++) /* connections expect non-blocking sockets */
		fcntl(sv[i], F_SETFL, fcntl(sv[i], F_GETFL) | O_NONBLOCK);
	struct proto_conn *a = proto_conn_new(sv[0]), *b = proto_conn_new(sv[1]);
	if (!a || !b) {
		proto_conn_free(a);
		proto_conn_free(b);
		return;
	}
	int rc = 0;
	switch (m->type) {
	case MSG_HELLO: rc = proto_send_hello(a, &m->u.hello); break;
	case MSG_AUTH: rc = proto_send_auth(a, m->u.mac); break;
	case MSG_SCENE_OFFER:
		rc = proto_send_offer(a, m->u.offer.hash, m->u.offer.size, m->u.offer.width, m->u.offer.height);
		break;
	case MSG_SCENE_HAVE:
	case MSG_SCENE_NEED: rc = proto_send_hash(a, m->type, m->u.hash); break;
	case MSG_SCENE_DATA: rc = proto_send_data(a, m->u.data.offset, m->u.data.bytes, m->u.data.n); break;
	case MSG_SCENE_READY: rc = proto_send_ready(a, m->u.ready.hash, m->u.ready.cached, m->u.ready.build_ms); break;
	case MSG_TILE: rc = proto_send_tile(a, &m->u.tile); break;
	case MSG_TILE_RESULT: rc = proto_send_result(a, &m->u.result.tile, m->u.result.pixels, m->u.result.crc); break;
	case MSG_HEARTBEAT: rc = proto_send_heartbeat(a, m->u.heartbeat.done, m->u.heartbeat.queued); break;
	case MSG_CANCEL: rc = proto_send_cancel(a, m->u.cancel_id); break;
	case MSG_ERROR: rc = proto_send_error(a, m->u.error.code, "%s", m->u.error.text); break;
	case MSG_BYE: rc = proto_send_bye(a); break;
	}
	/* small frames only: a socket buffer holds them whole */
	if (rc == 0 && proto_conn_outq(a) < 64 * 1024 && proto_conn_flush(a) == 0 && proto_conn_outq(a) == 0) {
		const char *why;
		int code;
		struct proto_msg m2;
		while (proto_conn_read(b, &why) > 0)
			;
		if (proto_conn_next(b, &m2, &code, &why) != 1 || m2.type != m->type)
			abort();
		if (m->type == MSG_TILE && memcmp(&m2.u.tile, &m->u.tile, sizeof m->u.tile) != 0)
			abort();
		if (m->type == MSG_HELLO && (m2.u.hello.version != m->u.hello.version ||
					     strcmp(m2.u.hello.build, m->u.hello.build) != 0))
			abort();
	}
	proto_conn_free(a);
	proto_conn_free(b);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	size_t pos = 0;
	while (size - pos >= PROTO_HEADER_BYTES) {
		uint16_t type, version;
		uint32_t plen;
		int code;
		const char *why;
		if (proto_header_parse(data + pos, size - pos, &type, &version, &plen, &code, &why) < 0)
			return 0;
		if (plen > size - pos - PROTO_HEADER_BYTES)
			return 0;
		struct proto_msg m;
		if (proto_msg_decode(type, data + pos + PROTO_HEADER_BYTES, plen, &m, &why) == 0)
			reencode(&m);
		pos += PROTO_HEADER_BYTES + plen;
	}
	return 0;
}
