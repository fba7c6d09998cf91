// A brake pad on a rotating drum (2D): a friction lining (0.150 ≤ r ≤ 0.160 m) on a steel
// backplate (0.160 ≤ r ≤ 0.166 m), 60° wide about the +y axis, outside a rigid drum of radius
// 0.150 m centred at the origin.
// Made with Gmsh 4.15.2:  gmsh brake_pad.geo -2 -format msh41 -o brake_pad.msh
// Parts (physical groups): friction (r = 0.150, the contact with the drum), back (r = 0.166),
// abutment (the backplate's end at 120°, which holds the pad against the drag of a drum turning
// counter-clockwise), sides (the other three radial ends); cell regions: lining, backplate.
SetFactory("Built-in");
DefineConstant[ h = {0.002, Name "mesh size"}, hc = {0.0005, Name "mesh size at the friction face"} ];
a = 0.150; b = 0.160; c = 0.166;
t1 = Pi / 3; t2 = 2 * Pi / 3;
Point(1) = {0, 0, 0, h};
Point(2) = {a * Cos(t1), a * Sin(t1), 0, hc};
Point(3) = {a * Cos(t2), a * Sin(t2), 0, hc};
Point(4) = {b * Cos(t1), b * Sin(t1), 0, h};
Point(5) = {b * Cos(t2), b * Sin(t2), 0, h};
Point(6) = {c * Cos(t1), c * Sin(t1), 0, h};
Point(7) = {c * Cos(t2), c * Sin(t2), 0, h};
Circle(1) = {2, 1, 3};   // friction face, from 60° to 120°
Circle(2) = {4, 1, 5};   // lining | backplate
Circle(3) = {6, 1, 7};   // back
Line(4) = {2, 4};        // lining end at 60°
Line(5) = {3, 5};        // lining end at 120°
Line(6) = {4, 6};        // backplate end at 60°
Line(7) = {5, 7};        // backplate end at 120°: the abutment
Curve Loop(1) = {1, 5, -2, -4};
Plane Surface(1) = {1};
Curve Loop(2) = {2, 7, -3, -6};
Plane Surface(2) = {2};
Physical Curve("friction") = {1};
Physical Curve("back") = {3};
Physical Curve("abutment") = {7};
Physical Curve("sides") = {4, 5, 6};
Physical Surface("lining") = {1};
Physical Surface("backplate") = {2};
Mesh.ElementOrder = 1;
