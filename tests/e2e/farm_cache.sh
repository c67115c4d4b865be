#!/bin/sh
# A second job with the same scene: the worker reports a cache hit and no
# scene bytes move (worker log and the master's bytes-sent summary).
. "$(dirname "$0")/farm_lib.inc"
start_worker a -j 1
local_render "$SCENE" "$T/local.ppm"
"$BIN/portray-master" "$SCENE" -o "$T/f1.ppm" -w "127.0.0.1:$a_PORT" --no-local 2>"$T/m1.log" || fail "first job failed"
"$BIN/portray-master" "$SCENE" -o "$T/f2.ppm" -w "127.0.0.1:$a_PORT" --no-local 2>"$T/m2.log" || fail "second job failed"
cmp "$T/local.ppm" "$T/f1.ppm" || fail "first image differs"
cmp "$T/local.ppm" "$T/f2.ppm" || fail "second image differs"
wait_count "$T/a.log" " job .* tiles in " 2 "worker a to log two jobs"
grep -q "scene cache miss" "$T/a.log" || fail "first job was not a cache miss"
grep "scene cache hit (0 scene bytes received)" "$T/a.log" >/dev/null || fail "second job was not a cache hit"
grep -q "cache miss" "$T/m1.log" || fail "master 1 did not report the miss"
grep -q "(scene 0 B, cache hit)" "$T/m2.log" || fail "master 2 sent scene bytes on a cache hit"
grep -q "bytes sent [0-9]* (scene 0," "$T/m2.log" || fail "master 2's total shows scene bytes"
# a changed scene is a different hash: a miss again
sed 's/radius 0.7/radius 0.6/' "$SCENE" >"$T/changed.sce"
"$BIN/portray-master" "$T/changed.sce" -o "$T/f3.ppm" -w "127.0.0.1:$a_PORT" --no-local 2>"$T/m3.log" || fail "third job failed"
wait_count "$T/a.log" " job .* tiles in " 3 "worker a to log three jobs"
[ "$(grep -c 'scene cache miss' "$T/a.log")" -eq 2 ] || fail "changed scene was not a miss"
# the cache is bounded (--cache-mb), least recently used out: two scenes of
# ~750 KB do not both fit in 1 MiB
start_worker small -j 1 --cache-mb 1
B1=tests/data/spd/balls_s4.sce
sed 's/radius 0.5 ;/radius 0.45 ;/' "$B1" >"$T/balls2.sce"
cmp -s "$B1" "$T/balls2.sce" && fail "could not make a second scene"
for s in "$B1" "$B1" "$T/balls2.sce" "$B1"; do
	"$BIN/portray-master" "$s" --size 32x24 -o "$T/b.ppm" -w "127.0.0.1:$small_PORT" --no-local -q ||
		fail "job on the small cache failed"
done
wait_count "$T/small.log" " job .* tiles in " 4 "the small worker to log four jobs"
grep -o 'cache [a-z]*' "$T/small.log" | tr '\n' ' ' >"$T/seq"
[ "$(cat "$T/seq")" = "cache miss cache hit cache miss cache miss " ] ||
	fail "LRU sequence wrong: $(cat "$T/seq")"
echo ok
