~ bg_tumbler.sce - a glass tumbler (bgammon.sce): a thick-bottomed glass
  cylinder hollowed out by CSG subtraction; tumbler-full holds whisky.
  The whisky does not bend light (refractive-index 1): portray does not
  track media inside media, so a liquid touching glass would be treated as
  liquid next to air, with total internal reflection at its bottom.
  Stand them a hair above the table (translate y 0.005): a glass bottom
  exactly on the table top is a coplanar contact, where the tracer cannot
  tell which surface a ray meets first. ~

define object
    name tumbler
    object csg
        operand1 object cylinder from (0 0 0) to (0 2.6 0) radius 0.95 capped ; ;
        operand2 object cylinder from (0 0.35 0) to (0 2.8 0) radius 0.85 capped ; ;
        subtract
        ;
        material called glass ;
    ;
    ;
;

define object
    name tumbler-full
    object tumbler ; ;
    object cylinder from (0 0.351 0) to (0 1.3 0) radius 0.849 capped ; material called whisky ; ;
;
;
