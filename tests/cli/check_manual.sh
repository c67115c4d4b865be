#!/bin/sh
# check_manual.sh - the manual's own examples (camera file, image, light,
# objects, materials, fades, define) written as the manual shows them parse
# with `--check`, exit 0, and give the expected summary.
M=$(pwd)/bin/portray-master
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
cat >"$T/manual.sce" <<'SCE'
camera
 look-at (0.0 0.0 0.0)
 drop-line (0.0 -1.0 0.0)
 look-from ( 0.0 5.0 -25.0)
 depth 0.028
 x-size 0.032
 y-size 0.024
 filter adaptive
 ;
 filter lens
 samples 10
 focal-length 30.0
 radius 0.1
 ;
 filter super-sample
 x-samples 3
 y-samples 3
 ;
 filter disk
 samples 10
 radius 0.707
 ;

;
image
 xsize 320
 ysize 240
 no-shadows
 no-reflections
 nonstop
 Intersect-Buffer 1000
;
light
 colour (1.0 1.0 1.0)
 position (-10.0 20.0 -5.0)
 shape sphere
 centre (-10 20.0 -5.0)
 radius 2.6
 ;
 samples 20
 fall-off 1
 no-shadows
;
Object Sphere Centre (1 2 3) Radius 2 ; ;
Object
 Sphere
 ;
;
define
 material
 named flat-red
 colour (1.0 0.0 0.0)
 ;
;
Object
 primitive sphere
 centre (0.0 0.0 0.0)
 radius 1.0
 ;
 material called flat-red ;
;
material
 fades
 axis (1 1 1)
 colours 0.1 (0 0 0)
 2.0 (0 0 1)
 0.0 (0 0 0)
 ;
 named fader
;
DEFINE
 OBJECT
 NAME ATHING
 OBJECT sphere ; ;
 ;
 MATERIAL
 NAMED AMATERIAL
 colour (0 1 0)
 ;
;
object
 translate (0 0 1)
 ATHING
 ;
;
object
 sphere
 ;
 material
 called AMATERIAL
 ;
;
SCE
out=$("$M" --check "$T/manual.sce") || { echo "FAIL: exit $?"; exit 1; }
echo "$out"
echo "$out" | grep -qx 'filters: adaptive (threshold 0.2, max-depth 3, cache-size 1000, relax 1.2), lens (samples 10, radius 0.1, focal-length 30), super-sample (3 x 3), disk (samples 10, radius 0.707)' || { echo "FAIL: filters"; exit 1; }
echo "$out" | grep -qx 'lights: 1 (0 point, 1 shaped)' || { echo "FAIL: lights"; exit 1; }
echo "$out" | grep -qx 'objects: 6 (5 sphere, 1 instance)' || { echo "FAIL: objects"; exit 1; }
echo "$out" | grep -qx 'materials: 3 (3 named, 0 inline)' || { echo "FAIL: materials"; exit 1; }
echo ok
