#include "structured/active_set.hpp"

#include <algorithm>

#include "model/grid.hpp"

namespace dpsm {

namespace {
// How far a sweep reads beyond its tile: its levels plus one ring of ghosts.
constexpr std::int64_t kReach = ActiveSet::kMaxLevels + 1;
}  // namespace

template <class Visit>
void ActiveSet::for_tiles_reaching(std::int64_t i, std::int64_t j, Visit &&visit) const {
    const std::int64_t t0 = std::max<std::int64_t>(0, (i - kReach) / kTile);
    const std::int64_t t1 = std::min(tiles_x_ - 1, (i + kReach) / kTile);
    const std::int64_t s0 = std::max<std::int64_t>(0, (j - kReach) / kTile);
    const std::int64_t s1 = std::min(tiles_y_ - 1, (j + kReach) / kTile);
    for (std::int64_t tj = s0; tj <= s1; ++tj)
        for (std::int64_t ti = t0; ti <= t1; ++ti) visit(ti + tiles_x_ * tj);
}

ActiveSet::ActiveSet(std::int64_t nx, std::int64_t ny)
    : nx_(nx),
      ny_(ny),
      tiles_x_((nx + kTile - 1) / kTile),
      tiles_y_((ny + kTile - 1) / kTile),
      hot_(static_cast<std::size_t>(tiles_x_ * tiles_y_)),
      driven_(hot_.size()),
      source_(hot_.size()),
      masked_(hot_.size(), 0),
      has_source_(hot_.size(), 0) {
    mark_all();
}

CellBox ActiveSet::tile_cells(std::int64_t t) const {
    const std::int64_t ti = t % tiles_x_, tj = t / tiles_x_;
    CellBox box;
    box.add(ti * kTile, std::min(nx_, (ti + 1) * kTile), tj * kTile, std::min(ny_, (tj + 1) * kTile));
    return box;
}

void ActiveSet::mark_all() {
    for (std::int64_t t = 0; t < tiles(); ++t) hot_[t] = tile_cells(t);
}

void ActiveSet::mark_block(std::int64_t i0, std::int64_t j0, std::int64_t ni, std::int64_t nj) {
    // A changed cell can steepen the faces within one of it: those cells are hot.
    CellBox changed;
    changed.add(i0 - 1, i0 + ni + 1, j0 - 1, j0 + nj + 1);
    const std::int64_t t0 = std::max<std::int64_t>(0, (i0 - 1) / kTile), t1 = std::min(tiles_x_ - 1, (i0 + ni) / kTile);
    const std::int64_t s0 = std::max<std::int64_t>(0, (j0 - 1) / kTile), s1 = std::min(tiles_y_ - 1, (j0 + nj) / kTile);
    for (std::int64_t tj = s0; tj <= s1; ++tj)
        for (std::int64_t ti = t0; ti <= t1; ++ti) {
            const std::int64_t t = ti + tiles_x_ * tj;
            if (changed.reaches(tile_cells(t), 0)) hot_[t].add(changed);
        }
}

void ActiveSet::refresh_masks(const Grid &grid) {
    const std::vector<std::uint8_t> &kind = grid.kinds();
    // The domain's edge is not here: the sweep masks what reads beyond it.
    std::fill(masked_.begin(), masked_.end(), 0);
    for (std::int64_t j = 0; j < ny_; ++j)
        for (std::int64_t i = 0; i < nx_; ++i) {
            if (kind[i + nx_ * j] != kSand) for_tiles_reaching(i, j, [&](std::int64_t t) { masked_[t] = 1; });
        }
}

void ActiveSet::refresh_source(const Grid &grid) {
    std::fill(has_source_.begin(), has_source_.end(), 0);
    std::fill(source_.begin(), source_.end(), CellBox{});
    const std::vector<double> &q = grid.source();
    if (q.empty()) return;
    const std::vector<std::uint8_t> &kind = grid.kinds();
    auto acts = [&](std::int64_t c) { return q[c] != 0.0 && kind[c] == kSand; };
    // Per tile and row, the first and the last cell with a source: a host
    // sets a source every step, often on every cell, so each row's scan stops
    // at its first cell from either end.
    for (std::int64_t t = 0; t < tiles(); ++t) {
        const CellBox cells = tile_cells(t);
        for (std::int64_t j = cells.j0; j < cells.j1; ++j) {
            std::int64_t first = cells.i0;
            while (first < cells.i1 && !acts(first + nx_ * j)) ++first;
            if (first == cells.i1) continue;
            std::int64_t last = cells.i1 - 1;
            while (!acts(last + nx_ * j)) --last;
            source_[t].add(first, last + 1, j, j + 1);
        }
    }
    // A tile sees a source when its sweep reads a cell with one.
    for (std::int64_t t = 0; t < tiles(); ++t) {
        if (source_[t].empty()) continue;
        const std::int64_t ti = t % tiles_x_, tj = t / tiles_x_;
        for (std::int64_t uj = std::max<std::int64_t>(0, tj - 1); uj <= std::min(tiles_y_ - 1, tj + 1); ++uj)
            for (std::int64_t ui = std::max<std::int64_t>(0, ti - 1); ui <= std::min(tiles_x_ - 1, ti + 1); ++ui) {
                const std::int64_t u = ui + tiles_x_ * uj;
                if (source_[t].reaches(tile_cells(u), kReach)) has_source_[u] = 1;
            }
    }
}

void ActiveSet::set_remote_activity(const std::vector<CellBox> &hot, const std::vector<CellBox> &sources) {
    remote_.assign(hot_.size(), CellBox{});
    remote_source_.assign(hot_.size(), 0);
    // Each box joins the union of every tile it can reach within a sweep; the
    // union may be larger than the boxes, which only visits more cells at rest.
    auto spread = [&](const CellBox &box, bool source) {
        if (box.empty()) return;
        const std::int64_t t0 = std::max<std::int64_t>(0, (box.i0 - kReach) / kTile);
        const std::int64_t t1 = std::min(tiles_x_ - 1, std::max<std::int64_t>(0, (box.i1 - 1 + kReach) / kTile));
        const std::int64_t s0 = std::max<std::int64_t>(0, (box.j0 - kReach) / kTile);
        const std::int64_t s1 = std::min(tiles_y_ - 1, std::max<std::int64_t>(0, (box.j1 - 1 + kReach) / kTile));
        for (std::int64_t tj = s0; tj <= s1; ++tj)
            for (std::int64_t ti = t0; ti <= t1; ++ti) {
                const std::int64_t t = ti + tiles_x_ * tj;
                if (!box.reaches(tile_cells(t), kReach)) continue;
                if (source)
                    remote_source_[t] = 1;
                else
                    remote_[t].add(box);
            }
    };
    for (const CellBox &box : hot) spread(box, false);
    // The neighbours' sources only say which tiles must see them: their
    // driven cells come with the hot boxes.
    for (const CellBox &box : sources) spread(box.grown(1), true);
}

CellBox ActiveSet::sources_near(std::int64_t t) const {
    const std::int64_t ti = t % tiles_x_, tj = t / tiles_x_;
    CellBox near;
    for (std::int64_t uj = std::max<std::int64_t>(0, tj - 1); uj <= std::min(tiles_y_ - 1, tj + 1); ++uj)
        for (std::int64_t ui = std::max<std::int64_t>(0, ti - 1); ui <= std::min(tiles_x_ - 1, ti + 1); ++ui)
            near.add(source_[ui + tiles_x_ * uj]);
    return near;
}

bool ActiveSet::may_move() const {
    for (std::int64_t t = 0; t < tiles(); ++t)
        if (!hot_[t].empty() || !driven_[t].empty()) return true;
    return false;
}

bool ActiveSet::any_driven() const {
    for (const CellBox &box : driven_)
        if (!box.empty()) return true;
    return false;
}

void ActiveSet::drive_every_source() { driven_ = source_; }

bool ActiveSet::drive_sources_near_moves() {
    bool any = false;
    for (std::int64_t t = 0; t < tiles(); ++t) {
        if (!has_source(t)) continue;
        const CellBox tile = tile_cells(t);
        const CellBox region = has_remote_source(t) ? tile : sources_near(t).grown_within(1, tile);
        if (region.empty()) continue;
        auto drive_near = [&](const CellBox &moved) {
            const CellBox near = moved.grown(1).grown_within(0, region);
            if (near.empty()) return;
            driven_[t].add(near);
            any = true;
        };
        const std::int64_t ti = t % tiles_x_, tj = t / tiles_x_;
        for (std::int64_t uj = std::max<std::int64_t>(0, tj - 1); uj <= std::min(tiles_y_ - 1, tj + 1); ++uj)
            for (std::int64_t ui = std::max<std::int64_t>(0, ti - 1); ui <= std::min(tiles_x_ - 1, ti + 1); ++ui)
                drive_near(hot_[ui + tiles_x_ * uj]);
        if (!remote_.empty()) drive_near(remote_[t]);
    }
    return any;
}

void ActiveSet::forget_driven() { std::fill(driven_.begin(), driven_.end(), CellBox{}); }

void ActiveSet::end_of_step() {
    for (std::size_t t = 0; t < driven_.size(); ++t) {
        if (driven_[t].empty()) continue;
        hot_[t].add(driven_[t].grown(1));
        driven_[t] = CellBox{};
    }
}

void ActiveSet::tiles_to_visit(int levels, bool visit_all, std::vector<std::int64_t> &tiles, std::vector<CellBox> &boxes,
                               std::vector<CellBox> &seeds) const {
    // A face carries sand in a sub-step only if it did in the one before or a
    // cell within one of it changed: the cells touching moving faces spread by
    // at most one cell a sub-step. A hot box holds the cells that may touch a
    // moving face in a sweep's first sub-step, so in its sub-step s such cells
    // lie within s - 1 of it: a hot box reaches levels - 1 cells. A driven
    // box holds cells whose faces a source may make steep in any sub-step:
    // grown by one it is a hot box.
    const std::int64_t reach = levels - 1;
    tiles.clear();
    boxes.clear();
    seeds.clear();
    // Only the tiles next to one with activity can be reached: mark those
    // first, so that a grid mostly at rest costs a byte per tile, not the
    // look at nine neighbours' boxes.
    near_activity_.assign(hot_.size(), visit_all ? 1 : 0);
    for (std::int64_t tj = 0; tj < tiles_y_ && !visit_all; ++tj)
        for (std::int64_t ti = 0; ti < tiles_x_; ++ti) {
            const std::int64_t t = ti + tiles_x_ * tj;
            if (!remote_.empty() && !remote_[t].empty()) near_activity_[t] = 1;
            if (hot_[t].empty() && driven_[t].empty()) continue;
            for (std::int64_t uj = std::max<std::int64_t>(0, tj - 1); uj <= std::min(tiles_y_ - 1, tj + 1); ++uj)
                for (std::int64_t ui = std::max<std::int64_t>(0, ti - 1); ui <= std::min(tiles_x_ - 1, ti + 1); ++ui)
                    near_activity_[ui + tiles_x_ * uj] = 1;
        }
    for (std::int64_t tj = 0; tj < tiles_y_; ++tj)
        for (std::int64_t ti = 0; ti < tiles_x_; ++ti) {
            const std::int64_t t = ti + tiles_x_ * tj;
            if (!near_activity_[t]) continue;
            const CellBox cells = tile_cells(t);
            // Seeds farther than the sweep's reach from the tile do not matter to it.
            const CellBox near = cells.grown(2 * reach);
            CellBox reached, seed;
            for (std::int64_t dj = -1; dj <= 1; ++dj)
                for (std::int64_t di = -1; di <= 1; ++di) {
                    const std::int64_t ui = ti + di, uj = tj + dj;
                    if (ui < 0 || uj < 0 || ui >= tiles_x_ || uj >= tiles_y_) continue;
                    const std::int64_t u = ui + tiles_x_ * uj;
                    for (const CellBox &from : {hot_[u], driven_[u].grown(1)}) {
                        const CellBox part = from.grown_within(reach, cells);
                        if (part.empty()) continue;
                        reached.add(part);
                        seed.add(from.grown_within(0, near));
                    }
                }
            // The neighbours' activity on a block of a distributed grid (its
            // sources already grown by one): as this block's own.
            if (!remote_.empty()) {
                const CellBox part = remote_[t].grown_within(reach, cells);
                if (!part.empty()) {
                    reached.add(part);
                    seed.add(remote_[t].grown_within(0, near));
                }
            }
            if (visit_all) {  // every cell of the tile may change from the first sub-step
                reached = cells;
                seed = cells.grown(levels);
            }
            if (reached.empty()) continue;
            tiles.push_back(t);
            boxes.push_back(reached);
            seeds.push_back(seed);
        }
}

}  // namespace dpsm
