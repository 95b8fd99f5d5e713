// One explicit sweep of the slide fluxes on a 1D or axisymmetric grid (2D
// grids use structured/tiled_sweep.hpp). Every face between two cells carries one flux
// by the law in model/face_law.hpp, which one cell loses and the other gains, so mass
// is conserved face by face: the paper's pairwise exchange (its Eq. 12).
// Faces no steeper than the rest threshold tan(theta) (1 + tol) carry nothing,
// as in the 2D kernel, so a surface at rest is exactly at rest.
// Kernels read the grid and write rates; they never call back up.
#pragma once

#include <vector>

#include "model/grid.hpp"
#include "model/engine.hpp"

namespace dpsm {

// Fills the grid's rate workspace with dh/dt from the slide fluxes for every
// sand cell, 0 for wall and open cells, for a sub-step of dt. Sources are not
// included, except on a grid with a bed, where the rate holds the part of the
// source that finds sand. Updates which cells are moving (hysteresis).
// With record, adds the volume each face carries in the sub-step to the
// grid's face fluxes.
SubstepSummary slide_rates_1d(Grid &grid, double dt, bool record = false);

// h += dt * (rate + q) on sand cells.
void apply_rates(Grid &grid, double dt);

// Sources on a line without the physics of real scenes: whether a face with
// a source on a side is steeper than the rest threshold (less a margin for
// rounding) at the end of T under the sources alone. A face's slope moves
// linearly, so where it is not steep now, nor then, it is not in between:
// once a sub-step has moved nothing and this says no, the rest of the step
// is the source in closed form, apply_source_1d over `substeps` sub-steps of
// dt (source_lag, model/ledger.hpp).
bool source_may_steepen_1d(const Grid &grid, double T);
void apply_source_1d(Grid &grid, double substeps, double dt);

}  // namespace dpsm
