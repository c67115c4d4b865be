/*
 * http_parse.c - the live view's parts that touch no socket (http.h):
 * parsing a request's head, the text and JSON writers of its responses,
 * base64 for the tile events, and the pixels shown. Small and pure, so
 * test_http drives them alone.
 */
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "common/filter.h"
#include "master/http.h"
#include "proto/buf.h"

/* a request target longer than this is refused (400) */
#define HTTP_TARGET_MAX 2048

void http_put_str(struct proto_wbuf *b, const char *s) { proto_put_bytes(b, s, strlen(s)); }

void http_put_fmt(struct proto_wbuf *b, const char *fmt, ...)
{
	char tmp[512];
	va_list ap;
	va_start(ap, fmt);
	int n = vsnprintf(tmp, sizeof tmp, fmt, ap);
	va_end(ap);
	if (n > 0)
		proto_put_bytes(b, tmp, (size_t)n < sizeof tmp ? (size_t)n : sizeof tmp - 1);
}

/* A JSON string: quotes, backslashes, control bytes and bytes past ASCII
 * escaped (a name from a workers file or a peer need not be UTF-8). */
void http_put_json_str(struct proto_wbuf *b, const char *s)
{
	proto_put_u8(b, '"');
	for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
		if (*p == '"' || *p == '\\') {
			proto_put_u8(b, '\\');
			proto_put_u8(b, *p);
		} else if (*p < 0x20 || *p >= 0x7f) {
			http_put_fmt(b, "\\u%04x", *p);
		} else {
			proto_put_u8(b, *p);
		}
	}
	proto_put_u8(b, '"');
}

size_t http_base64(const uint8_t *in, size_t n, char *out)
{
	static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
	size_t o = 0, i = 0;
	for (; i + 3 <= n; i += 3) {
		uint32_t v = (uint32_t)in[i] << 16 | (uint32_t)in[i + 1] << 8 | in[i + 2];
		out[o++] = tab[v >> 18];
		out[o++] = tab[(v >> 12) & 63];
		out[o++] = tab[(v >> 6) & 63];
		out[o++] = tab[v & 63];
	}
	if (i < n) {
		uint32_t v = (uint32_t)in[i] << 16 | (i + 1 < n ? (uint32_t)in[i + 1] << 8 : 0);
		out[o++] = tab[v >> 18];
		out[o++] = tab[(v >> 12) & 63];
		out[o++] = i + 1 < n ? tab[(v >> 6) & 63] : '=';
		out[o++] = '=';
	}
	return o;
}

void http_to_rgb8(const uint8_t *px, uint32_t bpp, size_t n_px, uint8_t *rgb)
{
	if (bpp == 3) {
		memcpy(rgb, px, n_px * 3);
		return;
	}
	for (size_t i = 0; i < n_px; i++) {
		float v[3];
		memcpy(v, px + i * 12, sizeof v);
		filter_quantise((vec3){ v[0], v[1], v[2] }, rgb + i * 3);
	}
}

static bool is_tchar(char ch)
{
	return (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') ||
	       (ch && strchr("!#$%&'*+-.^_`|~", ch));
}

/* A Host header that names a loopback address (a page elsewhere cannot
 * reach a loopback view by rebinding a name of its own to 127.0.0.1). */
static bool host_is_loopback(const char *v, size_t n)
{
	while (n && (v[n - 1] == ' ' || v[n - 1] == '\t'))
		n--;
	size_t k;
	if (n >= 9 && strncasecmp(v, "localhost", 9) == 0)
		k = 9;
	else if (n >= 5 && memcmp(v, "[::1]", 5) == 0)
		k = 5;
	else if (n >= 4 && memcmp(v, "127.", 4) == 0)
		for (k = 4; k < n && ((v[k] >= '0' && v[k] <= '9') || v[k] == '.'); k++)
			;
	else
		return false;
	if (k == n)
		return true;
	if (v[k] != ':' || k + 1 == n)
		return false;
	for (k++; k < n; k++)
		if (v[k] < '0' || v[k] > '9')
			return false;
	return true;
}

int http_parse(const char *req, size_t len, bool any_host, struct http_request *rq)
{
	const char *p = req, *stop = req + len;
	while (p < stop && (*p == '\r' || *p == '\n'))
		p++; /* blank lines before a request are allowed */
	const char *eol = memchr(p, '\n', (size_t)(stop - p));
	if (!eol)
		return 400;
	/* request-line = method SP target SP HTTP-version CRLF */
	const char *m = p, *sp1 = memchr(m, ' ', (size_t)(eol - m));
	if (!sp1 || sp1 == m || sp1 - m > 16)
		return 400;
	for (const char *q = m; q < sp1; q++)
		if (!is_tchar(*q))
			return 400;
	const char *t = sp1 + 1, *sp2 = memchr(t, ' ', (size_t)(eol - t));
	if (!sp2 || *t != '/' || sp2 - t > HTTP_TARGET_MAX)
		return 400;
	const char *v = sp2 + 1, *ve = eol > v && eol[-1] == '\r' ? eol - 1 : eol;
	if (ve - v != 8 || memcmp(v, "HTTP/1.", 7) != 0 || v[7] < '0' || v[7] > '9')
		return 400;
	/* header-field = name ":" OWS value OWS CRLF, up to the blank line */
	bool host_ok = any_host, blank = false;
	int n_host = 0;
	for (const char *line = eol + 1; line < stop && !blank;) {
		const char *le = memchr(line, '\n', (size_t)(stop - line));
		if (!le)
			return 400; /* no blank line: not a whole head */
		const char *e = le > line && le[-1] == '\r' ? le - 1 : le;
		blank = e == line;
		if (blank)
			break; /* the end of the head */
		const char *colon = memchr(line, ':', (size_t)(e - line));
		if (!colon || colon == line)
			return 400;
		for (const char *q = line; q < colon; q++)
			if (!is_tchar(*q))
				return 400;
		if (colon - line == 4 && strncasecmp(line, "host", 4) == 0) {
			const char *hv = colon + 1;
			while (hv < e && (*hv == ' ' || *hv == '\t'))
				hv++;
			n_host++;
			host_ok |= host_is_loopback(hv, (size_t)(e - hv));
		}
		line = le + 1;
	}
	if (!blank || n_host > 1)
		return 400;
	if (n_host == 0)
		host_ok = true; /* HTTP/1.0 without Host: not a browser's request */
	bool get = sp1 - m == 3 && memcmp(m, "GET", 3) == 0, head = sp1 - m == 4 && memcmp(m, "HEAD", 4) == 0;
	if (!get && !head)
		return 405;
	if (!host_ok)
		return 403;
	size_t tl = (size_t)(sp2 - t);
	const char *qm = memchr(t, '?', tl);
	if (qm)
		tl = (size_t)(qm - t);
	rq->head = head;
#define IS(path) (tl == strlen(path) && memcmp(t, path, tl) == 0)
	if (IS("/") || IS("/index.html"))
		rq->target = HTTP_PAGE;
	else if (IS("/events"))
		rq->target = HTTP_EVENTS;
	else if (IS("/status"))
		rq->target = HTTP_STATUS;
	else
		return 404;
#undef IS
	return 200;
}
