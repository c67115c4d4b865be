#!/bin/sh
# bench/ab.sh - two portray-master builds on one scene, alternating: the
# way docs/performance.md measures a change (rounds 14 to 19). A and B run
# in turn N times each (default 7), 1 thread, 1280x960, quiet; each run's
# CPU time of the whole process comes from `perf stat -e task-clock`, and
# the best of each and B/A are printed. Alternating cancels most of the
# machine's drift; readings within 1% are still noise on a shared VM.
#
#   A=/path/to/old/portray-master B=bin/portray-master sh bench/ab.sh SCENE [N]
#
# `make bench` runs every script: with A or B unset this one only says so.
# Nothing here is a test.
if [ -z "${A:-}" ] || [ -z "${B:-}" ] || [ -z "${1:-}" ]; then
	echo "A, B or SCENE not set: skipped (A=old/portray-master B=new/portray-master sh bench/ab.sh SCENE [N])"
	exit 0
fi
if ! command -v perf >/dev/null 2>&1; then
	echo "perf not installed: skipped"
	exit 0
fi
SCENE=$1
N=${2:-7}
SIZE=${AB_SIZE:-1280x960}
TMP=$(mktemp -d "${TMPDIR:-/tmp}/portray-ab.XXXXXX")
trap 'rm -rf "$TMP"' EXIT

# run BIN NAME: one render's task-clock in whole milliseconds, or nothing
run() {
	perf stat -x, -e task-clock "$1" -q -j 1 --size "$SIZE" -o "$TMP/$2.png" "$SCENE" 2>&1 >/dev/null |
		awk -F, '$3 == "task-clock" { printf "%d\n", $1 }'
}

best_a=
best_b=
i=0
while [ "$i" -lt "$N" ]; do
	a=$(run "$A" a)
	b=$(run "$B" b)
	if [ -z "$a" ] || [ -z "$b" ]; then
		echo "ab: a run failed (A '$A', B '$B', scene '$SCENE')"
		exit 1
	fi
	if [ -z "$best_a" ] || [ "$a" -lt "$best_a" ]; then best_a=$a; fi
	if [ -z "$best_b" ] || [ "$b" -lt "$best_b" ]; then best_b=$b; fi
	i=$((i + 1))
done
cmp -s "$TMP/a.png" "$TMP/b.png" && same="the same image" || same="images differ"
awk -v a="$best_a" -v b="$best_b" -v n="$N" -v s="$SCENE" -v same="$same" \
	'BEGIN { printf "%s: A %d ms, B %d ms (best of %d each, alternating): B/A %.4f; %s\n", s, a, b, n, b / a, same }'
