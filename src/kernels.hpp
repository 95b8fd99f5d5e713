// One explicit sweep of the slide fluxes. Every face between two cells carries
// one flux by the law in closure.hpp, which one cell loses and the other gains,
// so mass is conserved face by face. Two schemes share the sweep:
//  - pairwise (the paper's Eq. 12): the slope of a face is the difference of
//    its two cells over their distance; it limits the slope along each grid
//    axis, so in 2D it builds pyramids;
//  - isotropic: the face also sees the transverse slope (the average of its
//    two cells' central differences across it), so the law acts on the full
//    |grad h| and piles converge to cones under refinement.
// In 1D and on the axisymmetric grid the two are the same.
// Kernels read the grid and write rates; they never call back up.
#pragma once

#include <vector>

#include "grid.hpp"

namespace dpsm {

struct SweepResult {
    double max_excess_slope = 0.0;  // max over open faces of |grad h| - tan(theta), at least 0
    double outflow_rate = 0.0;      // mass per unit time leaving through open sides and cells
};

// Fills the grid's rate workspace with dh/dt from the slide fluxes (sources
// not included) for every sand cell, 0 for wall and open cells.
SweepResult slide_rates(Grid &grid);

// h += dt * (rate + q) on sand cells.
void apply_rates(Grid &grid, double dt);

}  // namespace dpsm
