#!/bin/sh
# Master + two workers render a scene with every primitive: the image is
# byte-identical to the local render, with and without local threads, and
# at a --size other than the scene's.
. "$(dirname "$0")/farm_lib.inc"
start_pair 2

local_render "$SCENE" "$T/local.ppm"
"$BIN/portray-master" "$SCENE" -o "$T/farm.ppm" -w "$W" --no-local --tile 16 2>"$T/m1.log" ||
	fail "farm render (--no-local) failed"
cmp "$T/local.ppm" "$T/farm.ppm" || fail "farm image (--no-local) differs from the local render"
grep -q "127.0.0.1:$a_PORT .* tiles" "$T/m1.log" || fail "no summary line for worker a"
grep -q "127.0.0.1:$b_PORT .* tiles" "$T/m1.log" || fail "no summary line for worker b"

# local threads join in; PNG output this time (without the render time,
# which is not the same twice)
local_render "$SCENE" "$T/local.png" --no-render-time
"$BIN/portray-master" "$SCENE" -o "$T/farm.png" -w "$W" -j 1 --tile 8 --no-render-time 2>"$T/m2.log" ||
	fail "farm render with local threads failed"
cmp "$T/local.png" "$T/farm.png" || fail "farm image (with local threads) differs from the local render"

# another size than the image statement's: the job carries it
local_render "$SCENE" "$T/local2.ppm" --size 50x37
"$BIN/portray-master" "$SCENE" -o "$T/farm2.ppm" -w "$W" --no-local --size 50x37 -q || fail "farm --size failed"
cmp "$T/local2.ppm" "$T/farm2.ppm" || fail "farm image at --size 50x37 differs"

# the same workers from a workers file (comments, blank lines, spaces)
printf '# the farm\n\n  127.0.0.1:%s   # a\n127.0.0.1:%s\n' "$a_PORT" "$b_PORT" >"$T/workers"
"$BIN/portray-master" "$SCENE" -o "$T/farm3.ppm" --workers-file "$T/workers" --no-local -q || fail "--workers-file failed"
cmp "$T/local.ppm" "$T/farm3.ppm" || fail "farm image via --workers-file differs"

# the worker's own command line
"$BIN/portray-worker" --help | grep -q -- "--cache-mb" || fail "worker --help"
"$BIN/portray-worker" --version | grep -q "protocol 3" || fail "worker --version"
"$BIN/portray-worker" --bogus 2>/dev/null
[ $? -eq 64 ] || fail "worker: unknown option should exit 64"

# every job logged one line on the workers
# (the render with local threads may end before a worker's handshake: its
# BYE then closes the connection without a job and without an error)
wait_count "$T/a.log" ' job .* tiles in ' 3 "worker a to log its three --no-local jobs"
grep -q "unexpected BYE" "$T/a.log" "$T/b.log" && fail "a BYE before the job started was taken as an error"
echo "ok"
