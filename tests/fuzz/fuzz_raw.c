/*
 * fuzz_raw.c - libFuzzer target for the RAW reader: the input bytes are the
 * file. The first byte (when the input starts with '#') chooses the options,
 * so weld distances, smoothing, rotation and AT are fuzzed too:
 *   '#' then one option byte o: bit 0 smooth, bits 1-3 weld exponent
 *   (0 = default 1e-5, else 10^-(2k) or 0 for k = 7), bit 4 rotate, bit 5 at.
 * Invariants checked on success: indices in range, finite vertices, unit
 * normals; on error: arrays NULL and a message naming the file.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "common/raw.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct scene_mesh m;
	struct scene_error err;
	memset(&m, 0, sizeof m);
	m.file = (char *)"fuzz.raw";
	m.weld = 0.00001;
	if (size >= 2 && data[0] == '#') {
		uint8_t o = data[1];
		int k = (o >> 1) & 7;
		m.smooth = o & 1;
		if (k == 7)
			m.weld = 0;
		else if (k)
			m.weld = pow(10.0, -2.0 * k + 4); /* 100, 1, 0.01 ... 1e-8 */
		if (o & 16)
			m.rotation = v3(30, -45, 400);
		if (o & 32)
			m.at = v3(1e6, -2, 0.5);
		data += 2;
		size -= 2;
	}
	int rc = raw_parse((const char *)data, size, &m, &err);
	if (rc == 0) {
		if (m.n_triangles == 0 || !m.tris || !m.vertices)
			abort();
		for (uint64_t i = 0; i < 3ull * m.n_triangles; i++)
			if (m.tris[i] >= m.n_vertices)
				abort();
		for (uint32_t i = 0; i < m.n_vertices; i++) {
			if (!v3_finite(m.vertices[i]))
				abort();
			if (m.smooth && !(fabs(v3_len(m.normals[i]) - 1) < 1e-9))
				abort();
		}
		if (!m.smooth && m.normals)
			abort();
	} else {
		if (m.tris || m.vertices || m.normals || rc != 1 || strncmp(err.msg, "fuzz.raw", 8) != 0)
			abort();
	}
	free(m.vertices);
	free(m.normals);
	free(m.tris);
	return 0;
}
