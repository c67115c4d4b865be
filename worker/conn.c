/*
 * conn.c - one connection's state machine (conn.h).
 *
 * Nothing a peer sends can make this program open a file or run anything:
 * a scene arrives as bytes (RAW meshes inside it) and is decoded with every
 * count bounded. A peer that breaks the protocol gets an ERROR and is
 * closed. Until it has authenticated, a peer's frames are at most
 * LIM_HANDSHAKE_PAYLOAD long, nothing but HELLO, AUTH, ERROR and BYE is
 * acted on, and nothing it sends counts as a sign of life.
 */
#include <poll.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "proto/net.h"
#include "worker/conn.h"

static void on_io(struct ev_loop *l, int fd, short revents, void *arg);
static void on_handshake_timeout(struct ev_loop *l, void *arg);
static void on_silence_check(struct ev_loop *l, void *arg);
static void on_heartbeat(struct ev_loop *l, void *arg);
static void on_linger_over(struct ev_loop *l, void *arg);

/* Moves to state st, keeping the server's count of bytes being received. */
static void set_state(struct wk_conn *c, enum wk_state st)
{
	if (c->state == ST_RECV)
		c->srv->receiving -= c->scene_size;
	if (st == ST_RECV)
		c->srv->receiving += c->scene_size;
	c->state = st;
}

/* Log lines about peers that have not authenticated are rate-limited: a
 * flood must not fill the disk. */
static void peer_log(struct wk_conn *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void peer_log(struct wk_conn *c, const char *fmt, ...)
{
	char line[LIM_ERROR_TEXT * 2 + 256];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(line, sizeof line, fmt, ap);
	va_end(ap);
	if (c->authed)
		wk_log("%s", line);
	else
		wk_log_limited(&c->srv->quiet_log, "%s", line);
}

void wk_conn_job_log(struct wk_conn *c, const char *how)
{
	if (c->logged || c->state < ST_BUILD || c->state == ST_CLOSING)
		return;
	char hx[17];
	wk_hex8(c->hash, hx);
	wk_log("job %s scene %s %ux%u: %u tiles in %.2f s, scene cache %s (%llu scene bytes received), %s", c->peer,
	       hx, c->w, c->h, c->tiles_done, net_now() - c->started, c->cache_hit ? "hit" : "miss",
	       (unsigned long long)c->scene_len, how);
	c->logged = true;
}

/* Lets go of the job (cancelled: a tracer on one of its tiles gives up) or
 * of the scene the connection was waiting for. */
static void drop_job(struct wk_conn *c)
{
	if (c->job)
		wk_job_release(&c->srv->tracers, c->job);
	else if (c->entry)
		wk_cache_unref(&c->srv->cache, c->entry);
	c->job = NULL;
	c->entry = NULL;
}

/* ERROR sent, BYE or the peer's ERROR: nothing more is read or traced; the
 * output is flushed for at most WK_LINGER_S, then the socket closes. */
static void enter_closing(struct wk_conn *c)
{
	struct ev_loop *l = c->srv->loop;
	c->logged = true;
	drop_job(c);
	set_state(c, ST_CLOSING);
	wk_server_forget(c->srv, c, false);
	ev_timer_stop(l, &c->t_handshake);
	ev_timer_stop(l, &c->t_silence);
	ev_timer_stop(l, &c->t_heartbeat);
	ev_timer_arm(l, &c->t_linger, net_now() + WK_LINGER_S);
}

void wk_conn_fail(struct wk_conn *c, int code, const char *fmt, ...)
{
	if (c->state == ST_CLOSING)
		return;
	char text[LIM_ERROR_TEXT + 1];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(text, sizeof text, fmt, ap);
	va_end(ap);
	if (c->state >= ST_BUILD && !c->logged) {
		char how[LIM_ERROR_TEXT + 64];
		snprintf(how, sizeof how, "ended: %s (%s error)", text, proto_err_name(code));
		wk_conn_job_log(c, how);
	} else if (!c->logged) {
		peer_log(c, "%s: refused: %s (%s error)", c->peer, text, proto_err_name(code));
	}
	proto_send_error(c->pc, code, "%s", text);
	enter_closing(c);
}

void wk_conn_close(struct wk_conn *c)
{
	struct ev_loop *l = c->srv->loop;
	drop_job(c);
	set_state(c, ST_CLOSING);
	ev_timer_stop(l, &c->t_handshake);
	ev_timer_stop(l, &c->t_silence);
	ev_timer_stop(l, &c->t_heartbeat);
	ev_timer_stop(l, &c->t_linger);
	ev_io_del(l, c->fd);
	wk_server_forget(c->srv, c, true);
	proto_conn_free(c->pc);
	free(c->scene);
	free(c);
}

static void on_message(struct wk_conn *c, const struct proto_msg *m);

/*
 * The master closed while this end was still sending: after refusing a
 * tile it sends its ERROR and closes, and the tiles this worker sends
 * meanwhile make its side reset the connection. What it sent before is
 * still readable (a reset does not take back data already received), so
 * its ERROR is read and logged, as it would have been without the race.
 */
static void last_words(struct wk_conn *c)
{
	const char *why = NULL;
	for (int i = 0; i < 64 && c->state != ST_CLOSING; i++) {
		int r = proto_conn_read(c->pc, &why);
		struct proto_msg m;
		int code;
		while (c->state != ST_CLOSING && proto_conn_next(c->pc, &m, &code, &why) > 0)
			if (m.type == MSG_ERROR)
				on_message(c, &m);
		if (r <= 0)
			break;
	}
}

bool wk_conn_settle(struct wk_conn *c)
{
	if (proto_conn_flush(c->pc) < 0) {
		last_words(c);
		wk_conn_job_log(c, "connection lost while sending");
		wk_conn_close(c);
		return false;
	}
	size_t q = proto_conn_outq(c->pc);
	if (c->state == ST_CLOSING && q == 0) {
		wk_conn_close(c);
		return false;
	}
	if (c->job)
		wk_job_set_outq(&c->srv->tracers, c->job, q); /* back-pressure */
	ev_io_events(c->srv->loop, c->fd, (short)((c->state != ST_CLOSING ? POLLIN : 0) | (q ? POLLOUT : 0)));
	return true;
}

/* ---- the handshake ---- */

static void send_hello(struct wk_conn *c)
{
	const struct wk_opts *o = c->srv->opt;
	struct proto_hello h;
	memset(&h, 0, sizeof h);
	h.version = wk_fault_version(&o->faults);
	h.role = ROLE_WORKER;
	h.secret = o->secret != NULL;
	h.threads = (uint16_t)(c->srv->threads > 65535 ? 65535 : c->srv->threads);
	memcpy(h.nonce, c->nonce, PROTO_NONCE_BYTES);
	wk_fault_build_id(&o->faults, h.build, sizeof h.build);
	if (h.version != PROTO_VERSION)
		proto_conn_set_version(c->pc, (uint16_t)h.version);
	proto_send_hello(c->pc, &h);
}

struct wk_conn *wk_conn_new(struct wk_server *srv, int fd, const char *peer, const char **why)
{
	struct wk_conn *c = calloc(1, sizeof *c);
	struct proto_conn *pc = c ? proto_conn_new(fd) : NULL;
	if (!pc) {
		close(fd);
		free(c);
		*why = "out of memory";
		return NULL;
	}
	c->srv = srv;
	c->pc = pc;
	c->fd = fd;
	snprintf(c->peer, sizeof c->peer, "%s", peer);
	const char *colon = strrchr(c->peer, ':');
	c->addr_len = colon ? (size_t)(colon - c->peer) : strlen(c->peer);
	if (proto_random(c->nonce, sizeof c->nonce) < 0 || ev_io_set(srv->loop, fd, POLLIN, on_io, c) < 0) {
		proto_conn_free(pc);
		free(c);
		*why = "no random source or out of memory";
		return NULL;
	}
	/* until the handshake is done, no frame longer than a HELLO */
	proto_conn_set_limit(pc, LIM_HANDSHAKE_PAYLOAD);
	c->state = ST_HELLO;
	c->started = c->last_rx = net_now();
	ev_timer_init(&c->t_handshake, on_handshake_timeout, c);
	ev_timer_init(&c->t_silence, on_silence_check, c);
	ev_timer_init(&c->t_heartbeat, on_heartbeat, c);
	ev_timer_init(&c->t_linger, on_linger_over, c);
	ev_timer_arm(srv->loop, &c->t_handshake, c->started + srv->opt->handshake_s);
	send_hello(c);
	return c;
}

/* Authenticated (the secret's proof checked, or the HELLO when there is no
 * secret): scene chunks may come now, and from now on the master's frames
 * are signs of life and we heartbeat, so a long scene transfer or build
 * never looks like a dead peer to either side. */
static void enter_offer(struct wk_conn *c)
{
	if (!wk_server_authed(c->srv, c))
		return;
	double now = net_now();
	set_state(c, ST_OFFER);
	proto_conn_set_limit(c->pc, PROTO_MASTER_FRAME_MAX);
	c->last_rx = now;
	ev_timer_arm(c->srv->loop, &c->t_silence, now + proto_hb_deadline(c->hb_interval));
	ev_timer_arm(c->srv->loop, &c->t_heartbeat, now + c->hb_interval);
}

static void on_hello(struct wk_conn *c, const struct proto_msg *m)
{
	const struct wk_opts *o = c->srv->opt;
	char why[LIM_ERROR_TEXT + 1];
	int code = proto_hello_check(m, ROLE_MASTER, o->secret != NULL, wk_fault_version(&o->faults), why, sizeof why);
	if (code) {
		wk_conn_fail(c, code, "%s", why);
		return;
	}
	c->spoke = true;
	memcpy(c->peer_nonce, m->u.hello.nonce, PROTO_NONCE_BYTES);
	/* the interval as agreed: proto_hello_check bounded it */
	c->hb_interval = m->u.hello.heartbeat_ms / 1000.0;
	if (o->secret)
		set_state(c, ST_AUTH);
	else
		enter_offer(c);
}

static void on_auth(struct wk_conn *c, const struct proto_msg *m)
{
	const struct wk_opts *o = c->srv->opt;
	uint8_t want[PROTO_MAC_BYTES];
	proto_auth_mac(o->secret, o->secret_len, ROLE_MASTER, c->peer_nonce, c->nonce, want);
	if (!proto_mac_equal(want, m->u.mac, PROTO_MAC_BYTES)) {
		wk_conn_fail(c, PERR_AUTH, "authentication failed: the master's secret differs from this worker's");
		return;
	}
	proto_auth_mac(o->secret, o->secret_len, ROLE_WORKER, c->peer_nonce, c->nonce, want);
	proto_send_auth(c->pc, want);
	enter_offer(c);
}

/* ---- the scene ---- */

/* Answers every queued tile with black pixels (--test-fault black). */
static void answer_black(struct wk_conn *c, const struct proto_tile *t)
{
	size_t n = proto_tile_bytes(t); /* black: zero bytes in every pixel type */
	uint8_t *px = calloc(1, n);
	if (!px) {
		wk_conn_fail(c, PERR_INTERNAL, "out of memory");
		return;
	}
	proto_send_result(c->pc, t, px, crc32_update(0, px, n));
	c->tiles_done++;
	free(px);
}

/* The scene is built: SCENE_READY, then the tiles queued meanwhile go to
 * the tracers (their results come strictly after it). */
static void job_ready(struct wk_conn *c)
{
	set_state(c, ST_READY);
	proto_send_ready(c->pc, c->hash, c->cache_hit, c->entry->build_ms);
	if (wk_fault_black(&c->srv->opt->faults)) {
		struct proto_tile t;
		while (c->state == ST_READY && wk_job_pop_tile(&c->srv->tracers, c->job, &t))
			answer_black(c, &t);
		return;
	}
	wk_job_start(&c->srv->tracers, c->job);
}

void wk_conn_built(struct wk_conn *c, struct wk_entry *e)
{
	if (c->state != ST_BUILD || c->entry != e)
		return;
	if (e->state == WK_ENTRY_READY)
		job_ready(c);
	else if (e->state == WK_ENTRY_FAILED)
		wk_conn_fail(c, PERR_SCENE, "scene rejected: %s", e->error);
}

/* The scene is in hand (cached, or received whole), with the connection's
 * reference: the job exists from now on, so tiles may be queued while the
 * scene builds; it starts once the entry is ready. */
static void use_entry(struct wk_conn *c, struct wk_entry *e)
{
	c->entry = e;
	c->job = wk_job_new(&c->srv->tracers, e, c); /* the reference moves to the job */
	if (!c->job) {
		wk_conn_fail(c, PERR_INTERNAL, "out of memory");
		return;
	}
	set_state(c, ST_BUILD);
	wk_conn_built(c, e);
}

/* A new entry for bytes (taken), queued for building, then used. */
static void build_new(struct wk_conn *c, uint8_t *bytes, size_t len)
{
	struct wk_server *s = c->srv;
	struct wk_entry *e = wk_cache_add(&s->cache, c->hash, c->w, c->h, bytes, len);
	if (!e) {
		wk_conn_fail(c, PERR_INTERNAL, "out of memory");
		return;
	}
	if (wk_tracers_build(&s->tracers, e) < 0) {
		snprintf(e->error, sizeof e->error, "out of memory");
		wk_cache_built(&s->cache, e, false);
	}
	use_entry(c, e);
	wk_cache_trim(&s->cache);
}

static void on_offer(struct wk_conn *c, const struct proto_msg *m)
{
	struct wk_server *s = c->srv;
	ev_timer_stop(s->loop, &c->t_handshake);
	memcpy(c->hash, m->u.offer.hash, PROTO_HASH_BYTES);
	c->w = m->u.offer.width;
	c->h = m->u.offer.height;
	c->scene_size = m->u.offer.size;
	c->started = net_now();
	if (c->scene_size > s->opt->cache_bytes) {
		wk_conn_fail(c, PERR_LIMIT, "scene of %llu bytes exceeds this worker's --cache-mb",
			     (unsigned long long)c->scene_size);
		return;
	}
	bool exact;
	struct wk_entry *e = wk_cache_find(&s->cache, c->hash, c->w, c->h, &exact);
	if (e && exact) {
		c->cache_hit = true;
		proto_send_hash(c->pc, MSG_SCENE_HAVE, c->hash);
		use_entry(c, e);
		return;
	}
	if (e) { /* the same scene at another size: built again from the cached bytes */
		uint8_t *copy = malloc(e->len);
		if (copy) {
			memcpy(copy, e->bytes, e->len);
			c->cache_hit = true;
			proto_send_hash(c->pc, MSG_SCENE_HAVE, c->hash);
			build_new(c, copy, e->len);
			return;
		}
	}
	/* scenes being received count against the same budget: many peers
	 * offering big scenes at once cannot make the worker hold more */
	if (s->receiving + c->scene_size > s->opt->cache_bytes) {
		wk_conn_fail(c, PERR_LIMIT, "scenes being received would exceed this worker's --cache-mb: try again later");
		return;
	}
	proto_send_hash(c->pc, MSG_SCENE_NEED, c->hash);
	set_state(c, ST_RECV);
}

static void on_data(struct wk_conn *c, const struct proto_msg *m)
{
	if (m->u.data.offset != c->scene_len || c->scene_len + m->u.data.n > c->scene_size) {
		wk_conn_fail(c, PERR_PROTOCOL, "scene chunk at offset %llu out of order or past the offered size",
			     (unsigned long long)m->u.data.offset);
		return;
	}
	if (c->scene_len + m->u.data.n > c->scene_cap) {
		/* grow with the bytes that actually arrived, never to the offered size at once */
		size_t nc = c->scene_cap ? c->scene_cap * 2 : PROTO_CHUNK_BYTES;
		while (nc < c->scene_len + m->u.data.n)
			nc *= 2;
		if (nc > c->scene_size)
			nc = (size_t)c->scene_size;
		uint8_t *p = realloc(c->scene, nc);
		if (!p) {
			wk_conn_fail(c, PERR_INTERNAL, "out of memory for the scene");
			return;
		}
		c->scene = p;
		c->scene_cap = nc;
	}
	memcpy(c->scene + c->scene_len, m->u.data.bytes, m->u.data.n);
	c->scene_len += m->u.data.n;
	if (c->scene_len < c->scene_size)
		return;
	uint8_t h[PROTO_HASH_BYTES];
	proto_scene_hash(c->scene, c->scene_len, h);
	if (!proto_mac_equal(h, c->hash, PROTO_HASH_BYTES)) {
		wk_conn_fail(c, PERR_SCENE, "scene bytes do not match the offered hash");
		return;
	}
	uint8_t *bytes = c->scene;
	c->scene = NULL;
	c->scene_cap = 0;
	set_state(c, ST_BUILD); /* no longer receiving (use_entry says it again) */
	/* another connection may have brought the same scene meanwhile: share it */
	bool exact;
	struct wk_entry *same = wk_cache_find(&c->srv->cache, c->hash, c->w, c->h, &exact);
	if (same && exact) {
		free(bytes);
		use_entry(c, same);
		return;
	}
	build_new(c, bytes, c->scene_len);
}

/* ---- tiles ---- */

static void on_tile(struct wk_conn *c, const struct proto_tile *t)
{
	if ((uint64_t)t->x + t->w > c->w || (uint64_t)t->y + t->h > c->h) {
		wk_conn_fail(c, PERR_PROTOCOL, "tile %u (%u,%u %ux%u) is outside the %ux%u image", t->id, t->x, t->y,
			     t->w, t->h, c->w, c->h);
		return;
	}
	if (!c->got_tile) {
		char hx[17];
		wk_hex8(c->hash, hx);
		wk_log("job %s scene %s %ux%u: started", c->peer, hx, c->w, c->h);
		c->got_tile = true;
	}
	if (c->state == ST_READY && wk_fault_black(&c->srv->opt->faults)) {
		answer_black(c, t); /* simulated worker: instant black tiles */
		return;
	}
	int rc = wk_job_add_tile(&c->srv->tracers, c->job, t);
	if (rc > 0)
		wk_conn_fail(c, PERR_LIMIT, "more than %u tiles queued", LIM_TILES_QUEUED);
	else if (rc < 0)
		wk_conn_fail(c, PERR_INTERNAL, "out of memory");
}

void wk_conn_result(struct wk_conn *c, const struct wk_result *r)
{
	if (c->state != ST_READY)
		return;
	if (!r->pixels) {
		wk_conn_fail(c, PERR_INTERNAL, "out of memory tracing a tile");
		return;
	}
	struct proto_tile t = r->tile;
	uint32_t crc = r->crc;
	wk_fault_result(&c->srv->opt->faults, &t, &crc);
	proto_send_result_timed(c->pc, &t, r->pixels, crc, r->trace_us);
	c->tiles_done++;
}

/* ---- messages ---- */

/* One decoded message, by state. */
static void on_message(struct wk_conn *c, const struct proto_msg *m)
{
	if (m->type == MSG_ERROR) {
		peer_log(c, "%s: peer says: %s (%s error)", c->peer, m->u.error.text, proto_err_name(m->u.error.code));
		wk_conn_job_log(c, "ended by the master's error");
		enter_closing(c);
		return;
	}
	if (m->type == MSG_BYE) {
		/* in any state: a master whose render ended before its job started */
		wk_conn_job_log(c, "done"); /* (no line for a job that never started) */
		enter_closing(c);
		return;
	}
	/* a heartbeat proves life only from an authenticated master */
	if (m->type == MSG_HEARTBEAT && c->state >= ST_OFFER)
		return;
	switch (c->state) {
	case ST_HELLO:
		if (m->type != MSG_HELLO)
			break;
		on_hello(c, m);
		return;
	case ST_AUTH:
		if (m->type != MSG_AUTH)
			break;
		on_auth(c, m);
		return;
	case ST_OFFER:
		if (m->type != MSG_SCENE_OFFER)
			break;
		on_offer(c, m);
		return;
	case ST_RECV:
		if (m->type != MSG_SCENE_DATA)
			break;
		on_data(c, m);
		return;
	case ST_BUILD: /* protocol 2: the master may pipeline tiles behind its scene */
	case ST_READY:
		if (m->type == MSG_TILE) {
			on_tile(c, &m->u.tile);
			return;
		}
		if (m->type == MSG_CANCEL) {
			wk_job_cancel_tiles(&c->srv->tracers, c->job, m->u.cancel_id);
			return;
		}
		break;
	case ST_CLOSING:
		return;
	}
	wk_conn_fail(c, PERR_PROTOCOL, "unexpected %s message", proto_type_name(m->type));
}

void wk_conn_input(struct wk_conn *c)
{
	const char *why = NULL;
	if (proto_conn_read(c->pc, &why) < 0) {
		if (c->state != ST_CLOSING) {
			wk_conn_job_log(c, why);
			if (!c->logged)
				peer_log(c, "%s: %s", c->peer, why);
		}
		wk_conn_close(c);
		return;
	}
	struct proto_msg m;
	int code;
	while (c->state != ST_CLOSING) {
		int k = proto_conn_next(c->pc, &m, &code, &why);
		if (k == 0)
			break;
		if (k < 0) {
			wk_conn_fail(c, code, "%s", why);
			break;
		}
		/* only whole frames of an authenticated master count as a sign
		 * of life: a peer trickling bytes of a frame it never finishes,
		 * or heartbeating instead of authenticating, still times out */
		if (c->state >= ST_OFFER)
			c->last_rx = net_now();
		on_message(c, &m);
	}
	wk_conn_settle(c);
}

/* ---- events and timers ---- */

static void on_io(struct ev_loop *l, int fd, short revents, void *arg)
{
	(void)l;
	(void)fd;
	struct wk_conn *c = arg;
	if (c->state != ST_CLOSING && (revents & (POLLIN | POLLHUP | POLLERR)))
		wk_conn_input(c);
	else if (revents & (POLLHUP | POLLERR) && !(revents & POLLOUT))
		wk_conn_close(c); /* closing, and the peer is gone: nothing will flush */
	else
		wk_conn_settle(c);
}

static void on_handshake_timeout(struct ev_loop *l, void *arg)
{
	(void)l;
	struct wk_conn *c = arg;
	wk_conn_fail(c, PERR_TIMEOUT, "handshake took longer than %.1f s", c->srv->opt->handshake_s);
	wk_conn_settle(c);
}

/* The silence deadline is not moved at every frame: when it fires it looks
 * at the last one and sleeps again if the master spoke meanwhile. */
static void on_silence_check(struct ev_loop *l, void *arg)
{
	struct wk_conn *c = arg;
	double deadline = proto_hb_deadline(c->hb_interval);
	double due = c->last_rx + deadline;
	if (net_now() < due) {
		ev_timer_arm(l, &c->t_silence, due);
		return;
	}
	wk_conn_job_log(c, "master silent: dropped");
	wk_conn_fail(c, PERR_TIMEOUT, "master silent for %.0f s", deadline);
	wk_conn_settle(c);
}

/* Our heartbeat, unless output is still queued: what waits reaches the
 * master before a heartbeat would, and a master that does not read must
 * not make the queue grow by one every interval. */
static void on_heartbeat(struct ev_loop *l, void *arg)
{
	struct wk_conn *c = arg;
	ev_timer_arm(l, &c->t_heartbeat, net_now() + c->hb_interval);
	if (proto_conn_outq(c->pc) > 0)
		return;
	uint32_t pending = c->job ? wk_job_pending(&c->srv->tracers, c->job) : 0;
	proto_send_heartbeat(c->pc, c->tiles_done, pending);
	wk_conn_settle(c);
}

static void on_linger_over(struct ev_loop *l, void *arg)
{
	(void)l;
	wk_conn_close(arg);
}
