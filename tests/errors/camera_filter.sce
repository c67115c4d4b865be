// expect: 1 camera_filter.sce:3:27: error: unrecognised keyword in camera section (filter lens) near 'threshold'
camera
    filter lens samples 4 threshold 0.1 ;
;
