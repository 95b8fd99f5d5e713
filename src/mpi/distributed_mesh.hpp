// Distributed meshes (distributed_mesh.cpp), for the loader of restart files
// (distributed.cpp).
#pragma once

#include <mpi.h>

#include <memory>

#include "api/handle.hpp"
#include "model/mesh_part.hpp"
#include "model/grid.hpp"

namespace dpsm {

// Finishes a rank's part of a mesh (model/mesh.hpp: part_from_*, with its
// input's global ids and owners) with the other ranks and makes its grid,
// tied to a duplicate of `comm`; with `state`, the grid restores it.
// Collective; throws Error on every rank alike.
dpsm_grid *part_grid(MPI_Comm comm, std::shared_ptr<Mesh> mesh, const char *fn, GridState *state);

}  // namespace dpsm
