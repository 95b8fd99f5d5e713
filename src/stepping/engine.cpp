#include "stepping/engine.hpp"

#include "model/grid.hpp"
#include "structured/structured_engine.hpp"

namespace dpsm {

// The only place that knows which engines there are.
const Engine &engine_for(const Grid &grid) {
    return grid.geometry().dim == 2 ? tiled_engine() : line_engine();
}

}  // namespace dpsm
