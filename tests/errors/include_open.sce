// expect: 1 include_open.sce:3:9: error: unable to open include file 'inc/missing.inc'
object sphere ; ;
include inc/missing.inc
