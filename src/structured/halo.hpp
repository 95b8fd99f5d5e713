// How a 2D grid runs as one block of a larger, distributed grid: the cells
// within a sweep's reach beyond the block, which other ranks own, kept in a
// HaloStore that the MPI component (mpi/distributed.cpp) fills. The tiled
// sweep reads them as it reads its own:
//
//  - after gather() (structured/tiled_sweep.cpp) has copied a tile at the block's edge,
//    gather_halo() fills its cells beyond the block from the store:
//    heights and residuals of the neighbours' cells as they were at the start
//    of the sweep, their kinds and sources as the host last set them;
//  - before a sweep the Halo refreshes that store (one exchange per sweep of
//    up to ActiveSet::kMaxLevels sub-steps) and tells the active set where the
//    neighbours' cells may move (ActiveSet::set_remote_activity).
//
// Coordinates are the block's own (0 .. nx-1, 0 .. ny-1); the block starts at
// (i0, j0) of the global grid of global_nx x global_ny cells.
#pragma once

#include <cstdint>
#include <vector>

#include "model/side_levels.hpp"

namespace dpsm {

class Grid;
struct StructuredState;

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
    // blocks along it hold them.
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

// A block's exchange with its neighbours, which the grid's Distribution
// implements (model/distribution.hpp).
class Halo {
public:
    virtual ~Halo() = default;
    virtual const HaloStore &store() const = 0;
    // Collective, before each sweep: the store's heights and residuals (and
    // moving flags, and the lazy sources' clocks) as the neighbours hold them
    // now, and the active set's view of the neighbours' activity.
    virtual void before_sweep(const Grid &grid, StructuredState &state) = 0;
};

}  // namespace dpsm
