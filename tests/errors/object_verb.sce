// expect: 1 object_verb.sce:3:12: error: unknown verb in object (sphere) near 'diameter'; expected centre, radius, pole, equator, a transform or ';'
object
    sphere diameter 2 ;
;
