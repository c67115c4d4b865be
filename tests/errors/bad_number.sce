// expect: 1 bad_number.sce:3:19: error: malformed number near '1.2.3'
object
    sphere radius 1.2.3 ;
;
