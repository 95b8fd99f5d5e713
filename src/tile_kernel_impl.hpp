// The tile kernel, written once over a lane type (simd.hpp). Included by
// tile_kernel_generic.cpp and tile_kernel_avx512.cpp, each of which compiles
// it for its own CPU.
//
// One pass over the rows of the region does everything for a row: the
// transverse slopes of the next row, the faces towards it, the faces along
// the row and the row's update. The faces run ahead of the update (the y
// faces one chunk of lanes, the x faces two), so that no update waits on the
// flux law, and a cell's east face is its neighbour chunk's west face moved
// by one lane (a register shuffle, no store and reload); the y faces towards
// the next row wait in a row of scratch for that row. Faces are computed
// once, already scaled to heights per sub-step (nu dt / d), so the update
// adds four numbers. What the level did (motion, the cells touching moving
// faces) is kept as lane bits in integer registers, off the vector units.
//
// Loads read whole vectors, also past the region's last column (the buffer
// has room); those lanes are computed and thrown away: they carry no flux,
// count for nothing and are never stored into the heights.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <utility>

#include "grid.hpp"
#include "simd.hpp"
#include "tile_kernel.hpp"

#if defined(__GNUC__) || defined(__clang__)
// Everything the kernel calls is inlined into it, so its constants and row
// pointers stay in registers rather than behind the lambdas' references.
#define DPSM_KERNEL_FLATTEN __attribute__((flatten))
#else
#define DPSM_KERNEL_FLATTEN
#endif

namespace dpsm {

// GridIn, GridOut: the residuals read from / written to the grid (float), not the buffer.
template <class V, bool Masked, bool Isotropic, bool Source, bool GridIn, bool GridOut>
DPSM_KERNEL_FLATTEN void advance_tile_level(TileBuffers &b, const LevelCells &io, const TileRect &reg,
                                            const TileRect &tile, const TileLevelParams &p, TileLevelStats &st) {
    using M = typename V::Mask;
    constexpr int w = V::width;
    const int W = io.stride, W_out = io.out_stride;
    const double *h = io.h;
    const auto *res = [&] {
        if constexpr (GridIn) return io.residual_grid;
        else return io.residual;
    }();
    double *__restrict h_out = io.h_out;
    auto *__restrict res_out = [&] {
        if constexpr (GridOut) return io.residual_grid_out;
        else return io.residual_out;
    }();
    const std::uint8_t *kind = io.kind;
    const double *q = io.source;
    const int n = reg.c1 - reg.c0;
    const int chunks = (n + w - 1) / w;
    // Rows of scratch, each a vector longer than the region (whole-vector stores).
    const int stride = (chunks + 1) * w;
    double *__restrict tx_lo = b.rows.data();     // transverse slopes of this row
    double *__restrict tx_hi = tx_lo + stride;    // and of the next
    double *__restrict fy_below = tx_hi + stride; // faces from the row below, towards this row
    double *__restrict fy_above = fy_below + stride;
    double *__restrict outflow_row = fy_above + stride;
    // Per chunk, as lane bits: which of its y faces carry sand, below and
    // above the row; which of its lanes are tile cells; which of those
    // touched a moving face in some row.
    unsigned *__restrict carries_below = b.chunk_bits.data();
    unsigned *__restrict carries_above = carries_below + chunks;
    unsigned *__restrict in_tile = carries_above + chunks;
    unsigned *__restrict moved_columns_of = in_tile + chunks;

    const V zero = V::broadcast(0.0);
    // A face's slopes are taken in units of its spacing d (dx for x faces):
    // D = d^2 |grad h|^2 = dh_n^2 + (d grad_t h)^2 needs no division by d,
    // and with it the flux in height per sub-step is
    //   nu dt / d^2 * dh_n (|grad h| - tan(theta)) / (|grad h| sqrt(1 + |grad h|^2))
    //   = (nu dt / d) * dh_n * (1 - d tan(theta) / sqrt(D)) / sqrt(d^2 + D).
    struct Direction {
        V tan_d, threshold2, spacing2, scale;  // d tan(theta), (d tan(theta) (1 + tol))^2, d^2, nu dt / d
        V transverse;                          // a central difference across, to d times a face's transverse slope
        V steepest2;                           // largest D of a face that carries sand
    };
    auto direction = [&](double d, double d_across) {
        const double threshold = p.tan_theta * p.rest_factor * d;
        return Direction{V::broadcast(p.tan_theta * d), V::broadcast(threshold * threshold), V::broadcast(d * d),
                         V::broadcast(p.nu * p.dt / d), V::broadcast(0.25 * d / d_across), zero};
    };
    Direction along_x = direction(p.dx, p.dy), along_y = direction(p.dy, p.dx);
    const V dt = V::broadcast(p.dt);
    const bool track_excess = p.track_excess;

    auto valid_lanes = [&](int count) { return V::first_lanes(count); };
    // A wall neighbour mirrors the cell that asks (zero normal gradient).
    auto mirrored = [&](V h_cell, V h_next, int next) {
        if constexpr (Masked) return select(V::kind_is(kind + next, kWall), h_cell, h_next);
        return h_next;
    };
    // Open faces: no wall on either side, sand on at least one.
    auto open_face = [&](int a, int b_) {
        if constexpr (Masked)
            return V::but_not(V::either(V::kind_is(kind + a, kSand), V::kind_is(kind + b_, kSand)),
                              V::either(V::kind_is(kind + a, kWall), V::kind_is(kind + b_, kWall)));
        return V::first_lanes(w);
    };
    // The flux law on the full slope (dn the height difference across the
    // face, dt d times the slope along it), positive from the first cell to
    // the second; zero up to the threshold and on faces that are not `open`.
    // 1 - d tan(theta) / sqrt(D) cancels near the threshold, so 1/sqrt(D) is
    // refined to full precision; 1/sqrt(d^2 + D) only scales the flux and takes
    // the cheaper refinement. Lanes at or below the threshold may compute
    // infinities or NaN (1/sqrt(0)); they are masked out. `carries` tells the
    // faces whose flux is not zero (even where the scaled flux is too small to
    // change a height: a tiny dt).
    auto face_flux = [&](V dn, V dt_, M open, Direction &d, M &carries) {
        const V D = fma(dn, dn, dt_ * dt_);
        const M hot = V::both(D > d.threshold2, open);
        const V flux = mul_where(hot, dn * fnma(d.tan_d, rsqrt(D), V::broadcast(1.0)), rsqrt_fast(d.spacing2 + D));
        carries = flux != zero;
        // Only faces that carry sand count: a face that is steep only across
        // its normal (dn = 0) carries none, and a tile at rest is not visited,
        // so counting it would make the figure depend on the active set.
        if (track_excess) d.steepest2 = max_where(carries, d.steepest2, D);
        return flux * d.scale;
    };
    // Central differences along x at cells c .. c + w - 1, scaled for the y faces.
    auto slopes_along_x = [&](int c) {
        const V hc = V::load(h + c);
        return (mirrored(hc, V::load(h + c + 1), c + 1) - mirrored(hc, V::load(h + c - 1), c - 1)) *
               along_y.transverse;
    };
    auto slopes_along_y = [&](int c) {
        const V hc = V::load(h + c);
        return (mirrored(hc, V::load(h + c + W), c + W) - mirrored(hc, V::load(h + c - W), c - W)) *
               along_x.transverse;
    };
    // The faces between cells c and c + W, given the transverse slopes of both rows.
    auto faces_along_y = [&](int c, V tx_here, V tx_next, M valid, M &carries) {
        const V dn = V::load(h + c) - V::load(h + c + W);
        const V dt_ = Isotropic ? tx_here + tx_next : zero;
        return face_flux(dn, dt_, V::both(valid, open_face(c, c + W)), along_y, carries);
    };
    // The faces between cells c - 1 and c, given the transverse slopes of both columns.
    auto faces_along_x = [&](int c, V ty_west, V ty_here, M valid, M &carries) {
        const V dn = V::load(h + c - 1) - V::load(h + c);
        const V dt_ = Isotropic ? ty_west + ty_here : zero;
        return face_flux(dn, dt_, V::both(valid, open_face(c - 1, c)), along_x, carries);
    };

    // The y faces between the first row and the one below it.
    for (int j = 0; j < chunks; ++j) {
        const int c = (reg.r0 - 1) * W + reg.c0 + j * w;
        V tx_below = zero, tx_first = zero;
        if constexpr (Isotropic) {
            tx_below = slopes_along_x(c);
            tx_first = slopes_along_x(c + W);
            tx_first.store(tx_lo + j * w);
        }
        M carries;
        faces_along_y(c, tx_below, tx_first, valid_lanes(n - j * w), carries).store(fy_below + j * w);
        carries_below[j] = V::bits(carries);
    }
    for (int j = 0; j < chunks; ++j) {
        const int col = reg.c0 + j * w;
        in_tile[j] = V::bits(V::but_not(V::first_lanes(tile.c1 - col), V::first_lanes(tile.c0 - col)));
        moved_columns_of[j] = 0;
    }

    unsigned moved = 0;  // lanes of cells that moved, anywhere in the region
    int moved_r0 = st.hot_r0, moved_r1 = st.hot_r1;
    double outflow = 0.0;

    for (int r = reg.r0; r < reg.r1; ++r) {
        const int row = r * W + reg.c0, row_out = (r - io.out_row0) * W_out + reg.c0 - io.out_col0;
        // Rows straight from or into the grid are far from this core's caches;
        // asked for a few rows ahead, they arrive while this row computes.
        if constexpr (GridIn) {
            if (r + kRowsAhead <= reg.r1) {
                const int ahead = row + kRowsAhead * W - 1;  // a row as the faces read it: c0 - 1 .. c1
                simd::prefetch<false>(h + ahead, n + 2);
                simd::prefetch<false>(res + ahead, n + 2);
                if constexpr (Source) simd::prefetch<false>(q + ahead, n + 2);
            }
        }
        if constexpr (GridOut) {
            if (r + kRowsAhead < reg.r1) {
                simd::prefetch<true>(h_out + row_out + kRowsAhead * W_out, n);
                simd::prefetch<true>(res_out + row_out + kRowsAhead * W_out, n);
            }
        }
        const bool row_in_tile = r >= tile.r0 && r < tile.r1;
        unsigned row_hot = 0;
        // Software-pipelined: iteration j updates chunk j from faces found in
        // the iterations before (its y faces in j - 1, its x faces in j - 2
        // and j - 1) while it finds the y faces of chunk j + 1 and the x faces
        // of chunk j + 2, so that no update waits on the long chains of the
        // flux law (dpsm-bench throughput: about 5 % faster than finding a
        // chunk's faces in the iteration that updates it).
        auto y_faces_of = [&](int j, unsigned &bits) {
            const int c = row + j * w, k = j * w;
            V tx_next = zero;
            if constexpr (Isotropic) {
                tx_next = slopes_along_x(c + W);
                tx_next.store(tx_hi + k);
            }
            M carries;
            const V f = faces_along_y(c, V::load(tx_lo + k), tx_next, valid_lanes(n - k), carries);
            f.store(fy_above + k);
            bits = V::bits(carries);
            carries_above[j] = bits;
            return f;
        };
        // The x faces west of chunk j's cells, given the transverse slopes of
        // the cells before them and of the chunk itself.
        auto x_faces_of = [&](int j, V ty_west, V ty_here, unsigned &bits) {
            M carries;
            const V f = faces_along_x(row + j * w, ty_west, ty_here, valid_lanes(n + 1 - j * w), carries);
            bits = V::bits(carries);
            return f;
        };
        // The x faces are needed up to the east face of the last cell: a chunk
        // further when the last chunk is full.
        const int x_chunks = chunks + (n % w == 0 ? 1 : 0);
        unsigned north_bits_next = 0, x0_bits = 0, x1_bits = 0;
        V f_north_next = y_faces_of(0, north_bits_next);
        V ty_last = Isotropic ? slopes_along_y(row) : zero;  // of the last chunk whose x faces are found
        V x0 = x_faces_of(0, Isotropic ? slopes_along_y(row - 1) : zero, ty_last, x0_bits), x1 = zero;
        auto next_x_faces = [&](int j, V &faces, unsigned &bits) {
            const V ty = Isotropic ? slopes_along_y(row + j * w) : zero;
            faces = x_faces_of(j, V::shift_west(ty_last, ty), ty, bits);
            ty_last = ty;
        };
        if (x_chunks > 1) next_x_faces(1, x1, x1_bits);
        for (int j = 0; j < chunks; ++j) {
            const int c = row + j * w, k = j * w;
            const M valid = valid_lanes(n - k);
            const V f_north = f_north_next, f_west = x0, f_east = V::shift_east(x0, x1);
            const unsigned north_bits = north_bits_next, west_bits = x0_bits;
            const unsigned east_bits = (x0_bits >> 1) | (x1_bits << (w - 1));
            // The faces of the chunks ahead.
            if (j + 1 < chunks) f_north_next = y_faces_of(j + 1, north_bits_next);
            x0 = x1;
            x0_bits = x1_bits;
            x1 = zero;
            x1_bits = 0;
            if (j + 2 < x_chunks) next_x_faces(j + 2, x1, x1_bits);
            const V f_south = V::load(fy_below + k);

            // The update: h + increment as a TwoSum, carrying what rounding drops.
            const V hc = V::load(h + c);
            V increment = (f_west - f_east) + (f_south - f_north);
            if constexpr (Source) increment = fma(V::load(q + c), dt, increment);
            M sand = valid;
            if constexpr (Masked) sand = V::both(valid, V::kind_is(kind + c, kSand));
            // Cells that do not move keep height and residual bit for bit, as
            // they would in a tile that is not visited.
            const M changes = V::both(sand, increment != zero);
            V sum;
            if (p.residuals) {
                const V rc = V::load(res + c);
                const V b_ = increment + rc;
                sum = hc + b_;
                const V b_virtual = sum - hc;
                const V err = (hc - (sum - b_virtual)) + (b_ - b_virtual);
                select(changes, err, rc).store_where(res_out + row_out + k, valid);
            } else {
                sum = hc + increment;
            }
            select(changes, sum, hc).store_where(h_out + row_out + k, valid);

            // Motion is sand carried by a face, even where an increment is too
            // small to change a height (a tiny dt): such a cell stays hot.
            const unsigned hot =
                (V::bits(changes) | west_bits | east_bits | carries_below[j] | north_bits) & V::bits(valid);
            moved |= hot;
            if (row_in_tile) {
                const unsigned hot_in_tile = hot & in_tile[j];
                moved_columns_of[j] |= hot_in_tile;
                row_hot |= hot_in_tile;
            }
            if constexpr (Masked) {
                // Sand that this tile's cells send into sinks (open cells and
                // the outside of open sides); what sinks feed them counts negative.
                if (row_in_tile) {
                    const V east = select(V::kind_is(kind + c + 1, kOpen), f_east, zero);
                    const V west = select(V::kind_is(kind + c - 1, kOpen), f_west, zero);
                    const V north = select(V::kind_is(kind + c + W, kOpen), f_north, zero);
                    const V south = select(V::kind_is(kind + c - W, kOpen), f_south, zero);
                    const M counted = V::both(sand, V::from_bits(in_tile[j]));
                    select(counted, (east - west) + (north - south), zero).store(outflow_row + k);
                }
            }
        }
        if (row_hot) {
            moved_r0 = std::min(moved_r0, r);
            moved_r1 = std::max(moved_r1, r + 1);
        }
        if constexpr (Masked) {
            // Each cell's outflow summed one by one in column order and row by
            // row, so that the sum does not depend on where the computed region
            // starts (lanes would group the cells by it): a tile visited whole
            // or in part, or after a restart, books the same outflow.
            if (row_in_tile)
                for (int k = 0; k < n; ++k) outflow += outflow_row[k];
        }
        std::swap(tx_lo, tx_hi);
        std::swap(fy_below, fy_above);
        std::swap(carries_below, carries_above);
    }

    std::uint64_t moved_columns = 0;  // as bits from tile.c0
    for (int j = 0; j < chunks; ++j) {
        const std::uint64_t bits = moved_columns_of[j];  // tile lanes only, so the shift stays below 64
        if (bits == 0) continue;
        const int shift = reg.c0 + j * w - tile.c0;
        moved_columns |= shift >= 0 ? bits << shift : bits >> -shift;
    }
    if (moved_columns) {
        st.hot_r0 = moved_r0;
        st.hot_r1 = moved_r1;
        st.hot_c0 = std::min(st.hot_c0, tile.c0 + __builtin_ctzll(moved_columns));
        st.hot_c1 = std::max(st.hot_c1, tile.c0 + 64 - __builtin_clzll(moved_columns));
    }
    st.moved = st.moved || moved != 0;
    const double steepest =
        std::max(std::sqrt(V::hmax(along_x.steepest2)) * p.inv_dx, std::sqrt(V::hmax(along_y.steepest2)) * p.inv_dy);
    if (steepest > 0.0) st.max_excess = std::max(st.max_excess, steepest - p.tan_theta);
    // The outflow in heights per sub-step, as mass per unit time.
    st.outflow_rate += outflow * (p.cell_area / p.dt);
}

template <class V>
TileKernel tile_kernel_for(bool masked, bool isotropic, bool source, bool grid_in, bool grid_out) {
    // Masked kernels read the buffer only (tile_kernel.hpp).
    auto choose = [&](auto masked_, auto isotropic_, auto source_) -> TileKernel {
        constexpr bool Mk = decltype(masked_)::value, I = decltype(isotropic_)::value, S = decltype(source_)::value;
        if constexpr (!Mk) {
            if (grid_in)
                return grid_out ? advance_tile_level<V, false, I, S, true, true>
                                : advance_tile_level<V, false, I, S, true, false>;
        }
        return grid_out ? advance_tile_level<V, Mk, I, S, false, true> : advance_tile_level<V, Mk, I, S, false, false>;
    };
    using yes = std::true_type;
    using no = std::false_type;
    if (masked) {
        if (isotropic) return source ? choose(yes{}, yes{}, yes{}) : choose(yes{}, yes{}, no{});
        return source ? choose(yes{}, no{}, yes{}) : choose(yes{}, no{}, no{});
    }
    if (isotropic) return source ? choose(no{}, yes{}, yes{}) : choose(no{}, yes{}, no{});
    return source ? choose(no{}, no{}, yes{}) : choose(no{}, no{}, no{});
}

}  // namespace dpsm
