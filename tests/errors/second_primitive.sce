// expect: 1 second_primitive.sce:5:5: error: ';' expected (to close 'object' at line 2) near 'sphere'
object
    sphere radius 1 ;
    material colour (1 0 0) ;
    sphere radius 2 ;
;
