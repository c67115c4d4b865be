~ exam_004.sce - more glass: tinted glass in three shapes.

  On a wooden table stand a blue glass ball, a green glass block and a
  clear lens (the intersection of two spheres). Each combines specular
  reflection (highlights and a faint mirror image) with refraction; the
  tran-colour tints the light passing through, so the shadows are
  coloured too. The striped wall behind shows how each shape bends the
  view. A sphere light gives soft shadows. ~

camera
    look-from (0 3.2 8.5)
    look-at (0 0.9 0)
    drop-line (0 -1 0)
    filter adaptive threshold 0.08 max-depth 2 ;
;

image xsize 480 ysize 360 ;

light colour (0.9 0.9 0.9) shape sphere centre (-4 8 6) radius 0.8 ; samples 16 ;
light colour (0.3 0.3 0.3) position (6 5 6) ;

// the table top: pine-like wood (grain along x, slightly turbulent)
object box a (-6 -0.4 -4) b (6 0 4) ;
    material turb3d size 1.5 depth 0.06 terms 4
        material material fades axis (0 0.3 1)
            colours 0.09 (0.86 0.64 0.38) 0.03 (0.66 0.42 0.2) 0 (0.86 0.64 0.38) ;
        ; ;
    ;
;

// the wall: vertical stripes
object plane position (0 0 -4) normal (0 0 1) ;
    material fades axis (1 0 0)
        colours 0.5 (0.9 0.9 0.9) 0.05 (0.9 0.9 0.9) 0.5 (0.15 0.15 0.2) 0.05 (0.15 0.15 0.2) 0 (0.9 0.9 0.9) ;
    ;
;

// blue glass ball
object sphere centre (-2.3 1 0) radius 1 ;
    material colour (0.7 0.8 1) diffuse-reflection 0
        specular-reflection 0.9 specular-power 250 reflection 0.1
        transparency 0.9 tran-colour (0.55 0.7 1) refractive-index 1.5 ;
;

// green glass block
object box a (-0.7 0 -0.7) b (0.7 1.8 0.7) y-rotate 30 translate (0.2 0 -0.6) ;
    material colour (0.7 1 0.75) diffuse-reflection 0
        specular-reflection 0.9 specular-power 250 reflection 0.1
        transparency 0.9 tran-colour (0.6 1 0.65) refractive-index 1.5 ;
;

// a clear lens: two spheres intersected, standing on its rim
object csg
    operand1 object sphere centre (0 0 -1.6) radius 2 ; ;
    operand2 object sphere centre (0 0 1.6) radius 2 ; ;
    intersect
    ;
    y-rotate -60 translate (2.4 1.2 0.3)
    material colour (1 1 1) diffuse-reflection 0
        specular-reflection 0.9 specular-power 250 reflection 0.1
        transparency 0.95 refractive-index 1.5 ;
;
