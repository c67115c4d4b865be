/*
 * check.h - the smallest test harness: CHECK(cond) records a failure with
 * file:line and carries on; TEST_MAIN_END prints the tally and exits 1 on
 * any failure. One test binary per module: tests/unit/test_<module>.c.
 */
#ifndef PORTRAY_CHECK_H
#define PORTRAY_CHECK_H

#include <math.h>
#include <stdio.h>

static int check_failed, check_total;

#define CHECK(cond)                                                                    \
	do {                                                                           \
		check_total++;                                                         \
		if (!(cond)) {                                                         \
			check_failed++;                                                \
			fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
		}                                                                      \
	} while (0)

#define CHECK_NEAR(a, b, eps)                                                          \
	do {                                                                           \
		double check_a_ = (a), check_b_ = (b);                                 \
		check_total++;                                                         \
		if (!(fabs(check_a_ - check_b_) <= (eps))) {                           \
			check_failed++;                                                \
			fprintf(stderr, "%s:%d: CHECK_NEAR failed: %s = %.9g, %s = %.9g\n", \
				__FILE__, __LINE__, #a, check_a_, #b, check_b_);       \
		}                                                                      \
	} while (0)

#define TEST_MAIN_END()                                                                \
	do {                                                                           \
		printf("%d checks, %d failed\n", check_total, check_failed);           \
		return check_failed ? 1 : 0;                                           \
	} while (0)

#endif
