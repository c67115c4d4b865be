/*
 * pixstat.c - what a PFM holds, for shell tests (tests/cli/render_formats.sh,
 * tests/e2e/farm_formats.sh):
 *
 *   pixstat FILE.pfm   one line: "WxH min MIN max MAX above1 N below0 N
 *                      levels N" over every channel value (levels: distinct
 *                      values), MIN and MAX with %.9g
 *
 * The header must be portray's ("PF\n<w> <h>\n-1.0\n": little-endian) and
 * the file exactly as long as it says; values are read as little-endian
 * whatever the host. A file that is not such a PFM (or cannot be read)
 * gives exit status 1 and a message on stderr.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tests/unit/slurp.h"

static int cmp_u32(const void *a, const void *b)
{
	uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
	return x < y ? -1 : x > y;
}

int main(int argc, char **argv)
{
	if (argc != 2) {
		fprintf(stderr, "usage: pixstat FILE.pfm\n");
		return 2;
	}
	size_t n;
	uint8_t *p = slurp(argv[1], &n);
	if (!p) {
		fprintf(stderr, "pixstat: cannot read %s\n", argv[1]);
		return 1;
	}
	unsigned w, h;
	int head = 0;
	char text[64] = { 0 };
	memcpy(text, p, n < sizeof text - 1 ? n : sizeof text - 1);
	if (sscanf(text, "PF\n%u %u\n-1.0\n%n", &w, &h, &head) != 2 || head == 0 || w == 0 || h == 0 ||
	    (size_t)head + (size_t)w * h * 12 != n) {
		fprintf(stderr, "pixstat: %s is not a little-endian RGB PFM of the length its header says\n", argv[1]);
		free(p);
		return 1;
	}
	size_t k = (size_t)w * h * 3;
	uint32_t *bits = malloc(k * sizeof *bits);
	if (!bits) {
		fprintf(stderr, "pixstat: out of memory\n");
		free(p);
		return 1;
	}
	float lo = 0, hi = 0;
	size_t above = 0, below = 0;
	for (size_t i = 0; i < k; i++) {
		const uint8_t *q = p + head + 4 * i;
		uint32_t u = (uint32_t)q[0] | (uint32_t)q[1] << 8 | (uint32_t)q[2] << 16 | (uint32_t)q[3] << 24;
		float f;
		memcpy(&f, &u, sizeof f);
		bits[i] = u;
		if (i == 0 || f < lo)
			lo = f;
		if (i == 0 || f > hi)
			hi = f;
		above += f > 1;
		below += f < 0;
	}
	qsort(bits, k, sizeof *bits, cmp_u32);
	size_t levels = 0;
	for (size_t i = 0; i < k; i++)
		levels += i == 0 || bits[i] != bits[i - 1];
	printf("%ux%u min %.9g max %.9g above1 %zu below0 %zu levels %zu\n", w, h, (double)lo, (double)hi, above,
	       below, levels);
	free(bits);
	free(p);
	return 0;
}
