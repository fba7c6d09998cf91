// A slab of two layers for tests/material_regions.rs: [0, 2] × [0, 0.5], the layer `first`
// on x < 0.5, `second` on x > 0.5; boundary parts left, right, bottom, top.
h = 0.25;
Point(1) = {0, 0, 0, h};
Point(2) = {0.5, 0, 0, h};
Point(3) = {2, 0, 0, h};
Point(4) = {2, 0.5, 0, h};
Point(5) = {0.5, 0.5, 0, h};
Point(6) = {0, 0.5, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 6};
Line(6) = {6, 1};
Line(7) = {2, 5};
Curve Loop(1) = {1, 7, 5, 6};
Plane Surface(1) = {1};
Curve Loop(2) = {2, 3, 4, -7};
Plane Surface(2) = {2};
Physical Curve("left") = {6};
Physical Curve("right") = {3};
Physical Curve("bottom") = {1, 2};
Physical Curve("top") = {4, 5};
Physical Surface("first") = {1};
Physical Surface("second") = {2};
