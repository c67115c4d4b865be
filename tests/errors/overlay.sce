// expect: 1 overlay.sce:7:9: error: attempt to overlay a material with the named material 'flat-red'
define material named flat-red colour (1 0 0) ; ;
object
    sphere ;
    material
        diffuse-reflection 0.5
        called flat-red
    ;
;
