/*
 * same_hit.h - whether two closest-hit answers are the same, bit for bit
 * (what accel_intersect4, the leaf blocks and every traversal promise
 * against accel_intersect and accel_intersect_brute).
 */
#ifndef PORTRAY_TEST_SAME_HIT_H
#define PORTRAY_TEST_SAME_HIT_H

#include <stdbool.h>
#include <string.h>

#include "common/accel.h"

static inline bool same_hit(bool b1, const struct hit *h1, bool b2, const struct hit *h2)
{
	if (b1 != b2)
		return false;
	return !b1 || (memcmp(&h1->t, &h2->t, sizeof h1->t) == 0 && memcmp(&h1->p, &h2->p, sizeof h1->p) == 0 &&
		       memcmp(&h1->n, &h2->n, sizeof h1->n) == 0 && memcmp(&h1->ng, &h2->ng, sizeof h1->ng) == 0 &&
		       h1->object == h2->object && h1->material == h2->material);
}

#endif
