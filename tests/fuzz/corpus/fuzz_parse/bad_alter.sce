define material named m colour (1 1 1) ; ;
object sphere ; material called m colour (1 1 1) ; ;
object sphere ; material colour (1 1 1) called m ; ;
