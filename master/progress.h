/*
 * progress.h - the progress bar on stderr (percent, tiles, elapsed, ETA),
 * drawn only when asked to (stderr a terminal and not -q).
 */
#ifndef PORTRAY_PROGRESS_H
#define PORTRAY_PROGRESS_H

#include <stdbool.h>
#include <stdint.h>

struct progress {
	uint64_t total;     /* tiles in the image */
	uint64_t done;      /* tiles finished, last reported */
	double start;       /* progress_now() at progress_init */
	double last_draw;   /* when the bar was last drawn */
	bool draw;          /* draw the bar at all */
	bool drawn;         /* something is on the line (progress_end clears it) */
};

/* Seconds on a monotonic clock. */
double progress_now(void);

/* True when a bar should be drawn: stderr is a terminal and not quiet. */
bool progress_wanted(bool quiet);

void progress_init(struct progress *p, uint64_t total, bool draw);
/* Records done tiles; redraws at most ten times a second and at the end. Not
 * thread-safe: callers serialise (render_image calls its callback under a mutex). */
void progress_update(struct progress *p, uint64_t done);
/* Clears the bar's line. */
void progress_end(struct progress *p);
/* Seconds since progress_init. */
double progress_elapsed(const struct progress *p);

/* render_progress callback: arg is a struct progress. */
void progress_callback(void *arg, uint64_t done, uint64_t total);

#endif
