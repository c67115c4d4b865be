#!/bin/sh
# bench/identity.sh - the same bytes as a reference build: renders a set of
# scenes with bin/portray-master and with REF (another build's
# portray-master, e.g. one made from the commit before a speed change) and
# compares the PPM files byte for byte. For changes that must not move a
# pixel (packets, caches, leaf layouts): run it before and after.
#
#   REF=/path/to/old/portray-master sh bench/identity.sh
#
# The set: tests/golden/scenes (every filter, light shape and shader),
# examples/*.sce, the four SPD scenes at 640x480 plain, with super-sample
# 2x2 and with adaptive filtering, and the teapot and dragon meshes when
# $PORTRAY_SHARED (default ../shared/data) has them. ID_SIZE (default
# 640x480) sets the size of the SPD and mesh renders. ID_EXT=png compares
# PNG files instead of PPM, so the encoder's bytes too (with
# --no-render-time, the default, said outright). Prints one line per
# difference and a summary; exits 1 when anything differs. Nothing here is
# a test (the reference binary is not part of the tree).
if [ -z "${REF:-}" ]; then # `make bench` runs every script: no reference, nothing to compare
	echo "REF not set: skipped (REF=/path/to/reference/portray-master sh bench/identity.sh)"
	exit 0
fi
MASTER=${MASTER:-bin/portray-master}
SHARED=${PORTRAY_SHARED:-../shared/data}
SIZE=${ID_SIZE:-640x480}
J=${ID_THREADS:-2}
EXT=${ID_EXT:-ppm}
NRT=
[ "$EXT" = png ] && NRT=--no-render-time
TMP=$(mktemp -d "${TMPDIR:-/tmp}/portray-id.XXXXXX")
trap 'rm -rf "$TMP"' EXIT
n=0
bad=0

# one NAME SCENE [OPTIONS...]: renders SCENE with both binaries and compares
one() {
	name=$1
	scene=$2
	shift 2
	n=$((n + 1))
	"$MASTER" -q -j "$J" $NRT "$@" -o "$TMP/new.$EXT" "$scene" 2>/dev/null
	a=$?
	"$REF" -q -j "$J" $NRT "$@" -o "$TMP/ref.$EXT" "$scene" 2>/dev/null
	b=$?
	if [ "$a" != "$b" ]; then
		echo "DIFF $name: exit $a, reference $b"
		bad=$((bad + 1))
	elif [ -f "$TMP/ref.$EXT" ] && ! cmp -s "$TMP/new.$EXT" "$TMP/ref.$EXT"; then
		echo "DIFF $name: pixels differ"
		bad=$((bad + 1))
	fi
	rm -f "$TMP/new.$EXT" "$TMP/ref.$EXT"
}

# variant SCENE FILTER: SCENE with its camera's filter replaced by FILTER
variant() {
	sed "s/filter standard/filter $2/" "$1" >"$TMP/variant.sce"
	echo "$TMP/variant.sce"
}

for f in tests/golden/scenes/*.sce; do
	one "golden/$(basename "$f" .sce)" "$f"
done
for f in examples/*.sce; do
	one "examples/$(basename "$f" .sce)" "$f" --size 320x240
done
for s in balls_s4 gears_s2 rings_s3 tetra_s4; do
	f=tests/data/spd/$s.sce
	one "$s" "$f" --size "$SIZE"
	one "$s ss2" "$(variant "$f" "super-sample x-samples 2 y-samples 2")" --size "$SIZE"
	one "$s adaptive" "$(variant "$f" "adaptive threshold 0.1 max-depth 2")" --size "$SIZE"
	one "$s tile 7" "$f" --size 320x240 --tile 7 -j 1
done
if [ -f "$SHARED/meshes/teapot.sce" ]; then
	SH=$(cd "$SHARED" && pwd)
	for m in teapot dragon; do
		[ -f "$SH/meshes/$m.raw" ] || continue
		sed "s#file teapot.raw#file $SH/meshes/$m.raw#" "$SH/meshes/teapot.sce" >"$TMP/$m.sce"
		one "$m" "$TMP/$m.sce" --size "$SIZE"
		one "$m ss2" "$(variant "$TMP/$m.sce" "super-sample x-samples 2 y-samples 2")" --size "$SIZE"
		one "$m adaptive" "$(variant "$TMP/$m.sce" "adaptive threshold 0.1 max-depth 2")" --size "$SIZE"
	done
else
	echo "no meshes in $SHARED: teapot and dragon left out"
fi
echo "identity: $n renders, $bad differ"
[ "$bad" -eq 0 ]
