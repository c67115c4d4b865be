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
	EXIT_TOO_FEW = 75,    /* --min-workers: fewer workers joined (EX_TEMPFAIL: try again later) */
	EXIT_INTERRUPTED = 130, /* never used for a finished partial render; SIGTERM 143, SIGHUP 129 (128 + signal) */
	EXIT_JOURNAL = 65     /* --resume: the journal is another render's or damaged (EX_DATAERR) */
};

/* default --audit: about 3 tiles in 100 re-rendered locally (plus each
 * worker's first few), a few percent of the farm's work */
#define MASTER_AUDIT_DEFAULT 0.03
/* default --join-timeout: a worker's connect retries, handshake, scene
 * transfer and build fit with room to spare on a LAN */
#define MASTER_JOIN_TIMEOUT_DEFAULT 30.0

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
	/* issue 12: progress, --min-workers, preview switches */
	double progress_interval; /* --progress-interval S: seconds between lines off a terminal;
				   * 0 = none, < 0 = PROGRESS_LINES_DEFAULT_S */
	uint32_t min_workers;  /* --min-workers N: fail (EXIT_TOO_FEW) unless N workers join; 0 = none */
	double join_timeout_s; /* --join-timeout S: how long they may take (MASTER_JOIN_TIMEOUT_DEFAULT) */
	bool region;           /* --region X0,Y0,X1,Y1: only these pixels, written as a cropped image */
	uint32_t rx0, ry0, rx1, ry1; /* the region, x1 and y1 exclusive */
	bool no_aa;            /* --no-aa (--preview): the standard filter alone */
	bool no_shadows;       /* --no-shadows (--preview): no light casts shadows */
	bool no_reflections;   /* --no-reflections (--preview): no reflection rays */
	/* checkpoint and resume (master/journal.h) */
	bool resume;           /* --resume: continue from OUT.journal */
	double checkpoint_s;   /* --checkpoint S: seconds between checkpoints, 0 = only when the render stops;
				* main sets JOURNAL_INTERVAL_DEFAULT */
	bool keep_journal;     /* --keep-journal: keep OUT.journal after a finished render */
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
/* master/preview.c: applies --no-aa, --no-shadows, --no-reflections to the
 * parsed scene (before it is encoded for the wire: workers trace the same). */
struct scene;
void master_preview_apply(const struct master_opts *o, struct scene *s);
/* master/preview.c: checks --region against the image size w x h; 0, or
 * EXIT_USAGE after saying why. */
int master_region_check(const struct master_opts *o, uint32_t w, uint32_t h);

/* master/render.c: load, render (locally or on the farm), write; exit code. */
int master_render(const struct master_opts *o);

#endif
