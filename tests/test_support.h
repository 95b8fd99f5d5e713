/* Helpers shared by the CMocka tests: scenes, sums and the ledger check. */
#ifndef DPSM_TEST_SUPPORT_H
#define DPSM_TEST_SUPPORT_H

#include <stddef.h>
#include <stdint.h>

#include <dpsm/dpsm.h>

/* Fails the test with the library's message when a call does not succeed. */
#define CHECK_OK(g, call) check_ok_((g), (call), #call, __FILE__, __LINE__)
void check_ok_(const dpsm_grid *g, int status, const char *text, const char *file, int line);

/* The four ledger figures. */
typedef struct {
    double total, sourced, external, outflow;
} ledger_t;
ledger_t read_ledger(const dpsm_grid *g);
/* |total - (sourced + external - outflow)| relative to the largest figure. */
double ledger_residual(const dpsm_grid *g);

/* Fails the test at file:line with a formatted explanation unless cond holds. */
#if defined(__GNUC__)
__attribute__((format(printf, 4, 5)))
#endif
void require_at(int cond, const char *file, int line, const char *fmt, ...);
#define REQUIRE(cond, ...) require_at((cond) != 0, __FILE__, __LINE__, __VA_ARGS__)

double max_of(const double *v, size_t n);
double min_of(const double *v, size_t n);

/* The largest |h_j - h_i| / d over face neighbours of a nx-by-ny array (sand
 * cells only when kinds is not NULL). */
double max_face_slope(const double *h, const uint8_t *kinds, int64_t nx, int64_t ny, double dx, double dy);

/* One figure of dpsm_get_step_info / dpsm_get_mass, failing the test when the call fails. */
double step_info_of(const dpsm_grid *g, int item);
double mass_of(const dpsm_grid *g, int quantity);

/* Sets every side of a 2D grid (or both of a 1D grid) to kind. */
void set_all_sides(dpsm_grid *g, int kind, int dim);

#endif
