#include "stepper.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "closure.hpp"
#include "decomposition.hpp"
#include "dpsm/dpsm.h"
#include "error.hpp"
#include "kernels.hpp"
#include "relax_to_rest.hpp"
#include "tiled_sweep.hpp"

namespace dpsm {

double stable_dt(const Grid &grid) {
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

// Without a source, the slide flux only carries sand downhill, so the energy
// sum (h - L)^2 over sand cells falls whenever sand moves, as long as every
// held level (open sides at 0, open cells) is the same L: the surface must come
// to rest. Held levels that differ can keep sand flowing between them forever.
bool can_flow_forever(const Grid &grid, const StepAgreement &state) {
    if (state.source_active) return true;
    if (!state.has_open_cells) return false;
    const Geometry &geo = grid.geometry();
    bool any_side_open = grid.side_open(kXMin) || grid.side_open(kXMax);
    if (geo.dim == 2) any_side_open = any_side_open || grid.side_open(kYMin) || grid.side_open(kYMax);
    if (state.open_level_min != state.open_level_max) return true;
    return any_side_open && state.open_level_min != 0.0;
}

// What decides the step's work: the grid's own figures, or on a block of a
// distributed grid the same figures over all blocks (decomposition.hpp).
StepAgreement agree_before_step(Grid &grid, double dt) {
    if (Decomposition *decomposition = grid.decomposition()) return decomposition->agree_before_step(grid, dt, false);
    StepAgreement state;
    state.source_active = grid.source_active();
    state.has_open_cells = grid.has_open_cells();
    state.may_move = grid.geometry().dim == 2 && grid.active_set().may_move();
    state.open_level_min = grid.open_level_min();
    state.open_level_max = grid.open_level_max();
    return state;
}

}  // namespace

void step(Grid &grid, double dt) {
    // The default relaxes to rest where the relaxation supports the scene and
    // gets there in no more flux evaluations than the time-accurate step would
    // take sub-steps over dt: then the sand would (nearly) have come to rest
    // within dt anyway, and the relaxation is the shorter way there. A flow
    // that lasts longer than that is stepped in time, and a dt of fewer than
    // kAutoLeastSubsteps sub-steps is stepped in time at once (the relaxation
    // rarely rests so soon, and trying would double the step's cost). A
    // distributed grid is not supported, on every rank alike, so its ranks
    // all step in time.
    constexpr double kAutoLeastSubsteps = 16.0;
    const Relaxation relaxation = grid.relaxation();
    bool relax = relaxation == kToRest;
    std::int64_t budget = grid.max_substeps();
    if (relaxation == kAutoRelaxation && relaxation_unsupported(grid) == nullptr) {
        const double substeps = std::ceil(dt / stable_dt(grid));
        relax = substeps >= kAutoLeastSubsteps;
        if (substeps < static_cast<double>(budget)) budget = static_cast<std::int64_t>(substeps);
    }
    if (!relax) {
        step_in_time(grid, dt);
        return;
    }
    // Not on a distributed grid (relax_to_rest refuses it): its peers may
    // be waiting in the step's first agreement, so take part, refusing.
    if (Decomposition *decomposition = grid.decomposition()) {
        try {
            decomposition->agree_before_step(grid, 0.0, true);
        } catch (const Error &) {
            // every rank throws; this one reports its own reason below
        }
    }
    // No time scale: dt only says that time passed.
    double tried = 0.0;
    const bool automatic = relaxation == kAutoRelaxation;
    if (relax_to_rest(grid, budget, automatic, tried)) return;
    // Where the relaxation could not reach a rest of the model's own (or, by
    // default, not within its budget), the time-accurate sub-steps take over
    // from the same start: by default over dt; asked to rest, to rest, within
    // as many sub-steps as the relaxation had evaluations (dpsm_set_max_substeps).
    if (automatic)
        step_in_time(grid, dt);
    else
        step_in_time(grid, std::numeric_limits<double>::infinity(), budget);
    grid.last_step().cell_updates += tried;
}

void step_in_time(Grid &grid, double dt, std::int64_t most) {
    const StepAgreement state = agree_before_step(grid, dt);  // first: it may set the smallest angle
    const double dt_max = stable_dt(grid);
    const double needed = std::ceil(dt / dt_max);
    // A count beyond 2^53 cannot be stepped exactly; a scene that comes to rest
    // never gets there, and one that may flow forever is refused.
    const bool bounded = needed <= 9007199254740992.0;
    if (can_flow_forever(grid, state) && (!bounded || needed > static_cast<double>(grid.max_substeps()))) {
        std::ostringstream msg;
        msg << "dpsm_step: dt = " << dt << " needs " << needed << " sub-steps of at most " << dt_max
            << " in a scene that may never come to rest (an active source or open cells at different"
               " levels), more than the limit of "
            << grid.max_substeps() << "; take shorter steps or raise the limit with dpsm_set_max_substeps";
        throw Error(DPSM_ERR_WORK_LIMIT, msg.str());
    }
    const bool two_d = grid.geometry().dim == 2;
    if (two_d) prepare_tiled_sweep(grid, grid.threads());  // allocates before anything changes

    // Without a bound, step at dt_max until the surface rests (it must, or the
    // check above would have refused).
    const std::int64_t substeps = bounded ? std::max<std::int64_t>(1, static_cast<std::int64_t>(needed)) : most;
    const double sub_dt = bounded ? dt / static_cast<double>(substeps) : dt_max;
    const bool source_active = state.source_active;
    MassLedger &ledger = grid.ledger();

    // Books one sub-step; false once the surface is found at rest (nothing
    // moved and no source acts: no later sub-step can change anything).
    StepInfo info;
    // With a bed, erosion takes at most the sand there, so the source booked is
    // what the sweep applied, cell by cell: the rate asked for less the unmet
    // part would cancel two large figures when erosion asks far more than lies there.
    const bool source_capped = source_active && !grid.bed().empty();
    auto book = [&](bool moved, double outflow_rate, double max_excess, double unmet_mass, double sourced_mass) {
        info.max_excess_slope = max_excess;
        if (!moved && !source_active) {
            info.at_rest = true;
            return false;
        }
        ledger.outflow.add(outflow_rate * sub_dt);
        if (source_capped)
            ledger.sourced.add(sourced_mass);
        else if (source_active)
            ledger.sourced.add(grid.source_mass_rate() * sub_dt);
        if (unmet_mass != 0.0) ledger.unmet.add(unmet_mass);  // erosion that found no sand above the bed
        ++info.substeps;
        return true;
    };

    if (two_d) {
        // Idle: no tile can move and no source acts.
        if (!source_active && !state.may_move) {
            info.at_rest = true;
        } else {
            std::vector<LevelSummary> levels;
            for (std::int64_t k = 0; k < substeps && !info.at_rest; k += ActiveSet::kMaxLevels) {
                const int count = static_cast<int>(std::min<std::int64_t>(ActiveSet::kMaxLevels, substeps - k));
                // The step reports the largest excess slope of its last sub-step.
                const bool last_sweep = k + count >= substeps;
                const double visited = static_cast<double>(tiled_sweep(grid, count, sub_dt, levels, last_sweep));
                for (const LevelSummary &level : levels) {
                    if (!book(level.moved, level.outflow_rate, level.max_excess, level.unmet_mass, level.sourced_mass))
                        break;
                    info.cell_updates += visited;
                }
            }
        }
    } else {
        for (std::int64_t k = 0; k < substeps; ++k) {
            const SweepResult sweep = slide_rates_1d(grid, sub_dt);
            if (!book(sweep.moved, sweep.outflow_rate, sweep.max_excess_slope, sweep.unmet_mass, sweep.sourced_mass))
                break;
            apply_rates(grid, sub_dt);
            info.cell_updates += static_cast<double>(grid.geometry().cells());
        }
    }
    if (grid.decomposition()) info.cell_updates = grid.global_sum(info.cell_updates);
    info.time_integrated = info.at_rest || !bounded ? static_cast<double>(info.substeps) * sub_dt : dt;
    grid.last_step() = info;
}

}  // namespace dpsm
