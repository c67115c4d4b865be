/*
 * pngchunks.c - a PNG's chunks, for shell tests (tests/cli/render_formats.sh).
 *
 *   pngchunks FILE              one line per chunk: TYPE LENGTH, and for
 *                               tEXt the keyword and the text ('\n' as \n);
 *                               IHDR: width, height, bit depth, colour type
 *   pngchunks -d KEYWORD IN OUT IN without its tEXt chunks of that keyword
 *   pngchunks -s IN OUT         IN with only its critical chunks (IHDR, IDAT,
 *                               IEND): what the plain encoder writes
 *
 * Every chunk's CRC is checked; a file that is not a well-formed PNG (or a
 * read or write error) gives exit status 1 and a message on stderr.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/crc32.h"
#include "tests/unit/slurp.h"

static uint32_t be32(const uint8_t *p)
{
	return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

int main(int argc, char **argv)
{
	const char *in, *out = NULL, *drop = NULL;
	int strip = 0;
	if (argc == 2) {
		in = argv[1];
	} else if (argc == 5 && !strcmp(argv[1], "-d")) {
		drop = argv[2];
		in = argv[3];
		out = argv[4];
	} else if (argc == 4 && !strcmp(argv[1], "-s")) {
		strip = 1;
		in = argv[2];
		out = argv[3];
	} else {
		fprintf(stderr, "usage: pngchunks FILE | pngchunks -d KEYWORD IN OUT | pngchunks -s IN OUT\n");
		return 2;
	}
	size_t n = 0;
	uint8_t *p = slurp(in, &n);
	static const uint8_t sig[8] = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n' };
	if (!p || n < 8 || memcmp(p, sig, 8) != 0) {
		fprintf(stderr, "pngchunks: %s: not a PNG\n", in);
		return 1;
	}
	FILE *o = out ? fopen(out, "wb") : NULL;
	if (out && (!o || fwrite(p, 1, 8, o) != 8)) {
		fprintf(stderr, "pngchunks: cannot write %s\n", out);
		return 1;
	}
	size_t pos = 8;
	int iend = 0;
	while (pos < n && !iend) {
		if (n - pos < 12 || be32(p + pos) > n - pos - 12) {
			fprintf(stderr, "pngchunks: %s: truncated chunk at byte %zu\n", in, pos);
			return 1;
		}
		uint32_t len = be32(p + pos);
		const uint8_t *type = p + pos + 4, *data = p + pos + 8;
		if (crc32_update(0, type, 4 + (size_t)len) != be32(data + len)) {
			fprintf(stderr, "pngchunks: %s: bad CRC at byte %zu\n", in, pos);
			return 1;
		}
		int is_text = !memcmp(type, "tEXt", 4);
		size_t kn = is_text ? strnlen((const char *)data, len) : 0;
		if (!out) {
			printf("%.4s %u", (const char *)type, (unsigned)len);
			if (!memcmp(type, "IHDR", 4) && len == 13)
				printf(" %ux%u depth %u colour %u", (unsigned)be32(data), (unsigned)be32(data + 4), data[8],
				       data[9]);
			if (is_text) {
				printf(" %.*s=", (int)kn, (const char *)data);
				for (size_t i = kn + 1; i < len; i++)
					data[i] == '\n' ? printf("\\n") : putchar(data[i]);
			}
			putchar('\n');
		} else {
			int keep = strip ? !(type[0] & 0x20)
					 : !(is_text && kn == strlen(drop) && !memcmp(data, drop, kn));
			if (keep && fwrite(p + pos, 1, 12 + (size_t)len, o) != 12 + (size_t)len) {
				fprintf(stderr, "pngchunks: cannot write %s\n", out);
				return 1;
			}
		}
		iend = !memcmp(type, "IEND", 4);
		pos += 12 + (size_t)len;
	}
	if (!iend || pos != n) {
		fprintf(stderr, "pngchunks: %s: %s\n", in, iend ? "bytes after IEND" : "no IEND");
		return 1;
	}
	if (o && fclose(o) != 0) {
		fprintf(stderr, "pngchunks: cannot write %s\n", out);
		return 1;
	}
	free(p);
	return 0;
}
