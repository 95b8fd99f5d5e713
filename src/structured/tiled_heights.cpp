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

}  // namespace

void set_heights_between_sweeps(Grid &grid, const double *y, const CellBox &within) {
    StructuredState &state = structured_state(grid);
    const Geometry &geo = grid.geometry();
    const std::int64_t nx = geo.nx, ny = geo.ny, side = ActiveSet::kTile;
    const std::int64_t wi0 = std::max<std::int64_t>(within.i0, 0), wi1 = std::min(within.i1, nx);
    const std::int64_t wj0 = std::max<std::int64_t>(within.j0, 0), wj1 = std::min(within.j1, ny);
    if (wi0 >= wi1 || wj0 >= wj1) return;
    std::vector<double> &heights = grid.heights_for_stepping();
    std::vector<float> &residuals = grid.residuals_for_stepping();
    for (std::int64_t tj = wj0 - wj0 % side; tj < wj1; tj += side)
        for (std::int64_t ti = wi0 - wi0 % side; ti < wi1; ti += side) {
            // Per tile, so that a pile in one corner wakes only its own cells.
            const std::int64_t i_begin = std::max(ti, wi0), i_end = std::min(ti + side, wi1);
            const std::int64_t j_begin = std::max(tj, wj0), j_end = std::min(tj + side, wj1);
            std::int64_t i0 = nx, i1 = -1, j0 = ny, j1 = -1;
            for (std::int64_t j = j_begin; j < j_end; ++j) {
                const double *row_y = y + nx * j;
                double *row_h = heights.data() + nx * j;
                float *row_r = residuals.data() + nx * j;
                auto differs = [&](std::int64_t i) { return row_h[i] != row_y[i] || row_r[i] != 0.0f; };
                // The first and the last cell that differ; those between are
                // simply overwritten (where they agree, with the same values).
                std::int64_t first = i_begin;
                while (first < i_end && !differs(first)) ++first;
                if (first == i_end) continue;
                std::int64_t last = i_end - 1;
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
            if (i1 < 0) continue;
            CellBox box;
            box.add(i0, i1 + 1, j0, j1 + 1);
            heights_changed(state, box);
        }
}

void copy_heights_between_sweeps(Grid &grid, const double *y, const CellBox &within) {
    StructuredState &state = structured_state(grid);
    const Geometry &geo = grid.geometry();
    const std::int64_t nx = geo.nx, ny = geo.ny, side = ActiveSet::kTile;
    const std::int64_t wi0 = std::max<std::int64_t>(within.i0, 0), wi1 = std::min(within.i1, nx);
    const std::int64_t wj0 = std::max<std::int64_t>(within.j0, 0), wj1 = std::min(within.j1, ny);
    if (wi0 >= wi1 || wj0 >= wj1) return;
    std::vector<double> &heights = grid.heights_for_stepping();
    for (std::int64_t j = wj0; j < wj1; ++j) std::copy(y + nx * j + wi0, y + nx * j + wi1, heights.data() + nx * j + wi0);
    // Per tile, as the host's edits are.
    for (std::int64_t tj = wj0 - wj0 % side; tj < wj1; tj += side)
        for (std::int64_t ti = wi0 - wi0 % side; ti < wi1; ti += side) {
            CellBox box;
            box.add(std::max(ti, wi0), std::min(ti + side, wi1), std::max(tj, wj0), std::min(tj + side, wj1));
            heights_changed(state, box);
        }
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
