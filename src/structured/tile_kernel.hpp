// The 2D sweep on one tile: a private copy of the tile and a halo of `levels`
// cells (plus one ring of ghosts) is advanced `levels` sub-steps in cache,
// shrinking by one cell a level, and only the tile itself is kept. Faces are
// computed once per level; the flux law is the dead-zone form of model/face_law.hpp
// (no flux up to the rest threshold tan(theta) (1 + tol)), so a tile whose
// faces are all below it is exactly at rest and may be skipped.
//
// Ghost and non-sand cells carry kinds: an open cell (or the outside of an
// open side) is a sink held at its height, a wall cell (or a wall side) closes
// its faces and mirrors the asking cell in transverse slopes.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

namespace dpsm {

// How many rows ahead a copy or a level that reads or writes the grid asks
// the caches for the grid's rows (a fully active sweep of 2048^2 cells on one
// core: 192-204 Mcells/s without, 290-307 with 4 to 8 rows ahead).
constexpr int kRowsAhead = 6;

// The physics of real scenes, as every kernel with physics computes it
// (structured/tile_kernel_physics.cpp is the specification): a face takes at most a
// quarter of the sand its upstream cell has above the bed after the cell's
// own erosion, and on the isotropic scheme a face between two cells level to
// within kLevelWithinRounding of their heights carries nothing.
constexpr double kFacesPerCell = 4.0;
constexpr double kLevelWithinRounding = 4.0 * std::numeric_limits<double>::epsilon();

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
    // The physics of real scenes: read by kernels with physics only.
    double flux_exponent = 1.0;
    double tan_static = 0.0;  // hysteresis: the threshold between cells at rest
    bool hysteresis = false, bed = false, angle_field = false;
    double bed_film = 0.0;  // sand this thin above the bed is left in place (see dpsm_set_bedrock)
    double cell_area = 1.0;  // dx dy: heights per sub-step to mass
    // The buffer holds cells beyond open sides (kOutside): count what each side takes.
    bool outside = false;
    // Add every face's flux, in heights per sub-step, to TileBuffers::face_x and face_y.
    bool record = false;
    // Kernels with a source: the index in the step of this level's sub-step
    // (a cell whose faces carry sand in it is current after it: since = substep + 1).
    double substep = 0.0;
};

// What one level did, over the tile itself (moved and max_excess also over
// its valid halo, which holds true values of the global state).
struct TileLevelStats {
    bool moved = false;         // some face carried sand
    double max_excess = 0.0;    // largest |grad h| - tan(theta) over faces that carried sand
    double outflow_rate = 0.0;  // mass per unit time into sinks from the tile's sand cells
    double side_outflow_rate[4] = {};  // the part of it that left through each side
    double unmet_mass = 0.0;    // erosion asked for on the tile's cells where no sand lay above the bed
    double sourced_mass = 0.0;  // with a bed: what the source put on (or took from) the tile's cells
    int hot_r0 = 1 << 30, hot_r1 = -1, hot_c0 = 1 << 30, hot_c1 = -1;  // cells of the tile touching moving faces
};

// A thread's private buffers, sized for the largest tile with its halo.
struct TileBuffers {
    int width = 0, height = 0;  // of the buffer, cells
    std::vector<double> h[2], residual[2], source;
    // Lazy sources (structured/lazy_sources.hpp): per cell, the sub-step of the step
    // after which its stored height h is current; and, per level, the height
    // now (true_h, what faces see) and what its source added since (lag).
    std::vector<double> since[2], true_h, lag;
    std::vector<std::uint8_t> kind;
    std::vector<double> rows;  // scratch rows for faces, transverse slopes and what cells may give
    // With TileLevelParams::record: per cell, the flux its low x (y) face
    // carried over the visit's levels, positive towards the cell; 0 where no level computed it.
    std::vector<double> face_x, face_y;
    std::vector<unsigned> chunk_bits;  // scratch lane bits, per chunk of a row
    // The physics of real scenes, sized only when a grid uses it: the bed,
    // angles and moving flags of the buffer's cells, and the scalar physics
    // kernel's scratch.
    std::vector<double> bed, tan_theta;
    std::vector<std::uint8_t> moving[2];
    std::vector<double> available, applied, x_faces, y_faces;
    void resize(int w, int h_);
    void resize_physics();
};

// Which physics of real scenes a tile kernel carries: none (a plain scene),
// the bed alone (compiled in: the common feature, which must cost little), or
// any of them, as TileLevelParams says at run time.
enum class PhysicsKind { none, bed, any };
inline PhysicsKind physics_kind(const TileLevelParams &p, bool uses_physics) {
    if (!uses_physics) return PhysicsKind::none;
    const bool bed_alone = p.bed && !p.angle_field && !p.hysteresis && p.flux_exponent == 1.0;
    return bed_alone ? PhysicsKind::bed : PhysicsKind::any;
}

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
    const double *h = nullptr;  // with a source: the heights now (TileBuffers::true_h)
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
    // Kernels with a source, which work in the buffer only: the stored
    // heights and what sources added since (lag), the sub-steps after which
    // the stored heights are current, in and out.
    const double *h_stored = nullptr;
    const double *lag = nullptr;
    const double *since = nullptr;
    double *since_out = nullptr;
    // The physics of real scenes (read by kernels with physics): the bed and
    // each cell's tan(theta), read as the heights are, and which cells are
    // moving (hysteresis), read and written as the heights are.
    const double *bed = nullptr, *tan_theta = nullptr;
    const std::uint8_t *moving = nullptr;
    std::uint8_t *moving_out = nullptr;
};

// Slot `in` of the buffer to slot 1 - in (with the buffer's bed, angles and
// moving flags where it has them).
LevelCells buffer_level_cells(TileBuffers &buffers, int in);

// Advances the cells of `region` by one level. `tile` is the part of the
// region whose statistics count; `buffers` gives the scratch rows.
using TileKernel = void (*)(TileBuffers &buffers, const LevelCells &cells, const TileRect &region,
                            const TileRect &tile, const TileLevelParams &params, TileLevelStats &stats);

// The kernel for a tile: masked (walls, sinks or ghosts in reach), isotropic
// or pairwise, with or without a source, reading its residuals from the grid
// or the buffer, writing them to the grid or the buffer (masked kernels and
// kernels with a source: the buffer only), with the physics of real scenes
// it carries. The widest lanes this CPU has.
//
// With a source and without the physics of real scenes, a cell's height
// changes only in a sub-step in which one of its faces carries sand: then it
// takes its source since it was last current (lag) and for this sub-step,
// and becomes current. Elsewhere it keeps its stored height, and what its
// source adds is applied later in closed form (structured/lazy_sources.hpp), so the bits
// of a cell do not depend on which sweeps visit it. With the physics of real
// scenes the source is applied at every sub-step (a bed caps erosion).
TileKernel select_tile_kernel(bool masked, bool isotropic, bool source, bool grid_in = false, bool grid_out = false,
                              PhysicsKind physics = PhysicsKind::none);
// The lanes of the kernels chosen: 8 (AVX-512), 4 (AVX2 and FMA) or 1, the
// widest this CPU has that DPSM_NO_AVX512=1 or DPSM_NO_AVX2=1 does not rule
// out (model/switches.hpp), chosen once per process.
int tile_kernel_lanes();
// Whether the kernels chosen run in AVX-512.
bool tile_kernels_use_avx512();

// The reference kernel of a grid that uses a bed, an angle field, a flux
// exponent or hysteresis (structured/tile_kernel_physics.cpp): plain scalar code, the
// specification of the physics, which the vectorised kernels with physics
// compute to round-off. DPSM_SCALAR_PHYSICS=1 steps such grids with it, for
// every tile (it reads cell kinds always), so that every face of the grid is
// computed by the same arithmetic. It works in the buffer only, from slot
// `in` to slot 1 - in.
using PhysicsTileKernel = void (*)(TileBuffers &buffers, int in, const TileRect &region, const TileRect &tile,
                                   const TileLevelParams &params, TileLevelStats &stats);
PhysicsTileKernel select_physics_tile_kernel(bool isotropic, bool source);

}  // namespace dpsm
