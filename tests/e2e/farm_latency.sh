#!/bin/sh
# Through the project's TCP delay proxy (tests/tools/delayproxy.c; this
# kernel may have no netem) at 20 ms one-way, a master and two workers give
# the local image byte for byte, with and without local threads, with a
# secret and without: the pipelined handshake and the latency-sized window
# change the timing of everything and the pixels of nothing.
. "$(dirname "$0")/farm_lib.inc"
[ -x "$TOOLS/delayproxy" ] || fail "missing $TOOLS/delayproxy (make test builds it)"
printf 'latency test secret\n' >"$T/secret"
chmod 600 "$T/secret"
start_worker a -j 1
start_worker b -j 1 --secret-file "$T/secret"
start_worker c -j 1 --secret-file "$T/secret"
# proxy NAME TARGET_PORT: sets NAME_PORT
proxy() {
	"$TOOLS/delayproxy" --listen 127.0.0.1:0 --port-file "$T/$1.port" --to "127.0.0.1:$2" --delay-ms 20 \
		2>"$T/$1.log" &
	PIDS="$PIDS $!"
	i=0
	while [ ! -s "$T/$1.port" ]; do
		i=$((i + 1))
		[ $i -gt 600 ] && fail "proxy $1 did not start"
		sleep 0.05
	done
	eval "${1}_PORT=$(cat "$T/$1.port")"
}
proxy pa "$a_PORT"
proxy pb "$b_PORT"
proxy pc "$c_PORT"
local_render "$SCENE" "$T/local.ppm" --size 160x120
t0=$(now)
timeout 120 "$BIN/portray-master" "$SCENE" --size 160x120 --tile 16 -o "$T/f1.ppm" --no-local \
	-w "127.0.0.1:$pa_PORT" 2>"$T/m1.log" || fail "render through the proxy failed (exit $?)"
echo "one worker, 20 ms one-way, no secret: $(elapsed "$t0") s"
cmp "$T/local.ppm" "$T/f1.ppm" || fail "image through the proxy differs"
t0=$(now)
timeout 120 "$BIN/portray-master" "$SCENE" --size 160x120 --tile 8 -o "$T/f2.ppm" --no-local \
	--secret-file "$T/secret" -w "127.0.0.1:$pb_PORT,127.0.0.1:$pc_PORT" 2>"$T/m2.log" ||
	fail "render through two proxies with a secret failed (exit $?)"
echo "two workers, 20 ms one-way, secret: $(elapsed "$t0") s"
cmp "$T/local.ppm" "$T/f2.ppm" || fail "image through two proxies differs"
timeout 120 "$BIN/portray-master" "$SCENE" --size 160x120 --tile 8 -o "$T/f3.ppm" -j 1 \
	--secret-file "$T/secret" -w "127.0.0.1:$pb_PORT,127.0.0.1:$pc_PORT" 2>"$T/m3.log" ||
	fail "render through two proxies with local threads failed (exit $?)"
cmp "$T/local.ppm" "$T/f3.ppm" || fail "image through two proxies with local threads differs"
# the window is past 2 x threads + 1 = 3: it follows the round trip (from the
# first tiles on, with a guessed tile time until a result says: docs/protocol.md)
grep -q "window \([4-9]\|[1-9][0-9]\)" "$T/m2.log" || fail "the window did not follow the round trip"
echo ok
