object sphere centre (0 0 0) radius 1 ; material colour (1 0 0) ; ;
