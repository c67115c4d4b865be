#!/bin/sh
# The live view (--http) of a farm render, master + two workers: the page
# and /status are served, a viewer that follows the tile stream from the
# start and one that connects halfway both rebuild an image equal to the
# written file, and a slow viewer (reading 200 kB/s for a while) does too;
# a 17th viewer is refused (503) while 16 that read nothing hold their slots;
# a render stopped by SIGINT ends the stream saying so, with the partial image.
# Plus the option checks: beyond loopback, a bad address or a companion
# option without --http is refused at once (64).
. "$(dirname "$0")/farm_lib.inc"
LC=$TOOLS/liveclient
[ -x "$LC" ] || fail "no $LC (make test builds it)"

# refused at once, before any parsing: no scene file needed
for bad in "--http 0.0.0.0:0" "--http 192.0.2.1:8080" "--http nonsense" "--http-linger 3" \
	"--http-port-file $T/x" "--http 127.0.0.1:0 --http-linger -1"; do
	# shellcheck disable=SC2086
	"$BIN/portray-master" /nonexistent.sce $bad 2>"$T/bad.err"
	rc=$?
	[ $rc -eq 64 ] || fail "'$bad' gave exit $rc, not 64"
done
grep -q "http-public" "$T/bad.err" || true
"$BIN/portray-master" /nonexistent.sce --http 0.0.0.0:0 2>"$T/bad.err"
grep -q -- "--http-public" "$T/bad.err" || fail "the refusal does not name --http-public: $(cat "$T/bad.err")"

start_pair
# slow enough (16 samples a pixel, 8-pixel tiles) that viewers join in time
OPTS="--size 640x480 --tile 8 -j 1"

"$BIN/portray-master" "$SLOW" -o "$T/farm.ppm" -w "$W" $OPTS --http 127.0.0.1:0 \
	--http-port-file "$T/http.port" 2>"$T/master.log" &
M=$!
PIDS="$PIDS $M"
wait_port http $M
"$LC" stream "$http_PORT" "$T/v1.ppm" >"$T/v1.out" 2>"$T/v1.log" &
V1=$!
"$LC" stream "$http_PORT" "$T/v2.ppm" --after 0.5 >"$T/v2.out" 2>"$T/v2.log" &
V2=$!
"$LC" stream "$http_PORT" "$T/v3.ppm" --slow-for 3 >"$T/v3.out" 2>"$T/v3.log" &
V3=$!
"$LC" get "$http_PORT" / >"$T/page" || fail "GET / failed"
"$LC" get "$http_PORT" /status >"$T/status" || fail "GET /status failed"
"$LC" get "$http_PORT" / HEAD >"$T/head" || fail "HEAD / failed"
wait $M || fail "the master failed ($?)"
wait $V1 || fail "viewer 1 (from the start) failed: $(cat "$T/v1.log")"
wait $V2 || fail "viewer 2 (halfway) failed: $(cat "$T/v2.log")"
wait $V3 || fail "viewer 3 (slow) failed: $(cat "$T/v3.log")"

grep -q "live view on http://127.0.0.1:$http_PORT/" "$T/master.log" || fail "the URL is not logged"
head -n 1 "$T/page" | grep -q "^HTTP/1.1 200" || fail "GET / is not 200"
grep -q "<canvas" "$T/page" || fail "the page has no canvas"
grep -q "EventSource" "$T/page" || fail "the page does not follow the stream"
# self-contained: nothing fetched from elsewhere
grep -Eiq '(src|href)="?(https?:)?//' "$T/page" && fail "the page loads something from elsewhere"
grep -q '"workers":\[{"name":"local"' "$T/status" || fail "/status has no farm table: $(cat "$T/status")"
grep -q "\"name\":\"127.0.0.1:$a_PORT\"" "$T/status" || fail "/status does not list worker a"
grep -q "^Content-Length: [1-9]" "$T/head" || fail "HEAD / has no length"
grep -q "<canvas" "$T/head" && fail "HEAD / sent a body"

for v in v1 v2 v3; do
	cmp "$T/farm.ppm" "$T/$v.ppm" || fail "viewer $v rebuilt another image than the written one"
	cat "$T/$v.out"
done
# viewer 2 joined halfway: half the tiles were done already, and it still got all
awk '{ if (!($8 > 0 && $8 < $10)) exit 1 }' "$T/v2.out" ||
	fail "viewer 2 did not join during the render: $(cat "$T/v2.out")"
grep -q '"stopped":false' "$T/v1.log" || fail "the end event does not say finished"

# a render stopped by Ctrl-C (SIGINT): the stream ends saying so, and the
# viewer's image is the partial one written (the rest black)
"$BIN/portray-master" "$SLOW" -o "$T/part.ppm" $OPTS --http 127.0.0.1:0 --http-port-file "$T/h3.port" \
	2>"$T/master3.log" &
M=$!
PIDS="$PIDS $M"
wait_port h3 $M
"$LC" stream "$h3_PORT" "$T/v4.ppm" >"$T/v4.out" 2>"$T/v4.log" &
V4=$!
wait_for "$T/v4.log" "streaming" "viewer 4 to join"
kill -INT $M
wait $M
rc=$?
[ $rc -eq 130 ] || fail "the master stopped by SIGINT exited $rc, not 130"
wait $V4 || fail "viewer 4 (stopped render) failed: $(cat "$T/v4.log")"
grep -q '"stopped":true' "$T/v4.log" || fail "the end event of a stopped render does not say so"
cmp "$T/part.ppm" "$T/v4.ppm" || fail "the viewer's image differs from the partial file"

# at most 16 viewers: 16 that read nothing hold their slots, a 17th gets 503,
# one leaving makes room; and the render goes on regardless
"$BIN/portray-master" "$SLOW" -o "$T/local.ppm" $OPTS --http 127.0.0.1:0 --http-port-file "$T/h2.port" \
	2>"$T/master2.log" &
M=$!
PIDS="$PIDS $M"
wait_port h2 $M
"$LC" viewers "$h2_PORT" 16 || fail "the viewer limit"
wait $M || fail "the master with 16 viewers failed"
cmp "$T/farm.ppm" "$T/local.ppm" || fail "the local render with 16 stuck viewers differs"
echo "ok"
