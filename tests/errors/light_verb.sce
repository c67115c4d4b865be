// expect: 1 light_verb.sce:4:5: error: unknown verb in light near 'brightness'
light
    colour (1 1 1)
    brightness 2
;
