// The tile kernel for any CPU, and the choice of kernel at run time.
#include <cstdlib>

#include "tile_kernel_impl.hpp"

namespace dpsm {

#if defined(DPSM_HAVE_AVX512_KERNEL)
TileKernel tile_kernel_avx512(bool masked, bool isotropic, bool source, bool grid_in, bool grid_out);
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
    kind.assign(cells, kSand);
    rows.assign(static_cast<std::size_t>(9) * (w + 32), 0.0);
    chunk_bits.assign(static_cast<std::size_t>(4) * (w + 1), 0u);
}

static bool use_avx512() {
#if defined(DPSM_HAVE_AVX512_KERNEL)
    // DPSM_NO_AVX512=1 forces the generic kernel (to compare the two).
    const char *off = std::getenv("DPSM_NO_AVX512");
    if (off && *off && *off != '0') return false;
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
           __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq");
#else
    return false;
#endif
}

bool tile_kernels_use_avx512() {
    static const bool avx512 = use_avx512();
    return avx512;
}

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
    return cells;
}

TileKernel select_tile_kernel(bool masked, bool isotropic, bool source, bool grid_in, bool grid_out) {
    const bool avx512 = tile_kernels_use_avx512();
#if defined(DPSM_HAVE_AVX512_KERNEL)
    if (avx512) return tile_kernel_avx512(masked, isotropic, source, grid_in, grid_out);
#endif
    (void)avx512;
    return tile_kernel_for<simd::Lanes1>(masked, isotropic, source, grid_in, grid_out);
}

}  // namespace dpsm
