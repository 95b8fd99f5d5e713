// What the 2D sweep and the lazy sources share: copying a tile and the ring
// of cells around it from the grid into a thread's buffers (structured/tile_kernel.hpp),
// the cells beyond the domain as the ghosts of its sides, those beyond a
// distributed block from its halo (structured/halo.hpp); and the rows of
// residuals widened to double and narrowed back.
#pragma once

#include <cstdint>

#include "structured/active_set.hpp"
#include "structured/tile_kernel.hpp"

namespace dpsm {

class Grid;
struct Geometry;
struct HaloStore;

// Whether the rows' conversions (and the lazy sources' row loops) run in
// AVX-512: tested once, on the CPU (not by an ifunc: ifunc resolvers run
// before a sanitizer's runtime and crash it).
bool rows_in_avx512();
// Residuals are float in the grid and double in a tile's buffer; a
// conversion rounds the same way on every CPU.
void widen(const float *from, double *to, int count);
void narrow(const double *from, float *to, int count);

// The columns [c0, c1) of a buffer row (of `width` cells from grid column gi0,
// at grid row j) that lie inside the grid: none (c0 = c1 = width) off its rows.
struct RowSpan {
    int c0, c1;
};
RowSpan inside_of_row(const Geometry &geo, std::int64_t gi0, std::int64_t j, int width);

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
            bool source, const CellBox &sources, bool residuals);

// Copies what kernels with physics read besides heights into the buffer:
// the bed and angles (those the grid has) and, with `moving_flags`, which
// cells are moving (hysteresis); ghost cells are never moving and have no
// bed or angle. On a block of a distributed grid, the cells beyond the block
// that lie in the global domain come from the halo store.
void gather_physics(const Grid &grid, const HaloStore *halo, TileBuffers &b, std::int64_t gi0, std::int64_t gj0,
                    bool moving_flags);

// On a block of a distributed grid, replaces what gather() put in the buffer
// for the cells beyond the block: the neighbours' cells come from the halo
// store, the cells beyond the global domain are ghosts of its sides. The
// block's own cells are left as gather() copied them.
void gather_halo(const Grid &grid, const HaloStore &halo, TileBuffers &b, std::int64_t gi0, std::int64_t gj0,
                 bool masked, bool source);

}  // namespace dpsm
