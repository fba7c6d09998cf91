// The annulus 1 ≤ r ≤ 2 (a ring on a shaft), for the reader's tests.
// Made with Gmsh 4.15.2:
//   gmsh annulus.geo -2 -format msh41 -o annulus_41.msh
//   gmsh annulus.geo -2 -format msh41 -bin -o annulus_41_binary.msh
//   gmsh annulus.geo -2 -format msh22 -o annulus_22.msh
//   gmsh annulus.geo -2 -order 2 -format msh41 -o annulus_order2.msh          (refused)
//   gmsh annulus.geo -2 -string "Mesh.RecombineAll = 1;" -format msh41 -o annulus_quads.msh  (refused)
// Parts: inner (r = 1), outer (r = 2); the surface: domain.
SetFactory("Built-in");
DefineConstant[ h = {0.5, Name "mesh size"} ];
Point(1) = {0, 0, 0, h};
Point(2) = {1, 0, 0, h}; Point(3) = {0, 1, 0, h}; Point(4) = {-1, 0, 0, h}; Point(5) = {0, -1, 0, h};
Point(6) = {2, 0, 0, h}; Point(7) = {0, 2, 0, h}; Point(8) = {-2, 0, 0, h}; Point(9) = {0, -2, 0, h};
Circle(1) = {2, 1, 3}; Circle(2) = {3, 1, 4}; Circle(3) = {4, 1, 5}; Circle(4) = {5, 1, 2};
Circle(5) = {6, 1, 7}; Circle(6) = {7, 1, 8}; Circle(7) = {8, 1, 9}; Circle(8) = {9, 1, 6};
Curve Loop(1) = {5, 6, 7, 8};
Curve Loop(2) = {1, 2, 3, 4};
Plane Surface(1) = {1, 2};
Physical Curve("inner") = {1, 2, 3, 4};
Physical Curve("outer") = {5, 6, 7, 8};
Physical Surface("domain") = {1};
