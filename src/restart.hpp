// Restart files (dpsm_save, dpsm_load): a grid's geometry and state in a
// versioned, portable binary format with checksums. The layout is documented
// in docs/guide_restart.md and written by one function, read by another, in
// the same order (restart.cpp).
#pragma once

#include <cstdint>

#include "grid.hpp"

namespace dpsm {

// The format version this library writes, and the newest it reads.
constexpr std::uint32_t kRestartVersion = 1;

// Writes the grid to `path` through `path + ".tmp"`, renamed over `path` only
// once complete. Throws Error (DPSM_ERR_IO) naming the path and the reason.
void save_restart(const Grid &grid, const char *path, const char *function);

// Reads and checks a whole file: on return `geometry` and `state` hold values
// the setters would accept. Throws Error: DPSM_ERR_IO when the file cannot be
// read, DPSM_ERR_BAD_FILE when its contents are wrong in any way.
void load_restart(const char *path, Geometry &geometry, GridState &state, const char *function);

}  // namespace dpsm
