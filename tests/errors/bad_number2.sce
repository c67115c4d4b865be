// expect: 1 bad_number2.sce:2:13: error: malformed number near '1e999'
image xsize 1e999 ;
