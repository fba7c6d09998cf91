// A brake pad in 3D: the annular sector 10 ≤ r ≤ 13 m, 60° wide and symmetric about the −y axis,
// extruded 4 m along z, pressed onto a rigid cylinder of radius 10 m (axis z).
// Made with Gmsh 4.15.2:  gmsh pad3d.geo -3 -format msh41 -o pad3d.msh
// Parts (physical groups): contact (the cylindrical face r = 10), back (r = 13), pivot (the end
// at −120°), tip (the end at −60°), sides (z = 0 and z = 4); the volume: pad.
SetFactory("Built-in");
DefineConstant[ h = {0.5, Name "mesh size"} ];
a = 10; b = 13; phi = Pi / 6; w = 4;
Point(1) = {0, 0, 0, h};
Point(2) = {-a * Sin(phi), -a * Cos(phi), 0, h};
Point(3) = { a * Sin(phi), -a * Cos(phi), 0, h};
Point(4) = { b * Sin(phi), -b * Cos(phi), 0, h};
Point(5) = {-b * Sin(phi), -b * Cos(phi), 0, h};
Circle(1) = {2, 1, 3};
Line(2) = {3, 4};
Circle(3) = {4, 1, 5};
Line(4) = {5, 2};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
out[] = Extrude {0, 0, w} { Surface{1}; };
// out[0]: the top (z = w), out[1]: the volume, out[2..5]: the faces swept by curves 1..4.
Physical Surface("contact") = {out[2]};
Physical Surface("tip") = {out[3]};
Physical Surface("back") = {out[4]};
Physical Surface("pivot") = {out[5]};
Physical Surface("sides") = {1, out[0]};
Physical Volume("pad") = {out[1]};
Mesh.ElementOrder = 1;
