// The tile kernel of scenes that use the physics of real scenes: a bed that
// cannot erode, an angle of repose per cell, a flux exponent, hysteresis.
// Same contract as structured/tile_kernel_impl.hpp (one level of a region, from slot
// `in` to slot 1 - in, statistics over `tile`), but plain scalar code in three
// passes, because the bed's cap on a face needs its upstream cell's erosion
// before any face: (1) each cell's applied source and the sand it can give,
// (2) every face once, (3) every cell's update.
#include <algorithm>
#include <cmath>
#include <limits>

#include "model/face_law.hpp"
#include "model/grid.hpp"
#include "structured/tile_kernel.hpp"

namespace dpsm {

void TileBuffers::resize_physics() {
    const std::size_t cells = h[0].size();
    if (available.size() == cells) return;
    bed.assign(cells, 0.0);
    tan_theta.assign(cells, 0.0);
    moving[0].assign(cells, 0);
    moving[1].assign(cells, 0);
    available.assign(cells, 0.0);
    applied.assign(cells, 0.0);
    x_faces.assign(cells, 0.0);
    y_faces.assign(cells, 0.0);
}

namespace {

template <bool Isotropic, bool Source>
void advance_tile_level_physics(TileBuffers &b, int in, const TileRect &reg, const TileRect &tile,
                                const TileLevelParams &p, TileLevelStats &st) {
    const int W = b.width;
    const double *h = b.h[in].data();
    const double *res = b.residual[in].data();
    double *h_out = b.h[1 - in].data();
    double *res_out = b.residual[1 - in].data();
    const std::uint8_t *kind = b.kind.data();
    const std::uint8_t *moving = b.moving[in].data();
    std::uint8_t *moving_out = b.moving[1 - in].data();
    const double *q = b.source.data();
    const double *zb = b.bed.data();
    const double *tan_cell = b.tan_theta.data();
    double *available = b.available.data();
    double *applied = b.applied.data();
    double *fx = b.x_faces.data();  // fx[c]: the face between c - 1 and c, positive towards c
    double *fy = b.y_faces.data();  // fy[c]: the face between c - W and c, positive towards c

    // (1) The source each cell receives, and the sand above the bed its faces
    // may share, for the region and the ring around it (upstream cells).
    for (int r = reg.r0 - 1; r < reg.r1 + 1; ++r)
        for (int c = r * W + reg.c0 - 1; c < r * W + reg.c1 + 1; ++c) {
            const double asked = Source && kind[c] == kSand ? q[c] * p.dt : 0.0;
            if (!p.bed || kind[c] != kSand) {
                applied[c] = asked;
                continue;
            }
            const double sand = std::max(0.0, h[c] - zb[c]);
            applied[c] = asked < 0.0 ? -std::min(-asked, sand) : asked;
            const double left = sand + std::min(0.0, applied[c]);
            available[c] = left > p.bed_film ? left : 0.0;
        }

    // (2) Faces. The transverse slope of a cell mirrors a wall neighbour.
    auto across_y = [&](int c) {
        const double north = kind[c + W] == kWall ? h[c] : h[c + W];
        const double south = kind[c - W] == kWall ? h[c] : h[c - W];
        return (north - south) * p.half_inv_dy;
    };
    auto across_x = [&](int c) {
        const double east = kind[c + 1] == kWall ? h[c] : h[c + 1];
        const double west = kind[c - 1] == kWall ? h[c] : h[c - 1];
        return (east - west) * p.half_inv_dx;
    };
    double excess_max = 0.0;
    // The flux per unit length from cell a to cell c, normal slope gn, transverse gt.
    auto face = [&](int a, int c, double gn, double gt, double inv_d) {
        const bool a_sand = kind[a] == kSand, c_sand = kind[c] == kSand;
        if (kind[a] == kWall || kind[c] == kWall || (!a_sand && !c_sand)) return 0.0;
        const double tan_face = p.angle_field ? law::face_tan(tan_cell[a], tan_cell[c], a_sand, c_sand) : p.tan_theta;
        double threshold = tan_face * p.rest_factor;
        if (p.hysteresis) threshold = law::threshold(threshold, !moving[a] && !moving[c], p.tan_static);
        const double u = gn * gn + gt * gt;
        if (!(u > threshold * threshold)) return 0.0;
        // A face steep only across its normal, its two cells level to within
        // the rounding of their heights, carries nothing. Where the cells'
        // angles differ (a field, hysteresis), the faces across it may rest
        // steeper than its own threshold, and a flux of an ulp's difference
        // would pass an ulp back and forth between the two cells for ever.
        if (Isotropic && std::fabs(h[a] - h[c]) <= kLevelWithinRounding * std::max(std::fabs(h[a]), std::fabs(h[c])))
            return 0.0;
        const double s = std::sqrt(u);
        double flux = slide_flux_at(p.nu, tan_face, s, u, p.flux_exponent) * (gn / s);
        if (p.bed) {
            const double unlimited = std::numeric_limits<double>::infinity();
            const auto most = [&](int cell, bool sand) {
                return sand ? law::share_of_sand(available[cell], kFacesPerCell, p.dt, inv_d) : unlimited;
            };
            flux = law::capped(flux, most(a, a_sand), -most(c, c_sand));
        }
        if (flux != 0.0) excess_max = std::max(excess_max, s - tan_face);
        return flux;
    };
    for (int r = reg.r0; r < reg.r1; ++r)
        for (int c = r * W + reg.c0; c <= r * W + reg.c1; ++c) {
            const double gt = Isotropic ? 0.5 * (across_y(c - 1) + across_y(c)) : 0.0;
            fx[c] = face(c - 1, c, (h[c - 1] - h[c]) * p.inv_dx, gt, p.inv_dx);
        }
    for (int r = reg.r0; r <= reg.r1; ++r)
        for (int c = r * W + reg.c0; c < r * W + reg.c1; ++c) {
            const double gt = Isotropic ? 0.5 * (across_x(c - W) + across_x(c)) : 0.0;
            fy[c] = face(c - W, c, (h[c - W] - h[c]) * p.inv_dy, gt, p.inv_dy);
        }

    if (p.record) {
        // Every face the region touches, as a height per sub-step of its cells.
        for (int r = reg.r0; r < reg.r1; ++r)
            for (int c = r * W + reg.c0; c <= r * W + reg.c1; ++c) b.face_x[c] += fx[c] * p.inv_dx * p.dt;
        for (int r = reg.r0; r <= reg.r1; ++r)
            for (int c = r * W + reg.c0; c < r * W + reg.c1; ++c) b.face_y[c] += fy[c] * p.inv_dy * p.dt;
    }

    // (3) Cells.
    bool moved = false;
    for (int r = reg.r0; r < reg.r1; ++r) {
        const bool row_in_tile = r >= tile.r0 && r < tile.r1;
        for (int col = reg.c0; col < reg.c1; ++col) {
            const int c = r * W + col;
            const double west = fx[c], east = fx[c + 1], south = fy[c], north = fy[c + W];
            const bool sand = kind[c] == kSand;
            double increment = ((west - east) * p.inv_dx + (south - north) * p.inv_dy) * p.dt;
            if (Source || p.bed) increment += applied[c];
            // h + increment as a TwoSum, carrying what rounding drops.
            const double b_ = increment + res[c];
            double sum = h[c] + b_;
            const double b_virtual = sum - h[c];
            double err = (h[c] - (sum - b_virtual)) + (b_ - b_virtual);
            const bool changes = sand && increment != 0.0;
            if (!changes) {
                sum = h[c];
                err = res[c];
            } else if (p.bed && sum < zb[c]) {
                // Rounding left a drained cell below its bed: lift it, and take
                // the lift from the rounding it carries.
                err -= zb[c] - sum;
                sum = zb[c];
            }
            h_out[c] = sum;
            res_out[c] = err;
            const bool carried = west != 0.0 || east != 0.0 || south != 0.0 || north != 0.0;
            moving_out[c] = sand && carried;
            moved = moved || changes || carried;
            const bool in_tile = row_in_tile && col >= tile.c0 && col < tile.c1;
            if (!in_tile) continue;
            if (changes || carried) {
                st.hot_r0 = std::min(st.hot_r0, r);
                st.hot_r1 = std::max(st.hot_r1, r + 1);
                st.hot_c0 = std::min(st.hot_c0, col);
                st.hot_c1 = std::max(st.hot_c1, col + 1);
            }
            if (!sand) continue;
            // Sand sent into sinks (open cells, and the outside of open sides,
            // side by side); what sinks feed counts negative.
            const double out[4] = {-west * p.x_face_length, east * p.x_face_length, -south * p.y_face_length,
                                   north * p.y_face_length};
            const int beyond[4] = {c - 1, c + 1, c - W, c + W};
            for (int side = 0; side < 4; ++side) {
                if (kind[beyond[side]] == kOpen) st.outflow_rate += out[side];
                if (kind[beyond[side]] == kOutside) {
                    st.outflow_rate += out[side];
                    st.side_outflow_rate[side] += out[side];
                }
            }
            if (Source && p.bed) {
                st.sourced_mass += applied[c] * p.cell_area;
                if (q[c] < 0.0) st.unmet_mass += (applied[c] - q[c] * p.dt) * p.cell_area;
            }
        }
    }
    st.moved = st.moved || moved;
    st.max_excess = std::max(st.max_excess, excess_max);
}

}  // namespace

PhysicsTileKernel select_physics_tile_kernel(bool isotropic, bool source) {
    if (isotropic) return source ? advance_tile_level_physics<true, true> : advance_tile_level_physics<true, false>;
    return source ? advance_tile_level_physics<false, true> : advance_tile_level_physics<false, false>;
}

}  // namespace dpsm
