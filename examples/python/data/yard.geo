// A stockyard for examples/python/mesh_pile.py: an irregular boundary (a
// straight quay, a curved embankment) around a round silo. Made with
//   gmsh -2 -format msh22 examples/python/data/yard.geo -o examples/python/data/yard.msh
// (gmsh 4.8.4, Debian's package).
h = 0.16;
Point(1) = {0, 0, 0, h};
Point(2) = {6, 0, 0, h};
Point(3) = {6.5, 2.5, 0, h};
Point(4) = {4, 4.2, 0, h};
Point(5) = {0.8, 3.6, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
BSpline(3) = {3, 4, 5};
Line(4) = {5, 1};
// The silo: a circle of radius 0.6 at (4.2, 1.6).
Point(10) = {4.2, 1.6, 0, h};
Point(11) = {4.8, 1.6, 0, h / 2};
Point(12) = {4.2, 2.2, 0, h / 2};
Point(13) = {3.6, 1.6, 0, h / 2};
Point(14) = {4.2, 1.0, 0, h / 2};
Circle(5) = {11, 10, 12};
Circle(6) = {12, 10, 13};
Circle(7) = {13, 10, 14};
Circle(8) = {14, 10, 11};
Curve Loop(1) = {1, 2, 3, 4};
Curve Loop(2) = {5, 6, 7, 8};
Plane Surface(1) = {1, 2};
Physical Surface("yard") = {1};
