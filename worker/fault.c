/*
 * fault.c - the --test-fault and --test-delay-ms hooks (fault.h).
 */
#include "worker/fault.h"

#include <stdio.h>
#include <string.h>
#include <time.h>

static const struct {
	const char *name;
	enum wk_fault kind;
} fault_names[] = {
	{ "bad-checksum", FAULT_BAD_CHECKSUM }, { "wrong-size", FAULT_WRONG_SIZE },
	{ "proto-version", FAULT_PROTO_VERSION }, { "build-id", FAULT_BUILD },
	{ "black", FAULT_BLACK }, { "trace-fail", FAULT_TRACE_FAIL },
	{ "lie", FAULT_LIE }, { "hang-tile", FAULT_HANG_TILE }, { "probe", FAULT_PROBE },
};

int wk_fault_parse(const char *name, enum wk_fault *out)
{
	for (size_t i = 0; i < sizeof fault_names / sizeof fault_names[0]; i++)
		if (strcmp(name, fault_names[i].name) == 0) {
			*out = fault_names[i].kind;
			return 0;
		}
	return -1;
}

uint32_t wk_fault_version(const struct wk_faults *f)
{
	return f->kind == FAULT_PROTO_VERSION ? PROTO_VERSION + 1 : PROTO_VERSION;
}

void wk_fault_build_id(const struct wk_faults *f, char *out, size_t n)
{
	const char *id = proto_build_id(), *probe = strstr(id, "/probe-");
	int compat = probe ? (int)(probe - id) : (int)strlen(id);
	if (f->kind == FAULT_BUILD) /* another pixel revision: "pixels-N-other" */
		snprintf(out, n, "%.*s-other%s", compat, id, id + compat);
	else if (f->kind == FAULT_PROBE) /* the probe's last digit changed */
		snprintf(out, n, "%.*s%c", (int)strlen(id) - 1, id, id[strlen(id) - 1] == '0' ? '1' : '0');
	else
		snprintf(out, n, "%s", id);
}

static bool cancelled(atomic_int *cancel)
{
	return cancel && atomic_load_explicit(cancel, memory_order_relaxed);
}

int wk_sleep_cancellable(int ms, atomic_int *cancel)
{
	while (ms > 0) {
		if (cancelled(cancel))
			return 0;
		int step = ms < WK_SLEEP_STEP_MS ? ms : WK_SLEEP_STEP_MS;
		struct timespec ts = { 0, (long)step * 1000000L };
		nanosleep(&ts, NULL);
		ms -= step;
	}
	return !cancelled(cancel);
}

int wk_fault_traced(struct wk_faults *f, uint8_t *px, int ok, atomic_int *cancel)
{
	if (ok != 1)
		return ok;
	if (f->kind == FAULT_TRACE_FAIL)
		return -1;
	if (f->kind == FAULT_LIE || f->kind == FAULT_HANG_TILE) {
		unsigned nth = atomic_fetch_add(&f->traced, 1) + 1;
		if (f->kind == FAULT_LIE && nth % WK_LIE_EVERY == 2 % WK_LIE_EVERY)
			px[0] ^= 1; /* the checksum is computed after this, over it */
		if (f->kind == FAULT_HANG_TILE && nth == WK_HANG_AT) {
			while (wk_sleep_cancellable(WK_SLEEP_STEP_MS, cancel))
				;
			return 0;
		}
	}
	if (f->delay_ms > 0 && !wk_sleep_cancellable(f->delay_ms, cancel))
		return 0;
	return ok;
}

void wk_fault_result(const struct wk_faults *f, struct proto_tile *t, uint32_t *crc)
{
	if (f->kind == FAULT_BAD_CHECKSUM)
		*crc ^= 0x5a5a5a5au;
	if (f->kind == FAULT_WRONG_SIZE && t->w > 1)
		t->w -= 1; /* the pixels then match the smaller rectangle */
}
