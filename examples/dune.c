/* A transverse dune on a bed of rock whose slip face is slightly steeper than
 * the angle of repose relaxes to rest: the paper's Fig. 10 (its Section 6),
 * with the physics of real scenes (dpsm_set_bedrock).
 *
 * The dune is uniform across the wind (y); its stoss side rises at 12 degrees
 * to a brink, its slip face falls at 36 degrees, steeper than the angle of
 * repose of 33 degrees, and its toe lies on bare rock that rises into a small
 * outcrop downwind. The slip face avalanches: sand slides from below the brink
 * down onto the rock at the toe until every slope is at or below 33 degrees.
 * The rock itself never moves, however steep its outcrop.
 *
 *   dpsm-dune [profile.csv]
 *
 * prints what happened and, given a path, writes the profile along the dune
 * (x, bed, initial surface, surface at four times, final surface) as CSV.
 * Exits non-zero if the surface went below the rock, a slope stayed
 * supercritical, or the mass ledger did not close. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <dpsm/dpsm.h>

#define CHECK(call)                                                                  \
    do {                                                                             \
        if ((call) != DPSM_OK) {                                                     \
            fprintf(stderr, "%s failed: %s\n", #call, dpsm_last_error(g));           \
            exit(1);                                                                 \
        }                                                                            \
    } while (0)

enum { NX = 480, NY = 16, SNAPSHOTS = 4 };
static const double kDx = 0.125; /* metres */
static const double kPi = 3.14159265358979323846;

static double deg(double d) { return d * kPi / 180.0; }

/* The rock: flat, with an outcrop steeper than the sand downwind of the toe. */
static double rock(double x) {
    const double d = fabs(x - 50.0);
    return d < 3.0 ? 0.8 * (3.0 - d) : 0.0; /* 38.7 degree flanks */
}

/* The dune: stoss at 12 degrees from x = 5 up to the brink at x = 30, slip face
 * at 36 degrees down to the rock. */
static double dune(double x) {
    const double brink = 30.0, height = tan(deg(12.0)) * (brink - 5.0);
    if (x < 5.0) return 0.0;
    if (x <= brink) return tan(deg(12.0)) * (x - 5.0);
    return fmax(0.0, height - tan(deg(36.0)) * (x - brink));
}

int main(int argc, char **argv) {
    dpsm_grid *g = NULL;
    if (dpsm_create_2d(NX, NY, kDx, kDx, &g) != DPSM_OK) {
        fprintf(stderr, "dpsm_create_2d: %s\n", dpsm_last_error(NULL));
        return 1;
    }
    static double zb[NX * NY], h[NX * NY], profile[SNAPSHOTS + 2][NX];
    for (int j = 0; j < NY; ++j)
        for (int i = 0; i < NX; ++i) {
            const double x = (i + 0.5) * kDx;
            zb[i + NX * j] = rock(x);
            h[i + NX * j] = rock(x) + dune(x);
        }
    CHECK(dpsm_set_repose_angle(g, deg(33.0)));
    CHECK(dpsm_set_mobility(g, 1.0));
    CHECK(dpsm_set_heights(g, h));
    CHECK(dpsm_set_bedrock(g, zb));
    /* Upwind the sand leaves the domain; downwind and across, walls (the
     * dune continues across the wind: a wall is a mirror). */
    CHECK(dpsm_set_boundary(g, DPSM_XMIN, DPSM_OPEN));
    for (int i = 0; i < NX; ++i) profile[0][i] = h[i];

    double mass0 = 0.0, elapsed = 0.0, substeps = 0.0, info = 0.0;
    CHECK(dpsm_get_mass(g, DPSM_MASS_TOTAL, &mass0));
    const double times[SNAPSHOTS] = {0.5, 2.0, 8.0, 32.0};
    for (int s = 0; s < SNAPSHOTS; ++s) {
        CHECK(dpsm_step(g, times[s] - elapsed));
        elapsed = times[s];
        CHECK(dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &info));
        substeps += info;
        CHECK(dpsm_get_heights(g, h));
        for (int i = 0; i < NX; ++i) profile[1 + s][i] = h[i];
    }
    CHECK(dpsm_step(g, 1e6)); /* to rest */
    CHECK(dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &info));
    substeps += info;
    double at_rest = 0.0, rest_time = 0.0;
    CHECK(dpsm_get_step_info(g, DPSM_INFO_AT_REST, &at_rest));
    CHECK(dpsm_get_step_info(g, DPSM_INFO_TIME_INTEGRATED, &rest_time));
    CHECK(dpsm_get_heights(g, h));
    for (int i = 0; i < NX; ++i) profile[SNAPSHOTS + 1][i] = h[i];

    /* What the host would check. */
    int failed = 0;
    double steepest_sand = 0.0, lowest_above_rock = INFINITY, brink_drop = 0.0, toe_advance = 0.0;
    const double toe0 = 30.0 + dune(30.0) / tan(deg(36.0)); /* where the slip face met the rock */
    for (int i = 0; i + 1 < NX; ++i) {
        const double sand_here = h[i] - zb[i], sand_next = h[i + 1] - zb[i + 1];
        lowest_above_rock = fmin(lowest_above_rock, sand_here);
        /* A face over sand on both sides: the slope the model limits. */
        if (sand_here > 1e-6 && sand_next > 1e-6) steepest_sand = fmax(steepest_sand, fabs(h[i + 1] - h[i]) / kDx);
        brink_drop = fmax(brink_drop, profile[0][i] - h[i]);
        if (h[i] - zb[i] > 1e-6) toe_advance = fmax(toe_advance, (i + 0.5) * kDx - toe0);
    }
    double total, sourced, external, outflow;
    CHECK(dpsm_get_mass(g, DPSM_MASS_TOTAL, &total));
    CHECK(dpsm_get_mass(g, DPSM_MASS_SOURCED, &sourced));
    CHECK(dpsm_get_mass(g, DPSM_MASS_EXTERNAL, &external));
    CHECK(dpsm_get_mass(g, DPSM_MASS_OUTFLOW, &outflow));
    const double residual = fabs(total - (sourced + external - outflow)) / mass0;

    printf("transverse dune on rock, %d x %d cells of %.3f m, repose 33 degrees, slip face 36 degrees\n", NX, NY, kDx);
    printf("  at rest: %s after t = %.2f (%.0f sub-steps)\n", at_rest ? "yes" : "no", elapsed + rest_time, substeps);
    printf("  steepest slope over sand: %.4f degrees (repose 33)\n", atan(steepest_sand) * 180.0 / kPi);
    printf("  brink lowered by %.3f m; the toe advanced %.3f m over the rock\n", brink_drop, toe_advance);
    printf("  lowest sand above the rock: %.3g m (never negative)\n", lowest_above_rock);
    printf("  mass ledger residual %.2e of the dune's mass\n", residual);
    if (!at_rest) failed = fprintf(stderr, "error: the dune did not come to rest\n");
    if (lowest_above_rock < 0.0) failed = fprintf(stderr, "error: the surface went below the rock\n");
    if (steepest_sand > tan(deg(33.0)) * (1.0 + DPSM_DEFAULT_REST_TOLERANCE) + 1e-12)
        failed = fprintf(stderr, "error: a slope over sand is supercritical at rest\n");
    if (residual > 1e-12) failed = fprintf(stderr, "error: the ledger does not close\n");

    if (argc > 1) {
        FILE *f = fopen(argv[1], "w");
        if (!f) {
            perror(argv[1]);
            return 1;
        }
        fprintf(f, "x,bed,initial");
        for (int s = 0; s < SNAPSHOTS; ++s) fprintf(f, ",t=%g", times[s]);
        fprintf(f, ",rest\n");
        for (int i = 0; i < NX; ++i) {
            fprintf(f, "%.4f,%.6f", (i + 0.5) * kDx, zb[i]);
            for (int s = 0; s < SNAPSHOTS + 2; ++s) fprintf(f, ",%.6f", profile[s][i]);
            fprintf(f, "\n");
        }
        fclose(f);
    }
    dpsm_destroy(g);
    return failed ? 1 : 0;
}
