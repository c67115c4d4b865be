/*
 * wconn.c - the master's connection to one worker (farm_int.h): connect,
 * handshake, scene transfer, build, tiles; every state with a deadline, on
 * the farm's event loop.
 *
 * Deadlines. Each handshake step (connect, HELLO, AUTH, OFFER) must be done
 * within the heartbeat timeout; a scene transfer must make progress within
 * it; a build must end within FARM_BUILD_HB heartbeat timeouts plus
 * FARM_BUILD_LOCAL times the master's own build of the same scene. Only
 * while the worker builds or traces do its frames (heartbeats included)
 * prove it alive; a HEARTBEAT before its handshake is a protocol error.
 * Holding tiles without returning any for far longer than its usual tile time
 * is a hung tracer. One timer per worker is armed at the nearest of all
 * these (and of our next heartbeat and its reconnection), and re-armed
 * whenever it fires.
 *
 * The window. A worker may hold 2 x threads + 1 tiles plus what it traces in
 * 1.5 round trips at its measured rate (threads / trace time per tile,
 * which each result reports): a bandwidth-delay product, so the link never
 * sits idle whatever the latency, bounded by FARM_DEPTH_MAX tiles and
 * FARM_WINDOW_BYTES of results. The round trip is measured by the OFFER,
 * which the worker answers at once; until the first result, the rate is a
 * guess (size_window).
 *
 * Round trips saved: without a secret our OFFER travels with our HELLO;
 * with one, with our proof; the first window of tiles follows the scene's
 * last chunk (or the HAVE) without waiting for SCENE_READY.
 */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <poll.h>

#include "master/farm_int.h"
#include "proto/net.h"

static void worker_timer(struct ev_loop *l, void *arg);


int worker_init(struct farm *f, struct worker *w, const struct worker_addr *a, uint16_t index)
{
	memset(w, 0, sizeof *w);
	w->f = f;
	w->addr = *a;
	w->name = w->addr.name;
	w->index = index;
	w->state = W_IDLE;
	w->fd = -1;
	ev_timer_init(&w->tm, worker_timer, w);
	w->inflight = calloc(FARM_DEPTH_MAX, sizeof *w->inflight);
	w->sent_at = calloc(FARM_DEPTH_MAX, sizeof *w->sent_at);
	w->cancelled = calloc(FARM_DEPTH_MAX, sizeof *w->cancelled);
	return w->inflight && w->sent_at && w->cancelled ? 0 : -1;
}

void worker_free(struct worker *w)
{
	if (w->f && w->f->loop)
		ev_timer_stop(w->f->loop, &w->tm);
	proto_conn_free(w->pc);
	w->pc = NULL;
	free(w->inflight);
	free(w->sent_at);
	free(w->cancelled);
}

static const char *state_name(enum wstate s)
{
	static const char *const n[] = { "idle", "connect", "handshake (HELLO)", "handshake (AUTH)",
					 "scene offer", "scene transfer", "scene build", "tracing", "done" };
	return n[s];
}

/* ---- timers ---- */

static double hang_deadline(const struct worker *w)
{
	const struct farm *f = w->f;
	if (w->n_lat == 0)
		return FARM_HANG_HB_FIRST * f->hb_timeout;
	double d = FARM_HANG_MEDIANS * w->median;
	return d > FARM_HANG_HB * f->hb_timeout ? d : FARM_HANG_HB * f->hb_timeout;
}

static double hang_since(const struct worker *w)
{
	double s = w->last_result > w->busy_since ? w->last_result : w->busy_since;
	return s > w->state_at ? s : w->state_at; /* tiles sent during the build wait for it */
}

/* The nearest time anything of w's is due, or 0. */
static double next_due(const struct worker *w)
{
	const struct farm *f = w->f;
	double t = 0;
#define AT(x)                               \
	do {                                \
		double x_ = (x);            \
		if (t == 0 || x_ < t)       \
			t = x_;             \
	} while (0)
	switch (w->state) {
	case W_IDLE:
		if (!w->dropped && w->retry_at > 0)
			AT(w->retry_at);
		break;
	case W_DONE:
		break;
	default:
		if (w->deadline > 0)
			AT(w->deadline);
		if (w->state >= W_BUILDING)
			AT(w->last_rx + f->hb_timeout);
		if (w->state == W_READY && w->n_inflight > 0)
			AT(hang_since(w) + hang_deadline(w));
		if (w->state >= W_OFFER)
			AT(w->last_hb + f->hb_interval);
		break;
	}
#undef AT
	return t;
}

static void rearm(struct worker *w)
{
	double t = next_due(w);
	if (t == 0)
		ev_timer_stop(w->f->loop, &w->tm);
	else if (!ev_timer_armed(&w->tm) || t < w->tm.at)
		ev_timer_arm(w->f->loop, &w->tm, t);
}

/* A new state, with its deadline (0: none but liveness). */
static void set_state(struct worker *w, enum wstate s, double deadline_in)
{
	double now = net_now();
	w->state = s;
	w->state_at = now;
	w->deadline = deadline_in > 0 ? now + deadline_in : 0;
	if (s == W_BUILDING || s == W_READY)
		w->last_rx = now;
	rearm(w);
}

/* ---- losing a worker ---- */

static void watch(struct worker *w)
{
	short ev = 0;
	if (w->pc) {
		ev = w->state == W_CONNECTING ? POLLOUT : POLLIN;
		if (proto_conn_outq(w->pc))
			ev |= POLLOUT;
	}
	if (w->fd >= 0)
		ev_io_events(w->f->loop, w->fd, ev);
}

void worker_close(struct worker *w)
{
	struct farm *f = w->f;
	for (uint32_t i = 0; i < w->n_inflight; i++)
		sched_release(f->s, w->inflight[i], w->index);
	w->n_inflight = 0;
	w->n_cancelled = 0;
	if (w->fd >= 0)
		ev_io_del(f->loop, w->fd);
	w->fd = -1;
	if (w->pc) {
		w->bytes_out += proto_conn_bytes_out(w->pc);
		w->bytes_in += proto_conn_bytes_in(w->pc);
		proto_conn_free(w->pc);
		w->pc = NULL;
	}
	w->state = W_IDLE;
	w->deadline = 0;
	/* its tiles are back in the queue: others may take them */
	for (uint32_t i = 0; i < f->n_w; i++)
		if (&f->w[i] != w)
			worker_dispatch(&f->w[i]);
}

/* Ends the connection; fatal drops the worker for good, otherwise it is
 * retried with back-off. */
static void worker_lost(struct worker *w, bool fatal, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void worker_lost(struct worker *w, bool fatal, const char *fmt, ...)
{
	struct farm *f = w->f;
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(w->why, sizeof w->why, fmt, ap);
	va_end(ap);
	worker_close(w);
	if (w->accepted) {
		/* it dialled us: it may dial again (as a new worker), we cannot;
		 * peers that never said a valid HELLO are only counted */
		w->dropped = true;
		if (w->spoke)
			farm_log_limited(f, "worker %s gone: %s", w->name, w->why);
		else
			f->n_mute++;
	} else if (!fatal && w->retries < FARM_MAX_RETRIES && !atomic_load(sched_stop_flag(f->s))) {
		w->retry_at = net_now() + FARM_BACKOFF_S * pow(2, w->retries);
		w->retries++;
		farm_log(f, "worker %s lost: %s (retry %d of %d in %.1f s)", w->name, w->why, w->retries,
			 FARM_MAX_RETRIES, w->retry_at - net_now());
	} else {
		w->dropped = true;
		farm_log(f, "worker %s dropped: %s", w->name, w->why);
	}
	rearm(w);
	farm_check_alive(f);
}

/* ERROR to the peer (best effort), then dropped for good. */
static void worker_refuse(struct worker *w, int code, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void worker_refuse(struct worker *w, int code, const char *fmt, ...)
{
	char text[LIM_ERROR_TEXT + 1];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(text, sizeof text, fmt, ap);
	va_end(ap);
	if (w->pc) {
		proto_send_error(w->pc, code, "%s", text);
		proto_conn_flush(w->pc);
	}
	worker_lost(w, true, "%s (%s error)", text, proto_err_name(code));
}

void worker_check_caught(struct worker *w)
{
	struct sched_trust tr;
	bool first;
	if (!sched_caught(w->f->s, w->index, &tr, &first) || !first)
		return;
	snprintf(w->why, sizeof w->why, "returned wrong pixels for tile %u (audit)", tr.tile);
	if (w->pc && w->state >= W_HELLO) {
		proto_send_error(w->pc, PERR_PROTOCOL, "wrong pixels for tile %u (audit)", tr.tile);
		proto_conn_flush(w->pc);
	}
	worker_close(w);
	w->dropped = true;
	w->tiles_done = 0; /* none of its tiles is kept */
	rearm(w);
	farm_log(w->f, "worker %s returned wrong pixels for tile %u (audit): dropped; its %u tiles re-rendered",
		 w->name, tr.tile, tr.requeued);
	farm_check_alive(w->f);
}

/* ---- sending ---- */

static void flush(struct worker *w)
{
	if (w->pc && proto_conn_flush(w->pc) < 0) {
		worker_lost(w, false, "connection lost while sending");
		return;
	}
	watch(w);
}

static int send_hello(struct worker *w)
{
	const struct farm *f = w->f;
	struct proto_hello h;
	memset(&h, 0, sizeof h);
	h.version = PROTO_VERSION;
	h.role = ROLE_MASTER;
	h.secret = f->secret != NULL;
	uint32_t ms = (uint32_t)(f->hb_interval * 1000);
	h.heartbeat_ms = ms < PROTO_HB_MIN_MS ? PROTO_HB_MIN_MS : ms > PROTO_HB_MAX_MS ? PROTO_HB_MAX_MS : ms;
	memcpy(h.nonce, w->nonce, sizeof h.nonce);
	snprintf(h.build, sizeof h.build, "%s", proto_build_id());
	return proto_send_hello(w->pc, &h);
}

static int send_offer(struct worker *w)
{
	const struct farm *f = w->f;
	w->offer_at = net_now();
	return proto_send_offer(w->pc, f->hash, f->scene_len, f->width, f->height);
}

/* The window: 2 x threads + 1, plus 1.5 round trips of its tile rate.
 * Before the first result tells the worker's trace time, the rate is a
 * quick tile's (FARM_SVC_GUESS_PX a pixel, FARM_SVC_GUESS_MIN at least:
 * small tiles must not hand a near worker the whole image before it has
 * returned a tile to audit): the first window then covers the round
 * trip too, where 2 x threads + 1 tiles left a far worker idle for one
 * round trip after its first tiles (at 20 ms one way, a tenth of a 0.5 s
 * render); too many tiles at first costs nothing that the end game's
 * duplicates do not already cover. */
static void size_window(struct worker *w)
{
	const struct farm *f = w->f;
	double d = 2.0 * w->threads + 1;
	double guess = FARM_SVC_GUESS_PX * f->tg.side * f->tg.side;
	double svc = w->svc > 0 ? w->svc : guess > FARM_SVC_GUESS_MIN ? guess : FARM_SVC_GUESS_MIN;
	if (w->rtt > 0)
		d += ceil(1.5 * w->rtt * w->threads / svc);
	double tile_bytes = (double)f->tg.side * f->tg.side * render_pixel_bytes(f->px);
	double by_mem = FARM_WINDOW_BYTES / tile_bytes;
	if (d > by_mem)
		d = by_mem;
	if (d > FARM_DEPTH_MAX)
		d = FARM_DEPTH_MAX;
	if (d < w->threads + 1)
		d = w->threads + 1;
	if (d > FARM_DEPTH_MAX)
		d = FARM_DEPTH_MAX;
	w->depth = (uint32_t)d;
}

void worker_dispatch(struct worker *w)
{
	struct farm *f = w->f;
	if ((w->state != W_READY && w->state != W_BUILDING) || !w->pc)
		return;
	double now = net_now();
	bool sent = false;
	while (w->n_inflight < w->depth) {
		/* duplicates only for an idle worker: the tail, not the middle */
		uint32_t id = sched_take(f->s, w->index, w->n_inflight == 0, now);
		if (id == SCHED_NO_TILE)
			break;
		struct tile_rect r = sched_rect(f->s, id);
		struct proto_tile t = { id, r.x, r.y, r.w, r.h, (uint8_t)f->px };
		if (proto_send_tile(w->pc, &t) < 0) {
			sched_release(f->s, id, w->index);
			break;
		}
		if (w->n_inflight == 0)
			w->busy_since = now;
		w->sent_at[w->n_inflight] = now;
		w->inflight[w->n_inflight++] = id;
		sent = true;
	}
	if (sent) {
		rearm(w);
		flush(w);
	}
}

/* Queues scene chunks while the connection's output is short; the first
 * tiles follow the last chunk. */
static void send_scene(struct worker *w)
{
	const struct farm *f = w->f;
	while (w->sent_off < f->scene_len && proto_conn_outq(w->pc) < PROTO_OUT_HIGH_WATER) {
		size_t n = f->scene_len - w->sent_off;
		if (n > PROTO_CHUNK_BYTES)
			n = PROTO_CHUNK_BYTES;
		if (proto_send_data(w->pc, w->sent_off, f->scene + w->sent_off, (uint32_t)n) < 0)
			return;
		w->sent_off += n;
		w->scene_bytes += n;
	}
	if (w->sent_off == f->scene_len) {
		set_state(w, W_BUILDING, FARM_BUILD_HB * f->hb_timeout + FARM_BUILD_LOCAL * f->build_s);
		worker_dispatch(w);
	}
}

static void cancel_on(struct worker *w, uint32_t id)
{
	for (uint32_t k = 0; k < w->n_inflight; k++) {
		if (w->inflight[k] != id)
			continue;
		w->n_inflight--;
		w->inflight[k] = w->inflight[w->n_inflight];
		w->sent_at[k] = w->sent_at[w->n_inflight];
		if (w->n_cancelled == FARM_DEPTH_MAX) /* forget the oldest */
			memmove(w->cancelled, w->cancelled + 1, --w->n_cancelled * sizeof *w->cancelled);
		w->cancelled[w->n_cancelled++] = id;
		proto_send_cancel(w->pc, id);
		flush(w);
		return;
	}
}

static void note_latency(struct worker *w, double dt)
{
	w->lat[w->n_lat % FARM_LAT_KEEP] = dt;
	w->n_lat++;
	uint32_t n = w->n_lat < FARM_LAT_KEEP ? w->n_lat : FARM_LAT_KEEP;
	double v[FARM_LAT_KEEP];
	memcpy(v, w->lat, n * sizeof *v);
	for (uint32_t i = 1; i < n; i++) /* insertion sort: a few dozen values */
		for (uint32_t j = i; j > 0 && v[j - 1] > v[j]; j--) {
			double x = v[j];
			v[j] = v[j - 1];
			v[j - 1] = x;
		}
	w->median = v[n / 2];
}

/* ---- receiving ---- */

/* A TILE_RESULT: check it against what was sent, then hand it to the scheduler. */
static void on_result(struct worker *w, const struct proto_msg *m)
{
	struct farm *f = w->f;
	const struct proto_tile *t = &m->u.result.tile;
	uint32_t k, c = UINT32_MAX;
	for (k = 0; k < w->n_inflight; k++)
		if (w->inflight[k] == t->id)
			break;
	if (k == w->n_inflight)
		for (c = 0; c < w->n_cancelled; c++)
			if (w->cancelled[c] == t->id)
				break;
	if (k == w->n_inflight && c >= w->n_cancelled) {
		f->invalid_results++;
		worker_refuse(w, PERR_PROTOCOL, "result for tile %u, which is not in flight on this connection", t->id);
		return;
	}
	struct tile_rect r = sched_rect(f->s, t->id);
	if (t->x != r.x || t->y != r.y || t->w != r.w || t->h != r.h) {
		f->invalid_results++;
		worker_refuse(w, PERR_PROTOCOL, "tile %u came back as %ux%u at (%u,%u), sent as %ux%u at (%u,%u)",
			      t->id, t->w, t->h, t->x, t->y, r.w, r.h, r.x, r.y);
		return;
	}
	if (t->px != (uint8_t)f->px) { /* its length follows its type: wrong either way */
		f->invalid_results++;
		worker_refuse(w, PERR_PROTOCOL, "tile %u came back with pixel type %u, sent with %u", t->id,
			      (unsigned)t->px, (unsigned)f->px);
		return;
	}
	if (crc32_update(0, m->u.result.pixels, proto_tile_bytes(t)) != m->u.result.crc) {
		f->invalid_results++;
		worker_refuse(w, PERR_PROTOCOL, "tile %u failed its checksum", t->id);
		return;
	}
	/* a valid tile earns the worker its retries back (reaching READY does
	 * not: a worker failing every tile after READY was retried for ever) */
	w->retries = 0;
	double now = net_now();
	w->last_result = now;
	if (m->u.result.trace_us > 0) {
		/* the window follows the worker's trace time (a moving mean) */
		double s = m->u.result.trace_us * 1e-6;
		w->svc = w->svc > 0 ? 0.8 * w->svc + 0.2 * s : s;
		size_window(w);
	}
	if (k == w->n_inflight) { /* answered after its CANCEL: someone else was first */
		w->cancelled[c] = w->cancelled[--w->n_cancelled];
		return;
	}
	note_latency(w, now - w->sent_at[k]);
	w->n_inflight--;
	w->inflight[k] = w->inflight[w->n_inflight];
	w->sent_at[k] = w->sent_at[w->n_inflight];
	uint16_t other;
	bool audit = sched_audit_due(f->s, w->index, w->delivered, t->id);
	if (sched_result(f->s, t->id, w->index, m->u.result.pixels, audit, &other) == SCHED_USED) {
		w->tiles_done++;
		w->delivered++;
		if (other < f->n_w && f->w[other].state == W_READY) {
			cancel_on(&f->w[other], t->id);
			worker_dispatch(&f->w[other]); /* its window has room again */
		}
	}
}

/* The worker's HELLO: checked, then our proof (and OFFER) or, without a
 * secret, nothing more to send (our OFFER went with our HELLO). */
static void on_hello(struct worker *w, const struct proto_msg *m)
{
	struct farm *f = w->f;
	char why[LIM_ERROR_TEXT + 1];
	w->spoke = true; /* a HELLO, good or not: its fate is worth a line, and it is no idle peer */
	int code = proto_hello_check(m, ROLE_WORKER, f->secret != NULL, PROTO_VERSION, why, sizeof why);
	if (code) {
		worker_refuse(w, code, "%s", why);
		return;
	}
	memcpy(w->peer_nonce, m->u.hello.nonce, PROTO_NONCE_BYTES);
	w->threads = m->u.hello.threads ? m->u.hello.threads : 1;
	if (w->accepted && !f->o->quiet)
		farm_log_limited(f, "worker %s dialled in (%u threads)", w->name, w->threads);
	size_window(w);
	if (f->secret) {
		uint8_t mac[PROTO_MAC_BYTES];
		proto_auth_mac(f->secret, f->secret_len, ROLE_MASTER, w->nonce, w->peer_nonce, mac);
		proto_send_auth(w->pc, mac);
		send_offer(w);
		set_state(w, W_AUTH, f->hb_timeout);
	} else {
		set_state(w, W_OFFER, f->hb_timeout);
		proto_conn_set_limit(w->pc, LIM_FRAME_PAYLOAD); /* tile results from now on */
	}
}

/* One message from w, by state. */
static void on_message(struct worker *w, const struct proto_msg *m)
{
	struct farm *f = w->f;
	if (w->state == W_DONE)
		return; /* BYE sent: whatever it still says is moot */
	if (m->type == MSG_ERROR) {
		/* transient: the worker timed out, is shutting down, ran out of
		 * memory or is busy (connection or transfer limits): try again */
		bool fatal = m->u.error.code != PERR_TIMEOUT && m->u.error.code != PERR_SHUTDOWN &&
			     m->u.error.code != PERR_INTERNAL && m->u.error.code != PERR_LIMIT;
		worker_lost(w, fatal, "worker says: %s (%s error)", m->u.error.text, proto_err_name(m->u.error.code));
		return;
	}
	if (m->type == MSG_HEARTBEAT && w->state >= W_OFFER)
		return; /* life only where it counts (last_rx is kept by the caller) */
	switch (w->state) {
	case W_HELLO:
		if (m->type != MSG_HELLO)
			break;
		on_hello(w, m);
		return;
	case W_AUTH: {
		if (m->type != MSG_AUTH)
			break;
		uint8_t want[PROTO_MAC_BYTES];
		proto_auth_mac(f->secret, f->secret_len, ROLE_WORKER, w->nonce, w->peer_nonce, want);
		if (!proto_mac_equal(want, m->u.mac, PROTO_MAC_BYTES)) {
			worker_refuse(w, PERR_AUTH, "authentication failed: the worker's secret differs");
			return;
		}
		/* the OFFER left with our proof: its deadline runs from then. A
		 * proof read in the same round as its own (passed) deadline
		 * leaves nothing, which set_state would take for no deadline */
		double left = f->hb_timeout - (net_now() - w->offer_at);
		if (left <= 0) {
			worker_refuse(w, PERR_TIMEOUT, "%s not done within %.1f s", state_name(W_OFFER), f->hb_timeout);
			return;
		}
		set_state(w, W_OFFER, left);
		proto_conn_set_limit(w->pc, LIM_FRAME_PAYLOAD); /* tile results from now on */
		return;
	}
	case W_OFFER:
		if ((m->type == MSG_SCENE_HAVE || m->type == MSG_SCENE_NEED) &&
		    memcmp(m->u.hash, f->hash, PROTO_HASH_BYTES) == 0) {
			double rtt = net_now() - w->offer_at;
			if (w->rtt == 0 || rtt < w->rtt)
				w->rtt = rtt;
			size_window(w);
			w->cache_hit = m->type == MSG_SCENE_HAVE;
			w->sent_off = 0;
			if (m->type == MSG_SCENE_NEED) {
				set_state(w, W_SENDING, f->hb_timeout);
				send_scene(w);
			} else {
				set_state(w, W_BUILDING, FARM_BUILD_HB * f->hb_timeout + FARM_BUILD_LOCAL * f->build_s);
				worker_dispatch(w);
			}
			return;
		}
		break;
	case W_SENDING:
	case W_BUILDING:
		if (m->type == MSG_SCENE_READY && w->state == W_BUILDING &&
		    memcmp(m->u.ready.hash, f->hash, PROTO_HASH_BYTES) == 0) {
			set_state(w, W_READY, 0);
			worker_dispatch(w);
			return;
		}
		break;
	case W_READY:
		if (m->type == MSG_TILE_RESULT) {
			on_result(w, m);
			if (w->state == W_READY)
				worker_dispatch(w);
			return;
		}
		break;
	default:
		break;
	}
	worker_refuse(w, PERR_PROTOCOL, "unexpected %s message during the %s", proto_type_name(m->type),
		      state_name(w->state));
}

static void on_input(struct worker *w)
{
	const char *why;
	int r = proto_conn_read(w->pc, &why);
	struct proto_msg m;
	int code;
	while (w->pc) {
		int k = proto_conn_next(w->pc, &m, &code, &why);
		if (k == 0)
			break;
		if (k < 0) {
			worker_refuse(w, code, "%s", why);
			return;
		}
		/* whole frames only: trickled bytes are no heartbeat */
		if (w->state >= W_BUILDING)
			w->last_rx = net_now();
		on_message(w, &m);
	}
	/* bytes already buffered (an ERROR, say) were read before giving up */
	if (r < 0 && w->pc)
		worker_lost(w, false, "%s", why);
}

/* Connected (either way): our HELLO, and without a secret our OFFER. */
static void begin_handshake(struct worker *w)
{
	struct farm *f = w->f;
	/* an unauthenticated peer gets no big buffers from us */
	proto_conn_set_limit(w->pc, LIM_HANDSHAKE_PAYLOAD);
	w->last_hb = net_now();
	/* a fresh nonce per connection, or no handshake: a predictable one
	 * would let a recorded proof be replayed */
	if (proto_random(w->nonce, sizeof w->nonce) < 0) {
		worker_lost(w, true, "no random source for the handshake nonce");
		return;
	}
	if (send_hello(w) < 0 || (!f->secret && send_offer(w) < 0)) {
		worker_lost(w, false, "out of memory");
		return;
	}
	set_state(w, W_HELLO, f->hb_timeout);
}

static void on_connected(struct worker *w)
{
	char err[300];
	if (net_connect_finish(w->fd, err, sizeof err) < 0) {
		worker_lost(w, false, "%s", err);
		return;
	}
	begin_handshake(w);
}

static void on_io(struct ev_loop *l, int fd, short re, void *arg)
{
	(void)l;
	(void)fd;
	struct worker *w = arg;
	if (w->state == W_CONNECTING) {
		on_connected(w);
	} else {
		if (re & (POLLIN | POLLHUP | POLLERR))
			on_input(w);
		if (w->pc && w->state == W_SENDING && (re & POLLOUT)) {
			/* the socket took bytes: the transfer makes progress */
			w->deadline = net_now() + w->f->hb_timeout;
			send_scene(w);
		}
	}
	if (w->pc)
		flush(w);
}

void worker_start(struct worker *w)
{
	struct farm *f = w->f;
	char err[300];
	int fd = net_connect_start(w->addr.host, w->addr.port, err, sizeof err);
	w->connections++;
	w->retry_at = 0;
	if (fd < 0 || !(w->pc = proto_conn_new(fd)) || ev_io_set(f->loop, fd, POLLOUT, on_io, w) < 0) {
		if (fd >= 0 && !w->pc)
			close(fd);
		worker_lost(w, false, "%s", fd < 0 ? err : "out of memory");
		return;
	}
	w->fd = fd;
	set_state(w, W_CONNECTING, f->hb_timeout);
}

void worker_accepted(struct worker *w, int fd)
{
	struct farm *f = w->f;
	w->accepted = true;
	w->connections++;
	if (!(w->pc = proto_conn_new(fd)) || ev_io_set(f->loop, fd, POLLIN, on_io, w) < 0) {
		if (!w->pc)
			close(fd);
		worker_lost(w, true, "out of memory");
		return;
	}
	w->fd = fd;
	begin_handshake(w);
	if (w->pc)
		flush(w);
}

void worker_bye(struct worker *w)
{
	if (w->pc && w->state >= W_HELLO) {
		proto_send_bye(w->pc);
		w->state = W_DONE;
		ev_timer_stop(w->f->loop, &w->tm);
	}
}

/* The worker's timer: whichever of its deadlines or duties is due. */
static void worker_timer(struct ev_loop *l, void *arg)
{
	(void)l;
	struct worker *w = arg;
	struct farm *f = w->f;
	double now = net_now();
	if (w->state == W_IDLE) {
		if (!w->dropped && w->retry_at > 0 && now >= w->retry_at && !atomic_load(sched_stop_flag(f->s)))
			worker_start(w);
		else
			rearm(w);
		return;
	}
	if (w->state == W_DONE)
		return;
	if (w->deadline > 0 && now >= w->deadline) {
		if (w->state == W_CONNECTING)
			worker_lost(w, false, "no connection within %.1f s", f->hb_timeout);
		else if (w->state == W_SENDING)
			worker_refuse(w, PERR_TIMEOUT, "scene transfer stalled for %.1f s", f->hb_timeout);
		else
			worker_refuse(w, PERR_TIMEOUT, "%s not done within %.1f s", state_name(w->state),
				      w->deadline - w->state_at);
		return;
	}
	if (w->state >= W_BUILDING && now - w->last_rx > f->hb_timeout) {
		worker_lost(w, false, "no heartbeat for %.1f s", now - w->last_rx);
		return;
	}
	if (w->state == W_READY && w->n_inflight > 0) {
		/* a tracer stuck on a tile while the worker heartbeats */
		double since = hang_since(w), d = hang_deadline(w);
		if (now - since > d) {
			worker_refuse(w, PERR_TIMEOUT, "hung: no tile result for %.1f s while holding %u tiles (deadline %.1f s)",
				      now - since, w->n_inflight, d);
			return;
		}
	}
	if (w->state >= W_OFFER && now - w->last_hb >= f->hb_interval * 0.999) {
		proto_send_heartbeat(w->pc, 0, 0);
		w->last_hb = now;
		flush(w);
		if (!w->pc)
			return;
	}
	ev_timer_stop(f->loop, &w->tm);
	rearm(w);
}
