// The flux law of the Degenerate Parabolic Sliding Model (the paper's Eq. 6):
// sand moves down the steepest slope at a rate nu * f(|grad h|) with
//     f(s) = (s - tan(theta))_+^p / sqrt(1 + s^2),
// zero at or below the angle of repose; p = 1 is the paper's law, p = 2 its
// Bingham closure (dpsm_set_flux_exponent). On a face between two cells a
// distance d apart with height difference dh and p = 1 this is the paper's
// pairwise exchange (Eq. 12): (|dh| - d tan(theta))_+ / sqrt(d^2 + dh^2).
#pragma once

#include <cmath>

namespace dpsm {

// The excess slope raised to the flux exponent, without a call to pow for the
// exponents people use.
inline double excess_power(double excess, double p) noexcept {
    if (p == 1.0) return excess;
    if (p == 2.0) return excess * excess;
    return std::pow(excess, p);
}

// Flux per unit face length from the higher to the lower cell, for slope
// magnitude s >= 0.
inline double slide_flux(double nu, double tan_theta, double s, double p = 1.0) noexcept {
    const double excess = s - tan_theta;
    return excess > 0.0 ? nu * excess_power(excess, p) / std::sqrt(1.0 + s * s) : 0.0;
}

// The largest slope of nu f over all s: it sets the explicit stability limit.
// For p = 1 it is f'(tan theta) = cos(theta); for 1 < p <= 2 the largest
// derivative lies beyond the threshold and is found by sampling (f' is smooth
// there, and bounded because f grows at most linearly).
inline double slide_flux_max_derivative(double nu, double theta, double p = 1.0) noexcept {
    if (p == 1.0) return nu * std::cos(theta);
    const double tan_theta = std::tan(theta);
    double largest = 0.0;
    // Excess slopes from 1e-8 to 1e8, 1 % apart.
    for (double excess = 1e-8; excess < 1e8; excess *= 1.01) {
        const double s = tan_theta + excess;
        const double root = std::sqrt(1.0 + s * s);
        const double derivative = p * std::pow(excess, p - 1.0) / root - std::pow(excess, p) * s / (root * root * root);
        largest = derivative > largest ? derivative : largest;
    }
    return nu * largest * 1.02;  // room for the peak between two samples
}

}  // namespace dpsm
