/*
 * server.c - portray-worker's listener and its connection budgets, the
 * event loop's side of the tracers, and the shutdown (conn.h).
 *
 * Budgets: a connection that has authenticated (passed AUTH when a secret
 * is configured, its HELLO when none is) counts against WK_MAX_CONNS; a
 * newer one past that is told ERROR(limit). Before that it counts against
 * WK_MAX_UNAUTH (and WK_MAX_UNAUTH_PER_ADDR from its address), and a full
 * budget never turns a newcomer away: it evicts the oldest unauthenticated
 * connection instead (one that has not sent a valid HELLO first, each read
 * once more before it goes). Evictions are paced (WK_EVICT_RATE): a flood
 * that reconnects as fast as it is evicted waits in the kernel's accept
 * queue, and a master queued behind it has sent its HELLO by the time it is
 * accepted. So peers that connect and say nothing, however many and however
 * often they reconnect, hold at most WK_MAX_UNAUTH descriptors, cost little
 * CPU, and cannot keep a real master out.
 */
#include <errno.h>
#include <poll.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "proto/net.h"
#include "worker/conn.h"

void wk_log_limited(struct wk_ratelog *rl, const char *fmt, ...)
{
	double now = net_now();
	if (now - rl->since >= WK_LOG_QUIET_S) {
		if (rl->suppressed)
			wk_log("(%lu more lines about unauthenticated peers left out in %.0f s)", rl->suppressed,
			       now - rl->since);
		rl->since = now;
		rl->logged = rl->suppressed = 0;
	}
	if (rl->logged >= WK_LOG_BURST) {
		rl->suppressed++;
		return;
	}
	rl->logged++;
	char line[1024];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(line, sizeof line, fmt, ap);
	va_end(ap);
	wk_log("%s", line);
}

/* ---- the lists and the budgets ---- */

void wk_server_forget(struct wk_server *srv, struct wk_conn *c, bool gone)
{
	if (c->budgeted && c->authed) {
		srv->n_authed--;
	} else if (c->budgeted) {
		*(c->uprev ? &c->uprev->unext : &srv->unauth_head) = c->unext;
		*(c->unext ? &c->unext->uprev : &srv->unauth_tail) = c->uprev;
		c->uprev = c->unext = NULL;
		srv->n_unauth--;
	}
	c->budgeted = false;
	if (gone) {
		*(c->prev ? &c->prev->next : &srv->conns) = c->next;
		if (c->next)
			c->next->prev = c->prev;
		srv->n_conns--;
		if (c->dialed && !srv->stop)
			wk_dial_lost(srv, c->got_tile);
	}
}

void wk_server_link(struct wk_server *srv, struct wk_conn *c)
{
	c->prev = NULL;
	c->next = srv->conns;
	if (srv->conns)
		srv->conns->prev = c;
	srv->conns = c;
	srv->n_conns++;
}

bool wk_server_authed(struct wk_server *srv, struct wk_conn *c)
{
	wk_server_forget(srv, c, false);
	if (srv->n_authed >= WK_MAX_CONNS) {
		wk_conn_fail(c, PERR_LIMIT, "worker serves %d connections already", WK_MAX_CONNS);
		return false;
	}
	c->authed = true;
	c->budgeted = true;
	srv->n_authed++;
	return true;
}

static bool same_addr(const struct wk_conn *c, const char *peer, size_t len)
{
	return c->addr_len == len && memcmp(c->peer, peer, len) == 0;
}

/* The unauthenticated connection to evict (from peer's address when
 * peer is not NULL): the oldest that has not sent a valid HELLO, else
 * the oldest. */
static struct wk_conn *victim(struct wk_server *srv, const char *peer, size_t len)
{
	struct wk_conn *oldest = NULL;
	for (struct wk_conn *c = srv->unauth_head; c; c = c->unext) {
		if (peer && !same_addr(c, peer, len))
			continue;
		if (!c->spoke)
			return c;
		if (!oldest)
			oldest = c;
	}
	return oldest;
}

/* Unauthenticated connections from peer's address (peer NULL: from anywhere). */
static size_t count_unauth(struct wk_server *srv, const char *peer, size_t len)
{
	if (!peer)
		return srv->n_unauth;
	size_t n = 0;
	for (struct wk_conn *c = srv->unauth_head; c; c = c->unext)
		n += same_addr(c, peer, len);
	return n;
}

/*
 * Evicts unauthenticated connections (from peer's address, or from
 * anywhere when peer is NULL) until fewer than max remain. A silent victim
 * is read once more first: a master's HELLO that arrived since the last
 * poll saves it (a flood's newcomers arrive faster than a poll round).
 */
static int make_room(struct wk_server *srv, const char *peer, size_t len, size_t max, const char *why)
{
	int evicted = 0;
	while (count_unauth(srv, peer, len) >= max) {
		struct wk_conn *v = victim(srv, peer, len);
		if (!v)
			break;
		if (!v->spoke && !v->last_chance) {
			v->last_chance = true;
			wk_conn_input(v); /* may close it, fail it or move it on: counted again */
			continue;
		}
		wk_conn_fail(v, PERR_LIMIT, "%s", why);
		wk_conn_settle(v);
		evicted++;
	}
	return evicted;
}

/* Serves a new connection, making room in the unauthenticated budget;
 * returns the number of connections evicted for it. */
static int admit(struct wk_server *srv, int fd, const char *peer)
{
	const char *colon = strrchr(peer, ':');
	size_t len = colon ? (size_t)(colon - peer) : strlen(peer);
	int evicted = make_room(srv, peer, len, WK_MAX_UNAUTH_PER_ADDR,
				"evicted: too many unauthenticated connections from one address");
	evicted += make_room(srv, NULL, 0, WK_MAX_UNAUTH, "evicted: too many unauthenticated connections");
	const char *why = "";
	struct wk_conn *c = wk_conn_new(srv, fd, peer, &why);
	if (!c) {
		wk_log_limited(&srv->quiet_log, "%s: refused: %s", peer, why);
		return evicted;
	}
	wk_server_link(srv, c);
	wk_log_limited(&srv->quiet_log, "%s: connected", peer);
	c->uprev = srv->unauth_tail;
	*(srv->unauth_tail ? &srv->unauth_tail->unext : &srv->unauth_head) = c;
	srv->unauth_tail = c;
	c->budgeted = true;
	srv->n_unauth++;
	/* a master sends its HELLO as soon as it is connected: often it is
	 * here already, and the connection is out of the eviction order's
	 * front before the next newcomer arrives */
	wk_conn_input(c);
	return evicted;
}

/* Takes n evictions from the credit (refilled at WK_EVICT_RATE up to
 * WK_EVICT_BURST); when it runs out, the listening socket rests until one
 * more is due. true when accepting may go on. */
static bool pace_evictions(struct wk_server *srv, int n)
{
	double now = net_now();
	srv->evict_credit += (now - srv->evict_credit_at) * WK_EVICT_RATE;
	if (srv->evict_credit > WK_EVICT_BURST)
		srv->evict_credit = WK_EVICT_BURST;
	srv->evict_credit_at = now;
	srv->evict_credit -= n;
	if (srv->evict_credit >= 1)
		return true;
	ev_io_events(srv->loop, srv->lfd, 0);
	ev_timer_arm(srv->loop, &srv->t_accept, now + (1 - srv->evict_credit) / WK_EVICT_RATE);
	return false;
}

static void on_accept(struct ev_loop *l, int fd, short revents, void *arg)
{
	(void)revents;
	struct wk_server *srv = arg;
	for (int i = 0; i < WK_ACCEPT_BATCH; i++) {
		char peer[96];
		int cfd = net_accept(fd, peer, sizeof peer);
		if (cfd >= 0) {
			srv->accept_starved = false;
			int evicted = admit(srv, cfd, peer);
			if (evicted && !pace_evictions(srv, evicted))
				return;
			continue;
		}
		if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
			/* the socket stays readable: polling it now would spin */
			if (!srv->accept_starved)
				wk_log("cannot accept: %s; pausing accepts", strerror(errno));
			srv->accept_starved = true;
			ev_io_events(l, fd, 0);
			ev_timer_arm(l, &srv->t_accept, net_now() + WK_ACCEPT_PAUSE_S);
			return;
		}
		if (errno == EAGAIN || errno == EWOULDBLOCK)
			return;
		/* a connection reset before we took it, and the like: next */
	}
}

static void on_accept_resume(struct ev_loop *l, void *arg)
{
	struct wk_server *srv = arg;
	ev_io_events(l, srv->lfd, POLLIN);
}

/* ---- the tracers' results ---- */

static void mark_dirty(struct wk_server *srv, struct wk_conn *c)
{
	if (c->dirty)
		return;
	c->dirty = true;
	c->dirty_next = srv->dirty;
	srv->dirty = c;
}

/* Woken by a tracer (or a signal): results go to their sockets, finished
 * builds to the connections waiting for them. */
static void on_wake(struct ev_loop *l, void *arg)
{
	struct wk_server *srv = arg;
	if (srv->stop) {
		ev_stop(l);
		return;
	}
	struct wk_result *results;
	struct wk_entry *built;
	wk_tracers_collect(&srv->tracers, &results, &built);
	while (results) {
		struct wk_result *next = results->next;
		struct wk_conn *c = results->job->owner;
		size_t outq = SIZE_MAX;
		if (c) {
			wk_conn_result(c, results);
			outq = proto_conn_outq(c->pc);
			mark_dirty(srv, c);
		}
		wk_result_release(&srv->tracers, results, outq);
		results = next;
	}
	while (built) {
		struct wk_entry *next = built->built_next;
		wk_cache_built(&srv->cache, built, built->build_result == WK_BUILD_OK);
		for (struct wk_conn *c = srv->conns; c; c = c->next)
			if (c->state == ST_BUILD && c->entry == built) {
				wk_conn_built(c, built);
				mark_dirty(srv, c);
			}
		built = next;
	}
	wk_cache_trim(&srv->cache); /* failed builds leave; released jobs may free space */
	/* one flush per connection for the whole batch (closing only here, so
	 * no connection on the list is freed before its turn) */
	while (srv->dirty) {
		struct wk_conn *c = srv->dirty;
		srv->dirty = c->dirty_next;
		c->dirty = false;
		wk_conn_settle(c);
	}
}

/* ---- life ---- */

int wk_server_init(struct wk_server *srv, struct wk_opts *opt, int lfd)
{
	memset(srv, 0, sizeof *srv);
	srv->opt = opt;
	srv->lfd = lfd;
	wk_cache_init(&srv->cache, opt->cache_bytes);
	srv->dial.fd = -1;
	srv->loop = ev_new();
	if (!srv->loop || (lfd >= 0 && ev_io_set(srv->loop, lfd, POLLIN, on_accept, srv) < 0)) {
		fprintf(stderr, "portray-worker: cannot set up the event loop: %s\n", strerror(errno));
		ev_free(srv->loop);
		return WK_EXIT_OSERR;
	}
	ev_on_wake(srv->loop, on_wake, srv);
	ev_timer_init(&srv->t_accept, on_accept_resume, srv);
	srv->evict_credit = WK_EVICT_BURST;
	srv->evict_credit_at = net_now();
	srv->threads = wk_tracers_start(&srv->tracers, opt->threads, srv->loop, &srv->cache, &opt->faults);
	if (srv->threads == 0) {
		fprintf(stderr, "portray-worker: cannot start tracer threads\n");
		wk_tracers_free(&srv->tracers);
		ev_free(srv->loop);
		return WK_EXIT_OSERR;
	}
	return 0;
}

int wk_server_run(struct wk_server *srv) { return ev_run(srv->loop); }

void wk_server_stop(struct wk_server *srv)
{
	srv->stop = 1;
	ev_wake(srv->loop);
}

void wk_server_free(struct wk_server *srv)
{
	srv->stop = 1; /* (also when the loop failed): closing connections dial nothing */
	wk_dial_stop(srv);
	wk_log("shutting down (%zu connections)", srv->n_conns);
	for (struct wk_conn *c = srv->conns; c; c = c->next) {
		if (c->state != ST_CLOSING) {
			wk_conn_job_log(c, "cut off: worker shutting down");
			proto_send_error(c->pc, PERR_SHUTDOWN, "worker shutting down");
		}
		proto_conn_flush(c->pc);
	}
	/* every build and tile gives up, the tracers end */
	wk_cache_cancel_all(&srv->cache);
	wk_tracers_stop(&srv->tracers);
	while (srv->conns)
		wk_conn_close(srv->conns);
	wk_tracers_free(&srv->tracers);
	wk_cache_free(&srv->cache);
	ev_free(srv->loop);
}
