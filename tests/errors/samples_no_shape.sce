// expect: 2 samples_no_shape.sce:4:5: error: 'samples' on a light with no shape
light
    position (0 10 0)
    samples 20
;
