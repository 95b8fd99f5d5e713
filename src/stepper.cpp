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

// A step that records face fluxes starts from none: a 2D grid's tiles are
// cleared as the step first visits them (tiled_sweep.cpp), a line's faces here.
void begin_face_fluxes(Grid &grid) {
    FaceFluxes &fluxes = grid.face_fluxes();
    ++fluxes.step;
    fluxes.available = true;
    if (grid.geometry().dim == 1) std::fill(fluxes.x.begin(), fluxes.x.end(), 0.0);
}

// Without a source that makes a face steep (`driven`), the slide flux only
// carries sand downhill, so the energy
// sum (h - L)^2 over sand cells falls whenever sand moves, as long as every
// held level (open cells, and the outside of open sides) is the same L: the
// surface must come to rest. Held levels that differ can keep sand flowing
// between them forever.
bool can_flow_forever(const Grid &grid, const StepAgreement &state, bool driven) {
    if (driven) return true;
    const Geometry &geo = grid.geometry();
    bool any_side_open = grid.side_open(kXMin) || grid.side_open(kXMax);
    if (geo.dim == 2) any_side_open = any_side_open || grid.side_open(kYMin) || grid.side_open(kYMax);
    if (!state.has_open_cells && !any_side_open) return false;
    double lowest = state.has_open_cells ? state.open_level_min : state.side_level_min;
    double highest = state.has_open_cells ? state.open_level_max : state.side_level_max;
    if (any_side_open) {
        lowest = std::min(lowest, state.side_level_min);
        highest = std::max(highest, state.side_level_max);
    }
    return lowest != highest;
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
    state.side_level_min = grid.side_level_min();
    state.side_level_max = grid.side_level_max();
    return state;
}

}  // namespace

void step(Grid &grid, double dt) {
    // The default advances the model's time by dt, as the time-accurate
    // steps do; relaxing straight to rest is a host's explicit choice.
    if (grid.relaxation() != kToRest) {
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
    const std::int64_t budget = grid.max_substeps();
    if (relax_to_rest(grid, budget, tried)) {
        if (grid.records_face_fluxes()) grid.face_fluxes().available = false;
        return;
    }
    // Where the relaxation could not reach a rest of the model's own, the
    // time-accurate sub-steps take over from the same start, to rest, within
    // as many sub-steps as the relaxation had evaluations (dpsm_set_max_substeps).
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
    const bool two_d = grid.geometry().dim == 2;
    if (two_d) prepare_tiled_sweep(grid, grid.threads());  // allocates before anything changes
    // Without a bound, step at dt_max until the surface rests (it must, or the
    // check below refuses).
    const std::int64_t substeps = bounded ? std::max<std::int64_t>(1, static_cast<std::int64_t>(needed)) : most;
    const double sub_dt = bounded ? dt / static_cast<double>(substeps) : dt_max;

    // A source is applied lazily where it cannot make a face steep within
    // the step (tiled_sweep.hpp), with the physics of real scenes at every
    // sub-step; `driven`: a source may keep sand moving in this step.
    const bool source_active = state.source_active;
    const bool lazy = source_active && bounded && !grid.uses_physics();
    bool driven = source_active;
    if (two_d && source_active) {
        if (lazy)
            driven = grid.global_sum(drive_sources(grid, dt, sub_dt) ? 1.0 : 0.0) > 0.0;
        else
            grid.active_set().drive_every_source();
    } else if (lazy) {
        driven = source_may_steepen_1d(grid, dt);
    }
    if (can_flow_forever(grid, state, driven) && (!bounded || needed > static_cast<double>(grid.max_substeps()))) {
        if (two_d) grid.active_set().forget_driven();
        std::ostringstream msg;
        msg << "dpsm_step: dt = " << dt << " needs " << needed << " sub-steps of at most " << dt_max
            << " in a scene that may never come to rest (a source that makes a face steep, or open cells and open "
               "sides held at different levels), more than the limit of "
            << grid.max_substeps() << "; take shorter steps or raise the limit with dpsm_set_max_substeps";
        throw Error(DPSM_ERR_WORK_LIMIT, msg.str());
    }
    if (grid.records_face_fluxes()) begin_face_fluxes(grid);
    MassLedger &ledger = grid.ledger();

    // Books one sub-step; false once the surface is found at rest (nothing
    // moved and no source may make a face steep: no later sub-step can move
    // anything).
    StepInfo info;
    // With a bed, erosion takes at most the sand there, so the source booked is
    // what the sweep applied, cell by cell: the rate asked for less the unmet
    // part would cancel two large figures when erosion asks far more than lies there.
    const bool source_capped = source_active && !grid.bed().empty();
    auto book = [&](bool moved, double outflow_rate, const double *side_outflow_rate, double max_excess,
                    double unmet_mass, double sourced_mass) {
        info.max_excess_slope = max_excess;
        if (!moved && !driven) {
            info.at_rest = true;
            return false;
        }
        ledger.outflow.add(outflow_rate * sub_dt);
        for (int side = 0; side < 4; ++side)
            if (side_outflow_rate[side] != 0.0) ledger.side_outflow[side].add(side_outflow_rate[side] * sub_dt);
        if (source_capped)
            ledger.sourced.add(sourced_mass);
        else if (source_active && !lazy)
            ledger.sourced.add(grid.source_mass_rate() * sub_dt);
        if (unmet_mass != 0.0) ledger.unmet.add(unmet_mass);  // erosion that found no sand above the bed
        ++info.substeps;
        return true;
    };

    if (two_d) {
        if (driven || state.may_move) {
            std::vector<LevelSummary> levels;
            for (std::int64_t k = 0; k < substeps && !info.at_rest; k += ActiveSet::kMaxLevels) {
                const int count = static_cast<int>(std::min<std::int64_t>(ActiveSet::kMaxLevels, substeps - k));
                // The step reports the largest excess slope of its last sub-step.
                const bool last_sweep = k + count >= substeps;
                const double visited = static_cast<double>(
                    tiled_sweep(grid, count, sub_dt, levels, last_sweep, true, static_cast<double>(k)));
                for (const LevelSummary &level : levels) {
                    if (!book(level.moved, level.outflow_rate, level.side_outflow_rate, level.max_excess,
                              level.unmet_mass, level.sourced_mass))
                        break;
                    info.cell_updates += visited;
                }
            }
        } else {
            info.at_rest = true;  // idle: no tile can move and no source can make a face steep
        }
        if (lazy) {
            info.cell_updates += catch_up_sources(grid, static_cast<double>(substeps), sub_dt);
            grid.set_clock_base(grid.clock_base() + static_cast<double>(substeps));
        }
        grid.active_set().end_of_step();
    } else {
        for (std::int64_t k = 0; k < substeps; ++k) {
            const SweepResult sweep = slide_rates_1d(grid, sub_dt, grid.records_face_fluxes());
            // Once nothing moves, a source that cannot make a face steep by the
            // end of the step is the rest of it, in closed form.
            const double left = static_cast<double>(substeps - k);
            if (!sweep.moved && lazy && !source_may_steepen_1d(grid, left * sub_dt)) {
                apply_source_1d(grid, left, sub_dt);
                info.cell_updates += static_cast<double>(grid.geometry().cells());
                info.max_excess_slope = 0.0;
                info.at_rest = true;
                break;
            }
            if (!book(sweep.moved, sweep.outflow_rate, sweep.side_outflow_rate, sweep.max_excess_slope,
                      sweep.unmet_mass, sweep.sourced_mass))
                break;
            apply_rates(grid, sub_dt);
            info.cell_updates += static_cast<double>(grid.geometry().cells());
        }
    }
    // A lazy source acts over all of dt, whenever its cells took it.
    if (lazy) ledger.sourced.add(grid.source_mass_rate() * dt);
    if (grid.decomposition()) info.cell_updates = grid.global_sum(info.cell_updates);
    const bool whole_dt = source_active || !(info.at_rest || !bounded);
    info.time_integrated = whole_dt ? dt : static_cast<double>(info.substeps) * sub_dt;
    grid.last_step() = info;
}

}  // namespace dpsm
