~ mats2.sce - transparency and refractive-index.

  Two rows of balls on a floor, in front of a chequered wall:
    back    transparency 0, 0.25, 0.5, 0.75, 1.0 (red, refractive-index 1,
            so nothing bends): from an opaque ball to an invisible one;
            their shadows lighten to match
    front   clear glass (transparency 0.9) with refractive-index 1.0, 1.1,
            1.33, 1.5 and 2.0: the higher the index, the more the view
            through the ball is bent (and turned upside down) ~

camera
    look-from (0 4.2 10)
    look-at (0 0.9 0)
    drop-line (0 -1 0)
    filter adaptive threshold 0.1 max-depth 2 ;
;

image xsize 480 ysize 360 ;

light colour (1 1 1) position (-8 7 5) ;

object plane position (0 0 -4) normal (0 0 1) ;
    material chequers size 0.6
        material-a material colour (0.95 0.85 0.3) ;
        material-b material colour (0.2 0.3 0.7) ;
    ; ;
;

object plane position (0 0 0) normal (0 1 0) ;
    material chequers size 0.5
        material-a material colour (0.9 0.9 0.9) ;
        material-b material colour (0.45 0.45 0.5) ;
    ; ;
;

object sphere centre (-4 0.8 -1.2) radius 0.8 ; material colour (0.9 0.25 0.2) spec-colour (1 1 1) specular-reflection 0.6 specular-power 80
    transparency 0.00 tran-colour (1 1 1) refractive-index 1 ; ;
object sphere centre (-2 0.8 -1.2) radius 0.8 ; material colour (0.9 0.25 0.2) spec-colour (1 1 1) specular-reflection 0.6 specular-power 80
    transparency 0.25 tran-colour (1 1 1) refractive-index 1 ; ;
object sphere centre (0 0.8 -1.2) radius 0.8 ; material colour (0.9 0.25 0.2) spec-colour (1 1 1) specular-reflection 0.6 specular-power 80
    transparency 0.50 tran-colour (1 1 1) refractive-index 1 ; ;
object sphere centre (2 0.8 -1.2) radius 0.8 ; material colour (0.9 0.25 0.2) spec-colour (1 1 1) specular-reflection 0.6 specular-power 80
    transparency 0.75 tran-colour (1 1 1) refractive-index 1 ; ;
object sphere centre (4 0.8 -1.2) radius 0.8 ; material colour (0.9 0.25 0.2) spec-colour (1 1 1) specular-reflection 0.6 specular-power 80
    transparency 1.00 tran-colour (1 1 1) refractive-index 1 ; ;

object sphere centre (-4 0.6 1.6) radius 0.6 ; material colour (1 1 1) diffuse-reflection 0 specular-reflection 0.8 specular-power 200
    reflection 0.05 transparency 0.9 refractive-index 1.0 ; ;
object sphere centre (-2 0.6 1.6) radius 0.6 ; material colour (1 1 1) diffuse-reflection 0 specular-reflection 0.8 specular-power 200
    reflection 0.05 transparency 0.9 refractive-index 1.1 ; ;
object sphere centre (0 0.6 1.6) radius 0.6 ; material colour (1 1 1) diffuse-reflection 0 specular-reflection 0.8 specular-power 200
    reflection 0.05 transparency 0.9 refractive-index 1.33 ; ;
object sphere centre (2 0.6 1.6) radius 0.6 ; material colour (1 1 1) diffuse-reflection 0 specular-reflection 0.8 specular-power 200
    reflection 0.05 transparency 0.9 refractive-index 1.5 ; ;
object sphere centre (4 0.6 1.6) radius 0.6 ; material colour (1 1 1) diffuse-reflection 0 specular-reflection 0.8 specular-power 200
    reflection 0.05 transparency 0.9 refractive-index 2.0 ; ;
