#include "structured/tile_gather.hpp"

#include <algorithm>
#include <cstring>

#include "model/grid.hpp"
#include "structured/halo.hpp"
#include "structured/simd.hpp"

namespace dpsm {

namespace {

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
#endif

}  // namespace

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
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
bool rows_in_avx512() { return false; }
void widen(const float *from, double *to, int count) { convert_row(from, to, count); }
void narrow(const double *from, float *to, int count) { convert_row(from, to, count); }
#endif

namespace {

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

}  // namespace

RowSpan inside_of_row(const Geometry &geo, std::int64_t gi0, std::int64_t j, int width) {
    if (j < 0 || j >= geo.ny) return {width, width};
    const int c0 = static_cast<int>(std::clamp<std::int64_t>(-gi0, 0, width));
    return {c0, static_cast<int>(std::clamp<std::int64_t>(geo.nx - gi0, c0, width))};
}

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

}  // namespace dpsm
