// The fast relaxation to rest (dpsm_set_relaxation(g, DPSM_RELAX_TO_REST)):
// dpsm_step brings the surface to rest in far fewer evaluations of the slide
// fluxes than explicit sub-steps, without a time scale. It follows the flow's
// own path by Runge-Kutta-Chebyshev steps while much sand moves, then lets
// momentum finish the small tail (docs/performance.md, "Larger steps").
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "model/grid.hpp"
#include "structured/active_set.hpp"

namespace dpsm {

// The relaxation's arrays, kept by the grid between steps so that each step
// touches only the pages of the tiles where sand moves, not fresh ones
// (structured/relax_to_rest.cpp). Outside a step every box is empty.
struct RelaxWorkspace {
    RelaxWorkspace(std::size_t cells, std::size_t tiles);
    static constexpr int kStates = 4;
    std::unique_ptr<double[]> states[kStates], start, rates;  // over the grid, not initialised
    std::vector<CellBox> filled, live;                       // per tile of the active set
    std::vector<std::int64_t> filled_tiles, live_tiles;      // the tiles whose box is not empty
};

// Relaxes the grid to rest (or until `budget` flux evaluations are spent),
// booking what leaves through open sides and cells as outflow, and returns
// true. Returns false with the grid as it was, residuals included, where the
// state it reached is not one the model's own steps could reach (new
// extremes, or a closed scene's mass off by more than rounding); the caller
// then steps in time. cells_visited: the work done either way. Throws
// Error(DPSM_ERR_NOT_APPLICABLE) before changing anything for a scene this
// relaxation does not support.
bool relax_to_rest(Grid &grid, std::int64_t budget, double &cells_visited);

// What of the grid's scene the relaxation does not support, as a phrase for
// a message; null when it supports all of it.
const char *relaxation_unsupported(const Grid &grid);

}  // namespace dpsm
