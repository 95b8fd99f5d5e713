// The hook by which a 2D grid runs as one block of a larger, distributed grid
// (the MPI component, src/mpi/). A serial grid has no Decomposition and never
// reaches any of this; the core only calls it at the few points where the
// ranks must agree or see each other's cells:
//
//  - after gather() (structured/tiled_sweep.cpp) has copied a tile at the block's edge,
//    gather_halo() fills its cells beyond the block from the HaloStore:
//    heights and residuals of the neighbours' cells as they were at the start
//    of the sweep, their kinds and sources as the host last set them;
//  - before a sweep the Decomposition refreshes that store (one exchange per
//    sweep of up to ActiveSet::kMaxLevels sub-steps) and tells the active set
//    where the neighbours' cells may move (ActiveSet::set_remote_activity);
//  - after a sweep it makes every level's "moved" and largest excess slope global;
//  - before a step it makes the flags that decide the step's work global;
//  - sums (the ledger, cell updates) are taken over all blocks;
//  - dpsm_save writes each block to its own file, with its place and a mark
//    that all the files of one save share, and agrees on success.
//
// Coordinates are the block's own (0 .. nx-1, 0 .. ny-1); the block starts at
// (i0, j0) of the global grid of global_nx x global_ny cells.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "model/side_levels.hpp"

namespace dpsm {

class Grid;
struct SubstepSummary;

// The cells within `depth` of a block that lie outside it, in four strips:
// below (rows -depth .. -1, columns -depth .. nx+depth-1), above (rows ny ..
// ny+depth-1, same columns), left and right (rows 0 .. ny-1, depth columns).
// Cells beyond the global domain are never read from here (they are ghosts).
struct HaloStore {
    int depth = 0;
    std::int64_t nx = 0, ny = 0;                   // the block
    std::int64_t i0 = 0, j0 = 0;                   // its first cell in the global grid
    std::int64_t global_nx = 0, global_ny = 0;
    std::vector<double> heights, sources;          // sources: 0 where none
    std::vector<double> since;                     // lazy sources: as TileBuffers::since
    std::vector<float> residuals;
    std::vector<std::uint8_t> kinds;
    // The physics of real scenes: bed and tan(theta) (0 where none) as the
    // host last set them, and which cells were moving at the start of the sweep.
    std::vector<double> bed, tan_theta;
    std::vector<std::uint8_t> moving;
    // The levels beyond the global domain's sides, each side whole (global_ny
    // values for the x sides, global_nx for the y sides; empty: 0), as the
    // blocks along it hold them (Decomposition::agree_before_step assembles them).
    SideLevels side_levels;

    void resize(int halo_depth, std::int64_t block_nx, std::int64_t block_ny) {
        depth = halo_depth;
        nx = block_nx;
        ny = block_ny;
        const std::size_t n = static_cast<std::size_t>(2 * depth * (nx + 2 * depth) + 2 * depth * ny);
        heights.assign(n, 0.0);
        sources.assign(n, 0.0);
        since.assign(n, 0.0);
        residuals.assign(n, 0.0f);
        kinds.assign(n, 0);
        bed.assign(n, 0.0);
        tan_theta.assign(n, 0.0);
        moving.assign(n, 0);
    }
    // The level of the global ghost cell (i, j) (global coordinates).
    double outside_level(std::int64_t i, std::int64_t j) const {
        return level_beyond(side_levels, global_nx, global_ny, i, j);
    }
    // Whether block cell (i, j) (outside the block, within depth) is a cell of the global grid.
    bool in_domain(std::int64_t i, std::int64_t j) const {
        return i + i0 >= 0 && i + i0 < global_nx && j + j0 >= 0 && j + j0 < global_ny;
    }
    // The index in the strips of block cell (i, j), which must lie outside the
    // block and within depth of it.
    std::size_t index(std::int64_t i, std::int64_t j) const {
        const std::int64_t wide = nx + 2 * depth;
        if (j < 0) return static_cast<std::size_t>((i + depth) + wide * (j + depth));
        if (j >= ny) return static_cast<std::size_t>(wide * depth + (i + depth) + wide * (j - ny));
        const std::int64_t sides = 2 * wide * depth;
        if (i < 0) return static_cast<std::size_t>(sides + (i + depth) + depth * j);
        return static_cast<std::size_t>(sides + depth * ny + (i - nx) + depth * j);
    }
};

// What every rank must agree on before a step (each a global figure).
struct StepAgreement {
    bool source_active = false;   // a source acts somewhere
    bool has_open_cells = false;  // open cells somewhere
    bool may_move = false;        // some tile anywhere is hot or has a source
    double open_level_min = 0.0, open_level_max = 0.0;  // over all open cells (when there are any)
    double side_level_min = 0.0, side_level_max = 0.0;  // over the levels beyond the open sides (0 where none)
    bool any_side_open = false;  // a side, or a face of a mesh's domain edge, is open
};

class Decomposition {
public:
    virtual ~Decomposition() = default;

    const HaloStore &halo() const { return halo_; }

    // Collective, at the start of dpsm_step: refreshes the halo's kinds,
    // sources, bed and angles, and the side levels along the global domain,
    // if the host changed them on any rank, checks
    // that every rank steps the same dt with the same parameters (throws Error
    // otherwise, on every rank alike), gives the grid the smallest angle of
    // repose of all blocks (it sets the sub-step), and returns the global flags.
    // A rank whose own dt was refused still takes part, with `refused`, so
    // that the others do not wait for it: then every rank throws, before
    // anything changed (the refusing rank's caller reports its own reason).
    virtual StepAgreement agree_before_step(Grid &grid, double dt, bool refused) = 0;
    // Collective, before each sweep: refreshes the halo's heights and
    // residuals and the active set's view of the neighbours' activity.
    virtual void before_sweep(Grid &grid) = 0;
    // Collective, after each sweep: moved and max_excess_slope of every level over all ranks.
    virtual void after_sweep(std::vector<SubstepSummary> &levels) = 0;
    // A distributed mesh's hooks (mpi/distributed_mesh.cpp), collective, in
    // every sub-step: the ghosts' gradients from their owners once the owned
    // cells' are known, and the ghosts' heights (and moving flags) once the
    // owned cells changed. Only values that changed since they were last sent
    // travel: `computed` lists the owned cells whose values this sub-step may
    // have changed (null: any owned cell); the ghosts whose values changed
    // are appended to `changed_ghosts`. Nothing on a block of a grid.
    virtual void exchange_ghost_gradients(Grid &, double * /*gx*/, double * /*gy*/,
                                          const std::vector<std::int64_t> * /*computed*/,
                                          std::vector<std::int64_t> & /*changed_ghosts*/) {}
    virtual void exchange_ghost_heights(Grid &, const std::vector<std::int64_t> * /*computed*/,
                                        std::vector<std::int64_t> & /*changed_ghosts*/) {}
    // The point-to-point messages of ghost cells' values this rank sent, and
    // their bytes, since the last call (collectives are not counted).
    void take_traffic(double &messages, double &bytes) {
        messages = messages_sent_;
        bytes = bytes_sent_;
        messages_sent_ = bytes_sent_ = 0.0;
    }
    // The sub-steps taken between two exchanges of ghost values: a block of
    // a grid refreshes its halo in every sub-step.
    virtual double substeps_per_exchange(const Grid &) const { return 1.0; }
    // Collective: the sum over all ranks, the same on every rank.
    virtual double sum(double local) const = 0;
    // Collective: as sum(), for a call that a rank may have refused (its
    // `local` is then ignored): false on every rank when any rank refused.
    virtual bool sum_unless_refused(double local, bool refused, double &total) const = 0;

    // This block's place: its rank, the number of ranks, the global grid.
    virtual int rank() const = 0;
    virtual int ranks() const = 0;
    // Collective: a number that every rank gets alike and that differs from
    // one call to the next (and between runs): the mark of one save.
    virtual std::uint64_t shared_mark() const = 0;
    // Collective: the lowest rank whose `status` is not DPSM_OK (0), with that
    // status; rank -1 when every rank succeeded.
    virtual void first_failure(int status, int &failed_rank, int &failed_status) const = 0;

protected:
    HaloStore halo_;
    double messages_sent_ = 0.0, bytes_sent_ = 0.0;
};

}  // namespace dpsm
