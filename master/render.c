/* render.c - placeholder until the renderer lands (issue 3). */
#include <stdio.h>

#include "master/master.h"

int master_render(const struct master_opts *o)
{
	fprintf(stderr, "portray-master: %s: renderer not built yet\n", o->scene);
	return 1;
}
