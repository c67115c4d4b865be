/*
 * fakepeer.c - misbehaving farm peers, for tests of the master's and the
 * worker's deadlines (docs/protocol.md is the protocol they bend).
 *
 *   fakepeer worker --listen HOST:PORT [--port-file F] --mode MODE
 *                   [--secret | --secret-file F] [--heartbeat-ms N]
 *   fakepeer hold --to HOST:PORT --count N [--port-file-ready F] [--pause-ms N]
 *
 * worker: a fake portray-worker. It accepts any number of connections and
 * speaks the worker's side of the handshake (as worker/main.c does: a HELLO
 * at accept with PROTO_VERSION, ROLE_WORKER, proto_build_id(), 1 thread and
 * a fresh nonce; the master's AUTH checked and answered with proto_auth_mac;
 * SCENE_NEED for every offer; the scene received and its hash checked;
 * SCENE_READY) up to the stage where MODE makes it stop. Once its handshake
 * is done (protocol 2 allows no earlier ones) it sends HEARTBEATs every
 * --heartbeat-ms (100) ms, except `silent`; heartbeat-only sends nothing
 * else, from accept on. Modes
 * (the table `modes` below):
 *   silent          accepts, never sends anything
 *   heartbeat-only  HEARTBEATs only, never a HELLO
 *   stall-hello     a valid HELLO, then nothing
 *   stall-auth      a valid HELLO; never answers the master's AUTH (needs
 *                   --secret or --secret-file, so that the master sends one)
 *   stall-offer     the handshake (AUTH too with --secret-file), then never
 *                   answers the SCENE_OFFER
 *   stall-data      answers the offer with SCENE_NEED, then never reads the
 *                   socket again (HEARTBEATs go on)
 *   stall-build     receives the whole scene, never sends SCENE_READY
 *   stall-tile      SCENE_READY, then takes TILEs and never answers them
 *   wrong-type      SCENE_READY, then answers every TILE at once with black
 *                   pixels of the other pixel type (RGBF32 for RGB8 and back;
 *                   the checksum right): a protocol error for the master
 * --secret sets the HELLO's secret flag without knowing a secret (enough for
 * stall-hello and stall-auth); --secret-file F is a real one (F as for
 * portray-worker). It logs on stderr a line per connection accepted and
 * closed, and one per message received (HEARTBEATs counted, SCENE_DATA
 * summed); nothing it receives is refused, except a wrong AUTH proof.
 *
 * hold: opens N connections to a worker and keeps them open and idle (it
 * never sends a byte; what the worker sends is read and dropped); each one
 * the worker closes is opened again after --pause-ms (20) ms. Writes
 * --port-file-ready F (the number N) once all N are connected and the worker
 * has sent its first bytes (its HELLO) on each: then it has accepted them
 * all (a connect completes in the kernel before the worker accepts it).
 *
 * Both run until SIGTERM or SIGINT (exit 0). Usage errors exit 64.
 */
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "proto/net.h"
#include "proto/proto.h"
#include "tests/tools/stop.h"

/* the largest scene a fake worker buffers (it checks the hash over all of it) */
#define FP_SCENE_MAX (256u << 20)
/* connections held at most by `hold` */
#define FP_HOLD_MAX 4096
/* connections `hold` has opening at once (not yet greeted by the worker): below
 * the worker's listen backlog (64). A client that never sends and whose final
 * handshake ACK met a full accept queue can stay connected on its side and
 * unknown to the worker (SYN cookies): such limbo connections are never held */
#define FP_HOLD_OPENING 16
/* seconds a connection may wait for the worker's first bytes before it is opened again */
#define FP_HOLD_GREET_S 2.0

/* ---- common ---- */

static const char *role = "fakepeer";

static void fp_log(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static void fp_log(const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	fprintf(stderr, "fakepeer %s %.3f ", role, net_now());
	vfprintf(stderr, fmt, ap);
	fputc('\n', stderr);
	va_end(ap);
}

/* poll() timeout in ms until `at` (seconds, net_now's clock); -1 for INFINITY. */
static int ms_until(double at, double now)
{
	if (at == INFINITY)
		return -1;
	return at <= now ? 0 : (int)ceil((at - now) * 1000);
}

/* ---- fake worker ---- */

/* The worker's stages, in protocol order (worker/main.c's states). */
enum fp_stage { FS_HELLO, FS_AUTH, FS_OFFER, FS_RECV, FS_BUILD, FS_READY };
static const char *const stage_names[] = { "HELLO", "AUTH", "OFFER", "RECV", "BUILD", "READY" };

/* A mode: whether it sends a HELLO and heartbeats, and the stage it stops at
 * (it still reads and logs there, but never answers; FS_RECV stops reading). */
struct fp_mode {
	const char *name;
	bool hello, heartbeat;
	enum fp_stage stall;
	bool wrong_type; /* answers TILEs with the other pixel type (at its stall, READY) */
};

static const struct fp_mode modes[] = {
	{ "silent", false, false, FS_HELLO, false },
	{ "heartbeat-only", false, true, FS_HELLO, false },
	{ "stall-hello", true, true, FS_HELLO, false },
	{ "stall-auth", true, true, FS_AUTH, false },
	{ "stall-offer", true, true, FS_OFFER, false },
	{ "stall-data", true, true, FS_RECV, false },
	{ "stall-build", true, true, FS_BUILD, false },
	{ "stall-tile", true, true, FS_READY, false },
	{ "wrong-type", true, true, FS_READY, true },
};

static struct {
	const struct fp_mode *mode;
	bool secret_flag;
	uint8_t *secret;
	size_t secret_len;
	double hb_interval;
} wopt;

struct fp_conn {
	struct proto_conn *pc;
	char peer[96];
	enum fp_stage stage;
	bool reading;          /* false: the socket is never read again (stall-data) */
	double opened, next_hb;
	uint8_t nonce[PROTO_NONCE_BYTES], master_nonce[PROTO_NONCE_BYTES];
	uint8_t hash[PROTO_HASH_BYTES];
	uint64_t scene_size;
	uint8_t *scene;
	size_t scene_len, scene_cap;
	uint32_t n_data, n_heartbeats, n_tiles;
};

static struct fp_conn **conns;
static size_t n_conns, cap_conns;

static void conn_free(size_t i, const char *how)
{
	struct fp_conn *c = conns[i];
	fp_log("%s: closed (%s) after %.2f s at stage %s: %u heartbeats, %u scene chunks (%zu bytes), %u tiles received",
	       c->peer, how, net_now() - c->opened, stage_names[c->stage], c->n_heartbeats, c->n_data, c->scene_len,
	       c->n_tiles);
	proto_conn_free(c->pc);
	free(c->scene);
	free(c);
	conns[i] = conns[--n_conns];
}

static void send_hello(struct fp_conn *c)
{
	struct proto_hello h;
	memset(&h, 0, sizeof h);
	h.version = PROTO_VERSION;
	h.role = ROLE_WORKER;
	h.secret = wopt.secret_flag;
	h.threads = 1;
	memcpy(h.nonce, c->nonce, PROTO_NONCE_BYTES);
	snprintf(h.build, sizeof h.build, "%s", proto_build_id());
	proto_send_hello(c->pc, &h);
}

/* Scene bytes of one SCENE_DATA; at the end the hash is checked and the stage moves on. */
static int on_data(struct fp_conn *c, const struct proto_msg *m)
{
	c->n_data++;
	if (m->u.data.offset != c->scene_len || c->scene_len + m->u.data.n > c->scene_size) {
		fp_log("%s: SCENE_DATA at offset %llu out of order or past the offered size", c->peer,
		       (unsigned long long)m->u.data.offset);
		return 0;
	}
	if (c->scene_len + m->u.data.n > c->scene_cap) {
		size_t nc = c->scene_cap ? 2 * c->scene_cap : PROTO_CHUNK_BYTES;
		while (nc < c->scene_len + m->u.data.n)
			nc *= 2;
		uint8_t *p = realloc(c->scene, nc);
		if (!p) {
			fp_log("%s: out of memory for the scene", c->peer);
			return -1;
		}
		c->scene = p;
		c->scene_cap = nc;
	}
	memcpy(c->scene + c->scene_len, m->u.data.bytes, m->u.data.n);
	c->scene_len += m->u.data.n;
	if (c->scene_len < c->scene_size)
		return 0;
	uint8_t h[PROTO_HASH_BYTES];
	proto_scene_hash(c->scene, c->scene_len, h);
	bool ok = memcmp(h, c->hash, PROTO_HASH_BYTES) == 0;
	fp_log("%s: scene complete: %zu bytes in %u chunks, hash %s", c->peer, c->scene_len, c->n_data,
	       ok ? "ok" : "MISMATCH");
	c->stage = FS_BUILD;
	if (wopt.mode->stall != FS_BUILD) {
		proto_send_ready(c->pc, c->hash, false, 0);
		c->stage = FS_READY;
		fp_log("%s: sent SCENE_READY", c->peer);
	}
	return 0;
}

/*
 * One message from the master. Returns -1 when the connection must close
 * (the master's ERROR or BYE, a wrong proof).
 */
static int on_message(struct fp_conn *c, const struct proto_msg *m)
{
	switch (m->type) {
	case MSG_HEARTBEAT: c->n_heartbeats++; return 0;
	case MSG_ERROR:
		fp_log("%s: received ERROR (%s): %s", c->peer, proto_err_name(m->u.error.code), m->u.error.text);
		return -1;
	case MSG_BYE: fp_log("%s: received BYE", c->peer); return -1;
	case MSG_SCENE_DATA:
		if (c->stage == FS_RECV)
			return on_data(c, m);
		break;
	case MSG_HELLO:
		fp_log("%s: received HELLO (version %u, role %u, secret %u, heartbeat %u ms, build %s)", c->peer,
		       m->u.hello.version, m->u.hello.role, m->u.hello.secret, m->u.hello.heartbeat_ms,
		       m->u.hello.build);
		break;
	case MSG_SCENE_OFFER:
		fp_log("%s: received SCENE_OFFER (%llu bytes, %ux%u)", c->peer, (unsigned long long)m->u.offer.size,
		       m->u.offer.width, m->u.offer.height);
		break;
	case MSG_TILE:
		c->n_tiles++;
		fp_log("%s: received TILE %u (%u,%u %ux%u, %s pixels)", c->peer, m->u.tile.id, m->u.tile.x, m->u.tile.y,
		       m->u.tile.w, m->u.tile.h, m->u.tile.px ? "RGBF32" : "RGB8");
		if (wopt.mode->wrong_type && c->stage == FS_READY) {
			struct proto_tile t = m->u.tile;
			t.px = t.px ? 0 : 1;
			size_t n = proto_tile_bytes(&t);
			uint8_t *px = calloc(1, n);
			if (!px)
				return -1;
			proto_send_result(c->pc, &t, px, crc32_update(0, px, n));
			free(px);
			fp_log("%s: answered TILE %u with %s pixels", c->peer, t.id, t.px ? "RGBF32" : "RGB8");
		}
		break;
	default: fp_log("%s: received %s", c->peer, proto_type_name(m->type)); break;
	}
	if (c->stage == wopt.mode->stall) /* stalled here: nothing is answered */
		return 0;
	switch (c->stage) {
	case FS_HELLO:
		if (m->type != MSG_HELLO)
			break;
		memcpy(c->master_nonce, m->u.hello.nonce, PROTO_NONCE_BYTES);
		c->stage = wopt.secret_flag ? FS_AUTH : FS_OFFER;
		return 0;
	case FS_AUTH: {
		if (m->type != MSG_AUTH)
			break;
		uint8_t want[PROTO_MAC_BYTES];
		proto_auth_mac(wopt.secret, wopt.secret_len, ROLE_MASTER, c->master_nonce, c->nonce, want);
		if (!proto_mac_equal(want, m->u.mac, PROTO_MAC_BYTES)) {
			fp_log("%s: the master's proof is wrong: ERROR(auth) sent", c->peer);
			proto_send_error(c->pc, PERR_AUTH, "authentication failed: the master's secret differs");
			proto_conn_flush(c->pc);
			return -1;
		}
		proto_auth_mac(wopt.secret, wopt.secret_len, ROLE_WORKER, c->master_nonce, c->nonce, want);
		proto_send_auth(c->pc, want);
		fp_log("%s: the master's proof is right: AUTH sent", c->peer);
		c->stage = FS_OFFER;
		return 0;
	}
	case FS_OFFER:
		if (m->type != MSG_SCENE_OFFER)
			break;
		memcpy(c->hash, m->u.offer.hash, PROTO_HASH_BYTES);
		c->scene_size = m->u.offer.size;
		if (c->scene_size > FP_SCENE_MAX) {
			fp_log("%s: scene too large for a fake worker", c->peer);
			proto_send_error(c->pc, PERR_LIMIT, "scene too large for a fake worker");
			proto_conn_flush(c->pc);
			return -1;
		}
		proto_send_hash(c->pc, MSG_SCENE_NEED, c->hash);
		c->stage = FS_RECV;
		if (wopt.mode->stall == FS_RECV) {
			c->reading = false;
			fp_log("%s: sent SCENE_NEED; not reading any more", c->peer);
		} else {
			fp_log("%s: sent SCENE_NEED", c->peer);
		}
		return 0;
	default: break;
	}
	fp_log("%s: (%s not expected at stage %s: ignored)", c->peer, proto_type_name(m->type), stage_names[c->stage]);
	return 0;
}

/* Reads and handles what c has; -1 when it must close. */
static int conn_input(struct fp_conn *c)
{
	const char *why = NULL;
	if (proto_conn_read(c->pc, &why) < 0) {
		fp_log("%s: %s", c->peer, why ? why : "connection lost");
		return -1;
	}
	struct proto_msg m;
	int code;
	while (c->reading) {
		int k = proto_conn_next(c->pc, &m, &code, &why);
		if (k == 0)
			break;
		if (k < 0) {
			fp_log("%s: bad frame: %s (%s)", c->peer, why, proto_err_name(code));
			return -1;
		}
		if (on_message(c, &m) < 0)
			return -1;
	}
	return 0;
}

static void accept_all(int lfd, double now)
{
	for (;;) {
		char peer[96];
		int fd = net_accept(lfd, peer, sizeof peer);
		if (fd < 0)
			return;
		struct fp_conn *c = calloc(1, sizeof *c);
		if (n_conns == cap_conns) {
			size_t nc = cap_conns ? 2 * cap_conns : 16;
			struct fp_conn **p = realloc(conns, nc * sizeof *p);
			if (p) {
				conns = p;
				cap_conns = nc;
			}
		}
		if (!c || n_conns == cap_conns || !(c->pc = proto_conn_new(fd)) ||
		    proto_random(c->nonce, sizeof c->nonce) < 0) {
			fp_log("%s: refused: out of memory or no random source", peer);
			if (c && c->pc)
				proto_conn_free(c->pc);
			else
				close(fd);
			free(c);
			continue;
		}
		snprintf(c->peer, sizeof c->peer, "%s", peer);
		c->opened = now;
		c->reading = true;
		c->next_hb = now;
		if (wopt.mode->hello)
			send_hello(c);
		conns[n_conns++] = c;
		fp_log("%s: accepted (mode %s)", c->peer, wopt.mode->name);
	}
}

static int worker_loop(int lfd)
{
	struct pollfd *pfd = NULL;
	size_t cap = 0;
	while (!stop_flag) {
		double now = net_now(), next = INFINITY;
		for (size_t i = 0; i < n_conns;) {
			struct fp_conn *c = conns[i];
			/* heartbeats only where protocol 2 allows them (from the
			 * offer on), but for heartbeat-only, whose point they are */
			bool hb = wopt.mode->heartbeat && (!wopt.mode->hello || c->stage >= FS_OFFER);
			if (hb && now >= c->next_hb) {
				proto_send_heartbeat(c->pc, 0, c->n_tiles);
				c->next_hb = now + wopt.hb_interval;
			}
			if (hb && c->next_hb < next)
				next = c->next_hb;
			if (proto_conn_flush(c->pc) < 0) {
				conn_free(i, "the master is gone: a write failed");
				continue;
			}
			i++;
		}
		if (cap < n_conns + 2) {
			size_t nc = 2 * (n_conns + 2);
			struct pollfd *p = realloc(pfd, nc * sizeof *p);
			if (!p)
				break;
			pfd = p;
			cap = nc;
		}
		pfd[0] = (struct pollfd){ .fd = lfd, .events = POLLIN };
		pfd[1] = (struct pollfd){ .fd = wake_pipe[0], .events = POLLIN };
		for (size_t i = 0; i < n_conns; i++) {
			struct fp_conn *c = conns[i];
			short ev = (short)((c->reading ? POLLIN : 0) | (proto_conn_outq(c->pc) ? POLLOUT : 0));
			pfd[i + 2] = (struct pollfd){ .fd = ev ? proto_conn_fd(c->pc) : -1, .events = ev };
		}
		int k = poll(pfd, (nfds_t)(n_conns + 2), ms_until(next, now));
		if (k < 0 && errno != EINTR)
			break;
		if (k <= 0)
			continue;
		size_t nc = n_conns; /* new connections are polled from the next round */
		for (size_t i = nc; i-- > 0;) { /* backwards: conn_free moves the last one into i */
			if (pfd[i + 2].revents & (POLLIN | POLLHUP | POLLERR)) {
				struct fp_conn *c = conns[i];
				if (c->reading && conn_input(c) < 0)
					conn_free(i, "by the master or on its message");
			}
		}
		if (pfd[0].revents & POLLIN)
			accept_all(lfd, net_now());
	}
	while (n_conns)
		conn_free(n_conns - 1, "fakepeer shutting down");
	free(conns);
	free(pfd);
	return 0;
}

static int main_worker(int argc, char **argv)
{
	enum { OPT_LISTEN = 256, OPT_PORTFILE, OPT_MODE, OPT_SECRET, OPT_SECRET_FILE, OPT_HB };
	static const struct option longopts[] = {
		{ "listen", required_argument, NULL, OPT_LISTEN },
		{ "port-file", required_argument, NULL, OPT_PORTFILE },
		{ "mode", required_argument, NULL, OPT_MODE },
		{ "secret", no_argument, NULL, OPT_SECRET },
		{ "secret-file", required_argument, NULL, OPT_SECRET_FILE },
		{ "heartbeat-ms", required_argument, NULL, OPT_HB },
		{ NULL, 0, NULL, 0 },
	};
	const char *listen_at = NULL, *port_file = NULL, *secret_file = NULL, *mode = NULL;
	long hb_ms = 100;
	char *end;
	int c;
	while ((c = getopt_long(argc, argv, "", longopts, NULL)) != -1) {
		switch (c) {
		case OPT_LISTEN: listen_at = optarg; break;
		case OPT_PORTFILE: port_file = optarg; break;
		case OPT_MODE: mode = optarg; break;
		case OPT_SECRET: wopt.secret_flag = true; break;
		case OPT_SECRET_FILE: secret_file = optarg; break;
		case OPT_HB:
			hb_ms = strtol(optarg, &end, 10);
			if (*end || end == optarg || hb_ms < 1 || hb_ms > 600000) {
				fprintf(stderr, "fakepeer: --heartbeat-ms wants 1..600000\n");
				return 64;
			}
			break;
		default: return 64;
		}
	}
	for (size_t i = 0; mode && i < sizeof modes / sizeof *modes; i++)
		if (strcmp(mode, modes[i].name) == 0)
			wopt.mode = &modes[i];
	if (!wopt.mode || !listen_at || optind != argc) {
		fprintf(stderr, "fakepeer worker: --listen HOST:PORT and --mode MODE are required; modes:");
		for (size_t i = 0; i < sizeof modes / sizeof *modes; i++)
			fprintf(stderr, " %s", modes[i].name);
		fputc('\n', stderr);
		return 64;
	}
	char err[512], warn[512];
	if (secret_file) {
		if (proto_read_secret(secret_file, &wopt.secret, &wopt.secret_len, err, sizeof err, warn,
				      sizeof warn) < 0) {
			fprintf(stderr, "fakepeer: %s\n", err);
			return 64;
		}
		wopt.secret_flag = true;
	}
	if (wopt.mode->stall == FS_AUTH && !wopt.secret_flag) {
		fprintf(stderr, "fakepeer: --mode stall-auth needs --secret or --secret-file (else no AUTH comes)\n");
		return 64;
	}
	if (wopt.mode->stall > FS_AUTH && wopt.secret_flag && !wopt.secret) {
		fprintf(stderr, "fakepeer: --mode %s gets past AUTH: it needs --secret-file, not --secret\n", mode);
		return 64;
	}
	wopt.hb_interval = hb_ms / 1000.0;
	char host[NET_HOST_LEN], port[NET_PORT_LEN];
	if (net_parse_hostport(listen_at, host, port, err, sizeof err) < 0) {
		fprintf(stderr, "fakepeer: --listen: %s\n", err);
		return 64;
	}
	int lfd = net_listen(host, port, err, sizeof err);
	if (lfd < 0) {
		fprintf(stderr, "fakepeer: %s\n", err);
		return 69;
	}
	if (stop_init() < 0) {
		perror("fakepeer: pipe");
		return 71;
	}
	if (port_file && net_write_number(port_file, net_local_port(lfd)) < 0) {
		fprintf(stderr, "fakepeer: cannot write %s: %s\n", port_file, strerror(errno));
		return 73;
	}
	fp_log("listening on %s:%d, mode %s%s", host, net_local_port(lfd), wopt.mode->name,
	       wopt.secret ? ", secret" : wopt.secret_flag ? ", secret flag only" : "");
	int rc = worker_loop(lfd);
	close(lfd);
	free(wopt.secret);
	return rc;
}

/* ---- hold: idle connections to a worker ---- */

struct fp_slot {
	struct proto_conn *pc; /* NULL: waiting for retry_at */
	bool connecting;
	bool greeted;          /* the worker's first bytes arrived: it accepted the connection */
	double retry_at, opened;
	char said[LIM_ERROR_TEXT + 32]; /* the worker's ERROR, if any */
};

static int hold_loop(const char *host, const char *port, struct fp_slot *s, long n, const char *ready_file,
		     double pause)
{
	struct pollfd *pfd = calloc((size_t)n + 1, sizeof *pfd);
	if (!pfd)
		return 71;
	bool ready_written = false;
	unsigned long reopened = 0;
	while (!stop_flag) {
		double now = net_now(), next = INFINITY;
		long connected = 0, opening = 0;
		for (long i = 0; i < n; i++) {
			struct fp_slot *sl = &s[i];
			if (sl->pc && !sl->greeted && now - sl->opened > FP_HOLD_GREET_S) {
				fp_log("connection %ld: not accepted by the worker within %.0f s; opened again", i,
				       FP_HOLD_GREET_S);
				proto_conn_free(sl->pc);
				sl->pc = NULL;
				sl->retry_at = now;
				reopened++;
			}
			opening += sl->pc && !sl->greeted;
		}
		for (long i = 0; i < n; i++) {
			struct fp_slot *sl = &s[i];
			if (!sl->pc && now >= sl->retry_at && opening < FP_HOLD_OPENING) {
				char err[300];
				int fd = net_connect_start(host, port, err, sizeof err);
				if (fd >= 0 && !(sl->pc = proto_conn_new(fd)))
					close(fd);
				if (!sl->pc) {
					fp_log("connection %ld: %s", i, fd < 0 ? err : "out of memory");
					sl->retry_at = now + pause;
				} else {
					sl->connecting = true;
					sl->greeted = false;
					sl->opened = now;
					sl->said[0] = 0;
					opening++;
				}
			}
			/* (a slot waiting for room to open is woken by a greeting or a timeout) */
			if (!sl->pc && sl->retry_at > now && sl->retry_at < next)
				next = sl->retry_at;
			if (sl->pc && !sl->greeted && sl->opened + FP_HOLD_GREET_S < next)
				next = sl->opened + FP_HOLD_GREET_S;
			connected += sl->pc && sl->greeted;
		}
		if (connected == n && !ready_written) {
			fp_log("all %ld connections open (the worker greeted each)", n);
			if (ready_file && net_write_number(ready_file, n) < 0)
				fp_log("cannot write %s: %s", ready_file, strerror(errno));
			ready_written = true;
		}
		pfd[0] = (struct pollfd){ .fd = wake_pipe[0], .events = POLLIN };
		for (long i = 0; i < n; i++) {
			short ev = s[i].pc ? (s[i].connecting ? POLLOUT : POLLIN) : 0;
			pfd[i + 1] = (struct pollfd){ .fd = ev ? proto_conn_fd(s[i].pc) : -1, .events = ev };
		}
		int k = poll(pfd, (nfds_t)n + 1, ms_until(next, now));
		if (k < 0 && errno != EINTR)
			break;
		now = net_now();
		for (long i = 0; k > 0 && i < n; i++) {
			struct fp_slot *sl = &s[i];
			if (!sl->pc || !pfd[i + 1].revents)
				continue;
			const char *why = "closed by the worker";
			char err[300];
			if (sl->connecting) {
				if (net_connect_finish(proto_conn_fd(sl->pc), err, sizeof err) == 0) {
					sl->connecting = false;
					continue;
				}
				why = err;
			} else if (proto_conn_read(sl->pc, &why) >= 0) {
				/* the worker's HELLO, maybe an ERROR: dropped, the ERROR kept for the log.
				 * Only its first bytes show that the worker took the connection (a
				 * connect completes in the kernel's accept queue before that) */
				sl->greeted = true;
				struct proto_msg m;
				int code;
				while (proto_conn_next(sl->pc, &m, &code, &why) > 0)
					if (m.type == MSG_ERROR)
						snprintf(sl->said, sizeof sl->said, ": worker says: %s (%s)", m.u.error.text,
							 proto_err_name(m.u.error.code));
				continue;
			}
			if (!why)
				why = "closed by the worker";
			fp_log("connection %ld: %s after %.2f s%s; again in %.0f ms", i, why,
			       now - sl->opened, sl->said, pause * 1000);
			proto_conn_free(sl->pc);
			sl->pc = NULL;
			sl->retry_at = now + pause;
			reopened++;
		}
	}
	fp_log("stopping: %lu connections were opened again", reopened);
	for (long i = 0; i < n; i++)
		proto_conn_free(s[i].pc);
	free(pfd);
	return 0;
}

static int main_hold(int argc, char **argv)
{
	enum { OPT_TO = 256, OPT_COUNT, OPT_READY, OPT_PAUSE };
	static const struct option longopts[] = {
		{ "to", required_argument, NULL, OPT_TO },
		{ "count", required_argument, NULL, OPT_COUNT },
		{ "port-file-ready", required_argument, NULL, OPT_READY },
		{ "pause-ms", required_argument, NULL, OPT_PAUSE },
		{ NULL, 0, NULL, 0 },
	};
	const char *to = NULL, *ready = NULL;
	long count = 0, pause_ms = 20;
	char *end;
	int c;
	while ((c = getopt_long(argc, argv, "", longopts, NULL)) != -1) {
		switch (c) {
		case OPT_TO: to = optarg; break;
		case OPT_READY: ready = optarg; break;
		case OPT_COUNT:
			count = strtol(optarg, &end, 10);
			if (*end || end == optarg || count < 1 || count > FP_HOLD_MAX) {
				fprintf(stderr, "fakepeer: --count wants 1..%d\n", FP_HOLD_MAX);
				return 64;
			}
			break;
		case OPT_PAUSE:
			pause_ms = strtol(optarg, &end, 10);
			if (*end || end == optarg || pause_ms < 0 || pause_ms > 600000) {
				fprintf(stderr, "fakepeer: --pause-ms wants 0..600000\n");
				return 64;
			}
			break;
		default: return 64;
		}
	}
	if (!to || count < 1 || optind != argc) {
		fprintf(stderr, "fakepeer hold: --to HOST:PORT and --count N are required\n");
		return 64;
	}
	char host[NET_HOST_LEN], port[NET_PORT_LEN], err[300];
	if (net_parse_hostport(to, host, port, err, sizeof err) < 0) {
		fprintf(stderr, "fakepeer: --to: %s\n", err);
		return 64;
	}
	if (stop_init() < 0) {
		perror("fakepeer: pipe");
		return 71;
	}
	struct fp_slot *s = calloc((size_t)count, sizeof *s);
	if (!s)
		return 71;
	fp_log("holding %ld idle connections to %s", count, to);
	int rc = hold_loop(host, port, s, count, ready, pause_ms / 1000.0);
	free(s);
	return rc;
}

static void usage(FILE *f)
{
	fprintf(f, "Usage: fakepeer worker --listen HOST:PORT [--port-file F] --mode MODE\n"
		   "                       [--secret | --secret-file F] [--heartbeat-ms N]\n"
		   "       fakepeer hold --to HOST:PORT --count N [--port-file-ready F] [--pause-ms N]\n"
		   "MODE:");
	for (size_t i = 0; i < sizeof modes / sizeof *modes; i++)
		fprintf(f, " %s", modes[i].name);
	fputc('\n', f);
}

int main(int argc, char **argv)
{
	if (argc >= 2 && strcmp(argv[1], "worker") == 0) {
		role = "worker";
		return main_worker(argc - 1, argv + 1);
	}
	if (argc >= 2 && strcmp(argv[1], "hold") == 0) {
		role = "hold";
		return main_hold(argc - 1, argv + 1);
	}
	if (argc >= 2 && (strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "--help") == 0)) {
		usage(stdout);
		return 0;
	}
	usage(stderr);
	return 64;
}
