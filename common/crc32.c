/*
 * crc32.c - CRC-32 (crc32.h), eight bytes a step ("slicing by 8"): table k
 * holds the CRC of a byte followed by k zero bytes, so the CRC of eight
 * bytes is the XOR of eight lookups, one for each byte (the four of the
 * running CRC folded into the first four). Any tail goes a byte at a time
 * through table 0.
 */
#include "common/crc32.h"

#include <pthread.h>

static uint32_t table[8][256];
static pthread_once_t table_once = PTHREAD_ONCE_INIT;

static void table_init(void)
{
	for (uint32_t n = 0; n < 256; n++) {
		uint32_t c = n;
		for (int k = 0; k < 8; k++)
			c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
		table[0][n] = c;
	}
	for (uint32_t n = 0; n < 256; n++)
		for (int k = 1; k < 8; k++)
			table[k][n] = (table[k - 1][n] >> 8) ^ table[0][table[k - 1][n] & 0xff];
}

uint32_t crc32_update(uint32_t crc, const uint8_t *p, size_t n)
{
	/* once: tracer threads checksum tiles concurrently (two threads filling
	 * the table at once would be a data race, even writing the same values) */
	pthread_once(&table_once, table_init);
	crc = ~crc;
	for (; n >= 8; n -= 8, p += 8) {
		uint32_t lo = crc ^ ((uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24);
		uint32_t hi = (uint32_t)p[4] | (uint32_t)p[5] << 8 | (uint32_t)p[6] << 16 | (uint32_t)p[7] << 24;
		crc = table[7][lo & 0xff] ^ table[6][(lo >> 8) & 0xff] ^ table[5][(lo >> 16) & 0xff] ^ table[4][lo >> 24] ^
		      table[3][hi & 0xff] ^ table[2][(hi >> 8) & 0xff] ^ table[1][(hi >> 16) & 0xff] ^ table[0][hi >> 24];
	}
	for (size_t i = 0; i < n; i++)
		crc = table[0][(crc ^ p[i]) & 0xff] ^ (crc >> 8);
	return ~crc;
}
