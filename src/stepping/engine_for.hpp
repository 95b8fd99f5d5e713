// The one place that knows which engines there are (model/engine.hpp says
// what an engine is).
#pragma once

#include "model/engine.hpp"

namespace dpsm {

class Grid;

// The engine that steps this grid.
const Engine &engine_for(const Grid &grid);

}  // namespace dpsm
