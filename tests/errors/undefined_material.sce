// expect: 1 undefined_material.sce:4:21: error: undefined material 'flat-blue'
define material named flat-red colour (1 0 0) ; ;
object sphere ;
    material called flat-blue ;
;
