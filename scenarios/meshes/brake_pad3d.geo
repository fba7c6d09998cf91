// The brake pad of brake_pad.geo extruded 40 mm along z (3D): a friction lining on a steel
// backplate outside a rigid drum of radius 0.150 m turning about the z axis.
// Made with Gmsh 4.15.2:  gmsh brake_pad3d.geo -3 -format msh41 -o brake_pad3d.msh
// Parts (physical groups): friction (r = 0.150), back (r = 0.166), abutment (the backplate's end
// at 120°), sides (the other radial ends and the two faces z = 0 and z = 0.04); cell regions:
// lining, backplate.
SetFactory("Built-in");
DefineConstant[ h = {0.005, Name "mesh size"}, hc = {0.0025, Name "mesh size at the friction face"},
                layers = {5, Name "cells across the width"} ];
a = 0.150; b = 0.160; c = 0.166; w = 0.04;
t1 = Pi / 3; t2 = 2 * Pi / 3;
Point(1) = {0, 0, 0, h};
Point(2) = {a * Cos(t1), a * Sin(t1), 0, hc};
Point(3) = {a * Cos(t2), a * Sin(t2), 0, hc};
Point(4) = {b * Cos(t1), b * Sin(t1), 0, h};
Point(5) = {b * Cos(t2), b * Sin(t2), 0, h};
Point(6) = {c * Cos(t1), c * Sin(t1), 0, h};
Point(7) = {c * Cos(t2), c * Sin(t2), 0, h};
Circle(1) = {2, 1, 3};
Circle(2) = {4, 1, 5};
Circle(3) = {6, 1, 7};
Line(4) = {2, 4};
Line(5) = {3, 5};
Line(6) = {4, 6};
Line(7) = {5, 7};
Curve Loop(1) = {1, 5, -2, -4};
Plane Surface(1) = {1};
Curve Loop(2) = {2, 7, -3, -6};
Plane Surface(2) = {2};
lining[] = Extrude {0, 0, w} { Surface{1}; Layers{layers}; };
plate[] = Extrude {0, 0, w} { Surface{2}; Layers{layers}; };
// Extrude returns [top, volume, the lateral surfaces in the order of the loop's curves].
Physical Surface("friction") = {lining[2]};
Physical Surface("back") = {plate[4]};
Physical Surface("abutment") = {plate[3]};
Physical Surface("sides") = {lining[3], lining[5], plate[5], 1, 2, lining[0], plate[0]};
Physical Volume("lining") = {lining[1]};
Physical Volume("backplate") = {plate[1]};
Mesh.ElementOrder = 1;
