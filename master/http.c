/*
 * http.c - the live view (http.h): a read-only HTTP/1.1 server on the farm's
 * event loop, one connection per request (Connection: close).
 *
 * A connection goes HC_REQ (reading the request line and headers, with a
 * deadline) -> HC_RESP (a whole response in its buffer) or HC_STREAM (the
 * event stream) -> HC_DRAIN (our side shut, the peer's leftovers read and
 * dropped so closing does not reset the response away) -> closed.
 *
 * Stream events (text/event-stream; data lines never hold a newline):
 *   info    {"w":W,"h":H,"tiles":N,"side":S,"scene":"NAME"}   first
 *   tile    "X Y W H BASE64"  the tile's pixels, RGB8 rows top to bottom
 *   undo    "X Y W H"         a tile taken back (its worker was caught lying)
 *   status  the /status object (progress, ETA, the farm table)
 *   end     the final status; the server then closes the stream
 */
#include "master/http.h"

#include <errno.h>
#include <poll.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "master/farm_int.h"
#include "proto/buf.h"

enum hstate { HC_FREE, HC_REQ, HC_RESP, HC_STREAM, HC_DRAIN };

/* seconds a finished connection's leftovers are read before it is closed */
#define HTTP_DRAIN_S 1.0

struct hconn {
	struct http *h;
	int fd;
	enum hstate st;
	double opened;          /* accepted at: the oldest request is evicted first */
	double progress_at;     /* when the peer last took bytes (the stall deadline) */
	struct ev_timer tm;     /* request deadline, stall, or drain */
	char *req;              /* HC_REQ: the request so far (HTTP_REQ_MAX bytes, owned) */
	size_t req_len;
	struct proto_wbuf out;  /* bytes to send, from out_off */
	size_t out_off;
	bool polling_out;       /* POLLOUT asked for: the socket was full */
	bool peer_eof;          /* the peer shut its side: no more reading */
	/* HC_STREAM: tiles to send (a bit each) and tiles the viewer shows */
	uint64_t *pending, *shown;
	uint32_t n_pending, cursor;
	bool end_queued;
};

struct http {
	struct farm *f;
	struct ev_loop *loop;
	int lfd;
	bool public;            /* --http-public: no Host check */
	int local_threads;
	struct hconn c[HTTP_CONN_MAX];
	uint32_t n_streams;
	struct ev_timer tick;   /* status events, while there are streams */
	bool ended, stopped;
	uint32_t n_tiles, words, bpp;
	uint8_t *px;            /* one tile's pixels as the scheduler keeps them */
	uint8_t *rgb;           /* ... as RGB8 */
	char *b64;              /* ... in base64 */
	struct proto_wbuf status; /* the latest status object */
	/* recent rates: tiles over the last second or so */
	double rate_t0;
	uint32_t *rate_n0;      /* per worker (f->cap_w), then the local threads */
	double *rate;
	char scene[256];        /* the scene's file name, JSON-escaped */
};

/* ---- status ---- */

static const char *worker_state(const struct http *h, const struct worker *w)
{
	if (w->dropped)
		return "dropped";
	if (h->ended)
		return w->tiles_done ? "finished" : "unused";
	switch (w->state) {
	case W_IDLE: return w->accepted ? "gone" : w->why[0] ? "waiting to reconnect" : "idle";
	case W_CONNECTING: return "connecting";
	case W_HELLO: return "hello";
	case W_AUTH: return "authenticating";
	case W_OFFER: return "offered the scene";
	case W_SENDING: return "receiving the scene";
	case W_BUILDING: return "building";
	case W_READY: return "tracing";
	case W_DONE: return "done";
	}
	return "?";
}

static void put_row(struct proto_wbuf *b, const char *name, uint32_t threads, uint32_t tiles, double rate,
		    const char *state, const char *problem)
{
	proto_put_u8(b, '{');
	http_put_str(b, "\"name\":");
	http_put_json_str(b, name);
	http_put_fmt(b, ",\"threads\":%u,\"tiles\":%u,\"rate\":%.2f,\"state\":", threads, tiles, rate);
	http_put_json_str(b, state);
	http_put_str(b, ",\"problem\":");
	http_put_json_str(b, problem);
	proto_put_u8(b, '}');
}

/* Rebuilds h->status: progress, ETA and the farm table. */
static void status_build(struct http *h)
{
	struct farm *f = h->f;
	struct sched_stats st;
	sched_stats(f->s, &st);
	double now = net_now(), el = now - f->t0;
	/* the rates: counted over a second or more */
	uint32_t nw = f->n_w;
	if (now - h->rate_t0 >= 1.0 || h->rate_t0 == 0) {
		double dt = now - h->rate_t0;
		for (uint32_t i = 0; i <= nw; i++) {
			uint32_t n = i < nw ? f->w[i].tiles_done : st.local_done;
			uint32_t k = i < nw ? i : f->cap_w;
			if (h->rate_t0 > 0)
				h->rate[k] = n >= h->rate_n0[k] ? (n - h->rate_n0[k]) / dt : 0;
			h->rate_n0[k] = n;
		}
		h->rate_t0 = now;
	}
	struct proto_wbuf *b = &h->status;
	b->len = 0;
	b->oom = 0;
	http_put_fmt(b, "{\"done\":%u,\"tiles\":%u,\"elapsed\":%.2f,\"eta\":", st.done, st.n, el);
	if (st.done > 0 && st.done < st.n && !h->ended)
		http_put_fmt(b, "%.1f", el * (st.n - st.done) / st.done);
	else
		http_put_str(b, st.done == st.n ? "0" : "null");
	http_put_fmt(b, ",\"ended\":%s,\"stopped\":%s,\"farmed\":%s,\"workers\":[", h->ended ? "true" : "false",
		h->stopped ? "true" : "false", f->farmed ? "true" : "false");
	const char *lstate = h->local_threads == 0 ? "off"
			     : atomic_load(&f->local_gave_up) ? "out of memory"
			     : h->ended			       ? "done"
			     : f->o->no_local		       ? "audits only"
							       : "tracing";
	put_row(b, "local", (uint32_t)h->local_threads, st.local_done, h->rate[f->cap_w], lstate, "");
	uint32_t rows = 0, more = 0;
	for (uint32_t i = 0; i < nw; i++) {
		const struct worker *w = &f->w[i];
		if (w->accepted && !w->spoke)
			continue; /* dialled in and said nothing valid (yet) */
		if (rows == HTTP_STATUS_ROWS) {
			more++;
			continue;
		}
		proto_put_u8(b, ',');
		put_row(b, w->name, w->threads, w->tiles_done, h->rate[i], worker_state(h, w), w->why);
		rows++;
	}
	http_put_fmt(b, "],\"more\":%u}", more);
}

/* ---- connections ---- */

static void conn_io(struct ev_loop *l, int fd, short revents, void *arg);

static void conn_close(struct hconn *c)
{
	struct http *h = c->h;
	if (c->st == HC_FREE)
		return;
	if (c->pending)
		h->n_streams--;
	ev_timer_stop(h->loop, &c->tm);
	ev_io_del(h->loop, c->fd);
	close(c->fd);
	free(c->req);
	free(c->pending);
	free(c->shown);
	proto_wbuf_free(&c->out);
	c->req = NULL;
	c->pending = c->shown = NULL;
	c->st = HC_FREE;
	c->fd = -1;
	if (h->n_streams == 0)
		ev_timer_stop(h->loop, &h->tick);
}

static void set_events(struct hconn *c)
{
	short ev = (c->peer_eof ? 0 : POLLIN) | (c->polling_out ? POLLOUT : 0);
	ev_io_events(c->h->loop, c->fd, ev);
}

/* Everything sent: shut our side and read the peer's leftovers a moment. */
static void start_drain(struct hconn *c)
{
	c->st = HC_DRAIN;
	shutdown(c->fd, SHUT_WR);
	if (c->peer_eof) {
		conn_close(c);
		return;
	}
	c->polling_out = false;
	set_events(c);
	ev_timer_arm(c->h->loop, &c->tm, net_now() + HTTP_DRAIN_S);
}

static void append_tile_event(struct http *h, struct hconn *c, uint32_t id, bool done)
{
	struct tile_rect r = sched_rect(h->f->s, id);
	uint32_t word = id / 64;
	uint64_t bit = (uint64_t)1 << (id % 64);
	if (!done) {
		if (c->shown[word] & bit) {
			http_put_fmt(&c->out, "event: undo\ndata: %u %u %u %u\n\n", r.x, r.y, r.w, r.h);
			c->shown[word] &= ~bit;
		}
		return;
	}
	http_to_rgb8(h->px, h->bpp, (size_t)r.w * r.h, h->rgb);
	size_t n = http_base64(h->rgb, (size_t)r.w * r.h * 3, h->b64);
	http_put_fmt(&c->out, "event: tile\ndata: %u %u %u %u ", r.x, r.y, r.w, r.h);
	proto_put_bytes(&c->out, h->b64, n);
	http_put_str(&c->out, "\n\n");
	c->shown[word] |= bit;
}

static void append_status_event(struct http *h, struct hconn *c, const char *name)
{
	http_put_fmt(&c->out, "event: %s\ndata: ", name);
	proto_put_bytes(&c->out, h->status.p, h->status.len);
	http_put_str(&c->out, "\n\n");
}

/* The next tile of c's set, from its cursor on (wrapping); the set is not empty. */
static uint32_t pending_next(struct hconn *c)
{
	uint32_t words = c->h->words, wi = c->cursor / 64;
	uint64_t m = c->pending[wi] & (~(uint64_t)0 << (c->cursor % 64));
	while (!m) {
		wi = wi + 1 == words ? 0 : wi + 1;
		m = c->pending[wi];
	}
	uint32_t id = wi * 64 + (uint32_t)__builtin_ctzll(m);
	c->pending[wi] &= ~((uint64_t)1 << (id % 64));
	c->n_pending--;
	c->cursor = id + 1 == c->h->n_tiles ? 0 : id + 1;
	return id;
}

/* Refills a stream's buffer from its tile set while it is below the low
 * water mark; the end event once the set is empty after the render. */
static void stream_fill(struct hconn *c)
{
	struct http *h = c->h;
	if (c->out_off > 0) {
		memmove(c->out.p, c->out.p + c->out_off, c->out.len - c->out_off);
		c->out.len -= c->out_off;
		c->out_off = 0;
	}
	while (c->out.len < HTTP_LOW_WATER && c->n_pending > 0) {
		uint32_t id = pending_next(c);
		append_tile_event(h, c, id, sched_tile_pixels(h->f->s, id, h->px));
	}
	if (c->n_pending == 0 && h->ended && !c->end_queued && c->out.len < HTTP_LOW_WATER) {
		append_status_event(h, c, "end");
		c->end_queued = true;
	}
}

static void stall_check(struct ev_loop *l, void *arg);

/*
 * Sends what c has (refilling a stream as it goes), at most HTTP_SEND_ROUND
 * bytes this round; asks for POLLOUT when the socket is full or the round is
 * used up. A response sent whole, or a stream whose end event left, drains.
 */
static void pump(struct hconn *c)
{
	size_t sent = 0;
	for (;;) {
		if (c->st == HC_STREAM)
			stream_fill(c);
		if (c->out.oom) {
			conn_close(c); /* out of memory: the viewer reconnects */
			return;
		}
		size_t left = c->out.len - c->out_off;
		if (left == 0)
			break;
		if (sent >= HTTP_SEND_ROUND) {
			c->polling_out = true;
			set_events(c);
			return;
		}
		ssize_t n = send(c->fd, c->out.p + c->out_off, left, MSG_NOSIGNAL | MSG_DONTWAIT);
		if (n < 0 && errno == EINTR)
			continue;
		if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
			c->polling_out = true;
			set_events(c);
			if (!ev_timer_armed(&c->tm)) {
				/* a stall starts: the peer has HTTP_STALL_S from now to take bytes */
				c->progress_at = net_now();
				ev_timer_arm(c->h->loop, &c->tm, c->progress_at + HTTP_STALL_S);
			}
			return;
		}
		if (n <= 0) {
			conn_close(c);
			return;
		}
		c->out_off += (size_t)n;
		sent += (size_t)n;
		c->progress_at = net_now();
	}
	c->out.len = c->out_off = 0;
	ev_timer_stop(c->h->loop, &c->tm);
	if (c->st == HC_RESP || (c->st == HC_STREAM && c->end_queued)) {
		start_drain(c);
		return;
	}
	c->polling_out = false;
	set_events(c);
}

/* A connection's timer: its request deadline, a stall, or the drain's end. */
static void stall_check(struct ev_loop *l, void *arg)
{
	struct hconn *c = arg;
	if ((c->st == HC_RESP || c->st == HC_STREAM) && c->out.len > c->out_off &&
	    net_now() - c->progress_at < HTTP_STALL_S) {
		ev_timer_arm(l, &c->tm, c->progress_at + HTTP_STALL_S);
		return;
	}
	if (c->st == HC_RESP || c->st == HC_STREAM) {
		if (c->out.len == c->out_off)
			return; /* nothing waiting: no stall */
	}
	conn_close(c);
}

/* ---- requests ---- */

static const char *reason(int code)
{
	switch (code) {
	case 200: return "OK";
	case 400: return "Bad Request";
	case 403: return "Forbidden";
	case 404: return "Not Found";
	case 405: return "Method Not Allowed";
	case 431: return "Request Header Fields Too Large";
	case 503: return "Service Unavailable";
	}
	return "Error";
}

/* The response head, into c->out (which must be empty). */
static void put_head(struct hconn *c, int code, const char *type, long length)
{
	struct proto_wbuf *b = &c->out;
	http_put_fmt(b, "HTTP/1.1 %d %s\r\nContent-Type: %s\r\n", code, reason(code), type);
	if (length >= 0)
		http_put_fmt(b, "Content-Length: %ld\r\n", length);
	http_put_str(b, "Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\nConnection: close\r\n");
	if (code == 405)
		http_put_str(b, "Allow: GET, HEAD\r\n");
	if (code == 503)
		http_put_str(b, "Retry-After: 5\r\n");
}

/* A whole response; body may be NULL (HEAD, or none). */
static void respond(struct hconn *c, int code, const char *type, const void *body, size_t len, bool head,
		    const char *extra)
{
	free(c->req);
	c->req = NULL;
	c->out.len = c->out_off = 0;
	put_head(c, code, type, body || !head ? (long)len : -1); /* HEAD of a stream: no length */
	if (extra)
		http_put_str(&c->out, extra);
	http_put_str(&c->out, "\r\n");
	if (body && !head)
		proto_put_bytes(&c->out, body, len);
	c->st = HC_RESP;
	c->progress_at = net_now();
	ev_timer_stop(c->h->loop, &c->tm);
	pump(c);
}

static void respond_error(struct hconn *c, int code)
{
	char body[96];
	int n = snprintf(body, sizeof body, "%d %s\n", code, reason(code));
	respond(c, code, "text/plain; charset=utf-8", body, (size_t)n, false, NULL);
}

static void start_stream(struct hconn *c, bool head)
{
	struct http *h = c->h;
	if (head) {
		respond(c, 200, "text/event-stream", NULL, 0, true, NULL);
		return;
	}
	if (h->n_streams >= HTTP_VIEWERS_MAX) {
		respond_error(c, 503);
		return;
	}
	c->pending = calloc(h->words, sizeof *c->pending);
	c->shown = calloc(h->words, sizeof *c->shown);
	if (!c->pending || !c->shown) {
		free(c->pending);
		free(c->shown);
		c->pending = c->shown = NULL;
		respond_error(c, 503);
		return;
	}
	h->n_streams++;
	/* every tile, done or not: the image so far comes first */
	for (uint32_t i = 0; i < h->n_tiles; i++)
		c->pending[i / 64] |= (uint64_t)1 << (i % 64);
	c->n_pending = h->n_tiles;
	c->cursor = 0;
	free(c->req);
	c->req = NULL;
	c->out.len = c->out_off = 0;
	put_head(c, 200, "text/event-stream", -1);
	http_put_str(&c->out, "X-Accel-Buffering: no\r\n\r\nretry: 2000\n\n");
	const struct farm *f = h->f;
	http_put_fmt(&c->out, "event: info\ndata: {\"w\":%u,\"h\":%u,\"tiles\":%u,\"side\":%u,\"scene\":%s}\n\n", f->width,
		f->height, h->n_tiles, f->tg.side, h->scene);
	status_build(h);
	append_status_event(h, c, "status");
	c->st = HC_STREAM;
	c->progress_at = net_now();
	ev_timer_stop(h->loop, &c->tm);
	if (!h->ended && !ev_timer_armed(&h->tick))
		ev_timer_arm(h->loop, &h->tick, net_now() + HTTP_STATUS_S);
	pump(c);
}

/* The request in c->req[0..end) is whole (end: past its blank line): answers it. */
static void handle_request(struct hconn *c, size_t end)
{
	struct http_request rq;
	int code = http_parse(c->req, end, c->h->public, &rq);
	if (code != 200) {
		respond_error(c, code);
		return;
	}
	switch (rq.target) {
	case HTTP_PAGE:
		respond(c, 200, "text/html; charset=utf-8", view_page, view_page_len, rq.head,
			"Content-Security-Policy: default-src 'none'; script-src 'unsafe-inline'; "
			"style-src 'unsafe-inline'; connect-src 'self'; img-src data:; frame-ancestors 'none'\r\n"
			"Referrer-Policy: no-referrer\r\n");
		break;
	case HTTP_EVENTS:
		start_stream(c, rq.head);
		break;
	case HTTP_STATUS: {
		status_build(c->h);
		struct proto_wbuf *s = &c->h->status;
		respond(c, s->oom ? 503 : 200, "application/json", s->p, s->len, rq.head, NULL);
		break;
	}
	}
}

/* Where the request's head ends (past its blank line), or 0 when not yet. */
static size_t head_end(const char *r, size_t n)
{
	for (size_t i = 1; i < n; i++) {
		if (r[i] != '\n')
			continue;
		if (r[i - 1] == '\n')
			return i + 1;
		if (i >= 2 && r[i - 1] == '\r' && r[i - 2] == '\n')
			return i + 1;
	}
	return 0;
}

static void read_request(struct hconn *c)
{
	size_t was = c->req_len;
	ssize_t n = recv(c->fd, c->req + c->req_len, HTTP_REQ_MAX - c->req_len, MSG_DONTWAIT);
	if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR))
		return;
	if (n <= 0) {
		conn_close(c); /* gone before asking anything */
		return;
	}
	c->req_len += (size_t)n;
	for (size_t i = was; i < c->req_len; i++) {
		unsigned char ch = (unsigned char)c->req[i];
		if ((ch < 0x20 && ch != '\r' && ch != '\n' && ch != '\t') || ch == 0x7f) {
			respond_error(c, 400); /* not text: not HTTP */
			return;
		}
	}
	/* skip leading blank lines when looking for the blank line that ends it */
	size_t skip = 0;
	while (skip < c->req_len && (c->req[skip] == '\r' || c->req[skip] == '\n'))
		skip++;
	size_t end = skip < c->req_len ? head_end(c->req + skip, c->req_len - skip) : 0;
	if (end)
		handle_request(c, skip + end);
	else if (c->req_len == HTTP_REQ_MAX)
		respond_error(c, 431);
}

static void conn_io(struct ev_loop *l, int fd, short revents, void *arg)
{
	(void)l;
	(void)fd;
	struct hconn *c = arg;
	if (c->st == HC_REQ) {
		if (revents & (POLLIN | POLLHUP | POLLERR))
			read_request(c);
		return;
	}
	if ((revents & POLLERR) || ((revents & POLLHUP) && !(revents & POLLIN))) {
		conn_close(c);
		return;
	}
	if ((revents & POLLIN) && !c->peer_eof) {
		/* nothing more is asked for: read and drop (bounded per round) */
		char sink[4096];
		ssize_t n = recv(c->fd, sink, sizeof sink, MSG_DONTWAIT);
		if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
			c->peer_eof = true;
			/* a viewer that shuts its side is gone (EventSource never
			 * half-closes); a response may still be read after it */
			if (c->st != HC_RESP || n < 0) {
				conn_close(c);
				return;
			}
			set_events(c);
		}
	}
	if (c->st != HC_DRAIN && (revents & POLLOUT))
		pump(c);
}

/* A slot for a new connection: a free one, or the oldest still sending its
 * request (evicted); NULL when every slot is answering or streaming. */
static struct hconn *conn_slot(struct http *h)
{
	struct hconn *old = NULL;
	for (int i = 0; i < HTTP_CONN_MAX; i++) {
		struct hconn *c = &h->c[i];
		if (c->st == HC_FREE)
			return c;
		if ((c->st == HC_REQ || c->st == HC_DRAIN) && (!old || c->opened < old->opened))
			old = c;
	}
	if (old)
		conn_close(old);
	return old;
}

static void on_accept(struct ev_loop *l, int lfd, short revents, void *arg)
{
	(void)revents;
	struct http *h = arg;
	for (int k = 0; k < 16; k++) {
		char peer[96];
		int fd = net_accept(lfd, peer, sizeof peer);
		if (fd < 0)
			return;
		struct hconn *c = conn_slot(h);
		if (!c) {
			static const char busy[] = "HTTP/1.1 503 Service Unavailable\r\nContent-Length: 0\r\n"
						   "Connection: close\r\nRetry-After: 5\r\n\r\n";
			ssize_t n = send(fd, busy, sizeof busy - 1, MSG_NOSIGNAL | MSG_DONTWAIT);
			(void)n;
			close(fd);
			continue;
		}
		*c = (struct hconn){ .h = h, .fd = fd, .st = HC_REQ, .opened = net_now() };
		c->progress_at = c->opened;
		ev_timer_init(&c->tm, stall_check, c);
		c->req = malloc(HTTP_REQ_MAX);
		if (!c->req || ev_io_set(l, fd, POLLIN, conn_io, c) < 0) {
			free(c->req);
			c->req = NULL;
			close(fd);
			c->st = HC_FREE;
			continue;
		}
		ev_timer_arm(l, &c->tm, c->opened + HTTP_HEADER_S);
	}
}

/* ---- the observer and the status tick ---- */

static void on_tiles(void *arg, struct farm *f, const uint32_t *ids, uint32_t n)
{
	(void)f;
	struct http *h = arg;
	for (int i = 0; i < HTTP_CONN_MAX; i++) {
		struct hconn *c = &h->c[i];
		if (c->st != HC_STREAM)
			continue;
		for (uint32_t k = 0; k < n; k++) {
			uint64_t bit = (uint64_t)1 << (ids[k] % 64);
			if (!(c->pending[ids[k] / 64] & bit)) {
				c->pending[ids[k] / 64] |= bit;
				c->n_pending++;
			}
		}
		if (!c->polling_out)
			pump(c);
	}
}

static void on_tick(struct ev_loop *l, void *arg)
{
	struct http *h = arg;
	if (h->n_streams == 0 || h->ended)
		return;
	status_build(h);
	for (int i = 0; i < HTTP_CONN_MAX; i++) {
		struct hconn *c = &h->c[i];
		if (c->st != HC_STREAM || c->out.len - c->out_off >= HTTP_LOW_WATER)
			continue; /* a viewer behind skips a status: the next one says it all */
		append_status_event(h, c, "status");
		if (!c->polling_out)
			pump(c);
	}
	ev_timer_arm(l, &h->tick, net_now() + HTTP_STATUS_S);
}

/* ---- the server ---- */

static void stop_listening(struct http *h)
{
	if (h->lfd < 0)
		return;
	ev_io_del(h->loop, h->lfd);
	close(h->lfd);
	h->lfd = -1;
}

int http_start(struct farm *f, int local_threads, struct http **out)
{
	const struct master_opts *o = f->o;
	char host[NET_HOST_LEN], port[NET_PORT_LEN], err[300];
	*out = NULL;
	if (net_parse_hostport(o->http, host, port, err, sizeof err) < 0) {
		fprintf(stderr, "portray-master: --http: %s\n", err);
		return -1;
	}
	uint32_t bpp = sched_bpp(f->s);
	if (bpp != 3 && bpp != 12) {
		fprintf(stderr, "portray-master: --http: cannot show pixels of %u bytes\n", bpp);
		return -1;
	}
	struct http *h = calloc(1, sizeof *h);
	if (!h)
		goto oom;
	h->f = f;
	h->loop = f->loop;
	h->lfd = -1;
	h->public = o->http_public;
	h->local_threads = local_threads;
	h->bpp = bpp;
	h->n_tiles = f->tg.n;
	h->words = (f->tg.n + 63) / 64;
	for (int i = 0; i < HTTP_CONN_MAX; i++)
		h->c[i] = (struct hconn){ .h = h, .fd = -1 };
	ev_timer_init(&h->tick, on_tick, h);
	size_t side = f->tg.side, px = side * side;
	h->px = malloc(px * bpp);
	h->rgb = malloc(px * 3);
	h->b64 = malloc((px * 3 + 2) / 3 * 4);
	h->rate_n0 = calloc(f->cap_w + 1, sizeof *h->rate_n0);
	h->rate = calloc(f->cap_w + 1, sizeof *h->rate);
	if (!h->px || !h->rgb || !h->b64 || !h->rate_n0 || !h->rate)
		goto oom;
	const char *base = strrchr(o->scene, '/');
	struct proto_wbuf sb = { 0 };
	http_put_json_str(&sb, base ? base + 1 : o->scene);
	snprintf(h->scene, sizeof h->scene, "%.*s", (int)sb.len, sb.oom ? "\"\"" : (const char *)sb.p);
	if (sb.oom || sb.len >= sizeof h->scene)
		snprintf(h->scene, sizeof h->scene, "\"scene\"");
	proto_wbuf_free(&sb);
	h->lfd = net_listen(host, port, err, sizeof err);
	if (h->lfd < 0) {
		fprintf(stderr, "portray-master: --http: %s\n", err);
		http_free(h);
		return -1;
	}
	int bound = net_local_port(h->lfd);
	if (o->http_port_file && net_write_number(o->http_port_file, bound) < 0) {
		fprintf(stderr, "portray-master: cannot write %s: %s\n", o->http_port_file, strerror(errno));
		http_free(h);
		return -1;
	}
	/* the observer last: nothing may fail after it (it would outlive h) */
	if (ev_io_set(h->loop, h->lfd, POLLIN, on_accept, h) < 0 ||
	    farm_observe(f, &(struct farm_observer){ on_tiles, h }) < 0)
		goto oom;
	if (!o->quiet)
		farm_log(f, strchr(host, ':') ? "live view on http://[%s]:%d/" : "live view on http://%s:%d/", host,
			 bound);
	*out = h;
	return 0;
oom:
	fprintf(stderr, "portray-master: out of memory for the live view\n");
	http_free(h);
	return -1;
}

/* the one process-wide figure: a master renders once */
static double lingered_s;

double http_lingered(void) { return lingered_s; }

void http_finish(struct http *h)
{
	if (!h)
		return;
	struct farm *f = h->f;
	h->ended = true;
	h->stopped = atomic_load(f->cancel) || !sched_finished(f->s);
	ev_timer_stop(h->loop, &h->tick);
	status_build(h);
	double linger = h->stopped ? 0 : f->o->http_linger;
	double t0 = net_now(), until = t0 + (linger > 0 ? linger : HTTP_FLUSH_S);
	if (linger > 0 && !f->o->quiet)
		farm_log(f, "live view: serving the finished image for %.0f s more (q or Ctrl-C ends it)", linger);
	if (linger <= 0) {
		/* nobody new; requests already here are read (one round), those
		 * not yet whole will not be answered */
		stop_listening(h);
		ev_run_once(h->loop, 0);
		for (int i = 0; i < HTTP_CONN_MAX; i++)
			if (h->c[i].st == HC_REQ)
				conn_close(&h->c[i]);
	}
	for (int i = 0; i < HTTP_CONN_MAX; i++)
		if (h->c[i].st == HC_STREAM && !h->c[i].polling_out)
			pump(&h->c[i]);
	for (;;) {
		bool busy = false; /* something left to send (draining ones are not waited for) */
		for (int i = 0; i < HTTP_CONN_MAX && !busy; i++)
			busy = h->c[i].st == HC_RESP || h->c[i].st == HC_STREAM;
		double left = until - net_now();
		if ((linger <= 0 && !busy) || left <= 0)
			break;
		if (linger > 0 && atomic_load(f->cancel))
			break;
		if (ev_run_once(h->loop, left) < 0 && errno != EINTR)
			break;
	}
	if (linger > 0)
		lingered_s = net_now() - t0;
}

void http_free(struct http *h)
{
	if (!h)
		return;
	for (int i = 0; i < HTTP_CONN_MAX; i++)
		conn_close(&h->c[i]);
	stop_listening(h);
	ev_timer_stop(h->loop, &h->tick);
	proto_wbuf_free(&h->status);
	free(h->px);
	free(h->rgb);
	free(h->b64);
	free(h->rate_n0);
	free(h->rate);
	free(h);
}
