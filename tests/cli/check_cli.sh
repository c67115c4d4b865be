#!/bin/sh
# check_cli.sh - `portray-master --check` on the command line: the summary's
# lines, a camera file (-c), errors on stderr with the Appendix B exit code,
# a missing scene file.
M=$(pwd)/bin/portray-master
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

cat >"$T/s.sce" <<'SCE'
define object name pair object sphere ; ; object box ; ; ; ;
define material named red colour (1 0 0) ; ;
camera filter standard filter super-sample x-samples 3 ; ;
light shape sphere radius 1 ; samples 4 ;
object pair ; translate (1 0 0) ;
object pair ; material called red ; ;
object triangle ; ;
object csg operand1 object sphere ; ; operand2 object disk ; ; union ; material colour (0 1 0) ; ;
SCE
cat >"$T/c.cam" <<'CAM'
image xsize 64 ysize 48 ;
light ;
CAM
out=$("$M" --check -c "$T/c.cam" "$T/s.sce" 2>"$T/err") || fail "exit $?: $(cat "$T/err")"
echo "$out"
echo "$out" | grep -qx 'image: 64x48' || fail "image line"
echo "$out" | grep -qx 'filters: standard, super-sample (3 x 2)' || fail "filters line"
echo "$out" | grep -qx 'lights: 2 (1 point, 1 shaped)' || fail "lights line"
echo "$out" | grep -qx 'objects: 8 (2 sphere, 1 box, 1 triangle, 1 csg, 1 disk, 2 instance)' || fail "objects line"
echo "$out" | grep -qx 'definitions: 1' || fail "definitions line"
echo "$out" | grep -qx 'instances: 2' || fail "instances line"
echo "$out" | grep -qx 'materials: 2 (1 named, 1 inline)' || fail "materials line"
echo "$out" | grep -qx 'triangles: 1 stored, 1 drawn (every instance counted)' || fail "triangles line"
# pair (sphere, box) twice, the triangle, the csg's sphere and disk: 2 + 2 + 1 + 2
echo "$out" | grep -qx 'primitive instances: 7' || fail "primitive instances line"
[ -s "$T/err" ] && fail "unexpected stderr: $(cat "$T/err")"

# primitive instances through nested defines: exact up to 2^64 - 1, then "at least"
out=$("$M" --check tests/data/hostile/nested64.sce) || fail "nested64 --check exit $?"
echo "$out" | grep -qx 'primitive instances: 9223372036854775808' || fail "nested64: 2^63 primitive instances"
{
	echo 'define object name a1 object sphere ; ; ;'
	i=2
	while [ $i -le 33 ]; do
		p=a$((i - 1))
		echo "object name a$i object $p ; ; object $p ; ; object $p ; ; object $p ; ; ;"
		i=$((i + 1))
	done
	echo '; object a33 ; ; object triangle ; ;'
} >"$T/quad.sce"
out=$("$M" --check "$T/quad.sce") || fail "4^32 --check exit $?"
echo "$out" | grep -qx 'primitive instances: at least 18446744073709551615' || fail "4^32 + 1 primitives: saturated"
echo "$out" | grep -qx 'triangles: 1 stored, 1 drawn (every instance counted)' || fail "4^32 scene's triangle"

# errors: stderr only, exit code = level
printf 'light samples 3 ;\n' >"$T/l2.sce"
"$M" --check "$T/l2.sce" >"$T/out" 2>"$T/err"
rc=$?
[ "$rc" = 2 ] || fail "level 2 error gave exit $rc"
[ -s "$T/out" ] && fail "stdout on error: $(cat "$T/out")"
grep -q "l2.sce:1:7: error: 'samples' on a light with no shape" "$T/err" || fail "level 2 message: $(cat "$T/err")"

"$M" --check "$T/none.sce" >"$T/out" 2>"$T/err"
rc=$?
[ "$rc" = 1 ] || fail "missing scene gave exit $rc"
grep -q "none.sce: error: unable to open scene file: No such file" "$T/err" || fail "missing scene message: $(cat "$T/err")"

# a filter before standard: a warning, not an error
printf 'camera filter lens ; filter standard ;\n' >"$T/w.sce"
"$M" --check "$T/w.sce" >"$T/out" 2>"$T/err" || fail "warning case failed"
grep -q "w.sce:1:8: warning: filter lens before the first standard or adaptive filter is ignored" "$T/err" ||
	fail "warning text: $(cat "$T/err")"
grep -qx 'filters: standard' "$T/out" || fail "filters after the warning"

# a second adaptive filter is ignored with a warning, under --check as when rendering
printf 'camera filter standard ; filter adaptive ; ;\n' >"$T/w2.sce"
"$M" --check "$T/w2.sce" >"$T/out" 2>"$T/err" || fail "second base filter case failed"
grep -q "w2.sce:1:26: warning: filter adaptive ignored: only the first standard or adaptive filter samples the pixel" "$T/err" ||
	fail "second base filter warning: $(cat "$T/err")"

# a summary that cannot be written is an I/O error (74), not success
if [ -w /dev/full ]; then
	"$M" --check "$T/s.sce" >/dev/full 2>"$T/err"
	rc=$?
	[ "$rc" = 74 ] || fail "--check to a full device gave exit $rc"
	grep -q "cannot write the summary" "$T/err" || fail "full device message: $(cat "$T/err")"
fi
echo ok
