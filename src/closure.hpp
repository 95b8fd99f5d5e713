// The flux law of the Degenerate Parabolic Sliding Model (the paper's Eq. 6):
// sand moves down the steepest slope at a rate nu * f(|grad h|) with
//     f(s) = (s - tan(theta))_+ / sqrt(1 + s^2),
// zero at or below the angle of repose. On a face between two cells a distance
// d apart with height difference dh this is the paper's pairwise exchange
// (Eq. 12): (|dh| - d tan(theta))_+ / sqrt(d^2 + dh^2), with s = dh/d.
#pragma once

#include <cmath>

namespace dpsm {

// Flux per unit face length from the higher to the lower cell, for slope
// magnitude s >= 0.
inline double slide_flux(double nu, double tan_theta, double s) noexcept {
    const double excess = s - tan_theta;
    return excess > 0.0 ? nu * excess / std::sqrt(1.0 + s * s) : 0.0;
}

// The largest slope of f, f'(tan theta) = cos(theta): it sets the explicit
// stability limit.
inline double slide_flux_max_derivative(double nu, double theta) noexcept {
    return nu * std::cos(theta);
}

}  // namespace dpsm
