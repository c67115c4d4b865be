// expect: 1 alter.sce:7:9: error: attempt to alter the named material 'flat-red'
define material named flat-red colour (1 0 0) ; ;
object
    sphere ;
    material
        called flat-red
        diffuse-reflection 0.5
    ;
;
