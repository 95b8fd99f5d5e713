// The 2D sweep: visits the tiles of the active set (structured/active_set.hpp) and runs
// the tile kernel (structured/tile_kernel.hpp) on each, in parallel with OpenMP. Every
// tile reads the heights at the start of the sweep and writes its own cells
// to a separate output, so results do not depend on the order of tiles or the
// number of threads; sums over tiles are taken in tile order. Sources that
// cannot make a face steep wait for the end of the step (structured/lazy_sources.hpp).
#pragma once

#include <cstdint>
#include <vector>

#include "model/engine.hpp"
#include "structured/active_set.hpp"
#include "structured/tile_kernel.hpp"

namespace dpsm {

class Grid;

// Scratch of the 2D sweep, kept by the grid between steps. A sweep writes
// the visited cells into heights (residuals, moving) and then swaps them with
// the grid's: the old grid becomes this scratch. So that a sparse sweep does
// not copy its cells back, the scratch is kept equal to the grid except in
// the stale boxes (per tile: the cells the last sweep wrote, and those the
// host changed since), which the next sweep copies from the grid where it
// does not write them itself. Until the next sweep, the scratch holds the
// heights from before the last one everywhere, and `visit` and `boxes` the
// tiles it visited and the cells it wrote in each (the relaxation to rest
// reads both).
struct TiledWorkspace {
    std::vector<double> heights;     // the grid's heights but in the stale boxes
    std::vector<float> residuals;
    std::vector<std::uint8_t> moving;  // the moving cells (hysteresis)
    std::vector<double> clock;         // the source cells' clocks (lazy sources)
    std::vector<std::uint8_t> visited_in_step;  // per tile: a sweep of this step wrote some of its cells
    bool all_stale = true;             // nothing of the scratch can be trusted
    std::vector<CellBox> stale;        // per tile: where the scratch may differ from the grid
    std::vector<std::int64_t> stale_tiles;  // the tiles whose stale box is not empty
    std::vector<CellBox> written;      // per tile, during a sweep: the cells it writes
    CellBox last_written;              // after a sweep: every cell it wrote (where the grid may have changed)
    std::vector<TileBuffers> buffers;  // one per thread
    std::vector<std::int64_t> visit;
    std::vector<CellBox> boxes;         // per visited tile: the cells that can change
    std::vector<CellBox> seeds;         // per visited tile: the hot boxes and sources that reach it
    std::vector<TileLevelStats> stats;  // per visited tile and level
    std::vector<std::int64_t> origin;   // per visited tile: its buffer's first cell (i, j)
};

// Below this many cells a pass over tiles runs on the calling thread: the
// threads would cost more than they save.
constexpr std::int64_t kCellsForThreads = 8 * ActiveSet::kTile * ActiveSet::kTile;

// Makes sure the workspace can run a sweep with `threads` threads
// (Grid::step_threads). Allocates; call before changing anything.
void prepare_tiled_sweep(Grid &grid, int threads);

// The host changed the cells of box (heights or residuals): the scratch no
// longer holds them.
void tiled_workspace_changed(TiledWorkspace &ws, const ActiveSet &active, const CellBox &box);

// Advances a 2D grid `levels` (1 .. ActiveSet::kMaxLevels) sub-steps of dt and
// fills one summary per level; returns the number of cells it visited.
// Without residuals (the relaxation to rest, which has no use for them) every
// residual must be 0 and stays 0, and the heights are those the sweep with
// them would give; the physics kernel always carries them. The largest
// excess slope costs a little on every face, so it is found on the last
// level only, and only with find_excess (elsewhere it is 0). first_substep:
// the index in the step of the sweep's first sub-step (lazy sources).
std::int64_t tiled_sweep(Grid &grid, int levels, double dt, std::vector<SubstepSummary> &summaries,
                         bool find_excess, bool residuals = true, double first_substep = 0.0);

}  // namespace dpsm
