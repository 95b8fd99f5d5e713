// The face law: what a face between two cells carries, written once for
// every engine (the line sweep, the tile kernels in their lanes and the mesh
// engine call it).
//
// The flux law of the Degenerate Parabolic Sliding Model (the paper's Eq. 6):
// sand moves down the steepest slope at a rate nu * f(|grad h|) with
//     f(s) = (s - tan(theta))_+^p / sqrt(1 + s^2),
// zero at or below the angle of repose; p = 1 is the paper's law, p = 2 its
// Bingham closure (dpsm_set_flux_exponent). On a face between two cells a
// distance d apart with height difference dh and p = 1 this is the paper's
// pairwise exchange (Eq. 12): (|dh| - d tan(theta))_+ / sqrt(d^2 + dh^2).
//
// The physics of real scenes, on a face: its tan(theta) is the mean of its
// cells' (an angle field); it carries nothing up to its threshold, tan(theta)
// (1 + tol), or, between two cells at rest, the static angle's where that is
// steeper (hysteresis); and it takes from its upstream sand cell at most its
// share of the sand that cell has above the bed (the bed's cap). These rules
// are templates over the number type: double in the scalar engines, a lane
// vector of structured/simd.hpp in the tile kernels, each engine keeping its
// own arithmetic around them (the lanes' max and min choose as the x86
// instructions do, the scalar engines as std::max and std::min).
#pragma once

#include <algorithm>
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

// Flux per unit face length as slide_flux, for a slope whose square s2 the
// caller has (the square of s need not round to it).
inline double slide_flux_at(double nu, double tan_theta, double s, double s2, double p = 1.0) noexcept {
    const double excess = s - tan_theta;
    return excess > 0.0 ? nu * excess_power(excess, p) / std::sqrt(1.0 + s2) : 0.0;
}

namespace law {

// The scalar engines' arithmetic; the lanes bring their own.
inline double select(bool m, double a, double b) { return m ? a : b; }
inline double max(double a, double b) { return std::max(a, b); }
inline double min(double a, double b) { return std::min(a, b); }
template <class T>
struct Constant {
    static T of(double x) { return T::broadcast(x); }
};
template <>
struct Constant<double> {
    static double of(double x) { return x; }
};

// A face's tan(theta) from its cells' (an angle field): their mean, the
// sand cell's standing in for a cell that is not sand (where both are sand,
// mean_tan alone).
template <class T>
inline T mean_tan(T tan_a, T tan_b) {
    return (tan_a + tan_b) * Constant<T>::of(0.5);
}
template <class T, class Mask>
inline T face_tan(T tan_a, T tan_b, Mask a_sand, Mask b_sand) {
    const T ta = select(a_sand, tan_a, tan_b);
    return mean_tan(ta, select(b_sand, tan_b, ta));
}

// A face's threshold from `rest`, its tan(theta) (1 + tol) in the caller's
// units: between two cells at rest (hysteresis) the static angle's,
// `static_threshold` in the same units, where that is steeper.
template <class T, class Mask>
inline T threshold(T rest, Mask both_at_rest, T static_threshold) {
    return select(both_at_rest, max(rest, static_threshold), rest);
}

// The bed's cap on a face's flux from its cell a to its cell b: at most
// `most_out` out of a, at most -`least` out of b (least <= 0; each the share
// of a sand cell's sand, +-infinity from a cell that is not sand).
template <class T>
inline T capped(T flux, T most_out, T least) {
    return max(min(flux, most_out), least);
}

// A sand cell's share of the sand it has above the bed, as a flux: `faces`
// share it, over a sub-step of dt; `weight` turns the flux into the cell's
// dh/dt (1 / d per unit face length on a grid, length over area on a line, 1
// for a volume).
inline double share_of_sand(double available, double faces, double dt, double weight) {
    return available / (faces * dt * weight);
}

}  // namespace law
}  // namespace dpsm
