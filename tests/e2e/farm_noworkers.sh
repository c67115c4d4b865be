#!/bin/sh
# Nobody listening: with --no-local the master retries with back-off, then
# fails with a clear message and exit code 69; without it, it renders locally.
. "$(dirname "$0")/farm_lib.inc"
start_worker gone -j 1
P=$gone_PORT
kill -KILL "$gone_PID"
wait "$gone_PID" 2>/dev/null
local_render "$SCENE" "$T/local.ppm"
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --no-local -w "127.0.0.1:$P" 2>"$T/m1.log"
rc=$?
[ $rc -eq 69 ] || fail "exit $rc, expected 69"
[ "$(grep -c "lost: connect" "$T/m1.log")" -eq 3 ] || fail "expected three retries"
grep -q "dropped" "$T/m1.log" || fail "worker not dropped"
grep -q "every worker is lost and --no-local forbids rendering here" "$T/m1.log" || fail "no clear message"
[ ! -e "$T/x.ppm" ] || fail "an image was written"
"$BIN/portray-master" "$SCENE" -o "$T/l.ppm" -w "127.0.0.1:$P" 2>"$T/m2.log" || fail "local fallback failed"
cmp "$T/local.ppm" "$T/l.ppm" || fail "local fallback image differs"
# a bad worker list is a usage error
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" -w "127.0.0.1" 2>"$T/m3.log"
[ $? -eq 64 ] || fail "bad -w: expected exit 64"
grep -q "not HOST:PORT" "$T/m3.log" || fail "bad -w: unclear message"
echo ok
