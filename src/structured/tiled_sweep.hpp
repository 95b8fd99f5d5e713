// The 2D sweep: visits the tiles of the active set (structured/active_set.hpp) and runs
// the tile kernel (structured/tile_kernel.hpp) on each, in parallel with OpenMP. Every
// tile reads the heights at the start of the sweep and writes its own cells
// to a separate output, so results do not depend on the order of tiles or the
// number of threads; sums over tiles are taken in tile order.
//
// Lazy sources (2D grids without the physics of real scenes). A source that
// cannot make a face steep within a step needs no sub-steps: the height of a
// cell none of whose faces carries sand grows as h + q t, which one addition
// gives at the end of the step as well as many. So a step starts by finding
// the cells whose faces a source may make steep within it (drive_sources:
// each face's slope moves linearly in time under sources alone, so its
// magnitude is largest at one end of the step, and both ends are looked at);
// only those drive the active set. The kernel updates a cell only in a
// sub-step in which one of its faces carries sand (then it adds the source
// since the cell was last current); everywhere else what the source adds
// waits, and catch_up_sources applies it at the end of the step in closed
// form. A cell's stored height thus depends on when sand moved across its
// faces, not on which sweeps visited it, and results stay independent of
// the active set and the threads. drive_sources judges the heights as if
// only sources changed them: where sand moves near a source during the
// step, the source cells there are driven for the rest of it
// (ActiveSet::drive_sources_near_moves), and the step does not end at rest
// before its end.
#pragma once

#include <cstdint>
#include <vector>

#include "stepping/engine.hpp"
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

// Makes sure the workspace can run a sweep with `threads` threads
// (Grid::step_threads). Allocates; call before changing anything.
void prepare_tiled_sweep(Grid &grid, int threads);

// The host changed the cells of box (heights or residuals): the scratch no
// longer holds them.
void tiled_workspace_changed(TiledWorkspace &ws, const ActiveSet &active, const CellBox &box);

// What a source q adds to a cell in `substeps` sub-steps of dt, the same
// bits wherever it is applied.
inline double source_lag(double q, double dt, double substeps) { return (q * dt) * substeps; }

// Lazy sources, at the start of a step of duration T: sets the active set's
// driven boxes to the cells whose faces are steeper than the rest threshold
// (less a margin for rounding) now or at T under the sources alone, and
// returns whether any face is steep at T: a source that keeps sand moving
// (a face steep only now comes to rest by itself). Changes no height. On a
// distributed grid it exchanges the halo first (collective); the result is
// this block's.
// `reach` receives the largest |h| and |h + q T| over the cells it read
// (every cell with a source), as its bound on slopes finds them.
bool drive_sources(Grid &grid, double T, double dt, double &reach);

// Lazy sources, at the end of a step: every source cell not current after
// sub-step `substeps` of dt gets its source since in closed form (a TwoSum
// with its residual). Returns the number of cells it changed.
double catch_up_sources(Grid &grid, double substeps, double dt);

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
