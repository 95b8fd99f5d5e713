// The MPI component's distributed meshes (include/dpsm/dpsm_mpi.h): a mesh as
// one rank's part, the cells it owns and the ghost cells around them that
// other ranks own. The mesh engine runs the part as it runs any mesh, over
// its owned cells and the faces that touch them (mesh/mesh_engine.cpp); this
// file is its Distribution (model/distribution.hpp) and its GhostExchange
// (mesh/ghost_exchange.hpp), which moves whatever the engine asks for
// (mesh/mesh_parts.hpp):
//
//  - construction: every rank builds its part (model/mesh_part.cpp), then the ranks
//    check together that the owners agree (each global id owned once, every
//    ghost held by the rank that claims to own it, faces seen alike from both
//    sides), learn each ghost's neighbours and face count from its owner, and
//    agree on what a serial mesh decides over all cells (the sub-step's
//    scale, the smallest face distance). Each cell's faces and gradient neighbours are summed in the
//    order of their global ids, so an owned cell is computed from the same
//    values by the same arithmetic as in the serial mesh: bit for bit;
//  - sub-steps: exchanges with the ranks that own this part's ghosts or
//    hold its cells as ghosts (mesh/mesh_parts.hpp says which values).
//    Only values that changed since they were last sent travel, one
//    synchronous message per neighbour that has any, and a non-blocking
//    barrier tells every rank that all messages arrived; a part at rest
//    near its neighbours sends nothing and, with the active set, computes
//    nothing (mesh/mesh_engine.cpp);
//  - agreement: one MAX all-reduce before a step (parameters, flags, and
//    whether a host changed heights or masks anywhere, which then go to the
//    ghosts whole, by neighbourhood all-to-alls over a distributed-graph
//    communicator), one after each sub-step, and gathers for sums.
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "api/guarded.hpp"
#include "api/handle.hpp"
#include "dpsm/dpsm.h"
#include "dpsm/dpsm_mpi.h"
#include "mesh/ghost_exchange.hpp"
#include "mesh/mesh_parts.hpp"
#include "model/engine.hpp"
#include "model/error.hpp"
#include "model/grid.hpp"
#include "model/mesh_part.hpp"
#include "model/switches.hpp"
#include "mpi/collective.hpp"
#include "mpi/distributed_mesh.hpp"

namespace dpsm {
namespace {

// Cells this rank sends to (or receives from) each neighbouring rank, as
// library indices, each rank's in ascending global id: the order both sides
// of an exchange agree on without telling each other.
struct CellLists {
    std::vector<int> ranks;  // ascending
    std::vector<int> counts, offsets;
    std::vector<std::int64_t> cells;

    void add(int rank, std::vector<std::int64_t> list) {
        ranks.push_back(rank);
        offsets.push_back(static_cast<int>(cells.size()));
        counts.push_back(static_cast<int>(list.size()));
        cells.insert(cells.end(), list.begin(), list.end());
    }
};

// Sends each rank r the values `to[r]` and returns what every rank sent this
// one, by rank (an all-to-all of counts, then of the values).
std::vector<std::vector<std::int64_t>> all_to_all(MPI_Comm comm, const std::vector<std::vector<std::int64_t>> &to) {
    const int size = static_cast<int>(to.size());
    std::vector<int> send_counts(static_cast<std::size_t>(size)), receive_counts(static_cast<std::size_t>(size));
    std::vector<int> send_offsets(static_cast<std::size_t>(size)), receive_offsets(static_cast<std::size_t>(size));
    std::vector<std::int64_t> out;
    for (int r = 0; r < size; ++r) {
        send_offsets[static_cast<std::size_t>(r)] = static_cast<int>(out.size());
        send_counts[static_cast<std::size_t>(r)] = static_cast<int>(to[static_cast<std::size_t>(r)].size());
        out.insert(out.end(), to[static_cast<std::size_t>(r)].begin(), to[static_cast<std::size_t>(r)].end());
    }
    check_mpi(MPI_Alltoall(send_counts.data(), 1, MPI_INT, receive_counts.data(), 1, MPI_INT, comm),
              "MPI_Alltoall of counts");
    int total = 0;
    for (int r = 0; r < size; ++r) {
        receive_offsets[static_cast<std::size_t>(r)] = total;
        total += receive_counts[static_cast<std::size_t>(r)];
    }
    std::vector<std::int64_t> in(static_cast<std::size_t>(total));
    check_mpi(MPI_Alltoallv(out.data(), send_counts.data(), send_offsets.data(), MPI_INT64_T, in.data(),
                            receive_counts.data(), receive_offsets.data(), MPI_INT64_T, comm),
              "MPI_Alltoallv");
    std::vector<std::vector<std::int64_t>> from(static_cast<std::size_t>(size));
    for (int r = 0; r < size; ++r) {
        const auto begin = in.begin() + receive_offsets[static_cast<std::size_t>(r)];
        from[static_cast<std::size_t>(r)].assign(begin, begin + receive_counts[static_cast<std::size_t>(r)]);
    }
    return from;
}

// A cell for messages: the host's number on this rank and its global id.
std::string name_cell(const Mesh &m, std::int64_t c) {
    const int base = m.input.start_index;
    return "cell " + std::to_string(m.host_cell[static_cast<std::size_t>(c)] + base) + " (global id " +
           std::to_string(m.global_id[static_cast<std::size_t>(c)] + base) + ")";
}

// Per owned cell, where it stands in the lists sent to the neighbours: the
// neighbour's index and the place in that neighbour's list.
struct SendSlots {
    std::int64_t owned = 0;
    std::vector<std::int32_t> start, neighbour, position;

    SendSlots(const CellLists &send, std::int64_t owned_cells) : owned(owned_cells) {
        start.assign(static_cast<std::size_t>(owned) + 1, 0);
        for (const std::int64_t c : send.cells) ++start[static_cast<std::size_t>(c) + 1];
        for (std::size_t c = 0; c < static_cast<std::size_t>(owned); ++c) start[c + 1] += start[c];
        neighbour.resize(send.cells.size());
        position.resize(send.cells.size());
        std::vector<std::int32_t> next(start.begin(), start.end() - 1);
        for (std::size_t r = 0; r < send.ranks.size(); ++r)
            for (int k = 0; k < send.counts[r]; ++k) {
                const std::int64_t c = send.cells[static_cast<std::size_t>(send.offsets[r] + k)];
                const std::int32_t at = next[static_cast<std::size_t>(c)]++;
                neighbour[static_cast<std::size_t>(at)] = static_cast<std::int32_t>(r);
                position[static_cast<std::size_t>(at)] = k;
            }
    }
};

// What the ranks learn about a part when they make it, beyond the part itself.
struct PartLinks {
    CellLists send_heights, receive_heights;      // every ghost
    CellLists send_gradients, receive_gradients;  // the ghosts across a face from an owned cell
    std::int64_t global_cells = 0;
    int edge_faces = 0;  // the most faces on the domain edge of any cell, over all ranks
};

// Checks the owners and the ghosts of all ranks' parts together, learns each
// ghost's neighbours and faces from its owner, and finishes the part as the
// serial mesh of all cells would be. Collective; throws on every rank alike.
PartLinks link_parts(MPI_Comm comm, Mesh &m, const std::vector<int> &owner_of_cell, const char *fn) {
    int rank = 0, size = 1;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    const std::size_t ranks = static_cast<std::size_t>(size);
    PartLinks links;
    std::int64_t n_global = m.owned;
    check_mpi(MPI_Allreduce(MPI_IN_PLACE, &n_global, 1, MPI_INT64_T, MPI_SUM, comm), "MPI_Allreduce of the cell counts");
    links.global_cells = n_global;

    // Each global id in [0, n_global), owned once, its ghosts held by their owner:
    // checked at a home rank for every id (id % size).
    on_every_rank(Communicator(comm), fn, [&] {
        for (std::int64_t c = 0; c < m.cells; ++c)
            if (m.global_id[c] >= n_global)
                fail(DPSM_ERR_INVALID_VALUE, fn, name_cell(m, c), ": its global id is beyond ",
                     n_global - 1 + m.input.start_index, "; the ", n_global, " cells the ranks own are numbered from ",
                     m.input.start_index, " without gaps");
    });
    const int base = m.input.start_index;
    std::vector<std::vector<std::int64_t>> claims(ranks);
    for (std::int64_t c = 0; c < m.cells; ++c) {
        auto &to = claims[static_cast<std::size_t>(m.global_id[c] % size)];
        to.push_back(m.global_id[c]);
        to.push_back(owner_of_cell[static_cast<std::size_t>(c)]);
    }
    const std::vector<std::vector<std::int64_t>> at_home = all_to_all(comm, claims);
    on_every_rank(Communicator(comm), fn, [&] {
        std::unordered_map<std::int64_t, int> owner;
        for (int r = 0; r < size; ++r) {
            const std::vector<std::int64_t> &v = at_home[static_cast<std::size_t>(r)];
            for (std::size_t k = 0; k < v.size(); k += 2) {
                if (v[k + 1] != r) continue;
                const auto placed = owner.emplace(v[k], r);
                if (!placed.second)
                    fail(DPSM_ERR_INVALID_VALUE, fn, "the cell of global id ", v[k] + base, " is owned by rank ",
                         placed.first->second, " and by rank ", r, "; every cell has one owner");
            }
        }
        for (int r = 0; r < size; ++r) {
            const std::vector<std::int64_t> &v = at_home[static_cast<std::size_t>(r)];
            for (std::size_t k = 0; k < v.size(); k += 2) {
                if (v[k + 1] == r) continue;
                const auto found = owner.find(v[k]);
                if (found == owner.end())
                    fail(DPSM_ERR_INVALID_VALUE, fn, "rank ", r, " holds the cell of global id ", v[k] + base,
                         " as a ghost of rank ", v[k + 1], ", which does not own it; no rank does");
                if (found->second != v[k + 1])
                    fail(DPSM_ERR_INVALID_VALUE, fn, "rank ", r, " holds the cell of global id ", v[k] + base,
                         " as a ghost of rank ", v[k + 1], ", but rank ", found->second, " owns it");
            }
        }
    });

    // Which ghosts lie across a face from an owned cell (the first layer).
    std::vector<std::uint8_t> first_layer(static_cast<std::size_t>(m.cells), 0);
    for (std::int64_t f = 0; f < m.live_faces; ++f)
        if (m.face_b[f] >= m.owned) first_layer[static_cast<std::size_t>(m.face_b[f])] = 1;
    // Each ghost asked of its owner, in ascending global id: its faces over the
    // whole mesh and the global ids of the cells across them.
    std::vector<std::vector<std::int64_t>> asked(ranks);
    std::vector<std::vector<std::int64_t>> ghosts_of(ranks);  // library indices, the same order
    {
        std::vector<std::int64_t> ghosts;
        for (std::int64_t c = m.owned; c < m.cells; ++c) ghosts.push_back(c);
        std::sort(ghosts.begin(), ghosts.end(), [&](std::int64_t l, std::int64_t r) { return m.global_id[l] < m.global_id[r]; });
        for (const std::int64_t c : ghosts) {
            const std::size_t o = static_cast<std::size_t>(owner_of_cell[static_cast<std::size_t>(c)]);
            asked[o].push_back(m.global_id[c]);
            asked[o].push_back(first_layer[static_cast<std::size_t>(c)]);
            ghosts_of[o].push_back(c);
        }
    }
    const std::vector<std::vector<std::int64_t>> requests = all_to_all(comm, asked);
    std::unordered_map<std::int64_t, std::int64_t> local_of_id;
    local_of_id.reserve(static_cast<std::size_t>(m.cells));
    for (std::int64_t c = 0; c < m.cells; ++c) local_of_id.emplace(m.global_id[c], c);
    std::vector<std::vector<std::int64_t>> answers(ranks);
    for (int r = 0; r < size; ++r) {
        const std::vector<std::int64_t> &v = requests[static_cast<std::size_t>(r)];
        std::vector<std::int64_t> heights, gradients;
        std::vector<std::int64_t> &out = answers[static_cast<std::size_t>(r)];
        for (std::size_t k = 0; k < v.size(); k += 2) {
            const std::int64_t c = local_of_id.at(v[k]);  // owned here: checked at home above
            heights.push_back(c);
            if (v[k + 1]) gradients.push_back(c);
            const std::int64_t k0 = m.cell_face_start[c], k1 = m.cell_face_start[c + 1];
            out.push_back(k1 - k0);
            std::int64_t across = 0;
            for (std::int64_t j = k0; j < k1; ++j) across += m.other[j] >= 0;
            out.push_back(across);
            for (std::int64_t j = k0; j < k1; ++j)
                if (m.other[j] >= 0) out.push_back(m.global_id[m.other[j]]);
        }
        if (!heights.empty()) links.send_heights.add(r, heights);
        if (!heights.empty()) links.send_gradients.add(r, gradients);
    }
    const std::vector<std::vector<std::int64_t>> told = all_to_all(comm, answers);

    // The ghosts' neighbours as library indices (-1: not on this rank); faces
    // seen alike from both sides; the second ring complete where it is used.
    const std::size_t nghosts = static_cast<std::size_t>(m.cells - m.owned);
    std::vector<std::int64_t> ghost_start(nghosts + 1, 0), ghost_neighbours;
    std::vector<double> ghost_faces(nghosts, 0.0);
    std::vector<std::vector<std::int64_t>> neighbours_of(nghosts);
    on_every_rank(Communicator(comm), fn, [&] {
        for (int r = 0; r < size; ++r) {
            const std::vector<std::int64_t> &v = told[static_cast<std::size_t>(r)];
            std::size_t k = 0;
            for (const std::int64_t c : ghosts_of[static_cast<std::size_t>(r)]) {
                const std::size_t g = static_cast<std::size_t>(c - m.owned);
                ghost_faces[g] = static_cast<double>(v[k]);
                const std::int64_t across = v[k + 1];
                for (std::int64_t j = 0; j < across; ++j) {
                    const auto found = local_of_id.find(v[k + 2 + static_cast<std::size_t>(j)]);
                    neighbours_of[g].push_back(found == local_of_id.end() ? -1 : found->second);
                }
                k += 2 + static_cast<std::size_t>(across);
                // The faces its owner gives this ghost with cells owned here are faces here too.
                for (const std::int64_t n : neighbours_of[g])
                    if (n >= 0 && n < m.owned) {
                        bool face = false;
                        for (std::int64_t j = m.cell_face_start[n]; j < m.cell_face_start[n + 1]; ++j)
                            face = face || m.other[j] == c;
                        if (!face)
                            fail(DPSM_ERR_INVALID_VALUE, fn, "rank ", r, ", the owner of ghost ", name_cell(m, c),
                                 ", gives it a face with owned ", name_cell(m, n), ", which this rank does not have");
                    }
            }
        }
        for (std::int64_t c = 0; c < m.owned; ++c)
            for (std::int64_t j = m.cell_face_start[c]; j < m.cell_face_start[c + 1]; ++j) {
                const std::int64_t n = m.other[j];
                if (n < m.owned) continue;
                const std::vector<std::int64_t> &of_n = neighbours_of[static_cast<std::size_t>(n - m.owned)];
                if (std::find(of_n.begin(), of_n.end(), c) == of_n.end())
                    fail(DPSM_ERR_INVALID_VALUE, fn, "owned ", name_cell(m, c), " has a face with ghost ",
                         name_cell(m, n), ", which the ghost's owner, rank ", owner_of_cell[static_cast<std::size_t>(n)],
                         ", does not have");
            }
    });
    for (std::size_t g = 0; g < nghosts; ++g) {
        ghost_neighbours.insert(ghost_neighbours.end(), neighbours_of[g].begin(), neighbours_of[g].end());
        ghost_start[g + 1] = static_cast<std::int64_t>(ghost_neighbours.size());
    }
    finish_part(m, ghost_start, ghost_neighbours, ghost_faces);
    double smallest[2] = {m.step_scale, m.min_distance};
    check_mpi(MPI_Allreduce(MPI_IN_PLACE, smallest, 2, MPI_DOUBLE, MPI_MIN, comm), "MPI_Allreduce of the scales");
    m.step_scale = smallest[0];
    m.min_distance = smallest[1];
    // Sub-steps per exchange: as many as every rank's ghost layer allows
    // (mesh.cpp, set_reach), at most DPSM_MPI_SUBSTEPS_PER_EXCHANGE (0: the
    // two exchanges in every sub-step, for comparisons).
    int most[2] = {-m.substeps_per_exchange, 0};
    for (std::int64_t c = 0; c < m.cells; ++c) {
        int edges = 0;
        for (std::int64_t k = m.cell_face_start[c]; k < m.cell_face_start[c + 1]; ++k) edges += m.other[k] < 0;
        most[1] = std::max(most[1], edges);
    }
    if (const int limit = read_switches().mpi_substeps_per_exchange; limit >= 0) most[0] = std::max(most[0], -limit);
    check_mpi(MPI_Allreduce(MPI_IN_PLACE, most, 2, MPI_INT, MPI_MAX, comm), "MPI_Allreduce of the ghost layers' reach");
    m.substeps_per_exchange = -most[0];
    links.edge_faces = most[1];

    for (int r = 0; r < size; ++r) {
        const std::vector<std::int64_t> &ghosts = ghosts_of[static_cast<std::size_t>(r)];
        if (ghosts.empty()) continue;
        std::vector<std::int64_t> across;
        for (const std::int64_t c : ghosts)
            if (first_layer[static_cast<std::size_t>(c)]) across.push_back(c);
        links.receive_heights.add(r, ghosts);
        links.receive_gradients.add(r, across);
    }
    return links;
}

class MeshPartDistribution final : public CollectiveDistribution, public GhostExchange {
public:
    // `comm` is this part's own duplicate; `neighbours` its distributed-graph
    // communicator over the ranks in `links` (both freed with it).
    MeshPartDistribution(MPI_Comm comm, MPI_Comm neighbours, PartLinks links, std::int64_t owned)
        : CollectiveDistribution(comm),
          neighbours_(neighbours),
          links_(std::move(links)),
          slots_{SendSlots(links_.send_heights, owned), SendSlots(links_.send_gradients, owned)} {}

    ~MeshPartDistribution() override {
        int finalized = 0;
        MPI_Finalized(&finalized);
        if (!finalized) MPI_Comm_free(&neighbours_);
    }

    StepAgreement agree_before_step(Grid &grid, const Engine &engine, double dt, bool refused) override {
        std::vector<double> flags = {masks_changed_ ? 1.0 : 0.0, heights_changed_ ? 1.0 : 0.0,
                                     static_cast<double>(grid.relaxation())};
        const std::vector<double> state = local_state(grid, engine);
        flags.insert(flags.end(), state.begin(), state.end());
        // Whether a host changed edge kinds or levels (read on the ghosts' edge faces when they are stepped here).
        flags.push_back(steps_ghosts(grid) && sides_changed_ ? 1.0 : 0.0);
        // The relaxation mode: every rank steps in time or every rank relaxes.
        flags.push_back(-static_cast<double>(grid.relaxation()));
        std::vector<double> v = agree_on_step(grid, dt, refused, flags);
        if (v[2] != -v.back())
            throw Error(DPSM_ERR_INVALID_VALUE, "dpsm_step: the ranks of the distributed mesh differ in the relaxation "
                                                "(dpsm_set_relaxation); every rank must step the same way");
        const bool edges_changed = v[v.size() - 2] != 0.0;
        std::vector<double> agreed(v.begin() + 3, v.end() - 2);
        if (edges_changed) take_owners_edges(grid, *this, links_.edge_faces);
        if (v[0] != 0.0 || v[1] != 0.0) {
            // A host changed something on some rank: the ghosts take their owners' values, then the flags again.
            if (v[0] != 0.0) take_owners_masks(grid, *this);
            take_owners_heights(grid, *this);
            agreed = local_state(grid, engine);
            check_mpi(MPI_Allreduce(MPI_IN_PLACE, agreed.data(), static_cast<int>(agreed.size()), MPI_DOUBLE, MPI_MAX,
                                    comm_),
                      "MPI_Allreduce before dpsm_step");
        }
        // What the ghosts took from their owners is no edit of this rank's host.
        masks_changed_ = heights_changed_ = sides_changed_ = false;
        grid.set_distributed_min_repose_angle(-agreed[5]);
        StepAgreement out;
        out.source_active = agreed[0] != 0.0;
        out.has_open_cells = agreed[1] != 0.0;
        out.may_move = agreed[2] != 0.0;
        out.open_level_min = out.has_open_cells ? -agreed[3] : 0.0;
        out.open_level_max = out.has_open_cells ? agreed[4] : 0.0;
        const bool edge_levels = agreed[6] != 0.0;
        out.side_level_min = edge_levels ? -agreed[7] : 0.0;
        out.side_level_max = edge_levels ? agreed[8] : 0.0;
        out.any_side_open = agreed[9] != 0.0;
        return out;
    }

    DistributedPlace place() const override { return {links_.global_cells, 1, 0, 0}; }

    // K sub-steps per exchange where the ghost layer allows K >= 1, else
    // exchanges in every sub-step (0.5); local time steps exchange in every tick.
    double substeps_per_exchange(const Grid &grid) const override {
        const int k = grid.geometry().mesh->substeps_per_exchange;
        return k > 0 && grid.relaxation() != kLocalSteps ? static_cast<double>(k) : 0.5;
    }

    void changed(const Grid &, unsigned what, const ChangedCells *) override {
        if (what & (kMasksChanged | kSourcesChanged)) masks_changed_ = true;
        if (what & kCellsChanged) heights_changed_ = true;
        if (what & kSidesChanged) sides_changed_ = true;
        if (what & (kCellsChanged | kMasksChanged | kSidesChanged)) held_.known = false;
    }

    // Point-to-point, each value only when it changed since it was last sent
    // (the ghost's copy on the other rank is then that value): a part whose
    // cells near its neighbours are at rest sends nothing.
    void send_changed(Ghosts ghosts, const std::vector<GhostField> &fields, const std::vector<std::int64_t> *computed,
                      std::vector<std::int64_t> &changed_ghosts) override {
        const CellLists &send = ghosts == kEveryGhost ? links_.send_heights : links_.send_gradients;
        const CellLists &receive = ghosts == kEveryGhost ? links_.receive_heights : links_.receive_gradients;
        std::vector<std::vector<double>> &sent = sent_[ghosts];
        std::vector<std::size_t> &present = present_;
        present.clear();
        for (std::size_t k = 0; k < fields.size(); ++k)
            if (fields[k].present()) present.push_back(k);
        if (sent.size() < fields.size()) sent.resize(fields.size());
        for (const std::size_t k : present) sent[k].resize(send.cells.size(), 0.0);
        const int width = static_cast<int>(present.size());
        // A tag of the set and the first field sent: a rank that has left
        // one call's barrier may send the next call's values while another
        // still takes this call's.
        const int tag = kTags[ghosts] + 2 * static_cast<int>(present.empty() ? 0 : present[0]);
        send_changes(send, slots_[ghosts], computed, width, tag,
                     [&](std::size_t slot, std::int64_t c, double *out) {
                         bool differs = false;
                         for (const std::size_t k : present) differs = differs || fields[k].get(c) != sent[k][slot];
                         if (!differs) return false;
                         for (std::size_t j = 0; j < present.size(); ++j)
                             out[j] = sent[present[j]][slot] = fields[present[j]].get(c);
                         return true;
                     });
        receive_changes(receive, width, tag, [&](std::int64_t c, const double *in) {
            // A ghost stepped here already holds its owner's values: it changed only beyond reach.
            bool differs = false;
            for (std::size_t j = 0; j < present.size(); ++j) {
                const GhostField &field = fields[present[j]];
                differs = differs || field.get(c) != unpacked(field, in[j]);
                field.set(c, in[j]);
            }
            if (differs) changed_ghosts.push_back(c);
        });
    }

    // One neighbourhood all-to-all of the fields' values of every listed cell.
    void send_all(Ghosts ghosts, const std::vector<GhostField> &fields, bool remember) override {
        const CellLists &send = ghosts == kEveryGhost ? links_.send_heights : links_.send_gradients;
        const CellLists &receive = ghosts == kEveryGhost ? links_.receive_heights : links_.receive_gradients;
        std::vector<std::size_t> &present = present_;
        present.clear();
        for (std::size_t k = 0; k < fields.size(); ++k)
            if (fields[k].present()) present.push_back(k);
        exchange(send, receive, static_cast<int>(present.size()),
                 [&](std::int64_t c, double *out) {
                     for (std::size_t j = 0; j < present.size(); ++j) out[j] = fields[present[j]].get(c);
                 },
                 [&](std::int64_t c, const double *in) {
                     for (std::size_t j = 0; j < present.size(); ++j) fields[present[j]].set(c, in[j]);
                 });
        if (!remember) return;
        std::vector<std::vector<double>> &sent = sent_[ghosts];
        if (sent.size() < fields.size()) sent.resize(fields.size());
        for (const std::size_t k : present) {
            sent[k].resize(send.cells.size());
            for (std::size_t slot = 0; slot < send.cells.size(); ++slot) sent[k][slot] = fields[k].get(send.cells[slot]);
        }
    }

private:
    // A value as a field holds it once received (a float or a byte rounds).
    static double unpacked(const GhostField &field, double value) {
        if (field.f64) return value;
        if (field.f32) return static_cast<double>(static_cast<float>(value));
        return static_cast<double>(static_cast<std::uint8_t>(value));
    }

    // This rank's figures for the step's agreement, each as a maximum (minima
    // negated): a source, open cells, something that may move, the lowest and
    // highest open cell, the smallest angle, the open edge faces' levels, an
    // open edge. Over its owned cells and the faces that touch them.
    std::vector<double> local_state(const Grid &grid, const Engine &engine) {
        const HeldLevels &held = held_levels(grid);
        const double none = -std::numeric_limits<double>::infinity();
        return {grid.source_active() ? 1.0 : 0.0,
                held.open ? 1.0 : 0.0,
                engine.may_move(grid) ? 1.0 : 0.0,
                held.open ? -held.open_lo : none,
                held.open ? held.open_hi : none,
                -grid.own_min_repose_angle(),
                held.edge ? 1.0 : 0.0,
                held.edge ? -held.edge_lo : none,
                held.edge ? held.edge_hi : none,
                held.edge || grid.side_open(0) ? 1.0 : 0.0};
    }

    // The levels held by the owned open cells and the open edge faces. Steps
    // change neither (open cells are not stepped): they are found again only
    // when a host set heights, masks, edges or levels, not at every step.
    struct HeldLevels {
        bool known = false, open = false, edge = false;
        double open_lo = 0.0, open_hi = 0.0, edge_lo = 0.0, edge_hi = 0.0;
    };
    const HeldLevels &held_levels(const Grid &grid) {
        HeldLevels &h = held_;
        if (h.known) return h;
        h = HeldLevels{};
        h.known = true;
        const Mesh &m = *grid.geometry().mesh;
        if (grid.has_open_cells()) {
            const std::vector<std::uint8_t> &kind = grid.kinds();
            const std::vector<double> &height = grid.heights();
            for (std::int64_t c = 0; c < m.owned; ++c) {
                if (kind[c] != kOpen) continue;
                h.open_lo = h.open ? std::min(h.open_lo, height[c]) : height[c];
                h.open_hi = h.open ? std::max(h.open_hi, height[c]) : height[c];
                h.open = true;
            }
        }
        const std::vector<double> &levels = grid.side_levels(0);
        for (std::int64_t f = 0; f < m.live_faces; ++f) {
            if (m.face_b[f] >= 0 || !grid.edge_open(f)) continue;
            const double level = levels.empty() ? 0.0 : levels[f];
            h.edge_lo = h.edge ? std::min(h.edge_lo, level) : level;
            h.edge_hi = h.edge ? std::max(h.edge_hi, level) : level;
            h.edge = true;
        }
        return h;
    }

    // Packs, for each neighbour, the listed cells' values that `pack(slot, c,
    // out)` finds changed (it writes them and returns true) as (position in
    // the neighbour's list, values), or the values alone when every listed
    // cell changed, and sends each neighbour that has any one synchronous
    // message. `computed` (null: every listed cell) names the owned cells to
    // look at.
    template <class Pack>
    void send_changes(const CellLists &send, const SendSlots &slots, const std::vector<std::int64_t> *computed,
                      int width, int tag, Pack &&pack) {
        const std::size_t record = 1 + static_cast<std::size_t>(width);
        outgoing_.resize(send.ranks.size());
        for (std::vector<double> &to : outgoing_) to.assign(1, kChangedCells);
        const auto look_at = [&](std::size_t neighbour, std::size_t position) {
            std::vector<double> &to = outgoing_[neighbour];
            const std::size_t slot = static_cast<std::size_t>(send.offsets[neighbour]) + position;
            to.resize(to.size() + record);
            double *out = &to[to.size() - record];
            out[0] = static_cast<double>(position);
            if (!pack(slot, send.cells[slot], out + 1)) to.resize(to.size() - record);
        };
        if (!computed) {
            for (std::size_t r = 0; r < send.ranks.size(); ++r)
                for (int k = 0; k < send.counts[r]; ++k) look_at(r, static_cast<std::size_t>(k));
        } else {
            for (const std::int64_t c : *computed) {
                if (c >= slots.owned) continue;
                for (std::int32_t k = slots.start[c]; k < slots.start[c + 1]; ++k)
                    look_at(static_cast<std::size_t>(slots.neighbour[k]), static_cast<std::size_t>(slots.position[k]));
            }
        }
        sends_.clear();
        for (std::size_t r = 0; r < outgoing_.size(); ++r) {
            std::vector<double> &to = outgoing_[r];
            const std::size_t changed = (to.size() - 1) / record, listed = static_cast<std::size_t>(send.counts[r]);
            if (changed == 0) continue;
            if (changed == listed) {
                // Every listed cell changed (a fully active border): the values alone, in the list's order.
                whole_.assign(1 + listed * static_cast<std::size_t>(width), kEveryCell);
                for (std::size_t k = 1; k < to.size(); k += record) {
                    const std::size_t position = static_cast<std::size_t>(to[k]);
                    std::copy(&to[k + 1], &to[k + record], &whole_[1 + position * static_cast<std::size_t>(width)]);
                }
                to.swap(whole_);
            }
            sends_.emplace_back();
            check_mpi(MPI_Issend(outgoing_[r].data(), static_cast<int>(outgoing_[r].size()), MPI_DOUBLE, send.ranks[r],
                                 tag, neighbours_, &sends_.back()),
                      "MPI_Issend of changed ghost values");
            count_message(static_cast<double>(outgoing_[r].size() * sizeof(double)));
        }
    }

    // Receives what the neighbours sent by send_changes, unpacking each value
    // into its ghost, until every rank's messages have arrived: a rank
    // enters a non-blocking barrier once its own synchronous sends have been
    // received, so the barrier completes only when no message is still on
    // its way (the NBX exchange of Hoefler, Siebert and Lumsdaine, 2010: no
    // rank needs to know beforehand who sends to it).
    template <class Unpack>
    void receive_changes(const CellLists &receive, int width, int tag, Unpack &&unpack) {
        const std::size_t record = 1 + static_cast<std::size_t>(width);
        MPI_Request barrier = MPI_REQUEST_NULL;
        bool in_barrier = false;
        for (;;) {
            int arrived = 0;
            MPI_Status status;
            check_mpi(MPI_Iprobe(MPI_ANY_SOURCE, tag, neighbours_, &arrived, &status), "MPI_Iprobe of ghost values");
            if (arrived) {
                int count = 0;
                check_mpi(MPI_Get_count(&status, MPI_DOUBLE, &count), "MPI_Get_count of ghost values");
                incoming_.resize(static_cast<std::size_t>(count));
                check_mpi(MPI_Recv(incoming_.data(), count, MPI_DOUBLE, status.MPI_SOURCE, tag, neighbours_,
                                   MPI_STATUS_IGNORE),
                          "MPI_Recv of ghost values");
                const auto from = std::lower_bound(receive.ranks.begin(), receive.ranks.end(), status.MPI_SOURCE);
                if (from == receive.ranks.end() || *from != status.MPI_SOURCE)
                    throw Error(DPSM_ERR_INTERNAL, "dpsm_step: ghost values from rank " +
                                                       std::to_string(status.MPI_SOURCE) + ", which owns no ghost here");
                const std::size_t r = static_cast<std::size_t>(from - receive.ranks.begin());
                const std::int64_t *cells = &receive.cells[static_cast<std::size_t>(receive.offsets[r])];
                if (!incoming_.empty() && incoming_[0] == kEveryCell) {
                    const std::size_t n = std::min(static_cast<std::size_t>(receive.counts[r]),
                                                   (incoming_.size() - 1) / static_cast<std::size_t>(width));
                    for (std::size_t k = 0; k < n; ++k) unpack(cells[k], &incoming_[1 + k * static_cast<std::size_t>(width)]);
                } else {
                    for (std::size_t k = 1; k + record <= incoming_.size(); k += record)
                        unpack(cells[static_cast<std::size_t>(incoming_[k])], &incoming_[k + 1]);
                }
                continue;
            }
            int done = 0;
            if (!in_barrier) {
                check_mpi(MPI_Testall(static_cast<int>(sends_.size()), sends_.data(), &done, MPI_STATUSES_IGNORE),
                          "MPI_Testall of ghost values");
                if (done) {
                    check_mpi(MPI_Ibarrier(neighbours_, &barrier), "MPI_Ibarrier after ghost values");
                    in_barrier = true;
                }
            } else {
                check_mpi(MPI_Test(&barrier, &done, MPI_STATUS_IGNORE), "MPI_Test of the barrier after ghost values");
                if (done) return;
            }
        }
    }

    // One neighbourhood all-to-all of `per_cell` values per listed cell.
    template <class Pack, class Unpack>
    void exchange(const CellLists &send, const CellLists &receive, int per_cell, Pack &&pack, Unpack &&unpack) {
        const std::size_t width = static_cast<std::size_t>(per_cell);
        send_buffer_.resize(send.cells.size() * width);
        receive_buffer_.resize(receive.cells.size() * width);
        for (std::size_t k = 0; k < send.cells.size(); ++k) pack(send.cells[k], &send_buffer_[k * width]);
        scaled(send, per_cell, send_counts_, send_offsets_);
        scaled(receive, per_cell, receive_counts_, receive_offsets_);
        for (const int count : send_counts_)
            if (count > 0) count_message(static_cast<double>(count) * sizeof(double));
        check_mpi(MPI_Neighbor_alltoallv(send_buffer_.data(), send_counts_.data(), send_offsets_.data(), MPI_DOUBLE,
                                         receive_buffer_.data(), receive_counts_.data(), receive_offsets_.data(),
                                         MPI_DOUBLE, neighbours_),
                  "MPI_Neighbor_alltoallv of the ghosts");
        for (std::size_t k = 0; k < receive.cells.size(); ++k) unpack(receive.cells[k], &receive_buffer_[k * width]);
    }

    // Counts and offsets of `lists`, times `per_cell`, one per neighbour of
    // the distributed graph (the lists of gradients name the same ranks as
    // those of heights, some with no cells).
    static void scaled(const CellLists &lists, int per_cell, std::vector<int> &counts, std::vector<int> &offsets) {
        counts.resize(lists.counts.size());
        offsets.resize(lists.offsets.size());
        for (std::size_t r = 0; r < counts.size(); ++r) {
            counts[r] = lists.counts[r] * per_cell;
            offsets[r] = lists.offsets[r] * per_cell;
        }
    }

    // Per set of ghosts (GhostExchange::Ghosts), the message tag of its values
    // (send_changed adds twice the place of the first field sent).
    static constexpr int kTags[2] = {2, 1};
    // The first value of a message: (position, values) of the cells that
    // changed, or the values of every listed cell in order.
    static constexpr double kChangedCells = 0.0, kEveryCell = 1.0;
    MPI_Comm neighbours_;
    PartLinks links_;
    // Per set of ghosts and owned cell, the places it has in the lists sent to neighbours.
    SendSlots slots_[2];
    // Per set of ghosts, field and place in those lists, the value last sent
    // (the ghost's copy; 0 before any, as the ghosts' gradients start).
    std::vector<std::vector<double>> sent_[2];
    std::vector<std::vector<double>> outgoing_;
    std::vector<double> incoming_, whole_;
    // The places of the fields a call sends (GhostField::present).
    std::vector<std::size_t> present_;
    std::vector<MPI_Request> sends_;
    std::vector<double> send_buffer_, receive_buffer_;
    std::vector<int> send_counts_, send_offsets_, receive_counts_, receive_offsets_;
    // A host changed kinds, sources, bed or angles, heights, or edges and
    // their levels on this rank since the ghosts last took them (none yet).
    bool masks_changed_ = true, heights_changed_ = true, sides_changed_ = true;
    HeldLevels held_;
};

}  // namespace

// The part's grid, tied to a duplicate of `comm` and a distributed graph over
// its neighbours; with `state`, as a restart file saved it. Collective.
dpsm_grid *part_grid(MPI_Comm comm, std::shared_ptr<Mesh> mesh, const char *fn, GridState *state) {
    std::vector<int> owner_of_cell(static_cast<std::size_t>(mesh->cells));
    for (std::int64_t c = 0; c < mesh->cells; ++c) owner_of_cell[c] = mesh->input.owner[mesh->host_cell[c]];
    PartLinks links = link_parts(comm, *mesh, owner_of_cell, fn);
    std::unique_ptr<dpsm_grid> made;
    on_every_rank(Communicator(comm), fn, [&] {
        std::shared_ptr<const Mesh> done = mesh;
        made = std::make_unique<dpsm_grid>(Geometry{2, false, done->cells, 1, done->min_distance, done->min_distance, done});
        if (state) made->core.restore(std::move(*state));
    });
    MPI_Comm own = MPI_COMM_NULL, neighbours = MPI_COMM_NULL;
    check_mpi(MPI_Comm_dup(comm, &own), "MPI_Comm_dup");
    MPI_Comm_set_errhandler(own, MPI_ERRORS_RETURN);
    const std::vector<int> &sources = links.receive_heights.ranks, &destinations = links.send_heights.ranks;
    const int status = MPI_Dist_graph_create_adjacent(
        own, static_cast<int>(sources.size()), sources.empty() ? MPI_WEIGHTS_EMPTY : sources.data(), MPI_UNWEIGHTED,
        static_cast<int>(destinations.size()), destinations.empty() ? MPI_WEIGHTS_EMPTY : destinations.data(),
        MPI_UNWEIGHTED, MPI_INFO_NULL, 0, &neighbours);
    if (status != MPI_SUCCESS) {
        MPI_Comm_free(&own);
        check_mpi(status, "MPI_Dist_graph_create_adjacent");
    }
    made->core.set_distribution(std::make_unique<MeshPartDistribution>(own, neighbours, std::move(links), mesh->owned));
    return made.release();
}

// The arguments every constructor checks on its own rank: the communicator,
// out, and per cell a global id and an owner; which cells are ghosts.
std::vector<std::uint8_t> ghosts_of_rank(MPI_Comm comm, std::int64_t ncells, const std::int64_t *global_id,
                                         const int *owner, dpsm_grid **out, int base, const char *fn) {
    int rank = 0, size = 1;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    if (!out) fail(DPSM_ERR_NULL_POINTER, fn, "out is NULL");
    if (ncells < 1) fail(DPSM_ERR_INVALID_SIZE, fn, "ncells = ", ncells, " must be at least 1");
    if (!global_id) fail(DPSM_ERR_NULL_POINTER, fn, "global_id is NULL");
    if (!owner) fail(DPSM_ERR_NULL_POINTER, fn, "owner is NULL");
    std::vector<std::uint8_t> ghost(static_cast<std::size_t>(ncells));
    std::int64_t owned = 0;
    for (std::int64_t c = 0; c < ncells; ++c) {
        if (global_id[c] < base)
            fail(DPSM_ERR_INVALID_VALUE, fn, host_position("global_id", c, base), " (cell ", c + base, ") = ",
                 global_id[c], " is below ", base, "; global ids number the cells from ", base);
        if (owner[c] < 0 || owner[c] >= size)
            fail(DPSM_ERR_INVALID_VALUE, fn, host_position("owner", c, base), " (cell ", c + base, ") = ", owner[c],
                 " is not a rank of the communicator, [0, ", size - 1, "]");
        ghost[static_cast<std::size_t>(c)] = owner[c] != rank;
        owned += owner[c] == rank;
    }
    if (owned == 0) fail(DPSM_ERR_INVALID_SIZE, fn, "rank ", rank, " owns none of its ", ncells, " cells (owner[k] == ", rank, " for none)");
    std::vector<std::int64_t> ids(global_id, global_id + ncells);
    std::sort(ids.begin(), ids.end());
    const auto twice = std::adjacent_find(ids.begin(), ids.end());
    if (twice != ids.end()) {
        std::int64_t first = -1, second = -1;
        for (std::int64_t c = 0; c < ncells; ++c)
            if (global_id[c] == *twice) (first < 0 ? first : second) = c;
        fail(DPSM_ERR_INVALID_VALUE, fn, "cells ", first + base, " and ", second + base, " have the same global id, ",
             *twice);
    }
    return ghost;
}

namespace {

template <class Build>
int create_part(MPI_Comm comm, int start_index, std::int64_t ncells, const std::int64_t *global_id, const int *owner,
                dpsm_grid **out, const char *fn, Build &&build) noexcept {
    if (out) *out = nullptr;
    return guarded(nullptr, fn, [&] {
        int rank = 0, size = 0;
        check_communicator(comm, fn, rank, size);
        std::shared_ptr<Mesh> mesh;
        on_every_rank(Communicator(comm), fn, [&] {
            const std::vector<std::uint8_t> ghost = ghosts_of_rank(comm, ncells, global_id, owner, out, start_index, fn);
            // From here on global ids count from 0 (the messages add start_index again).
            std::vector<std::int64_t> ids(global_id, global_id + ncells);
            for (std::int64_t &id : ids) id -= start_index;
            mesh = build(PartOfMesh{ids.data(), ghost.data()});
            mesh->input.global_id = std::move(ids);
            mesh->input.owner.assign(owner, owner + ncells);
        });
        *out = part_grid(comm, std::move(mesh), fn, nullptr);
    });
}

}  // namespace
}  // namespace dpsm

extern "C" {

int dpsm_create_graph_mpi(MPI_Comm comm, int64_t ncells, const int64_t *global_id, const int *owner,
                          const double *cell_xy, const double *cell_area, int64_t nfaces, const int64_t *face_cells,
                          const double *face_xy, const double *face_length, dpsm_grid **out) {
    const char *fn = "dpsm_create_graph_mpi";
    return dpsm::create_part(comm, 0, ncells, global_id, owner, out, fn, [&](const dpsm::PartOfMesh &part) {
        return dpsm::part_from_graph(ncells, cell_xy, cell_area, nfaces, face_cells, face_xy, face_length, part, fn, 0);
    });
}

int dpsm_create_graph_mpi_f(MPI_Fint comm, int64_t ncells, const int64_t *global_id, const int *owner,
                            const double *cell_xy, const double *cell_area, int64_t nfaces, const int64_t *face_cells,
                            const double *face_xy, const double *face_length, dpsm_grid **out) {
    const char *fn = "dpsm_create_graph_mpi_f";
    return dpsm::create_part(MPI_Comm_f2c(comm), 1, ncells, global_id, owner, out, fn, [&](const dpsm::PartOfMesh &part) {
        return dpsm::part_from_graph(ncells, cell_xy, cell_area, nfaces, face_cells, face_xy, face_length, part, fn, 1);
    });
}

int dpsm_create_mesh_mpi(MPI_Comm comm, int64_t nnodes, const double *node_xy, int64_t ncells,
                         const int64_t *cell_start, const int64_t *cell_nodes, const int64_t *global_id,
                         const int *owner, dpsm_grid **out) {
    const char *fn = "dpsm_create_mesh_mpi";
    return dpsm::create_part(comm, 0, ncells, global_id, owner, out, fn, [&](const dpsm::PartOfMesh &part) {
        return dpsm::part_from_polygons(nnodes, node_xy, ncells, cell_start, cell_nodes, part, fn, 0);
    });
}

int dpsm_create_mesh_mpi_f(MPI_Fint comm, int64_t nnodes, const double *node_xy, int64_t ncells,
                           const int64_t *cell_start, const int64_t *cell_nodes, const int64_t *global_id,
                           const int *owner, dpsm_grid **out) {
    const char *fn = "dpsm_create_mesh_mpi_f";
    return dpsm::create_part(MPI_Comm_f2c(comm), 1, ncells, global_id, owner, out, fn,
                             [&](const dpsm::PartOfMesh &part) {
                                 return dpsm::part_from_polygons(nnodes, node_xy, ncells, cell_start, cell_nodes, part,
                                                                 fn, 1);
                             });
}

}  // extern "C"
