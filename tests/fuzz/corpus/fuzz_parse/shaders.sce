define material named g colour (0.5 0.5 0.5) ; ;
material named b bricks mortar material colour (1 1 1) ; brick called g size 2 ; ;
material named t tiles face called g grout called b tile-width 6 grout-width 1 size 2 ; ;
material named c chequers material-a called g material-b called t size 0.5 ; ;
material named u bumpy size 2 terms 3 xsize 1 ysize 2 zsize 3 material called c saturation 1 depth 0.2 ; ;
material named n noise size 1 material called g varience 0.3 colour (1 0 0) ; ;
material named f fades axis (1 1 1) colours 0.1 (0 0 0) 2.0 (0 0 1) 0.0 (0 0 0) ; ;
material named f2 fades materials 1 called g 1 material colour (1 0 0) ; 0 called g ; ;
material named r turb3d terms 4 depth 1 size 2 material called f ; ;
