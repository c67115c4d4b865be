// golden: reflection
camera
    look-from (0 2.5 7)
    look-at (0 0.3 0)
    drop-line (0 -1 0)
    filter standard ;
;
image xsize 64 ysize 48 ;
light colour (1 1 1) position (-4 6 5) ;
object plane position (0 -1 0) normal (0 1 0) ;
    material chequers size 1
        material-a material colour (0.9 0.9 0.9) ;
        material-b material colour (0.35 0.35 0.4) ;
    ; ;
;
object plane position (0 0 -3) normal (0 0 1) ;
    material chequers size 1
        material-a material colour (0.9 0.8 0.2) ;
        material-b material colour (0.2 0.3 0.8) ;
    ; ;
;
object sphere centre (0 0 0) radius 1 ;
    material colour (0.9 0.9 0.9) diffuse-reflection 0.1 specular-reflection 0.6 specular-power 60 reflection 0.8 ;
;
