/*
 * test_proto_peer.c - a real portray-worker (bin/portray-worker, started
 * here on an OS-chosen port) against hostile and broken peers speaking raw
 * frames: each gets an ERROR with the right code and is closed, and the
 * worker goes on serving; then a whole job over the raw protocol (in
 * protocol 2's flights: offer behind HELLO, tiles behind the scene) returns
 * the same pixels as the local renderer. Floods of idle connections cannot
 * keep a master out; heartbeats come at the agreed interval; a master that
 * leaves frees its tracer; SIGTERM ends the worker within a second, even
 * mid-tile, with status 0.
 */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "common/parse.h"
#include "common/render.h"
#include "proto/net.h"
#include "proto/proto.h"
#include "proto/serial.h"
#include "scene_fixture.h"
#include "tests/unit/rss.h"

#if defined(__SANITIZE_ADDRESS__)
#define RSS_BOUND_KIB (40 * 1024)
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RSS_BOUND_KIB (40 * 1024)
#endif
#endif
#ifndef RSS_BOUND_KIB
#define RSS_BOUND_KIB (20 * 1024) /* a worker with back-pressure stays well below */
#endif

static char port[16];

/* A worker started for one test, with its own port file. */
struct test_worker {
	pid_t pid;
	char pf[64];
	char saved[16]; /* the port `port` held before */
};

/*
 * Starts bin/portray-worker on 127.0.0.1:0 with `-j threads` and the extra
 * arguments (NULL-terminated), stderr to /dev/null (or $PEER_WORKER_LOG),
 * at most max_fds open descriptors when max_fds > 0; waits for its port
 * file and points `port`
 * (which dial() and hello() use) at it. Returns 0, or -1 when the worker
 * reported no port. worker_stop() ends it and restores `port`.
 */
static int worker_start(struct test_worker *w, int max_fds, const char *threads, const char *const *extra)
{
	snprintf(w->pf, sizeof w->pf, "/tmp/portray-peer-XXXXXX");
	int fd = mkstemp(w->pf);
	if (fd >= 0)
		close(fd);
	unlink(w->pf);
	const char *argv[32] = { "portray-worker", "--listen", "127.0.0.1:0", "--port-file", w->pf, "-j", threads };
	int n = 7;
	for (int i = 0; extra && extra[i] && n < 31; i++)
		argv[n++] = extra[i];
	w->pid = fork();
	if (w->pid == 0) {
		if (max_fds > 0) {
			struct rlimit rl = { (rlim_t)max_fds, (rlim_t)max_fds };
			setrlimit(RLIMIT_NOFILE, &rl);
		}
		/* PEER_WORKER_LOG=F keeps the workers' logs (a sanitizer's reports) */
		const char *keep = getenv("PEER_WORKER_LOG");
		int out = open(keep ? keep : "/dev/null", O_WRONLY | O_CREAT | O_APPEND, 0644);
		dup2(out, 2);
		close(out);
		execv("bin/portray-worker", (char *const *)argv);
		_exit(127);
	}
	memcpy(w->saved, port, sizeof w->saved);
	port[0] = 0;
	for (int i = 0; i < 200 && !port[0]; i++) {
		FILE *f = fopen(w->pf, "r");
		if (f) {
			if (fscanf(f, "%15s", port) != 1)
				port[0] = 0;
			fclose(f);
		}
		if (!port[0])
			usleep(20000);
	}
	return port[0] ? 0 : -1;
}

/* SIGTERM, reap (checking a clean exit 0), remove the port file, restore `port`. */
static void worker_stop(struct test_worker *w)
{
	int st = -1;
	kill(w->pid, SIGTERM);
	waitpid(w->pid, &st, 0);
	CHECK(WIFEXITED(st) && WEXITSTATUS(st) == 0);
	unlink(w->pf);
	memcpy(port, w->saved, sizeof port);
}

static struct proto_conn *dial(void)
{
	char err[300];
	int fd = net_connect_start("127.0.0.1", port, err, sizeof err);
	if (fd < 0)
		return NULL;
	struct pollfd p = { fd, POLLOUT, 0 };
	poll(&p, 1, 2000);
	if (net_connect_finish(fd, err, sizeof err) < 0) {
		close(fd);
		return NULL;
	}
	return proto_conn_new(fd);
}

/* Next message within 5 s: 1, or 0 on EOF/timeout/garbage. */
static int next_msg(struct proto_conn *c, struct proto_msg *m)
{
	double until = net_now() + 5;
	for (;;) {
		int code;
		const char *why;
		int k = proto_conn_next(c, m, &code, &why);
		if (k != 0)
			return k > 0;
		proto_conn_flush(c);
		struct pollfd p = { proto_conn_fd(c), POLLIN, 0 };
		if (net_now() > until || poll(&p, 1, 100) < 0)
			return 0;
		if (proto_conn_read(c, &why) < 0)
			return 0;
	}
}

/* The next message that is not a HEARTBEAT, within `seconds`: 1, or 0. */
static int next_real_within(struct proto_conn *c, struct proto_msg *m, double seconds)
{
	double until = net_now() + seconds;
	while (net_now() < until) {
		int code;
		const char *why;
		int k;
		while ((k = proto_conn_next(c, m, &code, &why)) == 1)
			if (m->type != MSG_HEARTBEAT)
				return 1;
		struct pollfd p = { proto_conn_fd(c), POLLIN, 0 };
		if (k < 0 || poll(&p, 1, 20) < 0 || ((p.revents & POLLIN) && proto_conn_read(c, &why) < 0))
			return 0;
	}
	return 0;
}

/* The next message that is not a HEARTBEAT. */
static int next_real(struct proto_conn *c, struct proto_msg *m)
{
	while (next_msg(c, m))
		if (m->type != MSG_HEARTBEAT)
			return 1;
	return 0;
}

/* Expects an ERROR with code, then EOF. */
static int expect_error(struct proto_conn *c, int code, const char *text)
{
	struct proto_msg m;
	int ok = next_real(c, &m) && m.type == MSG_ERROR && m.u.error.code == code &&
		 (!text || strstr(m.u.error.text, text));
	if (!ok)
		fprintf(stderr, "expected error %d '%s', got type %d code %d '%s'\n", code, text ? text : "",
			m.type, m.type == MSG_ERROR ? m.u.error.code : 0, m.type == MSG_ERROR ? m.u.error.text : "");
	ok = ok && !next_real(c, &m); /* then closed */
	return ok;
}

/* Queues a master's HELLO (not flushed: something may follow in the same
 * flight). */
static void queue_hello(struct proto_conn *c, uint8_t role, uint32_t version, uint32_t heartbeat_ms, bool secret,
			const uint8_t nonce[PROTO_NONCE_BYTES])
{
	struct proto_hello h;
	memset(&h, 0, sizeof h);
	h.version = version;
	h.role = role;
	h.secret = secret;
	h.heartbeat_ms = heartbeat_ms;
	if (nonce)
		memcpy(h.nonce, nonce, sizeof h.nonce);
	snprintf(h.build, sizeof h.build, "%s", proto_build_id());
	proto_send_hello(c, &h);
}

/* Dials and sends a master's HELLO (role, version, heartbeat interval, no
 * secret) once the worker's HELLO arrived. NULL when it did not. */
static struct proto_conn *hello_hb(uint8_t role, uint32_t version, uint32_t heartbeat_ms)
{
	struct proto_conn *c = dial();
	if (!c)
		return NULL;
	struct proto_msg m;
	if (!next_real(c, &m) || m.type != MSG_HELLO) {
		proto_conn_free(c);
		return NULL;
	}
	queue_hello(c, role, version, heartbeat_ms, false, NULL);
	proto_conn_flush(c);
	return c;
}

static struct proto_conn *hello(uint8_t role, uint32_t version) { return hello_hb(role, version, 200); }

/* Whether c has been told ERROR(code) by now (reads what has arrived, without waiting). */
static int told_error(struct proto_conn *c, int code)
{
	struct proto_msg m;
	const char *why;
	int k, ecode;
	for (;;) {
		while ((k = proto_conn_next(c, &m, &ecode, &why)) == 1)
			if (m.type == MSG_ERROR)
				return m.u.error.code == code;
		struct pollfd p = { proto_conn_fd(c), POLLIN, 0 };
		if (k < 0 || poll(&p, 1, 0) <= 0 || proto_conn_read(c, &why) < 0)
			return 0;
	}
}

/*
 * The authenticated handshake of a master with secret key on a fresh
 * connection, in protocol 2's flights and as portray-master does it: HELLO
 * at once; then, with the worker's nonce, AUTH and the scene offer
 * together. Returns 1 when the worker's proof came back and was right.
 */
static int secret_handshake(struct proto_conn *c, const char *key, const uint8_t hash[32], uint64_t len, uint32_t w,
			    uint32_t h)
{
	struct proto_msg m;
	uint8_t wnonce[PROTO_NONCE_BYTES], mnonce[PROTO_NONCE_BYTES], mac[PROTO_MAC_BYTES];
	memset(mnonce, 9, sizeof mnonce);
	queue_hello(c, ROLE_MASTER, PROTO_VERSION, 200, true, mnonce);
	proto_conn_flush(c);
	if (!next_real(c, &m) || m.type != MSG_HELLO || !m.u.hello.secret)
		return 0;
	memcpy(wnonce, m.u.hello.nonce, sizeof wnonce);
	proto_auth_mac((const uint8_t *)key, strlen(key), ROLE_MASTER, mnonce, wnonce, mac);
	proto_send_auth(c, mac);
	proto_send_offer(c, hash, len, w, h);
	proto_conn_flush(c);
	proto_auth_mac((const uint8_t *)key, strlen(key), ROLE_WORKER, mnonce, wnonce, mac);
	return next_real(c, &m) && m.type == MSG_AUTH && proto_mac_equal(m.u.mac, mac, sizeof mac);
}

/*
 * The rest of a job on c, whose offer of scene enc (hash, w x h) was sent:
 * the bytes if the worker needs them, the n tiles pipelined behind them
 * (protocol 2: queued while the scene builds), then SCENE_READY (its cached
 * flag in *cached when not NULL) strictly before the results, and every
 * result equal to r's pixels with the right checksum. 1 when all holds.
 */
static int run_job(struct proto_conn *c, const uint8_t *enc, size_t len, const struct renderer *r,
		   const struct proto_tile *tiles, int n, int *cached)
{
	struct proto_msg m;
	if (!next_real(c, &m) || (m.type != MSG_SCENE_NEED && m.type != MSG_SCENE_HAVE))
		return 0;
	if (m.type == MSG_SCENE_NEED)
		for (size_t off = 0; off < len; off += 1000)
			proto_send_data(c, off, enc + off, (uint32_t)(len - off < 1000 ? len - off : 1000));
	for (int i = 0; i < n; i++)
		proto_send_tile(c, &tiles[i]);
	proto_conn_flush(c);
	if (!next_real(c, &m) || m.type != MSG_SCENE_READY) {
		fprintf(stderr, "run_job: expected SCENE_READY, got %s\n", proto_type_name(m.type));
		return 0;
	}
	if (cached)
		*cached = m.u.ready.cached;
	int same = 0;
	for (int got = 0; got < n; got++) {
		if (!next_real(c, &m) || m.type != MSG_TILE_RESULT)
			return 0;
		const struct proto_tile *t = &m.u.result.tile;
		uint8_t px[16 * 16 * RENDER_PIXEL_MAX_BYTES];
		struct tile_rect rect = { t->x, t->y, t->w, t->h };
		size_t bytes = proto_tile_bytes(t);
		if (bytes > sizeof px)
			return 0;
		renderer_tile_px(r, rect, (enum render_pixel)t->px, px, NULL);
		for (int i = 0; i < n; i++)
			same += t->id == tiles[i].id && memcmp(px, m.u.result.pixels, bytes) == 0 &&
				crc32_update(0, px, bytes) == m.u.result.crc;
	}
	return same == n;
}

/* Open file descriptors of process pid (Linux /proc), or -1. */
static int count_fds(pid_t pid)
{
	char path[64];
	snprintf(path, sizeof path, "/proc/%d/fd", (int)pid);
	DIR *d = opendir(path);
	if (!d)
		return -1;
	int n = 0;
	struct dirent *e;
	while ((e = readdir(d)))
		n += e->d_name[0] != '.';
	closedir(d);
	return n;
}

/* CPU time (user + system, clock ticks) used so far by process pid, or -1. */
static long cpu_ticks(pid_t pid)
{
	char path[64], buf[1024];
	snprintf(path, sizeof path, "/proc/%d/stat", (int)pid);
	FILE *f = fopen(path, "r");
	if (!f)
		return -1;
	size_t n = fread(buf, 1, sizeof buf - 1, f);
	fclose(f);
	buf[n] = 0;
	char *p = strrchr(buf, ')'); /* fields after the command name */
	unsigned long ut, st;
	if (!p || sscanf(p + 2, "%*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %lu %lu", &ut, &st) != 2)
		return -1;
	return (long)(ut + st);
}

/*
 * A worker out of file descriptors (RLIMIT_NOFILE 16) under a flood of
 * connections: accept() fails with EMFILE while the listening socket stays
 * readable; the worker must not spin on it, and serves again afterwards.
 */
static void test_out_of_fds(void)
{
	struct test_worker w;
	CHECK(worker_start(&w, 16, "1", NULL) == 0);
	pid_t pid = w.pid;
	enum { N = 40 };
	struct proto_conn *cs[N];
	for (int i = 0; i < N; i++)
		cs[i] = dial(); /* the kernel's backlog takes them all */
	usleep(300000);
	long t0 = cpu_ticks(pid);
	usleep(1500000);
	long t1 = cpu_ticks(pid);
	/* a busy loop burns ~150 ticks here; an idle worker about none */
	CHECK(t0 >= 0 && t1 - t0 < 40);
	if (t1 - t0 >= 40)
		fprintf(stderr, "worker out of fds used %ld ticks in 1.5 s\n", t1 - t0);
	for (int i = 0; i < N; i++)
		proto_conn_free(cs[i]);
	struct proto_conn *c = NULL;
	for (int i = 0; i < 100 && !c; i++) { /* served again */
		c = hello(ROLE_MASTER, PROTO_VERSION);
		if (!c)
			usleep(50000);
	}
	CHECK(c != NULL);
	proto_conn_free(c);
	worker_stop(&w);
}

/*
 * A worker with a shared secret: before the master's proof is checked it acts
 * on nothing else. A scene offer instead of AUTH is refused unparsed, a scene
 * chunk is refused from its header (longer than a handshake frame), a
 * heartbeat is out of turn, and a wrong proof is ERROR(auth); the right one
 * gets the worker's proof back.
 */
static void test_secret_first(void)
{
	char sf[] = "/tmp/portray-peer-key-XXXXXX";
	int fd = mkstemp(sf);
	CHECK(fd >= 0 && write(fd, "k3y\n", 4) == 4);
	close(fd);
	const char *const extra[] = { "--secret-file", sf, NULL };
	struct test_worker w;
	CHECK(worker_start(&w, 0, "1", extra) == 0);
	struct proto_msg m;
	uint8_t hash[32] = { 3 }, chunk[2000] = { 0 };
	for (int round = 0; round < 5; round++) {
		struct proto_conn *c = dial();
		CHECK(c != NULL);
		if (!c)
			break;
		uint8_t wnonce[PROTO_NONCE_BYTES] = { 0 };
		CHECK(next_real(c, &m) && m.type == MSG_HELLO && m.u.hello.secret == 1);
		memcpy(wnonce, m.u.hello.nonce, sizeof wnonce);
		struct proto_hello h;
		memset(&h, 0, sizeof h);
		h.version = PROTO_VERSION;
		h.role = ROLE_MASTER;
		h.secret = 1;
		h.heartbeat_ms = 200;
		memset(h.nonce, 7, sizeof h.nonce);
		snprintf(h.build, sizeof h.build, "%s", proto_build_id());
		proto_send_hello(c, &h);
		uint8_t mac[PROTO_MAC_BYTES];
		if (round == 0) { /* an offer instead of the proof */
			proto_send_offer(c, hash, 100, 64, 48);
			proto_conn_flush(c);
			CHECK(expect_error(c, PERR_PROTOCOL, "unexpected SCENE_OFFER"));
		} else if (round == 1) { /* scene bytes instead of the proof */
			proto_send_data(c, 0, chunk, sizeof chunk);
			proto_conn_flush(c);
			CHECK(expect_error(c, PERR_LIMIT, NULL));
		} else if (round == 2) { /* a proof under another key */
			proto_auth_mac((const uint8_t *)"k3Y", 3, ROLE_MASTER, h.nonce, wnonce, mac);
			proto_send_auth(c, mac);
			proto_conn_flush(c);
			CHECK(expect_error(c, PERR_AUTH, "authentication failed"));
		} else if (round == 3) { /* a heartbeat is no proof of anything before the proof */
			proto_send_heartbeat(c, 0, 0);
			proto_conn_flush(c);
			CHECK(expect_error(c, PERR_PROTOCOL, "unexpected HEARTBEAT"));
		} else { /* the right proof: the worker proves itself in turn */
			proto_auth_mac((const uint8_t *)"k3y", 3, ROLE_MASTER, h.nonce, wnonce, mac);
			proto_send_auth(c, mac);
			proto_conn_flush(c);
			uint8_t want[PROTO_MAC_BYTES];
			proto_auth_mac((const uint8_t *)"k3y", 3, ROLE_WORKER, h.nonce, wnonce, want);
			CHECK(next_real(c, &m) && m.type == MSG_AUTH && proto_mac_equal(m.u.mac, want, sizeof want));
		}
		proto_conn_free(c);
	}
	worker_stop(&w);
	unlink(sf);
}

/*
 * Slowloris: a peer that trickles a HELLO one byte at a time (each byte a
 * sign of life at the socket level, never a whole frame) is cut off at the
 * handshake deadline with ERROR(timeout). The worker here gets 1 s.
 */
static void test_slow_handshake(void)
{
	const char *const extra[] = { "--test-handshake-ms", "1000", NULL };
	struct test_worker w;
	CHECK(worker_start(&w, 0, "1", extra) == 0);
	struct proto_conn *c = dial();
	CHECK(c != NULL);
	struct proto_msg m;
	int got_error = 0;
	if (c && next_real(c, &m) && m.type == MSG_HELLO) {
		uint8_t hdr[12]; /* a HELLO header announcing 100 bytes, then zeros */
		proto_wr32(hdr, PROTO_MAGIC), proto_wr16(hdr + 4, 1), proto_wr16(hdr + 6, MSG_HELLO);
		proto_wr32(hdr + 8, 100);
		double until = net_now() + 30; /* generous: the deadline is 1 s */
		for (int i = 0; i < 12 + 100 && net_now() < until && !got_error; i++) {
			uint8_t b = i < 12 ? hdr[i] : 0;
			if (send(proto_conn_fd(c), &b, 1, MSG_NOSIGNAL) != 1)
				break;
			struct pollfd p = { proto_conn_fd(c), POLLIN, 0 };
			if (poll(&p, 1, 200) > 0) {
				const char *why;
				int code;
				if (proto_conn_read(c, &why) < 0)
					break;
				while (proto_conn_next(c, &m, &code, &why) == 1)
					if (m.type == MSG_ERROR && m.u.error.code == PERR_TIMEOUT)
						got_error = 1;
			}
		}
	}
	CHECK(got_error);
	proto_conn_free(c);
	worker_stop(&w);
}

/*
 * Back-pressure: a master that queues 1000 tiles of 128x128 (48 MiB of
 * results) and reads nothing. The worker pauses the job once about
 * PROTO_OUT_HIGH_WATER of results wait, so its memory stays far below the
 * 48 MiB; when the master reads again every result arrives, checked.
 */
static void test_back_pressure(pid_t pid)
{
	static const char text[] = "image xsize 16 ysize 16 ;\n"; /* empty: tiles cost next to nothing */
	struct scene *s = NULL;
	struct scene_error err;
	uint8_t *enc = NULL, hash[32];
	size_t len = 0;
	CHECK(parse_buffer("bp.sce", text, sizeof text - 1, 0, &s, &err) == 0);
	CHECK(s && proto_scene_encode(s, &enc, &len) == 0);
	scene_free(s);
	if (!enc)
		return;
	proto_scene_hash(enc, len, hash);
	struct proto_conn *c = hello(ROLE_MASTER, PROTO_VERSION);
	struct proto_msg m;
	CHECK(c != NULL);
	if (!c) {
		free(enc);
		return;
	}
	proto_send_offer(c, hash, len, 1024, 1024);
	CHECK(next_real(c, &m) && (m.type == MSG_SCENE_NEED || m.type == MSG_SCENE_HAVE));
	if (m.type == MSG_SCENE_NEED)
		proto_send_data(c, 0, enc, (uint32_t)len);
	free(enc);
	CHECK(next_real(c, &m) && m.type == MSG_SCENE_READY);
	long rss0 = rss_kib(pid);
	enum { N = 1000, SIDE = 128 };
	for (uint32_t i = 0; i < N; i++) {
		struct proto_tile t = { i, (i % 8) * SIDE, (i / 8 % 8) * SIDE, SIDE, SIDE, RENDER_RGB8 };
		proto_send_tile(c, &t);
	}
	while (proto_conn_outq(c) > 0) { /* the tiles go out; nothing is read */
		struct pollfd p = { proto_conn_fd(c), POLLOUT, 0 };
		poll(&p, 1, 100);
		proto_conn_flush(c);
	}
	/* wait until the worker's memory settles (it pauses, or finishes all) */
	long prev = -1, rss1 = rss_kib(pid);
	for (int stable = 0, i = 0; i < 200 && stable < 5; i++) {
		usleep(100000);
		prev = rss1;
		rss1 = rss_kib(pid);
		stable = rss1 == prev ? stable + 1 : 0;
	}
	/* AddressSanitizer's quarantine keeps freed blocks resident, so under it
	 * RSS measures allocations, not live bytes: the bound is loosened there
	 * (the worker without back-pressure grows by 44 MiB even without ASan). */
	CHECK(rss0 > 0 && rss1 > 0 && rss1 - rss0 < RSS_BOUND_KIB);
	if (rss1 - rss0 >= RSS_BOUND_KIB)
		fprintf(stderr, "worker grew by %ld KiB with a master that does not read\n", rss1 - rss0);
	/* now read: every tile arrives, with the right checksum */
	uint32_t got = 0, good = 0;
	while (got < N && next_real(c, &m) && m.type == MSG_TILE_RESULT) {
		size_t n = proto_tile_bytes(&m.u.result.tile);
		good += m.u.result.tile.w == SIDE && crc32_update(0, m.u.result.pixels, n) == m.u.result.crc;
		got++;
	}
	CHECK(got == N && good == N);
	proto_conn_free(c);
}

/*
 * Heartbeats (protocol 2): the worker sends them at the interval the
 * master's HELLO asked for, with no clamp (200 ms: several in a second;
 * 60 s: none), from its HELLO on when there is no secret; before that a
 * heartbeat is out of turn, and an interval outside the bounds is refused.
 */
static void test_heartbeats(void)
{
	struct proto_msg m;
	struct proto_conn *c = dial();
	CHECK(c && next_real(c, &m) && m.type == MSG_HELLO);
	if (c) {
		proto_send_heartbeat(c, 0, 0);
		proto_conn_flush(c);
		CHECK(expect_error(c, PERR_PROTOCOL, "unexpected HEARTBEAT"));
		proto_conn_free(c);
	}
	c = hello_hb(ROLE_MASTER, PROTO_VERSION, PROTO_HB_MIN_MS - 1);
	CHECK(c && expect_error(c, PERR_PROTOCOL, "heartbeat interval"));
	proto_conn_free(c);

	struct proto_conn *fast = hello_hb(ROLE_MASTER, PROTO_VERSION, 200);
	struct proto_conn *slow = hello_hb(ROLE_MASTER, PROTO_VERSION, 60000);
	CHECK(fast && slow);
	if (!fast || !slow) {
		proto_conn_free(fast);
		proto_conn_free(slow);
		return;
	}
	int n[2] = { 0, 0 };
	struct proto_conn *cs[2] = { fast, slow };
	double until = net_now() + 1.0;
	while (net_now() < until) {
		struct pollfd p[2] = { { proto_conn_fd(fast), POLLIN, 0 }, { proto_conn_fd(slow), POLLIN, 0 } };
		if (poll(p, 2, 50) <= 0)
			continue;
		for (int i = 0; i < 2; i++) {
			const char *why;
			int code;
			if (!(p[i].revents & POLLIN) || proto_conn_read(cs[i], &why) < 0)
				continue;
			while (proto_conn_next(cs[i], &m, &code, &why) == 1)
				n[i] += m.type == MSG_HEARTBEAT;
		}
	}
	CHECK(n[0] >= 3 && n[0] <= 6);
	CHECK(n[1] == 0);
	if (n[0] < 3 || n[0] > 6 || n[1])
		fprintf(stderr, "heartbeats in 1 s: %d at 200 ms, %d at 60 s\n", n[0], n[1]);
	proto_conn_free(fast);
	proto_conn_free(slow);
}

/*
 * A master that goes away mid-tile frees the tracer at once: on a one-thread
 * worker whose third tile hangs until cancelled (--test-fault hang-tile), a
 * job whose master closed on that tile is followed by a job that is served.
 */
static void test_cancel_on_close(const uint8_t hash[32], const uint8_t *enc, size_t len, const struct renderer *r)
{
	const char *const extra[] = { "--test-fault", "hang-tile", NULL };
	struct test_worker w;
	CHECK(worker_start(&w, 0, "1", extra) == 0);
	struct proto_msg m;
	struct proto_tile tiles[3] = { { 1, 0, 0, 8, 8, RENDER_RGB8 }, { 2, 8, 0, 8, 8, RENDER_RGB8 },
				       { 3, 16, 0, 8, 8, RENDER_RGB8 } };
	struct proto_conn *c = hello(ROLE_MASTER, PROTO_VERSION);
	CHECK(c != NULL);
	if (c) {
		proto_send_offer(c, hash, len, 64, 48);
		CHECK(run_job(c, enc, len, r, tiles, 2, NULL)); /* the first two come back */
		proto_send_tile(c, &tiles[2]);                  /* the third hangs */
		proto_conn_flush(c);
		CHECK(!next_real_within(c, &m, 0.3));
		proto_conn_free(c); /* the master goes */
	}
	c = hello(ROLE_MASTER, PROTO_VERSION);
	CHECK(c != NULL);
	if (c) {
		proto_send_offer(c, hash, len, 64, 48);
		int cached = -1;
		CHECK(run_job(c, enc, len, r, tiles, 2, &cached) && cached == 1);
		proto_conn_free(c);
	}
	worker_stop(&w);
}

/*
 * SIGTERM while a tile of a slow job is being traced (60 s of
 * --test-delay-ms): the worker ends within a second, with status 0.
 */
static void test_sigterm_slow(const uint8_t hash[32], const uint8_t *enc, size_t len)
{
	const char *const extra[] = { "--test-delay-ms", "60000", NULL };
	struct test_worker w;
	CHECK(worker_start(&w, 0, "1", extra) == 0);
	struct proto_msg m;
	struct proto_conn *c = hello(ROLE_MASTER, PROTO_VERSION);
	CHECK(c != NULL);
	if (c) {
		struct proto_tile t = { 1, 0, 0, 8, 8, RENDER_RGB8 };
		proto_send_offer(c, hash, len, 64, 48);
		CHECK(next_real(c, &m) && m.type == MSG_SCENE_NEED);
		proto_send_data(c, 0, enc, (uint32_t)len);
		proto_send_tile(c, &t);
		proto_conn_flush(c);
		CHECK(next_real(c, &m) && m.type == MSG_SCENE_READY);
		usleep(300000); /* traced by now, and asleep */
	}
	double t0 = net_now();
	worker_stop(&w); /* checks the exit status 0 */
	double took = net_now() - t0;
	CHECK(took < 1.0);
	if (took >= 1.0)
		fprintf(stderr, "SIGTERM mid-tile took %.2f s\n", took);
	if (c) { /* told why */
		CHECK(next_real(c, &m) && m.type == MSG_ERROR && m.u.error.code == PERR_SHUTDOWN);
		proto_conn_free(c);
	}
}

/* The child of test_idle_flood: holds n idle connections to `port`, each
 * made again as soon as the worker closes it, until killed. */
static void flood_child(int n)
{
	struct rlimit rl;
	if (getrlimit(RLIMIT_NOFILE, &rl) == 0 && rl.rlim_cur < (rlim_t)n + 64) {
		rl.rlim_cur = rl.rlim_max < (rlim_t)n + 64 ? rl.rlim_max : (rlim_t)n + 64;
		setrlimit(RLIMIT_NOFILE, &rl);
	}
	struct pollfd p[512];
	if (n > 512)
		n = 512;
	for (int i = 0; i < n; i++) {
		char err[300];
		p[i].fd = net_connect_start("127.0.0.1", port, err, sizeof err);
		p[i].events = POLLIN;
	}
	for (;;) {
		poll(p, (nfds_t)n, 50);
		for (int i = 0; i < n; i++) {
			char buf[4096], err[300];
			if (p[i].fd >= 0 && !(p[i].revents & (POLLIN | POLLHUP | POLLERR)))
				continue;
			if (p[i].fd >= 0 && recv(p[i].fd, buf, sizeof buf, 0) > 0)
				continue; /* a HELLO or an ERROR: read and ignored */
			if (p[i].fd >= 0)
				close(p[i].fd);
			p[i].fd = net_connect_start("127.0.0.1", port, err, sizeof err);
		}
	}
}

/*
 * 300 idle connections held open against a worker with a secret, each
 * reconnecting as soon as it is closed: a real master (HELLO, then its proof
 * and offer in one flight) still gets its job done, and the worker holds no
 * more than its unauthenticated budget of them.
 */
static void test_idle_flood(const uint8_t hash[32], const uint8_t *enc, size_t len, const struct renderer *r)
{
	char sf[] = "/tmp/portray-peer-key-XXXXXX";
	int fd = mkstemp(sf);
	CHECK(fd >= 0 && write(fd, "k3y\n", 4) == 4);
	close(fd);
	const char *const extra[] = { "--secret-file", sf, NULL };
	struct test_worker w;
	CHECK(worker_start(&w, 0, "2", extra) == 0);
	pid_t child = fork();
	if (child == 0) {
		flood_child(300);
		_exit(0);
	}
	usleep(1000000); /* the flood is on */
	int fds = count_fds(w.pid);
	CHECK(fds > 0 && fds <= 64 + 32);
	if (fds > 64 + 32)
		fprintf(stderr, "worker under an idle flood holds %d descriptors\n", fds);
	struct proto_tile tiles[2] = { { 1, 0, 0, 16, 16, RENDER_RGB8 }, { 2, 16, 16, 16, 16, RENDER_RGB8 } };
	int ok = 0, attempts = 0;
	for (; attempts < 3 && !ok; attempts++) { /* a real master retries too */
		struct proto_conn *c = dial();
		ok = c && secret_handshake(c, "k3y", hash, len, 64, 48) && run_job(c, enc, len, r, tiles, 2, NULL);
		proto_conn_free(c);
	}
	CHECK(ok && attempts == 1);
	if (!ok || attempts != 1)
		fprintf(stderr, "a master under an idle flood: %s after %d attempts\n", ok ? "served" : "refused",
			attempts);
	kill(child, SIGKILL);
	waitpid(child, NULL, 0);
	worker_stop(&w);
	unlink(sf);
}

int main(void)
{
	signal(SIGPIPE, SIG_IGN);
	struct rlimit rl; /* the floods below hold a few hundred connections */
	if (getrlimit(RLIMIT_NOFILE, &rl) == 0 && rl.rlim_cur < 2048) {
		rl.rlim_cur = rl.rlim_max < 2048 ? rl.rlim_max : 2048;
		setrlimit(RLIMIT_NOFILE, &rl);
	}
	const char *const extra[] = { "--cache-mb", "1", NULL };
	struct test_worker main_worker;
	int started = worker_start(&main_worker, 0, "2", extra);
	pid_t pid = main_worker.pid;
	CHECK(started == 0);
	if (started != 0) {
		kill(pid, SIGKILL);
		TEST_MAIN_END();
	}

	/* garbage instead of a frame */
	struct proto_conn *c = dial();
	CHECK(c != NULL);
	CHECK(send(proto_conn_fd(c), "GET / HTTP/1.0\r\n\r\n", 18, 0) == 18);
	struct proto_msg m;
	CHECK(next_real(c, &m) && m.type == MSG_HELLO); /* the worker speaks first */
	CHECK(expect_error(c, PERR_PROTOCOL, "magic"));
	proto_conn_free(c);

	/* a frame longer than the limit */
	c = dial();
	uint8_t hdr[12];
	proto_wr32(hdr, PROTO_MAGIC), proto_wr16(hdr + 4, 1), proto_wr16(hdr + 6, MSG_HELLO);
	proto_wr32(hdr + 8, LIM_FRAME_PAYLOAD + 1);
	CHECK(send(proto_conn_fd(c), hdr, 12, 0) == 12);
	CHECK(next_real(c, &m) && m.type == MSG_HELLO);
	CHECK(expect_error(c, PERR_LIMIT, NULL));
	proto_conn_free(c);

	/* before the handshake no frame longer than a HELLO is buffered: a
	 * declared 64 KiB "HELLO" is refused at once, not waited for */
	int fds0 = count_fds(pid);
	c = dial();
	proto_wr32(hdr + 8, 64u * 1024);
	CHECK(send(proto_conn_fd(c), hdr, 12, 0) == 12);
	CHECK(next_real(c, &m) && m.type == MSG_HELLO);
	CHECK(expect_error(c, PERR_LIMIT, "allowed"));
	proto_conn_free(c);

	/* a master that is not one, another version, a message out of turn */
	c = hello(ROLE_WORKER, PROTO_VERSION);
	CHECK(c && expect_error(c, PERR_PROTOCOL, "not a master"));
	proto_conn_free(c);
	c = hello(ROLE_MASTER, PROTO_VERSION + 7);
	char vtext[128];
	snprintf(vtext, sizeof vtext, "the master speaks version %u, this worker speaks %u", PROTO_VERSION + 7,
		 PROTO_VERSION);
	CHECK(c && expect_error(c, PERR_VERSION, vtext));
	proto_conn_free(c);
	c = hello(ROLE_MASTER, PROTO_VERSION);
	struct proto_tile t0 = { 1, 0, 0, 8, 8, RENDER_RGB8 };
	proto_send_tile(c, &t0);
	proto_conn_flush(c);
	CHECK(c && expect_error(c, PERR_PROTOCOL, "unexpected TILE"));
	proto_conn_free(c);

	/* a BYE before any job (the master's render ended first): closed, no ERROR */
	c = hello(ROLE_MASTER, PROTO_VERSION);
	proto_send_bye(c);
	proto_conn_flush(c);
	CHECK(c && !next_real(c, &m));
	proto_conn_free(c);

	/* a scene over the cache budget (1 MiB here) */
	uint8_t hash[32] = { 1 };
	c = hello(ROLE_MASTER, PROTO_VERSION);
	proto_send_offer(c, hash, 2u << 20, 64, 48);
	CHECK(c && expect_error(c, PERR_LIMIT, "--cache-mb"));
	proto_conn_free(c);

	/* scenes being received share the cache budget: two peers offering
	 * 600 KB each to a 1 MiB worker cannot both send */
	uint8_t hash2[32] = { 2 };
	struct proto_conn *c1 = hello(ROLE_MASTER, PROTO_VERSION);
	CHECK(c1 != NULL);
	proto_send_offer(c1, hash, 600000, 64, 48);
	CHECK(c1 && next_real(c1, &m) && m.type == MSG_SCENE_NEED);
	c = hello(ROLE_MASTER, PROTO_VERSION);
	proto_send_offer(c, hash2, 600000, 64, 48);
	CHECK(c && expect_error(c, PERR_LIMIT, "being received"));
	proto_conn_free(c);
	proto_conn_free(c1);

	/* scene bytes that do not match their hash; chunks out of order */
	struct scene *s = fx_scene();
	uint8_t *enc;
	size_t len;
	CHECK(proto_scene_encode(s, &enc, &len) == 0);
	c = hello(ROLE_MASTER, PROTO_VERSION);
	proto_send_offer(c, hash, len, 64, 48);
	CHECK(next_real(c, &m) && m.type == MSG_SCENE_NEED);
	proto_send_data(c, 0, enc, (uint32_t)len);
	CHECK(expect_error(c, PERR_SCENE, "hash"));
	proto_conn_free(c);
	uint8_t real[32];
	proto_scene_hash(enc, len, real);
	c = hello(ROLE_MASTER, PROTO_VERSION);
	proto_send_offer(c, real, len, 64, 48);
	CHECK(next_real(c, &m) && m.type == MSG_SCENE_NEED);
	proto_send_data(c, 10, enc + 10, 100);
	CHECK(expect_error(c, PERR_PROTOCOL, "out of order"));
	proto_conn_free(c);

	/* a tile during the scene transfer is out of turn (only once the whole
	 * scene is in may tiles come, protocol 2) */
	c = hello(ROLE_MASTER, PROTO_VERSION);
	CHECK(c != NULL);
	if (c) {
		proto_send_offer(c, real, len, 64, 48);
		CHECK(next_real(c, &m) && m.type == MSG_SCENE_NEED);
		proto_send_data(c, 0, enc, 100);
		proto_send_tile(c, &t0);
		proto_conn_flush(c);
		CHECK(expect_error(c, PERR_PROTOCOL, "unexpected TILE"));
		proto_conn_free(c);
	}

	/* a whole job in protocol 2's flights: HELLO and the offer together,
	 * the tiles behind the scene's last chunk (queued while it builds); the
	 * pixels equal the local renderer's */
	struct renderer *r = NULL;
	struct scene_error err;
	CHECK(renderer_new(s, &r, &err) == 0);
	/* (protocol 3: either pixel type, even within one job) */
	struct proto_tile tiles[3] = { { 7, 0, 0, 16, 16, RENDER_RGB8 }, { 8, 48, 40, 16, 8, RENDER_RGBF32 },
				       { 9, 10, 20, 5, 3, RENDER_RGBF32 } };
	int cached = -1;
	c = dial();
	CHECK(c && next_real(c, &m) && m.type == MSG_HELLO);
	if (!c) {
		kill(pid, SIGKILL);
		TEST_MAIN_END();
	}
	queue_hello(c, ROLE_MASTER, PROTO_VERSION, 200, false, NULL);
	proto_send_offer(c, real, len, 64, 48);
	CHECK(run_job(c, enc, len, r, tiles, 3, &cached) && cached == 0);
	/* a tile outside the image ends the job with an error */
	struct proto_tile out = { 10, 60, 40, 8, 8, RENDER_RGB8 };
	proto_send_tile(c, &out);
	CHECK(expect_error(c, PERR_PROTOCOL, "outside"));
	proto_conn_free(c);

	/* the same scene again: a cache hit, no bytes */
	c = hello(ROLE_MASTER, PROTO_VERSION);
	proto_send_offer(c, real, len, 64, 48);
	CHECK(next_real(c, &m) && m.type == MSG_SCENE_HAVE);
	CHECK(next_real(c, &m) && m.type == MSG_SCENE_READY && m.u.ready.cached);
	proto_send_bye(c);
	proto_conn_flush(c);
	CHECK(!next_real(c, &m)); /* BYE: the worker closes */
	proto_conn_free(c);

	/* a flood of idle connections: those that have not authenticated have
	 * a budget of their own (64, and 16 from one address) and, past it,
	 * the oldest make room for each newcomer (ERROR(limit), closed): the
	 * newest are served, and a master that says HELLO still gets in */
	enum { FLOOD = 300, UNAUTH = 64 };
	static struct proto_conn *flood[FLOOD];
	int n_flood = 0;
	for (int i = 0; i < FLOOD; i++)
		if ((flood[i] = dial()))
			n_flood++;
	CHECK(n_flood == FLOOD);
	CHECK(flood[FLOOD - 1] && next_real(flood[FLOOD - 1], &m) && m.type == MSG_HELLO);
	usleep(200000);
	int evicted = 0;
	for (int i = 0; i < FLOOD; i++)
		evicted += flood[i] && told_error(flood[i], PERR_LIMIT);
	CHECK(evicted >= FLOOD - UNAUTH && evicted < FLOOD);
	CHECK(flood[FLOOD - 1] && !told_error(flood[FLOOD - 1], PERR_LIMIT));
	c = hello(ROLE_MASTER, PROTO_VERSION);
	CHECK(c != NULL);
	if (c) {
		proto_send_offer(c, real, len, 64, 48);
		CHECK(run_job(c, enc, len, r, tiles, 1, &cached) && cached == 1);
		proto_conn_free(c);
	}
	for (int i = 0; i < FLOOD; i++)
		proto_conn_free(flood[i]);

	/* the budget of authenticated connections (256; with no secret a HELLO
	 * authenticates): one more master is told ERROR(limit), and is served
	 * again once they are gone */
	enum { AUTHED = 256 };
	static struct proto_conn *full[AUTHED];
	int n_full = 0;
	for (int i = 0; i < AUTHED; i++)
		full[i] = hello(ROLE_MASTER, PROTO_VERSION);
	for (int i = 0; i < AUTHED; i++) /* a heartbeat: it is past its HELLO */
		n_full += full[i] && next_msg(full[i], &m) && m.type == MSG_HEARTBEAT;
	CHECK(n_full == AUTHED);
	c = hello(ROLE_MASTER, PROTO_VERSION);
	CHECK(c && expect_error(c, PERR_LIMIT, "serves 256"));
	proto_conn_free(c);
	for (int i = 0; i < AUTHED; i++)
		proto_conn_free(full[i]);
	c = NULL;
	for (int i = 0; i < 100 && !c; i++) { /* served again once they are gone */
		c = hello(ROLE_MASTER, PROTO_VERSION);
		if (c && !(next_msg(c, &m) && m.type == MSG_HEARTBEAT)) {
			proto_conn_free(c);
			c = NULL;
		}
		if (!c)
			usleep(50000);
	}
	CHECK(c != NULL);
	proto_conn_free(c);

	/* every connection above is closed: the worker holds no more fds than
	 * before them (it closes a connection once its ERROR is flushed) */
	int fds1 = -1;
	for (int i = 0; i < 100 && (fds1 = count_fds(pid)) != fds0; i++)
		usleep(50000);
	CHECK(fds0 > 0 && fds1 == fds0);
	if (fds1 != fds0)
		fprintf(stderr, "worker fds: %d before, %d after\n", fds0, fds1);

	test_back_pressure(pid);
	test_heartbeats();
	test_out_of_fds();
	test_secret_first();
	test_slow_handshake();
	test_cancel_on_close(real, enc, len, r);
	test_sigterm_slow(real, enc, len);
	test_idle_flood(real, enc, len, r);

	renderer_free(r);
	free(enc);
	scene_free(s);
	worker_stop(&main_worker);
	TEST_MAIN_END();
}
