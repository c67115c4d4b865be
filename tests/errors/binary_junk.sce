// expect: 1 binary_junk.sce:3:1: error: unknown verb in scene file near '\xff\xfe\x9b[31mred'
object sphere ; ;
ÿþ›[31mred ;
