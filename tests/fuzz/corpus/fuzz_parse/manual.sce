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
