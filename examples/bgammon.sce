~ bgammon.sce - a pine table with two tumblers and a backgammon board with
  brass inlays and two dice.

  Built from several include files:
    bg_mats.sce     the materials (pine, mahogany, brass, baize, glass ...)
    bg_table.sce    the table
    bg_board.sce    the board (defined object backgammon-board) and a checker
    bg_tumbler.sce  the tumblers (defined objects tumbler, tumbler-full)
    die.sce         the die (also used by exam_006 and dice) ~

include bg_mats.sce
include die.sce
include bg_table.sce
include bg_board.sce
include bg_tumbler.sce

camera
    look-from (-1.5 12.5 10.5)
    look-at (0.3 0 0.4)
    drop-line (0 -1 0)
    filter adaptive threshold 0.1 max-depth 2 ;
;

image xsize 640 ysize 480 ;

light colour (0.95 0.9 0.8) shape sphere centre (-8 16 10) radius 1.5 ; samples 12 ;
light colour (0.35 0.35 0.4) position (12 10 6) ;

object backgammon-board ; y-rotate 0 ;

// checkers stacked on their points
object checker ; translate (-4.44 0.221 -2.85) material called checker-white ; ;
object checker ; translate (-4.44 0.361 -2.85) material called checker-white ; ;
object checker ; translate (-4.44 0.501 -2.85) material called checker-white ; ;
object checker ; translate (-1.57 0.221 -2.85) material called checker-black ; ;
object checker ; translate (-1.57 0.361 -2.85) material called checker-black ; ;
object checker ; translate (0.86 0.221 2.85) material called checker-black ; ;
object checker ; translate (0.86 0.361 2.85) material called checker-black ; ;
object checker ; translate (0.86 0.501 2.85) material called checker-black ; ;
object checker ; translate (0.86 0.641 2.85) material called checker-black ; ;
object checker ; translate (2.3 0.221 2.85) material called checker-white ; ;
object checker ; translate (2.3 0.361 2.85) material called checker-white ; ;
object checker ; translate (4.44 0.221 -2.85) material called checker-white ; ;
object checker ; translate (4.44 0.361 -2.85) material called checker-white ; ;
object checker ; translate (4.44 0.501 -2.85) material called checker-white ; ;
object checker ; translate (-3 0.221 2.85) material called checker-black ; ;
object checker ; translate (-3 0.361 2.85) material called checker-black ; ;
object checker ; translate (-3 0.501 2.85) material called checker-black ; ;

// the two dice (die.sce, side 2) scaled to side 0.59, thrown on the right field
object die ; shrink-x 3.4 shrink-y 3.4 shrink-z 3.4 y-rotate 25 translate (2.3 0.516 0.2) ;
object die ; shrink-x 3.4 shrink-y 3.4 shrink-z 3.4 x-rotate -90 y-rotate -40 translate (3.4 0.516 -0.7) ;

// two tumblers: one empty, one with whisky
object tumbler ; translate (-6.7 0.005 -1.9) ;
object tumbler-full ; translate (7.2 0.005 -1.5) ;
