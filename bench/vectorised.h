/* A straightforward vectorised loop for the isotropic scheme (vectorised.c). */
#ifndef DPSM_BENCH_VECTORISED_H
#define DPSM_BENCH_VECTORISED_H

#include <stdint.h>

#include "reference.h"

/* Million cell updates per second of the loop on h (n x n, cells of width 1,
 * nu = 1) over `substeps` sub-steps of dt on `threads` threads. Before, runs
 * check_substeps sub-steps and writes to *difference the largest relative
 * difference from `check` (the reference loop after as many sub-steps of dt)
 * away from the edges. */
double vectorised_mcells_per_s(int64_t n, const double *h, double theta, double tolerance, double dt, int threads,
                               int substeps, const reference_grid *check, int check_substeps, double *difference);

#endif
