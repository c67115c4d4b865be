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
"$TOOLS/fakepeer" hold --to "127.0.0.1:$w_PORT" --count 300 --port-file-ready "$T/ready" 2>"$T/hold.log" &
PIDS="$PIDS $!"
i=0
while [ ! -f "$T/ready" ]; do
	i=$((i + 1))
	[ $i -gt 600 ] && fail "the 300 connections were not all open within 30 s"
	sleep 0.05
done
local_render "$SCENE" "$T/local.ppm" --size 64x48
timeout 60 "$BIN/portray-master" "$SCENE" --size 64x48 -o "$T/farm.ppm" --no-local --secret-file "$T/secret" \
	-w "127.0.0.1:$w_PORT" 2>"$T/m.log" || fail "the master could not render past 300 idle connections (exit $?)"
cmp "$T/local.ppm" "$T/farm.ppm" || fail "image differs"
# and again, while the flood keeps reconnecting
timeout 60 "$BIN/portray-master" "$SCENE" --size 64x48 -o "$T/farm2.ppm" --no-local --secret-file "$T/secret" \
	-w "127.0.0.1:$w_PORT" 2>"$T/m2.log" || fail "the second render failed (exit $?)"
cmp "$T/local.ppm" "$T/farm2.ppm" || fail "second image differs"
echo ok
