#include "mesh/mesh_engine.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "mesh/ghost_exchange.hpp"
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
// A sub-step over more hot cells than this share of the mesh runs the plain
// passes over every cell: the lists would cost more than they save.
constexpr double kDenseShare = 0.125;

// One sub-step's view of the grid: what every pass reads.
struct FaceLaw {
    const Mesh &m;
    const double *h;
    const std::uint8_t *kind;
    const double *gx, *gy;
    const std::uint8_t *edge_open;  // per face; null: every edge as open_edges says
    bool open_edges;
    const double *edge_level;       // per face; null: 0
    const double *tan_field;        // null: uniform
    const std::uint8_t *moving;     // hysteresis: null when off
    const double *available;        // bed: the sand each cell may give, as a volume; null when none
    double nu, tan_theta, tolerance, tan_static, p, dt;
    bool isotropic;

    // The volume per unit time from a to b over face f, and its excess slope.
    double operator()(std::int64_t f, double &excess) const {
        const std::int64_t a = m.face_a[f], b = m.face_b[f];
        const std::uint8_t ka = kind[a];
        double hb, tangential = 0.0;
        std::uint8_t kb;
        if (b >= 0) {
            kb = kind[b];
            if (ka == kWall || kb == kWall || (ka != kSand && kb != kSand)) return 0.0;
            hb = h[b];
            if (isotropic)
                tangential = 0.5 * ((gx[a] + gx[b]) * m.tangent_x[f] + (gy[a] + gy[b]) * m.tangent_y[f]);
        } else {
            if (ka != kSand || !(edge_open ? edge_open[f] != 0 : open_edges)) return 0.0;
            kb = kOutside;
            hb = edge_level ? edge_level[f] : 0.0;
            if (isotropic) tangential = gx[a] * m.tangent_x[f] + gy[a] * m.tangent_y[f];
        }
        const double normal = (h[a] - hb) / m.distance[f];
        const double tan_face =
            tan_field ? law::face_tan(tan_field[a], b >= 0 ? tan_field[b] : tan_field[a], ka == kSand, kb == kSand)
                      : tan_theta;
        double threshold = tan_face * (1.0 + tolerance);
        if (moving) threshold = law::threshold(threshold, !moving[a] && !(b >= 0 && moving[b]), tan_static);
        const double s = std::sqrt(normal * normal + tangential * tangential);
        if (!(s > threshold)) return 0.0;
        const double abs_normal = std::fabs(normal);
        if (!(abs_normal > tolerance * tan_face)) return 0.0;
        // The flux across the face's normal, -nu f(s)/s grad h . L n, with
        // grad h . e from the two points and grad h . t reconstructed, written
        // as C (h_a - h_b): its factor C d / (nu f(s)/s) is held in [0, |L n|]
        // (a face never carries sand up its two-point slope, nor more than
        // the stable sub-step allows).
        double factor = m.orthogonal[f];
        if (m.skew[f] != 0.0) factor -= tangential * m.skew[f] / normal;
        const double most = m.conductance[f] * m.distance[f];
        factor = std::min(factor, most);
        // The slope across the face. Near rest, a face nearly parallel to the
        // slope (across it at most kMeshDeadZone tan(theta)) carries nothing
        // unless its slope is clearly steep, and none carries sand with a
        // slope across it below the rest tolerance (mesh_engine.hpp,
        // docs/guarantees.md).
        const double across = factor * abs_normal / most;
        if (!(across > tolerance * tan_face)) return 0.0;
        if (!(across > kMeshDeadZone * tan_face) && !(s > tan_face * (1.0 + kMeshNearRest))) return 0.0;
        excess = s - tan_face;
        double flux = slide_flux(nu, tan_face, s, p) / s * factor * normal;
        if (available) {
            // A face takes from its sand cell at most its share of the sand there.
            const double unlimited = std::numeric_limits<double>::infinity();
            const auto share = [&](std::int64_t c) {
                return c >= 0 && kind[c] == kSand ? law::share_of_sand(available[c], m.face_count[c], dt, 1.0)
                                                  : unlimited;
            };
            flux = law::capped(flux, share(a), -share(b));
        }
        return flux;
    }
};

void gradient_of(const Mesh &m, const double *h, const std::uint8_t *kind, std::int64_t c, double *gx, double *gy) {
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
        if (s.flux.size() != nf) s.flux.assign(nf, 0.0);
        s.face_seen.resize(nf, 0), s.cell_seen.resize(n, 0);
        s.carried.resize(n, 0);
        if (s.exchange) s.in_batch.resize(n, 0);
        if (!grid.bed().empty()) s.available.resize(n, 0.0);
        if (s.lists_current) return;
        s.lists_current = true;
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
    }

    bool may_move(const Grid &grid) const override { return mesh_state(grid).activity.may_move(); }

    // Every source cell takes its source at every sub-step and counts as driven.
    bool drive_sources(Grid &, double, double, bool, double &reach) const override {
        reach = std::numeric_limits<double>::infinity();
        return true;
    }
    void forget_driven(Grid &) const override {}

    void advance(Grid &grid, const SubstepPlan &plan, const BookSubstep &book, StepInfo &info) const override {
        const Mesh &m = *grid.geometry().mesh;
        MeshState &s = mesh_state(grid);
        const bool record = grid.records_face_fluxes();
        if (record) std::fill(grid.face_fluxes().x.begin(), grid.face_fluxes().x.end(), 0.0);
        if (!plan.something_may_move) {
            info.at_rest = true;
            return;
        }
        s.switches = read_switches();
        const Distribution *parts = grid.distribution();
        // A part whose ghost layer is deep enough steps its ghosts in reach
        // too and exchanges once per batch of sub-steps (mesh/mesh_parts.hpp);
        // the step ends with an exchange, so that a step starts exact.
        const int per_exchange = s.exchange ? m.substeps_per_exchange : 0;
        for (std::int64_t k = 0; k < plan.substeps; ++k) {
            double visited = 0.0;
            const int in_batch = per_exchange > 0 ? static_cast<int>(k % per_exchange) + 1 : 0;
            SubstepSummary did = substep(grid, m, s, plan.sub_dt, record, visited, in_batch);
            info.cell_updates += visited;
            if (parts) {
                // Every rank takes the same sub-steps and stops at the same one.
                std::vector<SubstepSummary> agreed{did};
                parts->agree_on_substeps(agreed);
                did = agreed[0];
            }
            const bool go_on = book(did);
            if (in_batch > 0 && (!go_on || in_batch == per_exchange || k + 1 == plan.substeps)) end_batch(grid, m, s);
            if (!go_on) break;
        }
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

        bool operator()(std::int64_t c) const {
            bool carried = false;
            double rate = net_rate(m, flux, c, carried);
            if (kind[c] != kSand) return carried;
            if (!q.empty()) rate += zb.empty() ? q[c] : source_applied(zb, h, q, c, dt);
            if (rate != 0.0) add_with_residual(h[c], residual[c], dt * rate);
            if (!zb.empty() && h[c] < zb[c]) {
                residual[c] = static_cast<float>(static_cast<double>(residual[c]) - (zb[c] - h[c]));
                h[c] = zb[c];
            }
            return carried;
        }
    };

    // `in_batch`: the sub-step's place after the last exchange (from 1) on a
    // part that takes several per exchange; 0: two exchanges in this one.
    SubstepSummary substep(Grid &grid, const Mesh &m, MeshState &s, double dt, bool record, double &visited,
                           int in_batch) const {
        MeshActivity &act = s.activity;
        const bool physics = grid.hysteresis() || !grid.bed().empty();
        // A part of a distributed mesh steps its owned cells and the faces
        // that touch them; its ghosts' heights and gradients come from their
        // owners, only where they changed (mesh/mesh_parts.hpp).
        const bool parts = s.exchange != nullptr;
        const bool dense = physics || act.all_hot || s.switches.visit_all_cells ||
                           static_cast<double>(act.hot_list.size()) > kDenseShare * static_cast<double>(m.owned);
        std::vector<std::int64_t> &changed_ghosts = s.changed_ghosts;
        changed_ghosts.clear();
        std::vector<double> &h = grid.heights_for_stepping();
        std::vector<float> &residual = grid.residuals_for_stepping();
        const std::vector<std::uint8_t> &kind = grid.kinds();
        const std::vector<double> &q = grid.source();
        SubstepSummary did;

        FaceLaw law{m,
                    h.data(),
                    kind.data(),
                    s.gx.data(),
                    s.gy.data(),
                    grid.edge_open_flags().empty() ? nullptr : grid.edge_open_flags().data(),
                    grid.side_open(0),
                    grid.side_levels(0).empty() ? nullptr : grid.side_levels(0).data(),
                    grid.tan_field().empty() ? nullptr : grid.tan_field().data(),
                    grid.hysteresis() ? grid.moving().data() : nullptr,
                    nullptr,
                    grid.mobility(),
                    grid.tan_repose(),
                    std::max(grid.rest_tolerance(), kMeshRestTolerance),
                    grid.tan_static(),
                    grid.flux_exponent(),
                    dt,
                    grid.scheme() == kIsotropic};
        if (!grid.bed().empty()) {
            prepare_bed(grid, m, s, dt, did);
            law.available = s.available.data();
        }
        const int threads = grid.step_threads();
        double max_excess = 0.0;
        bool moved = false;
        const CellUpdate update_cell{m, s.flux.data(), kind.data(), q, grid.bed(), h, residual, dt};
        // On a part that steps its ghosts in reach: their gradients, faces and cells too.
        const BatchReach reach{m, in_batch};

        if (dense) {
            // The owned cells and the faces that touch them: all of a serial mesh.
            const std::int64_t n = m.owned, nf = m.live_faces;
            const bool parallel = threads > 1 && n >= kCellsForThreads;
            const std::int64_t *extra_cells = reach.ghosts();
            const std::int64_t extra_count = reach.ghost_count();
            if (law.isotropic) {
#pragma omp parallel for num_threads(threads) if (parallel) schedule(static)
                for (std::int64_t c = 0; c < n; ++c) gradient_of(m, h.data(), kind.data(), c, s.gx.data(), s.gy.data());
                if (in_batch) {
                    for (std::int64_t k = 0; k < reach.ghost_gradient_count(); ++k)
                        gradient_of(m, h.data(), kind.data(), reach.ghost_gradients()[k], s.gx.data(), s.gy.data());
                } else if (parts) {
                    exchange_ghost_gradients(s, nullptr, changed_ghosts);
                }
            }
            double *flux = s.flux.data();
#pragma omp parallel for num_threads(threads) if (parallel) schedule(static) reduction(max : max_excess) reduction(|| : moved)
            for (std::int64_t f = 0; f < nf; ++f) {
                double excess = 0.0;
                const double v = law(f, excess);
                flux[f] = v;
                if (v != 0.0) {
                    moved = true;
                    max_excess = std::max(max_excess, excess);
                }
            }
            // The faces beyond the owned cells' that the ghosts in reach need; they count for nothing here.
            for (std::int64_t k = 0; k < reach.face_count(); ++k) {
                const std::int64_t f = reach.faces()[k];
                double excess = 0.0;
                flux[f] = law(f, excess);
            }
            s.flux_clean = false;
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
            // The next sub-step looks at the cells that changed and those whose
            // gradients read them; where that is most of the mesh, at all.
            const std::size_t most = static_cast<std::size_t>(kDenseShare * static_cast<double>(n));
            if (static_cast<std::size_t>(changed_cells) + s.source_cells.size() > most) {
                act.wake_all();
            } else {
                act.cool_all();
                for (std::int64_t c = 0; c < n && !act.all_hot; ++c)
                    if (changed[c]) {
                        act.wake_around(m, c);
                        if (act.hot_list.size() > most) act.wake_all();
                    }
                for (const std::int64_t c : s.source_cells) act.wake_around(m, c);
                for (const std::int64_t c : changed_ghosts) act.wake_around(m, c);
                for (std::int64_t k = 0; k < extra_count && !act.all_hot; ++k)
                    if (changed[extra_cells[k]]) act.wake_around(m, extra_cells[k]);
                if (in_batch)
                    for (const std::int64_t c : s.ghost_source_cells) act.wake_around(m, c);
            }
        } else {
            // The faces of the hot cells, the owned cells whose gradients they
            // read (a ghost's comes from its owner).
            std::uint32_t stamp = next_stamp(s);
            s.faces.clear();
            s.gradient_cells.clear();
            const auto look_at_faces_of = [&](std::int64_t c) {
                for (std::int64_t k = m.cell_face_start[c]; k < m.cell_face_start[c + 1]; ++k) {
                    const std::int64_t f = m.cell_faces[k];
                    if (!reach.face(f) || s.face_seen[f] == stamp) continue;
                    s.face_seen[f] = stamp;
                    s.faces.push_back(f);
                    for (const std::int64_t e : {m.face_a[f], m.face_b[f]})
                        if (e >= 0 && reach.gradient(e) && s.cell_seen[e] != stamp) {
                            s.cell_seen[e] = stamp;
                            s.gradient_cells.push_back(e);
                        }
                }
            };
            for (const std::int64_t c : act.hot_list) look_at_faces_of(c);
            if (!s.flux_clean) {
                std::fill(s.flux.begin(), s.flux.end(), 0.0);
                s.flux_clean = true;
            }
            if (law.isotropic) {
                for (const std::int64_t c : s.gradient_cells) gradient_of(m, h.data(), kind.data(), c, s.gx.data(), s.gy.data());
                if (parts && !in_batch) {
                    // A ghost whose gradient changed makes its faces steep or flat
                    // whether or not anything near them here changed.
                    exchange_ghost_gradients(s, &s.gradient_cells, changed_ghosts);
                    for (const std::int64_t c : changed_ghosts) look_at_faces_of(c);
                    changed_ghosts.clear();
                }
            }
            // The cells to update: those of faces that carried sand, and the sources.
            const std::uint32_t update_stamp = next_stamp(s);
            s.update_cells.clear();
            const auto to_update = [&](std::int64_t c) {
                if (reach.cell(c) && s.cell_seen[c] != update_stamp) {
                    s.cell_seen[c] = update_stamp;
                    s.update_cells.push_back(c);
                }
            };
            for (const std::int64_t f : s.faces) {
                double excess = 0.0;
                const double v = law(f, excess);
                s.flux[f] = v;
                if (v == 0.0) continue;
                if (f < m.live_faces) {
                    moved = true;
                    max_excess = std::max(max_excess, excess);
                }
                for (const std::int64_t e : {m.face_a[f], m.face_b[f]})
                    if (e >= 0) to_update(e);
            }
            const std::size_t carried_cells = s.update_cells.size();
            for (const std::int64_t c : s.source_cells) to_update(c);
            if (in_batch)
                for (const std::int64_t c : s.ghost_source_cells) to_update(c);
            for (const std::int64_t c : s.update_cells) update_cell(c);
            visited = static_cast<double>(s.gradient_cells.size() + s.update_cells.size() - carried_cells);
            if (in_batch) {
                note_batch_updates(s, m, s.update_cells);
            } else if (parts) {
                exchange_ghost_heights(grid, s, &s.update_cells, changed_ghosts);
            }
            act.cool_all();
            for (const std::int64_t c : s.update_cells) act.wake_around(m, c);
            for (const std::int64_t c : changed_ghosts) act.wake_around(m, c);
        }
        // What went into sinks, face by face in one order whatever the threads.
        for (const std::int64_t f : s.sink_faces) {
            const double v = s.flux[f];
            if (v == 0.0) continue;
            const std::int64_t a = m.face_a[f], b = m.face_b[f];
            const double into_sink = b < 0 ? v * 1.0 : (kind[b] == kOpen ? v : -v);
            did.outflow_rate += into_sink;
            if (b < 0) did.side_outflow_rate[0] += v;
            (void)a;
        }
        if (record) {
            std::vector<double> &faces = grid.face_fluxes().x;
            // A part records the faces of its owned cells only (those beyond carry nothing here).
            if (dense) {
                for (std::int64_t f = 0; f < m.live_faces; ++f) faces[f] += s.flux[f] * dt;
            } else {
                for (const std::int64_t f : s.faces)
                    if (f < m.live_faces) faces[f] += s.flux[f] * dt;
            }
        }
        if (!dense)
            for (const std::int64_t f : s.faces) s.flux[f] = 0.0;
        else
            s.flux_clean = false;
        did.moved = moved;
        did.max_excess_slope = max_excess;
        return did;
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
