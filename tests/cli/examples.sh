#!/bin/sh
# tests/cli/examples.sh - every example scene parses (--check exits 0) and
# renders at 80x60 to a picture that is not all black; two examples with
# sphere lights, glass and shaders give the same bytes for any -j and tile.
set -u
M=bin/portray-master
OUT=tests/out/examples
mkdir -p "$OUT"
fail=0
for n in exam_001 exam_002 exam_003 exam_004 exam_005 exam_006 exam_007 bgammon dice mats1 mats2; do
	s=examples/$n.sce
	if ! $M --check "$s" >"$OUT/$n.check" 2>&1; then
		echo "FAIL $n: --check: $(tail -n 3 "$OUT/$n.check")"
		fail=1
		continue
	fi
	if ! $M -q -j 2 --size 80x60 -o "$OUT/$n.ppm" "$s" 2>"$OUT/$n.err"; then
		echo "FAIL $n: render: $(cat "$OUT/$n.err")"
		fail=1
		continue
	fi
	# 80x60 binary PPM: "P6\n80 60\n255\n" is 13 bytes, then 14400 bytes of pixels
	size=$(wc -c <"$OUT/$n.ppm")
	lit=$(tail -c 14400 "$OUT/$n.ppm" | tr -d '\000' | wc -c)
	if [ "$size" -ne 14413 ] || [ "$lit" -lt 1440 ]; then
		echo "FAIL $n: image of $size bytes with $lit non-zero channel values"
		fail=1
		continue
	fi
	echo "ok   $n"
done
for n in exam_004 bgammon; do
	$M -q -j 1 --tile 16 --size 96x72 -o "$OUT/$n.j1.ppm" "examples/$n.sce" &&
		$M -q -j 2 --tile 7 --size 96x72 -o "$OUT/$n.j2.ppm" "examples/$n.sce" || fail=1
	if cmp -s "$OUT/$n.j1.ppm" "$OUT/$n.j2.ppm"; then
		echo "ok   $n: -j 1 --tile 16 == -j 2 --tile 7"
	else
		echo "FAIL $n: -j 1 --tile 16 and -j 2 --tile 7 differ"
		fail=1
	fi
done
exit $fail
