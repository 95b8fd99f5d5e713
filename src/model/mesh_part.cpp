#include "model/mesh_part.hpp"

#include <algorithm>

#include "dpsm/dpsm.h"
#include "model/error.hpp"
#include "model/mesh_build.hpp"

namespace dpsm {

namespace {

// How many sub-steps after an exchange each cell of a part stays its
// owner's when stepped here (Mesh::reach), and the ghosts by reach. Valid after 0 sub-steps: every cell. A sub-step's passes
// (mesh/mesh_engine.cpp) read outward: in sub-step j a gradient is exact
// when its cell has its own stencil and every cell of it was exact after j -
// 1; a face's slope and fluxes of its own when its cells and their
// gradients were; a cell's pull (M^-1 P) when it has its own stencil, all
// its faces over the whole mesh are here (ghost_faces: as its owner counts
// them) and their slopes exact; a face's gradient-flow flux when its slope
// and its cells' pulls are; a cell's limiter when it was exact, all its
// faces are here and their gradient-flow fluxes exact; a face's limited flux
// when its cells' limiters are; a cell's new height when all its faces'
// limited fluxes are. Sets substeps_per_exchange to the highest j at which
// every owned cell is exact (the caller takes the smallest over ranks).
void set_reach(Mesh &m, const std::vector<std::uint8_t> &has_stencil, const std::vector<double> &ghost_faces) {
    const std::size_t n = static_cast<std::size_t>(m.cells), nf = static_cast<std::size_t>(m.faces);
    std::vector<std::uint8_t> valid(n, 1), gradient(n, 0), slope(nf, 0), pull(n, 0), high(nf, 0), limiter(n, 0),
        flux(nf, 0), faces_here(n, 1);
    for (std::int64_t c = m.owned; c < m.cells; ++c)
        faces_here[static_cast<std::size_t>(c)] =
            static_cast<double>(m.cell_face_start[c + 1] - m.cell_face_start[c]) == ghost_faces[c - m.owned];
    m.reach.assign(n, 0);
    m.substeps_per_exchange = 0;
    // Whether every face of c is here and `exact` for it.
    const auto all_faces = [&](std::size_t c, const std::vector<std::uint8_t> &exact) {
        bool all = faces_here[c] != 0;
        for (std::int64_t k = m.cell_face_start[c]; all && k < m.cell_face_start[c + 1]; ++k)
            all = exact[static_cast<std::size_t>(m.cell_faces[k])] != 0;
        return all;
    };
    // Whether both cells of f are `exact`.
    const auto both_cells = [&](std::size_t f, const std::vector<std::uint8_t> &exact) {
        const std::int64_t b = m.face_b[f];
        return exact[static_cast<std::size_t>(m.face_a[f])] && (b < 0 || exact[static_cast<std::size_t>(b)]);
    };
    for (int j = 1; j <= Mesh::kMaxReach; ++j) {
        for (std::size_t c = 0; c < n; ++c) {
            bool exact = has_stencil[c] && valid[c];
            for (std::int64_t k = m.grad_start[c]; exact && k < m.grad_start[c + 1]; ++k)
                exact = valid[static_cast<std::size_t>(m.grad_cells[k])] != 0;
            gradient[c] = exact;
        }
        for (std::size_t f = 0; f < nf; ++f) slope[f] = both_cells(f, valid) && both_cells(f, gradient);
        for (std::size_t c = 0; c < n; ++c) pull[c] = has_stencil[c] && all_faces(c, slope);
        for (std::size_t f = 0; f < nf; ++f) high[f] = slope[f] && both_cells(f, pull);
        for (std::size_t c = 0; c < n; ++c) limiter[c] = valid[c] && all_faces(c, high);
        for (std::size_t f = 0; f < nf; ++f) flux[f] = high[f] && both_cells(f, limiter);
        bool owned_exact = true;
        for (std::size_t c = 0; c < n; ++c) {
            const bool exact = valid[c] && all_faces(c, flux);
            valid[c] = exact;
            if (exact) m.reach[c] = static_cast<std::int8_t>(j);
            if (static_cast<std::int64_t>(c) < m.owned) owned_exact = owned_exact && exact;
        }
        if (!owned_exact) break;
        m.substeps_per_exchange = j;
    }
    // The ghosts in reach, highest reach first, and per j how many reach j.
    std::vector<std::int64_t> &list = m.ghosts_by_reach;
    list.clear();
    for (std::int64_t c = m.owned; c < m.cells; ++c)
        if (m.reach[static_cast<std::size_t>(c)] > 0) list.push_back(c);
    std::stable_sort(list.begin(), list.end(), [&](std::int64_t l, std::int64_t r) {
        return m.reach[static_cast<std::size_t>(l)] > m.reach[static_cast<std::size_t>(r)];
    });
    m.ghosts_with_reach.assign(Mesh::kMaxReach + 1, 0);
    for (const std::int64_t c : list)
        for (int j = 0; j <= m.reach[static_cast<std::size_t>(c)]; ++j) ++m.ghosts_with_reach[static_cast<std::size_t>(j)];
}

}  // namespace

std::shared_ptr<Mesh> part_from_polygons(std::int64_t nnodes, const double *node_xy, std::int64_t ncells,
                                         const std::int64_t *cell_start, const std::int64_t *cell_nodes,
                                         const PartOfMesh &part, const char *function, int base) {
    return assemble_polygons(nnodes, node_xy, ncells, cell_start, cell_nodes, &part, function, base);
}

std::shared_ptr<Mesh> part_from_graph(std::int64_t ncells, const double *cell_xy, const double *cell_area,
                                      std::int64_t nfaces, const std::int64_t *face_cells, const double *face_xy,
                                      const double *face_length, const PartOfMesh &part, const char *function,
                                      int base) {
    return assemble_graph(ncells, cell_xy, cell_area, nfaces, face_cells, face_xy, face_length, &part, function, base);
}

std::shared_ptr<Mesh> part_from_input(const MeshInput &input, int rank, const char *function) {
    const std::size_t n = input.global_id.size();
    std::vector<std::uint8_t> ghost(n);
    for (std::size_t c = 0; c < n; ++c) ghost[c] = input.owner[c] != rank;
    const PartOfMesh part{input.global_id.data(), ghost.data()};
    std::shared_ptr<Mesh> mesh;
    const int base = input.start_index;
    if (input.kind == MeshInput::kPolygons) {
        const std::int64_t ncells = static_cast<std::int64_t>(input.cell_start.size()) - 1;
        if (ncells != static_cast<std::int64_t>(n) ||
            input.cell_start.back() - base != static_cast<std::int64_t>(input.cell_nodes.size()))
            fail(DPSM_ERR_BAD_FILE, function, "the mesh's cells do not match their node list");
        mesh = assemble_polygons(static_cast<std::int64_t>(input.node_xy.size() / 2), input.node_xy.data(), ncells,
                                 input.cell_start.data(), input.cell_nodes.data(), &part, function, base);
    } else if (input.kind == MeshInput::kGraph && input.ncells == static_cast<std::int64_t>(n)) {
        mesh = assemble_graph(input.ncells, input.cell_xy.data(), input.cell_area.data(),
                              static_cast<std::int64_t>(input.face_length.size()), input.face_cells.data(),
                              input.face_xy.data(), input.face_length.data(), &part, function, base);
    } else {
        fail(DPSM_ERR_BAD_FILE, function, "a part of a distributed mesh of kind ", static_cast<unsigned>(input.kind),
             " with ", n, " cells");
    }
    mesh->input.global_id = input.global_id;
    mesh->input.owner = input.owner;
    return mesh;
}

void finish_part(Mesh &m, const std::vector<std::int64_t> &ghost_start,
                 const std::vector<std::int64_t> &ghost_neighbours, const std::vector<double> &ghost_faces) {
    std::vector<std::uint8_t> has_stencil;
    gradient_weights(m, ghost_start, ghost_neighbours, has_stencil);
    set_reach(m, has_stencil, ghost_faces);
    for (std::int64_t c = m.owned; c < m.cells; ++c) m.face_count[c] = ghost_faces[c - m.owned];
    set_step_scale(m);
}

}  // namespace dpsm
