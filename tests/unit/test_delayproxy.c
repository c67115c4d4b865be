/*
 * test_delayproxy.c - the test tool $BUILD/tools/delayproxy (found beside
 * this binary: ../tools/delayproxy) between a client and a server of ours:
 * megabytes pass intact both ways at once on two connections; EOFs are
 * forwarded after the data ahead of them, half-closes included; with a
 * 50 ms delay a round trip takes at least 100 ms and an EOF at least 50 ms
 * (lower bounds only: a loaded machine may be slower, never faster); a
 * receiver that does not read stalls the sender with the proxy's memory
 * bounded; a target that refuses closes the client; SIGTERM exits 0.
 */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "proto/net.h"
#include "tests/unit/rss.h"

static char tool[4096];

struct proxy {
	pid_t pid;
	char port[16];
	char pf[64];
};

/* Starts the proxy to 127.0.0.1:to with the delay and extra option (or NULL); 0 or -1. */
static int proxy_start(struct proxy *p, int to, int delay_ms, const char *extra)
{
	snprintf(p->pf, sizeof p->pf, "/tmp/portray-dp-XXXXXX");
	int fd = mkstemp(p->pf);
	if (fd >= 0)
		close(fd);
	unlink(p->pf);
	char target[32], delay[16];
	snprintf(target, sizeof target, "127.0.0.1:%d", to);
	snprintf(delay, sizeof delay, "%d", delay_ms);
	const char *argv[] = { "delayproxy", "--listen", "127.0.0.1:0", "--port-file", p->pf, "--to", target,
			       "--delay-ms", delay, "-q", extra, extra ? "1" : NULL, NULL };
	p->pid = fork();
	if (p->pid == 0) {
		execv(tool, (char *const *)argv);
		_exit(127);
	}
	p->port[0] = 0;
	for (int i = 0; i < 250 && !p->port[0]; i++) {
		FILE *f = fopen(p->pf, "r");
		if (f) {
			if (fscanf(f, "%15s", p->port) != 1)
				p->port[0] = 0;
			fclose(f);
		}
		if (!p->port[0])
			usleep(20000);
	}
	return p->port[0] ? 0 : -1;
}

/* SIGTERM; the proxy must exit 0. */
static void proxy_stop(struct proxy *p)
{
	int st = -1;
	kill(p->pid, SIGTERM);
	waitpid(p->pid, &st, 0);
	CHECK(WIFEXITED(st) && WEXITSTATUS(st) == 0);
	unlink(p->pf);
}

/* A connected socket to 127.0.0.1:port (non-blocking), or -1. */
static int dial(const char *port)
{
	char err[300];
	int fd = net_connect_start("127.0.0.1", port, err, sizeof err);
	if (fd < 0)
		return -1;
	struct pollfd p = { fd, POLLOUT, 0 };
	poll(&p, 1, 5000);
	if (net_connect_finish(fd, err, sizeof err) < 0) {
		close(fd);
		return -1;
	}
	return fd;
}

/* The next connection on the listener within 5 s, or -1. */
static int take(int lfd)
{
	struct pollfd p = { lfd, POLLIN, 0 };
	if (poll(&p, 1, 5000) <= 0)
		return -1;
	char peer[96];
	return net_accept(lfd, peer, sizeof peer);
}

/* Byte k of the stream with this seed: no period short enough to hide a shift. */
static uint8_t pattern(uint32_t seed, uint64_t k)
{
	uint64_t x = (k + 1) * 0x9E3779B97F4A7C15ull ^ seed;
	x ^= x >> 29;
	x *= 0xBF58476D1CE4E5B9ull;
	return (uint8_t)(x >> 32);
}

/*
 * One end of a transfer: sends `len` bytes of the pattern `out_seed`, then
 * shuts its writing side down; reads and checks the pattern `in_seed`
 * until EOF.
 */
struct end {
	int fd;
	uint32_t out_seed, in_seed;
	uint64_t len, sent, got;
	int bad;              /* bytes that differ */
	bool shut, eof;
	double eof_at;
};

static void end_step(struct end *e, short re)
{
	uint8_t b[32768];
	if ((re & POLLOUT) && e->sent < e->len) {
		size_t n = sizeof b;
		if (n > e->len - e->sent)
			n = (size_t)(e->len - e->sent);
		for (size_t i = 0; i < n; i++)
			b[i] = pattern(e->out_seed, e->sent + i);
		ssize_t w = write(e->fd, b, n);
		if (w > 0)
			e->sent += (uint64_t)w;
	}
	if (e->sent == e->len && !e->shut) {
		shutdown(e->fd, SHUT_WR);
		e->shut = true;
	}
	if ((re & (POLLIN | POLLHUP | POLLERR)) && !e->eof) {
		ssize_t r = read(e->fd, b, sizeof b);
		if (r == 0 || (r < 0 && errno != EAGAIN && errno != EINTR)) {
			e->eof = true;
			e->eof_at = net_now();
		}
		for (ssize_t i = 0; i < r; i++)
			e->bad += b[i] != pattern(e->in_seed, e->got + (uint64_t)i);
		if (r > 0)
			e->got += (uint64_t)r;
	}
}

/* Runs the ends until all have sent everything and seen EOF, or 60 s pass. */
static void pump(struct end *e, int n)
{
	double until = net_now() + 60;
	for (;;) {
		struct pollfd p[8];
		int done = 0;
		for (int i = 0; i < n; i++) {
			p[i] = (struct pollfd){ e[i].fd, (short)((e[i].eof ? 0 : POLLIN) | (e[i].shut ? 0 : POLLOUT)), 0 };
			done += e[i].eof && e[i].shut;
		}
		if (done == n || net_now() > until)
			return;
		poll(p, (nfds_t)n, 100);
		for (int i = 0; i < n; i++)
			end_step(&e[i], p[i].revents);
	}
}

/* Two connections at once, several MB each way on each: intact, with EOFs. */
static void intact(int lfd, int delay_ms, uint64_t len)
{
	struct proxy px;
	CHECK(proxy_start(&px, net_local_port(lfd), delay_ms, NULL) == 0);
	struct end e[4];
	memset(e, 0, sizeof e);
	for (int c = 0; c < 2; c++) {
		struct end *cl = &e[2 * c], *sv = &e[2 * c + 1];
		cl->fd = dial(px.port);
		sv->fd = take(lfd);
		CHECK(cl->fd >= 0 && sv->fd >= 0);
		cl->out_seed = sv->in_seed = 100 + (uint32_t)c;
		sv->out_seed = cl->in_seed = 200 + (uint32_t)c;
		cl->len = len;
		sv->len = len / 2 + 12345 * (uint64_t)c; /* unequal both ways */
	}
	double t0 = net_now();
	pump(e, 4);
	for (int i = 0; i < 4; i++) {
		CHECK(e[i].eof);
		CHECK(e[i].sent == e[i].len);
		CHECK(e[i].got == e[i ^ 1].len);
		CHECK(e[i].bad == 0);
		/* the EOF comes after the data, at least a delay after it was sent */
		CHECK(e[i].eof_at - t0 >= delay_ms / 1000.0);
		close(e[i].fd);
	}
	printf("delay %d ms: 2 connections, %llu + %llu bytes each way, intact, in %.2f s\n", delay_ms,
	       (unsigned long long)e[0].len, (unsigned long long)e[1].len, net_now() - t0);
	proxy_stop(&px);
}

/* Reads exactly one byte within 5 s: the byte, or -1. */
static int read1(int fd)
{
	struct pollfd p = { fd, POLLIN, 0 };
	if (poll(&p, 1, 5000) <= 0)
		return -1;
	uint8_t b;
	return read(fd, &b, 1) == 1 ? b : -1;
}

/* With 50 ms each way: round trips >= 100 ms, a half-close forwarded after >= 50 ms. */
static void latency(int lfd)
{
	struct proxy px;
	CHECK(proxy_start(&px, net_local_port(lfd), 50, NULL) == 0);
	int c = dial(px.port), s = take(lfd);
	CHECK(c >= 0 && s >= 0);
	for (int i = 0; i < 3; i++) {
		uint8_t b = (uint8_t)('a' + i);
		double t0 = net_now();
		CHECK(write(c, &b, 1) == 1);
		int r = read1(s);
		CHECK(r == b);
		CHECK(write(s, &b, 1) == 1);
		CHECK(read1(c) == b);
		double rtt = net_now() - t0;
		printf("round trip %d: %.1f ms\n", i, rtt * 1000);
		CHECK(rtt >= 0.1);
	}
	/* the client half-closes: the server reads EOF >= 50 ms later and can still answer */
	double t0 = net_now();
	shutdown(c, SHUT_WR);
	struct pollfd p = { s, POLLIN, 0 };
	CHECK(poll(&p, 1, 5000) == 1);
	uint8_t b;
	CHECK(read(s, &b, 1) == 0);
	CHECK(net_now() - t0 >= 0.05);
	CHECK(write(s, "z", 1) == 1);
	CHECK(read1(c) == 'z');
	close(s);
	p = (struct pollfd){ c, POLLIN, 0 };
	CHECK(poll(&p, 1, 5000) == 1 && read(c, &b, 1) == 0);
	close(c);
	proxy_stop(&px);
}

/* A server that never reads: the client stalls; the proxy holds about --max-queue-mb. */
static void bounded(int lfd)
{
	struct proxy px;
	CHECK(proxy_start(&px, net_local_port(lfd), 0, "--max-queue-mb") == 0);
	int c = dial(px.port), s = take(lfd);
	CHECK(c >= 0 && s >= 0);
	static uint8_t chunk[1 << 20];
	uint64_t sent = 0;
	double idle_since = net_now();
	while (net_now() - idle_since < 0.5 && sent < (256ull << 20)) {
		struct pollfd p = { c, POLLOUT, 0 };
		poll(&p, 1, 50);
		ssize_t w = write(c, chunk, sizeof chunk);
		if (w > 0) {
			sent += (uint64_t)w;
			idle_since = net_now();
		}
	}
	long kb = rss_kib(px.pid);
	printf("a server that does not read: the client stalled after %.1f MB; proxy RSS %ld KiB\n", sent / 1e6, kb);
	/* socket buffers on both sides of the proxy hold some MB, the queue 1 MiB;
	 * without the bound the proxy would take all 256 MB (the RSS bound leaves
	 * room for a sanitizer build's own memory) */
	CHECK(sent < (64ull << 20));
	CHECK(kb < 0 || kb < 48 * 1024);
	close(c);
	close(s);
	proxy_stop(&px);
}

/* Nothing listens at the target: the client's connection is closed. */
static void refused(void)
{
	int lfd = net_listen("127.0.0.1", "0", (char[300]){ 0 }, 300);
	int dead = net_local_port(lfd);
	close(lfd); /* that port now refuses */
	struct proxy px;
	CHECK(proxy_start(&px, dead, 10, NULL) == 0);
	int c = dial(px.port);
	CHECK(c >= 0);
	struct pollfd p = { c, POLLIN, 0 };
	uint8_t b;
	CHECK(poll(&p, 1, 5000) == 1 && read(c, &b, 1) <= 0);
	close(c);
	proxy_stop(&px);
}

int main(int argc, char **argv)
{
	(void)argc;
	const char *slash = strrchr(argv[0], '/');
	snprintf(tool, sizeof tool, "%.*s/../tools/delayproxy", slash ? (int)(slash - argv[0]) : 1,
		 slash ? argv[0] : ".");
	if (access(tool, X_OK) != 0) {
		printf("%s not built (make test builds it)\n", tool);
		return 1;
	}
	signal(SIGPIPE, SIG_IGN);
	char err[300];
	int lfd = net_listen("127.0.0.1", "0", err, sizeof err);
	CHECK(lfd >= 0);
	intact(lfd, 0, 3u << 20);
	intact(lfd, 50, 2u << 20);
	latency(lfd);
	bounded(lfd);
	refused();
	close(lfd);
	TEST_MAIN_END();
}
