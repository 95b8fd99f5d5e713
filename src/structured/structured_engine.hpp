// The structured engine behind the Engine interface (model/engine.hpp):
// the tiled sweep with its active set for 2D grids, the line sweep for 1D
// and axisymmetric ones.
#pragma once

#include "model/engine.hpp"

namespace dpsm {

// The stable sub-step of a 1D, 2D or axisymmetric grid.
double structured_stable_dt(const Grid &grid);

const Engine &tiled_engine();  // 2D grids
const Engine &line_engine();   // 1D and axisymmetric grids

}  // namespace dpsm
