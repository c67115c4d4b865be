#!/bin/sh
# render_tbox.sh - TRANSPARENT BOXES (common/shade_tbox.h): a shadow ray that
# provably meets no surface that may be transparent is traced with an
# any-hit query (or a packet) instead of closest hits. gears_s2 (glass gears
# made of triangles: the shortcut is on) must render byte for byte as the
# same scene with one more transparent object, a tiny sphere out of sight
# and off every shadow ray (a sphere gets no box: the shortcut is off), at
# -j 1 and -j 2.
. tests/cli/render_lib.inc
SCENE=tests/data/spd/gears_s2.sce
cp "$SCENE" "$TMP/on.sce"
cp "$SCENE" "$TMP/off.sce"
cat >>"$TMP/off.sce" <<'SCE'
object sphere centre (-60 -110 140) radius 0.001 ; material called mat2 ; ;
SCE
"$MASTER" -q -j 1 --size 160x120 -o "$TMP/on.ppm" "$TMP/on.sce" || fail "render on"
ppm_check "$TMP/on.ppm" 160 120
"$MASTER" -q -j 2 --size 160x120 -o "$TMP/off.ppm" "$TMP/off.sce" || fail "render off"
cmp "$TMP/on.ppm" "$TMP/off.ppm" || fail "the shortcut moved pixels"
echo "render_tbox: ok"
