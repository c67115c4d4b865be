~ exam_001.sce - diffuse reflection, specular reflection and refraction.

  Three balls of the same size on a chequered floor, in front of a
  chequered wall:
    left    diffuse (Lambertian) reflection only: a matt orange ball
    middle  specular reflection: highlights and a mirror finish
    right   refraction: a clear glass ball, which shows the wall and the
            floor behind it upside down ~

camera
    look-from (0 2.2 9)
    look-at (0 0.9 0)
    drop-line (0 -1 0)
    x-size 0.032 y-size 0.018
    filter adaptive threshold 0.1 max-depth 2 ;
;

image xsize 640 ysize 360 ;

light colour (0.9 0.9 0.9) position (-6 9 8) ;
light colour (0.4 0.4 0.45) position (7 5 6) ;

define material named floor-check
    chequers size 1
        material-a material colour (0.92 0.92 0.88) ;
        material-b material colour (0.25 0.27 0.32) ;
    ;
    ;
;

object plane position (0 0 0) normal (0 1 0) ;
    material called floor-check ;
;

object plane position (0 0 -4) normal (0 0 1) ;
    material chequers size 1.5
        material-a material colour (0.95 0.8 0.25) ;
        material-b material colour (0.2 0.35 0.75) ;
    ; ;
;

// behind the camera: a pale sky for the mirror ball to reflect
object plane position (0 0 20) normal (0 0 -1) ;
    material colour (0.55 0.7 0.9) diffuse-reflection 0.8 ;
;

// diffuse reflection
object sphere centre (-2.6 1.1 0) radius 1.1 ;
    material colour (1 0.45 0.1) diffuse-reflection 1.0 ;
;

// specular reflection
object sphere centre (0 1.1 0) radius 1.1 ;
    material colour (0.85 0.85 0.9) diffuse-reflection 0.1
        specular-reflection 0.8 specular-power 80 reflection 0.8 ;
;

// refraction
object sphere centre (2.6 1.1 0) radius 1.1 ;
    material colour (1 1 1) diffuse-reflection 0
        specular-reflection 0.8 specular-power 200 reflection 0.06
        transparency 0.94 refractive-index 1.5 ;
;
