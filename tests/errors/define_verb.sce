// expect: 1 define_verb.sce:3:5: error: unknown verb in definition (object or material expected) near 'sphere'
define
    sphere ;
;
