// How a host's edit reaches the code that keeps state of its own about a
// grid (an engine's active set and scratch, a distributed run's ghosts): the
// grid tells every listener what changed, once, as the edit happens; no
// listener keeps counters to compare.
#pragma once

#include <cstdint>
#include <vector>

namespace dpsm {

class Grid;

// What changed; a notice may carry several.
enum Change : unsigned {
    kCellsChanged = 1u << 0,    // the heights (and residuals) of some cells: ChangedCells says which
    kSourcesChanged = 1u << 1,  // the source rates
    kMasksChanged = 1u << 2,    // cell kinds, the bed, the angle field: what faces read per cell
    kSidesChanged = 1u << 3,    // open sides and edge faces, the levels held beyond them
    kLawChanged = 1u << 4,      // a parameter of the face law: any face may start or stop carrying sand
    kEverythingChanged = (1u << 5) - 1,  // a whole state restored
};

// With kCellsChanged: the block of cells the host wrote, [i0, i0 + ni) x
// [j0, j0 + nj) (a mesh's cells are one row), and, for listeners that ask
// for them, the cells of it whose heights or residuals now differ (null
// where not listed).
struct ChangedCells {
    std::int64_t i0 = 0, j0 = 0, ni = 0, nj = 0;
    const std::vector<std::int64_t> *cells = nullptr;
};

class ChangeListener {
public:
    virtual ~ChangeListener() = default;
    // After the change; `cells` is set with kCellsChanged.
    virtual void changed(const Grid &grid, unsigned what, const ChangedCells *cells) = 0;
    // Whether ChangedCells::cells should list the cells that changed (it costs the grid a list).
    virtual bool wants_changed_cells() const { return false; }
};

}  // namespace dpsm
