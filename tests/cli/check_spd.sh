#!/bin/sh
# check_spd.sh - `portray-master --check` exits 0 on every scene in tests/data
# (spd and meshes) and prints the counts the files' own header comments state:
#   spd:    "// primitives: 7381 spheres, 0 cylinders, 2 triangles; 3 lights; 2 materials"
#   meshes: "~ Spot the cow (5,856 triangles) on a floor."
ROOT=$(pwd)
M=$ROOT/bin/portray-master
fail=0
n=0
for f in tests/data/spd/*.sce; do
	n=$((n + 1))
	want=$(sed -n 's|^// primitives: |primitives: |p' "$f" | head -n 1)
	[ -n "$want" ] || { echo "FAIL: $f has no primitives header"; fail=1; continue; }
	out=$("$M" --check "$f") || { echo "FAIL: $f: exit $?"; fail=1; continue; }
	got=$(printf '%s\n' "$out" | grep '^primitives: ')
	if [ "$got" = "$want" ]; then
		echo "ok   $f: $got"
	else
		echo "FAIL $f: got '$got', header says '$want'"
		fail=1
	fi
done
for f in tests/data/meshes/*.sce; do
	n=$((n + 1))
	want=$(head -n 1 "$f" | sed -n 's|.*(\([0-9,]*\) triangles).*|\1|p' | tr -d ,)
	[ -n "$want" ] || { echo "FAIL: $f has no triangle count in its header"; fail=1; continue; }
	# raw files are named relative to the scene: run from its folder
	out=$(cd "$(dirname "$f")" && "$M" --check "$(basename "$f")") || { echo "FAIL: $f: exit $?"; fail=1; continue; }
	got=$(printf '%s\n' "$out" | sed -n 's|^triangles: \([0-9]*\) .*|\1|p')
	if [ "$got" = "$want" ]; then
		echo "ok   $f: $got triangles"
	else
		echo "FAIL $f: got '$got' triangles, header says '$want'"
		fail=1
	fi
done
[ "$n" -ge 5 ] || { echo "FAIL: only $n scenes found"; fail=1; }
exit $fail
