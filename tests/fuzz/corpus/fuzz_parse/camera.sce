camera look-at (0 0 0) drop-line (0 -1 0) look-from (0 5 -25) depth 0.028 x-size 0.032 y-size 0.024
  filter adaptive threshold 0.1 max-depth 2 cache-size 10 relax 1.1 ;
  filter lens samples 10 focal-length 30.0 radius 0.1 ;
  filter super-sample x-samples 3 y-samples 3 ;
  filter disk samples 10 radius 0.707 ;
;
image xsize 320 ysize 240 no-shadows no-reflections nonstop intersect-buffer 1000 ;
light colour (1 1 1) position (-10 20 -5) shape sphere centre (-10 20 -5) radius 2.6 ; samples 20 fall-off 1 no-shadows ;
light shape box a (0 0 0) b (1 1 1) ; samples 2 ;
light shape cylinder from (0 0 0) to (0 1 0) radius 0.1 ; ;
