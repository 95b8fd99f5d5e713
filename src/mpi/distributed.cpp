// The MPI component: a 2D grid as one rank's block of a grid distributed over
// a communicator (include/dpsm/dpsm_mpi.h). The core runs the block as it runs
// any grid; this file is its Distribution (model/distribution.hpp) and its
// Halo (structured/halo.hpp):
//
//  - the halo: every cell within kHaloDepth (the most a sweep reads beyond a
//    tile) of the block that another rank owns. Whoever owns it sends it: one
//    message per neighbouring rank per sweep, holding the cells' heights and
//    residuals and the sender's hot boxes that can reach the receiver. Kinds
//    and sources go the same way, but only when the host changed them on some
//    rank. Neighbours are found from the rectangles alone, so blocks narrower
//    than the halo simply have more of them;
//  - restart files: each rank saves its block to its own file, which records
//    the block's place and a mark shared by all files of that save; a load
//    reads them back on as many ranks, checks that they are the blocks of one
//    save, and builds the grid as dpsm_create_2d_mpi does;
//  - agreement: one MAX all-reduce before a step (flags, and the parameters,
//    so that ranks that disagree fail alike; one more for the levels along the
//    global domain's sides when a host changed them), one after each sweep (each
//    level's "moved" and largest excess slope), and gathers for sums, which
//    are added in rank order so every rank gets the same figure.
//
// With the halo filled and the same sub-steps on every rank, each cell is
// computed from the same values by the same arithmetic as in a serial run:
// heights are bit for bit those of the serial grid; only sums over cells (the
// ledger) are added in a different order.
#include <mpi.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "api/guarded.hpp"
#include "api/handle.hpp"
#include "dpsm/dpsm.h"
#include "dpsm/dpsm_mpi.h"
#include "io/restart.hpp"
#include "model/engine.hpp"
#include "model/error.hpp"
#include "model/grid.hpp"
#include "model/ledger.hpp"
#include "model/limits.hpp"
#include "mpi/collective.hpp"
#include "mpi/distributed_mesh.hpp"
#include "structured/active_set.hpp"
#include "structured/halo.hpp"
#include "structured/structured_state.hpp"

namespace dpsm {
namespace {

// A sweep reads ActiveSet::kMaxLevels cells beyond a tile plus one ring of ghosts.
constexpr int kHaloDepth = ActiveSet::kMaxLevels + 1;
constexpr int kTagHeights = 1;
constexpr int kTagMasks = 2;

struct Rect {
    std::int64_t i0 = 0, j0 = 0, ni = 0, nj = 0;  // [i0, i0 + ni) x [j0, j0 + nj)
    bool empty() const { return ni <= 0 || nj <= 0; }
    std::int64_t cells() const { return empty() ? 0 : ni * nj; }
    Rect grown(std::int64_t d) const { return {i0 - d, j0 - d, ni + 2 * d, nj + 2 * d}; }
};

Rect intersect(const Rect &a, const Rect &b) {
    const std::int64_t i0 = std::max(a.i0, b.i0), j0 = std::max(a.j0, b.j0);
    const std::int64_t i1 = std::min(a.i0 + a.ni, b.i0 + b.ni), j1 = std::min(a.j0 + a.nj, b.j0 + b.nj);
    return {i0, j0, std::max<std::int64_t>(0, i1 - i0), std::max<std::int64_t>(0, j1 - j0)};
}

// The end of [start, start + count) for a message; a host's block may pass
// the range of int64 (i0 = INT64_MAX), which the message then spells out.
std::string end_of(std::int64_t start, std::int64_t count) {
    const bool overflows = count > 0 ? start > std::numeric_limits<std::int64_t>::max() - count
                                     : start < std::numeric_limits<std::int64_t>::min() - count;
    return overflows ? std::to_string(start) + " + " + std::to_string(count) : std::to_string(start + count);
}

std::string describe(const Rect &r) {
    std::ostringstream s;
    s << "[" << r.i0 << ", " << end_of(r.i0, r.ni) << ") x [" << r.j0 << ", " << end_of(r.j0, r.nj) << ")";
    return s.str();
}

// One rank whose cells this block reads, or which reads this block's cells
// (always both: the halo is as deep both ways).
struct Neighbour {
    int rank = 0;
    Rect block;       // its block, global coordinates
    Rect send;        // this block's cells it reads
    Rect receive;     // its cells this block reads
    std::int64_t tiles = 0;  // its tiles: the most hot boxes it sends
    std::vector<double> send_buffer, receive_buffer;
};

class BlockDistribution final : public CollectiveDistribution, public Halo {
public:
    BlockDistribution(MPI_Comm comm, int rank, const std::vector<Rect> &blocks, std::int64_t global_nx,
                      std::int64_t global_ny)
        : CollectiveDistribution(comm), block_(blocks[static_cast<std::size_t>(rank)]) {
        halo_.resize(kHaloDepth, block_.ni, block_.nj);
        halo_.i0 = block_.i0;
        halo_.j0 = block_.j0;
        halo_.global_nx = global_nx;
        halo_.global_ny = global_ny;
        const Rect domain{0, 0, global_nx, global_ny};
        const Rect reach = intersect(block_.grown(kHaloDepth), domain);
        for (std::size_t r = 0; r < blocks.size(); ++r) {
            if (static_cast<int>(r) == rank) continue;
            Neighbour n;
            n.rank = static_cast<int>(r);
            n.block = blocks[r];
            n.receive = intersect(reach, n.block);
            if (n.receive.empty()) continue;
            n.send = intersect(intersect(n.block.grown(kHaloDepth), domain), block_);
            n.tiles = ((n.block.ni + ActiveSet::kTile - 1) / ActiveSet::kTile) *
                      ((n.block.nj + ActiveSet::kTile - 1) / ActiveSet::kTile);
            neighbours_.push_back(std::move(n));
        }
        requests_.resize(2 * neighbours_.size());
    }

    StepAgreement agree_before_step(Grid &grid, const Engine &engine, double dt, bool refused) override {
        // Everything as a maximum: minima are maxima of the negated values.
        const double none = -std::numeric_limits<double>::infinity();
        const bool open = grid.has_open_cells();
        const std::vector<double> v =
            agree_on_step(grid, dt, refused,
                          {grid.source_active() ? 1.0 : 0.0, open ? 1.0 : 0.0, engine.may_move(grid) ? 1.0 : 0.0,
                           masks_changed_ ? 1.0 : 0.0, open ? -grid.open_level_min() : none,
                           open ? grid.open_level_max() : none, -grid.own_min_repose_angle(),
                           sides_changed_ ? 1.0 : 0.0});
        grid.set_distributed_min_repose_angle(-v[6]);
        if (v[3] != 0.0) exchange_masks(grid);
        if (v[7] != 0.0) assemble_side_levels(grid);
        StepAgreement state;
        state.source_active = v[0] != 0.0;
        // Lazy sources (structured/lazy_sources.hpp): the halo carries each cell's clock.
        lazy_sources_ = state.source_active && !grid.uses_physics();
        state.has_open_cells = v[1] != 0.0;
        state.may_move = v[2] != 0.0;
        state.open_level_min = state.has_open_cells ? -v[4] : 0.0;
        state.open_level_max = state.has_open_cells ? v[5] : 0.0;
        // The sides' levels are whole on every rank, and the sides agreed on.
        const std::array<bool, 4> open_sides{grid.side_open(kXMin), grid.side_open(kXMax), grid.side_open(kYMin),
                                       grid.side_open(kYMax)};
        const SideLevelRange range = side_level_range(open_sides, halo_.side_levels);
        state.side_level_min = range.lowest;
        state.side_level_max = range.highest;
        state.any_side_open = grid.any_side_open();  // the sides are agreed on
        return state;
    }

    void agree_on_substeps(std::vector<SubstepSummary> &levels) const override {
        CollectiveDistribution::agree_on_substeps(levels);
    }
    DistributedPlace place() const override { return {halo_.global_nx, halo_.global_ny, halo_.i0, halo_.j0}; }
    // A block refreshes its halo before every sweep.
    double substeps_per_exchange(const Grid &) const override { return 1.0; }

    void changed(const Grid &, unsigned what, const ChangedCells *) override {
        if (what & (kMasksChanged | kSourcesChanged)) masks_changed_ = true;
        if (what & kSidesChanged) sides_changed_ = true;
    }

    const HaloStore &store() const override { return halo_; }

    void before_sweep(const Grid &grid, StructuredState &state) override {
        ActiveSet &active = *state.active;
        const std::vector<double> &h = grid.heights();
        const std::vector<float> &res = grid.residuals();
        const std::vector<std::uint8_t> &moving = grid.moving();
        const bool hysteresis = grid.hysteresis();  // the same on every rank (agree_before_step)
        const bool lazy = lazy_sources_;
        const std::vector<double> &clock = state.clock;
        const double base = state.clock_base;
        const int per_cell = 2 + (hysteresis ? 1 : 0) + (lazy ? 1 : 0);
        for (std::size_t k = 0; k < neighbours_.size(); ++k) {
            Neighbour &n = neighbours_[k];
            n.receive_buffer.resize(static_cast<std::size_t>(per_cell * n.receive.cells() + 1 + 8 * n.tiles));
            check_mpi(MPI_Irecv(n.receive_buffer.data(), static_cast<int>(n.receive_buffer.size()), MPI_DOUBLE, n.rank,
                                kTagHeights, comm_, &requests_[k]),
                      "MPI_Irecv of the halo");
        }
        for (std::size_t k = 0; k < neighbours_.size(); ++k) {
            Neighbour &n = neighbours_[k];
            std::vector<double> &out = n.send_buffer;
            out.clear();
            for_cells(n.send, [&](std::size_t c) { out.push_back(h[c]); });
            for_cells(n.send, [&](std::size_t c) { out.push_back(static_cast<double>(res[c])); });
            if (hysteresis) for_cells(n.send, [&](std::size_t c) { out.push_back(static_cast<double>(moving[c])); });
            if (lazy)
                for_cells(n.send, [&](std::size_t c) {
                    out.push_back(clock.empty() ? 0.0 : std::max(clock[c], base) - base);
                });
            // The hot and driven boxes that can reach its block within a
            // sweep, in global coordinates (a driven box grown by one is a hot box).
            const std::size_t count_at = out.size();
            out.push_back(0.0);
            CellBox near;
            near.add(n.block.i0 - block_.i0, n.block.i0 + n.block.ni - block_.i0, n.block.j0 - block_.j0,
                     n.block.j0 + n.block.nj - block_.j0);
            auto send_box = [&](const CellBox &box) {
                if (!box.reaches(near, kHaloDepth)) return;
                out.push_back(static_cast<double>(box.i0 + block_.i0));
                out.push_back(static_cast<double>(box.i1 + block_.i0));
                out.push_back(static_cast<double>(box.j0 + block_.j0));
                out.push_back(static_cast<double>(box.j1 + block_.j0));
                out[count_at] += 1.0;
            };
            for (std::int64_t t = 0; t < active.tiles(); ++t) {
                send_box(active.hot(t));
                send_box(active.driven(t).grown(1));
            }
            check_mpi(MPI_Isend(out.data(), static_cast<int>(out.size()), MPI_DOUBLE, n.rank, kTagHeights, comm_,
                                &requests_[neighbours_.size() + k]),
                      "MPI_Isend of the halo");
            count_message(static_cast<double>(out.size() * sizeof(double)));
        }
        check_mpi(MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE),
                  "MPI_Waitall of the halo");
        remote_hot_.clear();
        for (Neighbour &n : neighbours_) {
            const double *in = n.receive_buffer.data();
            std::size_t k = 0;
            for_halo_cells(n.receive, [&](std::size_t at) { halo_.heights[at] = in[k++]; });
            for_halo_cells(n.receive, [&](std::size_t at) { halo_.residuals[at] = static_cast<float>(in[k++]); });
            if (hysteresis)
                for_halo_cells(n.receive, [&](std::size_t at) { halo_.moving[at] = static_cast<std::uint8_t>(in[k++]); });
            if (lazy) for_halo_cells(n.receive, [&](std::size_t at) { halo_.since[at] = in[k++]; });
            const std::size_t boxes = static_cast<std::size_t>(in[k]);
            for (std::size_t b = 0; b < boxes; ++b) {
                const double *box = in + k + 1 + 4 * b;
                CellBox local;
                local.add(static_cast<std::int64_t>(box[0]) - block_.i0, static_cast<std::int64_t>(box[1]) - block_.i0,
                          static_cast<std::int64_t>(box[2]) - block_.j0, static_cast<std::int64_t>(box[3]) - block_.j0);
                remote_hot_.push_back(local);
            }
        }
        active.set_remote_activity(remote_hot_, remote_sources_);
    }

private:

    // Calls f(cell index in the block) for the cells of r (global coordinates, inside the block), x fastest.
    template <class F>
    void for_cells(const Rect &r, F &&f) const {
        for (std::int64_t j = r.j0; j < r.j0 + r.nj; ++j)
            for (std::int64_t i = r.i0; i < r.i0 + r.ni; ++i)
                f(static_cast<std::size_t>((i - block_.i0) + block_.ni * (j - block_.j0)));
    }
    // Calls f(index in the halo store) for the cells of r (global coordinates, in the halo), x fastest.
    template <class F>
    void for_halo_cells(const Rect &r, F &&f) const {
        for (std::int64_t j = r.j0; j < r.j0 + r.nj; ++j)
            for (std::int64_t i = r.i0; i < r.i0 + r.ni; ++i) f(halo_.index(i - block_.i0, j - block_.j0));
    }

    // The levels along the global domain's sides, whole on every rank: each
    // face of a side belongs to the one block beside it, which gives its level
    // (what the host set on that block, 0 where it set none); the others give
    // -infinity, and a maximum keeps the level, every bit of it.
    void assemble_side_levels(const Grid &grid) {
        const std::int64_t along[4] = {halo_.global_ny, halo_.global_ny, halo_.global_nx, halo_.global_nx};
        const bool touches[4] = {block_.i0 == 0, block_.i0 + block_.ni == halo_.global_nx, block_.j0 == 0,
                                 block_.j0 + block_.nj == halo_.global_ny};
        const std::int64_t first[4] = {block_.j0, block_.j0, block_.i0, block_.i0};
        const std::int64_t count[4] = {block_.nj, block_.nj, block_.ni, block_.ni};
        std::vector<double> all;
        for (int side = 0; side < 4; ++side) {
            const std::size_t at = all.size();
            all.resize(at + static_cast<std::size_t>(along[side]), -std::numeric_limits<double>::infinity());
            if (!touches[side]) continue;
            for (std::int64_t k = 0; k < count[side]; ++k)
                all[at + static_cast<std::size_t>(first[side] + k)] = grid.side_level(side, k);
        }
        check_mpi(MPI_Allreduce(MPI_IN_PLACE, all.data(), static_cast<int>(all.size()), MPI_DOUBLE, MPI_MAX, comm_),
                  "MPI_Allreduce of the side levels");
        auto next = all.begin();
        for (int side = 0; side < 4; ++side) {
            halo_.side_levels[side].assign(next, next + along[side]);
            next += along[side];
        }
        sides_changed_ = false;
    }

    // The halo's kinds, sources, bed and angles, and the boxes of its cells with a source.
    void exchange_masks(Grid &grid) {
        const std::vector<std::uint8_t> &kinds = grid.kinds();
        const std::vector<double> &q = grid.source(), &zb = grid.bed(), &tan_theta = grid.tan_field();
        for (std::size_t k = 0; k < neighbours_.size(); ++k) {
            Neighbour &n = neighbours_[k];
            n.receive_buffer.resize(static_cast<std::size_t>(4 * n.receive.cells()));
            check_mpi(MPI_Irecv(n.receive_buffer.data(), static_cast<int>(n.receive_buffer.size()), MPI_DOUBLE, n.rank,
                                kTagMasks, comm_, &requests_[k]),
                      "MPI_Irecv of the halo's cell kinds and sources");
        }
        for (std::size_t k = 0; k < neighbours_.size(); ++k) {
            Neighbour &n = neighbours_[k];
            std::vector<double> &out = n.send_buffer;
            out.clear();
            for_cells(n.send, [&](std::size_t c) { out.push_back(static_cast<double>(kinds[c])); });
            for_cells(n.send, [&](std::size_t c) { out.push_back(q.empty() ? 0.0 : q[c]); });
            for_cells(n.send, [&](std::size_t c) { out.push_back(zb.empty() ? 0.0 : zb[c]); });
            for_cells(n.send, [&](std::size_t c) { out.push_back(tan_theta.empty() ? 0.0 : tan_theta[c]); });
            check_mpi(MPI_Isend(out.data(), static_cast<int>(out.size()), MPI_DOUBLE, n.rank, kTagMasks, comm_,
                                &requests_[neighbours_.size() + k]),
                      "MPI_Isend of the halo's cell kinds and sources");
            count_message(static_cast<double>(out.size() * sizeof(double)));
        }
        check_mpi(MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE),
                  "MPI_Waitall of the halo's cell kinds and sources");
        remote_sources_.clear();
        for (Neighbour &n : neighbours_) {
            const double *in = n.receive_buffer.data();
            std::size_t k = 0;
            for_halo_cells(n.receive, [&](std::size_t at) { halo_.kinds[at] = static_cast<std::uint8_t>(in[k++]); });
            for_halo_cells(n.receive, [&](std::size_t at) { halo_.sources[at] = in[k++]; });
            for_halo_cells(n.receive, [&](std::size_t at) { halo_.bed[at] = in[k++]; });
            for_halo_cells(n.receive, [&](std::size_t at) { halo_.tan_theta[at] = in[k++]; });
            CellBox sources;
            for (std::int64_t j = n.receive.j0; j < n.receive.j0 + n.receive.nj; ++j)
                for (std::int64_t i = n.receive.i0; i < n.receive.i0 + n.receive.ni; ++i) {
                    const std::size_t at = halo_.index(i - block_.i0, j - block_.j0);
                    if (halo_.kinds[at] == kSand && halo_.sources[at] != 0.0)
                        sources.add(i - block_.i0, i - block_.i0 + 1, j - block_.j0, j - block_.j0 + 1);
                }
            if (!sources.empty()) remote_sources_.push_back(sources);
        }
        masks_changed_ = false;
    }

    HaloStore halo_;
    Rect block_;
    std::vector<Neighbour> neighbours_;
    std::vector<MPI_Request> requests_;
    std::vector<CellBox> remote_hot_, remote_sources_;
    bool lazy_sources_ = false;  // this step applies sources lazily (agree_before_step)
    // A host changed kinds, sources, bed or angles (the halo's copies), or
    // sides and their levels, on this rank since the last exchange (none yet).
    bool masks_changed_ = true, sides_changed_ = true;
};

// What each rank passes to dpsm_create_2d_mpi, gathered on every rank.
struct Arguments {
    std::int64_t nx_global, ny_global, i0, j0, nx_local, ny_local, out_is_null;
    double dx, dy;
};

bool bad_spacing(double d) { return !std::isfinite(d) || !(d >= 1.0 / kMaxMagnitude && d <= kMaxMagnitude); }

// Checks the gathered arguments of all ranks; throws the first problem, the
// same on every rank (everything here depends on the gathered values only).
void check_decomposition(const std::vector<Arguments> &all, const char *fn) {
    const std::size_t ranks = all.size();
    for (std::size_t r = 0; r < ranks; ++r)
        if (all[r].out_is_null) fail(DPSM_ERR_NULL_POINTER, fn, "out is NULL on rank ", r);
    const Arguments &a0 = all[0];
    for (std::size_t r = 0; r < ranks; ++r) {
        const Arguments &a = all[r];
        if (a.nx_global < 1 || a.ny_global < 1)
            fail(DPSM_ERR_INVALID_SIZE, fn, "rank ", r, " passes a global grid of nx_global = ", a.nx_global,
                 " by ny_global = ", a.ny_global, " cells; both must be at least 1");
        if (a.nx_global > kMaxCells / a.ny_global)
            fail(DPSM_ERR_INVALID_SIZE, fn, "rank ", r, " passes a global grid of ", a.nx_global, " x ", a.ny_global,
                 " cells, more than this library can address (", kMaxCells, ")");
        if (bad_spacing(a.dx) || bad_spacing(a.dy))
            fail(DPSM_ERR_INVALID_VALUE, fn, "rank ", r, " passes dx = ", a.dx, ", dy = ", a.dy,
                 "; both must be finite and in [1e-50, 1e50]");
        if (a.nx_global != a0.nx_global || a.ny_global != a0.ny_global)
            fail(DPSM_ERR_INVALID_SIZE, fn, "the ranks disagree on the global grid: rank 0 passes ", a0.nx_global,
                 " x ", a0.ny_global, " cells, rank ", r, " passes ", a.nx_global, " x ", a.ny_global);
        if (a.dx != a0.dx || a.dy != a0.dy)
            fail(DPSM_ERR_INVALID_VALUE, fn, "the ranks disagree on the spacing: rank 0 passes dx = ", a0.dx,
                 ", dy = ", a0.dy, ", rank ", r, " passes dx = ", a.dx, ", dy = ", a.dy);
        if (a.nx_local < 1 || a.ny_local < 1)
            fail(DPSM_ERR_INVALID_SIZE, fn, "rank ", r, " passes a block of nx_local = ", a.nx_local,
                 " by ny_local = ", a.ny_local, " cells; both must be at least 1");
        if (a.i0 < 0 || a.j0 < 0 || a.i0 > a.nx_global - a.nx_local || a.j0 > a.ny_global - a.ny_local)
            fail(DPSM_ERR_INVALID_SIZE, fn, "the block of rank ", r, ", ",
                 describe({a.i0, a.j0, a.nx_local, a.ny_local}), ", does not lie in the global grid [0, ",
                 a.nx_global, ") x [0, ", a.ny_global, ")");
    }
    std::vector<Rect> blocks;
    for (const Arguments &a : all) blocks.push_back({a.i0, a.j0, a.nx_local, a.ny_local});
    // Overlaps: every pair once (P^2 / 2 tests of two rectangles, done once per grid).
    for (std::size_t a = 0; a < ranks; ++a)
        for (std::size_t b = a + 1; b < ranks; ++b) {
            const Rect both = intersect(blocks[a], blocks[b]);
            if (!both.empty())
                fail(DPSM_ERR_INVALID_SIZE, fn, "the blocks of rank ", a, ", ", describe(blocks[a]), ", and rank ", b,
                     ", ", describe(blocks[b]), ", overlap in ", describe(both),
                     "; every cell must belong to exactly one rank");
        }
    // Without overlaps, the blocks tile the grid if their cells add up.
    std::int64_t covered = 0;
    for (const Rect &r : blocks) covered += r.cells();
    const std::int64_t wanted = a0.nx_global * a0.ny_global;
    if (covered != wanted) {
        std::ostringstream where;
        // The lowest, then leftmost, uncovered cell lies in row 0 or just above
        // a block, in column 0 or just right of one: try those (few ranks only).
        if (ranks <= 64) {
            std::vector<std::int64_t> is{0}, js{0};
            for (const Rect &r : blocks) {
                is.push_back(r.i0 + r.ni);
                js.push_back(r.j0 + r.nj);
            }
            std::sort(is.begin(), is.end());
            std::sort(js.begin(), js.end());
            bool found = false;
            for (std::int64_t j : js) {
                for (std::int64_t i : is) {
                    if (i >= a0.nx_global || j >= a0.ny_global) continue;
                    bool owned = false;
                    for (const Rect &r : blocks)
                        owned = owned || (i >= r.i0 && i < r.i0 + r.ni && j >= r.j0 && j < r.j0 + r.nj);
                    if (!owned) {
                        where << "; cell (i, j) = (" << i << ", " << j << ") belongs to no rank";
                        found = true;
                        break;
                    }
                }
                if (found) break;
            }
        }
        fail(DPSM_ERR_INVALID_SIZE, fn, "the blocks of the ", ranks, " ranks cover ", covered, " of the ",
             a0.nx_global, " x ", a0.ny_global, " = ", wanted, " cells of the global grid", where.str(),
             "; the blocks must tile the global grid");
    }
}

// Gathers every rank's arguments and checks them together, so that all fail alike.
std::vector<Rect> agreed_blocks(MPI_Comm comm, int size, const Arguments &mine, const char *fn) {
    std::vector<Arguments> all(static_cast<std::size_t>(size));
    check_mpi(MPI_Allgather(&mine, static_cast<int>(sizeof(Arguments)), MPI_BYTE, all.data(),
                            static_cast<int>(sizeof(Arguments)), MPI_BYTE, comm),
              "MPI_Allgather of the blocks");
    check_decomposition(all, fn);
    std::vector<Rect> blocks;
    for (const Arguments &a : all) blocks.push_back({a.i0, a.j0, a.nx_local, a.ny_local});
    return blocks;
}

// Makes the block's grid with `build` (which may throw std::bad_alloc) and
// ties it to a duplicate of `comm`. Allocation failures are agreed on before
// the communicator is duplicated, so that no rank keeps a grid its peers do
// not have.
template <class Build>
dpsm_grid *distributed_grid(MPI_Comm comm, int rank, const std::vector<Rect> &blocks, std::int64_t nx_global,
                            std::int64_t ny_global, Build &&build, const char *fn) {
    std::unique_ptr<dpsm_grid> made;
    on_every_rank(Communicator(comm), fn, [&] { made = build(); });
    MPI_Comm own = MPI_COMM_NULL;
    check_mpi(MPI_Comm_dup(comm, &own), "MPI_Comm_dup");
    MPI_Comm_set_errhandler(own, MPI_ERRORS_RETURN);
    try {
        made->core.set_distribution(std::make_unique<BlockDistribution>(own, rank, blocks, nx_global, ny_global));
    } catch (...) {
        MPI_Comm_free(&own);
        throw;
    }
    return made.release();
}

int create_distributed(MPI_Comm comm, std::int64_t nx_global, std::int64_t ny_global, std::int64_t i0,
                       std::int64_t j0, std::int64_t nx_local, std::int64_t ny_local, double dx, double dy,
                       dpsm_grid **out, const char *fn) noexcept {
    if (out) *out = nullptr;
    return guarded(nullptr, fn, [&] {
        int rank = 0, size = 0;
        check_communicator(comm, fn, rank, size);
        const Arguments mine{nx_global, ny_global, i0, j0, nx_local, ny_local, out == nullptr ? 1 : 0, dx, dy};
        const std::vector<Rect> blocks = agreed_blocks(comm, size, mine, fn);
        *out = distributed_grid(comm, rank, blocks, nx_global, ny_global, [&] {
            return std::make_unique<dpsm_grid>(Geometry{2, false, nx_local, ny_local, dx, dy, nullptr});
        }, fn);
    });
}

std::string hex64(std::uint64_t v) {
    std::ostringstream s;
    s << "0x" << std::hex << v;
    return s.str();
}

// Each rank reads its own file, of the block it saved; then every rank learns
// whether all could, and whether the files are the blocks of one save, before
// any grid is made: every rank fails alike, none waits.
int load_distributed(MPI_Comm comm, const char *path, dpsm_grid **out, const char *fn) noexcept {
    if (out) *out = nullptr;
    return guarded(nullptr, fn, [&] {
        int rank = 0, size = 0;
        check_communicator(comm, fn, rank, size);
        Geometry geometry{};
        GridState state;
        RestartBlock block;
        on_every_rank(
            Communicator(comm), fn,
            [&] {
                if (!path) fail(DPSM_ERR_NULL_POINTER, fn, "path is NULL");
                if (!out) fail(DPSM_ERR_NULL_POINTER, fn, "out is NULL");
                load_restart(path, geometry, state, block, fn);
                if (!block.present)
                    fail(DPSM_ERR_NOT_APPLICABLE, fn, path,
                         " holds a grid of its own, not a block of a distributed grid; load it with dpsm_load");
                if (block.ranks != size)
                    fail(DPSM_ERR_INVALID_SIZE, fn, path, " holds a block of a grid saved on ", block.ranks,
                         " ranks; this communicator has ", size,
                         " (load a distributed grid on as many ranks as saved it)");
                if (block.rank != rank)
                    fail(DPSM_ERR_INVALID_VALUE, fn, path, " holds the block of rank ", block.rank, "; this is rank ",
                         rank, " (each rank loads the file it saved)");
            },
            [&](const Failure &failure) {
                return std::string(fn) + ": rank " + std::to_string(failure.rank) + " could not load its file (" +
                       dpsm_status_string(failure.status) +
                       "; its dpsm_last_error(NULL) says why), so no rank loaded";
            });

        std::vector<std::uint64_t> marks(static_cast<std::size_t>(size));
        check_mpi(MPI_Allgather(&block.save_mark, 1, MPI_UINT64_T, marks.data(), 1, MPI_UINT64_T, comm),
                  "MPI_Allgather of the saves' marks");
        for (int r = 1; r < size; ++r)
            if (marks[static_cast<std::size_t>(r)] != marks[0])
                fail(DPSM_ERR_BAD_FILE, fn, "the files are not the blocks of one save: rank 0's file was written by the "
                     "save marked ", hex64(marks[0]), ", rank ", r, "'s by the save marked ",
                     hex64(marks[static_cast<std::size_t>(r)]), " (each rank must load the file of the same save)");
        if (block.part) {
            // A part of a distributed mesh: the ranks finish it together.
            *out = part_grid(comm, block.part, fn, &state);
            return;
        }
        const Arguments mine{block.global_nx, block.global_ny, block.i0, block.j0, geometry.nx, geometry.ny, 0,
                             geometry.dx, geometry.dy};
        const std::vector<Rect> blocks = agreed_blocks(comm, size, mine, fn);
        *out = distributed_grid(comm, rank, blocks, block.global_nx, block.global_ny, [&] {
            auto grid = std::make_unique<dpsm_grid>(geometry);
            grid->core.restore(std::move(state));
            return grid;
        }, fn);
    });
}

}  // namespace
}  // namespace dpsm

extern "C" {

int dpsm_create_2d_mpi(MPI_Comm comm, int64_t nx_global, int64_t ny_global, int64_t i0, int64_t j0,
                       int64_t nx_local, int64_t ny_local, double dx, double dy, dpsm_grid **out) {
    return dpsm::create_distributed(comm, nx_global, ny_global, i0, j0, nx_local, ny_local, dx, dy, out,
                                    "dpsm_create_2d_mpi");
}

int dpsm_create_2d_mpi_f(MPI_Fint comm, int64_t nx_global, int64_t ny_global, int64_t i0, int64_t j0,
                         int64_t nx_local, int64_t ny_local, double dx, double dy, dpsm_grid **out) {
    return dpsm::create_distributed(MPI_Comm_f2c(comm), nx_global, ny_global, i0, j0, nx_local, ny_local, dx, dy,
                                    out, "dpsm_create_2d_mpi_f");
}

int dpsm_load_mpi(MPI_Comm comm, const char *path, dpsm_grid **out) {
    return dpsm::load_distributed(comm, path, out, "dpsm_load_mpi");
}

int dpsm_load_mpi_f(MPI_Fint comm, const char *path, dpsm_grid **out) {
    return dpsm::load_distributed(MPI_Comm_f2c(comm), path, out, "dpsm_load_mpi_f");
}

}  // extern "C"
