/*
 * workers.h - the list of workers a master renders with: -w HOST:PORT,...
 * and --workers-file (one HOST:PORT per line, '#' comments).
 */
#ifndef PORTRAY_WORKERS_H
#define PORTRAY_WORKERS_H

#include <stddef.h>
#include <stdint.h>

#include "proto/net.h"

/* workers named on one command line and workers file together */
#define WORKERS_MAX 1024
/* a workers file: far more than WORKERS_MAX lines of addresses */
#define WORKERS_FILE_MAX (1024u * 1024)
/* one line of a workers file */
#define WORKERS_LINE_MAX 512

struct worker_addr {
	char name[NET_HOST_LEN + NET_PORT_LEN + 4]; /* as written */
	char host[NET_HOST_LEN], port[NET_PORT_LEN];
};

/*
 * Parses the comma-separated list (may be NULL) then the file (may be NULL)
 * into *out (caller frees) and *n. A file must be a regular file or a pipe
 * of text: a directory, a device, binary data (NUL or other control bytes),
 * an over-long line or a file over WORKERS_FILE_MAX is refused. Returns 0,
 * or -1 with a message naming the file and line in err. An empty result is
 * an error too.
 */
int workers_parse(const char *list, const char *file, struct worker_addr **out, uint32_t *n, char *err,
		  size_t errlen);

/*
 * Replaces every entry whose host resolves to several addresses (A and AAAA
 * records: a Kubernetes headless Service, a round-robin name) by one entry
 * per address, named "NAME:PORT/ADDRESS", keeping the order. A name that
 * does not resolve (yet) stays as it is: connecting retries it later.
 * Returns 0, or -1 with err (more than WORKERS_MAX in all, out of memory).
 */
int workers_expand(struct worker_addr **w, uint32_t *n, char *err, size_t errlen);

#endif
