object sphere radius 1.2.3 ; ;
~ unfinished