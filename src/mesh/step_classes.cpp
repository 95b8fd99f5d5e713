#include "mesh/step_classes.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace dpsm {

namespace {

// `items` 0 .. level.size() sorted by level then index, and where each
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

}  // namespace

StepClasses step_classes_of(const Mesh &m) {
    StepClasses out;
    const std::size_t cells = static_cast<std::size_t>(m.cells), faces = static_cast<std::size_t>(m.live_faces);
    std::vector<std::uint8_t> cell_class(cells, kMaxStepClass);
    int top = 0;
    for (std::int64_t c = 0; c < m.cells; ++c) {
        double sum = 0.0;
        for (std::int64_t k = m.cell_face_start[c]; k < m.cell_face_start[c + 1]; ++k) sum += m.conductance[m.cell_faces[k]];
        if (!(sum > 0.0)) continue;
        const double bound = m.area[c] / sum;
        int k = 0;
        while (k < kMaxStepClass && std::ldexp(m.step_scale, k + 1) <= bound) ++k;
        cell_class[static_cast<std::size_t>(c)] = static_cast<std::uint8_t>(k);
        top = std::max(top, k);
    }
    out.top = top;
    // A cell without conductance has no face that carries: its class only caps.
    for (std::uint8_t &k : cell_class) k = static_cast<std::uint8_t>(std::min<int>(k, top));
    out.face_class.resize(faces);
    for (std::int64_t f = 0; f < m.live_faces; ++f) {
        const std::int64_t b = m.face_b[f];
        const std::uint8_t ka = cell_class[static_cast<std::size_t>(m.face_a[f])];
        out.face_class[static_cast<std::size_t>(f)] = b >= 0 ? std::min(ka, cell_class[static_cast<std::size_t>(b)]) : ka;
    }
    // Each item's level: the finest of the items it reads.
    const auto finest_face_of = [&](const std::vector<std::uint8_t> &face_level) {
        std::vector<std::uint8_t> level(cells, static_cast<std::uint8_t>(top));
        for (std::int64_t c = 0; c < m.cells; ++c)
            for (std::int64_t k = m.cell_face_start[c]; k < m.cell_face_start[c + 1]; ++k) {
                const std::int64_t f = m.cell_faces[k];
                if (f < m.live_faces)
                    level[static_cast<std::size_t>(c)] = std::min(level[static_cast<std::size_t>(c)], face_level[f]);
            }
        return level;
    };
    const std::vector<std::uint8_t> reading = finest_face_of(out.face_class);
    out.finest = reading;
    out.coarsest.assign(cells, 0);
    for (std::int64_t c = 0; c < m.cells; ++c)
        for (std::int64_t k = m.cell_face_start[c]; k < m.cell_face_start[c + 1]; ++k) {
            const std::int64_t f = m.cell_faces[k];
            std::uint8_t &coarsest = out.coarsest[static_cast<std::size_t>(c)];
            if (f < m.live_faces) coarsest = std::max(coarsest, out.face_class[static_cast<std::size_t>(f)]);
        }
    std::vector<std::uint8_t> carrying(faces);
    for (std::int64_t f = 0; f < m.live_faces; ++f) {
        const std::int64_t b = m.face_b[f];
        const std::uint8_t la = reading[static_cast<std::size_t>(m.face_a[f])];
        carrying[static_cast<std::size_t>(f)] = b >= 0 ? std::min(la, reading[static_cast<std::size_t>(b)]) : la;
    }
    const std::vector<std::uint8_t> taking = finest_face_of(carrying);
    out.taking_level = taking;
    sort_by_level(out.face_class, top, out.firing_faces, out.firing_end);
    sort_by_level(reading, top, out.reading_cells, out.reading_end);
    sort_by_level(carrying, top, out.carrying_faces, out.carrying_end);
    sort_by_level(taking, top, out.taking_cells, out.taking_end);
    return out;
}

}  // namespace dpsm
