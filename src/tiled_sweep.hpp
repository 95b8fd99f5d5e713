// The 2D sweep: visits the tiles of the active set (active_set.hpp) and runs
// the tile kernel (tile_kernel.hpp) on each, in parallel with OpenMP. Every
// tile reads the heights at the start of the sweep and writes its own cells
// to a separate output, so results do not depend on the order of tiles or the
// number of threads; sums over tiles are taken in tile order.
#pragma once

#include <cstdint>
#include <vector>

#include "active_set.hpp"
#include "tile_kernel.hpp"

namespace dpsm {

class Grid;

struct LevelSummary {
    bool moved = false;         // some face carried sand in this sub-step
    double outflow_rate = 0.0;  // mass per unit time into sinks
    double max_excess = 0.0;    // largest |grad h| - tan(theta) over faces that carried sand
    double unmet_mass = 0.0;    // erosion asked for where no sand lay above the bed
};

// Scratch of the 2D sweep, kept by the grid between steps.
struct TiledWorkspace {
    std::vector<double> heights;     // the new heights of visited tiles
    std::vector<float> residuals;
    std::vector<std::uint8_t> moving;  // the new moving cells (hysteresis)
    std::vector<TileBuffers> buffers;  // one per thread
    std::vector<std::int64_t> visit;
    std::vector<CellBox> boxes;         // per visited tile: the cells that can change
    std::vector<CellBox> seeds;         // per visited tile: the hot boxes and sources that reach it
    std::vector<TileLevelStats> stats;  // per visited tile and level
    std::vector<std::int64_t> origin;   // per visited tile: its buffer's first cell (i, j)
};

// Makes sure the workspace can run a sweep with `threads` threads (0: the
// OpenMP default). Allocates; call before changing anything.
void prepare_tiled_sweep(Grid &grid, int threads);

// Advances a 2D grid `levels` (1 .. ActiveSet::kMaxLevels) sub-steps of dt and
// fills one summary per level; returns the number of cells it visited.
std::int64_t tiled_sweep(Grid &grid, int levels, double dt, std::vector<LevelSummary> &summaries);

}  // namespace dpsm
