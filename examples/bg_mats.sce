~ bg_mats.sce - materials for bgammon.sce: pine, mahogany, brass, baize,
  the colours of the points and checkers, and glass. ~

// pine: pale yellow wood with narrow darker grain lines running along x,
// made to wander by turbulence (turb3d over a fades colour list)
define material named pine
    turb3d size 4 depth 0.3 terms 4
        material material
            specular-reflection 0.25 specular-power 30 spec-colour (1 1 1)
            fades axis (0 0.1 1)
                colours 0.28 (0.93 0.78 0.52) 0.04 (0.9 0.72 0.46) 0.07 (0.72 0.46 0.22)
                        0 (0.93 0.78 0.52) ;
        ;
    ;
;
;

// mahogany for the board's case
define material named mahogany
    turb3d size 2 depth 0.08 terms 3
        material material
            specular-reflection 0.5 specular-power 60 spec-colour (1 1 1) reflection 0.05
            fades axis (1 0.1 0)
                colours 0.12 (0.45 0.16 0.08) 0.05 (0.32 0.1 0.05) 0 (0.45 0.16 0.08) ;
        ;
    ;
;
;

define material named brass
    colour (0.85 0.62 0.25) spec-colour (1 0.85 0.5) diffuse-reflection 0.5
    specular-reflection 0.9 specular-power 80 reflection 0.45 ;
;

define material named baize
    colour (0.12 0.35 0.18) noise size 0.05 colour (1 1 1) varience 0.2 ;
    ;
;

define material named point-red
    colour (0.7 0.1 0.08) specular-reflection 0.2 specular-power 20 spec-colour (1 1 1) ;
;
define material named point-cream
    colour (0.92 0.86 0.7) specular-reflection 0.2 specular-power 20 spec-colour (1 1 1) ;
;

define material named checker-white
    colour (0.95 0.93 0.88) specular-reflection 0.6 specular-power 60 spec-colour (1 1 1) ;
;
define material named checker-black
    colour (0.08 0.07 0.07) specular-reflection 0.6 specular-power 60 spec-colour (1 1 1) ;
;

define material named glass
    colour (1 1 1) diffuse-reflection 0 specular-reflection 0.9 specular-power 300
    reflection 0.08 transparency 0.92 refractive-index 1.5 ;
;

define material named whisky
    colour (0.9 0.6 0.2) diffuse-reflection 0.05 specular-reflection 0.6 specular-power 200
    transparency 0.9 tran-colour (1 0.8 0.45) refractive-index 1 ;
;
