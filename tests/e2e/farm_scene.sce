~ farm_scene.sce - every primitive, CSG, a define used twice, a RAW mesh and a
  few shaders, small: the farm's end-to-end tests render it locally and
  through workers and compare the bytes. ~

camera
    look-from (1 3 10)
    look-at (0 0.8 0)
    drop-line (0 -1 0)
    depth 1 x-size 0.8 y-size 0.6
    filter standard ;
;

image xsize 96 ysize 72 ;

light colour (0.9 0.9 0.9) position (-6 9 8) ;
light colour (0.4 0.4 0.45) position (7 5 6) shape sphere centre (7 5 6) radius 0.5 ; samples 2 ;

define material named check
    chequers size 1
        material-a material colour (0.92 0.92 0.88) ;
        material-b material colour (0.25 0.27 0.32) ;
    ;
    ;
;

define object name block
    object box a (0 0 0) b (0.4 0.4 0.4) ; material colour (0.8 0.2 0.2) ; ;
    object sphere centre (0.2 0.6 0.2) radius 0.2 ; ;
    ;
;

object plane position (0 0 0) normal (0 1 0) ; material called check ; ;
object sphere centre (-2.5 1 0) radius 1 ; material colour (1 0.45 0.1) specular-reflection 0.4 ; ;
object cylinder from (-0.5 0 -2) to (-0.5 2 -2) radius 0.4 capped ; material colour (0.2 0.6 0.9) ; ;
object box a (1 0 -1) b (2 1 0) ; material reflection 0.3 colour (0.7 0.7 0.2) ; ;
object triangle a (2.5 0 1) b (3.5 0 1) c (3 1.5 1) ; ;
object triangle a (-4 0 1) b (-3 0 1) c (-3.5 1.5 1)
    normal-a (0 0 1) normal-b (0.3 0 1) normal-c (0 0.3 1) ; material colour (0.3 0.9 0.3) ; ;
object disk position (0 1.5 -3) normal (0 0 1) radius 0.7 ; material colour (0.9 0.1 0.9) ; ;
object polygon
    contour (2 0.1 2) (3 0.1 2) (3 0.1 3) (2 0.1 3) ;
    contour (2.3 0.1 2.3) (2.7 0.1 2.3) (2.5 0.1 2.7) ;
    ; material colour (0.1 0.1 0.9) ;
;
object raw file farm_tri.raw smooth ; translate (-1 0 2) material colour (0.9 0.9 0.9) ; ;
object csg
    operand1 object sphere centre (0 1 1) radius 0.8 ; ;
    operand2 object box a (0 1 0) b (1 2 2) ; ;
    subtract ;
    material colour (0.6 0.3 0.9) transparency 0.3 refractive-index 1.3 ;
;
object block translate (-1.5 0 2.5) ; ;
object block y-rotate 30 translate (0.5 0 3) ; ;
