/*
 * buf.h - byte buffers for the wire and the scene serializer: a growable
 * writer and a bounds-checked reader, both big-endian (network byte order)
 * whatever the host, doubles as their IEEE-754 bit patterns.
 *
 * The reader never reads past its end: a short buffer sets err and every
 * later get returns 0, so a decoder checks err once at the end (or before it
 * trusts a count) instead of after every field.
 */
#ifndef PORTRAY_PROTO_BUF_H
#define PORTRAY_PROTO_BUF_H

#include <stddef.h>
#include <stdint.h>

struct proto_wbuf {
	uint8_t *p;  /* owned; free with proto_wbuf_free */
	size_t len;  /* bytes written */
	size_t cap;
	int oom;     /* an allocation failed: the contents are incomplete */
};

void proto_wbuf_free(struct proto_wbuf *b);
/* Makes room for n more bytes; returns 0, or -1 (and sets oom) on failure. */
int proto_wbuf_reserve(struct proto_wbuf *b, size_t n);
void proto_put_u8(struct proto_wbuf *b, uint8_t v);
void proto_put_u16(struct proto_wbuf *b, uint16_t v);
void proto_put_u32(struct proto_wbuf *b, uint32_t v);
void proto_put_u64(struct proto_wbuf *b, uint64_t v);
void proto_put_f64(struct proto_wbuf *b, double v);
void proto_put_bytes(struct proto_wbuf *b, const void *p, size_t n);
/* u32 length then the bytes, no terminator; NULL is written as length 0. */
void proto_put_str(struct proto_wbuf *b, const char *s);

struct proto_rbuf {
	const uint8_t *p; /* not owned */
	size_t len, pos;
	int err;          /* read past the end (or a decoder set it) */
};

static inline size_t proto_rbuf_left(const struct proto_rbuf *r) { return r->err ? 0 : r->len - r->pos; }
uint8_t proto_get_u8(struct proto_rbuf *r);
uint16_t proto_get_u16(struct proto_rbuf *r);
uint32_t proto_get_u32(struct proto_rbuf *r);
uint64_t proto_get_u64(struct proto_rbuf *r);
double proto_get_f64(struct proto_rbuf *r);
/* Copies n bytes into out (zeros on error). */
void proto_get_bytes(struct proto_rbuf *r, void *out, size_t n);
/* Returns a pointer to the next n bytes inside the buffer and skips them, or NULL. */
const uint8_t *proto_get_span(struct proto_rbuf *r, size_t n);

/* Big-endian helpers on raw memory. */
static inline uint32_t proto_be32(const uint8_t *p)
{
	return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}
static inline uint16_t proto_be16(const uint8_t *p) { return (uint16_t)(p[0] << 8 | p[1]); }
static inline void proto_wr32(uint8_t *p, uint32_t v)
{
	p[0] = (uint8_t)(v >> 24), p[1] = (uint8_t)(v >> 16), p[2] = (uint8_t)(v >> 8), p[3] = (uint8_t)v;
}
static inline void proto_wr16(uint8_t *p, uint16_t v) { p[0] = (uint8_t)(v >> 8), p[1] = (uint8_t)v; }

#endif
