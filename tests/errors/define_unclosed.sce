// expect: 1 define_unclosed.sce:3:8: error: undefined complex object 'pair': its definition (line 2) is not closed yet (';' missing?)
define object name pair object sphere ; ; object box ; ;
object pair ; ;
