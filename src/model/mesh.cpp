#include "model/mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <sstream>
#include <string>
#include <utility>

#include "dpsm/dpsm.h"
#include "model/error.hpp"
#include "model/limits.hpp"
#include "model/mesh_build.hpp"
#include "model/mesh_part.hpp"
#include "model/sphere.hpp"
#include "model/switches.hpp"

namespace dpsm {

namespace {

struct Vec {
    double x, y;
};
Vec operator-(Vec a, Vec b) { return {a.x - b.x, a.y - b.y}; }
Vec operator+(Vec a, Vec b) { return {a.x + b.x, a.y + b.y}; }
Vec operator*(double s, Vec a) { return {s * a.x, s * a.y}; }
double dot(Vec a, Vec b) { return a.x * b.x + a.y * b.y; }
double cross(Vec a, Vec b) { return a.x * b.y - a.y * b.x; }
double norm(Vec a) { return std::hypot(a.x, a.y); }

// A face as the builders find it, in the host's numbering.
struct RawFace {
    std::int64_t a, b;  // b == -1: domain edge
    Vec mid;
    double length;
    Vec normal_length;  // length times the unit normal, pointing from a to b (outwards on the edge)
    bool normal_known;  // false on a graph: the normal is taken along a to b
    std::int64_t along = 0;  // polygons: the edge's place in cell a, which orders the host's faces
    // When positive, the distance between the face's cells (on the domain
    // edge: between the cell and its mirror image) instead of the one
    // between their centres in the plane: on the sphere for a geographic
    // mesh; for a graph's cell whose centre lies on this edge face.
    double distance = 0.0;
};

struct RawCells {
    std::vector<double> area;
    std::vector<Vec> centre;
};

void require_coordinates(const double *xy, std::int64_t n, const char *function, const char *name, const char *what,
                         int base) {
    if (!xy) fail(DPSM_ERR_NULL_POINTER, function, name, " is NULL");
    for (std::int64_t k = 0; k < 2 * n; ++k)
        if (!std::isfinite(xy[k]) || std::fabs(xy[k]) > kMaxMagnitude)
            fail(DPSM_ERR_INVALID_VALUE, function, host_position(name, k, base, 2), " (", k % 2 ? "y" : "x", " of ",
                 what, " ", k / 2 + base, ") = ", xy[k], " is not finite or lies outside [-1e50, 1e50]");
}

// Whether the host's index v (counting from base) names one of n things.
bool is_index(std::int64_t v, std::int64_t n, int base) { return v >= base && v <= n - 1 + base; }

// The host's indices counting from 0, for the work after the checks: the
// host's own array when it counts from 0, else a copy in `buffer`. A value
// base - 1 (face_cells' domain edge) becomes -1.
const std::int64_t *from_zero(const std::int64_t *v, std::int64_t n, int base, std::vector<std::int64_t> &buffer) {
    if (base == 0) return v;
    buffer.resize(static_cast<std::size_t>(n));
    for (std::int64_t k = 0; k < n; ++k) buffer[k] = v[k] - base;
    return buffer.data();
}

void require_count(std::int64_t n, const char *function, const char *name) {
    if (n < 1) fail(DPSM_ERR_INVALID_SIZE, function, name, " = ", n, " must be at least 1");
    if (n > kMaxCells) fail(DPSM_ERR_INVALID_SIZE, function, name, " = ", n, " is more than this library can address");
}

// The Hilbert index of (x, y) on a 2^16 by 2^16 lattice.
std::uint64_t hilbert_index(std::uint32_t x, std::uint32_t y) {
    std::uint64_t d = 0;
    for (std::uint32_t s = 1u << 15; s > 0; s >>= 1) {
        const std::uint32_t rx = (x & s) ? 1u : 0u, ry = (y & s) ? 1u : 0u;
        d += static_cast<std::uint64_t>(s) * s * ((3u * rx) ^ ry);
        if (ry == 0) {
            if (rx == 1) {
                x = s - 1 - (x & (s - 1)) + (x & ~(s - 1));
                y = s - 1 - (y & (s - 1)) + (y & ~(s - 1));
                x &= (s << 1) - 1;
                y &= (s << 1) - 1;
            }
            std::swap(x, y);
        }
    }
    return d;
}

// Cells ordered along a Hilbert curve over their centres.
std::vector<std::int64_t> hilbert_order(const std::vector<Vec> &centre) {
    double x0 = centre[0].x, x1 = x0, y0 = centre[0].y, y1 = y0;
    for (const Vec &c : centre) {
        x0 = std::min(x0, c.x), x1 = std::max(x1, c.x);
        y0 = std::min(y0, c.y), y1 = std::max(y1, c.y);
    }
    const double span = std::max({x1 - x0, y1 - y0, 1e-300});
    std::vector<std::pair<std::uint64_t, std::int64_t>> keyed(centre.size());
    for (std::size_t c = 0; c < centre.size(); ++c) {
        const auto lattice = [&](double v, double lo) {
            return static_cast<std::uint32_t>(std::min(65535.0, std::floor((v - lo) / span * 65535.0)));
        };
        keyed[c] = {hilbert_index(lattice(centre[c].x, x0), lattice(centre[c].y, y0)), static_cast<std::int64_t>(c)};
    }
    std::sort(keyed.begin(), keyed.end());
    std::vector<std::int64_t> order(centre.size());
    for (std::size_t k = 0; k < keyed.size(); ++k) order[k] = keyed[k].second;
    return order;
}

// Each cell's faces in the order its sums take them (net flux, summed
// conductance): the cells across them by the host's numbers, then the domain
// edge's faces by their midpoints. Neither the library's order of cells nor
// the order or direction in which the host lists faces changes a sum, as a
// distributed mesh needs: its ranks order their parts each their own way.
void order_each_cells_faces(Mesh &m, const std::vector<RawFace> &faces) {
    struct Entry {
        std::int64_t face, other;
        double into;
    };
    std::vector<Entry> entries;
    for (std::int64_t c = 0; c < m.cells; ++c) {
        const std::int64_t k0 = m.cell_face_start[c], k1 = m.cell_face_start[c + 1];
        entries.clear();
        for (std::int64_t k = k0; k < k1; ++k) entries.push_back({m.cell_faces[k], m.other[k], m.into[k]});
        std::sort(entries.begin(), entries.end(), [&](const Entry &l, const Entry &r) {
            if ((l.other < 0) != (r.other < 0)) return r.other < 0;
            if (l.other >= 0) return m.global_id[l.other] < m.global_id[r.other];
            const Vec &ml = faces[m.host_face[l.face]].mid, &mr = faces[m.host_face[r.face]].mid;
            return ml.x < mr.x || (ml.x == mr.x && ml.y < mr.y);
        });
        for (std::int64_t k = k0; k < k1; ++k) {
            const Entry &e = entries[static_cast<std::size_t>(k - k0)];
            m.cell_faces[k] = e.face, m.other[k] = e.other, m.into[k] = e.into;
        }
    }
}

}  // namespace

// The least-squares gradient weights of every owned cell, weighted by
// inverse distance squared, over the cells across its faces; a cell whose
// neighbours do not span the plane gets none (its faces use the two-point
// slope alone). The neighbours of a ghost n are
// ghost_neighbours[ghost_start[n - owned] .. ghost_start[n - owned + 1]), as
// n's owner knows them (-1: not on this rank). A ghost whose neighbours are
// all on this rank gets its weights too, as its owner has them
// (has_stencil); another ghost's list holds the cells whose gradients read
// it (weights 0), so that a change of its height wakes them. With the
// weights: each cell's inverse least-squares matrix and each face's pair
// offsets (Mesh::grad_ixx, Mesh::pair_ax), what the gradient flow's pair
// terms read.
void gradient_weights(Mesh &m, const std::vector<std::int64_t> &ghost_start,
                      const std::vector<std::int64_t> &ghost_neighbours, std::vector<std::uint8_t> &has_stencil) {
    std::vector<std::int64_t> stencil_start(static_cast<std::size_t>(m.cells) + 1, 0), stencil;
    has_stencil.assign(static_cast<std::size_t>(m.cells), 0);
    std::vector<std::int64_t> seen(m.cells, -1), ring;
    for (std::int64_t c = 0; c < m.cells; ++c) {
        ring.clear();
        seen[c] = c;
        const auto visit_neighbours = [&](std::int64_t n) {
            bool all_here = true;
            const auto visit = [&](std::int64_t v) {
                if (v >= 0 && seen[v] != c) seen[v] = c, ring.push_back(v);
            };
            if (n < m.owned) {
                for (std::int64_t k = m.cell_face_start[n]; k < m.cell_face_start[n + 1]; ++k) visit(m.other[k]);
            } else {
                const std::size_t g = static_cast<std::size_t>(n - m.owned);
                for (std::int64_t k = ghost_start[g]; k < ghost_start[g + 1]; ++k) {
                    all_here = all_here && ghost_neighbours[k] >= 0;
                    visit(ghost_neighbours[k]);
                }
            }
            return all_here;
        };
        if (visit_neighbours(c)) {
            has_stencil[static_cast<std::size_t>(c)] = 1;
            std::sort(ring.begin(), ring.end(),
                      [&](std::int64_t l, std::int64_t r) { return m.global_id[l] < m.global_id[r]; });
            stencil.insert(stencil.end(), ring.begin(), ring.end());
        }
        stencil_start[static_cast<std::size_t>(c) + 1] = static_cast<std::int64_t>(stencil.size());
    }
    // A cell without its own stencil: the cells whose stencils hold it, in ascending order.
    std::vector<std::int64_t> readers(static_cast<std::size_t>(m.cells), 0);
    for (const std::int64_t n : stencil)
        if (!has_stencil[static_cast<std::size_t>(n)]) ++readers[static_cast<std::size_t>(n)];
    m.grad_start.assign(m.cells + 1, 0);
    for (std::int64_t c = 0; c < m.cells; ++c) {
        const std::size_t k = static_cast<std::size_t>(c);
        m.grad_start[k + 1] = m.grad_start[k] + (has_stencil[k] ? stencil_start[k + 1] - stencil_start[k] : readers[k]);
    }
    m.grad_cells.assign(static_cast<std::size_t>(m.grad_start[m.cells]), 0);
    std::vector<std::int64_t> next(m.grad_start.begin(), m.grad_start.end() - 1);
    for (std::int64_t c = 0; c < m.cells; ++c) {
        if (!has_stencil[static_cast<std::size_t>(c)]) continue;
        for (std::int64_t k = stencil_start[c]; k < stencil_start[c + 1]; ++k) {
            const std::int64_t n = stencil[static_cast<std::size_t>(k)];
            m.grad_cells[static_cast<std::size_t>(next[c]++)] = n;
            if (!has_stencil[static_cast<std::size_t>(n)]) m.grad_cells[static_cast<std::size_t>(next[n]++)] = c;
        }
    }
    m.grad_wx.assign(m.grad_cells.size(), 0.0);
    m.grad_wy.assign(m.grad_cells.size(), 0.0);
    m.grad_ixx.assign(static_cast<std::size_t>(m.cells), 0.0);
    m.grad_ixy.assign(static_cast<std::size_t>(m.cells), 0.0);
    m.grad_iyy.assign(static_cast<std::size_t>(m.cells), 0.0);
    // The neighbours' offsets: in the plane, or on a geographic mesh as seen
    // from the cell on the sphere (great-circle distance and direction), so
    // that the gradient is the true one in metres.
    const auto offset = [&](std::int64_t c, std::int64_t n) {
        if (!m.projection) return PlanePoint{m.x[n] - m.x[c], m.y[n] - m.y[c]};
        return m.projection->offset({m.x[c], m.y[c]}, {m.x[n], m.y[n]});
    };
    for (std::int64_t c = 0; c < m.cells; ++c) {
        if (!has_stencil[static_cast<std::size_t>(c)]) continue;
        double sxx = 0.0, sxy = 0.0, syy = 0.0;
        const std::int64_t k0 = m.grad_start[c], k1 = m.grad_start[c + 1];
        for (std::int64_t k = k0; k < k1; ++k) {
            const PlanePoint o = offset(c, m.grad_cells[k]);
            const double dx = o.x, dy = o.y;
            const double w = 1.0 / (dx * dx + dy * dy);
            sxx += w * dx * dx, sxy += w * dx * dy, syy += w * dy * dy;
        }
        const double det = sxx * syy - sxy * sxy;
        const double trace = sxx + syy;
        if (!(det > 1e-6 * trace * trace)) continue;
        m.grad_ixx[static_cast<std::size_t>(c)] = syy / det;
        m.grad_ixy[static_cast<std::size_t>(c)] = -sxy / det;
        m.grad_iyy[static_cast<std::size_t>(c)] = sxx / det;
        for (std::int64_t k = k0; k < k1; ++k) {
            const PlanePoint o = offset(c, m.grad_cells[k]);
            const double dx = o.x, dy = o.y;
            const double w = 1.0 / (dx * dx + dy * dy);
            m.grad_wx[k] = w * (syy * dx - sxy * dy) / det;
            m.grad_wy[k] = w * (sxx * dy - sxy * dx) / det;
        }
    }
    const std::size_t nf = static_cast<std::size_t>(m.faces);
    m.pair_ax.assign(nf, 0.0), m.pair_ay.assign(nf, 0.0), m.pair_bx.assign(nf, 0.0), m.pair_by.assign(nf, 0.0);
    const auto over_square = [](PlanePoint o) {
        const double w = 1.0 / (o.x * o.x + o.y * o.y);
        return PlanePoint{w * o.x, w * o.y};
    };
    for (std::size_t f = 0; f < nf; ++f) {
        const std::int64_t a = m.face_a[f], b = m.face_b[f];
        if (b < 0) continue;
        const PlanePoint toward_b = over_square(offset(a, b)), toward_a = over_square(offset(b, a));
        m.pair_ax[f] = toward_b.x, m.pair_ay[f] = toward_b.y;
        m.pair_bx[f] = toward_a.x, m.pair_by[f] = toward_a.y;
    }
}

namespace {

// Renumbers cells and faces, derives what a face's slope needs and checks
// the faces' geometry. `cells` and `faces` are in the host's numbering; on a
// part of a distributed mesh the owned cells come first, then the ghosts,
// and the faces that touch an owned cell come before the others. Everything
// but the gradients and the sub-step's scale (finish_serial, finish_part).
std::shared_ptr<Mesh> assemble(MeshInput &&input, const RawCells &cells, const std::vector<RawFace> &faces,
                               const PartOfMesh *part, const char *function, int base) {
    auto mesh = std::make_shared<Mesh>();
    Mesh &m = *mesh;
    m.input = std::move(input);
    m.cells = static_cast<std::int64_t>(cells.area.size());
    m.faces = static_cast<std::int64_t>(faces.size());
    // DPSM_MESH_HOST_ORDER=1 keeps the host's order (for tests: no result may depend on it).
    if (read_switches().mesh_host_order) {
        m.host_cell.resize(cells.area.size());
        for (std::size_t c = 0; c < cells.area.size(); ++c) m.host_cell[c] = static_cast<std::int64_t>(c);
    } else {
        m.host_cell = hilbert_order(cells.centre);
    }
    if (part)
        std::stable_partition(m.host_cell.begin(), m.host_cell.end(), [&](std::int64_t h) { return !part->ghost[h]; });
    m.owned = part ? static_cast<std::int64_t>(std::count(part->ghost, part->ghost + m.cells, 0)) : m.cells;
    m.global_id.resize(m.cells);
    for (std::int64_t c = 0; c < m.cells; ++c) m.global_id[c] = part ? part->global_id[m.host_cell[c]] : m.host_cell[c];
    m.cell_of_host.assign(m.cells, 0);
    for (std::int64_t c = 0; c < m.cells; ++c) m.cell_of_host[m.host_cell[c]] = c;
    m.area.resize(m.cells), m.x.resize(m.cells), m.y.resize(m.cells);
    for (std::int64_t c = 0; c < m.cells; ++c) {
        const std::int64_t h = m.host_cell[c];
        m.area[c] = cells.area[h], m.x[c] = cells.centre[h].x, m.y[c] = cells.centre[h].y;
    }
    // Faces follow their first cell in the library's order.
    std::vector<std::pair<std::pair<std::int64_t, std::int64_t>, std::int64_t>> keyed(faces.size());
    for (std::size_t f = 0; f < faces.size(); ++f) {
        const std::int64_t a = m.cell_of_host[faces[f].a];
        const std::int64_t b = faces[f].b < 0 ? -1 : m.cell_of_host[faces[f].b];
        const std::int64_t lo = b < 0 ? a : std::min(a, b), hi = b < 0 ? -1 : std::max(a, b);
        keyed[f] = {{lo, hi}, static_cast<std::int64_t>(f)};
    }
    std::sort(keyed.begin(), keyed.end());
    const std::size_t nf = faces.size();
    m.host_face.resize(nf), m.face_of_host.resize(nf), m.face_a.resize(nf), m.face_b.resize(nf);
    m.distance.resize(nf), m.conductance.resize(nf), m.tangent_x.resize(nf),
        m.tangent_y.resize(nf), m.orthogonal.resize(nf), m.skew.resize(nf), m.host_sign.resize(nf);
    double smallest = 0.0;
    for (std::size_t f = 0; f < nf; ++f) {
        const std::int64_t h = keyed[f].second;
        const RawFace &raw = faces[h];
        m.host_face[f] = h;
        m.face_of_host[h] = static_cast<std::int64_t>(f);
        const std::int64_t a = keyed[f].first.first, b = keyed[f].first.second;
        const bool flipped = b >= 0 && a != m.cell_of_host[raw.a];
        m.face_a[f] = a, m.face_b[f] = b;
        m.host_sign[f] = flipped ? -1 : 1;
        const Vec ca{m.x[a], m.y[a]};
        Vec nl = raw.normal_length;
        if (flipped) nl = -1.0 * nl;
        const auto name_face = [&] {
            return std::string("face ") + std::to_string(h + base) + " (cells " + std::to_string(raw.a + base) +
                   (raw.b < 0 ? std::string(" and the domain edge") : " and " + std::to_string(raw.b + base)) + ")";
        };
        if (!(raw.length > 0.0) || !std::isfinite(raw.length))
            fail(DPSM_ERR_INVALID_VALUE, function, name_face(), " has length ", raw.length, ", not a positive number");
        Vec e;
        double d;
        if (b >= 0) {
            const Vec between = Vec{m.x[b], m.y[b]} - ca;
            const double apart = norm(between);
            if (!(apart > 0.0))
                fail(DPSM_ERR_INVALID_VALUE, function, name_face(), " joins two cells whose centres coincide at (",
                     ca.x, ", ", ca.y, ")");
            e = (1.0 / apart) * between;
            d = raw.distance > 0.0 ? raw.distance : apart;
            if (!raw.normal_known) nl = raw.length * e;
        } else {
            // The outside is the cell's mirror image across the face.
            const Vec to_mid = raw.mid - ca;
            d = raw.distance > 0.0 ? raw.distance : 2.0 * norm(to_mid);
            if (!raw.normal_known) nl = (raw.length / norm(to_mid)) * to_mid;
            e = (1.0 / raw.length) * nl;
            if (!(d > 0.0))
                fail(DPSM_ERR_INVALID_VALUE, function, name_face(), " has its midpoint at the cell's centre (",
                     ca.x, ", ", ca.y, ")");
        }
        m.distance[f] = d;
        m.tangent_x[f] = -e.y, m.tangent_y[f] = e.x;
        m.orthogonal[f] = std::max(0.0, dot(nl, e));
        m.skew[f] = dot(nl, Vec{m.tangent_x[f], m.tangent_y[f]});
        m.conductance[f] = norm(nl) / d;
        if (a < m.owned) {
            smallest = smallest == 0.0 ? d : std::min(smallest, d);
            m.live_faces = static_cast<std::int64_t>(f) + 1;
        }
    }
    m.min_distance = smallest;
    // Each cell's faces (order_each_cells_faces sorts them).
    m.cell_face_start.assign(m.cells + 1, 0);
    for (std::size_t f = 0; f < nf; ++f) {
        ++m.cell_face_start[m.face_a[f] + 1];
        if (m.face_b[f] >= 0) ++m.cell_face_start[m.face_b[f] + 1];
    }
    for (std::int64_t c = 0; c < m.cells; ++c) m.cell_face_start[c + 1] += m.cell_face_start[c];
    m.cell_faces.resize(m.cell_face_start[m.cells]);
    m.other.resize(m.cell_faces.size());
    m.into.resize(m.cell_faces.size());
    std::vector<std::int64_t> fill(m.cell_face_start.begin(), m.cell_face_start.end() - 1);
    for (std::size_t f = 0; f < nf; ++f) {
        const std::int64_t a = m.face_a[f], b = m.face_b[f];
        m.cell_faces[fill[a]] = static_cast<std::int64_t>(f);
        m.into[fill[a]] = -1.0;
        m.other[fill[a]++] = b;
        if (b >= 0) {
            m.cell_faces[fill[b]] = static_cast<std::int64_t>(f);
            m.into[fill[b]] = 1.0;
            m.other[fill[b]++] = a;
        }
    }
    order_each_cells_faces(m, faces);
    m.face_count.resize(m.cells);
    for (std::int64_t c = 0; c < m.cells; ++c)
        m.face_count[c] = static_cast<double>(m.cell_face_start[c + 1] - m.cell_face_start[c]);
    return mesh;
}

}  // namespace

// The smallest area over summed conductance of any owned cell (1 where no
// face conducts: nothing ever moves).
void set_step_scale(Mesh &m) {
    m.step_scale = 0.0;
    for (std::int64_t c = 0; c < m.owned; ++c) {
        double sum = 0.0;
        for (std::int64_t k = m.cell_face_start[c]; k < m.cell_face_start[c + 1]; ++k) sum += m.conductance[m.cell_faces[k]];
        if (sum > 0.0 && (m.step_scale == 0.0 || m.area[c] / sum < m.step_scale)) m.step_scale = m.area[c] / sum;
    }
    if (m.step_scale == 0.0) m.step_scale = 1.0;
}

namespace {

std::shared_ptr<const Mesh> finish_serial(std::shared_ptr<Mesh> mesh) {
    Mesh &m = *mesh;
    std::vector<std::uint8_t> has_stencil;
    gradient_weights(m, {}, {}, has_stencil);
    set_step_scale(m);
    return mesh;
}

// Polygons over nodes: the shoelace area and centroid per cell, and faces
// from edges, found by sorting the edges' node pairs.
struct EdgeUse {
    std::int64_t lo, hi, cell, along;  // along: the position of the edge in its cell
    bool operator<(const EdgeUse &o) const {
        return lo != o.lo ? lo < o.lo : hi != o.hi ? hi < o.hi : cell != o.cell ? cell < o.cell : along < o.along;
    }
};

// The uses of one edge: edges[k .. end), sorted so that they lie together;
// more than two is a mesh no face can describe.
std::size_t end_of_edge(const std::vector<EdgeUse> &edges, std::size_t k, const char *function, int base,
                        const char *cells) {
    std::size_t end = k + 1;
    while (end < edges.size() && edges[end].lo == edges[k].lo && edges[end].hi == edges[k].hi) ++end;
    if (end - k > 2)
        fail(DPSM_ERR_INVALID_VALUE, function, "the edge between nodes ", edges[k].lo + base, " and ",
             edges[k].hi + base, " is shared by ", end - k, " ", cells, " (", edges[k].cell + base, ", ",
             edges[k + 1].cell + base, ", ", edges[k + 2].cell + base, "); an edge belongs to one or two");
    return end;
}

// Two nodes at the same point that cells use: the edges through them would
// not join, and the cells there would meet at two domain edges (open ones
// let sand leave in the middle of the domain). Refused, naming both nodes
// and a cell of each. `nodes` are the cells' node indices from 0, `cell_of`
// gives the cell of a position in them, `what` names the cells.
template <class CellOf>
void refuse_coincident_nodes(const double *node_xy, const std::int64_t *nodes, std::int64_t count, CellOf &&cell_of,
                             const char *what, const char *function, int base) {
    std::vector<std::int64_t> used(nodes, nodes + count);
    std::sort(used.begin(), used.end());
    used.erase(std::unique(used.begin(), used.end()), used.end());
    std::sort(used.begin(), used.end(), [&](std::int64_t l, std::int64_t r) {
        const double lx = node_xy[2 * l], rx = node_xy[2 * r];
        if (lx != rx) return lx < rx;
        const double ly = node_xy[2 * l + 1], ry = node_xy[2 * r + 1];
        return ly != ry ? ly < ry : l < r;
    });
    for (std::size_t k = 1; k < used.size(); ++k) {
        const std::int64_t p = used[k - 1], q = used[k];
        if (node_xy[2 * p] != node_xy[2 * q] || node_xy[2 * p + 1] != node_xy[2 * q + 1]) continue;
        const auto first_cell = [&](std::int64_t node) { return cell_of(std::find(nodes, nodes + count, node) - nodes); };
        fail(DPSM_ERR_INVALID_VALUE, function, "nodes ", p + base, " and ", q + base, " lie at the same point (",
             node_xy[2 * p], ", ", node_xy[2 * p + 1], "), used by ", what, " ", first_cell(p) + base, " and ",
             first_cell(q) + base, ": edges through them would not join, and the ", what,
             " there would meet at a domain edge; give the ", what, " one node there");
    }
}

// A geographic mesh is built in the plane of its projection, then its
// lengths and areas are taken on the sphere: its projection, and its nodes in
// that plane (2 per node), to which node_xy is pointed. A planar mesh: none.
struct PlaneNodes {
    std::shared_ptr<const Stereographic> projection;
    std::vector<double> xy;
};
PlaneNodes into_plane_if_geographic(bool geographic, const double *&node_xy, std::int64_t nnodes,
                                    const char *function, int base) {
    PlaneNodes in_plane;
    if (!geographic) return in_plane;
    in_plane.projection = std::make_shared<const Stereographic>(node_xy, nnodes, function, base);
    in_plane.xy.resize(static_cast<std::size_t>(2 * nnodes));
    for (std::int64_t n = 0; n < nnodes; ++n) {
        const PlanePoint p = in_plane.projection->forward(node_xy[2 * n], node_xy[2 * n + 1]);
        in_plane.xy[2 * n] = p.x, in_plane.xy[2 * n + 1] = p.y;
    }
    node_xy = in_plane.xy.data();  // a moved vector keeps its buffer
    return in_plane;
}
}  // namespace

std::shared_ptr<Mesh> assemble_polygons(std::int64_t nnodes, const double *node_xy, std::int64_t ncells,
                                        const std::int64_t *cell_start, const std::int64_t *cell_nodes,
                                        const PartOfMesh *part, const char *function, int base,
                                        bool geographic) {
    require_count(nnodes, function, "nnodes");
    require_count(ncells, function, "ncells");
    require_coordinates(node_xy, nnodes, function, geographic ? "node_lonlat" : "node_xy", "node", base);
    if (!cell_start) fail(DPSM_ERR_NULL_POINTER, function, "cell_start is NULL");
    if (!cell_nodes) fail(DPSM_ERR_NULL_POINTER, function, "cell_nodes is NULL");
    if (cell_start[0] != base)
        fail(DPSM_ERR_INVALID_VALUE, function, host_position("cell_start", 0, base), " = ", cell_start[0],
             " must be ", base);
    for (std::int64_t c = 0; c < ncells; ++c)
        if (cell_start[c + 1] < cell_start[c] + 3 || cell_start[c + 1] - cell_start[c] > (1 << 20))
            fail(DPSM_ERR_INVALID_VALUE, function, "cell ", c + base, " has ", cell_start[c + 1] - cell_start[c],
                 " nodes (", host_position("cell_start", c, base), " = ", cell_start[c], ", ",
                 host_position("cell_start", c + 1, base), " = ", cell_start[c + 1], "); a polygon needs at least 3");
    const std::int64_t total = cell_start[ncells] - base;
    for (std::int64_t k = 0; k < total; ++k)
        if (!is_index(cell_nodes[k], nnodes, base))
            fail(DPSM_ERR_INVALID_VALUE, function, host_position("cell_nodes", k, base), " = ", cell_nodes[k],
                 " is not a node index in [", base, ", ", nnodes - 1 + base, "]");
    MeshInput input;
    input.kind = MeshInput::kPolygons;
    input.start_index = base;
    input.geographic = geographic;
    input.node_xy.assign(node_xy, node_xy + 2 * nnodes);
    input.cell_start.assign(cell_start, cell_start + ncells + 1);
    input.cell_nodes.assign(cell_nodes, cell_nodes + total);
    // From here on the indices count from 0 (the messages add base again).
    std::vector<std::int64_t> start_buffer, nodes_buffer;
    cell_start = from_zero(cell_start, ncells + 1, base, start_buffer);
    cell_nodes = from_zero(cell_nodes, total, base, nodes_buffer);
    refuse_coincident_nodes(
        node_xy, cell_nodes, total,
        [&](std::int64_t at) { return std::upper_bound(cell_start, cell_start + ncells + 1, at) - cell_start - 1; },
        "cells", function, base);
    // Lengths and areas of a geographic mesh are taken on the sphere (below).
    const PlaneNodes in_plane = into_plane_if_geographic(geographic, node_xy, nnodes, function, base);
    const std::shared_ptr<const Stereographic> &projection = in_plane.projection;
    const auto node = [&](std::int64_t n) { return Vec{node_xy[2 * n], node_xy[2 * n + 1]}; };

    RawCells cells;
    cells.area.resize(ncells), cells.centre.resize(ncells);
    std::vector<signed char> orientation(ncells);
    std::vector<EdgeUse> edges;
    edges.reserve(total);
    for (std::int64_t c = 0; c < ncells; ++c) {
        const std::int64_t k0 = cell_start[c], count = cell_start[c + 1] - k0;
        std::vector<std::int64_t> distinct(cell_nodes + k0, cell_nodes + k0 + count);
        std::sort(distinct.begin(), distinct.end());
        if (std::unique(distinct.begin(), distinct.end()) - distinct.begin() < 3)
            fail(DPSM_ERR_INVALID_VALUE, function, "cell ", c + base, " has fewer than 3 distinct nodes");
        // Relative to the first node, so that a small cell far from the origin keeps its digits.
        const Vec origin = node(cell_nodes[k0]);
        double twice_area = 0.0;
        Vec moment{0.0, 0.0};
        double perimeter = 0.0;
        for (std::int64_t k = 0; k < count; ++k) {
            const Vec p = node(cell_nodes[k0 + k]) - origin, q = node(cell_nodes[k0 + (k + 1) % count]) - origin;
            const double w = cross(p, q);
            twice_area += w;
            moment = moment + (w / 3.0) * (p + q);
            perimeter += norm(q - p);
            const std::int64_t u = cell_nodes[k0 + k], v = cell_nodes[k0 + (k + 1) % count];
            if (u == v)
                fail(DPSM_ERR_INVALID_VALUE, function, "cell ", c + base, " repeats node ", u + base,
                     " in consecutive places: an edge of zero length");
            edges.push_back({std::min(u, v), std::max(u, v), c, k});
        }
        const double area = 0.5 * std::fabs(twice_area);
        if (!(area > 1e-12 * perimeter * perimeter))
            fail(DPSM_ERR_INVALID_VALUE, function, "cell ", c + base, " has zero area (", area,
                 ") for its perimeter ", perimeter, ": its nodes lie on a line");
        orientation[c] = twice_area > 0.0 ? 1 : -1;
        cells.area[c] = area;
        cells.centre[c] = origin + (1.0 / twice_area) * moment;
    }
    std::sort(edges.begin(), edges.end());
    std::vector<RawFace> faces;
    faces.reserve(edges.size());
    for (std::size_t k = 0; k < edges.size();) {
        const std::size_t end = end_of_edge(edges, k, function, base, "cells");
        const EdgeUse &first = edges[k];
        if (end - k == 2 && edges[k + 1].cell == first.cell)
            fail(DPSM_ERR_INVALID_VALUE, function, "cell ", first.cell + base, " has the edge between nodes ",
                 first.lo + base, " and ", first.hi + base, " twice");
        const Vec p = node(first.lo), q = node(first.hi);
        RawFace face;
        face.a = first.cell;
        face.b = end - k == 2 ? edges[k + 1].cell : -1;
        face.mid = 0.5 * (p + q);
        face.length = norm(q - p);
        // The normal pointing out of a: the edge's direction in a's own
        // orientation, turned clockwise for a counter-clockwise cell.
        const std::int64_t k0 = cell_start[first.cell], count = cell_start[first.cell + 1] - k0;
        const Vec from = node(cell_nodes[k0 + first.along]), to = node(cell_nodes[k0 + (first.along + 1) % count]);
        const Vec along = to - from;
        face.normal_length = orientation[first.cell] > 0 ? Vec{along.y, -along.x} : Vec{-along.y, along.x};
        face.normal_known = true;
        face.along = first.along;
        faces.push_back(face);
        k = end;
    }
    // The host's face order: as the faces first appear, cell by cell in the
    // host's order, edge by edge in each cell's order.
    std::sort(faces.begin(), faces.end(),
              [](const RawFace &l, const RawFace &r) { return l.a != r.a ? l.a < r.a : l.along < r.along; });
    if (projection) {
        const auto point = [](Vec v) { return PlanePoint{v.x, v.y}; };
        std::vector<PlanePoint> corners;
        for (std::int64_t c = 0; c < ncells; ++c) {
            corners.clear();
            for (std::int64_t k = cell_start[c]; k < cell_start[c + 1]; ++k) corners.push_back(point(node(cell_nodes[k])));
            const std::int64_t count = static_cast<std::int64_t>(corners.size());
            cells.area[c] = std::fabs(projection->polygon_area(corners.data(), count));
            const PlanePoint centroid = projection->polygon_centroid(corners.data(), count);
            cells.centre[c] = Vec{centroid.x, centroid.y};
        }
        for (RawFace &face : faces) {
            const std::int64_t k0 = cell_start[face.a], count = cell_start[face.a + 1] - k0;
            const Vec p = node(cell_nodes[k0 + face.along]), q = node(cell_nodes[k0 + (face.along + 1) % count]);
            const double length = projection->distance(point(p), point(q));
            face.normal_length = (length / face.length) * face.normal_length;
            face.length = length;
            const PlanePoint mid = projection->midpoint(point(p), point(q));
            face.mid = Vec{mid.x, mid.y};
            face.distance = face.b >= 0 ? projection->distance(point(cells.centre[face.a]), point(cells.centre[face.b]))
                                        : 2.0 * projection->distance(point(cells.centre[face.a]), point(face.mid));
        }
    }
    std::shared_ptr<Mesh> mesh = assemble(std::move(input), cells, faces, part, function, base);
    mesh->projection = projection;
    return mesh;
}

std::shared_ptr<Mesh> assemble_graph(std::int64_t ncells, const double *cell_xy, const double *cell_area,
                                     std::int64_t nfaces, const std::int64_t *face_cells, const double *face_xy,
                                     const double *face_length, const PartOfMesh *part, const char *function,
                                     int base) {
    require_count(ncells, function, "ncells");
    require_count(nfaces, function, "nfaces");
    require_coordinates(cell_xy, ncells, function, "cell_xy", "cell", base);
    require_coordinates(face_xy, nfaces, function, "face_xy", "face", base);
    if (!cell_area) fail(DPSM_ERR_NULL_POINTER, function, "cell_area is NULL");
    if (!face_cells) fail(DPSM_ERR_NULL_POINTER, function, "face_cells is NULL");
    if (!face_length) fail(DPSM_ERR_NULL_POINTER, function, "face_length is NULL");
    RawCells cells;
    cells.area.resize(ncells), cells.centre.resize(ncells);
    for (std::int64_t c = 0; c < ncells; ++c) {
        if (!(cell_area[c] > 0.0) || !(cell_area[c] <= kMaxMagnitude))
            fail(DPSM_ERR_INVALID_VALUE, function, host_position("cell_area", c, base), " (cell ", c + base, ") = ",
                 cell_area[c], " is not a positive area within 1e50");
        cells.area[c] = cell_area[c];
        cells.centre[c] = Vec{cell_xy[2 * c], cell_xy[2 * c + 1]};
    }
    std::vector<RawFace> faces(nfaces);
    // Per cell, the direction from its centre to each of its faces and the
    // face; the faces on the domain edge whose midpoint is the cell's centre.
    struct Towards {
        double angle;
        std::int64_t face;
    };
    std::vector<std::vector<Towards>> angles(ncells);
    std::vector<std::int64_t> edge_at_centre;
    for (std::int64_t f = 0; f < nfaces; ++f) {
        const std::int64_t host_a = face_cells[2 * f], host_b = face_cells[2 * f + 1];
        if (!is_index(host_a, ncells, base))
            fail(DPSM_ERR_INVALID_VALUE, function, "face ", f + base, ": ", host_position("face_cells", 2 * f, base, 2),
                 " = ", host_a, " is not a cell index in [", base, ", ", ncells - 1 + base, "]");
        if (host_b != base - 1 && !is_index(host_b, ncells, base))
            fail(DPSM_ERR_INVALID_VALUE, function, "face ", f + base, ": ",
                 host_position("face_cells", 2 * f + 1, base, 2), " = ", host_b, " is not a cell index in [", base,
                 ", ", ncells - 1 + base, "] nor ", base - 1, " (the domain edge)");
        // From here on from 0, -1 on the domain edge.
        const std::int64_t a = host_a - base, b = host_b - base;
        if (a == b)
            fail(DPSM_ERR_INVALID_VALUE, function, "face ", f + base, " joins cell ", a + base, " to itself");
        if (b >= 0 && cells.centre[a].x == cells.centre[b].x && cells.centre[a].y == cells.centre[b].y)
            fail(DPSM_ERR_INVALID_VALUE, function, "face ", f + base, " (cells ", a + base, " and ", b + base,
                 ") joins two cells whose centres coincide at (", cells.centre[a].x, ", ", cells.centre[a].y, ")");
        if (!(face_length[f] > 0.0) || !(face_length[f] <= kMaxMagnitude))
            fail(DPSM_ERR_INVALID_VALUE, function, host_position("face_length", f, base), " (face ", f + base, ") = ",
                 face_length[f], " is not a positive length within 1e50");
        RawFace &face = faces[f];
        face.a = a, face.b = b;
        face.mid = Vec{face_xy[2 * f], face_xy[2 * f + 1]};
        face.length = face_length[f];
        face.normal_length = Vec{0.0, 0.0};
        face.normal_known = false;
        for (const std::int64_t c : {a, b}) {
            if (c < 0) continue;
            const std::int64_t other = c == a ? b : a;
            Vec to = face.mid - cells.centre[c];
            // A centre on the face's midpoint: a right triangle's circumcentre
            // on its hypotenuse, as Delft3D FM writes mesh2d_face_x/y. The face
            // lies towards the cell across it; on the domain edge, in the gap
            // the cell's other faces leave (found below).
            if (norm(to) <= 1e-6 * face.length) {
                if (other < 0) {
                    edge_at_centre.push_back(f);
                    continue;
                }
                to = cells.centre[other] - cells.centre[c];
            }
            if (norm(to) > 0.0) angles[c].push_back({std::atan2(to.y, to.x), f});
        }
    }
    // A cell is closed when its faces surround its centre: no gap of half a
    // turn or more between the directions to their midpoints. A face on the
    // domain edge at the cell's centre faces the middle of the widest gap.
    const auto widest_gap = [](std::vector<Towards> &dir, double &from) {
        std::sort(dir.begin(), dir.end(), [](const Towards &l, const Towards &r) { return l.angle < r.angle; });
        if (dir.empty()) return from = 0.0, 2.0 * M_PI;
        double gap = dir.front().angle + 2.0 * M_PI - dir.back().angle;
        from = dir.back().angle;
        for (std::size_t k = 1; k < dir.size(); ++k)
            if (dir[k].angle - dir[k - 1].angle > gap) gap = dir[k].angle - dir[k - 1].angle, from = dir[k - 1].angle;
        return gap;
    };
    std::vector<std::int64_t> face_count(static_cast<std::size_t>(ncells), 0);
    for (const RawFace &face : faces) {
        ++face_count[face.a];
        if (face.b >= 0) ++face_count[face.b];
    }
    for (const std::int64_t f : edge_at_centre) {
        RawFace &face = faces[f];
        if (face_count[face.a] != 3 || angles[face.a].size() != 2)
            fail(DPSM_ERR_INVALID_VALUE, function, "face ", f + base, " (cell ", face.a + base,
                 " and the domain edge) has its midpoint at the cell's centre (", cells.centre[face.a].x, ", ",
                 cells.centre[face.a].y, "); only a triangle's centre may lie on one of its faces (a right triangle's "
                 "circumcentre, on its hypotenuse), and cell ", face.a + base, " has ", face_count[face.a], " faces");
        double from = 0.0;
        const double gap = widest_gap(angles[face.a], from);
        const double towards = from + 0.5 * gap;
        const Vec outward{std::cos(towards), std::sin(towards)};
        face.normal_length = face.length * outward;
        face.normal_known = true;
        // The outside mirrors the centroid of a triangle on this face: two
        // thirds of the triangle's height, 2 area / length, from the face, twice.
        face.distance = 2.0 * (2.0 * cells.area[face.a] / (3.0 * face.length));
        angles[face.a].push_back({towards, f});
    }
    for (std::int64_t c = 0; c < ncells; ++c) {
        if (part && part->ghost[c]) continue;  // a ghost's faces beyond the owned cells need not be given
        std::vector<Towards> &dir = angles[c];
        double from = 0.0;
        const double gap = widest_gap(dir, from);
        if (dir.size() >= 3 && gap < M_PI * (1.0 - 1e-9)) continue;
        std::ostringstream given;
        given.precision(17);
        std::vector<std::int64_t> listed;
        for (const Towards &t : dir) listed.push_back(t.face);
        std::sort(listed.begin(), listed.end());
        for (std::size_t k = 0; k < listed.size(); ++k) given << (k ? ", " : "") << listed[k] + base;
        const double degrees = 180.0 / M_PI;
        const auto normalised = [](double angle) { return angle < 0.0 ? angle + 360.0 : angle; };
        std::ostringstream where;
        where.precision(17);
        if (dir.size() > 1)
            where << "no face lies between " << normalised(from * degrees) << " and "
                  << normalised(std::fmod(from + gap, 2.0 * M_PI) * degrees) << " degrees";
        else
            where << (dir.empty() ? "it has no face" : "its one face lies at ")
                  << (dir.empty() ? std::string() : std::to_string(std::lround(normalised(dir[0].angle * degrees))) + " degrees");
        fail(DPSM_ERR_INVALID_VALUE, function, "the faces of cell ", c + base, " (", dir.size(), " of them",
             dir.empty() ? "" : dir.size() == 1 ? ": face " : ": faces ", given.str(), ") do not close it: around its "
             "centre (", cells.centre[c].x, ", ", cells.centre[c].y, ") ", where.str(),
             " (counter-clockwise from +x), so a face is missing there; give every face of the cell, "
             "domain edges with b = ",
             base - 1);
    }
    MeshInput input;
    input.kind = MeshInput::kGraph;
    input.start_index = base;
    input.ncells = ncells;
    input.cell_xy.assign(cell_xy, cell_xy + 2 * ncells);
    input.cell_area.assign(cell_area, cell_area + ncells);
    input.face_cells.assign(face_cells, face_cells + 2 * nfaces);
    input.face_xy.assign(face_xy, face_xy + 2 * nfaces);
    input.face_length.assign(face_length, face_length + nfaces);
    return assemble(std::move(input), cells, faces, part, function, base);
}

std::shared_ptr<const Mesh> mesh_from_polygons(std::int64_t nnodes, const double *node_xy, std::int64_t ncells,
                                               const std::int64_t *cell_start, const std::int64_t *cell_nodes,
                                               const char *function, int base, bool geographic) {
    return finish_serial(
        assemble_polygons(nnodes, node_xy, ncells, cell_start, cell_nodes, nullptr, function, base, geographic));
}

std::shared_ptr<const Mesh> mesh_from_graph(std::int64_t ncells, const double *cell_xy, const double *cell_area,
                                            std::int64_t nfaces, const std::int64_t *face_cells,
                                            const double *face_xy, const double *face_length, const char *function,
                                            int base) {
    return finish_serial(
        assemble_graph(ncells, cell_xy, cell_area, nfaces, face_cells, face_xy, face_length, nullptr, function, base));
}

std::shared_ptr<const Mesh> mesh_from_dual(std::int64_t nnodes, const double *node_xy, std::int64_t ntriangles,
                                           const std::int64_t *triangle_nodes, const char *function, int base,
                                           bool geographic) {
    require_count(nnodes, function, "nnodes");
    require_count(ntriangles, function, "ntriangles");
    require_coordinates(node_xy, nnodes, function, geographic ? "node_lonlat" : "node_xy", "node", base);
    if (!triangle_nodes) fail(DPSM_ERR_NULL_POINTER, function, "triangle_nodes is NULL");
    for (std::int64_t k = 0; k < 3 * ntriangles; ++k)
        if (!is_index(triangle_nodes[k], nnodes, base))
            fail(DPSM_ERR_INVALID_VALUE, function, host_position("triangle_nodes", k, base, 3), " (triangle ",
                 k / 3 + base, ") = ", triangle_nodes[k], " is not a node index in [", base, ", ", nnodes - 1 + base,
                 "]");
    MeshInput input;
    input.kind = MeshInput::kDual;
    input.start_index = base;
    input.geographic = geographic;
    input.node_xy.assign(node_xy, node_xy + 2 * nnodes);
    input.cell_nodes.assign(triangle_nodes, triangle_nodes + 3 * ntriangles);
    // From here on the indices count from 0 (the messages add base again).
    std::vector<std::int64_t> nodes_buffer;
    triangle_nodes = from_zero(triangle_nodes, 3 * ntriangles, base, nodes_buffer);
    refuse_coincident_nodes(
        node_xy, triangle_nodes, 3 * ntriangles, [](std::int64_t at) { return at / 3; }, "triangles", function, base);
    // A geographic mesh: as in assemble_polygons, the plane, then the sphere.
    const PlaneNodes in_plane = into_plane_if_geographic(geographic, node_xy, nnodes, function, base);
    const std::shared_ptr<const Stereographic> &projection = in_plane.projection;
    const auto node = [&](std::int64_t n) { return Vec{node_xy[2 * n], node_xy[2 * n + 1]}; };
    // Lengths and areas: in the plane, or on the sphere.
    const auto point = [](Vec v) { return PlanePoint{v.x, v.y}; };
    const auto length_of = [&](Vec p, Vec q) { return projection ? projection->distance(point(p), point(q)) : norm(q - p); };
    // An edge's midpoint and a triangle's centroid: on the sphere for a
    // geographic mesh, so that no length depends on where the plane is centred.
    const auto midpoint_of = [&](Vec p, Vec q) {
        if (!projection) return 0.5 * (p + q);
        const PlanePoint mid = projection->midpoint(point(p), point(q));
        return Vec{mid.x, mid.y};
    };
    const auto centroid_of = [&](const std::int64_t *v) {
        if (!projection) return (1.0 / 3.0) * (node(v[0]) + node(v[1]) + node(v[2]));
        const PlanePoint corners[3] = {point(node(v[0])), point(node(v[1])), point(node(v[2]))};
        const PlanePoint centroid = projection->polygon_centroid(corners, 3);
        return Vec{centroid.x, centroid.y};
    };
    RawCells cells;
    cells.area.assign(nnodes, 0.0);
    cells.centre.resize(nnodes);
    for (std::int64_t n = 0; n < nnodes; ++n) cells.centre[n] = node(n);
    std::vector<EdgeUse> edges;
    edges.reserve(3 * ntriangles);
    for (std::int64_t t = 0; t < ntriangles; ++t) {
        const std::int64_t *v = triangle_nodes + 3 * t;
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
            fail(DPSM_ERR_INVALID_VALUE, function, "triangle ", t + base, " has fewer than 3 distinct nodes");
        const Vec p = node(v[0]), q = node(v[1]), r = node(v[2]);
        double area = 0.5 * std::fabs(cross(q - p, r - p));
        const double perimeter = norm(q - p) + norm(r - q) + norm(p - r);
        if (!(area > 1e-12 * perimeter * perimeter))
            fail(DPSM_ERR_INVALID_VALUE, function, "triangle ", t + base, " has zero area: its nodes lie on a line");
        if (projection) {
            const PlanePoint corners[3] = {point(p), point(q), point(r)};
            area = std::fabs(projection->polygon_area(corners, 3));
        }
        for (int k = 0; k < 3; ++k) {
            cells.area[v[k]] += area / 3.0;
            edges.push_back({std::min(v[k], v[(k + 1) % 3]), std::max(v[k], v[(k + 1) % 3]), t, k});
        }
    }
    for (std::int64_t n = 0; n < nnodes; ++n)
        if (!(cells.area[n] > 0.0))
            fail(DPSM_ERR_INVALID_VALUE, function, "node ", n + base, " belongs to no triangle: its cell has no area");
    std::sort(edges.begin(), edges.end());
    std::vector<RawFace> faces, edge_faces;
    for (std::size_t k = 0; k < edges.size();) {
        const std::size_t end = end_of_edge(edges, k, function, base, "triangles");
        const EdgeUse &first = edges[k];
        const Vec p = node(first.lo), q = node(first.hi), m = midpoint_of(p, q);
        // The dual face between the edge's nodes: from the edge's midpoint to
        // the centroid of each triangle on it; its normal, integrated along
        // it, points from lo to hi.
        RawFace face;
        face.a = first.lo, face.b = first.hi;
        face.length = 0.0;
        face.normal_length = Vec{0.0, 0.0};
        Vec mid_sum{0.0, 0.0};
        for (std::size_t u = k; u < end; ++u) {
            const Vec centroid = centroid_of(triangle_nodes + 3 * edges[u].cell);
            const Vec seg = centroid - m;
            const double length = length_of(m, centroid);
            Vec normal = (length / norm(seg)) * Vec{seg.y, -seg.x};
            if (dot(normal, q - p) < 0.0) normal = -1.0 * normal;
            face.normal_length = face.normal_length + normal;
            face.length += length;
            mid_sum = mid_sum + length * (0.5 * (centroid + m));
        }
        face.mid = (1.0 / face.length) * mid_sum;
        face.normal_known = true;
        if (projection) face.distance = length_of(p, q);
        faces.push_back(face);
        if (end - k == 1) {
            // A boundary edge: each of its nodes has half of it on the domain edge.
            const Vec centroid = centroid_of(triangle_nodes + 3 * first.cell);
            Vec outward{(q - p).y, -(q - p).x};
            if (dot(outward, m - centroid) < 0.0) outward = -1.0 * outward;
            outward = (1.0 / norm(outward)) * outward;
            for (const std::int64_t n : {first.lo, first.hi}) {
                RawFace half;
                half.a = n, half.b = -1;
                half.mid = 0.5 * (node(n) + m);
                half.length = length_of(node(n), m);
                half.normal_length = half.length * outward;
                half.normal_known = true;
                if (projection) half.distance = length_of(node(n), m);  // twice to the midpoint of the half
                edge_faces.push_back(half);
            }
        }
        k = end;
    }
    faces.insert(faces.end(), edge_faces.begin(), edge_faces.end());
    std::shared_ptr<Mesh> mesh = assemble(std::move(input), cells, faces, nullptr, function, base);
    mesh->projection = projection;
    return finish_serial(std::move(mesh));
}

std::shared_ptr<const Mesh> mesh_from_input(const MeshInput &input, const char *function) {
    switch (input.kind) {
        case MeshInput::kPolygons: {
            const std::int64_t ncells = static_cast<std::int64_t>(input.cell_start.size()) - 1;
            if (ncells < 1 ||
                input.cell_start.back() - input.start_index != static_cast<std::int64_t>(input.cell_nodes.size()))
                fail(DPSM_ERR_BAD_FILE, function, "the mesh's cells do not match their node list");
            return mesh_from_polygons(static_cast<std::int64_t>(input.node_xy.size() / 2), input.node_xy.data(), ncells,
                                      input.cell_start.data(), input.cell_nodes.data(), function, input.start_index,
                                      input.geographic);
        }
        case MeshInput::kGraph:
            return mesh_from_graph(input.ncells, input.cell_xy.data(), input.cell_area.data(),
                                   static_cast<std::int64_t>(input.face_length.size()), input.face_cells.data(),
                                   input.face_xy.data(), input.face_length.data(), function, input.start_index);
        case MeshInput::kDual:
            return mesh_from_dual(static_cast<std::int64_t>(input.node_xy.size() / 2), input.node_xy.data(),
                                  static_cast<std::int64_t>(input.cell_nodes.size() / 3), input.cell_nodes.data(),
                                  function, input.start_index, input.geographic);
    }
    fail(DPSM_ERR_BAD_FILE, function, "unknown mesh kind ", static_cast<unsigned>(input.kind));
}

std::string host_position(const char *name, std::int64_t k, int base, std::int64_t rows) {
    if (base == 0) return std::string(name) + "[" + std::to_string(k) + "]";
    if (rows <= 1) return std::string(name) + "(" + std::to_string(k + base) + ")";
    return std::string(name) + "(" + std::to_string(k % rows + base) + ", " + std::to_string(k / rows + base) + ")";
}

}  // namespace dpsm
