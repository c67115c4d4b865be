object csg
  operand1 object csg operand1 object sphere ; ; operand2 object box ; ; intersect ; ;
  operand2 object cylinder capped ; material colour (1 0 0) ; ;
  subtract
; ;
