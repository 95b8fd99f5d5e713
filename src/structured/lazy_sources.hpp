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

#include "model/ledger.hpp"
#include "structured/tile_kernel.hpp"

namespace dpsm {

class Grid;
struct HaloStore;

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


// Within a sweep (structured/tiled_sweep.cpp). The sub-step of the step
// after which each buffer cell's stored height is current (0 for cells
// beyond the domain, and for a cell last current before the step began).
void gather_since(const Grid &grid, const HaloStore *halo, TileBuffers &b, std::int64_t gi0, std::int64_t gj0);
// Before a level that computes `region` at sub-step `substep` of the step:
// every cell it reads gets its height now (what its faces see) and what its
// source added since it was current (which the kernel adds to a cell whose
// faces carry sand). One formula for every cell and every visit, so that a
// cell's height now is the same bits whichever tile reads it;
// catch_up_sources adds the same lag.
void lazy_level(TileBuffers &b, int in, const TileRect &region, double substep, double dt);

}  // namespace dpsm
