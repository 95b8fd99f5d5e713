// What an engine is to the stepping policy: the code that evaluates fluxes
// and advances heights over one kind of geometry (src/structured/ for 1D,
// 2D and axisymmetric grids, src/mesh/ for unstructured meshes, a GPU one
// day). The stepper (src/stepping/) splits dt into sub-steps, decides when
// the surface rests, refuses work it cannot bound and books the ledger; an
// engine only does what is asked over its own cells, keeps its own state
// (an EngineState the grid holds for it: active set, scratch, clocks) and
// reports what each sub-step did. A new engine implements this class and is
// chosen in stepping/engine_for.cpp; nothing in the C boundary or the
// stepper changes.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>

namespace dpsm {

class Grid;
struct EngineState;
struct StepInfo;

// What one sub-step did over the engine's cells (on a block of a distributed
// grid: over all blocks, once the distribution has agreed on it).
struct SubstepSummary {
    bool moved = false;                // some face carried sand
    double outflow_rate = 0.0;         // mass per unit time into sinks (open sides and open cells)
    double side_outflow_rate[4] = {};  // the part of it that left through each side
    double max_excess_slope = 0.0;     // largest |grad h| - tan(theta) over faces that carried sand, where found
    double unmet_mass = 0.0;           // erosion asked for where no sand lay above the bed
    double sourced_mass = 0.0;         // with a bed: what the source put on (or took from) the sand
    // A lazy source may still make a face steep before the step ends: sand
    // moved near it after the step's start judged it (no rest before the end).
    bool source_may_steepen = false;
    // The sub-steps it stands for: more than 1 where local time steps
    // (mesh/step_classes.hpp) skip the ticks at which nothing is due.
    std::int64_t substeps = 1;
};

// Books one sub-step in the ledger; false once the surface is found at rest
// (the engine then takes no further sub-step).
using BookSubstep = std::function<bool(const SubstepSummary &)>;

// How the stepper asks for a step of `substeps` sub-steps of sub_dt.
struct SubstepPlan {
    std::int64_t substeps = 0;
    double sub_dt = 0.0;
    // Sources applied in closed form where they cannot make a face steep
    // (src/structured/lazy_sources.hpp).
    bool lazy_sources = false;
    // Some cell may move: a source keeps a face steep, or the engine said
    // may_move() before the step.
    bool something_may_move = false;
};

class Engine {
public:
    virtual ~Engine() = default;

    // The state this engine keeps on a grid between calls, made with the
    // grid (its handle attaches it before any call reaches the grid, so that
    // the state hears of every change).
    virtual std::unique_ptr<EngineState> make_state(const Grid &grid) const = 0;
    // The largest sub-step at which explicit Euler is monotone for the flux
    // law on this geometry (dpsm_stable_dt).
    virtual double stable_dt(const Grid &grid) const = 0;
    // Allocates what a step needs; called before anything changes, so that
    // running out of memory leaves the grid as it was.
    virtual void prepare(Grid &grid) const = 0;
    // Whether anything can move with no source acting (an engine without an
    // active set answers true).
    virtual bool may_move(const Grid &grid) const = 0;
    // Whether this engine applies sources in closed form on this grid where
    // they cannot make a face steep (a bounded step with a source).
    virtual bool takes_lazy_sources(const Grid &grid) const = 0;
    // At the start of a step of dt in sub-steps of sub_dt with sources on:
    // marks what the sources may make steep and returns whether a source
    // keeps some face steep at the end of the step (it may then flow for
    // ever). Without lazy sources every source cell is marked and the answer
    // is true. `reach` receives a bound on |h + q dt| over the cells with a
    // source where the engine's pass found one on the way (the stepper then
    // need not look at every cell), else +infinity.
    virtual bool drive_sources(Grid &grid, double dt, double sub_dt, bool lazy, double &reach) const = 0;
    // Undoes drive_sources for a step that is refused.
    virtual void forget_driven(Grid &grid) const = 0;
    // Advances the plan's sub-steps, calling book after each, until book
    // says rest; adds the cells it visited to info.cell_updates, sets
    // info.at_rest and info.max_excess_slope, and leaves every cell current
    // (lazy sources caught up) at the end. A grid that records face fluxes
    // reads, after it, the volume each face carried in this step and 0 on
    // faces that carried nothing.
    virtual void advance(Grid &grid, const SubstepPlan &plan, const BookSubstep &book, StepInfo &info) const = 0;

    // The relaxation to rest (DPSM_RELAX_TO_REST), with the contract of
    // src/structured/relax_to_rest.hpp: true at rest, false with the grid as
    // it was where the stepper must step in time instead; throws
    // Error(DPSM_ERR_NOT_APPLICABLE) for a scene it does not support.
    virtual bool relax_to_rest(Grid &grid, std::int64_t budget, double &cells_visited) const = 0;

    // The last step's face fluxes in the layout of dpsm_get_face_fluxes
    // (library order; fy on 2D grids only), where the grid records them.
    virtual void read_face_fluxes(const Grid &grid, double *fx, double *fy) const = 0;
};

}  // namespace dpsm
