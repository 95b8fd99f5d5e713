#include "structured/lazy_sources.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "model/grid.hpp"
#include "model/ledger.hpp"
#include "structured/halo.hpp"
#include "structured/simd.hpp"
#include "structured/structured_state.hpp"
#include "structured/tile_gather.hpp"
#include "structured/tiled_sweep.hpp"

namespace dpsm {

namespace {

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

}  // namespace

void gather_since(const Grid &grid, const HaloStore *halo, TileBuffers &b, std::int64_t gi0, std::int64_t gj0) {
    const Geometry &geo = grid.geometry();
    const StructuredState &state = structured_state(grid);
    const double *clock = state.clock.data();
    const double base = state.clock_base;
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

namespace {

// Calls visit(k, buffers) for k in [0, count) on the grid's threads (the
// calling thread alone when there is too little work for more).
template <class Visit>
void for_tiles_in_parallel(Grid &grid, std::int64_t count, std::int64_t cells, Visit &&visit) {
    TiledWorkspace &ws = structured_state(grid).tiled_workspace();
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
    StructuredState &state = structured_state(grid);
    ActiveSet &active = *state.active;
    if (state.halo) state.halo->before_sweep(grid, state);  // the neighbours' heights now
    const HaloStore *halo_store = state.halo ? &state.halo->store() : nullptr;
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
    StructuredState &state = structured_state(grid);
    ActiveSet &active = *state.active;
    const std::vector<double> &q = grid.source(), &clock = state.clock;
    const std::vector<std::uint8_t> &kind = grid.kinds();
    std::vector<double> &h = grid.heights_for_stepping();
    std::vector<float> &residual = grid.residuals_for_stepping();
    const double base = state.clock_base;
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
    TiledWorkspace &ws = state.tiled_workspace();
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
        state.residuals_written(box);
        total += changed[k];
    }
    return total;
}

}  // namespace dpsm
