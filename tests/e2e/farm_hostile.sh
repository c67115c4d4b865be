#!/bin/sh
# A scene that never finishes a pixel (tests/data/hostile/nested64.sce: 64
# nested defines of two overlapping instances each, 2^63 instances) cannot
# stall a farm:
#  1. on a worker, the master (--no-local, short heartbeat timeout) gives up
#     on the hung tile and exits 69; the worker abandons the tile within a
#     moment and serves the next job at once (a -j 1 worker: the next job
#     needs the very thread that traced the hostile tile);
#  2. SIGTERM to a worker tracing such a tile ends it within 1 s;
#  3. the master's own threads: SIGINT during a local render of it ends the
#     render within 1 s, exit 130, the (black) partial image written.
. "$(dirname "$0")/farm_lib.inc"
NESTED=$(cd "$E2E/../data/hostile" && pwd)/nested64.sce
[ -f "$NESTED" ] || fail "missing $NESTED"
"$BIN/portray-master" --check "$NESTED" >"$T/check.txt" 2>&1 || fail "--check of the nested scene failed"

# 1. the master gives up; the worker is free again
start_worker w -j 1
timeout 60 "$BIN/portray-master" "$NESTED" --size 16x12 --tile 16 -o "$T/n.ppm" --no-local \
	--heartbeat-timeout 0.5 -w "127.0.0.1:$w_PORT" 2>"$T/m1.log"
rc=$?
t_gone=$(now)
[ $rc -eq 69 ] || fail "hostile scene on a worker alone: exit $rc, expected 69"
grep -q "dropped: hung: no tile result" "$T/m1.log" || fail "the master did not say why it gave up"
local_render "$SCENE" "$T/local.ppm" --size 64x48
timeout 60 "$BIN/portray-master" "$SCENE" --size 64x48 -o "$T/next.ppm" --no-local --audit 0 \
	-w "127.0.0.1:$w_PORT" 2>"$T/m2.log" || fail "the next job on the same worker failed (exit $?)"
t_next=$(now)
cmp "$T/local.ppm" "$T/next.ppm" || fail "the next job's image differs"
echo "next job done $(elapsed "$t_gone" "$t_next") s after the master gave up"
within 5 "$t_gone" "$t_next" || fail "the worker was not free for the next job within 5 s"
wait_for "$T/w.log" "ended\|connection lost\|master silent" "the worker to log the abandoned job"

# 2. SIGTERM while tracing a hostile tile
start_worker v -j 1
timeout 60 "$BIN/portray-master" "$NESTED" --size 16x12 --tile 16 -o "$T/n2.ppm" --no-local \
	--heartbeat-timeout 30 -w "127.0.0.1:$v_PORT" 2>"$T/m3.log" &
M=$!
PIDS="$PIDS $M"
wait_for "$T/v.log" " job .*: started" "worker v to start the hostile tile"
sleep 0.3
t0=$(now)
kill -TERM "$v_PID"
wait_exit "$v_PID" 5 || fail "worker still running 5 s after SIGTERM"
echo "worker ended $(elapsed "$t0") s after SIGTERM"
within 1 "$t0" || fail "worker took more than 1 s to end after SIGTERM"
wait "$v_PID"
[ $? -eq 0 ] || fail "worker exit status after SIGTERM is not 0"
kill "$M" 2>/dev/null

# 3. the master's own threads, SIGINT
"$BIN/portray-master" "$NESTED" --size 16x12 -j 2 -o "$T/part.ppm" 2>"$T/m4.log" &
M=$!
PIDS="$PIDS $M"
sleep 1
kill -0 "$M" 2>/dev/null || fail "the local render of the hostile scene ended by itself"
t0=$(now)
kill -INT "$M"
wait_exit "$M" 5 || fail "master still running 5 s after SIGINT"
echo "master ended $(elapsed "$t0") s after SIGINT"
within 1 "$t0" || fail "master took more than 1 s to end after SIGINT"
wait "$M"
rc=$?
[ $rc -eq 130 ] || fail "master exit $rc after SIGINT, want 130"
[ -s "$T/part.ppm" ] || fail "no partial image written"
echo ok
