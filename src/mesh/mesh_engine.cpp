#include "mesh/mesh_engine.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <vector>

#include "mesh/face_lanes.hpp"
#include "mesh/ghost_exchange.hpp"
#include "mesh/list_passes.hpp"
#include "mesh/mesh_parts.hpp"
#include "mesh/mesh_state.hpp"
#include "model/distribution.hpp"
#include "model/engine.hpp"
#include "model/face_law.hpp"
#include "model/grid.hpp"
#include "model/ledger.hpp"

namespace dpsm {

namespace {

// Below this many cells in a pass the threads cost more than they save.
constexpr std::int64_t kCellsForThreads = 32768;
// A sub-step over more hot cells than this share of the mesh runs the
// plain passes over every cell: the lists would cost more than they save. A
// cell on the lists costs about three cells of the plain passes (measured
// on the column collapse: 2.5 times at 16k cells, 3.5 at 65k). The same
// share on any number of threads: the lists are built and passed on the
// threads as the plain passes are (mesh/index_set.hpp). Until they were, it
// fell in proportion to the threads; on two threads the column collapse on
// 33,800 triangles then updated 4.3 times the cells and took longer in 8 of
// 10 runs (docs/performance.md, "The dense share on two threads").
constexpr double kDenseShare = 0.25;

// The threads a pass over every cell of `cells` runs on.
inline int threads_in_use(int threads, std::int64_t cells) { return cells >= kCellsForThreads ? threads : 1; }

// The share of the room to its bounds a cell's limiter lets the gradient
// flow's excess fill.
constexpr double kLimiterRoom = 1.0 - 1e-9;
// MeshState::source_reach and MeshState::watch (lazy sources).
constexpr std::uint8_t kSourceReach = 1, kSourceNear = 2;
constexpr std::uint8_t kWatched = 1, kNearMoves = 2;

// The heights a sub-step reads. With lazy sources a sand cell's stored
// height is current after sub-step since[c] of the step, and what its source
// added since is read, the same bits wherever it is read ("Sources in closed
// form" below).
struct Heights {
    const double *h;
    const double *q = nullptr;  // lazy sources: the sand cells' sources (0 elsewhere); null: none lags
    const double *since = nullptr;
    double dt = 0.0;   // the sub-step
    double now = 0.0;  // the sub-step read, counted from the step's start

    double operator[](std::int64_t c) const { return q ? h[c] + source_lag(q[c], dt, now - since[c]) : h[c]; }
};

// What a face's own slope gives it in a sub-step (FaceLaw::terms).
struct FaceTerms {
    double low = 0.0;        // the monotone two-point flux, a to b
    double two_point = 0.0;  // the gradient flow's two-point part, a to b
    double pull = 0.0;       // V g t: what the face asks of its cells' gradients along t (along a wall: V g)
    double excess = 0.0;     // its slope beyond tan(theta)
    bool steep = false;      // its slope exceeds its threshold
};

// One sub-step's view of the grid: what every pass reads.
struct FaceLaw {
    const Mesh &m;
    Heights h;
    const std::uint8_t *kind;
    const double *gx, *gy;
    const std::uint8_t *carrying;   // per face: a FaceRole (carrying_faces)
    const std::uint8_t *beside_wall;  // per cell: whether a face of it lies along a wall; null: none does
    const double *edge_level;       // per face; null: 0
    const double *tan_field;        // null: uniform
    const std::uint8_t *moving;     // hysteresis: null when off
    const double *available;        // bed: the sand each cell may give, as a volume; null when none
    double nu, tan_theta, tolerance, tan_static, p, dt;
    bool isotropic;

    bool carries(std::int64_t f) const { return carrying[f] == kCarries; }
    bool along_wall(std::int64_t f) const { return carrying[f] == kAlongWall; }
    // The sand cell of a face along a wall.
    std::int64_t sand_side(std::int64_t f) const {
        const std::int64_t b = m.face_b[f];
        return b >= 0 && kind[b] == kSand ? b : m.face_a[f];
    }

    // Face f's slope and what it gives the sub-step's fluxes.
    //
    // The step is the gradient flow of the faces' energy E = sum_f V_f
    // Phi(|G_f|) (docs/guarantees.md, "Meshes"): G_f is the two-point slope
    // along e plus the mean of the cells' least-squares gradients along t,
    // V_f = L n.e d / 2 (a quarter on the domain edge), Phi' = the slide
    // flux. Its derivative in the heights has a two-point part on the face
    // itself and a pull V g t on its cells' gradients, which their stencils'
    // pairs carry (the pass over cells). The monotone flux, limited towards
    // the gradient flow's, is the two-point law C (h_a - h_b) with C held
    // in [0, |L n| / d].
    // Face f's slope, where it carries sand.
    struct Slope {
        double ha, hb, normal, tangential, s, tan_face, threshold;
    };
    Slope slope(std::int64_t f) const {
        const std::int64_t a = m.face_a[f], b = m.face_b[f];
        const std::uint8_t ka = kind[a];
        Slope out;
        out.ha = h[a];
        out.tangential = 0.0;
        std::uint8_t kb;
        if (b >= 0) {
            kb = kind[b];
            out.hb = h[b];
            if (isotropic)
                out.tangential = 0.5 * ((gx[a] + gx[b]) * m.tangent_x[f] + (gy[a] + gy[b]) * m.tangent_y[f]);
        } else {
            kb = kOutside;
            out.hb = edge_level ? edge_level[f] : 0.0;
            if (isotropic) out.tangential = gx[a] * m.tangent_x[f] + gy[a] * m.tangent_y[f];
        }
        out.normal = (out.ha - out.hb) / m.distance[f];
        out.tan_face =
            tan_field ? law::face_tan(tan_field[a], b >= 0 ? tan_field[b] : tan_field[a], ka == kSand, kb == kSand)
                      : tan_theta;
        out.threshold = out.tan_face * (1.0 + tolerance);
        if (moving) out.threshold = law::threshold(out.threshold, !moving[a] && !(b >= 0 && moving[b]), tan_static);
        out.s = std::sqrt(out.normal * out.normal + out.tangential * out.tangential);
        return out;
    }

    // A face between sand cell c and a wall (a closed edge or a wall cell):
    // nothing crosses it, and the surface on c's side of it, its diamond's
    // half in c, has c's gradient for its slope. That half counts in E like
    // any other diamond, so that a slope running along a wall drains as it
    // does away from one.
    Slope slope_along_wall(std::int64_t f, std::int64_t c) const {
        Slope out;
        out.ha = out.hb = h[c];
        out.normal = isotropic ? gx[c] * m.tangent_y[f] - gy[c] * m.tangent_x[f] : 0.0;
        out.tangential = isotropic ? gx[c] * m.tangent_x[f] + gy[c] * m.tangent_y[f] : 0.0;
        out.tan_face = tan_field ? tan_field[c] : tan_theta;
        out.threshold = out.tan_face * (1.0 + tolerance);
        if (moving) out.threshold = law::threshold(out.threshold, !moving[c], tan_static);
        out.s = std::sqrt(out.normal * out.normal + out.tangential * out.tangential);
        return out;
    }

    // Whether face f may be steep, where the rounding of its heights and
    // gradients could decide it: its slope within a band of rounding below
    // its threshold counts.
    bool may_be_steep(std::int64_t f) const {
        const std::uint8_t role = carrying[f];
        if (role == kCarriesNothing) return false;
        const Slope sl = role == kAlongWall ? slope_along_wall(f, sand_side(f)) : slope(f);
        const double band = 1e-9 * sl.threshold + kRoundOff * (std::fabs(sl.ha) + std::fabs(sl.hb)) / m.distance[f];
        return sl.s > sl.threshold - band;
    }

    FaceTerms terms(std::int64_t f) const {
        FaceTerms out;
        const std::uint8_t role = carrying[f];
        if (role == kAlongWall) return terms_along_wall(f);
        if (role != kCarries) return out;
        const std::int64_t a = m.face_a[f], b = m.face_b[f];
        const Slope sl = slope(f);
        const double distance = m.distance[f], normal = sl.normal, tangential = sl.tangential, s = sl.s,
                     tan_face = sl.tan_face;
        if (!(s > sl.threshold)) return out;
        out.steep = true;
        out.excess = s - tan_face;
        const double g = slide_flux(nu, tan_face, s, p) / s;
        const double diamond = (b >= 0 ? 0.5 : 0.25) * m.orthogonal[f] * distance;
        out.two_point = diamond * g * normal / distance;
        // dG_f/d(gradient of a cell) along t: 1/2 each between cells, 1 on the edge.
        out.pull = diamond * g * tangential * (b >= 0 ? 0.5 : 1.0);
        // A cell whose sand is down to its bed cannot lower the face's slope
        // by giving sand: the face keeps out of the gradient flow, whose pull
        // would otherwise drive sand round its neighbours for ever, and
        // carries the monotone flux alone.
        const bool on_bed = available && (bare(a) || bare(b));
        if (on_bed) out.two_point = out.pull = 0.0;
        const double abs_normal = std::fabs(normal);
        if (!(abs_normal > tolerance * tan_face)) return out;
        double factor = m.orthogonal[f];
        if (m.skew[f] != 0.0) factor -= tangential * m.skew[f] / normal;
        const double most = m.conductance[f] * distance;
        factor = std::min(factor, most);
        const double across = factor * abs_normal / most;
        if (!(across > tolerance * tan_face)) return out;
        out.low = capped(g * factor * normal, a, b);
        if (on_bed) out.two_point = out.low;
        return out;
    }

    // A face along a wall carries nothing itself: its part of E's derivative
    // is a pull on its sand cell's gradient, V g along that gradient (pull_of
    // applies it so), which the cell's stencil carries.
    FaceTerms terms_along_wall(std::int64_t f) const {
        FaceTerms out;
        const std::int64_t c = sand_side(f);
        const Slope sl = slope_along_wall(f, c);
        if (!(sl.s > sl.threshold)) return out;
        out.steep = true;
        out.excess = sl.s - sl.tan_face;
        if (available && bare(c)) return out;  // as a face on a bare cell: no pull
        const double diamond = 0.25 * m.orthogonal[f] * m.distance[f];
        out.pull = diamond * slide_flux(nu, sl.tan_face, sl.s, p) / sl.s;
        return out;
    }

    // A sand cell whose faces may take none of its sand (a bed, at most a film above it).
    bool bare(std::int64_t c) const { return c >= 0 && kind[c] == kSand && !(available[c] > 0.0); }

    // A flux from a to b within what a bed lets each sand cell give.
    double capped(double flux, std::int64_t a, std::int64_t b) const {
        if (!available) return flux;
        // A face takes from its sand cell at most its share of the sand there.
        const double unlimited = std::numeric_limits<double>::infinity();
        const auto share = [&](std::int64_t c) {
            return c >= 0 && kind[c] == kSand ? law::share_of_sand(available[c], m.face_count[c], dt, 1.0) : unlimited;
        };
        return law::capped(flux, share(a), -share(b));
    }
};

void gradient_of(const Mesh &m, const Heights &h, const std::uint8_t *kind, std::int64_t c, double *gx, double *gy) {
    double x = 0.0, y = 0.0;
    const double hc = h[c];
    for (std::int64_t k = m.grad_start[c]; k < m.grad_start[c + 1]; ++k) {
        const std::int64_t n = m.grad_cells[k];
        // A wall reads as the cell itself: no slope towards it.
        if (kind[n] == kWall) continue;
        const double dh = h[n] - hc;
        x += m.grad_wx[k] * dh;
        y += m.grad_wy[k] * dh;
    }
    gx[c] = x;
    gy[c] = y;
}

// The net rate of cell c from its faces' fluxes, summed in the cell's face
// order whichever faces a sub-step evaluated (the others carry 0).
// Whether any face carried sand is returned in `carried`.
inline double net_rate(const Mesh &m, const double *flux, std::int64_t c, bool &carried) {
    double rate = 0.0;
    bool any = false;
    for (std::int64_t k = m.cell_face_start[c]; k < m.cell_face_start[c + 1]; ++k) {
        const double v = flux[m.cell_faces[k]];
        any = any || v != 0.0;
        rate += m.into[k] * v;
    }
    carried = any;
    return rate / m.area[c];
}

// Cell c's pull: M_c^-1 P_c, with P_c the sum of its faces' pulls along
// their tangents (a face along a wall: along c's gradient), in the cell's
// face order (0 without a stencil).
inline void pull_of(const Mesh &m, const FaceLaw &law, const double *pull, std::int64_t c, double *pull_x,
                    double *pull_y) {
    double x = 0.0, y = 0.0;
    // Most cells have no face along a wall: they skip the faces' roles.
    const bool walls = law.beside_wall && law.beside_wall[c];
    for (std::int64_t k = m.cell_face_start[c]; k < m.cell_face_start[c + 1]; ++k) {
        const std::int64_t f = m.cell_faces[k];
        if (walls && law.along_wall(f)) {
            // A wall cell has no gradient the face reads.
            if (pull[f] == 0.0 || law.kind[c] != kSand) continue;
            x += pull[f] * law.gx[c];
            y += pull[f] * law.gy[c];
            continue;
        }
        x += pull[f] * m.tangent_x[f];
        y += pull[f] * m.tangent_y[f];
    }
    pull_x[c] = m.grad_ixx[c] * x + m.grad_ixy[c] * y;
    pull_y[c] = m.grad_ixy[c] * x + m.grad_iyy[c] * y;
}

// The gradient flow's flux over face f from a to b: its two-point part and
// the pair terms of both cells' stencils across it. Cell c's gradient reads
// n with the weight M_c^-1 o/|o|^2, so E's derivative puts w_cn . P_c on n
// and takes it from c: a flux w_cn . P_c from n to c over their face.
inline double gradient_flow_flux(const Mesh &m, const FaceLaw &law, std::int64_t f, double two_point,
                                 const double *pull_x, const double *pull_y) {
    if (!law.carries(f)) return 0.0;
    const std::int64_t a = m.face_a[f], b = m.face_b[f];
    if (b < 0) return two_point;
    // Added so that the face read from b to a gives exactly the opposite.
    const double from_b = m.pair_bx[f] * pull_x[b] + m.pair_by[f] * pull_y[b];
    const double from_a = m.pair_ax[f] * pull_x[a] + m.pair_ay[f] * pull_y[a];
    return beyond_round_off(two_point + (from_b - from_a), std::fabs(two_point) + std::fabs(from_b) + std::fabs(from_a));
}

// Zalesak's limiter for cell c: the shares of the gradient flow's excess
// over the monotone flux (high - low) that may enter and leave it, so that
// its height stays within its own and its neighbours' (open edges' levels
// included; with a bed, not below it) after the monotone update.
//
// A cell at rest in a hollow (no face of it steep, no neighbour lower) takes
// none of the excess. The pair terms of its neighbours' stencils reach it
// across faces that are not steep, and beyond the toe of a slope they would
// lay films of sand where the exact deposit has none (docs/guarantees.md,
// "No new extremum"); such a cell fills as the model's own flux reaches it,
// once a face of it is steep.
inline void limits_of(const Mesh &m, const FaceLaw &law, const double *low, const double *high,
                      const std::uint8_t *steep, const double *bed, std::int64_t c, double *limit_in,
                      double *limit_out) {
    limit_in[c] = limit_out[c] = 1.0;
    if (law.kind[c] != kSand) return;
    if (law.available && law.bare(c)) {
        // Sand down to its bed takes the monotone flux alone (FaceLaw::terms).
        limit_in[c] = limit_out[c] = 0.0;
        return;
    }
    const double h = law.h[c];
    // The monotone update's rate, summed over every face in the cell's face
    // order as net_rate does (the faces that carry nothing add 0).
    double rate = 0.0, highest = h, lowest = h, entering = 0.0, leaving = 0.0;
    bool any_steep = false;
    for (std::int64_t k = m.cell_face_start[c]; k < m.cell_face_start[c + 1]; ++k) {
        const std::int64_t f = m.cell_faces[k];
        rate += m.into[k] * low[f];
        any_steep = any_steep || steep[f];
        if (!law.carries(f)) continue;
        const std::int64_t o = m.other[k];
        const double v = o >= 0 ? law.h[o] : (law.edge_level ? law.edge_level[f] : 0.0);
        highest = std::max(highest, v);
        lowest = std::min(lowest, v);
        const double enters = m.into[k] * (high[f] - low[f]);
        if (enters > 0.0)
            entering += enters;
        else
            leaving -= enters;
    }
    const double monotone = h + law.dt * (rate / m.area[c]);
    const bool resting_in_hollow = !any_steep && lowest >= h;
    if (bed) lowest = std::max(lowest, bed[c]);
    // A hair short of the bounds, so that the update's rounding does not cross them.
    const double room = kLimiterRoom * m.area[c] / law.dt;
    const double room_up = (highest - monotone) * room, room_down = (monotone - lowest) * room;
    if (entering > 0.0) limit_in[c] = resting_in_hollow ? 0.0 : std::min(1.0, std::max(0.0, room_up / entering));
    if (leaving > 0.0) limit_out[c] = std::min(1.0, std::max(0.0, room_down / leaving));
}

// The limited flux over face f from a to b.
inline double limited_flux(const Mesh &m, const FaceLaw &law, std::int64_t f, double low, double high,
                           const double *limit_in, const double *limit_out) {
    const double excess = high - low;
    if (excess == 0.0) return low;
    const std::int64_t a = m.face_a[f], b = m.face_b[f];
    double share = excess > 0.0 ? limit_out[a] : limit_in[a];
    if (b >= 0) share = std::min(share, excess > 0.0 ? limit_in[b] : limit_out[b]);
    const double limited = share * excess;
    return law.capped(beyond_round_off(low + limited, std::fabs(low) + std::fabs(limited)), a, b);
}

class MeshEngine final : public Engine {
public:
    std::unique_ptr<EngineState> make_state(const Grid &grid) const override {
        return std::make_unique<MeshState>(grid);
    }

    double stable_dt(const Grid &grid) const override {
        const double stiffness =
            slide_flux_max_derivative(grid.mobility(), grid.min_repose_angle(), grid.flux_exponent());
        return kMeshStepSafety * grid.geometry().mesh->step_scale / stiffness;
    }

    void prepare(Grid &grid) const override {
        const Mesh &m = *grid.geometry().mesh;
        MeshState &s = mesh_state(grid);
        // A part of a distributed mesh takes its ghosts' values from their owners.
        s.exchange = dynamic_cast<GhostExchange *>(grid.distribution());
        const std::size_t n = static_cast<std::size_t>(m.cells), nf = static_cast<std::size_t>(m.faces);
        s.gx.resize(n, 0.0), s.gy.resize(n, 0.0);
        if (s.flux.size() != nf) {
            s.flux.assign(nf, 0.0), s.low.assign(nf, 0.0), s.high.assign(nf, 0.0), s.pull.assign(nf, 0.0);
            s.excess.assign(nf, 0.0);
            s.steep.assign(nf, 0);
            s.steep_faces.clear();
            s.steep_faces_listed = true;
        }
        if (s.pull_x.size() != n) {
            s.pull_x.assign(n, 0.0), s.pull_y.assign(n, 0.0);
            s.limit_in.assign(n, 1.0), s.limit_out.assign(n, 1.0);
            // A ghost's values start as the exchange's record of what was sent to it: 0.
            std::fill(s.limit_in.begin() + m.owned, s.limit_in.end(), 0.0);
            std::fill(s.limit_out.begin() + m.owned, s.limit_out.end(), 0.0);
        }
        s.face_seen.resize(nf, 0), s.cell_seen.resize(n, 0);
        s.carried.resize(n, 0);
        s.watch.resize(n, 0);
        s.lazy = false;
        if (s.exchange) s.in_batch.resize(n, 0);
        if (!grid.bed().empty()) s.available.resize(n, 0.0);
        if (s.lists_current) return;
        s.lists_current = true;
        carrying_faces(grid, m, s.carrying, s.beside_wall);
        s.faces_off_lanes.clear();
        for (std::int64_t f = 0; f < m.faces; ++f)
            if (off_lanes(m, s.carrying.data(), f)) s.faces_off_lanes.push_back(f);
        // Faces onto a sink: the outflow is summed over them alone, in one
        // order. On a distributed mesh the rank that owns the cell the sand
        // leaves books it.
        s.sink_faces.clear();
        const std::vector<std::uint8_t> &kind = grid.kinds();
        for (std::int64_t f = 0; f < m.live_faces; ++f) {
            const std::int64_t a = m.face_a[f], b = m.face_b[f];
            const bool sink = b < 0 ? grid.edge_open(f) : (kind[a] == kOpen || kind[b] == kOpen);
            const std::int64_t leaves = b >= 0 && kind[a] == kOpen ? b : a;
            if (sink && leaves < m.owned) s.sink_faces.push_back(f);
        }
        s.source_cells.clear();
        s.ghost_source_cells.clear();
        const std::vector<double> &q = grid.source();
        for (std::int64_t c = 0; c < static_cast<std::int64_t>(q.size()); ++c)
            if (kind[c] == kSand && q[c] != 0.0) (c < m.owned ? s.source_cells : s.ghost_source_cells).push_back(c);
        list_source_faces(m, q, s);
    }

    // Per face, its FaceRole: it carries sand where no wall is on it and a
    // sand cell is (on the domain edge, an open edge); between a sand cell
    // and a wall cell or a closed edge it lies along a wall. Per cell,
    // whether a face of it lies along a wall (empty when none does). They
    // follow the kinds and the edges, so they are found with the lists that
    // follow them.
    static void carrying_faces(const Grid &grid, const Mesh &m, std::vector<std::uint8_t> &carrying,
                               std::vector<std::uint8_t> &beside_wall) {
        const std::uint8_t *kind = grid.kinds().data();
        const std::uint8_t *edge_open = grid.edge_open_flags().empty() ? nullptr : grid.edge_open_flags().data();
        const bool open_edges = grid.side_open(0);
        carrying.resize(static_cast<std::size_t>(m.faces));
        beside_wall.assign(static_cast<std::size_t>(m.cells), 0);
        bool any = false;
        for (std::int64_t f = 0; f < m.faces; ++f) {
            const std::int64_t a = m.face_a[f], b = m.face_b[f];
            const std::uint8_t ka = kind[a];
            if (b < 0) {
                const bool open = edge_open ? edge_open[f] != 0 : open_edges;
                carrying[f] = ka != kSand ? kCarriesNothing : open ? kCarries : kAlongWall;
            } else {
                const std::uint8_t kb = kind[b];
                if (ka != kWall && kb != kWall)
                    carrying[f] = ka == kSand || kb == kSand ? kCarries : kCarriesNothing;
                else
                    carrying[f] = ka == kSand || kb == kSand ? kAlongWall : kCarriesNothing;
            }
            if (carrying[f] != kAlongWall) continue;
            any = true;
            beside_wall[a] = 1;
            if (b >= 0) beside_wall[b] = 1;
        }
        if (!any) beside_wall.clear();
    }

    // Not with a bed (erosion stops at it, so a source's part depends on the
    // sand there) nor with a static angle (a cell's threshold depends on
    // whether it moved).
    bool takes_lazy_sources(const Grid &grid) const override { return grid.bed().empty() && !grid.hysteresis(); }

    // After a step with lazy sources, the cells a source kept hot are hot:
    // what its closed form made steep at its end is among them.
    bool may_move(const Grid &grid) const override { return mesh_state(grid).activity.may_move(); }

    // Without lazy sources every source cell takes its source at every
    // sub-step and counts as driven. With them, the faces a source may make
    // steep within the step keep their cells hot ("Sources in closed form").
    bool drive_sources(Grid &grid, double dt, double sub_dt, bool lazy, double &reach) const override {
        reach = std::numeric_limits<double>::infinity();
        if (!lazy) return true;
        MeshState &s = mesh_state(grid);
        s.lazy = true;
        s.lazy_substeps = std::round(dt / sub_dt);
        s.moved_since_look = s.source_may_steepen = false;
        const Mesh &m = *grid.geometry().mesh;
        return look_under_sources(grid, m, s, sub_dt, -1.0, s.lazy_substeps, true).second;
    }
    void forget_driven(Grid &grid) const override {
        MeshState &s = mesh_state(grid);
        forget_watches(s);
        s.lazy = false;
    }

    void advance(Grid &grid, const SubstepPlan &plan, const BookSubstep &book, StepInfo &info) const override {
        const Mesh &m = *grid.geometry().mesh;
        MeshState &s = mesh_state(grid);
        const bool record = grid.records_face_fluxes();
        if (record) std::fill(grid.face_fluxes().x.begin(), grid.face_fluxes().x.end(), 0.0);
        if (!plan.something_may_move) {
            info.at_rest = true;
            if (s.lazy) info.cell_updates += catch_up_sources(grid, s, plan.sub_dt);
            return;
        }
        s.switches = read_switches();
        if (s.lazy)
            for (const std::int64_t c : s.watched_cells) s.activity.wake(c);
        const Distribution *parts = grid.distribution();
        // A part whose ghost layer is deep enough steps its ghosts in reach
        // too and exchanges once per batch of sub-steps (mesh/mesh_parts.hpp);
        // the step ends with an exchange, so that a step starts exact.
        const int per_exchange = s.exchange && grid.relaxation() != kLocalSteps ? m.substeps_per_exchange : 0;
        // Local time steps: a part exchanges in every tick.
        const bool local = grid.relaxation() == kLocalSteps;
        if (local) begin_local_steps(grid, m, s);
        bool rested = false;
        for (std::int64_t k = 0; k < plan.substeps; ++k) {
            double visited = 0.0;
            const int in_batch = per_exchange > 0 ? static_cast<int>(k % per_exchange) + 1 : 0;
            SubstepSummary did = local ? local_tick(grid, m, s, plan.sub_dt, k, plan.substeps, record, visited)
                                       : substep(grid, m, s, plan.sub_dt, static_cast<double>(k), record, visited, in_batch);
            info.cell_updates += visited;
            if (local) {
                // The ticks at which nothing is due here pass at once (the
                // ranks take the fewest any rank may pass).
                const std::int64_t next = next_local_tick(s, k);
                did.substeps = (next < 0 ? plan.substeps : std::min(next, plan.substeps)) - k;
            }
            if (parts) {
                // Every rank takes the same sub-steps and stops at the same one.
                std::vector<SubstepSummary> &agreed = s.agreed;
                agreed.assign(1, did);
                parts->agree_on_substeps(agreed);
                did = agreed[0];
            }
            if (s.lazy) did.source_may_steepen = source_may_steepen(grid, m, s, plan.sub_dt, did.moved, k + 1);
            if (!did.moved) did.substeps = 1;
            const bool go_on = book(did);
            if (in_batch > 0 && (!go_on || in_batch == per_exchange || k + 1 == plan.substeps)) end_batch(grid, m, s);
            if (!go_on) {
                rested = true;
                break;
            }
            k += did.substeps - 1;
        }
        if (local) end_local_steps(m, s, rested);
        if (s.lazy) info.cell_updates += catch_up_sources(grid, s, plan.sub_dt);
    }

    // Meshes relax by time-accurate sub-steps to rest: the stepper takes over.
    bool relax_to_rest(Grid &, std::int64_t, double &cells_visited) const override {
        cells_visited = 0.0;
        return false;
    }

    void read_face_fluxes(const Grid &grid, double *fx, double *) const override {
        const std::vector<double> &faces = grid.face_fluxes().x;
        std::copy(faces.begin(), faces.end(), fx);
    }

private:
    // The new height of a sand cell from its faces' fluxes and its source
    // (with a bed: the sand it may lose); whether a face of it carried sand.
    struct CellUpdate {
        const Mesh &m;
        const double *flux;
        const std::uint8_t *kind;
        const std::vector<double> &q, &zb;
        std::vector<double> &h;
        std::vector<float> &residual;
        double dt;
        // Lazy sources: the heights as read (null: sources at every sub-step),
        // and where a cell's clock is kept.
        const Heights *lazy;
        double *since;
        // The faces' fluxes are amounts, volumes over their spans (local
        // time steps, no bed), not rates over dt.
        bool amounts = false;

        bool operator()(std::int64_t c) const {
            bool carried = false;
            double rate = net_rate(m, flux, c, carried);
            if (kind[c] != kSand) return carried;
            if (lazy) {
                // The stored height changes only where a face carries sand,
                // and then takes what the source added since it was current.
                if (!carried) return false;
                const double q_c = lazy->q[c];
                const double own = amounts ? rate + dt * q_c : dt * (rate + q_c);
                const double increment = own + source_lag(q_c, dt, lazy->now - since[c]);
                if (increment != 0.0) add_with_residual(h[c], residual[c], increment);
                if (q_c != 0.0) since[c] = lazy->now + 1.0;
                return true;
            }
            if (amounts) {
                if (!q.empty()) rate += dt * (zb.empty() ? q[c] : source_applied(zb, h, q, c, dt));
                if (rate != 0.0) add_with_residual(h[c], residual[c], rate);
            } else {
                if (!q.empty()) rate += zb.empty() ? q[c] : source_applied(zb, h, q, c, dt);
                if (rate != 0.0) add_with_residual(h[c], residual[c], dt * rate);
            }
            if (!zb.empty() && h[c] < zb[c]) {
                residual[c] = static_cast<float>(static_cast<double>(residual[c]) - (zb[c] - h[c]));
                h[c] = zb[c];
            }
            return carried;
        }
    };

    // `in_batch`: the sub-step's place after the last exchange (from 1) on a
    // part that takes several per exchange; 0: exchanges in this one.
    //
    // The passes: gradients; faces (slope, monotone flux, two-point part,
    // pull); cells (pull M^-1 P); faces (gradient flow's flux); cells
    // (limiters); faces (limited flux); cells (update). Each is a gather in
    // an order that does not depend on the threads, the library's order or
    // the partition.
    // `now`: the sub-step's place in the step, from 0.
    SubstepSummary substep(Grid &grid, const Mesh &m, MeshState &s, double dt, double now, bool record,
                           double &visited, int in_batch) const {
        MeshActivity &act = s.activity;
        const bool physics = grid.hysteresis() || !grid.bed().empty();
        // A part of a distributed mesh steps its owned cells and the faces
        // that touch them; its ghosts' values come from their owners
        // (mesh/mesh_parts.hpp), or in a batch it steps them too, densely.
        const bool parts = s.exchange != nullptr, exchanges = parts && !in_batch;
        const int threads = grid.step_threads();
        const bool dense = (in_batch && m.cells > m.owned) || physics || act.all_hot || s.switches.visit_all_cells ||
                           static_cast<double>(act.hot_list.size()) > kDenseShare * static_cast<double>(m.owned);
        std::vector<std::int64_t> &changed_ghosts = s.changed_ghosts;
        changed_ghosts.clear();
        std::vector<double> &h = grid.heights_for_stepping();
        std::vector<float> &residual = grid.residuals_for_stepping();
        const std::vector<std::uint8_t> &kind = grid.kinds();
        const std::vector<double> &q = grid.source();
        SubstepSummary did;

        FaceLaw law = law_of(grid, heights_read(grid, s, dt, now), s.gx.data(), s.gy.data(), dt);
        // Behind lazy sources a dense sub-step reads every cell's height,
        // most of them many times (a gradient's stencil, a limiter's
        // neighbours): it finds them once. The scalar reference reads them
        // through the clocks.
        const Heights lagging = law.h;
        if (dense && lagging.q && !s.switches.scalar_mesh) law.h = heights_found_once(m, lagging, threads, s.heights_read);
        if (!grid.bed().empty()) {
            prepare_bed(grid, m, s, dt, did);
            law.available = s.available.data();
        }
        const double *bed = grid.bed().empty() ? nullptr : grid.bed().data();
        double max_excess = 0.0;
        bool moved = false;
        const CellUpdate update_cell{m,        s.flux.data(), kind.data(), q, grid.bed(), h, residual, dt,
                                     s.lazy ? &lagging : nullptr, s.since.data()};
        double *low = s.low.data(), *high = s.high.data(), *pull = s.pull.data(), *flux = s.flux.data();
        double *pull_x = s.pull_x.data(), *pull_y = s.pull_y.data();
        double *limit_in = s.limit_in.data(), *limit_out = s.limit_out.data();
        double *excess = s.excess.data();
        std::uint8_t *steep = s.steep.data();
        const auto face_terms = [&](std::int64_t f) {
            const FaceTerms t = law.terms(f);
            low[f] = t.low, high[f] = t.two_point, pull[f] = t.pull, excess[f] = t.excess;
            steep[f] = t.steep;
            return t;
        };
        const bool lanes_run = in_lanes(law, s);
        const PassLanes lanes = lanes_of(m, law, s);
        const FaceLanes &term_lanes = lanes.terms;
        const FlowLanes &flow_lanes = lanes.flow;
        const LimitLanes &limit_lanes = lanes.limit;

        if (dense) {
            // The owned cells and the faces that touch them: all of a serial
            // mesh. On a part that steps its ghosts, the passes before the
            // update run over every ghost and face too (those beyond reach
            // compute what nothing in reach reads); the update steps the
            // ghosts in reach alone.
            const BatchReach reach{m, in_batch};
            const std::int64_t n = m.owned;
            const std::int64_t pass_cells = in_batch ? m.cells : n, pass_faces = in_batch ? m.faces : m.live_faces;
            const bool parallel = threads_in_use(threads, n) > 1;
            const int ranges = parallel ? threads : 1;  // the face passes in lanes: a range of faces a thread
            const auto range_of = [&](int r) {
                return std::make_pair(pass_faces * r / ranges, pass_faces * (r + 1) / ranges);
            };
            const std::int64_t *extra_cells = reach.ghosts();
            const std::int64_t extra_count = reach.ghost_count();
            if (law.isotropic) {
#pragma omp parallel for num_threads(threads) if (parallel) schedule(static)
                for (std::int64_t c = 0; c < pass_cells; ++c) gradient_of(m, law.h, kind.data(), c, s.gx.data(), s.gy.data());
                if (parts && !in_batch) {
                    exchange_ghost_gradients(s, changed_ghosts);
                    watch_near_moves(m, s, changed_ghosts);
                }
            }
            if (lanes_run) {
                const std::vector<std::int64_t> &off = s.faces_off_lanes;
#pragma omp parallel for num_threads(threads) if (parallel) schedule(static)
                for (int r = 0; r < ranges; ++r) {
                    const auto [begin, end] = range_of(r);
                    face_terms_in_lanes(term_lanes, begin, end);
                    for (auto k = std::lower_bound(off.begin(), off.end(), begin); k != off.end() && *k < end; ++k)
                        face_terms(*k);
                }
            } else {
#pragma omp parallel for num_threads(threads) if (parallel) schedule(static)
                for (std::int64_t f = 0; f < pass_faces; ++f) face_terms(f);
            }
#pragma omp parallel for num_threads(threads) if (parallel) schedule(static)
            for (std::int64_t c = 0; c < pass_cells; ++c) pull_of(m, law, pull, c, pull_x, pull_y);
            if (parts && !in_batch) take_every_ghosts_pull(m, s);
            if (!s.switches.scalar_mesh) {
#pragma omp parallel for num_threads(threads) if (parallel) schedule(static)
                for (int r = 0; r < ranges; ++r) {
                    const auto [begin, end] = range_of(r);
                    flow_fluxes_in_lanes(flow_lanes, begin, end);
                }
            } else {
#pragma omp parallel for num_threads(threads) if (parallel) schedule(static)
                for (std::int64_t f = 0; f < pass_faces; ++f)
                    high[f] = gradient_flow_flux(m, law, f, high[f], pull_x, pull_y);
            }
#pragma omp parallel for num_threads(threads) if (parallel) schedule(static)
            for (std::int64_t c = 0; c < pass_cells; ++c) limits_of(m, law, low, high, steep, bed, c, limit_in, limit_out);
            if (parts && !in_batch) exchange_ghost_limits(s);
            if (!s.switches.scalar_mesh && !law.available) {
                double largest = -1.0;
#pragma omp parallel for num_threads(threads) if (parallel) schedule(static) reduction(max : largest)
                for (int r = 0; r < ranges; ++r) {
                    const auto [begin, end] = range_of(r);
                    largest = std::max(largest, limited_fluxes_in_lanes(limit_lanes, begin, end, m.live_faces));
                }
                moved = largest >= 0.0;
                max_excess = std::max(max_excess, largest);
            } else {
#pragma omp parallel for num_threads(threads) if (parallel) schedule(static) reduction(max : max_excess) reduction(|| : moved)
                for (std::int64_t f = 0; f < pass_faces; ++f) {
                    const double v = limited_flux(m, law, f, low[f], high[f], limit_in, limit_out);
                    flux[f] = v;
                    if (v != 0.0 && f < m.live_faces) {
                        moved = true;
                        max_excess = std::max(max_excess, excess[f]);
                    }
                }
            }
            s.flux_clean = false;
            s.steep_faces.clear();
            s.steep_faces_listed = false;  // listed where a sparse pass reads them (list_steep_faces)
            std::uint8_t *changed = s.carried.data();
            std::int64_t changed_cells = 0;
#pragma omp parallel for num_threads(threads) if (parallel) schedule(static) reduction(+ : changed_cells)
            for (std::int64_t c = 0; c < n; ++c) {
                const bool carried = update_cell(c);
                changed[c] = carried;
                changed_cells += carried;
            }
            for (std::int64_t k = 0; k < extra_count; ++k) {
                const std::int64_t c = extra_cells[k];
                changed[c] = update_cell(c);
            }
            visited = static_cast<double>(n + extra_count);
            if (grid.hysteresis()) {
                std::vector<std::uint8_t> &moving = grid.moving_for_stepping();
                for (std::int64_t c = 0; c < n; ++c) moving[c] = kind[c] == kSand && changed[c];
                for (std::int64_t k = 0; k < extra_count; ++k)
                    moving[extra_cells[k]] = kind[extra_cells[k]] == kSand && changed[extra_cells[k]];
            }
            changed_ghosts.clear();
            if (in_batch)
                note_batch_updates_everywhere(s);
            else if (parts)
                exchange_ghost_heights(grid, s, nullptr, changed_ghosts);
            if (s.lazy && changed_cells > 0)
                for (std::int64_t c = 0; c < n; ++c)
                    if (changed[c]) watch_near_moves(m, s, c);
            if (s.lazy)
                for (std::int64_t k = 0; k < extra_count; ++k)
                    if (changed[extra_cells[k]]) watch_near_moves(m, s, extra_cells[k]);
            watch_near_moves(m, s, changed_ghosts);
            // The next sub-step looks at the cells that changed and those whose
            // gradients read them, and the cells a source keeps hot; where that
            // is most of the mesh, at all.
            const std::size_t most = static_cast<std::size_t>(kDenseShare * static_cast<double>(n));
            if (static_cast<std::size_t>(changed_cells) + kept_hot_by_sources(s) > most) {
                act.wake_all();
            } else {
                act.cool_all(threads);
                for (std::int64_t c = 0; c < n && !act.all_hot; ++c)
                    if (changed[c]) {
                        act.wake_around(m, c);
                        if (act.hot_list.size() > most) act.wake_all();
                    }
                wake_what_sources_keep_hot(m, s, in_batch != 0);
                for (const std::int64_t c : changed_ghosts) act.wake_around(m, c);
                for (std::int64_t k = 0; k < extra_count && !act.all_hot; ++k)
                    if (changed[extra_cells[k]]) act.wake_around(m, extra_cells[k]);
            }
        } else {
            // A few moving cells. The faces whose slopes may have changed
            // (those of the hot cells) are looked at again; with the faces
            // still steep they set every pass's reach: the steep faces' cells
            // pull, the faces of the pulling cells carry the gradient flow's
            // flux, their cells limit it. Everything beyond holds 0 (the
            // limiters 1). A part computes its owned cells and the faces that
            // touch them; its ghosts' gradients, pulls and limiters come from
            // their owners.
            const std::uint32_t stamp = next_stamp(s);
            s.faces.clear();
            s.gradient_cells.clear();
            const auto look_at_faces_of = [&](std::int64_t c) { look_at_faces(m, s, c, stamp, nullptr, 0); };
            mark_faces_of(m, s, act.hot_list, nullptr, 0, threads);
            list_looked_at(m, s, stamp, exchanges, threads);
            clear_passes(m, s);
            if (law.isotropic) {
                for_each_item(s.gradient_cells, threads,
                              [&](std::int64_t c) { gradient_of(m, law.h, kind.data(), c, s.gx.data(), s.gy.data()); });
                if (exchanges) {
                    // A ghost whose gradient changed makes its faces steep or flat
                    // whether or not anything near them here changed.
                    exchange_ghost_gradients(s, changed_ghosts);
                    watch_near_moves(m, s, changed_ghosts);
                    for (const std::int64_t c : changed_ghosts) look_at_faces_of(c);
                    changed_ghosts.clear();
                }
            }
            // The steep faces: those looked at again as they are now, the others as they were.
            list_steep_faces(m, s);
            std::vector<std::int64_t> &steep_faces = s.steep_faces;
            if (lanes_run)
                for_each_share(s.faces, threads, [&](const std::int64_t *faces, std::int64_t count) {
                    face_terms_in_lanes(term_lanes, faces, count);
                    for (std::int64_t k = 0; k < count; ++k)
                        if (off_lanes(m, law.carrying, faces[k])) face_terms(faces[k]);
                });
            else
                for_each_item(s.faces, threads, face_terms);
            // Each steep face once, in face order: those of the list still
            // steep (a face looked at may have turned flat) and those looked
            // at that are.
            s.face_set.reserve(m.faces);
            for (const std::vector<std::int64_t> *list : {&steep_faces, &s.faces})
                for_each_item(*list, threads, [&](std::int64_t f) {
                    if (steep[f]) s.face_set.add(f);
                });
            steep_faces.clear();
            s.face_set.take(steep_faces, threads);
            // The steep faces not looked at again: as they were, with this sub-step's terms.
            for_each_item(steep_faces, threads, [&](std::int64_t f) {
                if (s.face_seen[f] != stamp) face_terms(f);
            });
            // Pulls: the owned cells of steep faces.
            owned_cells_of(m, s, steep_faces, s.pull_cells, threads);
            for_each_item(s.pull_cells, threads, [&](std::int64_t c) { pull_of(m, law, pull, c, pull_x, pull_y); });
            if (exchanges) list_pulling_ghosts(s);
            // The gradient flow's flux: the steep faces and the faces of the pulling cells.
            s.faces.clear();
            carrying_faces(m, s, steep_faces, threads);
            if (!s.switches.scalar_mesh)
                for_each_share(s.faces, threads, [&](const std::int64_t *faces, std::int64_t count) {
                    flow_fluxes_in_lanes(flow_lanes, faces, count);
                });
            else
                for_each_item(s.faces, threads,
                              [&](std::int64_t f) { high[f] = gradient_flow_flux(m, law, f, high[f], pull_x, pull_y); });
            // Limiters: the owned cells of those faces.
            owned_cells_of(m, s, s.faces, s.limit_cells, threads);
            for_each_item(s.limit_cells, threads,
                          [&](std::int64_t c) { limits_of(m, law, low, high, steep, bed, c, limit_in, limit_out); });
            if (exchanges) exchange_ghost_limits(s);
            if (!s.switches.scalar_mesh && !law.available)
                for_each_share(s.faces, threads, [&](const std::int64_t *faces, std::int64_t count) {
                    limited_fluxes_in_lanes(limit_lanes, faces, count);
                });
            else
                for_each_item(s.faces, threads, [&](std::int64_t f) {
                    flux[f] = limited_flux(m, law, f, low[f], high[f], limit_in, limit_out);
                });
            list_updates(m, s, moved, max_excess, threads);
            for_each_item(s.update_cells, threads, [&](std::int64_t c) { update_cell(c); });
            visited = cells_visited(m, s, threads);
            if (exchanges) exchange_ghost_heights(grid, s, &s.update_cells, changed_ghosts);
            watch_near_moves(m, s, s.update_cells);
            watch_near_moves(m, s, changed_ghosts);
            // The next sub-step's hot cells (MeshActivity::wake_around), woken on the threads.
            act.cool_all(threads);
            s.cell_set.reserve(m.cells);
            const auto wake_around = [&](std::int64_t c) {
                MeshActivity::for_each_around(m, c, [&](std::int64_t e) { s.cell_set.add(e); });
            };
            for_each_item(s.update_cells, threads, wake_around);
            for (const std::int64_t c : changed_ghosts) wake_around(c);
            if (s.lazy)  // else the sources' cells are among those updated
                for_each_item(s.watched_cells, threads, [&](std::int64_t c) { s.cell_set.add(c); });
            act.wake_set(s.cell_set, threads);
            for_each_item(s.pull_cells, threads, [&](std::int64_t c) { pull_x[c] = pull_y[c] = 0.0; });
            for_each_item(s.limit_cells, threads, [&](std::int64_t c) { limit_in[c] = limit_out[c] = 1.0; });
        }
        into_sinks(m, s, kind.data(), did);
        if (record) {
            std::vector<double> &faces = grid.face_fluxes().x;
            // A part records the faces of its owned cells only (those beyond carry nothing here).
            if (dense) {
                for (std::int64_t f = 0; f < m.live_faces; ++f) faces[f] += s.flux[f] * dt;
            } else {
                for (const std::int64_t f : s.faces) faces[f] += s.flux[f] * dt;
            }
        }
        if (!dense)
            for_each_item(s.faces, threads, [&](std::int64_t f) { flux[f] = low[f] = high[f] = pull[f] = 0.0; });
        did.moved = moved;
        did.max_excess_slope = max_excess;
        return did;
    }


    // The steep faces in face order, where a dense sub-step left them to
    // its flags: the sparse passes read them as a list, and a dense sub-step
    // followed by another has no use for one.
    static void list_steep_faces(const Mesh &m, MeshState &s) {
        if (s.steep_faces_listed) return;
        s.steep_faces.clear();
        for (std::int64_t f = 0; f < m.live_faces; ++f)
            if (s.steep[f]) s.steep_faces.push_back(f);
        s.steep_faces_listed = true;
    }

    // The faces of cell c that touch an owned cell (with classes given,
    // those of a class at most `level`), each once a sub-step (`stamp`), into
    // s.faces, and their owned cells, whose gradients the sub-step finds,
    // into s.gradient_cells.
    static void look_at_faces(const Mesh &m, MeshState &s, std::int64_t c, std::uint32_t stamp,
                              const std::uint8_t *face_class, int level) {
        for (std::int64_t k = m.cell_face_start[c]; k < m.cell_face_start[c + 1]; ++k) {
            const std::int64_t f = m.cell_faces[k];
            if (f >= m.live_faces || (face_class && face_class[f] > level) || s.face_seen[f] == stamp) continue;
            s.face_seen[f] = stamp;
            s.faces.push_back(f);
            for (const std::int64_t e : {m.face_a[f], m.face_b[f]})
                if (e >= 0 && e < m.owned && s.cell_seen[e] != stamp) {
                    s.cell_seen[e] = stamp;
                    s.gradient_cells.push_back(e);
                }
        }
    }

    // look_at_faces on the threads for the cells of a list: their faces
    // (with classes given, those of a class at most `level`) marked in
    // s.face_set, for list_looked_at.
    static void mark_faces_of(const Mesh &m, MeshState &s, const std::vector<std::int64_t> &cells,
                              const std::uint8_t *face_class, int level, int threads) {
        s.face_set.reserve(m.faces);
        for_each_item(cells, threads, [&](std::int64_t c) {
            for (std::int64_t k = m.cell_face_start[c]; k < m.cell_face_start[c + 1]; ++k) {
                const std::int64_t f = m.cell_faces[k];
                if (f < m.live_faces && (!face_class || face_class[f] <= level)) s.face_set.add(f);
            }
        });
    }
    // The faces marked into s.faces in face order, each with the stamp, and
    // their owned cells into s.gradient_cells in cell order; the cells
    // stamped too where more will be looked at (a part's ghosts).
    static void list_looked_at(const Mesh &m, MeshState &s, std::uint32_t stamp, bool more, int threads) {
        s.face_set.take(s.faces, threads);
        for_each_item(s.faces, threads, [&](std::int64_t f) { s.face_seen[f] = stamp; });
        owned_cells_of(m, s, s.faces, s.gradient_cells, threads);
        if (more)
            for (const std::int64_t c : s.gradient_cells) s.cell_seen[c] = stamp;
    }

    // On a part, after every owned cell's pull: the ghosts' pulls from
    // their owners, and every ghost that pulls.
    static void take_every_ghosts_pull(const Mesh &m, MeshState &s) {
        std::vector<std::int64_t> &changed_ghosts = s.changed_ghosts;
        changed_ghosts.clear();
        exchange_ghost_pulls(s, changed_ghosts);
        changed_ghosts.clear();
        s.pulling_ghosts.clear();
        for (std::int64_t c = m.owned; c < m.cells; ++c)
            if (s.pull_x[c] != 0.0 || s.pull_y[c] != 0.0) s.pulling_ghosts.push_back(c);
    }

    // On a part, after its owned cells' pulls: the ghosts' pulls from their
    // owners, and the ghosts that pull (those whose pull changed, and those
    // that pulled before and still do), each once.
    static void list_pulling_ghosts(MeshState &s) {
        std::vector<std::int64_t> &changed_ghosts = s.changed_ghosts;
        changed_ghosts.clear();
        exchange_ghost_pulls(s, changed_ghosts);
        std::vector<std::int64_t> &ghosts = s.pulling_ghosts;
        ghosts.insert(ghosts.end(), changed_ghosts.begin(), changed_ghosts.end());
        changed_ghosts.clear();
        const std::uint32_t listed = next_stamp(s);
        std::size_t still = 0;
        for (const std::int64_t c : ghosts)
            if ((s.pull_x[c] != 0.0 || s.pull_y[c] != 0.0) && s.cell_seen[c] != listed) {
                s.cell_seen[c] = listed;
                ghosts[still++] = c;
            }
        ghosts.resize(still);
    }

    // Between sparse sub-steps every face's values and every owned cell's
    // pull hold 0, its limiters 1: after a dense one, they are set so.
    static void clear_passes(const Mesh &m, MeshState &s) {
        if (s.flux_clean) return;
        for (std::vector<double> *v : {&s.flux, &s.low, &s.high, &s.pull}) std::fill(v->begin(), v->end(), 0.0);
        std::fill(s.pull_x.begin(), s.pull_x.begin() + m.owned, 0.0);
        std::fill(s.pull_y.begin(), s.pull_y.begin() + m.owned, 0.0);
        std::fill(s.limit_in.begin(), s.limit_in.begin() + m.owned, 1.0);
        std::fill(s.limit_out.begin(), s.limit_out.begin() + m.owned, 1.0);
        s.flux_clean = true;
    }

    // The faces that carry the gradient flow's flux, each once, into
    // s.faces: the steep ones and those of the cells that pull (owned, and
    // a part's ghosts).
    static void carrying_faces(const Mesh &m, MeshState &s, const std::vector<std::int64_t> &steep_faces,
                               int threads) {
        s.face_set.reserve(m.faces);
        const auto carry_faces_of = [&](std::int64_t c) {
            for (std::int64_t k = m.cell_face_start[c]; k < m.cell_face_start[c + 1]; ++k)
                if (m.cell_faces[k] < m.live_faces) s.face_set.add(m.cell_faces[k]);
        };
        for_each_item(steep_faces, threads, [&](std::int64_t f) {
            if (f < m.live_faces) s.face_set.add(f);
        });
        for_each_item(s.pull_cells, threads, carry_faces_of);
        for (const std::int64_t c : s.pulling_ghosts) carry_faces_of(c);
        s.face_set.take(s.faces, threads);
    }

    // The owned cells of `faces`, each once, into `cells`.
    static void owned_cells_of(const Mesh &m, MeshState &s, const std::vector<std::int64_t> &faces,
                               std::vector<std::int64_t> &cells, int threads) {
        cells.clear();
        s.cell_set.reserve(m.cells);
        for_each_item(faces, threads, [&](std::int64_t f) {
            for (const std::int64_t e : {m.face_a[f], m.face_b[f]})
                if (e >= 0 && e < m.owned) s.cell_set.add(e);
        });
        s.cell_set.take(cells, threads);
    }

    // The cells a sparse sub-step updates, each once, into update_cells: the
    // owned cells of its faces that carried sand and, with sources at every
    // sub-step (not lazy), every source cell; whether a face carried sand,
    // and the largest excess slope of those that did.
    static void list_updates(const Mesh &m, MeshState &s, bool &moved, double &max_excess, int threads) {
        s.update_cells.clear();
        s.cell_set.reserve(m.cells);
        const std::int64_t count = static_cast<std::int64_t>(s.faces.size());
        const std::int64_t *faces = s.faces.data();
        bool any = false;
        double largest = max_excess;
        const auto carried = [&](std::int64_t f) {
            if (s.flux[f] == 0.0) return false;
            for (const std::int64_t e : {m.face_a[f], m.face_b[f]})
                if (e >= 0 && e < m.owned) s.cell_set.add(e);
            return true;
        };
        if (threads < 2 || count < kListItemsForThreads) {
            for (std::int64_t k = 0; k < count; ++k)
                if (carried(faces[k])) any = true, largest = std::max(largest, s.excess[faces[k]]);
        } else {
#pragma omp parallel for num_threads(threads) schedule(static) reduction(|| : any) reduction(max : largest)
            for (std::int64_t k = 0; k < count; ++k)
                if (carried(faces[k])) any = true, largest = std::max(largest, s.excess[faces[k]]);
        }
        if (!s.lazy)
            for (const std::int64_t c : s.source_cells)
                if (c < m.owned) s.cell_set.add(c);
        s.cell_set.take(s.update_cells, threads);
        moved = moved || any;
        max_excess = largest;
    }

    // The cells a sparse sub-step's passes read or wrote, each once.
    static double cells_visited(const Mesh &m, MeshState &s, int threads) {
        s.cell_set.reserve(m.cells);
        for (const std::vector<std::int64_t> *list : {&s.gradient_cells, &s.pull_cells, &s.limit_cells, &s.update_cells})
            for_each_item(*list, threads, [&](std::int64_t c) { s.cell_set.add(c); });
        return static_cast<double>(s.cell_set.take_count(threads));
    }

    // What went into sinks in a sub-step, face by face in one order whatever
    // the threads, as rates (the faces' fluxes).
    static void into_sinks(const Mesh &m, const MeshState &s, const std::uint8_t *kind, SubstepSummary &did) {
        for (const std::int64_t f : s.sink_faces) {
            const double v = s.flux[f];
            if (v == 0.0) continue;
            const std::int64_t b = m.face_b[f];
            did.outflow_rate += b < 0 ? v : (kind[b] == kOpen ? v : -v);
            if (b < 0) did.side_outflow_rate[0] += v;
        }
    }

    // Local time steps (mesh/step_classes.hpp). Tick j of n of sub_dt fires
    // the faces of the classes due at it; the faces' values are amounts over
    // their spans, so the limiter's sub-step is 1. Between ticks every
    // face's values and every cell's pull hold 0 and its limiters 1, as
    // between sparse sub-steps. While every cell is hot a tick runs over the
    // prefixes of the classes' lists; else over the due faces of the hot
    // cells and the steep faces, as a sparse sub-step does, and a hot cell
    // stays hot until all its faces have fired.
    SubstepSummary local_tick(Grid &grid, const Mesh &m, MeshState &s, double sub_dt, std::int64_t j, std::int64_t n,
                              bool record, double &visited) const {
        const StepClasses &sc = *s.classes;
        const int level = sc.level_of_tick(j);
        const int threads = grid.step_threads();
        const std::vector<std::uint8_t> &kind = grid.kinds();
        MeshActivity &act = s.activity;
        SubstepSummary did;
        FaceLaw law = law_of(grid, heights_read(grid, s, sub_dt, static_cast<double>(j)), s.gx.data(), s.gy.data(), 1.0);
        // A bed: the sand each cell may give in this tick, after its source
        // (every tick looks at every cell, as a sub-step with a bed does).
        const double *bed = grid.bed().empty() ? nullptr : grid.bed().data();
        if (bed) {
            prepare_bed(grid, m, s, sub_dt, did);
            law.available = s.available.data();
        }
        const CellUpdate update_cell{m,
                                     s.flux.data(),
                                     kind.data(),
                                     grid.source(),
                                     grid.bed(),
                                     grid.heights_for_stepping(),
                                     grid.residuals_for_stepping(),
                                     sub_dt,
                                     s.lazy ? &law.h : nullptr,
                                     s.since.data(),
                                     true};
        double *low = s.low.data(), *high = s.high.data(), *pull = s.pull.data(), *flux = s.flux.data();
        double *pull_x = s.pull_x.data(), *pull_y = s.pull_y.data(), *excess = s.excess.data();
        double *limit_in = s.limit_in.data(), *limit_out = s.limit_out.data();
        std::uint8_t *steep = s.steep.data();
        // Face f's terms as amounts over its span.
        const auto span_of = [&](std::int64_t f) {
            return static_cast<double>(StepClasses::span(sc.face_class[f], j, n)) * sub_dt;
        };
        const auto terms_of = [&](std::int64_t f) {
            const FaceTerms t = law.terms(f);
            const double span = span_of(f);
            low[f] = t.low * span, high[f] = t.two_point * span, pull[f] = t.pull * span, excess[f] = t.excess;
            steep[f] = t.steep;
        };
        const auto gradient = [&](std::int64_t c) { gradient_of(m, law.h, kind.data(), c, s.gx.data(), s.gy.data()); };
        const auto flow = [&](std::int64_t f) { high[f] = gradient_flow_flux(m, law, f, high[f], pull_x, pull_y); };
        const auto limit = [&](std::int64_t c) { limits_of(m, law, low, high, steep, bed, c, limit_in, limit_out); };
        const auto limited = [&](std::int64_t f) { flux[f] = limited_flux(m, law, f, low[f], high[f], limit_in, limit_out); };
        // The three face passes over a list of faces (each listed once), in
        // lanes where a sub-step's would be: the faces' terms on a plain
        // scene (those the lanes leave to FaceLaw::terms after them), the
        // flow always, the limited flux without a bed; the terms then
        // scaled to amounts as terms_of scales them.
        const PassLanes lanes = lanes_of(m, law, s);
        const bool terms_run = in_lanes(law, s), flow_run = !s.switches.scalar_mesh, limited_run = flow_run && !bed;
        const auto terms_over = [&](const std::int64_t *faces, std::int64_t count) {
            if (!terms_run) return for_each_item(faces, count, threads, terms_of);
            for_each_share(faces, count, threads, [&](const std::int64_t *share, std::int64_t share_count) {
                face_terms_in_lanes(lanes.terms, share, share_count);
                for (std::int64_t k = 0; k < share_count; ++k) {
                    const std::int64_t f = share[k];
                    if (off_lanes(m, law.carrying, f)) {
                        terms_of(f);
                        continue;
                    }
                    const double span = span_of(f);
                    low[f] = low[f] * span, high[f] = high[f] * span, pull[f] = pull[f] * span;
                }
            });
        };
        const auto flow_over = [&](const std::int64_t *faces, std::int64_t count) {
            if (!flow_run) return for_each_item(faces, count, threads, flow);
            for_each_share(faces, count, threads, [&](const std::int64_t *share, std::int64_t share_count) {
                flow_fluxes_in_lanes(lanes.flow, share, share_count);
            });
        };
        const auto limited_over = [&](const std::int64_t *faces, std::int64_t count) {
            if (!limited_run) return for_each_item(faces, count, threads, limited);
            for_each_share(faces, count, threads, [&](const std::int64_t *share, std::int64_t share_count) {
                limited_fluxes_in_lanes(lanes.limit, share, share_count);
            });
        };
        const auto count_of = [](const std::vector<std::int64_t> &list) { return static_cast<std::int64_t>(list.size()); };
        const auto carried = [&](std::int64_t f) {
            if (flux[f] == 0.0) return false;
            did.moved = true;
            did.max_excess_slope = std::max(did.max_excess_slope, excess[f]);
            return true;
        };
        // The faces whose values the tick wrote, the cells whose pulls it wrote.
        const std::int64_t *written_faces, *pulled_cells;
        std::int64_t written_count, pulled_count;

        // Sand that may still move after this tick: it moved, or a cell woken
        // by a change waits for its faces to fire (a source may keep it so).
        bool pending = false;
        if (act.all_hot) {
            // On a part, its owned cells and the faces that touch them, with
            // the ghosts' gradients, pulls, limiters and heights from their
            // owners, as in a dense sub-step.
            const bool parts = s.exchange != nullptr;
            std::vector<std::int64_t> &changed_ghosts = s.changed_ghosts;
            changed_ghosts.clear();
            const std::int64_t *firing = sc.firing_faces.data(), *reading = sc.reading_cells.data();
            const std::int64_t *carrying = sc.carrying_faces.data(), *taking = sc.taking_cells.data();
            const std::int64_t firing_n = sc.firing_end[level], reading_n = sc.reading_end[level];
            const std::int64_t carrying_n = sc.carrying_end[level], taking_n = sc.taking_end[level];
            if (law.isotropic) {
                for_each_item(reading, reading_n, threads, gradient);
                if (parts) {
                    exchange_ghost_gradients(s, changed_ghosts);
                    watch_near_moves(m, s, changed_ghosts);
                }
            }
            terms_over(firing, firing_n);
            for_each_item(reading, reading_n, threads, [&](std::int64_t c) { pull_of(m, law, pull, c, pull_x, pull_y); });
            if (parts) take_every_ghosts_pull(m, s);
            flow_over(carrying, carrying_n);
            for_each_item(taking, taking_n, threads, limit);
            if (parts) exchange_ghost_limits(s);
            limited_over(carrying, carrying_n);
            for (std::int64_t k = 0; k < carrying_n; ++k) carried(carrying[k]);
            std::uint8_t *changed = s.carried.data();
            for_each_item(taking, taking_n, threads, [&](std::int64_t c) {
                changed[c] = update_cell(c);
                limit_in[c] = limit_out[c] = 1.0;
            });
            if (grid.hysteresis()) note_moving_cells(grid, s, taking, taking_n, level, threads);
            if (!s.lazy) {
                // Sources at every tick (with a bed or a static angle they
                // are not in closed form): the cells beyond the tick's lists
                // take theirs too.
                for (const std::int64_t c : s.source_cells)
                    if (sc.taking_level[c] > level) changed[c] = update_cell(c);
            }
            if (parts) {
                exchange_ghost_heights(grid, s, nullptr, changed_ghosts);
                watch_near_moves(m, s, changed_ghosts);
            }
            std::int64_t changed_cells = 0;
            int woken = -1;  // the coarsest class the changes woke
            for (std::int64_t k = 0; k < taking_n; ++k)
                if (changed[taking[k]]) {
                    ++changed_cells;
                    woken = std::max<int>(woken, sc.waking[taking[k]]);
                    if (s.lazy) watch_near_moves(m, s, taking[k]);
                }
            if (woken >= 0) s.pending_until = std::max(s.pending_until, StepClasses::next_tick_at(woken, j));
            pending = s.pending_until > j || waits_for_sources(s);
            visited = static_cast<double>(taking_n);
            // Where every face has fired and few cells changed, the ticks
            // after look at those cells and the steep faces alone.
            const double most = kDenseShare * static_cast<double>(m.owned);
            if (level == sc.top && !s.switches.visit_all_cells && !bed && !grid.hysteresis() &&
                static_cast<double>(changed_cells + kept_hot_by_sources(s)) <= most) {
                act.all_hot = false;
                for (std::int64_t c = 0; c < m.owned; ++c)
                    if (changed[c]) wake_local_around(m, s, c);
                for (const std::int64_t c : changed_ghosts) wake_local_around(m, s, c);
                if (s.lazy)
                    for (const std::int64_t c : s.watched_cells) wake_local(s, c);
                list_steep_faces_by_level(m, s);
            }
            written_faces = carrying, written_count = carrying_n, pulled_cells = reading, pulled_count = reading_n;
        } else {
            // On a part, with the exchanges of a sparse sub-step: a ghost
            // whose gradient changed has its due faces looked at now and
            // stays hot as its owner keeps it; the faces of the ghosts that
            // pull carry; the ghosts whose heights changed wake the cells
            // that read them.
            const bool parts = s.exchange != nullptr;
            std::vector<std::int64_t> &changed_ghosts = s.changed_ghosts;
            changed_ghosts.clear();
            const std::uint32_t stamp = next_stamp(s);
            s.faces.clear();
            s.gradient_cells.clear();
            const auto look_at_due_faces_of = [&](std::int64_t c) {
                look_at_faces(m, s, c, stamp, sc.face_class.data(), level);
            };
            for (int l = 0; l <= level; ++l) {
                std::vector<std::int64_t> &hot = s.hot_by_level[static_cast<std::size_t>(l)];
                mark_faces_of(m, s, hot, sc.face_class.data(), level, threads);
                std::size_t kept = 0;
                for (const std::int64_t c : hot) {
                    if (sc.coarsest[c] <= level)
                        act.hot[c] = 0;
                    else
                        hot[kept++] = c;
                }
                hot.resize(kept);
            }
            list_looked_at(m, s, stamp, parts, threads);
            if (law.isotropic) {
                for_each_item(s.gradient_cells, threads, gradient);
                if (parts) {
                    exchange_ghost_gradients(s, changed_ghosts);
                    watch_near_moves(m, s, changed_ghosts);
                    for (const std::int64_t c : changed_ghosts) {
                        look_at_due_faces_of(c);
                        if (sc.coarsest[c] > level) wake_local(s, c);
                    }
                    changed_ghosts.clear();
                }
            }
            std::vector<std::uint8_t> &became_steep = s.became_steep;
            became_steep.resize(s.faces.size());
            // Whether each face was steep, before its terms write its flag.
            for (std::size_t k = 0; k < s.faces.size(); ++k) became_steep[k] = steep[s.faces[k]];
            terms_over(s.faces.data(), count_of(s.faces));
            for (std::size_t k = 0; k < s.faces.size(); ++k)
                became_steep[k] = steep[s.faces[k]] && !became_steep[k];
            for (std::size_t k = 0; k < s.faces.size(); ++k)
                if (became_steep[k]) s.steep_by_level[sc.face_class[s.faces[k]]].push_back(s.faces[k]);
            // Each due steep face once; those not looked at fire as they are.
            std::vector<std::int64_t> &due = s.limit_cells;  // scratch until the limiters' list
            due.clear();
            for (int l = 0; l <= level; ++l) {
                std::vector<std::int64_t> &listed = s.steep_by_level[static_cast<std::size_t>(l)];
                std::size_t kept = 0;
                for (const std::int64_t f : listed)
                    if (steep[f] == 1) {
                        steep[f] = 2, listed[kept++] = f;
                        if (s.face_seen[f] != stamp) due.push_back(f);
                    }
                listed.resize(kept);
                for (const std::int64_t f : listed) steep[f] = 1;
            }
            terms_over(due.data(), count_of(due));
            // The due steep faces: their cells pull.
            due.clear();
            for (int l = 0; l <= level; ++l)
                for (const std::int64_t f : s.steep_by_level[static_cast<std::size_t>(l)])
                    if (steep[f]) due.push_back(f);
            owned_cells_of(m, s, due, s.pull_cells, threads);
            for_each_item(s.pull_cells, threads, [&](std::int64_t c) { pull_of(m, law, pull, c, pull_x, pull_y); });
            if (parts) list_pulling_ghosts(s);
            s.faces.clear();
            carrying_faces(m, s, due, threads);
            flow_over(s.faces.data(), count_of(s.faces));
            owned_cells_of(m, s, s.faces, s.limit_cells, threads);
            for_each_item(s.limit_cells, threads, limit);
            if (parts) exchange_ghost_limits(s);
            limited_over(s.faces.data(), count_of(s.faces));
            list_updates(m, s, did.moved, did.max_excess_slope, threads);
            for_each_item(s.update_cells, threads, [&](std::int64_t c) { update_cell(c); });
            visited = cells_visited(m, s, threads);
            if (parts) exchange_ghost_heights(grid, s, &s.update_cells, changed_ghosts);
            watch_near_moves(m, s, s.update_cells);
            watch_near_moves(m, s, changed_ghosts);
            for (const std::int64_t c : s.update_cells) wake_local_around(m, s, c);
            for (const std::int64_t c : changed_ghosts) wake_local_around(m, s, c);
            if (s.lazy)
                for (const std::int64_t c : s.watched_cells) wake_local(s, c);
            for_each_item(s.limit_cells, threads, [&](std::int64_t c) { limit_in[c] = limit_out[c] = 1.0; });
            written_faces = s.faces.data(), written_count = static_cast<std::int64_t>(s.faces.size());
            pulled_cells = s.pull_cells.data(), pulled_count = static_cast<std::int64_t>(s.pull_cells.size());
            // Most of the mesh hot: the ticks run over the classes' lists until every face has fired.
            std::size_t hot_cells = 0;
            for (const std::vector<std::int64_t> &hot : s.hot_by_level) hot_cells += hot.size();
            pending = hot_cells > 0 || waits_for_sources(s);
            if (static_cast<double>(hot_cells) > kDenseShare * static_cast<double>(m.owned)) {
                // Each hot cell would cool at the first tick whose level reaches its coarsest face.
                for (std::vector<std::int64_t> &hot : s.hot_by_level) {
                    for (const std::int64_t c : hot) {
                        act.hot[c] = 0;
                        s.pending_until = std::max(s.pending_until, StepClasses::next_tick_at(sc.coarsest[c], j));
                    }
                    hot.clear();
                }
                act.all_hot = true;
            }
        }
        // The sinks' amounts as rates over the tick.
        into_sinks(m, s, kind.data(), did);
        did.outflow_rate /= sub_dt;
        did.side_outflow_rate[0] /= sub_dt;
        if (record) {
            std::vector<double> &faces = grid.face_fluxes().x;
            for (std::int64_t k = 0; k < written_count; ++k) faces[written_faces[k]] += flux[written_faces[k]];
        }
        for (std::int64_t k = 0; k < written_count; ++k) {
            const std::int64_t f = written_faces[k];
            flux[f] = low[f] = high[f] = pull[f] = excess[f] = 0.0;
        }
        for (std::int64_t k = 0; k < pulled_count; ++k) pull_x[pulled_cells[k]] = pull_y[pulled_cells[k]] = 0.0;
        did.moved = did.moved || pending;
        return did;
    }

    // With a static angle a cell is moving while a face of it carried sand
    // since all its faces last fired together (its coarsest class's span),
    // so that a face of a coarse class reads its cells as moving while sand
    // crosses it though finer ticks in between found nothing to carry. On a
    // mesh of one class, and at tick 0, where every face fires, this is
    // what a sub-step does: moving where a face carried. A cycle starts
    // with the step (tick 0 fires every face), so nothing of it outlives a
    // step but the flags themselves.
    static void note_moving_cells(Grid &grid, MeshState &s, const std::int64_t *taking, std::int64_t count, int level,
                                  int threads) {
        const StepClasses &sc = *s.classes;
        const std::uint8_t *kind = grid.kinds().data(), *changed = s.carried.data();
        std::uint8_t *moving = grid.moving_for_stepping().data(), *cycle = s.carried_in_cycle.data();
        for_each_item(taking, count, threads, [&](std::int64_t c) {
            const std::uint8_t carried = kind[c] == kSand && changed[c];
            if (sc.coarsest[c] <= level) {
                moving[c] = cycle[c] | carried;
                cycle[c] = 0;
            } else {
                moving[c] |= carried;
                cycle[c] |= carried;
            }
        });
    }

    // Sources that keep cells hot in every tick: the lazy sources' watched
    // cells, or sources at every tick.
    static bool waits_for_sources(const MeshState &s) {
        return s.lazy ? !s.watched_cells.empty() : !s.source_cells.empty();
    }

    // The steep faces by their classes, from the faces' flags (after ticks over the classes' lists).
    static void list_steep_faces_by_level(const Mesh &m, MeshState &s) {
        for (std::vector<std::int64_t> &listed : s.steep_by_level) listed.clear();
        for (std::int64_t f = 0; f < m.live_faces; ++f)
            if (s.steep[f]) s.steep_by_level[s.classes->face_class[f]].push_back(f);
    }

    // After tick j: the next tick at which a face may fire (every tick while
    // every cell is hot; else the first whose level reaches the finest class
    // of a hot cell's faces, where a face may start to carry sand or keeps
    // carrying it: one that carried sand at its last firing woke its cells),
    // or -1 where no cell is hot. Between them nothing moves but the lazy
    // sources, in closed form.
    static std::int64_t next_local_tick(const MeshState &s, std::int64_t j) {
        if (s.activity.all_hot || (!s.lazy && !s.source_cells.empty())) return j + 1;
        for (std::size_t l = 0; l < s.hot_by_level.size(); ++l)
            if (!s.hot_by_level[l].empty()) return ((j >> l) + 1) << l;
        return -1;
    }

    // Local time steps: the hot cells kept by the finest class of their faces.
    static void wake_local(MeshState &s, std::int64_t c) {
        MeshActivity &act = s.activity;
        if (act.all_hot || act.hot[c]) return;
        act.hot[c] = 1;
        s.hot_by_level[s.classes->finest[c]].push_back(c);
    }
    static void wake_local_around(const Mesh &m, MeshState &s, std::int64_t c) {
        MeshActivity::for_each_around(m, c, [&](std::int64_t e) { wake_local(s, e); });
    }

    // Before the first tick of a step with local time steps: the classes
    // (once per grid; on a part, collective: the ranks find them together),
    // the passes' values as between sparse sub-steps, and the hot cells by
    // level.
    static void begin_local_steps(const Grid &grid, const Mesh &m, MeshState &s) {
        if (!s.classes)
            s.classes = std::make_unique<const StepClasses>(
                s.exchange ? step_classes_of(m, *s.exchange, *grid.distribution()) : step_classes_of(m));
        clear_passes(m, s);
        std::fill(s.excess.begin(), s.excess.end(), 0.0);
        s.hot_by_level.resize(static_cast<std::size_t>(s.classes->top) + 1);
        s.pending_until = 0;
        MeshActivity &act = s.activity;
        if (s.switches.visit_all_cells || !grid.bed().empty() || grid.hysteresis()) act.wake_all();
        if (grid.hysteresis()) s.carried_in_cycle.assign(static_cast<std::size_t>(m.owned), 0);
        for (const std::int64_t c : act.hot_list) s.hot_by_level[s.classes->finest[c]].push_back(c);
        act.hot_list.clear();
        s.steep_by_level.resize(s.hot_by_level.size());
        list_steep_faces(m, s);
        for (const std::int64_t f : s.steep_faces) s.steep_by_level[s.classes->face_class[f]].push_back(f);
        s.steep_faces.clear();
    }
    // After the last tick: the hot cells and the steep faces back where
    // sub-steps keep them; where the step found rest, no cell is hot.
    static void end_local_steps(const Mesh &m, MeshState &s, bool rested) {
        MeshActivity &act = s.activity;
        if (rested && act.all_hot) {
            act.all_hot = false;
            list_steep_faces_by_level(m, s);
        }
        for (std::vector<std::int64_t> &hot : s.hot_by_level) {
            act.hot_list.insert(act.hot_list.end(), hot.begin(), hot.end());
            hot.clear();
        }
        for (std::vector<std::int64_t> &listed : s.steep_by_level) {
            s.steep_faces.insert(s.steep_faces.end(), listed.begin(), listed.end());
            listed.clear();
        }
    }

    // Sources in closed form (lazy sources). A source that cannot make a
    // face steep needs no sub-steps: the stored height of a sand cell
    // changes only in a sub-step in which one of its faces carries sand (it
    // then takes what its source added since it was current, and its clock,
    // since, moves on), every pass reads a cell's stored height plus what its
    // source added since (Heights), and at the end of the step every source
    // cell takes the rest in closed form (catch_up_sources). A cell's stored
    // height thus depends on when sand crossed its faces, not on which cells
    // a sub-step visited: results stay independent of the active set, the
    // threads and the partition.
    //
    // Which faces must still be looked at. Under the sources alone a face's
    // slope vector (its two-point slope and its cells' gradients along t) is
    // affine in time, so its length is convex: where a face is not steep at
    // the start of the step nor at its end, it is not in between. So the
    // step starts by looking at every face whose slope a source moves at the
    // end (look_under_sources), and keeps the cells of those steep then hot.
    // Those steep now are hot already: the step before looked at them at its
    // own end, and its last sub-step woke what the sources kept hot; a step
    // without lazy sources woke every source cell. Where sand moves, the
    // faces that read the cells it changed no longer follow the sources
    // alone: for the rest of the step the cells near those faces whose slopes
    // a source moves are kept hot too (watch_near_moves). And a sub-step that
    // moved nothing ends the step at rest only when no such face is steep
    // then nor at the end (source_may_steepen).

    // The heights sub-step `now` reads.
    static Heights heights_read(Grid &grid, MeshState &s, double dt, double now) {
        Heights hv{grid.heights_for_stepping().data()};
        if (s.lazy) hv.q = s.sand_source.data(), hv.since = s.since.data(), hv.dt = dt, hv.now = now;
        return hv;
    }

    // Every cell's height as `lagging` reads it, into `into`.
    static Heights heights_found_once(const Mesh &m, const Heights &lagging, int threads, std::vector<double> &into) {
        if (!lagging.q) return lagging;
        into.resize(static_cast<std::size_t>(m.cells));
        double *found = into.data();
        const bool parallel = threads_in_use(threads, m.cells) > 1;
#pragma omp parallel for num_threads(threads) if (parallel) schedule(static)
        for (std::int64_t c = 0; c < m.cells; ++c) found[c] = lagging[c];
        return Heights{found};
    }

    // What the sources make of the mesh (after the host changed them, which
    // every change of a source's value is): the sand cells' sources, which
    // cells' slopes they move, the faces whose slopes they move and those
    // faces' cells.
    static void list_source_faces(const Mesh &m, const std::vector<double> &q, MeshState &s) {
        const std::size_t n = static_cast<std::size_t>(m.cells);
        s.sand_source.assign(n, 0.0);
        s.source_reach.assign(n, 0);
        s.source_faces.clear();
        s.source_face_cells.clear();
        if (s.source_cells.empty() && s.ghost_source_cells.empty()) return;
        for (const std::vector<std::int64_t> *list : {&s.source_cells, &s.ghost_source_cells})
            for (const std::int64_t c : *list) s.sand_source[c] = q[c];
        // A cell's height moves under a source, or its gradient reads one.
        for (std::int64_t c = 0; c < m.cells; ++c) {
            bool reach = s.sand_source[c] != 0.0;
            for (std::int64_t k = m.grad_start[c]; k < m.grad_start[c + 1] && !reach; ++k)
                reach = s.sand_source[m.grad_cells[k]] != 0.0;
            if (reach) s.source_reach[c] |= kSourceReach;
        }
        // A face's slope moves where it reads such a cell; the cells of its faces are near a source.
        const std::uint32_t listed = next_stamp(s);
        for (std::int64_t f = 0; f < m.live_faces; ++f) {
            const std::int64_t a = m.face_a[f], b = m.face_b[f];
            if (!((s.source_reach[a] & kSourceReach) || (b >= 0 && (s.source_reach[b] & kSourceReach)))) continue;
            s.source_faces.push_back(f);
            for (const std::int64_t e : {a, b}) {
                if (e < 0) continue;
                s.source_reach[e] |= kSourceNear;
                if (s.cell_seen[e] != listed) s.cell_seen[e] = listed, s.source_face_cells.push_back(e);
            }
        }
        std::sort(s.source_face_cells.begin(), s.source_face_cells.end());
    }

    // Which faces whose slopes the sources move are steep (or within a band
    // of rounding below their thresholds) at sub-steps `first` (none where it
    // is negative) and `second` of the step, the sources alone acting from the
    // heights now: whether any is at `first`, whether any is at `second`; with
    // `watch`, the cells of those steep at either are kept hot for the rest
    // of the step. Collective
    // on a part with one layer of ghosts (their gradients come from their
    // owners; a part that steps its ghosts holds their stencils); the answers
    // are this part's.
    struct Steep {
        bool first = false, second = false;
    };
    Steep look_under_sources(Grid &grid, const Mesh &m, MeshState &s, double dt, double first, double second,
                             bool watch) const {
        const std::size_t n = static_cast<std::size_t>(m.cells);
        for (std::vector<double> *v : {&s.look_gx, &s.look_gy, &s.look_gx_later, &s.look_gy_later}) v->resize(n, 0.0);
        s.look_steep.resize(static_cast<std::size_t>(m.faces), 0);
        const std::uint8_t *kind = grid.kinds().data();
        FaceLaw at_first = law_of(grid, heights_read(grid, s, dt, first), s.look_gx.data(), s.look_gy.data(), dt);
        FaceLaw at_second =
            law_of(grid, heights_read(grid, s, dt, second), s.look_gx_later.data(), s.look_gy_later.data(), dt);
        const int threads = grid.step_threads();
        const bool both = first >= 0.0;
        // Where the look reads most cells' heights, many times each
        // (gradients' stencils, faces), it finds them once at each time, as a
        // dense sub-step does; a few source cells are not worth a pass over all.
        const bool every_owned_cell = s.exchange && !steps_ghosts(grid);
        const bool most_cells = every_owned_cell || static_cast<double>(s.source_face_cells.size()) >
                                                        kDenseShare * static_cast<double>(m.owned);
        if (most_cells && !s.switches.scalar_mesh) {
            at_second.h = heights_found_once(m, at_second.h, threads, s.heights_read);
            if (both) at_first.h = heights_found_once(m, at_first.h, threads, s.heights_read_earlier);
        }
        const auto gradients = [&](std::int64_t c) {
            if (both) gradient_of(m, at_first.h, kind, c, s.look_gx.data(), s.look_gy.data());
            gradient_of(m, at_second.h, kind, c, s.look_gx_later.data(), s.look_gy_later.data());
        };
        if (at_first.isotropic) {
            if (every_owned_cell) {
                // Every owned cell: a ghost's owner reads the gradient of the cell across their face.
                const std::int64_t owned = m.owned;
#pragma omp parallel for num_threads(threads) if (threads_in_use(threads, owned) > 1) schedule(static)
                for (std::int64_t c = 0; c < owned; ++c) gradients(c);
                s.exchange->send_all(GhostExchange::kFaceGhosts,
                                     {GhostField{s.look_gx.data()}, GhostField{s.look_gy.data()},
                                      GhostField{s.look_gx_later.data()}, GhostField{s.look_gy_later.data()}},
                                     false);
            } else {
                const std::int64_t count = static_cast<std::int64_t>(s.source_face_cells.size());
                const std::int64_t *cells = s.source_face_cells.data();
#pragma omp parallel for num_threads(threads) if (threads_in_use(threads, count) > 1) schedule(static)
                for (std::int64_t k = 0; k < count; ++k) gradients(cells[k]);
            }
        }
        const std::int64_t count = static_cast<std::int64_t>(s.source_faces.size());
        std::uint8_t *steep = s.look_steep.data();
        // The faces in lanes as if each carried sand between two cells where
        // the laws allow, the others (and every face where they do not) as
        // FaceLaw finds them; a face is kept if steep at either time.
        const bool lanes = looks_in_lanes(at_second, s) && (!both || looks_in_lanes(at_first, s));
        s.look_steep_earlier.resize(static_cast<std::size_t>(m.faces), 0);
        std::uint8_t *steep_then = s.look_steep_earlier.data();
        std::atomic<bool> found_first{false}, found_second{false};
        // Where the sources move every face the list is the faces in order, read as a range.
        const bool every_face = count == m.live_faces;
        const auto find_in_lanes = [&](const FaceLaw &law, std::uint8_t *into, const std::int64_t *list,
                                       std::int64_t listed) {
            const SteepLanes steep_lanes_of = steep_lanes(m, law, into);
            if (every_face && listed > 0)
                may_be_steep_in_lanes(steep_lanes_of, list[0], list[0] + listed);
            else
                may_be_steep_in_lanes(steep_lanes_of, list, listed);
        };
        for_each_share(s.source_faces, threads, [&](const std::int64_t *list, std::int64_t listed) {
            if (lanes) {
                find_in_lanes(at_second, steep, list, listed);
                if (both) find_in_lanes(at_first, steep_then, list, listed);
            }
            bool first_here = false, second_here = false;
            for (std::int64_t k = 0; k < listed; ++k) {
                const std::int64_t f = list[k];
                if (!lanes || off_lanes(m, at_second.carrying, f)) {
                    steep[f] = at_second.may_be_steep(f);
                    if (both) steep_then[f] = at_first.may_be_steep(f);
                }
                const bool then = both && steep_then[f], later = steep[f];
                steep[f] = then || later;
                first_here = first_here || then;
                second_here = second_here || later;
            }
            if (first_here) found_first = true;
            if (second_here) found_second = true;
        });
        const bool any_first = found_first, any_second = found_second;
        if (watch && (any_first || any_second))
            for (const std::int64_t f : s.source_faces)
                if (steep[f])
                    for (const std::int64_t e : {m.face_a[f], m.face_b[f]})
                        if (e >= 0) watch_cell(s, e);
        return Steep{any_first, any_second};
    }

    static void watch_cell(MeshState &s, std::int64_t c) {
        if (s.watch[c] & kWatched) return;
        s.watch[c] |= kWatched;
        s.watched_cells.push_back(c);
    }

    // Sand moved in cell c: the faces that read it no longer follow the
    // sources alone, so the cells near a source among those whose faces read
    // it are kept hot for the rest of the step (each cell looked at once).
    static void watch_near_moves(const Mesh &m, MeshState &s, std::int64_t c) {
        if (s.watch[c] & kNearMoves) return;
        s.watch[c] |= kNearMoves;
        s.moved_cells.push_back(c);
        if (s.source_reach[c] & kSourceNear) watch_cell(s, c);
        for (std::int64_t k = m.grad_start[c]; k < m.grad_start[c + 1]; ++k) {
            const std::int64_t e = m.grad_cells[k];
            if (s.source_reach[e] & kSourceNear) watch_cell(s, e);
        }
    }
    static void watch_near_moves(const Mesh &m, MeshState &s, const std::vector<std::int64_t> &cells) {
        if (!s.lazy) return;
        for (const std::int64_t c : cells) watch_near_moves(m, s, c);
    }

    static void forget_watches(MeshState &s) {
        for (const std::int64_t c : s.watched_cells) s.watch[c] = static_cast<std::uint8_t>(s.watch[c] & ~kWatched);
        for (const std::int64_t c : s.moved_cells) s.watch[c] = static_cast<std::uint8_t>(s.watch[c] & ~kNearMoves);
        s.watched_cells.clear();
        s.moved_cells.clear();
    }

    // How many cells the sources keep hot in the next sub-step, and waking them.
    static std::size_t kept_hot_by_sources(const MeshState &s) {
        return s.lazy ? s.watched_cells.size() : s.source_cells.size();
    }
    static void wake_what_sources_keep_hot(const Mesh &m, MeshState &s, bool ghosts_too) {
        MeshActivity &act = s.activity;
        if (s.lazy) {
            for (const std::int64_t c : s.watched_cells) act.wake(c);
            return;
        }
        for (const std::int64_t c : s.source_cells) act.wake_around(m, c);
        if (ghosts_too)
            for (const std::int64_t c : s.ghost_source_cells) act.wake_around(m, c);
    }

    // After sub-step `done` (counted from 1) of a step with lazy sources:
    // whether a source may still make a face steep before the step ends. Only
    // a sub-step that moved nothing asks, and only where sand has moved
    // since the last answer (else the sources alone acted since, and it
    // stands; before any move, drive_sources gave it). Collective on a part.
    bool source_may_steepen(Grid &grid, const Mesh &m, MeshState &s, double dt, bool moved, std::int64_t done) const {
        if (moved) s.moved_since_look = true;
        if (moved || !s.moved_since_look) return s.source_may_steepen;
        s.moved_since_look = false;
        const double now = static_cast<double>(done);
        const Steep found = look_under_sources(grid, m, s, dt, now, s.lazy_substeps, false);
        bool steep = found.first || found.second;
        if (grid.distribution()) steep = grid.global_sum(steep ? 1.0 : 0.0) > 0.0;
        s.source_may_steepen = steep;
        return steep;
    }

    // The end of a step with lazy sources: every owned source cell takes
    // what its source added since it was current, a TwoSum with its
    // residual as the sub-steps' updates; the clocks start again from 0. A
    // part that steps its ghosts holds their owners' heights, residuals and
    // clocks after the step's last exchange, and does the same to them;
    // another takes them from their owners (collective). Returns the owned
    // cells it changed.
    double catch_up_sources(Grid &grid, MeshState &s, double dt) const {
        std::vector<double> &h = grid.heights_for_stepping();
        std::vector<float> &residual = grid.residuals_for_stepping();
        const bool ghosts_here = s.exchange && steps_ghosts(grid);
        const int threads = grid.step_threads();
        std::int64_t changed = 0;
        for (const std::vector<std::int64_t> *list : {&s.source_cells, &s.ghost_source_cells}) {
            if (list == &s.ghost_source_cells && !ghosts_here) break;
            const std::int64_t count = static_cast<std::int64_t>(list->size()), *cells = list->data();
            const bool owned = list == &s.source_cells;
            std::int64_t taken = 0;
            // Each cell its own: the same bits on any number of threads.
#pragma omp parallel for num_threads(threads) if (threads_in_use(threads, count) > 1) schedule(static) reduction(+ : taken)
            for (std::int64_t k = 0; k < count; ++k) {
                const std::int64_t c = cells[k];
                const double lag = source_lag(s.sand_source[c], dt, s.lazy_substeps - s.since[c]);
                if (lag != 0.0) {
                    add_with_residual(h[c], residual[c], lag);
                    ++taken;
                }
                s.since[c] = 0.0;
            }
            if (owned) changed += taken;
        }
        if (s.exchange && !ghosts_here) {
            std::vector<std::int64_t> &changed_ghosts = s.changed_ghosts;
            changed_ghosts.clear();
            exchange_ghost_heights(grid, s, &s.source_cells, changed_ghosts);
            changed_ghosts.clear();
        }
        forget_watches(s);
        s.lazy = false;
        return static_cast<double>(changed);
    }

    // Whether the faces' terms run in lanes (mesh/face_lanes.hpp), over every
    // face or over a sparse sub-step's list: on a plain scene, unless a test
    // asks for FaceLaw::terms alone.
    static bool in_lanes(const FaceLaw &law, const MeshState &s) {
        return !s.switches.scalar_mesh && law.isotropic && !law.tan_field && !law.moving && !law.available &&
               (law.p == 1.0 || law.p == 2.0);
    }

    // The three face passes' lanes over sub-step law `law`'s view and the state's values.
    struct PassLanes {
        FaceLanes terms;
        FlowLanes flow;
        LimitLanes limit;
    };
    static PassLanes lanes_of(const Mesh &m, const FaceLaw &law, MeshState &s) {
        double *low = s.low.data(), *high = s.high.data(), *pull = s.pull.data(), *excess = s.excess.data();
        double *pull_x = s.pull_x.data(), *pull_y = s.pull_y.data();
        return PassLanes{
            FaceLanes{m.face_a.data(), m.face_b.data(), m.tangent_x.data(), m.tangent_y.data(), m.distance.data(),
                      m.orthogonal.data(), m.skew.data(), m.conductance.data(), law.h.h, law.gx, law.gy, law.h.q,
                      law.h.since, law.h.dt, law.h.now, law.nu, law.tan_theta, law.tolerance, law.p == 2.0, low,
                      high, pull, excess, s.steep.data()},
            FlowLanes{m.face_a.data(), m.face_b.data(), law.carrying, m.pair_ax.data(), m.pair_ay.data(),
                      m.pair_bx.data(), m.pair_by.data(), pull_x, pull_y, high},
            LimitLanes{m.face_a.data(), m.face_b.data(), low, high, excess, s.limit_in.data(), s.limit_out.data(),
                       s.flux.data()}};
    }

    // Whether the look under the sources finds a law's steep faces in lanes
    // (may_be_steep_in_lanes): on a plain scene whose heights it found once.
    static bool looks_in_lanes(const FaceLaw &law, const MeshState &s) {
        return !s.switches.scalar_mesh && law.isotropic && !law.tan_field && !law.moving && !law.h.q;
    }
    static SteepLanes steep_lanes(const Mesh &m, const FaceLaw &law, std::uint8_t *steep) {
        return SteepLanes{m.face_a.data(), m.face_b.data(), m.tangent_x.data(), m.tangent_y.data(), m.distance.data(),
                          law.h.h, law.gx, law.gy, law.tan_theta, law.tolerance, steep};
    }

    // A face whose terms the lanes do not take (FaceLaw::terms does): on the
    // domain edge, along a wall, carrying nothing.
    static bool off_lanes(const Mesh &m, const std::uint8_t *carrying, std::int64_t f) {
        return carrying[f] != kCarries || m.face_b[f] < 0;
    }

    // One sub-step's law over the grid, reading heights `hv` and gradients gx, gy.
    static FaceLaw law_of(Grid &grid, const Heights &hv, const double *gx, const double *gy, double dt) {
        const Mesh &m = *grid.geometry().mesh;
        return FaceLaw{m,
                       hv,
                       grid.kinds().data(),
                       gx,
                       gy,
                       mesh_state(grid).carrying.data(),
                       mesh_state(grid).beside_wall.empty() ? nullptr : mesh_state(grid).beside_wall.data(),
                       grid.side_levels(0).empty() ? nullptr : grid.side_levels(0).data(),
                       grid.tan_field().empty() ? nullptr : grid.tan_field().data(),
                       grid.hysteresis() ? grid.moving().data() : nullptr,
                       nullptr,
                       grid.mobility(),
                       grid.tan_repose(),
                       grid.rest_tolerance(),
                       grid.tan_static(),
                       grid.flux_exponent(),
                       dt,
                       grid.scheme() == kIsotropic};
    }

    static std::uint32_t next_stamp(MeshState &s) {
        if (++s.stamp == 0) {
            std::fill(s.face_seen.begin(), s.face_seen.end(), 0);
            std::fill(s.cell_seen.begin(), s.cell_seen.end(), 0);
            s.stamp = 1;
        }
        return s.stamp;
    }

    // With a bed: the source a cell takes this sub-step (erosion at most the
    // sand there), as prepare_bed found it.
    static double source_applied(const std::vector<double> &zb, const std::vector<double> &h,
                                 const std::vector<double> &q, std::int64_t c, double dt) {
        const double asked = q[c] * dt;
        if (asked >= 0.0) return q[c];
        const double sand = std::max(0.0, h[c] - zb[c]);
        return -std::min(-asked, sand) / dt;
    }

    // The sand above the bed that faces may take this sub-step, after the
    // cell's own erosion; books what the source applied and what it could not.
    static void prepare_bed(Grid &grid, const Mesh &m, MeshState &s, double dt, SubstepSummary &did) {
        const std::vector<double> &zb = grid.bed(), &h = grid.heights(), &q = grid.source();
        const std::vector<std::uint8_t> &kind = grid.kinds();
        const double film = bed_film(grid);
        CompensatedSum unmet, sourced;
        for (std::int64_t c = 0; c < m.cells; ++c) {
            if (kind[c] != kSand) {
                s.available[c] = 0.0;
                continue;
            }
            double sand = std::max(0.0, h[c] - zb[c]);
            const double asked = q.empty() ? 0.0 : q[c] * dt;
            double applied = asked;
            if (asked < 0.0) {
                applied = -std::min(-asked, sand);
                if (c < m.owned) unmet.add((applied - asked) * m.area[c]);
                sand += applied;
            }
            if (c < m.owned) sourced.add(applied * m.area[c]);  // a ghost's owner books it
            s.available[c] = sand > film ? sand * m.area[c] : 0.0;
        }
        did.unmet_mass = unmet.value();
        did.sourced_mass = sourced.value();
    }
};

}  // namespace

const Engine &mesh_engine() {
    static const MeshEngine engine;
    return engine;
}

}  // namespace dpsm
