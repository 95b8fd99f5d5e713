// The tile kernel for any CPU, and the choice of kernel at run time.
#include "model/switches.hpp"
#include "structured/tile_kernel_impl.hpp"

namespace dpsm {

#if defined(DPSM_HAVE_AVX512_KERNEL)
TileKernel tile_kernel_avx512(bool masked, bool isotropic, bool source, bool grid_in, bool grid_out, PhysicsKind physics);
#endif
#if defined(DPSM_HAVE_AVX2_KERNEL)
TileKernel tile_kernel_avx2(bool masked, bool isotropic, bool source, bool grid_in, bool grid_out, PhysicsKind physics);
#endif

void TileBuffers::resize(int w, int h_) {
    width = w;
    height = h_;
    // Lanes may read up to a vector past the end of a row or a buffer.
    const std::size_t cells = static_cast<std::size_t>(w) * h_ + 64;
    for (int s = 0; s < 2; ++s) {
        h[s].assign(cells, 0.0);
        residual[s].assign(cells, 0.0);
    }
    source.assign(cells, 0.0);
    for (int s = 0; s < 2; ++s) since[s].assign(cells, 0.0);
    true_h.assign(cells, 0.0);
    lag.assign(cells, 0.0);
    kind.assign(cells, kSand);
    rows.assign(static_cast<std::size_t>(14) * (w + 32), 0.0);  // the kernel's thirteen rows of scratch, and room
    chunk_bits.assign(static_cast<std::size_t>(4) * (w + 1), 0u);
}

// DPSM_NO_AVX512=1 and DPSM_NO_AVX2=1 rule those kernels out, so that one
// machine can run (and the tests compare) every kernel it has.
static int widest_lanes() {
    const Switches switches = read_switches();
    (void)switches;
#if defined(DPSM_HAVE_AVX512_KERNEL)
    __builtin_cpu_init();
    if (!switches.no_avx512 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
        __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq"))
        return 8;
#endif
#if defined(DPSM_HAVE_AVX2_KERNEL)
    __builtin_cpu_init();
    if (!switches.no_avx2 && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return 4;
#endif
    return 1;
}

int tile_kernel_lanes() {
    static const int lanes = widest_lanes();
    return lanes;
}

bool tile_kernels_use_avx512() { return tile_kernel_lanes() == 8; }

LevelCells buffer_level_cells(TileBuffers &b, int in) {
    LevelCells cells;
    cells.h = b.h[in].data();
    cells.residual = b.residual[in].data();
    cells.source = b.source.data();
    cells.kind = b.kind.data();
    cells.stride = b.width;
    cells.h_out = b.h[1 - in].data();
    cells.residual_out = b.residual[1 - in].data();
    cells.out_stride = b.width;
    cells.h_stored = b.h[in].data();
    cells.lag = b.lag.data();
    cells.since = b.since[in].data();
    cells.since_out = b.since[1 - in].data();
    cells.bed = b.bed.data();
    cells.tan_theta = b.tan_theta.data();
    cells.moving = b.moving[in].data();
    cells.moving_out = b.moving[1 - in].data();
    return cells;
}

TileKernel select_tile_kernel(bool masked, bool isotropic, bool source, bool grid_in, bool grid_out, PhysicsKind physics) {
    switch (tile_kernel_lanes()) {
#if defined(DPSM_HAVE_AVX512_KERNEL)
        case 8: return tile_kernel_avx512(masked, isotropic, source, grid_in, grid_out, physics);
#endif
#if defined(DPSM_HAVE_AVX2_KERNEL)
        case 4: return tile_kernel_avx2(masked, isotropic, source, grid_in, grid_out, physics);
#endif
        default: return tile_kernel_for<simd::Lanes1>(masked, isotropic, source, grid_in, grid_out, physics);
    }
}

}  // namespace dpsm
