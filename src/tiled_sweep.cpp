#include "tiled_sweep.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "active_set.hpp"
#include "decomposition.hpp"
#include "grid.hpp"
#include "simd.hpp"

namespace dpsm {

namespace {

constexpr int kBufferSide = ActiveSet::kTile + 2 * (ActiveSet::kMaxLevels + 1);
constexpr std::int64_t kCellsForThreads = 8 * ActiveSet::kTile * ActiveSet::kTile;
// The longest grid row a tile kernel reads or writes in place: its indices
// (rows of the buffer times the row length) stay within an int.
constexpr std::int64_t kMaxDirectRowLength = std::numeric_limits<int>::max() / (2 * kBufferSide);

int thread_count(int requested) {
#if defined(_OPENMP)
    return requested > 0 ? requested : omp_get_max_threads();
#else
    (void)requested;
    return 1;
#endif
}

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

// The kind of a ghost cell beyond the domain: a sink at 0 beyond an open
// side, a wall beyond a wall side; a corner is a sink only if both sides are.
std::uint8_t ghost_kind(const Grid &grid, std::int64_t i, std::int64_t j) {
    const Geometry &geo = grid.geometry();
    bool open = true;
    if (i < 0) open = open && grid.side_open(kXMin);
    if (i >= geo.nx) open = open && grid.side_open(kXMax);
    if (j < 0) open = open && grid.side_open(kYMin);
    if (j >= geo.ny) open = open && grid.side_open(kYMax);
    return open ? kOpen : kWall;
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
        const int c_in0 = row_in ? static_cast<int>(std::clamp<std::int64_t>(-gi0, 0, b.width)) : b.width;
        const int c_in1 = row_in ? static_cast<int>(std::clamp<std::int64_t>(geo.nx - gi0, c_in0, b.width)) : b.width;
        auto ghosts = [&](int c0, int c1) {
            for (int c = c0; c < c1; ++c) {
                if (heights) {
                    hb[c] = 0.0;
                    rb[c] = 0.0;
                }
                if (masked) kb[c] = ghost_kind(grid, gi0 + c, j);
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

// Copies what the physics kernel reads besides heights: bed, angles and which
// cells are moving; ghost cells are never moving and have no bed or angle.
// On a block of a distributed grid, the cells beyond the block that lie in
// the global domain come from the halo store (decomposition.hpp).
void gather_physics(const Grid &grid, const HaloStore *halo, TileBuffers &b, std::int64_t gi0, std::int64_t gj0) {
    const Geometry &geo = grid.geometry();
    const std::vector<double> &zb = grid.bed(), &tan_theta = grid.tan_field();
    const std::vector<std::uint8_t> &moving = grid.moving();
    for (int r = 0; r < b.height; ++r)
        for (int c = 0; c < b.width; ++c) {
            const std::int64_t i = gi0 + c, j = gj0 + r;
            const std::size_t at = static_cast<std::size_t>(r) * b.width + c;
            const bool in = i >= 0 && j >= 0 && i < geo.nx && j < geo.ny;
            if (!in && halo && halo->in_domain(i, j)) {
                const std::size_t k = halo->index(i, j);
                if (!zb.empty()) b.bed[at] = halo->bed[k];
                if (!tan_theta.empty()) b.tan_theta[at] = halo->tan_theta[k];
                if (!moving.empty()) b.moving[0][at] = halo->moving[k];
                continue;
            }
            const std::size_t cell = in ? static_cast<std::size_t>(i + geo.nx * j) : 0;
            if (!zb.empty()) b.bed[at] = in ? zb[cell] : 0.0;
            if (!tan_theta.empty()) b.tan_theta[at] = in ? tan_theta[cell] : 0.0;
            if (!moving.empty()) b.moving[0][at] = in ? moving[cell] : 0;
        }
}

// The kind of a ghost cell (i, j) beyond the global domain of a distributed
// grid, in global coordinates: as ghost_kind, with the global grid's sides.
std::uint8_t global_ghost_kind(const Grid &grid, const HaloStore &halo, std::int64_t i, std::int64_t j) {
    bool open = true;
    if (i < 0) open = open && grid.side_open(kXMin);
    if (i >= halo.global_nx) open = open && grid.side_open(kXMax);
    if (j < 0) open = open && grid.side_open(kYMin);
    if (j >= halo.global_ny) open = open && grid.side_open(kYMax);
    return open ? kOpen : kWall;
}

// On a block of a distributed grid, replaces what gather() put in the buffer
// for the cells beyond the block: the neighbours' cells come from the halo
// store (decomposition.hpp), the cells beyond the global domain are ghosts of
// its sides. The block's own cells are left as gather() copied them.
void gather_halo(const Grid &grid, const HaloStore &halo, TileBuffers &b, std::int64_t gi0, std::int64_t gj0,
                 bool masked, bool source) {
    const Geometry &geo = grid.geometry();
    for (int r = 0; r < b.height; ++r) {
        const std::int64_t j = gj0 + r;
        const std::size_t row = static_cast<std::size_t>(r) * b.width;
        // The block's own columns of this row, [own0, own1) in the buffer (none off the block's rows).
        int own0 = b.width, own1 = b.width;
        if (j >= 0 && j < geo.ny) {
            own0 = static_cast<int>(std::clamp<std::int64_t>(-gi0, 0, b.width));
            own1 = static_cast<int>(std::clamp<std::int64_t>(geo.nx - gi0, 0, b.width));
        }
        for (int c = 0; c < b.width; ++c) {
            if (c == own0 && own0 < own1) c = own1;
            if (c >= b.width) break;
            const std::int64_t i = gi0 + c;
            const std::size_t at = row + static_cast<std::size_t>(c);
            if (halo.in_domain(i, j)) {
                const std::size_t k = halo.index(i, j);
                b.h[0][at] = halo.heights[k];
                b.residual[0][at] = static_cast<double>(halo.residuals[k]);
                if (masked) b.kind[at] = halo.kinds[k];
                if (source) b.source[at] = halo.kinds[k] == kSand ? halo.sources[k] : 0.0;
            } else {
                b.h[0][at] = 0.0;
                b.residual[0][at] = 0.0;
                if (masked) b.kind[at] = global_ghost_kind(grid, halo, i + halo.i0, j + halo.j0);
                if (source) b.source[at] = 0.0;
            }
        }
    }
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
void refresh_scratch(const Grid &grid, TiledWorkspace &ws, const CellBox &box, bool hysteresis) {
    const std::int64_t nx = grid.geometry().nx;
    for (std::int64_t j = box.j0; j < box.j1; ++j) {
        const std::size_t at = static_cast<std::size_t>(j * nx + box.i0);
        const std::size_t count = static_cast<std::size_t>(box.i1 - box.i0);
        std::memcpy(ws.heights.data() + at, grid.heights().data() + at, sizeof(double) * count);
        std::memcpy(ws.residuals.data() + at, grid.residuals().data() + at, sizeof(float) * count);
        if (hysteresis) std::memcpy(ws.moving.data() + at, grid.moving().data() + at, count);
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
    const std::size_t want = static_cast<std::size_t>(thread_count(threads));
    while (ws.buffers.size() < want) {
        ws.buffers.emplace_back();
        ws.buffers.back().resize(kBufferSide, kBufferSide);
    }
    if (grid.uses_physics())
        for (TileBuffers &b : ws.buffers) b.resize_physics();
    if (grid.hysteresis() && ws.moving.size() != cells) {
        ws.moving.assign(cells, 0);
        ws.all_stale = true;
    }
    const std::size_t tiles = static_cast<std::size_t>(grid.active_set().tiles());
    ws.stale.resize(tiles);
    ws.written.resize(tiles);
    ws.stale_tiles.reserve(tiles);
    ws.visit.reserve(tiles);
    ws.boxes.reserve(tiles);
    ws.seeds.reserve(tiles);
    ws.stats.reserve(tiles * ActiveSet::kMaxLevels);
    ws.origin.reserve(2 * tiles);
}

std::int64_t tiled_sweep(Grid &grid, int levels, double dt, std::vector<LevelSummary> &summaries, bool find_excess,
                         bool residuals) {
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
    residuals = residuals || physics;  // the physics kernel always carries them
    params.residuals = residuals;
    params.cell_area = geo.dx * geo.dy;
    params.rest_factor = 1.0 + grid.rest_tolerance();
    if (physics) {
        params.flux_exponent = grid.flux_exponent();
        params.tan_static = grid.tan_static();
        params.hysteresis = hysteresis;
        params.bed = !grid.bed().empty();
        params.angle_field = !grid.tan_field().empty();
        params.bed_film = bed_film(grid);
    }
    const bool isotropic = grid.scheme() == kIsotropic;
    // DPSM_COPY_TILES=1 copies every tile into a buffer and back (no tile is
    // read or written in place), for tests that show it changes no result.
    const char *copy_all = std::getenv("DPSM_COPY_TILES");
    const bool in_place = !(copy_all && *copy_all && *copy_all != '0');
    const int threads = thread_count(grid.threads());
    std::int64_t visited_cells = 0;
    for (const CellBox &cells : ws.boxes) visited_cells += (cells.i1 - cells.i0) * (cells.j1 - cells.j0);
    // Threads pay off only with enough work between their barriers; below this
    // a sweep runs on the calling thread (results are the same either way).
    const bool parallel = threads > 1 && visits > 1 && visited_cells >= kCellsForThreads;

    auto visit_tile = [&](std::int64_t k, TileBuffers &b) {
        const std::int64_t t = ws.visit[k];
        const CellBox &cells = ws.boxes[k];
        const bool source = active.has_source(t);
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
        const bool masked = active.masked(t) || !inside;
        // Copies cost about a third of a fully active sweep, so where it can a
        // visit works in place. Its last level computes exactly its cells and
        // writes them straight into the scratch. Its first level reads
        // straight from the grid if every level computes all that the next
        // one reads (else later levels would need cells the first one leaves
        // alone) and the visit needs no ghosts; its whole-vector loads run up
        // to a vector past the read box, still within the grid's arrays unless
        // the box ends at the grid's last row and column. The kernel indexes
        // a row of the grid by an int.
        constexpr int kVectorSlack = 8;
        const bool out_in_place = in_place && !physics && residuals && geo.nx <= kMaxDirectRowLength &&
                                  level_cells[levels - 1] == cells;
        const bool in_in_place = out_in_place && !masked && every_cell &&
                                 (gj0 + b.height < geo.ny || gi0 + b.width + kVectorSlack <= geo.nx);
        // The physics kernel reads cell kinds on every tile.
        if (!in_in_place || source)
            gather(grid, b, gi0, gj0, !in_in_place, masked || physics, source,
                   source ? active.sources_near(t) : CellBox{}, residuals);
        if (halo_store && !inside) gather_halo(grid, *halo_store, b, gi0, gj0, masked || physics, source);
        if (physics) gather_physics(grid, halo_store, b, gi0, gj0);
        if (!every_cell) {
            // A cell a level leaves alone keeps its gathered value, which the
            // next level then reads from the other slot.
            const std::size_t count = static_cast<std::size_t>(b.width) * b.height;
            std::memcpy(b.h[1].data(), b.h[0].data(), sizeof(double) * count);
            if (residuals) std::memcpy(b.residual[1].data(), b.residual[0].data(), sizeof(double) * count);
            if (hysteresis) std::memcpy(b.moving[1].data(), b.moving[0].data(), count);
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
            TileLevelStats &stats = ws.stats[static_cast<std::size_t>(k) * levels + (s - 1)];
            const TileRect region = in_buffer(level_cells[s - 1]);
            if (physics) {
                select_physics_tile_kernel(isotropic, source)(b, in, region, tile, level_params, stats);
            } else {
                LevelCells io = buffer_level_cells(b, in);
                const bool grid_in = in_in_place && s == 1, grid_out = out_in_place && s == levels;
                if (grid_in) {  // from the buffer's (0, 0), inside the grid
                    const std::size_t origin = grid_index(0, 0);
                    io.h = grid.heights().data() + origin;
                    io.residual = nullptr;
                    io.residual_grid = grid.residuals().data() + origin;
                    if (source) io.source = grid.source().data() + origin;  // all sand: unmasked
                    io.stride = static_cast<int>(geo.nx);
                }
                if (grid_out) {  // from the first of the visit's cells
                    const std::size_t origin = grid_index(tile.r0, tile.c0);
                    io.h_out = ws.heights.data() + origin;
                    io.residual_out = nullptr;
                    io.residual_grid_out = ws.residuals.data() + origin;
                    io.out_stride = static_cast<int>(geo.nx);
                    io.out_row0 = tile.r0;
                    io.out_col0 = tile.c0;
                }
                select_tile_kernel(masked, isotropic, source, grid_in, grid_out)(b, io, region, tile, level_params,
                                                                                 stats);
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
            }
            std::memcpy(ws.heights.data() + to, b.h[in].data() + from, sizeof(double) * count);
            if (residuals)
                narrow(b.residual[in].data() + from, ws.residuals.data() + to, count);
            else
                std::fill_n(ws.residuals.data() + to, count, 0.0f);
            if (hysteresis) std::memcpy(ws.moving.data() + to, b.moving[in].data() + from, count);
        }
        ws.origin[2 * k] = gi0;
        ws.origin[2 * k + 1] = gj0;
    };

    // The scratch becomes the grid at the end: where this sweep does not write
    // it, it must hold the grid's cells. It does, but in its stale boxes.
    if (ws.all_stale) {
        ws.heights = grid.heights();
        ws.residuals = grid.residuals();
        if (hysteresis) ws.moving = grid.moving();
        for (const std::int64_t t : ws.stale_tiles) ws.stale[static_cast<std::size_t>(t)] = CellBox{};
        ws.stale_tiles.clear();
        ws.all_stale = false;
    }
    for (std::int64_t k = 0; k < visits; ++k) ws.written[static_cast<std::size_t>(ws.visit[k])] = ws.boxes[k];
    const std::int64_t stale_count = static_cast<std::int64_t>(ws.stale_tiles.size());
    auto refresh_tile = [&](std::int64_t k) {
        const std::size_t t = static_cast<std::size_t>(ws.stale_tiles[static_cast<std::size_t>(k)]);
        for_parts_outside(ws.stale[t], ws.written[t],
                          [&](const CellBox &part) { refresh_scratch(grid, ws, part, hysteresis); });
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
    // The old grid, now the scratch, differs from the new one where this sweep wrote.
    for (const std::int64_t t : ws.stale_tiles) ws.stale[static_cast<std::size_t>(t)] = CellBox{};
    ws.stale_tiles.clear();
    ws.last_written = CellBox{};
    for (std::int64_t k = 0; k < visits; ++k) {
        const std::size_t t = static_cast<std::size_t>(ws.visit[k]);
        ws.written[t] = CellBox{};
        if (ws.boxes[k].empty()) continue;
        ws.stale[t] = ws.boxes[k];
        ws.last_written.add(ws.boxes[k]);
        ws.stale_tiles.push_back(ws.visit[k]);
    }

    // New hot boxes: the cells touching moving faces in any level, grown by the
    // one cell a last move can make steep. Sums in tile order, whatever the threads.
    summaries.assign(static_cast<std::size_t>(levels), LevelSummary{});
    for (std::int64_t k = 0; k < visits; ++k) {
        CellBox moved;
        for (int s = 0; s < levels; ++s) {
            const TileLevelStats &st = ws.stats[static_cast<std::size_t>(k) * levels + s];
            LevelSummary &sum = summaries[static_cast<std::size_t>(s)];
            sum.moved = sum.moved || st.moved;
            sum.outflow_rate += st.outflow_rate;
            sum.unmet_mass += st.unmet_mass;
            sum.sourced_mass += st.sourced_mass;
            sum.max_excess = std::max(sum.max_excess, st.max_excess);
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
