// How many OpenMP threads a pass runs on: the host's choice
// (dpsm_set_threads), or OpenMP's default when it made none; 1 without OpenMP.
#pragma once

#if defined(_OPENMP)
#include <omp.h>
#endif

namespace dpsm {

inline int thread_count(int requested) {
#if defined(_OPENMP)
    return requested > 0 ? requested : omp_get_max_threads();
#else
    (void)requested;
    return 1;
#endif
}

}  // namespace dpsm
