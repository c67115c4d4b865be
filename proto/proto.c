/*
 * proto.c - frames, message codecs and the buffered connection (proto.h).
 */
#include "proto/proto.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/probe.h"
#include "common/render.h"
#include "proto/serial.h"

/* ---- small pure helpers ---- */

/* the versions as plain numbers for the build id (the header constants carry a u suffix) */
#define PROTO_BUILD_PROTO 3
#define PROTO_BUILD_SCENE 2
_Static_assert(PROTO_BUILD_PROTO == PROTO_VERSION && PROTO_BUILD_SCENE == PROTO_SCENE_VERSION, "build id numbers");
#define STR2(x) #x
#define STR(x) STR2(x)
/* the pixels' revision as a plain number (common/render.h) */
#define PROTO_BUILD_PIXELS 5
_Static_assert(PROTO_BUILD_PIXELS == RENDER_PIXEL_REV, "build id numbers");

/* What decides whether two builds may share a render: the protocol and
 * scene encoding they speak and the pixels' revision, then the pixels
 * themselves, proven by the probe (common/probe.h) rendered at the first
 * call. The compiler, its flags, the C library and the CPU are left out:
 * the pixel path computes in plain IEEE-754 doubles with in-tree maths
 * (common/xmath.h), and a build that still draws other pixels shows it in
 * its probe. */
#define BUILD_COMPAT "proto-" STR(PROTO_BUILD_PROTO) "/scene-" STR(PROTO_BUILD_SCENE) "/pixels-" STR(PROTO_BUILD_PIXELS)
#define BUILD_PROBE "/probe-"
static pthread_once_t build_once = PTHREAD_ONCE_INIT;
static char build_id[sizeof BUILD_COMPAT BUILD_PROBE + 16];
_Static_assert(sizeof build_id - 1 <= LIM_BUILD_ID, "the build id fits HELLO");

static void build_id_init(void)
{
	snprintf(build_id, sizeof build_id, "%s%s%016llx", BUILD_COMPAT, BUILD_PROBE,
		 (unsigned long long)probe_hash());
}

const char *proto_build_id(void)
{
	pthread_once(&build_once, build_id_init);
	return build_id;
}

int proto_hello_check(const struct proto_msg *m, enum proto_role want, bool have_secret, uint32_t my_version,
		      char *why, size_t whylen)
{
	const struct proto_hello *h = &m->u.hello;
	const char *peer = want == ROLE_MASTER ? "master" : "worker";
	const char *me = want == ROLE_MASTER ? "worker" : "master";
	if (h->version != my_version || m->frame_version != my_version) {
		snprintf(why, whylen, "protocol version mismatch: the %s speaks version %u, this %s speaks %u", peer,
			 h->version, me, my_version);
		return PERR_VERSION;
	}
	if (h->role != want) {
		snprintf(why, whylen, "peer is not a %s", peer);
		return PERR_PROTOCOL;
	}
	const char *mine = proto_build_id();
	size_t compat = sizeof BUILD_COMPAT BUILD_PROBE - 1;
	if (strncmp(h->build, mine, compat) != 0) {
		snprintf(why, whylen, "core build mismatch: the %s runs '%s', this %s runs '%s'", peer, h->build, me,
			 mine);
		return PERR_BUILD;
	}
	if (strcmp(h->build + compat, mine + compat) != 0 || strcmp(mine + compat, "0000000000000000") == 0) {
		snprintf(why, whylen,
			 "pixel probe mismatch: the %s's probe image hashes to %.16s, this %s's to %s: their "
			 "compilers, flags or CPUs make different pixels (docs/maths.md)",
			 peer, h->build + compat, me, mine + compat);
		return PERR_BUILD;
	}
	if (h->secret && !have_secret) {
		snprintf(why, whylen, want == ROLE_WORKER ? "the worker requires a shared secret: give --secret-file"
							  : "this worker has no shared secret but the master has one");
		return PERR_AUTH;
	}
	if (!h->secret && have_secret) {
		snprintf(why, whylen, want == ROLE_WORKER ? "the worker has no shared secret, this master has one"
							  : "this worker requires a shared secret (--secret-file)");
		return PERR_AUTH;
	}
	if (want == ROLE_MASTER && (h->heartbeat_ms < PROTO_HB_MIN_MS || h->heartbeat_ms > PROTO_HB_MAX_MS)) {
		snprintf(why, whylen, "heartbeat interval %u ms outside %u..%u", h->heartbeat_ms, PROTO_HB_MIN_MS,
			 PROTO_HB_MAX_MS);
		return PERR_PROTOCOL;
	}
	return 0;
}

const char *proto_type_name(int type)
{
	static const char *const names[] = { "?", "HELLO", "AUTH", "SCENE_OFFER", "SCENE_HAVE", "SCENE_NEED",
					     "SCENE_DATA", "SCENE_READY", "TILE", "TILE_RESULT", "HEARTBEAT",
					     "CANCEL", "ERROR", "BYE" };
	return type > 0 && type <= MSG_TYPE_MAX ? names[type] : "?";
}

const char *proto_err_name(int code)
{
	static const char *const names[] = { "?", "protocol", "version", "auth", "build", "scene",
					     "limit", "timeout", "internal", "shutdown" };
	return code > 0 && code <= PERR_SHUTDOWN ? names[code] : "?";
}

int proto_random(uint8_t *p, size_t n)
{
	/* getrandom(): the kernel's CSPRNG without a file descriptor (a worker
	 * at its descriptor limit could not open /dev/urandom and refused every
	 * peer); /dev/urandom only where the call does not exist */
	size_t got = 0;
	while (got < n) {
		ssize_t r = getrandom(p + got, n - got, 0);
		if (r < 0 && errno == EINTR)
			continue;
		if (r <= 0)
			break;
		got += (size_t)r;
	}
	if (got == n)
		return 0;
	if (errno != ENOSYS)
		return -1;
	int fd = open("/dev/urandom", O_RDONLY | O_CLOEXEC);
	if (fd < 0)
		return -1;
	got = 0;
	while (got < n) {
		ssize_t r = read(fd, p + got, n - got);
		if (r < 0 && errno == EINTR)
			continue;
		if (r <= 0) {
			close(fd);
			return -1;
		}
		got += (size_t)r;
	}
	close(fd);
	return 0;
}

/* ---- header and message decoding ---- */

int proto_header_parse(const uint8_t *p, size_t len, uint16_t *type, uint16_t *version, uint32_t *plen,
		       int *code, const char **why)
{
	if (len < PROTO_HEADER_BYTES) {
		*code = PERR_PROTOCOL;
		*why = "short header";
		return -1;
	}
	if (proto_be32(p) != PROTO_MAGIC) {
		*code = PERR_PROTOCOL;
		*why = "bad frame magic (not a portray peer?)";
		return -1;
	}
	*version = proto_be16(p + 4);
	*type = proto_be16(p + 6);
	*plen = proto_be32(p + 8);
	if (*plen > LIM_FRAME_PAYLOAD) {
		*code = PERR_LIMIT;
		*why = "frame longer than the limit";
		return -1;
	}
	if (*type == 0 || *type > MSG_TYPE_MAX) {
		/* a newer peer's message we do not know: only fatal within our version */
		*code = PERR_PROTOCOL;
		*why = "unknown message type";
		return -1;
	}
	return 0;
}

/* Copies a u32-length-prefixed string of at most max bytes into out; 0/-1. */
static int get_text(struct proto_rbuf *r, char *out, size_t max)
{
	uint32_t n = proto_get_u32(r);
	if (r->err || n > max)
		return -1;
	const uint8_t *s = proto_get_span(r, n);
	if (!s)
		return -1;
	/* printable text only: it ends up in logs and on terminals */
	for (uint32_t i = 0; i < n; i++)
		out[i] = s[i] >= 0x20 && s[i] < 0x7f ? (char)s[i] : '?';
	out[n] = 0;
	return 0;
}

_Static_assert(RENDER_RGB8 == 0 && RENDER_RGBF32 == 1, "the wire's pixel types are render.h's");

static int tile_ok(const struct proto_tile *t)
{
	return t->px <= RENDER_RGBF32 && t->w >= 1 && t->h >= 1 && t->w <= LIM_TILE_PIXELS &&
	       t->h <= LIM_TILE_PIXELS && (uint64_t)t->w * t->h <= LIM_TILE_PIXELS && t->x <= UINT32_MAX - t->w &&
	       t->y <= UINT32_MAX - t->h;
}

static void get_tile(struct proto_rbuf *r, struct proto_tile *t)
{
	t->id = proto_get_u32(r);
	t->x = proto_get_u32(r);
	t->y = proto_get_u32(r);
	t->w = proto_get_u32(r);
	t->h = proto_get_u32(r);
	t->px = proto_get_u8(r);
}

size_t proto_tile_bytes(const struct proto_tile *t)
{
	return (size_t)t->w * t->h * render_pixel_bytes((enum render_pixel)t->px);
}

int proto_msg_decode(uint16_t type, const uint8_t *p, uint32_t len, struct proto_msg *m, const char **why)
{
	struct proto_rbuf r = { .p = p, .len = len };
	memset(m, 0, sizeof *m);
	m->type = (enum proto_type)type;
	*why = "malformed message";
	switch (type) {
	case MSG_HELLO: {
		struct proto_hello *h = &m->u.hello;
		h->version = proto_get_u32(&r);
		h->role = proto_get_u8(&r);
		h->secret = proto_get_u8(&r);
		h->threads = proto_get_u16(&r);
		h->heartbeat_ms = proto_get_u32(&r);
		proto_get_bytes(&r, h->nonce, PROTO_NONCE_BYTES);
		if (get_text(&r, h->build, LIM_BUILD_ID) < 0)
			return -1;
		if (h->role != ROLE_MASTER && h->role != ROLE_WORKER) {
			*why = "HELLO with an unknown role";
			return -1;
		}
		if (h->secret > 1)
			return -1;
		break;
	}
	case MSG_AUTH:
		proto_get_bytes(&r, m->u.mac, PROTO_MAC_BYTES);
		break;
	case MSG_SCENE_OFFER:
		proto_get_bytes(&r, m->u.offer.hash, PROTO_HASH_BYTES);
		m->u.offer.size = proto_get_u64(&r);
		m->u.offer.width = proto_get_u32(&r);
		m->u.offer.height = proto_get_u32(&r);
		if (r.err)
			break;
		if (m->u.offer.size > LIM_SCENE_BYTES || m->u.offer.size == 0) {
			*why = "scene size out of range";
			return -1;
		}
		if (m->u.offer.width < 1 || m->u.offer.height < 1 || m->u.offer.width > LIM_IMAGE_SIDE ||
		    m->u.offer.height > LIM_IMAGE_SIDE ||
		    (uint64_t)m->u.offer.width * m->u.offer.height > LIM_IMAGE_PIXELS) {
			*why = "image size out of range";
			return -1;
		}
		break;
	case MSG_SCENE_HAVE:
	case MSG_SCENE_NEED:
		proto_get_bytes(&r, m->u.hash, PROTO_HASH_BYTES);
		break;
	case MSG_SCENE_DATA:
		m->u.data.offset = proto_get_u64(&r);
		if (r.err)
			break;
		m->u.data.n = (uint32_t)proto_rbuf_left(&r);
		m->u.data.bytes = proto_get_span(&r, m->u.data.n);
		if (m->u.data.n == 0 || m->u.data.n > PROTO_CHUNK_BYTES) {
			*why = "scene chunk size out of range";
			return -1;
		}
		break;
	case MSG_SCENE_READY:
		proto_get_bytes(&r, m->u.ready.hash, PROTO_HASH_BYTES);
		m->u.ready.cached = proto_get_u8(&r);
		m->u.ready.build_ms = proto_get_u32(&r);
		if (m->u.ready.cached > 1)
			return -1;
		break;
	case MSG_TILE:
		get_tile(&r, &m->u.tile);
		if (!r.err && !tile_ok(&m->u.tile)) {
			*why = m->u.tile.px > RENDER_RGBF32 ? "unknown pixel type" : "tile size out of range";
			return -1;
		}
		break;
	case MSG_TILE_RESULT:
		get_tile(&r, &m->u.result.tile);
		m->u.result.crc = proto_get_u32(&r);
		m->u.result.trace_us = proto_get_u32(&r);
		if (r.err)
			break;
		if (!tile_ok(&m->u.result.tile)) {
			*why = m->u.result.tile.px > RENDER_RGBF32 ? "unknown pixel type" : "tile size out of range";
			return -1;
		}
		if (proto_rbuf_left(&r) != proto_tile_bytes(&m->u.result.tile)) {
			*why = "tile result has the wrong number of pixel bytes";
			return -1;
		}
		m->u.result.pixels = proto_get_span(&r, proto_rbuf_left(&r));
		break;
	case MSG_HEARTBEAT:
		m->u.heartbeat.done = proto_get_u32(&r);
		m->u.heartbeat.queued = proto_get_u32(&r);
		break;
	case MSG_CANCEL:
		m->u.cancel_id = proto_get_u32(&r);
		break;
	case MSG_ERROR:
		m->u.error.code = proto_get_u16(&r);
		if (get_text(&r, m->u.error.text, LIM_ERROR_TEXT) < 0)
			return -1;
		break;
	case MSG_BYE:
		break;
	default:
		*why = "unknown message type";
		return -1;
	}
	if (r.err) {
		*why = "message shorter than its fields";
		return -1;
	}
	if (r.pos != r.len) {
		*why = "message longer than its fields";
		return -1;
	}
	return 0;
}

/* ---- the connection ---- */

struct proto_conn {
	int fd;
	uint16_t version;   /* written into our headers */
	uint8_t *in;        /* input buffer: grows as bytes arrive */
	size_t in_len, in_cap, in_pos;
	struct proto_wbuf out;
	size_t out_pos;     /* bytes of out already written */
	uint64_t bytes_out, bytes_in;
	uint32_t max_payload; /* longest frame payload accepted now */
};

/* the input buffer starts small (or at one allowed frame, if less) and may
 * grow to one whole frame of the connection's limit */
#define IN_START (64u * 1024)

struct proto_conn *proto_conn_new(int fd)
{
	struct proto_conn *c = calloc(1, sizeof *c);
	if (!c)
		return NULL;
	c->fd = fd;
	c->version = PROTO_VERSION;
	c->max_payload = LIM_FRAME_PAYLOAD;
	return c;
}

void proto_conn_free(struct proto_conn *c)
{
	if (!c)
		return;
	if (c->fd >= 0)
		close(c->fd);
	free(c->in);
	proto_wbuf_free(&c->out);
	free(c);
}

int proto_conn_fd(const struct proto_conn *c) { return c->fd; }
void proto_conn_set_version(struct proto_conn *c, uint16_t version) { c->version = version; }
void proto_conn_set_limit(struct proto_conn *c, uint32_t max_payload)
{
	c->max_payload = max_payload < LIM_FRAME_PAYLOAD ? max_payload : LIM_FRAME_PAYLOAD;
}
size_t proto_conn_pending(const struct proto_conn *c) { return c->in_len - c->in_pos; }
size_t proto_conn_outq(const struct proto_conn *c) { return c->out.len - c->out_pos; }
uint64_t proto_conn_bytes_out(const struct proto_conn *c) { return c->bytes_out; }
uint64_t proto_conn_bytes_in(const struct proto_conn *c) { return c->bytes_in; }

int proto_conn_read(struct proto_conn *c, const char **why)
{
	/* compact: consumed bytes go, so a frame always starts at in[0] */
	if (c->in_pos > 0) {
		memmove(c->in, c->in + c->in_pos, c->in_len - c->in_pos);
		c->in_len -= c->in_pos;
		c->in_pos = 0;
	}
	if (c->in_len == c->in_cap) {
		/* grow only when full, by doubling, never past one frame: what the
		 * peer declared is never allocated before it has been sent */
		size_t max = PROTO_HEADER_BYTES + (size_t)c->max_payload;
		size_t nc = c->in_cap ? c->in_cap * 2 : IN_START;
		if (nc > max)
			nc = max;
		if (nc <= c->in_cap)
			return 0; /* a whole frame is buffered: proto_conn_next will take it */
		uint8_t *p = realloc(c->in, nc);
		if (!p) {
			*why = "out of memory";
			return -1;
		}
		c->in = p;
		c->in_cap = nc;
	}
	for (;;) {
		ssize_t n = recv(c->fd, c->in + c->in_len, c->in_cap - c->in_len, 0);
		if (n > 0) {
			c->in_len += (size_t)n;
			c->bytes_in += (uint64_t)n;
			return 1;
		}
		if (n == 0) {
			*why = c->in_len ? "connection closed in the middle of a frame" : "connection closed";
			return -1;
		}
		if (errno == EINTR)
			continue;
		if (errno == EAGAIN || errno == EWOULDBLOCK)
			return 0;
		*why = strerror(errno);
		return -1;
	}
}

int proto_conn_next(struct proto_conn *c, struct proto_msg *m, int *code, const char **why)
{
	size_t avail = c->in_len - c->in_pos;
	if (avail < PROTO_HEADER_BYTES)
		return 0;
	const uint8_t *h = c->in + c->in_pos;
	uint16_t type, version;
	uint32_t plen;
	if (proto_header_parse(h, avail, &type, &version, &plen, code, why) < 0)
		return -1;
	if (plen > c->max_payload) {
		*code = PERR_LIMIT;
		*why = "frame longer than allowed at this point of the protocol";
		return -1;
	}
	if (avail < PROTO_HEADER_BYTES + (size_t)plen)
		return 0;
	if (version != PROTO_VERSION && type != MSG_HELLO && type != MSG_ERROR) {
		*code = PERR_VERSION;
		*why = "frame of another protocol version";
		return -1;
	}
	if (proto_msg_decode(type, h + PROTO_HEADER_BYTES, plen, m, why) < 0) {
		*code = PERR_PROTOCOL;
		return -1;
	}
	m->frame_version = version;
	c->in_pos += PROTO_HEADER_BYTES + (size_t)plen;
	return 1;
}

int proto_conn_flush(struct proto_conn *c)
{
	while (c->out_pos < c->out.len) {
		ssize_t n = send(c->fd, c->out.p + c->out_pos, c->out.len - c->out_pos, MSG_NOSIGNAL);
		if (n > 0) {
			c->out_pos += (size_t)n;
			c->bytes_out += (uint64_t)n;
			continue;
		}
		if (n < 0 && errno == EINTR)
			continue;
		if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK))
			break;
		return -1;
	}
	if (c->out_pos == c->out.len) {
		c->out.len = 0;
		c->out_pos = 0;
	} else if (c->out_pos > (1u << 20) && c->out_pos * 2 > c->out.len) {
		memmove(c->out.p, c->out.p + c->out_pos, c->out.len - c->out_pos);
		c->out.len -= c->out_pos;
		c->out_pos = 0;
	}
	return 0;
}

/* Starts a frame: writes the header with a zero length; returns its offset. */
static size_t frame_begin(struct proto_conn *c, enum proto_type type)
{
	size_t at = c->out.len;
	proto_put_u32(&c->out, PROTO_MAGIC);
	proto_put_u16(&c->out, c->version);
	proto_put_u16(&c->out, (uint16_t)type);
	proto_put_u32(&c->out, 0);
	return at;
}

static int frame_end(struct proto_conn *c, size_t at)
{
	if (c->out.oom)
		return -1;
	proto_wr32(c->out.p + at + 8, (uint32_t)(c->out.len - at - PROTO_HEADER_BYTES));
	return 0;
}

int proto_send_hello(struct proto_conn *c, const struct proto_hello *h)
{
	size_t at = frame_begin(c, MSG_HELLO);
	proto_put_u32(&c->out, h->version);
	proto_put_u8(&c->out, h->role);
	proto_put_u8(&c->out, h->secret);
	proto_put_u16(&c->out, h->threads);
	proto_put_u32(&c->out, h->heartbeat_ms);
	proto_put_bytes(&c->out, h->nonce, PROTO_NONCE_BYTES);
	proto_put_str(&c->out, h->build);
	return frame_end(c, at);
}

int proto_send_auth(struct proto_conn *c, const uint8_t mac[PROTO_MAC_BYTES])
{
	size_t at = frame_begin(c, MSG_AUTH);
	proto_put_bytes(&c->out, mac, PROTO_MAC_BYTES);
	return frame_end(c, at);
}

int proto_send_offer(struct proto_conn *c, const uint8_t hash[PROTO_HASH_BYTES], uint64_t size, uint32_t w,
		     uint32_t h)
{
	size_t at = frame_begin(c, MSG_SCENE_OFFER);
	proto_put_bytes(&c->out, hash, PROTO_HASH_BYTES);
	proto_put_u64(&c->out, size);
	proto_put_u32(&c->out, w);
	proto_put_u32(&c->out, h);
	return frame_end(c, at);
}

int proto_send_hash(struct proto_conn *c, enum proto_type type, const uint8_t hash[PROTO_HASH_BYTES])
{
	size_t at = frame_begin(c, type);
	proto_put_bytes(&c->out, hash, PROTO_HASH_BYTES);
	return frame_end(c, at);
}

int proto_send_data(struct proto_conn *c, uint64_t offset, const uint8_t *p, uint32_t n)
{
	size_t at = frame_begin(c, MSG_SCENE_DATA);
	proto_put_u64(&c->out, offset);
	proto_put_bytes(&c->out, p, n);
	return frame_end(c, at);
}

int proto_send_ready(struct proto_conn *c, const uint8_t hash[PROTO_HASH_BYTES], bool cached, uint32_t build_ms)
{
	size_t at = frame_begin(c, MSG_SCENE_READY);
	proto_put_bytes(&c->out, hash, PROTO_HASH_BYTES);
	proto_put_u8(&c->out, cached ? 1 : 0);
	proto_put_u32(&c->out, build_ms);
	return frame_end(c, at);
}

static void put_tile(struct proto_wbuf *b, const struct proto_tile *t)
{
	proto_put_u32(b, t->id);
	proto_put_u32(b, t->x);
	proto_put_u32(b, t->y);
	proto_put_u32(b, t->w);
	proto_put_u32(b, t->h);
	proto_put_u8(b, t->px);
}

int proto_send_tile(struct proto_conn *c, const struct proto_tile *t)
{
	size_t at = frame_begin(c, MSG_TILE);
	put_tile(&c->out, t);
	return frame_end(c, at);
}

int proto_send_result(struct proto_conn *c, const struct proto_tile *t, const uint8_t *pixels, uint32_t crc)
{
	return proto_send_result_timed(c, t, pixels, crc, 0);
}

int proto_send_result_timed(struct proto_conn *c, const struct proto_tile *t, const uint8_t *pixels, uint32_t crc,
			    uint32_t trace_us)
{
	size_t at = frame_begin(c, MSG_TILE_RESULT);
	put_tile(&c->out, t);
	proto_put_u32(&c->out, crc);
	proto_put_u32(&c->out, trace_us);
	proto_put_bytes(&c->out, pixels, proto_tile_bytes(t));
	return frame_end(c, at);
}

int proto_send_heartbeat(struct proto_conn *c, uint32_t done, uint32_t queued)
{
	size_t at = frame_begin(c, MSG_HEARTBEAT);
	proto_put_u32(&c->out, done);
	proto_put_u32(&c->out, queued);
	return frame_end(c, at);
}

int proto_send_cancel(struct proto_conn *c, uint32_t id)
{
	size_t at = frame_begin(c, MSG_CANCEL);
	proto_put_u32(&c->out, id);
	return frame_end(c, at);
}

int proto_send_error(struct proto_conn *c, int code, const char *fmt, ...)
{
	char text[LIM_ERROR_TEXT + 1];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(text, sizeof text, fmt, ap);
	va_end(ap);
	size_t at = frame_begin(c, MSG_ERROR);
	proto_put_u16(&c->out, (uint16_t)code);
	proto_put_str(&c->out, text);
	return frame_end(c, at);
}

int proto_send_bye(struct proto_conn *c)
{
	size_t at = frame_begin(c, MSG_BYE);
	return frame_end(c, at);
}

int proto_read_secret(const char *path, uint8_t **out, size_t *len, char *err, size_t errlen, char *warn,
		      size_t warnlen)
{
	*out = NULL;
	*len = 0;
	if (warnlen)
		warn[0] = 0;
	/* O_NONBLOCK: a FIFO named by mistake must not hang the open */
	int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
	if (fd < 0) {
		snprintf(err, errlen, "%s: %s", path, strerror(errno));
		return -1;
	}
	struct stat st;
	if (fstat(fd, &st) < 0 || !S_ISREG(st.st_mode)) {
		snprintf(err, errlen, "%s: not a regular file", path);
		close(fd);
		return -1;
	}
	if (st.st_mode & (S_IRWXG | S_IRWXO))
		snprintf(warn, warnlen, "%s: readable by other users (mode %03o): chmod 600 it", path,
			 (unsigned)(st.st_mode & 0777));
	FILE *f = fdopen(fd, "rb");
	if (!f) {
		snprintf(err, errlen, "%s: %s", path, strerror(errno));
		close(fd);
		return -1;
	}
	uint8_t *buf = malloc(LIM_SECRET_BYTES + 1);
	if (!buf) {
		fclose(f);
		snprintf(err, errlen, "%s: out of memory", path);
		return -1;
	}
	size_t n = fread(buf, 1, LIM_SECRET_BYTES + 1, f);
	int rerr = ferror(f);
	fclose(f);
	if (rerr || n > LIM_SECRET_BYTES) {
		snprintf(err, errlen, "%s: %s", path, rerr ? "read error" : "secret longer than 4096 bytes");
		free(buf);
		return -1;
	}
	while (n > 0 && (buf[n - 1] == '\n' || buf[n - 1] == '\r'))
		n--;
	if (n == 0) {
		snprintf(err, errlen, "%s: the secret is empty", path);
		free(buf);
		return -1;
	}
	*out = buf;
	*len = n;
	return 0;
}
