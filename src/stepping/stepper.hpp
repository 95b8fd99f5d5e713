// Time stepping: splits dpsm_step's dt into stable explicit sub-steps, stops
// when the surface is at rest, and books sources and outflow in the ledger.
#pragma once

#include "model/grid.hpp"

namespace dpsm {

// The largest sub-step at which explicit Euler is monotone for the flux law
// (see dpsm_stable_dt in dpsm.h).
double stable_dt(const Grid &grid);

// dpsm_step: relaxes to rest or advances in time, as the grid's relaxation
// asks (model/grid.hpp). Refuses a dt that is not finite or not positive
// (on every rank of a distributed grid).
void step(Grid &grid, double dt);

// The last step's face fluxes in the layout of dpsm_get_face_fluxes (library
// order; fy on 2D grids only); the grid records them.
void read_face_fluxes(const Grid &grid, double *fx, double *fy);

// Advances exactly dt (or until rest) by time-accurate sub-steps; a dt of
// more than 2^53 stable sub-steps (infinity included) steps at the stable
// sub-step until rest, at most `most` of them. Throws
// Error(DPSM_ERR_WORK_LIMIT) before changing anything if a scene that can
// flow forever needs more sub-steps than the grid's limit.
void step_in_time(Grid &grid, double dt, std::int64_t most = INT64_MAX);

}  // namespace dpsm
