#include "model/switches.hpp"

#include <algorithm>
#include <cstdlib>

namespace dpsm {

namespace {

bool flag(const char *name) {
    const char *value = std::getenv(name);
    return value && *value && *value != '0';
}

}  // namespace

Switches read_switches() {
    Switches s;
    s.visit_all_tiles = flag("DPSM_VISIT_ALL_TILES");
    s.copy_tiles = flag("DPSM_COPY_TILES");
    s.scalar_physics = flag("DPSM_SCALAR_PHYSICS");
    s.visit_all_cells = flag("DPSM_VISIT_ALL_CELLS");
    s.scalar_mesh = flag("DPSM_SCALAR_MESH");
    s.mesh_host_order = flag("DPSM_MESH_HOST_ORDER");
    if (const char *limit = std::getenv("DPSM_MPI_SUBSTEPS_PER_EXCHANGE"))
        if (*limit) s.mpi_substeps_per_exchange = std::max(0, std::atoi(limit));
    s.no_avx512 = flag("DPSM_NO_AVX512");
    s.no_avx2 = flag("DPSM_NO_AVX2");
    return s;
}

}  // namespace dpsm
