// An unstructured disk of radius 2.5 for the column collapse (dpsm-bench
// mesh-accuracy): triangles of size h (gmsh -2 -setnumber h 0.04 disk.geo).
DefineConstant[ h = {0.08, Name "mesh size"} ];
Point(1) = {0, 0, 0, h};
Point(2) = {2.5, 0, 0, h};
Point(3) = {0, 2.5, 0, h};
Point(4) = {-2.5, 0, 0, h};
Point(5) = {0, -2.5, 0, h};
Circle(1) = {2, 1, 3};
Circle(2) = {3, 1, 4};
Circle(3) = {4, 1, 5};
Circle(4) = {5, 1, 2};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Physical Surface("table") = {1};
Physical Curve("edge") = {1, 2, 3, 4};
