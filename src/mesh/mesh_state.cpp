#include "mesh/mesh_state.hpp"

namespace dpsm {

MeshState::MeshState(const Grid &grid) {
    const std::size_t cells = static_cast<std::size_t>(grid.geometry().cells());
    activity.hot.assign(cells, 0);
    // Every part sends it with the heights, so every part holds it (mesh/mesh_parts.cpp).
    since.assign(cells, 0.0);
}

void MeshState::changed(const Grid &grid, unsigned what, const ChangedCells *cells) {
    // The sinks' faces and the source cells follow the kinds, edges and sources.
    if (what & (kMasksChanged | kSourcesChanged | kSidesChanged)) lists_current = false;
    if (what & (kMasksChanged | kLawChanged | kSidesChanged)) {
        activity.wake_all();  // any face may now carry sand
    } else if ((what & kCellsChanged) && cells) {
        // Only the cells that changed, and those across their faces, wake.
        if (!cells->cells) {
            activity.wake_all();
            return;
        }
        const Mesh &m = *grid.geometry().mesh;
        for (const std::int64_t c : *cells->cells) activity.wake_around(m, c);
    }
}

MeshState &mesh_state(Grid &grid) { return static_cast<MeshState &>(*grid.engine_state()); }

const MeshState &mesh_state(const Grid &grid) { return static_cast<const MeshState &>(*grid.engine_state()); }

}  // namespace dpsm
