// The levels beyond the sides of a domain (dpsm_set_side_levels), and the
// level of a cell beyond them as a sweep reads it: across from a boundary
// face, that face's level, the same however far out; beyond a corner, the
// mean of the two sides' levels nearest to it (it only enters the transverse
// slopes of the corner's faces). One rule for a grid and for the global
// domain of a distributed grid.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace dpsm {

// Per side (DPSM_XMIN .. DPSM_YMAX), one level per boundary face; empty: all 0.
using SideLevels = std::array<std::vector<double>, 4>;

inline double side_level_of(const SideLevels &levels, int side, std::int64_t k) {
    return levels[side].empty() ? 0.0 : levels[side][static_cast<std::size_t>(k)];
}

// The level of cell (i, j) beyond a domain of nx x ny cells.
inline double level_beyond(const SideLevels &levels, std::int64_t nx, std::int64_t ny, std::int64_t i, std::int64_t j) {
    const std::int64_t ic = i < 0 ? 0 : i >= nx ? nx - 1 : i, jc = j < 0 ? 0 : j >= ny ? ny - 1 : j;
    const bool beyond_x = i < 0 || i >= nx, beyond_y = j < 0 || j >= ny;
    const int x_side = i < 0 ? 0 : 1, y_side = j < 0 ? 2 : 3;
    if (beyond_x && beyond_y) return 0.5 * (side_level_of(levels, x_side, jc) + side_level_of(levels, y_side, ic));
    return beyond_x ? side_level_of(levels, x_side, jc) : side_level_of(levels, y_side, ic);
}

}  // namespace dpsm
