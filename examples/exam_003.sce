~ exam_003.sce - glass: specular reflection combined with refraction.

  A clear glass ball stands in front of a row of coloured pillars. The
  glass bends the light (refractive-index 1.5), so the pillars and the
  floor appear through it magnified and upside down, while its surface
  keeps a sharp highlight and a faint mirror reflection. ~

camera
    look-from (0 2.4 8)
    look-at (0 1.2 0)
    drop-line (0 -1 0)
    filter adaptive threshold 0.08 max-depth 2 ;
;

image xsize 480 ysize 360 ;

light colour (0.85 0.85 0.85) position (-5 8 7) ;
light colour (0.35 0.35 0.35) position (6 6 4) ;

object plane position (0 0 0) normal (0 1 0) ;
    material chequers size 0.8
        material-a material colour (0.9 0.9 0.85) ;
        material-b material colour (0.3 0.32 0.38) ;
    ; ;
;

// a pale backdrop
object plane position (0 0 -6) normal (0 0 1) ;
    material colour (0.6 0.65 0.75) ;
;

object cylinder from (-3 0 -3) to (-3 3.2 -3) radius 0.35 capped ; material colour (0.9 0.15 0.1) ; ;
object cylinder from (-1.5 0 -3) to (-1.5 3.2 -3) radius 0.35 capped ; material colour (0.95 0.6 0.1) ; ;
object cylinder from (0 0 -3) to (0 3.2 -3) radius 0.35 capped ; material colour (0.95 0.9 0.2) ; ;
object cylinder from (1.5 0 -3) to (1.5 3.2 -3) radius 0.35 capped ; material colour (0.2 0.7 0.25) ; ;
object cylinder from (3 0 -3) to (3 3.2 -3) radius 0.35 capped ; material colour (0.2 0.35 0.9) ; ;

// the glass ball
object sphere centre (0 1.3 0.5) radius 1.3 ;
    material colour (1 1 1) diffuse-reflection 0
        specular-reflection 0.9 specular-power 300 reflection 0.1
        transparency 0.9 refractive-index 1.5 ;
;
