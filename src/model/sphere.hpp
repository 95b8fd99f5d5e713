// Geographic meshes: nodes given in longitude and latitude (degrees) on a
// sphere of radius kEarthRadius. The mesh builders (mesh.cpp) work in a
// plane; for a geographic mesh that plane is the stereographic projection
// about the nodes' mean direction, and every length, distance, area and
// centroid the engine reads is taken on the sphere instead (great circles,
// spherical polygons), so that none depends on where the plane is centred.
// Stereographic is conformal: directions in the plane are true directions on
// the sphere, so a face's normal and tangent come from the plane, and each
// cell's least-squares gradient from its neighbours' offsets as seen from the
// cell on the sphere (distance and direction of the great circle). What is
// left of the plane is the direction of chords: angles off by about
// d r / (4 R^2) for cells d apart at r from the centre (2e-5 radians for
// 1 km cells 2800 km away).
#pragma once

#include <cstdint>

namespace dpsm {

// The mean radius of the Earth (IUGG R1), in metres.
constexpr double kEarthRadius = 6371008.8;

struct PlanePoint {
    double x, y;
};

class Stereographic {
public:
    // The projection about the mean direction of the nodes (node_lonlat:
    // longitude, latitude in degrees, 2 per node). Checks the nodes (latitude
    // within [-90, 90], longitude within [-540, 540], every node within 90
    // degrees of arc of the centre) and throws Error(DPSM_ERR_INVALID_VALUE)
    // naming the node as a host counting from `base` does.
    Stereographic(const double *node_lonlat, std::int64_t nnodes, const char *function, int base);

    // Degrees to the plane (metres at the centre) and back.
    PlanePoint forward(double lon_degrees, double lat_degrees) const;
    void inverse(PlanePoint p, double &lon_degrees, double &lat_degrees) const;
    // The great-circle distance between two points of the plane, metres.
    double distance(PlanePoint p, PlanePoint q) const;
    // The signed area (positive counter-clockwise in the plane) of the
    // spherical polygon with great-circle edges through `n` points of the
    // plane, square metres.
    double polygon_area(const PlanePoint *points, std::int64_t n) const;
    // The centroid on the sphere of that polygon (the area-weighted mean of
    // its fan triangles' centres, normalised), back in the plane: a point
    // that does not depend on where the projection is centred.
    PlanePoint polygon_centroid(const PlanePoint *points, std::int64_t n) const;
    // The offset from `from` to `to` as seen at `from` on the sphere: the
    // great-circle distance (metres) along the great circle's direction at
    // `from`, in the plane's axes (where the projection keeps angles).
    PlanePoint offset(PlanePoint from, PlanePoint to) const;
    // The midpoint of the great circle between two points of the plane.
    PlanePoint midpoint(PlanePoint p, PlanePoint q) const;

private:
    struct Unit {
        double x, y, z;
    };
    Unit unit(PlanePoint p) const;
    PlanePoint to_plane(Unit u) const;  // u of length 1
    double lon0_ = 0.0;  // degrees, for inverse()
    Unit centre_{0, 0, 1}, east_{1, 0, 0}, north_{0, 1, 0};
};

}  // namespace dpsm
