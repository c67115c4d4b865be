// bright.sce - a light of colour 1.5 on a white sphere: the float formats
// (png16, pfm, exr) carry values above 1 (up to about 2) where the 8-bit
// files clamp to 255. Used by tests/cli/render_formats.sh and
// tests/e2e/farm_formats.sh.
camera look-from (0 0 10) look-at (0 0 0) drop-line (0 -1 0) depth 1 x-size 0.8 y-size 0.6 ;
image xsize 64 ysize 48 ;
light colour (1.5 1.5 1.5) position (-5 5 10) ;
object sphere centre (0 0 0) radius 3 ; material colour (0.9 0.9 0.9) ; ;
