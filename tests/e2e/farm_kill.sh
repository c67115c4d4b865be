#!/bin/sh
# One worker SIGKILLed mid-render: its tiles go back to the queue, the image
# completes through the other worker and is identical to the local render.
. "$(dirname "$0")/farm_lib.inc"
# 25 ms per tile on top of tracing: the render lasts a few seconds whatever the load
start_worker a -j 1 --test-delay-ms 25
start_worker b -j 1 --test-delay-ms 25
local_render "$SCENE" "$T/local.ppm" --size 192x144
"$BIN/portray-master" "$SCENE" -o "$T/farm.ppm" --size 192x144 --tile 12 --no-local \
	-w "127.0.0.1:$a_PORT,127.0.0.1:$b_PORT" 2>"$T/m.log" &
M=$!
PIDS="$PIDS $M"
# a condition, not a fixed sleep: once a has its first tile it keeps tiles in
# flight until the queue runs dry (192 tiles of >= 25 ms on two -j 1 workers)
wait_for "$T/a.log" " job .*: started" "worker a to start its job"
kill -0 $M 2>/dev/null || fail "render ended before the kill: test too fast"
kill -KILL "$a_PID"
wait $M || fail "master failed after a worker was killed (exit $?)"
cmp "$T/local.ppm" "$T/farm.ppm" || fail "image differs after a worker was killed"
grep -q "worker 127.0.0.1:$a_PORT \(lost\|dropped\)" "$T/m.log" || fail "master did not report the lost worker"
grep -q " [1-9][0-9]* re-dispatched" "$T/m.log" || fail "no tile was re-dispatched"
echo ok
