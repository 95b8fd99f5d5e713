// How many OpenMP threads a pass runs on: the host's choice
// (dpsm_set_threads), or when it made none OpenMP's default, but 1 on a block
// of a distributed grid unless OMP_NUM_THREADS is set: an MPI host runs a
// rank per core, and OpenMP's default (every core of the node) would give
// each of them as many threads. 1 without OpenMP.
#pragma once

#include <cstdlib>

#if defined(_OPENMP)
#include <omp.h>
#endif

namespace dpsm {

// More threads than this run as this many: each thread of a sweep holds
// buffers of its own, and no machine runs more in one process usefully.
constexpr int kMaxThreads = 1024;

inline int thread_count(int requested, bool distributed) {
#if defined(_OPENMP)
    if (requested > 0) return requested < kMaxThreads ? requested : kMaxThreads;
    if (distributed && !std::getenv("OMP_NUM_THREADS")) return 1;
    return omp_get_max_threads();
#else
    (void)requested;
    (void)distributed;
    return 1;
#endif
}

}  // namespace dpsm
