#include "structured/tiled_heights.hpp"

#include <algorithm>

#include "model/grid.hpp"
#include "model/ledger.hpp"
#include "structured/structured_state.hpp"
#include "structured/tiled_sweep.hpp"

namespace dpsm {

namespace {

// The cells of the box changed: their tiles are looked at again and the
// sweep's scratch no longer holds them.
void heights_changed(StructuredState &state, const CellBox &box) {
    state.active->mark_block(box.i0, box.j0, box.i1 - box.i0, box.j1 - box.j0);
    if (state.has_tiled_workspace()) tiled_workspace_changed(state.tiled_workspace(), *state.active, box);
}

// Calls part(box) with the part of `within` in each tile it meets, clipped
// to the grid: the relaxation's writes, as the host's edits, cost the tiles
// they touch.
template <class Part>
void for_tile_parts(const Geometry &geo, const CellBox &within, Part &&part) {
    const std::int64_t side = ActiveSet::kTile;
    const CellBox clipped = within.grown_within(0, CellBox{0, geo.nx, 0, geo.ny});
    if (clipped.empty()) return;
    for (std::int64_t tj = clipped.j0 - clipped.j0 % side; tj < clipped.j1; tj += side)
        for (std::int64_t ti = clipped.i0 - clipped.i0 % side; ti < clipped.i1; ti += side) {
            CellBox box;
            box.add(std::max(ti, clipped.i0), std::min(ti + side, clipped.i1), std::max(tj, clipped.j0),
                    std::min(tj + side, clipped.j1));
            part(box);
        }
}

}  // namespace

void set_heights_between_sweeps(Grid &grid, const double *y, const CellBox &within) {
    StructuredState &state = structured_state(grid);
    const std::int64_t nx = grid.geometry().nx, ny = grid.geometry().ny;
    std::vector<double> &heights = grid.heights_for_stepping();
    std::vector<float> &residuals = grid.residuals_for_stepping();
    // Per tile, so that a pile in one corner wakes only its own cells.
    for_tile_parts(grid.geometry(), within, [&](const CellBox &part) {
        std::int64_t i0 = nx, i1 = -1, j0 = ny, j1 = -1;
        for (std::int64_t j = part.j0; j < part.j1; ++j) {
            const double *row_y = y + nx * j;
            double *row_h = heights.data() + nx * j;
            float *row_r = residuals.data() + nx * j;
            auto differs = [&](std::int64_t i) { return row_h[i] != row_y[i] || row_r[i] != 0.0f; };
            // The first and the last cell that differ; those between are
            // simply overwritten (where they agree, with the same values).
            std::int64_t first = part.i0;
            while (first < part.i1 && !differs(first)) ++first;
            if (first == part.i1) continue;
            std::int64_t last = part.i1 - 1;
            while (!differs(last)) --last;
            for (std::int64_t i = first; i <= last; ++i) {
                row_h[i] = row_y[i];
                row_r[i] = 0.0f;
            }
            i0 = std::min(i0, first);
            i1 = std::max(i1, last);
            j0 = std::min(j0, j);
            j1 = j;
        }
        if (i1 < 0) return;
        CellBox box;
        box.add(i0, i1 + 1, j0, j1 + 1);
        heights_changed(state, box);
    });
}

void copy_heights_between_sweeps(Grid &grid, const double *y, const CellBox &within) {
    StructuredState &state = structured_state(grid);
    const std::int64_t nx = grid.geometry().nx;
    std::vector<double> &heights = grid.heights_for_stepping();
    // Per tile, as the host's edits are.
    for_tile_parts(grid.geometry(), within, [&](const CellBox &part) {
        for (std::int64_t j = part.j0; j < part.j1; ++j)
            std::copy(y + nx * j + part.i0, y + nx * j + part.i1, heights.data() + nx * j + part.i0);
        heights_changed(state, part);
    });
}

SavedResiduals drop_residuals(Grid &grid) {
    StructuredState &state = structured_state(grid);
    const Geometry &geo = grid.geometry();
    const std::vector<float> &residuals = grid.residuals();
    SavedResiduals saved;
    const CellBox box = state.residual_bounds.grown_within(0, CellBox{0, geo.nx, 0, geo.ny});
    saved.box = box;
    if (!box.empty()) {
        saved.values.reserve(static_cast<std::size_t>((box.i1 - box.i0) * (box.j1 - box.j0)));
        for (std::int64_t j = box.j0; j < box.j1; ++j)
            saved.values.insert(saved.values.end(), residuals.begin() + (box.i0 + geo.nx * j),
                                residuals.begin() + (box.i1 + geo.nx * j));
    }
    set_heights_between_sweeps(grid, grid.heights().data(), state.residual_bounds);
    state.residual_bounds = CellBox{};
    return saved;
}

void restore_residuals(Grid &grid, const SavedResiduals &saved) {
    StructuredState &state = structured_state(grid);
    const CellBox &box = saved.box;
    if (box.empty()) return;
    const std::int64_t nx = grid.geometry().nx, width = box.i1 - box.i0;
    std::vector<float> &residuals = grid.residuals_for_stepping();
    for (std::int64_t j = box.j0; j < box.j1; ++j)
        std::copy_n(saved.values.begin() + width * (j - box.j0), width, residuals.begin() + (box.i0 + nx * j));
    state.residual_bounds.add(box);
    heights_changed(state, box);
}

double sand_mass_change(const Grid &grid, const double *from, const double *to, const CellBox &within) {
    const Geometry &geo = grid.geometry();
    const std::vector<std::uint8_t> &kinds = grid.kinds();
    CompensatedSum change;
    const std::int64_t nx = geo.nx;
    const std::int64_t i0 = std::max<std::int64_t>(within.i0, 0), i1 = std::min(within.i1, nx);
    const std::int64_t j0 = std::max<std::int64_t>(within.j0, 0), j1 = std::min(within.j1, geo.ny);
    for (std::int64_t j = j0; j < j1; ++j)
        for (std::int64_t c = i0 + nx * j; c < i1 + nx * j; ++c)
            if (kinds[c] == kSand && to[c] != from[c]) change.add((to[c] - from[c]) * geo.cell_area(c));
    return change.value();
}

}  // namespace dpsm
