/*
 * master.h - the portray-master command: options shared by every mode.
 */
#ifndef PORTRAY_MASTER_H
#define PORTRAY_MASTER_H

#include <stdbool.h>
#include <stdint.h>

/* Exit codes beyond the manual's Appendix B levels (0, 1, 2). */
enum {
	EXIT_USAGE = 64,      /* bad command line (sysexits EX_USAGE) */
	EXIT_IO = 74,         /* could not write the output image (EX_IOERR) */
	EXIT_NO_WORKERS = 69, /* --no-local and every worker lost (EX_UNAVAILABLE) */
	EXIT_INTERRUPTED = 130 /* never used for a finished partial render */
};

/* default --audit: about 3 tiles in 100 re-rendered locally (plus each
 * worker's first few), a few percent of the farm's work */
#define MASTER_AUDIT_DEFAULT 0.03

struct master_opts {
	const char *camera;    /* -c FILE, may be NULL */
	const char *scene;     /* SCENE */
	const char *out;       /* -o FILE ("-": standard output), default: scene name with .png */
	const char *format;    /* --format NAME (img_format_parse), NULL: by the extension of out */
	bool no_render_time;   /* no render-time text (the default: files stay byte-identical); --render-time clears it */
	bool check;            /* --check: parse and summarise only */
	int threads;           /* -j N, 0 = all cores */
	uint32_t tile;         /* --tile N, 0 = TILE_DEFAULT (common/tiles.h) */
	uint32_t width, height; /* --size WxH, 0 = from the image statement */
	bool quiet;            /* -q */
	const char *workers;   /* -w HOST:PORT[,HOST:PORT...] */
	const char *workers_file; /* --workers-file F */
	const char *secret_file;  /* --secret-file F */
	const char *accept;       /* --accept ADDR:PORT: workers that dial in (--connect) */
	const char *port_file;    /* --port-file F: the --accept port, written once listening */
	bool insecure;            /* --insecure: --accept beyond loopback without a secret */
	bool no_local;         /* --no-local */
	double heartbeat_s;    /* --heartbeat-timeout S (farm) */
	double audit;          /* --audit F: fraction of worker tiles re-rendered here to check them (farm);
				* 0 = no audits; main sets MASTER_AUDIT_DEFAULT */
	/* the live view (master/http.h, docs/live-view.md) */
	const char *http;          /* --http ADDR:PORT, or NULL */
	const char *http_port_file; /* --http-port-file F: the --http port, written once listening */
	bool http_public;          /* --http-public: --http beyond loopback */
	double http_linger;        /* --http-linger S: serve the finished image S seconds more */
};

struct scene_camera;
/* Prints the camera's ignored-filter warnings (filter_warnings) on stderr:
 * --check and rendering say the same (master/check.c). */
void master_filter_warnings(const struct scene_camera *c);

/* master/check.c: parse everything, print the summary, return the error level. */
int master_check(const struct master_opts *o);
/* master/render.c: load, render (locally or on the farm), write; exit code. */
int master_render(const struct master_opts *o);

#endif
