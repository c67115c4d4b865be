// expect: 1 missing_semi_eof.sce:7:1: error: ';' expected (to close 'object' at line 3) near end of file
camera ;
object
    sphere radius 1 ;
    material colour (1 0 0) ;

