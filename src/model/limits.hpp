// The supported range (dpsm.h), in one place for every part that checks input:
// the C boundary (api/capi.cpp), restart files (io/restart.cpp) and distributed grids
// (mpi/distributed.cpp).
#pragma once

#include <cstdint>
#include <limits>

namespace dpsm {

// The range in which every slope, its square and every cell area stay finite:
// heights and sources within +-kMaxMagnitude, spacings and the mobility within
// [1/kMaxMagnitude, kMaxMagnitude] (so |dh| / d <= 2e100, squared 4e200).
constexpr double kMaxMagnitude = 1e50;

// The largest number of cells we agree to address: every per-cell array must
// fit in memory indices with room to spare.
constexpr std::int64_t kMaxCells = std::numeric_limits<std::int64_t>::max() / 64;

}  // namespace dpsm
