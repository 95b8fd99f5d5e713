/**
 * @file dpsm.h
 * @brief The public C API of dpsm: granular surfaces moved by the Degenerate
 *        Parabolic Sliding Model.
 *
 * A host creates a grid, sets its parameters, masks and sources, calls
 * dpsm_step() once per time step, reads heights back and checks the mass
 * balance. Everything here is plain C; C++ callers get `extern "C"`.
 *
 * Conventions:
 * - Every function that can fail returns an `int` status: ::DPSM_OK (0) on
 *   success, one of the other `DPSM_ERR_*` codes otherwise. A failed call leaves
 *   the grid exactly as it was; dpsm_last_error() tells what went wrong.
 * - Arrays hold `nx*ny` values (`nx` for a 1D grid), x fastest: cell `(i, j)`
 *   is element `i + nx*j`, so a Fortran `h(nx, ny)` and a C `h[ny][nx]` match.
 * - Sizes are `int64_t`; angles are in radians; heights, lengths and times are
 *   in whatever consistent units the host uses.
 * - The supported range, in which every slope, its square and every mass stay
 *   finite: heights and sources within [-1e50, 1e50]; cell sizes and the
 *   mobility within [1e-50, 1e50]. Values outside it are refused with
 *   ::DPSM_ERR_INVALID_VALUE.
 * - A handle may be used by one thread at a time; any number of handles may be
 *   used concurrently.
 */
#ifndef DPSM_DPSM_H
#define DPSM_DPSM_H

#include <stdint.h>

#include <dpsm/dpsm_version.h>

/** @cond INTERNAL */
#if defined(_WIN32) && !defined(DPSM_STATIC_DEFINE)
#  ifdef DPSM_BUILDING_LIBRARY
#    define DPSM_API __declspec(dllexport)
#  else
#    define DPSM_API __declspec(dllimport)
#  endif
#elif defined(__GNUC__)
#  define DPSM_API __attribute__((visibility("default")))
#else
#  define DPSM_API
#endif
/** @endcond */

#ifdef __cplusplus
extern "C" {
#endif

/**
 * @brief An opaque grid: geometry, parameters, masks, sources, heights and the
 *        mass ledger of one granular surface.
 *
 * Created by dpsm_create_1d() or dpsm_create_2d(), released by dpsm_destroy().
 */
typedef struct dpsm_grid dpsm_grid;

/** @name Status codes
 *  Returned by every function that can fail. @{ */
/** Success. */
#define DPSM_OK 0
/** A required pointer argument (handle, array or output) was NULL. */
#define DPSM_ERR_NULL_POINTER 1
/** A value was out of range: NaN, infinite, non-positive where a positive value is needed, an angle outside (0, pi/2). */
#define DPSM_ERR_INVALID_VALUE 2
/** A size was zero, negative, or so large that the grid cannot be addressed. */
#define DPSM_ERR_INVALID_SIZE 3
/** An enumerated argument (side, boundary kind, cell kind, mass quantity, info item) is not one this library knows. */
#define DPSM_ERR_UNKNOWN_ENUM 4
/** The request does not apply to this grid (for example a y side of a 1D grid). */
#define DPSM_ERR_NOT_APPLICABLE 5
/** The step would need more sub-steps than the limit set with dpsm_set_max_substeps(). */
#define DPSM_ERR_WORK_LIMIT 6
/** Memory could not be allocated. */
#define DPSM_ERR_OUT_OF_MEMORY 7
/** An internal error; please report it. */
#define DPSM_ERR_INTERNAL 8
/** A file could not be opened, read or written (dpsm_save(), dpsm_load()). */
#define DPSM_ERR_IO 9
/** A file is not a complete, intact dpsm restart file of a version this
 *  library reads: truncated, corrupted (checksum mismatch), or of another format. */
#define DPSM_ERR_BAD_FILE 10
/** @} */

/** @name Sides of the domain
 *  For dpsm_set_boundary(). A 1D grid has only ::DPSM_XMIN and ::DPSM_XMAX. @{ */
#define DPSM_XMIN 0 /**< The side at x = 0. */
#define DPSM_XMAX 1 /**< The side at x = nx*dx. */
#define DPSM_YMIN 2 /**< The side at y = 0 (2D only). */
#define DPSM_YMAX 3 /**< The side at y = ny*dy (2D only). */
/** Every domain edge of a mesh at once (meshes only; dpsm_set_edge_kinds()
 *  sets them face by face). */
#define DPSM_MESH_EDGE 4
/** @} */

/** @name Grid kinds
 *  What dpsm_get_grid_kind() says a grid is: the constructor that made it
 *  (through dpsm_load(), the one that made the grid saved). None is 0. @{ */
#define DPSM_GRID_1D 1           /**< dpsm_create_1d(): a line of nx cells. */
#define DPSM_GRID_AXISYMMETRIC 2 /**< dpsm_create_axisymmetric(): nr rings about an axis. */
#define DPSM_GRID_2D 3           /**< dpsm_create_2d(): nx by ny cells. */
/** dpsm_create_mesh(), dpsm_create_graph(), dpsm_create_dual_mesh() (and
 *  their _indexed forms): an unstructured mesh of ncells cells. */
#define DPSM_GRID_MESH 4
/** @} */

/** @name Boundary kinds
 *  For dpsm_set_boundary(). @{ */
/** Sand that reaches the side leaves the domain and is counted as outflow.
 *  The outside acts as a cell held at a level one cell width beyond the edge
 *  cell: 0 (the paper's node held at h = 0) unless dpsm_set_side_levels()
 *  sets another; sand flows in from a higher outside level as it flows out
 *  to a lower one. */
#define DPSM_OPEN 0
/** No flux crosses the side. The default for every side. */
#define DPSM_WALL 1
/** @} */

/** @name Schemes
 *  For dpsm_set_scheme(): how a face's slope is measured. @{ */
/** The paper's pairwise exchange (its Eq. 12): the slope of a face is the
 *  height difference of its two cells over their distance. It limits the slope
 *  along each grid axis, not |grad h|, so in 2D it builds pyramids where sand
 *  builds cones and does not converge to the exact deposit. Kept to reproduce
 *  the paper. */
#define DPSM_SCHEME_PAIRWISE 0
/** A flux-form scheme on the full gradient: each face adds to its normal
 *  difference the transverse slope (the mean of its two cells' central
 *  differences across it), so the flux law acts on |grad h| and deposits
 *  converge to the exact ones under refinement. The default in 2D. */
#define DPSM_SCHEME_ISOTROPIC 1
/** @} */

/** @name Relaxations
 *  For dpsm_set_relaxation(): how dpsm_step() moves the surface. @{ */
/** Explicit sub-steps, each stable and time accurate, to the end of `dt` or
 *  to rest: the model's time advances by `dt`. */
#define DPSM_RELAX_TIME_ACCURATE 0
/** To rest in each dpsm_step(), in few flux evaluations, without a time
 *  scale, as dune models treat avalanches (instantaneous); refused on
 *  scenes it does not support. A host's explicit choice: it does not keep
 *  the flow's time. */
#define DPSM_RELAX_TO_REST 1
/** The default: the time-accurate steps of ::DPSM_RELAX_TIME_ACCURATE (the
 *  model's time advances by `dt`), by whatever integrator this version
 *  finds fastest among those that land within 1e-3 of them; in this version
 *  they themselves. */
#define DPSM_RELAX_AUTO 2
/** Time-accurate sub-steps, each cell of a mesh at the pace of its own
 *  stable bound (local time steps in power-of-two classes): the model's time
 *  advances by `dt`, mass is exact and no new extremum appears, but the
 *  large cells' sub-steps are not those of ::DPSM_RELAX_TIME_ACCURATE, so the
 *  heights differ from its by their own time error. A host's explicit
 *  choice; on a grid the same as ::DPSM_RELAX_TIME_ACCURATE. On a distributed
 *  mesh the parts exchange in every tick and step bit for bit as the serial
 *  mesh does. */
#define DPSM_RELAX_LOCAL_STEPS 3
/** @} */

/** @name Cell kinds
 *  For dpsm_set_cell_kinds(). @{ */
/** An ordinary cell whose height the model evolves. The default. */
#define DPSM_CELL_SAND 0
/** An obstacle: no flux crosses its faces and its height never changes. */
#define DPSM_CELL_WALL 1
/** A sink held at its height: sand that flows into it is counted as outflow
 *  (and sand it feeds to a lower neighbour as negative outflow). */
#define DPSM_CELL_OPEN 2
/** @} */

/** @name Mass quantities
 *  For dpsm_get_mass(). Mass is `sum h*dx` in 1D and `sum h*dx*dy` in 2D over
 *  sand cells (unit density). After any sequence of calls,
 *  `TOTAL == SOURCED + EXTERNAL - OUTFLOW` to round-off. Heights count from
 *  the same datum as a bed (dpsm_set_bedrock()), so the sand above a bed is
 *  `TOTAL - sum zb*dx*dy`. @{ */
/** The mass on the grid now. */
#define DPSM_MASS_TOTAL 0
/** Net mass added by sources (negative where erosion dominated). */
#define DPSM_MASS_SOURCED 1
/** Net mass added or removed by the host: dpsm_set_heights() and the other
 *  height setters, a bed set above the sand (dpsm_set_bedrock() lifts it),
 *  and cell-kind changes that turn sand cells into wall or open cells or back. */
#define DPSM_MASS_EXTERNAL 2
/** Net mass that left through open sides and open cells (negative where
 *  more came in than left); dpsm_get_side_outflow() tells each side's part. */
#define DPSM_MASS_OUTFLOW 3
/** Erosion that found no sand above the bed (see dpsm_set_bedrock()) and was
 *  therefore not applied: the mass a host should give back to its flow. Never
 *  negative. ::DPSM_MASS_SOURCED counts only what was applied, so the source
 *  the host asked for is `SOURCED - UNMET`. */
#define DPSM_MASS_UNMET 4
/** @} */

/** @name Step information
 *  For dpsm_get_step_info(): what the last successful dpsm_step() did. @{ */
/** The number of sub-steps it took. */
#define DPSM_INFO_SUBSTEPS 0
/** The simulated time it integrated: the requested `dt` when sand moved to
 *  its end or a source acted (a source acts over all of `dt`, in closed form
 *  where it cannot make a face steep), else the time until the surface came
 *  to rest; 0 after a relaxation to rest (::DPSM_RELAX_TO_REST), which
 *  integrates no time. */
#define DPSM_INFO_TIME_INTEGRATED 1
/** 1 if it stopped because it found no sand sliding (or had nothing to do),
 *  0 if sand slid to the end of `dt`; a surface that came to rest in the last
 *  sub-step reads 0 here, and the next step returns at once with 1. A source
 *  that cannot make a face steep does not keep a surface from rest: its
 *  heights still grow by `q dt`. */
#define DPSM_INFO_AT_REST 2
/** The largest slope excess `|grad h| - tan(theta)` over the faces that
 *  carried sand in its last sub-step, measured at the start of that sub-step:
 *  how far from rest the surface still was. 0 when the step found the surface
 *  at rest, since then no face carried sand (a face steep only across its
 *  normal, or held by hysteresis or a bare bed, carries none). */
#define DPSM_INFO_MAX_EXCESS_SLOPE 3
/** The cell updates it computed: cells visited times sub-steps. On 2D grids
 *  only the tiles of 64 x 64 cells near moving sand or a source are visited, so
 *  this measures what the step cost (a step at rest computes none). */
#define DPSM_INFO_CELL_UPDATES 4
/** This rank's part of ::DPSM_INFO_CELL_UPDATES on a distributed grid (the
 *  other items are global): a rank whose cells are all at rest computes none.
 *  On a serial grid the same as ::DPSM_INFO_CELL_UPDATES. */
#define DPSM_INFO_RANK_CELL_UPDATES 5
/** The point-to-point messages of ghost cells' values this rank sent to
 *  other ranks in the step (dpsm_mpi.h); the all-reductions by which the
 *  ranks agree are not counted. A rank of a distributed mesh sends only the
 *  values that changed, so one whose cells near its neighbours are at rest
 *  sends none. 0 on a serial grid. */
#define DPSM_INFO_MESSAGES_SENT 6
/** The bytes of those messages. 0 on a serial grid. */
#define DPSM_INFO_BYTES_SENT 7
/** The sub-steps a rank takes between two exchanges of ghost values with
 *  its neighbours: 1 on a distributed 2D grid (its halo in every sub-step);
 *  on a distributed mesh as many as the host's ghost layer allows
 *  (dpsm_mpi.h, "Ghosts needed"), or 0.5 where it allows less than one (an
 *  exchange of gradients and one of heights in every sub-step). The same on
 *  every rank; 0 on a serial grid. */
#define DPSM_INFO_SUBSTEPS_PER_EXCHANGE 8
/** The sub-steps at which it evaluated any face's flux. With local time
 *  steps (::DPSM_RELAX_LOCAL_STEPS) ::DPSM_INFO_SUBSTEPS counts the sub-steps
 *  of the smallest class of cells, and this those at which a class near
 *  moving sand was due: the ticks it passed over cost nothing. Otherwise the
 *  same as ::DPSM_INFO_SUBSTEPS (and so after dpsm_load()). */
#define DPSM_INFO_SUBSTEPS_EVALUATED 9
/** @} */

/** The default angle of repose: 30 degrees, in radians. */
#define DPSM_DEFAULT_REPOSE_ANGLE 0.52359877559829887
/** The default mobility `nu`. */
#define DPSM_DEFAULT_MOBILITY 1.0
/** The default rest tolerance (relative to tan(theta)); see dpsm_set_rest_tolerance(). */
#define DPSM_DEFAULT_REST_TOLERANCE 1e-6
/** The default limit on sub-steps per dpsm_step() of a driven scene; see dpsm_set_max_substeps(). */
#define DPSM_DEFAULT_MAX_SUBSTEPS 10000000
/** The default flux exponent: the paper's law, linear in the excess slope; see dpsm_set_flux_exponent(). */
#define DPSM_DEFAULT_FLUX_EXPONENT 1.0
/** The largest flux exponent accepted by dpsm_set_flux_exponent(). */
#define DPSM_MAX_FLUX_EXPONENT 2.0

/**
 * @brief Creates a 1D grid of `nx` cells of width `dx`.
 *
 * The new grid has all heights 0, both sides walls, every cell sand, no source,
 * the angle of repose ::DPSM_DEFAULT_REPOSE_ANGLE and mobility ::DPSM_DEFAULT_MOBILITY.
 *
 * @param nx  number of cells, at least 1.
 * @param dx  cell width, finite and positive.
 * @param out receives the new grid, or NULL on failure.
 * @return ::DPSM_OK, or ::DPSM_ERR_NULL_POINTER, ::DPSM_ERR_INVALID_SIZE,
 *         ::DPSM_ERR_INVALID_VALUE, ::DPSM_ERR_OUT_OF_MEMORY. On failure the
 *         message is read with `dpsm_last_error(NULL)`.
 */
DPSM_API int dpsm_create_1d(int64_t nx, double dx, dpsm_grid **out);

/**
 * @brief Creates a 2D grid of `nx` by `ny` cells of size `dx` by `dy`.
 *
 * Defaults as for dpsm_create_1d(); all four sides are walls.
 *
 * @param nx  number of cells along x, at least 1.
 * @param ny  number of cells along y, at least 1.
 * @param dx  cell size along x, finite and positive.
 * @param dy  cell size along y, finite and positive.
 * @param out receives the new grid, or NULL on failure.
 * @return ::DPSM_OK, or ::DPSM_ERR_NULL_POINTER, ::DPSM_ERR_INVALID_SIZE (also
 *         when `nx*ny` overflows), ::DPSM_ERR_INVALID_VALUE,
 *         ::DPSM_ERR_OUT_OF_MEMORY. On failure the message is read with
 *         `dpsm_last_error(NULL)`.
 */
DPSM_API int dpsm_create_2d(int64_t nx, int64_t ny, double dx, double dy, dpsm_grid **out);

/**
 * @brief Creates an axisymmetric grid of `nr` rings of width `dr`.
 *
 * Cell `i` spans radii `[i*dr, (i+1)*dr]`; heights are `h(r)` of a surface of
 * revolution. The axis (::DPSM_XMIN) is a symmetry line, not a boundary; the
 * outer side ::DPSM_XMAX is a wall by default and may be made open. Mass is the
 * volume `sum h * 2 pi r_i dr` with `r_i = (i + 1/2) dr`. Otherwise it behaves
 * like a 1D grid (arrays of `nr` values, no y sides).
 *
 * @param nr  number of rings, at least 1.
 * @param dr  ring width, finite and positive.
 * @param out receives the new grid, or NULL on failure.
 * @return as dpsm_create_1d().
 */
DPSM_API int dpsm_create_axisymmetric(int64_t nr, double dr, dpsm_grid **out);

/**
 * @brief Creates a mesh of polygonal cells over shared nodes (UGRID's
 *        `face_node_connectivity` in CSR form).
 *
 * Cell `c` has the nodes `cell_nodes[cell_start[c] .. cell_start[c+1]-1]`,
 * in either orientation. An edge of two cells is a face between them; an
 * edge of one cell is a domain edge (a wall by default: see
 * dpsm_set_boundary() with ::DPSM_MESH_EDGE and dpsm_set_edge_kinds()).
 * Every array of the other functions then holds one value per cell, in this
 * cell order; dpsm_get_shape() gives `(ncells, 1)`. The faces are numbered
 * as they first appear, cell by cell, edge by edge in each cell's node
 * order; dpsm_get_mesh_faces() lists their cells. The library renumbers
 * cells inside for memory locality; the host never sees it. Indices count
 * from 0 here and in the messages; dpsm_create_mesh_indexed() takes them
 * from 1, as a Fortran host or a UGRID file with `start_index = 1` holds them.
 *
 * A face's slope is the two-point difference between its cells' centroids
 * plus the part across it of their least-squares gradients (see
 * `docs/guarantees.md`, "Meshes").
 *
 * @param nnodes      number of nodes, at least 1.
 * @param node_xy     `2*nnodes` coordinates (x, y), finite.
 * @param ncells      number of cells, at least 1.
 * @param cell_start  `ncells+1` offsets into `cell_nodes`, `cell_start[0] == 0`,
 *                    at least 3 nodes per cell.
 * @param cell_nodes  node indices, from 0.
 * @param out         receives the new mesh, or NULL on failure.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER, ::DPSM_ERR_INVALID_SIZE,
 *         ::DPSM_ERR_INVALID_VALUE (the message names the cell, node or edge:
 *         an index out of range, fewer than 3 distinct nodes, zero area, an
 *         edge of three or more cells, non-finite coordinates, two nodes of
 *         the cells at the same point: their edges would not join, and sand
 *         could leave through an open edge in the middle of the domain) or
 *         ::DPSM_ERR_OUT_OF_MEMORY; read the message with `dpsm_last_error(NULL)`.
 */
DPSM_API int dpsm_create_mesh(int64_t nnodes, const double *node_xy, int64_t ncells, const int64_t *cell_start,
                              const int64_t *cell_nodes, dpsm_grid **out);

/**
 * @brief Creates a mesh from cells as a finite-volume graph, as a host holds
 *        it (Delft3D FM's links, lengths and areas; OpenFOAM's owner and
 *        neighbour, centres and face areas).
 *
 * Face `f` joins cells `face_cells[2f]` and `face_cells[2f+1]`, or lies on
 * the domain edge when the second is -1. Faces are taken as orthogonal to the
 * line between their cells' centres (as these codes' meshes are built); on
 * the domain edge the outside is the cell's mirror image across the face
 * midpoint. Arrays of the other functions hold one value per cell, faces
 * keep the host's order. Indices count from 0; dpsm_create_graph_indexed()
 * takes them from 1.
 *
 * A cell's centre may lie on the midpoint of one of its domain-edge faces:
 * that is the circumcentre of a right triangle, which Delft3D FM writes as
 * `mesh2d_face_x/y`. That face's outward normal is then taken towards the
 * gap the cell's two other faces leave, and the distance across it as
 * twice the one from the face to the triangle's centroid (`4 area / (3
 * length)`), instead of the zero between the centre and the face; on a face
 * between two cells the direction is the one towards the other cell's
 * centre. A centre on the midpoint of a domain-edge face of a cell that is
 * not a triangle is refused.
 *
 * @param ncells       number of cells, at least 1.
 * @param cell_xy      `2*ncells` centres.
 * @param cell_area    `ncells` positive areas.
 * @param nfaces       number of faces, at least 1.
 * @param face_cells   `2*nfaces` cell indices (a, b), b == -1 on the domain edge.
 * @param face_xy      `2*nfaces` face midpoints.
 * @param face_length  `nfaces` positive lengths.
 * @param out          receives the new mesh, or NULL on failure.
 * @return as dpsm_create_mesh(); also ::DPSM_ERR_INVALID_VALUE for a face
 *         whose cells coincide and for a cell whose faces do not close it
 *         (their midpoints leave half a turn or more around its centre: the
 *         message gives the cell, its faces and the directions, counter-
 *         clockwise from +x, between which a face is missing).
 */
DPSM_API int dpsm_create_graph(int64_t ncells, const double *cell_xy, const double *cell_area, int64_t nfaces,
                               const int64_t *face_cells, const double *face_xy, const double *face_length,
                               dpsm_grid **out);

/**
 * @brief Creates the median dual of a triangle mesh: one cell around each
 *        node, for hosts whose bed lives at the nodes (TELEMAC).
 *
 * Node `n`'s cell is bounded by the segments from the midpoints of its edges
 * to the centroids of its triangles; its area is a third of theirs. Heights,
 * sources and kinds are per node. The faces are the triangle edges, in order
 * of their node pair (lower node first), then the halves of the boundary
 * edges on the domain edge, in the same order, the lower node's half first.
 * Indices count from 0; dpsm_create_dual_mesh_indexed() takes them from 1.
 *
 * @param nnodes          number of nodes, at least 1; every node in some triangle.
 * @param node_xy         `2*nnodes` coordinates.
 * @param ntriangles      number of triangles, at least 1.
 * @param triangle_nodes  `3*ntriangles` node indices, from 0.
 * @param out             receives the new mesh, or NULL on failure.
 * @return as dpsm_create_mesh().
 */
DPSM_API int dpsm_create_dual_mesh(int64_t nnodes, const double *node_xy, int64_t ntriangles,
                                   const int64_t *triangle_nodes, dpsm_grid **out);

/**
 * @brief As dpsm_create_mesh(), with the index arrays counting from
 *        `start_index`: 0 as in C, or 1 as in Fortran (UGRID's
 *        `start_index` attribute).
 *
 * With `start_index` s, `cell_start[0] == s` and the offsets count from s:
 * the cell at C position `c` of `cell_start` (the host's cell `c + s`) has
 * the nodes `cell_nodes[cell_start[c] - s .. cell_start[c+1] - 1 - s]` (C
 * positions), and the node indices in `cell_nodes` count from s. A Fortran
 * host passes its own arrays: `cell_start(ncells+1)` from 1, cell `c` the
 * nodes `cell_nodes(cell_start(c) : cell_start(c+1)-1)`.
 *
 * The mesh remembers s: every message of this call and of later calls that
 * names a cell, node or face of the mesh counts from s and quotes the values
 * as the host gave them (a node index 10 on 9 nodes, from 1: "= 10 is not a
 * node index in [1, 9]"); with s = 1 array positions read as Fortran writes
 * them, `cell_nodes(5)`, `node_xy(2, 4)` (C: `cell_nodes[4]`, `node_xy[7]`).
 * dpsm_get_mesh_faces() returns cells from s, s - 1 on the domain edge, and
 * dpsm_save() keeps s with the mesh. Everything else is as
 * dpsm_create_mesh(), which is this function with s = 0 (its messages name
 * dpsm_create_mesh, these dpsm_create_mesh_indexed).
 *
 * @param start_index where the indices count from: 0 or 1.
 * @param nnodes      number of nodes, at least 1.
 * @param node_xy     `2*nnodes` coordinates (x, y), finite.
 * @param ncells      number of cells, at least 1.
 * @param cell_start  `ncells+1` offsets into `cell_nodes`, counting from
 *                    `start_index` (`cell_start[0] == start_index`), at least
 *                    3 nodes per cell.
 * @param cell_nodes  node indices, from `start_index`.
 * @param out         receives the new mesh, or NULL on failure.
 * @return as dpsm_create_mesh(); also ::DPSM_ERR_INVALID_VALUE for a
 *         `start_index` other than 0 and 1 (the message names the value and
 *         the two allowed).
 */
DPSM_API int dpsm_create_mesh_indexed(int start_index, int64_t nnodes, const double *node_xy, int64_t ncells,
                                      const int64_t *cell_start, const int64_t *cell_nodes, dpsm_grid **out);

/**
 * @brief As dpsm_create_graph(), with the index arrays counting from
 *        `start_index`: 0 as in C, or 1 as in Fortran.
 *
 * With `start_index` s, the cells in `face_cells` count from s and the domain
 * edge is s - 1 (-1 from 0, 0 from 1): a Fortran host passes its own
 * `face_cells(2, nfaces)`. The mesh remembers s, as
 * dpsm_create_mesh_indexed() says: messages name cells and faces from s with
 * the host's values, dpsm_get_mesh_faces() returns cells from s and s - 1 on
 * the domain edge. dpsm_create_graph() is this function with s = 0.
 *
 * @param start_index  where the indices count from: 0 or 1.
 * @param ncells       number of cells, at least 1.
 * @param cell_xy      `2*ncells` centres.
 * @param cell_area    `ncells` positive areas.
 * @param nfaces       number of faces, at least 1.
 * @param face_cells   `2*nfaces` cell indices (a, b) from `start_index`;
 *                     b == `start_index - 1` on the domain edge.
 * @param face_xy      `2*nfaces` face midpoints.
 * @param face_length  `nfaces` positive lengths.
 * @param out          receives the new mesh, or NULL on failure.
 * @return as dpsm_create_graph(); also ::DPSM_ERR_INVALID_VALUE for a
 *         `start_index` other than 0 and 1.
 */
DPSM_API int dpsm_create_graph_indexed(int start_index, int64_t ncells, const double *cell_xy, const double *cell_area,
                                       int64_t nfaces, const int64_t *face_cells, const double *face_xy,
                                       const double *face_length, dpsm_grid **out);

/**
 * @brief As dpsm_create_dual_mesh(), with the node indices counting from
 *        `start_index`: 0 as in C, or 1 as in Fortran (TELEMAC's IKLE).
 *
 * With `start_index` s, `triangle_nodes` holds node indices from s (a Fortran
 * host passes its own `triangle_nodes(3, ntriangles)`); node `n` of the host
 * is the mesh's cell `n`, so cells count from s too. The mesh remembers s, as
 * dpsm_create_mesh_indexed() says. dpsm_create_dual_mesh() is this function
 * with s = 0.
 *
 * @param start_index     where the indices count from: 0 or 1.
 * @param nnodes          number of nodes, at least 1; every node in some triangle.
 * @param node_xy         `2*nnodes` coordinates.
 * @param ntriangles      number of triangles, at least 1.
 * @param triangle_nodes  `3*ntriangles` node indices, from `start_index`.
 * @param out             receives the new mesh, or NULL on failure.
 * @return as dpsm_create_mesh_indexed().
 */
DPSM_API int dpsm_create_dual_mesh_indexed(int start_index, int64_t nnodes, const double *node_xy, int64_t ntriangles,
                                           const int64_t *triangle_nodes, dpsm_grid **out);

/**
 * @brief As dpsm_create_mesh_indexed(), with the nodes in longitude and
 *        latitude (degrees): a mesh on the sphere, as coastal models (ADCIRC,
 *        Delft3D FM's spherical models) hold it.
 *
 * Degrees are never taken as metres: every length, distance and area the
 * model uses is taken on a sphere of radius 6371008.8 m (the Earth's mean
 * radius): cell areas are those of the spherical polygons with great-circle
 * edges, face lengths and the distances between cell centres are
 * great-circle lengths, centroids are those of the spherical polygons, and
 * each cell's least-squares gradient is taken over its neighbours' offsets
 * as seen from it on the sphere. Directions (a face's normal and tangent)
 * come from the stereographic projection about the nodes' mean direction,
 * which keeps angles; the chords it draws turn them by about `d r / (4 R^2)`
 * for cells `d` apart at `r` from that centre (2e-5 radians for 1 km cells
 * 2800 km away). The mesh must lie within 90 degrees of arc of the centre. Heights stay in metres; dpsm_get_cell_centres() gives the
 * centres in degrees and the areas in square metres, dpsm_stable_dt() and
 * the ledger (square metres times metres) follow the sphere.
 *
 * Everything else, the start index included, is as dpsm_create_mesh_indexed();
 * a mesh made by this function is saved and loaded as one (restart format
 * version 8).
 *
 * @param start_index  where the indices count from: 0 or 1.
 * @param nnodes       number of nodes, at least 1.
 * @param node_lonlat  `2*nnodes` values: the longitude (within [-540, 540])
 *                     and latitude (within [-90, 90]) of each node, degrees.
 * @param ncells       number of cells, at least 1.
 * @param cell_start   `ncells+1` offsets into `cell_nodes`, from `start_index`.
 * @param cell_nodes   node indices, from `start_index`.
 * @param out          receives the new mesh, or NULL on failure.
 * @return as dpsm_create_mesh_indexed(); also ::DPSM_ERR_INVALID_VALUE for a
 *         latitude or longitude out of range and for a mesh that reaches more
 *         than 90 degrees of arc from its centre (the message names the node).
 */
DPSM_API int dpsm_create_mesh_geographic(int start_index, int64_t nnodes, const double *node_lonlat, int64_t ncells,
                                         const int64_t *cell_start, const int64_t *cell_nodes, dpsm_grid **out);

/**
 * @brief As dpsm_create_dual_mesh_indexed(), with the nodes in longitude and
 *        latitude (degrees): the median dual of a triangle mesh on the sphere.
 *
 * Lengths, distances and areas are on the sphere, as
 * dpsm_create_mesh_geographic() says: each triangle gives a third of its
 * spherical area to each of its nodes' cells, and the dual's faces (from an
 * edge's midpoint to a triangle's centroid, both taken in the projection's
 * plane) are measured along great circles.
 *
 * @param start_index     where the indices count from: 0 or 1.
 * @param nnodes          number of nodes, at least 1; every node in some triangle.
 * @param node_lonlat     `2*nnodes` values: longitude and latitude of each node, degrees.
 * @param ntriangles      number of triangles, at least 1.
 * @param triangle_nodes  `3*ntriangles` node indices, from `start_index`.
 * @param out             receives the new mesh, or NULL on failure.
 * @return as dpsm_create_mesh_geographic().
 */
DPSM_API int dpsm_create_dual_mesh_geographic(int start_index, int64_t nnodes, const double *node_lonlat,
                                              int64_t ntriangles, const int64_t *triangle_nodes, dpsm_grid **out);

/**
 * @brief Reads where each cell's height stands and the area that turns it
 *        into a volume: what a host needs to place heights on the cells.
 *
 * On a mesh of polygons the centre is the polygon's centroid; on a graph,
 * the centre the host gave; on a median dual, the node. On a geographic mesh
 * (dpsm_create_mesh_geographic()) centres are longitude and latitude in
 * degrees and areas square metres on the sphere. On a 2D grid cell `(i, j)`
 * is centred at `((i + 1/2) dx, (j + 1/2) dy)` with area `dx dy`; on a 1D grid
 * at `((i + 1/2) dx, 0)` with `dx`; on an axisymmetric grid at radius
 * `(i + 1/2) dr` with the ring's area `2 pi r dr`: the weights of the mass
 * ledger. A block of a distributed grid counts from its own first cell (add
 * `i0 dx`, `j0 dy` for the global position); a part of a distributed mesh
 * gives every local cell, its ghosts included.
 *
 * @param g          the grid or mesh.
 * @param cell_xy    room for `2*ncells` values (x, y per cell, in the host's
 *                   cell order, x fastest on a grid), or NULL.
 * @param cell_area  room for `ncells` values, or NULL.
 * @return ::DPSM_OK or ::DPSM_ERR_NULL_POINTER (no grid, or both arrays NULL).
 */
DPSM_API int dpsm_get_cell_centres(const dpsm_grid *g, double *cell_xy, double *cell_area);

/**
 * @brief Reads the number of faces of a mesh (interior and domain edge).
 * @param g       the mesh.
 * @param nfaces  receives the count.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_NOT_APPLICABLE (a grid).
 */
DPSM_API int dpsm_get_face_count(const dpsm_grid *g, int64_t *nfaces);

/**
 * @brief Reads the two cells of every face of a mesh, in the host's cell
 *        and face order: what the values of dpsm_get_face_fluxes() and
 *        dpsm_set_edge_kinds() stand for.
 * @param g           the mesh.
 * @param face_cells  room for `2*nfaces` indices (a, b); b == -1 on the domain
 *                    edge. On a mesh made with a start index
 *                    (dpsm_create_mesh_indexed() and the others) the cells
 *                    count from it and the domain edge is one less (0 from 1).
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_NOT_APPLICABLE (a grid).
 */
DPSM_API int dpsm_get_mesh_faces(const dpsm_grid *g, int64_t *face_cells);

/**
 * @brief Sets which faces of a mesh's domain edge are open, face by face.
 *
 * An open face acts as an open side does on a grid (::DPSM_OPEN): the outside
 * is held at the face's level (dpsm_set_side_levels() with ::DPSM_MESH_EDGE)
 * and what leaves is booked as outflow of ::DPSM_MESH_EDGE
 * (dpsm_get_side_outflow()). dpsm_set_boundary() with ::DPSM_MESH_EDGE sets
 * every edge face at once and replaces these kinds.
 *
 * @param g      the mesh.
 * @param kinds  one value per face, ::DPSM_OPEN or ::DPSM_WALL; the values of
 *               faces between two cells are ignored. NULL: every edge a wall.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER, ::DPSM_ERR_UNKNOWN_ENUM (the
 *         message names the face) or ::DPSM_ERR_NOT_APPLICABLE (a grid).
 */
DPSM_API int dpsm_set_edge_kinds(dpsm_grid *g, const uint8_t *kinds);

/**
 * @brief Releases a grid and everything it holds.
 * @param g the grid; NULL is allowed and does nothing.
 */
DPSM_API void dpsm_destroy(dpsm_grid *g);

/**
 * @brief Sets the angle of repose `theta`.
 * @param g              the grid.
 * @param theta_radians  strictly between 0 and pi/2.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_INVALID_VALUE.
 */
DPSM_API int dpsm_set_repose_angle(dpsm_grid *g, double theta_radians);

/**
 * @brief Sets the mobility `nu` (the paper's `W * delta`): how fast a
 *        supercritical slope relaxes.
 * @param g   the grid.
 * @param nu  finite and positive.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_INVALID_VALUE.
 */
DPSM_API int dpsm_set_mobility(dpsm_grid *g, double nu);

/**
 * @brief Chooses how face slopes are measured: ::DPSM_SCHEME_ISOTROPIC (the
 *        default) or ::DPSM_SCHEME_PAIRWISE.
 *
 * On 1D and axisymmetric grids the two are the same; the call is accepted and
 * changes nothing.
 *
 * @param g       the grid.
 * @param scheme  ::DPSM_SCHEME_PAIRWISE or ::DPSM_SCHEME_ISOTROPIC.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_UNKNOWN_ENUM.
 */
DPSM_API int dpsm_set_scheme(dpsm_grid *g, int scheme);

/**
 * @brief Chooses how dpsm_step() moves the surface: ::DPSM_RELAX_AUTO (the
 *        default), ::DPSM_RELAX_TO_REST or ::DPSM_RELAX_TIME_ACCURATE.
 *
 * ::DPSM_RELAX_TO_REST makes every dpsm_step() bring the surface to rest in
 * far fewer evaluations of the slide fluxes than the time-accurate explicit
 * sub-steps take (on the cone of the performance page about a tenth of the
 * time), whatever its `dt` (which must still be finite and positive): for a
 * host that needs the deposit after each change, not the flow's timing. It
 * follows the flow's own path by Runge-Kutta-Chebyshev steps while much sand
 * moves and lets momentum finish the last small motions; the deposit stays
 * within about 0.2 % (L1) of the time-accurate one on the scenes of the
 * performance page, at rest tolerances up to 1e-3 (at 1e-2 it strays
 * further). Mass is kept: what leaves through open sides and cells is booked
 * as outflow, with the rounding of the combined stages (about 1e-16 of the
 * mass per evaluation); in a scene without open sides or cells nothing is
 * booked, and that rounding is the balance's only residual. Then
 * ::DPSM_INFO_SUBSTEPS counts the flux evaluations that moved sand (the one
 * that finds rest is not counted, as a time-accurate sub-step that finds
 * rest is not), ::DPSM_INFO_TIME_INTEGRATED is 0, and ::DPSM_INFO_AT_REST is
 * 1 unless the sub-step limit (dpsm_set_max_substeps()) ran out first.
 *
 * Where the state it reaches would lie beyond the extremes of the start's
 * sand (and of the levels open sides and cells hold), or a closed scene's
 * mass would be off by more than 1e-14, the step goes back to its start and
 * takes time-accurate sub-steps to rest instead, at most as many as
 * dpsm_set_max_substeps() allows; then ::DPSM_INFO_TIME_INTEGRATED is the
 * time that took.
 *
 * Like the time-accurate steps it costs what the scene needs: each evaluation
 * visits only the tiles near moving sand (::DPSM_INFO_CELL_UPDATES counts
 * their cells), its work arrays are touched only where sand moved, and a step
 * on a surface at rest takes no evaluation at all.
 *
 * In this version it relaxes 2D grids with the isotropic scheme, walls, open
 * sides and open cells at one level. dpsm_step() refuses it
 * (::DPSM_ERR_NOT_APPLICABLE, the grid unchanged) on 1D, axisymmetric and
 * distributed grids, with the pairwise scheme, and with a bed, an angle
 * field, a flux exponent other than 1, a static angle, an active source or
 * open cells at different levels. A host adds its deposit with
 * dpsm_add_heights_region() instead of a source.
 *
 * ::DPSM_RELAX_AUTO, the default, keeps the flow's time: after every call
 * the heights are those of the time-accurate sub-steps over the same `dt`
 * (in this version it takes them; \ref guide_time_steps says what faster
 * integrators were measured against that promise), and rest is reported
 * when they would report it. ::DPSM_INFO_TIME_INTEGRATED tells which mode a
 * step took (0 after a relaxation to rest). On the column collapse of the
 * guide, relaxing to rest reports rest after 0.15 model seconds where the
 * flow takes 1.05, its summit 5 % lower at that time: a host that needs the
 * flow's timing keeps the default.
 *
 * ::DPSM_RELAX_LOCAL_STEPS takes time-accurate sub-steps with each cell of a
 * mesh at the pace of its own stable bound: cells fall into classes whose
 * sub-steps are 1, 2, 4, ... times the smallest (::DPSM_INFO_SUBSTEPS counts
 * the smallest class's), a face fires at the sub-steps of the smaller class
 * of its cells over that class's span, and both its cells take its sand at
 * once, so mass is exact and no height leaves its neighbours' range. Where
 * sand moves only on large cells, a step evaluates only at their sub-steps
 * (::DPSM_INFO_SUBSTEPS_EVALUATED): on a mesh graded from h to 512 h, a
 * pile on the coarse cells costs about what it costs on a uniform mesh of
 * them, where the default would take some 1e5 times more. The large cells
 * step at their own stable size, so the heights differ from the default's
 * by the time error of that size (on meshes graded from h to 8 h, up to a
 * fifth of the volume moved during the flow and 2 % at rest;
 * \ref guide_meshes). A host's explicit choice. On a grid it is
 * ::DPSM_RELAX_TIME_ACCURATE; on a distributed mesh the parts step bit for
 * bit as the serial mesh does. Over a bed every tick looks at every cell (as
 * a sub-step with a bed does), and a face takes at most its share of the
 * sand its cell may give in that tick. With a static angle a cell is moving
 * while a face of it carried sand since all its faces last fired together
 * (dpsm_set_static_angle()), and every tick looks at every cell.
 *
 * @param g           the grid.
 * @param relaxation  ::DPSM_RELAX_AUTO, ::DPSM_RELAX_TO_REST,
 *                    ::DPSM_RELAX_TIME_ACCURATE or ::DPSM_RELAX_LOCAL_STEPS.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_UNKNOWN_ENUM.
 */
DPSM_API int dpsm_set_relaxation(dpsm_grid *g, int relaxation);

/**
 * @brief Makes one side of the domain open or a wall.
 * @param g     the grid.
 * @param side  ::DPSM_XMIN, ::DPSM_XMAX, ::DPSM_YMIN or ::DPSM_YMAX (the last
 *              two on 2D grids only).
 * @param kind  ::DPSM_OPEN or ::DPSM_WALL.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER, ::DPSM_ERR_UNKNOWN_ENUM, or
 *         ::DPSM_ERR_NOT_APPLICABLE for a y side of a 1D grid or the axis of an
 *         axisymmetric grid.
 */
DPSM_API int dpsm_set_boundary(dpsm_grid *g, int side, int kind);

/**
 * @brief Sets the surface level outside an open side, face by face.
 *
 * The outside of an open side acts as a cell held at this level one cell
 * width beyond each boundary face (the paper's node held at `h = 0` is the
 * default): sand leaves towards a lower level and comes in from a higher one,
 * until the faces are no steeper than the angle of repose, and the ledger
 * books both as outflow (dpsm_get_side_outflow()). For a host that knows what
 * lies beyond (a table at some height, the surface of a neighbouring domain
 * it couples itself). Levels may be set on a wall side; they act once the
 * side is made open (dpsm_set_boundary()). Beyond a corner of two open sides
 * the outside is the mean of the two levels nearest to it (it only enters
 * the transverse slopes of the corner's faces). A scene whose held levels
 * differ (open sides and open cells) may flow for ever: dpsm_step() then
 * limits its sub-steps (dpsm_set_max_substeps()).
 *
 * @param g       the grid.
 * @param side    ::DPSM_XMIN, ::DPSM_XMAX, ::DPSM_YMIN or ::DPSM_YMAX (the
 *                last two on 2D grids only; not the axis of an axisymmetric grid).
 * @param levels  one finite value per boundary face, within the supported
 *                range: `ny` values for ::DPSM_XMIN and ::DPSM_XMAX (face `j`
 *                beside cell `(0, j)` or `(nx-1, j)`), `nx` for ::DPSM_YMIN and
 *                ::DPSM_YMAX; on a 1D or axisymmetric grid one value; on a
 *                mesh (side ::DPSM_MESH_EDGE) one per face, those of faces
 *                between two cells finite but not used. NULL returns the side
 *                to 0.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER, ::DPSM_ERR_UNKNOWN_ENUM,
 *         ::DPSM_ERR_NOT_APPLICABLE (a side the grid does not have) or
 *         ::DPSM_ERR_INVALID_VALUE (the message names the face).
 */
DPSM_API int dpsm_set_side_levels(dpsm_grid *g, int side, const double *levels);

/**
 * @brief Sets the kind of every cell.
 *
 * A sand cell that becomes a wall or open cell takes its mass off the grid,
 * and a wall or open cell that becomes sand brings its current height on; both
 * are booked as ::DPSM_MASS_EXTERNAL.
 *
 * @param g      the grid.
 * @param kinds  `nx*ny` values, each ::DPSM_CELL_SAND, ::DPSM_CELL_WALL or
 *               ::DPSM_CELL_OPEN; NULL makes every cell sand.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_UNKNOWN_ENUM.
 */
DPSM_API int dpsm_set_cell_kinds(dpsm_grid *g, const uint8_t *kinds);

/**
 * @brief Sets the height of every cell.
 *
 * The height of a wall cell is kept and reported but moves nothing; the height
 * of an open cell is the level it holds. The change of mass on sand cells is
 * booked as ::DPSM_MASS_EXTERNAL.
 *
 * @param g  the grid.
 * @param h  `nx*ny` finite heights.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_INVALID_VALUE.
 */
DPSM_API int dpsm_set_heights(dpsm_grid *g, const double *h);

/**
 * @brief Copies the height of every cell out.
 * @param g  the grid.
 * @param h  room for `nx*ny` values.
 * @return ::DPSM_OK or ::DPSM_ERR_NULL_POINTER.
 */
DPSM_API int dpsm_get_heights(const dpsm_grid *g, double *h);

/**
 * @brief Sets the heights of a block of cells, leaving the others as they are.
 *
 * For a host that changes a few cells between steps (deposition from a flow
 * solver): only the cells of the block, and their neighbours, are looked at
 * again by the next step. The change of mass on sand cells is booked as
 * ::DPSM_MASS_EXTERNAL.
 *
 * @param g   the grid.
 * @param i0  first column of the block, `0 <= i0`.
 * @param j0  first row of the block, `0 <= j0` (0 on a 1D grid).
 * @param ni  columns in the block, at least 1, `i0 + ni <= nx`.
 * @param nj  rows in the block, at least 1, `j0 + nj <= ny` (1 on a 1D grid).
 * @param h   `ni*nj` finite heights, x fastest: cell `(i0+i, j0+j)` is `h[i + ni*j]`.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER, ::DPSM_ERR_INVALID_SIZE (a block
 *         that does not lie on the grid) or ::DPSM_ERR_INVALID_VALUE.
 */
DPSM_API int dpsm_set_heights_region(dpsm_grid *g, int64_t i0, int64_t j0, int64_t ni, int64_t nj, const double *h);

/**
 * @brief Adds to the heights of a block of cells (deposition > 0, erosion < 0).
 *
 * As dpsm_set_heights_region(), but `dh` is added to each cell.
 *
 * @param g   the grid.
 * @param i0  first column of the block.
 * @param j0  first row of the block.
 * @param ni  columns in the block.
 * @param nj  rows in the block.
 * @param dh  `ni*nj` finite changes, x fastest.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER, ::DPSM_ERR_INVALID_SIZE or
 *         ::DPSM_ERR_INVALID_VALUE (also when a sum overflows).
 */
DPSM_API int dpsm_add_heights_region(dpsm_grid *g, int64_t i0, int64_t j0, int64_t ni, int64_t nj, const double *dh);

/**
 * @brief Copies the heights of a block of cells out.
 * @param g   the grid.
 * @param i0  first column of the block.
 * @param j0  first row of the block.
 * @param ni  columns in the block.
 * @param nj  rows in the block.
 * @param h   room for `ni*nj` values, x fastest.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_INVALID_SIZE.
 */
DPSM_API int dpsm_get_heights_region(const dpsm_grid *g, int64_t i0, int64_t j0, int64_t ni, int64_t nj, double *h);

/**
 * @brief Sets the source `q`: height per unit time added to each cell
 *        (deposition > 0, erosion < 0).
 *
 * The source acts on sand cells only; values given for wall and open cells are
 * ignored. It stays in force for every following step until replaced.
 *
 * @param g  the grid.
 * @param q  `nx*ny` finite values, or NULL for no source.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_INVALID_VALUE.
 */
DPSM_API int dpsm_set_source(dpsm_grid *g, const double *q);

/**
 * @brief The largest stable explicit sub-step:
 *        `1 / (2 nu cos(theta) (1/dx^2 + 1/dy^2))` in 2D, `dx^2 / (2 nu cos(theta))`
 *        in 1D, `3 dr^2 / (8 nu cos(theta))` on the axisymmetric grid.
 *
 * `cos(theta)` is the largest slope of the flux law. At this sub-step no pair
 * of cells exchanges more sand than brings it to the angle of repose (the
 * paper's bound on the mass exchanged per step), and every new height is a
 * weighted mean of old ones, so the surface gains no new maximum or minimum:
 * a face carries `C * (h_a - h_b)` with `0 <= C <= nu cos(theta) / d`, for both
 * schemes (the isotropic one only makes `C` depend on the transverse slope).
 * dpsm_step() picks its sub-steps from it.
 *
 * @param g   the grid.
 * @param dt  receives the sub-step.
 * @return ::DPSM_OK or ::DPSM_ERR_NULL_POINTER.
 */
DPSM_API int dpsm_stable_dt(const dpsm_grid *g, double *dt);

/**
 * @brief Advances the surface by `dt` (or, with ::DPSM_RELAX_TO_REST,
 *        straight to rest).
 *
 * By default the step is time-accurate, as described here;
 * dpsm_set_relaxation() tells the relaxation to rest, a host's explicit choice.
 *
 * Sub-steps of at most dpsm_stable_dt() are taken. When the surface is at rest
 * (no face steeper than `tan(theta) * (1 + tol)`, see
 * dpsm_set_rest_tolerance()) and nothing drives it (no source can make a
 * face steep by the end of `dt`), stepping stops early: nothing would slide
 * in the remaining time, and a source adds the rest of `dt` in closed form. So a large `dt` on a
 * collapsing pile costs the work to reach rest, not `dt / dpsm_stable_dt()`
 * sub-steps.
 *
 * A source costs what the sand it moves needs. Where it cannot make a face
 * steep within the step (a face's slope under the sources alone moves
 * linearly in time, so looking at the start and the end of the step
 * suffices), it is applied in closed form, `h += q dt`, which equals what
 * the sub-steps would add to round-off; sub-steps are taken only where a
 * face is, or becomes within `dt`, steeper than the threshold, and a cell
 * takes what its source added while it waited when one of its faces first
 * carries sand. So a source on a resting dune field costs about a pass over
 * its cells, and a source of 1e-300 does not keep a pile from stopping early.
 *
 * A scene that may flow forever must finish all its sub-steps: one with a
 * source that makes a face steep within the step, or with held levels that
 * differ (open cells and the outside of open sides at different levels,
 * dpsm_set_side_levels()), between which sand can run without end. If it would need more than the limit of
 * dpsm_set_max_substeps(), the call fails at once with ::DPSM_ERR_WORK_LIMIT
 * and changes nothing. Any other scene comes to rest by itself (its energy
 * falls while sand moves) and is not limited.
 *
 * A source that would carry a sand cell's height beyond the supported range
 * within `dt` (`h + q dt` outside [-1e50, 1e50]; erosion down to a bed
 * excepted) fails the call at once with ::DPSM_ERR_INVALID_VALUE, naming the
 * cell, and changes nothing (steps of ::DPSM_RELAX_TO_REST, which integrate
 * no time, are not checked).
 *
 * @param g   the grid.
 * @param dt  finite and positive.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER, ::DPSM_ERR_INVALID_VALUE,
 *         ::DPSM_ERR_WORK_LIMIT or ::DPSM_ERR_NOT_APPLICABLE
 *         (::DPSM_RELAX_TO_REST on a scene it does not support).
 */
DPSM_API int dpsm_step(dpsm_grid *g, double dt);

/**
 * @brief Reads one figure of the mass ledger.
 * @param g         the grid.
 * @param quantity  ::DPSM_MASS_TOTAL, ::DPSM_MASS_SOURCED,
 *                  ::DPSM_MASS_EXTERNAL, ::DPSM_MASS_OUTFLOW or ::DPSM_MASS_UNMET.
 * @param value     receives the figure.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_UNKNOWN_ENUM.
 */
DPSM_API int dpsm_get_mass(const dpsm_grid *g, int quantity, double *value);

/**
 * @brief Reads what the last successful dpsm_step() did.
 * @param g      the grid.
 * @param item   ::DPSM_INFO_SUBSTEPS, ::DPSM_INFO_TIME_INTEGRATED,
 *               ::DPSM_INFO_AT_REST, ::DPSM_INFO_MAX_EXCESS_SLOPE,
 *               ::DPSM_INFO_CELL_UPDATES, ::DPSM_INFO_RANK_CELL_UPDATES,
 *               ::DPSM_INFO_MESSAGES_SENT, ::DPSM_INFO_BYTES_SENT,
 *               ::DPSM_INFO_SUBSTEPS_PER_EXCHANGE or
 *               ::DPSM_INFO_SUBSTEPS_EVALUATED.
 * @param value  receives the figure (0 for every item before the first step).
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_UNKNOWN_ENUM.
 */
DPSM_API int dpsm_get_step_info(const dpsm_grid *g, int item, double *value);

/**
 * @brief Reads the net mass that has left through one side since the grid was
 *        created (negative where more came in from a higher outside level).
 *
 * The four sides and the open cells together make ::DPSM_MASS_OUTFLOW, to
 * round-off; a wall side, or a side a grid does not have on a 1D grid, reads
 * what it took while it was open.
 *
 * @param g      the grid.
 * @param side   ::DPSM_XMIN, ::DPSM_XMAX, ::DPSM_YMIN or ::DPSM_YMAX (the last
 *               two on 2D grids only; not the axis of an axisymmetric grid).
 * @param value  receives the mass.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER, ::DPSM_ERR_UNKNOWN_ENUM or
 *         ::DPSM_ERR_NOT_APPLICABLE.
 */
DPSM_API int dpsm_get_side_outflow(const dpsm_grid *g, int side, double *value);

/**
 * @brief Turns the recording of face fluxes on (1) or off (0, the default).
 *
 * While it is on, every dpsm_step() keeps the volume each face carried, for
 * dpsm_get_face_fluxes(). It costs memory for one value per face and, on a
 * 2D grid, a little time in every sub-step that moves sand, so it is off
 * unless a host asks for it (a host that carries sediment fractions, or adds
 * the avalanche's flux to its bed load on the faces).
 *
 * @param g   the grid.
 * @param on  1 to record, 0 to stop (the recorded fluxes are dropped).
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_INVALID_VALUE.
 */
DPSM_API int dpsm_set_face_flux_recording(dpsm_grid *g, int on);

/**
 * @brief Reads the volume of sand that crossed each face during the last
 *        successful dpsm_step().
 *
 * Positive towards increasing x (y). For every sand cell, what its faces
 * brought in less what they took out equals its change of height times its
 * area, less what its source added, to round-off; on an open side the faces
 * add up to what the side took in that step (dpsm_get_side_outflow()), and
 * faces next to an open cell to what that cell took. Faces of walls and
 * between two cells that are not sand carry nothing. After a step that moved
 * nothing every face reads 0.
 *
 * Recording must be on before the step (dpsm_set_face_flux_recording());
 * a relaxation to rest (::DPSM_RELAX_TO_REST) carries sand by combinations of
 * trial states, not across faces in time, and leaves no fluxes.
 *
 * @param g   the grid.
 * @param fx  room for `(nx+1)*ny` values: `fx[i + (nx+1)*j]` is the face on
 *            the low side of cell `(i, j)` (`i = nx`: the high side of the
 *            last column); on a 1D or axisymmetric grid `nx+1` values (on the
 *            axisymmetric grid face `i` lies at radius `i*dr`).
 * @param fy  room for `nx*(ny+1)` values: `fy[i + nx*j]` is the face on the
 *            low side of cell `(i, j)` (`j = ny`: the high side of the last
 *            row); NULL on a 1D or axisymmetric grid.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER, ::DPSM_ERR_INVALID_VALUE (an
 *         `fy` given to a grid without y faces), or ::DPSM_ERR_NOT_APPLICABLE
 *         (recording is off, or the last step relaxed to rest). Before the
 *         first step every face reads 0.
 */
DPSM_API int dpsm_get_face_fluxes(const dpsm_grid *g, double *fx, double *fy);

/**
 * @brief Reads the size of the grid.
 * @param g   the grid.
 * @param nx  receives the number of cells along x.
 * @param ny  receives the number of cells along y (1 for a 1D grid).
 * @return ::DPSM_OK or ::DPSM_ERR_NULL_POINTER.
 */
DPSM_API int dpsm_get_shape(const dpsm_grid *g, int64_t *nx, int64_t *ny);

/**
 * @brief Says what kind of grid this is: which constructor made it.
 *
 * A host (or a binding) that holds a grid it did not make, one dpsm_load()
 * or dpsm_load_mpi() returned, learns here how to read its shape: nx cells
 * on a line, nr rings, nx by ny cells, or ncells cells of a mesh (with
 * dpsm_get_face_count() faces). On a rank's part of a distributed grid the
 * kind of the whole.
 *
 * @param g     the grid.
 * @param kind  receives ::DPSM_GRID_1D, ::DPSM_GRID_AXISYMMETRIC,
 *              ::DPSM_GRID_2D or ::DPSM_GRID_MESH.
 * @return ::DPSM_OK or ::DPSM_ERR_NULL_POINTER.
 */
DPSM_API int dpsm_get_grid_kind(const dpsm_grid *g, int *kind);

/**
 * @brief Sets how close to the angle of repose counts as rest.
 *
 * The surface is at rest when no face slope exceeds `tan(theta) * (1 + tol)`.
 * Supercritical slopes relax exponentially, so a smaller tolerance costs a
 * little more time to rest; the final heights are off by at most about
 * `tol * tan(theta) * L` over a slope of length `L`. On a mesh a face's slope
 * takes its part along the face from the cells' least-squares gradients, and
 * the same tolerance holds for every face (see `docs/guarantees.md`).
 *
 * @param g    the grid.
 * @param tol  finite and positive; default ::DPSM_DEFAULT_REST_TOLERANCE.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_INVALID_VALUE.
 */
DPSM_API int dpsm_set_rest_tolerance(dpsm_grid *g, double tol);

/**
 * @brief Limits the sub-steps one dpsm_step() of a driven scene may take.
 *
 * A scene that may flow forever (see dpsm_step()) may never come to rest, so
 * dpsm_step() checks before it starts that `dt` needs no more than this many
 * sub-steps, and fails with ::DPSM_ERR_WORK_LIMIT otherwise. Scenes that come
 * to rest by themselves are not limited: they stop when at rest.
 *
 * @param g  the grid.
 * @param n  at least 1; default ::DPSM_DEFAULT_MAX_SUBSTEPS.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_INVALID_VALUE.
 */
DPSM_API int dpsm_set_max_substeps(dpsm_grid *g, int64_t n);

/**
 * @brief Sets how many threads dpsm_step() may use on this grid.
 *
 * Results do not depend on the number of threads: every face flux is computed
 * the same way whichever thread computes it, and sums are taken in a fixed
 * order. Without OpenMP support in the build the library runs on one thread
 * and accepts any valid `n`.
 *
 * The default (`n` = 0) is OpenMP's default, usually one thread per core,
 * except on a block of a distributed grid (dpsm_mpi.h), which takes one
 * thread unless the environment sets `OMP_NUM_THREADS`: an MPI host runs a
 * rank per core, and each rank taking every core of the node would
 * oversubscribe it. dpsm_get_threads() says what a step will use.
 *
 * @param g  the grid.
 * @param n  at least 0; 0 (the default) means the default above; counts
 *           beyond 1024 run as 1024 (each thread holds buffers of its own).
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_INVALID_VALUE.
 */
DPSM_API int dpsm_set_threads(dpsm_grid *g, int n);

/**
 * @brief How many threads dpsm_step() will use on this grid.
 *
 * The count dpsm_set_threads() asked for, or the default it describes (1 on
 * a block of a distributed grid without `OMP_NUM_THREADS`, else OpenMP's
 * default); 1 on 1D and axisymmetric grids, whose steps are serial, and
 * without OpenMP support in the build.
 *
 * @param g  the grid.
 * @param n  receives the count, at least 1.
 * @return ::DPSM_OK or ::DPSM_ERR_NULL_POINTER.
 */
DPSM_API int dpsm_get_threads(const dpsm_grid *g, int *n);

/**
 * @brief Where this grid's messages count cells and array positions from: 0
 *        as C does (the default), or 1 as Fortran does.
 *
 * With base 1 every message of dpsm_last_error() that names a cell, a face
 * or a position in an array names it as a Fortran host holding `h(nx, ny)`
 * writes it: `kinds(3, 3) (cell i = 3, j = 3) = 9` where base 0 reads
 * `kinds[14] (cell i = 2, j = 2) = 9`; `h(4)` on a 1D or axisymmetric grid.
 * Positions in a block of dpsm_set_heights_region() and the others count
 * within the block (`dh(1, 2)`); the offsets `i0`, `j0` themselves stay as
 * the host passed them. Nothing else changes: arrays keep x fastest from
 * index 0 in memory, and results are the same. The Fortran module sets 1 on
 * every grid it creates or loads. Not kept in restart files.
 *
 * A mesh counts from the start index its constructor was given
 * (dpsm_create_mesh_indexed() and the others); on a mesh `base` must equal it.
 *
 * @param g     the grid.
 * @param base  0 or 1.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER, ::DPSM_ERR_INVALID_VALUE (base
 *         other than 0 and 1) or ::DPSM_ERR_NOT_APPLICABLE (a mesh counting
 *         from the other base).
 */
DPSM_API int dpsm_set_index_base(dpsm_grid *g, int base);

/** @name Physics for real scenes
 *  A bed that cannot erode, angles that vary, other flow laws and
 *  hysteresis. Each costs nothing when a scene does not use it; a scene that
 *  uses any of them is stepped by a plain (not vectorised) kernel. @{ */

/**
 * @brief Sets a non-erodible bed `zb` under the sand, or removes it.
 *
 * It may be set before the sand or after: a cell whose height lies below its
 * bed is lifted to it (whatever its kind), and the sand this adds to sand
 * cells is booked as ::DPSM_MASS_EXTERNAL, as dpsm_set_heights() would book
 * it. So a host sets the rock, then the sand (heights at or above the bed).
 *
 * Sand above the bed moves as usual; the surface never goes below it. A face
 * takes from its upstream cell at most a quarter (a half in 1D) of the sand
 * that cell holds above its bed in a sub-step, after that cell's own erosion,
 * so the exchanges of a cell together take at most the sand that is there.
 * Sand thinner than `tol * tan(theta) * dx` (the height scale of the rest
 * tolerance, dpsm_set_rest_tolerance(), with the smallest angle and spacing)
 * is left where it is, so that a drained slope comes to rest instead of
 * thinning forever.
 * A negative source erodes only the sand there is: what it asked for beyond
 * that is not applied and is counted as ::DPSM_MASS_UNMET. A bare bed steeper
 * than the angle of repose does not move and is at rest.
 *
 * While a bed is set, dpsm_set_heights(), dpsm_set_heights_region() and
 * dpsm_add_heights_region() refuse heights below it (any cell kind).
 *
 * @param g   the grid.
 * @param zb  `nx*ny` finite values within the supported range; NULL removes
 *            the bed.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_INVALID_VALUE (a
 *         value not finite or outside the range).
 */
DPSM_API int dpsm_set_bedrock(dpsm_grid *g, const double *zb);

/**
 * @brief Sets an angle of repose per cell, or returns to the uniform angle of
 *        dpsm_set_repose_angle().
 *
 * For wet and dry sand, vegetated patches. A face between two sand cells uses
 * the mean of their two `tan(theta)`; a face between a sand cell and a wall,
 * an open cell or the outside uses the sand cell's. The stable sub-step
 * (dpsm_stable_dt()) follows the smallest angle.
 *
 * @param g              the grid.
 * @param theta_radians  `nx*ny` angles, each strictly between 0 and pi/2;
 *                       NULL returns to the uniform angle.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_INVALID_VALUE.
 */
DPSM_API int dpsm_set_repose_angle_field(dpsm_grid *g, const double *theta_radians);

/**
 * @brief Sets the exponent `p` of the flux law: sand moves at
 *        `nu * (|grad h| - tan(theta))_+^p / sqrt(1 + |grad h|^2)`.
 *
 * `p = 1` (::DPSM_DEFAULT_FLUX_EXPONENT) is the paper's law; `p = 2` the
 * Bingham closure the paper names, `1 + 1/n` a Herschel-Bulkley fluid of index
 * `n >= 1`. Rest states are the same (slopes at the angle of repose); a larger
 * `p` moves slightly supercritical slopes more slowly (the excess decays like a
 * power of time instead of exponentially) and very steep ones faster.
 * Exponents above ::DPSM_MAX_FLUX_EXPONENT are refused: the law's largest
 * slope, which sets the stable sub-step, would grow without bound with the
 * slope. dpsm_stable_dt() follows the law.
 *
 * @param g  the grid.
 * @param p  within [1, ::DPSM_MAX_FLUX_EXPONENT].
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_INVALID_VALUE.
 */
DPSM_API int dpsm_set_flux_exponent(dpsm_grid *g, double p);

/**
 * @brief Sets the static angle: sand at rest starts to move only where the
 *        slope is steeper than it, and once moving stops at the angle of repose.
 *
 * As on dune slip faces: a slope between the two angles holds; one steeper
 * than the static angle avalanches down to the angle of repose. A cell is
 * moving while one of its faces carried sand in the last sub-step (under
 * ::DPSM_RELAX_LOCAL_STEPS: since all its faces last fired); a face with
 * a moving cell on either side uses the angle of repose, a face between two
 * cells at rest the larger of the static angle and the angle of repose. By
 * default the static angle equals the angle of repose (and follows it), which
 * is the paper's model. Which cells are moving is part of the state, kept
 * between steps; setting the static angle puts every cell at rest.
 *
 * @param g        the grid.
 * @param radians  strictly between 0 and pi/2; a value below the angle of
 *                 repose acts as the angle of repose.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_INVALID_VALUE.
 */
DPSM_API int dpsm_set_static_angle(dpsm_grid *g, double radians);
/** @} */

/** @name Restart files
 *  Saving a grid and continuing it bit for bit (see \ref guide_restart). @{ */

/**
 * @brief Writes everything needed to continue a run bit for bit to a file.
 *
 * Geometry, parameters, sides, cell kinds, bed, angle field, source, heights
 * (with the rounding each cell carries), which cells are moving, the mass
 * ledger and the last step's information. The format is versioned, portable
 * (little-endian, IEEE doubles, independent of the machine) and ends with a
 * CRC-32 checksum. The file is written to `path` through a temporary file
 * that replaces it only when complete.
 *
 * On a distributed grid (dpsm_mpi.h) the call is collective: each rank writes
 * its own block to the path it passes (each rank its own file), and when any
 * rank fails every rank returns that rank's status (its message says why, the
 * others' name it); read the files back with dpsm_load_mpi().
 *
 * @param g     the grid.
 * @param path  the file to write.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER or ::DPSM_ERR_IO (the message
 *         names the path and the system's reason).
 */
DPSM_API int dpsm_save(const dpsm_grid *g, const char *path);

/**
 * @brief Reads a file written by dpsm_save() into a new grid.
 *
 * The new grid continues exactly as the saved one would have: the same calls
 * give bit-identical heights and ledger. A file that is truncated, corrupted
 * (any byte changed), of another format or of a newer version is refused with
 * a message that says which; no grid is made. A file that holds one rank's
 * block of a distributed grid is refused with ::DPSM_ERR_NOT_APPLICABLE: it is
 * read by dpsm_load_mpi() on as many ranks.
 *
 * @param path  the file to read.
 * @param out   receives the new grid, or NULL on failure.
 * @return ::DPSM_OK, ::DPSM_ERR_NULL_POINTER, ::DPSM_ERR_IO,
 *         ::DPSM_ERR_BAD_FILE, ::DPSM_ERR_NOT_APPLICABLE or
 *         ::DPSM_ERR_OUT_OF_MEMORY. On failure the
 *         message is read with `dpsm_last_error(NULL)`.
 */
DPSM_API int dpsm_load(const char *path, dpsm_grid **out);
/** @} */


/**
 * @brief The message of the last failed call on `g`, or `""` if its last call
 *        succeeded.
 *
 * With `g == NULL`: the message of the last failure in this thread that had no
 * grid to keep it (a failed create, a NULL handle).
 * The string stays valid until the next call on the same grid (or thread).
 *
 * @param g  the grid, or NULL.
 * @return never NULL.
 */
DPSM_API const char *dpsm_last_error(const dpsm_grid *g);

/**
 * @brief A short name for a status code, e.g. `"DPSM_ERR_INVALID_VALUE"`.
 * @param status  any integer.
 * @return never NULL; `"unknown status"` for codes this library does not know.
 */
DPSM_API const char *dpsm_status_string(int status);

/**
 * @brief The version of the library actually linked, e.g. `"0.1.0"`.
 * @return never NULL.
 */
DPSM_API const char *dpsm_version_string(void);

/**
 * @brief The version of the library actually linked as
 *        `MAJOR*10000 + MINOR*100 + PATCH`; compare with ::DPSM_VERSION_NUMBER.
 */
DPSM_API int dpsm_version_number(void);

#ifdef __cplusplus
}
#endif

#endif /* DPSM_DPSM_H */
