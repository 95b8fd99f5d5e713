#include "structured/tiled_sweep.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "model/distribution.hpp"
#include "model/grid.hpp"
#include "model/ledger.hpp"
#include "structured/active_set.hpp"
#include "structured/halo.hpp"
#include "structured/lazy_sources.hpp"
#include "structured/simd.hpp"
#include "structured/structured_state.hpp"
#include "structured/tile_gather.hpp"

namespace dpsm {

namespace {

constexpr int kBufferSide = ActiveSet::kTile + 2 * (ActiveSet::kMaxLevels + 1);
// The longest grid row a tile kernel reads or writes in place: its indices
// (rows of the buffer times the row length) stay within an int.
constexpr std::int64_t kMaxDirectRowLength = std::numeric_limits<int>::max() / (2 * kBufferSide);

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
    const CellBox tile = active_set(grid).tile_cells(t);
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
void refresh_scratch(const Grid &grid, const std::vector<double> &clock, TiledWorkspace &ws, const CellBox &box,
                     bool hysteresis, bool clocks) {
    const std::int64_t nx = grid.geometry().nx;
    for (std::int64_t j = box.j0; j < box.j1; ++j) {
        const std::size_t at = static_cast<std::size_t>(j * nx + box.i0);
        const std::size_t count = static_cast<std::size_t>(box.i1 - box.i0);
        std::memcpy(ws.heights.data() + at, grid.heights().data() + at, sizeof(double) * count);
        std::memcpy(ws.residuals.data() + at, grid.residuals().data() + at, sizeof(float) * count);
        if (hysteresis) std::memcpy(ws.moving.data() + at, grid.moving().data() + at, count);
        if (clocks) std::memcpy(ws.clock.data() + at, clock.data() + at, sizeof(double) * count);
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
    StructuredState &state = structured_state(grid);
    TiledWorkspace &ws = state.tiled_workspace();
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
    const std::size_t tiles = static_cast<std::size_t>(state.active->tiles());
    if (grid.records_face_fluxes()) {
        for (TileBuffers &b : ws.buffers) {
            b.face_x.resize(b.h[0].size());
            b.face_y.resize(b.h[0].size());
        }
        // Each tile notes the step whose fluxes its faces hold (FaceFluxes).
        std::vector<std::uint64_t> &tile_step = grid.face_fluxes().tile_step;
        if (tile_step.size() != tiles) tile_step.assign(tiles, 0);
    }
    if (grid.hysteresis() && ws.moving.size() != cells) {
        ws.moving.assign(cells, 0);
        ws.all_stale = true;
    }
    if (state.clock.size() == cells && ws.clock.size() != cells) {
        ws.clock.assign(cells, 0.0);
        ws.all_stale = true;
    }
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
    StructuredState &state = structured_state(grid);
    ActiveSet &active = *state.active;
    TiledWorkspace &ws = state.tiled_workspace();
    if (state.halo) state.halo->before_sweep(grid, state);  // the neighbours' cells and activity
    const HaloStore *halo_store = state.halo ? &state.halo->store() : nullptr;
    active.tiles_to_visit(levels, state.switches.visit_all_tiles, ws.visit, ws.boxes, ws.seeds);
    const std::int64_t visits = static_cast<std::int64_t>(ws.visit.size());
    ws.stats.assign(static_cast<std::size_t>(visits) * levels, TileLevelStats{});
    ws.origin.assign(static_cast<std::size_t>(2 * visits), 0);

    TileLevelParams params{grid.mobility(), grid.tan_repose(), geo.dx, geo.dy, 1.0 / geo.dx, 1.0 / geo.dy,
                           0.5 / geo.dx,    0.5 / geo.dy,      dt,     geo.dy, geo.dx};
    const bool physics = grid.uses_physics(), hysteresis = grid.hysteresis();
    // Source cells' clocks move with their heights (lazy sources).
    const bool clocks = !physics && state.clock.size() == static_cast<std::size_t>(geo.cells());
    const double clock_base = state.clock_base;
    // DPSM_SCALAR_PHYSICS=1 steps a grid with physics by the scalar reference
    // kernel (structured/tile_kernel_physics.cpp), in the buffer, on every tile; read at
    // every sweep, so that a test can compare the two within one process.
    const bool scalar_physics = physics && state.switches.scalar_physics;
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
    const bool in_place = !state.switches.copy_tiles;
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
        if (clocks) ws.clock = state.clock;
        for (const std::int64_t t : ws.stale_tiles) ws.stale[static_cast<std::size_t>(t)] = CellBox{};
        ws.stale_tiles.clear();
        ws.all_stale = false;
    }
    for (std::int64_t k = 0; k < visits; ++k) ws.written[static_cast<std::size_t>(ws.visit[k])] = ws.boxes[k];
    const std::int64_t stale_count = static_cast<std::int64_t>(ws.stale_tiles.size());
    auto refresh_tile = [&](std::int64_t k) {
        const std::size_t t = static_cast<std::size_t>(ws.stale_tiles[static_cast<std::size_t>(k)]);
        for_parts_outside(ws.stale[t], ws.written[t],
                          [&](const CellBox &part) { refresh_scratch(grid, state.clock, ws, part, hysteresis, clocks); });
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
    if (clocks) state.clock.swap(ws.clock);
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
        if (residuals) state.residuals_written(moved);
    }
    // Every rank takes the same sub-steps.
    if (const Distribution *distribution = grid.distribution()) distribution->agree_on_substeps(summaries);
    return visited_cells;
}


}  // namespace dpsm
