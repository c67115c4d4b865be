/*
 * test_evloop.c - the event loop (proto/evloop.c): timers fire in deadline
 * order and only when due, stopping and re-arming (also from callbacks),
 * descriptors become ready, deletion inside a round, and ev_wake from
 * another thread.
 */
#include <poll.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "proto/evloop.h"
#include "proto/net.h"
#include "tests/unit/check.h"

static int order[64], n_order;

static void record(struct ev_loop *l, void *arg)
{
	(void)l;
	order[n_order++] = (int)(size_t)arg;
}

/* Many timers armed in a scrambled order fire sorted by deadline. */
static void test_order(void)
{
	struct ev_loop *l = ev_new();
	CHECK(l != NULL);
	struct ev_timer t[40];
	double now = net_now();
	n_order = 0;
	for (int i = 0; i < 40; i++) {
		int k = (i * 17) % 40; /* a permutation of 0..39 */
		ev_timer_init(&t[k], record, (void *)(size_t)k);
		ev_timer_arm(l, &t[k], now + 0.001 * k);
	}
	/* stop a few (from the middle of the heap, its root and its end) */
	ev_timer_stop(l, &t[0]);
	ev_timer_stop(l, &t[20]);
	ev_timer_stop(l, &t[39]);
	ev_timer_stop(l, &t[39]); /* twice: harmless */
	CHECK(!ev_timer_armed(&t[20]));
	CHECK(ev_timers(l) == 37);
	/* move one later than all the others */
	ev_timer_arm(l, &t[5], now + 0.1);
	while (ev_timers(l))
		CHECK(ev_run_once(l, 1.0) == 0);
	CHECK(n_order == 37);
	CHECK(order[n_order - 1] == 5);
	int sorted = 1;
	for (int i = 1; i < n_order - 1; i++)
		if (order[i] < order[i - 1])
			sorted = 0;
	CHECK(sorted);
	CHECK(order[0] == 1);
	ev_free(l);
}

/* A timer is not fired before its time, and the loop sleeps until it. */
static void test_not_early(void)
{
	struct ev_loop *l = ev_new();
	struct ev_timer t;
	ev_timer_init(&t, record, (void *)(size_t)7);
	n_order = 0;
	double t0 = net_now();
	ev_timer_arm(l, &t, t0 + 0.05);
	CHECK(ev_run_once(l, 0) == 0); /* not due: nothing happens */
	CHECK(n_order == 0);
	CHECK(ev_run_once(l, -1) == 0); /* sleeps until it is due */
	CHECK(n_order == 1);
	CHECK(net_now() - t0 >= 0.05);
	ev_free(l);
}

/* A periodic timer that re-arms itself, and ev_stop from a callback. */
struct periodic {
	struct ev_timer t;
	int fired;
};

static void tick(struct ev_loop *l, void *arg)
{
	struct periodic *p = arg;
	if (++p->fired == 5)
		ev_stop(l);
	else
		ev_timer_arm(l, &p->t, net_now() + 0.002);
}

static void test_periodic(void)
{
	struct ev_loop *l = ev_new();
	struct periodic p = { .fired = 0 };
	ev_timer_init(&p.t, tick, &p);
	ev_timer_arm(l, &p.t, net_now());
	CHECK(ev_run(l) == 0);
	CHECK(p.fired == 5);
	CHECK(!ev_timer_armed(&p.t));
	ev_free(l);
}

/* Descriptors: a readable pipe calls back; a callback that deletes another
 * ready descriptor keeps that one's callback from running this round. */
struct io_state {
	int fds[2][2];
	int calls[2];
};

static void on_read(struct ev_loop *l, int fd, short revents, void *arg)
{
	struct io_state *s = arg;
	int which = fd == s->fds[0][0] ? 0 : 1;
	s->calls[which]++;
	CHECK(revents & POLLIN);
	char b[16];
	CHECK(read(fd, b, sizeof b) > 0);
	ev_io_del(l, s->fds[1 - which][0]);
}

static void test_io(void)
{
	struct ev_loop *l = ev_new();
	struct io_state s;
	memset(&s, 0, sizeof s);
	CHECK(pipe(s.fds[0]) == 0 && pipe(s.fds[1]) == 0);
	CHECK(ev_io_set(l, s.fds[0][0], POLLIN, on_read, &s) == 0);
	CHECK(ev_io_set(l, s.fds[1][0], POLLIN, on_read, &s) == 0);
	CHECK(write(s.fds[0][1], "a", 1) == 1 && write(s.fds[1][1], "b", 1) == 1);
	CHECK(ev_run_once(l, 1.0) == 0);
	CHECK(s.calls[0] + s.calls[1] == 1); /* the first deleted the second */
	/* events 0: registered but not polled */
	int alive = s.calls[0] ? 0 : 1;
	CHECK(write(s.fds[alive][1], "c", 1) == 1);
	ev_io_events(l, s.fds[alive][0], 0);
	CHECK(ev_run_once(l, 0.01) == 0);
	CHECK(s.calls[0] + s.calls[1] == 1);
	ev_io_events(l, s.fds[alive][0], POLLIN);
	CHECK(ev_run_once(l, 1.0) == 0);
	CHECK(s.calls[alive] == 2 || s.calls[alive] == 1);
	CHECK(s.calls[0] + s.calls[1] == 2);
	for (int i = 0; i < 2; i++)
		close(s.fds[i][0]), close(s.fds[i][1]);
	ev_free(l);
}

/* ev_wake from another thread ends a poll that has no timeout. */
static int woken;
static void on_wake(struct ev_loop *l, void *arg)
{
	(void)arg;
	woken++;
	ev_stop(l);
}

static void *waker(void *arg)
{
	usleep(20000);
	ev_wake(arg);
	return NULL;
}

static void test_wake(void)
{
	struct ev_loop *l = ev_new();
	ev_on_wake(l, on_wake, NULL);
	pthread_t th;
	CHECK(pthread_create(&th, NULL, waker, l) == 0);
	CHECK(ev_run(l) == 0);
	pthread_join(th, NULL);
	CHECK(woken == 1);
	ev_free(l);
}

int main(void)
{
	test_order();
	test_not_early();
	test_periodic();
	test_io();
	test_wake();
	TEST_MAIN_END();
}
