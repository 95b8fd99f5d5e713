// What a part of a distributed mesh adds to the mesh engine: its ghosts take
// their owners' values through the part's GhostExchange (mesh/ghost_exchange.hpp).
//
//  - In a sub-step, four exchanges: the owned cells' gradients (for the
//    faces between an owned cell and a ghost), their pulls and their
//    limiters' factors (mesh/mesh_engine.cpp), and after the update their
//    heights.
//  - Where the host's ghost layer is deep enough, a part steps the ghosts in
//    reach too (Mesh::reach, model/mesh_part.hpp) and exchanges heights once
//    per batch of that many sub-steps; the step ends with an exchange.
//  - After a host's edit on any rank, at the start of the next step: the
//    ghosts' kinds, sources, bed and angles, their heights, and the edge
//    faces of the ghosts stepped here.
//
// Each is collective over the part's ranks; only values that changed travel
// in a sub-step.
#pragma once

#include <cstdint>
#include <vector>

#include "model/mesh.hpp"

namespace dpsm {

class Grid;
class GhostExchange;
struct MeshState;

// What the j-th sub-step after an exchange (j from 1; 0: a sub-step that
// exchanges, and steps the owned cells alone) updates beyond the owned
// cells: the ghosts whose reach is at least j (Mesh::reach), which the part
// then steps as their owners do (the passes before the update run over
// every ghost and face).
struct BatchReach {
    const Mesh &m;
    int j;

    // The ghosts in reach: the first ghost_count() of the list.
    const std::int64_t *ghosts() const { return m.ghosts_by_reach.data(); }
    std::int64_t ghost_count() const { return j ? m.ghosts_with_reach[static_cast<std::size_t>(j)] : 0; }
};

// Whether this part steps its ghosts in reach (several sub-steps per exchange).
bool steps_ghosts(const Grid &grid);

// In a sub-step that exchanges: the ghosts' gradients once the owned
// cells' are known, then their pulls (the ghosts whose values changed are
// appended to `changed_ghosts`), then their limiters' factors.
void exchange_ghost_gradients(MeshState &s, std::vector<std::int64_t> &changed_ghosts);
void exchange_ghost_pulls(MeshState &s, std::vector<std::int64_t> &changed_ghosts);
void exchange_ghost_limits(MeshState &s);
// The ghosts' heights (with hysteresis their moving flags, on a part that
// steps its ghosts their residuals) once the owned cells changed.
void exchange_ghost_heights(Grid &grid, MeshState &s, const std::vector<std::int64_t> *computed,
                            std::vector<std::int64_t> &changed_ghosts);
// In a batch: the owned cells a sub-step updated go to the batch's exchange
// (all of them with `every_cell`).
void note_batch_updates(MeshState &s, const Mesh &m, const std::vector<std::int64_t> &cells);
void note_batch_updates_everywhere(MeshState &s);
// The end of a batch: the owned cells' heights that changed since the last
// exchange go to the ranks that hold them as ghosts; ghosts that were beyond
// reach, and so differ from their owners' values, wake the cells that read them.
void end_batch(Grid &grid, const Mesh &m, MeshState &s);

// After a host's edit: every ghost's kinds, source, bed and angle from its
// owner, set as a host would set them (so that all that follows from them follows).
void take_owners_masks(Grid &grid, GhostExchange &exchange);
// Every ghost's height (moving flag, residual) from its owner; the ghosts
// that changed wake the cells that read them.
void take_owners_heights(Grid &grid, GhostExchange &exchange);
// The kinds and levels of the domain edge's faces of the ghosts stepped
// here, from their owners: each cell's edge faces in the order its sums take
// them (by midpoint), alike on both ranks when the ghost's faces are all
// here; `most_edge_faces`, the most any cell has over all ranks.
void take_owners_edges(Grid &grid, GhostExchange &exchange, int most_edge_faces);

}  // namespace dpsm
