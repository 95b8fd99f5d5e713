// What the relaxation to rest (structured/relax_to_rest.cpp) does to a 2D
// grid's heights between its sweeps, tile by tile, so that the active set
// and the sweep's scratch learn of it as they learn of a host's edits, and
// nothing is booked in the ledger.
#pragma once

#include <vector>

#include "structured/active_set.hpp"

namespace dpsm {

class Grid;

// Every height becomes y's and every residual 0, where y may differ from
// the heights only within the box. Only the cells that change are looked at
// again, tile by tile.
void set_heights_between_sweeps(Grid &grid, const double *y, const CellBox &within);
// The same where every residual is 0 already: copies the box without a look
// at which cells differ, and wakes all of it.
void copy_heights_between_sweeps(Grid &grid, const double *y, const CellBox &within);

// The residuals of the cells where steps may have left some (the state's
// residual_bounds), the box's row by row.
struct SavedResiduals {
    CellBox box;
    std::vector<float> values;
};
// Every residual becomes 0, waking the cells whose residual was not (the
// relaxation has no use for them); costs what the residuals that steps left
// behind cover, not the grid. Returns what they were.
SavedResiduals drop_residuals(Grid &grid);
void restore_residuals(Grid &grid, const SavedResiduals &saved);

// The mass of `to` less that of `from` on the sand cells of a box, summed
// cell by cell, so that a change to a few cells of a large pile comes out
// exactly rather than as the difference of two large sums.
double sand_mass_change(const Grid &grid, const double *from, const double *to, const CellBox &within);

}  // namespace dpsm
