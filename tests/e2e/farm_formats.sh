#!/bin/sh
# Every output format from the farm is byte-identical to the local render's
# file (the render-time text left out: it is the one thing that changes
# from run to run), with and without local threads. The float formats
# (png16, pfm, exr, exr-half) travel as float tiles (protocol 3): a bright
# scene's PFM from the farm holds the same values above 1 as the local one,
# whatever the tile size, and a worker lying about one float bit is caught
# by the audits as an 8-bit liar is.
. "$(dirname "$0")/farm_lib.inc"
PIXSTAT=$TOOLS/pixstat
[ -x "$PIXSTAT" ] || fail "$PIXSTAT missing (make test builds it)"
start_pair 2
for f in png png16 ppm pfm exr exr-half; do
	local_render "$SCENE" "$T/local.$f" --format $f --no-render-time --size 48x36
	"$BIN/portray-master" "$SCENE" -o "$T/farm.$f" --format $f --no-render-time --size 48x36 -w "$W" --no-local \
		--tile 8 2>"$T/m.log" || fail "farm render ($f, --no-local) failed"
	cmp "$T/local.$f" "$T/farm.$f" || fail "farm $f (--no-local) differs from the local render"
	"$BIN/portray-master" "$SCENE" -o - --format $f --no-render-time --size 48x36 -w "$W" -j 1 --tile 16 \
		>"$T/farm2.$f" 2>"$T/m.log" || fail "farm render ($f, local threads, -o -) failed"
	cmp "$T/local.$f" "$T/farm2.$f" || fail "farm $f (local threads, -o -) differs from the local render"
done

# values above 1 come through the farm as they are
BRIGHT=$E2E/../data/bright.sce
local_render "$BRIGHT" "$T/local_b.pfm" -j 1 --tile 8
"$PIXSTAT" "$T/local_b.pfm" >"$T/stat" || fail "pixstat: $(cat "$T/stat")"
read -r _ _ _ _ _ _ above _ <"$T/stat"
[ "$above" -gt 1000 ] || fail "bright PFM: $above values above 1 ($(cat "$T/stat"))"
for tile in 5 32 64; do
	"$BIN/portray-master" "$BRIGHT" -o "$T/farm_b.pfm" -w "$W" --no-local --tile $tile 2>"$T/m.log" ||
		fail "farm render of the bright scene (--tile $tile) failed"
	cmp "$T/local_b.pfm" "$T/farm_b.pfm" || fail "farm bright PFM (--tile $tile) differs from the local render"
done

# a float liar (one bit of one float flipped, checksum valid) is caught
# beside an honest worker (20 ms a tile: the liar takes part whatever the load)
start_worker liar -j 1 --test-fault lie
start_worker slow -j 1 --test-delay-ms 20
"$BIN/portray-master" "$BRIGHT" -o "$T/farm_l.pfm" -w "127.0.0.1:$slow_PORT,127.0.0.1:$liar_PORT" \
	--no-local --tile 8 2>"$T/ml.log" || fail "farm render with a float liar failed"
cmp "$T/local_b.pfm" "$T/farm_l.pfm" || fail "PFM differs with a lying worker"
grep -q "worker 127.0.0.1:$liar_PORT returned wrong pixels" "$T/ml.log" || fail "the float liar was not caught"
echo "farm_formats: ok"
