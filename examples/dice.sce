~ dice.sce - objects brought together from another file.

  The die is defined once, in die.sce, and included here; each die below
  is a use of that one definition with its own rotation and position (a
  reference: the die's geometry is stored only once). Five dice lie on
  green baize (the noise shader gives the cloth its mottle), showing
  different faces; one is stacked on another. ~

include die.sce

camera
    look-from (2 7 11)
    look-at (0 0.3 0)
    drop-line (0 -1 0)
    filter adaptive threshold 0.1 max-depth 2 ;
;

image xsize 480 ysize 360 ;

light colour (1 1 1) shape sphere centre (-5 10 6) radius 1 ; samples 12 ;
light colour (0.3 0.3 0.35) position (8 6 4) ;

// the baize
object plane position (0 -1 0) normal (0 1 0) ;
    material colour (0.2 0.5 0.25)
        noise size 0.08 colour (1 1 1) varience 0.25 ;
    ;
;

object die ; y-rotate 20 translate (-2.6 0 0.8) ;           // 1 up front, 2 on top
object die ; x-rotate -90 y-rotate -15 translate (0 0 1.5) ; // 1 on top
object die ; z-rotate 90 y-rotate 40 translate (2.8 0 0.5) ; // 3 on top
object die ; x-rotate 180 y-rotate 65 translate (-0.5 0 -2.2) ; // 5 on top
object die ; x-rotate 90 y-rotate -30 translate (-0.5 2 -2.2) ; // stacked: 6 on top
