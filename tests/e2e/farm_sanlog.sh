#!/bin/sh
# farm_lib.inc's cleanup fails a test whose logs hold a sanitizer report (a
# background worker's, which the master would only drop), whatever the test
# itself found, and leaves a test with clean logs as it was.
E2E=$(cd "$(dirname "$0")" && pwd)
for report in "w.c:1:1: runtime error: signed integer overflow" "==1==ERROR: AddressSanitizer: heap-use-after-free" \
	"==1==ERROR: LeakSanitizer: detected memory leaks"; do
	(. "$E2E/farm_lib.inc" && echo "$report" >"$T/w.log" && exit 0) >/dev/null 2>&1
	rc=$?
	[ $rc -eq 1 ] || { echo "FAIL: a log with '$report' left the test's status $rc"; exit 1; }
done
(. "$E2E/farm_lib.inc" && echo "portray-worker: listening" >"$T/w.log" && exit 0) >/dev/null 2>&1
rc=$?
[ $rc -eq 0 ] || { echo "FAIL: a clean log made the test's status $rc"; exit 1; }
(. "$E2E/farm_lib.inc" && exit 77) >/dev/null 2>&1
rc=$?
[ $rc -eq 77 ] || { echo "FAIL: a skip became status $rc"; exit 1; }
echo ok
