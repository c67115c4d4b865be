object sphere ; include x.inc ;
