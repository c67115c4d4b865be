object sphere ; material called nowhere ; ;
