#include "kernels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "closure.hpp"

namespace dpsm {

namespace {

// Accumulates the fluxes of one sweep. A face joins cells a and b a distance d
// apart; `transverse` is the slope across it (0 for the pairwise scheme);
// weight_a and weight_b turn a flux per unit face length into dh/dt of each
// cell (face length / cell area); len turns it into mass per unit time. The
// outside of an open side is a cell held at 0.
class FaceSweep {
public:
    FaceSweep(const Grid &grid, std::vector<double> &rate)
        : h_(grid.heights().data()),
          kind_(grid.kinds().data()),
          rate_(rate.data()),
          nu_(grid.mobility()),
          tan_theta_(grid.tan_repose()) {}

    void interior_face(std::int64_t a, std::int64_t b, double d, double transverse, double weight_a,
                       double weight_b, double len) {
        const std::uint8_t ka = kind_[a], kb = kind_[b];
        if (ka == kWall || kb == kWall || (ka != kSand && kb != kSand)) return;
        const double flux = flux_from_to(h_[a], h_[b], d, transverse);
        if (ka == kSand)
            rate_[a] -= flux * weight_a;
        else
            result.outflow_rate -= flux * len;  // an open cell feeds b
        if (kb == kSand)
            rate_[b] += flux * weight_b;
        else
            result.outflow_rate += flux * len;  // b is an open cell: a sink
    }

    void open_side_face(std::int64_t a, double d, double transverse, double weight_a, double len) {
        if (kind_[a] != kSand) return;
        const double flux = flux_from_to(h_[a], 0.0, d, transverse);
        rate_[a] -= flux * weight_a;
        result.outflow_rate += flux * len;
    }

    SweepResult result;

private:
    // Flux per unit length from a to b (negative when b is the higher): the
    // law acts on the full slope, and the face carries its normal share.
    double flux_from_to(double ha, double hb, double d, double transverse) {
        const double normal = (ha - hb) / d;
        const double magnitude = std::sqrt(normal * normal + transverse * transverse);
        result.max_excess_slope = std::max(result.max_excess_slope, magnitude - tan_theta_);
        const double flux = slide_flux(nu_, tan_theta_, magnitude);
        return flux > 0.0 ? flux * (normal / magnitude) : 0.0;
    }

    const double *h_;
    const std::uint8_t *kind_;
    double *rate_;
    double nu_, tan_theta_;
};

// Central differences of every cell along x and y, for the isotropic scheme.
// A neighbour beyond an open side is at 0; a wall (side or cell) mirrors the
// cell itself, the paper's zero normal gradient at walls.
void transverse_slopes(const Grid &grid, std::vector<double> &along_x, std::vector<double> &along_y) {
    const Geometry &geo = grid.geometry();
    const std::int64_t nx = geo.nx, ny = geo.ny;
    const double *h = grid.heights().data();
    const std::uint8_t *kind = grid.kinds().data();
    const bool open_xmin = grid.side_open(kXMin), open_xmax = grid.side_open(kXMax);
    const bool open_ymin = grid.side_open(kYMin), open_ymax = grid.side_open(kYMax);
    auto neighbour = [&](std::int64_t c, std::int64_t n, bool inside, bool side_open) {
        if (!inside) return side_open ? 0.0 : h[c];
        return kind[n] == kWall ? h[c] : h[n];
    };
    for (std::int64_t j = 0; j < ny; ++j)
        for (std::int64_t i = 0; i < nx; ++i) {
            const std::int64_t c = i + nx * j;
            const double west = neighbour(c, c - 1, i > 0, open_xmin);
            const double east = neighbour(c, c + 1, i + 1 < nx, open_xmax);
            const double south = neighbour(c, c - nx, j > 0, open_ymin);
            const double north = neighbour(c, c + nx, j + 1 < ny, open_ymax);
            along_x[c] = (east - west) / (2.0 * geo.dx);
            along_y[c] = (north - south) / (2.0 * geo.dy);
        }
}

}  // namespace

SweepResult slide_rates(Grid &grid) {
    const Geometry &geo = grid.geometry();
    const std::int64_t nx = geo.nx, ny = geo.ny;
    std::vector<double> &rate = grid.rate_workspace();
    std::fill(rate.begin(), rate.end(), 0.0);
    FaceSweep sweep(grid, rate);

    if (geo.dim == 1) {
        // Along a line or a radius: weights are face length over cell area.
        for (std::int64_t i = 0; i + 1 < nx; ++i) {
            const double len = geo.x_face_length(i);
            sweep.interior_face(i, i + 1, geo.dx, 0.0, len / geo.cell_area(i), len / geo.cell_area(i + 1), len);
        }
        if (grid.side_open(kXMin) && !geo.axisymmetric) sweep.open_side_face(0, geo.dx, 0.0, 1.0 / geo.dx, 1.0);
        if (grid.side_open(kXMax)) {
            const double len = geo.x_face_length(nx - 1);
            sweep.open_side_face(nx - 1, geo.dx, 0.0, len / geo.cell_area(nx - 1), len);
        }
        return sweep.result;
    }

    const bool isotropic = grid.scheme() == kIsotropic;
    const double *tx = nullptr, *ty = nullptr;
    if (isotropic) {
        transverse_slopes(grid, grid.transverse_x_workspace(), grid.transverse_y_workspace());
        tx = grid.transverse_x_workspace().data();
        ty = grid.transverse_y_workspace().data();
    }
    // An open side's outside is flat at 0: it adds nothing across the face.
    auto across_x = [&](std::int64_t a, std::int64_t b) { return isotropic ? 0.5 * (ty[a] + ty[b]) : 0.0; };
    auto across_x_side = [&](std::int64_t a) { return isotropic ? 0.5 * ty[a] : 0.0; };
    auto across_y = [&](std::int64_t a, std::int64_t b) { return isotropic ? 0.5 * (tx[a] + tx[b]) : 0.0; };
    auto across_y_side = [&](std::int64_t a) { return isotropic ? 0.5 * tx[a] : 0.0; };
    const double wx = 1.0 / geo.dx, wy = 1.0 / geo.dy;

    for (std::int64_t j = 0; j < ny; ++j) {
        const std::int64_t row = j * nx;
        if (grid.side_open(kXMin)) sweep.open_side_face(row, geo.dx, across_x_side(row), wx, geo.dy);
        for (std::int64_t c = row; c + 1 < row + nx; ++c)
            sweep.interior_face(c, c + 1, geo.dx, across_x(c, c + 1), wx, wx, geo.dy);
        if (grid.side_open(kXMax)) sweep.open_side_face(row + nx - 1, geo.dx, across_x_side(row + nx - 1), wx, geo.dy);
    }
    for (std::int64_t i = 0; i < nx; ++i) {
        if (grid.side_open(kYMin)) sweep.open_side_face(i, geo.dy, across_y_side(i), wy, geo.dx);
        const std::int64_t top = i + nx * (ny - 1);
        if (grid.side_open(kYMax)) sweep.open_side_face(top, geo.dy, across_y_side(top), wy, geo.dx);
    }
    for (std::int64_t c = 0; c + nx < nx * ny; ++c) sweep.interior_face(c, c + nx, geo.dy, across_y(c, c + nx), wy, wy, geo.dx);
    return sweep.result;
}

void apply_rates(Grid &grid, double dt) {
    const std::vector<double> &rate = grid.rate_workspace();
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
