/*
 * workers.c - parsing the worker list (workers.h).
 */
#include "master/workers.h"

#include <errno.h>
#include <netdb.h>
#include <fcntl.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static int add(struct worker_addr *w, uint32_t *n, const char *spec, const char *where, char *err, size_t errlen)
{
	if (*n >= WORKERS_MAX) {
		snprintf(err, errlen, "%s: more than %d workers", where, WORKERS_MAX);
		return -1;
	}
	char why[300];
	struct worker_addr *a = &w[*n];
	if (net_parse_hostport(spec, a->host, a->port, why, sizeof why) < 0) {
		snprintf(err, errlen, "%s: %s", where, why);
		return -1;
	}
	snprintf(a->name, sizeof a->name, "%s", spec);
	(*n)++;
	return 0;
}

/* Reads the whole file (bounded) into a NUL-terminated buffer; NULL with err. */
static char *slurp(const char *path, size_t *len, char *err, size_t errlen)
{
	int fd = open(path, O_RDONLY | O_NOCTTY | O_CLOEXEC | O_NONBLOCK);
	if (fd < 0) {
		snprintf(err, errlen, "%s: %s", path, strerror(errno));
		return NULL;
	}
	struct stat st;
	if (fstat(fd, &st) < 0 || !(S_ISREG(st.st_mode) || S_ISFIFO(st.st_mode))) {
		snprintf(err, errlen, "%s: %s", path,
			 S_ISDIR(st.st_mode) ? "is a directory, not a workers file"
					     : "is not a regular file (a device?): a workers file lists HOST:PORT lines");
		close(fd);
		return NULL;
	}
	fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK); /* a pipe: wait for its writer */
	char *buf = malloc(WORKERS_FILE_MAX + 1);
	size_t n = 0;
	for (;;) {
		if (!buf) {
			snprintf(err, errlen, "%s: out of memory", path);
			break;
		}
		ssize_t r = read(fd, buf + n, WORKERS_FILE_MAX + 1 - n);
		if (r < 0 && errno == EINTR)
			continue;
		if (r < 0) {
			snprintf(err, errlen, "%s: %s", path, strerror(errno));
			free(buf);
			buf = NULL;
			break;
		}
		if (r == 0) {
			buf[n] = 0;
			*len = n;
			break;
		}
		n += (size_t)r;
		if (n > WORKERS_FILE_MAX) {
			snprintf(err, errlen, "%s: larger than %u bytes: not a workers file", path, WORKERS_FILE_MAX);
			free(buf);
			buf = NULL;
			break;
		}
	}
	close(fd);
	return buf;
}

static int parse_file(const char *path, struct worker_addr *w, uint32_t *n, char *err, size_t errlen)
{
	size_t len;
	char *buf = slurp(path, &len, err, errlen);
	if (!buf)
		return -1;
	int rc = 0, ln = 0;
	for (char *line = buf; rc == 0 && line < buf + len;) {
		ln++;
		char *eol = memchr(line, '\n', (size_t)(buf + len - line));
		char *end = eol ? eol : buf + len;
		char where[WORKERS_LINE_MAX + 64];
		snprintf(where, sizeof where, "%s:%d", path, ln);
		if (end - line > WORKERS_LINE_MAX) {
			snprintf(err, errlen, "%s: line longer than %d bytes", where, WORKERS_LINE_MAX);
			rc = -1;
			break;
		}
		for (char *p = line; p < end; p++) {
			unsigned char c = (unsigned char)*p;
			if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7f) {
				snprintf(err, errlen, "%s: binary data (byte 0x%02x): not a workers file", where, c);
				rc = -1;
				break;
			}
		}
		if (rc)
			break;
		*end = 0;
		char *hash = strchr(line, '#');
		if (hash)
			*hash = 0;
		char *p = line, *e;
		while (*p == ' ' || *p == '\t')
			p++;
		for (e = p + strlen(p); e > p && (e[-1] == '\r' || e[-1] == ' ' || e[-1] == '\t');)
			*--e = 0;
		if (*p && add(w, n, p, where, err, errlen) < 0)
			rc = -1;
		line = end + 1;
	}
	free(buf);
	return rc;
}

int workers_parse(const char *list, const char *file, struct worker_addr **out, uint32_t *n, char *err,
		  size_t errlen)
{
	struct worker_addr *w = calloc(WORKERS_MAX, sizeof *w);
	*n = 0;
	if (!w) {
		snprintf(err, errlen, "out of memory");
		return -1;
	}
	if (list) {
		char *copy = strdup(list), *save = NULL;
		if (!copy) {
			snprintf(err, errlen, "out of memory");
			free(w);
			return -1;
		}
		for (char *tok = strtok_r(copy, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
			while (*tok == ' ')
				tok++;
			if (*tok && add(w, n, tok, "-w", err, errlen) < 0) {
				free(copy);
				free(w);
				return -1;
			}
		}
		free(copy);
	}
	if (file && parse_file(file, w, n, err, errlen) < 0) {
		free(w);
		return -1;
	}
	if (*n == 0) {
		snprintf(err, errlen, "no workers named (-w HOST:PORT or --workers-file)");
		free(w);
		return -1;
	}
	*out = w;
	return 0;
}

/* The distinct numeric addresses of host:port, in resolver order; how many (0: none). */
static int addresses(const struct worker_addr *a, char out[][64], int max)
{
	struct addrinfo hints, *res = NULL;
	memset(&hints, 0, sizeof hints);
	hints.ai_family = AF_UNSPEC;
	hints.ai_socktype = SOCK_STREAM;
	if (getaddrinfo(a->host, a->port, &hints, &res) != 0)
		return 0;
	int n = 0;
	for (struct addrinfo *ai = res; ai && n < max; ai = ai->ai_next) {
		char host[NET_HOST_LEN];
		if (getnameinfo(ai->ai_addr, ai->ai_addrlen, host, sizeof host, NULL, 0, NI_NUMERICHOST) != 0)
			continue;
		bool seen = false;
		for (int i = 0; i < n && !seen; i++)
			seen = strcmp(out[i], host) == 0;
		if (!seen)
			snprintf(out[n++], 64, "%.63s", host);
	}
	freeaddrinfo(res);
	return n;
}

int workers_expand(struct worker_addr **w, uint32_t *n, char *err, size_t errlen)
{
	struct worker_addr *out = calloc(WORKERS_MAX, sizeof *out);
	char addr[64][64]; /* numeric addresses: at most 45 bytes and a scope */
	if (!out) {
		snprintf(err, errlen, "out of memory");
		return -1;
	}
	uint32_t m = 0;
	for (uint32_t i = 0; i < *n; i++) {
		const struct worker_addr *a = &(*w)[i];
		int k = addresses(a, addr, 64);
		if (m + (k > 1 ? (uint32_t)k : 1) > WORKERS_MAX) {
			snprintf(err, errlen, "%s: more than %d workers once names are resolved", a->name, WORKERS_MAX);
			free(out);
			return -1;
		}
		if (k <= 1) {
			out[m++] = *a;
			continue;
		}
		for (int j = 0; j < k; j++, m++) {
			out[m] = *a;
			snprintf(out[m].host, sizeof out[m].host, "%.63s", addr[j]);
			snprintf(out[m].name, sizeof out[m].name, "%.200s/%.63s", a->name, addr[j]);
		}
	}
	free(*w);
	*w = out;
	*n = m;
	return 0;
}
