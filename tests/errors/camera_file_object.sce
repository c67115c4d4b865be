// expect: 1 inc/object.cam:3:1: error: unrecognised keyword in camera file (only camera, image, light and include) near 'object'
// camera: inc/object.cam
object sphere ; ;
