~ bg_table.sce - the pine table (bgammon.sce): a top of five planks on
  four legs. Each plank is cut from a different part of the same wood (its
  box lies elsewhere in its own object space and is translated into
  place), so the grain differs from plank to plank. ~

object box a (-14 -1 0) b (14 0 3.57) ; translate (0 0 -9) material called pine ; ;
object box a (-8.3 -1 11.3) b (19.7 0 14.87) ; translate (-5.7 0 -16.7) material called pine ; ;
object box a (-2.6 -1 22.6) b (25.4 0 26.17) ; translate (-11.4 0 -24.4) material called pine ; ;
object box a (3.1 -1 33.9) b (31.1 0 37.47) ; translate (-17.1 0 -32.1) material called pine ; ;
object box a (8.8 -1 45.2) b (36.8 0 48.77) ; translate (-22.8 0 -39.8) material called pine ; ;
object box a (-13 -12 -8) b (-11.5 -1 -6.5) ; material called pine ; ;
object box a (11.5 -12 -8) b (13 -1 -6.5) ; material called pine ; ;
object box a (-13 -12 6.5) b (-11.5 -1 8) ; material called pine ; ;
object box a (11.5 -12 6.5) b (13 -1 8) ; material called pine ; ;
