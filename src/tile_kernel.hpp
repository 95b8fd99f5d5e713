// The 2D sweep on one tile: a private copy of the tile and a halo of `levels`
// cells (plus one ring of ghosts) is advanced `levels` sub-steps in cache,
// shrinking by one cell a level, and only the tile itself is kept. Faces are
// computed once per level; the flux law is the dead-zone form of closure.hpp
// (no flux up to the rest threshold tan(theta) (1 + tol)), so a tile whose
// faces are all below it is exactly at rest and may be skipped.
//
// Ghost and non-sand cells carry kinds: an open cell (or the outside of an
// open side) is a sink held at its height, a wall cell (or a wall side) closes
// its faces and mirrors the asking cell in transverse slopes.
#pragma once

#include <cstdint>
#include <vector>

namespace dpsm {

// How many rows ahead a copy or a level that reads or writes the grid asks
// the caches for the grid's rows (a fully active sweep of 2048^2 cells on one
// core: 192-204 Mcells/s without, 290-307 with 4 to 8 rows ahead).
constexpr int kRowsAhead = 6;

struct TileRect {
    int r0, r1, c0, c1;  // rows [r0, r1), columns [c0, c1), in buffer coordinates
};

struct TileLevelParams {
    double nu, tan_theta;
    double dx, dy, inv_dx, inv_dy, half_inv_dx, half_inv_dy;
    double dt;
    double x_face_length, y_face_length;  // dy and dx: flux per unit length to mass per unit time
    double rest_factor = 1.0;  // 1 + tol: a face's threshold is tan(theta) times this
    // Carry what rounding drops from each height in its residual (a TwoSum).
    // Without, residuals are neither read nor written: they must be 0.
    bool residuals = true;
    // Find the largest excess slope (TileLevelStats::max_excess); without, it stays 0.
    bool track_excess = true;
    // Read by the physics kernel only (tile_kernel_physics.cpp).
    double flux_exponent = 1.0;
    double tan_static = 0.0;  // hysteresis: the threshold between cells at rest
    bool hysteresis = false, bed = false, angle_field = false;
    double bed_film = 0.0;  // sand this thin above the bed is left in place (see dpsm_set_bedrock)
    double cell_area = 1.0;  // dx dy: heights per sub-step to mass
};

// What one level did, over the tile itself (moved and max_excess also over
// its valid halo, which holds true values of the global state).
struct TileLevelStats {
    bool moved = false;         // some face carried sand
    double max_excess = 0.0;    // largest |grad h| - tan(theta) over faces that carried sand
    double outflow_rate = 0.0;  // mass per unit time into sinks from the tile's sand cells
    double unmet_mass = 0.0;    // erosion asked for on the tile's cells where no sand lay above the bed
    double sourced_mass = 0.0;  // with a bed: what the source put on (or took from) the tile's cells
    int hot_r0 = 1 << 30, hot_r1 = -1, hot_c0 = 1 << 30, hot_c1 = -1;  // cells of the tile touching moving faces
};

// A thread's private buffers, sized for the largest tile with its halo.
struct TileBuffers {
    int width = 0, height = 0;  // of the buffer, cells
    std::vector<double> h[2], residual[2], source;
    std::vector<std::uint8_t> kind;
    std::vector<double> rows;  // scratch rows for faces and transverse slopes
    std::vector<unsigned> chunk_bits;  // scratch lane bits, per chunk of a row
    // The physics kernel's inputs and scratch, sized only when a grid uses it.
    std::vector<double> bed, tan_theta;
    std::vector<std::uint8_t> moving[2];
    std::vector<double> available, applied, x_faces, y_faces;
    void resize(int w, int h_);
    void resize_physics();
};

// Where a level of the tile kernel reads and writes its cells. Cell (r, c)
// in the buffer's coordinates is element r * stride + c of each array read
// and (r - out_row0) * out_stride + c - out_col0 of each array written: the
// buffer's slots, or, on a tile whose sweep reads its cells straight from the
// grid (first level) or writes them straight into the next grid (last level),
// the grid's arrays from the cell at the buffer's origin (read) or at the
// first cell written (written). Residuals are double in the buffer and
// float in the grid: one of each pair is set. Reads may run a vector past the
// region's last column (the caller makes sure the arrays reach that far).
struct LevelCells {
    const double *h = nullptr;
    const double *residual = nullptr;
    const float *residual_grid = nullptr;
    const double *source = nullptr;      // per sand cell; 0 elsewhere (read by kernels with a source)
    const std::uint8_t *kind = nullptr;  // (read by masked kernels, which always work in the buffer)
    int stride = 0;
    double *h_out = nullptr;
    double *residual_out = nullptr;
    float *residual_grid_out = nullptr;
    int out_stride = 0;
    int out_row0 = 0, out_col0 = 0;  // the cell of the buffer's coordinates at the start of the arrays written
};

// Slot `in` of the buffer to slot 1 - in.
LevelCells buffer_level_cells(TileBuffers &buffers, int in);

// Advances the cells of `region` by one level. `tile` is the part of the
// region whose statistics count; `buffers` gives the scratch rows.
using TileKernel = void (*)(TileBuffers &buffers, const LevelCells &cells, const TileRect &region,
                            const TileRect &tile, const TileLevelParams &params, TileLevelStats &stats);

// The kernel for a tile: masked (walls, sinks or ghosts in reach), isotropic
// or pairwise, with or without a source, reading its residuals from the grid
// or the buffer, writing them to the grid or the buffer (masked kernels: the
// buffer only). The widest lanes this CPU has.
TileKernel select_tile_kernel(bool masked, bool isotropic, bool source, bool grid_in = false, bool grid_out = false);
// The lanes of the kernels chosen: 8 (AVX-512), 4 (AVX2 and FMA) or 1, the
// widest this CPU has that DPSM_NO_AVX512=1 or DPSM_NO_AVX2=1 does not rule out.
int tile_kernel_lanes();
// Whether the kernels chosen run in AVX-512.
bool tile_kernels_use_avx512();

// The kernel of a grid that uses a bed, an angle field, a flux exponent or
// hysteresis (tile_kernel_physics.cpp): plain scalar code, used for every tile
// of such a grid (it reads cell kinds always), so that every face of the grid
// is computed by the same arithmetic. It works in the buffer only, from slot
// `in` to slot 1 - in.
using PhysicsTileKernel = void (*)(TileBuffers &buffers, int in, const TileRect &region, const TileRect &tile,
                                   const TileLevelParams &params, TileLevelStats &stats);
PhysicsTileKernel select_physics_tile_kernel(bool isotropic, bool source);

}  // namespace dpsm
