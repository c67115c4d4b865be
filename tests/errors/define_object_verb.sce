// expect: 1 define_object_verb.sce:4:9: error: unknown verb in definition (name or object expected) near 'radius'
define
    object name thing
        radius 2
    ;
;
