/*
 * fuzz_parse.c - libFuzzer target for the scene language: the lexer and
 * parser on arbitrary bytes, with no file access (includes and raw files are
 * refused). Every scene built is freed, so leaks show up under ASan.
 */
#include <stddef.h>
#include <stdint.h>

#include "common/parse.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct scene *s = NULL;
	struct scene_error err;
	int rc = parse_buffer("fuzz.sce", (const char *)data, size, 0, &s, &err);
	if (rc == 0) {
		struct scene_stats st;
		scene_stats(s, &st); /* walks every object and define */
	}
	scene_free(s);
	return 0;
}
