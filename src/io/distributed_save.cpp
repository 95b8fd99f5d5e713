#include "io/distributed_save.hpp"

#include <string>

#include "dpsm/dpsm.h"
#include "io/restart.hpp"
#include "model/distribution.hpp"
#include "model/error.hpp"

namespace dpsm {

void save_distributed(const Grid &grid, const Distribution &distribution, const char *path, const char *function) {
    const DistributedPlace place = distribution.place();
    RestartBlock block;
    block.present = true;
    block.save_mark = distribution.shared_mark();
    block.global_nx = place.global_nx;
    block.global_ny = place.global_ny;
    block.i0 = place.i0;
    block.j0 = place.j0;
    block.rank = distribution.rank();
    block.ranks = distribution.ranks();
    const auto incomplete = [&](const Failure &failure) {
        return std::string(function) + ": rank " + std::to_string(failure.rank) +
               " of the distributed grid could not save its block (" + dpsm_status_string(failure.status) +
               "; its dpsm_last_error says why), so this save is not a complete set of files; this rank's block went "
               "to " + path;
    };
    on_every_rank(
        distribution, function,
        [&] {
            if (!path) fail(DPSM_ERR_NULL_POINTER, function, "path is NULL");
            save_restart(grid, path, function, block);
        },
        incomplete);
    // Once every rank has written, each file must still hold its own block:
    // ranks given the same path on a shared file system write over each other.
    on_every_rank(
        distribution, function,
        [&] {
            const RestartBlock back = written_block(path, function);
            if (!back.present || back.rank != block.rank || back.save_mark != block.save_mark)
                fail(DPSM_ERR_IO, function, path,
                     " no longer holds this rank's block once every rank has saved: another rank saved to the same "
                     "file; give each rank its own path");
        },
        incomplete);
}

}  // namespace dpsm
