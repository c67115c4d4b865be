/*
 * delayproxy.c - a TCP proxy that adds a fixed one-way delay, for tests and
 * benchmarks of the farm over a slow link (the kernel here has no netem).
 *
 *   delayproxy --listen HOST:PORT [--port-file F] --to HOST:PORT --delay-ms D
 *              [--max-queue-mb N] [-q]
 *
 * Accepts any number of connections; for each it connects to the target and
 * forwards bytes both ways. Every chunk read is queued with its arrival time
 * and written D ms later, in order: a fixed one-way latency, no bandwidth cap
 * (it reads whatever is available). An EOF (the peer's shutdown or close, or
 * a reset) is queued like data and forwarded as a shutdown(SHUT_WR) once the
 * bytes ahead of it are out; a connection ends when both directions have
 * ended. A direction stops reading while its queue holds more than
 * --max-queue-mb (default 64) MiB, so a fast sender costs bounded memory.
 * One thread, one poll() loop whose timeout is the next release time.
 * SIGTERM or SIGINT: closes everything, exits 0. Logs one line per connection
 * opened and closed on stderr (-q: errors only).
 */
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "proto/net.h"
#include "tests/tools/stop.h"

/* bytes read per read() call: one chunk of a queue */
#define DP_READ_BYTES (64 * 1024)
/* bytes read from one socket per poll round: the others get their turn */
#define DP_ROUND_BYTES (1024 * 1024)
#define DP_QUEUE_MB_DEFAULT 64
/* seconds the listener rests after accept() failed (out of descriptors) */
#define DP_ACCEPT_PAUSE_S 0.1

/* One chunk read and waiting for its release time; len 0 is an EOF marker. */
struct dp_chunk {
	struct dp_chunk *next;
	double due;
	size_t len, off;
	unsigned char data[];
};

/* One direction of a connection: bytes read from src, written to dst. */
struct dp_dir {
	int src, dst;
	struct dp_chunk *head, *tail;
	size_t queued;     /* bytes in the queue */
	bool eof_read;     /* src said EOF (or failed): nothing more is read */
	bool done;         /* the EOF was forwarded (or dst failed): nothing more is written */
	unsigned long long bytes; /* forwarded */
};

/* One proxied connection: up = client to target, down = target to client. */
struct dp_pair {
	int client, target;
	bool connecting;   /* the connect to the target is in progress */
	char peer[96];
	double opened;
	struct dp_dir up, down;
};

static struct {
	double delay;      /* seconds */
	size_t max_queue;  /* bytes per direction */
	bool quiet;
	char host[NET_HOST_LEN], port[NET_PORT_LEN]; /* the target */
} opt;

static struct dp_pair **pairs;
static size_t n_pairs, cap_pairs;
static unsigned char rbuf[DP_READ_BYTES];

static void dir_init(struct dp_dir *d, int src, int dst)
{
	memset(d, 0, sizeof *d);
	d->src = src;
	d->dst = dst;
}

/* Appends a chunk of len bytes (0: the EOF marker), due at now + delay. 0 or -1 (out of memory). */
static int dir_push(struct dp_dir *d, const unsigned char *p, size_t len, double now)
{
	struct dp_chunk *c = malloc(sizeof *c + len);
	if (!c)
		return -1;
	c->next = NULL;
	c->due = now + opt.delay;
	c->len = len;
	c->off = 0;
	if (len)
		memcpy(c->data, p, len);
	if (d->tail)
		d->tail->next = c;
	else
		d->head = c;
	d->tail = c;
	d->queued += len;
	return 0;
}

static void dir_clear(struct dp_dir *d)
{
	while (d->head) {
		struct dp_chunk *c = d->head;
		d->head = c->next;
		free(c);
	}
	d->tail = NULL;
	d->queued = 0;
}

/* Reading is wanted: no EOF yet, room in the queue, someone to forward to. */
static bool dir_reading(const struct dp_pair *p, const struct dp_dir *d)
{
	return !p->connecting && !d->eof_read && d->queued <= opt.max_queue;
}

/* The head chunk is due and waits to be written. */
static bool dir_writing(const struct dp_pair *p, const struct dp_dir *d, double now)
{
	return !p->connecting && !d->done && d->head && d->head->due <= now;
}

/*
 * Reads what src has (up to DP_ROUND_BYTES) into the queue. After the
 * direction failed to write, bytes are read and dropped (the sender is not
 * left blocked); EOF or an error queues the EOF marker.
 */
static void dir_read(struct dp_dir *d, double now)
{
	size_t got = 0;
	while (got < DP_ROUND_BYTES && d->queued <= opt.max_queue) {
		ssize_t n = read(d->src, rbuf, sizeof rbuf);
		if (n < 0 && errno == EINTR)
			continue;
		if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK))
			return;
		if (n <= 0) { /* EOF, or a reset: both end this direction */
			d->eof_read = true;
			if (!d->done && dir_push(d, NULL, 0, now) < 0)
				d->done = true;
			return;
		}
		got += (size_t)n;
		if (d->done)
			continue;
		if (dir_push(d, rbuf, (size_t)n, now) < 0) {
			fprintf(stderr, "delayproxy: out of memory: dropping a connection's data\n");
			dir_clear(d);
			d->done = true;
		}
	}
}

/* Writes the chunks that are due; forwards a due EOF as shutdown(SHUT_WR). */
static void dir_write(struct dp_dir *d, double now)
{
	while (!d->done && d->head && d->head->due <= now) {
		struct dp_chunk *c = d->head;
		if (c->len == 0) {
			shutdown(d->dst, SHUT_WR);
			d->done = true;
		} else {
			ssize_t n = write(d->dst, c->data + c->off, c->len - c->off);
			if (n < 0 && errno == EINTR)
				continue;
			if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK))
				return;
			if (n < 0) { /* the receiver is gone: drop what waits for it */
				dir_clear(d);
				d->done = true;
				return;
			}
			c->off += (size_t)n;
			d->bytes += (unsigned long long)n;
			d->queued -= (size_t)n;
			if (c->off < c->len)
				return;
		}
		d->head = c->next;
		if (!d->head)
			d->tail = NULL;
		free(c);
	}
}

static void pair_close(size_t i, const char *how)
{
	struct dp_pair *p = pairs[i];
	if (!opt.quiet)
		fprintf(stderr, "delayproxy: %s: %s after %.2f s, %llu bytes up, %llu down\n", p->peer, how,
			net_now() - p->opened, p->up.bytes, p->down.bytes);
	dir_clear(&p->up);
	dir_clear(&p->down);
	close(p->client);
	if (p->target >= 0)
		close(p->target);
	free(p);
	pairs[i] = pairs[--n_pairs];
}

/* while out of descriptors the listener rests (it stays readable: poll would spin) */
static double accept_paused_until;

static void accept_all(int lfd, double now)
{
	for (;;) {
		char peer[96];
		int fd = net_accept(lfd, peer, sizeof peer);
		if (fd < 0) {
			if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
				fprintf(stderr, "delayproxy: accept: %s\n", strerror(errno));
				accept_paused_until = now + DP_ACCEPT_PAUSE_S;
			}
			return;
		}
		char err[300];
		int tfd = net_connect_start(opt.host, opt.port, err, sizeof err);
		struct dp_pair *p = calloc(1, sizeof *p);
		if (n_pairs == cap_pairs) {
			size_t nc = cap_pairs ? 2 * cap_pairs : 64;
			struct dp_pair **np = realloc(pairs, nc * sizeof *np);
			if (np) {
				pairs = np;
				cap_pairs = nc;
			}
		}
		if (tfd < 0 || !p || n_pairs == cap_pairs) {
			fprintf(stderr, "delayproxy: %s: refused: %s\n", peer, tfd < 0 ? err : "out of memory");
			if (tfd >= 0)
				close(tfd);
			close(fd);
			free(p);
			continue;
		}
		p->client = fd;
		p->target = tfd;
		p->connecting = true;
		p->opened = now;
		snprintf(p->peer, sizeof p->peer, "%s", peer);
		dir_init(&p->up, fd, tfd);
		dir_init(&p->down, tfd, fd);
		pairs[n_pairs++] = p;
	}
}

static void usage(FILE *f)
{
	fprintf(f, "Usage: delayproxy --listen HOST:PORT [--port-file F] --to HOST:PORT --delay-ms D\n"
		   "                  [--max-queue-mb N] [-q]\n"
		   "Forwards TCP connections to --to, each byte D ms after it arrived, both ways.\n");
}

enum { OPT_LISTEN = 256, OPT_PORTFILE, OPT_TO, OPT_DELAY, OPT_QUEUE };

int main(int argc, char **argv)
{
	static const struct option longopts[] = {
		{ "listen", required_argument, NULL, OPT_LISTEN },
		{ "port-file", required_argument, NULL, OPT_PORTFILE },
		{ "to", required_argument, NULL, OPT_TO },
		{ "delay-ms", required_argument, NULL, OPT_DELAY },
		{ "max-queue-mb", required_argument, NULL, OPT_QUEUE },
		{ "quiet", no_argument, NULL, 'q' },
		{ "help", no_argument, NULL, 'h' },
		{ NULL, 0, NULL, 0 },
	};
	const char *listen_at = NULL, *to = NULL, *port_file = NULL;
	long delay_ms = -1, queue_mb = DP_QUEUE_MB_DEFAULT;
	char *end;
	int c;
	while ((c = getopt_long(argc, argv, "qh", longopts, NULL)) != -1) {
		switch (c) {
		case OPT_LISTEN: listen_at = optarg; break;
		case OPT_PORTFILE: port_file = optarg; break;
		case OPT_TO: to = optarg; break;
		case OPT_DELAY:
			delay_ms = strtol(optarg, &end, 10);
			if (*end || end == optarg || delay_ms < 0 || delay_ms > 600000) {
				fprintf(stderr, "delayproxy: --delay-ms wants 0..600000, not '%s'\n", optarg);
				return 64;
			}
			break;
		case OPT_QUEUE:
			queue_mb = strtol(optarg, &end, 10);
			if (*end || end == optarg || queue_mb < 1 || queue_mb > 65536) {
				fprintf(stderr, "delayproxy: --max-queue-mb wants 1..65536, not '%s'\n", optarg);
				return 64;
			}
			break;
		case 'q': opt.quiet = true; break;
		case 'h': usage(stdout); return 0;
		default: usage(stderr); return 64;
		}
	}
	if (optind != argc || !listen_at || !to || delay_ms < 0) {
		usage(stderr);
		return 64;
	}
	opt.delay = delay_ms / 1000.0;
	opt.max_queue = (size_t)queue_mb << 20;
	char err[300], host[NET_HOST_LEN], port[NET_PORT_LEN];
	if (net_parse_hostport(to, opt.host, opt.port, err, sizeof err) < 0 ||
	    net_parse_hostport(listen_at, host, port, err, sizeof err) < 0) {
		fprintf(stderr, "delayproxy: %s\n", err);
		return 64;
	}
	int lfd = net_listen(host, port, err, sizeof err);
	if (lfd < 0) {
		fprintf(stderr, "delayproxy: %s\n", err);
		return 69;
	}
	if (port_file && net_write_number(port_file, net_local_port(lfd)) < 0) {
		fprintf(stderr, "delayproxy: cannot write %s: %s\n", port_file, strerror(errno));
		return 73;
	}
	if (stop_init() < 0) {
		perror("delayproxy: pipe");
		return 71;
	}
	if (!opt.quiet)
		fprintf(stderr, "delayproxy: listening on %s:%d, to %s, %ld ms each way\n", host, net_local_port(lfd),
			to, delay_ms);

	struct pollfd *pfd = NULL;
	size_t cap_pfd = 0;
	while (!stop_flag) {
		double now = net_now();
		/* write what is due, close what has ended */
		for (size_t i = 0; i < n_pairs;) {
			struct dp_pair *p = pairs[i];
			if (!p->connecting) {
				dir_write(&p->up, now);
				dir_write(&p->down, now);
			}
			if (p->up.done && p->down.done) /* both EOFs forwarded, or nobody to forward to */
				pair_close(i, "closed");
			else
				i++;
		}
		/* poll: the listener, client and target of every pair, the wake pipe */
		if (cap_pfd < 2 + 2 * n_pairs) {
			size_t nc = 2 * (2 + 2 * n_pairs);
			struct pollfd *np = realloc(pfd, nc * sizeof *np);
			if (!np) {
				fprintf(stderr, "delayproxy: out of memory\n");
				break;
			}
			pfd = np;
			cap_pfd = nc;
		}
		double next = INFINITY;
		pfd[0] = (struct pollfd){ .fd = now >= accept_paused_until ? lfd : -1, .events = POLLIN };
		pfd[1 + 2 * n_pairs] = (struct pollfd){ .fd = wake_pipe[0], .events = POLLIN };
		if (now < accept_paused_until)
			next = accept_paused_until;
		for (size_t i = 0; i < n_pairs; i++) {
			struct dp_pair *p = pairs[i];
			short ce = 0, te = 0;
			if (p->connecting) {
				te = POLLOUT;
			} else {
				if (dir_reading(p, &p->up))
					ce |= POLLIN;
				if (dir_reading(p, &p->down))
					te |= POLLIN;
				if (dir_writing(p, &p->up, now))
					te |= POLLOUT;
				if (dir_writing(p, &p->down, now))
					ce |= POLLOUT;
				for (int k = 0; k < 2; k++) {
					const struct dp_dir *d = k ? &p->down : &p->up;
					if (!d->done && d->head && d->head->due > now && d->head->due < next)
						next = d->head->due;
				}
			}
			/* no events wanted: not polled at all (a hang-up would wake us for ever) */
			pfd[1 + 2 * i] = (struct pollfd){ .fd = ce ? p->client : -1, .events = ce };
			pfd[2 + 2 * i] = (struct pollfd){ .fd = te ? p->target : -1, .events = te };
		}
		int timeout = -1;
		if (next < INFINITY)
			timeout = (int)ceil((next - now) * 1000);
		int k = poll(pfd, (nfds_t)(2 + 2 * n_pairs), timeout);
		if (k < 0 && errno != EINTR) {
			fprintf(stderr, "delayproxy: poll: %s\n", strerror(errno));
			break;
		}
		if (k <= 0)
			continue;
		now = net_now();
		size_t np = n_pairs; /* pairs accepted below are polled next round */
		for (size_t i = 0; i < np; i++) {
			struct dp_pair *p = pairs[i];
			short cr = pfd[1 + 2 * i].revents, tr = pfd[2 + 2 * i].revents;
			if (p->connecting) {
				if (!tr)
					continue;
				if (net_connect_finish(p->target, err, sizeof err) < 0) {
					fprintf(stderr, "delayproxy: %s: to %s: %s\n", p->peer, to, err);
					p->up.done = p->down.done = true; /* closed next round */
					p->up.eof_read = p->down.eof_read = true;
					continue;
				}
				p->connecting = false;
				if (!opt.quiet)
					fprintf(stderr, "delayproxy: %s: connected to %s\n", p->peer, to);
				continue;
			}
			if ((cr & (POLLIN | POLLHUP | POLLERR)) && dir_reading(p, &p->up))
				dir_read(&p->up, now);
			if ((tr & (POLLIN | POLLHUP | POLLERR)) && dir_reading(p, &p->down))
				dir_read(&p->down, now);
		}
		if (pfd[0].revents & POLLIN)
			accept_all(lfd, now);
	}
	while (n_pairs)
		pair_close(n_pairs - 1, "cut off");
	free(pairs);
	free(pfd);
	close(lfd);
	close(wake_pipe[0]);
	close(wake_pipe[1]);
	return 0;
}
