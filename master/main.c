/*
 * main.c - portray-master: command line parsing and dispatch.
 */
#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/img.h"
#include "common/tiles.h"
#include "master/journal.h"
#include "master/master.h"
#include "master/sched.h"
#include "proto/net.h"

static void usage(FILE *f)
{
	fprintf(f,
		"Usage: portray-master [OPTION]... [-c CAMERA] SCENE\n"
		"Render a PortRAY scene, locally on all cores or on a farm of portray-worker daemons.\n"
		"\n"
		"  -c, --camera FILE        camera file (camera, image and light statements)\n"
		"  -o, --output FILE        output image, .png .ppm .pfm or .exr (default: SCENE with\n"
		"                           .png); - for standard output (PNG unless --format)\n"
		"      --format F           png, png16, ppm, pfm, exr (float) or exr-half; the default\n"
		"                           is the one the output's extension names\n"
		"      --render-time        write the render time as a PNG text / EXR attribute (two\n"
		"                           renders then differ in it; default: left out, the same\n"
		"                           render gives the same bytes; --no-render-time says so)\n"
		"      --check              parse the scene, print a summary, exit with its error level\n"
		"  -j, --threads N          local threads (default: all cores)\n"
		"      --tile N             tile side in pixels (default %u)\n"
		"      --size WxH           override the image statement's size\n"
		"  -q, --quiet              no progress bar or summary\n"
		"  -w, --workers LIST       HOST:PORT[,HOST:PORT...] of portray-worker daemons\n"
		"      --workers-file FILE  one HOST:PORT per line ('#' comments); a name with several\n"
		"                           addresses (-w too) is one worker per address\n"
		"      --accept ADDR:PORT   take workers that dial in (portray-worker --connect);\n"
		"                           port 0 = any (see --port-file)\n"
		"      --port-file FILE     write the --accept port to FILE\n"
		"      --insecure           allow --accept beyond loopback without --secret-file\n"
		"      --secret-file FILE   shared secret for the worker handshake\n"
		"      --no-local           do not trace on this machine, workers only\n"
		"      --heartbeat-timeout S  drop a worker silent for S seconds, or stalled that long\n"
		"                           in a handshake step or scene transfer (default 10)\n"
		"      --audit F            re-render fraction F (0..1) of worker tiles here to check\n"
		"                           them (default 0.03; 0: no audits; see docs/protocol.md)\n"
		"      --progress-interval S  seconds between progress lines when stderr is not a\n"
		"                           terminal (default 10; 0: none; on a terminal: a bar)\n"
		"      --min-workers N      exit 75 unless N workers join (get ready to trace);\n"
		"                           the local threads wait for them\n"
		"      --join-timeout S     how long --min-workers waits for them (default 30)\n"
		"      --region X0,Y0,X1,Y1 only the pixels X0..X1-1, Y0..Y1-1, into a cropped\n"
		"                           image (the same bytes as a full render's)\n"
		"      --preview            quick look: --no-aa --no-shadows --no-reflections\n"
		"      --no-aa              one ray a pixel: the standard filter alone\n"
		"      --no-shadows         no light casts shadows\n"
		"      --no-reflections     no reflection rays\n"
		"      --resume             continue the render from the journal OUT.journal, tracing\n"
		"                           only the tiles it lacks (none there: render from the start)\n"
		"      --checkpoint S       write the journal every S seconds (default %g; 0: only when\n"
		"                           the render stops: q, Esc, SIGINT, SIGTERM, SIGHUP)\n"
		"      --keep-journal       keep OUT.journal after the render finished\n"
		"      --http ADDR:PORT     serve a live view of the render (a web page) on ADDR:PORT;\n"
		"                           loopback only unless --http-public; port 0 = any (see\n"
		"                           --http-port-file; docs/live-view.md)\n"
		"      --http-port-file FILE  write the --http port to FILE\n"
		"      --http-public        allow --http beyond loopback (anyone who reaches it sees\n"
		"                           the render)\n"
		"      --http-linger S      after the render, serve the finished image S seconds more\n"
		"                           before writing the output (q or Ctrl-C ends it)\n"
		"  -h, --help               show this help\n"
		"  -V, --version            show the version\n"
		"\n"
		"Exit status: 0 success; 1 and 2 the PortRAY manual's error levels (Appendix B);\n"
		"64 usage (an unknown output extension too); 65 --resume refused: the journal is\n"
		"another render's or damaged; 69 no worker left with --no-local; 74 output not\n"
		"written (a missing or read-only directory is found before rendering); 75 fewer\n"
		"workers joined than --min-workers; 130, 143, 129 stopped by SIGINT, SIGTERM,\n"
		"SIGHUP (the finished part and journal written).\n",
		TILE_DEFAULT, JOURNAL_INTERVAL_DEFAULT);
}

static int parse_uint(const char *s, unsigned long max, unsigned long *out)
{
	char *end;
	errno = 0;
	unsigned long v = strtoul(s, &end, 10);
	if (errno || end == s || *end || v > max || s[0] == '-')
		return -1;
	*out = v;
	return 0;
}

/*
 * --http and its companions, refused at once (before any parsing or
 * tracing): a bad address, an address beyond loopback without
 * --http-public, a companion without --http. 0, or -1 after saying why.
 */
static int check_http(const struct master_opts *o)
{
	if (!o->http) {
		if (o->http_port_file || o->http_public || o->http_linger > 0) {
			fprintf(stderr, "portray-master: --http-port-file, --http-public and --http-linger go with --http\n");
			return -1;
		}
		return 0;
	}
	char host[NET_HOST_LEN], port[NET_PORT_LEN], err[300];
	if (net_parse_hostport(o->http, host, port, err, sizeof err) < 0) {
		fprintf(stderr, "portray-master: --http: %s\n", err);
		return -1;
	}
	if (!o->http_public && !net_is_loopback(host)) {
		fprintf(stderr,
			"portray-master: --http %s would show the render to anyone who reaches it; give a loopback\n"
			"portray-master: address (127.0.0.1:PORT) or, to mean it, --http-public\n",
			o->http);
		return -1;
	}
	return 0;
}

enum { OPT_CHECK = 256, OPT_TILE, OPT_SIZE, OPT_WFILE, OPT_SECRET, OPT_NOLOCAL, OPT_HB, OPT_AUDIT, OPT_ACCEPT,
       OPT_PORTFILE, OPT_INSECURE, OPT_FORMAT, OPT_NO_RTIME, OPT_RTIME,
       /* issue 12: progress, --min-workers, preview switches */
       OPT_PINTERVAL, OPT_MINW, OPT_JOINTO, OPT_REGION, OPT_PREVIEW, OPT_NOAA, OPT_NOSHADOWS, OPT_NOREFL,
       /* issue 12: checkpoint and resume */
       OPT_RESUME, OPT_CHECKPOINT, OPT_KEEP_JOURNAL,
       /* issue 12: the live view */
       OPT_HTTP, OPT_HTTP_PORTFILE, OPT_HTTP_PUBLIC, OPT_HTTP_LINGER };

/* seconds in 0..max (zero_ok), or -1 */
static int parse_seconds(const char *s, double max, bool zero_ok, double *out)
{
	char *end;
	errno = 0;
	double v = strtod(s, &end);
	if (errno || end == s || *end || !(v >= 0 && v <= max) || (v == 0 && !zero_ok))
		return -1;
	*out = v;
	return 0;
}

int main(int argc, char **argv)
{
	static const struct option longopts[] = {
		{ "camera", required_argument, NULL, 'c' },
		{ "output", required_argument, NULL, 'o' },
		{ "check", no_argument, NULL, OPT_CHECK },
		{ "threads", required_argument, NULL, 'j' },
		{ "tile", required_argument, NULL, OPT_TILE },
		{ "size", required_argument, NULL, OPT_SIZE },
		{ "quiet", no_argument, NULL, 'q' },
		{ "workers", required_argument, NULL, 'w' },
		{ "workers-file", required_argument, NULL, OPT_WFILE },
		{ "secret-file", required_argument, NULL, OPT_SECRET },
		{ "no-local", no_argument, NULL, OPT_NOLOCAL },
		{ "heartbeat-timeout", required_argument, NULL, OPT_HB },
		{ "audit", required_argument, NULL, OPT_AUDIT },
		{ "accept", required_argument, NULL, OPT_ACCEPT },
		{ "port-file", required_argument, NULL, OPT_PORTFILE },
		{ "insecure", no_argument, NULL, OPT_INSECURE },
		{ "format", required_argument, NULL, OPT_FORMAT },
		{ "no-render-time", no_argument, NULL, OPT_NO_RTIME },
		{ "render-time", no_argument, NULL, OPT_RTIME },
		{ "progress-interval", required_argument, NULL, OPT_PINTERVAL },
		{ "min-workers", required_argument, NULL, OPT_MINW },
		{ "join-timeout", required_argument, NULL, OPT_JOINTO },
		{ "region", required_argument, NULL, OPT_REGION },
		{ "preview", no_argument, NULL, OPT_PREVIEW },
		{ "no-aa", no_argument, NULL, OPT_NOAA },
		{ "no-shadows", no_argument, NULL, OPT_NOSHADOWS },
		{ "no-reflections", no_argument, NULL, OPT_NOREFL },
		{ "resume", no_argument, NULL, OPT_RESUME },
		{ "checkpoint", required_argument, NULL, OPT_CHECKPOINT },
		{ "keep-journal", no_argument, NULL, OPT_KEEP_JOURNAL },
		{ "http", required_argument, NULL, OPT_HTTP },
		{ "http-port-file", required_argument, NULL, OPT_HTTP_PORTFILE },
		{ "http-public", no_argument, NULL, OPT_HTTP_PUBLIC },
		{ "http-linger", required_argument, NULL, OPT_HTTP_LINGER },
		{ "help", no_argument, NULL, 'h' },
		{ "version", no_argument, NULL, 'V' },
		{ NULL, 0, NULL, 0 },
	};
	struct master_opts o = { .no_render_time = true, .tile = 0 /* TILE_DEFAULT */, .heartbeat_s = 10.0, .audit = MASTER_AUDIT_DEFAULT,
				  .progress_interval = -1, .join_timeout_s = MASTER_JOIN_TIMEOUT_DEFAULT };
	o.checkpoint_s = JOURNAL_INTERVAL_DEFAULT;
	unsigned long v;
	int c;
	while ((c = getopt_long(argc, argv, "c:o:j:qw:hV", longopts, NULL)) != -1) {
		switch (c) {
		case 'c': o.camera = optarg; break;
		case 'o': o.out = optarg; break;
		case OPT_CHECK: o.check = true; break;
		case 'j':
			if (parse_uint(optarg, 4096, &v) < 0) {
				fprintf(stderr, "portray-master: -j wants a number 0..4096, not '%s'\n", optarg);
				return EXIT_USAGE;
			}
			o.threads = (int)v;
			break;
		case OPT_TILE:
			if (parse_uint(optarg, 4096, &v) < 0 || v == 0) {
				fprintf(stderr, "portray-master: --tile wants a number 1..4096, not '%s'\n", optarg);
				return EXIT_USAGE;
			}
			o.tile = (uint32_t)v;
			break;
		case OPT_SIZE: {
			unsigned w, h;
			char extra;
			if (sscanf(optarg, "%ux%u%c", &w, &h, &extra) != 2 || w == 0 || h == 0 || w > 65536 ||
			    h > 65536) {
				fprintf(stderr, "portray-master: --size wants WxH (e.g. 640x480), not '%s'\n", optarg);
				return EXIT_USAGE;
			}
			o.width = w;
			o.height = h;
			break;
		}
		case 'q': o.quiet = true; break;
		case 'w': o.workers = optarg; break;
		case OPT_WFILE: o.workers_file = optarg; break;
		case OPT_SECRET: o.secret_file = optarg; break;
		case OPT_NOLOCAL: o.no_local = true; break;
		case OPT_ACCEPT: o.accept = optarg; break;
		case OPT_PORTFILE: o.port_file = optarg; break;
		case OPT_INSECURE: o.insecure = true; break;
		case OPT_FORMAT: {
			enum img_format f;
			if (img_format_parse(optarg, &f) < 0) {
				fprintf(stderr, "portray-master: --format wants png, png16, ppm, pfm, exr or exr-half, "
					"not '%s'\n", optarg);
				return EXIT_USAGE;
			}
			o.format = optarg;
			break;
		}
		case OPT_NO_RTIME: o.no_render_time = true; break;
		case OPT_RTIME: o.no_render_time = false; break;
		case OPT_HB: {
			char *end;
			o.heartbeat_s = strtod(optarg, &end);
			if (*end || !(o.heartbeat_s > 0 && o.heartbeat_s < 86400)) {
				fprintf(stderr, "portray-master: --heartbeat-timeout wants seconds, not '%s'\n", optarg);
				return EXIT_USAGE;
			}
			break;
		}
		case OPT_AUDIT: {
			char *end;
			o.audit = strtod(optarg, &end);
			if (end == optarg || *end || !(o.audit >= 0 && o.audit <= 1)) {
				fprintf(stderr, "portray-master: --audit wants a fraction 0..1, not '%s'\n", optarg);
				return EXIT_USAGE;
			}
			break;
		}
		case OPT_PINTERVAL:
			if (parse_seconds(optarg, 86400, true, &o.progress_interval) < 0) {
				fprintf(stderr, "portray-master: --progress-interval wants seconds 0..86400, not '%s'\n", optarg);
				return EXIT_USAGE;
			}
			break;
		case OPT_MINW:
			if (parse_uint(optarg, SCHED_MAX_WORKERS, &v) < 0) {
				fprintf(stderr, "portray-master: --min-workers wants a number 0..%u, not '%s'\n",
					SCHED_MAX_WORKERS, optarg);
				return EXIT_USAGE;
			}
			o.min_workers = (uint32_t)v;
			break;
		case OPT_JOINTO:
			if (parse_seconds(optarg, 86400, false, &o.join_timeout_s) < 0) {
				fprintf(stderr, "portray-master: --join-timeout wants seconds (0..86400], not '%s'\n", optarg);
				return EXIT_USAGE;
			}
			break;
		case OPT_REGION: {
			unsigned x0, y0, x1, y1;
			char extra;
			if (sscanf(optarg, "%u,%u,%u,%u%c", &x0, &y0, &x1, &y1, &extra) != 4 || optarg[0] == '-' ||
			    strchr(optarg, '-') || x1 <= x0 || y1 <= y0) {
				fprintf(stderr, "portray-master: --region wants X0,Y0,X1,Y1 with X0 < X1 and Y0 < Y1 "
					"(pixels, X1 and Y1 excluded), not '%s'\n", optarg);
				return EXIT_USAGE;
			}
			o.region = true;
			o.rx0 = x0, o.ry0 = y0, o.rx1 = x1, o.ry1 = y1;
			break;
		}
		case OPT_PREVIEW: o.no_aa = o.no_shadows = o.no_reflections = true; break;
		case OPT_NOAA: o.no_aa = true; break;
		case OPT_NOSHADOWS: o.no_shadows = true; break;
		case OPT_NOREFL: o.no_reflections = true; break;
		case OPT_RESUME: o.resume = true; break;
		case OPT_KEEP_JOURNAL: o.keep_journal = true; break;
		case OPT_CHECKPOINT: {
			char *end;
			o.checkpoint_s = strtod(optarg, &end);
			if (end == optarg || *end || !(o.checkpoint_s >= 0 && o.checkpoint_s <= 86400)) {
				fprintf(stderr, "portray-master: --checkpoint wants seconds 0..86400, not '%s'\n", optarg);
				return EXIT_USAGE;
			}
			break;
		}
		case OPT_HTTP: o.http = optarg; break;
		case OPT_HTTP_PORTFILE: o.http_port_file = optarg; break;
		case OPT_HTTP_PUBLIC: o.http_public = true; break;
		case OPT_HTTP_LINGER: {
			char *end;
			o.http_linger = strtod(optarg, &end);
			if (end == optarg || *end || !(o.http_linger >= 0 && o.http_linger <= 86400)) {
				fprintf(stderr, "portray-master: --http-linger wants seconds 0..86400, not '%s'\n", optarg);
				return EXIT_USAGE;
			}
			break;
		}
		case 'h': usage(stdout); return 0;
		case 'V': printf("portray-master %s (PortRAY 0.11 scene language)\n", PORTRAY_VERSION); return 0;
		default: usage(stderr); return EXIT_USAGE;
		}
	}
	if (optind != argc - 1) {
		fprintf(stderr, "portray-master: %s\n", optind >= argc ? "no scene file given" : "one scene file, please");
		usage(stderr);
		return EXIT_USAGE;
	}
	o.scene = argv[optind];
	if (o.min_workers && !o.workers && !o.workers_file && !o.accept) {
		fprintf(stderr, "portray-master: --min-workers wants workers: -w, --workers-file or --accept\n");
		return EXIT_USAGE;
	}
	if (o.accept) {
		/* refused at once, before any parsing or tracing */
		char host[NET_HOST_LEN], port[NET_PORT_LEN], err[300];
		if (net_parse_hostport(o.accept, host, port, err, sizeof err) < 0) {
			fprintf(stderr, "portray-master: --accept: %s\n", err);
			return EXIT_USAGE;
		}
		if (!o.secret_file && !o.insecure && !net_is_loopback(host)) {
			fprintf(stderr,
				"portray-master: --accept %s without --secret-file would let anyone who reaches it\n"
				"portray-master: pose as a worker; give --secret-file (docs/deploy.md) or --insecure\n",
				o.accept);
			return EXIT_USAGE;
		}
	}
	if (check_http(&o) < 0)
		return EXIT_USAGE;
	return o.check ? master_check(&o) : master_render(&o);
}
