// The tile kernel, written once over a lane type (simd.hpp). Included by
// tile_kernel_generic.cpp and tile_kernel_avx512.cpp, each of which compiles
// it for its own CPU.
#pragma once

#include <algorithm>
#include <cmath>
#include <utility>

#include "grid.hpp"
#include "simd.hpp"
#include "tile_kernel.hpp"

namespace dpsm {

template <class V, bool Masked, bool Isotropic, bool Source>
void advance_tile_level(TileBuffers &b, int in, const TileRect &reg, const TileRect &tile, const TileLevelParams &p,
                        TileLevelStats &st) {
    using M = typename V::Mask;
    constexpr int w = V::width;
    const int W = b.width;
    const double *h = b.h[in].data();
    const double *res = b.residual[in].data();
    double *h_out = b.h[1 - in].data();
    double *res_out = b.residual[1 - in].data();
    const std::uint8_t *kind = b.kind.data();
    const double *q = b.source.data();
    const int n = reg.c1 - reg.c0;
    const int stride = ((n + 2) / w + 2) * w;
    double *__restrict ty = b.rows.data();
    double *__restrict fx = ty + stride;
    double *fy_below = fx + stride, *fy_above = fy_below + stride;
    double *tx_lo = fy_above + stride, *tx_hi = tx_lo + stride;
    // Masked tiles: each cell's outflow rate of the row, summed one by one in
    // column order and row by row, so that the sum does not depend on where
    // the computed region starts (lanes would group the cells by it): a tile
    // visited whole or in part, or after a restart, books the same outflow.
    double *outflow_row = tx_hi + stride;
    double outflow = 0.0;

    const V zero = V::broadcast(0.0), one = V::broadcast(1.0), half = V::broadcast(0.5);
    const V nu = V::broadcast(p.nu), tan_theta = V::broadcast(p.tan_theta), threshold2 = V::broadcast(p.threshold2);
    const V inv_dx = V::broadcast(p.inv_dx), inv_dy = V::broadcast(p.inv_dy);
    const V half_inv_dx = V::broadcast(p.half_inv_dx), half_inv_dy = V::broadcast(p.half_inv_dy);
    const V dt = V::broadcast(p.dt);
    const V x_len = V::broadcast(p.x_face_length), y_len = V::broadcast(p.y_face_length);
    const M all = V::first_lanes(w);
    V steepest2 = zero;  // largest squared slope of a face that carries sand
    M moved = V::first_lanes(0);
    // The tile's cells that moved: rows, and columns as bits from tile.c0.
    int moved_r0 = st.hot_r0, moved_r1 = st.hot_r1;
    std::uint64_t moved_columns = 0;

    auto load = [](const double *ptr, int m) { return m == w ? V::load(ptr) : V::load_partial(ptr, m); };
    auto store = [](double *ptr, V v, int m) {
        if (m == w)
            v.store(ptr);
        else
            v.store_partial(ptr, m);
    };
    // A wall neighbour mirrors the cell that asks (zero normal gradient).
    auto mirrored = [&](V h_cell, V h_next, const std::uint8_t *kind_next) {
        if constexpr (Masked) return select(V::kind_is(kind_next, kWall), h_cell, h_next);
        return h_next;
    };
    // Open faces: no wall on either side, sand on at least one.
    auto open_face = [&](const std::uint8_t *ka, const std::uint8_t *kb) {
        if constexpr (Masked)
            return V::but_not(V::either(V::kind_is(ka, kSand), V::kind_is(kb, kSand)),
                              V::either(V::kind_is(ka, kWall), V::kind_is(kb, kWall)));
        return all;
    };
    // The flux law on the full slope (gn along the face normal, gt across),
    // positive from the first cell to the second; zero up to the threshold.
    // 1 - tan(theta) / |g| cancels near the threshold, so 1/|g| is refined to
    // full precision; 1/sqrt(1 + |g|^2) only scales the flux and takes the
    // cheaper refinement.
    auto face_flux = [&](V gn, V gt, M open, double *flux_out, int m) {
        const V u = gn * gn + gt * gt;
        const M hot = V::both(u > threshold2, open);
        const V r1 = rsqrt(max(u, threshold2));
        const V r2 = rsqrt_fast(one + u);
        const V flux = select(hot, nu * gn * (one - tan_theta * r1) * r2, zero);
        // Only faces that carry sand count: a face that is steep only across
        // its normal (gn = 0) carries none, and a tile at rest is not visited,
        // so counting it would make the figure depend on the active set.
        steepest2 = max(steepest2, select(flux != zero, u, zero));
        store(flux_out, flux, m);
    };
    // Central differences along x of row r, for the faces across it.
    auto slopes_along_x = [&](int r, double *out) {
        for (int k = 0; k < n; k += w) {
            const int m = std::min(w, n - k), c = r * W + reg.c0 + k;
            const V hc = load(h + c, m);
            const V east = mirrored(hc, load(h + c + 1, m), kind + c + 1);
            const V west = mirrored(hc, load(h + c - 1, m), kind + c - 1);
            store(out + k, (east - west) * half_inv_dx, m);
        }
    };
    // Faces between rows r and r + 1.
    auto faces_along_y = [&](int r, const double *tx_r, const double *tx_r1, double *flux_out) {
        for (int k = 0; k < n; k += w) {
            const int m = std::min(w, n - k), c = r * W + reg.c0 + k;
            const V gn = (load(h + c, m) - load(h + c + W, m)) * inv_dy;
            const V gt = Isotropic ? half * (load(tx_r + k, m) + load(tx_r1 + k, m)) : zero;
            face_flux(gn, gt, open_face(kind + c, kind + c + W), flux_out + k, m);
        }
    };

    if constexpr (Isotropic) {
        slopes_along_x(reg.r0 - 1, tx_lo);
        slopes_along_x(reg.r0, tx_hi);
    }
    faces_along_y(reg.r0 - 1, tx_lo, tx_hi, fy_below);

    for (int r = reg.r0; r < reg.r1; ++r) {
        const int row = r * W;
        if constexpr (Isotropic) {
            std::swap(tx_lo, tx_hi);
            slopes_along_x(r + 1, tx_hi);
        }
        faces_along_y(r, tx_lo, tx_hi, fy_above);

        // Faces between columns c - 1 and c of row r, c = c0 .. c1.
        if constexpr (Isotropic) {
            for (int t = 0; t < n + 2; t += w) {
                const int m = std::min(w, n + 2 - t), c = row + reg.c0 - 1 + t;
                const V hc = load(h + c, m);
                const V north = mirrored(hc, load(h + c + W, m), kind + c + W);
                const V south = mirrored(hc, load(h + c - W, m), kind + c - W);
                store(ty + t, (north - south) * half_inv_dy, m);
            }
        }
        for (int k = 0; k < n + 1; k += w) {
            const int m = std::min(w, n + 1 - k), c = row + reg.c0 - 1 + k;
            const V gn = (load(h + c, m) - load(h + c + 1, m)) * inv_dx;
            const V gt = Isotropic ? half * (load(ty + k, m) + load(ty + k + 1, m)) : zero;
            face_flux(gn, gt, open_face(kind + c, kind + c + 1), fx + k, m);
        }

        const bool row_in_tile = r >= tile.r0 && r < tile.r1;
        for (int k = 0; k < n; k += w) {
            const int m = std::min(w, n - k), col = reg.c0 + k, c = row + col;
            const V hc = load(h + c, m), rc = p.residuals ? load(res + c, m) : zero;
            const V f_west = load(fx + k, m), f_east = load(fx + k + 1, m);
            const V f_south = load(fy_below + k, m), f_north = load(fy_above + k, m);
            V increment = ((f_west - f_east) * inv_dx + (f_south - f_north) * inv_dy) * dt;
            if constexpr (Source) increment = increment + load(q + c, m) * dt;
            // h + increment as a TwoSum, carrying what rounding drops.
            const V b_ = increment + rc;
            V sum = hc + b_;
            // Cells that do not move keep height and residual bit for bit, as
            // they would in a tile that is not visited.
            M sand = all;
            if constexpr (Masked) sand = V::kind_is(kind + c, kSand);
            const M changes = V::both(sand, increment != zero);
            if (p.residuals) {
                const V b_virtual = sum - hc;
                const V err = (hc - (sum - b_virtual)) + (b_ - b_virtual);
                store(res_out + c, select(changes, err, rc), m);
            }
            sum = select(changes, sum, hc);
            store(h_out + c, sum, m);

            // Motion is sand carried by a face, even where an increment is too
            // small to change a height (a tiny dt): such a cell stays hot.
            const M carried = V::any_nonzero(f_west, f_east, f_south, f_north);
            moved = V::either(moved, V::either(changes, carried));
            if (!row_in_tile) continue;
            const M in_tile =
                V::both(V::but_not(V::first_lanes(tile.c1 - col), V::first_lanes(tile.c0 - col)), V::first_lanes(m));
            const M hot = V::both(V::either(changes, carried), in_tile);
            if (V::any(hot)) {
                moved_r0 = std::min(moved_r0, r);
                moved_r1 = std::max(moved_r1, r + 1);
                const int shift = col - tile.c0;
                const std::uint64_t bits = static_cast<std::uint64_t>(hot);
                moved_columns |= shift >= 0 ? bits << shift : bits >> -shift;
            }
            if constexpr (Masked) {
                // Sand that this tile's cells send into sinks (open cells and
                // the outside of open sides); what sinks feed them counts negative.
                const V east = select(V::kind_is(kind + c + 1, kOpen), f_east, zero);
                const V west = select(V::kind_is(kind + c - 1, kOpen), f_west, zero);
                const V north = select(V::kind_is(kind + c + W, kOpen), f_north, zero);
                const V south = select(V::kind_is(kind + c - W, kOpen), f_south, zero);
                const V rate = (east - west) * x_len + (north - south) * y_len;
                store(outflow_row + k, select(V::both(sand, in_tile), rate, zero), m);
            }
        }
        if constexpr (Masked) {
            if (row_in_tile)
                for (int k = 0; k < n; ++k) outflow += outflow_row[k];
        }
        std::swap(fy_below, fy_above);
    }
    if (moved_columns) {
        st.hot_r0 = moved_r0;
        st.hot_r1 = moved_r1;
        st.hot_c0 = std::min(st.hot_c0, tile.c0 + __builtin_ctzll(moved_columns));
        st.hot_c1 = std::max(st.hot_c1, tile.c0 + 64 - __builtin_clzll(moved_columns));
    }
    st.moved = st.moved || V::any(moved);
    const double steepest = std::sqrt(V::hmax(steepest2));
    if (steepest > 0.0) st.max_excess = std::max(st.max_excess, steepest - p.tan_theta);
    st.outflow_rate += outflow;
}

template <class V>
TileLevelFunction tile_kernel_for(bool masked, bool isotropic, bool source) {
    const int which = (masked ? 4 : 0) + (isotropic ? 2 : 0) + (source ? 1 : 0);
    switch (which) {
        case 0: return advance_tile_level<V, false, false, false>;
        case 1: return advance_tile_level<V, false, false, true>;
        case 2: return advance_tile_level<V, false, true, false>;
        case 3: return advance_tile_level<V, false, true, true>;
        case 4: return advance_tile_level<V, true, false, false>;
        case 5: return advance_tile_level<V, true, false, true>;
        case 6: return advance_tile_level<V, true, true, false>;
        default: return advance_tile_level<V, true, true, true>;
    }
}

}  // namespace dpsm
