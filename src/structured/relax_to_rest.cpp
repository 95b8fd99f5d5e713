// The fast relaxation to rest. The rule and the figures that chose it are in
// docs/performance.md ("Larger steps: what was tried", rkc-then-momentum):
//
//  - Runge-Kutta-Chebyshev steps (second order, damping 2/13) whose stage
//    count ramps up, s_k = min(20, 2 + k), each 0.9 of its stable length.
//    They follow the flow's path while much sand moves; the deposit depends
//    on that path.
//  - Once the largest excess slope of the faces that carry sand is below 5 %
//    of tan(theta), Nesterov's momentum (beta = k / (k + 3)) on explicit
//    sub-steps, restarted when a step works against the rates or when more
//    than 90 % of its motion lies in cells no face acts on (sand coasting past
//    the angle of repose, which nothing would bring back).
//  - At rest when a sub-step taken without momentum moves nothing.
//
// Every flux evaluation is one explicit sub-step of the grid's own 2D sweep
// from the state at hand (its change S(y) - y is dt times the rates), so the
// flux law, the masks and the sides stay in one place. Each stage is a
// combination of states of one mass; what leaves through open sides and cells
// is booked as outflow, as the difference of the mass before and after.
#include "structured/relax_to_rest.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include "dpsm/dpsm.h"
#include "model/error.hpp"
#include "model/ledger.hpp"
#include "structured/structured_engine.hpp"
#include "structured/structured_state.hpp"
#include "structured/tile_kernel.hpp"
#include "structured/tiled_heights.hpp"
#include "structured/tiled_sweep.hpp"

namespace dpsm {
namespace {

constexpr int kMaxStages = 20;
constexpr double kStageSafety = 0.9;
constexpr double kSwitchExcessShare = 0.05;  // of tan(theta): where momentum takes over
constexpr double kCoastingShare = 0.9;
// A state may stray this far (relative to the heights) beyond the start's
// extremes, and a closed scene's mass this far (relative to the mass): rounding.
constexpr double kBoundsSlack = 4.0 * std::numeric_limits<double>::epsilon();
constexpr double kMassSlack = 1e-14;

// The coefficients of a second-order RKC step of s stages (Sommeijer,
// Shampine and Verwer 1997).
struct RkcStep {
    int s = 2;
    double w0 = 0.0, w1 = 0.0, beta = 0.0;  // beta: the stable length in units of 1 / lambda_max
    double T[kMaxStages + 1] = {}, b[kMaxStages + 1] = {};

    explicit RkcStep(int stages) : s(stages) {
        double dT[kMaxStages + 1] = {}, ddT[kMaxStages + 1] = {};
        w0 = 1.0 + (2.0 / 13.0) / (static_cast<double>(s) * s);
        T[0] = 1.0;
        T[1] = w0;
        dT[1] = 1.0;
        for (int j = 2; j <= s; ++j) {
            T[j] = 2.0 * w0 * T[j - 1] - T[j - 2];
            dT[j] = 2.0 * T[j - 1] + 2.0 * w0 * dT[j - 1] - dT[j - 2];
            ddT[j] = 4.0 * dT[j - 1] + 2.0 * w0 * ddT[j - 1] - ddT[j - 2];
        }
        w1 = dT[s] / ddT[s];
        for (int j = 2; j <= s; ++j) b[j] = ddT[j] / (dT[j] * dT[j]);
        b[0] = b[1] = b[2];
        beta = (w0 + 1.0) * ddT[s] / dT[s];
    }
};

// The arithmetic on the cells of one row, [c0, c1), after every evaluation.
// Where the kernels run in AVX-512 so do these, 8 cells at a time instead of
// 2 (copies built for it; chosen by a test of the CPU, as in structured/tiled_sweep.cpp).
// Neither copy has fused multiply-adds, so both round alike.
struct StageWeights {
    double mu, nu, mut_tau, gamt_tau;
};
// Four partial sums, so that the additions do not wait on each other.
struct MomentumStep {
    double along[4] = {}, motion[4] = {}, coasting[4] = {};
};

// A stage of an RKC step: y0 plus a combination of changes.
inline void rkc_stage_cells(std::size_t c0, std::size_t c1, const double *y0, const double *yjm1, const double *yjm2,
                            const double *next, const double *f0, StageWeights w, double *__restrict yj) {
    for (std::size_t c = c0; c < c1; ++c)
        yj[c] = y0[c] + (w.mu * (yjm1[c] - y0[c]) + w.nu * (yjm2[c] - y0[c]) + w.mut_tau * (next[c] - yjm1[c]) +
                         w.gamt_tau * f0[c]);
}
// Momentum's look-ahead: x where x = x_prev.
inline void extrapolate_cells(std::size_t c0, std::size_t c1, const double *x, const double *x_prev, double beta,
                              double *__restrict y) {
    for (std::size_t c = c0; c < c1; ++c) y[c] = x[c] + beta * (x[c] - x_prev[c]);
}
// Momentum's step to next = S(y), and how its motion went. The new x goes
// over x_prev (the caller then swaps the two), which saves a copy per cell.
inline void momentum_cells(std::size_t c0, std::size_t c1, const double *next, const double *y, const double *x,
                           double *__restrict x_next, MomentumStep &m) {
    // Sums in locals, which the stores to the cells cannot alias.
    double along[4], motion[4], coasting[4];
    for (int part = 0; part < 4; ++part) {
        along[part] = m.along[part];
        motion[part] = m.motion[part];
        coasting[part] = m.coasting[part];
    }
    const auto advance = [&](std::size_t c, int part) {
        const double change = next[c] - y[c], to = y[c] + change, moved = std::fabs(to - x[c]);
        along[part] += change * (to - x[c]);
        motion[part] += moved;
        coasting[part] += change == 0.0 ? moved : 0.0;
        x_next[c] = to;
    };
    std::size_t c = c0;
    for (; c + 4 <= c1; c += 4)
        for (int part = 0; part < 4; ++part) advance(c + part, part);
    for (; c < c1; ++c) advance(c, 0);
    for (int part = 0; part < 4; ++part) {
        m.along[part] = along[part];
        m.motion[part] = motion[part];
        m.coasting[part] = coasting[part];
    }
}

struct CellLoops {
    void (*rkc_stage)(std::size_t, std::size_t, const double *, const double *, const double *, const double *,
                      const double *, StageWeights, double *);
    void (*extrapolate)(std::size_t, std::size_t, const double *, const double *, double, double *);
    void (*momentum)(std::size_t, std::size_t, const double *, const double *, const double *, double *,
                     MomentumStep &);
};
void rkc_stage_plain(std::size_t c0, std::size_t c1, const double *y0, const double *yjm1, const double *yjm2,
                     const double *next, const double *f0, StageWeights w, double *yj) {
    rkc_stage_cells(c0, c1, y0, yjm1, yjm2, next, f0, w, yj);
}
void extrapolate_plain(std::size_t c0, std::size_t c1, const double *x, const double *x_prev, double beta, double *y) {
    extrapolate_cells(c0, c1, x, x_prev, beta, y);
}
void momentum_plain(std::size_t c0, std::size_t c1, const double *next, const double *y, const double *x,
                    double *x_next, MomentumStep &m) {
    momentum_cells(c0, c1, next, y, x, x_next, m);
}
#if defined(DPSM_HAVE_AVX512_KERNEL)
__attribute__((target("avx512f"))) void rkc_stage_avx512(std::size_t c0, std::size_t c1, const double *y0,
                                                          const double *yjm1, const double *yjm2, const double *next,
                                                          const double *f0, StageWeights w, double *yj) {
    rkc_stage_cells(c0, c1, y0, yjm1, yjm2, next, f0, w, yj);
}
__attribute__((target("avx512f"))) void extrapolate_avx512(std::size_t c0, std::size_t c1, const double *x,
                                                            const double *x_prev, double beta, double *y) {
    extrapolate_cells(c0, c1, x, x_prev, beta, y);
}
__attribute__((target("avx512f"))) void momentum_avx512(std::size_t c0, std::size_t c1, const double *next,
                                                         const double *y, const double *x, double *x_next,
                                                         MomentumStep &m) {
    momentum_cells(c0, c1, next, y, x, x_next, m);
}
#endif
const CellLoops &cell_loops() {
    static const CellLoops plain{rkc_stage_plain, extrapolate_plain, momentum_plain};
#if defined(DPSM_HAVE_AVX512_KERNEL)
    static const CellLoops avx512{rkc_stage_avx512, extrapolate_avx512, momentum_avx512};
    if (tile_kernels_use_avx512()) return avx512;
#endif
    return plain;
}

}  // namespace

RelaxWorkspace::RelaxWorkspace(std::size_t cells, std::size_t tiles)
    // Not value-initialised: a page is touched only where a step needs it.
    : start(new double[cells]), rates(new double[cells]), filled(tiles), live(tiles) {
    for (auto &state : states) state.reset(new double[cells]);
    filled_tiles.reserve(tiles);
    live_tiles.reserve(tiles);
}

namespace {

// The states of the relaxation (the RKC stages, momentum's points) and the
// rates at a step's start, each an array over the whole grid of which only
// the tiles near moving sand are ever touched: piles here and there on a
// large grid cost their own cells, in time and in pages of memory. Within a
// tile's box `filled` every state holds its value and every rate 0 until the
// relaxation computes one; outside it nothing is defined and nothing is read.
//
// Evaluates the slide fluxes at heights y (one of the states) by one
// explicit sub-step of dt from y: afterwards next() holds S(y), and S(y) - y
// is dt times the rates. It keeps per tile the box `live` of the cells that
// any sweep so far has changed: outside those boxes the grid holds the
// heights the relaxation started from, and so must every state the caller
// makes (and its rates must be 0), which lets every loop run over the live
// boxes alone.
class Evaluator {
public:
    Evaluator(Grid &grid, double dt)
        : grid_(grid), dt_(dt), nx_(grid.geometry().nx), ws_(structured_state(grid).relax_workspace(grid)) {
        residuals_ = drop_residuals(grid);  // the sweeps without residuals need them 0
    }
    // Every box empty again, for the next step.
    ~Evaluator() {
        for (const std::int64_t t : ws_.filled_tiles) ws_.filled[t] = ws_.live[t] = CellBox{};
        ws_.filled_tiles.clear();
        ws_.live_tiles.clear();
    }
    Evaluator(const Evaluator &) = delete;
    Evaluator &operator=(const Evaluator &) = delete;

    double *state(int k) { return ws_.states[k].get(); }
    double *rates() { return ws_.rates.get(); }

    SubstepSummary evaluate(const double *y) {
        // The active set then computes only the cells that y moved or that
        // touch a moving face, as in any sub-step.
        for (const std::int64_t t : ws_.live_tiles) copy_heights_between_sweeps(grid_, y, ws_.live[t]);
        last_visited_ = static_cast<double>(tiled_sweep(grid_, 1, dt_, levels_, /*find_excess=*/true,
                                                        /*residuals=*/false));
        visited_ += last_visited_;
        // The sweep leaves the heights from before it in its scratch
        // (structured/tiled_sweep.hpp): y in the live boxes, the start elsewhere.
        const TiledWorkspace &ws = structured_state(grid_).tiled_workspace();
        const double *next = grid_.heights().data(), *before = ws.heights.data();
        bool new_tiles = false;
        for (std::size_t k = 0; k < ws.visit.size(); ++k) {
            const std::int64_t t = ws.visit[k];
            const CellBox &written = ws.boxes[k];
            if (written.empty()) continue;
            fill(t, written, before);
            // The cells it changed join the tile's live box (it writes whole
            // boxes where little or nothing moves); those already in it need no look.
            CellBox &live = ws_.live[t];
            const CellBox was = live;
            for (std::int64_t j = written.j0; j < written.j1; ++j) {
                const double *next_row = next + nx_ * j, *from_row = before + nx_ * j;
                auto changed = [&](std::int64_t i) { return next_row[i] != from_row[i]; };
                // Where the row crosses the box, the cells left to look at lie on its two sides.
                const bool crosses = j >= was.j0 && j < was.j1;
                const std::int64_t left_end = crosses ? std::max(written.i0, was.i0) : written.i1;
                const std::int64_t right_begin = crosses ? std::min(written.i1, was.i1) : written.i0;
                std::int64_t first = written.i0;
                while (first < left_end && !changed(first)) ++first;
                std::int64_t last = written.i1 - 1;
                while (last >= right_begin && !changed(last)) --last;
                if (first < left_end) live.add(first, first + 1, j, j + 1);
                if (last >= right_begin) live.add(last, last + 1, j, j + 1);
            }
            if (was.empty() && !live.empty()) {
                ws_.live_tiles.push_back(t);
                new_tiles = true;
            }
        }
        // Tile order, whatever the order of visits: the sums over the boxes
        // must not depend on it.
        if (new_tiles) std::sort(ws_.live_tiles.begin(), ws_.live_tiles.end());
        ++evaluations_;
        return levels_.front();
    }
    // S(y) of the last evaluation, until the next one.
    const double *next() const { return grid_.heights().data(); }

    // Calls f(first, end) for the cells of each row of the live boxes, tile by tile.
    template <class F>
    void for_rows(F &&f) const {
        for (const std::int64_t t : ws_.live_tiles) {
            const CellBox &box = ws_.live[t];
            for (std::int64_t j = box.j0; j < box.j1; ++j)
                f(static_cast<std::size_t>(box.i0 + nx_ * j), static_cast<std::size_t>(box.i1 + nx_ * j));
        }
    }
    // The mass of the start less y's: what left, and what rounding took (on
    // the live boxes: elsewhere nothing changed).
    double mass_left(const double *y) const {
        CompensatedSum left;
        for (const std::int64_t t : ws_.live_tiles) left.add(sand_mass_change(grid_, y, ws_.start.get(), ws_.live[t]));
        return left.value();
    }
    // Whether y's sand lies within the extremes of the start's (and of the
    // levels that open sides and cells hold), as every sub-step of the
    // time-accurate scheme keeps it: its new heights mix those of the cells
    // around. Every cell a sweep has read is in a filled box.
    bool within_start_extremes(const double *y) const {
        const std::uint8_t *kind = grid_.kinds().data();
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        auto take = [&](double v) {
            lo = std::min(lo, v);
            hi = std::max(hi, v);
        };
        const double *start = ws_.start.get();
        for (const std::int64_t t : ws_.filled_tiles)
            for_cells(ws_.filled[t], [&](std::size_t c) {
                if (kind[c] == kSand) take(start[c]);
            });
        if (grid_.has_open_cells()) {
            take(grid_.open_level_min());
            take(grid_.open_level_max());
        }
        if (grid_.any_side_open()) {
            take(grid_.side_level_min());
            take(grid_.side_level_max());
        }
        const double slack = kBoundsSlack * std::max(std::fabs(lo), std::fabs(hi));
        bool within = true;
        for (const std::int64_t t : ws_.live_tiles)
            for_cells(ws_.live[t], [&](std::size_t c) {
                within = within && (kind[c] != kSand || (y[c] >= lo - slack && y[c] <= hi + slack));
            });
        return within;
    }
    // The grid's heights become y's.
    void finish(const double *y) {
        for (const std::int64_t t : ws_.live_tiles) set_heights_between_sweeps(grid_, y, ws_.live[t]);
    }
    // The grid becomes the start again, residuals included, and every cell a
    // sweep read may move: the active set as it was, or wider.
    void restore_start() {
        finish(ws_.start.get());
        restore_residuals(grid_, residuals_);
        for (const std::int64_t t : ws_.filled_tiles) {
            const CellBox &box = ws_.filled[t];
            active_set(grid_).mark_block(box.i0, box.j0, box.i1 - box.i0, box.j1 - box.j0);
        }
    }
    const double *start() const { return ws_.start.get(); }
    std::int64_t evaluations() const { return evaluations_; }
    double cells_visited() const { return visited_; }
    double cells_visited_last() const { return last_visited_; }

private:
    template <class F>
    void for_cells(const CellBox &box, F &&f) const {
        for (std::int64_t j = box.j0; j < box.j1; ++j)
            for (std::int64_t i = box.i0; i < box.i1; ++i) f(static_cast<std::size_t>(i + nx_ * j));
    }
    // Widens tile t's box `filled` to take in the box, with the heights from
    // before the sweep (the start there) in every state and 0 in the rates.
    void fill(std::int64_t t, const CellBox &box, const double *before) {
        CellBox &filled = ws_.filled[t];
        CellBox wider = filled;
        wider.add(box);
        if (wider == filled) return;
        if (filled.empty()) ws_.filled_tiles.push_back(t);
        auto fill_cells = [&](std::size_t c0, std::size_t c1) {
            for (auto &state : ws_.states) std::copy(before + c0, before + c1, state.get() + c0);
            std::copy(before + c0, before + c1, ws_.start.get() + c0);
            std::fill(ws_.rates.get() + c0, ws_.rates.get() + c1, 0.0);
        };
        for (std::int64_t j = wider.j0; j < wider.j1; ++j) {
            const std::size_t row = static_cast<std::size_t>(nx_ * j);
            if (filled.empty() || j < filled.j0 || j >= filled.j1) {
                fill_cells(row + wider.i0, row + wider.i1);
            } else {
                fill_cells(row + wider.i0, row + filled.i0);
                fill_cells(row + filled.i1, row + wider.i1);
            }
        }
        filled = wider;
    }

    Grid &grid_;
    double dt_;
    std::int64_t nx_;
    RelaxWorkspace &ws_;
    SavedResiduals residuals_;  // as they were before the relaxation
    std::vector<SubstepSummary> levels_;
    std::int64_t evaluations_ = 0;
    double visited_ = 0.0, last_visited_ = 0.0;
};

}  // namespace

const char *relaxation_unsupported(const Grid &grid) {
    if (grid.geometry().dim != 2) return "1D or axisymmetric grids";
    if (grid.distribution()) return "distributed grids";
    if (grid.scheme() != kIsotropic) return "the pairwise scheme (dpsm_set_scheme)";
    if (!grid.bed().empty()) return "a bed (dpsm_set_bedrock)";
    // Both were seen to need far more evaluations, or never to rest, in a
    // relaxation tuned on the plain law; they stay with the time-accurate steps.
    if (!grid.angle_field().empty()) return "an angle field (dpsm_set_repose_angle_field)";
    if (grid.flux_exponent() != 1.0) return "a flux exponent other than 1 (dpsm_set_flux_exponent)";
    if (grid.hysteresis()) return "a static angle (dpsm_set_static_angle)";
    if (grid.source_active()) return "an active source (dpsm_set_source); add the deposit with dpsm_add_heights_region";
    double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
    if (grid.has_open_cells()) {
        lowest = grid.open_level_min();
        highest = grid.open_level_max();
    }
    if (grid.any_side_open()) {
        lowest = std::min(lowest, grid.side_level_min());
        highest = std::max(highest, grid.side_level_max());
    }
    if (lowest < highest)
        return "open cells and open sides held at different levels (sand would flow for ever)";
    return nullptr;
}

namespace {

void require_supported(const Grid &grid) {
    if (const char *what = relaxation_unsupported(grid))
        fail(DPSM_ERR_NOT_APPLICABLE, "dpsm_step", "the relaxation DPSM_RELAX_TO_REST does not support ", what,
             " in this version; use DPSM_RELAX_TIME_ACCURATE (dpsm_set_relaxation)");
}

// What left through each side, carried along with a state: every state is a
// combination of the start and of evaluations' changes, and what an
// evaluation sends through a side is the same combination of theirs.
struct SideMass {
    double side[4] = {};
    SideMass plus(double weight, const SideMass &o) const {
        SideMass r;
        for (int k = 0; k < 4; ++k) r.side[k] = side[k] + weight * o.side[k];
        return r;
    }
    SideMass minus(const SideMass &o) const { return plus(-1.0, o); }
};
SideMass side_mass_of(const SubstepSummary &evaluation, double dt) {
    SideMass m;
    for (int k = 0; k < 4; ++k) m.side[k] = evaluation.side_outflow_rate[k] * dt;
    return m;
}

}  // namespace

bool relax_to_rest(Grid &grid, std::int64_t budget, double &cells_visited) {
    cells_visited = 0.0;
    require_supported(grid);
    prepare_tiled_sweep(grid, grid.step_threads());  // allocates before anything changes
    StepInfo info;
    info.at_rest = true;
    info.time_integrated = 0.0;
    // At rest already: no tile can move, and no evaluation is needed to know it.
    if (!active_set(grid).may_move()) {
        grid.last_step() = info;
        return true;
    }
    // All the memory first: an allocation that fails leaves the grid as it was.
    const double dt = structured_stable_dt(grid);
    Evaluator rates(grid, dt);
    // The states change roles by swapping these pointers; the evaluator only
    // needs to know which arrays they are, not which is which.
    double *y0 = rates.state(0), *yjm1 = rates.state(1), *yjm2 = rates.state(2), *yj = rates.state(3);
    double *f0 = rates.rates();
    SideMass out_y0, out_yjm1, out_yjm2, out_yj, out_f0;  // the states' side outflows since the start
    const double switch_excess = kSwitchExcessShare * std::tan(grid.min_repose_angle());
    const CellLoops &loops = cell_loops();

    // The flow's path by RKC steps, while much sand moves.
    bool rested = false, switched = false;
    double last_excess = 0.0;
    for (int k = 0; rates.evaluations() < budget; ++k) {
        const SubstepSummary start = rates.evaluate(y0);
        out_f0 = side_mass_of(start, dt);
        last_excess = start.max_excess_slope;
        if (!start.moved) {
            rested = true;
            break;
        }
        if (start.max_excess_slope < switch_excess) {
            switched = true;
            break;
        }
        // Its stages after the first evaluation must fit in what is left of the limit.
        const std::int64_t left = budget - rates.evaluations();
        if (left < 1) break;
        const RkcStep rkc(static_cast<int>(std::min<std::int64_t>(std::min(kMaxStages, 2 + k), left + 1)));
        const double tau = kStageSafety * rkc.beta / 2.0;  // the step in units of the explicit sub-step
        // Each stage as y0 plus a combination of changes, so that a cell no
        // face acts on keeps its height to the last bit.
        const double first = rkc.b[1] * rkc.w1 * tau;
        const double *start_next = rates.next();
        rates.for_rows([&](std::size_t c0, std::size_t c1) {
            for (std::size_t c = c0; c < c1; ++c) {
                f0[c] = start_next[c] - y0[c];  // dt times the rates at y0
                yjm2[c] = y0[c];
                yjm1[c] = y0[c] + first * f0[c];
            }
        });
        out_yjm2 = out_y0;
        out_yjm1 = out_y0.plus(first, out_f0);
        for (int j = 2; j <= rkc.s; ++j) {
            const SideMass out_next = side_mass_of(rates.evaluate(yjm1), dt);
            const double *next = rates.next();
            const double mu = 2.0 * rkc.b[j] * rkc.w0 / rkc.b[j - 1], nu = -rkc.b[j] / rkc.b[j - 2];
            const double mut = 2.0 * rkc.b[j] * rkc.w1 / rkc.b[j - 1];
            const double gamt = -(1.0 - rkc.b[j - 1] * rkc.T[j - 1]) * mut;
            const StageWeights weights{mu, nu, mut * tau, gamt * tau};
            rates.for_rows([&](std::size_t c0, std::size_t c1) {
                loops.rkc_stage(c0, c1, y0, yjm1, yjm2, next, f0, weights, yj);
            });
            out_yj = out_y0.plus(mu, out_yjm1.minus(out_y0))
                         .plus(nu, out_yjm2.minus(out_y0))
                         .plus(weights.mut_tau, out_next)
                         .plus(weights.gamt_tau, out_f0);
            std::swap(yjm2, yjm1);
            std::swap(yjm1, yj);
            std::swap(out_yjm2, out_yjm1);
            std::swap(out_yjm1, out_yj);
        }
        std::swap(y0, yjm1);
        std::swap(out_y0, out_yjm1);
    }

    // Momentum for the tail, where little sand is left to move.
    double *&x = y0, *&x_prev = yjm1, *&y = yjm2;
    SideMass &out_x = out_y0, &out_x_prev = out_yjm1, &out_y = out_yjm2;
    const auto copy = [&](double *to, const double *from) {
        rates.for_rows([&](std::size_t c0, std::size_t c1) { std::copy(from + c0, from + c1, to + c0); });
    };
    copy(x_prev, x);
    out_x_prev = out_x;
    for (std::int64_t k = 0; switched && !rested && rates.evaluations() < budget;) {
        const double beta = static_cast<double>(k) / static_cast<double>(k + 3);
        rates.for_rows([&](std::size_t c0, std::size_t c1) { loops.extrapolate(c0, c1, x, x_prev, beta, y); });
        out_y = out_x.plus(beta, out_x.minus(out_x_prev));
        const SubstepSummary at = rates.evaluate(y);
        const double *next = rates.next();
        last_excess = at.max_excess_slope;
        if (!at.moved) {
            copy(x, y);
            copy(x_prev, y);
            out_x = out_x_prev = out_y;
            rested = k == 0;
            k = 0;
            continue;
        }
        MomentumStep step;
        rates.for_rows([&](std::size_t c0, std::size_t c1) { loops.momentum(c0, c1, next, y, x, x_prev, step); });
        out_x_prev = out_y.plus(1.0, side_mass_of(at, dt));
        std::swap(x, x_prev);  // x_prev: the x before this step
        std::swap(out_x, out_x_prev);
        const auto total = [](const double *parts) { return (parts[0] + parts[1]) + (parts[2] + parts[3]); };
        if (total(step.along) < 0.0 || total(step.coasting) > kCoastingShare * total(step.motion)) {
            copy(x_prev, x);
            out_x_prev = out_x;
            k = 0;
        } else {
            ++k;
        }
    }

    // Where sand can leave, what left is booked as outflow, with the rounding
    // of the combined stages; where it cannot, that rounding is all the
    // change and is not outflow.
    const double left = rates.mass_left(x);
    const bool sinks = grid.has_open_cells() || grid.any_side_open();
    cells_visited = rates.cells_visited();
    // The stages and momentum are not monotone and their sums round: on rough
    // scenes they can leave a hole below the lowest start height, or lose
    // more mass to rounding than the time-accurate steps would. Then the
    // step is not the model's: the grid goes back to its start, for the
    // caller to step in time.
    const MassLedger &ledger = grid.ledger();
    const double mass = std::fabs(ledger.external.value() + ledger.sourced.value() - ledger.outflow.value() -
                                  ledger.unmet.value());
    if (!rates.within_start_extremes(x) || (!sinks && std::fabs(left) > kMassSlack * mass)) {
        rates.restore_start();
        return false;
    }
    // The state reached becomes the grid's (at rest, it already is).
    rates.finish(x);
    if (sinks) grid.ledger().outflow.add(left);
    for (int side = 0; side < 4; ++side)
        if (out_x.side[side] != 0.0) grid.ledger().side_outflow[side].add(out_x.side[side]);
    // The evaluation that found rest moved nothing and is not counted, as a
    // time-accurate sub-step that finds rest is not: a step on a surface at
    // rest reads 0, however it was found so.
    info.substeps = rates.evaluations() - (rested ? 1 : 0);
    info.substeps_evaluated = info.substeps;
    info.at_rest = rested;
    info.max_excess_slope = rested ? 0.0 : last_excess;
    info.cell_updates = rates.cells_visited() - (rested ? rates.cells_visited_last() : 0.0);
    grid.last_step() = info;
    return true;
}

}  // namespace dpsm
