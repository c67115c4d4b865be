// metamorphic: bumpflat_b
camera
    look-from (0 2.5 7)
    look-at (0 0.3 0)
    drop-line (0 -1 0)
    filter standard ;
;
image xsize 64 ysize 48 ;
light colour (1 1 1) position (-4 6 5) ;
object sphere centre (0 0 0) radius 1 ;
    material colour (0.9 0.5 0.3) specular-reflection 0.5 ;
;
object plane position (0 -1 0) normal (0 1 0) ;
    material colour (0.9 0.5 0.3) specular-reflection 0.5 ;
;
