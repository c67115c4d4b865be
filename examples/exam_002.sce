~ exam_002.sce - specular-power 10, 100 and 1000.

  Three identical red balls with the same specular-reflection; only the
  specular-power differs, from left to right 10, 100 and 1000: the higher
  the power, the smaller and sharper the highlight. ~

camera
    look-from (0 2 9)
    look-at (0 1 0)
    drop-line (0 -1 0)
    x-size 0.032 y-size 0.018
    filter adaptive threshold 0.1 max-depth 2 ;
;

image xsize 640 ysize 360 ;

light colour (1 1 1) position (-3 7 10) ;

object plane position (0 0 0) normal (0 1 0) ;
    material colour (0.35 0.35 0.4) ;
;

object sphere centre (-2.6 1.1 0) radius 1.1 ;
    material colour (0.8 0.08 0.05) spec-colour (1 1 1)
        specular-reflection 0.9 specular-power 10 ;
;

object sphere centre (0 1.1 0) radius 1.1 ;
    material colour (0.8 0.08 0.05) spec-colour (1 1 1)
        specular-reflection 0.9 specular-power 100 ;
;

object sphere centre (2.6 1.1 0) radius 1.1 ;
    material colour (0.8 0.08 0.05) spec-colour (1 1 1)
        specular-reflection 0.9 specular-power 1000 ;
;
