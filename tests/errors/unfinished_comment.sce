// expect: 1 unfinished_comment.sce:3:1: error: unfinished '~' comment
object sphere ; ;
~ this comment
never ends
