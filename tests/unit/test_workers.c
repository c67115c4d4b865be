/*
 * test_workers.c - the master's worker list (master/workers.c): -w lists and
 * workers files, and the files that are not workers files (a device, a
 * directory, binary data, an over-long line) refused with a message that
 * names the file and line.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "master/workers.h"
#include "tests/unit/check.h"

static char dir[] = "/tmp/portray-test-workers.XXXXXX";

static const char *file_with(const char *name, const void *bytes, size_t n)
{
	static char path[256];
	snprintf(path, sizeof path, "%s/%s", dir, name);
	FILE *f = fopen(path, "wb");
	CHECK(f != NULL);
	if (f) {
		fwrite(bytes, 1, n, f);
		fclose(f);
	}
	return path;
}

/* Parses and returns the error text ("" when it parsed), keeping the list. */
static const char *parse(const char *list, const char *file, struct worker_addr **w, uint32_t *n)
{
	static char err[600];
	err[0] = 0;
	*w = NULL;
	if (workers_parse(list, file, w, n, err, sizeof err) == 0)
		return "";
	CHECK(err[0] != 0);
	return err;
}

int main(void)
{
	CHECK(mkdtemp(dir) != NULL);
	struct worker_addr *w;
	uint32_t n;

	/* a list, then a file with comments, blank lines, CRLF and spaces */
	const char good[] = "# the farm\n\n  host1:7411  # first\r\n[::1]:7412\n\t127.0.0.1:1\n";
	CHECK(strcmp(parse("a:1, b:2", file_with("good", good, sizeof good - 1), &w, &n), "") == 0);
	CHECK(n == 5);
	if (n == 5) {
		CHECK(strcmp(w[0].host, "a") == 0 && strcmp(w[0].port, "1") == 0);
		CHECK(strcmp(w[1].name, "b:2") == 0);
		CHECK(strcmp(w[2].host, "host1") == 0 && strcmp(w[2].port, "7411") == 0);
		CHECK(strcmp(w[3].host, "::1") == 0 && strcmp(w[3].port, "7412") == 0);
		CHECK(strcmp(w[4].host, "127.0.0.1") == 0);
	}
	free(w);
	/* a last line without a newline still counts */
	CHECK(strcmp(parse(NULL, file_with("nonl", "h:9", 3), &w, &n), "") == 0 && n == 1);
	free(w);

	/* refused, each with a message naming what is wrong */
	CHECK(strstr(parse(NULL, "/dev/zero", &w, &n), "not a regular file") != NULL);
	CHECK(strstr(parse(NULL, "/dev/zero", &w, &n), "/dev/zero") != NULL);
	CHECK(strstr(parse(NULL, dir, &w, &n), "is a directory") != NULL);
	CHECK(strstr(parse(NULL, "/nonexistent/workers", &w, &n), "No such file") != NULL);
	const char bin[] = "h:1\nELF\x7f\x01\x02\x00\x00junk\n";
	const char *e = parse(NULL, file_with("bin", bin, sizeof bin - 1), &w, &n);
	CHECK(strstr(e, "binary data") != NULL && strstr(e, "bin:2") != NULL);
	char longline[2000];
	memset(longline, 'a', sizeof longline);
	CHECK(strstr(parse(NULL, file_with("long", longline, sizeof longline), &w, &n), "longer than") != NULL);
	CHECK(strstr(parse(NULL, file_with("badport", "h:99999\n", 8), &w, &n), "badport:1") != NULL);
	CHECK(strstr(parse(NULL, file_with("empty", "# none\n", 7), &w, &n), "no workers named") != NULL);
	CHECK(strstr(parse("", NULL, &w, &n), "no workers named") != NULL);
	/* a file too large to be a workers file (sparse: costs no disk) */
	char big[300];
	snprintf(big, sizeof big, "%s/big", dir);
	FILE *f = fopen(big, "w");
	CHECK(f && fseek(f, WORKERS_FILE_MAX + 10, SEEK_SET) == 0 && fputc('\n', f) == '\n' && fclose(f) == 0);
	e = parse(NULL, big, &w, &n);
	CHECK(strstr(e, "binary data") != NULL || strstr(e, "larger than") != NULL);
	/* more workers than the limit */
	size_t cap = (WORKERS_MAX + 1) * 16;
	char *many = malloc(cap);
	size_t len = 0;
	for (int i = 0; i <= WORKERS_MAX; i++)
		len += (size_t)snprintf(many + len, cap - len, "h%d:1\n", i);
	CHECK(strstr(parse(NULL, file_with("many", many, len), &w, &n), "more than") != NULL);
	free(many);

	char cmd[300];
	snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
	CHECK(system(cmd) == 0);
	TEST_MAIN_END();
}
