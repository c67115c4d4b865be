#!/bin/sh
# formats_tools.sh - our PNG (8 and 16 bits), PFM and OpenEXR (float, half)
# files read by other people's readers: ImageMagick (identify, convert) and
# the OpenEXR tools (exrheader, exrinfo, and exrcheck where the openexr
# package has it). Checks what each tool can: the sizes, depths and colour
# chunks identify reports, the pixels convert reads back, the header
# exrheader prints. Skipped (exit 77) when none of the tools is installed
# (Debian: apt-get install imagemagick openexr).
. tests/cli/render_lib.inc
have() { command -v "$1" >/dev/null 2>&1; }
IM=0
EXR=0
# identify and convert from ImageMagick itself (a stand-in convert may exist)
have identify && identify -version 2>/dev/null | grep -q ImageMagick && IM=1
have exrheader && EXR=1
if [ $IM = 0 ] && [ $EXR = 0 ]; then
	echo "neither ImageMagick (identify) nor the OpenEXR tools (exrheader) are installed"
	exit 77
fi
SCENE=$ROOT/tests/data/spd/tetra_s4.sce
for f in png png16 ppm pfm exr exr-half; do
	"$MASTER" -q "$SCENE" --size 64x48 --format $f --render-time -o "$TMP/t.$f" 2>"$TMP/err" || fail "render $f: $(cat "$TMP/err")"
done
for f in png16 pfm exr exr-half; do
	cp "$TMP/t.$f" "$TMP/t_$f.$(echo $f | sed 's/16//; s/-half//')"
done
checked=""

if [ $IM = 1 ]; then
	identify "$TMP/t.png" | grep -q 'PNG 64x48 64x48+0+0 8-bit sRGB' || fail "identify png: $(identify "$TMP/t.png")"
	identify "$TMP/t_png16.png" | grep -q 'PNG 64x48 64x48+0+0 16-bit sRGB' ||
		fail "identify png16: $(identify "$TMP/t_png16.png")"
	identify "$TMP/t_pfm.pfm" | grep -q 'PFM 64x48 ' || fail "identify pfm: $(identify "$TMP/t_pfm.pfm")"
	if identify -list format 2>/dev/null | grep -q '^ *EXR'; then
		for f in exr exr-half; do
			identify "$TMP/t_$f.exr" | grep -q 'EXR 64x48 ' || fail "identify $f: $(identify "$TMP/t_$f.exr")"
		done
	fi
	# the colour chunks as ImageMagick reads them
	identify -verbose "$TMP/t.png" >"$TMP/v.txt"
	grep -q 'Rendering intent: Perceptual' "$TMP/v.txt" || fail "no sRGB intent seen"
	grep -q 'Gamma: 0.45455' "$TMP/v.txt" || fail "no gAMA seen"
	grep -q 'white point: (0.3127,0.329)' "$TMP/v.txt" || fail "no cHRM seen"
	grep -q 'Software: portray' "$TMP/v.txt" || fail "no Software text seen"
	grep -q 'Source: tetra_s4.sce' "$TMP/v.txt" || fail "no Source text seen"
	grep -q 'Render time: [0-9.]* s' "$TMP/v.txt" || fail "no Render time text seen"
	# pixels: the 16-bit PNG (the renderer's floats in 65535 steps) taken
	# to 8 bits is the 8-bit one within one step (a value near a step's
	# edge may round either way), and is not merely the 8-bit one (v * 257)
	convert "$TMP/t_png16.png" -depth 8 "$TMP/from16.ppm" || fail "convert png16"
	ae=$(compare -metric AE -fuzz 0.5% "$TMP/from16.ppm" "$TMP/t.ppm" null: 2>&1)
	[ "$ae" = 0 ] || fail "16-bit PNG read by ImageMagick, to 8 bits: $ae pixels off by more than one step"
	convert "$TMP/t_png16.png" -format '%k' info: >"$TMP/k16" && convert "$TMP/t.png" -format '%k' info: >"$TMP/k8" ||
		fail "convert -format %k"
	[ "$(cat "$TMP/k16")" -gt "$(cat "$TMP/k8")" ] ||
		fail "16-bit PNG has $(cat "$TMP/k16") colours, the 8-bit one $(cat "$TMP/k8"): no more precision"
	convert "$TMP/t.png" "$TMP/from8.ppm" || fail "convert png"
	cmp "$TMP/from8.ppm" "$TMP/t.ppm" || fail "8-bit PNG read by ImageMagick differs from the PPM"
	# EXR: ImageMagick reads it as linear RGB; to sRGB it is the PNG again,
	# within one step (ImageMagick's own 16-bit rounding)
	if identify -list format 2>/dev/null | grep -q '^ *EXR'; then
		convert "$TMP/t_exr.exr" -colorspace sRGB -depth 8 "$TMP/fromexr.ppm" || fail "convert exr"
		ae=$(compare -metric AE -fuzz 0.5% "$TMP/fromexr.ppm" "$TMP/t.ppm" null: 2>&1)
		[ "$ae" = 0 ] || fail "EXR read by ImageMagick, back to sRGB: $ae pixels off by more than one step"
	fi
	checked="$checked identify/convert"
fi

if [ $EXR = 1 ]; then
	for f in exr exr-half; do
		exrheader "$TMP/t_$f.exr" >"$TMP/h.txt" 2>&1 || fail "exrheader $f: $(cat "$TMP/h.txt")"
		bits=32
		[ $f = exr-half ] && bits=16
		for want in 'file format version: 2, flags 0x0' "B, $bits-bit floating-point, sampling 1 1" \
			"G, $bits-bit floating-point, sampling 1 1" "R, $bits-bit floating-point, sampling 1 1" \
			'compression (type compression): none' 'dataWindow (type box2i): (0 0) - (63 47)' \
			'displayWindow (type box2i): (0 0) - (63 47)' 'lineOrder (type lineOrder): increasing y' \
			'pixelAspectRatio (type float): 1' 'screenWindowCenter (type v2f): (0 0)' \
			'screenWindowWidth (type float): 1' 'white (0.3127 0.329)' \
			'colorInteropID (type string): "lin_rec709_scene"' 'software (type string): "portray ' \
			'source (type string): "tetra_s4.sce"' 'renderTime (type string): "'; do
			grep -qF "$want" "$TMP/h.txt" || fail "exrheader $f: no '$want' in: $(cat "$TMP/h.txt")"
		done
	done
	checked="$checked exrheader"
	if have exrinfo; then
		for f in exr exr-half; do
			exrinfo --strict "$TMP/t_$f.exr" >"$TMP/i.txt" 2>&1 || fail "exrinfo --strict $f: $(cat "$TMP/i.txt")"
		done
		checked="$checked exrinfo"
	fi
	if have exrcheck; then
		for f in exr exr-half; do
			exrcheck "$TMP/t_$f.exr" >"$TMP/c.txt" 2>&1 || fail "exrcheck $f: $(cat "$TMP/c.txt")"
		done
		checked="$checked exrcheck"
	fi
fi
echo "formats_tools: ok (checked with$checked)"
