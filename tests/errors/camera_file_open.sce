// expect: 1 nonexistent.cam: error: unable to open camera file: No such file
// camera: nonexistent.cam
object sphere ; ;
