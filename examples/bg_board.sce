~ bg_board.sce - the backgammon board (bgammon.sce): a mahogany case with
  two baize playing fields, 24 points in red and cream, a centre bar, and
  brass inlays along the borders with brass hinges on the bar. The board
  lies centred on the origin, on y = 0. ~

define object
    name backgammon-board
    // the case: base and borders
    object box a (-5.2 0 -3.6) b (5.2 0.22 3.6) ; material called mahogany ; ;
    object box a (-5.2 0.22 -3.6) b (-4.8 0.45 3.6) ; material called mahogany ; ;
    object box a (4.8 0.22 -3.6) b (5.2 0.45 3.6) ; material called mahogany ; ;
    object box a (-5.2 0.22 -3.6) b (5.2 0.45 -3.2) ; material called mahogany ; ;
    object box a (-5.2 0.22 3.2) b (5.2 0.45 3.6) ; material called mahogany ; ;
    object box a (-0.5 0.22 -3.6) b (0.5 0.45 3.6) ; material called mahogany ; ;
    // the playing fields
    object box a (-4.8 0.2 -3.2) b (-0.5 0.221 3.2) ; material called baize ; ;
    object box a (0.5 0.2 -3.2) b (4.8 0.221 3.2) ; material called baize ; ;
    // brass inlays: strips set into the top of the borders, corner plates
    object box a (-5.1 0.45 -3.5) b (5.1 0.47 -3.32) ; material called brass ; ;
    object box a (-5.1 0.45 3.32) b (5.1 0.47 3.5) ; material called brass ; ;
    object box a (-5.1 0.45 -3.5) b (-4.92 0.47 3.5) ; material called brass ; ;
    object box a (4.92 0.45 -3.5) b (5.1 0.47 3.5) ; material called brass ; ;
    object box a (-0.09 0.45 -3.5) b (0.09 0.47 3.5) ; material called brass ; ;
    object box a (-5.2 0.45 -3.6) b (-4.6 0.48 -3) ; material called brass ; ;
    object box a (4.6 0.45 -3.6) b (5.2 0.48 -3) ; material called brass ; ;
    object box a (-5.2 0.45 3) b (-4.6 0.48 3.6) ; material called brass ; ;
    object box a (4.6 0.45 3) b (5.2 0.48 3.6) ; material called brass ; ;
    // brass hinges on the bar
    object cylinder from (0 0.5 -2.5) to (0 0.5 -1.3) radius 0.18 capped ; material called brass ; ;
    object cylinder from (0 0.5 1.3) to (0 0.5 2.5) radius 0.18 capped ; material called brass ; ;
    // the points
    object triangle a (-4.8 0.222 -3.2) b (-4.083 0.222 -3.2) c (-4.442 0.222 -0.5) ; material called point-red ; ;
    object triangle a (-4.083 0.222 -3.2) b (-3.367 0.222 -3.2) c (-3.725 0.222 -0.5) ; material called point-cream ; ;
    object triangle a (-3.367 0.222 -3.2) b (-2.65 0.222 -3.2) c (-3.008 0.222 -0.5) ; material called point-red ; ;
    object triangle a (-2.65 0.222 -3.2) b (-1.933 0.222 -3.2) c (-2.292 0.222 -0.5) ; material called point-cream ; ;
    object triangle a (-1.933 0.222 -3.2) b (-1.217 0.222 -3.2) c (-1.575 0.222 -0.5) ; material called point-red ; ;
    object triangle a (-1.217 0.222 -3.2) b (-0.5 0.222 -3.2) c (-0.858 0.222 -0.5) ; material called point-cream ; ;
    object triangle a (-4.8 0.222 3.2) b (-4.083 0.222 3.2) c (-4.442 0.222 0.5) ; material called point-cream ; ;
    object triangle a (-4.083 0.222 3.2) b (-3.367 0.222 3.2) c (-3.725 0.222 0.5) ; material called point-red ; ;
    object triangle a (-3.367 0.222 3.2) b (-2.65 0.222 3.2) c (-3.008 0.222 0.5) ; material called point-cream ; ;
    object triangle a (-2.65 0.222 3.2) b (-1.933 0.222 3.2) c (-2.292 0.222 0.5) ; material called point-red ; ;
    object triangle a (-1.933 0.222 3.2) b (-1.217 0.222 3.2) c (-1.575 0.222 0.5) ; material called point-cream ; ;
    object triangle a (-1.217 0.222 3.2) b (-0.5 0.222 3.2) c (-0.858 0.222 0.5) ; material called point-red ; ;
    object triangle a (0.5 0.222 -3.2) b (1.217 0.222 -3.2) c (0.858 0.222 -0.5) ; material called point-red ; ;
    object triangle a (1.217 0.222 -3.2) b (1.933 0.222 -3.2) c (1.575 0.222 -0.5) ; material called point-cream ; ;
    object triangle a (1.933 0.222 -3.2) b (2.65 0.222 -3.2) c (2.292 0.222 -0.5) ; material called point-red ; ;
    object triangle a (2.65 0.222 -3.2) b (3.367 0.222 -3.2) c (3.008 0.222 -0.5) ; material called point-cream ; ;
    object triangle a (3.367 0.222 -3.2) b (4.083 0.222 -3.2) c (3.725 0.222 -0.5) ; material called point-red ; ;
    object triangle a (4.083 0.222 -3.2) b (4.8 0.222 -3.2) c (4.442 0.222 -0.5) ; material called point-cream ; ;
    object triangle a (0.5 0.222 3.2) b (1.217 0.222 3.2) c (0.858 0.222 0.5) ; material called point-cream ; ;
    object triangle a (1.217 0.222 3.2) b (1.933 0.222 3.2) c (1.575 0.222 0.5) ; material called point-red ; ;
    object triangle a (1.933 0.222 3.2) b (2.65 0.222 3.2) c (2.292 0.222 0.5) ; material called point-cream ; ;
    object triangle a (2.65 0.222 3.2) b (3.367 0.222 3.2) c (3.008 0.222 0.5) ; material called point-red ; ;
    object triangle a (3.367 0.222 3.2) b (4.083 0.222 3.2) c (3.725 0.222 0.5) ; material called point-cream ; ;
    object triangle a (4.083 0.222 3.2) b (4.8 0.222 3.2) c (4.442 0.222 0.5) ; material called point-red ; ;
;
;

// a checker: a short capped cylinder with a bevelled look from its highlight
define object
    name checker
    object cylinder from (0 0 0) to (0 0.14 0) radius 0.3 capped ; ;
;
;
