// A brake shoe: the annular sector 10 ≤ r ≤ 13 m, 120° wide and symmetric about the −y axis,
// pressed onto a rigid cylinder of radius 10 m centred at the origin.
// Made with Gmsh 4.15.2:  gmsh brake_shoe.geo -2 -format msh41 -o brake_shoe.msh
// Parts (physical groups): lining (r = 10, the contact with the cylinder), back (r = 13),
// pivot (the end at −150°), tip (the end at −30°); the surface: shoe.
SetFactory("Built-in");
DefineConstant[ h = {0.3, Name "mesh size"} ];
a = 10; b = 13; phi = Pi / 3;   // ends at −90° ∓ 60°
Point(1) = {0, 0, 0, h};
Point(2) = {-a * Sin(phi), -a * Cos(phi), 0, h};
Point(3) = { a * Sin(phi), -a * Cos(phi), 0, h};
Point(4) = { b * Sin(phi), -b * Cos(phi), 0, h};
Point(5) = {-b * Sin(phi), -b * Cos(phi), 0, h};
Point(6) = {0, -a, 0, h};
Point(7) = {0, -b, 0, h};
Circle(1) = {2, 1, 6}; Circle(2) = {6, 1, 3};   // lining, from the pivot to the tip
Line(3) = {3, 4};                                // tip
Circle(4) = {4, 1, 7}; Circle(5) = {7, 1, 5};   // back
Line(6) = {5, 2};                                // pivot
Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Plane Surface(1) = {1};
Physical Curve("lining") = {1, 2};
Physical Curve("tip") = {3};
Physical Curve("back") = {4, 5};
Physical Curve("pivot") = {6};
Physical Surface("shoe") = {1};
Mesh.ElementOrder = 1;
