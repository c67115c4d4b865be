/*
 * probe.h - the pixel probe: a tiny built-in scene that uses every
 * primitive, transform, shader, filter, light shape, noise, reflection and
 * refraction, rendered at start-up by master and worker alike. Its 64-bit
 * fingerprint (the probe's pixels plus the exact doubles of the building
 * blocks they come from) is what the farm's handshake compares: two builds
 * with the same fingerprint are trusted to draw the same pixels, whatever
 * their compiler, flags or CPU (docs/maths.md, docs/protocol.md).
 */
#ifndef PORTRAY_PROBE_H
#define PORTRAY_PROBE_H

#include <stdint.h>

/* the probe's size: one standard-filter image and one small image per other filter */
#define PROBE_W 24
#define PROBE_H 16
#define PROBE_SMALL_W 8
#define PROBE_SMALL_H 6

/*
 * Renders the probe (a few milliseconds, one thread) and returns its
 * fingerprint; 0 when it could not be rendered (out of memory), which no
 * peer accepts. The first call renders, later calls return the same value;
 * thread-safe.
 */
uint64_t probe_hash(void);

/* Renders the probe now (for tests and timing): the fingerprint, or 0. */
uint64_t probe_compute(void);

#endif
