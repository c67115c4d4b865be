// expect: 1 xform_overflow.sce:3:33: error: 'stretch-x' makes the object's transform overflow or collapse
object sphere ; ;
object sphere ; stretch-x 1e200 stretch-x 1e200 ;
