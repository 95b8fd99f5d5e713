// The mass ledger: what sources, the host and the open boundaries did to the
// mass on the grid. Each account is a compensated (Neumaier) sum, so the
// balance total == sourced + external - outflow closes to round-off over
// millions of sub-steps. Do not build this file with -ffast-math: it would
// optimise the compensation away.
#pragma once

#include <cmath>

namespace dpsm {

class CompensatedSum {
public:
    CompensatedSum() = default;
    // A sum as it was (a restart file keeps both parts, so that later
    // additions round exactly as they would have).
    CompensatedSum(double sum, double correction) noexcept : sum_(sum), correction_(correction) {}
    void add(double x) noexcept {
        const double t = sum_ + x;
        if (std::fabs(sum_) >= std::fabs(x))
            correction_ += (sum_ - t) + x;
        else
            correction_ += (x - t) + sum_;
        sum_ = t;
    }
    double value() const noexcept { return sum_ + correction_; }
    double sum() const noexcept { return sum_; }
    double correction() const noexcept { return correction_; }

private:
    double sum_ = 0.0;
    double correction_ = 0.0;
};

// A cell's height plus an increment as a TwoSum: what rounding drops is kept
// in the cell's residual and added back with its next increment, so that a
// surface does not lose mass one half-ulp at a time (the tile kernel does the
// same in its lanes).
inline void add_with_residual(double &h, float &residual, double increment) noexcept {
    const double b = increment + static_cast<double>(residual);
    const double s = h + b;
    const double b_virtual = s - h;
    residual = static_cast<float>((h - (s - b_virtual)) + (b - b_virtual));
    h = s;
}

// What a source q adds to a cell in `substeps` sub-steps of dt, the same
// bits wherever it is applied: the engines add a lazy source in closed form
// with it (structured/lazy_sources.hpp, mesh/mesh_engine.cpp).
inline double source_lag(double q, double dt, double substeps) noexcept { return (q * dt) * substeps; }

struct MassLedger {
    CompensatedSum sourced;   // mass added by sources
    CompensatedSum external;  // mass added by the host's own calls
    CompensatedSum outflow;   // mass that left through open sides and cells
    CompensatedSum unmet;     // erosion asked for where no sand lay above the bed
    // The part of `outflow` that left through each side (DPSM_XMIN ..
    // DPSM_YMAX); the rest left through open cells.
    CompensatedSum side_outflow[4];
};

}  // namespace dpsm
