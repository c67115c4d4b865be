~ filters.sce - hostile: layered filters. Adaptive at max-depth 8 with a
  tiny threshold splits every pixel to 257 x 257 corners, and each corner
  is multiplied into 32 lens x 32 x 32 super-sample x 32 disk = 2^20 rays,
  the most LIM_RAYS_PER_SAMPLE allows: some 10^10 rays a pixel, far beyond
  a lifetime for this 8x6 image. A renderer must abandon it when cancelled
  (tests/unit/test_cancel.c). ~
camera look-from (0 0 10) look-at (0 0 0)
  filter adaptive threshold 1e-9 relax 1e-3 max-depth 8 cache-size 1 ;
  filter lens samples 32 radius 0.5 focal-length 7 ;
  filter super-sample x-samples 32 y-samples 32 ;
  filter disk samples 32 radius 2 ;
;
image xsize 8 ysize 6 ;
light position (5 5 10) ;
light colour (0.4 0.4 0.5) shape sphere centre (-5 3 8) radius 1 ; samples 4 ;
object sphere radius 3 ; material colour (0.9 0.5 0.2) specular-reflection 0.5 ; ;
object plane position (0 -3 0) ; ;
