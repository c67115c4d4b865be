/*
 * bench_rss.c - whole-process peak memory for a million instances of a
 * defined mesh (issue 13: at most 100 bytes per instance, 100 MB). Each
 * scenario runs in a child process of its own, which builds the scene
 * model through the builder calls (as the parser and the scene
 * deserializer do), builds the renderer (the acceleration structure) and
 * renders a 160x120 image; the parent reports the child's peak resident
 * set (wait4's ru_maxrss) and the child's high-water mark after each stage
 * (VmHWM). Scenarios: "flat", 1,000,000 root instances (each its own
 * translation) of one define holding a 1,000-triangle RAW mesh; "nested",
 * the same million drawn through three levels of 100 instances; "empty",
 * the same process with the mesh and no instance (the floor under the
 * figures). Not a test: prints figures only.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "common/render.h"
#include "common/scene.h"
#include "common/tiles.h"
#include "bench/bench_scene.h"
#include "tests/unit/rss.h"

static void stage(const char *what)
{
	printf("    %-34s VmHWM %7.1f MB\n", what, proc_status_kib("self", "VmHWM") / 1024.0);
}

/* The child's work: scene, renderer, a 160x120 image. */
static int run(const char *kind)
{
	struct scene *s = scene_new();
	if (!s)
		return 1;
	struct scene_camera cam;
	scene_camera_defaults(&cam);
	cam.look_from = v3(-60, 150, -120);
	cam.look_at = v3(50, 50, 50);
	struct scene_error err;
	if (scene_set_camera(s, &cam, &err))
		return 1;
	struct scene_light l;
	scene_light_defaults(&l);
	l.position = v3(-100, 300, -200);
	if (scene_add_light(s, &l, &err))
		return 1;
	bs_million(s, !strcmp(kind, "nested") ? BS_NESTED : !strcmp(kind, "flat") ? BS_FLAT : BS_NONE);
	stage("scene model built");
	struct renderer *r;
	if (renderer_new(s, &r, &err)) {
		fprintf(stderr, "%s\n", err.msg);
		return 1;
	}
	stage("acceleration built");
	enum { W = 160, H = 120 };
	if (renderer_set_size(r, W, H))
		return 1;
	static uint8_t rgb[W * H * 3];
	struct tile_rect t = { 0, 0, W, H };
	renderer_tile(r, t, rgb);
	unsigned long sum = 0;
	for (size_t i = 0; i < sizeof rgb; i++)
		sum += rgb[i];
	stage("160x120 rendered");
	printf("    (pixel sum %lu)\n", sum);
	renderer_free(r);
	scene_free(s);
	return 0;
}

int main(int argc, char **argv)
{
	if (argc == 2)
		return run(argv[1]);
	static const char *const kinds[] = { "empty", "flat", "nested" };
	double floor_mb = 0;
	for (size_t i = 0; i < sizeof kinds / sizeof *kinds; i++) {
		printf("%s:\n", kinds[i]);
		fflush(stdout);
		pid_t pid = fork();
		if (pid < 0)
			return 1;
		if (pid == 0) {
			execl("/proc/self/exe", argv[0], kinds[i], (char *)NULL);
			_exit(127);
		}
		int st;
		struct rusage ru;
		if (wait4(pid, &st, 0, &ru) < 0 || !WIFEXITED(st) || WEXITSTATUS(st)) {
			printf("  failed\n");
			continue;
		}
		double mb = ru.ru_maxrss / 1024.0;
		if (i == 0) {
			floor_mb = mb;
			printf("  peak RSS %.1f MB (the process without instances)\n", mb);
		} else {
			printf("  peak RSS %.1f MB = %.0f bytes per instance (%.0f above the empty process); target "
			       "<= 100 MB\n",
			       mb, mb * 1048576.0 / 1e6, (mb - floor_mb) * 1048576.0 / 1e6);
		}
		fflush(stdout);
	}
	return 0;
}
