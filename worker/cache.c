/*
 * cache.c - the scene cache (cache.h).
 */
#include "worker/cache.h"

#include <stdlib.h>
#include <string.h>

#include "proto/net.h"

void wk_cache_init(struct wk_cache *c, uint64_t budget)
{
	memset(c, 0, sizeof *c);
	c->budget = budget;
}

static void entry_free(struct wk_entry *e)
{
	renderer_free(e->r);
	scene_free(e->scene);
	free(e->bytes);
	free(e);
}

void wk_cache_free(struct wk_cache *c)
{
	while (c->head) {
		struct wk_entry *e = c->head;
		c->head = e->next;
		entry_free(e);
	}
	c->used = 0;
}

struct wk_entry *wk_cache_find(struct wk_cache *c, const uint8_t *hash, uint32_t w, uint32_t h, bool *exact)
{
	struct wk_entry *same_hash = NULL;
	*exact = false;
	for (struct wk_entry *e = c->head; e; e = e->next) {
		if (e->state == WK_ENTRY_FAILED || memcmp(e->hash, hash, PROTO_HASH_BYTES) != 0)
			continue;
		if (e->w == w && e->h == h) {
			*exact = true;
			e->refs++;
			e->last_used = net_now();
			atomic_store(&e->cancel, 0);
			return e;
		}
		same_hash = e;
	}
	return same_hash;
}

struct wk_entry *wk_cache_add(struct wk_cache *c, const uint8_t *hash, uint32_t w, uint32_t h, uint8_t *bytes,
			      size_t len)
{
	struct wk_entry *e = calloc(1, sizeof *e);
	if (!e) {
		free(bytes);
		return NULL;
	}
	memcpy(e->hash, hash, PROTO_HASH_BYTES);
	e->w = w;
	e->h = h;
	e->bytes = bytes;
	e->len = len;
	atomic_init(&e->cancel, 0);
	e->state = WK_ENTRY_BUILDING;
	e->refs = 1;
	e->last_used = net_now();
	e->next = c->head;
	c->head = e;
	c->used += len;
	return e;
}

void wk_cache_unref(struct wk_cache *c, struct wk_entry *e)
{
	(void)c;
	if (--e->refs == 0 && e->state == WK_ENTRY_BUILDING)
		atomic_store(&e->cancel, 1); /* nobody waits for it: free the tracer */
	e->last_used = net_now();
}

void wk_cache_built(struct wk_cache *c, struct wk_entry *e, bool ok)
{
	(void)c;
	e->state = ok ? WK_ENTRY_READY : WK_ENTRY_FAILED;
}

void wk_cache_trim(struct wk_cache *c)
{
	for (;;) {
		struct wk_entry **victim = NULL;
		for (struct wk_entry **pp = &c->head; *pp; pp = &(*pp)->next) {
			struct wk_entry *e = *pp;
			if (e->refs != 0 || e->state == WK_ENTRY_BUILDING)
				continue;
			if (e->state == WK_ENTRY_FAILED) {
				victim = pp;
				break;
			}
			if (c->used > c->budget && (!victim || e->last_used < (*victim)->last_used))
				victim = pp;
		}
		if (!victim)
			break;
		struct wk_entry *e = *victim;
		*victim = e->next;
		c->used -= e->len;
		entry_free(e);
	}
}

void wk_cache_cancel_all(struct wk_cache *c)
{
	for (struct wk_entry *e = c->head; e; e = e->next)
		atomic_store(&e->cancel, 1);
}
