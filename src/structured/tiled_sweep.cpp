#include "structured/tiled_sweep.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "structured/active_set.hpp"
#include "model/threads.hpp"
#include "mpi/decomposition.hpp"
#include "model/grid.hpp"
#include "model/ledger.hpp"
#include "structured/simd.hpp"

namespace dpsm {

namespace {

constexpr int kBufferSide = ActiveSet::kTile + 2 * (ActiveSet::kMaxLevels + 1);
constexpr std::int64_t kCellsForThreads = 8 * ActiveSet::kTile * ActiveSet::kTile;
// The longest grid row a tile kernel reads or writes in place: its indices
// (rows of the buffer times the row length) stay within an int.
constexpr std::int64_t kMaxDirectRowLength = std::numeric_limits<int>::max() / (2 * kBufferSide);

// Residuals are kept in float in the grid and in double in a tile's buffer.
// These loops run once per row of every tile visit; where the CPU has AVX-512
// a copy built for it converts 8 cells at a time instead of 2. (Chosen by a
// test of the CPU, not by an ifunc: ifunc resolvers run before a sanitizer's
// runtime and crash it.) A conversion rounds the same way on every CPU.
template <class From, class To>
inline void convert_row(const From *from, To *to, int count) {
    for (int c = 0; c < count; ++c) to[c] = static_cast<To>(from[c]);
}
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
__attribute__((target("avx512f"))) void widen_avx512(const float *from, double *to, int count) {
    convert_row(from, to, count);
}
__attribute__((target("avx512f"))) void narrow_avx512(const double *from, float *to, int count) {
    convert_row(from, to, count);
}
bool rows_in_avx512() {
    static const bool yes = [] {
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx512f") != 0;
    }();
    return yes;
}
void widen(const float *from, double *to, int count) {
    rows_in_avx512() ? widen_avx512(from, to, count) : convert_row(from, to, count);
}
void narrow(const double *from, float *to, int count) {
    rows_in_avx512() ? narrow_avx512(from, to, count) : convert_row(from, to, count);
}
#else
void widen(const float *from, double *to, int count) { convert_row(from, to, count); }
void narrow(const double *from, float *to, int count) { convert_row(from, to, count); }
#endif

// Lazy sources at the end of a step: a row of cells gets its source since
// each was last current (source_lag) as a TwoSum with its residual, as the
// kernel does; sand cells with a source only. Branch-free, so that it runs
// in vectors; a copy for AVX-512 as above (the file is built without
// contracted multiply-adds, so both round alike). Returns the cells changed.
struct SourceRow {
    double substeps, dt, base;
};
// Clocks: whether a cell may have become current within the step (its
// tile was visited); else every cell waited since the step began.
template <bool Clocks>
inline int catch_up_cells(const SourceRow &s, int count, const double *q, const std::uint8_t *kind,
                          const double *clock, double *__restrict h, float *__restrict residual) {
    int changed = 0;
    for (int c = 0; c < count; ++c) {
        // Everything computed for every cell, and kept where it applies.
        double lagging = s.substeps;
        if constexpr (Clocks) lagging -= (clock[c] > s.base ? clock[c] : s.base) - s.base;
        const double increment = source_lag(q[c], s.dt, lagging);
        const double b = increment + static_cast<double>(residual[c]);
        const double sum = h[c] + b;
        const double b_virtual = sum - h[c];
        const double error = (h[c] - (sum - b_virtual)) + (b - b_virtual);
        const bool moves = (kind[c] == kSand) & (increment != 0.0);
        h[c] = moves ? sum : h[c];
        residual[c] = moves ? static_cast<float>(error) : residual[c];
        changed += static_cast<int>(moves);
    }
    return changed;
}
template <bool Clocks>
int catch_up_plain(const SourceRow &s, int count, const double *q, const std::uint8_t *kind, const double *clock,
                   double *h, float *residual) {
    return catch_up_cells<Clocks>(s, count, q, kind, clock, h, residual);
}
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
template <bool Clocks>
__attribute__((target("avx512f"))) int catch_up_avx512(const SourceRow &s, int count, const double *q,
                                                        const std::uint8_t *kind, const double *clock, double *h,
                                                        float *residual) {
    return catch_up_cells<Clocks>(s, count, q, kind, clock, h, residual);
}
#endif
// clock: null where no cell of the row can have become current in the step.
int catch_up_row(const SourceRow &s, int count, const double *q, const std::uint8_t *kind, const double *clock,
                 double *h, float *residual) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    if (rows_in_avx512())
        return clock ? catch_up_avx512<true>(s, count, q, kind, clock, h, residual)
                     : catch_up_avx512<false>(s, count, q, kind, clock, h, residual);
#endif
    return clock ? catch_up_plain<true>(s, count, q, kind, clock, h, residual)
                 : catch_up_plain<false>(s, count, q, kind, clock, h, residual);
}

// The kind of a ghost cell (i, j) beyond a domain of nx x ny cells: the
// outside of an open side (a sink held at the side's level), a wall beyond a
// wall side; a corner is open only if both sides are.
std::uint8_t ghost_kind(const Grid &grid, std::int64_t i, std::int64_t j, std::int64_t nx, std::int64_t ny) {
    bool open = true;
    if (i < 0) open = open && grid.side_open(kXMin);
    if (i >= nx) open = open && grid.side_open(kXMax);
    if (j < 0) open = open && grid.side_open(kYMin);
    if (j >= ny) open = open && grid.side_open(kYMax);
    return open ? kOutside : kWall;
}

// The columns [c0, c1) of a buffer row (of `width` cells from grid column gi0,
// at grid row j) that lie inside the grid: none (c0 = c1 = width) off its rows.
struct RowSpan {
    int c0, c1;
};
RowSpan inside_of_row(const Geometry &geo, std::int64_t gi0, std::int64_t j, int width) {
    if (j < 0 || j >= geo.ny) return {width, width};
    const int c0 = static_cast<int>(std::clamp<std::int64_t>(-gi0, 0, width));
    return {c0, static_cast<int>(std::clamp<std::int64_t>(geo.nx - gi0, c0, width))};
}

// Calls f(c) for the columns of a buffer row of `width` cells outside `span`.
template <class F>
void for_columns_outside(const RowSpan &span, int width, F &&f) {
    for (int c = 0; c < span.c0; ++c) f(c);
    for (int c = span.c1; c < width; ++c) f(c);
}

// Copies a tile and its halo into the buffers, ghosts beyond the edge: the
// heights (and residuals) unless `heights` is false, the kinds of masked
// tiles, the sources of tiles that have them (those in `sources`, the box of
// every nonzero source: the rest are 0 and need no copy from the grid).
void gather(const Grid &grid, TileBuffers &b, std::int64_t gi0, std::int64_t gj0, bool heights, bool masked,
            bool source, const CellBox &sources, bool residuals) {
    const Geometry &geo = grid.geometry();
    const double *h = grid.heights().data();
    const float *res = grid.residuals().data();
    const std::uint8_t *kind = grid.kinds().data();
    const double *q = source ? grid.source().data() : nullptr;
    for (int r = 0; r < b.height; ++r) {
        const std::int64_t j = gj0 + r;
        const std::size_t row = static_cast<std::size_t>(r) * b.width;
        double *hb = b.h[0].data() + row;
        double *rb = b.residual[0].data() + row;
        std::uint8_t *kb = b.kind.data() + row;
        double *qb = b.source.data() + row;
        // The row's cells inside the domain are one span, copied at once (the
        // whole row but at the domain's edge); ghosts lie around it.
        const bool row_in = j >= 0 && j < geo.ny;
        const auto [c_in0, c_in1] = inside_of_row(geo, gi0, j, b.width);
        auto ghosts = [&](int c0, int c1) {
            for (int c = c0; c < c1; ++c) {
                if (heights) {
                    hb[c] = grid.outside_level(gi0 + c, j);
                    rb[c] = 0.0;
                }
                if (masked) kb[c] = ghost_kind(grid, gi0 + c, j, geo.nx, geo.ny);
            }
        };
        // The row's sources: the span within `sources`, zero around it.
        int q0 = b.width, q1 = b.width;
        if (source) {
            if (row_in && j >= sources.j0 && j < sources.j1) {
                q0 = static_cast<int>(std::clamp<std::int64_t>(sources.i0 - gi0, c_in0, c_in1));
                q1 = static_cast<int>(std::clamp<std::int64_t>(sources.i1 - gi0, q0, c_in1));
            }
            std::fill(qb, qb + q0, 0.0);
            std::fill(qb + q1, qb + b.width, 0.0);
        }
        ghosts(0, c_in0);
        // The same span some rows ahead, so that the copies wait on several rows at once.
        const std::int64_t j_ahead = j + kRowsAhead;
        if (c_in0 < c_in1 && r + kRowsAhead < b.height && j_ahead < geo.ny) {
            const std::size_t at = static_cast<std::size_t>(j_ahead * geo.nx + gi0 + c_in0);
            const int count = c_in1 - c_in0;
            if (heights) simd::prefetch<false>(h + at, count);
            if (heights && residuals) simd::prefetch<false>(res + at, count);
            if (masked) simd::prefetch<false>(kind + at, count);
        }
        if (c_in0 < c_in1) {
            const std::size_t at = static_cast<std::size_t>(j * geo.nx + gi0 + c_in0);
            const int count = c_in1 - c_in0;
            if (heights) std::memcpy(hb + c_in0, h + at, sizeof(double) * count);
            if (heights && residuals) widen(res + at, rb + c_in0, count);
            if (masked) std::memcpy(kb + c_in0, kind + at, count);
        }
        if (q0 < q1) {
            // Sources act on sand cells only (every cell of an unmasked tile).
            const std::size_t at = static_cast<std::size_t>(j * geo.nx + gi0 + q0);
            for (int c = 0; c < q1 - q0; ++c) qb[q0 + c] = masked && kind[at + c] != kSand ? 0.0 : q[at + c];
        }
        ghosts(c_in1, b.width);
    }
}

// Copies what kernels with physics read besides heights into the buffer:
// the bed and angles (those the grid has) and, with `moving_flags`, which
// cells are moving (hysteresis); ghost cells are never moving and have no
// bed or angle. On a block of a distributed grid, the cells beyond the block
// that lie in the global domain come from the halo store (mpi/decomposition.hpp).
void gather_physics(const Grid &grid, const HaloStore *halo, TileBuffers &b, std::int64_t gi0, std::int64_t gj0,
                    bool moving_flags) {
    const Geometry &geo = grid.geometry();
    const std::vector<double> &zb = grid.bed(), &tan_theta = grid.tan_field();
    const std::vector<std::uint8_t> &moving = grid.moving();
    const bool bed = !zb.empty(), angles = !tan_theta.empty();
    const bool flags = moving_flags && !moving.empty();
    for (int r = 0; r < b.height; ++r) {
        const std::int64_t j = gj0 + r;
        const std::size_t row = static_cast<std::size_t>(r) * b.width;
        const auto [c_in0, c_in1] = inside_of_row(geo, gi0, j, b.width);
        if (c_in0 < c_in1) {
            const std::size_t at = static_cast<std::size_t>(j * geo.nx + gi0 + c_in0);
            const std::size_t count = static_cast<std::size_t>(c_in1 - c_in0);
            if (bed) std::memcpy(b.bed.data() + row + c_in0, zb.data() + at, sizeof(double) * count);
            if (angles) std::memcpy(b.tan_theta.data() + row + c_in0, tan_theta.data() + at, sizeof(double) * count);
            if (flags) std::memcpy(b.moving[0].data() + row + c_in0, moving.data() + at, count);
        }
        for_columns_outside({c_in0, c_in1}, b.width, [&](int c) {
            const std::int64_t i = gi0 + c;
            const std::size_t at = row + static_cast<std::size_t>(c);
            const bool from_halo = halo && halo->in_domain(i, j);
            const std::size_t k = from_halo ? halo->index(i, j) : 0;
            if (bed) b.bed[at] = from_halo ? halo->bed[k] : 0.0;
            if (angles) b.tan_theta[at] = from_halo ? halo->tan_theta[k] : 0.0;
            if (flags) b.moving[0][at] = from_halo ? halo->moving[k] : 0;
        });
    }
}

// On a block of a distributed grid, replaces what gather() put in the buffer
// for the cells beyond the block: the neighbours' cells come from the halo
// store (mpi/decomposition.hpp), the cells beyond the global domain are ghosts of
// its sides. The block's own cells are left as gather() copied them.
void gather_halo(const Grid &grid, const HaloStore &halo, TileBuffers &b, std::int64_t gi0, std::int64_t gj0,
                 bool masked, bool source) {
    const Geometry &geo = grid.geometry();
    for (int r = 0; r < b.height; ++r) {
        const std::int64_t j = gj0 + r;
        const std::size_t row = static_cast<std::size_t>(r) * b.width;
        // The block's own columns of this row, [own0, own1) in the buffer (none off the block's rows).
        for_columns_outside(inside_of_row(geo, gi0, j, b.width), b.width, [&](int c) {
            const std::int64_t i = gi0 + c;
            const std::size_t at = row + static_cast<std::size_t>(c);
            if (halo.in_domain(i, j)) {
                const std::size_t k = halo.index(i, j);
                b.h[0][at] = halo.heights[k];
                b.residual[0][at] = static_cast<double>(halo.residuals[k]);
                if (masked) b.kind[at] = halo.kinds[k];
                if (source) b.source[at] = halo.kinds[k] == kSand ? halo.sources[k] : 0.0;
            } else {
                b.h[0][at] = halo.outside_level(i + halo.i0, j + halo.j0);
                b.residual[0][at] = 0.0;
                if (masked) b.kind[at] = ghost_kind(grid, i + halo.i0, j + halo.j0, halo.global_nx, halo.global_ny);
                if (source) b.source[at] = 0.0;
            }
        });
    }
}

// Lazy sources: the sub-step of the step after which each buffer cell's
// stored height is current (0 for cells beyond the domain, and for a cell
// last current before the step began).
void gather_since(const Grid &grid, const HaloStore *halo, TileBuffers &b, std::int64_t gi0, std::int64_t gj0) {
    const Geometry &geo = grid.geometry();
    const double *clock = grid.source_clock().data();
    const double base = grid.clock_base();
    for (int r = 0; r < b.height; ++r) {
        const std::int64_t j = gj0 + r;
        double *__restrict since = b.since[0].data() + static_cast<std::size_t>(r) * b.width;
        // The row's cells in the domain are one span; the rest lie beyond it.
        const RowSpan span = inside_of_row(geo, gi0, j, b.width);
        const double *from = clock + (j * geo.nx + gi0);
        if (r + kRowsAhead < b.height && j + kRowsAhead < geo.ny && span.c0 < span.c1)
            simd::prefetch<false>(from + span.c0 + kRowsAhead * geo.nx, span.c1 - span.c0);
        for (int c = span.c0; c < span.c1; ++c) since[c] = (from[c] > base ? from[c] : base) - base;
        for_columns_outside(span, b.width, [&](int c) {
            const std::int64_t i = gi0 + c;
            since[c] = halo && halo->in_domain(i, j) ? halo->since[halo->index(i, j)] : 0.0;
        });
    }
}

// Lazy sources, before a level that computes `region` at sub-step
// `substep` of the step: every cell it reads gets its height now (what its
// faces see) and what its source added since it was current (which the
// kernel adds to a cell whose faces carry sand). One formula for every cell
// and every visit, so that a cell's height now is the same bits whichever
// tile reads it; catch_up_sources adds the same lag.
void lazy_level(TileBuffers &b, int in, const TileRect &region, double substep, double dt) {
    const double *h = b.h[in].data(), *since = b.since[in].data(), *q = b.source.data();
    double *__restrict lag = b.lag.data(), *__restrict true_h = b.true_h.data();
    const int c_begin = std::max(0, region.c0 - 1), c_end = std::min(b.width, region.c1 + 1);
    for (int r = std::max(0, region.r0 - 1); r < std::min(b.height, region.r1 + 1); ++r)
        for (int c = r * b.width + c_begin; c < r * b.width + c_end; ++c) {
            lag[c] = source_lag(q[c], dt, substep - since[c]);
            true_h[c] = h[c] + lag[c];
        }
}

// After a visit that recorded its faces (TileLevelParams::record): adds what
// the faces of tile t carried to the grid's face fluxes, as volumes. A tile
// owns the low x and y faces of its cells, and the high faces of the
// domain's last column and row; the first visit of a step clears them, so
// that a tile no step visits keeps no stale figure (FaceFluxes). Only faces
// that touch the visit's cells, or the ring around them, can have carried sand.
void record_face_fluxes(Grid &grid, std::int64_t t, const CellBox &cells, const TileBuffers &b, std::int64_t gi0,
                        std::int64_t gj0) {
    const Geometry &geo = grid.geometry();
    FaceFluxes &fluxes = grid.face_fluxes();
    const CellBox tile = grid.active_set().tile_cells(t);
    const std::int64_t nx = geo.nx, ny = geo.ny;
    // x faces: columns [x0, x1) of rows [tile.j0, tile.j1); y faces: columns
    // [tile.i0, tile.i1) of rows [y0, y1).
    const std::int64_t x0 = tile.i0, x1 = tile.i1 + (tile.i1 == nx ? 1 : 0);
    const std::int64_t y0 = tile.j0, y1 = tile.j1 + (tile.j1 == ny ? 1 : 0);
    if (fluxes.tile_step[static_cast<std::size_t>(t)] != fluxes.step) {
        fluxes.tile_step[static_cast<std::size_t>(t)] = fluxes.step;
        for (std::int64_t j = tile.j0; j < tile.j1; ++j)
            std::fill_n(fluxes.x.begin() + (x0 + (nx + 1) * j), x1 - x0, 0.0);
        for (std::int64_t j = y0; j < y1; ++j) std::fill_n(fluxes.y.begin() + (tile.i0 + nx * j), tile.i1 - tile.i0, 0.0);
    }
    const CellBox near = cells.grown(1);
    const double area = geo.dx * geo.dy;
    auto buffer = [&](const std::vector<double> &faces, std::int64_t i, std::int64_t j) {
        return faces[static_cast<std::size_t>((j - gj0) * b.width + (i - gi0))];
    };
    for (std::int64_t j = std::max(tile.j0, near.j0); j < std::min(tile.j1, near.j1); ++j)
        for (std::int64_t i = std::max(x0, near.i0); i < std::min(x1, near.i1); ++i)
            fluxes.x[static_cast<std::size_t>(i + (nx + 1) * j)] += buffer(b.face_x, i, j) * area;
    for (std::int64_t j = std::max(y0, near.j0); j < std::min(y1, near.j1); ++j)
        for (std::int64_t i = std::max(tile.i0, near.i0); i < std::min(tile.i1, near.i1); ++i)
            fluxes.y[static_cast<std::size_t>(i + nx * j)] += buffer(b.face_y, i, j) * area;
}

// Calls part(b) for the boxes that together make the cells of `from` outside `cut`.
template <class Part>
void for_parts_outside(const CellBox &from, const CellBox &cut, Part &&part) {
    if (from.empty()) return;
    auto box = [](std::int64_t i0, std::int64_t i1, std::int64_t j0, std::int64_t j1) {
        CellBox b;
        b.add(i0, i1, j0, j1);
        return b;
    };
    if (cut.empty()) {
        part(from);
        return;
    }
    const std::int64_t j_lo = std::clamp(cut.j0, from.j0, from.j1), j_hi = std::clamp(cut.j1, j_lo, from.j1);
    if (from.j0 < j_lo) part(box(from.i0, from.i1, from.j0, j_lo));
    if (j_hi < from.j1) part(box(from.i0, from.i1, j_hi, from.j1));
    if (j_lo < j_hi) {
        if (from.i0 < cut.i0) part(box(from.i0, std::min(cut.i0, from.i1), j_lo, j_hi));
        if (cut.i1 < from.i1) part(box(std::max(cut.i1, from.i0), from.i1, j_lo, j_hi));
    }
}

// Copies the grid's cells of a box into the scratch.
void refresh_scratch(const Grid &grid, TiledWorkspace &ws, const CellBox &box, bool hysteresis, bool clocks) {
    const std::int64_t nx = grid.geometry().nx;
    for (std::int64_t j = box.j0; j < box.j1; ++j) {
        const std::size_t at = static_cast<std::size_t>(j * nx + box.i0);
        const std::size_t count = static_cast<std::size_t>(box.i1 - box.i0);
        std::memcpy(ws.heights.data() + at, grid.heights().data() + at, sizeof(double) * count);
        std::memcpy(ws.residuals.data() + at, grid.residuals().data() + at, sizeof(float) * count);
        if (hysteresis) std::memcpy(ws.moving.data() + at, grid.moving().data() + at, count);
        if (clocks) std::memcpy(ws.clock.data() + at, grid.source_clock().data() + at, sizeof(double) * count);
    }
}

}  // namespace

void tiled_workspace_changed(TiledWorkspace &ws, const ActiveSet &active, const CellBox &box) {
    if (ws.all_stale || box.empty()) return;
    // Only the tiles the box overlaps: a host's or the relaxation's small
    // edit on a large grid costs its own tiles.
    const std::int64_t side = ActiveSet::kTile;
    const std::int64_t ti0 = std::max<std::int64_t>(0, box.i0 / side);
    const std::int64_t ti1 = std::min(active.tiles_x() - 1, (box.i1 - 1) / side);
    const std::int64_t tj0 = std::max<std::int64_t>(0, box.j0 / side);
    const std::int64_t tj1 = std::min(active.tiles_y() - 1, (box.j1 - 1) / side);
    for (std::int64_t tj = tj0; tj <= tj1; ++tj)
        for (std::int64_t ti = ti0; ti <= ti1; ++ti) {
            const std::int64_t t = ti + active.tiles_x() * tj;
            const CellBox part = box.grown_within(0, active.tile_cells(t));
            if (part.empty()) continue;
            if (ws.stale[static_cast<std::size_t>(t)].empty()) ws.stale_tiles.push_back(t);
            ws.stale[static_cast<std::size_t>(t)].add(part);
        }
}

void prepare_tiled_sweep(Grid &grid, int threads) {
    TiledWorkspace &ws = grid.tiled_workspace();
    const std::size_t cells = static_cast<std::size_t>(grid.geometry().cells());
    if (ws.heights.size() != cells) {
        ws.heights.assign(cells, 0.0);
        ws.residuals.assign(cells, 0.0f);
        ws.all_stale = true;
    }
    const std::size_t want = static_cast<std::size_t>(threads);
    while (ws.buffers.size() < want) {
        ws.buffers.emplace_back();
        ws.buffers.back().resize(kBufferSide, kBufferSide);
    }
    if (grid.uses_physics())
        for (TileBuffers &b : ws.buffers) b.resize_physics();
    if (grid.records_face_fluxes())
        for (TileBuffers &b : ws.buffers) {
            b.face_x.resize(b.h[0].size());
            b.face_y.resize(b.h[0].size());
        }
    if (grid.hysteresis() && ws.moving.size() != cells) {
        ws.moving.assign(cells, 0);
        ws.all_stale = true;
    }
    if (grid.source_clock().size() == cells && ws.clock.size() != cells) {
        ws.clock.assign(cells, 0.0);
        ws.all_stale = true;
    }
    const std::size_t tiles = static_cast<std::size_t>(grid.active_set().tiles());
    ws.stale.resize(tiles);
    ws.written.resize(tiles);
    ws.visited_in_step.resize(tiles, 0);
    ws.stale_tiles.reserve(tiles);
    ws.visit.reserve(tiles);
    ws.boxes.reserve(tiles);
    ws.seeds.reserve(tiles);
    ws.stats.reserve(tiles * ActiveSet::kMaxLevels);
    ws.origin.reserve(2 * tiles);
}

std::int64_t tiled_sweep(Grid &grid, int levels, double dt, std::vector<SubstepSummary> &summaries, bool find_excess,
                         bool residuals, double first_substep) {
    const Geometry &geo = grid.geometry();
    ActiveSet &active = grid.active_set();
    TiledWorkspace &ws = grid.tiled_workspace();
    Decomposition *decomposition = grid.decomposition();
    if (decomposition) decomposition->before_sweep(grid);  // the neighbours' cells and activity
    const HaloStore *halo_store = decomposition ? &decomposition->halo() : nullptr;
    active.tiles_to_visit(levels, ws.visit, ws.boxes, ws.seeds);
    const std::int64_t visits = static_cast<std::int64_t>(ws.visit.size());
    ws.stats.assign(static_cast<std::size_t>(visits) * levels, TileLevelStats{});
    ws.origin.assign(static_cast<std::size_t>(2 * visits), 0);

    TileLevelParams params{grid.mobility(), grid.tan_repose(), geo.dx, geo.dy, 1.0 / geo.dx, 1.0 / geo.dy,
                           0.5 / geo.dx,    0.5 / geo.dy,      dt,     geo.dy, geo.dx};
    const bool physics = grid.uses_physics(), hysteresis = grid.hysteresis();
    // Source cells' clocks move with their heights (lazy sources).
    const bool clocks = !physics && grid.source_clock().size() == static_cast<std::size_t>(geo.cells());
    const double clock_base = grid.clock_base();
    // DPSM_SCALAR_PHYSICS=1 steps a grid with physics by the scalar reference
    // kernel (structured/tile_kernel_physics.cpp), in the buffer, on every tile; read at
    // every sweep, so that a test can compare the two within one process.
    const bool scalar_physics = physics && environment_flag("DPSM_SCALAR_PHYSICS");
    residuals = residuals || physics;  // kernels with physics always carry them
    params.residuals = residuals;
    params.cell_area = geo.dx * geo.dy;
    params.rest_factor = 1.0 + grid.rest_tolerance();
    params.record = grid.records_face_fluxes();
    const bool outside_open = grid.any_side_open();
    if (physics) {
        params.flux_exponent = grid.flux_exponent();
        params.tan_static = grid.tan_static();
        params.hysteresis = hysteresis;
        params.bed = !grid.bed().empty();
        params.angle_field = !grid.tan_field().empty();
        params.bed_film = bed_film(grid);
    }
    const PhysicsKind physics_kernel = physics_kind(params, physics);
    const bool isotropic = grid.scheme() == kIsotropic;
    // DPSM_COPY_TILES=1 copies every tile into a buffer and back (no tile is
    // read or written in place), for tests that show it changes no result.
    const bool in_place = !environment_flag("DPSM_COPY_TILES");
    const int threads = grid.step_threads();
    std::int64_t visited_cells = 0;
    for (const CellBox &cells : ws.boxes) visited_cells += (cells.i1 - cells.i0) * (cells.j1 - cells.j0);
    // Threads pay off only with enough work between their barriers; below this
    // a sweep runs on the calling thread (results are the same either way).
    const bool parallel = threads > 1 && visits > 1 && visited_cells >= kCellsForThreads;

    auto visit_tile = [&](std::int64_t k, TileBuffers &b) {
        const std::int64_t t = ws.visit[k];
        const CellBox &cells = ws.boxes[k];
        const bool source = active.has_source(t);
        const bool lazy = source && !physics;  // the physics kernel applies sources at every sub-step
        // Level s must be right on the cells that later levels read (within
        // levels - s of the box) but can change only those within s - 1 of the
        // seeds: it computes where both hold. What the levels read, one cell
        // around that, is all the buffer holds.
        CellBox level_cells[ActiveSet::kMaxLevels], read;
        bool every_cell = true;  // each level computes all that later ones read
        for (int s = 1; s <= levels; ++s) {
            const CellBox needed = cells.grown(levels - s);
            level_cells[s - 1] = ws.seeds[k].grown_within(s - 1, needed);
            every_cell = every_cell && level_cells[s - 1] == needed;
            read.add(level_cells[s - 1].grown(1));
        }
        const std::int64_t gi0 = read.i0, gj0 = read.j0;
        b.width = static_cast<int>(read.i1 - read.i0);
        b.height = static_cast<int>(read.j1 - read.j0);
        // Ghost cells beyond the edge are sinks or walls: only a box that reads
        // them needs the kernel that looks at cell kinds, not its whole tile.
        // (Both kernels round alike: src/CMakeLists.txt.)
        const bool inside = gi0 >= 0 && gj0 >= 0 && gi0 + b.width <= geo.nx && gj0 + b.height <= geo.ny;
        // A visit that records its faces takes the kernel that looks at cell
        // kinds: only that kernel records, so the others carry no branch for it.
        const bool record = params.record;
        const bool masked = active.masked(t) || !inside || record;
        if (record) {
            const std::size_t count = static_cast<std::size_t>(b.width) * b.height;
            std::fill_n(b.face_x.begin(), count, 0.0);
            std::fill_n(b.face_y.begin(), count, 0.0);
        }
        // Copies cost about a third of a fully active sweep, so where it can a
        // visit works in place. Its last level computes exactly its cells and
        // writes them straight into the scratch. Its first level reads
        // straight from the grid if every level computes all that the next
        // one reads (else later levels would need cells the first one leaves
        // alone) and the visit needs no ghosts; its whole-vector loads run up
        // to a vector past the read box, still within the grid's arrays unless
        // the box ends at the grid's last row and column. The kernel indexes
        // a row of the grid by an int. A visit that records its faces works
        // in the buffer alone: the kernel indexes the faces as it indexes what
        // it reads, and they are kept in the buffer's layout.
        constexpr int kVectorSlack = 8;
        const bool out_in_place = in_place && !record && !scalar_physics && !lazy && residuals &&
                                  geo.nx <= kMaxDirectRowLength && level_cells[levels - 1] == cells;
        const bool in_in_place = out_in_place && !masked && every_cell &&
                                 (gj0 + b.height < geo.ny || gi0 + b.width + kVectorSlack <= geo.nx);
        // The scalar physics kernel reads cell kinds on every tile.
        const bool kinds = masked || scalar_physics;
        if (!in_in_place || source)
            gather(grid, b, gi0, gj0, !in_in_place, kinds, source, source ? active.sources_near(t) : CellBox{},
                   residuals);
        if (halo_store && !inside) gather_halo(grid, *halo_store, b, gi0, gj0, kinds, source);
        // Bed and angles for the levels that work in the buffer (all but a
        // first one in place), moving flags for a first level there too.
        if (physics) gather_physics(grid, halo_store, b, gi0, gj0, hysteresis && !in_in_place);
        if (lazy) gather_since(grid, halo_store, b, gi0, gj0);
        if (!every_cell) {
            // A cell a level leaves alone keeps its gathered value, which the
            // next level then reads from the other slot.
            const std::size_t count = static_cast<std::size_t>(b.width) * b.height;
            std::memcpy(b.h[1].data(), b.h[0].data(), sizeof(double) * count);
            if (residuals) std::memcpy(b.residual[1].data(), b.residual[0].data(), sizeof(double) * count);
            if (hysteresis) std::memcpy(b.moving[1].data(), b.moving[0].data(), count);
            if (lazy) std::memcpy(b.since[1].data(), b.since[0].data(), sizeof(double) * count);
        }
        auto in_buffer = [&](const CellBox &box) {
            return TileRect{static_cast<int>(box.j0 - gj0), static_cast<int>(box.j1 - gj0),
                            static_cast<int>(box.i0 - gi0), static_cast<int>(box.i1 - gi0)};
        };
        const TileRect tile = in_buffer(cells);
        auto grid_index = [&](std::int64_t r, std::int64_t c) {  // of the buffer's cell (r, c)
            return static_cast<std::size_t>((gj0 + r) * geo.nx + gi0 + c);
        };
        int in = 0;
        for (int s = 1; s <= levels; ++s) {
            TileLevelParams level_params = params;
            level_params.track_excess = find_excess && s == levels;
            level_params.outside = !inside && outside_open;
            TileLevelStats &stats = ws.stats[static_cast<std::size_t>(k) * levels + (s - 1)];
            const TileRect region = in_buffer(level_cells[s - 1]);
            if (scalar_physics) {
                select_physics_tile_kernel(isotropic, source)(b, in, region, tile, level_params, stats);
            } else {
                LevelCells io = buffer_level_cells(b, in);
                if (lazy) {
                    level_params.substep = first_substep + (s - 1);
                    lazy_level(b, in, region, level_params.substep, dt);
                    io.h = b.true_h.data();
                }
                const bool grid_in = in_in_place && s == 1, grid_out = out_in_place && s == levels;
                if (grid_in) {  // from the buffer's (0, 0), inside the grid
                    const std::size_t origin = grid_index(0, 0);
                    io.h = grid.heights().data() + origin;
                    io.residual = nullptr;
                    io.residual_grid = grid.residuals().data() + origin;
                    if (source) io.source = grid.source().data() + origin;  // all sand: unmasked
                    if (!grid.bed().empty()) io.bed = grid.bed().data() + origin;
                    if (!grid.tan_field().empty()) io.tan_theta = grid.tan_field().data() + origin;
                    if (hysteresis) io.moving = grid.moving().data() + origin;
                    io.stride = static_cast<int>(geo.nx);
                }
                if (grid_out) {  // from the first of the visit's cells
                    const std::size_t origin = grid_index(tile.r0, tile.c0);
                    io.h_out = ws.heights.data() + origin;
                    io.residual_out = nullptr;
                    io.residual_grid_out = ws.residuals.data() + origin;
                    if (hysteresis) io.moving_out = ws.moving.data() + origin;
                    io.out_stride = static_cast<int>(geo.nx);
                    io.out_row0 = tile.r0;
                    io.out_col0 = tile.c0;
                }
                select_tile_kernel(masked, isotropic, source, grid_in, grid_out, physics_kernel)(b, io, region, tile,
                                                                                                 level_params, stats);
            }
            in = 1 - in;
        }
        for (int r = tile.r0; r < tile.r1 && !out_in_place; ++r) {
            const std::size_t from = static_cast<std::size_t>(r) * b.width + tile.c0;
            const std::size_t to = grid_index(r, tile.c0);
            const int count = tile.c1 - tile.c0;
            if (r + kRowsAhead < tile.r1) {
                const std::size_t ahead = to + static_cast<std::size_t>(kRowsAhead * geo.nx);
                simd::prefetch<true>(ws.heights.data() + ahead, count);
                simd::prefetch<true>(ws.residuals.data() + ahead, count);
                if (lazy) simd::prefetch<true>(ws.clock.data() + ahead, count);
            }
            std::memcpy(ws.heights.data() + to, b.h[in].data() + from, sizeof(double) * count);
            if (residuals)
                narrow(b.residual[in].data() + from, ws.residuals.data() + to, count);
            else
                std::fill_n(ws.residuals.data() + to, count, 0.0f);
            if (hysteresis) std::memcpy(ws.moving.data() + to, b.moving[in].data() + from, count);
            if (lazy)
                for (int c = 0; c < count; ++c) ws.clock[to + c] = clock_base + b.since[in][from + c];
        }
        if (record) record_face_fluxes(grid, t, cells, b, gi0, gj0);
        ws.origin[2 * k] = gi0;
        ws.origin[2 * k + 1] = gj0;
    };

    // The scratch becomes the grid at the end: where this sweep does not write
    // it, it must hold the grid's cells. It does, but in its stale boxes.
    if (ws.all_stale) {
        ws.heights = grid.heights();
        ws.residuals = grid.residuals();
        if (hysteresis) ws.moving = grid.moving();
        if (clocks) ws.clock = grid.source_clock();
        for (const std::int64_t t : ws.stale_tiles) ws.stale[static_cast<std::size_t>(t)] = CellBox{};
        ws.stale_tiles.clear();
        ws.all_stale = false;
    }
    for (std::int64_t k = 0; k < visits; ++k) ws.written[static_cast<std::size_t>(ws.visit[k])] = ws.boxes[k];
    const std::int64_t stale_count = static_cast<std::int64_t>(ws.stale_tiles.size());
    auto refresh_tile = [&](std::int64_t k) {
        const std::size_t t = static_cast<std::size_t>(ws.stale_tiles[static_cast<std::size_t>(k)]);
        for_parts_outside(ws.stale[t], ws.written[t],
                          [&](const CellBox &part) { refresh_scratch(grid, ws, part, hysteresis, clocks); });
    };

    // Both loops read only the grid and write disjoint cells of the scratch.
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (parallel)
    {
#pragma omp for schedule(dynamic, 4) nowait
        for (std::int64_t k = 0; k < stale_count; ++k) refresh_tile(k);
        TileBuffers &b = ws.buffers[static_cast<std::size_t>(omp_get_thread_num())];
#pragma omp for schedule(dynamic, 1)
        for (std::int64_t k = 0; k < visits; ++k) visit_tile(k, b);
    }
#else
    (void)threads;
    (void)parallel;
    for (std::int64_t k = 0; k < stale_count; ++k) refresh_tile(k);
    for (std::int64_t k = 0; k < visits; ++k) visit_tile(k, ws.buffers[0]);
#endif

    grid.swap_heights(ws.heights, ws.residuals);
    if (hysteresis) grid.moving_for_stepping().swap(ws.moving);
    if (clocks) grid.source_clock_for_stepping().swap(ws.clock);
    // The old grid, now the scratch, differs from the new one where this sweep wrote.
    for (const std::int64_t t : ws.stale_tiles) ws.stale[static_cast<std::size_t>(t)] = CellBox{};
    ws.stale_tiles.clear();
    ws.last_written = CellBox{};
    for (std::int64_t k = 0; k < visits; ++k) {
        const std::size_t t = static_cast<std::size_t>(ws.visit[k]);
        ws.written[t] = CellBox{};
        if (ws.boxes[k].empty()) continue;
        ws.visited_in_step[t] = 1;
        ws.stale[t] = ws.boxes[k];
        ws.last_written.add(ws.boxes[k]);
        ws.stale_tiles.push_back(ws.visit[k]);
    }

    // New hot boxes: the cells touching moving faces in any level, grown by the
    // one cell a last move can make steep. Sums in tile order, whatever the threads.
    summaries.assign(static_cast<std::size_t>(levels), SubstepSummary{});
    for (std::int64_t k = 0; k < visits; ++k) {
        CellBox moved;
        for (int s = 0; s < levels; ++s) {
            const TileLevelStats &st = ws.stats[static_cast<std::size_t>(k) * levels + s];
            SubstepSummary &sum = summaries[static_cast<std::size_t>(s)];
            sum.moved = sum.moved || st.moved;
            sum.outflow_rate += st.outflow_rate;
            for (int side = 0; side < 4; ++side) sum.side_outflow_rate[side] += st.side_outflow_rate[side];
            sum.unmet_mass += st.unmet_mass;
            sum.sourced_mass += st.sourced_mass;
            sum.max_excess_slope = std::max(sum.max_excess_slope, st.max_excess);
            if (st.hot_r0 < st.hot_r1)
                moved.add(ws.origin[2 * k] + st.hot_c0 - 1, ws.origin[2 * k] + st.hot_c1 + 1,
                          ws.origin[2 * k + 1] + st.hot_r0 - 1, ws.origin[2 * k + 1] + st.hot_r1 + 1);
        }
        active.hot(ws.visit[k]) = moved;
        // A residual changes only with its cell's height, which only a moving
        // face changes: within the new hot box.
        if (residuals) grid.residuals_written(moved);
    }
    if (decomposition) decomposition->after_sweep(summaries);  // every rank takes the same sub-steps
    return visited_cells;
}

}  // namespace dpsm

namespace dpsm {

namespace {

// Calls visit(k, buffers) for k in [0, count) on the grid's threads (the
// calling thread alone when there is too little work for more).
template <class Visit>
void for_tiles_in_parallel(Grid &grid, std::int64_t count, std::int64_t cells, Visit &&visit) {
    TiledWorkspace &ws = grid.tiled_workspace();
    const int threads = grid.step_threads();
#if defined(_OPENMP)
    const bool parallel = threads > 1 && count > 1 && cells >= kCellsForThreads;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads) if (parallel)
    for (std::int64_t k = 0; k < count; ++k) visit(k, ws.buffers[static_cast<std::size_t>(omp_get_thread_num())]);
#else
    (void)threads;
    (void)cells;
    for (std::int64_t k = 0; k < count; ++k) visit(k, ws.buffers[0]);
#endif
}

}  // namespace

namespace {

// The steepest a face of the box can be, now and at T under the sources
// alone, squared, in units of the slope: a face's normal difference is one
// of the box's differences along its normal, and its transverse slope (the
// mean of two central differences across it) at most the largest difference
// across; so (largest x difference / dx)^2 + (largest y difference / dy)^2
// bounds both schemes' squared slopes. Also the largest height. The box
// (with every cell sand) and its faces' neighbours must lie in the grid.
struct SlopeBound {
    double now2 = 0.0, later2 = 0.0, largest = 0.0;
};
// The per-column maxima of bound_slopes, and one row's part of them (the
// row's own x differences and heights, and its y differences to the next
// row unless next is null); a copy for AVX-512 as above.
struct ColumnMaxima {
    static constexpr int kWidest = ActiveSet::kTile + 2;
    double x_now[kWidest] = {}, x_later[kWidest] = {}, y_now[kWidest] = {}, y_later[kWidest] = {},
           largest[kWidest] = {};
};
inline void bound_row_cells(ColumnMaxima &m, int width, const double *h, const double *q, const double *h_next,
                            const double *q_next, double T) {
    auto larger = [](double a, double b) { return b > a ? b : a; };
    for (int i = 0; i < width; ++i) m.largest[i] = larger(m.largest[i], larger(std::fabs(h[i]), std::fabs(h[i] + q[i] * T)));
    for (int i = 0; i + 1 < width; ++i) {
        const double d = h[i + 1] - h[i];
        m.x_now[i] = larger(m.x_now[i], std::fabs(d));
        m.x_later[i] = larger(m.x_later[i], std::fabs(d + T * (q[i + 1] - q[i])));
    }
    if (!h_next) return;
    for (int i = 0; i < width; ++i) {
        const double d = h_next[i] - h[i];
        m.y_now[i] = larger(m.y_now[i], std::fabs(d));
        m.y_later[i] = larger(m.y_later[i], std::fabs(d + T * (q_next[i] - q[i])));
    }
}
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
__attribute__((target("avx512f"))) void bound_row_avx512(ColumnMaxima &m, int width, const double *h, const double *q,
                                                          const double *h_next, const double *q_next, double T) {
    bound_row_cells(m, width, h, q, h_next, q_next, T);
}
void bound_row(ColumnMaxima &m, int width, const double *h, const double *q, const double *h_next,
               const double *q_next, double T) {
    rows_in_avx512() ? bound_row_avx512(m, width, h, q, h_next, q_next, T)
                     : bound_row_cells(m, width, h, q, h_next, q_next, T);
}
#else
void bound_row(ColumnMaxima &m, int width, const double *h, const double *q, const double *h_next,
               const double *q_next, double T) {
    bound_row_cells(m, width, h, q, h_next, q_next, T);
}
#endif

SlopeBound bound_slopes(const Grid &grid, const CellBox &box, double T) {
    const Geometry &geo = grid.geometry();
    const std::int64_t nx = geo.nx;
    const double *h = grid.heights().data();
    const double *q = grid.source().empty() ? nullptr : grid.source().data();
    // Per column, the largest so far: element by element, so that the loops run in vectors.
    ColumnMaxima m;
    const double zeros[ColumnMaxima::kWidest + 1] = {};
    const int width = static_cast<int>(box.i1 - box.i0);
    for (std::int64_t j = box.j0; j < box.j1; ++j) {
        const double *hr = h + (box.i0 + nx * j), *qr = q ? q + (box.i0 + nx * j) : zeros;
        const bool last = j + 1 == box.j1;
        bound_row(m, width, hr, qr, last ? nullptr : hr + nx, last ? nullptr : q ? qr + nx : zeros, T);
    }
    const double *x_now = m.x_now, *x_later = m.x_later, *y_now = m.y_now, *y_later = m.y_later,
                 *largest = m.largest;
    auto larger = [](double a, double b) { return b > a ? b : a; };
    SlopeBound bound;
    double xn = 0.0, xl = 0.0, yn = 0.0, yl = 0.0;
    for (int i = 0; i < width; ++i) {
        xn = larger(xn, x_now[i]);
        xl = larger(xl, x_later[i]);
        yn = larger(yn, y_now[i]);
        yl = larger(yl, y_later[i]);
        bound.largest = larger(bound.largest, largest[i]);
    }
    auto squared = [&](double x, double y) { return (x / geo.dx) * (x / geo.dx) + (y / geo.dy) * (y / geo.dy); };
    bound.now2 = squared(xn, yn);
    bound.later2 = squared(xl, yl);
    return bound;
}

}  // namespace

bool drive_sources(Grid &grid, double T, double dt, double &reach) {
    const Geometry &geo = grid.geometry();
    ActiveSet &active = grid.active_set();
    Decomposition *decomposition = grid.decomposition();
    if (decomposition) decomposition->before_sweep(grid);  // the neighbours' heights now
    const HaloStore *halo_store = decomposition ? &decomposition->halo() : nullptr;
    std::vector<std::int64_t> tiles;
    for (std::int64_t t = 0; t < active.tiles(); ++t)
        if (active.has_source(t)) tiles.push_back(t);

    TileLevelParams params{grid.mobility(), grid.tan_repose(), geo.dx, geo.dy, 1.0 / geo.dx, 1.0 / geo.dy,
                           0.5 / geo.dx,    0.5 / geo.dy,      dt,     geo.dy, geo.dx};
    params.residuals = false;
    params.track_excess = false;
    params.cell_area = geo.dx * geo.dy;
    const bool isotropic = grid.scheme() == kIsotropic;
    const double tan_theta = grid.tan_repose(), tan_d = tan_theta * std::min(geo.dx, geo.dy);
    // A face in the band of rounding below the threshold counts as steep:
    // the kernel sees its slope through other roundings during the step,
    // and those grow with the heights (largest) against the cell size.
    auto margin_factor = [&](double largest) {
        return std::max(0.5, 1.0 + grid.rest_tolerance() -
                                 64.0 * std::numeric_limits<double>::epsilon() * largest / tan_d);
    };
    std::vector<CellBox> driven(tiles.size());
    std::vector<std::uint8_t> steep_later(tiles.size(), 0);
    std::vector<double> reached(tiles.size(), 0.0);

    auto classify = [&](std::int64_t k, TileBuffers &b) {
        const std::int64_t t = tiles[static_cast<std::size_t>(k)];
        const CellBox tile = active.tile_cells(t);
        // The faces whose slopes a source moves: those of the cells within one
        // of a source (a neighbour's, another rank's: the whole tile).
        const CellBox region =
            active.has_remote_source(t) ? tile : active.sources_near(t).grown_within(1, tile);
        if (region.empty()) return;
        const CellBox read = region.grown(1);
        const std::int64_t gi0 = read.i0, gj0 = read.j0;
        b.width = static_cast<int>(read.i1 - read.i0);
        b.height = static_cast<int>(read.j1 - read.j0);
        const bool inside = gi0 >= 0 && gj0 >= 0 && gi0 + b.width <= geo.nx && gj0 + b.height <= geo.ny;
        const bool masked = active.masked(t) || !inside;
        // Most of a dune field is far from steep: a bound on its slopes, a
        // few operations a cell, clears it without evaluating a face. Beyond
        // a wall side no face carries sand and a transverse slope mirrors the
        // cell that asks, so there the bound needs the domain's cells alone.
        const CellBox domain{0, geo.nx, 0, geo.ny};
        const bool walls_beyond = (read.i0 >= 0 || !grid.side_open(kXMin)) && (read.i1 <= geo.nx || !grid.side_open(kXMax)) &&
                                  (read.j0 >= 0 || !grid.side_open(kYMin)) && (read.j1 <= geo.ny || !grid.side_open(kYMax));
        if (!active.masked(t) && walls_beyond && (inside || !halo_store)) {
            const SlopeBound bound = bound_slopes(grid, read.grown_within(0, domain), T);
            reached[static_cast<std::size_t>(k)] = bound.largest;
            const double below = tan_theta * margin_factor(bound.largest);
            if (std::isfinite(bound.largest) && std::max(bound.now2, bound.later2) <= below * below) return;
        }
        gather(grid, b, gi0, gj0, true, masked, true, active.sources_near(t), false);
        if (halo_store && !inside) gather_halo(grid, *halo_store, b, gi0, gj0, masked, true);
        const std::size_t count = static_cast<std::size_t>(b.width) * b.height;
        double largest = 0.0;
        for (std::size_t c = 0; c < count; ++c)
            largest = std::max({largest, std::fabs(b.h[0][c]), std::fabs(b.h[0][c] + b.source[c] * T)});
        reached[static_cast<std::size_t>(k)] = largest;
        if (!std::isfinite(largest)) {  // beyond the supported range: every cell may move
            driven[static_cast<std::size_t>(k)] = region;
            steep_later[static_cast<std::size_t>(k)] = 1;
            return;
        }
        TileLevelParams p = params;
        p.rest_factor = margin_factor(largest);
        const TileRect rect{static_cast<int>(region.j0 - gj0), static_cast<int>(region.j1 - gj0),
                            static_cast<int>(region.i0 - gi0), static_cast<int>(region.i1 - gi0)};
        const TileKernel kernel = select_tile_kernel(masked, isotropic, false);
        TileLevelStats now, later;
        kernel(b, buffer_level_cells(b, 0), rect, rect, p, now);
        for (std::size_t c = 0; c < count; ++c) b.h[0][c] += b.source[c] * T;
        kernel(b, buffer_level_cells(b, 0), rect, rect, p, later);
        for (const TileLevelStats &st : {now, later})
            if (st.hot_r0 < st.hot_r1)
                driven[static_cast<std::size_t>(k)].add(gi0 + st.hot_c0, gi0 + st.hot_c1, gj0 + st.hot_r0,
                                                       gj0 + st.hot_r1);
        steep_later[static_cast<std::size_t>(k)] = later.hot_r0 < later.hot_r1;
    };
    std::int64_t cells = 0;
    for (const std::int64_t t : tiles) {
        const CellBox box = active.tile_cells(t);
        cells += (box.i1 - box.i0) * (box.j1 - box.j0);
    }
    for_tiles_in_parallel(grid, static_cast<std::int64_t>(tiles.size()), cells, classify);
    bool any = false;
    reach = 0.0;
    for (std::size_t k = 0; k < tiles.size(); ++k) {
        active.driven(tiles[k]) = driven[k];
        any = any || steep_later[k];
        if (!std::isnan(reach) && !(reached[k] <= reach)) reach = reached[k];  // NaN stays
    }
    return any;
}

double catch_up_sources(Grid &grid, double substeps, double dt) {
    const std::int64_t nx = grid.geometry().nx;
    ActiveSet &active = grid.active_set();
    const std::vector<double> &q = grid.source(), &clock = grid.source_clock();
    const std::vector<std::uint8_t> &kind = grid.kinds();
    std::vector<double> &h = grid.heights_for_stepping();
    std::vector<float> &residual = grid.residuals_for_stepping();
    const double base = grid.clock_base();
    std::vector<std::int64_t> tiles;
    std::int64_t cells = 0;
    for (std::int64_t t = 0; t < active.tiles(); ++t) {
        const CellBox &box = active.sources(t);
        if (box.empty()) continue;
        tiles.push_back(t);
        cells += (box.i1 - box.i0) * (box.j1 - box.j0);
    }
    std::vector<double> changed(tiles.size(), 0.0);
    const SourceRow row{substeps, dt, base};
    TiledWorkspace &ws = grid.tiled_workspace();
    auto catch_up = [&](std::int64_t k, TileBuffers &) {
        const CellBox &box = active.sources(tiles[static_cast<std::size_t>(k)]);
        double count = 0.0;
        // A tile no sweep of the step visited holds no cell that became current.
        const bool visited = ws.visited_in_step[static_cast<std::size_t>(tiles[static_cast<std::size_t>(k)])] != 0;
        for (std::int64_t j = box.j0; j < box.j1; ++j) {
            const std::size_t at = static_cast<std::size_t>(box.i0 + nx * j);
            count += catch_up_row(row, static_cast<int>(box.i1 - box.i0), q.data() + at, kind.data() + at,
                                  visited ? clock.data() + at : nullptr, h.data() + at, residual.data() + at);
        }
        changed[static_cast<std::size_t>(k)] = count;
    };
    for_tiles_in_parallel(grid, static_cast<std::int64_t>(tiles.size()), cells, catch_up);
    std::fill(ws.visited_in_step.begin(), ws.visited_in_step.end(), 0);
    double total = 0.0;
    for (std::size_t k = 0; k < tiles.size(); ++k) {
        if (changed[k] == 0.0) continue;
        const CellBox &box = active.sources(tiles[k]);
        tiled_workspace_changed(ws, active, box);
        grid.residuals_written(box);
        total += changed[k];
    }
    return total;
}

}  // namespace dpsm
