/*
 * imgcmp.c - compares two binary PPM (P6, maxval 255) images with a
 * per-channel tolerance. Built by tests/cli/golden.sh with $CC (the Makefile
 * only builds tests/unit/test_*.c).
 *
 *   imgcmp [-t TOL] [-f FRAC] [-m MAX] A.ppm B.ppm
 *       exit 0 when the images have the same size, at least FRAC of the
 *       pixels have every channel within TOL, and no channel differs by more
 *       than MAX. Defaults: TOL 2, FRAC 0.995, MAX 16.
 *   imgcmp -d [-t TOL] [-f FRAC] A.ppm B.ppm
 *       "must differ": exit 0 when more than 1 - FRAC of the pixels differ
 *       by more than TOL (defaults as above), i.e. when the first form fails
 *       on its fraction rule.
 * Prints one line of statistics either way. Exit 2 on unreadable input.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct ppm {
	int w, h;
	unsigned char *px;
};

/* Skips whitespace and '#' comments in a PPM header. */
static int skip_ws(FILE *f)
{
	int c;
	for (;;) {
		c = fgetc(f);
		if (c == '#') {
			while (c != '\n' && c != EOF)
				c = fgetc(f);
		} else if (c != ' ' && c != '\t' && c != '\n' && c != '\r') {
			return c;
		}
	}
}

static int read_int(FILE *f, int *v)
{
	int c = skip_ws(f);
	if (c < '0' || c > '9')
		return -1;
	long x = 0;
	while (c >= '0' && c <= '9') {
		x = x * 10 + (c - '0');
		if (x > 100000)
			return -1;
		c = fgetc(f);
	}
	*v = (int)x;
	return 0; /* the single whitespace after the number is consumed */
}

static int read_ppm(const char *path, struct ppm *p)
{
	FILE *f = fopen(path, "rb");
	if (!f)
		return -1;
	int maxval;
	if (fgetc(f) != 'P' || fgetc(f) != '6' || read_int(f, &p->w) || read_int(f, &p->h) ||
	    read_int(f, &maxval) || maxval != 255 || p->w < 1 || p->h < 1) {
		fclose(f);
		return -1;
	}
	size_t n = (size_t)p->w * (size_t)p->h * 3;
	p->px = malloc(n);
	if (!p->px || fread(p->px, 1, n, f) != n) {
		free(p->px);
		fclose(f);
		return -1;
	}
	fclose(f);
	return 0;
}

int main(int argc, char **argv)
{
	int tol = 2, maxd = 16, differ = 0;
	double frac = 0.995;
	int i = 1;
	for (; i < argc && argv[i][0] == '-'; i++) {
		if (!strcmp(argv[i], "-d"))
			differ = 1;
		else if (!strcmp(argv[i], "-t") && i + 1 < argc)
			tol = atoi(argv[++i]);
		else if (!strcmp(argv[i], "-f") && i + 1 < argc)
			frac = atof(argv[++i]);
		else if (!strcmp(argv[i], "-m") && i + 1 < argc)
			maxd = atoi(argv[++i]);
		else
			break;
	}
	if (argc - i != 2) {
		fprintf(stderr, "usage: imgcmp [-d] [-t TOL] [-f FRAC] [-m MAX] A.ppm B.ppm\n");
		return 2;
	}
	struct ppm a, b;
	if (read_ppm(argv[i], &a) || read_ppm(argv[i + 1], &b)) {
		fprintf(stderr, "imgcmp: cannot read %s or %s as binary PPM\n", argv[i], argv[i + 1]);
		return 2;
	}
	if (a.w != b.w || a.h != b.h) {
		printf("size differs: %dx%d vs %dx%d\n", a.w, a.h, b.w, b.h);
		return differ ? 0 : 1;
	}
	long n = (long)a.w * a.h, bad = 0;
	int worst = 0;
	for (long k = 0; k < n; k++) {
		int m = 0;
		for (int c = 0; c < 3; c++) {
			int d = abs(a.px[3 * k + c] - b.px[3 * k + c]);
			if (d > m)
				m = d;
		}
		if (m > tol)
			bad++;
		if (m > worst)
			worst = m;
	}
	double ok = 1.0 - (double)bad / (double)n;
	printf("%dx%d: %.4f%% of pixels within %d, max difference %d\n", a.w, a.h, 100 * ok, tol, worst);
	free(a.px);
	free(b.px);
	if (differ)
		return ok < frac ? 0 : 1;
	return ok >= frac && worst <= maxd ? 0 : 1;
}
