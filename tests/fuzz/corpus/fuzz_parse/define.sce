define object name athing object sphere ; ; object box ; ; ;
       material named wood colour (0.5 0.3 0.1) ; ;
define object name wall object athing ; translate (1 0 0) ; object athing ; ; ; ;
object translate (0 0 1) wall ; material called wood ; ;
