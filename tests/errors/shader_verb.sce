// expect: 1 shader_verb.sce:4:37: error: unknown verb in material (bricks shader) near 'grout'
define material named red colour (1 0 0) ; ;
define material named wall
    bricks size 2 mortar called red grout called red ;
;
;
