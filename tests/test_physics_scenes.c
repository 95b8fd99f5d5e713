/* The physics of real scenes (issue 8), feature by feature: a bed that cannot
 * erode, an angle of repose per cell, the flux exponent, hysteresis. Each test
 * asserts what the feature promises and prints the figures it measured. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "test_support.h"

static const double kDeg = 3.14159265358979323846 / 180.0;

static double unmet_of(const dpsm_grid *g) { return mass_of(g, DPSM_MASS_UNMET); }

/* ------------------------------------------------------------------------ */
/* Bed                                                                       */
/* ------------------------------------------------------------------------ */

/* A thin layer of sand on rock steeper than the angle of repose, eroded
 * faster than it has sand in places, with an open foot. The surface never
 * goes below the bed; erosion that found no sand is reported as unmet; the
 * ledger closes and SOURCED is what was asked for less what was unmet. */
static void check_bed_scene(dpsm_grid *g, int64_t nx, int64_t ny, double dx, double dy, int to_rest) {
    const int64_t n = nx * ny;
    double *zb = malloc(sizeof(double) * n), *h = malloc(sizeof(double) * n), *q = calloc(n, sizeof(double));
    for (int64_t j = 0; j < ny; ++j)
        for (int64_t i = 0; i < nx; ++i) {
            const int64_t c = i + nx * j;
            zb[c] = 1.0 * (double)i * dx;                         /* rock at slope 1 > tan 30 degrees */
            h[c] = zb[c] + 0.05 + 0.02 * sin(0.7 * (double)(i + 3 * j)); /* 3 to 7 cm of sand */
            if (i % 5 == 2) q[c] = -0.2;                            /* erosion that outruns the sand */
            if (i % 7 == 4) q[c] = 0.01;                            /* a little deposition */
        }
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_bedrock(g, zb));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMIN, DPSM_OPEN));
    CHECK_OK(g, dpsm_set_source(g, q));
    double asked_rate = 0.0;
    for (int64_t c = 0; c < n; ++c) asked_rate += q[c] * dx * dy;
    double dt = 0.0, asked = 0.0, lowest = INFINITY;
    CHECK_OK(g, dpsm_stable_dt(g, &dt));
    for (int k = 0; k < 200; ++k) {
        CHECK_OK(g, dpsm_step(g, 3.0 * dt));
        asked += asked_rate * 3.0 * dt;
        CHECK_OK(g, dpsm_get_heights(g, h));
        for (int64_t c = 0; c < n; ++c) {
            REQUIRE(h[c] >= zb[c], "step %d: cell %lld at %.17g is below its bed %.17g", k, (long long)c, h[c], zb[c]);
            lowest = fmin(lowest, h[c] - zb[c]);
        }
    }
    const ledger_t l = read_ledger(g);
    const double unmet = unmet_of(g);
    printf("bed %lldx%lld: sand left above the bed at least %.3g, unmet erosion %.6g of %.6g asked, "
           "ledger residual %.2e, sourced - (asked + unmet) = %.2e\n",
           (long long)nx, (long long)ny, lowest, unmet, asked, ledger_residual(g), l.sourced - (asked + unmet));
    REQUIRE(unmet > 0.01, "erosion on thin sand must find bare rock: unmet = %g", unmet);
    REQUIRE(ledger_residual(g) < 1e-12, "ledger residual %.3g", ledger_residual(g));
    REQUIRE(fabs(l.sourced - (asked + unmet)) < 1e-9 * fabs(asked), "sourced %.17g, asked %.17g, unmet %.17g",
            l.sourced, asked, unmet);
    /* With the erosion off, what is left on the steep rock drains to the open
     * foot or stays where the cap lets it: the bare rock does not count as
     * moving, so the scene comes to rest. (On the isotropic scheme the last
     * sand at the foot relaxes slowly: the rock's slope enters every face's
     * transverse slope; 2.4e5 sub-steps here, so that grid is only stepped.) */
    CHECK_OK(g, dpsm_set_source(g, NULL));
    CHECK_OK(g, dpsm_step(g, to_rest ? 1e7 : 100.0));
    if (to_rest)
        REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) == 1.0, "a bed steeper than the angle of repose must come to rest");
    CHECK_OK(g, dpsm_get_heights(g, h));
    for (int64_t c = 0; c < n; ++c) REQUIRE(h[c] >= zb[c], "cell %lld below its bed at rest", (long long)c);
    REQUIRE(ledger_residual(g) < 1e-12, "ledger residual %.3g at rest", ledger_residual(g));
    free(zb);
    free(h);
    free(q);
}

static void test_bed_never_crossed_1d(void **state) {
    (void)state;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_1d(80, 0.5, &g));
    check_bed_scene(g, 80, 1, 0.5, 1.0, 1);
    dpsm_destroy(g);
}

static void test_bed_never_crossed_2d(void **state) {
    (void)state;
    for (int scheme = DPSM_SCHEME_PAIRWISE; scheme <= DPSM_SCHEME_ISOTROPIC; ++scheme) {
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, dpsm_create_2d(90, 70, 0.5, 0.5, &g)); /* several tiles */
        CHECK_OK(g, dpsm_set_scheme(g, scheme));
        check_bed_scene(g, 90, 70, 0.5, 0.5, scheme == DPSM_SCHEME_PAIRWISE);
        dpsm_destroy(g);
    }
}

/* Erosion that asks a million times more than the sand there: each cell loses
 * exactly its sand, and SOURCED books exactly that loss, not the rate asked
 * for less the unmet part (two figures 1e6 times larger whose rounding left
 * the ledger open by 1.4e-10; found by the API fuzzer). 1D, axisymmetric and
 * 2D with both schemes. */
static void test_erosion_far_beyond_the_sand_closes_the_ledger(void **state) {
    (void)state;
    enum { N = 9 };
    for (int shape = 0; shape < 4; ++shape) {
        dpsm_grid *g = NULL;
        int64_t n = N;
        if (shape == 0) CHECK_OK(NULL, dpsm_create_1d(N, 1.0, &g));
        if (shape == 1) CHECK_OK(NULL, dpsm_create_axisymmetric(N, 1.0, &g));
        if (shape >= 2) {
            CHECK_OK(NULL, dpsm_create_2d(N, N, 1.0, 1.0, &g));
            CHECK_OK(g, dpsm_set_scheme(g, shape == 2 ? DPSM_SCHEME_PAIRWISE : DPSM_SCHEME_ISOTROPIC));
            n = N * N;
        }
        double zb[N * N], h[N * N], q[N * N];
        for (int64_t c = 0; c < n; ++c) {
            zb[c] = 1.0;
            h[c] = 4.0;
            q[c] = -1e6;
        }
        CHECK_OK(g, dpsm_set_heights(g, h));
        CHECK_OK(g, dpsm_set_bedrock(g, zb));
        double before = 0.0, dt = 0.0; /* heights 4 on a bed of 1: three quarters of it is sand */
        CHECK_OK(g, dpsm_get_mass(g, DPSM_MASS_TOTAL, &before));
        CHECK_OK(g, dpsm_set_mobility(g, 1e-6)); /* a stable sub-step of 1e5 or more: 1e11 asked per cell */
        CHECK_OK(g, dpsm_set_source(g, q));
        CHECK_OK(g, dpsm_stable_dt(g, &dt));
        CHECK_OK(g, dpsm_step(g, 100.0 * dt));
        CHECK_OK(g, dpsm_get_heights(g, h));
        for (int64_t c = 0; c < n; ++c)
            REQUIRE(h[c] == zb[c], "shape %d: cell %lld at %.17g, not its bed", shape, (long long)c, h[c]);
        const ledger_t l = read_ledger(g);
        const double unmet = unmet_of(g);
        printf("erosion 1e6 times the sand (shape %d): sourced %.17g for sand %.17g, unmet %.6g, "
               "ledger residual %.2e\n",
               shape, l.sourced, 0.75 * before, unmet, ledger_residual(g));
        REQUIRE(ledger_residual(g) < 1e-14, "shape %d: ledger residual %.3g", shape, ledger_residual(g));
        REQUIRE(fabs(l.sourced + 0.75 * before) < 1e-14 * before, "shape %d: sourced %.17g for sand %.17g", shape,
                l.sourced, 0.75 * before);
        REQUIRE(unmet > 1e9 * -l.sourced, "shape %d: unmet %.6g for sourced %.6g", shape, unmet, l.sourced);
        dpsm_destroy(g);
    }
}

/* Bare rock, however steep, does not move: the first step finds it at rest. */
static void test_bare_rock_is_at_rest(void **state) {
    (void)state;
    enum { NX = 40, NY = 30 };
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(NX, NY, 1.0, 1.0, &g));
    set_all_sides(g, DPSM_OPEN, 2);
    double zb[NX * NY], h[NX * NY];
    for (int c = 0; c < NX * NY; ++c) zb[c] = 3.0 * (c % NX) + 2.0 + 2.0 * sin(0.3 * (c / NX)); /* 72 degrees, rough, above the open sides' 0 */
    CHECK_OK(g, dpsm_set_heights(g, zb));
    CHECK_OK(g, dpsm_set_bedrock(g, zb));
    CHECK_OK(g, dpsm_step(g, 100.0));
    REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) == 1.0 && step_info_of(g, DPSM_INFO_SUBSTEPS) == 0.0,
            "bare rock must be at rest at once");
    CHECK_OK(g, dpsm_get_heights(g, h));
    REQUIRE(memcmp(h, zb, sizeof h) == 0, "bare rock moved");
    dpsm_destroy(g);
}

static void test_bed_axisymmetric(void **state) {
    (void)state;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_axisymmetric(60, 0.5, &g));
    const int n = 60;
    double zb[60], h[60];
    for (int i = 0; i < n; ++i) {
        zb[i] = 20.0 - 1.0 * (i + 0.5) * 0.5; /* a rocky cone, steeper than the sand */
        h[i] = zb[i] + (i < 10 ? 2.0 : 0.01);  /* a cap of sand on its top */
    }
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_bedrock(g, zb));
    CHECK_OK(g, dpsm_step(g, 1e6));
    CHECK_OK(g, dpsm_get_heights(g, h));
    for (int i = 0; i < n; ++i) REQUIRE(h[i] >= zb[i], "ring %d below its bed", i);
    REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) == 1.0, "the sand on the rocky cone comes to rest");
    REQUIRE(ledger_residual(g) < 1e-12, "ledger residual %.3g", ledger_residual(g));
    dpsm_destroy(g);
}

/* A scene that uses no feature moves by the same law through the kernels
 * with physics (here switched on by a bed far below every cell), vectorised
 * and scalar (DPSM_SCALAR_PHYSICS=1), and the plain vectorised kernels: the
 * three agree to round-off. */
static void test_physics_kernel_matches_plain_kernel(void **state) {
    (void)state;
    enum { NX = 100, NY = 80 };
    double *h[3];
    for (int run = 0; run < 3; ++run) { /* plain, bed on the vectorised kernels, bed on the scalar kernel */
        const int with_bed = run > 0;
        if (run == 2) setenv("DPSM_SCALAR_PHYSICS", "1", 1);
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, dpsm_create_2d(NX, NY, 1.0, 1.0, &g));
        /* The same sub-steps through both kernels (a bed is never relaxed to rest). */
        CHECK_OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE));
        set_all_sides(g, DPSM_OPEN, 2);
        h[run] = malloc(sizeof(double) * NX * NY);
        double *zb = malloc(sizeof(double) * NX * NY);
        for (int j = 0; j < NY; ++j)
            for (int i = 0; i < NX; ++i) {
                const double r = hypot(i - 50.5, j - 40.5);
                h[run][i + NX * j] = r < 12.0 ? 10.0 : 0.0;
                zb[i + NX * j] = -100.0;
            }
        CHECK_OK(g, dpsm_set_heights(g, h[run]));
        if (with_bed) CHECK_OK(g, dpsm_set_bedrock(g, zb));
        CHECK_OK(g, dpsm_step(g, 400.0));
        CHECK_OK(g, dpsm_get_heights(g, h[run]));
        unsetenv("DPSM_SCALAR_PHYSICS");
        free(zb);
        dpsm_destroy(g);
    }
    for (int run = 1; run < 3; ++run) {
        double worst = 0.0;
        for (int c = 0; c < NX * NY; ++c) worst = fmax(worst, fabs(h[0][c] - h[run][c]));
        printf("%s physics kernel against the plain vectorised kernel: largest height difference %.3g (of 10)\n",
               run == 1 ? "vectorised" : "scalar", worst);
        REQUIRE(worst < 1e-9, "the two kernels differ by %.3g", worst);
    }
    for (int run = 0; run < 3; ++run) free(h[run]);
}

/* ------------------------------------------------------------------------ */
/* Angle of repose per cell                                                  */
/* ------------------------------------------------------------------------ */

/* Angles that change from cell to cell (here drawn from 0.5 to 89.5 degrees)
 * let the faces across a face rest steeper than that face's own threshold, so
 * on the isotropic scheme a face can be supercritical by its transverse slope
 * alone. Its flux levels its two cells; once they are level to within the
 * rounding of their heights it carries nothing, and the scene comes to rest.
 * (It did not: an ulp went back and forth between two cells for ever, and
 * dpsm_step(huge dt) never returned; found by the stress suite. These seeds
 * were not at rest after 6e6 sub-steps then; they rest after 3e4 to 8e4 now.)
 * Bounded work here, so that a regression fails instead of hanging. */
static void test_angle_field_comes_to_rest_isotropic(void **state) {
    (void)state;
    enum { NX = 24, NY = 27 };
    for (int seed = 1; seed < 4; ++seed) {
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, dpsm_create_2d(NX, NY, 0.5, 0.5, &g));
        double h[NX * NY], theta[NX * NY];
        uint64_t r = 0x9E3779B97F4A7C15ull * (uint64_t)(seed + 1);
        for (int j = 0; j < NY; ++j)
            for (int i = 0; i < NX; ++i) {
                r = r * 6364136223846793005ull + 1442695040888963407ull;
                const double u = (double)(r >> 11) / 9007199254740992.0;
                r = r * 6364136223846793005ull + 1442695040888963407ull;
                const double v = (double)(r >> 11) / 9007199254740992.0;
                const int column = 3 * i >= NX && 3 * i < 2 * NX && 3 * j >= NY && 3 * j < 2 * NY;
                h[i + NX * j] = 0.1 * (2.0 * u - 1.0) + (column ? 4.0 : 0.0);
                theta[i + NX * j] = (0.5 + 89.0 * v) * kDeg;
            }
        CHECK_OK(g, dpsm_set_heights(g, h));
        CHECK_OK(g, dpsm_set_repose_angle_field(g, theta));
        double dt = 0.0;
        CHECK_OK(g, dpsm_stable_dt(g, &dt));
        CHECK_OK(g, dpsm_step(g, 1e6 * dt));
        const double substeps = step_info_of(g, DPSM_INFO_SUBSTEPS);
        REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) == 1.0, "seed %d: not at rest after 1e6 sub-steps", seed);
        printf("angle field 0.5 .. 89.5 deg, seed %d: at rest after %.0f sub-steps, ledger residual %.2e\n", seed,
               substeps, ledger_residual(g));
        REQUIRE(ledger_residual(g) < 1e-12, "ledger residual %.3g", ledger_residual(g));
        dpsm_destroy(g);
    }
}

/* Two patches, 25 and 40 degrees, each with a column that collapses into a
 * cone: each pile takes the height of the exact volume-conserving cone at its
 * own patch's angle, h_f = tan(theta) r0 (3 a / tan(theta))^(1/3). */
static void test_angle_field_gives_a_pile_per_patch(void **state) {
    (void)state;
    enum { NX = 120, NY = 60 };
    const double r0 = 8.0, h0 = 16.0, angles[2] = {25.0 * kDeg, 40.0 * kDeg};
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(NX, NY, 1.0, 1.0, &g));
    double *h = malloc(sizeof(double) * NX * NY), *theta = malloc(sizeof(double) * NX * NY);
    for (int j = 0; j < NY; ++j)
        for (int i = 0; i < NX; ++i) {
            const int patch = i < NX / 2;
            const double cx = patch ? 30.0 : 90.0;
            theta[i + NX * j] = angles[patch ? 0 : 1];
            h[i + NX * j] = hypot(i + 0.5 - cx, j + 0.5 - 30.0) < r0 ? h0 : 0.0;
        }
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_repose_angle_field(g, theta));
    double dt_field = 0.0;
    CHECK_OK(g, dpsm_stable_dt(g, &dt_field));
    REQUIRE(fabs(dt_field - 1.0 / (4.0 * cos(angles[0]))) < 1e-15, "the stable step follows the smallest angle: %.17g",
            dt_field);
    CHECK_OK(g, dpsm_step(g, 1e6));
    REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) == 1.0, "the piles come to rest");
    CHECK_OK(g, dpsm_get_heights(g, h));
    for (int patch = 0; patch < 2; ++patch) {
        double top = 0.0, edge = 0.0;
        for (int j = 0; j < NY; ++j)
            for (int i = patch ? 0 : NX / 2; i < (patch ? NX / 2 : NX); ++i) top = fmax(top, h[i + NX * j]);
        for (int j = 0; j < NY; ++j) edge = fmax(edge, h[NX / 2 - 1 + NX * j] + h[NX / 2 + NX * j]);
        const double alpha = tan(angles[patch ? 0 : 1]), a = h0 / r0;
        const double exact = alpha * r0 * cbrt(3.0 * a / alpha);
        printf("patch at %.0f degrees: pile top %.4f, exact cone %.4f (%+.2f %%)\n", (patch ? 25.0 : 40.0), top, exact,
               100.0 * (top - exact) / exact);
        REQUIRE(fabs(top - exact) < 0.03 * exact, "pile top %.4f, exact %.4f", top, exact);
        REQUIRE(edge == 0.0, "the piles stay on their patches");
    }
    REQUIRE(ledger_residual(g) < 1e-12, "ledger residual %.3g", ledger_residual(g));
    /* NULL returns to the uniform angle: a fresh copy of the heights rests at once. */
    CHECK_OK(g, dpsm_set_repose_angle_field(g, NULL));
    CHECK_OK(g, dpsm_stable_dt(g, &dt_field));
    REQUIRE(fabs(dt_field - 1.0 / (4.0 * cos(DPSM_DEFAULT_REPOSE_ANGLE))) < 1e-15, "uniform again: %.17g", dt_field);
    free(h);
    free(theta);
    dpsm_destroy(g);
}

/* In 1D the piles are exact trapezoids; the 40-degree patch keeps its slope
 * where the 25-degree one would have flattened it. */
static void test_angle_field_1d(void **state) {
    (void)state;
    enum { N = 200 };
    const double dx = 0.1;
    double h[N], theta[N];
    for (int i = 0; i < N; ++i) {
        theta[i] = (i < N / 2 ? 25.0 : 40.0) * kDeg;
        h[i] = (abs(i - 50) < 10 || abs(i - 150) < 10) ? 1.0 : 0.0;
    }
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_1d(N, dx, &g));
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_repose_angle_field(g, theta));
    CHECK_OK(g, dpsm_step(g, 1e6));
    CHECK_OK(g, dpsm_get_heights(g, h));
    for (int patch = 0; patch < 2; ++patch) {
        double steepest = 0.0;
        for (int i = patch * N / 2; i + 1 < (patch + 1) * N / 2; ++i) steepest = fmax(steepest, fabs(h[i + 1] - h[i]) / dx);
        const double alpha = tan(theta[patch * N / 2]);
        printf("1D patch %d: steepest slope %.6f, tan(theta) %.6f\n", patch, steepest, alpha);
        REQUIRE(steepest <= alpha * (1.0 + DPSM_DEFAULT_REST_TOLERANCE) + 1e-12, "slope %.9f above %.9f", steepest,
                alpha);
        REQUIRE(steepest >= alpha * 0.999, "the flanks rest at the patch's angle: %.9f, expected %.9f", steepest, alpha);
    }
    dpsm_destroy(g);
}

/* ------------------------------------------------------------------------ */
/* Flux exponent                                                             */
/* ------------------------------------------------------------------------ */

/* The speed the law promises: two cells with slope s exchange
 * nu (s - tan theta)^p / sqrt(1 + s^2) per unit length in one sub-step. */
static void test_flux_exponent_sets_the_speed(void **state) {
    (void)state;
    const double exponents[] = {1.0, 1.5, 2.0}, s = 3.0, nu = 0.7;
    for (size_t k = 0; k < sizeof exponents / sizeof *exponents; ++k) {
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, dpsm_create_1d(2, 1.0, &g));
        CHECK_OK(g, dpsm_set_mobility(g, nu));
        CHECK_OK(g, dpsm_set_flux_exponent(g, exponents[k]));
        const double h0[2] = {s, 0.0};
        CHECK_OK(g, dpsm_set_heights(g, h0));
        double dt = 0.0, h[2];
        CHECK_OK(g, dpsm_stable_dt(g, &dt));
        CHECK_OK(g, dpsm_step(g, dt));
        CHECK_OK(g, dpsm_get_heights(g, h));
        const double alpha = tan(DPSM_DEFAULT_REPOSE_ANGLE);
        const double expected = dt * nu * pow(s - alpha, exponents[k]) / sqrt(1.0 + s * s);
        printf("p = %.1f: stable dt %.6f, moved %.15f, law %.15f\n", exponents[k], dt, s - h[0], expected);
        REQUIRE(fabs((s - h[0]) - expected) < 1e-14, "p = %g: moved %.17g, law %.17g", exponents[k], s - h[0], expected);
        REQUIRE(fabs((h[1] - h0[1]) - (s - h[0])) < 1e-15, "mass moves face by face");
        dpsm_destroy(g);
    }
}

/* A steep column relaxes under p = 1 and p = 2 to the same exact trapezoid
 * (1D: top at h0, flanks at the angle of repose); p = 2 never overshoots
 * (no new extremum at its stable step) and takes longer over the slightly
 * supercritical tail: its excess decays like 1/t, not exponentially, so the
 * time to rest grows like 1/tol (hence a tolerance of 1e-3 here; at the
 * default 1e-6 p = 2 took over 5e7 sub-steps on this scene at dx = 0.05). */
static void test_flux_exponent_same_rest_state(void **state) {
    (void)state;
    enum { N = 150 };
    const double dx = 0.1, half = 2.0, h0 = 1.0;
    const double alpha = tan(DPSM_DEFAULT_REPOSE_ANGLE);
    double substeps[2];
    for (int k = 0; k < 2; ++k) {
        const double p = k == 0 ? 1.0 : 2.0;
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, dpsm_create_1d(N, dx, &g));
        CHECK_OK(g, dpsm_set_flux_exponent(g, p));
        CHECK_OK(g, dpsm_set_rest_tolerance(g, 1e-3));
        double h[N];
        for (int i = 0; i < N; ++i) h[i] = fabs((i + 0.5) * dx - N * dx / 2) < half ? h0 : 0.0;
        CHECK_OK(g, dpsm_set_heights(g, h));
        double dt = 0.0, total = 0.0;
        CHECK_OK(g, dpsm_stable_dt(g, &dt));
        for (int n = 0; n < 100000 && !step_info_of(g, DPSM_INFO_AT_REST); ++n) {
            CHECK_OK(g, dpsm_step(g, 50.0 * dt));
            total += step_info_of(g, DPSM_INFO_SUBSTEPS);
            CHECK_OK(g, dpsm_get_heights(g, h));
            REQUIRE(max_of(h, N) <= h0 && min_of(h, N) >= 0.0, "p = %g: new extremum %.17g / %.17g", p, max_of(h, N),
                    min_of(h, N));
        }
        REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) == 1.0, "p = %g: not at rest after %.0f sub-steps", p, total);
        substeps[k] = total;
        /* The exact trapezoid: top of half-width half - h0/(2 alpha), flanks at alpha. */
        const double top = half - h0 / (2.0 * alpha);
        double l1 = 0.0;
        for (int i = 0; i < N; ++i) {
            const double x = fabs((i + 0.5) * dx - N * dx / 2);
            const double exact = x < top ? h0 : fmax(0.0, h0 - alpha * (x - top));
            l1 += fabs(h[i] - exact) * dx;
        }
        printf("p = %.0f: stable dt %.4f, %.0f sub-steps to rest, L1/volume against the exact trapezoid %.3f %%\n", p,
               dt, total, 100.0 * l1 / (2.0 * half * h0));
        REQUIRE(l1 / (2.0 * half * h0) < 0.01, "p = %g: L1/volume %.4f", p, l1 / (2.0 * half * h0));
        dpsm_destroy(g);
    }
    REQUIRE(substeps[1] > substeps[0], "p = 2 relaxes its slightly supercritical tail more slowly: %.0f vs %.0f",
            substeps[1], substeps[0]);
}

/* ------------------------------------------------------------------------ */
/* Hysteresis                                                                */
/* ------------------------------------------------------------------------ */

/* A ramp between walls, 1D or 2D (a ramp along x, uniform in y). */
static dpsm_grid *ramp(int dim, double slope_deg, double *h, int n) {
    dpsm_grid *g = NULL;
    if (dim == 1)
        CHECK_OK(NULL, dpsm_create_1d(n, 1.0, &g));
    else
        CHECK_OK(NULL, dpsm_create_2d(n, 20, 1.0, 1.0, &g));
    const int rows = dim == 1 ? 1 : 20;
    for (int j = 0; j < rows; ++j)
        for (int i = 0; i < n; ++i) h[i + n * j] = 20.0 + tan(slope_deg * kDeg) * (n - i);
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_repose_angle(g, 30.0 * kDeg));
    CHECK_OK(g, dpsm_set_static_angle(g, 35.0 * kDeg));
    return g;
}

static void test_hysteresis_holds_and_releases(void **state) {
    (void)state;
    enum { N = 40 };
    for (int dim = 1; dim <= 2; ++dim) {
        const int cells = dim == 1 ? N : N * 20;
        double *h = malloc(sizeof(double) * cells), *before = malloc(sizeof(double) * cells);
        /* 33 degrees: steeper than the angle of repose, not the static angle. */
        dpsm_grid *g = ramp(dim, 33.0, before, N);
        CHECK_OK(g, dpsm_step(g, 1e4));
        CHECK_OK(g, dpsm_get_heights(g, h));
        REQUIRE(memcmp(h, before, sizeof(double) * cells) == 0, "%dD: a 33-degree slope must hold", dim);
        REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) == 1.0, "%dD: at rest", dim);
        /* The same slope without hysteresis flows: the static angle is what held it. */
        dpsm_grid *paper = NULL;
        if (dim == 1)
            CHECK_OK(NULL, dpsm_create_1d(N, 1.0, &paper));
        else
            CHECK_OK(NULL, dpsm_create_2d(N, 20, 1.0, 1.0, &paper));
        CHECK_OK(paper, dpsm_set_heights(paper, before));
        CHECK_OK(paper, dpsm_set_repose_angle(paper, 30.0 * kDeg));
        CHECK_OK(paper, dpsm_step(paper, 10.0));
        CHECK_OK(paper, dpsm_get_heights(paper, h));
        REQUIRE(memcmp(h, before, sizeof(double) * cells) != 0, "%dD: without a static angle the slope flows", dim);
        dpsm_destroy(paper);
        dpsm_destroy(g);

        /* 38 degrees: released, and it relaxes to the angle of repose, not to the static angle. */
        g = ramp(dim, 38.0, before, N);
        CHECK_OK(g, dpsm_step(g, 1e6));
        REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) == 1.0, "%dD: the released slope comes to rest", dim);
        CHECK_OK(g, dpsm_get_heights(g, h));
        double steepest = 0.0;
        for (int j = 0; j < (dim == 1 ? 1 : 20); ++j)
            for (int i = 2; i + 3 < N; ++i) steepest = fmax(steepest, fabs(h[i + 1 + N * j] - h[i + N * j]));
        printf("%dD hysteresis: 33 degrees held; 38 degrees released to a slope of %.4f degrees (repose 30, static 35)\n",
               dim, atan(steepest) / kDeg);
        REQUIRE(steepest < tan(30.0 * kDeg) * (1.0 + 1e-5), "%dD: steepest %.6f degrees", dim, atan(steepest) / kDeg);
        REQUIRE(steepest > tan(30.0 * kDeg) * 0.999, "%dD: the slope stops at the angle of repose: %.6f degrees", dim,
                atan(steepest) / kDeg);
        REQUIRE(ledger_residual(g) < 1e-12, "ledger residual %.3g", ledger_residual(g));
        free(h);
        free(before);
        dpsm_destroy(g);
    }
}

/* Sand is poured on a slope held by hysteresis: it builds up until the static
 * angle is exceeded somewhere, then avalanches (moving cells carry on at the
 * angle of repose), and stops: intermittent avalanching. */
static void test_hysteresis_intermittent_avalanches(void **state) {
    (void)state;
    enum { N = 60 };
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_1d(N, 1.0, &g));
    CHECK_OK(g, dpsm_set_repose_angle(g, 30.0 * kDeg));
    CHECK_OK(g, dpsm_set_static_angle(g, 34.0 * kDeg));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN));
    double q[N] = {0}, h[N];
    q[0] = 0.02;
    int avalanches = 0, was_moving = 0;
    double steepest_ever = 0.0;
    for (int n = 0; n < 4000; ++n) {
        CHECK_OK(g, dpsm_set_source(g, q));
        CHECK_OK(g, dpsm_step(g, 1.0));
        CHECK_OK(g, dpsm_set_source(g, NULL));
        CHECK_OK(g, dpsm_step(g, 1e6)); /* let any avalanche finish */
        const int moving = step_info_of(g, DPSM_INFO_SUBSTEPS) > 0;
        avalanches += moving && !was_moving;
        was_moving = moving;
        CHECK_OK(g, dpsm_get_heights(g, h));
        for (int i = 0; i + 1 < N; ++i) steepest_ever = fmax(steepest_ever, fabs(h[i + 1] - h[i]));
    }
    printf("intermittent avalanches under a source: %d, steepest slope seen %.3f degrees (static 34)\n", avalanches,
           atan(steepest_ever) / kDeg);
    REQUIRE(avalanches >= 3, "expected repeated avalanches, saw %d", avalanches);
    REQUIRE(steepest_ever <= tan(34.0 * kDeg) + 0.05, "slopes stay near the static angle: %.4f", steepest_ever);
    REQUIRE(ledger_residual(g) < 1e-12, "ledger residual %.3g", ledger_residual(g));
    dpsm_destroy(g);
}

/* ------------------------------------------------------------------------ */
/* Everything at once: no result depends on the active set or the threads    */
/* ------------------------------------------------------------------------ */

static double *run_physics_scene(int threads, int visit_all, double *unmet) {
    enum { NX = 150, NY = 100 };
    if (visit_all)
        setenv("DPSM_VISIT_ALL_TILES", "1", 1);
    else
        unsetenv("DPSM_VISIT_ALL_TILES");
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(NX, NY, 0.5, 0.5, &g));
    CHECK_OK(g, dpsm_set_threads(g, threads));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMIN, DPSM_OPEN));
    double *h = malloc(sizeof(double) * NX * NY), *zb = malloc(sizeof(double) * NX * NY);
    double *theta = malloc(sizeof(double) * NX * NY), *q = calloc(NX * NY, sizeof(double));
    for (int j = 0; j < NY; ++j)
        for (int i = 0; i < NX; ++i) {
            const int c = i + NX * j;
            zb[c] = 0.2 * i * 0.5;
            h[c] = zb[c] + 0.3 + (abs(i - 40) < 5 && abs(j - 50) < 5 ? 3.0 : 0.0) +
                   (abs(i - 120) < 4 && abs(j - 20) < 4 ? 2.0 : 0.0);
            theta[c] = (j < 50 ? 30.0 : 36.0) * kDeg;
            if (abs(i - 100) < 3 && abs(j - 80) < 3) q[c] = -0.5;
        }
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_bedrock(g, zb));
    CHECK_OK(g, dpsm_set_repose_angle_field(g, theta));
    CHECK_OK(g, dpsm_set_flux_exponent(g, 1.5));
    CHECK_OK(g, dpsm_set_rest_tolerance(g, 1e-3)); /* p > 1 rests in bounded time (see above) */
    CHECK_OK(g, dpsm_set_static_angle(g, 33.0 * kDeg));
    CHECK_OK(g, dpsm_set_source(g, q));
    for (int n = 0; n < 10; ++n) CHECK_OK(g, dpsm_step(g, 0.7));
    CHECK_OK(g, dpsm_set_source(g, NULL));
    for (int n = 0; n < 5; ++n) CHECK_OK(g, dpsm_step(g, 5.0));
    CHECK_OK(g, dpsm_get_heights(g, h));
    *unmet = unmet_of(g);
    REQUIRE(ledger_residual(g) < 1e-12, "ledger residual %.3g", ledger_residual(g));
    for (int c = 0; c < NX * NY; ++c) REQUIRE(h[c] >= zb[c], "cell %d below its bed", c);
    unsetenv("DPSM_VISIT_ALL_TILES");
    free(zb);
    free(theta);
    free(q);
    dpsm_destroy(g);
    return h;
}

static void test_physics_independent_of_active_set_and_threads(void **state) {
    (void)state;
    double unmet_ref = 0.0, unmet = 0.0;
    double *ref = run_physics_scene(1, 1, &unmet_ref);
    const int cases[][2] = {{1, 0}, {2, 0}, {3, 1}};
    for (size_t k = 0; k < sizeof cases / sizeof *cases; ++k) {
        double *h = run_physics_scene(cases[k][0], cases[k][1], &unmet);
        REQUIRE(memcmp(h, ref, sizeof(double) * 150 * 100) == 0, "threads %d, visit all %d: heights differ",
                cases[k][0], cases[k][1]);
        REQUIRE(unmet == unmet_ref, "unmet %.17g vs %.17g", unmet, unmet_ref);
        free(h);
    }
    REQUIRE(unmet_ref > 0.0, "the scene's erosion meets bare rock: %g", unmet_ref);
    free(ref);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bed_never_crossed_1d),
        cmocka_unit_test(test_bed_never_crossed_2d),
        cmocka_unit_test(test_erosion_far_beyond_the_sand_closes_the_ledger),
        cmocka_unit_test(test_bare_rock_is_at_rest),
        cmocka_unit_test(test_bed_axisymmetric),
        cmocka_unit_test(test_physics_kernel_matches_plain_kernel),
        cmocka_unit_test(test_angle_field_gives_a_pile_per_patch),
        cmocka_unit_test(test_angle_field_comes_to_rest_isotropic),
        cmocka_unit_test(test_angle_field_1d),
        cmocka_unit_test(test_flux_exponent_sets_the_speed),
        cmocka_unit_test(test_flux_exponent_same_rest_state),
        cmocka_unit_test(test_hysteresis_holds_and_releases),
        cmocka_unit_test(test_hysteresis_intermittent_avalanches),
        cmocka_unit_test(test_physics_independent_of_active_set_and_threads),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
