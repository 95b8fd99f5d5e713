// Time stepping: splits dpsm_step's dt into stable explicit sub-steps, stops
// when the surface is at rest, and books sources and outflow in the ledger.
#pragma once

#include "grid.hpp"

namespace dpsm {

// The largest sub-step at which explicit Euler is monotone for the flux law
// (see dpsm_stable_dt in dpsm.h).
double stable_dt(const Grid &grid);

// Advances exactly dt (or until rest). Throws Error(DPSM_ERR_WORK_LIMIT)
// before changing anything if a scene that can flow forever needs more
// sub-steps than the grid's limit.
void step(Grid &grid, double dt);

}  // namespace dpsm
