/* main.c - portray-worker: placeholder until the farm issue lands. */
#include <stdio.h>
#include <string.h>

int main(int argc, char **argv)
{
	if (argc > 1 && strcmp(argv[1], "--version") == 0) {
		printf("portray-worker %s\n", PORTRAY_VERSION);
		return 0;
	}
	printf("Usage: portray-worker [--listen ADDR:PORT] [-j N] [--secret-file F] [--port-file F]\n");
	return argc > 1 && strcmp(argv[1], "--help") != 0 ? 64 : 0;
}
