// expect: 1 camera_far.sce:2:1: error: camera vectors too large
camera look-from (1e300 0 0) ;
object sphere ; ;
