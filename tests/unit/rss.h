/*
 * rss.h - a process's resident memory, for the tests that bound it
 * (test_proto_peer: a worker under hostile peers; test_delayproxy: the
 * proxy's queue bound).
 */
#ifndef PORTRAY_TEST_RSS_H
#define PORTRAY_TEST_RSS_H

#include <stdio.h>
#include <sys/types.h>

/* Resident memory of process pid in KiB (Linux /proc), or -1. */
static inline long rss_kib(pid_t pid)
{
	char path[64], line[256];
	snprintf(path, sizeof path, "/proc/%d/status", (int)pid);
	FILE *f = fopen(path, "r");
	if (!f)
		return -1;
	long kib = -1;
	while (fgets(line, sizeof line, f))
		if (sscanf(line, "VmRSS: %ld", &kib) == 1)
			break;
	fclose(f);
	return kib;
}

#endif
