#include "mesh/face_lanes.hpp"

#include <cmath>

#include "model/ledger.hpp"

// Clang builds the plain copy alone, for the baseline instructions, where
// the gathers have no lanes: the pragmas are hints there, not demands.
#if defined(__clang__)
#pragma clang diagnostic ignored "-Wpass-failed"
#endif

// GCC builds a copy for AVX-512, one for AVX2 and a plain one of each pass,
// and picks one when the library loads; the copies round alike.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define LANE_COPIES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define LANE_COPIES
#endif

namespace dpsm {

// Every operation is FaceLaw::terms's, in its order, on one face per lane:
// the early returns there are selects here, whose both sides are computed
// (a division by a zero slope in a lane that does not carry is thrown away;
// this file is built without floating-point traps or errno, and without
// contraction, so each lane rounds as the scalar code). A copy per flux
// exponent: a select on it would keep the compiler from the lanes.
// With kListed, the faces list[begin, end) (each once), else faces [begin, end);
// with kLagged, each cell's height with what its lazy source added since.
template <bool kSquared, bool kListed, bool kLagged>
__attribute__((always_inline)) inline void terms_in_lanes(const FaceLanes &lanes, const std::int64_t *list,
                                                          std::int64_t begin, std::int64_t end) {
    const std::int64_t *__restrict face_a = lanes.face_a, *__restrict face_b = lanes.face_b;
    const double *__restrict tangent_x = lanes.tangent_x, *__restrict tangent_y = lanes.tangent_y;
    const double *__restrict distances = lanes.distance, *__restrict orthogonals = lanes.orthogonal;
    const double *__restrict skews = lanes.skew, *__restrict conductances = lanes.conductance;
    const double *__restrict h = lanes.h, *__restrict gx = lanes.gx, *__restrict gy = lanes.gy;
    const double *__restrict q = lanes.q, *__restrict since = lanes.since;
    const double dt = lanes.dt, now = lanes.now;
    double *__restrict low = lanes.low, *__restrict high = lanes.high, *__restrict pull = lanes.pull;
    double *__restrict excess = lanes.excess;
    std::uint8_t *__restrict steep = lanes.steep;
    const double nu = lanes.nu, tan_face = lanes.tan_theta, tolerance = lanes.tolerance;
    const double threshold = tan_face * (1.0 + tolerance), flat = tolerance * tan_face;
#pragma omp simd
    for (std::int64_t i = begin; i < end; ++i) {
        const std::int64_t f = kListed ? list[i] : i;
        const std::int64_t a = face_a[f], b_or_edge = face_b[f], b = b_or_edge < 0 ? a : b_or_edge;
        const double tangential =
            0.5 * ((gx[a] + gx[b]) * tangent_x[f] + (gy[a] + gy[b]) * tangent_y[f]);
        const double distance = distances[f];
        // As Heights reads them.
        const double ha = kLagged ? h[a] + source_lag(q[a], dt, now - since[a]) : h[a];
        const double hb = kLagged ? h[b] + source_lag(q[b], dt, now - since[b]) : h[b];
        const double normal = (ha - hb) / distance;
        const double s = std::sqrt(normal * normal + tangential * tangential);
        const bool is_steep = s > threshold;
        // slide_flux (model/face_law.hpp) over s.
        const double beyond = s - tan_face;
        const double power = kSquared ? beyond * beyond : beyond;
        const double flux = nu * power / std::sqrt(1.0 + s * s);
        const double g = (beyond > 0.0 ? flux : 0.0) / s;
        const double orthogonal = orthogonals[f];
        const double diamond = 0.5 * orthogonal * distance;
        const double two_point = diamond * g * normal / distance;
        const double face_pull = diamond * g * tangential * 0.5;
        // The monotone flux: C (h_a - h_b) with C held in [0, |L n| / d].
        const double abs_normal = std::fabs(normal), skew = skews[f];
        const double skewed = orthogonal - tangential * skew / normal;
        const double most = conductances[f] * distance;
        double factor = skew != 0.0 ? skewed : orthogonal;
        factor = most < factor ? most : factor;
        const double across = factor * abs_normal / most;
        const bool monotone = abs_normal > flat && across > flat;
        low[f] = is_steep && monotone ? g * factor * normal : 0.0;
        high[f] = is_steep ? two_point : 0.0;
        pull[f] = is_steep ? face_pull : 0.0;
        excess[f] = is_steep ? beyond : 0.0;
        steep[f] = is_steep;
    }
}

// One copy for each exponent and whether sources lag.
template <bool kListed>
__attribute__((always_inline)) inline void terms_for_scene(const FaceLanes &lanes, const std::int64_t *list,
                                                           std::int64_t begin, std::int64_t end) {
    if (lanes.squared) {
        if (lanes.q)
            terms_in_lanes<true, kListed, true>(lanes, list, begin, end);
        else
            terms_in_lanes<true, kListed, false>(lanes, list, begin, end);
    } else {
        if (lanes.q)
            terms_in_lanes<false, kListed, true>(lanes, list, begin, end);
        else
            terms_in_lanes<false, kListed, false>(lanes, list, begin, end);
    }
}

LANE_COPIES
void face_terms_in_lanes(const FaceLanes &lanes, std::int64_t begin, std::int64_t end) {
    terms_for_scene<false>(lanes, nullptr, begin, end);
}

LANE_COPIES
void face_terms_in_lanes(const FaceLanes &lanes, const std::int64_t *faces, std::int64_t count) {
    terms_for_scene<true>(lanes, faces, 0, count);
}

// FaceLaw::slope and may_be_steep's arithmetic, in their order; with
// kListed, the faces list[begin, end), else faces [begin, end).
template <bool kListed>
__attribute__((always_inline)) inline void steep_in_lanes(const SteepLanes &lanes, const std::int64_t *list,
                                                          std::int64_t begin, std::int64_t end) {
    const std::int64_t *__restrict face_a = lanes.face_a, *__restrict face_b = lanes.face_b;
    const double *__restrict tangent_x = lanes.tangent_x, *__restrict tangent_y = lanes.tangent_y;
    const double *__restrict distances = lanes.distance;
    const double *__restrict h = lanes.h, *__restrict gx = lanes.gx, *__restrict gy = lanes.gy;
    std::uint8_t *__restrict steep = lanes.steep;
    const double threshold = lanes.tan_theta * (1.0 + lanes.tolerance);
#pragma omp simd
    for (std::int64_t i = begin; i < end; ++i) {
        const std::int64_t f = kListed ? list[i] : i;
        const std::int64_t a = face_a[f], b_or_edge = face_b[f], b = b_or_edge < 0 ? a : b_or_edge;
        const double ha = h[a], hb = h[b], distance = distances[f];
        const double tangential =
            0.5 * ((gx[a] + gx[b]) * tangent_x[f] + (gy[a] + gy[b]) * tangent_y[f]);
        const double normal = (ha - hb) / distance;
        const double s = std::sqrt(normal * normal + tangential * tangential);
        const double band = 1e-9 * threshold + kRoundOff * (std::fabs(ha) + std::fabs(hb)) / distance;
        steep[f] = s > threshold - band;
    }
}

LANE_COPIES
void may_be_steep_in_lanes(const SteepLanes &lanes, std::int64_t begin, std::int64_t end) {
    steep_in_lanes<false>(lanes, nullptr, begin, end);
}

LANE_COPIES
void may_be_steep_in_lanes(const SteepLanes &lanes, const std::int64_t *faces, std::int64_t count) {
    steep_in_lanes<true>(lanes, faces, 0, count);
}

template <bool kListed>
__attribute__((always_inline)) inline void flow_in_lanes(const FlowLanes &lanes, const std::int64_t *list,
                                                         std::int64_t begin, std::int64_t end) {
    const std::int64_t *__restrict face_a = lanes.face_a, *__restrict face_b = lanes.face_b;
    const std::uint8_t *__restrict carrying = lanes.carrying;
    const double *__restrict pair_ax = lanes.pair_ax, *__restrict pair_ay = lanes.pair_ay;
    const double *__restrict pair_bx = lanes.pair_bx, *__restrict pair_by = lanes.pair_by;
    const double *__restrict pull_x = lanes.pull_x, *__restrict pull_y = lanes.pull_y;
    double *__restrict high = lanes.high;
#pragma omp simd
    for (std::int64_t i = begin; i < end; ++i) {
        const std::int64_t f = kListed ? list[i] : i;
        const std::int64_t a = face_a[f], b_or_edge = face_b[f], b = b_or_edge < 0 ? a : b_or_edge;
        const double two_point = high[f];
        const double from_b = pair_bx[f] * pull_x[b] + pair_by[f] * pull_y[b];
        const double from_a = pair_ax[f] * pull_x[a] + pair_ay[f] * pull_y[a];
        const double flow =
            beyond_round_off(two_point + (from_b - from_a), std::fabs(two_point) + std::fabs(from_b) + std::fabs(from_a));
        high[f] = carrying[f] != kCarries ? 0.0 : b_or_edge < 0 ? two_point : flow;
    }
}

LANE_COPIES
void flow_fluxes_in_lanes(const FlowLanes &lanes, std::int64_t begin, std::int64_t end) {
    flow_in_lanes<false>(lanes, nullptr, begin, end);
}

LANE_COPIES
void flow_fluxes_in_lanes(const FlowLanes &lanes, const std::int64_t *faces, std::int64_t count) {
    flow_in_lanes<true>(lanes, faces, 0, count);
}

template <bool kListed>
__attribute__((always_inline)) inline double limited_in_lanes(const LimitLanes &lanes, const std::int64_t *list,
                                                              std::int64_t begin, std::int64_t end,
                                                              std::int64_t live) {
    const std::int64_t *__restrict face_a = lanes.face_a, *__restrict face_b = lanes.face_b;
    const double *__restrict lows = lanes.low, *__restrict highs = lanes.high, *__restrict excess = lanes.excess;
    const double *__restrict limit_in = lanes.limit_in, *__restrict limit_out = lanes.limit_out;
    double *__restrict flux = lanes.flux;
    double largest = -1.0;
#pragma omp simd reduction(max : largest)
    for (std::int64_t i = begin; i < end; ++i) {
        const std::int64_t f = kListed ? list[i] : i;
        const std::int64_t a = face_a[f], b_or_edge = face_b[f], b = b_or_edge < 0 ? a : b_or_edge;
        const double low = lows[f], beyond = highs[f] - low;
        const bool out_of_a = beyond > 0.0;
        // Both factors of both cells read, then chosen: a choice of address
        // would keep the compiler from the lanes.
        const double a_in = limit_in[a], a_out = limit_out[a], b_in = limit_in[b], b_out = limit_out[b];
        const double share_a = out_of_a ? a_out : a_in;
        const double share_b = out_of_a ? b_in : b_out;
        const double share = b_or_edge >= 0 && share_b < share_a ? share_b : share_a;
        const double limited = share * beyond;
        const double v = beyond == 0.0 ? low : beyond_round_off(low + limited, std::fabs(low) + std::fabs(limited));
        flux[f] = v;
        if (!kListed) {
            const double carried = v != 0.0 && f < live ? excess[f] : -1.0;
            largest = carried > largest ? carried : largest;
        }
    }
    return largest;
}

LANE_COPIES
double limited_fluxes_in_lanes(const LimitLanes &lanes, std::int64_t begin, std::int64_t end, std::int64_t live) {
    return limited_in_lanes<false>(lanes, nullptr, begin, end, live);
}

LANE_COPIES
void limited_fluxes_in_lanes(const LimitLanes &lanes, const std::int64_t *faces, std::int64_t count) {
    limited_in_lanes<true>(lanes, faces, 0, count, 0);  // the excess: list_updates
}

}  // namespace dpsm
