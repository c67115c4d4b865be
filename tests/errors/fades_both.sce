// expect: 1 fades_both.sce:3:52: error: a fades takes one list: 'materials' or 'colours', never both
define material named m colour (1 1 1) ; ;
material named f fades colours 1 (0 0 0) 0 (1 1 1) materials 1 called m 0 called m ; ;
