// expect: 1 raw_open.sce:4:10: error: unable to open raw file 'missing.raw'
object
  raw
    file missing.raw
  ;
;
