#include "stepping/engine_for.hpp"

#include "mesh/mesh_engine.hpp"
#include "model/grid.hpp"
#include "structured/structured_engine.hpp"

namespace dpsm {

const Engine &engine_for(const Grid &grid) {
    const Geometry &geo = grid.geometry();
    if (geo.is_mesh()) return mesh_engine();
    return geo.dim == 2 ? tiled_engine() : line_engine();
}

}  // namespace dpsm
