#!/bin/sh
# Every output format from the farm is byte-identical to the local render's
# file (the render-time text left out: it is the one thing that changes
# from run to run), with and without local threads.
. "$(dirname "$0")/farm_lib.inc"
start_worker a -j 1
start_worker b -j 2
W=127.0.0.1:$a_PORT,127.0.0.1:$b_PORT
for f in png png16 ppm pfm exr exr-half; do
	local_render "$SCENE" "$T/local.$f" --format $f --no-render-time --size 48x36
	"$BIN/portray-master" "$SCENE" -o "$T/farm.$f" --format $f --no-render-time --size 48x36 -w "$W" --no-local \
		--tile 8 2>"$T/m.log" || fail "farm render ($f, --no-local) failed"
	cmp "$T/local.$f" "$T/farm.$f" || fail "farm $f (--no-local) differs from the local render"
	"$BIN/portray-master" "$SCENE" -o - --format $f --no-render-time --size 48x36 -w "$W" -j 1 --tile 16 \
		>"$T/farm2.$f" 2>"$T/m.log" || fail "farm render ($f, local threads, -o -) failed"
	cmp "$T/local.$f" "$T/farm2.$f" || fail "farm $f (local threads, -o -) differs from the local render"
done
echo "farm_formats: ok"
