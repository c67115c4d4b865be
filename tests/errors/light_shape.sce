// expect: 1 light_shape.sce:3:11: error: a plane cannot be the shape of a light (sphere, cylinder or box)
light
    shape plane normal (0 1 0) ;
;
