// expect: 1 inc/cycle_b.inc:2:9: error: include cycle: 'inc/cycle_a.inc' is already being read
include inc/cycle_a.inc
