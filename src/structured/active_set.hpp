// The active set of a 2D grid: which tiles of 64 x 64 cells can move. A
// tile's hot box holds the cells that carried sand in its last sweep (or that
// the host changed since); its driven box, during a step, the cells whose
// faces a source may make steep within the step (structured/tiled_sweep.hpp: a source
// elsewhere is applied in closed form). A sweep visits a tile when a hot or
// driven box lies near enough to reach it within the sweep. Everything else
// is exactly at rest under the dead-zone flux law, so skipping it changes no
// result.
#pragma once

#include <climits>
#include <cstdint>
#include <vector>

namespace dpsm {

class Grid;

// A box of cells [i0, i1) x [j0, j1) in grid coordinates; empty when i0 >= i1.
struct CellBox {
    std::int64_t i0 = INT64_MAX, i1 = INT64_MIN, j0 = INT64_MAX, j1 = INT64_MIN;

    bool empty() const { return i0 >= i1 || j0 >= j1; }
    void add(std::int64_t a0, std::int64_t a1, std::int64_t b0, std::int64_t b1) {
        if (a0 >= a1 || b0 >= b1) return;
        i0 = a0 < i0 ? a0 : i0;
        i1 = a1 > i1 ? a1 : i1;
        j0 = b0 < j0 ? b0 : j0;
        j1 = b1 > j1 ? b1 : j1;
    }
    void add(const CellBox &o) { add(o.i0, o.i1, o.j0, o.j1); }
    // This box grown by d cells and clipped to the other; empty if they do not meet.
    CellBox grown_within(std::int64_t d, const CellBox &o) const {
        CellBox b;
        if (empty() || o.empty()) return b;
        b.add(i0 - d > o.i0 ? i0 - d : o.i0, i1 + d < o.i1 ? i1 + d : o.i1, j0 - d > o.j0 ? j0 - d : o.j0,
              j1 + d < o.j1 ? j1 + d : o.j1);
        return b;
    }
    CellBox grown(std::int64_t d) const {
        CellBox b;
        if (!empty()) b.add(i0 - d, i1 + d, j0 - d, j1 + d);
        return b;
    }
    bool operator==(const CellBox &o) const {
        return (empty() && o.empty()) || (i0 == o.i0 && i1 == o.i1 && j0 == o.j0 && j1 == o.j1);
    }
    // Whether this box grown by d cells meets the other.
    bool reaches(const CellBox &o, std::int64_t d) const {
        return !empty() && !o.empty() && i0 - d < o.i1 && o.i0 < i1 + d && j0 - d < o.j1 && o.j0 < j1 + d;
    }
};

class ActiveSet {
public:
    static constexpr int kTile = 64;       // cells along each side of a tile
    static constexpr int kMaxLevels = 4;   // sub-steps per sweep over a tile

    ActiveSet(std::int64_t nx, std::int64_t ny);

    std::int64_t tiles_x() const { return tiles_x_; }
    std::int64_t tiles_y() const { return tiles_y_; }
    std::int64_t tiles() const { return tiles_x_ * tiles_y_; }
    CellBox tile_cells(std::int64_t t) const;

    // The host changed something everywhere (heights, parameters, masks).
    void mark_all();
    // The host changed the cells of a block: they and their neighbours may move.
    void mark_block(std::int64_t i0, std::int64_t j0, std::int64_t ni, std::int64_t nj);
    // Recomputes which tiles see walls, sinks or the domain's edge, and which a source.
    void refresh_masks(const Grid &grid);
    void refresh_source(const Grid &grid);

    bool may_move() const;  // some tile is hot or driven
    // The tiles a sweep of `levels` sub-steps must visit, in order, and in each
    // the box of its cells that can change (the rest of the tile stays as it is)
    // and the box of the hot boxes and sources (grown by one) that reach it,
    // its seeds: in sub-step s only cells within s - 1 of them can change.
    // visit_all (DPSM_VISIT_ALL_TILES, model/switches.hpp): every tile whole,
    // for tests that show that the active set changes no result.
    void tiles_to_visit(int levels, bool visit_all, std::vector<std::int64_t> &tiles, std::vector<CellBox> &boxes,
                        std::vector<CellBox> &seeds) const;

    CellBox &hot(std::int64_t t) { return hot_[t]; }
    const CellBox &hot(std::int64_t t) const { return hot_[t]; }
    // The driven boxes of a step (set by the stepper at its start); at its
    // end they join the hot boxes, since their last changes may have made
    // faces steep that no later sub-step looked at.
    CellBox &driven(std::int64_t t) { return driven_[t]; }
    const CellBox &driven(std::int64_t t) const { return driven_[t]; }
    bool any_driven() const;
    void drive_every_source();  // every source's cells are driven (sources applied at each sub-step)
    // Lazy sources: drive_sources judged a source by the heights at the
    // start of the step, as if only sources changed them. Where sand has
    // moved since (the hot boxes, here and beyond a distributed block's
    // edge), that judgement no longer holds: the source cells there and
    // their neighbours are driven for the rest of the step. Returns whether
    // any cell is driven this way.
    bool drive_sources_near_moves();
    void end_of_step();         // the driven boxes join the hot ones and are cleared
    void forget_driven();       // a refused step: the driven boxes are cleared
    // This tile's cells with a source in it; and whether a source of a
    // distributed grid's neighbour lies within its reach.
    const CellBox &sources(std::int64_t t) const { return source_[t]; }
    bool has_remote_source(std::int64_t t) const { return !remote_source_.empty() && remote_source_[t] != 0; }
    // The box of this grid's cells with a source in tile t and the tiles
    // around it: all a sweep of t reads (the sources of a distributed grid's
    // neighbours come with its halo).
    CellBox sources_near(std::int64_t t) const;
    bool masked(std::int64_t t) const { return masked_[t] != 0; }
    bool has_source(std::int64_t t) const {
        return has_source_[t] != 0 || (!remote_source_.empty() && remote_source_[t] != 0);
    }

    // A distributed grid's view of its neighbours (structured/halo.hpp): boxes of
    // cells beyond this block, in its coordinates, that may move in the coming
    // sweep (their hot and driven boxes) or hold a source. Tiles the first
    // reach are visited, and tiles the second reach see those sources, as if
    // the neighbours' tiles were this grid's. Replaces the previous view; a
    // serial grid never sets one.
    void set_remote_activity(const std::vector<CellBox> &hot, const std::vector<CellBox> &sources);

private:
    // Calls visit(t) for every tile whose sweep reads cell (i, j).
    template <class Visit>
    void for_tiles_reaching(std::int64_t i, std::int64_t j, Visit &&visit) const;

    std::int64_t nx_, ny_, tiles_x_, tiles_y_;
    std::vector<CellBox> hot_;
    std::vector<CellBox> driven_;          // per tile, during a step: see driven()
    std::vector<CellBox> source_;          // cells with a source, per tile
    std::vector<std::uint8_t> masked_;     // walls or sinks within a tile's reach (the sweep adds the edge)
    std::vector<std::uint8_t> has_source_; // a source within a tile's reach
    std::vector<CellBox> remote_;             // per tile: remote boxes that may reach it (empty: serial)
    std::vector<std::uint8_t> remote_source_; // per tile: a remote source within reach (empty: serial)
    mutable std::vector<std::uint8_t> near_activity_;  // tiles_to_visit's scratch: next to a tile with activity
};

}  // namespace dpsm
