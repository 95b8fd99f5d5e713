/**
 * @file dpsm_mpi.h
 * @brief Distributed 2D grids over MPI: the optional MPI component (libdpsm_mpi).
 *
 * A host that runs on many MPI ranks, each owning a rectangular block of the
 * domain, creates one dpsm grid per rank with dpsm_create_2d_mpi(), passing
 * its own communicator and the block the rank owns. The handle it gets back
 * works with every function of dpsm.h:
 *
 *  - heights, sources and cell kinds (dpsm_set_heights(), dpsm_get_heights(),
 *    dpsm_set_source(), dpsm_set_cell_kinds(), the *_region functions,
 *    dpsm_get_shape()) are the rank's block, `nx_local * ny_local` values,
 *    x fastest, region offsets counted from the block's first cell;
 *  - sides (dpsm_set_boundary()) name the sides of the global domain; the
 *    edges between blocks are neither walls nor open;
 *  - side levels (dpsm_set_side_levels()) are the rank's part of a side of
 *    the global domain: `ny_local` values for ::DPSM_XMIN and ::DPSM_XMAX (the
 *    block's rows), `nx_local` for ::DPSM_YMIN and ::DPSM_YMAX (its columns);
 *    a rank whose block does not touch that side may pass any valid values,
 *    which are ignored. The next dpsm_step() assembles each side from the
 *    blocks along it when any rank changed its part;
 *  - face fluxes (dpsm_get_face_fluxes()) are the block's own faces,
 *    `(nx_local+1)*ny_local` x faces and `nx_local*(ny_local+1)` y faces,
 *    both edges of the block included: a face between two blocks is read on
 *    both ranks, with the same value;
 *  - dpsm_step() exchanges the cells along the blocks' edges and takes the same
 *    sub-steps on every rank; its results equal those of one serial grid of
 *    `nx_global * ny_global` cells holding the same scene, bit for bit, for
 *    any decomposition;
 *  - dpsm_get_mass(), dpsm_get_side_outflow() and dpsm_get_step_info()
 *    return global figures, the same on every rank.
 *
 * Collective calls: dpsm_create_2d_mpi(), dpsm_create_2d_mpi_f(), dpsm_step(),
 * dpsm_get_mass(), dpsm_get_side_outflow(), dpsm_save(), dpsm_load_mpi(),
 * dpsm_load_mpi_f() and dpsm_destroy(). Every rank
 * of the communicator must call the collective ones, in the same order, with
 * the same `dt` and the same parameters (repose angle, mobility, scheme, rest
 * tolerance, sub-step limit, sides, flux exponent, static angle) and the same
 * features (a bed on every rank or none, an angle field on every rank or
 * none; their values are the rank's own block); dpsm_step() checks this and
 * fails on every rank alike when they differ. A rank whose own arguments to
 * dpsm_step(), dpsm_get_mass() or dpsm_get_side_outflow() are refused (a `dt`
 * that is not finite or not positive, a NULL `value`, an unknown quantity or
 * side) still takes part, and the call fails on every rank: no rank waits for
 * it. All other calls are local to the rank.
 *
 * Restart files: dpsm_save() on a distributed grid writes each rank's block to
 * the path that rank passes (one file per rank, e.g. `run.0003.dpsm` for rank
 * 3: each rank its own path), and dpsm_load_mpi() reads them back on as many
 * ranks, each rank the file it saved; the run continues bit for bit. The
 * files of one save carry a mark of that save, so that a set mixing files of
 * different saves, ranks or decompositions is refused on every rank.
 *
 * Link with `-ldpsm_mpi` (pkg-config: `dpsm-mpi`; CMake: `dpsm::dpsm_mpi`)
 * instead of `-ldpsm`: libdpsm_mpi holds the whole library. This header
 * includes `mpi.h` and dpsm.h. The user guide's page "Distributed grids over
 * MPI" (docs/guide_mpi.md) shows a C and a Fortran host handing over their
 * communicator and decomposition.
 */
#ifndef DPSM_DPSM_MPI_H
#define DPSM_DPSM_MPI_H

#include <mpi.h>
#include <stdint.h>

#include <dpsm/dpsm.h>

#ifdef __cplusplus
extern "C" {
#endif

/**
 * @brief Creates this rank's block of a 2D grid distributed over @p comm.
 *
 * Collective over @p comm: every rank calls it once, passing the same global
 * size and spacing and the block of cells it owns, `[i0, i0 + nx_local) x
 * [j0, j0 + ny_local)` of the global `nx_global x ny_global` cells (0-based).
 * The blocks may be any rectangles, of any sizes (even narrower than the
 * 5 cells a step reads beyond a block), as long as together they cover the
 * global grid exactly once. The grid keeps a duplicate of @p comm, so its
 * messages never mix with the host's; @p comm may be freed afterwards.
 *
 * The arguments of all ranks are gathered and checked together: when any
 * rank's are wrong (a block outside the grid, two blocks overlapping, cells
 * no block covers, ranks disagreeing on the global size or spacing, a NULL
 * @p out), every rank returns the same error and dpsm_last_error(NULL) names
 * the problem and the ranks concerned; no rank hangs, as long as every rank
 * of @p comm makes the call with a valid communicator.
 *
 * @param comm      the host's communicator (an intracommunicator); MPI must be initialized.
 * @param nx_global cells of the global grid along x, at least 1.
 * @param ny_global cells of the global grid along y, at least 1.
 * @param i0        the block's first column in the global grid, 0-based.
 * @param j0        the block's first row in the global grid, 0-based.
 * @param nx_local  the block's columns, at least 1.
 * @param ny_local  the block's rows, at least 1.
 * @param dx        cell size along x (as dpsm_create_2d()).
 * @param dy        cell size along y.
 * @param out       receives the handle (NULL on failure); release it with dpsm_destroy() on every rank.
 * @return #DPSM_OK; #DPSM_ERR_NULL_POINTER (@p out NULL on some rank),
 *         #DPSM_ERR_INVALID_SIZE (sizes, blocks that do not tile the grid),
 *         #DPSM_ERR_INVALID_VALUE (spacings; MPI not initialized or @p comm
 *         MPI_COMM_NULL), #DPSM_ERR_OUT_OF_MEMORY, #DPSM_ERR_INTERNAL (an MPI call failed).
 */
DPSM_API int dpsm_create_2d_mpi(MPI_Comm comm, int64_t nx_global, int64_t ny_global, int64_t i0, int64_t j0,
                                int64_t nx_local, int64_t ny_local, double dx, double dy, dpsm_grid **out);

/**
 * @brief dpsm_create_2d_mpi() for a Fortran communicator.
 *
 * The same as dpsm_create_2d_mpi(MPI_Comm_f2c(comm), ...): @p comm is the
 * integer handle of a Fortran communicator (`MPI_COMM_WORLD` of `use mpi`, or
 * `comm%MPI_VAL` of `use mpi_f08`). The Fortran module `dpsm_mpi` calls it.
 *
 * @param comm      the Fortran handle of the host's communicator.
 * @param nx_global cells of the global grid along x.
 * @param ny_global cells of the global grid along y.
 * @param i0        the block's first column, 0-based.
 * @param j0        the block's first row, 0-based.
 * @param nx_local  the block's columns.
 * @param ny_local  the block's rows.
 * @param dx        cell size along x.
 * @param dy        cell size along y.
 * @param out       receives the handle (NULL on failure).
 * @return as dpsm_create_2d_mpi().
 */
DPSM_API int dpsm_create_2d_mpi_f(MPI_Fint comm, int64_t nx_global, int64_t ny_global, int64_t i0, int64_t j0,
                                  int64_t nx_local, int64_t ny_local, double dx, double dy, dpsm_grid **out);

/**
 * @brief Loads this rank's block of a distributed grid from a file that
 *        dpsm_save() wrote on a distributed grid.
 *
 * Collective over @p comm: every rank calls it once with the path of the file
 * it saved (the same rank of a communicator of the same size as the one the
 * grid was saved on). Each rank reads and checks its own file as dpsm_load()
 * does; then the ranks check together that their files are the blocks of one
 * save and tile the global grid. The grid made is the one that was saved,
 * block by block, with its parameters, masks, physics, ledger and last step's
 * figures; it continues bit for bit, as the saved grid would have, as long
 * as the host makes the same calls. The grid keeps a duplicate of @p comm.
 *
 * When any rank fails, every rank fails and no grid is made (`*out` is NULL
 * on every rank): the failing rank's dpsm_last_error(NULL) names its file and
 * the problem, the others name the rank that failed and carry its status.
 *
 * @param comm the host's communicator (an intracommunicator of as many ranks
 *             as saved the grid); MPI must be initialized.
 * @param path this rank's file (NUL-terminated).
 * @param out  receives the handle (NULL on failure); release it with dpsm_destroy() on every rank.
 * @return #DPSM_OK; #DPSM_ERR_NULL_POINTER (@p path or @p out NULL on some rank);
 *         #DPSM_ERR_IO (a file cannot be read); #DPSM_ERR_BAD_FILE (a file is
 *         damaged, or the files are of different saves);
 *         #DPSM_ERR_NOT_APPLICABLE (a file holds a grid of its own: see dpsm_load());
 *         #DPSM_ERR_INVALID_SIZE (the grid was saved on another number of ranks);
 *         #DPSM_ERR_INVALID_VALUE (a rank was given another rank's file; MPI
 *         not initialized or @p comm MPI_COMM_NULL); #DPSM_ERR_OUT_OF_MEMORY;
 *         #DPSM_ERR_INTERNAL (an MPI call failed).
 */
DPSM_API int dpsm_load_mpi(MPI_Comm comm, const char *path, dpsm_grid **out);

/**
 * @brief dpsm_load_mpi() for a Fortran communicator.
 *
 * The same as dpsm_load_mpi(MPI_Comm_f2c(comm), path, out); the Fortran module
 * `dpsm_mpi` calls it.
 *
 * @param comm the Fortran handle of the host's communicator.
 * @param path this rank's file (NUL-terminated).
 * @param out  receives the handle (NULL on failure).
 * @return as dpsm_load_mpi().
 */
DPSM_API int dpsm_load_mpi_f(MPI_Fint comm, const char *path, dpsm_grid **out);

/**
 * @name Distributed meshes
 *
 * A host that partitions an unstructured mesh (with METIS, Scotch or its own
 * partitioner) hands each rank's part to dpsm as it holds it: the cells the
 * rank owns and the ghost cells around them that other ranks own, in the
 * host's own local numbering, each with a global id and its owner.
 *
 *  - **Ghosts needed.** Every cell across a face from an owned cell must be on
 *    the rank (one layer of ghosts: a cell's gradient reads the cells across
 *    its faces). Faces between two ghosts may be given or left out: dpsm
 *    learns each ghost's neighbours from its owner.
 *  - **Deeper layers** save exchanges: where a rank holds the ghosts' own
 *    neighbourhoods too, it steps those ghosts itself, exactly as their
 *    owners do, and the ranks exchange once per K sub-steps instead of four
 *    times in every one. dpsm finds K from the layers given (the smallest over the
 *    ranks, at most 8 and at most the sub-steps of a step: every step ends
 *    with an exchange); ::DPSM_INFO_SUBSTEPS_PER_EXCHANGE tells it. A
 *    sub-step reads four faces out, so each sub-step per exchange takes about
 *    four more layers (on METIS and strip parts of triangles 9 layers give
 *    K = 2). A ghost counts only where
 *    all its faces are on the rank, domain edges included (on a graph, give
 *    its edge faces too) and between two ghosts (given or derived from the
 *    polygons). The price: the ghosts in reach are stepped on both ranks
 *    (about 1 % more cell updates on parts of 250,000 triangles with 8
 *    layers) and an exchange sends the heights of the whole deep layer. The
 *    environment variable DPSM_MPI_SUBSTEPS_PER_EXCHANGE, read when a part is
 *    made, caps K (0: exchanges in every sub-step, as with one layer);
 *    the results are the same bit for bit whatever K.
 *  - **Global ids** number all cells of the mesh from 0 (from 1 in the `_f`
 *    constructors), each owned by exactly one rank; `owner[k]` is the rank of
 *    the communicator that owns local cell k (this rank for its own cells).
 *    Inconsistent partitions (a cell owned twice or by no rank, a ghost whose
 *    named owner does not own it, a face one side has and the other has not)
 *    fail on every rank with a message naming the cell.
 *  - **Arrays per cell** of the other functions (heights, sources, kinds,
 *    bed, angles) hold one value per local cell, owned and ghost, in the
 *    host's order. Ghost values must be valid, but are replaced by their
 *    owners' at the next dpsm_step(); after a step, dpsm_get_heights() gives
 *    the owners' values on the ghosts too.
 *  - **Faces** are the rank's (the host's list on a graph; those derived from
 *    the polygons on a mesh, dpsm_get_mesh_faces()): a face between an owned
 *    cell and a ghost is computed on both ranks, with the same flux; faces
 *    between two ghosts, and a ghost's outer edges, carry nothing on this
 *    rank (their fluxes read 0); edge kinds and levels are read on the faces
 *    of owned cells (a ghost stepped here takes its owner's, at the step).
 *  - **Results** equal those of one serial mesh holding all cells, numbered
 *    by their global ids (built with dpsm_create_graph() or
 *    dpsm_create_mesh() with cell k the cell of global id k), bit for bit,
 *    for any partition, any local order and any number of ranks: every sum
 *    over a cell's faces or its gradient's neighbours is taken in the order
 *    of their global ids, as a serial mesh takes it in the order of its cell
 *    numbers (a serial mesh numbered otherwise adds in another order and
 *    differs by round-off). Mass figures and step information are global,
 *    as on distributed 2D grids (their sums over ranks differ from the serial
 *    ones by round-off).
 *  - **Communication:** with one layer of ghosts, each sub-step sends the
 *    neighbouring ranks only the owned cells' gradients, pulls and limiters'
 *    factors (docs/guarantees.md, "Meshes") and, after the update, heights
 *    that changed since they were last sent (one message
 *    per neighbour that has any; a non-blocking barrier tells every rank that
 *    all have arrived), plus one all-reduce of a few numbers; where the
 *    layer allows K sub-steps per exchange (above), one exchange of heights
 *    (and their residuals) per K sub-steps and the all-reduce in each. A rank whose cells near its neighbours are
 *    at rest sends nothing, and one whose cells are all at rest also computes
 *    nothing (its active set is empty): ::DPSM_INFO_RANK_CELL_UPDATES,
 *    ::DPSM_INFO_MESSAGES_SENT and ::DPSM_INFO_BYTES_SENT say what this rank
 *    did in the last step. A new grid, and one whose heights or masks a host
 *    set, looks at every cell once. After a host changed heights, masks,
 *    sources, bed or angles on any rank, the next step sends every ghost's
 *    values whole (neighbourhood all-to-alls over a distributed-graph
 *    communicator). The ghost layer is the host's: dpsm does not deepen it
 *    (a host that wants fewer exchanges hands over more layers).
 *  - **Collective calls** are those of distributed 2D grids; dpsm_save()
 *    writes one restart file per rank and dpsm_load_mpi() links the parts
 *    again.
 * @{
 */

/**
 * @brief Creates this rank's part of a mesh given as a finite-volume graph,
 *        distributed over @p comm.
 *
 * Collective over @p comm. The arguments after @p owner are those of
 * dpsm_create_graph() for the rank's local cells (owned and ghost, indices
 * from 0; `face_cells` pairs of local cells, -1 for the domain edge). Every
 * face of an owned cell must be given, domain edges included; a ghost's faces
 * need not be.
 *
 * @param comm        the host's communicator (an intracommunicator); MPI must be initialized.
 * @param ncells      local cells, owned and ghost, at least 1 (at least one owned).
 * @param global_id   per local cell, its id in the whole mesh, from 0.
 * @param owner       per local cell, the rank of @p comm that owns it.
 * @param cell_xy     per local cell, its centre (x, y).
 * @param cell_area   per local cell, its area.
 * @param nfaces      local faces.
 * @param face_cells  per face, its two local cells a, b (b = -1: the domain edge).
 * @param face_xy     per face, its midpoint.
 * @param face_length per face, its length.
 * @param out         receives the handle (NULL on failure); release it with dpsm_destroy() on every rank.
 * @return #DPSM_OK; the errors of dpsm_create_graph() for this rank's own
 *         arrays; #DPSM_ERR_INVALID_VALUE (inconsistent partitions, too few
 *         ghosts, MPI not initialized); #DPSM_ERR_INVALID_SIZE (a rank owns no
 *         cell); #DPSM_ERR_NULL_POINTER; #DPSM_ERR_OUT_OF_MEMORY;
 *         #DPSM_ERR_INTERNAL (an MPI call failed). Every rank returns the same
 *         status; dpsm_last_error(NULL) names the rank and the cell.
 */
DPSM_API int dpsm_create_graph_mpi(MPI_Comm comm, int64_t ncells, const int64_t *global_id, const int *owner,
                                   const double *cell_xy, const double *cell_area, int64_t nfaces,
                                   const int64_t *face_cells, const double *face_xy, const double *face_length,
                                   dpsm_grid **out);

/**
 * @brief dpsm_create_graph_mpi() for a Fortran host: a Fortran communicator,
 *        indices and global ids from 1.
 *
 * @p comm is the integer handle of a Fortran communicator; `face_cells` holds
 * local cells from 1 (0 for the domain edge) and `global_id` counts from 1,
 * as the Fortran module `dpsm_mpi` passes them; messages count from 1 too.
 *
 * @param comm        the Fortran handle of the host's communicator.
 * @param ncells      local cells.
 * @param global_id   per local cell, its id in the whole mesh, from 1.
 * @param owner       per local cell, its owner's rank (from 0, as MPI counts).
 * @param cell_xy     per local cell, its centre.
 * @param cell_area   per local cell, its area.
 * @param nfaces      local faces.
 * @param face_cells  per face, its two local cells from 1 (0: the domain edge).
 * @param face_xy     per face, its midpoint.
 * @param face_length per face, its length.
 * @param out         receives the handle (NULL on failure).
 * @return as dpsm_create_graph_mpi().
 */
DPSM_API int dpsm_create_graph_mpi_f(MPI_Fint comm, int64_t ncells, const int64_t *global_id, const int *owner,
                                     const double *cell_xy, const double *cell_area, int64_t nfaces,
                                     const int64_t *face_cells, const double *face_xy, const double *face_length,
                                     dpsm_grid **out);

/**
 * @brief Creates this rank's part of a mesh given as polygons over nodes,
 *        distributed over @p comm.
 *
 * Collective over @p comm. The arguments before @p global_id are those of
 * dpsm_create_mesh() for the rank's local cells (owned and ghost) over its
 * local nodes (indices from 0); two local cells share a face where they share
 * an edge. An edge of an owned cell that no other local cell shares lies on
 * the domain edge.
 *
 * @param comm       the host's communicator (an intracommunicator); MPI must be initialized.
 * @param nnodes     local nodes.
 * @param node_xy    per node, (x, y).
 * @param ncells     local cells, owned and ghost (at least one owned).
 * @param cell_start ncells + 1 offsets into @p cell_nodes.
 * @param cell_nodes each cell's nodes in order around it.
 * @param global_id  per local cell, its id in the whole mesh, from 0.
 * @param owner      per local cell, the rank of @p comm that owns it.
 * @param out        receives the handle (NULL on failure); release it with dpsm_destroy() on every rank.
 * @return as dpsm_create_graph_mpi().
 */
DPSM_API int dpsm_create_mesh_mpi(MPI_Comm comm, int64_t nnodes, const double *node_xy, int64_t ncells,
                                  const int64_t *cell_start, const int64_t *cell_nodes, const int64_t *global_id,
                                  const int *owner, dpsm_grid **out);

/**
 * @brief dpsm_create_mesh_mpi() for a Fortran host: a Fortran communicator,
 *        indices and global ids from 1.
 *
 * @param comm       the Fortran handle of the host's communicator.
 * @param nnodes     local nodes.
 * @param node_xy    per node, (x, y).
 * @param ncells     local cells.
 * @param cell_start ncells + 1 offsets from 1 (`cell_start(1) = 1`).
 * @param cell_nodes each cell's nodes, from 1.
 * @param global_id  per local cell, its id in the whole mesh, from 1.
 * @param owner      per local cell, its owner's rank (from 0, as MPI counts).
 * @param out        receives the handle (NULL on failure).
 * @return as dpsm_create_graph_mpi().
 */
DPSM_API int dpsm_create_mesh_mpi_f(MPI_Fint comm, int64_t nnodes, const double *node_xy, int64_t ncells,
                                    const int64_t *cell_start, const int64_t *cell_nodes, const int64_t *global_id,
                                    const int *owner, dpsm_grid **out);

/** @} */

#ifdef __cplusplus
}
#endif

#endif /* DPSM_DPSM_MPI_H */
