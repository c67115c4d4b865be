#!/bin/sh
# 300 idle TCP connections held open (and reopened when closed) against a
# worker with a secret cannot lock a real master out: connections that have
# not authenticated have their own, smaller budget, and the oldest of them
# is evicted to admit a new one.
. "$(dirname "$0")/farm_lib.inc"
[ -x "$TOOLS/fakepeer" ] || fail "missing $TOOLS/fakepeer (make test builds it)"
printf 'flood test secret\n' >"$T/secret"
chmod 600 "$T/secret"
start_worker w -j 1 --secret-file "$T/secret"
"$TOOLS/fakepeer" hold --to "127.0.0.1:$w_PORT" --count 300 2>"$T/hold.log" &
PIDS="$PIDS $!"
# the flood is on once the worker has had to evict (its budget for
# unauthenticated connections is far below 300) and the holder reconnects
wait_for "$T/w.log" "evicted: too many unauthenticated" "the worker to evict idle connections" 30
wait_for "$T/hold.log" "again in" "the holder to reconnect evicted connections" 30
local_render "$SCENE" "$T/local.ppm" --size 64x48
timeout 60 "$BIN/portray-master" "$SCENE" --size 64x48 -o "$T/farm.ppm" --no-local --secret-file "$T/secret" \
	-w "127.0.0.1:$w_PORT" 2>"$T/m.log" || fail "the master could not render past 300 idle connections (exit $?)"
cmp "$T/local.ppm" "$T/farm.ppm" || fail "image differs"
# and again, while the flood keeps reconnecting
timeout 60 "$BIN/portray-master" "$SCENE" --size 64x48 -o "$T/farm2.ppm" --no-local --secret-file "$T/secret" \
	-w "127.0.0.1:$w_PORT" 2>"$T/m2.log" || fail "the second render failed (exit $?)"
cmp "$T/local.ppm" "$T/farm2.ppm" || fail "second image differs"
kill -0 "$w_PID" || fail "the worker died under the flood"
echo "$(grep -c 'again in' "$T/hold.log") connections reopened by the holder meanwhile"


# the same against a master taking workers that dial in (--accept): idle
# connections fill its room for them, the oldest silent one is evicted for
# each newcomer, and a real worker dialling in renders the image
P=$(free_port)
"$BIN/portray-master" "$SCENE" --size 64x48 -o "$T/farm3.ppm" --no-local --secret-file "$T/secret" \
	--accept "127.0.0.1:$P" --heartbeat-timeout 30 2>"$T/m3.log" &
M=$!
PIDS="$PIDS $M"
wait_for "$T/m3.log" "accepting workers" "the master to accept"
"$TOOLS/fakepeer" hold --to "127.0.0.1:$P" --count 300 2>"$T/hold3.log" &
PIDS="$PIDS $!"
wait_for "$T/hold3.log" "again in" "the master to evict idle connections" 30
start_dialer real "127.0.0.1:$P" -j 1 --secret-file "$T/secret"
timeout 60 sh -c "wait $M" 2>/dev/null
wait $M || fail "the master taking dial-ins could not render past 300 idle connections (exit $?)"
cmp "$T/local.ppm" "$T/farm3.ppm" || fail "image differs (--accept)"
grep -q "evicted to make room" "$T/m3.log" || fail "the master did not say it evicted idle connections"
[ "$(wc -l <"$T/m3.log")" -lt 200 ] || fail "the master's log grew to $(wc -l <"$T/m3.log") lines under the flood"
echo "ok   --accept: $(grep 'evicted to make room' "$T/m3.log" | sed 's/^portray-master: farm: //')"
echo ok
