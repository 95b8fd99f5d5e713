// The tile kernel for CPUs with AVX2 and FMA but not AVX-512: built with
// -mavx2 -mfma, called only after select_tile_kernel has checked the CPU.
#include "structured/tile_kernel_impl.hpp"

namespace dpsm {

TileKernel tile_kernel_avx2(bool masked, bool isotropic, bool source, bool grid_in, bool grid_out, PhysicsKind physics) {
    return tile_kernel_for<simd::Lanes4>(masked, isotropic, source, grid_in, grid_out, physics);
}

}  // namespace dpsm
