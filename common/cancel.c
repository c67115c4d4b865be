/*
 * cancel.c - the calling thread's cancel scope (cancel.h).
 */
#include "common/cancel.h"

/* Never written: cancel_never stays 0 and cancel_always 1. */
atomic_int cancel_never = 0, cancel_always = 1;

/* Every thread starts outside any scope: polls read cancel_never. */
_Thread_local struct cancel_scope cancel_cur = { &cancel_never };

void cancel_enter(atomic_int *flag, struct cancel_scope *saved)
{
	*saved = cancel_cur;
	cancel_cur.flag = flag ? flag : &cancel_never;
}

void cancel_leave(const struct cancel_scope *saved) { cancel_cur = *saved; }

bool cancel_note(void)
{
	cancel_cur.flag = &cancel_always; /* sticky, whatever the owner does next */
	return true;
}
