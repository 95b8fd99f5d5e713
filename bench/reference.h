/* A plain, obviously correct implementation of one explicit sub-step of the
 * isotropic scheme on a grid with every side open, for the benchmarks to time
 * dpsm against. No tiles, no threads, no vectors: every cell adds the fluxes
 * of its four faces (so every face is computed twice), with the same flux law,
 * dead zone and transverse slopes as the library. */
#ifndef DPSM_BENCH_REFERENCE_H
#define DPSM_BENCH_REFERENCE_H

#include <stdint.h>

typedef struct {
    int64_t nx, ny;
    double dx, dy, nu, tan_theta, threshold; /* threshold: tan(theta) (1 + rest tolerance) */
    double *h, *next;                         /* (nx + 2) * (ny + 2), a frame of zeros outside */
} reference_grid;

/* Allocates the grid with heights h (nx*ny, x fastest); 0 on failure. */
int reference_init(reference_grid *r, int64_t nx, int64_t ny, double dx, double dy, double nu, double theta,
                   double tolerance, const double *h);
void reference_free(reference_grid *r);
/* One sub-step of dt; returns the largest slope excess over faces that carried sand (0 at rest). */
double reference_substep(reference_grid *r, double dt);
double reference_height(const reference_grid *r, int64_t i, int64_t j);
void reference_set_height(reference_grid *r, int64_t i, int64_t j, double h);
/* dh/dt of every cell (nx*ny, x fastest) at the present heights; returns the
 * largest slope excess over faces that carried sand. */
double reference_rates(const reference_grid *r, double *rate);
/* The flux (per unit face length, nu included) across the face between cells
 * (i - 1, j) and (i, j), i in [0, nx], positive towards +x; and across the
 * face between (i, j - 1) and (i, j), j in [0, ny], positive towards +y.
 * Raises *excess to the face's slope excess over tan(theta) if it carries sand. */
double reference_flux_x(const reference_grid *r, int64_t i, int64_t j, double *excess);
double reference_flux_y(const reference_grid *r, int64_t i, int64_t j, double *excess);

#endif
