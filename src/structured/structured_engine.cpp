#include "structured/structured_engine.hpp"

#include <algorithm>
#include <limits>
#include <vector>

#include "model/distribution.hpp"
#include "model/face_law.hpp"
#include "model/grid.hpp"
#include "structured/halo.hpp"
#include "structured/lazy_sources.hpp"
#include "structured/line_sweep.hpp"
#include "structured/relax_to_rest.hpp"
#include "structured/structured_state.hpp"
#include "structured/tiled_sweep.hpp"

namespace dpsm {

double structured_stable_dt(const Grid &grid) {
    const Geometry &geo = grid.geometry();
    const double stiffness =
        slide_flux_max_derivative(grid.mobility(), grid.min_repose_angle(), grid.flux_exponent());
    // No face may take more than its share of the excess: a cell's faces
    // together at most all of it (monotone), a pair at most what brings it to
    // the angle of repose (the paper's bound). On the axisymmetric grid the
    // first ring is small next to its outer face, which tightens the pair
    // bound to 3 dr^2 / (8 nu cos(theta)).
    if (geo.axisymmetric) return 3.0 * geo.dx * geo.dx / (8.0 * stiffness);
    double inverse_spacing2 = 1.0 / (geo.dx * geo.dx);
    if (geo.dim == 2) inverse_spacing2 += 1.0 / (geo.dy * geo.dy);
    return 1.0 / (2.0 * stiffness * inverse_spacing2);
}

namespace {

// What both structured engines share: their state, their sub-step, their
// face fluxes on a line.
class StructuredEngine : public Engine {
public:
    std::unique_ptr<EngineState> make_state(const Grid &grid) const override {
        return std::make_unique<StructuredState>(grid);
    }
    double stable_dt(const Grid &grid) const override { return structured_stable_dt(grid); }
    // The tile kernels that keep the clocks are those without the physics of real scenes.
    bool takes_lazy_sources(const Grid &grid) const override { return !grid.uses_physics(); }
    bool relax_to_rest(Grid &grid, std::int64_t budget, double &cells_visited) const override {
        structured_state(grid).switches = read_switches();
        return dpsm::relax_to_rest(grid, budget, cells_visited);
    }
    void read_face_fluxes(const Grid &grid, double *fx, double *) const override {
        const std::vector<double> &faces = grid.face_fluxes().x;
        std::copy(faces.begin(), faces.end(), fx);
    }
};

// 2D grids: tiles of the active set, swept up to ActiveSet::kMaxLevels
// sub-steps at a time (structured/tiled_sweep.hpp).
class TiledEngine final : public StructuredEngine {
public:
    void prepare(Grid &grid) const override {
        // A block of a distributed grid reads the cells beyond it from its halo.
        structured_state(grid).halo = dynamic_cast<Halo *>(grid.distribution());
        prepare_tiled_sweep(grid, grid.step_threads());
    }
    bool may_move(const Grid &grid) const override { return active_set(grid).may_move(); }

    bool drive_sources(Grid &grid, double dt, double sub_dt, bool lazy, double &reach) const override {
        reach = std::numeric_limits<double>::infinity();
        if (lazy) return dpsm::drive_sources(grid, dt, sub_dt, reach);
        active_set(grid).drive_every_source();
        return true;
    }
    void forget_driven(Grid &grid) const override { active_set(grid).forget_driven(); }

    void advance(Grid &grid, const SubstepPlan &plan, const BookSubstep &book, StepInfo &info) const override {
        StructuredState &state = structured_state(grid);
        if (plan.something_may_move) {
            state.switches = read_switches();
            std::vector<SubstepSummary> levels;
            bool source_may_steepen = false;
            for (std::int64_t k = 0; k < plan.substeps && !info.at_rest; k += ActiveSet::kMaxLevels) {
                const int count = static_cast<int>(std::min<std::int64_t>(ActiveSet::kMaxLevels, plan.substeps - k));
                // The step reports the largest excess slope of its last sub-step.
                const bool last_sweep = k + count >= plan.substeps;
                const double visited = static_cast<double>(
                    tiled_sweep(grid, count, plan.sub_dt, levels, last_sweep, true, static_cast<double>(k)));
                if (plan.lazy_sources) {
                    // Collective on a distributed grid: every rank takes the same sub-steps.
                    const bool near_moves = state.active->drive_sources_near_moves();
                    source_may_steepen = source_may_steepen || grid.global_sum(near_moves ? 1.0 : 0.0) > 0.0;
                }
                for (SubstepSummary &level : levels) {
                    level.source_may_steepen = source_may_steepen;
                    if (!book(level)) break;
                    info.cell_updates += visited;
                }
            }
        } else {
            info.at_rest = true;  // idle: no tile can move and no source can make a face steep
        }
        if (plan.lazy_sources) {
            const double substeps = static_cast<double>(plan.substeps);
            info.cell_updates += catch_up_sources(grid, substeps, plan.sub_dt);
            state.clock_base += substeps;
        }
        state.active->end_of_step();
    }

    // A tile's faces hold the last step's fluxes only if that step visited it.
    void read_face_fluxes(const Grid &grid, double *fx, double *fy) const override {
        const FaceFluxes &fluxes = grid.face_fluxes();
        const ActiveSet &active = active_set(grid);
        const std::int64_t nx = grid.geometry().nx, ny = grid.geometry().ny;
        for (std::int64_t t = 0; t < active.tiles(); ++t) {
            const CellBox tile = active.tile_cells(t);
            // No step has numbered the tiles yet: every face holds 0.
            const bool current = static_cast<std::size_t>(t) >= fluxes.tile_step.size() ||
                                 fluxes.tile_step[static_cast<std::size_t>(t)] == fluxes.step;
            const std::int64_t x1 = tile.i1 + (tile.i1 == nx ? 1 : 0), y1 = tile.j1 + (tile.j1 == ny ? 1 : 0);
            for (std::int64_t j = tile.j0; j < tile.j1; ++j) {
                const std::size_t at = static_cast<std::size_t>(tile.i0 + (nx + 1) * j);
                if (current)
                    std::copy_n(fluxes.x.begin() + at, x1 - tile.i0, fx + at);
                else
                    std::fill_n(fx + at, x1 - tile.i0, 0.0);
            }
            for (std::int64_t j = tile.j0; j < y1; ++j) {
                const std::size_t at = static_cast<std::size_t>(tile.i0 + nx * j);
                if (current)
                    std::copy_n(fluxes.y.begin() + at, tile.i1 - tile.i0, fy + at);
                else
                    std::fill_n(fy + at, tile.i1 - tile.i0, 0.0);
            }
        }
    }
};

// 1D and axisymmetric grids: every face every sub-step (structured/line_sweep.hpp).
class LineEngine final : public StructuredEngine {
public:
    void prepare(Grid &) const override {}
    bool may_move(const Grid &) const override { return true; }

    bool drive_sources(Grid &grid, double dt, double, bool lazy, double &reach) const override {
        reach = std::numeric_limits<double>::infinity();
        return lazy ? source_may_steepen_1d(grid, dt) : true;
    }
    void forget_driven(Grid &) const override {}

    void advance(Grid &grid, const SubstepPlan &plan, const BookSubstep &book, StepInfo &info) const override {
        const double cells = static_cast<double>(grid.geometry().cells());
        if (grid.records_face_fluxes()) {
            std::vector<double> &faces = grid.face_fluxes().x;
            std::fill(faces.begin(), faces.end(), 0.0);
        }
        for (std::int64_t k = 0; k < plan.substeps; ++k) {
            SubstepSummary sweep = slide_rates_1d(grid, plan.sub_dt, grid.records_face_fluxes());
            // Once nothing moves, a source that cannot make a face steep by the
            // end of the step is the rest of it, in closed form. One that can
            // (the start of the step judged it before sand moved) keeps stepping.
            const double left = static_cast<double>(plan.substeps - k);
            if (!sweep.moved && plan.lazy_sources) {
                if (!source_may_steepen_1d(grid, left * plan.sub_dt)) {
                    apply_source_1d(grid, left, plan.sub_dt);
                    info.cell_updates += cells;
                    info.max_excess_slope = 0.0;
                    info.at_rest = true;
                    break;
                }
                sweep.source_may_steepen = true;
            }
            if (!book(sweep)) break;
            apply_rates(grid, plan.sub_dt);
            info.cell_updates += cells;
        }
    }
};

}  // namespace

const Engine &tiled_engine() {
    static const TiledEngine engine;
    return engine;
}

const Engine &line_engine() {
    static const LineEngine engine;
    return engine;
}

}  // namespace dpsm
