/* A small program built against an installed dpsm, outside the source tree
 * (tests/consume/run.sh builds it with pkg-config and with CMake). It calls a
 * few functions and checks their results; it exits non-zero on any wrong one.
 * It is written in the common subset of C and C++ so the header is checked
 * from both languages. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <dpsm/dpsm.h>

static int failures = 0;

#define EXPECT(cond)                                                        \
    do {                                                                    \
        if (!(cond)) {                                                      \
            fprintf(stderr, "%s:%d: expected %s\n", __FILE__, __LINE__, #cond); \
            ++failures;                                                     \
        }                                                                   \
    } while (0)

#define NX 40

int main(void) {
    const double dx = 0.1, theta = 0.5;
    double h[NX], h0 = 4.0; /* more than a slope at the angle of repose can hold: some must leave */
    dpsm_grid *g = NULL;
    int i;

    /* The header and the library agree. */
    EXPECT(dpsm_version_number() == DPSM_VERSION_NUMBER);
    EXPECT(strcmp(dpsm_version_string(), DPSM_VERSION_STRING) == 0);
    EXPECT(DPSM_VERSION_MAJOR == 0 && DPSM_VERSION_MINOR >= 1);

    /* A failed create leaves NULL and a message without a grid. */
    EXPECT(dpsm_create_1d(0, dx, &g) == DPSM_ERR_INVALID_SIZE);
    EXPECT(g == NULL);
    EXPECT(strlen(dpsm_last_error(NULL)) > 0);
    EXPECT(strcmp(dpsm_status_string(DPSM_ERR_INVALID_SIZE), "DPSM_ERR_INVALID_SIZE") == 0);

    if (dpsm_create_1d(NX, dx, &g) != DPSM_OK || g == NULL) {
        fprintf(stderr, "dpsm_create_1d failed: %s\n", dpsm_last_error(NULL));
        return 1;
    }
    {
        int64_t nx = 0, ny = 0;
        EXPECT(dpsm_get_shape(g, &nx, &ny) == DPSM_OK && nx == NX && ny == 1);
    }
    EXPECT(dpsm_set_repose_angle(g, theta) == DPSM_OK);
    EXPECT(dpsm_set_repose_angle(g, 2.0) == DPSM_ERR_INVALID_VALUE); /* outside (0, pi/2) */
    EXPECT(strlen(dpsm_last_error(g)) > 0);
    EXPECT(dpsm_set_boundary(g, DPSM_XMIN, DPSM_OPEN) == DPSM_OK);
    EXPECT(strcmp(dpsm_last_error(g), "") == 0);
    EXPECT(dpsm_set_boundary(g, DPSM_YMIN, DPSM_OPEN) == DPSM_ERR_NOT_APPLICABLE);

    {
        double dt = 0.0;
        EXPECT(dpsm_stable_dt(g, &dt) == DPSM_OK);
        EXPECT(fabs(dt - dx * dx / (2.0 * DPSM_DEFAULT_MOBILITY * cos(theta))) <= 1e-12 * dt);
    }

    /* A steep block against the wall at XMAX, open at XMIN: it slumps to rest. */
    for (i = 0; i < NX; ++i) h[i] = i >= NX / 2 ? h0 : 0.0;
    EXPECT(dpsm_set_heights(g, h) == DPSM_OK);
    EXPECT(dpsm_step(g, 1e6) == DPSM_OK);
    {
        double at_rest = 0.0, excess = 1.0, substeps = 0.0;
        EXPECT(dpsm_get_step_info(g, DPSM_INFO_AT_REST, &at_rest) == DPSM_OK && at_rest == 1.0);
        EXPECT(dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &substeps) == DPSM_OK && substeps > 0.0);
        EXPECT(dpsm_get_step_info(g, DPSM_INFO_MAX_EXCESS_SLOPE, &excess) == DPSM_OK);
        EXPECT(excess <= DPSM_DEFAULT_REST_TOLERANCE * tan(theta));
    }
    EXPECT(dpsm_get_heights(g, h) == DPSM_OK);
    for (i = 0; i < NX; ++i) EXPECT(h[i] >= -1e-12 && h[i] <= h0 + 1e-12); /* no new extremum */
    for (i = 0; i + 1 < NX; ++i) EXPECT(h[i + 1] - h[i] <= dx * tan(theta) * (1.0 + 1e-5));

    /* The ledger closes. */
    {
        double total, sourced, external, outflow;
        EXPECT(dpsm_get_mass(g, DPSM_MASS_TOTAL, &total) == DPSM_OK);
        EXPECT(dpsm_get_mass(g, DPSM_MASS_SOURCED, &sourced) == DPSM_OK);
        EXPECT(dpsm_get_mass(g, DPSM_MASS_EXTERNAL, &external) == DPSM_OK);
        EXPECT(dpsm_get_mass(g, DPSM_MASS_OUTFLOW, &outflow) == DPSM_OK);
        EXPECT(fabs(external - h0 * dx * (NX / 2)) <= 1e-12);
        EXPECT(sourced == 0.0);
        EXPECT(outflow > 0.0);
        EXPECT(fabs(total - (sourced + external - outflow)) <= 1e-12 * external);
        EXPECT(dpsm_get_mass(g, 99, &total) == DPSM_ERR_UNKNOWN_ENUM);
    }

    dpsm_destroy(g);
    dpsm_destroy(NULL);
    if (failures) {
        fprintf(stderr, "%d check(s) failed\n", failures);
        return 1;
    }
    printf("dpsm %s: consumer checks passed\n", dpsm_version_string());
    return 0;
}
