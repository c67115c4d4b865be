// PortRAY scene converted from NFF by tools/nff2portray.py
// source: SPD rings_s3
// NFF view angle 45 deg; film x-size/y-size chosen for square aspect
// NFF background colour (0.078 0.361 0.753) - PortRAY has no background statement
// primitives: 420 spheres, 420 cylinders, 2 triangles; 3 lights; 7 materials

camera
    look-from (-1 -2.61313 0.5)
    look-at (-1 -1.61313 0.5)
    drop-line (0 0 -1)
    depth 1
    x-size 0.8284271247
    y-size 0.8284271247
    filter standard
    ;
;

image
    xsize 320
    ysize 240
;

light
    colour (0.5773502692 0.5773502692 0.5773502692)
    position (3 -2.61313 3)
    fall-off 0
;

light
    colour (0.5773502692 0.5773502692 0.5773502692)
    position (-4 -2.61313 1)
    fall-off 0
;

light
    colour (0.5773502692 0.5773502692 0.5773502692)
    position (2 -2.61313 -4)
    fall-off 0
;

define
    material
        named mat1
        colour (1 1 1)
        spec-colour (1 1 1)
        diffuse-reflection 1
        specular-reflection 0
        reflection 0
        transparency 0
    ;
;

define
    material
        named mat2
        colour (1 0 0)
        spec-colour (1 1 1)
        diffuse-reflection 0.5
        specular-reflection 0.2
        specular-power 3.0827
        reflection 0.2
        transparency 0
    ;
;

define
    material
        named mat3
        colour (0 1 0)
        spec-colour (1 1 1)
        diffuse-reflection 0.5
        specular-reflection 0.2
        specular-power 3.0827
        reflection 0.2
        transparency 0
    ;
;

define
    material
        named mat4
        colour (0 0 1)
        spec-colour (1 1 1)
        diffuse-reflection 0.5
        specular-reflection 0.2
        specular-power 3.0827
        reflection 0.2
        transparency 0
    ;
;

define
    material
        named mat5
        colour (0 1 1)
        spec-colour (1 1 1)
        diffuse-reflection 0.5
        specular-reflection 0.2
        specular-power 3.0827
        reflection 0.2
        transparency 0
    ;
;

define
    material
        named mat6
        colour (1 0 1)
        spec-colour (1 1 1)
        diffuse-reflection 0.5
        specular-reflection 0.2
        specular-power 3.0827
        reflection 0.2
        transparency 0
    ;
;

define
    material
        named mat7
        colour (1 1 0)
        spec-colour (1 1 1)
        diffuse-reflection 0.5
        specular-reflection 0.2
        specular-power 3.0827
        reflection 0.2
        transparency 0
    ;
;

object triangle a (4.46608 10.4525 5.96608) b (-6.46608 10.4525 5.96608) c (-6.46608 10.4525 -4.96608) ; material called mat1 ; ;
object triangle a (4.46608 10.4525 5.96608) b (-6.46608 10.4525 -4.96608) c (4.46608 10.4525 -4.96608) ; material called mat1 ; ;
object cylinder from (0.930995 2.61313 0) to (0.287693 1.7277 0) radius 0.07412 ; material called mat2 ; ;
object sphere centre (0.930995 2.61313 0) radius 0.07412 ; material called mat2 ; ;
object cylinder from (0.287693 3.49855 0) to (0.930995 2.61313 0) radiu