light samples 4 ;
