// expect: 1 camera_keyword.sce:4:5: error: unrecognised keyword in camera section near 'zoom'
camera
    look-at (0 0 0)
    zoom 2
;
