/*
 * fuzz_scene.c - libFuzzer target: the scene decoder on arbitrary bytes.
 * Whatever it accepts must encode again and decode to the same bytes (the
 * encoding is canonical), and it must never crash, leak or hang.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "proto/serial.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct scene *s = NULL, *t = NULL;
	struct scene_error err;
	if (proto_scene_decode(data, size, &s, &err) != 0)
		return 0;
	uint8_t *a = NULL, *b = NULL;
	size_t la = 0, lb = 0;
	if (proto_scene_encode(s, &a, &la) == 0) {
		if (proto_scene_decode(a, la, &t, &err) != 0)
			abort();
		if (proto_scene_encode(t, &b, &lb) != 0 || la != lb || memcmp(a, b, la) != 0)
			abort();
	}
	free(a);
	free(b);
	scene_free(s);
	scene_free(t);
	return 0;
}
