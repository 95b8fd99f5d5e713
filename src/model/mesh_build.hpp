// What the serial builders (model/mesh.cpp) and a rank's part
// (model/mesh_part.cpp) share: the assembly of a mesh from the host's
// arrays, the least-squares stencils and the sub-step's scale. Internal to
// those two files.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "model/mesh.hpp"

namespace dpsm {

struct PartOfMesh;

// A mesh from polygons or a graph, checked and renumbered, without its
// gradients and sub-step scale; `part` null on a serial mesh. `geographic`:
// the nodes are longitude and latitude, lengths and areas on the sphere.
std::shared_ptr<Mesh> assemble_polygons(std::int64_t nnodes, const double *node_xy, std::int64_t ncells,
                                        const std::int64_t *cell_start, const std::int64_t *cell_nodes,
                                        const PartOfMesh *part, const char *function, int base,
                                        bool geographic = false);
std::shared_ptr<Mesh> assemble_graph(std::int64_t ncells, const double *cell_xy, const double *cell_area,
                                     std::int64_t nfaces, const std::int64_t *face_cells, const double *face_xy,
                                     const double *face_length, const PartOfMesh *part, const char *function,
                                     int base);

// The least-squares gradient weights of every cell whose stencil lies on
// this rank, over the cells across its faces; `has_stencil` says which
// (model/mesh.cpp).
void gradient_weights(Mesh &m, const std::vector<std::int64_t> &ghost_start,
                      const std::vector<std::int64_t> &ghost_neighbours, std::vector<std::uint8_t> &has_stencil);

// The smallest area over summed conductance of any owned cell (1 where no
// face conducts: nothing ever moves).
void set_step_scale(Mesh &m);

}  // namespace dpsm
