// layers.geo with a third cell group holding every cell: each cell in two physical groups.
Include "layers.geo";
Physical Surface("slab") = {1, 2};
