#include "mesh/mesh_parts.hpp"

#include <algorithm>

#include "mesh/ghost_exchange.hpp"
#include "mesh/mesh_state.hpp"
#include "model/grid.hpp"

namespace dpsm {

namespace {

// A ghost's height, moving flag (with hysteresis), residual (on a part
// that steps its ghosts: the next update adds to it) and the sub-step its
// height is current after (lazy sources: what its source added since is
// read, not stored), in that place.
const std::vector<GhostField> &height_fields(Grid &grid) {
    GhostField moving, residual;
    if (grid.hysteresis()) moving.u8 = grid.moving_for_stepping().data();
    if (steps_ghosts(grid)) residual.f32 = grid.residuals_for_stepping().data();
    MeshState &s = mesh_state(grid);
    s.ghost_fields.assign({GhostField{grid.heights_for_stepping().data()}, moving, residual, GhostField{s.since.data()}});
    return s.ghost_fields;
}

}  // namespace

bool steps_ghosts(const Grid &grid) { return grid.geometry().mesh->substeps_per_exchange > 0; }

// The fields across a face from an owned cell, in their places: the
// gradient, the pull (M^-1 P), the limiter's factors; each exchange sends
// its own and leaves the others absent.
namespace {
void exchange_face_fields(MeshState &s, int first, double *x, double *y, std::vector<std::int64_t> &changed_ghosts) {
    std::vector<GhostField> &fields = s.ghost_fields;
    fields.assign(6, GhostField{});
    fields[static_cast<std::size_t>(first)].f64 = x;
    fields[static_cast<std::size_t>(first) + 1].f64 = y;
    s.exchange->send_changed(GhostExchange::kFaceGhosts, fields, nullptr, changed_ghosts);
}
}  // namespace

void exchange_ghost_gradients(MeshState &s, std::vector<std::int64_t> &changed_ghosts) {
    exchange_face_fields(s, 0, s.gx.data(), s.gy.data(), changed_ghosts);
}

void exchange_ghost_pulls(MeshState &s, std::vector<std::int64_t> &changed_ghosts) {
    exchange_face_fields(s, 2, s.pull_x.data(), s.pull_y.data(), changed_ghosts);
}

void exchange_ghost_limits(MeshState &s) {
    std::vector<std::int64_t> ignored;
    exchange_face_fields(s, 4, s.limit_in.data(), s.limit_out.data(), ignored);
}

void exchange_ghost_heights(Grid &grid, MeshState &s, const std::vector<std::int64_t> *computed,
                            std::vector<std::int64_t> &changed_ghosts) {
    s.exchange->send_changed(GhostExchange::kEveryGhost, height_fields(grid), computed, changed_ghosts);
}

void note_batch_updates(MeshState &s, const Mesh &m, const std::vector<std::int64_t> &cells) {
    for (const std::int64_t c : cells)
        if (c < m.owned && !s.in_batch[c]) s.in_batch[c] = 1, s.batch_cells.push_back(c);
}

void note_batch_updates_everywhere(MeshState &s) { s.batch_all = true; }

void end_batch(Grid &grid, const Mesh &m, MeshState &s) {
    std::vector<std::int64_t> &changed_ghosts = s.changed_ghosts;
    changed_ghosts.clear();
    exchange_ghost_heights(grid, s, s.batch_all ? nullptr : &s.batch_cells, changed_ghosts);
    for (const std::int64_t c : s.batch_cells) s.in_batch[c] = 0;
    s.batch_cells.clear();
    s.batch_all = false;
    for (const std::int64_t c : changed_ghosts) s.activity.wake_around(m, c);
    changed_ghosts.clear();
}

void take_owners_masks(Grid &grid, GhostExchange &exchange) {
    const bool has_source = !grid.source().empty(), has_bed = !grid.bed().empty(),
               has_angles = !grid.angle_field().empty();
    std::vector<std::uint8_t> kinds = grid.kinds();
    std::vector<double> q = has_source ? grid.source() : std::vector<double>(kinds.size(), 0.0);
    std::vector<double> zb = grid.bed(), theta = grid.angle_field();
    GhostField bed, angles;
    if (has_bed) bed.f64 = zb.data();
    if (has_angles) angles.f64 = theta.data();
    exchange.send_all(GhostExchange::kEveryGhost, {GhostField{nullptr, nullptr, kinds.data()}, GhostField{q.data()}, bed, angles},
                      false);
    const bool any_source = std::any_of(q.begin(), q.end(), [](double v) { return v != 0.0; });
    if (kinds != grid.kinds()) grid.set_cell_kinds(kinds.data());
    if ((has_source && q != grid.source()) || (!has_source && any_source)) grid.set_source(q.data());
    if (has_bed && zb != grid.bed()) grid.set_bed(zb.data());
    if (has_angles && theta != grid.angle_field()) grid.set_angle_field(theta.data());
}

void take_owners_heights(Grid &grid, GhostExchange &exchange) {
    const Mesh &m = *grid.geometry().mesh;
    const std::vector<double> &h = grid.heights();
    const std::vector<std::uint8_t> &moving = grid.moving();
    const bool hysteresis = grid.hysteresis();
    const std::size_t ghosts = static_cast<std::size_t>(m.cells - m.owned);
    std::vector<double> h_before(h.begin() + m.owned, h.end());
    std::vector<std::uint8_t> moving_before = hysteresis ? std::vector<std::uint8_t>(moving.begin() + m.owned, moving.end())
                                                         : std::vector<std::uint8_t>();
    exchange.send_all(GhostExchange::kEveryGhost, height_fields(grid), true);
    MeshActivity &activity = mesh_state(grid).activity;
    for (std::size_t g = 0; g < ghosts; ++g) {
        const std::size_t c = static_cast<std::size_t>(m.owned) + g;
        if (h[c] != h_before[g] || (hysteresis && moving[c] != moving_before[g]))
            activity.wake_around(m, static_cast<std::int64_t>(c));
    }
}

void take_owners_edges(Grid &grid, GhostExchange &exchange, int most_edge_faces) {
    const Mesh &m = *grid.geometry().mesh;
    const std::size_t most = static_cast<std::size_t>(most_edge_faces), cells = static_cast<std::size_t>(m.cells);
    if (most == 0) return;
    const std::vector<double> &levels = grid.side_levels(0);
    std::vector<std::uint8_t> open(static_cast<std::size_t>(m.faces));
    for (std::int64_t f = 0; f < m.faces; ++f) open[f] = m.face_b[f] < 0 && grid.edge_open(f);
    std::vector<double> level = levels.empty() ? std::vector<double>(static_cast<std::size_t>(m.faces), 0.0) : levels;
    const auto edge_faces = [&](std::int64_t c, std::vector<std::int64_t> &out) {
        out.clear();
        for (std::int64_t k = m.cell_face_start[c]; k < m.cell_face_start[c + 1]; ++k)
            if (m.other[k] < 0) out.push_back(m.cell_faces[k]);
    };
    // Per cell, its k-th edge face's kind and level (0 beyond its last), and how many it has.
    std::vector<std::vector<double>> values(2 * most + 1, std::vector<double>(cells, 0.0));
    std::vector<double> &edge_count = values.back();
    std::vector<std::int64_t> faces;
    for (std::int64_t c = 0; c < m.owned; ++c) {
        edge_faces(c, faces);
        edge_count[static_cast<std::size_t>(c)] = static_cast<double>(faces.size());
        for (std::size_t k = 0; k < faces.size(); ++k) {
            values[2 * k][static_cast<std::size_t>(c)] = open[faces[k]];
            values[2 * k + 1][static_cast<std::size_t>(c)] = level[faces[k]];
        }
    }
    std::vector<GhostField> fields;
    for (std::vector<double> &v : values) fields.push_back(GhostField{v.data()});
    exchange.send_all(GhostExchange::kEveryGhost, fields, false);
    const std::vector<std::uint8_t> open_before = open;
    const std::vector<double> level_before = level;
    for (std::int64_t c = m.owned; c < m.cells; ++c) {
        // Only a ghost whose faces are all here orders them as its owner
        // does; the passes before the update read the others' faces for
        // nothing. A ghost on the layer's rim may hold as many faces as its
        // owner, some of them onto cells beyond the layer, which read as
        // edge faces here: it has more edge faces than its owner.
        if (static_cast<double>(m.cell_face_start[c + 1] - m.cell_face_start[c]) != m.face_count[c]) continue;
        edge_faces(c, faces);
        if (static_cast<double>(faces.size()) != edge_count[static_cast<std::size_t>(c)]) continue;
        for (std::size_t k = 0; k < faces.size(); ++k) {
            open[faces[k]] = values[2 * k][static_cast<std::size_t>(c)] != 0.0;
            level[faces[k]] = values[2 * k + 1][static_cast<std::size_t>(c)];
        }
    }
    if (open != open_before) grid.set_edge_open(open.data());
    if (level != level_before) grid.set_side_levels(0, level.data());
}

}  // namespace dpsm
