/*
 * evloop.c - poll() plus a timer heap (evloop.h).
 *
 * Descriptors live in a dense array (rebuilt into the pollfd array each
 * round) with an fd-indexed position table, so changing the events of one
 * connection is O(1) however many are open. A descriptor deleted during a
 * round keeps no callback: each slot carries a generation, and events that
 * poll reported for an older generation of the same fd number are dropped.
 * Timers are a binary min-heap on their deadline; each timer knows its slot,
 * so stopping one is O(log n).
 */
#include "proto/evloop.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdint.h>
#include <stdlib.h>
#include <unistd.h>

#include "proto/net.h"

struct ev_io {
	int fd;
	short events;
	ev_io_fn fn;
	void *arg;
	uint32_t gen;
};

struct ev_loop {
	struct ev_io *io;       /* registered descriptors, dense */
	size_t n_io, cap_io;
	size_t *pos;            /* pos[fd] = index in io + 1, 0 when not registered */
	size_t cap_pos;
	struct pollfd *pfd;     /* this round's poll set */
	uint32_t *pgen;         /* the generation each pfd entry was taken from */
	size_t cap_pfd;
	uint32_t gen;
	struct ev_timer **heap;
	size_t n_heap, cap_heap;
	struct ev_timer *overflow; /* armed while the heap could not grow (out of memory): scanned */
	int wake[2];
	ev_fn wake_fn;
	void *wake_arg;
	bool stop;
};

static void on_wake_pipe(struct ev_loop *l, int fd, short revents, void *arg)
{
	(void)revents;
	(void)arg;
	char b[64];
	while (read(fd, b, sizeof b) > 0)
		;
	if (l->wake_fn)
		l->wake_fn(l, l->wake_arg);
}

struct ev_loop *ev_new(void)
{
	struct ev_loop *l = calloc(1, sizeof *l);
	if (!l)
		return NULL;
	l->wake[0] = l->wake[1] = -1;
	if (pipe(l->wake) < 0) {
		free(l);
		return NULL;
	}
	for (int i = 0; i < 2; i++) {
		fcntl(l->wake[i], F_SETFL, fcntl(l->wake[i], F_GETFL) | O_NONBLOCK);
		fcntl(l->wake[i], F_SETFD, FD_CLOEXEC);
	}
	if (ev_io_set(l, l->wake[0], POLLIN, on_wake_pipe, NULL) < 0) {
		ev_free(l);
		return NULL;
	}
	return l;
}

void ev_free(struct ev_loop *l)
{
	if (!l)
		return;
	for (size_t i = 0; i < l->n_heap; i++)
		l->heap[i]->slot = 0;
	for (struct ev_timer *t = l->overflow; t; t = t->ov_next)
		t->slot = 0;
	for (int i = 0; i < 2; i++)
		if (l->wake[i] >= 0)
			close(l->wake[i]);
	free(l->io);
	free(l->pos);
	free(l->pfd);
	free(l->pgen);
	free(l->heap);
	free(l);
}

int ev_io_set(struct ev_loop *l, int fd, short events, ev_io_fn fn, void *arg)
{
	if (fd < 0)
		return -1;
	if ((size_t)fd >= l->cap_pos) {
		size_t nc = l->cap_pos ? l->cap_pos : 64;
		while (nc <= (size_t)fd)
			nc *= 2;
		size_t *p = realloc(l->pos, nc * sizeof *p);
		if (!p)
			return -1;
		for (size_t i = l->cap_pos; i < nc; i++)
			p[i] = 0;
		l->pos = p;
		l->cap_pos = nc;
	}
	struct ev_io *e;
	if (l->pos[fd]) {
		e = &l->io[l->pos[fd] - 1];
	} else {
		if (l->n_io == l->cap_io) {
			size_t nc = l->cap_io ? l->cap_io * 2 : 16;
			struct ev_io *p = realloc(l->io, nc * sizeof *p);
			if (!p)
				return -1;
			l->io = p;
			l->cap_io = nc;
		}
		e = &l->io[l->n_io++];
		l->pos[fd] = l->n_io;
		e->fd = fd;
		e->gen = ++l->gen;
	}
	e->events = events;
	e->fn = fn;
	e->arg = arg;
	return 0;
}

void ev_io_events(struct ev_loop *l, int fd, short events)
{
	if (fd >= 0 && (size_t)fd < l->cap_pos && l->pos[fd])
		l->io[l->pos[fd] - 1].events = events;
}

void ev_io_del(struct ev_loop *l, int fd)
{
	if (fd < 0 || (size_t)fd >= l->cap_pos || !l->pos[fd])
		return;
	size_t i = l->pos[fd] - 1;
	l->pos[fd] = 0;
	l->n_io--;
	if (i != l->n_io) {
		l->io[i] = l->io[l->n_io];
		l->pos[l->io[i].fd] = i + 1;
	}
}

/* ---- timers: a binary min-heap on `at` ---- */

static void heap_set(struct ev_loop *l, size_t i, struct ev_timer *t)
{
	l->heap[i] = t;
	t->slot = i + 1;
}

static void heap_up(struct ev_loop *l, size_t i)
{
	struct ev_timer *t = l->heap[i];
	while (i > 0) {
		size_t p = (i - 1) / 2;
		if (l->heap[p]->at <= t->at)
			break;
		heap_set(l, i, l->heap[p]);
		i = p;
	}
	heap_set(l, i, t);
}

static void heap_down(struct ev_loop *l, size_t i)
{
	struct ev_timer *t = l->heap[i];
	for (;;) {
		size_t c = 2 * i + 1;
		if (c >= l->n_heap)
			break;
		if (c + 1 < l->n_heap && l->heap[c + 1]->at < l->heap[c]->at)
			c++;
		if (t->at <= l->heap[c]->at)
			break;
		heap_set(l, i, l->heap[c]);
		i = c;
	}
	heap_set(l, i, t);
}

void ev_timer_init(struct ev_timer *t, ev_fn fn, void *arg)
{
	t->at = 0;
	t->fn = fn;
	t->arg = arg;
	t->slot = 0;
	t->ov_next = NULL;
}

void ev_timer_stop(struct ev_loop *l, struct ev_timer *t)
{
	if (!t->slot)
		return;
	if (t->slot == EV_SLOT_OVERFLOW) {
		for (struct ev_timer **pp = &l->overflow; *pp; pp = &(*pp)->ov_next)
			if (*pp == t) {
				*pp = t->ov_next;
				break;
			}
		t->slot = 0;
		t->ov_next = NULL;
		return;
	}
	size_t i = t->slot - 1;
	t->slot = 0;
	l->n_heap--;
	if (i == l->n_heap)
		return;
	struct ev_timer *m = l->heap[l->n_heap];
	heap_set(l, i, m);
	heap_up(l, i);
	heap_down(l, m->slot - 1);
}

void ev_timer_arm(struct ev_loop *l, struct ev_timer *t, double at)
{
	ev_timer_stop(l, t);
	if (l->n_heap == l->cap_heap) {
		size_t nc = l->cap_heap ? l->cap_heap * 2 : 16;
		struct ev_timer **p = realloc(l->heap, nc * sizeof *p);
		if (!p) {
			/* out of memory: the timer waits on a list the loop scans
			 * (never fired early, never lost, never called from here) */
			t->at = at;
			t->slot = EV_SLOT_OVERFLOW;
			t->ov_next = l->overflow;
			l->overflow = t;
			return;
		}
		l->heap = p;
		l->cap_heap = nc;
	}
	t->at = at;
	heap_set(l, l->n_heap++, t);
	heap_up(l, l->n_heap - 1);
}

size_t ev_timers(const struct ev_loop *l)
{
	size_t n = l->n_heap;
	for (const struct ev_timer *t = l->overflow; t; t = t->ov_next)
		n++;
	return n;
}

/* The overflow list's earliest deadline, or NULL. */
static struct ev_timer *overflow_first(const struct ev_loop *l)
{
	struct ev_timer *best = NULL;
	for (struct ev_timer *t = l->overflow; t; t = t->ov_next)
		if (!best || t->at < best->at)
			best = t;
	return best;
}

/* ---- running ---- */

void ev_wake(struct ev_loop *l)
{
	char b = 1;
	ssize_t r = write(l->wake[1], &b, 1);
	(void)r; /* a full pipe already means "wake up" */
}

void ev_on_wake(struct ev_loop *l, ev_fn fn, void *arg)
{
	l->wake_fn = fn;
	l->wake_arg = arg;
}

void ev_stop(struct ev_loop *l) { l->stop = true; }

/* Fires every timer due by now (timers armed by these callbacks for a time
 * already past fire in this round too, but each at most once per round). */
static void run_timers(struct ev_loop *l)
{
	double now = net_now();
	size_t budget = ev_timers(l);
	while (budget--) {
		struct ev_timer *t = l->n_heap && l->heap[0]->at <= now ? l->heap[0] : NULL;
		struct ev_timer *o = overflow_first(l);
		if (o && o->at <= now && (!t || o->at < t->at))
			t = o;
		if (!t)
			break;
		ev_timer_stop(l, t);
		t->fn(l, t->arg);
	}
}

int ev_run_once(struct ev_loop *l, double max_wait)
{
	if (l->n_io > l->cap_pfd) {
		size_t nc = l->n_io * 2;
		struct pollfd *p = realloc(l->pfd, nc * sizeof *p);
		if (!p)
			return -1;
		l->pfd = p;
		uint32_t *g = realloc(l->pgen, nc * sizeof *g);
		if (!g)
			return -1;
		l->pgen = g;
		l->cap_pfd = nc;
	}
	size_t n = l->n_io;
	for (size_t i = 0; i < n; i++) {
		l->pfd[i] = (struct pollfd){ .fd = l->io[i].events ? l->io[i].fd : -1, .events = l->io[i].events };
		l->pgen[i] = l->io[i].gen;
	}
	double wait = max_wait;
	struct ev_timer *first = l->n_heap ? l->heap[0] : NULL, *o = overflow_first(l);
	if (o && (!first || o->at < first->at))
		first = o;
	if (first) {
		double d = first->at - net_now();
		if (d < 0)
			d = 0;
		if (wait < 0 || d < wait)
			wait = d;
	}
	/* round up: a timer must not be polled for, found not yet due, and polled for again with 0 ms */
	int ms = wait < 0 ? -1 : wait > 86400 ? 86400000 : (int)(wait * 1000.0 + 0.999);
	int k = poll(l->pfd, (nfds_t)n, ms);
	if (k < 0 && errno != EINTR)
		return -1;
	for (size_t i = 0; k > 0 && i < n; i++) {
		struct pollfd *p = &l->pfd[i];
		if (!p->revents || p->fd < 0)
			continue;
		size_t pos = (size_t)p->fd < l->cap_pos ? l->pos[p->fd] : 0;
		if (!pos || l->io[pos - 1].gen != l->pgen[i])
			continue; /* deleted (or replaced) by an earlier callback this round */
		struct ev_io *e = &l->io[pos - 1];
		e->fn(l, p->fd, p->revents, e->arg);
	}
	run_timers(l);
	return 0;
}

int ev_run(struct ev_loop *l)
{
	l->stop = false;
	while (!l->stop)
		if (ev_run_once(l, -1) < 0)
			return -1;
	return 0;
}
