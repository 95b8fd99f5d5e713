#include "structured/structured_state.hpp"

#include "structured/relax_to_rest.hpp"
#include "structured/tiled_sweep.hpp"

namespace dpsm {

StructuredState::StructuredState(const Grid &grid) {
    const Geometry &geo = grid.geometry();
    if (geo.tiled()) {
        active = std::make_unique<ActiveSet>(geo.nx, geo.ny);
        active->refresh_masks(grid);
    } else {
        rates.assign(static_cast<std::size_t>(geo.cells()), 0.0);
    }
}

StructuredState::~StructuredState() = default;

TiledWorkspace &StructuredState::tiled_workspace() {
    if (!tiled_) tiled_ = std::make_unique<TiledWorkspace>();
    return *tiled_;
}

RelaxWorkspace &StructuredState::relax_workspace(const Grid &grid) {
    if (!relax_)
        relax_ = std::make_unique<RelaxWorkspace>(grid.heights().size(), static_cast<std::size_t>(active->tiles()));
    return *relax_;
}

void StructuredState::changed(const Grid &grid, unsigned what, const ChangedCells *cells) {
    if (!active) return;  // a line: every face is looked at in every sub-step
    const Geometry &geo = grid.geometry();
    if (what == kEverythingChanged) {
        residual_bounds = CellBox{};
        residual_bounds.add(0, geo.nx, 0, geo.ny);
        clock.assign(grid.source().empty() ? 0 : static_cast<std::size_t>(geo.cells()), 0.0);
        clock_base = 0.0;
    }
    if ((what & kCellsChanged) && cells) {
        // The host's cells and their neighbours may move; the scratch no longer holds them.
        active->mark_block(cells->i0, cells->j0, cells->ni, cells->nj);
        if (tiled_) {
            CellBox box;
            box.add(cells->i0, cells->i0 + cells->ni, cells->j0, cells->j0 + cells->nj);
            tiled_workspace_changed(*tiled_, *active, box);
        }
    }
    if ((what & kSourcesChanged) && !grid.source().empty() && clock.size() != static_cast<std::size_t>(geo.cells())) {
        clock.assign(static_cast<std::size_t>(geo.cells()), 0.0);
        if (tiled_) tiled_->all_stale = true;
    }
    if (what & (kSourcesChanged | kMasksChanged)) active->refresh_source(grid);
    if (what & kMasksChanged) active->refresh_masks(grid);
    if (what & (kMasksChanged | kLawChanged | kSidesChanged)) {
        // Any face may now carry sand: every tile is looked at again. Kinds
        // (and with them residuals), the bed or the moving flags changed
        // everywhere: the scratch holds none of them.
        active->mark_all();
        if (tiled_) tiled_->all_stale = true;
    }
}

StructuredState &structured_state(Grid &grid) { return static_cast<StructuredState &>(*grid.engine_state()); }

const StructuredState &structured_state(const Grid &grid) {
    return static_cast<const StructuredState &>(*grid.engine_state());
}

}  // namespace dpsm
