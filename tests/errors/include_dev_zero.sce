// expect: 1 /dev/zero:1:1: error: NUL byte (the include file is not text)
object sphere ; ;
include /dev/zero
