/*
 * conn.h - portray-worker's connections and the server that holds them.
 *
 * One event loop thread (proto/evloop.h) owns the listening socket and every
 * connection; each connection is a state machine driven by its socket and
 * its timers, nothing wakes up to look:
 *
 *   HELLO -> [AUTH] -> OFFER -> [RECV] -> BUILD -> READY -> CLOSING
 *
 * HELLO    accepted, our HELLO sent, waiting for the master's
 * AUTH     (secret) waiting for the master's proof
 * OFFER    authenticated, waiting for the scene offer
 * RECV     receiving the scene's bytes
 * BUILD    the scene is in hand (received or cached) and being built;
 *          TILE and CANCEL are queued for the job (protocol 2)
 * READY    SCENE_READY sent, tiles traced
 * CLOSING  ERROR or BYE: the output is flushed, then the socket closed
 *
 * Timers per connection: the handshake deadline (accept to the offer), the
 * master-silence deadline (from OFFER on, proto_hb_deadline of the
 * heartbeat interval the master's HELLO asked for), our heartbeats (from
 * OFFER on, at that interval) and the closing linger (WK_LINGER_S).
 *
 * conn.c is the state machine; server.c the listener, the budgets of
 * authenticated and unauthenticated connections, the tracers' results and
 * the shutdown.
 */
#ifndef PORTRAY_WORKER_CONN_H
#define PORTRAY_WORKER_CONN_H

#include <signal.h>
#include <stdbool.h>
#include <stdint.h>

#include "proto/evloop.h"
#include "proto/net.h"
#include "proto/proto.h"
#include "worker/cache.h"
#include "worker/tracers.h"
#include "worker/worker.h"

enum wk_state { ST_HELLO, ST_AUTH, ST_OFFER, ST_RECV, ST_BUILD, ST_READY, ST_CLOSING };

struct wk_server;

struct wk_conn {
	struct wk_server *srv;
	struct proto_conn *pc;
	int fd;
	char peer[96];                  /* "HOST:PORT", for logs */
	size_t addr_len;                /* peer[0..addr_len) is the host: the per-address budget */
	enum wk_state state;
	bool authed;                    /* passed AUTH (secret) or HELLO (none): counts in WK_MAX_CONNS */
	bool spoke;                     /* a valid HELLO arrived (evicted after silent peers) */
	bool last_chance;               /* its input was read once more before its eviction */
	uint8_t nonce[PROTO_NONCE_BYTES];
	uint8_t peer_nonce[PROTO_NONCE_BYTES];
	double hb_interval;             /* seconds, as the master's HELLO asked */
	double last_rx;                 /* the last whole frame (from OFFER on) */
	double started;                 /* accept, then the offer: the job's time */
	struct ev_timer t_handshake, t_silence, t_heartbeat, t_linger;
	/* the job */
	uint8_t hash[PROTO_HASH_BYTES];
	uint32_t w, h;
	uint8_t *scene;                 /* scene bytes being received, grows as they arrive */
	size_t scene_len, scene_cap;
	uint64_t scene_size;            /* as offered */
	struct wk_entry *entry;         /* the scene (the connection's reference until the job takes it) */
	struct wk_job *job;             /* from BUILD on */
	bool cache_hit;
	uint32_t tiles_done;
	bool got_tile;                  /* the first TILE arrived (logged: tests wait for it) */
	bool logged;                    /* the job's line (or the refusal) is written */
	bool dirty;                     /* output queued by the done handler: flush it */
	bool budgeted;                  /* counted in n_authed or n_unauth */
	bool dialed;                    /* we dialled the master (--connect): dial.c redials when it goes */
	/* lists */
	struct wk_conn *prev, *next;    /* every connection */
	struct wk_conn *uprev, *unext;  /* unauthenticated ones, oldest first */
	struct wk_conn *dirty_next;
};

/* Log lines that a hostile peer could make by the thousand: at most
 * WK_LOG_BURST of them per WK_LOG_QUIET_S, the others counted and the
 * count logged when the next period begins. */
#define WK_LOG_QUIET_S 10.0
#define WK_LOG_BURST 20
struct wk_ratelog {
	double since;              /* start of the current period */
	unsigned long logged, suppressed;
};

/* --connect: the master this worker dials, again after every job (dial.c) */
struct wk_dial {
	bool on;
	char host[NET_HOST_LEN], port[NET_PORT_LEN];
	struct ev_timer t;              /* the next attempt */
	int fd;                         /* a connect in progress, or -1 */
	double delay;                   /* back-off: 0.5 s doubling to WK_DIAL_MAX_S */
	unsigned failures;              /* attempts failed since the last connection */
	bool busy;                      /* a dialled connection is open */
};

struct wk_server {
	struct wk_opts *opt;            /* (the fault hooks count tiles in it) */
	struct ev_loop *loop;
	int lfd;                        /* the listening socket, or -1 (--connect only) */
	struct wk_dial dial;
	struct ev_timer t_accept;       /* resumes accepting (out of descriptors, or evictions paced) */
	bool accept_starved;            /* out of descriptors: logged once until an accept works */
	double evict_credit;            /* evictions allowed now (WK_EVICT_RATE, WK_EVICT_BURST) */
	double evict_credit_at;         /* when it was last refilled */
	struct wk_conn *conns;          /* every connection */
	size_t n_conns, n_authed, n_unauth;
	struct wk_conn *unauth_head, *unauth_tail;
	uint64_t receiving;             /* scene bytes offered by connections in RECV */
	struct wk_conn *dirty;
	struct wk_cache cache;
	struct wk_tracers tracers;
	int threads;                    /* tracers running */
	struct wk_ratelog quiet_log;    /* lines about unauthenticated peers */
	volatile sig_atomic_t stop;     /* set by a signal: the loop ends */
};

/* ---- server.c ---- */

/*
 * Sets up srv on listening socket lfd: event loop, cache, tracers. Returns
 * 0, or an exit code (WK_EXIT_OSERR) with a message on stderr.
 */
int wk_server_init(struct wk_server *srv, struct wk_opts *opt, int lfd);
/* Serves until wk_server_stop (signal-safe). 0, or -1 when the loop failed. */
int wk_server_run(struct wk_server *srv);
/* From a signal handler: ends wk_server_run soon. */
void wk_server_stop(struct wk_server *srv);
/*
 * Shutdown: every connection gets ERROR(shutdown), every build and tile is
 * cancelled, the tracers are joined, everything is freed (the listening
 * socket is the caller's).
 */
void wk_server_free(struct wk_server *srv);
/* A connection just authenticated: moves it to the authenticated budget.
 * false (and the connection is failed) when that budget is full. */
bool wk_server_authed(struct wk_server *srv, struct wk_conn *c);
/* Takes c out of the connection budgets (it is closing), and out of the
 * server's list too when `gone` (it is being freed). Idempotent. */
void wk_server_forget(struct wk_server *srv, struct wk_conn *c, bool gone);
/* Links a new connection into the server's list (not into any budget). */
void wk_server_link(struct wk_server *srv, struct wk_conn *c);
/* Log one line of a kind a flood could repeat (struct wk_ratelog). */
void wk_log_limited(struct wk_ratelog *rl, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* ---- dial.c ---- */

/* --connect HOST:PORT: starts dialling (at once). 0, or -1 with err. */
int wk_dial_start(struct wk_server *srv, const char *hostport, char *err, size_t errlen);
/* A dialled connection is gone; served: it got a job (dial again at once),
 * otherwise after the back-off. */
void wk_dial_lost(struct wk_server *srv, bool served);
void wk_dial_stop(struct wk_server *srv);

/* ---- conn.c ---- */

/* A connection for an accepted socket (owned from now on, closed on
 * failure): our HELLO sent, the handshake timer armed. NULL when out of
 * memory or randomness, with the reason in why. */
struct wk_conn *wk_conn_new(struct wk_server *srv, int fd, const char *peer, const char **why);
/* Reads and handles what the socket holds, flushes; the connection may be
 * closed (and freed) when this returns. */
void wk_conn_input(struct wk_conn *c);
/* Sends ERROR(code, text), logs the job's end or the refusal, moves to CLOSING. */
void wk_conn_fail(struct wk_conn *c, int code, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/* Flushes the output and closes the connection when it is done (CLOSING and
 * flushed) or broken; false when it was closed (c is gone). */
bool wk_conn_settle(struct wk_conn *c);
/* Closes and frees c now (its job is cancelled). */
void wk_conn_close(struct wk_conn *c);
/* Entry e finished building: the connection waiting on it goes on. */
void wk_conn_built(struct wk_conn *c, struct wk_entry *e);
/* A tracer's result for c's job: sent (c is settled by the caller). */
void wk_conn_result(struct wk_conn *c, const struct wk_result *r);
/* Logs the job's line (once): "job PEER scene HASH WxH: N tiles in ..., how". */
void wk_conn_job_log(struct wk_conn *c, const char *how);

#endif
