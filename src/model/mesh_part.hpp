// A rank's part of a distributed mesh as plain geometry: the cells it owns
// and the ghosts around them, built from the host's arrays as the serial
// builders build a mesh (model/mesh.hpp), and finished once the ranks have
// told each other what a part cannot see (mpi/distributed_mesh.cpp). Also
// how far a part may step its ghosts between two exchanges (Mesh::reach).
// No MPI here: the ranks' messages are the MPI component's.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "model/mesh.hpp"

namespace dpsm {

// Per host cell, its global id (from 0) and whether it is a ghost.
struct PartOfMesh {
    const std::int64_t *global_id;
    const std::uint8_t *ghost;
};

// A rank's part from the same arrays as mesh_from_polygons and
// mesh_from_graph, checked as they check, except that a ghost's faces need
// not close it. Not finished: see finish_part.
std::shared_ptr<Mesh> part_from_polygons(std::int64_t nnodes, const double *node_xy, std::int64_t ncells,
                                         const std::int64_t *cell_start, const std::int64_t *cell_nodes,
                                         const PartOfMesh &part, const char *function, int base);
std::shared_ptr<Mesh> part_from_graph(std::int64_t ncells, const double *cell_xy, const double *cell_area,
                                      std::int64_t nfaces, const std::int64_t *face_cells, const double *face_xy,
                                      const double *face_length, const PartOfMesh &part, const char *function,
                                      int base);
// The same part again from what a restart file kept, for the rank `rank`.
std::shared_ptr<Mesh> part_from_input(const MeshInput &input, int rank, const char *function);

// Finishes a part: the gradients of its owned cells and of the ghosts whose
// neighbours are all here (a ghost n's over ghost_neighbours[ghost_start[n -
// owned] .. ghost_start[n - owned + 1]), library indices, as n's owner has
// them), the
// faces of each ghost over the whole mesh (ghost_faces[n - owned]), the
// ghosts' reach, and the sub-step's scale over the owned cells; the caller
// makes step_scale, min_distance and substeps_per_exchange global.
void finish_part(Mesh &m, const std::vector<std::int64_t> &ghost_start,
                 const std::vector<std::int64_t> &ghost_neighbours, const std::vector<double> &ghost_faces);

}  // namespace dpsm
