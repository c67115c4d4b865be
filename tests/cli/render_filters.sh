#!/bin/sh
# render_filters.sh - metamorphic checks on the filters through the command:
# super-sample 1x1 == standard; the black background is black under every
# filter; a filter before the first standard/adaptive is ignored with one
# warning; super-sample 3x3 and an out-of-focus lens do change the picture.
. tests/cli/render_lib.inc
. tests/cli/render_scene.inc
M() { "$MASTER" -q "$@" || fail "render $*"; }

scene_with_filters "$TMP/std.sce" 'filter standard ;'
scene_with_filters "$TMP/ss1.sce" 'filter standard ;' 'filter super-sample x-samples 1 y-samples 1 ;'
M "$TMP/std.sce" -o "$TMP/std.ppm"
M "$TMP/ss1.sce" -o "$TMP/ss1.ppm"
cmp "$TMP/std.ppm" "$TMP/ss1.ppm" || fail "super-sample 1x1 differs from standard"
# an ignored filter before standard changes nothing, and is reported once
scene_with_filters "$TMP/pre.sce" 'filter disk samples 5 ;' 'filter standard ;'
"$MASTER" -q "$TMP/pre.sce" -o "$TMP/pre.ppm" 2>"$TMP/err" || fail "render pre"
cmp "$TMP/std.ppm" "$TMP/pre.ppm" || fail "a filter before standard changed the image"
[ "$(grep -c 'warning' "$TMP/err")" -eq 1 ] || fail "want one warning, got: $(cat "$TMP/err")"
grep -q 'pre.sce:4:' "$TMP/err" || fail "warning without its line: $(cat "$TMP/err")"

# nothing but background: black under every filter
for f in 'filter standard ;' 'filter adaptive ;' 'filter standard ; filter super-sample ;' \
	'filter standard ; filter disk ;' 'filter standard ; filter lens radius 0.5 focal-length 3 ;' \
	'filter adaptive threshold 0.0001 ; filter lens ; filter super-sample ; filter disk ;'; do
	printf 'camera look-from (0 0 5) look-at (0 0 0) %s ;\nimage xsize 16 ysize 12 ;\n' "$f" >"$TMP/black.sce"
	M "$TMP/black.sce" -o "$TMP/black.ppm"
	ppm_check "$TMP/black.ppm" 16 12
	nz=$(tail -c $((16 * 12 * 3)) "$TMP/black.ppm" | od -An -tu1 -v | tr -s ' ' '\n' | grep -c '[1-9]')
	[ "$nz" -eq 0 ] || fail "background not black under '$f'"
done

# filters change the picture (they are not ignored): super-sample and lens
scene_with_filters "$TMP/ss3.sce" 'filter standard ;' 'filter super-sample x-samples 3 y-samples 3 ;'
M "$TMP/ss3.sce" -o "$TMP/ss3.ppm"
cmp -s "$TMP/std.ppm" "$TMP/ss3.ppm" && fail "super-sample 3x3 == standard"
scene_with_filters "$TMP/lens.sce" 'filter standard ;' 'filter lens samples 8 radius 0.4 focal-length 2 ;'
M "$TMP/lens.sce" -o "$TMP/lens.ppm"
cmp -s "$TMP/std.ppm" "$TMP/lens.ppm" && fail "an out-of-focus lens == standard"
echo "render_filters: ok"
