// Restart files (dpsm_save, dpsm_load): a grid's geometry and state in a
// versioned, portable binary format with checksums. The layout is documented
// in docs/guide_restart.md and written by one function, read by another, in
// the same order (io/restart.cpp).
#pragma once

#include <cstdint>

#include "model/grid.hpp"

namespace dpsm {

// The newest format version this library reads. It writes the oldest that
// holds the grid: version 1 for a grid of its own, version 2 (version 1 and a
// block record) for one rank's block of a distributed grid or a grid set to
// DPSM_RELAX_TO_REST, version 3 for a grid left at the default relaxation
// (DPSM_RELAX_AUTO), version 4 for a grid with side levels, sand that left
// through a side, or face fluxes recorded, so that older libraries still
// read every file they could hold.
// Version 5 holds unstructured meshes (the mesh as its constructor got it),
// version 6 meshes whose indices count from 1 (a flag: the mesh record's
// arrays are as a start_index = 1 constructor got them); a mesh from 0 is
// still written as version 5. Version 7 holds a rank's part of a
// distributed mesh (its local cells' global ids and owners).
constexpr std::uint32_t kRestartVersion = 9;

// Where a block file's grid lies in its distributed grid (version 2): its
// place, which of how many ranks saved it, and the mark that all the files
// of one collective save share, so that files of different saves never mix.
struct RestartBlock {
    bool present = false;  // false: a grid of its own
    std::uint64_t save_mark = 0;
    std::int64_t global_nx = 0, global_ny = 0, i0 = 0, j0 = 0;
    std::int32_t rank = 0, ranks = 0;
    // A part of a distributed mesh, as load_restart rebuilt it from the file,
    // not finished (model/mesh_part.hpp, finish_part): the MPI component finishes
    // it with the other ranks. Null otherwise.
    std::shared_ptr<Mesh> part;
};

// Writes the grid to `path` through `path + ".tmp"`, renamed over `path` only
// once complete; with `block`, as that block of a distributed grid. Throws
// Error (DPSM_ERR_IO) naming the path and the reason.
void save_restart(const Grid &grid, const char *path, const char *function, const RestartBlock &block = {});

// The block record of a file that dpsm_save has just written (present =
// false when the file is shorter or holds no block): a distributed save reads
// it back to see that no other rank wrote over the file. Throws Error
// (DPSM_ERR_IO) when the file cannot be read.
RestartBlock written_block(const char *path, const char *function);

// Reads and checks a whole file: on return `geometry` and `state` hold values
// the setters would accept, and `block` says whether the file holds a block
// of a distributed grid and where (checked against its geometry only). Throws
// Error: DPSM_ERR_IO when the file cannot be read, DPSM_ERR_BAD_FILE when its
// contents are wrong in any way.
void load_restart(const char *path, Geometry &geometry, GridState &state, RestartBlock &block, const char *function);

}  // namespace dpsm
