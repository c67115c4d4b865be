// expect: 1 /dev/zero:1: error: NUL byte (a raw file is text)
object raw file /dev/zero ; ; ;
