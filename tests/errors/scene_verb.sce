// expect: 1 scene_verb.sce:4:1: error: unknown verb in scene file near 'sphere'
object sphere ; ;

sphere radius 2 ;
