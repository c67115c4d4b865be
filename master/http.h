/*
 * http.h - the live view (--http ADDR:PORT): a small read-only HTTP server
 * on the farm's event loop that serves one self-contained page (master/
 * view_page.c) and a Server-Sent Events stream of the render's tiles and
 * status (docs/live-view.md).
 *
 *   GET /        the page (HTML, CSS and JavaScript inline, no other asset)
 *   GET /events  text/event-stream: info, tile, undo, status, end
 *   GET /status  the status as one JSON object
 *
 * Viewers never slow the render: the server runs in the loop's thread on
 * non-blocking sockets and never waits for a viewer. Each viewer has a set
 * of tiles it still has to be sent (the image so far when it connects, then
 * every tile stored or undone since) and an output buffer that is refilled
 * from that set only when it runs low: a slow viewer's tiles coalesce in the
 * set (it later gets their pixels as they are then), its buffer never grows
 * past one low-water mark plus one event, and a viewer that takes nothing
 * for HTTP_STALL_S is disconnected (EventSource reconnects and starts over).
 */
#ifndef PORTRAY_HTTP_H
#define PORTRAY_HTTP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

struct farm;
struct http;

/* connections at once (requests being read, responses being written,
 * streams): beyond it the oldest connection still sending its request is
 * evicted for the newcomer, or the newcomer gets 503 */
#define HTTP_CONN_MAX 64
/* streams at once (viewers): beyond, 503 */
#define HTTP_VIEWERS_MAX 16
/* a request line and headers: more is 431 */
#define HTTP_REQ_MAX 8192
/* seconds a connection may take to send its request (slow-loris) */
#define HTTP_HEADER_S 10.0
/* seconds a response or stream may sit with bytes to send and none taken */
#define HTTP_STALL_S 30.0
/* a viewer's output buffer is refilled from its tile set below this many bytes */
#define HTTP_LOW_WATER (64u * 1024)
/* bytes sent to one connection per loop round at most (fairness: a fast
 * viewer's catch-up never holds the loop) */
#define HTTP_SEND_ROUND (256u * 1024)
/* seconds between status events */
#define HTTP_STATUS_S 0.5
/* seconds after a render (without --http-linger) to flush the viewers' last
 * tiles and their end event */
#define HTTP_FLUSH_S 2.0
/* workers listed in a status at most (the rest are counted) */
#define HTTP_STATUS_ROWS 64

/*
 * Starts the live view of f on f->o->http (already checked by main: its
 * address, loopback or --http-public): listens, writes --http-port-file,
 * says where on stderr (unless -q) and registers an observer of the tiles.
 * local_threads: the master's own tracing threads (for the farm table).
 * Call before the loop runs. 0 with *out (free with http_free), or -1 after
 * printing why.
 */
int http_start(struct farm *f, int local_threads, struct http **out);
/*
 * The render is over (finished or stopped; the observers had their last
 * tiles): sends every viewer what it is missing and an end event, serving
 * on for --http-linger seconds (not after a stop; q, Esc or Ctrl-C end the
 * linger) or, without it, at most HTTP_FLUSH_S for the viewers to take
 * their last bytes. Runs the loop; NULL is a no-op.
 */
void http_finish(struct http *h);
/* Seconds this process spent in http_finish's --http-linger (render.c
 * leaves them out of the render time). */
double http_lingered(void);
/* Closes every connection and the listening socket; NULL is a no-op. */
void http_free(struct http *h);

/* What a request asks for (http_parse). */
enum http_target { HTTP_PAGE, HTTP_EVENTS, HTTP_STATUS };
struct http_request {
	enum http_target target;
	bool head;              /* HEAD: the head alone */
};
/*
 * Parses a request's head, req[0..len) up to and with its blank line (bytes
 * already checked to be text). Returns 200 with *rq, or the error to answer:
 * 400 (malformed request line or header, a second Host), 405 (a method but
 * GET and HEAD), 403 (a Host that is not a loopback name, unless any_host),
 * 404 (another path).
 */
int http_parse(const char *req, size_t len, bool any_host, struct http_request *rq);

/*
 * n_px pixels as the scheduler keeps them (sched_bpp bytes each) to RGB8 for
 * the page: 3 bytes are RGB8 already; 12 are 3 floats (the float pipeline),
 * rounded as filter_quantise rounds them for an 8-bit file.
 */
void http_to_rgb8(const uint8_t *px, uint32_t bpp, size_t n_px, uint8_t *rgb);

/* The responses' text: s as it is; printf's output (at most 511 bytes); s
 * as a JSON string (quotes, backslashes, control bytes and bytes past ASCII
 * escaped: a name from a workers file or a peer need not be UTF-8). */
struct proto_wbuf;
void http_put_str(struct proto_wbuf *b, const char *s);
void http_put_fmt(struct proto_wbuf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void http_put_json_str(struct proto_wbuf *b, const char *s);

/* Base64 (RFC 4648, padded) of in[0..n) into out (4 * ((n + 2) / 3) bytes,
 * no terminator); returns the length written. */
size_t http_base64(const uint8_t *in, size_t n, char *out);

/* master/view_page.c: the page */
extern const char view_page[];
extern const size_t view_page_len;

#endif
