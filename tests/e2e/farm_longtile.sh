#!/bin/sh
# Heartbeat intervals are agreed at the handshake, so any --heartbeat-timeout
# works with tiles of any length: with --heartbeat-timeout 300 (heartbeats
# every 75 s) a tile that takes 70 s completes without a retry. (Before
# protocol 2 the worker clamped the interval to 10 s and dropped a master
# silent for 65 s.) Takes 70 s by design.
. "$(dirname "$0")/farm_lib.inc"
start_worker w -j 1 --test-delay-ms 70000
local_render "$SCENE" "$T/local.ppm" --size 16x12
timeout 200 "$BIN/portray-master" "$SCENE" --size 16x12 --tile 16 -o "$T/farm.ppm" --no-local --audit 0 \
	--heartbeat-timeout 300 -w "127.0.0.1:$w_PORT" 2>"$T/m.log" || fail "the 70 s tile's render failed (exit $?)"
cmp "$T/local.ppm" "$T/farm.ppm" || fail "image differs"
grep -q "lost\|retry\|dropped" "$T/m.log" && fail "the master lost the worker during a 70 s tile"
grep -q "127.0.0.1:$w_PORT *1 tiles" "$T/m.log" || fail "the worker did not deliver the tile"
grep -q "silent" "$T/w.log" && fail "the worker dropped the master during a 70 s tile"
echo ok
