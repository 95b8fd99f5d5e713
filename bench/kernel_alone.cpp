// dpsm-bench-kernel: the tile kernel alone, on one tile in cache, to tell
// the kernel's speed from the sweep's (copies, memory, threads). A visit of
// a fully active interior tile: four sub-steps of a 64 x 64 tile with its
// halo in the buffer, the region shrinking by a cell per sub-step, one
// thread. It links the static library and calls its internal kernel
// selection (src/structured/tile_kernel.hpp), so it times the very code a sweep runs.
//
//   dpsm-bench-kernel [visits [rounds [variant]]]   (defaults 20000, 7: the best round; every variant)
//
// CSV: lanes,variant,mcells_per_s,ns_per_cell,checksum. Cells are the tile's
// (4 x 64 x 64 per visit); the halo the sub-steps also compute is the
// kernel's own overhead and counts against it. The checksum (sum of the
// heights after the last round) shows that two builds computed the same.
// The variants with physics (a bed 100 below, a uniform angle field, flux
// exponents, a static angle below the plane's slopes) flow as the plain one
// does: their cost is the physics' alone.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "structured/active_set.hpp"
#include "structured/tile_kernel.hpp"

namespace {

constexpr int kLevels = dpsm::ActiveSet::kMaxLevels, kTile = dpsm::ActiveSet::kTile;
constexpr int kSide = kTile + 2 * (kLevels + 1);

struct Variant {
    const char *name;
    bool masked, isotropic, source;
    bool bed = false, angle_field = false;
    double flux_exponent = 1.0, static_angle_degrees = 0.0;
    bool physics() const { return bed || angle_field || flux_exponent != 1.0 || static_angle_degrees > 0.0; }
};

double run(const Variant &v, int visits, int rounds, double *checksum) {
    dpsm::TileBuffers b;
    b.resize(kSide, kSide);
    // The steep rippled plane of dpsm-bench throughput: every face flows.
    for (int r = 0; r < kSide; ++r)
        for (int c = 0; c < kSide; ++c)
            b.h[0][r * kSide + c] = b.h[1][r * kSide + c] = 2.0 * c + 1.5 * r + 0.3 * std::sin(0.7 * c) * std::cos(0.3 * r);
    const double theta = 30.0 * 3.14159265358979323846 / 180.0;
    dpsm::TileLevelParams p{1.0, std::tan(theta), 1.0, 1.0, 1.0, 1.0, 0.5, 0.5, 1.0 / (4.0 * std::cos(theta)), 1.0, 1.0};
    p.rest_factor = 1.0 + 1e-6;
    p.track_excess = false;
    if (v.physics()) {
        b.resize_physics();
        std::fill(b.bed.begin(), b.bed.end(), -100.0);
        std::fill(b.tan_theta.begin(), b.tan_theta.end(), std::tan(theta));
        p.bed = v.bed;
        p.bed_film = 1e-6 * std::tan(theta);
        p.angle_field = v.angle_field;
        p.flux_exponent = v.flux_exponent;
        p.hysteresis = v.static_angle_degrees > 0.0;
        p.tan_static = std::tan(v.static_angle_degrees * 3.14159265358979323846 / 180.0);
    }
    const dpsm::TileKernel kernel =
        dpsm::select_tile_kernel(v.masked, v.isotropic, v.source, false, false, dpsm::physics_kind(p, v.physics()));
    const dpsm::TileRect tile{kLevels + 1, kSide - kLevels - 1, kLevels + 1, kSide - kLevels - 1};
    double best = INFINITY;
    for (int round = 0; round < rounds; ++round) {
        const auto t0 = std::chrono::steady_clock::now();
        for (int v = 0; v < visits; ++v) {
            int in = 0;
            for (int s = 1; s <= kLevels; ++s) {
                const int halo = kLevels - s + 1;  // the buffer's ghost ring stays outside
                const dpsm::TileRect region{halo, kSide - halo, halo, kSide - halo};
                dpsm::TileLevelStats stats;
                kernel(b, dpsm::buffer_level_cells(b, in), region, tile, p, stats);
                in = 1 - in;
            }
        }
        best = std::fmin(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    *checksum = 0.0;
    for (int c = 0; c < kSide * kSide; ++c) *checksum += b.h[0][c];
    return best;
}

}  // namespace

int main(int argc, char **argv) {
    const int visits = argc > 1 ? std::atoi(argv[1]) : 20000;
    const int rounds = argc > 2 ? std::atoi(argv[2]) : 7;
    if (visits < 1 || rounds < 1) {
        std::fprintf(stderr, "usage: dpsm-bench-kernel [visits [rounds [variant]]] (both at least 1)\n");
        return 2;
    }
    std::printf("lanes,variant,mcells_per_s,ns_per_cell,checksum\n");
    const double cells = 4.0 * kTile * kTile * visits;
    const Variant variants[] = {{"isotropic", false, true, false},
                                {"isotropic-masked", true, true, false},
                                {"isotropic-source", false, true, true},
                                {"pairwise", false, false, false},
                                {"isotropic-bed", false, true, false, true},
                                {"isotropic-masked-bed", true, true, false, true},
                                {"pairwise-bed", false, false, false, true},
                                {"isotropic-angle-field", false, true, false, false, true},
                                {"isotropic-exponent-1.5", false, true, false, false, false, 1.5},
                                {"isotropic-exponent-2", false, true, false, false, false, 2.0},
                                {"isotropic-static-angle", false, true, false, false, false, 1.0, 35.0}};
    const char *only = argc > 3 ? argv[3] : nullptr;
    for (const Variant &v : variants) {
        if (only && std::strcmp(only, v.name) != 0) continue;
        double checksum = 0.0;
        const double seconds = run(v, visits, rounds, &checksum);
        std::printf("%d,%s,%.1f,%.3f,%.15e\n", dpsm::tile_kernel_lanes(), v.name, cells / seconds / 1e6,
                    seconds / cells * 1e9, checksum);
        std::fflush(stdout);
    }
    return 0;
}
