// expect: 1 undefined_complex.sce:4:5: error: undefined complex object 'athing'
object
    translate (0 0 1)
    athing ;
;
