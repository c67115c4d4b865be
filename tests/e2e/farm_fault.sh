#!/bin/sh
# Fake workers that return a tile with a bad checksum or of the wrong size:
# the tile is re-dispatched, the worker dropped, the image identical.
. "$(dirname "$0")/farm_lib.inc"
start_worker good -j 1
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
echo ok
