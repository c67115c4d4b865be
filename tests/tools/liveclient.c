/*
 * liveclient.c - a client of the master's live view (--http) for the shell
 * tests (tests/e2e/live_*.sh). Plain blocking sockets with poll() deadlines.
 *
 *   liveclient get PORT PATH [METHOD]
 *       one request; prints the response (head and body) on stdout
 *   liveclient stream PORT OUT.ppm [--after FRACTION] [--slow-for S] [--quiet-for S]
 *       (--after: first polls /status until that fraction of the tiles is
 *       done) follows /events to its end event and writes the image rebuilt
 *       from the tiles as a binary PPM; prints the tiles received and how
 *       many were done when the stream started. --slow-for S reads at most
 *       4 KiB every 20 ms for S seconds (a slow viewer); --quiet-for S reads
 *       nothing for S seconds (a stuck one). Exit 0 only with an end event.
 *   liveclient hash FILE.ppm
 *       FNV-1a (32 bits) of the pixel bytes, as the page computes it
 *   liveclient garbage PORT N [--hold S] [--seed X]
 *       N bad or odd requests of every kind (random bytes, huge headers,
 *       bad methods, malformed lines, requests left half sent, a slow-loris
 *       trickle, a viewer that reads nothing); checks each answer, holds the
 *       open ones S seconds (default 3) while checking that the server
 *       still answers a good request, then (with S > HTTP_HEADER_S) that it
 *       closed the unfinished ones. Exit 0 when every answer was right.
 *   liveclient viewers PORT N
 *       opens N streams that read nothing past their head (200 each), then
 *       checks that one more gets 503 and, once one of the N is closed, a
 *       new one is let in. Exit 0 when so.
 * Every mode gives up after 120 s (exit 1).
 */
#include <errno.h>
#include <netinet/in.h>
#include <arpa/inet.h>
#include <poll.h>
#include <signal.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#define GIVE_UP_S 120.0

static int port;

static double now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static double t_start;

static void die(const char *fmt, ...) __attribute__((noreturn, format(printf, 1, 2)));
static void die(const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	fputs("liveclient: ", stderr);
	vfprintf(stderr, fmt, ap);
	fputc('\n', stderr);
	va_end(ap);
	exit(1);
}

static int dial(void)
{
	int fd = socket(AF_INET, SOCK_STREAM, 0);
	struct sockaddr_in a = { .sin_family = AF_INET, .sin_port = htons((uint16_t)port) };
	a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
	if (fd < 0 || connect(fd, (struct sockaddr *)&a, sizeof a) < 0)
		die("connect to 127.0.0.1:%d: %s", port, strerror(errno));
	return fd;
}

static void send_all(int fd, const void *p, size_t n)
{
	const char *c = p;
	while (n) {
		ssize_t w = send(fd, c, n, MSG_NOSIGNAL);
		if (w < 0 && errno == EINTR)
			continue;
		if (w <= 0)
			return; /* the server may close first (a 431): the caller reads its answer */
		c += w;
		n -= (size_t)w;
	}
}

/* Reads until EOF or timeout seconds; returns the bytes (NUL-terminated, caller frees), *n. */
static char *read_all(int fd, double timeout, size_t *n, bool *reset)
{
	size_t cap = 4096, len = 0;
	char *b = malloc(cap + 1);
	double until = now() + timeout;
	*reset = false;
	for (;;) {
		double left = until - now();
		if (left <= 0)
			break;
		struct pollfd p = { fd, POLLIN, 0 };
		if (poll(&p, 1, (int)(left * 1000) + 1) <= 0)
			continue;
		if (len == cap)
			b = realloc(b, (cap *= 2) + 1);
		ssize_t r = recv(fd, b + len, cap - len, 0);
		if (r < 0 && errno == EINTR)
			continue;
		if (r < 0)
			*reset = true;
		if (r <= 0)
			break;
		len += (size_t)r;
	}
	b[len] = 0;
	*n = len;
	return b;
}

/* The status code of a response ("HTTP/1.1 200 ..."), 0 when there is none. */
static int status_of(const char *r)
{
	int code;
	if (sscanf(r, "HTTP/1.1 %d ", &code) == 1)
		return code;
	return 0;
}

static char *request(const char *method, const char *path, size_t *n)
{
	int fd = dial();
	char req[512];
	int len = snprintf(req, sizeof req, "%s %s HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n\r\n", method, path, port);
	send_all(fd, req, (size_t)len);
	bool reset;
	char *r = read_all(fd, 10, n, &reset);
	close(fd);
	return r;
}

/* ---- stream ---- */

struct image {
	uint32_t w, h;
	uint8_t *px;
};

static int b64val(int c)
{
	if (c >= 'A' && c <= 'Z')
		return c - 'A';
	if (c >= 'a' && c <= 'z')
		return c - 'a' + 26;
	if (c >= '0' && c <= '9')
		return c - '0' + 52;
	if (c == '+')
		return 62;
	if (c == '/')
		return 63;
	return -1;
}

/* "X Y W H BASE64" into the image; exits on anything malformed. */
static void put_tile(struct image *im, const char *d)
{
	unsigned x, y, w, h;
	int off;
	if (!im->px)
		die("a tile before the info event");
	if (sscanf(d, "%u %u %u %u %n", &x, &y, &w, &h, &off) != 4)
		die("bad tile event '%.60s'", d);
	if (w == 0 || h == 0 || x + w > im->w || y + h > im->h)
		die("tile %u,%u %ux%u outside the %ux%u image", x, y, w, h, im->w, im->h);
	const char *s = d + off;
	size_t len = strlen(s), need = (size_t)w * h * 3;
	if (len != (need + 2) / 3 * 4)
		die("tile %u,%u: %zu base64 characters for %zu bytes", x, y, len, need);
	uint8_t *out = malloc(need + 3);
	size_t o = 0;
	for (size_t i = 0; i < len; i += 4) {
		int v[4];
		for (int k = 0; k < 4; k++)
			v[k] = s[i + k] == '=' ? 0 : b64val((unsigned char)s[i + k]);
		if (v[0] < 0 || v[1] < 0 || v[2] < 0 || v[3] < 0)
			die("tile %u,%u: bad base64", x, y);
		uint32_t q = (uint32_t)v[0] << 18 | (uint32_t)v[1] << 12 | (uint32_t)v[2] << 6 | (uint32_t)v[3];
		out[o++] = (uint8_t)(q >> 16);
		out[o++] = (uint8_t)(q >> 8);
		out[o++] = (uint8_t)q;
	}
	for (uint32_t r = 0; r < h; r++)
		memcpy(im->px + ((size_t)(y + r) * im->w + x) * 3, out + (size_t)r * w * 3, (size_t)w * 3);
	free(out);
}

static void put_undo(struct image *im, const char *d)
{
	unsigned x, y, w, h;
	if (!im->px || sscanf(d, "%u %u %u %u", &x, &y, &w, &h) != 4 || x + w > im->w || y + h > im->h)
		die("bad undo event '%.60s'", d);
	for (uint32_t r = 0; r < h; r++)
		memset(im->px + ((size_t)(y + r) * im->w + x) * 3, 0, (size_t)w * 3);
}

static long json_num(const char *j, const char *key)
{
	char k[64];
	snprintf(k, sizeof k, "\"%s\":", key);
	const char *p = strstr(j, k);
	return p ? strtol(p + strlen(k), NULL, 10) : -1;
}

static void wait_fraction(double frac)
{
	for (;;) {
		if (now() - t_start > GIVE_UP_S)
			die("the render never reached %.0f%%", frac * 100);
		size_t n;
		char *r = request("GET", "/status", &n);
		char *body = strstr(r, "\r\n\r\n");
		long done = body ? json_num(body, "done") : -1, tiles = body ? json_num(body, "tiles") : -1;
		free(r);
		if (tiles > 0 && done >= frac * tiles) {
			fprintf(stderr, "liveclient: connecting at %ld of %ld tiles\n", done, tiles);
			return;
		}
		usleep(20000);
	}
}

static int do_stream(const char *out, double after, double slow_for, double quiet_for)
{
	if (after > 0)
		wait_fraction(after);
	int fd = dial();
	if (slow_for > 0 || quiet_for > 0) {
		int small = 4096;
		setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
	}
	char req[256];
	int rl = snprintf(req, sizeof req,
			  "GET /events HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nAccept: text/event-stream\r\n\r\n", port);
	send_all(fd, req, (size_t)rl);
	double t_conn = now();
	size_t cap = 1 << 16, len = 0, pos = 0;
	char *b = malloc(cap + 1);
	bool head_done = false, ended = false;
	char event[64] = "";
	char *data = NULL;
	size_t data_len = 0;
	struct image im = { 0 };
	long tiles = 0, statuses = 0, undos = 0, at_done = -1, at_tiles = -1;
	while (!ended) {
		if (now() - t_start > GIVE_UP_S)
			die("no end event after %.0f s", GIVE_UP_S);
		double t = now() - t_conn;
		if (t < quiet_for) {
			usleep(50000);
			continue;
		}
		struct pollfd p = { fd, POLLIN, 0 };
		int pr = poll(&p, 1, 1000);
		if (pr <= 0)
			continue;
		if (cap - len < 4096) {
			if (pos > 0) {
				memmove(b, b + pos, len - pos);
				len -= pos;
				pos = 0;
			}
			if (cap - len < 4096)
				b = realloc(b, (cap *= 2) + 1);
		}
		size_t want = cap - len;
		if (t < slow_for && want > 4096)
			want = 4096;
		ssize_t r = recv(fd, b + len, want, 0);
		if (r < 0 && errno == EINTR)
			continue;
		if (r <= 0)
			die("the stream closed before its end event (%ld tiles)", tiles);
		len += (size_t)r;
		b[len] = 0;
		if (t < slow_for)
			usleep(20000);
		if (!head_done) {
			char *e = strstr(b, "\r\n\r\n");
			if (!e)
				continue;
			if (status_of(b) != 200 || !strstr(b, "Content-Type: text/event-stream"))
				die("not an event stream: %.*s", (int)(e - b), b);
			head_done = true;
			pos = (size_t)(e + 4 - b);
			fprintf(stderr, "liveclient: streaming\n");
		}
		/* whole lines */
		for (;;) {
			char *nl = memchr(b + pos, '\n', len - pos);
			if (!nl)
				break;
			char *line = b + pos;
			size_t ll = (size_t)(nl - line);
			if (ll && line[ll - 1] == '\r')
				ll--;
			line[ll] = 0;
			pos = (size_t)(nl + 1 - b);
			if (ll == 0) { /* dispatch */
				const char *d = data ? data : "";
				if (!strcmp(event, "info")) {
					im.w = (uint32_t)json_num(d, "w");
					im.h = (uint32_t)json_num(d, "h");
					if (im.w == 0 || im.h == 0 || im.w > 65536 || im.h > 65536)
						die("bad info event '%s'", d);
					free(im.px);
					im.px = calloc((size_t)im.w * im.h, 3);
				} else if (!strcmp(event, "tile")) {
					put_tile(&im, d);
					tiles++;
				} else if (!strcmp(event, "undo")) {
					put_undo(&im, d);
					undos++;
				} else if (!strcmp(event, "status")) {
					if (statuses++ == 0) { /* sent as the stream starts */
						at_done = json_num(d, "done");
						at_tiles = json_num(d, "tiles");
					}
				} else if (!strcmp(event, "end")) {
					ended = true;
					fprintf(stderr, "liveclient: end: %s\n", d);
				} else if (event[0]) {
					die("unknown event '%s'", event);
				}
				event[0] = 0;
				data_len = 0;
				free(data);
				data = NULL;
				continue;
			}
			if (!strncmp(line, "event:", 6)) {
				snprintf(event, sizeof event, "%s", line + 6 + (line[6] == ' '));
			} else if (!strncmp(line, "data:", 5)) {
				const char *v = line + 5 + (line[5] == ' ');
				size_t vl = strlen(v);
				data = realloc(data, data_len + vl + 2);
				if (data_len)
					data[data_len++] = '\n';
				memcpy(data + data_len, v, vl + 1);
				data_len += vl;
			} /* retry:, comments: nothing to do */
		}
	}
	close(fd);
	if (!im.px)
		die("no info event");
	FILE *f = fopen(out, "wb");
	if (!f || fprintf(f, "P6\n%u %u\n255\n", im.w, im.h) < 0 || fwrite(im.px, 3, (size_t)im.w * im.h, f) !=
	    (size_t)im.w * im.h || fclose(f) != 0)
		die("cannot write %s", out);
	/* at_done: tiles done when the stream started (the image so far) */
	printf("tiles %ld undos %ld statuses %ld at_done %ld of %ld\n", tiles, undos, statuses, at_done, at_tiles);
	free(im.px);
	free(b);
	free(data);
	return 0;
}

/* ---- hash ---- */

static int do_hash(const char *path)
{
	FILE *f = fopen(path, "rb");
	unsigned w, h, maxv;
	if (!f || fscanf(f, "P6 %u %u %u", &w, &h, &maxv) != 3 || maxv != 255 || fgetc(f) == EOF)
		die("%s: not a binary PPM with maxval 255", path);
	uint32_t x = 0x811c9dc5u;
	size_t n = (size_t)w * h * 3;
	for (size_t i = 0; i < n; i++) {
		int c = fgetc(f);
		if (c == EOF)
			die("%s: short", path);
		x = (x ^ (uint32_t)c) * 0x01000193u;
	}
	fclose(f);
	printf("%ux%u %08x\n", w, h, x);
	return 0;
}

/* ---- garbage ---- */

static uint64_t rng = 0x9e3779b97f4a7c15ull;
static uint32_t rnd(void)
{
	rng ^= rng << 13;
	rng ^= rng >> 7;
	rng ^= rng << 17;
	return (uint32_t)(rng >> 16);
}

enum { HOLD_MAX = 64 };
static int held[HOLD_MAX], n_held;
static int trickle[HOLD_MAX], n_trickle;
static int failures;

static void expect(const char *what, int fd, const int *codes, int n_codes, bool close_ok)
{
	size_t n;
	bool reset;
	char *r = read_all(fd, 10, &n, &reset);
	int code = status_of(r);
	bool ok = (code == 0 && (n == 0 || reset) && close_ok);
	for (int i = 0; i < n_codes; i++)
		ok |= code == codes[i];
	if (code && !strstr(r, "\r\n\r\n"))
		ok = false; /* a head never finished */
	printf("%-34s -> %s%d%s\n", what, code ? "" : "closed ", code, ok ? "" : "  WRONG");
	if (!ok) {
		failures++;
		printf("     | %.200s\n", r);
	}
	free(r);
	close(fd);
}

#define CODES(...) (const int[]){ __VA_ARGS__ }, (int)(sizeof((const int[]){ __VA_ARGS__ }) / sizeof(int))

static void one_garbage(int i)
{
	char buf[32768];
	int fd = dial();
	switch (i % 16) {
	case 0: { /* random bytes */
		size_t n = 64 + rnd() % 2000;
		for (size_t k = 0; k < n; k++)
			buf[k] = (char)rnd();
		buf[0] = 'G'; /* starts like a request, then nonsense */
		send_all(fd, buf, n);
		expect("random bytes", fd, CODES(400, 431), true);
		return;
	}
	case 1: { /* a header over the limit */
		int n = snprintf(buf, sizeof buf, "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Big: ");
		memset(buf + n, 'a', 20000);
		send_all(fd, buf, (size_t)n + 20000);
		expect("huge header", fd, CODES(431), true);
		return;
	}
	case 2: {
		static const char *m[] = { "DELETE", "POST", "PUT", "BREW", "OPTIONS", "PATCH", "CONNECT" };
		const char *meth = m[rnd() % 7];
		int n = snprintf(buf, sizeof buf, "%s /events HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 5\r\n\r\nhello",
				 meth);
		send_all(fd, buf, (size_t)n);
		snprintf(buf, sizeof buf, "method %s", meth);
		expect(buf, fd, CODES(405), false);
		return;
	}
	case 3: /* half a request, left open */
		send_all(fd, "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nAcc", 36);
		if (n_held < HOLD_MAX) {
			held[n_held++] = fd;
			printf("%-34s -> held open\n", "half a request");
		} else {
			close(fd);
		}
		return;
	case 4: /* slow-loris: a byte now and then */
		send_all(fd, "GET / HTTP/1.1\r\n", 16);
		if (n_trickle < HOLD_MAX) {
			trickle[n_trickle++] = fd;
			printf("%-34s -> trickling\n", "slow-loris");
		} else {
			close(fd);
		}
		return;
	case 5: {
		static const char *bad[] = { "GET\r\n\r\n", "GET / HTTP/2.0\r\n\r\n", "GET nope HTTP/1.1\r\n\r\n",
					     "GET / HTTP/1.1\r\nno colon here\r\n\r\n", " / HTTP/1.1\r\n\r\n",
					     "GET / HTTP/1.1\r\n: empty\r\n\r\n", "G(T / HTTP/1.1\r\n\r\n",
					     "GET / HTTP/1.1\r\nHost: a\r\nHost: b\r\n\r\n" };
		const char *r = bad[rnd() % 8];
		send_all(fd, r, strlen(r));
		expect("malformed request line/header", fd, CODES(400), false);
		return;
	}
	case 6: {
		int n = snprintf(buf, sizeof buf, "GET /%s HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n",
				 rnd() % 2 ? "../../etc/passwd" : "favicon.ico");
		send_all(fd, buf, (size_t)n);
		expect("unknown path", fd, CODES(404), false);
		return;
	}
	case 7: {
		int n = snprintf(buf, sizeof buf, "GET /");
		memset(buf + n, 'x', 3000);
		n += 3000;
		n += snprintf(buf + n, sizeof buf - (size_t)n, " HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
		send_all(fd, buf, (size_t)n);
		expect("long target", fd, CODES(400), false);
		return;
	}
	case 8:
		send_all(fd, "GET / HTTP/1.1\r\nHost: evil.example.com\r\n\r\n", 42);
		expect("foreign Host (rebinding)", fd, CODES(403), false);
		return;
	case 9:
		send_all(fd, "GET / HTTP/1.1\r\nHost: 127.0.0.1\0\r\n\r\n", 36);
		expect("NUL byte", fd, CODES(400), false);
		return;
	case 10: /* gone at once */
		close(fd);
		printf("%-34s -> closed by us\n", "connect and go");
		return;
	case 11: { /* many small headers (within the limit): a good request */
		int n = snprintf(buf, sizeof buf, "GET /status HTTP/1.1\r\nHost: 127.0.0.1\r\n");
		for (int k = 0; k < 200; k++)
			n += snprintf(buf + n, sizeof buf - (size_t)n, "X-%d: y\r\n", k);
		n += snprintf(buf + n, sizeof buf - (size_t)n, "\r\n");
		send_all(fd, buf, (size_t)n);
		expect("200 headers", fd, CODES(200), false);
		return;
	}
	case 12:
		send_all(fd, "HEAD /events HTTP/1.0\r\n\r\n", 25);
		expect("HEAD /events", fd, CODES(200), false);
		return;
	case 13: { /* a viewer gone mid-stream */
		send_all(fd, "GET /events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 41);
		recv(fd, buf, 1000, 0);
		close(fd);
		printf("%-34s -> closed by us\n", "viewer gone mid-stream");
		return;
	}
	case 14: /* a viewer that reads nothing, held */
		send_all(fd, "GET /events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 41);
		if (n_held < HOLD_MAX) {
			int small = 1024;
			setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
			held[n_held++] = fd;
			printf("%-34s -> held open\n", "viewer reading nothing");
		} else {
			close(fd);
		}
		return;
	case 15: { /* a request in pieces with CRLF before it: fine */
		send_all(fd, "\r\nGET /?x=1 HT", 14);
		usleep(20000);
		send_all(fd, "TP/1.1\r\nhost: LOCALHOST:1\r\n\r\n", 29);
		expect("request in pieces", fd, CODES(200), false);
		return;
	}
	}
}

static int do_garbage(int n, double hold)
{
	for (int i = 0; i < n; i++)
		one_garbage(i);
	/* hold the open ones, trickling; good requests still answered meanwhile */
	double until = now() + hold;
	int k = 0;
	while (now() < until) {
		for (int i = 0; i < n_trickle; i++)
			send_all(trickle[i], "X", 1);
		if (k++ % 5 == 0) {
			size_t len;
			char *r = request("GET", "/status", &len);
			if (status_of(r) != 200) {
				printf("good request while held -> %d  WRONG\n", status_of(r));
				failures++;
			}
			free(r);
		}
		usleep(500000);
	}
	size_t len;
	char *r = request("GET", "/", &len);
	int code = status_of(r);
	bool page = strstr(r, "<canvas") != NULL;
	free(r);
	printf("good request after the garbage      -> %d%s\n", code, code == 200 && page ? "" : "  WRONG");
	failures += !(code == 200 && page);
	if (hold > 10.5) {
		/* past HTTP_HEADER_S: the unfinished requests are closed */
		int open = 0;
		for (int i = 0; i < n_trickle; i++) {
			char c[64];
			struct pollfd p = { trickle[i], POLLIN, 0 };
			ssize_t rr = poll(&p, 1, 0) > 0 ? recv(trickle[i], c, sizeof c, MSG_DONTWAIT) : 1;
			open += rr > 0;
		}
		printf("slow-loris still open past the deadline: %d of %d%s\n", open, n_trickle, open ? "  WRONG" : "");
		failures += open > 0;
	}
	for (int i = 0; i < n_held; i++)
		close(held[i]);
	for (int i = 0; i < n_trickle; i++)
		close(trickle[i]);
	printf("%d wrong answers\n", failures);
	return failures ? 1 : 0;
}

/* ---- the viewer limit ---- */

/* A stream request; returns the status code of its head (the socket kept in *fd). */
static int open_stream(int *fd)
{
	*fd = dial();
	int small = 2048;
	setsockopt(*fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
	char req[128];
	int n = snprintf(req, sizeof req, "GET /events HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n\r\n", port);
	send_all(*fd, req, (size_t)n);
	char head[64];
	size_t got = 0;
	while (got < 12) {
		struct pollfd p = { *fd, POLLIN, 0 };
		if (poll(&p, 1, 10000) <= 0)
			die("no answer to a stream request");
		ssize_t r = recv(*fd, head + got, 12 - got, 0);
		if (r <= 0)
			die("a stream request closed without an answer");
		got += (size_t)r;
	}
	head[got] = 0;
	return status_of(head);
}

static int do_viewers(int n)
{
	int *fds = calloc((size_t)n + 1, sizeof *fds);
	for (int i = 0; i < n; i++) {
		int code = open_stream(&fds[i]);
		if (code != 200)
			die("viewer %d of %d: %d, not 200", i + 1, n, code);
	}
	int extra, code = open_stream(&extra);
	printf("viewer %d: %d\n", n + 1, code);
	if (code != 503)
		die("viewer %d: %d, not 503", n + 1, code);
	close(extra);
	close(fds[0]);
	/* the server sees the close when it next writes or reads: retry a while */
	for (int k = 0;; k++) {
		usleep(100000);
		code = open_stream(&extra);
		close(extra);
		if (code == 200)
			break;
		if (k == 50)
			die("no room for a viewer after one left (%d)", code);
	}
	printf("a new viewer after one left: 200\n");
	for (int i = 1; i < n; i++)
		close(fds[i]);
	free(fds);
	return 0;
}

int main(int argc, char **argv)
{
	signal(SIGPIPE, SIG_IGN);
	t_start = now();
	if (argc == 3 && !strcmp(argv[1], "hash"))
		return do_hash(argv[2]);
	if (argc < 3)
		goto usage;
	port = atoi(argv[2]);
	if (port <= 0 || port > 65535)
		die("bad port '%s'", argv[2]);
	if (!strcmp(argv[1], "get") && (argc == 4 || argc == 5)) {
		size_t n;
		char *r = request(argc == 5 ? argv[4] : "GET", argv[3], &n);
		fwrite(r, 1, n, stdout);
		free(r);
		return n ? 0 : 1;
	}
	if (!strcmp(argv[1], "stream") && argc >= 4) {
		double after = 0, slow = 0, quiet = 0;
		for (int i = 4; i + 1 < argc; i += 2) {
			if (!strcmp(argv[i], "--after"))
				after = atof(argv[i + 1]);
			else if (!strcmp(argv[i], "--slow-for"))
				slow = atof(argv[i + 1]);
			else if (!strcmp(argv[i], "--quiet-for"))
				quiet = atof(argv[i + 1]);
			else
				goto usage;
		}
		return do_stream(argv[3], after, slow, quiet);
	}
	if (!strcmp(argv[1], "viewers") && argc == 4)
		return do_viewers(atoi(argv[3]));
	if (!strcmp(argv[1], "garbage") && argc >= 4) {
		double hold = 3;
		for (int i = 4; i + 1 < argc; i += 2) {
			if (!strcmp(argv[i], "--hold"))
				hold = atof(argv[i + 1]);
			else if (!strcmp(argv[i], "--seed"))
				rng = strtoull(argv[i + 1], NULL, 0) | 1;
			else
				goto usage;
		}
		return do_garbage(atoi(argv[3]), hold);
	}
usage:
	fprintf(stderr, "usage: liveclient get PORT PATH [METHOD] | stream PORT OUT.ppm [--after F] [--slow-for S]"
			" [--quiet-for S] | hash FILE.ppm | garbage PORT N [--hold S] [--seed X] | viewers PORT N\n");
	return 2;
}
