~ mats1.sce - diffuse-reflection, specular-reflection and specular-power.

  Fifteen balls in three rows; left to right one setting grows:
    top     diffuse-reflection 0.2, 0.4, 0.6, 0.8, 1.0 (no highlight):
            from a dark dull ball to a bright dull one
    middle  specular-reflection 0.2, 0.4, 0.6, 0.8, 1.0
            (diffuse-reflection 0.6, specular-power 25): the highlight
            gets stronger
    bottom  specular-power 5, 20, 50, 200, 1000 (specular-reflection 0.8):
            the highlight gets smaller and sharper ~

camera
    look-from (0 1.5 10.5)
    look-at (0 1.5 0)
    drop-line (0 -1 0)
    filter adaptive threshold 0.1 max-depth 2 ;
;

image xsize 480 ysize 360 ;

light colour (1 1 1) position (-2 5 16) ;

object sphere centre (-4 3.6 0) radius 0.85 ; material colour (0.2 0.85 0.3) diffuse-reflection 0.2 ; ;
object sphere centre (-2 3.6 0) radius 0.85 ; material colour (0.2 0.85 0.3) diffuse-reflection 0.4 ; ;
object sphere centre (0 3.6 0) radius 0.85 ; material colour (0.2 0.85 0.3) diffuse-reflection 0.6 ; ;
object sphere centre (2 3.6 0) radius 0.85 ; material colour (0.2 0.85 0.3) diffuse-reflection 0.8 ; ;
object sphere centre (4 3.6 0) radius 0.85 ; material colour (0.2 0.85 0.3) diffuse-reflection 1.0 ; ;

object sphere centre (-4 1.5 0) radius 0.85 ; material colour (0.2 0.4 0.95) spec-colour (1 1 1) diffuse-reflection 0.6
    specular-reflection 0.2 specular-power 25 ; ;
object sphere centre (-2 1.5 0) radius 0.85 ; material colour (0.2 0.4 0.95) spec-colour (1 1 1) diffuse-reflection 0.6
    specular-reflection 0.4 specular-power 25 ; ;
object sphere centre (0 1.5 0) radius 0.85 ; material colour (0.2 0.4 0.95) spec-colour (1 1 1) diffuse-reflection 0.6
    specular-reflection 0.6 specular-power 25 ; ;
object sphere centre (2 1.5 0) radius 0.85 ; material colour (0.2 0.4 0.95) spec-colour (1 1 1) diffuse-reflection 0.6
    specular-reflection 0.8 specular-power 25 ; ;
object sphere centre (4 1.5 0) radius 0.85 ; material colour (0.2 0.4 0.95) spec-colour (1 1 1) diffuse-reflection 0.6
    specular-reflection 1.0 specular-power 25 ; ;

object sphere centre (-4 -0.6 0) radius 0.85 ; material colour (0.95 0.2 0.15) spec-colour (1 1 1)
    specular-reflection 0.8 specular-power 5 ; ;
object sphere centre (-2 -0.6 0) radius 0.85 ; material colour (0.95 0.2 0.15) spec-colour (1 1 1)
    specular-reflection 0.8 specular-power 20 ; ;
object sphere centre (0 -0.6 0) radius 0.85 ; material colour (0.95 0.2 0.15) spec-colour (1 1 1)
    specular-reflection 0.8 specular-power 50 ; ;
object sphere centre (2 -0.6 0) radius 0.85 ; material colour (0.95 0.2 0.15) spec-colour (1 1 1)
    specular-reflection 0.8 specular-power 200 ; ;
object sphere centre (4 -0.6 0) radius 0.85 ; material colour (0.95 0.2 0.15) spec-colour (1 1 1)
    specular-reflection 0.8 specular-power 1000 ; ;
