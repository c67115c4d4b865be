/*
 * worker.h - what every room of portray-worker shares: its limits, options,
 * exit codes and log line.
 *
 * The rooms: main.c (command line, signals), conn.c (one connection's state
 * machine), server.c (the listener, connection budgets, the event loop's
 * side of the tracers), tracers.c (jobs, builds and the tracer pool),
 * cache.c (scenes by content hash), fault.c (the --test-fault hooks).
 * Protocol reference: docs/protocol.md.
 */
#ifndef PORTRAY_WORKER_H
#define PORTRAY_WORKER_H

#include <stddef.h>
#include <stdint.h>

#include "worker/fault.h"

/* connections that passed the handshake, served at once: each may cost a
 * scene transfer and a frame buffer of up to PROTO_MASTER_FRAME_MAX */
#define WK_MAX_CONNS 256
/* connections that have not (yet) authenticated: a budget of their own, so
 * idle or hostile peers never take a real master's slot; when it is full
 * the oldest of them makes room for the newcomer */
#define WK_MAX_UNAUTH 64
/* ... and from any one address: a flood from one host evicts only its own
 * connections, never those of a master on another host */
#define WK_MAX_UNAUTH_PER_ADDR 16
/* seconds a peer may take from accept to its scene offer */
#define WK_HANDSHAKE_S 10.0
/* seconds a failed connection may take to flush its ERROR before it is cut */
#define WK_LINGER_S 2.0
/* seconds the listening socket rests after accept() ran out of descriptors */
#define WK_ACCEPT_PAUSE_S 0.25
/* connections accepted per readiness of the listening socket: the others
 * (a master's HELLO among them) are read between two batches */
#define WK_ACCEPT_BATCH 8
/* evictions per second at most (and in a burst): past that, accepting waits.
 * A flood that reconnects as fast as it is evicted then waits in the
 * kernel's accept queue, and so does a master behind it, whose HELLO is
 * there when it is accepted (it sends it on connecting): read at once, it
 * is no longer a silent peer. Without the pace, a flood could turn the
 * unauthenticated budget over faster than a master's first frame arrives. */
#define WK_EVICT_RATE 500.0
#define WK_EVICT_BURST 64.0
/* --connect: the longest pause between two attempts to reach the master */
#define WK_DIAL_MAX_S 10.0
/* default scene cache budget, MiB of encoded scene bytes */
#define WK_CACHE_MB_DEFAULT 1024

/* Exit codes (sysexits.h values). */
enum wk_exit {
	WK_EXIT_OK = 0,
	WK_EXIT_USAGE = 64,       /* bad command line or secret file (EX_USAGE) */
	WK_EXIT_UNAVAILABLE = 69, /* cannot listen (EX_UNAVAILABLE) */
	WK_EXIT_SOFTWARE = 70,    /* the event loop failed (EX_SOFTWARE) */
	WK_EXIT_OSERR = 71,       /* no event loop or tracer thread (EX_OSERR) */
	WK_EXIT_CANTCREAT = 73    /* cannot write the port file (EX_CANTCREAT) */
};

/* The daemon's options, fixed once main has read the command line. */
struct wk_opts {
	int threads;            /* tracer threads (resolved: never 0) */
	uint8_t *secret;        /* shared secret, NULL when none (owned) */
	size_t secret_len;
	uint64_t cache_bytes;   /* --cache-mb in bytes */
	double handshake_s;     /* accept to scene offer (WK_HANDSHAKE_S; a test hook shortens it) */
	struct wk_faults faults; /* --test-fault, --test-delay-ms */
};

/* One log line on stderr: "portray-worker HH:MM:SS " + the text (UTC). */
void wk_log(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
/* The first 8 bytes of a hash in hex, for log lines. */
void wk_hex8(const uint8_t *h, char out[17]);

#endif
