~ exam_007.sce - the tiles and bricks shaders.

  A courtyard corner: the floor is shaded with TILES (glazed cream
  tiles in dark grout), the back wall with BRICKS (red bricks in running
  bond, pale mortar). A polished ball reflects both. ~

camera
    look-from (1.5 3 9)
    look-at (0 1.2 0)
    drop-line (0 -1 0)
    filter adaptive threshold 0.1 max-depth 2 ;
;

image xsize 480 ysize 360 ;

light colour (0.95 0.92 0.85) shape sphere centre (-4 8 7) radius 0.8 ; samples 12 ;
light colour (0.3 0.3 0.35) position (6 5 8) ;

// the floor: tiles of size 1 (8 units of tile, 1 of grout)
object plane position (0 0 0) normal (0 1 0) ;
    material tiles size 1 tile-width 8 grout-width 1
        face material colour (0.88 0.86 0.78) specular-reflection 0.5 specular-power 60
            spec-colour (1 1 1) reflection 0.08 ;
        grout material colour (0.3 0.3 0.32) ;
    ;
    ;
;

// the back wall: bricks 0.9 long (courses 0.3 high)
object box a (-8 0 -3) b (8 5 -2.5) ;
    material bricks size 0.9
        mortar material colour (0.82 0.8 0.74) ;
        brick material colour (0.62 0.24 0.14) ;
    ;
    ;
;

// behind the camera: a pale sky for the ball to reflect
object plane position (0 0 25) normal (0 0 -1) ;
    material colour (0.6 0.75 0.95) ;
;

object sphere centre (0.6 0.8 0) radius 0.8 ;
    material colour (0.8 0.8 0.85) diffuse-reflection 0.2 specular-reflection 0.8
        specular-power 100 reflection 0.7 ;
;
