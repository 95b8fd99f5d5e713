// What the structured engine keeps of its own on a grid between calls
// (model/engine.hpp): the 2D sweep's active set and scratch, the lazy
// sources' clocks, the relaxation's arrays, the line sweep's rates. It hears
// of every change the host makes (model/changes.hpp) and keeps the active
// set and the scratch true to it.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "model/grid.hpp"
#include "model/switches.hpp"
#include "structured/active_set.hpp"

namespace dpsm {

class Halo;
struct RelaxWorkspace;
struct TiledWorkspace;

struct StructuredState final : EngineState {
    explicit StructuredState(const Grid &grid);
    ~StructuredState() override;

    void changed(const Grid &grid, unsigned what, const ChangedCells *cells) override;

    // 2D grids: the tiles that can move (null on a line).
    std::unique_ptr<ActiveSet> active;
    // Outside this box every residual is 0 (2D grids): what the relaxation
    // to rest must clear before its sweeps without residuals.
    CellBox residual_bounds;
    // Lazy sources (structured/lazy_sources.hpp), once a 2D grid has a
    // source: per cell, the sub-steps counted since the grid began after
    // which a source cell's stored height is current, where that is later
    // than clock_base, the count at the start of the present step (at the
    // end of a step every source cell is current).
    std::vector<double> clock;
    double clock_base = 0.0;
    // The line sweep's rates (1D and axisymmetric grids).
    std::vector<double> rates;
    // The switches of tests (model/switches.hpp), read at the start of each step's work.
    Switches switches;
    // On a block of a distributed grid: its exchange with the neighbours
    // (the grid's Distribution), found at the start of each step.
    Halo *halo = nullptr;

    // The 2D sweep's scratch and the relaxation's arrays, made on first use.
    TiledWorkspace &tiled_workspace();
    bool has_tiled_workspace() const { return tiled_ != nullptr; }
    RelaxWorkspace &relax_workspace(const Grid &grid);

    // A sweep or step may have left residuals that are not 0 within the box.
    void residuals_written(const CellBox &box) { residual_bounds.add(box); }

private:
    std::unique_ptr<TiledWorkspace> tiled_;
    std::unique_ptr<RelaxWorkspace> relax_;
};

// The grid's structured state (the grid's engine is the structured engine).
StructuredState &structured_state(Grid &grid);
const StructuredState &structured_state(const Grid &grid);
// The active set of a 2D grid.
inline ActiveSet &active_set(Grid &grid) { return *structured_state(grid).active; }
inline const ActiveSet &active_set(const Grid &grid) { return *structured_state(grid).active; }

}  // namespace dpsm
