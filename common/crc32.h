/*
 * crc32.h - CRC-32 as in PNG, zlib and IEEE 802.3 (reflected polynomial
 * 0xEDB88320): the one copy, for PNG chunks and the farm's tile checksums.
 */
#ifndef PORTRAY_CRC32_H
#define PORTRAY_CRC32_H

#include <stddef.h>
#include <stdint.h>

/*
 * CRC of n bytes continuing from crc: start with 0; pieces chain, so
 * crc32_update(crc32_update(0, a), b) is the CRC of a followed by b.
 * "123456789" gives 0xCBF43926. Thread-safe.
 */
uint32_t crc32_update(uint32_t crc, const uint8_t *p, size_t n);

#endif
