// One explicit sweep of the paper's pairwise scheme (Eq. 12): every face
// between two cells exchanges sand by the flux law in closure.hpp, so what one
// cell loses its neighbour gains and mass is conserved pair by pair.
// Kernels read the grid and write rates; they never call back up.
#pragma once

#include <vector>

#include "grid.hpp"

namespace dpsm {

struct SweepResult {
    double max_excess_slope = 0.0;  // max over open faces of |slope| - tan(theta), at least 0
    double outflow_rate = 0.0;      // mass per unit time leaving through open sides and cells
};

// Fills rate[c] with dh/dt from the slide fluxes (sources not included) for
// every sand cell, 0 for wall and open cells.
SweepResult pairwise_rates(const Grid &grid, std::vector<double> &rate);

// h += dt * (rate + q) on sand cells.
void apply_rates(Grid &grid, const std::vector<double> &rate, double dt);

}  // namespace dpsm
