// expect: 1 object_verb2.sce:4:5: error: unknown verb in object near 'glow'
object
    sphere ;
    glow
;
