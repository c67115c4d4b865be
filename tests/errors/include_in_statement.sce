// expect: 1 include_in_statement.sce:4:5: error: 'include' inside a statement ('object' at line 2): only allowed between statements
object
    sphere ;
    include inc/mats.inc
;
