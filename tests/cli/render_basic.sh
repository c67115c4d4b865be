#!/bin/sh
# render_basic.sh - portray-master renders: PNG and PPM by extension, the default
# output name, --size, quiet stdout, exit codes for scene and output errors.
. tests/cli/render_lib.inc
SCENE=$ROOT/tests/data/spd/tetra_s4.sce

"$MASTER" -q "$SCENE" -o "$TMP/t.ppm" --size 64x48 >"$TMP/out" 2>"$TMP/err" || fail "render failed: $(cat "$TMP/err")"
[ -s "$TMP/out" ] && fail "stdout not quiet: $(cat "$TMP/out")"
[ -s "$TMP/err" ] && fail "-q but stderr: $(cat "$TMP/err")"
ppm_check "$TMP/t.ppm" 64 48
"$MASTER" -q "$SCENE" -o "$TMP/t.PNG" --size 64x48 || fail "png render"
png_check "$TMP/t.PNG"

# default output: the scene's name with .png, in the current directory, at the image size
(cd "$TMP" && "$MASTER" "$SCENE" -j 2 >out 2>err) || fail "default output render"
png_check "$TMP/tetra_s4.png"
[ -s "$TMP/out" ] && fail "stdout not quiet"
grep -q 'tetra_s4.png: 320x240, 2 threads' "$TMP/err" || fail "no summary: $(cat "$TMP/err")"
grep -q 'Mrays/s' "$TMP/err" || fail "no Mrays/s in the summary"
# not a terminal: no progress bar
grep -q 'ETA' "$TMP/err" && fail "progress bar drawn on a non-terminal"

# the image has content: the tetrahedron is lit somewhere
"$MASTER" -q "$SCENE" -o "$TMP/t2.ppm" --size 32x24 || fail "small render"
lit=$(tail -c $((32 * 24 * 3)) "$TMP/t2.ppm" | od -An -tu1 -v | tr -s ' ' '\n' | grep -cv '^0*$')
[ "$lit" -gt 100 ] || fail "image nearly black ($lit lit bytes)"

# scene errors: the error level and a file:line:col message
printf 'camera\n  look-at (0 0 0)\n  bogus 3\n;\n' >"$TMP/bad.sce"
"$MASTER" -q "$TMP/bad.sce" -o "$TMP/bad.png" 2>"$TMP/err"
rc=$?
[ "$rc" -eq 1 ] || fail "bad scene: exit $rc, want 1"
grep -q 'bad.sce:3:' "$TMP/err" || fail "bad scene message: $(cat "$TMP/err")"
[ -f "$TMP/bad.png" ] && fail "image written for a bad scene"
"$MASTER" -q "$TMP/missing.sce" 2>"$TMP/err"
[ $? -eq 1 ] || fail "missing scene: want exit 1"

# the output cannot be written: exit 74
"$MASTER" -q "$SCENE" --size 8x8 -o "$TMP/no/such/dir/x.png" 2>"$TMP/err"
rc=$?
[ "$rc" -eq 74 ] || fail "unwritable output: exit $rc, want 74"
grep -q 'cannot write' "$TMP/err" || fail "unwritable output message: $(cat "$TMP/err")"
echo "render_basic: ok"
