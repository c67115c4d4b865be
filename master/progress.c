/*
 * progress.c - the render's progress on stderr (progress.h).
 */
#include "master/progress.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <time.h>
#include <unistd.h>

/* cells of the bar: at most, and the fewest worth drawing */
#define BAR_CELLS_MAX 30
#define BAR_CELLS_MIN 8
/* a worker's name abbreviated to this many characters at most */
#define NAME_SHORT 14

double progress_now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

enum progress_mode progress_mode_for(bool quiet)
{
	if (quiet)
		return PROGRESS_OFF;
	return isatty(STDERR_FILENO) ? PROGRESS_BAR : PROGRESS_LINES;
}

bool progress_wanted(bool quiet)
{
	return progress_mode_for(quiet) == PROGRESS_BAR;
}

void progress_init(struct progress *p, uint64_t total, enum progress_mode mode, double interval, double now)
{
	memset(p, 0, sizeof *p);
	p->mode = mode;
	p->total = total;
	p->start = now;
	p->interval = interval > 0 ? interval : PROGRESS_LINES_DEFAULT_S;
	p->last_draw = -1;
	p->rate = -1;
	p->first_t = -1;
}

/*
 * The rate is exponentially weighted tiles over exponentially weighted
 * time: each sample's tiles and seconds fade by exp(-age / PROGRESS_TAU_S),
 * and the rate is their ratio. It needs no prior and no start-up guess:
 * sampling starts at the first finished tile (the time before it is
 * scene transfer, build and the first tiles in flight, not a pace).
 */
void progress_sample(struct progress *p, uint64_t done, double now)
{
	if (done > p->total)
		done = p->total;
	p->done = done;
	if (p->first_t < 0) {
		if (done > 0) {
			p->first_t = p->rate_t = now;
			p->rate_done = done;
		}
		return;
	}
	double dt = now - p->rate_t;
	if (dt < PROGRESS_SAMPLE_S || done < p->rate_done)
		return;
	double d = exp(-dt / PROGRESS_TAU_S);
	p->w_tiles = p->w_tiles * d + (double)(done - p->rate_done);
	p->w_time = p->w_time * d + dt;
	p->rate = p->w_tiles / p->w_time;
	p->rate_t = now;
	p->rate_done = done;
	p->sampled_s += dt;
}

double progress_eta(const struct progress *p, double now)
{
	(void)now;
	if (p->done >= p->total)
		return 0;
	if (p->first_t < 0 || p->sampled_s < PROGRESS_ETA_AFTER_S || !(p->rate > 0))
		return -1;
	return (double)(p->total - p->done) / p->rate;
}

/* h:mm:ss, or m:ss under an hour; "-:--" when s < 0. */
static void fmt_time(char *buf, size_t n, double s)
{
	if (!(s >= 0)) {
		snprintf(buf, n, "-:--");
		return;
	}
	if (s > 359999)
		s = 359999;
	unsigned t = (unsigned)(s + 0.5);
	if (t >= 3600)
		snprintf(buf, n, "%u:%02u:%02u", t / 3600, t / 60 % 60, t % 60);
	else
		snprintf(buf, n, "%u:%02u", t / 60, t % 60);
}

/* A string that grows up to its buffer (snprintf that keeps count). */
struct sbuf {
	char *s;
	size_t n, len;
};

static void sb_add(struct sbuf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void sb_add(struct sbuf *b, const char *fmt, ...)
{
	if (b->len + 1 >= b->n)
		return;
	va_list ap;
	va_start(ap, fmt);
	int k = vsnprintf(b->s + b->len, b->n - b->len, fmt, ap);
	va_end(ap);
	if (k > 0)
		b->len = b->len + (size_t)k < b->n ? b->len + (size_t)k : b->n - 1;
}

/* name without its domain ("node-7.example.com:7070" -> "node-7:7070"),
 * then its last characters after a '~': host numbers and ports tell
 * workers apart, and they are at the end */
static void short_name(char *out, size_t n, const char *name)
{
	char tmp[256];
	const char *colon = strrchr(name, ':'), *dot = strchr(name, '.');
	bool numeric = (name[0] >= '0' && name[0] <= '9') || name[0] == '[';
	if (!numeric && dot && colon && dot < colon)
		snprintf(tmp, sizeof tmp, "%.*s%s", (int)(dot - name), name, colon);
	else
		snprintf(tmp, sizeof tmp, "%s", name);
	size_t len = strlen(tmp);
	if (len <= NAME_SHORT)
		snprintf(out, n, "%s", tmp);
	else
		snprintf(out, n, "~%s", tmp + len - (NAME_SHORT - 1));
}

/*
 * The line in layout k (0 richest), without its bar: bar_at gets the
 * offset where a bar "[###...] " may be put (after the percentage).
 */
static size_t layout(const struct progress *p, double now, int k, const struct progress_farm *farm, char *buf,
		     size_t n, size_t *bar_at)
{
	struct sbuf b = { buf, n, 0 };
	buf[0] = '\0';
	unsigned pct = p->total ? (unsigned)(100 * p->done / p->total) : 100;
	char el[24], eta[24];
	fmt_time(el, sizeof el, now - p->start);
	fmt_time(eta, sizeof eta, progress_eta(p, now));
	sb_add(&b, "%3u%% ", pct);
	*bar_at = b.len;
	unsigned long long d = p->done, t = p->total;
	switch (k) {
	case 0: sb_add(&b, "%llu/%llu tiles  %s elapsed  ETA %s", d, t, el, eta); break;
	case 1: sb_add(&b, "%llu/%llu  %s  ETA %s", d, t, el, eta); break;
	case 2:
	case 3: sb_add(&b, "%llu/%llu ETA %s", d, t, eta); break;
	default: sb_add(&b, "ETA %s", eta); break;
	}
	if (!farm)
		return b.len;
	if (k == 0) {
		sb_add(&b, " | local %.1f t/s", farm->local_rate);
		for (uint32_t i = 0; i < farm->n_peers; i++) {
			const struct progress_peer *w = &farm->peers[i];
			sb_add(&b, " | %s %.1f t/s%s", w->name, w->rate, w->dropped ? " (dropped)" : w->working ? "" : " (-)");
		}
	} else if (k == 1) {
		sb_add(&b, " | local %.1f", farm->local_rate);
		for (uint32_t i = 0; i < farm->n_peers; i++) {
			const struct progress_peer *w = &farm->peers[i];
			char nm[NAME_SHORT + 2];
			short_name(nm, sizeof nm, w->name);
			if (w->dropped)
				sb_add(&b, " | %s x", nm);
			else
				sb_add(&b, " | %s %.1f%s", nm, w->rate, w->working ? "" : "-");
		}
	} else if (k == 2) {
		/* each worker's rate in order, no names */
		sb_add(&b, " | local %.1f | w", farm->local_rate);
		for (uint32_t i = 0; i < farm->n_peers; i++) {
			const struct progress_peer *w = &farm->peers[i];
			if (w->dropped)
				sb_add(&b, " x");
			else
				sb_add(&b, " %.1f%s", w->rate, w->working ? "" : "-");
		}
	} else {
		/* the workers summed up: working/all and their rate */
		uint32_t on = 0;
		double sum = 0;
		for (uint32_t i = 0; i < farm->n_peers; i++)
			if (farm->peers[i].working && !farm->peers[i].dropped) {
				on++;
				sum += farm->peers[i].rate;
			}
		if (k == 3)
			sb_add(&b, " | local %.1f | %u/%u workers %.1f", farm->local_rate, on, farm->n_peers, sum);
		else if (k == 4)
			sb_add(&b, " | %u/%uw %.1f", on, farm->n_peers, sum + farm->local_rate);
	}
	return b.len;
}

/* The order layouts are tried in: (layout, with a bar). A bar with shorter
 * words beats whole words without one; a farm's workers beat the bar. */
static const struct {
	int k;
	bool bar;
} tries[] = { { 0, true }, { 1, true }, { 0, false }, { 1, false }, { 2, true }, { 2, false },
	      { 3, true }, { 3, false }, { 4, true }, { 4, false }, { 5, true }, { 5, false } };

size_t progress_format(const struct progress *p, double now, int cols, const struct progress_farm *farm, char *buf,
		       size_t n)
{
	char text[PROGRESS_LINE_MAX];
	size_t limit = cols > 0 ? (size_t)cols : SIZE_MAX;
	size_t n_tries = sizeof tries / sizeof tries[0];
	if (n == 0)
		return 0;
	for (size_t i = 0; i < n_tries; i++) {
		size_t bar_at, len = layout(p, now, tries[i].k, farm, text, sizeof text, &bar_at);
		/* the bar when it fits with at least BAR_CELLS_MIN cells */
		size_t room = limit > len ? limit - len : 0;
		int cells = 0;
		if (tries[i].bar) {
			if (room < BAR_CELLS_MIN + 3) /* "[" cells "] " */
				continue;
			cells = room - 3 > BAR_CELLS_MAX ? BAR_CELLS_MAX : (int)(room - 3);
		} else if (len > limit && i < n_tries - 1) {
			continue;
		}
		struct sbuf b = { buf, n, 0 };
		buf[0] = '\0';
		sb_add(&b, "%.*s", (int)bar_at, text);
		if (cells > 0) {
			int full = p->total ? (int)((double)p->done / (double)p->total * cells) : cells;
			sb_add(&b, "[");
			for (int c = 0; c < cells; c++)
				sb_add(&b, "%c", c < full ? '#' : '.');
			sb_add(&b, "] ");
		}
		sb_add(&b, "%s", text + bar_at);
		if (b.len > limit) { /* the poorest layout still too long: cut */
			b.len = limit;
			buf[b.len] = '\0';
		}
		return b.len;
	}
	return 0; /* not reached: the last try always returns */
}

int progress_columns(void)
{
	struct winsize ws;
	if (ioctl(STDERR_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0)
		return ws.ws_col;
	const char *c = getenv("COLUMNS");
	if (c) {
		char *end;
		long v = strtol(c, &end, 10);
		if (end != c && *end == '\0' && v > 0 && v < 10000)
			return (int)v;
	}
	return PROGRESS_COLS_DEFAULT;
}

static void draw_bar(struct progress *p, double now, const struct progress_farm *farm)
{
	char line[PROGRESS_LINE_MAX];
	/* one column short of the width: a full line would wrap on some terminals */
	int cols = (p->cols > 0 ? p->cols : progress_columns()) - 1;
	if (cols < 1)
		cols = 1;
	progress_format(p, now, cols, farm, line, sizeof line);
	fprintf(stderr, "\r%s\033[K", line);
	fflush(stderr);
	p->drawn = true;
	p->last_draw = now;
}

static void print_line(struct progress *p, double now, const struct progress_farm *farm)
{
	char line[PROGRESS_LINE_MAX];
	progress_format(p, now, 0, farm, line, sizeof line);
	fprintf(stderr, "portray-master: progress %s\n", line + strspn(line, " "));
	fflush(stderr);
	p->lines++;
	p->last_draw = now;
}

void progress_show(struct progress *p, uint64_t done, double now, const struct progress_farm *farm)
{
	progress_sample(p, done, now);
	if (p->mode == PROGRESS_BAR) {
		if (p->last_draw < 0 || now - p->last_draw >= PROGRESS_REDRAW_S || p->done == p->total)
			draw_bar(p, now, farm);
	} else if (p->mode == PROGRESS_LINES) {
		/* the first line one interval after the start */
		double since = p->last_draw < 0 ? p->start : p->last_draw;
		if (now - since >= p->interval && p->done < p->total)
			print_line(p, now, farm);
	}
}

void progress_clear(struct progress *p)
{
	if (p->mode == PROGRESS_BAR && p->drawn) {
		fputs("\r\033[K", stderr);
		fflush(stderr);
	}
	p->drawn = false;
}

void progress_finish(struct progress *p, uint64_t done, double now, const struct progress_farm *farm)
{
	progress_sample(p, done, now);
	if (p->mode == PROGRESS_BAR)
		progress_clear(p);
	else if (p->mode == PROGRESS_LINES && p->lines > 0)
		print_line(p, now, farm);
}
