/* check.c - placeholder until the parser lands (issue 2). */
#include <stdio.h>

#include "master/master.h"

int master_check(const struct master_opts *o)
{
	fprintf(stderr, "portray-master: --check %s: parser not built yet\n", o->scene);
	return 1;
}
