// dpsm_save on a part of a distributed grid: every rank writes its own part
// to its own path, all with one mark, and every rank fails when any rank did.
#pragma once

namespace dpsm {

class Distribution;
class Grid;

// Collective. A rank whose own path is refused still takes part, so that no
// rank waits for it. Throws Error on every rank alike.
void save_distributed(const Grid &grid, const Distribution &distribution, const char *path, const char *function);

}  // namespace dpsm
