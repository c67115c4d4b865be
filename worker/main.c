/*
 * main.c - portray-worker: a daemon that renders tiles for portray-master.
 *
 * This file is the command line, the signals and the daemon's setup; the
 * work is done by the rooms worker.h lists. One event-loop thread owns the
 * listening socket and every connection (server.c, conn.c); a pool of
 * tracer threads builds scenes and traces tiles (tracers.c), several
 * masters' jobs round-robin; scenes are cached by content hash (cache.c).
 * Protocol reference: docs/protocol.md.
 */
#include <errno.h>
#include <getopt.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "common/bvh.h"
#include "common/render.h"
#include "proto/net.h"
#include "proto/proto.h"
#include "worker/conn.h"

/* the one server, for the signal handler only */
static struct wk_server *g_for_signals;

void wk_log(const char *fmt, ...)
{
	char ts[32];
	time_t t = time(NULL);
	struct tm tm;
	gmtime_r(&t, &tm);
	strftime(ts, sizeof ts, "%Y-%m-%dT%H:%M:%SZ", &tm); /* ISO 8601, UTC */
	va_list ap;
	va_start(ap, fmt);
	flockfile(stderr);
	fprintf(stderr, "portray-worker %s ", ts);
	vfprintf(stderr, fmt, ap);
	fputc('\n', stderr);
	funlockfile(stderr);
	va_end(ap);
}

void wk_hex8(const uint8_t *h, char out[17])
{
	for (int i = 0; i < 8; i++)
		snprintf(out + 2 * i, 3, "%02x", h[i]);
}

/* SIGTERM, SIGINT: the loop ends at its next round (wk_server_stop is a
 * flag and one write to a pipe: async-signal-safe). */
static void on_signal(int sig)
{
	(void)sig;
	int e = errno;
	if (g_for_signals)
		wk_server_stop(g_for_signals);
	errno = e;
}

static void usage(FILE *f)
{
	fprintf(f,
		"Usage: portray-worker [OPTION]...\n"
		"Render tiles for portray-master: a daemon serving several masters at once.\n"
		"\n"
		"      --listen ADDR:PORT  where to listen (default 127.0.0.1:%d; port 0 = any)\n"
		"      --connect HOST:PORT dial a master started with --accept instead (again after\n"
		"                          every job, with back-off while none answers)\n"
		"  -j, --threads N         tracing threads (default: all cores)\n"
		"      --secret-file F     shared secret: masters must prove they know it\n"
		"      --port-file F       write the port listened on to F (useful with port 0)\n"
		"      --cache-mb N        scene cache budget in MiB of scene data (default %d)\n"
		"  -h, --help              show this help\n"
		"  -V, --version           show the version\n"
		"\n"
		"Logs a line when a job starts and one when it ends, on stderr.\n"
		"SIGTERM or SIGINT ends it cleanly.\n",
		PROTO_DEFAULT_PORT, WK_CACHE_MB_DEFAULT);
}

/* A whole decimal number in lo..hi from text: 0 with *out, or -1. */
static int parse_long(const char *text, long lo, long hi, long *out)
{
	char *end;
	errno = 0;
	long v = strtol(text, &end, 10);
	if (errno || end == text || *end || v < lo || v > hi)
		return -1;
	*out = v;
	return 0;
}

enum { OPT_LISTEN = 256, OPT_CONNECT, OPT_SECRET, OPT_PORTFILE, OPT_CACHE, OPT_FAULT, OPT_DELAY, OPT_HANDSHAKE };

/* Command line into o and the listen, secret and port-file strings; 0, or
 * the exit code (-1: --help or --version printed, exit 0). */
static int parse_args(int argc, char **argv, struct wk_opts *o, const char **listen_at, const char **connect_to,
		      const char **secret_file, const char **port_file)
{
	static const struct option longopts[] = {
		{ "listen", required_argument, NULL, OPT_LISTEN },
		{ "connect", required_argument, NULL, OPT_CONNECT },
		{ "threads", required_argument, NULL, 'j' },
		{ "secret-file", required_argument, NULL, OPT_SECRET },
		{ "port-file", required_argument, NULL, OPT_PORTFILE },
		{ "cache-mb", required_argument, NULL, OPT_CACHE },
		{ "test-fault", required_argument, NULL, OPT_FAULT },         /* hidden: for tests */
		{ "test-delay-ms", required_argument, NULL, OPT_DELAY },      /* hidden: for tests */
		{ "test-handshake-ms", required_argument, NULL, OPT_HANDSHAKE }, /* hidden: for tests */
		{ "help", no_argument, NULL, 'h' },
		{ "version", no_argument, NULL, 'V' },
		{ NULL, 0, NULL, 0 },
	};
	long v, cache_mb = WK_CACHE_MB_DEFAULT;
	int c;
	while ((c = getopt_long(argc, argv, "j:hV", longopts, NULL)) != -1) {
		switch (c) {
		case OPT_LISTEN: *listen_at = optarg; break;
		case OPT_CONNECT: *connect_to = optarg; break;
		case 'j':
			if (parse_long(optarg, 0, 4096, &v) < 0) {
				fprintf(stderr, "portray-worker: -j wants a number 0..4096, not '%s'\n", optarg);
				return WK_EXIT_USAGE;
			}
			o->threads = (int)v;
			break;
		case OPT_SECRET: *secret_file = optarg; break;
		case OPT_PORTFILE: *port_file = optarg; break;
		case OPT_CACHE:
			if (parse_long(optarg, 1, 1024 * 1024, &cache_mb) < 0) {
				fprintf(stderr, "portray-worker: --cache-mb wants a number 1..1048576, not '%s'\n", optarg);
				return WK_EXIT_USAGE;
			}
			break;
		case OPT_FAULT:
			if (wk_fault_parse(optarg, &o->faults.kind) < 0) {
				fprintf(stderr, "portray-worker: unknown --test-fault '%s'\n", optarg);
				return WK_EXIT_USAGE;
			}
			break;
		case OPT_DELAY:
			if (parse_long(optarg, 0, WK_DELAY_MAX_MS, &v) < 0) {
				fprintf(stderr, "portray-worker: --test-delay-ms wants 0..%d\n", WK_DELAY_MAX_MS);
				return WK_EXIT_USAGE;
			}
			o->faults.delay_ms = (int)v;
			break;
		case OPT_HANDSHAKE:
			if (parse_long(optarg, 1, 600000, &v) < 0) {
				fprintf(stderr, "portray-worker: --test-handshake-ms wants 1..600000\n");
				return WK_EXIT_USAGE;
			}
			o->handshake_s = v / 1000.0;
			break;
		case 'h': usage(stdout); return -1;
		case 'V':
			printf("portray-worker %s (protocol %u, %s)\n", PORTRAY_VERSION, PROTO_VERSION, proto_build_id());
			return -1;
		default: usage(stderr); return WK_EXIT_USAGE;
		}
	}
	if (optind != argc) {
		fprintf(stderr, "portray-worker: unexpected argument '%s'\n", argv[optind]);
		usage(stderr);
		return WK_EXIT_USAGE;
	}
	if (o->threads == 0)
		o->threads = render_ncpus();
	bvh_set_threads((unsigned)o->threads); /* -j bounds scene builds too */
	if (o->handshake_s == 0)
		o->handshake_s = WK_HANDSHAKE_S;
	o->cache_bytes = (uint64_t)cache_mb << 20;
	return 0;
}

/* Listens as asked and writes the port file: the socket, or -(exit code). */
static int start_listening(const char *listen_at, const char *port_file, char *host, int *bound)
{
	char err[512], port[NET_PORT_LEN];
	if (net_parse_hostport(listen_at, host, port, err, sizeof err) < 0) {
		fprintf(stderr, "portray-worker: --listen: %s\n", err);
		return -WK_EXIT_USAGE;
	}
	int lfd = net_listen(host, port, err, sizeof err);
	if (lfd < 0) {
		fprintf(stderr, "portray-worker: %s\n", err);
		return -WK_EXIT_UNAVAILABLE;
	}
	*bound = net_local_port(lfd);
	if (port_file && net_write_number(port_file, *bound) < 0) {
		fprintf(stderr, "portray-worker: cannot write %s: %s\n", port_file, strerror(errno));
		close(lfd);
		return -WK_EXIT_CANTCREAT;
	}
	return lfd;
}

int main(int argc, char **argv)
{
	struct wk_opts opt;
	memset(&opt, 0, sizeof opt);
	atomic_init(&opt.faults.traced, 0);
	/* listening is the default; with --connect only when --listen is given too */
	const char *listen_at = NULL, *connect_to = NULL, *secret_file = NULL, *port_file = NULL;
	int rc = parse_args(argc, argv, &opt, &listen_at, &connect_to, &secret_file, &port_file);
	if (rc)
		return rc < 0 ? WK_EXIT_OK : rc;
	char err[512], warn[512];
	if (secret_file &&
	    proto_read_secret(secret_file, &opt.secret, &opt.secret_len, err, sizeof err, warn, sizeof warn) < 0) {
		fprintf(stderr, "portray-worker: %s\n", err);
		return WK_EXIT_USAGE;
	}
	if (secret_file && warn[0])
		fprintf(stderr, "portray-worker: warning: --secret-file %s\n", warn);
	/* the pixel probe, rendered once before anything listens (a few ms): HELLO
	 * carries its fingerprint in the build id (proto_build_id) */
	if (strstr(proto_build_id(), "/probe-0000000000000000")) {
		fprintf(stderr, "portray-worker: the pixel probe could not be rendered (out of memory)\n");
		free(opt.secret);
		return WK_EXIT_OSERR;
	}
	char host[NET_HOST_LEN] = "";
	int bound = -1, lfd = -1;
	if (!connect_to && !listen_at)
		listen_at = "127.0.0.1:7411";
	if (listen_at) {
		lfd = start_listening(listen_at, port_file, host, &bound);
		if (lfd < 0) {
			free(opt.secret);
			return -lfd;
		}
		if (!opt.secret && !net_is_loopback(host))
			fprintf(stderr,
				"portray-worker: WARNING: listening on %s without --secret-file: anyone who can reach\n"
				"portray-worker: WARNING: port %d can make this machine trace for them; make a secret\n"
				"portray-worker: WARNING: (docs/deploy.md) or listen on 127.0.0.1\n",
				host, bound);
	}
	signal(SIGPIPE, SIG_IGN);
	/* the tracer threads are born with SIGTERM and SIGINT blocked, so the
	 * handler always runs on this thread, the event loop's */
	sigset_t stops, old;
	sigemptyset(&stops);
	sigaddset(&stops, SIGTERM);
	sigaddset(&stops, SIGINT);
	pthread_sigmask(SIG_BLOCK, &stops, &old);
	static struct wk_server srv;
	rc = wk_server_init(&srv, &opt, lfd);
	if (rc) {
		if (lfd >= 0)
			close(lfd);
		free(opt.secret);
		return rc;
	}
	if (connect_to && wk_dial_start(&srv, connect_to, err, sizeof err) < 0) {
		fprintf(stderr, "portray-worker: --connect: %s\n", err);
		wk_server_free(&srv);
		if (lfd >= 0)
			close(lfd);
		free(opt.secret);
		return WK_EXIT_USAGE;
	}
	g_for_signals = &srv;
	struct sigaction sa;
	memset(&sa, 0, sizeof sa);
	sa.sa_handler = on_signal;
	sigaction(SIGTERM, &sa, NULL);
	sigaction(SIGINT, &sa, NULL);
	pthread_sigmask(SIG_SETMASK, &old, NULL);
	if (lfd >= 0)
		wk_log("listening on %s:%d, %d threads, protocol %u, %s%s", host, bound, srv.threads, PROTO_VERSION,
		       proto_build_id(), opt.secret ? ", secret required" : "");
	if (connect_to)
		wk_log("dialling master %s, %d threads, protocol %u, %s%s", connect_to, srv.threads, PROTO_VERSION,
		       proto_build_id(), opt.secret ? ", secret required" : "");

	rc = wk_server_run(&srv) < 0 ? WK_EXIT_SOFTWARE : WK_EXIT_OK;
	if (rc)
		wk_log("event loop failed: %s", strerror(errno));
	/* a second signal during the shutdown ends the process at once */
	signal(SIGTERM, SIG_DFL);
	signal(SIGINT, SIG_DFL);
	wk_server_free(&srv);
	free(opt.secret);
	if (lfd >= 0)
		close(lfd);
	return rc;
}
