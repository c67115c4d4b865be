/*
 * scene_text.h - scene source built in memory for the tests that write
 * their scenes out (test_lbuf, test_flatnear): st_put appends printf-style
 * text; st.ok turns false when it did not fit or the buffer could not be
 * made, and the test then fails its check rather than parse half a scene.
 */
#ifndef PORTRAY_SCENE_TEXT_H
#define PORTRAY_SCENE_TEXT_H

#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

struct scene_text {
	char *t;
	size_t len, cap;
	bool ok;
};

/* An empty text of room for cap - 1 bytes. */
static inline struct scene_text st_new(size_t cap)
{
	struct scene_text st = { malloc(cap), 0, cap, true };
	st.ok = st.t != NULL;
	if (st.ok)
		st.t[0] = 0;
	return st;
}

static inline __attribute__((format(printf, 2, 3))) void st_put(struct scene_text *st, const char *fmt, ...)
{
	if (!st->ok)
		return;
	va_list ap;
	va_start(ap, fmt);
	int n = vsnprintf(st->t + st->len, st->cap - st->len, fmt, ap);
	va_end(ap);
	if (n < 0 || (size_t)n >= st->cap - st->len)
		st->ok = false;
	else
		st->len += (size_t)n;
}

#endif
