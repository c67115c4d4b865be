#!/bin/sh
# --region and the preview switches on a farm of two workers: a region
# rendered by the workers alone (--no-local) and with local threads is the
# same bytes as the local region render and as the crop of a full render;
# --preview on the farm is the same bytes as --preview locally (the switches
# change the scene before it is sent, so workers trace what the master
# traces).
. "$(dirname "$0")/farm_lib.inc"
start_pair 2

# ppm_crop IN X0 Y0 X1 Y1 OUT: the region of a binary PPM as a PPM
ppm_crop() {
	w=$(head -n 2 "$1" | tail -n 1 | cut -d' ' -f1)
	hdr=$(head -n 3 "$1" | wc -c)
	{
		printf 'P6\n%d %d\n255\n' $(($4 - $2)) $(($5 - $3))
		y=$3
		while [ "$y" -lt "$5" ]; do
			tail -c +$((hdr + (y * w + $2) * 3 + 1)) "$1" | head -c $((($4 - $2) * 3))
			y=$((y + 1))
		done
	} >"$6"
}

local_render "$SLOW" "$T/full.ppm"
ppm_crop "$T/full.ppm" 11 9 83 61 "$T/crop.ppm"
local_render "$SLOW" "$T/local_r.ppm" --region 11,9,83,61 --tile 7
cmp "$T/crop.ppm" "$T/local_r.ppm" || fail "local region differs from the crop of the full render"
"$BIN/portray-master" "$SLOW" -o "$T/farm_r.ppm" -w "$W" --no-local --region 11,9,83,61 --tile 7 \
	2>"$T/m1.log" || fail "farm region render (--no-local) failed"
cmp "$T/crop.ppm" "$T/farm_r.ppm" || fail "farm region (--no-local) differs from the crop of the full render"
grep -q "127.0.0.1:$a_PORT .* tiles" "$T/m1.log" && grep -q "127.0.0.1:$b_PORT .* tiles" "$T/m1.log" ||
	fail "the workers did not take part"
"$BIN/portray-master" "$SLOW" -o "$T/farm_r2.ppm" -w "$W" -j 1 --region 11,9,83,61 --tile 5 -q ||
	fail "farm region render with local threads failed"
cmp "$T/crop.ppm" "$T/farm_r2.ppm" || fail "farm region (with local threads) differs from the crop"

# the preview switches: the farm traces the changed scene
local_render "$SLOW" "$T/local_p.ppm" --preview
cmp -s "$T/local_p.ppm" "$T/full.ppm" && fail "--preview changed nothing"
"$BIN/portray-master" "$SLOW" -o "$T/farm_p.ppm" -w "$W" --no-local --preview --tile 8 -q ||
	fail "farm --preview failed"
cmp "$T/local_p.ppm" "$T/farm_p.ppm" || fail "farm --preview differs from local --preview"
for sw in --no-aa --no-shadows --no-reflections; do
	local_render "$SLOW" "$T/local_s.ppm" $sw
	"$BIN/portray-master" "$SLOW" -o "$T/farm_s.ppm" -w "$W" --no-local $sw --tile 8 -q ||
		fail "farm $sw failed"
	cmp "$T/local_s.ppm" "$T/farm_s.ppm" || fail "farm $sw differs from local $sw"
done
echo ok
