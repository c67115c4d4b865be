#!/bin/sh
# bench/examples.sh - render time of every example scene at its own size,
# on one thread and on all threads (wall-clock seconds, best of one run).
M=bin/portray-master
OUT=${TMPDIR:-/tmp}/portray-bench-examples.$$
mkdir -p "$OUT" || exit 1
now() { date +%s.%N; }
printf '%-10s %10s %10s\n' example "-j 1 (s)" "all (s)"
for n in exam_001 exam_002 exam_003 exam_004 exam_005 exam_006 exam_007 bgammon dice mats1 mats2; do
	t0=$(now)
	$M -q -j 1 -o "$OUT/$n.ppm" "examples/$n.sce" || { echo "$n: render failed"; continue; }
	t1=$(now)
	$M -q -o "$OUT/$n.ppm" "examples/$n.sce" || { echo "$n: render failed"; continue; }
	t2=$(now)
	awk -v n="$n" -v a="$t0" -v b="$t1" -v c="$t2" 'BEGIN { printf "%-10s %10.2f %10.2f\n", n, b - a, c - b }'
done
rm -rf "$OUT"
