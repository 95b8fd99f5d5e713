#include "kernels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "closure.hpp"

namespace dpsm {

namespace {

// Accumulates the fluxes of one sweep. A face joins cells a and b a distance d
// apart; weight_a and weight_b turn a flux per unit face length into dh/dt of
// each cell (face length / cell area); len turns it into mass per unit time.
// The outside of an open side is a cell held at 0.
class FaceSweep {
public:
    FaceSweep(const Grid &grid, std::vector<double> &rate)
        : h_(grid.heights().data()),
          kind_(grid.kinds().data()),
          rate_(rate.data()),
          nu_(grid.mobility()),
          tan_theta_(grid.tan_repose()),
          threshold_(grid.tan_repose() * (1.0 + grid.rest_tolerance())) {}

    void interior_face(std::int64_t a, std::int64_t b, double d, double weight_a, double weight_b, double len) {
        const std::uint8_t ka = kind_[a], kb = kind_[b];
        if (ka == kWall || kb == kWall || (ka != kSand && kb != kSand)) return;
        const double flux = flux_from_to(h_[a], h_[b], d);
        if (ka == kSand)
            rate_[a] -= flux * weight_a;
        else
            result.outflow_rate -= flux * len;  // an open cell feeds b
        if (kb == kSand)
            rate_[b] += flux * weight_b;
        else
            result.outflow_rate += flux * len;  // b is an open cell: a sink
    }

    void open_side_face(std::int64_t a, double d, double weight_a, double len) {
        if (kind_[a] != kSand) return;
        const double flux = flux_from_to(h_[a], 0.0, d);
        rate_[a] -= flux * weight_a;
        result.outflow_rate += flux * len;
    }

    SweepResult result;

private:
    // Flux per unit length from a to b (negative when b is the higher).
    double flux_from_to(double ha, double hb, double d) {
        const double slope = (ha - hb) / d;
        const double magnitude = std::fabs(slope);
        if (!(magnitude > threshold_)) return 0.0;
        result.moved = true;
        result.max_excess_slope = std::max(result.max_excess_slope, magnitude - tan_theta_);
        const double flux = slide_flux(nu_, tan_theta_, magnitude);
        return slope > 0.0 ? flux : -flux;
    }

    const double *h_;
    const std::uint8_t *kind_;
    double *rate_;
    double nu_, tan_theta_, threshold_;
};

}  // namespace

SweepResult slide_rates_1d(Grid &grid) {
    const Geometry &geo = grid.geometry();
    const std::int64_t nx = geo.nx;
    std::vector<double> &rate = grid.rate_workspace();
    std::fill(rate.begin(), rate.end(), 0.0);
    FaceSweep sweep(grid, rate);
    // Along a line or a radius: weights are face length over cell area.
    for (std::int64_t i = 0; i + 1 < nx; ++i) {
        const double len = geo.x_face_length(i);
        sweep.interior_face(i, i + 1, geo.dx, len / geo.cell_area(i), len / geo.cell_area(i + 1), len);
    }
    if (grid.side_open(kXMin) && !geo.axisymmetric) sweep.open_side_face(0, geo.dx, 1.0 / geo.dx, 1.0);
    if (grid.side_open(kXMax)) {
        const double len = geo.x_face_length(nx - 1);
        sweep.open_side_face(nx - 1, geo.dx, len / geo.cell_area(nx - 1), len);
    }
    return sweep.result;
}

void apply_rates(Grid &grid, double dt) {
    const std::vector<double> &rate = grid.rate_workspace();
    std::vector<double> &h = grid.heights_for_stepping();
    std::vector<float> &residual = grid.residuals_for_stepping();
    const std::vector<std::uint8_t> &kind = grid.kinds();
    const std::vector<double> &q = grid.source();
    const std::size_t n = h.size();
    // h += increment as a TwoSum: what rounding drops is kept in residual and
    // added back next time, so mass is not lost one half-ulp at a time.
    auto add = [&](std::size_t c, double increment) {
        if (increment == 0.0) return;  // as the 2D kernel: still cells stay bit for bit
        const double b = increment + static_cast<double>(residual[c]);
        const double s = h[c] + b;
        const double b_virtual = s - h[c];
        residual[c] = static_cast<float>((h[c] - (s - b_virtual)) + (b - b_virtual));
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
