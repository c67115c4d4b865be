~ exam_005.sce - the three CSG operations.

  Each object combines the same red cube (operand1) with the same blue
  sphere (operand2); every surface keeps its own operand's colour.
    left    UNION:     everything inside either: the sphere bulges out of
                       the cube's faces
    middle  INTERSECT: what is inside both: a cube with rounded corners
    right   SUBTRACT:  the cube with the sphere taken out: the cube's
                       corners remain, hollowed by a blue spherical cavity ~

camera
    look-from (0 4.5 10)
    look-at (0 0.6 0)
    drop-line (0 -1 0)
    x-size 0.032 y-size 0.018
    filter adaptive threshold 0.1 max-depth 2 ;
;

image xsize 640 ysize 360 ;

light colour (0.9 0.9 0.9) shape sphere centre (-5 9 8) radius 1 ; samples 12 ;
light colour (0.35 0.35 0.35) position (7 5 6) ;

define material named cube-red
    colour (0.85 0.15 0.1) specular-reflection 0.4 specular-power 40 spec-colour (1 1 1) ;
;
define material named ball-blue
    colour (0.15 0.3 0.9) specular-reflection 0.4 specular-power 40 spec-colour (1 1 1) ;
;

object plane position (0 -1 0) normal (0 1 0) ;
    material colour (0.8 0.8 0.75) ;
;

object csg
    operand1 object box a (-1 -1 -1) b (1 1 1) ; material called cube-red ; ;
    operand2 object sphere radius 1.3 ; material called ball-blue ; ;
    union
    ;
    y-rotate 30 translate (-3.3 0 0)
;

object csg
    operand1 object box a (-1 -1 -1) b (1 1 1) ; material called cube-red ; ;
    operand2 object sphere radius 1.3 ; material called ball-blue ; ;
    intersect
    ;
    y-rotate 30
;

object csg
    operand1 object box a (-1 -1 -1) b (1 1 1) ; material called cube-red ; ;
    operand2 object sphere radius 1.3 ; material called ball-blue ; ;
    subtract
    ;
    y-rotate 30 translate (3.3 0 0)
;
