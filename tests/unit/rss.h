/*
 * rss.h - a process's resident memory, for the tests that bound it
 * (test_proto_peer: a worker under hostile peers; test_delayproxy: the
 * proxy's queue bound) and for bench_rss (its own high-water mark).
 */
#ifndef PORTRAY_TEST_RSS_H
#define PORTRAY_TEST_RSS_H

#include <stdio.h>
#include <sys/types.h>

/* The value in KiB of field key ("VmRSS", "VmHWM") of /proc/<who>/status
 * (who: a pid or "self"; Linux), or -1. */
static inline long proc_status_kib(const char *who, const char *key)
{
	char path[64], fmt[64], line[256];
	snprintf(path, sizeof path, "/proc/%s/status", who);
	snprintf(fmt, sizeof fmt, "%s: %%ld", key);
	FILE *f = fopen(path, "r");
	if (!f)
		return -1;
	long kib = -1;
	while (fgets(line, sizeof line, f))
		if (sscanf(line, fmt, &kib) == 1)
			break;
	fclose(f);
	return kib;
}

/* Resident memory of process pid in KiB, or -1. */
static inline long rss_kib(pid_t pid)
{
	char who[24];
	snprintf(who, sizeof who, "%d", (int)pid);
	return proc_status_kib(who, "VmRSS");
}

#endif
