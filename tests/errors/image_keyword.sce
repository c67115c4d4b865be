// expect: 1 image_keyword.sce:4:5: error: unrecognised keyword in image section (the pixel size is xsize/ysize; x-size/y-size belong in the camera statement) near 'x-size'
image
    xsize 320
    x-size 0.032
;
