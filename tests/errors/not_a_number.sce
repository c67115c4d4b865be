// expect: 1 not_a_number.sce:2:21: error: number expected (3 in the vector after 'position') near 'y'
light position (1 2 y) ;
