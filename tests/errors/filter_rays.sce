// expect: 1 filter_rays.sce:2:78: error: filter disk: the filters so far trace 2097152 rays per sample (at most 1048576)
camera filter standard ; filter super-sample x-samples 1024 y-samples 1024 ; filter disk samples 2 ; ;
object sphere ; ;
