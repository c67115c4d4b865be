// golden: filter_adaptive
camera
    look-from (0 2.5 7)
    look-at (0 0.3 0)
    drop-line (0 -1 0)
    filter adaptive threshold 0.1 max-depth 2 ;
;
image xsize 64 ysize 48 ;
light colour (1 1 1) position (-4 6 5) ;
object plane position (0 -1 0) normal (0 1 0) ;
    material chequers size 1
        material-a material colour (0.9 0.9 0.9) ;
        material-b material colour (0.35 0.35 0.4) ;
    ; ;
;
object sphere centre (-0.8 0 0) radius 0.7 ;
    material colour (1 0.3 0.2) specular-reflection 0.7 specular-power 50 ;
;
object sphere centre (0.9 0 -0.8) radius 0.7 ;
    material colour (0.2 0.3 1) reflection 0.5 diffuse-reflection 0.4 ;
;
