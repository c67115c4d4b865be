// golden: light_sphere
camera
    look-from (0 2.5 7)
    look-at (0 0.3 0)
    drop-line (0 -1 0)
    filter standard ;
;
image xsize 64 ysize 48 ;
light colour (1 1 1) shape sphere centre (-3 5 3) radius 1.5 ; samples 16 ;
object plane position (0 -1 0) normal (0 1 0) ;
    material chequers size 1
        material-a material colour (0.9 0.9 0.9) ;
        material-b material colour (0.35 0.35 0.4) ;
    ; ;
;
object sphere centre (0 0 0) radius 1 ;
    material colour (0.3 1 0.3) ;
;
