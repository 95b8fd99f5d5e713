// The C boundary. Every entry point checks its arguments, runs the core inside
// `guarded`, and turns any exception into a status code and a message kept on
// the handle (or, with no handle, per thread). Checks happen before the core
// changes anything, so a failed call leaves the grid as it was.
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <new>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "api/guarded.hpp"
#include "api/handle.hpp"
#include "dpsm/dpsm.h"
#include "io/distributed_save.hpp"
#include "io/restart.hpp"
#include "model/distribution.hpp"
#include "model/error.hpp"
#include "model/grid.hpp"
#include "model/limits.hpp"
#include "model/mesh.hpp"
#include "stepping/stepper.hpp"

namespace {

using dpsm::Error;
using dpsm::fail;
using dpsm::kMaxCells;
using dpsm::kMaxMagnitude;

using dpsm::guarded;

thread_local std::string error_without_grid;

void require_grid(const dpsm_grid *g, const char *function) {
    if (!g) fail(DPSM_ERR_NULL_POINTER, function, "the grid is NULL");
}

void require_pointer(const void *p, const char *function, const char *name) {
    if (!p) fail(DPSM_ERR_NULL_POINTER, function, name, " is NULL");
}

void require_finite(double value, const char *function, const char *name) {
    if (!std::isfinite(value)) fail(DPSM_ERR_INVALID_VALUE, function, name, " = ", value, " is not finite");
}

void require_positive(double value, const char *function, const char *name) {
    require_finite(value, function, name);
    if (!(value > 0.0)) fail(DPSM_ERR_INVALID_VALUE, function, name, " = ", value, " must be positive");
}


const char *describe(double value) { return std::isnan(value) ? "NaN" : value > 0 ? "+Inf" : "-Inf"; }

// Names the first value that is not finite or lies beyond the supported
// range by its position (as a host counting from `base` writes it, an array of
// `rows` rows: dpsm::host_position) and `where(k)`, the place it stands for.
template <class Where>
void require_in_range(const double *values, std::int64_t n, const char *function, const char *name, Where &&where,
                      int base = 0, std::int64_t rows = 1) {
    for (std::int64_t k = 0; k < n; ++k) {
        if (std::isfinite(values[k]) && std::fabs(values[k]) <= kMaxMagnitude) continue;
        if (!std::isfinite(values[k]))
            fail(DPSM_ERR_INVALID_VALUE, function, dpsm::host_position(name, k, base, rows), " (", where(k), ") is ",
                 describe(values[k]));
        fail(DPSM_ERR_INVALID_VALUE, function, dpsm::host_position(name, k, base, rows), " (", where(k), ") = ",
             values[k], " is outside the supported range [-1e50, 1e50]");
    }
}

// Cell (i, j) of a grid as a host counting from `base` names it.
std::string cell_name(std::int64_t i, std::int64_t j, int base) {
    return "cell i = " + std::to_string(i + base) + ", j = " + std::to_string(j + base);
}

const dpsm::Mesh *mesh_of(const dpsm_grid *g) { return g->core.geometry().mesh.get(); }

// Where the host's numbers of cells, faces and array positions begin: a
// mesh's start index (0 or 1, as its constructor was given), a grid's index
// base (0 unless dpsm_set_index_base said 1).
int host_base(const dpsm_grid *g) {
    const dpsm::Mesh *mesh = mesh_of(g);
    return mesh ? mesh->input.start_index : g->core.index_base();
}

// The rows of a per-cell array as a host counting from 1 shapes it: h(nx, ny)
// on a 2D grid; one row (h(nx), h(ncells)) on a line, an axisymmetric grid or
// a mesh.
std::int64_t cell_rows(const dpsm_grid *g) {
    const dpsm::Geometry &geo = g->core.geometry();
    return geo.dim == 2 && !geo.is_mesh() ? geo.nx : 1;
}

// A cell as the host numbers it: (i, j) on a grid, its index on a mesh
// (host order, from the mesh's start index).
std::string host_cell_name(const dpsm_grid *g, std::int64_t c) {
    const dpsm::Geometry &geo = g->core.geometry();
    if (geo.is_mesh()) return "cell " + std::to_string(c + host_base(g));
    return cell_name(c % geo.nx, c / geo.nx, host_base(g));
}

// Per-cell array `name`'s position k as the host writes it.
std::string host_position(const dpsm_grid *g, const char *name, std::int64_t k) {
    return dpsm::host_position(name, k, host_base(g), cell_rows(g));
}

// A mesh's per-face array `name`'s position k as the host writes it.
std::string host_face_position(const dpsm_grid *g, const char *name, std::int64_t k) {
    return dpsm::host_position(name, k, host_base(g));
}

// Names the first non-finite element by its index and cell.
void require_finite_array(const dpsm_grid *g, const double *values, const char *function, const char *name) {
    require_pointer(values, function, name);
    require_in_range(values, g->core.geometry().cells(), function, name,
                     [&](std::int64_t c) { return host_cell_name(g, c); }, host_base(g), cell_rows(g));
}

// On a mesh the library keeps its cells in an order of its own
// (model/mesh.hpp): a host's array goes through `buffer` into it, and comes
// back out in the host's order. On a grid the orders agree.
template <class T>
const T *in_library_order(const dpsm_grid *g, const T *host, std::vector<T> &buffer) {
    const dpsm::Mesh *mesh = mesh_of(g);
    if (!mesh || !host) return host;
    buffer.resize(static_cast<std::size_t>(mesh->cells));
    for (std::int64_t c = 0; c < mesh->cells; ++c) buffer[c] = host[mesh->host_cell[c]];
    return buffer.data();
}

void to_host_order(const dpsm_grid *g, const std::vector<double> &library, double *host) {
    const dpsm::Mesh *mesh = mesh_of(g);
    for (std::int64_t c = 0; c < mesh->cells; ++c) host[mesh->host_cell[c]] = library[c];
}

// Per face of a mesh, from the host's face order into the library's.
template <class T>
std::vector<T> faces_in_library_order(const dpsm::Mesh &mesh, const T *host) {
    std::vector<T> library(static_cast<std::size_t>(mesh.faces));
    for (std::int64_t f = 0; f < mesh.faces; ++f) library[f] = host[mesh.host_face[f]];
    return library;
}

void require_grid_not_mesh(const dpsm_grid *g, const char *function) {
    if (mesh_of(g))
        fail(DPSM_ERR_NOT_APPLICABLE, function, "a mesh has no blocks of cells; set every cell with the function "
             "without _region");
}

void require_mesh(const dpsm_grid *g, const char *function) {
    if (!mesh_of(g)) fail(DPSM_ERR_NOT_APPLICABLE, function, "this grid is not a mesh");
}

void require_size(std::int64_t n, const char *function, const char *name) {
    if (n < 1) fail(DPSM_ERR_INVALID_SIZE, function, name, " = ", n, " must be at least 1");
}

// Checks that [i0, i0+ni) x [j0, j0+nj) lies on the grid, without overflow.
dpsm::Grid::Block require_block(const dpsm_grid *g, std::int64_t i0, std::int64_t j0, std::int64_t ni,
                                std::int64_t nj, const char *function) {
    const dpsm::Geometry &geo = g->core.geometry();
    if (ni < 1 || nj < 1)
        fail(DPSM_ERR_INVALID_SIZE, function, "the block is ni = ", ni, " by nj = ", nj, " cells; both must be at least 1");
    if (i0 < 0 || i0 > geo.nx - ni)
        fail(DPSM_ERR_INVALID_SIZE, function, "the block's columns i0 = ", i0, " .. i0 + ni = ", i0, " + ", ni,
             " do not lie in [0, nx = ", geo.nx, "]");
    if (j0 < 0 || j0 > geo.ny - nj)
        fail(DPSM_ERR_INVALID_SIZE, function, "the block's rows j0 = ", j0, " .. j0 + nj = ", j0, " + ", nj,
             " do not lie in [0, ny = ", geo.ny, "]");
    return {i0, j0, ni, nj};
}

// Names the first non-finite value of a block by its index and cell.
void require_finite_block(const dpsm_grid *g, const double *values, const dpsm::Grid::Block &b, const char *function,
                          const char *name) {
    require_pointer(values, function, name);
    const int base = host_base(g);
    require_in_range(
        values, b.ni * b.nj, function, name,
        [&](std::int64_t k) { return cell_name(b.i0 + k % b.ni, b.j0 + k / b.ni, base); }, base, b.ni);
}

// Position k of a block's array (ni by nj values) as the host writes it.
std::string block_position(const dpsm_grid *g, const dpsm::Grid::Block &b, const char *name, std::int64_t k) {
    return dpsm::host_position(name, k, host_base(g), b.ni);
}

void require_scale(double value, const char *function, const char *name) {
    require_positive(value, function, name);
    if (value < 1.0 / kMaxMagnitude || value > kMaxMagnitude)
        fail(DPSM_ERR_INVALID_VALUE, function, name, " = ", value, " is outside the supported range [1e-50, 1e50]");
}

// With a bed, the host may not put a cell below it: names the first such cell.
// `values` are the block's new heights (add = false) or changes (add = true).
void require_above_bed(const dpsm_grid *g, const dpsm::Grid::Block &b, const double *values, bool add,
                       const char *function, const char *name) {
    const std::vector<double> &zb = g->core.bed();
    if (zb.empty()) return;
    const std::vector<double> &h = g->core.heights();
    const std::int64_t nx = g->core.geometry().nx;
    for (std::int64_t k = 0; k < b.ni * b.nj; ++k) {
        const std::int64_t c = (b.i0 + k % b.ni) + nx * (b.j0 + k / b.ni);
        const double next = add ? h[c] + values[k] : values[k];
        if (next < zb[c]) {
            const dpsm::Mesh *mesh = mesh_of(g);
            const std::int64_t host = mesh ? mesh->host_cell[c] : k;
            fail(DPSM_ERR_INVALID_VALUE, function,
                 mesh ? host_position(g, name, host) : block_position(g, b, name, k), " puts ",
                 host_cell_name(g, mesh ? host : c), " at ", next, ", below its bed zb = ", zb[c],
                 " (see dpsm_set_bedrock)");
        }
    }
}

// A figure of a distributed grid is global: every rank takes part in the
// sum, one that refused its arguments too, so that none waits for ever. On
// a serial grid, the grid's own. False on every rank when any refused.
bool global_figure(const dpsm_grid *g, double local, bool refused, double &total) {
    total = local;
    const dpsm::Distribution *distribution = g->core.distribution();
    return !distribution || distribution->sum_unless_refused(local, refused, total);
}

const char *side_name(int side) {
    static const char *const names[4] = {"DPSM_XMIN", "DPSM_XMAX", "DPSM_YMIN", "DPSM_YMAX"};
    return names[side];
}

// A side this grid has: the four of a 2D grid, the two of a line, the outer
// one of an axisymmetric grid.
void require_side(const dpsm_grid *g, int side, const char *function) {
    const dpsm::Geometry &geo = g->core.geometry();
    if (geo.is_mesh()) {
        if (side != DPSM_MESH_EDGE)
            fail(side >= DPSM_XMIN && side <= DPSM_YMAX ? DPSM_ERR_NOT_APPLICABLE : DPSM_ERR_UNKNOWN_ENUM, function,
                 "side = ", side, " is not DPSM_MESH_EDGE, the one side of a mesh");
        return;
    }
    if (side == DPSM_MESH_EDGE)
        fail(DPSM_ERR_NOT_APPLICABLE, function, "side = DPSM_MESH_EDGE is the edge of a mesh; this grid is not one");
    if (side < DPSM_XMIN || side > DPSM_YMAX)
        fail(DPSM_ERR_UNKNOWN_ENUM, function, "side = ", side, " is not DPSM_XMIN, DPSM_XMAX, DPSM_YMIN or DPSM_YMAX");
    if (geo.dim == 1 && side >= DPSM_YMIN)
        fail(DPSM_ERR_NOT_APPLICABLE, function, "a 1D grid has no y sides (side = ", side_name(side), ")");
    if (geo.axisymmetric && side == DPSM_XMIN)
        fail(DPSM_ERR_NOT_APPLICABLE, function, "side = DPSM_XMIN of an axisymmetric grid is the axis, not a boundary");
}

void require_angle(double theta, const char *function, const char *name) {
    require_finite(theta, function, name);
    if (!(theta > 0.0 && theta < 0.5 * M_PI))
        fail(DPSM_ERR_INVALID_VALUE, function, name, " = ", theta, " radians is outside (0, pi/2)");
}


int create(int dim, bool axisymmetric, std::int64_t nx, std::int64_t ny, double dx, double dy, dpsm_grid **out, const char *function) {
    if (out) *out = nullptr;
    return guarded(nullptr, function, [&] {
        require_pointer(out, function, "out");
        require_size(nx, function, axisymmetric ? "nr" : "nx");
        require_size(ny, function, "ny");
        if (nx > kMaxCells / ny)
            fail(DPSM_ERR_INVALID_SIZE, function, axisymmetric ? "nr = " : "nx * ny = ", nx, axisymmetric ? "" : " * ",
                 axisymmetric ? std::string() : std::to_string(ny), " cells is more than this library can address (",
                 kMaxCells, ")");
        require_scale(dx, function, axisymmetric ? "dr" : "dx");
        require_scale(dy, function, "dy");
        *out = new dpsm_grid(dpsm::Geometry{dim, axisymmetric, nx, ny, dx, dy, nullptr});
    });
}

// A mesh from a builder of model/mesh.hpp, the host's arrays counting from
// start_index.
template <class Build>
int create_mesh(dpsm_grid **out, int start_index, const char *function, Build &&build) {
    if (out) *out = nullptr;
    return guarded(nullptr, function, [&] {
        require_pointer(out, function, "out");
        if (start_index != 0 && start_index != 1)
            fail(DPSM_ERR_INVALID_VALUE, function, "start_index = ", start_index,
                 " is neither 0 (indices from 0, as in C) nor 1 (from 1, as in Fortran)");
        std::shared_ptr<const dpsm::Mesh> mesh = build();
        dpsm::Geometry geometry{2, false, mesh->cells, 1, mesh->min_distance, mesh->min_distance, mesh};
        *out = new dpsm_grid(geometry);
    });
}

}  // namespace

void dpsm::record_error(const dpsm_grid *g, const char *message) noexcept {
    try {
        if (g)
            g->last_error = message;
        else
            error_without_grid = message;
    } catch (...) {
        // Out of memory for the message itself: keep the old one.
    }
}

extern "C" {

int dpsm_create_1d(int64_t nx, double dx, dpsm_grid **out) {
    return create(1, false, nx, 1, dx, 1.0, out, "dpsm_create_1d");
}

int dpsm_create_2d(int64_t nx, int64_t ny, double dx, double dy, dpsm_grid **out) {
    return create(2, false, nx, ny, dx, dy, out, "dpsm_create_2d");
}

int dpsm_create_axisymmetric(int64_t nr, double dr, dpsm_grid **out) {
    return create(1, true, nr, 1, dr, 1.0, out, "dpsm_create_axisymmetric");
}

int dpsm_create_mesh_indexed(int start_index, int64_t nnodes, const double *node_xy, int64_t ncells,
                             const int64_t *cell_start, const int64_t *cell_nodes, dpsm_grid **out) {
    const char *fn = "dpsm_create_mesh_indexed";
    return create_mesh(out, start_index, fn, [&] {
        return dpsm::mesh_from_polygons(nnodes, node_xy, ncells, cell_start, cell_nodes, fn, start_index);
    });
}

int dpsm_create_graph_indexed(int start_index, int64_t ncells, const double *cell_xy, const double *cell_area,
                              int64_t nfaces, const int64_t *face_cells, const double *face_xy,
                              const double *face_length, dpsm_grid **out) {
    const char *fn = "dpsm_create_graph_indexed";
    return create_mesh(out, start_index, fn, [&] {
        return dpsm::mesh_from_graph(ncells, cell_xy, cell_area, nfaces, face_cells, face_xy, face_length, fn,
                                     start_index);
    });
}

int dpsm_create_dual_mesh_indexed(int start_index, int64_t nnodes, const double *node_xy, int64_t ntriangles,
                                  const int64_t *triangle_nodes, dpsm_grid **out) {
    const char *fn = "dpsm_create_dual_mesh_indexed";
    return create_mesh(out, start_index, fn, [&] {
        return dpsm::mesh_from_dual(nnodes, node_xy, ntriangles, triangle_nodes, fn, start_index);
    });
}

// The constructors from 0, as C counts: the same as _indexed(0, ...), their
// messages naming themselves.
int dpsm_create_mesh(int64_t nnodes, const double *node_xy, int64_t ncells, const int64_t *cell_start,
                     const int64_t *cell_nodes, dpsm_grid **out) {
    const char *fn = "dpsm_create_mesh";
    return create_mesh(out, 0, fn, [&] {
        return dpsm::mesh_from_polygons(nnodes, node_xy, ncells, cell_start, cell_nodes, fn, 0);
    });
}

int dpsm_create_graph(int64_t ncells, const double *cell_xy, const double *cell_area, int64_t nfaces,
                      const int64_t *face_cells, const double *face_xy, const double *face_length, dpsm_grid **out) {
    const char *fn = "dpsm_create_graph";
    return create_mesh(out, 0, fn, [&] {
        return dpsm::mesh_from_graph(ncells, cell_xy, cell_area, nfaces, face_cells, face_xy, face_length, fn, 0);
    });
}

int dpsm_create_dual_mesh(int64_t nnodes, const double *node_xy, int64_t ntriangles, const int64_t *triangle_nodes,
                          dpsm_grid **out) {
    const char *fn = "dpsm_create_dual_mesh";
    return create_mesh(out, 0, fn, [&] {
        return dpsm::mesh_from_dual(nnodes, node_xy, ntriangles, triangle_nodes, fn, 0);
    });
}

// Geographic meshes and where each cell lies (issue 36): a block of its own,
// beside the constructors it extends.

int dpsm_create_mesh_geographic(int start_index, int64_t nnodes, const double *node_lonlat, int64_t ncells,
                                const int64_t *cell_start, const int64_t *cell_nodes, dpsm_grid **out) {
    const char *fn = "dpsm_create_mesh_geographic";
    return create_mesh(out, start_index, fn, [&] {
        return dpsm::mesh_from_polygons(nnodes, node_lonlat, ncells, cell_start, cell_nodes, fn, start_index, true);
    });
}

int dpsm_create_dual_mesh_geographic(int start_index, int64_t nnodes, const double *node_lonlat, int64_t ntriangles,
                                     const int64_t *triangle_nodes, dpsm_grid **out) {
    const char *fn = "dpsm_create_dual_mesh_geographic";
    return create_mesh(out, start_index, fn, [&] {
        return dpsm::mesh_from_dual(nnodes, node_lonlat, ntriangles, triangle_nodes, fn, start_index, true);
    });
}

int dpsm_get_cell_centres(const dpsm_grid *g, double *cell_xy, double *cell_area) {
    const char *fn = "dpsm_get_cell_centres";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        if (!cell_xy && !cell_area) fail(DPSM_ERR_NULL_POINTER, fn, "cell_xy and cell_area are both NULL");
        const dpsm::Geometry &geo = g->core.geometry();
        if (const dpsm::Mesh *mesh = mesh_of(g)) {
            for (std::int64_t k = 0; k < mesh->cells; ++k) {
                const std::int64_t c = mesh->cell_of_host[k];
                if (cell_area) cell_area[k] = mesh->area[c];
                if (!cell_xy) continue;
                if (mesh->projection) {
                    // In degrees, the longitude on the turn of the host's own
                    // nodes: a dual's cell is its node; a polygon's centroid
                    // lies on the turn of its first node.
                    const dpsm::MeshInput &in = mesh->input;
                    const std::int64_t node = in.kind == dpsm::MeshInput::kDual
                                                  ? k
                                                  : in.cell_nodes[in.cell_start[k] - in.start_index] - in.start_index;
                    if (in.kind == dpsm::MeshInput::kDual) {
                        cell_xy[2 * k] = in.node_xy[2 * node], cell_xy[2 * k + 1] = in.node_xy[2 * node + 1];
                        continue;
                    }
                    double lon = 0.0;
                    mesh->projection->inverse({mesh->x[c], mesh->y[c]}, lon, cell_xy[2 * k + 1]);
                    cell_xy[2 * k] = lon + 360.0 * std::round((in.node_xy[2 * node] - lon) / 360.0);
                } else {
                    cell_xy[2 * k] = mesh->x[c], cell_xy[2 * k + 1] = mesh->y[c];
                }
            }
            return;
        }
        for (std::int64_t j = 0; j < geo.ny; ++j)
            for (std::int64_t i = 0; i < geo.nx; ++i) {
                const std::int64_t c = i + geo.nx * j;
                if (cell_area) cell_area[c] = geo.cell_area(c);
                if (!cell_xy) continue;
                cell_xy[2 * c] = (static_cast<double>(i) + 0.5) * geo.dx;
                cell_xy[2 * c + 1] = geo.dim == 2 ? (static_cast<double>(j) + 0.5) * geo.dy : 0.0;
            }
    });
}

int dpsm_get_face_count(const dpsm_grid *g, int64_t *nfaces) {
    const char *fn = "dpsm_get_face_count";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_pointer(nfaces, fn, "nfaces");
        require_mesh(g, fn);
        *nfaces = mesh_of(g)->faces;
    });
}

int dpsm_get_mesh_faces(const dpsm_grid *g, int64_t *face_cells) {
    const char *fn = "dpsm_get_mesh_faces";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_pointer(face_cells, fn, "face_cells");
        require_mesh(g, fn);
        const dpsm::Mesh &m = *mesh_of(g);
        const int base = host_base(g);  // the host's cells from it, base - 1 the domain edge
        for (std::int64_t f = 0; f < m.faces; ++f) {
            const std::int64_t a = m.host_cell[m.face_a[f]] + base;
            const std::int64_t b = (m.face_b[f] < 0 ? -1 : m.host_cell[m.face_b[f]]) + base;
            const std::int64_t k = m.host_face[f];
            face_cells[2 * k] = m.host_sign[f] > 0 ? a : b;
            face_cells[2 * k + 1] = m.host_sign[f] > 0 ? b : a;
        }
    });
}

int dpsm_set_edge_kinds(dpsm_grid *g, const uint8_t *kinds) {
    const char *fn = "dpsm_set_edge_kinds";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_mesh(g, fn);
        const dpsm::Mesh &m = *mesh_of(g);
        if (!kinds) {
            g->core.set_edge_open(nullptr);
            return;
        }
        for (std::int64_t k = 0; k < m.faces; ++k)
            if (m.face_b[m.face_of_host[k]] < 0 && kinds[k] != DPSM_OPEN && kinds[k] != DPSM_WALL)
                fail(DPSM_ERR_UNKNOWN_ENUM, fn, host_face_position(g, "kinds", k), " (face ", k + host_base(g),
                     ", on the domain edge) = ", static_cast<int>(kinds[k]), " is not DPSM_OPEN or DPSM_WALL");
        std::vector<std::uint8_t> open = faces_in_library_order(m, kinds);
        for (std::uint8_t &o : open) o = o == DPSM_OPEN;
        g->core.set_edge_open(open.data());
    });
}

void dpsm_destroy(dpsm_grid *g) { delete g; }

int dpsm_set_repose_angle(dpsm_grid *g, double theta) {
    const char *fn = "dpsm_set_repose_angle";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_angle(theta, fn, "theta");
        g->core.set_repose_angle(theta);
    });
}

int dpsm_set_mobility(dpsm_grid *g, double nu) {
    const char *fn = "dpsm_set_mobility";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_scale(nu, fn, "nu");
        g->core.set_mobility(nu);
    });
}

int dpsm_set_relaxation(dpsm_grid *g, int relaxation) {
    const char *fn = "dpsm_set_relaxation";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        if (relaxation != DPSM_RELAX_TIME_ACCURATE && relaxation != DPSM_RELAX_TO_REST &&
            relaxation != DPSM_RELAX_AUTO && relaxation != DPSM_RELAX_LOCAL_STEPS)
            fail(DPSM_ERR_UNKNOWN_ENUM, fn, "relaxation = ", relaxation,
                 " is not DPSM_RELAX_TIME_ACCURATE, DPSM_RELAX_TO_REST, DPSM_RELAX_AUTO or DPSM_RELAX_LOCAL_STEPS");
        g->core.set_relaxation(static_cast<dpsm::Relaxation>(relaxation));
    });
}

int dpsm_set_scheme(dpsm_grid *g, int scheme) {
    const char *fn = "dpsm_set_scheme";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        if (scheme != DPSM_SCHEME_PAIRWISE && scheme != DPSM_SCHEME_ISOTROPIC)
            fail(DPSM_ERR_UNKNOWN_ENUM, fn, "scheme = ", scheme, " is not DPSM_SCHEME_PAIRWISE or DPSM_SCHEME_ISOTROPIC");
        // In 1D and on the axisymmetric grid there is no transverse slope:
        // both schemes are the same, and the grid keeps its pairwise sweep.
        if (g->core.geometry().dim == 2)
            g->core.set_scheme(scheme == DPSM_SCHEME_ISOTROPIC ? dpsm::kIsotropic : dpsm::kPairwise);
    });
}

int dpsm_set_boundary(dpsm_grid *g, int side, int kind) {
    const char *fn = "dpsm_set_boundary";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        if (kind != DPSM_OPEN && kind != DPSM_WALL)
            fail(DPSM_ERR_UNKNOWN_ENUM, fn, "kind = ", kind, " is not DPSM_OPEN or DPSM_WALL");
        require_side(g, side, fn);
        g->core.set_side_open(side == DPSM_MESH_EDGE ? 0 : side, kind == DPSM_OPEN);
    });
}

int dpsm_set_cell_kinds(dpsm_grid *g, const uint8_t *kinds) {
    const char *fn = "dpsm_set_cell_kinds";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        if (kinds) {
            const dpsm::Geometry &geo = g->core.geometry();
            for (std::int64_t c = 0; c < geo.cells(); ++c)
                if (kinds[c] > DPSM_CELL_OPEN)
                    fail(DPSM_ERR_UNKNOWN_ENUM, fn, host_position(g, "kinds", c), " (", host_cell_name(g, c), ") = ",
                         static_cast<int>(kinds[c]), " is not DPSM_CELL_SAND, DPSM_CELL_WALL or DPSM_CELL_OPEN");
        }
        std::vector<std::uint8_t> buffer;
        g->core.set_cell_kinds(in_library_order(g, kinds, buffer));
    });
}

int dpsm_set_heights(dpsm_grid *g, const double *h) {
    const char *fn = "dpsm_set_heights";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_finite_array(g, h, fn, "h");
        std::vector<double> buffer;
        const double *values = in_library_order(g, h, buffer);
        require_above_bed(g, g->core.whole(), values, false, fn, "h");
        g->core.write_heights(g->core.whole(), values, false);
    });
}

int dpsm_set_heights_region(dpsm_grid *g, int64_t i0, int64_t j0, int64_t ni, int64_t nj, const double *h) {
    const char *fn = "dpsm_set_heights_region";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_grid_not_mesh(g, fn);
        const dpsm::Grid::Block block = require_block(g, i0, j0, ni, nj, fn);
        require_finite_block(g, h, block, fn, "h");
        require_above_bed(g, block, h, false, fn, "h");
        g->core.write_heights(block, h, false);
    });
}

int dpsm_add_heights_region(dpsm_grid *g, int64_t i0, int64_t j0, int64_t ni, int64_t nj, const double *dh) {
    const char *fn = "dpsm_add_heights_region";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_grid_not_mesh(g, fn);
        const dpsm::Grid::Block block = require_block(g, i0, j0, ni, nj, fn);
        require_finite_block(g, dh, block, fn, "dh");
        const std::vector<double> &h = g->core.heights();
        const std::int64_t nx = g->core.geometry().nx;
        for (std::int64_t k = 0; k < ni * nj; ++k) {
            const std::int64_t c = (i0 + k % ni) + nx * (j0 + k / ni);
            if (!(std::fabs(h[c] + dh[k]) <= kMaxMagnitude))
                fail(DPSM_ERR_INVALID_VALUE, fn, block_position(g, block, "dh", k), " = ", dh[k], " added to ",
                     host_cell_name(g, c), " of height ", h[c], " leaves the supported range [-1e50, 1e50]");
        }
        require_above_bed(g, block, dh, true, fn, "dh");
        g->core.write_heights(block, dh, true);
    });
}

int dpsm_get_heights_region(const dpsm_grid *g, int64_t i0, int64_t j0, int64_t ni, int64_t nj, double *h) {
    const char *fn = "dpsm_get_heights_region";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_grid_not_mesh(g, fn);
        const dpsm::Grid::Block block = require_block(g, i0, j0, ni, nj, fn);
        require_pointer(h, fn, "h");
        g->core.read_heights(block, h);
    });
}

int dpsm_get_heights(const dpsm_grid *g, double *h) {
    const char *fn = "dpsm_get_heights";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_pointer(h, fn, "h");
        if (mesh_of(g)) {
            to_host_order(g, g->core.heights(), h);
            return;
        }
        g->core.read_heights(g->core.whole(), h);
    });
}

int dpsm_set_source(dpsm_grid *g, const double *q) {
    const char *fn = "dpsm_set_source";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        if (q) require_finite_array(g, q, fn, "q");
        std::vector<double> buffer;
        g->core.set_source(in_library_order(g, q, buffer));
    });
}

int dpsm_stable_dt(const dpsm_grid *g, double *dt) {
    const char *fn = "dpsm_stable_dt";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_pointer(dt, fn, "dt");
        *dt = dpsm::stable_dt(g->core);
    });
}

int dpsm_step(dpsm_grid *g, double dt) {
    const char *fn = "dpsm_step";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        dpsm::step(g->core, dt);  // checks dt, on every rank of a distributed grid
    });
}

int dpsm_get_mass(const dpsm_grid *g, int quantity, double *value) {
    const char *fn = "dpsm_get_mass";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        const dpsm::MassLedger &ledger = g->core.ledger();
        double local = 0.0;
        bool known = true;
        switch (quantity) {
            case DPSM_MASS_TOTAL: local = g->core.total_mass(); break;
            case DPSM_MASS_SOURCED: local = ledger.sourced.value(); break;
            case DPSM_MASS_EXTERNAL: local = ledger.external.value(); break;
            case DPSM_MASS_OUTFLOW: local = ledger.outflow.value(); break;
            case DPSM_MASS_UNMET: local = ledger.unmet.value(); break;
            default: known = false;
        }
        double total = 0.0;
        const bool all_agreed = global_figure(g, local, !value || !known, total);
        require_pointer(value, fn, "value");
        if (!known)
            fail(DPSM_ERR_UNKNOWN_ENUM, fn, "quantity = ", quantity,
                 " is not DPSM_MASS_TOTAL, DPSM_MASS_SOURCED, DPSM_MASS_EXTERNAL, DPSM_MASS_OUTFLOW"
                 " or DPSM_MASS_UNMET");
        if (!all_agreed)
            fail(DPSM_ERR_INVALID_VALUE, fn,
                 "another rank of the distributed grid refused its arguments (a NULL value or an unknown quantity), "
                 "so no rank has the global figure");
        *value = total;
    });
}

int dpsm_get_step_info(const dpsm_grid *g, int item, double *value) {
    const char *fn = "dpsm_get_step_info";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_pointer(value, fn, "value");
        const dpsm::StepInfo &info = g->core.last_step();
        switch (item) {
            case DPSM_INFO_SUBSTEPS: *value = static_cast<double>(info.substeps); break;
            case DPSM_INFO_TIME_INTEGRATED: *value = info.time_integrated; break;
            case DPSM_INFO_AT_REST: *value = info.at_rest ? 1.0 : 0.0; break;
            case DPSM_INFO_MAX_EXCESS_SLOPE: *value = info.max_excess_slope; break;
            case DPSM_INFO_CELL_UPDATES: *value = info.cell_updates; break;
            case DPSM_INFO_RANK_CELL_UPDATES:
                *value = g->core.distribution() ? info.rank_cell_updates : info.cell_updates;
                break;
            case DPSM_INFO_MESSAGES_SENT: *value = info.messages_sent; break;
            case DPSM_INFO_BYTES_SENT: *value = info.bytes_sent; break;
            case DPSM_INFO_SUBSTEPS_PER_EXCHANGE: *value = info.substeps_per_exchange; break;
            case DPSM_INFO_SUBSTEPS_EVALUATED: *value = static_cast<double>(info.substeps_evaluated); break;
            default:
                fail(DPSM_ERR_UNKNOWN_ENUM, fn, "item = ", item,
                     " is not DPSM_INFO_SUBSTEPS, DPSM_INFO_TIME_INTEGRATED, DPSM_INFO_AT_REST,"
                     " DPSM_INFO_MAX_EXCESS_SLOPE, DPSM_INFO_CELL_UPDATES, DPSM_INFO_RANK_CELL_UPDATES,"
                     " DPSM_INFO_MESSAGES_SENT, DPSM_INFO_BYTES_SENT, DPSM_INFO_SUBSTEPS_PER_EXCHANGE or"
                     " DPSM_INFO_SUBSTEPS_EVALUATED");
        }
    });
}

int dpsm_get_shape(const dpsm_grid *g, int64_t *nx, int64_t *ny) {
    const char *fn = "dpsm_get_shape";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_pointer(nx, fn, "nx");
        require_pointer(ny, fn, "ny");
        *nx = g->core.geometry().nx;
        *ny = g->core.geometry().ny;
    });
}

int dpsm_get_grid_kind(const dpsm_grid *g, int *kind) {
    const char *fn = "dpsm_get_grid_kind";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_pointer(kind, fn, "kind");
        const dpsm::Geometry &geo = g->core.geometry();
        *kind = geo.is_mesh() ? DPSM_GRID_MESH
                : geo.dim == 2 ? DPSM_GRID_2D
                : geo.axisymmetric ? DPSM_GRID_AXISYMMETRIC
                : DPSM_GRID_1D;
    });
}

int dpsm_set_rest_tolerance(dpsm_grid *g, double tol) {
    const char *fn = "dpsm_set_rest_tolerance";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_positive(tol, fn, "tol");
        g->core.set_rest_tolerance(tol);
    });
}

int dpsm_set_max_substeps(dpsm_grid *g, int64_t n) {
    const char *fn = "dpsm_set_max_substeps";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        if (n < 1) fail(DPSM_ERR_INVALID_VALUE, fn, "n = ", n, " must be at least 1");
        g->core.set_max_substeps(n);
    });
}

int dpsm_set_threads(dpsm_grid *g, int n) {
    const char *fn = "dpsm_set_threads";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        if (n < 0) fail(DPSM_ERR_INVALID_VALUE, fn, "n = ", n, " must be at least 0 (0: OpenMP's default)");
        g->core.set_threads(n);
    });
}

int dpsm_get_threads(const dpsm_grid *g, int *n) {
    const char *fn = "dpsm_get_threads";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_pointer(n, fn, "n");
        *n = g->core.geometry().dim == 1 ? 1 : g->core.step_threads();  // 1D and axisymmetric: the serial line sweep
    });
}

int dpsm_set_index_base(dpsm_grid *g, int base) {
    const char *fn = "dpsm_set_index_base";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        if (base != 0 && base != 1)
            fail(DPSM_ERR_INVALID_VALUE, fn, "base = ", base, " is neither 0 (as C counts) nor 1 (as Fortran counts)");
        if (const dpsm::Mesh *mesh = mesh_of(g)) {
            if (base != mesh->input.start_index)
                fail(DPSM_ERR_NOT_APPLICABLE, fn, "base = ", base, ": a mesh counts from the start index its "
                     "constructor was given (", mesh->input.start_index, "); create it with start_index = ", base,
                     " (dpsm_create_mesh_indexed and the others) instead");
            return;
        }
        g->core.set_index_base(base);
    });
}

int dpsm_set_bedrock(dpsm_grid *g, const double *zb) {
    const char *fn = "dpsm_set_bedrock";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        if (zb) require_finite_array(g, zb, fn, "zb");
        std::vector<double> buffer;
        g->core.set_bed(in_library_order(g, zb, buffer));
    });
}

int dpsm_set_repose_angle_field(dpsm_grid *g, const double *theta) {
    const char *fn = "dpsm_set_repose_angle_field";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        if (theta) {
            const dpsm::Geometry &geo = g->core.geometry();
            for (std::int64_t c = 0; c < geo.cells(); ++c)
                if (!(theta[c] > 0.0 && theta[c] < 0.5 * M_PI))  // also NaN
                    fail(DPSM_ERR_INVALID_VALUE, fn, host_position(g, "theta_radians", c), " (", host_cell_name(g, c),
                         ") = ", theta[c], " is outside (0, pi/2)");
        }
        std::vector<double> buffer;
        g->core.set_angle_field(in_library_order(g, theta, buffer));
    });
}

int dpsm_set_flux_exponent(dpsm_grid *g, double p) {
    const char *fn = "dpsm_set_flux_exponent";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_finite(p, fn, "p");
        if (!(p >= 1.0 && p <= DPSM_MAX_FLUX_EXPONENT))
            fail(DPSM_ERR_INVALID_VALUE, fn, "p = ", p, " is outside [1, ", DPSM_MAX_FLUX_EXPONENT,
                 "] (below 1 the law has no finite stable step, above 2 its slope grows without bound)");
        g->core.set_flux_exponent(p);
    });
}

int dpsm_set_static_angle(dpsm_grid *g, double radians) {
    const char *fn = "dpsm_set_static_angle";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_angle(radians, fn, "radians");
        g->core.set_static_angle(radians);
    });
}

int dpsm_set_side_levels(dpsm_grid *g, int side, const double *levels) {
    const char *fn = "dpsm_set_side_levels";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_side(g, side, fn);
        if (const dpsm::Mesh *mesh = mesh_of(g)) {
            if (!levels) {
                g->core.set_side_levels(0, nullptr);
                return;
            }
            const int base = host_base(g);
            require_in_range(
                levels, mesh->faces, fn, "levels", [&](std::int64_t k) { return "face " + std::to_string(k + base); },
                base);
            g->core.set_side_levels(0, faces_in_library_order(*mesh, levels).data());
            return;
        }
        if (levels) {
            const dpsm::Geometry &geo = g->core.geometry();
            const bool x_side = side <= DPSM_XMAX;
            const int base = host_base(g);
            require_in_range(
                levels, x_side ? geo.ny : geo.nx, fn, "levels",
                [&](std::int64_t k) {
                    return std::string("the face of cell ") + (x_side ? "j = " : "i = ") + std::to_string(k + base) +
                           " on side " + side_name(side);
                },
                base);
        }
        g->core.set_side_levels(side, levels);
    });
}

int dpsm_get_side_outflow(const dpsm_grid *g, int side, double *value) {
    const char *fn = "dpsm_get_side_outflow";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        const bool known = side >= DPSM_XMIN && side <= DPSM_YMAX;
        const bool mesh_edge = side == DPSM_MESH_EDGE && mesh_of(g);
        const double local =
            mesh_edge ? g->core.ledger().side_outflow[0].value() : known ? g->core.ledger().side_outflow[side].value() : 0.0;
        double total = 0.0;
        const bool all_agreed = global_figure(g, local, !value || !(known || mesh_edge), total);
        require_pointer(value, fn, "value");
        require_side(g, side, fn);
        if (!all_agreed)
            fail(DPSM_ERR_INVALID_VALUE, fn,
                 "another rank of the distributed grid refused its arguments (a NULL value or an unknown side), so no "
                 "rank has the global figure");
        *value = total;
    });
}

int dpsm_set_face_flux_recording(dpsm_grid *g, int on) {
    const char *fn = "dpsm_set_face_flux_recording";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        if (on != 0 && on != 1) fail(DPSM_ERR_INVALID_VALUE, fn, "on = ", on, " is not 0 or 1");
        g->core.set_face_flux_recording(on == 1);
    });
}

int dpsm_get_face_fluxes(const dpsm_grid *g, double *fx, double *fy) {
    const char *fn = "dpsm_get_face_fluxes";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        require_pointer(fx, fn, "fx");
        const dpsm::Geometry &geo = g->core.geometry();
        if (geo.is_mesh() && fy)
            fail(DPSM_ERR_INVALID_VALUE, fn, "fy must be NULL on a mesh: fx holds every face");
        if (geo.tiled()) require_pointer(fy, fn, "fy");
        if (geo.dim == 1 && fy)
            fail(DPSM_ERR_INVALID_VALUE, fn, "fy must be NULL on a ", geo.axisymmetric ? "axisymmetric" : "1D",
                 " grid: it has no y faces");
        const dpsm::FaceFluxes *fluxes = g->core.face_fluxes_if_any();
        if (!fluxes)
            fail(DPSM_ERR_NOT_APPLICABLE, fn, "face fluxes are not recorded on this grid: call "
                 "dpsm_set_face_flux_recording(g, 1) before the steps whose fluxes you need");
        if (!fluxes->available)
            fail(DPSM_ERR_NOT_APPLICABLE, fn, "the last step relaxed to rest (DPSM_RELAX_TO_REST), which has no face "
                 "fluxes; step with DPSM_RELAX_TIME_ACCURATE or the default for them");
        if (const dpsm::Mesh *mesh = mesh_of(g)) {
            const std::vector<double> &library = fluxes->x;
            for (std::int64_t f = 0; f < mesh->faces; ++f) fx[mesh->host_face[f]] = mesh->host_sign[f] * library[f];
            return;
        }
        dpsm::read_face_fluxes(g->core, fx, fy);
    });
}

int dpsm_save(const dpsm_grid *g, const char *path) {
    const char *fn = "dpsm_save";
    return guarded(g, fn, [&] {
        require_grid(g, fn);
        if (const dpsm::Distribution *distribution = g->core.distribution()) {
            dpsm::save_distributed(g->core, *distribution, path, fn);
            return;
        }
        require_pointer(path, fn, "path");
        dpsm::save_restart(g->core, path, fn);
    });
}

int dpsm_load(const char *path, dpsm_grid **out) {
    const char *fn = "dpsm_load";
    if (out) *out = nullptr;
    return guarded(nullptr, fn, [&] {
        require_pointer(path, fn, "path");
        require_pointer(out, fn, "out");
        dpsm::Geometry geometry{};
        dpsm::GridState state;
        dpsm::RestartBlock block;
        dpsm::load_restart(path, geometry, state, block, fn);
        if (block.present)
            fail(DPSM_ERR_NOT_APPLICABLE, fn, path, " holds the block of rank ", block.rank, " of a grid distributed over ",
                 block.ranks, " ranks (written by dpsm_save on a distributed grid); load it with dpsm_load_mpi on ",
                 block.ranks, " ranks");
        // Built completely before it is handed out: a failure leaves *out NULL.
        auto grid = std::make_unique<dpsm_grid>(geometry);
        grid->core.restore(std::move(state));
        *out = grid.release();
    });
}

const char *dpsm_last_error(const dpsm_grid *g) {
    return g ? g->last_error.c_str() : error_without_grid.c_str();
}

const char *dpsm_status_string(int status) {
    switch (status) {
        case DPSM_OK: return "DPSM_OK";
        case DPSM_ERR_NULL_POINTER: return "DPSM_ERR_NULL_POINTER";
        case DPSM_ERR_INVALID_VALUE: return "DPSM_ERR_INVALID_VALUE";
        case DPSM_ERR_INVALID_SIZE: return "DPSM_ERR_INVALID_SIZE";
        case DPSM_ERR_UNKNOWN_ENUM: return "DPSM_ERR_UNKNOWN_ENUM";
        case DPSM_ERR_NOT_APPLICABLE: return "DPSM_ERR_NOT_APPLICABLE";
        case DPSM_ERR_WORK_LIMIT: return "DPSM_ERR_WORK_LIMIT";
        case DPSM_ERR_OUT_OF_MEMORY: return "DPSM_ERR_OUT_OF_MEMORY";
        case DPSM_ERR_INTERNAL: return "DPSM_ERR_INTERNAL";
        case DPSM_ERR_IO: return "DPSM_ERR_IO";
        case DPSM_ERR_BAD_FILE: return "DPSM_ERR_BAD_FILE";
        default: return "unknown status";
    }
}

const char *dpsm_version_string(void) { return DPSM_VERSION_STRING; }

int dpsm_version_number(void) { return DPSM_VERSION_NUMBER; }

}  // extern "C"
