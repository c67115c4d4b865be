/*
 * build_util.h - tiny helpers for tests that build scenes by hand through
 * the builder (scene.h): any builder refusal aborts the test binary with the
 * builder's message, since a test scene that fails to build is a test bug.
 */
#ifndef PORTRAY_BUILD_UTIL_H
#define PORTRAY_BUILD_UTIL_H

#include <stdio.h>
#include <stdlib.h>

#include "common/scene.h"

/* Appends o (ownership of its arrays moves to s); returns its index. */
static inline uint32_t bu_add(struct scene *s, struct scene_object *o)
{
	struct scene_error e;
	uint32_t id;
	if (scene_add_object(s, o, &id, &e)) {
		fprintf(stderr, "builder: %s\n", e.msg);
		abort();
	}
	return id;
}

/* Appends an anonymous matt material whose diffuse colour is (r 0 0), so
 * tests can tell materials apart by r; returns its index. */
static inline uint32_t bu_material(struct scene *s, double r)
{
	struct scene_material m;
	struct scene_error e;
	uint32_t id;
	scene_material_defaults(&m);
	m.diff_colour = v3(r, 0, 0);
	if (scene_add_material(s, &m, &id, &e)) {
		fprintf(stderr, "builder: %s\n", e.msg);
		abort();
	}
	return id;
}

#endif
