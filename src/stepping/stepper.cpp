#include "stepping/stepper.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "dpsm/dpsm.h"
#include "model/distribution.hpp"
#include "model/error.hpp"
#include "model/limits.hpp"
#include "stepping/engine_for.hpp"

namespace dpsm {

double stable_dt(const Grid &grid) { return engine_for(grid).stable_dt(grid); }

void read_face_fluxes(const Grid &grid, double *fx, double *fy) { engine_for(grid).read_face_fluxes(grid, fx, fy); }

namespace {

// A step that records face fluxes starts from none: the engine clears the
// faces it will write (Engine::advance), this numbers the step.
void begin_face_fluxes(Grid &grid) {
    FaceFluxes &fluxes = grid.face_fluxes();
    ++fluxes.step;
    fluxes.available = true;
}

// Without a source that makes a face steep (`driven`), the slide flux only
// carries sand downhill, so the energy
// sum (h - L)^2 over sand cells falls whenever sand moves, as long as every
// held level (open cells, and the outside of open sides) is the same L: the
// surface must come to rest. Held levels that differ can keep sand flowing
// between them forever.
bool can_flow_forever(const StepAgreement &state, bool driven) {
    if (driven) return true;
    const bool any_side_open = state.any_side_open;
    if (!state.has_open_cells && !any_side_open) return false;
    double lowest = state.has_open_cells ? state.open_level_min : state.side_level_min;
    double highest = state.has_open_cells ? state.open_level_max : state.side_level_max;
    if (any_side_open) {
        lowest = std::min(lowest, state.side_level_min);
        highest = std::max(highest, state.side_level_max);
    }
    return lowest != highest;
}

// A cell as the host numbers it, for messages: (i, j) from the grid's index
// base on a grid, its index from the mesh's start index on a mesh.
std::string host_cell_name(const Grid &grid, std::int64_t c) {
    const Geometry &geo = grid.geometry();
    if (const Mesh *mesh = geo.mesh.get())
        return "cell " + std::to_string(mesh->host_cell[static_cast<std::size_t>(c)] + mesh->input.start_index);
    const int base = grid.index_base();
    return "cell i = " + std::to_string(c % geo.nx + base) + ", j = " + std::to_string(c / geo.nx + base);
}

// A source that would carry a sand cell beyond the supported range within
// dt (dpsm.h) refuses the step before anything changes. Sliding sand never
// leaves the range of the heights and what the sources add, and erosion stops
// at a bed, which lies inside. `reach`, the engine's bound on |h + q dt|,
// spares the look at every cell where it is inside. Collective on a
// distributed grid.
void require_sources_within_range(Grid &grid, double dt, double reach) {
    std::int64_t beyond = -1;
    double reaches = 0.0;
    if (!(reach <= kMaxMagnitude)) {
        const std::vector<double> &h = grid.heights(), &q = grid.source();
        const std::vector<std::uint8_t> &kind = grid.kinds();
        const bool bed = !grid.bed().empty();
        for (std::size_t c = 0; c < h.size() && beyond < 0; ++c) {
            if (kind[c] != kSand || q[c] == 0.0 || (bed && q[c] < 0.0)) continue;
            reaches = h[c] + q[c] * dt;
            if (!(std::fabs(reaches) <= kMaxMagnitude)) beyond = static_cast<std::int64_t>(c);
        }
    }
    const bool anywhere = grid.distribution() ? grid.global_sum(beyond >= 0 ? 1.0 : 0.0) > 0.0 : beyond >= 0;
    if (!anywhere) return;
    std::ostringstream msg;
    msg << "dpsm_step: dt = " << dt << " would carry ";
    if (beyond >= 0)
        msg << host_cell_name(grid, beyond) << " from " << grid.heights()[static_cast<std::size_t>(beyond)] << " to "
            << reaches << " under its source q = " << grid.source()[static_cast<std::size_t>(beyond)];
    else
        msg << "a cell of another rank";
    msg << ", beyond the supported range [-1e50, 1e50]; take shorter steps or a smaller source";
    throw Error(DPSM_ERR_INVALID_VALUE, msg.str());
}

// What decides the step's work: the grid's own figures, or on a part of a
// distributed grid the same figures over all ranks (model/distribution.hpp).
StepAgreement agree_before_step(Grid &grid, const Engine &engine, double dt) {
    if (Distribution *distribution = grid.distribution()) return distribution->agree_before_step(grid, engine, dt, false);
    StepAgreement state;
    state.source_active = grid.source_active();
    state.has_open_cells = grid.has_open_cells();
    state.may_move = engine.may_move(grid);
    state.open_level_min = grid.open_level_min();
    state.open_level_max = grid.open_level_max();
    state.side_level_min = grid.side_level_min();
    state.side_level_max = grid.side_level_max();
    state.any_side_open = grid.any_side_open();
    return state;
}

// A rank that refuses a step takes part in the step's first agreement,
// refusing, so that the other ranks, which wait in it, fail too instead of
// waiting for ever; its caller then reports its own reason.
void take_part_refusing(Grid &grid) {
    Distribution *distribution = grid.distribution();
    if (!distribution) return;
    try {
        distribution->agree_before_step(grid, engine_for(grid), 0.0, true);
    } catch (const Error &) {
        // every rank throws; this one reports its own reason
    }
}

}  // namespace

void step(Grid &grid, double dt) {
    if (!(std::isfinite(dt) && dt > 0.0)) {
        take_part_refusing(grid);
        if (!std::isfinite(dt)) fail(DPSM_ERR_INVALID_VALUE, "dpsm_step", "dt = ", dt, " is not finite");
        fail(DPSM_ERR_INVALID_VALUE, "dpsm_step", "dt = ", dt, " must be positive");
    }
    // The default advances the model's time by dt, as the time-accurate
    // steps do; relaxing straight to rest is a host's explicit choice.
    if (grid.relaxation() != kToRest) {
        step_in_time(grid, dt);
        return;
    }
    // Not on a distributed grid (relax_to_rest refuses it, below). A mesh
    // relaxes by time-accurate sub-steps to rest, which its parts take together.
    if (!grid.geometry().is_mesh()) take_part_refusing(grid);
    // No time scale: dt only says that time passed.
    double tried = 0.0;
    const std::int64_t budget = grid.max_substeps();
    if (engine_for(grid).relax_to_rest(grid, budget, tried)) {
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
    const Engine &engine = engine_for(grid);
    double messages = 0.0, bytes = 0.0;
    Distribution *distribution = grid.distribution();
    if (distribution) distribution->take_traffic(messages, bytes);  // from here
    const StepAgreement state = agree_before_step(grid, engine, dt);  // first: it may set the smallest angle
    const double dt_max = stable_dt(grid);
    const double needed = std::ceil(dt / dt_max);
    // A count beyond 2^53 cannot be stepped exactly; a scene that comes to rest
    // never gets there, and one that may flow forever is refused.
    const bool bounded = needed <= 9007199254740992.0;
    engine.prepare(grid);  // allocates before anything changes
    // Without a bound, step at dt_max until the surface rests (it must, or the
    // check below refuses).
    SubstepPlan plan;
    plan.substeps = bounded ? std::max<std::int64_t>(1, static_cast<std::int64_t>(needed)) : most;
    plan.sub_dt = bounded ? dt / static_cast<double>(plan.substeps) : dt_max;

    // A source is applied lazily where it cannot make a face steep within
    // the step (structured/lazy_sources.hpp, mesh/mesh_engine.cpp), where
    // the engine can; `driven`: a source may keep sand moving in this step.
    const bool source_active = state.source_active;
    const bool lazy = source_active && bounded && engine.takes_lazy_sources(grid);
    plan.lazy_sources = lazy;
    bool driven = source_active;
    if (source_active) {
        double reach = 0.0;
        const bool steep_at_end = engine.drive_sources(grid, dt, plan.sub_dt, lazy, reach);
        if (std::isfinite(dt)) {
            try {
                require_sources_within_range(grid, dt, reach);
            } catch (const Error &) {
                engine.forget_driven(grid);
                throw;
            }
        }
        if (lazy) driven = grid.global_sum(steep_at_end ? 1.0 : 0.0) > 0.0;  // collective on a distributed grid
    }
    plan.something_may_move = driven || state.may_move;
    if (can_flow_forever(state, driven) && (!bounded || needed > static_cast<double>(grid.max_substeps()))) {
        engine.forget_driven(grid);
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
    const double sub_dt = plan.sub_dt;
    const BookSubstep book = [&](const SubstepSummary &did) {
        info.max_excess_slope = did.max_excess_slope;
        if (!did.moved && !driven && !did.source_may_steepen) {
            info.at_rest = true;
            return false;
        }
        ledger.outflow.add(did.outflow_rate * sub_dt);
        for (int side = 0; side < 4; ++side)
            if (did.side_outflow_rate[side] != 0.0) ledger.side_outflow[side].add(did.side_outflow_rate[side] * sub_dt);
        if (source_capped)
            ledger.sourced.add(did.sourced_mass);
        else if (source_active && !lazy)
            ledger.sourced.add(grid.source_mass_rate() * sub_dt * static_cast<double>(did.substeps));
        if (did.unmet_mass != 0.0) ledger.unmet.add(did.unmet_mass);  // erosion that found no sand above the bed
        info.substeps += did.substeps;
        ++info.substeps_evaluated;
        return true;
    };
    engine.advance(grid, plan, book, info);

    // A lazy source acts over all of dt, whenever its cells took it.
    if (lazy) ledger.sourced.add(grid.source_mass_rate() * dt);
    info.rank_cell_updates = info.cell_updates;
    if (distribution) {
        info.cell_updates = grid.global_sum(info.cell_updates);
        distribution->take_traffic(info.messages_sent, info.bytes_sent);
        info.substeps_per_exchange = distribution->substeps_per_exchange(grid);
    }
    const bool whole_dt = source_active || !(info.at_rest || !bounded);
    info.time_integrated = whole_dt ? dt : static_cast<double>(info.substeps) * sub_dt;
    grid.last_step() = info;
}

}  // namespace dpsm
