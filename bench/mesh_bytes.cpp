// dpsm-bench mesh's count of the memory a fully active sub-step of the mesh
// engine moves, from its data layout, beside the bound that the machine's
// triad bandwidth sets (docs/performance.md, "Bytes per cell update").
//
// Each pass of the dense sub-step in src/mesh/mesh_engine.cpp streams the
// arrays indexed by its own items (cells or faces) and gathers those of
// their neighbours. Every array a pass reads counts once per pass and every
// array it writes once more (no write-allocate), as if no pass found
// another's data in cache; gathered arrays count once too, since on the
// Hilbert order a neighbour's values share cache lines with the cell's own.
// The count is what the layout asks of memory, not what a cache hierarchy
// makes of it. Keep it in step with the passes it names: it reads the
// engine's own mesh (src/model/mesh.hpp) through the static library.
#include <cstdint>
#include <cstdio>

#include "api/handle.hpp"
#include "model/mesh.hpp"

namespace {

using dpsm::Mesh;

struct SubstepBytes {
    double gradients = 0.0, faces = 0.0, pulls = 0.0, flows = 0.0, limits = 0.0, limited = 0.0, updates = 0.0;
    double total() const { return gradients + faces + pulls + flows + limits + limited + updates; }
};

// A serial mesh's plain scene (sand everywhere; no bed, angle field, static
// angle or source), isotropic gradients.
SubstepBytes substep_bytes(const Mesh &m) {
    const double cells = static_cast<double>(m.cells), faces = static_cast<double>(m.faces);
    const double cell_faces = static_cast<double>(m.cell_faces.size());
    const double stencil = static_cast<double>(m.grad_cells.size());
    const double index = sizeof(std::int64_t), real = sizeof(double), flag = sizeof(std::uint8_t);
    const double starts = (cells + 1.0) * index;  // a CSR's starts
    SubstepBytes b;
    // gradient_of: grad_start, grad_cells, grad_wx, grad_wy; kind and h of
    // the stencil; gx, gy written.
    b.gradients = starts + stencil * (index + 2.0 * real) + cells * (flag + real) + 2.0 * cells * real;
    // FaceLaw::terms: carrying, face_a, face_b, tangent_x, tangent_y,
    // distance, orthogonal, skew, conductance; kind, h, gx, gy of the
    // cells; low, high, pull, excess and steep written.
    b.faces = faces * (flag + 2.0 * index + 6.0 * real) + cells * (flag + 3.0 * real) + faces * (4.0 * real + flag);
    // pull_of: cell_face_start, cell_faces; pull, tangent_x, tangent_y of
    // the faces; grad_ixx, grad_ixy, grad_iyy; pull_x, pull_y written.
    b.pulls = starts + cell_faces * index + faces * 3.0 * real + cells * 3.0 * real + cells * 2.0 * real;
    // gradient_flow_flux: carrying, face_a, face_b, pair_ax .. pair_by, high
    // read and written; pull_x, pull_y of the cells.
    b.flows = faces * (flag + 2.0 * index + 4.0 * real + 2.0 * real) + cells * 2.0 * real;
    // limits_of: kind, h, area; cell_face_start, cell_faces, into, other;
    // low, high, carrying of the faces; limit_in, limit_out written.
    b.limits = cells * (flag + 2.0 * real) + starts + cell_faces * (2.0 * index + real) + faces * (2.0 * real + flag) +
               cells * 2.0 * real;
    // limited_flux: low, high, excess, face_a, face_b; limit_in, limit_out
    // of the cells; flux written.
    b.limited = faces * (3.0 * real + 2.0 * index) + cells * 2.0 * real + faces * real;
    // CellUpdate: cell_face_start, cell_faces, into; flux of the faces;
    // kind, area; h and residual read and written; carried written.
    b.updates = starts + cell_faces * (index + real) + faces * real + cells * (flag + real) +
                cells * 2.0 * (real + sizeof(float)) + cells * flag;
    return b;
}


}  // namespace

// The bytes per cell update of a fully active sub-step on mesh g (0 where g
// is not a mesh), each pass's share written to `log`.
extern "C" double bench_mesh_bytes_per_update(const dpsm_grid *g, FILE *log) {
    const dpsm::Geometry &geometry = g->core.geometry();
    if (!geometry.is_mesh()) return 0.0;
    const Mesh &m = *geometry.mesh;
    const SubstepBytes b = substep_bytes(m);
    const double per = 1.0 / static_cast<double>(m.owned);
    std::fprintf(log,
                 "bytes per cell update: %.0f (gradients %.0f, faces %.0f, pulls %.0f, flows %.0f, limits %.0f, "
                 "limited fluxes %.0f, updates %.0f); %.2f faces and %.2f gradient neighbours a cell\n",
                 b.total() * per, b.gradients * per, b.faces * per, b.pulls * per, b.flows * per, b.limits * per,
                 b.limited * per, b.updates * per, static_cast<double>(m.faces) * per,
                 static_cast<double>(m.grad_cells.size()) * per);
    return b.total() * per;
}
