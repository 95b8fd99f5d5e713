// The fast relaxation to rest (dpsm_set_relaxation(g, DPSM_RELAX_TO_REST)):
// dpsm_step brings the surface to rest in far fewer evaluations of the slide
// fluxes than explicit sub-steps, without a time scale. It follows the flow's
// own path by Runge-Kutta-Chebyshev steps while much sand moves, then lets
// momentum finish the small tail (docs/performance.md, "Larger steps").
#pragma once

#include "grid.hpp"

namespace dpsm {

// Relaxes the grid to rest (or until its sub-step limit of flux evaluations),
// booking what leaves through open sides and cells as outflow. Throws
// Error(DPSM_ERR_NOT_APPLICABLE) before changing anything for a scene this
// relaxation does not support.
void relax_to_rest(Grid &grid);

}  // namespace dpsm
