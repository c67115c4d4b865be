object raw file teapot.raw weld 0.1 smooth x-rotation 90 at (0 1 0) ; ;
