object primitive plane position (0 -10 0) normal (0 1 0) x-axis (1 0 0) y-axis (0 0 1) ; ;
object cylinder from (10 0 0) to (-10 0 0) radius 1.0 capped ; shrink-x 2 stretch-y 3 ;
object box a (0 0 0) b (1 1 1) ; x-rotate 10 y-rotate 20 z-rotate 30 translate (1 2 3) ;
object triangle a (0 0 10) b (-5 0 0) c (5 0 0) normal-a (0 1 0) normal-b (0 1 0) normal-c (0 1 0) ; ;
object disk position (0 0 0) normal (0 0 1) radius 3 ; ;
object polygon contour (0 0 0) (4 0 0) (4 4 0) (0 4 0) ; contour (1 1 0) (2 1 0) (2 2 0) ; ; ;
