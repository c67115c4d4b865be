// expect: 1 fades_unclosed.sce:2:50: error: distance expected in the 'colours' list (it ends with an entry whose distance is 0) near ';'
object sphere ; material fades colours 1 (1 0 0) ; ; ; ;
