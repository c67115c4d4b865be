// expect: 1 material_verb.sce:5:9: error: unknown verb in material near 'shininess'
object
    sphere ;
    material
        shininess 3
    ;
;
