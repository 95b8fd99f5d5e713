#include "kernels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "closure.hpp"

namespace dpsm {

namespace {

// Accumulates the fluxes of one sweep. A face joins cells a and b a distance d
// apart; its length is len. The outside of an open side is a cell held at 0.
class FaceSweep {
public:
    FaceSweep(const Grid &grid, std::vector<double> &rate)
        : h_(grid.heights().data()),
          kind_(grid.kinds().data()),
          rate_(rate.data()),
          nu_(grid.mobility()),
          tan_theta_(grid.tan_repose()) {}

    void interior_face(std::int64_t a, std::int64_t b, double d, double len) {
        const std::uint8_t ka = kind_[a], kb = kind_[b];
        if (ka == kWall || kb == kWall || (ka != kSand && kb != kSand)) return;
        const double flux = flux_from_to(h_[a], h_[b], d);
        if (ka == kSand)
            rate_[a] -= flux / d;
        else
            result.outflow_rate -= flux * len;  // an open cell feeds b
        if (kb == kSand)
            rate_[b] += flux / d;
        else
            result.outflow_rate += flux * len;  // b is an open cell: a sink
    }

    void open_side_face(std::int64_t a, double d, double len) {
        if (kind_[a] != kSand) return;
        const double flux = flux_from_to(h_[a], 0.0, d);
        rate_[a] -= flux / d;
        result.outflow_rate += flux * len;
    }

    SweepResult result;

private:
    // Flux per unit length from a to b (negative when b is the higher).
    double flux_from_to(double ha, double hb, double d) {
        const double slope = (ha - hb) / d;
        const double magnitude = std::fabs(slope);
        result.max_excess_slope = std::max(result.max_excess_slope, magnitude - tan_theta_);
        const double flux = slide_flux(nu_, tan_theta_, magnitude);
        return slope > 0.0 ? flux : -flux;
    }

    const double *h_;
    const std::uint8_t *kind_;
    double *rate_;
    double nu_, tan_theta_;
};

}  // namespace

SweepResult pairwise_rates(const Grid &grid, std::vector<double> &rate) {
    const Geometry &geo = grid.geometry();
    const std::int64_t nx = geo.nx, ny = geo.ny;
    std::fill(rate.begin(), rate.end(), 0.0);
    FaceSweep sweep(grid, rate);

    for (std::int64_t j = 0; j < ny; ++j) {
        const std::int64_t row = j * nx;
        if (grid.side_open(kXMin)) sweep.open_side_face(row, geo.dx, geo.dy);
        for (std::int64_t i = 0; i + 1 < nx; ++i) sweep.interior_face(row + i, row + i + 1, geo.dx, geo.dy);
        if (grid.side_open(kXMax)) sweep.open_side_face(row + nx - 1, geo.dx, geo.dy);
    }
    if (geo.dim == 2) {
        for (std::int64_t i = 0; i < nx; ++i) {
            if (grid.side_open(kYMin)) sweep.open_side_face(i, geo.dy, geo.dx);
            if (grid.side_open(kYMax)) sweep.open_side_face(i + nx * (ny - 1), geo.dy, geo.dx);
        }
        for (std::int64_t j = 0; j + 1 < ny; ++j)
            for (std::int64_t i = 0; i < nx; ++i) sweep.interior_face(i + nx * j, i + nx * (j + 1), geo.dy, geo.dx);
    }
    return sweep.result;
}

void apply_rates(Grid &grid, const std::vector<double> &rate, double dt) {
    std::vector<double> &h = grid.heights_for_stepping();
    std::vector<double> &residual = grid.height_residuals();
    const std::vector<std::uint8_t> &kind = grid.kinds();
    const std::vector<double> &q = grid.source();
    const std::size_t n = h.size();
    // h += increment as a TwoSum: what rounding drops is kept in residual and
    // added back next time, so mass is not lost one half-ulp at a time.
    auto add = [&](std::size_t c, double increment) {
        const double b = increment + residual[c];
        const double s = h[c] + b;
        const double b_virtual = s - h[c];
        residual[c] = (h[c] - (s - b_virtual)) + (b - b_virtual);
        h[c] = s;
    };
    // rate is 0 on wall and open cells, so only the source needs the mask.
    if (q.empty()) {
        for (std::size_t c = 0; c < n; ++c) add(c, dt * rate[c]);
    } else {
        for (std::size_t c = 0; c < n; ++c) add(c, dt * (rate[c] + (kind[c] == kSand ? q[c] : 0.0)));
    }
}

}  // namespace dpsm
