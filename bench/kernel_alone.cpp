// dpsm-bench-kernel: the tile kernel alone, on one tile in cache, to tell
// the kernel's speed from the sweep's (copies, memory, threads). A visit of
// a fully active interior tile: four sub-steps of a 64 x 64 tile with its
// halo in the buffer, the region shrinking by a cell per sub-step, one
// thread. It links the static library and calls its internal kernel
// selection (src/tile_kernel.hpp), so it times the very code a sweep runs.
//
//   dpsm-bench-kernel [visits [rounds]]     (defaults 20000, 7: the best round)
//
// CSV: lanes,variant,mcells_per_s,ns_per_cell,checksum. Cells are the tile's
// (4 x 64 x 64 per visit); the halo the sub-steps also compute is the
// kernel's own overhead and counts against it. The checksum (sum of the
// heights after the last round) shows that two builds computed the same.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "active_set.hpp"
#include "tile_kernel.hpp"

namespace {

constexpr int kLevels = dpsm::ActiveSet::kMaxLevels, kTile = dpsm::ActiveSet::kTile;
constexpr int kSide = kTile + 2 * (kLevels + 1);

double run(dpsm::TileKernel kernel, int visits, int rounds, double *checksum) {
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
        std::fprintf(stderr, "usage: dpsm-bench-kernel [visits [rounds]] (both at least 1)\n");
        return 2;
    }
    std::printf("lanes,variant,mcells_per_s,ns_per_cell,checksum\n");
    const double cells = 4.0 * kTile * kTile * visits;
    struct Variant {
        const char *name;
        bool masked, isotropic, source;
    } variants[] = {{"isotropic", false, true, false},
                    {"isotropic-masked", true, true, false},
                    {"isotropic-source", false, true, true},
                    {"pairwise", false, false, false}};
    for (const Variant &v : variants) {
        double checksum = 0.0;
        const double seconds = run(dpsm::select_tile_kernel(v.masked, v.isotropic, v.source), visits, rounds, &checksum);
        std::printf("%d,%s,%.1f,%.3f,%.15e\n", dpsm::tile_kernel_lanes(), v.name, cells / seconds / 1e6,
                    seconds / cells * 1e9, checksum);
        std::fflush(stdout);
    }
    return 0;
}
