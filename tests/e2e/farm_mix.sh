#!/bin/sh
# Determinism across the farm's shapes: three workers with different thread
# counts, odd tile sizes, with and without local threads, at an odd image
# size: every image is byte-identical to a one-thread local render.
. "$(dirname "$0")/farm_lib.inc"
start_worker a -j 1
start_worker b -j 2
start_worker c -j 3
W=127.0.0.1:$a_PORT,127.0.0.1:$b_PORT,127.0.0.1:$c_PORT
local_render "$SCENE" "$T/ref.ppm" --size 101x77 -j 1
local_render "$SCENE" "$T/l3.ppm" --size 101x77 -j 3 --tile 5
cmp "$T/ref.ppm" "$T/l3.ppm" || fail "local renders differ between -j 1 and -j 3 --tile 5"
"$BIN/portray-master" "$SCENE" -o "$T/f1.ppm" --size 101x77 -w "$W" --no-local --tile 7 2>"$T/m1.log" ||
	fail "farm render (--no-local, tile 7) failed"
cmp "$T/ref.ppm" "$T/f1.ppm" || fail "farm image (3 workers, tile 7) differs"
"$BIN/portray-master" "$SCENE" -o "$T/f2.ppm" --size 101x77 -w "$W" -j 2 --tile 13 2>"$T/m2.log" ||
	fail "farm render (local -j 2, tile 13) failed"
cmp "$T/ref.ppm" "$T/f2.ppm" || fail "farm image (3 workers + 2 local threads, tile 13) differs"
echo ok
