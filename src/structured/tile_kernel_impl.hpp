// The tile kernel, written once over a lane type (structured/simd.hpp). Included by
// structured/tile_kernel_generic.cpp, structured/tile_kernel_avx2.cpp and structured/tile_kernel_avx512.cpp,
// each of which compiles it for its own CPU.
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
//
// Kernels with physics carry the physics of real scenes in the same pass, as
// structured/tile_kernel_physics.cpp (the specification) does in three: a face's own
// angle from its cells' (angle field) and, between two cells at rest, the
// static angle's threshold (hysteresis); the flux exponent; the bed, which
// caps a face at a quarter of what its upstream sand cell may give (its sand
// above the bed after its own erosion, none within the film), found once for
// each cell, with the y faces towards its row, and kept in a row of scratch
// for its x faces and its y faces towards the next row; and lifts a drained
// cell that rounding left below it. Which of them a kernel carries is its PhysicsKind
// (structured/tile_kernel.hpp): none (the plain scene's kernels, free of them all), the
// bed alone (compiled in), or any, each a runtime flag, the same for every
// face of a sweep, so that each branch on one always goes the same way.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>

#include "model/face_law.hpp"
#include "model/grid.hpp"
#include "structured/simd.hpp"
#include "structured/tile_kernel.hpp"

#if defined(__GNUC__) || defined(__clang__)
// Everything the kernel calls is inlined into it, so its constants and row
// pointers stay in registers rather than behind the lambdas' references.
#define DPSM_KERNEL_FLATTEN __attribute__((flatten))
#else
#define DPSM_KERNEL_FLATTEN
#endif

namespace dpsm {

// How a kernel with physics raises the excess slope to the flux exponent p:
// its law is the one for p = 1, multiplied on the faces that flow by the
// excess to the power p - 1: itself (p = 2), its square root (p = 3/2), or
// else simd::power (exp and log in lanes, to a few units in the last place).
enum class ExponentKind { one, three_halves, two, other };
inline ExponentKind exponent_kind(double p) {
    if (p == 1.0) return ExponentKind::one;
    if (p == 1.5) return ExponentKind::three_halves;
    return p == 2.0 ? ExponentKind::two : ExponentKind::other;
}

// GridIn, GridOut: the residuals read from / written to the grid (float), not the buffer.
// Physics: which physics of real scenes (a bed, an angle field, a flux exponent, hysteresis) it carries.
template <class V, bool Masked, bool Isotropic, bool Source, bool GridIn, bool GridOut, PhysicsKind Physics>
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
    double *__restrict outside_rows[4];  // per side: what each cell of the row sends out through it
    for (int side = 0; side < 4; ++side) outside_rows[side] = outflow_row + (side + 1) * stride;
    double *__restrict face_x = p.record ? b.face_x.data() : nullptr;
    double *__restrict face_y = p.record ? b.face_y.data() : nullptr;
    // With a bed and a source, what the source put on this row's tile cells
    // and the erosion there that found no sand.
    double *__restrict sourced_row = outside_rows[3] + stride;
    double *__restrict unmet_row = sourced_row + stride;
    // With a bed, what the cells of this row and of the next may give their
    // faces, from the column before the region's (element -1) on.
    double *__restrict available_lo = unmet_row + stride + w;
    double *__restrict available_hi = available_lo + stride;
    // Per chunk, as lane bits: which of its y faces carry sand, below and
    // above the row; which of its lanes are tile cells; which of those
    // touched a moving face in some row.
    unsigned *__restrict carries_below = b.chunk_bits.data();
    unsigned *__restrict carries_above = carries_below + chunks;
    unsigned *__restrict in_tile = carries_above + chunks;
    unsigned *__restrict moved_columns_of = in_tile + chunks;

    const V zero = V::broadcast(0.0);
    // The physics of real scenes this grid uses: the same for every tile.
    constexpr bool plain = Physics == PhysicsKind::none, any = Physics == PhysicsKind::any;
    const bool bed = Physics == PhysicsKind::bed || (any && p.bed);
    const bool angle_field = any && p.angle_field, hysteresis = any && p.hysteresis;
    const ExponentKind exponent = any ? exponent_kind(p.flux_exponent) : ExponentKind::one;
    const double *zb = io.bed, *tan_cell = io.tan_theta;
    const std::uint8_t *moving = io.moving;
    std::uint8_t *__restrict moving_out = io.moving_out;
    // A face's slopes are taken in units of its spacing d (dx for x faces):
    // D = d^2 |grad h|^2 = dh_n^2 + (d grad_t h)^2 needs no division by d,
    // and with it the flux in height per sub-step is
    //   nu dt / d^2 * dh_n (|grad h| - tan(theta)) / (|grad h| sqrt(1 + |grad h|^2))
    //   = (nu dt / d) * dh_n * (1 - d tan(theta) / sqrt(D)) / sqrt(d^2 + D).
    struct Direction {
        V tan_d, threshold2, spacing2, scale;  // d tan(theta), (d tan(theta) (1 + tol))^2, d^2, nu dt / d
        V transverse;                          // a central difference across, to d times a face's transverse slope
        V steepest2;                           // largest D of a face that carries sand
        // With physics:
        V spacing, inverse_spacing;  // d, 1 / d
        V rest_spacing;              // d (1 + tol): a face's tan(theta) to d times its threshold
        V static_spacing;            // d tan(static angle)
        V threshold2_at_rest;        // uniform angle: threshold2 between two cells at rest (hysteresis)
        V most_per_sand;             // d / (4 nu dt): a cell's available sand to the most flux a face takes from it
        V least_per_sand;            // - most_per_sand: the same towards the cell
        V largest_excess;            // largest d (|grad h| - tan(theta)) of a face that carries sand
    };
    auto direction = [&](double d, double d_across) {
        const double threshold = p.tan_theta * p.rest_factor * d;
        const double at_rest = law::threshold(p.tan_theta * p.rest_factor, true, p.tan_static) * d;
        const double scale = p.nu * p.dt / d;
        return Direction{V::broadcast(p.tan_theta * d), V::broadcast(threshold * threshold), V::broadcast(d * d),
                         V::broadcast(scale), V::broadcast(0.25 * d / d_across), zero, V::broadcast(d),
                         V::broadcast(1.0 / d), V::broadcast(p.rest_factor * d), V::broadcast(p.tan_static * d),
                         V::broadcast(at_rest * at_rest), V::broadcast(1.0 / (kFacesPerCell * scale)),
                         V::broadcast(-1.0 / (kFacesPerCell * scale)), zero};
    };
    Direction along_x = direction(p.dx, p.dy), along_y = direction(p.dy, p.dx);
    const V dt = V::broadcast(p.dt);
    const V substep_done = V::broadcast(p.substep + 1.0);
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
    // The cells of a face (a before b), with physics: their indices, their
    // heights and (bed) the sand each may give.
    struct FaceCells {
        int a, b;
        V h_a, h_b, available_a, available_b;
    };
    // A face's own d tan(theta) and threshold2 with an angle field or
    // hysteresis: its angle is the mean of its cells' (the sand cell's where
    // one is not sand), its threshold between two cells at rest the static
    // angle's where that is steeper.
    auto face_law = [&](const FaceCells &f, const Direction &d, V &tan_d, V &threshold2) {
        M at_rest{};
        if (hysteresis) at_rest = V::both(V::kind_is(moving + f.a, 0), V::kind_is(moving + f.b, 0));
        if (!angle_field) {
            threshold2 = select(at_rest, d.threshold2_at_rest, d.threshold2);
            return;
        }
        const V tan_a = V::load(tan_cell + f.a), tan_b = V::load(tan_cell + f.b);
        V tan_face;
        if constexpr (Masked)
            tan_face = law::face_tan(tan_a, tan_b, V::kind_is(kind + f.a, kSand), V::kind_is(kind + f.b, kSand));
        else
            tan_face = law::mean_tan(tan_a, tan_b);
        V threshold = tan_face * d.rest_spacing;
        if (hysteresis) threshold = law::threshold(threshold, at_rest, d.static_spacing);
        tan_d = tan_face * d.spacing;
        threshold2 = threshold * threshold;
    };
    // The flux times the excess slope (>= 0) to the power p - 1, on the
    // faces `flowing`. An excess below the smallest normal number is raised
    // as that number (a flux of that excess is far below any height's ulp).
    auto raised = [&](V flux, V excess, M flowing) {
        if (exponent == ExponentKind::two) return mul_where(flowing, flux, excess);
        if (exponent == ExponentKind::three_halves) return mul_where(flowing, flux, sqrt(excess));
        const V normal_excess = max(excess, V::broadcast(std::numeric_limits<double>::min()));
        return mul_where(flowing, flux, simd::power(normal_excess, V::broadcast(p.flux_exponent - 1.0)));
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
    //
    // With physics, the face's own law (face_law); on the isotropic scheme
    // nothing across a face whose cells are level within the rounding of
    // their heights; the flux exponent; and the bed's cap, which leaves a
    // face that takes from a cell with nothing to give carrying nothing.
    auto face_flux = [&](V dn, V dt_, M open, Direction &d, M &carries, const FaceCells &f) {
        const V D = fma(dn, dn, dt_ * dt_);
        if constexpr (plain) {
            (void)f;
            const M hot = V::both(D > d.threshold2, open);
            const V flux = mul_where(hot, dn * fnma(d.tan_d, rsqrt(D), V::broadcast(1.0)), rsqrt_fast(d.spacing2 + D));
            carries = flux != zero;
            // Only faces that carry sand count: a face that is steep only across
            // its normal (dn = 0) carries none, and a tile at rest is not visited,
            // so counting it would make the figure depend on the active set.
            if (track_excess) d.steepest2 = max_where(carries, d.steepest2, D);
            return flux * d.scale;
        } else {
            V tan_d = d.tan_d, threshold2 = d.threshold2;
            if (angle_field || hysteresis) face_law(f, d, tan_d, threshold2);
            M hot = V::both(D > threshold2, open);
            if constexpr (Isotropic)
                hot = V::greater_where(hot, abs(dn), max_magnitude(f.h_a, f.h_b) * V::broadcast(kLevelWithinRounding));
            const V inverse = rsqrt(D);
            V flux = mul_where(hot, dn * fnma(tan_d, inverse, V::broadcast(1.0)), rsqrt_fast(d.spacing2 + D));
            // sqrt(D) - d tan(theta): 0 where the lanes computed 1/sqrt(0).
            auto excess = [&] { return max(D * inverse - tan_d, zero); };
            if (exponent != ExponentKind::one) flux = raised(flux, excess() * d.inverse_spacing, hot);
            if (bed) flux = law::capped(flux, f.available_a * d.most_per_sand, f.available_b * d.least_per_sand);
            carries = flux != zero;
            if (track_excess) d.largest_excess = max_where(carries, d.largest_excess, excess());
            return flux * d.scale;
        }
    };
    // The source a sand cell receives this sub-step: erosion takes at most its sand above the bed.
    auto applied = [&](int c, V sand) { return max(V::load(q + c) * dt, zero - sand); };
    // The sand cell c may give its faces with a bed: what it has above the
    // bed after its own erosion, none if no more than the film (a face takes
    // at most its share of it); no limit from a cell that is not sand.
    // (Without a source, h - zb above the film is the sand itself.)
    auto available = [&](int c) {
        V left = V::load(h + c) - V::load(zb + c);
        if constexpr (Source) {
            const V sand = max(left, zero);
            left = sand + min(zero, applied(c, sand));
        }
        const V sand_given = select(left > V::broadcast(p.bed_film), left, zero);
        if constexpr (Masked) return select(V::kind_is(kind + c, kSand), sand_given, V::broadcast(HUGE_VAL));
        return sand_given;
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
    // The faces between cells c and c + W, given the transverse slopes of
    // both rows and (bed) the sand each cell may give.
    auto faces_along_y = [&](int c, V tx_here, V tx_next, V given_here, V given_next, M valid, M &carries) {
        const V h_here = V::load(h + c), h_next = V::load(h + c + W);
        const V dt_ = Isotropic ? tx_here + tx_next : zero;
        return face_flux(h_here - h_next, dt_, V::both(valid, open_face(c, c + W)), along_y, carries,
                         FaceCells{c, c + W, h_here, h_next, given_here, given_next});
    };
    // The faces between cells c - 1 and c, given the transverse slopes of
    // both columns and (bed) the sand each cell may give.
    auto faces_along_x = [&](int c, V ty_west, V ty_here, V given_west, V given_here, M valid, M &carries) {
        const V h_west = V::load(h + c - 1), h_here = V::load(h + c);
        const V dt_ = Isotropic ? ty_west + ty_here : zero;
        return face_flux(h_west - h_here, dt_, V::both(valid, open_face(c - 1, c)), along_x, carries,
                         FaceCells{c - 1, c, h_west, h_here, given_west, given_here});
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
        V given_below = zero, given_first = zero;
        if (bed) {
            given_below = available(c);
            given_first = available(c + W);
            given_first.store(available_lo + j * w);
        }
        M carries;
        faces_along_y(c, tx_below, tx_first, given_below, given_first, valid_lanes(n - j * w), carries)
            .store(fy_below + j * w);
        carries_below[j] = V::bits(carries);
    }
    for (int j = 0; j < chunks; ++j) {
        const int col = reg.c0 + j * w;
        in_tile[j] = V::bits(V::but_not(V::first_lanes(tile.c1 - col), V::first_lanes(tile.c0 - col)));
        moved_columns_of[j] = 0;
    }

    unsigned moved = 0;  // lanes of cells that moved, anywhere in the region
    int moved_r0 = st.hot_r0, moved_r1 = st.hot_r1;
    double outflow = 0.0, outside[4] = {}, sourced = 0.0, unmet = 0.0;

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
                if (bed) simd::prefetch<false>(zb + ahead, n + 2);
                if (angle_field) simd::prefetch<false>(tan_cell + ahead, n + 2);
                if (hysteresis) simd::prefetch<false>(moving + ahead, n + 2);
            }
        }
        if constexpr (GridOut) {
            if (r + kRowsAhead < reg.r1) {
                simd::prefetch<true>(h_out + row_out + kRowsAhead * W_out, n);
                simd::prefetch<true>(res_out + row_out + kRowsAhead * W_out, n);
                if (hysteresis) simd::prefetch<true>(moving_out + row_out + kRowsAhead * W_out, n);
            }
        }
        const bool row_in_tile = r >= tile.r0 && r < tile.r1;
        unsigned row_hot = 0;
        // The sides of the domain whose outside this row's tile cells touch:
        // only they can send sand there (every other cell's share is zero).
        // The region may reach past the tile, into the ghosts; the tile does not.
        bool beside[4] = {};
        bool beside_any = false;
        if constexpr (Masked) {
            if (p.outside && row_in_tile) {
                const int first = r * W + tile.c0;
                const int next_to[4] = {first - 1, r * W + tile.c1, first - W, first + W};
                for (int side = 0; side < 4; ++side) {
                    beside[side] = kind[next_to[side]] == kOutside;
                    beside_any = beside_any || beside[side];
                }
            }
        }
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
            V given_here = zero, given_next = zero;
            if (bed) {
                given_here = V::load(available_lo + k);
                given_next = available(c + W);
                given_next.store(available_hi + k);
            }
            M carries;
            const V f = faces_along_y(c, V::load(tx_lo + k), tx_next, given_here, given_next,
                                      valid_lanes(n - k), carries);
            f.store(fy_above + k);
            bits = V::bits(carries);
            carries_above[j] = bits;
            return f;
        };
        // The x faces west of chunk j's cells, given the transverse slopes of
        // the cells before them and of the chunk itself.
        auto x_faces_of = [&](int j, V ty_west, V ty_here, unsigned &bits) {
            const int k = j * w;
            V given_west = zero, given_here = zero;
            if (bed) {
                given_west = V::load(available_lo + k - 1);
                given_here = V::load(available_lo + k);
            }
            M carries;
            const V f = faces_along_x(row + k, ty_west, ty_here, given_west, given_here,
                                      valid_lanes(n + 1 - k), carries);
            bits = V::bits(carries);
            return f;
        };
        // The x faces are needed up to the east face of the last cell: a chunk
        // further when the last chunk is full.
        const int x_chunks = chunks + (n % w == 0 ? 1 : 0);
        if (bed) {
            // What the x faces read beyond this row's chunks: the cells before
            // the first and (full last chunk) after the last. The first store
            // also writes the first chunk's cells again, as they were.
            available(row - 1).store(available_lo - 1);
            if (x_chunks > chunks) available(row + n).store(available_lo + n);
        }
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
            V increment = (f_west - f_east) + (f_south - f_north);
            M sand = valid;
            if constexpr (Masked) sand = V::both(valid, V::kind_is(kind + c, kSand));
            // Cells that do not move keep height and residual bit for bit, as
            // they would in a tile that is not visited; with a lazy source
            // (no physics of real scenes), cells none of whose faces carries
            // sand keep them too, and their lag.
            M changes;
            V hc;
            V source_applied = zero;  // with a bed
            if constexpr (Source && plain) {
                hc = V::load(io.h_stored + c);
                increment = fma(V::load(q + c), dt, increment) + V::load(io.lag + c);
                const unsigned carrying = west_bits | east_bits | carries_below[j] | north_bits;
                changes = V::both(sand, V::from_bits(carrying));
                select(changes, substep_done, V::load(io.since + c)).store_where(io.since_out + row_out + k, valid);
            } else {
                hc = V::load(h + c);
                if constexpr (Source) {
                    if (bed) {
                        source_applied = applied(c, max(hc - V::load(zb + c), zero));
                        increment = increment + source_applied;
                    } else {
                        increment = fma(V::load(q + c), dt, increment);
                    }
                }
                changes = V::both(sand, increment != zero);
            }
            V sum;
            if (p.residuals) {
                const V rc = V::load(res + c);
                const V b_ = increment + rc;
                sum = hc + b_;
                const V b_virtual = sum - hc;
                V err = (hc - (sum - b_virtual)) + (b_ - b_virtual);
                if (bed) {
                    // Rounding left a drained cell below its bed: lift it, and
                    // take the lift from the rounding it carries (a lift of 0
                    // elsewhere, which changes nothing).
                    const V lifted = max(sum, V::load(zb + c));
                    err = err - (lifted - sum);
                    sum = lifted;
                }
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
            // Moving: sand cells with a face that carried sand (hysteresis).
            if (hysteresis)
                V::store_flags(moving_out + row_out + k,
                               (west_bits | east_bits | carries_below[j] | north_bits) & V::bits(sand), V::bits(valid));
            if constexpr (Source) {
                // What the source put on this row's tile cells, and the erosion there that found no sand (bed).
                if (bed && row_in_tile) {
                    const M counted = V::both(sand, V::from_bits(in_tile[j]));
                    const V asked = V::load(q + c) * dt;
                    select(counted, source_applied, zero).store(sourced_row + k);
                    select(V::both(counted, asked < zero), source_applied - asked, zero).store(unmet_row + k);
                }
            }
            if constexpr (Masked) {
                // Sand that this tile's cells send into sinks: open cells, and
                // the outside of open sides, side by side; what sinks feed
                // them counts negative.
                if (row_in_tile) {
                    const V east = select(V::kind_is(kind + c + 1, kOpen), f_east, zero);
                    const V west = select(V::kind_is(kind + c - 1, kOpen), f_west, zero);
                    const V north = select(V::kind_is(kind + c + W, kOpen), f_north, zero);
                    const V south = select(V::kind_is(kind + c - W, kOpen), f_south, zero);
                    const M counted = V::both(sand, V::from_bits(in_tile[j]));
                    select(counted, (east - west) + (north - south), zero).store(outflow_row + k);
                    if (beside_any) {
                        const V out[4] = {zero - f_west, f_east, zero - f_south, f_north};
                        const int beyond[4] = {c - 1, c + 1, c - W, c + W};
                        for (int side = 0; side < 4; ++side)
                            if (beside[side])
                                select(V::both(counted, V::kind_is(kind + beyond[side], kOutside)), out[side], zero)
                                    .store(outside_rows[side] + k);
                    }
                }
            }
            // A visit that records its faces takes the masked kernel and works in
            // the buffer (structured/tiled_sweep.cpp): the branch costs the others 2-10 %.
            if constexpr (Masked && !GridIn && !GridOut) {
                if (p.record) {
                    // Each face once: the west and south faces of every cell, the
                    // east face of the row's last cell, the north faces of the last row.
                    (V::load(face_x + c) + f_west).store_where(face_x + c, valid);
                    (V::load(face_y + c) + f_south).store_where(face_y + c, valid);
                    if (j == chunks - 1)
                        (V::load(face_x + c + 1) + f_east)
                            .store_where(face_x + c + 1, V::but_not(valid, V::first_lanes(n - k - 1)));
                    if (r == reg.r1 - 1) (V::load(face_y + c + W) + f_north).store_where(face_y + c + W, valid);
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
            if (row_in_tile) {
                for (int k = 0; k < n; ++k) outflow += outflow_row[k];
                for (int side = 0; side < 4; ++side)
                    if (beside[side])
                        for (int k = 0; k < n; ++k) outside[side] += outside_rows[side][k];
            }
        }
        if constexpr (Source) {
            if (bed && row_in_tile)  // as the outflow, cell by cell
                for (int k = 0; k < n; ++k) {
                    sourced += sourced_row[k];
                    unmet += unmet_row[k];
                }
        }
        std::swap(tx_lo, tx_hi);
        std::swap(fy_below, fy_above);
        std::swap(carries_below, carries_above);
        std::swap(available_lo, available_hi);
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
    if constexpr (!plain) {
        const double excess =
            std::max(V::hmax(along_x.largest_excess) * p.inv_dx, V::hmax(along_y.largest_excess) * p.inv_dy);
        st.max_excess = std::max(st.max_excess, excess);
        // Heights per sub-step, as mass.
        st.sourced_mass += sourced * p.cell_area;
        st.unmet_mass += unmet * p.cell_area;
    } else {
        const double steepest = std::max(std::sqrt(V::hmax(along_x.steepest2)) * p.inv_dx,
                                         std::sqrt(V::hmax(along_y.steepest2)) * p.inv_dy);
        if (steepest > 0.0) st.max_excess = std::max(st.max_excess, steepest - p.tan_theta);
    }
    // The outflow in heights per sub-step, as mass per unit time.
    const double to_rate = p.cell_area / p.dt;
    double sides = 0.0;
    for (int side = 0; side < 4; ++side) {
        st.side_outflow_rate[side] += outside[side] * to_rate;
        sides += outside[side];
    }
    st.outflow_rate += (outflow + sides) * to_rate;
}

// Calls f with std::true_type or std::false_type, as flag is.
template <class F>
TileKernel with_flag(bool flag, F &&f) {
    return flag ? f(std::true_type{}) : f(std::false_type{});
}

// Calls f with std::integral_constant<PhysicsKind, kind>.
template <class F>
TileKernel with_physics(PhysicsKind kind, F &&f) {
    switch (kind) {
        case PhysicsKind::bed: return f(std::integral_constant<PhysicsKind, PhysicsKind::bed>{});
        case PhysicsKind::any: return f(std::integral_constant<PhysicsKind, PhysicsKind::any>{});
        default: return f(std::integral_constant<PhysicsKind, PhysicsKind::none>{});
    }
}

template <class V>
TileKernel tile_kernel_for(bool masked, bool isotropic, bool source, bool grid_in, bool grid_out, PhysicsKind physics) {
    // Masked kernels read the buffer only (structured/tile_kernel.hpp).
    auto choose = [&](auto masked_, auto isotropic_, auto source_, auto physics_) -> TileKernel {
        constexpr bool Mk = decltype(masked_)::value, I = decltype(isotropic_)::value, S = decltype(source_)::value;
        constexpr PhysicsKind P = decltype(physics_)::value;
        // Kernels with a lazy source work in the buffer only (structured/tile_kernel.hpp).
        if constexpr (S && P == PhysicsKind::none) {
            return advance_tile_level<V, Mk, I, S, false, false, P>;
        } else {
            if constexpr (!Mk) {
                if (grid_in)
                    return grid_out ? advance_tile_level<V, false, I, S, true, true, P>
                                    : advance_tile_level<V, false, I, S, true, false, P>;
            }
            return grid_out ? advance_tile_level<V, Mk, I, S, false, true, P>
                            : advance_tile_level<V, Mk, I, S, false, false, P>;
        }
    };
    return with_flag(masked, [&](auto Mk) {
        return with_flag(isotropic, [&](auto I) {
            return with_flag(source, [&](auto S) { return with_physics(physics, [&](auto P) { return choose(Mk, I, S, P); }); });
        });
    });
}

}  // namespace dpsm
