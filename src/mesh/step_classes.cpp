#include "mesh/step_classes.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "mesh/ghost_exchange.hpp"
#include "model/distribution.hpp"

namespace dpsm {

namespace {

// Items 0 .. level.size() sorted by level then index, and where each
// level's items end.
void sort_by_level(const std::vector<std::uint8_t> &level, int top, std::vector<std::int64_t> &items,
                   std::vector<std::int64_t> &end) {
    items.resize(level.size());
    std::iota(items.begin(), items.end(), std::int64_t{0});
    std::stable_sort(items.begin(), items.end(), [&](std::int64_t a, std::int64_t b) { return level[a] < level[b]; });
    end.assign(static_cast<std::size_t>(top) + 1, 0);
    for (const std::uint8_t l : level) ++end[l];
    std::partial_sum(end.begin(), end.end(), end.begin());
}

// Per cell, the finest (or the coarsest) of its faces' levels; `none` where it has no face here.
std::vector<std::uint8_t> over_faces(const Mesh &m, const std::vector<std::uint8_t> &face_level, bool finest,
                                     std::uint8_t none) {
    std::vector<std::uint8_t> level(static_cast<std::size_t>(m.cells), none);
    for (std::int64_t c = 0; c < m.cells; ++c)
        for (std::int64_t k = m.cell_face_start[c]; k < m.cell_face_start[c + 1]; ++k) {
            const std::int64_t f = m.cell_faces[k];
            if (f >= m.live_faces) continue;
            std::uint8_t &l = level[static_cast<std::size_t>(c)];
            l = finest ? std::min(l, face_level[static_cast<std::size_t>(f)]) : std::max(l, face_level[static_cast<std::size_t>(f)]);
        }
    return level;
}

// Per face here, the finer of its cells' levels (its one cell's on the domain edge).
std::vector<std::uint8_t> finer_of_cells(const Mesh &m, const std::vector<std::uint8_t> &cell_level) {
    std::vector<std::uint8_t> level(static_cast<std::size_t>(m.live_faces));
    for (std::int64_t f = 0; f < m.live_faces; ++f) {
        const std::int64_t b = m.face_b[f];
        const std::uint8_t la = cell_level[static_cast<std::size_t>(m.face_a[f])];
        level[static_cast<std::size_t>(f)] = b >= 0 ? std::min(la, cell_level[static_cast<std::size_t>(b)]) : la;
    }
    return level;
}

// The ghosts take their owners' values of a per-cell level (a part's
// ghosts lack some of their faces, so their own would be wrong); nothing on
// a serial mesh.
void from_owners(GhostExchange *exchange, std::vector<std::uint8_t> &level) {
    if (exchange) exchange->send_all(GhostExchange::kEveryGhost, {GhostField{nullptr, nullptr, level.data()}}, false);
}

StepClasses classes_of(const Mesh &m, GhostExchange *exchange, const Collectives *ranks) {
    StepClasses out;
    std::vector<std::uint8_t> cell_class(static_cast<std::size_t>(m.cells), kMaxStepClass);
    int top = 0;
    for (std::int64_t c = 0; c < m.owned; ++c) {
        double sum = 0.0;
        for (std::int64_t k = m.cell_face_start[c]; k < m.cell_face_start[c + 1]; ++k) sum += m.conductance[m.cell_faces[k]];
        if (!(sum > 0.0)) continue;
        const double bound = m.area[c] / sum;
        int k = 0;
        while (k < kMaxStepClass && std::ldexp(m.step_scale, k + 1) <= bound) ++k;
        cell_class[static_cast<std::size_t>(c)] = static_cast<std::uint8_t>(k);
        top = std::max(top, k);
    }
    if (ranks) top = static_cast<int>(ranks->max(static_cast<double>(top)));
    from_owners(exchange, cell_class);
    out.top = top;
    const std::uint8_t top_level = static_cast<std::uint8_t>(top);
    // A cell without conductance has no face that carries: its class only caps.
    for (std::uint8_t &k : cell_class) k = std::min(k, top_level);
    out.face_class = finer_of_cells(m, cell_class);
    // Each item's level: the finest of the items it reads.
    std::vector<std::uint8_t> reading = over_faces(m, out.face_class, true, top_level);
    from_owners(exchange, reading);
    out.finest = reading;
    out.coarsest = over_faces(m, out.face_class, false, 0);
    from_owners(exchange, out.coarsest);
    const std::vector<std::uint8_t> carrying = finer_of_cells(m, reading);
    out.taking_level = over_faces(m, carrying, true, top_level);
    from_owners(exchange, out.taking_level);
    out.waking.assign(static_cast<std::size_t>(m.cells), 0);
    for (std::int64_t c = 0; c < m.cells; ++c) {
        std::uint8_t &w = out.waking[static_cast<std::size_t>(c)];
        w = out.coarsest[static_cast<std::size_t>(c)];
        for (std::int64_t k = m.grad_start[c]; k < m.grad_start[c + 1]; ++k)
            w = std::max(w, out.coarsest[static_cast<std::size_t>(m.grad_cells[k])]);
    }
    // A part computes its owned cells and the faces that touch them (all a serial mesh has).
    const auto owned = [&](const std::vector<std::uint8_t> &level) {
        return std::vector<std::uint8_t>(level.begin(), level.begin() + m.owned);
    };
    sort_by_level(out.face_class, top, out.firing_faces, out.firing_end);
    sort_by_level(owned(reading), top, out.reading_cells, out.reading_end);
    sort_by_level(carrying, top, out.carrying_faces, out.carrying_end);
    sort_by_level(owned(out.taking_level), top, out.taking_cells, out.taking_end);
    return out;
}

}  // namespace

StepClasses step_classes_of(const Mesh &m) { return classes_of(m, nullptr, nullptr); }

StepClasses step_classes_of(const Mesh &m, GhostExchange &exchange, const Collectives &ranks) {
    return classes_of(m, &exchange, &ranks);
}

}  // namespace dpsm
