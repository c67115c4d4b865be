// expect: 1 image_too_large.sce:2:1: error: image size 65536x65536 out of range (1..65536 per side, at most 268435456 pixels)
image xsize 65536 ysize 65536 ;
object sphere ; ;
