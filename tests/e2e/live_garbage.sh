#!/bin/sh
# 50 bad or odd requests to the live view during a farm render (random
# bytes, a header over the limit, bad methods, malformed lines, unknown
# paths, a foreign Host, requests left half sent, a slow-loris trickle, a
# viewer that reads nothing, one gone mid-stream): each gets its HTTP error
# (or is closed), good requests are still answered meanwhile, the unfinished
# requests are closed after their deadline, the master stays alive, and the
# image equals a render without --http. --http-linger keeps it serving
# while the tool holds its connections; Ctrl-C (SIGINT) ends the linger.
. "$(dirname "$0")/farm_lib.inc"
LC=$TOOLS/liveclient
[ -x "$LC" ] || fail "no $LC (make test builds it)"
start_pair
OPTS="--size 480x360 --tile 8 -j 1"
local_render "$SLOW" "$T/ref.ppm" $OPTS

"$BIN/portray-master" "$SLOW" -o "$T/farm.ppm" -w "$W" $OPTS --http 127.0.0.1:0 \
	--http-port-file "$T/http.port" --http-linger 60 2>"$T/master.log" &
M=$!
PIDS="$PIDS $M"
wait_port http $M
# held past the 10 s request deadline: the tool checks they were closed
"$LC" garbage "$http_PORT" 50 --hold 11 --seed 12345 >"$T/garbage.out" 2>&1
rc=$?
cat "$T/garbage.out"
[ $rc -eq 0 ] || fail "wrong answers to bad requests"
kill -0 $M 2>/dev/null || fail "the master died"
wait_for "$T/master.log" "serving the finished image" "the render to end"
kill -INT $M
wait $M
rc=$?
[ $rc -eq 0 ] || fail "the master exited $rc"
cmp "$T/ref.ppm" "$T/farm.ppm" || fail "the image differs from a render without --http"
echo "ok"
