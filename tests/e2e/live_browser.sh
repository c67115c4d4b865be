#!/bin/sh
# A real browser on the live view: headless Chromium loads the page during a
# farm render; when the stream ends the page writes an FNV-1a hash of its
# canvas's RGB bytes into #result, read here with --dump-dom and compared
# with the written image's. Skipped (77) without chromium. The master
# lingers (--http-linger) in case the browser is slow to start; SIGINT ends
# the linger. Chromium runs under timeout: an endless stream would hang it.
. "$(dirname "$0")/farm_lib.inc"
LC=$TOOLS/liveclient
[ -x "$LC" ] || fail "no $LC (make test builds it)"
CHROMIUM=${CHROMIUM:-$(command -v chromium || command -v chromium-browser || command -v google-chrome)}
[ -n "$CHROMIUM" ] && [ -x "$CHROMIUM" ] || { echo "no chromium installed"; exit 77; }
start_pair

"$BIN/portray-master" "$SLOW" -o "$T/farm.ppm" -w "$W" --size 640x480 --tile 8 -j 1 --http 127.0.0.1:0 \
	--http-port-file "$T/http.port" --http-linger 60 2>"$T/master.log" &
M=$!
PIDS="$PIDS $M"
wait_port http $M
# a private profile; --virtual-time-budget lets the page's scripts and the
# stream run before the DOM is dumped (the open stream holds the budget)
timeout -k 5 120 "$CHROMIUM" --headless --no-sandbox --disable-gpu --hide-scrollbars --no-first-run \
	--user-data-dir="$T/profile" --window-size=1000,1000 --virtual-time-budget=60000 \
	--dump-dom "http://127.0.0.1:$http_PORT/" >"$T/dom.html" 2>"$T/chromium.log"
rc=$?
[ $rc -eq 0 ] || fail "chromium exited $rc"
kill -INT $M
wait $M
rc=$?
[ $rc -eq 0 ] || fail "the master exited $rc"
shown=$(sed -n 's/.*id="result">\([^<]*\)<.*/\1/p' "$T/dom.html")
echo "page: $shown"
want=$("$LC" hash "$T/farm.ppm") || fail "cannot hash the image"
echo "file: $want"
set -- $want
case "$shown" in
"shown $(echo "$1" | tr -d ' ') fnv1a $2 finished"*) ;;
*) fail "the page shows another image than the written one (page '$shown', file '$want')" ;;
esac
echo "ok"
