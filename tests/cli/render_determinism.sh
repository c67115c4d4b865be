#!/bin/sh
# render_determinism.sh - with every filter on, -j 1, -j 2 and tile sizes 7, 16
# and 64 write byte-identical files.
. tests/cli/render_lib.inc
. tests/cli/render_scene.inc
scene_with_filters "$TMP/all.sce" \
	'filter adaptive threshold 0.05 max-depth 2 cache-size 40 ;' \
	'filter lens samples 2 radius 0.05 focal-length 9 ;' \
	'filter super-sample x-samples 2 y-samples 1 ;' \
	'filter disk samples 2 radius 0.6 ;'
"$MASTER" -q "$TMP/all.sce" -o "$TMP/a.ppm" -j 1 --tile 7 || fail "render -j 1 --tile 7"
ppm_check "$TMP/a.ppm" 40 30
for args in "-j 2 --tile 16" "-j 2 --tile 64" "-j 1 --tile 64" "-j 3 --tile 1"; do
	# shellcheck disable=SC2086
	"$MASTER" -q "$TMP/all.sce" -o "$TMP/b.ppm" $args || fail "render $args"
	cmp "$TMP/a.ppm" "$TMP/b.ppm" || fail "$args differs from -j 1 --tile 7"
done
# and the PNG holds the same pixels the same way every time (the render
# time, which is not the same twice, left out)
"$MASTER" -q "$TMP/all.sce" -o "$TMP/a.png" -j 1 --tile 7 --no-render-time || fail "png 1"
"$MASTER" -q "$TMP/all.sce" -o "$TMP/b.png" -j 2 --tile 16 --no-render-time || fail "png 2"
cmp "$TMP/a.png" "$TMP/b.png" || fail "PNG files differ"
echo "render_determinism: ok"
