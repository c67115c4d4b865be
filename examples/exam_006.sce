~ exam_006.sce - CSG: a die.

  The die is defined in die.sce (included below): a cube intersected with a
  sphere gives the rounded body, and 21 small spheres, joined by union, are
  subtracted from it to make the pips. Each part keeps its own material, so
  the pips are black hollows in an ivory die. ~

include die.sce

camera
    look-from (3.6 3.4 4.6)
    look-at (0 0.2 0)
    drop-line (0 -1 0)
    filter adaptive threshold 0.1 max-depth 2 ;
;

image xsize 480 ysize 360 ;

light colour (1 1 1) shape sphere centre (-3 9 6) radius 1 ; samples 16 ;
light colour (0.35 0.35 0.4) position (8 4 2) ;

object plane position (0 -1 0) normal (0 1 0) ;
    material colour (0.25 0.4 0.3) ;
;

object die ;
    y-rotate 5
;
