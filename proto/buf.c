/*
 * buf.c - big-endian writer and bounds-checked reader (see buf.h).
 */
#include "proto/buf.h"

#include <stdlib.h>
#include <string.h>

void proto_wbuf_free(struct proto_wbuf *b)
{
	free(b->p);
	memset(b, 0, sizeof *b);
}

int proto_wbuf_reserve(struct proto_wbuf *b, size_t n)
{
	if (b->oom)
		return -1;
	if (n <= b->cap - b->len)
		return 0;
	size_t nc = b->cap ? b->cap : 256;
	while (nc - b->len < n) {
		if (nc > SIZE_MAX / 2) {
			b->oom = 1;
			return -1;
		}
		nc *= 2;
	}
	uint8_t *p = realloc(b->p, nc);
	if (!p) {
		b->oom = 1;
		return -1;
	}
	b->p = p;
	b->cap = nc;
	return 0;
}

void proto_put_bytes(struct proto_wbuf *b, const void *p, size_t n)
{
	if (n == 0 || proto_wbuf_reserve(b, n) < 0)
		return;
	memcpy(b->p + b->len, p, n);
	b->len += n;
}

void proto_put_u8(struct proto_wbuf *b, uint8_t v) { proto_put_bytes(b, &v, 1); }

void proto_put_u16(struct proto_wbuf *b, uint16_t v)
{
	uint8_t t[2];
	proto_wr16(t, v);
	proto_put_bytes(b, t, 2);
}

void proto_put_u32(struct proto_wbuf *b, uint32_t v)
{
	uint8_t t[4];
	proto_wr32(t, v);
	proto_put_bytes(b, t, 4);
}

void proto_put_u64(struct proto_wbuf *b, uint64_t v)
{
	proto_put_u32(b, (uint32_t)(v >> 32));
	proto_put_u32(b, (uint32_t)v);
}

void proto_put_f64(struct proto_wbuf *b, double v)
{
	uint64_t u;
	memcpy(&u, &v, sizeof u);
	proto_put_u64(b, u);
}

void proto_put_str(struct proto_wbuf *b, const char *s)
{
	size_t n = s ? strlen(s) : 0;
	proto_put_u32(b, (uint32_t)n);
	proto_put_bytes(b, s, n);
}

const uint8_t *proto_get_span(struct proto_rbuf *r, size_t n)
{
	if (r->err || n > r->len - r->pos) {
		r->err = 1;
		return NULL;
	}
	const uint8_t *p = r->p + r->pos;
	r->pos += n;
	return p;
}

void proto_get_bytes(struct proto_rbuf *r, void *out, size_t n)
{
	const uint8_t *p = proto_get_span(r, n);
	if (p)
		memcpy(out, p, n);
	else
		memset(out, 0, n);
}

uint8_t proto_get_u8(struct proto_rbuf *r)
{
	const uint8_t *p = proto_get_span(r, 1);
	return p ? p[0] : 0;
}

uint16_t proto_get_u16(struct proto_rbuf *r)
{
	const uint8_t *p = proto_get_span(r, 2);
	return p ? proto_be16(p) : 0;
}

uint32_t proto_get_u32(struct proto_rbuf *r)
{
	const uint8_t *p = proto_get_span(r, 4);
	return p ? proto_be32(p) : 0;
}

uint64_t proto_get_u64(struct proto_rbuf *r)
{
	uint64_t hi = proto_get_u32(r);
	return hi << 32 | proto_get_u32(r);
}

double proto_get_f64(struct proto_rbuf *r)
{
	uint64_t u = proto_get_u64(r);
	double v;
	memcpy(&v, &u, sizeof v);
	return v;
}
