#include "model/sphere.hpp"

#include <cmath>

#include "dpsm/dpsm.h"
#include "model/error.hpp"
#include "model/mesh.hpp"

namespace dpsm {

namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

}  // namespace

Stereographic::Unit Stereographic::unit(PlanePoint p) const {
    const double s = (p.x * p.x + p.y * p.y) / (4.0 * kEarthRadius * kEarthRadius);
    const double a = (1.0 - s) / (1.0 + s), b = 1.0 / (kEarthRadius * (1.0 + s));
    return {a * centre_.x + b * (p.x * east_.x + p.y * north_.x), a * centre_.y + b * (p.x * east_.y + p.y * north_.y),
            a * centre_.z + b * (p.x * east_.z + p.y * north_.z)};
}

Stereographic::Stereographic(const double *node_lonlat, std::int64_t nnodes, const char *function, int base) {
    double sx = 0.0, sy = 0.0, sz = 0.0;
    for (std::int64_t n = 0; n < nnodes; ++n) {
        const double lon = node_lonlat[2 * n], lat = node_lonlat[2 * n + 1];
        if (!(std::fabs(lat) <= 90.0))
            fail(DPSM_ERR_INVALID_VALUE, function, host_position("node_lonlat", 2 * n + 1, base, 2), " (latitude of node ",
                 n + base, ") = ", lat, " is not within [-90, 90] degrees");
        if (!(std::fabs(lon) <= 540.0))
            fail(DPSM_ERR_INVALID_VALUE, function, host_position("node_lonlat", 2 * n, base, 2), " (longitude of node ",
                 n + base, ") = ", lon, " is not within [-540, 540] degrees");
        sx += std::cos(lat * kDegree) * std::cos(lon * kDegree);
        sy += std::cos(lat * kDegree) * std::sin(lon * kDegree);
        sz += std::sin(lat * kDegree);
    }
    const double length = std::sqrt(sx * sx + sy * sy + sz * sz);
    if (!(length > 1e-6 * static_cast<double>(nnodes)))
        fail(DPSM_ERR_INVALID_VALUE, function, "the nodes surround the globe (their mean direction is undefined); dpsm "
             "takes geographic meshes that lie within 90 degrees of arc of their centre");
    centre_ = {sx / length, sy / length, sz / length};
    const double lat0 = std::atan2(centre_.z, std::hypot(centre_.x, centre_.y));
    lon0_ = std::atan2(centre_.y, centre_.x) / kDegree;
    const double l0 = lon0_ * kDegree;
    east_ = {-std::sin(l0), std::cos(l0), 0.0};
    north_ = {-std::sin(lat0) * std::cos(l0), -std::sin(lat0) * std::sin(l0), std::cos(lat0)};
    // Within 90 degrees of the centre the plane's scale factor stays below 2,
    // and no node comes near the antipode, where the projection has no image.
    for (std::int64_t n = 0; n < nnodes; ++n) {
        const double lon = node_lonlat[2 * n] * kDegree, lat = node_lonlat[2 * n + 1] * kDegree;
        const double cosine = std::cos(lat) * std::cos(lon) * centre_.x + std::cos(lat) * std::sin(lon) * centre_.y +
                              std::sin(lat) * centre_.z;
        if (cosine < 0.0)
            fail(DPSM_ERR_INVALID_VALUE, function, "node ", n + base, " (", node_lonlat[2 * n], ", ",
                 node_lonlat[2 * n + 1], ") lies ", std::acos(std::fmax(-1.0, cosine)) / kDegree,
                 " degrees of arc from the mesh's centre (", lon0_, ", ", lat0 / kDegree,
                 "); dpsm takes geographic meshes that lie within 90 degrees of arc of their centre");
    }
}

PlanePoint Stereographic::forward(double lon_degrees, double lat_degrees) const {
    const double lon = lon_degrees * kDegree, lat = lat_degrees * kDegree;
    const Unit u{std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
    const double d = 1.0 + u.x * centre_.x + u.y * centre_.y + u.z * centre_.z;
    const double e = u.x * east_.x + u.y * east_.y + u.z * east_.z;
    const double n = u.x * north_.x + u.y * north_.y + u.z * north_.z;
    return {2.0 * kEarthRadius * e / d, 2.0 * kEarthRadius * n / d};
}

void Stereographic::inverse(PlanePoint p, double &lon_degrees, double &lat_degrees) const {
    const Unit u = unit(p);
    lat_degrees = std::atan2(u.z, std::hypot(u.x, u.y)) / kDegree;
    double lon = std::atan2(u.y, u.x) / kDegree;
    // The turn nearest the centre's, so that a mesh across 180 degrees reads as it was given.
    lon += 360.0 * std::round((lon0_ - lon) / 360.0);
    lon_degrees = lon;
}

double Stereographic::distance(PlanePoint p, PlanePoint q) const {
    const Unit a = unit(p), b = unit(q);
    // |a x b| as |a x (b - a)|: the difference keeps its digits for points a metre apart.
    const Unit d{b.x - a.x, b.y - a.y, b.z - a.z};
    const double cx = a.y * d.z - a.z * d.y, cy = a.z * d.x - a.x * d.z, cz = a.x * d.y - a.y * d.x;
    const double dot = a.x * b.x + a.y * b.y + a.z * b.z;
    return kEarthRadius * std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), dot);
}

double Stereographic::polygon_area(const PlanePoint *points, std::int64_t n) const {
    // A fan of spherical triangles from the first point, each by the formula
    // of van Oosterom and Strackee (1983): tan(E/2) = a.(b x c) / (1 + a.b + b.c + c.a),
    // the triple product taken over differences to keep its digits.
    const Unit a = unit(points[0]);
    double excess = 0.0;
    for (std::int64_t k = 1; k + 1 < n; ++k) {
        const Unit b = unit(points[k]), c = unit(points[k + 1]);
        const Unit ab{b.x - a.x, b.y - a.y, b.z - a.z}, ac{c.x - a.x, c.y - a.y, c.z - a.z};
        const double triple = a.x * (ab.y * ac.z - ab.z * ac.y) + a.y * (ab.z * ac.x - ab.x * ac.z) +
                              a.z * (ab.x * ac.y - ab.y * ac.x);
        const double denominator = 1.0 + (a.x * b.x + a.y * b.y + a.z * b.z) + (b.x * c.x + b.y * c.y + b.z * c.z) +
                                   (c.x * a.x + c.y * a.y + c.z * a.z);
        excess += 2.0 * std::atan2(triple, denominator);
    }
    return excess * kEarthRadius * kEarthRadius;
}

PlanePoint Stereographic::polygon_centroid(const PlanePoint *points, std::int64_t n) const {
    const Unit a = unit(points[0]);
    double sx = 0.0, sy = 0.0, sz = 0.0;
    for (std::int64_t k = 1; k + 1 < n; ++k) {
        const PlanePoint fan[3] = {points[0], points[k], points[k + 1]};
        const double weight = polygon_area(fan, 3);
        const Unit b = unit(points[k]), c = unit(points[k + 1]);
        // The triangle's centre (a + b + c) / 3, relative to a to keep its digits.
        sx += weight * ((b.x - a.x) + (c.x - a.x)) / 3.0;
        sy += weight * ((b.y - a.y) + (c.y - a.y)) / 3.0;
        sz += weight * ((b.z - a.z) + (c.z - a.z)) / 3.0;
    }
    const double total = polygon_area(points, n);
    Unit u{a.x + sx / total, a.y + sy / total, a.z + sz / total};
    const double length = std::sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
    return to_plane({u.x / length, u.y / length, u.z / length});
}

PlanePoint Stereographic::midpoint(PlanePoint p, PlanePoint q) const {
    const Unit a = unit(p), b = unit(q);
    const Unit u{a.x + 0.5 * (b.x - a.x), a.y + 0.5 * (b.y - a.y), a.z + 0.5 * (b.z - a.z)};
    const double length = std::sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
    return to_plane({u.x / length, u.y / length, u.z / length});
}

PlanePoint Stereographic::offset(PlanePoint from, PlanePoint to) const {
    const Unit a = unit(from), b = unit(to);
    const double along = a.x * b.x + a.y * b.y + a.z * b.z;
    // The great circle's direction at a: b less its part along a.
    Unit t{(b.x - a.x) - (along - 1.0) * a.x, (b.y - a.y) - (along - 1.0) * a.y, (b.z - a.z) - (along - 1.0) * a.z};
    const double norm_t = std::sqrt(t.x * t.x + t.y * t.y + t.z * t.z);
    if (!(norm_t > 0.0)) return {0.0, 0.0};
    t = {t.x / norm_t, t.y / norm_t, t.z / norm_t};
    // Its image in the plane, by a central difference over a few metres.
    const double e = 1e-6;
    const auto moved = [&](double s) {
        Unit u{a.x + s * t.x, a.y + s * t.y, a.z + s * t.z};
        const double n = std::sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
        return to_plane({u.x / n, u.y / n, u.z / n});
    };
    const PlanePoint ahead = moved(e), behind = moved(-e);
    const double dx = ahead.x - behind.x, dy = ahead.y - behind.y, length = std::hypot(dx, dy);
    const double d = distance(from, to);
    return {d * dx / length, d * dy / length};
}

PlanePoint Stereographic::to_plane(Unit u) const {
    const double d = 1.0 + u.x * centre_.x + u.y * centre_.y + u.z * centre_.z;
    return {2.0 * kEarthRadius * (u.x * east_.x + u.y * east_.y + u.z * east_.z) / d,
            2.0 * kEarthRadius * (u.x * north_.x + u.y * north_.y + u.z * north_.z) / d};
}

}  // namespace dpsm
