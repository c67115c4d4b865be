/*
 * dial.c - portray-worker --connect: the worker dials its master instead of
 * waiting to be dialled, so that a cluster engine (systemd, Slurm's srun, a
 * Kubernetes Deployment) that just starts N copies of it makes a farm with
 * no discovery at all (conn.h).
 *
 * One connection at a time. While no master answers, attempts follow a
 * back-off of 0.5 s doubling to WK_DIAL_MAX_S, for ever: a pool may be
 * started before, during or after its master. After a job (the connection
 * got tiles) it dials again at once, so one worker serves one job after
 * another. Once connected, the connection is an ordinary one (conn.c): the
 * same handshake, secret, cache, deadlines and limits as an accepted one;
 * the protocol does not care who dialled.
 */
#include <errno.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "worker/conn.h"

/* a pause before dialling again after a job: a master that has just ended
 * may still hold its listening socket for a moment */
#define WK_DIAL_AGAIN_S 0.1
/* attempts between two "still no master" lines */
#define WK_DIAL_LOG_EVERY 30

static void dial_later(struct wk_server *srv, const char *why)
{
	struct wk_dial *d = &srv->dial;
	d->delay = d->delay > 0 ? d->delay * 2 : 0.5;
	if (d->delay > WK_DIAL_MAX_S)
		d->delay = WK_DIAL_MAX_S;
	if (d->failures++ % WK_DIAL_LOG_EVERY == 0)
		wk_log("master %s:%s: %s; trying again in %.1f s%s", d->host, d->port, why, d->delay,
		       d->failures > 1 ? " (still)" : "");
	ev_timer_arm(srv->loop, &d->t, net_now() + d->delay);
}

static void on_dial_io(struct ev_loop *l, int fd, short revents, void *arg)
{
	(void)revents;
	struct wk_server *srv = arg;
	struct wk_dial *d = &srv->dial;
	char err[300], peer[NET_HOST_LEN + NET_PORT_LEN + 4];
	d->fd = -1;
	if (net_connect_finish(fd, err, sizeof err) < 0) {
		ev_io_del(l, fd);
		close(fd);
		dial_later(srv, err);
		return;
	}
	snprintf(peer, sizeof peer, "%s:%s", d->host, d->port);
	const char *why = "";
	struct wk_conn *c = wk_conn_new(srv, fd, peer, &why); /* takes over fd and its registration */
	if (!c) {
		ev_io_del(l, fd);
		dial_later(srv, why);
		return;
	}
	c->dialed = true;
	d->busy = true; /* the back-off stays until a job is served (wk_dial_lost) */
	wk_server_link(srv, c);
	wk_log("connected to master %s", peer);
}

static void dial_now(struct ev_loop *l, void *arg)
{
	(void)l;
	struct wk_server *srv = arg;
	struct wk_dial *d = &srv->dial;
	if (srv->stop || d->busy || d->fd >= 0)
		return;
	char err[300];
	int fd = net_connect_start(d->host, d->port, err, sizeof err);
	if (fd < 0) {
		dial_later(srv, err);
		return;
	}
	if (ev_io_set(srv->loop, fd, POLLOUT, on_dial_io, srv) < 0) {
		close(fd);
		dial_later(srv, "out of memory");
		return;
	}
	d->fd = fd;
}

int wk_dial_start(struct wk_server *srv, const char *hostport, char *err, size_t errlen)
{
	struct wk_dial *d = &srv->dial;
	if (net_parse_hostport(hostport, d->host, d->port, err, errlen) < 0)
		return -1;
	d->on = true;
	d->fd = -1;
	ev_timer_init(&d->t, dial_now, srv);
	ev_timer_arm(srv->loop, &d->t, net_now());
	return 0;
}

void wk_dial_lost(struct wk_server *srv, bool served)
{
	struct wk_dial *d = &srv->dial;
	d->busy = false;
	if (served) {
		d->delay = 0;
		d->failures = 0;
		ev_timer_arm(srv->loop, &d->t, net_now() + WK_DIAL_AGAIN_S);
	} else {
		dial_later(srv, "connection ended before a job");
	}
}

void wk_dial_stop(struct wk_server *srv)
{
	struct wk_dial *d = &srv->dial;
	if (!d->on)
		return;
	ev_timer_stop(srv->loop, &d->t);
	if (d->fd >= 0) {
		ev_io_del(srv->loop, d->fd);
		close(d->fd);
		d->fd = -1;
	}
	d->on = false;
}
