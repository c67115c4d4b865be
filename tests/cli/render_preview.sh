#!/bin/sh
# render_preview.sh - --region and the preview switches, locally:
#   a region's file is the same bytes as that crop of a full render (odd
#   origin, odd tile size, one pixel, the whole image); a region outside the
#   image or badly written is a usage error (64);
#   --no-shadows is brighter or equal everywhere (brighter somewhere) and
#   equals the scene with the image statement's no-shadows; --no-reflections
#   equals no-reflections; --no-aa equals the scene with the standard filter
#   alone; --preview equals all three.
. "$(dirname "$0")/render_lib.inc"

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

# bytes FILE: the pixel bytes of a PPM, one decimal a line
bytes() {
	hdr=$(head -n 3 "$1" | wc -c)
	tail -c +$((hdr + 1)) "$1" | od -An -v -tu1 -w1
}

cat >"$TMP/s.sce" <<'SCE'
camera look-from (0 3 8) look-at (0 0.5 0) drop-line (0 -1 0) depth 1 x-size 0.8 y-size 0.6
  filter standard ; filter super-sample x-samples 2 y-samples 2 ; ;
image xsize 64 ysize 48 ;
light colour (1 1 1) position (-3 6 4) ;
object plane position (0 0 0) normal (0 1 0) ; material colour (0.8 0.8 0.8) reflection 0.3 ; ;
object sphere centre (0 1 0) radius 1 ; material colour (0.9 0.3 0.2) reflection 0.5 ; ;
object sphere centre (2 0.5 1) radius 0.5 ; material colour (0.2 0.4 0.9) ; ;
SCE
S=$TMP/s.sce
"$MASTER" -q -o "$TMP/full.ppm" "$S" || fail "full render"

# regions: the same bytes as the crop of the full render
for spec in "13,7,51,40 --tile=5" "13,7,51,40" "0,0,64,48 --tile=7" "63,47,64,48" "5,0,6,48 -j1" "0,20,64,21 --tile=64"; do
	reg=${spec%% *}
	extra=
	[ "$reg" != "$spec" ] && extra=${spec#* }
	# shellcheck disable=SC2086
	"$MASTER" -q -o "$TMP/r.ppm" --region "$reg" $extra "$S" || fail "--region $spec"
	IFS=, read -r x0 y0 x1 y1 <<EOF
$reg
EOF
	ppm_check "$TMP/r.ppm" $((x1 - x0)) $((y1 - y0))
	ppm_crop "$TMP/full.ppm" "$x0" "$y0" "$x1" "$y1" "$TMP/crop.ppm"
	cmp -s "$TMP/crop.ppm" "$TMP/r.ppm" || fail "--region $spec: not the crop of the full render"
done
# a PNG region too (the format is the output's business)
"$MASTER" -q -o "$TMP/r.png" --region 1,2,30,20 "$S" || fail "--region to PNG"
png_check "$TMP/r.png"

# bad regions: usage errors before anything is written
for bad in 0,0,65,48 0,0,64,49 10,10,10,20 10,10,5,20 1,2,3 1,2,3,4,5 a,b,c,d -1,0,4,4 "1,2,3,4x"; do
	"$MASTER" -q -o "$TMP/bad.ppm" --region "$bad" "$S" 2>"$TMP/bad.log"
	rc=$?
	[ $rc -eq 64 ] || fail "--region $bad: exit $rc, want 64"
	grep -q -- "--region" "$TMP/bad.log" || fail "--region $bad: no message naming --region"
	[ -e "$TMP/bad.ppm" ] && fail "--region $bad: an image was written"
done

# --no-shadows: brighter or equal everywhere, brighter somewhere; the same as the scene's own flag
"$MASTER" -q -o "$TMP/ns.ppm" --no-shadows "$S" || fail "--no-shadows"
sed 's/^image xsize 64 ysize 48 ;/image xsize 64 ysize 48 no-shadows ;/' "$S" >"$TMP/ns.sce"
"$MASTER" -q -o "$TMP/ns_scene.ppm" "$TMP/ns.sce" || fail "no-shadows scene"
cmp -s "$TMP/ns.ppm" "$TMP/ns_scene.ppm" || fail "--no-shadows differs from the image statement's no-shadows"
bytes "$TMP/full.ppm" >"$TMP/a.txt"
bytes "$TMP/ns.ppm" >"$TMP/b.txt"
cmpres=$(paste "$TMP/a.txt" "$TMP/b.txt" | awk '{ if ($2 < $1) lt++; if ($2 > $1) gt++ } END { print lt + 0, gt + 0 }')
set -- $cmpres
[ "$1" -eq 0 ] || fail "--no-shadows: $1 bytes darker than with shadows"
[ "$2" -gt 100 ] || fail "--no-shadows: only $2 bytes brighter (the scene has shadows)"

# --no-reflections
"$MASTER" -q -o "$TMP/nr.ppm" --no-reflections "$S" || fail "--no-reflections"
sed 's/^image xsize 64 ysize 48 ;/image xsize 64 ysize 48 no-reflections ;/' "$S" >"$TMP/nr.sce"
"$MASTER" -q -o "$TMP/nr_scene.ppm" "$TMP/nr.sce" || fail "no-reflections scene"
cmp -s "$TMP/nr.ppm" "$TMP/nr_scene.ppm" || fail "--no-reflections differs from the image statement's no-reflections"
cmp -s "$TMP/nr.ppm" "$TMP/full.ppm" && fail "--no-reflections changed nothing (the scene has mirrors)"

# --no-aa: the standard filter alone
"$MASTER" -q -o "$TMP/na.ppm" --no-aa "$S" || fail "--no-aa"
sed 's/filter super-sample x-samples 2 y-samples 2 ;//' "$S" >"$TMP/na.sce"
"$MASTER" -q -o "$TMP/na_scene.ppm" "$TMP/na.sce" || fail "standard-filter scene"
cmp -s "$TMP/na.ppm" "$TMP/na_scene.ppm" || fail "--no-aa differs from the standard filter alone"
cmp -s "$TMP/na.ppm" "$TMP/full.ppm" && fail "--no-aa changed nothing (the scene super-samples)"

# --preview: all three, and a region of a preview is its crop
"$MASTER" -q -o "$TMP/pv.ppm" --preview "$S" || fail "--preview"
"$MASTER" -q -o "$TMP/pv3.ppm" --no-aa --no-shadows --no-reflections "$S" || fail "the three switches"
cmp -s "$TMP/pv.ppm" "$TMP/pv3.ppm" || fail "--preview is not the three switches"
"$MASTER" -q -o "$TMP/pvr.ppm" --preview --region 10,10,40,30 --tile 6 "$S" || fail "--preview --region"
ppm_crop "$TMP/pv.ppm" 10 10 40 30 "$TMP/pvcrop.ppm"
cmp -s "$TMP/pvr.ppm" "$TMP/pvcrop.ppm" || fail "--preview --region is not the crop of --preview"
echo ok
