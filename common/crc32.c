/*
 * crc32.c - CRC-32 (crc32.h), a byte-at-a-time table.
 */
#include "common/crc32.h"

#include <pthread.h>

static uint32_t table[256];
static pthread_once_t table_once = PTHREAD_ONCE_INIT;

static void table_init(void)
{
	for (uint32_t n = 0; n < 256; n++) {
		uint32_t c = n;
		for (int k = 0; k < 8; k++)
			c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
		table[n] = c;
	}
}

uint32_t crc32_update(uint32_t crc, const uint8_t *p, size_t n)
{
	/* once: tracer threads checksum tiles concurrently (two threads filling
	 * the table at once would be a data race, even writing the same values) */
	pthread_once(&table_once, table_init);
	crc = ~crc;
	for (size_t i = 0; i < n; i++)
		crc = table[(crc ^ p[i]) & 0xff] ^ (crc >> 8);
	return ~crc;
}
