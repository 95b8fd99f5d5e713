// The tile kernel for CPUs with AVX-512: built with -mavx512f and friends,
// called only after select_tile_kernel has checked the CPU.
#include "structured/tile_kernel_impl.hpp"

namespace dpsm {

TileKernel tile_kernel_avx512(bool masked, bool isotropic, bool source, bool grid_in, bool grid_out, PhysicsKind physics) {
    return tile_kernel_for<simd::Lanes8>(masked, isotropic, source, grid_in, grid_out, physics);
}

}  // namespace dpsm
