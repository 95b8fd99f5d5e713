#include "reference.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define AT(r, a, i, j) ((a)[((j) + 1) * ((r)->nx + 2) + (i) + 1])

int reference_init(reference_grid *r, int64_t nx, int64_t ny, double dx, double dy, double nu, double theta,
                   double tolerance, const double *h) {
    r->nx = nx;
    r->ny = ny;
    r->dx = dx;
    r->dy = dy;
    r->nu = nu;
    r->tan_theta = tan(theta);
    r->threshold = r->tan_theta * (1.0 + tolerance);
    const size_t cells = (size_t)(nx + 2) * (size_t)(ny + 2);
    r->h = calloc(cells, sizeof(double));
    r->next = calloc(cells, sizeof(double));
    if (!r->h || !r->next) return 0;
    for (int64_t j = 0; j < ny; ++j)
        for (int64_t i = 0; i < nx; ++i) AT(r, r->h, i, j) = h[i + nx * j];
    return 1;
}

void reference_free(reference_grid *r) {
    free(r->h);
    free(r->next);
}

double reference_height(const reference_grid *r, int64_t i, int64_t j) { return AT(r, r->h, i, j); }

void reference_set_height(reference_grid *r, int64_t i, int64_t j, double h) { AT(r, r->h, i, j) = h; }

/* Central differences; the frame (the outside of the open sides) is flat at 0. */
static double slope_y(const reference_grid *r, int64_t i, int64_t j) {
    if (i < 0 || i >= r->nx || j < 0 || j >= r->ny) return 0.0;
    return (AT(r, r->h, i, j + 1) - AT(r, r->h, i, j - 1)) / (2.0 * r->dy);
}

static double slope_x(const reference_grid *r, int64_t i, int64_t j) {
    if (i < 0 || i >= r->nx || j < 0 || j >= r->ny) return 0.0;
    return (AT(r, r->h, i + 1, j) - AT(r, r->h, i - 1, j)) / (2.0 * r->dx);
}

/* The flux from a to b across a face: the law on the full slope, its normal share. */
static double flux(const reference_grid *r, double normal, double transverse, double *excess) {
    const double g = sqrt(normal * normal + transverse * transverse);
    if (!(g > r->threshold)) return 0.0;
    if (g - r->tan_theta > *excess) *excess = g - r->tan_theta;
    return r->nu * (g - r->tan_theta) / sqrt(1.0 + g * g) * normal / g;
}

double reference_flux_x(const reference_grid *r, int64_t i, int64_t j, double *excess) {
    return flux(r, (AT(r, r->h, i - 1, j) - AT(r, r->h, i, j)) / r->dx,
                0.5 * (slope_y(r, i - 1, j) + slope_y(r, i, j)), excess);
}

double reference_flux_y(const reference_grid *r, int64_t i, int64_t j, double *excess) {
    return flux(r, (AT(r, r->h, i, j - 1) - AT(r, r->h, i, j)) / r->dy,
                0.5 * (slope_x(r, i, j - 1) + slope_x(r, i, j)), excess);
}

/* dh/dt of cell (i, j): the fluxes of its four faces. */
static double cell_rate(const reference_grid *r, int64_t i, int64_t j, double *excess) {
    const double west = reference_flux_x(r, i, j, excess), east = reference_flux_x(r, i + 1, j, excess);
    const double south = reference_flux_y(r, i, j, excess), north = reference_flux_y(r, i, j + 1, excess);
    return (west - east) / r->dx + (south - north) / r->dy;
}

double reference_rates(const reference_grid *r, double *rate) {
    double excess = 0.0;
    for (int64_t j = 0; j < r->ny; ++j)
        for (int64_t i = 0; i < r->nx; ++i) rate[i + r->nx * j] = cell_rate(r, i, j, &excess);
    return excess;
}

double reference_substep(reference_grid *r, double dt) {
    double excess = 0.0;
    for (int64_t j = 0; j < r->ny; ++j)
        for (int64_t i = 0; i < r->nx; ++i) AT(r, r->next, i, j) = AT(r, r->h, i, j) + dt * cell_rate(r, i, j, &excess);
    double *t = r->h;
    r->h = r->next;
    r->next = t;
    return excess;
}
