#!/bin/sh
# The delay proxy (tests/tools/delayproxy.c) under a real farm: a master
# reaches a worker through it at 0 ms and at 50 ms each way; both images are
# byte-identical to the local render (scene bytes up, tiles down, the BYE and
# the closes through it), and the 50 ms run takes longer by at least 150 ms
# (a lower bound: protocol 2 needs two round trips of 100 ms, HELLO and
# OFFER out / HELLO and NEED back, then scene and first tiles out / results
# back; the proxy accepts the TCP connection itself, so the connect costs
# none; test_delayproxy checks the proxy's own timing and limits).
. "$(dirname "$0")/farm_lib.inc"
now() { date +%s.%N; }
start_worker a -j 1
start_proxy p0 "$a_PORT" 0
start_proxy p50 "$a_PORT" 50
local_render "$SCENE" "$T/local.ppm"
# farm RUN PROXY_PORT: a --no-local render through the proxy; its seconds in $T/RUN.time
farm() {
	t0=$(now)
	"$BIN/portray-master" "$SCENE" -o "$T/$1.ppm" -w "127.0.0.1:$2" --no-local 2>"$T/m_$1.log" ||
		fail "render $1 through the proxy failed (exit $?)"
	t1=$(now)
	cmp "$T/local.ppm" "$T/$1.ppm" || fail "image $1 differs from the local render"
	awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f\n", b - a }' >"$T/$1.time"
}
# the 0 ms time: best of 2 (a loaded machine only makes it longer)
farm z1 "$p0_PORT"
farm z2 "$p0_PORT"
farm d50 "$p50_PORT"
a0=$(cat "$T/z1.time")
b0=$(cat "$T/z2.time")
d50=$(cat "$T/d50.time")
echo "through the proxy: 0 ms ${a0} s and ${b0} s, 50 ms ${d50} s"
awk -v a="$a0" -v b="$b0" -v d="$d50" 'BEGIN { z = a < b ? a : b; exit !(d >= z + 0.15 && d >= 0.2) }' ||
	fail "the 50 ms run was not at least 150 ms slower (and 200 ms long)"
# every connection went through and was closed
wait_count "$T/p0.log" "closed after" 2 "proxy p0 to log its two connections closed"
wait_count "$T/p50.log" "closed after" 1 "proxy p50 to log its connection closed"
echo ok
