// An unstructured mesh as the mesh engine reads it: cells with an area and a
// centre, faces between two cells (or on the domain edge), and what a face's
// slope needs (its distance, its conductance, the least-squares gradients of
// its cells). Built from what a host holds (polygons over nodes, a
// finite-volume graph, the median dual of a triangle mesh), checked, and
// renumbered along a Hilbert curve over the cell centres so that neighbours
// lie near each other in memory; the host keeps its own numbering
// (host_cell, cell_of_host, host_face, face_of_host).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "model/sphere.hpp"

namespace dpsm {

// What the host gave, kept to save in a restart file and to build the same
// mesh from it again: the arrays as the host passed them, their indices
// counting from start_index.
struct MeshInput {
    enum Kind : std::uint32_t { kPolygons = 1, kGraph = 2, kDual = 3 };
    Kind kind = kPolygons;
    // 0 (C) or 1 (Fortran, UGRID's start_index = 1): where the host's
    // numbers of cells, nodes and faces begin, in its arrays and in every
    // message that names one of them, of the constructor and later ones.
    int start_index = 0;
    // The nodes' coordinates are longitude and latitude in degrees (the
    // _geographic constructors); lengths and areas are then on the sphere
    // (model/sphere.hpp).
    bool geographic = false;
    // kPolygons and kDual: nodes and cells over them (kDual: 3 per triangle,
    // cell_start empty).
    std::vector<double> node_xy;
    std::vector<std::int64_t> cell_start, cell_nodes;
    // kGraph: cells and faces as the host holds them.
    std::int64_t ncells = 0;
    std::vector<double> cell_xy, cell_area, face_xy, face_length;
    std::vector<std::int64_t> face_cells;
    // A rank's part of a distributed mesh: per host cell, its global id (from
    // 0) and its owner's rank; empty on a serial mesh.
    std::vector<std::int64_t> global_id;
    std::vector<std::int32_t> owner;
};

struct Mesh {
    MeshInput input;
    std::int64_t cells = 0, faces = 0;

    // Per cell, in the library's order.
    std::vector<double> area, x, y;
    // Cell c's faces are cell_faces[cell_face_start[c] .. cell_face_start[c + 1]):
    // those between cells by the host's number of the cell across, then those
    // on the domain edge by their midpoints, so that no sum over them depends
    // on the library's order or the host's listing of faces; a face's other
    // cell is `other` at the same place (-1 on the domain edge).
    std::vector<std::int64_t> cell_face_start, cell_faces, other;
    // At the same place: +1 where the face's flux (from its a to its b)
    // enters the cell, -1 where it leaves.
    std::vector<double> into;
    // The least-squares gradient of cell c is the sum over
    // grad_cells[grad_start[c] .. grad_start[c + 1]) of (grad_wx, grad_wy) *
    // (h_n - h_c), over the cells across its faces (none where they do not
    // span the plane), in the order of the host's cell numbers, as the
    // faces. One ring, so that every pair of a stencil shares a face, over
    // which the gradient flow's pair term runs (mesh/mesh_engine.cpp). The
    // cells a change of height reaches through gradients are
    // the same list (the stencil is symmetric), which the active set wakes.
    // A ghost of a distributed mesh's part takes its gradient from its owner:
    // its list holds the owned cells whose gradients read it (weights 0), so
    // that a change of its height wakes them.
    std::vector<std::int64_t> grad_start, grad_cells;
    std::vector<double> grad_wx, grad_wy;
    // Per cell, the inverse of its least-squares matrix M = sum w o o^T (0
    // without a stencil); per face, the offset o from a to b as a's fit sees
    // it over |o|^2 (pair_ax, pair_ay), and from b to a as b's sees it
    // (pair_bx, pair_by; 0 on the domain edge). The weight of b in a's
    // gradient is M_a^-1 (pair_ax, pair_ay), so a vector P_a enters a face as
    // pair_a . (M_a^-1 P_a) and a part needs its ghosts' M^-1 P alone.
    std::vector<double> grad_ixx, grad_ixy, grad_iyy;
    std::vector<double> pair_ax, pair_ay, pair_bx, pair_by;

    // Per face, in the library's order: cells a < b (b == -1 on the domain
    // edge), the centre-to-centre distance d (on the domain edge twice the
    // distance to the face's midpoint: the outside is the cell's mirror
    // image), the unit tangent t perpendicular to the unit vector e from a
    // to b, whose gradient component completes the face's slope, and the
    // face's normal times its length, L n, split along e and t: orthogonal =
    // L n . e (at least 0), skew = L n . t (0 where the face is orthogonal to
    // the line between its cells, as on a graph); conductance = |L n| / d
    // bounds what a face may carry per unit height difference and slope law.
    std::vector<std::int64_t> face_a, face_b;
    std::vector<double> distance, tangent_x, tangent_y, orthogonal, skew, conductance;
    // The direction from a to b relative to the host's face (+1 or -1): a
    // host reads a face's flux as positive from its own cell a to its b.
    std::vector<signed char> host_sign;

    // The library's cell c is the host's host_cell[c]; the host's cell k is
    // the library's cell_of_host[k]. The same for faces.
    std::vector<std::int64_t> host_cell, cell_of_host, host_face, face_of_host;

    // A rank's part of a distributed mesh (mpi/distributed_mesh.cpp): cells
    // [0, owned) are the rank's own, [owned, cells) its ghosts, whose values
    // come from the ranks that own them; faces [0, live_faces) touch an owned
    // cell, the others (between two ghosts, or on a ghost's outer edges)
    // carry nothing on this rank. A serial mesh owns every cell and face.
    std::int64_t owned = 0, live_faces = 0;
    // Per cell, the number by which every sum orders it: the host's number on
    // a serial mesh, the cell's global id on a distributed one, so that each
    // rank adds in the serial mesh's order.
    std::vector<std::int64_t> global_id;
    // Per cell, its faces over the whole mesh (a ghost's from its owner): a
    // face may take this share of a cell's sand above its bed.
    std::vector<double> face_count;

    // A part's redundant sub-steps (mpi/distributed_mesh.cpp). After an
    // exchange every local cell holds its owner's values; where the host's
    // ghost layer is deep, ghosts near the owned cells can then be stepped
    // here exactly as their owners step them, for a few sub-steps, and the
    // ranks exchange once per that many sub-steps. In the j-th sub-step
    // after an exchange (from 1), cell c's new height is its owner's if
    // reach[c] >= j (owned cells: kMaxReach). The ghosts in reach are listed
    // by reach, highest first, in ghosts_by_reach; its first
    // ghosts_with_reach[j] entries are those whose reach is at least j.
    // substeps_per_exchange: the sub-steps all ranks take per exchange (0:
    // exchanges in every sub-step).
    static constexpr int kMaxReach = 8;
    std::vector<std::int8_t> reach;
    std::vector<std::int64_t> ghosts_by_reach;
    std::vector<std::int64_t> ghosts_with_reach;  // per j, 0 .. kMaxReach
    int substeps_per_exchange = 0;

    // A geographic mesh (MeshInput::geographic): the plane its x and y lie in
    // (null on other meshes); lengths, distances and areas are on the sphere.
    std::shared_ptr<const Stereographic> projection;

    // The smallest distance of any face (the rest tolerance's length scale).
    double min_distance = 0.0;
    // The smallest area over summed conductance of any cell: the largest
    // monotone sub-step is this over the flux law's largest slope.
    double step_scale = 0.0;
};

// Each builds a mesh from the host's arrays, checked, or throws
// Error(DPSM_ERR_*) naming the host's cell, node or face and the function in
// `function`. The arrays' indices count from `base` (0 or 1, checked by the
// caller): cell_start[0] == base, node and cell indices from base, base - 1
// for the domain edge in face_cells; the messages count from it too, quote
// the host's values and name array positions as the host writes them
// (host_position).
// With `geographic`, node_xy holds longitude and latitude in degrees
// (model/sphere.hpp).
std::shared_ptr<const Mesh> mesh_from_polygons(std::int64_t nnodes, const double *node_xy, std::int64_t ncells,
                                               const std::int64_t *cell_start, const std::int64_t *cell_nodes,
                                               const char *function, int base, bool geographic = false);
std::shared_ptr<const Mesh> mesh_from_graph(std::int64_t ncells, const double *cell_xy, const double *cell_area,
                                            std::int64_t nfaces, const std::int64_t *face_cells,
                                            const double *face_xy, const double *face_length, const char *function,
                                            int base);
std::shared_ptr<const Mesh> mesh_from_dual(std::int64_t nnodes, const double *node_xy, std::int64_t ntriangles,
                                           const std::int64_t *triangle_nodes, const char *function, int base,
                                           bool geographic = false);

// The same mesh again from what a restart file kept.
std::shared_ptr<const Mesh> mesh_from_input(const MeshInput &input, const char *function);

// Position k of the host's array `name`, as a host that counts from `base`
// writes it: C's name[k] (base 0), Fortran's name(k+1) (base 1). With `rows`
// > 1 the array holds tuples of that many values (node_xy, face_cells,
// triangle_nodes; a 2D grid's rows of nx cells), which Fortran holds as the
// columns of name(rows, n): name(k % rows + 1, k / rows + 1).
std::string host_position(const char *name, std::int64_t k, int base, std::int64_t rows = 1);

}  // namespace dpsm
