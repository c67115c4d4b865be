#!/bin/sh
# A worker that keeps heartbeating while a tracer never finishes a tile
# (--test-fault hang-tile: its third tile) is declared hung once it has held
# tiles for max(10 x its median tile time, 3 x the heartbeat timeout) without
# a result: dropped, its tiles re-dispatched. Alone with --no-local the
# master ends with exit 69 instead of waiting for ever.
. "$(dirname "$0")/farm_lib.inc"
start_worker hang -j 1 --test-fault hang-tile
# heartbeat timeout 3 s: deadline 9 s
timeout 120 "$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --no-local --heartbeat-timeout 3 \
	-w "127.0.0.1:$hang_PORT" 2>"$T/m1.log"
rc=$?
[ $rc -eq 69 ] || fail "a hung worker alone with --no-local: exit $rc, expected 69"
grep -q "worker 127.0.0.1:$hang_PORT dropped: hung: no tile result for [0-9.]* s while holding [0-9]* tiles" "$T/m1.log" ||
	fail "the hung worker was not reported"
grep -q "every worker is lost" "$T/m1.log" || fail "no word on why the render stopped"

# with an honest worker the render completes, identical to the local one
start_worker good -j 1 --test-delay-ms 10
start_worker hang2 -j 1 --test-fault hang-tile
local_render "$SCENE" "$T/local.ppm"
timeout 120 "$BIN/portray-master" "$SCENE" -o "$T/farm.ppm" --no-local --heartbeat-timeout 3 --tile 16 \
	-w "127.0.0.1:$hang2_PORT,127.0.0.1:$good_PORT" 2>"$T/m2.log" ||
	fail "render with a hung worker and an honest one failed (exit $?)"
cmp "$T/local.ppm" "$T/farm.ppm" || fail "image differs with a hung worker"
echo ok
