#!/bin/sh
# Fake workers that return a tile with a bad checksum or of the wrong size:
# the tile is re-dispatched, the worker dropped, the image identical.
# A worker that fails to trace its tiles.
. "$(dirname "$0")/farm_lib.inc"
# the good worker takes 20 ms a tile, about 0.6 s for all 30: time for the
# faulty ones to start and get tiles even in a sanitizer build (where,
# without it, the wrong-size worker got none and went unnoticed)
start_worker good -j 1 --test-delay-ms 20
start_worker badsum -j 1 --test-fault bad-checksum
start_worker badsize -j 1 --test-fault wrong-size
local_render "$SCENE" "$T/local.ppm"
"$BIN/portray-master" "$SCENE" -o "$T/farm.ppm" --no-local --tile 16 \
	-w "127.0.0.1:$badsum_PORT,127.0.0.1:$badsize_PORT,127.0.0.1:$good_PORT" 2>"$T/m.log" ||
	fail "farm render with faulty workers failed (exit $?)"
cmp "$T/local.ppm" "$T/farm.ppm" || fail "image differs with faulty workers"
grep -q "worker 127.0.0.1:$badsum_PORT dropped: tile [0-9]* failed its checksum" "$T/m.log" ||
	fail "bad checksum not detected"
grep -q "worker 127.0.0.1:$badsize_PORT dropped: tile [0-9]* came back as 15x16" "$T/m.log" ||
	fail "wrong-sized tile not detected"
grep -q " [1-9][0-9]* re-dispatched, .* 2 invalid results" "$T/m.log" || fail "summary does not show the re-dispatch"
grep -q "^portray-master:   127.0.0.1:$badsum_PORT  *0 tiles" "$T/m.log" || fail "a bad tile was counted"
# the workers were told why
wait_for "$T/badsum.log" "peer says: tile [0-9]* failed its checksum" "the faulty worker to be told"

# a worker that cannot trace a tile (out of memory) says so instead of
# dropping it: the master retries, then gives up (--no-local: exit 69)
# rather than waiting for the tile for ever; with local threads it completes
start_worker oom -j 1 --test-fault trace-fail
timeout 120 "$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --no-local -w "127.0.0.1:$oom_PORT" 2>"$T/m2.log"
rc=$?
[ $rc -eq 69 ] || fail "worker failing every tile: exit $rc, expected 69"
grep -q "out of memory tracing a tile" "$T/m2.log" || fail "the master did not report the worker's failure"
"$BIN/portray-master" "$SCENE" -o "$T/l.ppm" -j 1 -w "127.0.0.1:$oom_PORT" 2>"$T/m3.log" ||
	fail "render with a failing worker and local threads failed"
cmp "$T/local.ppm" "$T/l.ppm" || fail "image differs with a failing worker"
echo ok
