// The sub-step's three face passes in vector lanes, over a range of faces
// (a dense sub-step) or a list (a sparse one): what
// FaceLaw::terms, gradient_flow_flux and limited_flux (mesh/mesh_engine.cpp)
// give, bit for bit, branch-free so that the compiler runs several faces at
// once (docs/performance.md, "The face passes in lanes"). The scalar
// functions stay the reference: they take the faces and scenes the lanes do
// not, and DPSM_SCALAR_MESH runs them alone, as the tests compare.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

namespace dpsm {

// What counts as the round-off of a sum, relative to its terms' magnitudes.
constexpr double kRoundOff = 64.0 * std::numeric_limits<double>::epsilon();

// A sum whose terms' magnitudes add up to `scale`, or 0 where it is within
// their round-off: where the parts of a flux cancel (a state the bed holds
// still) the rounding must not keep a face carrying sand for ever.
inline double beyond_round_off(double sum, double scale) {
    return std::fabs(sum) > kRoundOff * scale ? sum : 0.0;
}

// What a face does in a sub-step (carrying_faces): carries sand between its
// cells or over an open edge, lies between a sand cell and a wall (it
// carries none, but the surface on the sand's side of it counts in the
// faces' energy), or nothing (no sand on it).
enum FaceRole : std::uint8_t { kCarriesNothing = 0, kCarries = 1, kAlongWall = 2 };

// A plain scene: isotropic gradients, one angle of repose, no static angle,
// no bed, flux exponent 1 or 2.
struct FaceLanes {
    // The mesh (model/mesh.hpp).
    const std::int64_t *face_a, *face_b;
    const double *tangent_x, *tangent_y, *distance, *orthogonal, *skew, *conductance;
    // The sub-step's stored heights and the cells' gradients.
    const double *h, *gx, *gy;
    // Lazy sources behind the stored heights (Heights in mesh/mesh_engine.cpp):
    // a cell reads h + source_lag(q, dt, now - since). q null: none lags.
    const double *q, *since;
    double dt, now;
    double nu, tan_theta, tolerance;
    bool squared;  // flux exponent 2 (else 1)
    // What FaceLaw::terms writes, per face.
    double *low, *high, *pull, *excess;
    std::uint8_t *steep;
};

// Faces [begin, end) as if each carried sand between two cells; the caller
// then passes the others (on the domain edge, along a wall, carrying
// nothing) to FaceLaw::terms, which overwrites what this wrote for them.
void face_terms_in_lanes(const FaceLanes &lanes, std::int64_t begin, std::int64_t end);
// The same for the `count` faces of a list, each listed once (a sparse sub-step's).
void face_terms_in_lanes(const FaceLanes &lanes, const std::int64_t *faces, std::int64_t count);

// Whether each of `count` listed faces (each once) may be steep, as
// FaceLaw::may_be_steep finds it (its slope within a band of rounding below
// its threshold counts), into steep[f]: on a plain scene whose heights lag
// no source, each face as if it carried sand between two cells (the caller
// then passes the others to FaceLaw::may_be_steep). The look under the
// sources (mesh/mesh_engine.cpp) asks it of every face a source moves.
struct SteepLanes {
    const std::int64_t *face_a, *face_b;
    const double *tangent_x, *tangent_y, *distance;
    const double *h, *gx, *gy;
    double tan_theta, tolerance;
    std::uint8_t *steep;
};
void may_be_steep_in_lanes(const SteepLanes &lanes, const std::int64_t *faces, std::int64_t count);
// The same over faces [begin, end).
void may_be_steep_in_lanes(const SteepLanes &lanes, std::int64_t begin, std::int64_t end);

// The gradient flow's flux over faces [begin, end), any scene: high holds
// each face's two-point part and takes its flux, as gradient_flow_flux.
struct FlowLanes {
    const std::int64_t *face_a, *face_b;
    const std::uint8_t *carrying;  // per face, its FaceRole
    const double *pair_ax, *pair_ay, *pair_bx, *pair_by;
    const double *pull_x, *pull_y;
    double *high;
};
void flow_fluxes_in_lanes(const FlowLanes &lanes, std::int64_t begin, std::int64_t end);
void flow_fluxes_in_lanes(const FlowLanes &lanes, const std::int64_t *faces, std::int64_t count);

// The limited flux over faces [begin, end), without a bed (limited_flux with
// no cap), into flux. Returns the largest excess slope of the faces below
// `live` that carry sand, or -1 where none does.
struct LimitLanes {
    const std::int64_t *face_a, *face_b;
    const double *low, *high, *excess;
    const double *limit_in, *limit_out;
    double *flux;
};
double limited_fluxes_in_lanes(const LimitLanes &lanes, std::int64_t begin, std::int64_t end, std::int64_t live);
// The same over the `count` faces of a list (each once), the excess not sought.
void limited_fluxes_in_lanes(const LimitLanes &lanes, const std::int64_t *faces, std::int64_t count);

}  // namespace dpsm
