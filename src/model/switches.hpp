// The switches by which tests and benchmarks compare ways of computing the
// same results, all in one place: environment variables set to anything
// but 0 (or, for DPSM_MPI_SUBSTEPS_PER_EXCHANGE, a count). None changes a
// result; none is meant for hosts. docs/architecture.md lists them.
//
// Each is read once where it takes effect: the per-step ones at the start
// of a step's work (so that a test may change them between two steps of one
// process), the mesh's order when a mesh is built, the MPI part's when a
// part is made, the kernels' lanes once per process.
#pragma once

namespace dpsm {

struct Switches {
    // Per step.
    bool visit_all_tiles = false;  // DPSM_VISIT_ALL_TILES: a 2D grid's active set off (every tile whole)
    bool copy_tiles = false;       // DPSM_COPY_TILES: every tile through a buffer (none in place)
    bool scalar_physics = false;   // DPSM_SCALAR_PHYSICS: the scalar reference kernel for scenes with physics
    bool visit_all_cells = false;  // DPSM_VISIT_ALL_CELLS: a mesh's active set off (every cell)
    bool scalar_mesh = false;      // DPSM_SCALAR_MESH: a mesh's dense face pass in FaceLaw::terms alone (no lanes)
    // When a mesh is built.
    bool mesh_host_order = false;  // DPSM_MESH_HOST_ORDER: the host's cell order, not the Hilbert curve's
    // When a part of a distributed mesh is made: at most this many sub-steps
    // per exchange (0: two exchanges in every sub-step); -1: unset.
    int mpi_substeps_per_exchange = -1;  // DPSM_MPI_SUBSTEPS_PER_EXCHANGE
    // Once per process.
    bool no_avx512 = false;  // DPSM_NO_AVX512: no AVX-512 kernels
    bool no_avx2 = false;    // DPSM_NO_AVX2: no AVX2 kernels
};

// Every switch as the environment sets it now.
Switches read_switches();

}  // namespace dpsm
