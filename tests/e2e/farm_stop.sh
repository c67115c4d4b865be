#!/bin/sh
# One worker SIGSTOPped past the heartbeat deadline: the master drops its
# connection and re-queues its tiles; the image completes and is identical.
# After SIGCONT its late results are ignored: the connection they would
# travel on is closed, and the worker logs that its job was cut off.
. "$(dirname "$0")/farm_lib.inc"
start_worker a -j 1 --test-delay-ms 25
start_worker b -j 1 --test-delay-ms 25
local_render "$SCENE" "$T/local.ppm" --size 192x144
"$BIN/portray-master" "$SCENE" -o "$T/farm.ppm" --size 192x144 --tile 12 --no-local \
	--heartbeat-timeout 1 -w "127.0.0.1:$a_PORT,127.0.0.1:$b_PORT" 2>"$T/m.log" &
M=$!
PIDS="$PIDS $M"
wait_for "$T/a.log" " job .*: started" "worker a to start its job"
kill -0 $M 2>/dev/null || fail "render ended before the stop: test too fast"
kill -STOP "$a_PID"
# wait for the deadline to pass, then continue the worker while the render goes on
wait_for "$T/m.log" "no heartbeat" "the master to notice the stopped worker"

kill -0 $M 2>/dev/null || fail "render ended before the worker was continued"
kill -CONT "$a_PID"
wait $M || fail "master failed (exit $?)"
cmp "$T/local.ppm" "$T/farm.ppm" || fail "image differs after a stopped worker"
grep -q "worker 127.0.0.1:$a_PORT lost: no heartbeat" "$T/m.log" || fail "master did not report the heartbeat loss"
grep -q " 0 invalid results" "$T/m.log" || fail "late results were taken as invalid"
# the continued worker found its old connection gone (or reset)
wait_for "$T/a.log" "job .*: [0-9]* tiles in .*\(connection\|reset\|Broken\)" "worker a to log the end of its cut-off job"
kill -0 "$a_PID" || fail "worker a died"
echo ok
