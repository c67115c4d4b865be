#!/bin/sh
# render_simd.sh - DIRECT IN FOURS end to end: scenes whose eye hits take the
# four-lane shading (point lights with one that casts no shadows: spot.sce;
# more point lights than the shadow packets make ways for: six here, with
# mirrors) render to the same bytes as with PORTRAY_SIMD=sse2, which keeps
# every hit on the one-at-a-time path (PPM and PFM, 1 and 2 threads).
# Skipped (exit 77) where the CPU has no AVX2: both runs would take the
# same path and compare nothing.
. tests/cli/render_lib.inc
if ! grep -qw avx2 /proc/cpuinfo 2>/dev/null; then
	echo "no AVX2 here (or no /proc/cpuinfo): both paths are the same one"
	exit 77
fi
cat >"$TMP/six.sce" <<'EOF'
camera
  look-from (0.0 2.0 -6.0)
  look-at (0.0 0.5 0.0)
  drop-line (0.0 -1.0 0.0)
  depth 0.028
  x-size 0.032
  y-size 0.024
  filter standard ;
;
light colour (0.4 0.4 0.4) position (-6 8 -6) ;
light colour (0.3 0.2 0.2) position (6 7 -5) ;
light colour (0.2 0.3 0.2) position (0 9 6) ;
light colour (0.2 0.2 0.3) position (-5 3 2) ;
light colour (0.3 0.3 0.2) position (5 2 2) ;
light colour (0.2 0.3 0.3) position (0 4 -8) ;
object plane position (0 0 0) normal (0 1 0) ;
  material colour (0.6 0.6 0.6) diffuse-reflection 0.8 ; ;
object sphere centre (-0.8 0.7 0) radius 0.7 ;
  material colour (0.9 0.5 0.3) diffuse-reflection 0.6 specular-reflection 0.5 specular-power 3.0827
    reflection 0.4 ; ;
object sphere centre (0.9 0.5 0.3) radius 0.5 ;
  material colour (0.3 0.6 0.9) diffuse-reflection 0.8 specular-reflection 0.3 specular-power 60 ; ;
EOF
cp tests/data/meshes/spot.sce tests/data/meshes/spot.raw "$TMP/" || fail "copy spot"
for s in "$TMP/spot.sce" "$TMP/six.sce"; do
	for ext in ppm pfm; do
		for j in 1 2; do
			"$MASTER" -q -j $j --size 160x120 -o "$TMP/a.$ext" "$s" || fail "render $s"
			PORTRAY_SIMD=sse2 "$MASTER" -q -j $j --size 160x120 -o "$TMP/b.$ext" "$s" || fail "render $s (sse2)"
			cmp "$TMP/a.$ext" "$TMP/b.$ext" || fail "$(basename "$s") -j $j .$ext: AVX2 and SSE2 paths differ"
		done
	done
done
# the scenes are not black (the comparison compared pictures)
"$MASTER" -q --size 160x120 -o "$TMP/c.ppm" "$TMP/six.sce" || fail "render six"
ppm_check "$TMP/c.ppm" 160 120
bright=$(tail -c 57600 "$TMP/c.ppm" | od -An -tu1 -v | tr -s ' ' '\n' | awk '$1 > 40 { n++ } END { print n + 0 }')
[ "$bright" -gt 10000 ] || fail "six.sce is nearly black ($bright bright bytes)"
echo "render_simd: ok"
