/*
 * progress.h - the render's progress on stderr, for the local render and
 * the farm alike (master/farm.c feeds it from the event loop).
 *
 * Three ways to show it (progress_mode_for):
 *   PROGRESS_BAR    stderr is a terminal: one line redrawn in place, fitted
 *                   to the terminal's width (read at every redraw), with a
 *                   bar, tiles, elapsed time, ETA and, on a farm, the rate of
 *                   the local threads and of each worker, abbreviated until
 *                   the line fits;
 *   PROGRESS_LINES  stderr is a pipe or a file: one whole line every
 *                   interval seconds (as POV-Ray and Blender print in a log),
 *                   and a last one at the end when any was printed;
 *   PROGRESS_OFF    -q.
 * The ETA divides the tiles left by an exponentially weighted tile rate
 * (time constant PROGRESS_TAU_S), not by elapsed/done, so a slow start, a
 * cheap first part of the image or a change of pace (a worker joining or
 * lost) is forgotten within seconds. Every function takes the time
 * (`now`, seconds on any monotonic clock) from the caller, so tests drive it
 * with a fake clock.
 */
#ifndef PORTRAY_PROGRESS_H
#define PORTRAY_PROGRESS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* the rate's memory: a sample this many seconds old weighs 1/e as much */
#define PROGRESS_TAU_S 3.0
/* the rate is sampled at most this often (shorter gaps are merged) */
#define PROGRESS_SAMPLE_S 0.15
/* no ETA before the first tile and this many seconds of rate samples */
#define PROGRESS_ETA_AFTER_S 1.0
/* terminal redraws at most this often */
#define PROGRESS_REDRAW_S 0.2
/* default seconds between lines off a terminal (--progress-interval) */
#define PROGRESS_LINES_DEFAULT_S 10.0
/* the line's length when the width cannot be known, and the longest one */
#define PROGRESS_COLS_DEFAULT 80
#define PROGRESS_LINE_MAX 1024

enum progress_mode { PROGRESS_OFF, PROGRESS_BAR, PROGRESS_LINES };

/* A worker as the farm line shows it. */
struct progress_peer {
	const char *name;
	double rate;       /* tiles/s lately */
	bool working;      /* ready and tracing */
	bool dropped;      /* gone for good */
};

/* What a farm adds to the line (NULL for a local render). */
struct progress_farm {
	double local_rate; /* tiles/s of the master's own threads */
	const struct progress_peer *peers;
	uint32_t n_peers;
};

struct progress {
	enum progress_mode mode;
	uint64_t total, done;
	double start;       /* now at progress_init */
	double interval;    /* PROGRESS_LINES: seconds between lines */
	double last_draw;   /* < 0: never */
	/* the smoothed rate */
	double rate;        /* tiles/s; < 0 until the first sample */
	double w_tiles, w_time; /* the weighted tiles and seconds (rate = their ratio) */
	double rate_t;      /* the last sample's time */
	uint64_t rate_done; /* done at that time */
	double first_t;     /* when done first went above 0 (< 0: not yet) */
	double sampled_s;   /* seconds of samples since then */
	bool drawn;         /* PROGRESS_BAR: something is on the line */
	unsigned lines;     /* PROGRESS_LINES: lines printed */
	int cols;           /* fixed width for tests; 0: ask the terminal */
};

/* Seconds on a monotonic clock. */
double progress_now(void);

/* PROGRESS_OFF when quiet, else BAR on a terminal, else LINES. */
enum progress_mode progress_mode_for(bool quiet);
/* Kept for callers that only ask whether to draw a bar. */
bool progress_wanted(bool quiet);

/* interval: PROGRESS_LINES' period (<= 0: PROGRESS_LINES_DEFAULT_S). */
void progress_init(struct progress *p, uint64_t total, enum progress_mode mode, double interval, double now);

/* Records done tiles at now and updates the smoothed rate. */
void progress_sample(struct progress *p, uint64_t done, double now);
/* Seconds left, or -1 when not known yet. */
double progress_eta(const struct progress *p, double now);

/*
 * The progress line (no newline, no escape codes) into buf (n bytes), at
 * most cols characters long (cols <= 0: no limit): the richest layout that
 * fits, then ones with shorter words, abbreviated worker names, the workers
 * summed up, and finally a hard cut. Returns its length.
 */
size_t progress_format(const struct progress *p, double now, int cols, const struct progress_farm *farm, char *buf,
		       size_t n);

/* The terminal's width on stderr (TIOCGWINSZ), else $COLUMNS, else PROGRESS_COLS_DEFAULT. */
int progress_columns(void);

/*
 * Samples done and shows the progress if it is time: a redraw at most
 * every PROGRESS_REDRAW_S on a terminal (and at once when done reaches
 * the total), a line every interval off one. Not thread-safe (the farm's
 * loop calls it).
 */
void progress_show(struct progress *p, uint64_t done, double now, const struct progress_farm *farm);
/* The end: on a terminal the bar's last state is cleared; off one a last
 * line is printed when any was printed before (short renders add none). */
void progress_finish(struct progress *p, uint64_t done, double now, const struct progress_farm *farm);
/* Clears the bar's line (before a message). */
void progress_clear(struct progress *p);

#endif
