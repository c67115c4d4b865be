~ die.sce - a die built by CSG, for exam_006, dice and bgammon.

  define object die: a die of side 2 centred on the origin.
    body   = box (-1 -1 -1)..(1 1 1) INTERSECT sphere radius 1.55:
             a cube whose corners and the ends of its edges are rounded
    pips   = the UNION of 21 small spheres (radius 0.2) sunk into the faces
    die    = body SUBTRACT pips
  The pips keep their own (black) material: CSG shades a point with the
  material of the surface the ray actually hits, so the hollows of the
  subtraction are black and the rest of the die is ivory.
  Faces: 1 toward +z, 6 toward -z, 2 toward +y, 5 toward -y, 3 toward +x,
  4 toward -x (opposite faces add up to 7). ~

define material named die-ivory
    colour (0.95 0.93 0.86) diffuse-reflection 0.9
    specular-reflection 0.5 specular-power 60 spec-colour (1 1 1)
    reflection 0.05 ;
;

define material named die-pip
    colour (0.05 0.05 0.06) diffuse-reflection 0.8
    specular-reflection 0.4 specular-power 40 spec-colour (1 1 1) ;
;

define object
    name die
    object csg
        operand1 object csg
            operand1 object box a (-1 -1 -1) b (1 1 1) ; ;
            operand2 object sphere centre (0 0 0) radius 1.55 ; ;
            intersect
            ;
            material called die-ivory ;
        ;
        operand2 object csg
                operand1 object csg
                    operand1 object csg
                        operand1 object csg
                            operand1 object sphere centre (0 0 1.07) radius 0.2 ; ;
                            operand2 object sphere centre (-0.5 -0.5 -1.07) radius 0.2 ; ;
                            union
                            ;
                        ;
                        operand2 object csg
                            operand1 object sphere centre (0.5 0.5 -1.07) radius 0.2 ; ;
                            operand2 object csg
                                operand1 object sphere centre (-0.5 0.5 -1.07) radius 0.2 ; ;
                                operand2 object sphere centre (0.5 -0.5 -1.07) radius 0.2 ; ;
                                union
                                ;
                            ;
                            union
                            ;
                        ;
                        union
                        ;
                    ;
                    operand2 object csg
                        operand1 object csg
                            operand1 object sphere centre (-0.5 0 -1.07) radius 0.2 ; ;
                            operand2 object sphere centre (0.5 0 -1.07) radius 0.2 ; ;
                            union
                            ;
                        ;
                        operand2 object csg
                            operand1 object sphere centre (-0.5 1.07 -0.5) radius 0.2 ; ;
                            operand2 object csg
                                operand1 object sphere centre (0.5 1.07 0.5) radius 0.2 ; ;
                                operand2 object sphere centre (-0.5 -1.07 -0.5) radius 0.2 ; ;
                                union
                                ;
                            ;
                            union
                            ;
                        ;
                        union
                        ;
                    ;
                    union
                    ;
                ;
                operand2 object csg
                    operand1 object csg
                        operand1 object csg
                            operand1 object sphere centre (0.5 -1.07 0.5) radius 0.2 ; ;
                            operand2 object sphere centre (-0.5 -1.07 0.5) radius 0.2 ; ;
                            union
                            ;
                        ;
                        operand2 object csg
                            operand1 object sphere centre (0.5 -1.07 -0.5) radius 0.2 ; ;
                            operand2 object csg
                                operand1 object sphere centre (0 -1.07 0) radius 0.2 ; ;
                                operand2 object sphere centre (1.07 -0.5 -0.5) radius 0.2 ; ;
                                union
                                ;
                            ;
                            union
                            ;
                        ;
                        union
                        ;
                    ;
                    operand2 object csg
                        operand1 object csg
                            operand1 object sphere centre (1.07 0 0) radius 0.2 ; ;
                            operand2 object csg
                                operand1 object sphere centre (1.07 0.5 0.5) radius 0.2 ; ;
                                operand2 object sphere centre (-1.07 -0.5 -0.5) radius 0.2 ; ;
                                union
                                ;
                            ;
                            union
                            ;
                        ;
                        operand2 object csg
                            operand1 object sphere centre (-1.07 0.5 0.5) radius 0.2 ; ;
                            operand2 object csg
                                operand1 object sphere centre (-1.07 -0.5 0.5) radius 0.2 ; ;
                                operand2 object sphere centre (-1.07 0.5 -0.5) radius 0.2 ; ;
                                union
                                ;
                            ;
                            union
                            ;
                        ;
                        union
                        ;
                    ;
                    union
                    ;
                ;
                union
                ;
            material called die-pip ;
        ;
        subtract
        ;
    ;
    ;
;
