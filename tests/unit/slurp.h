/*
 * slurp.h - a whole file into memory, for tests and test tools (one copy:
 * test_img, test_imgfmt and tests/tools/pngchunks read files back).
 */
#ifndef PORTRAY_TEST_SLURP_H
#define PORTRAY_TEST_SLURP_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

/* The bytes of path (caller frees) and their count in *n; NULL when the
 * file cannot be read or memory runs out. */
static inline uint8_t *slurp(const char *path, size_t *n)
{
	FILE *f = fopen(path, "rb");
	if (!f)
		return NULL;
	size_t cap = 1 << 16, len = 0, r;
	uint8_t *b = malloc(cap);
	while (b && (r = fread(b + len, 1, cap - len, f)) > 0) {
		len += r;
		if (len == cap) {
			uint8_t *nb = realloc(b, cap *= 2);
			if (!nb)
				free(b);
			b = nb;
		}
	}
	fclose(f);
	*n = len;
	return b;
}

#endif
