/*
 * progress.c - the progress bar on stderr (progress.h).
 */
#include "master/progress.h"

#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* Redraw interval: ten times a second is smooth and costs nothing. */
#define PROGRESS_INTERVAL_S 0.1
/* Cells in the bar itself; the whole line stays under 80 columns. */
#define PROGRESS_BAR_CELLS 24

double progress_now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

bool progress_wanted(bool quiet)
{
	return !quiet && isatty(STDERR_FILENO);
}

void progress_init(struct progress *p, uint64_t total, bool draw)
{
	memset(p, 0, sizeof *p);
	p->total = total;
	p->draw = draw;
	p->start = progress_now();
	p->last_draw = -1;
}

double progress_elapsed(const struct progress *p)
{
	return progress_now() - p->start;
}

/* h:mm:ss, or m:ss under an hour. */
static void fmt_time(char *buf, size_t n, double s)
{
	if (!(s >= 0) || s > 360000)
		s = 0;
	unsigned t = (unsigned)(s + 0.5);
	if (t >= 3600)
		snprintf(buf, n, "%u:%02u:%02u", t / 3600, t / 60 % 60, t % 60);
	else
		snprintf(buf, n, "%u:%02u", t / 60, t % 60);
}

static void draw(struct progress *p, double now)
{
	double frac = p->total ? (double)p->done / (double)p->total : 1.0;
	char bar[PROGRESS_BAR_CELLS + 1];
	int full = (int)(frac * PROGRESS_BAR_CELLS);
	for (int i = 0; i < PROGRESS_BAR_CELLS; i++)
		bar[i] = i < full ? '#' : '.';
	bar[PROGRESS_BAR_CELLS] = '\0';
	double el = now - p->start;
	char elapsed[16], eta[16];
	fmt_time(elapsed, sizeof elapsed, el);
	if (p->done > 0 && p->done < p->total)
		fmt_time(eta, sizeof eta, el / frac - el);
	else
		snprintf(eta, sizeof eta, p->done ? "0:00" : "-:--");
	fprintf(stderr, "\r%3d%% [%s] %llu/%llu tiles  %s elapsed  ETA %s\033[K", (int)(frac * 100), bar,
		(unsigned long long)p->done, (unsigned long long)p->total, elapsed, eta);
	fflush(stderr);
	p->drawn = true;
	p->last_draw = now;
}

void progress_update(struct progress *p, uint64_t done)
{
	p->done = done;
	if (!p->draw)
		return;
	double now = progress_now();
	if (done == p->total || p->last_draw < 0 || now - p->last_draw >= PROGRESS_INTERVAL_S)
		draw(p, now);
}

void progress_end(struct progress *p)
{
	if (p->drawn) {
		fputs("\r\033[K", stderr);
		fflush(stderr);
	}
	p->drawn = false;
}

void progress_callback(void *arg, uint64_t done, uint64_t total)
{
	struct progress *p = arg;
	p->total = total;
	progress_update(p, done);
}
