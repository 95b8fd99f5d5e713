#include "structured/line_sweep.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "model/face_law.hpp"
#include "model/ledger.hpp"
#include "structured/lazy_sources.hpp"
#include "structured/structured_state.hpp"

namespace dpsm {

namespace {

// Accumulates the fluxes of one sweep. A face joins cells a and b a distance d
// apart; weight_a and weight_b turn a flux per unit face length into dh/dt of
// each cell (face length / cell area); len turns it into mass per unit time.
// The outside of an open side is a cell held at 0.
//
// The physics of real scenes enter here only when the grid uses them: a
// face's angle from its cells' (angle field), the static threshold between
// cells at rest (hysteresis), the flux exponent, and the bed, which caps what
// a face takes from its upstream cell at a share of the sand that cell holds.
class FaceSweep {
public:
    FaceSweep(Grid &grid, std::vector<double> &rate, double dt, bool record)
        : grid_(grid),
          faces_(record ? grid.face_fluxes().x.data() : nullptr),
          h_(grid.heights().data()),
          kind_(grid.kinds().data()),
          rate_(rate.data()),
          nu_(grid.mobility()),
          tan_theta_(grid.tan_repose()),
          threshold_(grid.tan_repose() * (1.0 + grid.rest_tolerance())),
          physics_(grid.uses_physics()),
          dt_(dt) {
        if (!physics_) return;
        const std::size_t n = grid.heights().size();
        if (grid.hysteresis()) moving_next_.assign(n, 0);
        if (!grid.bed().empty()) prepare_bed(grid, n);
    }

    // The face between cells a and b = a + 1, face index b.
    void interior_face(std::int64_t a, std::int64_t b, double d, double weight_a, double weight_b, double len) {
        const std::uint8_t ka = kind_[a], kb = kind_[b];
        if (ka == kWall || kb == kWall || (ka != kSand && kb != kSand)) return;
        double flux = flux_from_to(a, b, h_[a], h_[b], d);
        if (flux == 0.0) return;
        if (!available_.empty()) flux = capped(flux, a, b, weight_a, weight_b);
        if (flux == 0.0) return;
        carried(a, b);
        if (faces_) faces_[b] += flux * len * dt_;
        if (ka == kSand)
            rate_[a] -= flux * weight_a;
        else
            result.outflow_rate -= flux * len;  // an open cell feeds b
        if (kb == kSand)
            rate_[b] += flux * weight_b;
        else
            result.outflow_rate += flux * len;  // b is an open cell: a sink
    }

    // The face between cell a and the outside of an open side, held at `level`.
    void open_side_face(int side, std::int64_t a, double level, double d, double weight_a, double len) {
        if (kind_[a] != kSand) return;
        double flux = flux_from_to(a, -1, h_[a], level, d);
        if (flux == 0.0) return;
        if (!available_.empty() && flux > 0.0) flux = capped(flux, a, -1, weight_a, 0.0);
        if (flux == 0.0) return;
        carried(a, -1);
        rate_[a] -= flux * weight_a;
        result.outflow_rate += flux * len;
        result.side_outflow_rate[side] += flux * len;
        // Face 0 lies on the low side of cell 0, face nx on the high side of the last.
        if (faces_) faces_[side == kXMin ? 0 : a + 1] += (side == kXMin ? -flux : flux) * len * dt_;
    }

    // Hands the new moving cells to the grid (hysteresis) once every face is done.
    void finish() {
        if (!moving_next_.empty()) grid_.moving_for_stepping().swap(moving_next_);
    }

    SubstepSummary result;

private:
    // Flux per unit length from a to b (negative when b is the higher); b < 0
    // is the outside of an open side.
    double flux_from_to(std::int64_t a, std::int64_t b, double ha, double hb, double d) {
        const double slope = (ha - hb) / d;
        const double magnitude = std::fabs(slope);
        double tan_face = tan_theta_, threshold = threshold_, p = 1.0;
        if (physics_) face_law(a, b, tan_face, threshold, p);
        if (!(magnitude > threshold)) return 0.0;
        excess_ = magnitude - tan_face;
        const double flux = slide_flux(nu_, tan_face, magnitude, p);
        return slope > 0.0 ? flux : -flux;
    }

    void face_law(std::int64_t a, std::int64_t b, double &tan_face, double &threshold, double &p) const {
        const bool b_sand = b >= 0 && kind_[b] == kSand;
        const std::vector<double> &tan_field = grid_.tan_field();
        if (!tan_field.empty()) {
            tan_face = law::face_tan(tan_field[a], b >= 0 ? tan_field[b] : tan_field[a], kind_[a] == kSand, b_sand);
            threshold = tan_face * (1.0 + grid_.rest_tolerance());
        }
        if (grid_.hysteresis()) {
            const std::vector<std::uint8_t> &moving = grid_.moving();
            threshold = law::threshold(threshold, !moving[a] && !(b >= 0 && moving[b]), grid_.tan_static());
        }
        p = grid_.flux_exponent();
    }

    // A face takes from its sand cell at most its share of the sand there
    // (b < 0: the outside of an open side, which gives without limit).
    double capped(double flux, std::int64_t a, std::int64_t b, double weight_a, double weight_b) const {
        const double unlimited = std::numeric_limits<double>::infinity();
        const auto most = [&](std::int64_t c, double weight) {
            return c >= 0 && kind_[c] == kSand ? law::share_of_sand(available_[c], kFaces, dt_, weight) : unlimited;
        };
        return law::capped(flux, most(a, weight_a), -most(b, weight_b));
    }

    void carried(std::int64_t a, std::int64_t b) {
        result.moved = true;
        result.max_excess_slope = std::max(result.max_excess_slope, excess_);
        if (moving_next_.empty()) return;
        if (kind_[a] == kSand) moving_next_[a] = 1;
        if (b >= 0 && kind_[b] == kSand) moving_next_[b] = 1;
    }

    // The sand above the bed that exchanges may take this sub-step: what the
    // cell holds after its own erosion, which takes what it asks for first.
    // The applied source goes into the rate, so apply_rates adds no more.
    void prepare_bed(const Grid &grid, std::size_t n) {
        const std::vector<double> &zb = grid.bed();
        const std::vector<double> &q = grid.source();
        const Geometry &geo = grid.geometry();
        available_.assign(n, 0.0);
        const double film = bed_film(grid);
        CompensatedSum unmet, sourced;
        for (std::size_t c = 0; c < n; ++c) {
            if (kind_[c] != kSand) continue;
            double sand = std::max(0.0, h_[c] - zb[c]);
            const double asked = q.empty() ? 0.0 : q[c] * dt_;
            double applied = asked;
            if (asked < 0.0) {
                applied = -std::min(-asked, sand);
                unmet.add((applied - asked) * geo.cell_area(static_cast<std::int64_t>(c)));
                sand += applied;
            }
            sourced.add(applied * geo.cell_area(static_cast<std::int64_t>(c)));
            rate_[c] += applied / dt_;
            available_[c] = sand > film ? sand : 0.0;
        }
        result.unmet_mass = unmet.value();
        result.sourced_mass = sourced.value();
    }

    static constexpr double kFaces = 2.0;  // faces of a cell on a line or a radius

    Grid &grid_;
    double *faces_;  // the face fluxes to add to; null when not recorded
    const double *h_;
    const std::uint8_t *kind_;
    double *rate_;
    double nu_, tan_theta_, threshold_;
    bool physics_;
    double dt_;
    double excess_ = 0.0;
    std::vector<std::uint8_t> moving_next_;
    std::vector<double> available_;  // empty: no bed
};

}  // namespace

bool source_may_steepen_1d(const Grid &grid, double T) {
    const Geometry &geo = grid.geometry();
    const std::int64_t nx = geo.nx;
    const std::vector<double> &h = grid.heights(), &q = grid.source();
    const std::vector<std::uint8_t> &kind = grid.kinds();
    auto later = [&](std::int64_t c) { return kind[c] == kSand ? h[c] + q[c] * T : h[c]; };
    double largest = 0.0;
    for (std::int64_t c = 0; c < nx; ++c) largest = std::max({largest, std::fabs(h[c]), std::fabs(later(c))});
    if (!std::isfinite(largest)) return true;
    // A face in the band of rounding below the threshold counts as steep.
    const double threshold = grid.tan_repose() * (1.0 + grid.rest_tolerance()) * geo.dx -
                             64.0 * std::numeric_limits<double>::epsilon() * largest;
    // Only faces with a source on a side move; the others are as they are now.
    auto sourced = [&](std::int64_t c) { return kind[c] == kSand && q[c] != 0.0; };
    auto steep = [&](double ha, double hb) { return std::fabs(ha - hb) > threshold; };
    for (std::int64_t i = 0; i + 1 < nx; ++i) {
        const std::uint8_t ka = kind[i], kb = kind[i + 1];
        if (ka == kWall || kb == kWall || (ka != kSand && kb != kSand) || !(sourced(i) || sourced(i + 1))) continue;
        if (steep(later(i), later(i + 1))) return true;
    }
    if (grid.side_open(kXMin) && !geo.axisymmetric && sourced(0) && steep(later(0), grid.side_level(kXMin, 0)))
        return true;
    return grid.side_open(kXMax) && sourced(nx - 1) && steep(later(nx - 1), grid.side_level(kXMax, 0));
}

void apply_source_1d(Grid &grid, double substeps, double dt) {
    std::vector<double> &h = grid.heights_for_stepping();
    std::vector<float> &residual = grid.residuals_for_stepping();
    const std::vector<double> &q = grid.source();
    const std::vector<std::uint8_t> &kind = grid.kinds();
    for (std::size_t c = 0; c < h.size(); ++c)
        if (kind[c] == kSand && q[c] != 0.0) add_with_residual(h[c], residual[c], source_lag(q[c], dt, substeps));
}

SubstepSummary slide_rates_1d(Grid &grid, double dt, bool record) {
    const Geometry &geo = grid.geometry();
    const std::int64_t nx = geo.nx;
    std::vector<double> &rate = structured_state(grid).rates;
    std::fill(rate.begin(), rate.end(), 0.0);
    FaceSweep sweep(grid, rate, dt, record);
    // Along a line or a radius: weights are face length over cell area.
    for (std::int64_t i = 0; i + 1 < nx; ++i) {
        const double len = geo.x_face_length(i);
        sweep.interior_face(i, i + 1, geo.dx, len / geo.cell_area(i), len / geo.cell_area(i + 1), len);
    }
    if (grid.side_open(kXMin) && !geo.axisymmetric)
        sweep.open_side_face(kXMin, 0, grid.side_level(kXMin, 0), geo.dx, 1.0 / geo.dx, 1.0);
    if (grid.side_open(kXMax)) {
        const double len = geo.x_face_length(nx - 1);
        sweep.open_side_face(kXMax, nx - 1, grid.side_level(kXMax, 0), geo.dx, len / geo.cell_area(nx - 1), len);
    }
    sweep.finish();
    return sweep.result;
}

void apply_rates(Grid &grid, double dt) {
    const std::vector<double> &rate = structured_state(grid).rates;
    std::vector<double> &h = grid.heights_for_stepping();
    std::vector<float> &residual = grid.residuals_for_stepping();
    const std::vector<std::uint8_t> &kind = grid.kinds();
    const std::vector<double> &q = grid.source();
    const std::vector<double> &zb = grid.bed();
    const std::size_t n = h.size();
    auto add = [&](std::size_t c, double increment) {
        if (increment == 0.0) return;  // as the 2D kernel: still cells stay bit for bit
        add_with_residual(h[c], residual[c], increment);
    };
    if (!zb.empty()) {
        // The rate holds the applied source already. Rounding may leave a
        // drained cell an ulp below its bed: it is lifted to the bed and the
        // lift is taken from the rounding it carries.
        for (std::size_t c = 0; c < n; ++c) {
            add(c, dt * rate[c]);
            if (kind[c] == kSand && h[c] < zb[c]) {
                residual[c] = static_cast<float>(static_cast<double>(residual[c]) - (zb[c] - h[c]));
                h[c] = zb[c];
            }
        }
        return;
    }
    // rate is 0 on wall and open cells, so only the source needs the mask.
    if (q.empty()) {
        for (std::size_t c = 0; c < n; ++c) add(c, dt * rate[c]);
    } else {
        for (std::size_t c = 0; c < n; ++c) add(c, dt * (rate[c] + (kind[c] == kSand ? q[c] : 0.0)));
    }
}

}  // namespace dpsm
