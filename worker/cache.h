/*
 * cache.h - portray-worker's scene cache: scenes by content hash and image
 * size, built once and shared by every job that offers them, kept after
 * their jobs while the --cache-mb budget allows (least recently used out
 * first).
 *
 * The cache belongs to the event loop thread: only it adds, looks up, counts
 * references and frees. The one exception is an entry being built: its
 * builder (a tracer thread, tracers.c) owns the fields marked so until it
 * hands the entry back through the tracers' done list, and reads the bytes,
 * which never change once the entry exists.
 */
#ifndef PORTRAY_WORKER_CACHE_H
#define PORTRAY_WORKER_CACHE_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "common/render.h"
#include "common/scene.h"
#include "proto/proto.h"

enum wk_entry_state {
	WK_ENTRY_BUILDING, /* queued for a tracer or being built: not freed meanwhile */
	WK_ENTRY_READY,    /* scene and renderer usable by any job */
	WK_ENTRY_FAILED    /* the bytes do not decode or build: error says why */
};

/* What a builder reports (build_result). */
enum { WK_BUILD_OK = 0, WK_BUILD_FAILED = -1, WK_BUILD_CANCELLED = -2 };

/* One scene at one image size. */
struct wk_entry {
	uint8_t hash[PROTO_HASH_BYTES];
	uint32_t w, h;
	uint8_t *bytes;           /* the encoded scene (kept so that another size can be built); immutable */
	size_t len;
	/* the builder's while BUILDING; read-only once READY */
	struct scene *scene;
	struct renderer *r;
	uint32_t build_ms;
	int build_result;         /* WK_BUILD_* */
	char error[sizeof((struct scene_error *)0)->msg];
	struct wk_entry *built_next; /* the tracers' done list */
	/* set when no connection wants the entry any more, or at shutdown: the
	 * build is abandoned (checked between its steps) */
	atomic_int cancel;
	/* event loop only */
	enum wk_entry_state state;
	int refs;                 /* connections and jobs using it */
	double last_used;
	struct wk_entry *next;
};

struct wk_cache {
	struct wk_entry *head;
	uint64_t used;            /* encoded bytes held by every entry */
	uint64_t budget;          /* --cache-mb */
};

void wk_cache_init(struct wk_cache *c, uint64_t budget);
/* Frees every entry, whatever its state (the tracers must have stopped). */
void wk_cache_free(struct wk_cache *c);

/*
 * The entry for (hash, w, h) with a new reference (*exact = true), or else
 * an entry holding the same bytes at another size, without a reference
 * (*exact = false), or NULL. Failed entries are skipped. An entry still
 * building whose build was cancelled is wanted again: its cancel is cleared
 * (tracers.c builds it again should the build have given up already).
 */
struct wk_entry *wk_cache_find(struct wk_cache *c, const uint8_t *hash, uint32_t w, uint32_t h, bool *exact);
/*
 * A new BUILDING entry owning bytes (taken, even on failure), with one
 * reference, added to the cache. NULL when out of memory.
 */
struct wk_entry *wk_cache_add(struct wk_cache *c, const uint8_t *hash, uint32_t w, uint32_t h, uint8_t *bytes,
			      size_t len);
/* One user less. The last one of an entry being built cancels its build. */
void wk_cache_unref(struct wk_cache *c, struct wk_entry *e);
/* A build came back: the entry becomes READY or FAILED. */
void wk_cache_built(struct wk_cache *c, struct wk_entry *e, bool ok);
/*
 * Frees unused failed entries, then unused ready ones least recently used
 * first until the budget holds. Entries in use or building stay.
 */
void wk_cache_trim(struct wk_cache *c);
/* Cancels every build (shutdown). */
void wk_cache_cancel_all(struct wk_cache *c);

#endif
