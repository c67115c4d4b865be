/*
 * parse.h - the PortRAY scene language: lexer and parser (common/lex.c,
 * common/parse.c). The parser never renders anything; it hands each statement
 * to the scene builder (scene.h).
 */
#ifndef PORTRAY_PARSE_H
#define PORTRAY_PARSE_H

#include <stddef.h>

#include "common/scene.h"

/*
 * Loads an optional camera file (camera, image and light statements only)
 * and a scene file (everything), following includes and RAW files relative
 * to the including file. camera_path may be NULL. On error returns the
 * Appendix B level, fills err ("file:line:col: error: ...") and *out is NULL.
 * On success *out is a new scene (caller frees with scene_free).
 */
int parse_files(const char *camera_path, const char *scene_path, struct scene **out,
		struct scene_error *err);

/*
 * Parses scene text from memory (name is used in messages). Includes and RAW
 * files are refused (an error) unless allow_files; for fuzzing and tests.
 */
int parse_buffer(const char *name, const char *text, size_t len, int allow_files,
		 struct scene **out, struct scene_error *err);

#endif
