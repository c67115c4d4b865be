#!/bin/sh
# tests/cli/golden.sh - golden images and metamorphic pairs for shading.
#
# Golden: every tests/golden/scenes/NAME.sce (64x48) is rendered with
# bin/portray-master and compared with tests/golden/NAME.ppm by
# tests/golden/imgcmp.c: at least 99.5% of the pixels within 2 per channel,
# no channel off by more than 16 (sampling or rounding changes elsewhere may
# move a few pixels; a real change of shading moves many).
#
# Metamorphic: tests/golden/meta/NAME_a.sce and NAME_b.sce must render
# alike ("same", same tolerance) or visibly differently ("differ"), as listed
# below. These survive changes of sampling that would invalidate goldens.
#
# GOLDEN_UPDATE=1 sh tests/cli/golden.sh rewrites the goldens (look at them
# before committing: `portray-master -o x.png` the scene at a larger --size).
set -u
BUILD=${BUILD:-build}
CC=${CC:-cc}
G=tests/golden
OUT=tests/out/golden
M=bin/portray-master
mkdir -p "$OUT"
$CC -O2 -o "$OUT/imgcmp" "$G/imgcmp.c" || exit 1

fail=0
render() { # scene out.ppm
	if ! $M -q -j 2 -o "$2" "$1" 2>"$OUT/err.txt"; then
		echo "FAIL: cannot render $1: $(cat "$OUT/err.txt")"
		return 1
	fi
}

for s in "$G"/scenes/*.sce; do
	n=$(basename "$s" .sce)
	render "$s" "$OUT/$n.ppm" || { fail=1; continue; }
	if [ -n "${GOLDEN_UPDATE:-}" ]; then
		cp "$OUT/$n.ppm" "$G/$n.ppm"
		echo "updated $G/$n.ppm"
		continue
	fi
	if [ ! -f "$G/$n.ppm" ]; then
		echo "FAIL $n: no golden $G/$n.ppm"
		fail=1
		continue
	fi
	if r=$("$OUT/imgcmp" "$G/$n.ppm" "$OUT/$n.ppm"); then
		echo "ok   golden $n: $r"
	else
		echo "FAIL golden $n: $r"
		fail=1
	fi
done

# metamorphic pairs: MODE NAME   (why)
while read -r mode n why; do
	[ -n "$mode" ] || continue
	render "$G/meta/${n}_a.sce" "$OUT/meta_${n}_a.ppm" || { fail=1; continue; }
	render "$G/meta/${n}_b.sce" "$OUT/meta_${n}_b.ppm" || { fail=1; continue; }
	case $mode in
	exact) r=$("$OUT/imgcmp" -t 0 -f 1 -m 0 "$OUT/meta_${n}_a.ppm" "$OUT/meta_${n}_b.ppm") ;;
	same) r=$("$OUT/imgcmp" "$OUT/meta_${n}_a.ppm" "$OUT/meta_${n}_b.ppm") ;;
	differ) r=$("$OUT/imgcmp" -d -t 8 -f 0.99 "$OUT/meta_${n}_a.ppm" "$OUT/meta_${n}_b.ppm") ;;
	esac
	if [ $? -eq 0 ]; then
		echo "ok   $mode $n: $r"
	else
		echo "FAIL $mode $n ($why): $r"
		fail=1
	fi
done <<'EOF'
exact noshadow light no-shadows == image no-shadows with that one light
differ shadowdiff shadows change the picture
same tinysphere a sphere light of radius 1e-5 == a point light at its centre
same pointbox a box light of zero size == a point light at its corner
exact noreflect image no-reflections == every reflection 0
same invisible a fully transparent sphere (ior 1, no diffuse, no highlight) is invisible
exact samechq chequers of one material == that material
exact turbplain turb3d over a plain material changes nothing
exact opaqueior refractive-index does nothing without transparency
exact bumpflat bumpy of depth 0 == the plain material
exact noiseflat noise of variance 0 around (1 1 1) == the plain material
exact nogrout tiles with grout-width 0 == the face material
exact fadesflat fades between two equal colours == that colour
EOF
exit $fail
