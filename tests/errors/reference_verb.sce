// expect: 1 reference_verb.sce:7:12: error: unknown verb in complex reference near 'colour'
define
    object name athing object sphere ; ; ;
;
object
    translate (0 0 1)
    athing colour (1 0 0) ;
;
