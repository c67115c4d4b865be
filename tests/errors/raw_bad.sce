// expect: 1 inc/bad.raw:2: error: expected 9 numbers, found 5
object raw file inc/bad.raw ; ;
