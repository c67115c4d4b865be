/*
 * test_http.c - the live view's request parser (master/http_parse.c, http_parse):
 * what each request line and header set is answered with, the Host check
 * against DNS rebinding, and that no prefix of a good request (a head cut
 * anywhere, as a slow peer's bytes arrive) is taken for a request; and the
 * pixels shown (http_to_rgb8): RGB8 as it is, floats rounded as an 8-bit
 * file rounds them; and base64 (http_base64) against RFC 4648's vectors.
 */
#include <string.h>

#include "check.h"
#include "common/filter.h"
#include "master/http.h"
#include "proto/buf.h"

static int parse(const char *req, bool any_host, struct http_request *rq)
{
	return http_parse(req, strlen(req), any_host, rq);
}

static int code(const char *req) { struct http_request rq; return parse(req, false, &rq); }

/* RFC 4648, section 10: BASE64("") .. BASE64("foobar") */
static void test_base64(void)
{
	static const char *want[] = { "", "Zg==", "Zm8=", "Zm9v", "Zm9vYg==", "Zm9vYmE=", "Zm9vYmFy" };
	char out[16];
	for (size_t n = 0; n <= 6; n++) {
		size_t m = http_base64((const uint8_t *)"foobar", n, out);
		CHECK(m == strlen(want[n]) && memcmp(out, want[n], m) == 0);
	}
	const uint8_t hi[3] = { 0xff, 0xfe, 0xfd }; /* the table's last letters */
	CHECK(http_base64(hi, 3, out) == 4 && memcmp(out, "//79", 4) == 0);
}

/* A JSON string for /status: quotes, backslashes, control bytes and bytes
 * past ASCII escaped, the rest as it is. */
static void test_json_str(void)
{
	struct proto_wbuf b = { 0 };
	http_put_json_str(&b, "a\"b\\c\n\xc3\xa9~");
	const char *want = "\"a\\\"b\\\\c\\u000a\\u00c3\\u00a9~\"";
	CHECK(b.len == strlen(want) && memcmp(b.p, want, b.len) == 0);
	proto_wbuf_free(&b);
}

int main(void)
{
	struct http_request rq;

	test_base64();
	test_json_str();

	/* the three paths, GET and HEAD, queries ignored */
	CHECK(parse("GET / HTTP/1.1\r\nHost: 127.0.0.1:8080\r\n\r\n", false, &rq) == 200);
	CHECK(rq.target == HTTP_PAGE && !rq.head);
	CHECK(parse("GET /index.html?x=1 HTTP/1.0\r\n\r\n", false, &rq) == 200 && rq.target == HTTP_PAGE);
	CHECK(parse("GET /events HTTP/1.1\r\nHost: localhost:1\r\nAccept: text/event-stream\r\n\r\n", false, &rq) ==
	      200);
	CHECK(rq.target == HTTP_EVENTS);
	CHECK(parse("HEAD /status HTTP/1.1\r\nHost: [::1]:80\r\n\r\n", false, &rq) == 200);
	CHECK(rq.target == HTTP_STATUS && rq.head);
	/* bare LF line ends, blank lines before the request */
	CHECK(parse("\r\n\nGET /status HTTP/1.1\nHost: 127.1.2.3\n\n", false, &rq) == 200 && rq.target == HTTP_STATUS);

	/* 404: other paths */
	CHECK(code("GET /favicon.ico HTTP/1.1\r\n\r\n") == 404);
	CHECK(code("GET /../../etc/passwd HTTP/1.1\r\n\r\n") == 404);
	CHECK(code("GET /events/ HTTP/1.1\r\n\r\n") == 404);
	CHECK(code("GET //status HTTP/1.1\r\n\r\n") == 404);

	/* 405: read-only */
	CHECK(code("POST / HTTP/1.1\r\nContent-Length: 0\r\n\r\n") == 405);
	CHECK(code("DELETE /events HTTP/1.1\r\n\r\n") == 405);
	CHECK(code("get / HTTP/1.1\r\n\r\n") == 405); /* methods are case-sensitive */
	CHECK(code("OPTIONS /nope HTTP/1.1\r\n\r\n") == 405);

	/* 400: malformed */
	CHECK(code("GET\r\n\r\n") == 400);
	CHECK(code("GET / \r\n\r\n") == 400);
	CHECK(code("GET / HTTP/2.0\r\n\r\n") == 400);
	CHECK(code("GET / HTTP/1.10\r\n\r\n") == 400);
	CHECK(code("GET / http/1.1\r\n\r\n") == 400);
	CHECK(code("GET nope HTTP/1.1\r\n\r\n") == 400);
	CHECK(code("GET  / HTTP/1.1\r\n\r\n") == 400);
	CHECK(code(" GET / HTTP/1.1\r\n\r\n") == 400);
	CHECK(code("G(T / HTTP/1.1\r\n\r\n") == 400);
	CHECK(code("AVERYLONGMETHODNAME / HTTP/1.1\r\n\r\n") == 400);
	CHECK(code("GET / HTTP/1.1\r\nno colon\r\n\r\n") == 400);
	CHECK(code("GET / HTTP/1.1\r\n: no name\r\n\r\n") == 400);
	CHECK(code("GET / HTTP/1.1\r\nBad Name: x\r\n\r\n") == 400);
	CHECK(code("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nHost: 127.0.0.1\r\n\r\n") == 400);
	{
		static char big[3000];
		memcpy(big, "GET /", 5);
		memset(big + 5, 'x', 2100);
		strcpy(big + 2105, " HTTP/1.1\r\n\r\n");
		CHECK(code(big) == 400); /* a target over HTTP_TARGET_MAX */
	}

	/* 403: a Host that is not loopback (a rebound name), unless --http-public */
	CHECK(code("GET / HTTP/1.1\r\nHost: evil.example.com\r\n\r\n") == 403);
	CHECK(code("GET / HTTP/1.1\r\nHost: evil.example.com:8080\r\n\r\n") == 403);
	CHECK(code("GET / HTTP/1.1\r\nHost: 127.0.0.1.evil.com\r\n\r\n") == 403);
	CHECK(code("GET / HTTP/1.1\r\nHost: localhost.evil.com\r\n\r\n") == 403);
	CHECK(code("GET / HTTP/1.1\r\nHost: 127.0.0.1:80x\r\n\r\n") == 403);
	CHECK(code("GET / HTTP/1.1\r\nHost: 127.0.0.1:\r\n\r\n") == 403);
	CHECK(code("GET / HTTP/1.1\r\nHost:\r\n\r\n") == 403);
	CHECK(code("GET / HTTP/1.1\r\nhost:   LOCALHOST  \r\n\r\n") == 200);
	CHECK(parse("GET / HTTP/1.1\r\nHost: evil.example.com\r\n\r\n", true, &rq) == 200);

	/* every cut of a good request before its blank line is not a request */
	const char *good = "GET /events HTTP/1.1\r\nHost: 127.0.0.1:1\r\nAccept: */*\r\n\r\n";
	size_t n = strlen(good);
	int taken = 0;
	for (size_t k = 0; k + 2 < n; k++)
		taken += http_parse(good, k, false, &rq) == 200;
	CHECK(taken == 0);
	CHECK(http_parse(good, n, false, &rq) == 200 && rq.target == HTTP_EVENTS);

	/* pixels: RGB8 copied; floats (out of range, on the rounding edges) as filter_quantise */
	uint8_t rgb8[6] = { 0, 1, 127, 128, 254, 255 }, out[12];
	http_to_rgb8(rgb8, 3, 2, out);
	CHECK(memcmp(out, rgb8, 6) == 0);
	static const float fv[12] = { -1.0f, 0.0f, 1.0f, 2.5f, 0.5f / 255, 0.499f / 255, 0.5f, 1.0f - 0.5f / 255,
				      1e30f, 0.25f, 0.75f, 100.0f / 255 };
	uint8_t fpx[sizeof fv];
	memcpy(fpx, fv, sizeof fv);
	http_to_rgb8(fpx, 12, 4, out);
	for (int i = 0; i < 4; i++) {
		uint8_t want[3];
		filter_quantise((vec3){ fv[3 * i], fv[3 * i + 1], fv[3 * i + 2] }, want);
		CHECK(memcmp(out + 3 * i, want, 3) == 0);
	}
	CHECK(out[0] == 0 && out[2] == 255 && out[3] == 255 && out[6] == 128 && out[11] == 100);

	TEST_MAIN_END();
}
