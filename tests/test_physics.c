/* The physics of both schemes: conservation, the discrete maximum principle, the paper's steady states and scenes (Eqs. 15-16,
 * Figs. 3c and 4a), obstacles, open cells, and steps far beyond the stable one.
 * Each test prints the figure it checks, so a failing run says by how much. */
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

static const double kPi = 3.14159265358979323846;

static double deg(double d) { return d * kPi / 180.0; }

/* A reproducible rough terrain in [0, amplitude). */
static void rough_terrain(double *h, size_t n, double amplitude, unsigned seed) {
    unsigned s = seed;
    for (size_t c = 0; c < n; ++c) {
        s = s * 1664525u + 1013904223u;
        h[c] = amplitude * (double)(s >> 8) / (double)(1u << 24);
    }
}

/* Walls all round: the sand only rearranges, the mass stays to round-off. */
static void test_mass_is_conserved_between_walls(void **state) {
    (void)state;
    const int64_t nx = 48, ny = 32;
    for (int scheme = DPSM_SCHEME_PAIRWISE; scheme <= DPSM_SCHEME_ISOTROPIC; ++scheme) {
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, dpsm_create_2d(nx, ny, 0.1, 0.07, &g));
        CHECK_OK(g, dpsm_set_scheme(g, scheme));
        double *h = malloc(sizeof(double) * nx * ny);
        rough_terrain(h, nx * ny, 2.0, 7u);
        CHECK_OK(g, dpsm_set_heights(g, h));
        const double m0 = read_ledger(g).total;
        for (int k = 0; k < 20; ++k) CHECK_OK(g, dpsm_step(g, 0.01));
        const ledger_t l = read_ledger(g);
        const double drift = fabs(l.total - m0) / m0;
        print_message("walls, %s: relative mass drift %.2e, ledger residual %.2e, outflow %g\n",
                      scheme ? "isotropic" : "pairwise", drift, ledger_residual(g), l.outflow);
        assert_true(drift < 1e-13);
        assert_true(ledger_residual(g) < 1e-13);
        assert_true(l.outflow == 0.0);
        assert_true(l.sourced == 0.0);
        free(h);
        dpsm_destroy(g);
    }
}

/* Without sources the surface gains no new maximum or minimum (open sides
 * hold the outside at 0, so 0 counts as a level it may reach). */
static void test_no_new_extrema_without_source(void **state) {
    (void)state;
    const int64_t nx = 40, ny = 40;
    for (int run = 0; run < 4; ++run) {
        const int open = run & 1, scheme = run >> 1;
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, dpsm_create_2d(nx, ny, 1.0, 1.0, &g));
        CHECK_OK(g, dpsm_set_scheme(g, scheme));
        if (open) set_all_sides(g, DPSM_OPEN, 2);
        double *h = malloc(sizeof(double) * nx * ny);
        rough_terrain(h, nx * ny, 5.0, 11u + open);
        for (int64_t c = 0; c < nx * ny; ++c) h[c] += 1.0; /* all above the outside level */
        const double hmax = max_of(h, nx * ny), hmin = open ? 0.0 : min_of(h, nx * ny);
        CHECK_OK(g, dpsm_set_heights(g, h));
        double worst_over = 0.0, worst_under = 0.0;
        for (int k = 0; k < 30; ++k) {
            CHECK_OK(g, dpsm_step(g, 0.5));
            CHECK_OK(g, dpsm_get_heights(g, h));
            worst_over = fmax(worst_over, max_of(h, nx * ny) - hmax);
            worst_under = fmax(worst_under, hmin - min_of(h, nx * ny));
        }
        print_message("%s sides, %s: worst new maximum %+.2e, worst new minimum %+.2e\n", open ? "open" : "wall",
                      scheme ? "isotropic" : "pairwise", worst_over, worst_under);
        assert_true(worst_over <= 0.0);
        assert_true(worst_under <= 0.0);
        free(h);
        dpsm_destroy(g);
    }
}

/* The paper's Eqs. 15-16: a uniform source q << nu/L on an open 1D table ends
 * in h = tan(theta) min(x, L - x) + q x (L - x) / (2 nu cos(theta)). The open
 * sides are nodes held at 0 one cell width beyond the edge cells, so cell i
 * sits at x = (i + 1) dx and L = (nx + 1) dx. */
static void test_open_table_steady_state_matches_eqs_15_16(void **state) {
    (void)state;
    const int64_t nx = 49;
    const double L = 1.0, dx = L / (nx + 1), nu = 1.0, theta = deg(30.0), q = 0.01;
    const double alpha = tan(theta);
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_1d(nx, dx, &g));
    CHECK_OK(g, dpsm_set_repose_angle(g, theta));
    CHECK_OK(g, dpsm_set_mobility(g, nu));
    set_all_sides(g, DPSM_OPEN, 1);
    double source[49], h[49], previous[49];
    for (int i = 0; i < nx; ++i) source[i] = q;
    CHECK_OK(g, dpsm_set_source(g, source));
    for (int k = 0; k < 40; ++k) CHECK_OK(g, dpsm_step(g, 1.0));
    CHECK_OK(g, dpsm_get_heights(g, previous));
    CHECK_OK(g, dpsm_step(g, 1.0));
    CHECK_OK(g, dpsm_get_heights(g, h));

    double change = 0.0, worst = 0.0, bump_max = 0.0;
    for (int i = 0; i < nx; ++i) {
        const double x = (i + 1) * dx;
        const double bump = q * x * (L - x) / (2.0 * nu * cos(theta));
        const double exact = alpha * fmin(x, L - x) + bump;
        change = fmax(change, fabs(h[i] - previous[i]));
        worst = fmax(worst, fabs(h[i] - exact));
        bump_max = fmax(bump_max, bump);
    }
    /* Outflow balances the source at steady state. */
    const ledger_t l = read_ledger(g);
    print_message("Eq. 15-16: max |h - exact| = %.3e (%.2f%% of the parabolic term %.3e), change over the "
                  "last unit of time %.1e, ledger residual %.1e\n",
                  worst, 100.0 * worst / bump_max, bump_max, change, ledger_residual(g));
    assert_true(change < 1e-10);
    /* Eq. 15 is first order in q L / nu: the parabolic term must be right to a
     * few percent, far below its own size and far below tan(theta) dx. */
    assert_true(worst < 0.05 * bump_max);
    assert_true(ledger_residual(g) < 1e-12);
    assert_true(fabs(l.sourced - q * nx * dx * 41.0) < 1e-12);
    dpsm_destroy(g);
}

/* The paper's Fig. 3c: sand poured in (0.45, 0.55) between two walls. There is
 * no steady state: every grain stays, the pile is symmetric, and its flanks
 * stand at the angle of repose (a little steeper, as sand must flow down them). */
static void test_filling_between_two_walls_fig_3c(void **state) {
    (void)state;
    const int64_t nx = 100;
    const double dx = 0.01, nu = 1.0, theta = deg(45.0), q = 0.05;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_1d(nx, dx, &g));
    CHECK_OK(g, dpsm_set_repose_angle(g, theta));
    double source[100], h[100];
    for (int i = 0; i < nx; ++i) {
        const double x = (i + 0.5) * dx;
        source[i] = (x > 0.45 && x < 0.55) ? q : 0.0;
    }
    CHECK_OK(g, dpsm_set_source(g, source));
    const double t_end = 20.0;
    for (int k = 0; k < 20; ++k) CHECK_OK(g, dpsm_step(g, t_end / 20));
    CHECK_OK(g, dpsm_get_heights(g, h));

    const ledger_t l = read_ledger(g);
    const double poured = q * 10 * dx * t_end;
    double asymmetry = 0.0;
    for (int i = 0; i < nx / 2; ++i) asymmetry = fmax(asymmetry, fabs(h[i] - h[nx - 1 - i]));
    const double slope = max_face_slope(h, NULL, nx, 1, dx, 1.0);
    /* Quasi-static pile: with the mass M = poured it is a triangle of slope
     * tan(theta) (its top spread over the source) that has not reached the walls. */
    const double peak = max_of(h, nx);
    const double triangle_peak = sqrt(poured * tan(theta));
    print_message("Fig. 3c: poured %.6f, total %.6f, outflow %g; asymmetry %.1e; max slope %.4f (tan theta 1); "
                  "peak %.4f, triangle of the same mass %.4f\n",
                  poured, l.total, l.outflow, asymmetry, slope, peak, triangle_peak);
    assert_true(fabs(l.total - poured) < 1e-12 * poured);
    assert_true(l.outflow == 0.0);
    assert_true(asymmetry < 1e-12);
    assert_true(slope > tan(theta) && slope < tan(theta) * 1.05);
    assert_true(fabs(peak - triangle_peak) < 0.03 * triangle_peak);
    assert_true(h[0] == 0.0 && h[nx - 1] == 0.0); /* not yet at the walls */
    dpsm_destroy(g);
}

/* Pours q over a square open table of side 1 until the pile is steady and
 * returns its heights (n*n values, caller frees) and the outflow rate. */
static double *steady_pile_on_open_table(int64_t n, int scheme, double q, double nu, double theta, double t_end,
                                         double *outflow_rate) {
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(n, n, 1.0 / n, 1.0 / n, &g));
    CHECK_OK(g, dpsm_set_scheme(g, scheme));
    CHECK_OK(g, dpsm_set_repose_angle(g, theta));
    CHECK_OK(g, dpsm_set_mobility(g, nu));
    set_all_sides(g, DPSM_OPEN, 2);
    double *source = malloc(sizeof(double) * n * n), *h = malloc(sizeof(double) * n * n);
    for (int64_t c = 0; c < n * n; ++c) source[c] = q;
    CHECK_OK(g, dpsm_set_source(g, source));
    CHECK_OK(g, dpsm_step(g, t_end));
    const double out0 = read_ledger(g).outflow;
    CHECK_OK(g, dpsm_step(g, 1.0));
    *outflow_rate = read_ledger(g).outflow - out0;
    CHECK_OK(g, dpsm_get_heights(g, h));
    const ledger_t l = read_ledger(g);
    print_message("steady pile: ledger residual %.1e (total %.4f, sourced %.4f, outflow %.4f)\n", ledger_residual(g),
                  l.total, l.sourced, l.outflow);
    assert_true(ledger_residual(g) < 1e-12);
    free(source);
    dpsm_destroy(g);
    return h;
}

/* The largest difference under the 8 symmetries of the square. */
static double square_asymmetry(const double *h, int64_t n) {
    double worst = 0.0;
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) {
            const double v = h[i + n * j];
            worst = fmax(worst, fabs(v - h[(n - 1 - i) + n * j]));
            worst = fmax(worst, fabs(v - h[i + n * (n - 1 - j)]));
            worst = fmax(worst, fabs(v - h[j + n * i]));
        }
    return worst;
}

/* The paper's Fig. 4a: q/nu = 0.5 poured over a square open table reaches a
 * steady pile, symmetric, whose outflow balances the source. */
static void test_steady_pile_on_square_open_table_fig_4a(void **state) {
    (void)state;
    const int64_t n = 40;
    const double q = 0.5, nu = 1.0, theta = deg(30.0);
    double outflow_rate;
    double *h = steady_pile_on_open_table(n, DPSM_SCHEME_PAIRWISE, q, nu, theta, 5.0, &outflow_rate);
    const double centre = h[n / 2 + n * (n / 2)];
    print_message("Fig. 4a: outflow rate %.8f vs poured %.8f; asymmetry %.1e; centre %.4f (tan(theta) L/2 = %.4f)\n",
                  outflow_rate, q, square_asymmetry(h, n), centre, tan(theta) * 0.5);
    assert_true(fabs(outflow_rate - q) < 1e-6 * q); /* steady: all that is poured leaves */
    assert_true(square_asymmetry(h, n) < 1e-10);
    assert_true(centre > tan(theta) * 0.5); /* the flux needs slopes above the angle */
    free(h);
}

/* With a slow source the steady pile shows its shape: the pairwise scheme
 * limits the slope along each axis, so it is a pyramid, h = tan(theta) times
 * the distance to the nearest side, along the axes and along the diagonals
 * alike (a cone would be flat-zero near the corners). */
static void test_pairwise_scheme_builds_a_pyramid(void **state) {
    (void)state;
    /* Under AddressSanitizer a coarser table: the same kernels and the same
     * steady state, in a sixteenth of the work (45 s there at 40). */
#if defined(DPSM_TESTS_UNDER_ASAN)
    const int64_t n = 20;
#else
    const int64_t n = 40;
#endif
    const double q = 0.01, nu = 1.0, theta = deg(30.0), dx = 1.0 / n;
    double outflow_rate, worst = 0.0;
    double *h = steady_pile_on_open_table(n, DPSM_SCHEME_PAIRWISE, q, nu, theta, 60.0, &outflow_rate);
    for (int64_t k = 0; k < n / 2; ++k) {
        const double pyramid = tan(theta) * (k + 1) * dx; /* the open side is a node 1 dx beyond */
        worst = fmax(worst, fabs(h[k + n * k] - pyramid) / pyramid);
        worst = fmax(worst, fabs(h[k + n * (n / 2)] - pyramid) / pyramid);
    }
    print_message("pyramid: worst |h - tan(theta) d| / (tan(theta) d) along axis and diagonal %.2f%%, "
                  "outflow rate %.6f vs poured %.6f\n",
                  100.0 * worst, outflow_rate, q);
    assert_true(worst < 0.03);
    assert_true(fabs(outflow_rate - q) < 1e-6 * q);
    free(h);
}

/* An obstacle: a wall of cells across the table. A column collapses against
 * it; no sand crosses, the wall cells keep their height, the mass stays. */
static void test_obstacle_stops_sand(void **state) {
    (void)state;
    const int64_t nx = 60, ny = 30;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(nx, ny, 1.0, 1.0, &g));
    uint8_t *kinds = calloc(nx * ny, 1);
    double *h = calloc(nx * ny, sizeof(double));
    for (int64_t j = 0; j < ny; ++j) {
        kinds[30 + nx * j] = DPSM_CELL_WALL;
        h[30 + nx * j] = 3.0; /* the wall's own height, which must never change */
        for (int64_t i = 20; i < 30; ++i) h[i + nx * j] = 12.0; /* a sand cliff against the wall */
    }
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_cell_kinds(g, kinds));
    set_all_sides(g, DPSM_OPEN, 2);
    const double m0 = read_ledger(g).total;
    CHECK_OK(g, dpsm_step(g, 1e6));
    CHECK_OK(g, dpsm_get_heights(g, h));
    double beyond = 0.0, wall_change = 0.0;
    for (int64_t j = 0; j < ny; ++j) {
        wall_change = fmax(wall_change, fabs(h[30 + nx * j] - 3.0));
        for (int64_t i = 31; i < nx; ++i) beyond = fmax(beyond, fabs(h[i + nx * j]));
    }
    const ledger_t l = read_ledger(g);
    print_message("obstacle: sand beyond the wall %g, wall height change %g, outflow %.4f, ledger residual %.1e\n",
                  beyond, wall_change, l.outflow, ledger_residual(g));
    assert_true(beyond == 0.0);
    assert_true(wall_change == 0.0);
    assert_true(l.outflow > 0.0); /* some sand left on the open side x = 0 */
    assert_true(l.total < m0);
    assert_true(ledger_residual(g) < 1e-13);
    assert_true(max_face_slope(h, kinds, nx, ny, 1.0, 1.0) <= tan(DPSM_DEFAULT_REPOSE_ANGLE) * (1 + 1e-6) + 1e-12);
    free(kinds);
    free(h);
    dpsm_destroy(g);
}

/* An open cell is a sink held at its height: what flows in is outflow. */
static void test_open_cell_is_a_sink(void **state) {
    (void)state;
    const int64_t nx = 21;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_1d(nx, 1.0, &g));
    uint8_t kinds[21] = {0};
    double h[21] = {0};
    kinds[10] = DPSM_CELL_OPEN;
    for (int i = 0; i < nx; ++i) h[i] = i == 10 ? 0.0 : 10.0;
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_cell_kinds(g, kinds));
    const double m0 = read_ledger(g).total;
    CHECK_OK(g, dpsm_step(g, 1e6));
    CHECK_OK(g, dpsm_get_heights(g, h));
    const ledger_t l = read_ledger(g);
    double at_rest;
    CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_AT_REST, &at_rest));
    print_message("open cell: held at %g, outflow %.6f, total %.6f of %.6f, at rest %g\n", h[10], l.outflow,
                  l.total, m0, at_rest);
    assert_true(h[10] == 0.0);
    assert_true(l.outflow > 0.0);
    assert_true(fabs(l.total + l.outflow - m0) < 1e-12 * m0);
    assert_true(at_rest == 1.0);
    /* a funnel: the flanks rise from the sink at the angle of repose */
    assert_true(fabs(h[9] - h[11]) < 1e-12);
    assert_true(h[9] <= tan(DPSM_DEFAULT_REPOSE_ANGLE) * (1 + 1e-6) + 1e-12);
    dpsm_destroy(g);
}

/* dpsm_step(g, 1e6) on a collapsing column costs the work to reach rest, and
 * leaves no face steeper than the angle of repose beyond the tolerance. */
static void test_huge_dt_stops_at_rest(void **state) {
    (void)state;
    const int64_t n = 96;
    const double dx = 1.0 / 16, theta = deg(32.0), tol = 1e-6;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(n, n, dx, dx, &g));
    CHECK_OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE)); /* sub-steps to rest */
    CHECK_OK(g, dpsm_set_repose_angle(g, theta));
    CHECK_OK(g, dpsm_set_rest_tolerance(g, tol));
    set_all_sides(g, DPSM_OPEN, 2);
    double *h = calloc(n * n, sizeof(double));
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) {
            const double x = (i - n / 2) * dx, y = (j - n / 2) * dx;
            if (x * x + y * y <= 1.0) h[i + n * j] = 1.5;
        }
    CHECK_OK(g, dpsm_set_heights(g, h));
    const double m0 = read_ledger(g).total;
    CHECK_OK(g, dpsm_step(g, 1e6));
    double substeps, at_rest, t_rest, excess, dt_stable;
    CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &substeps));
    CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_AT_REST, &at_rest));
    CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_TIME_INTEGRATED, &t_rest));
    CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_MAX_EXCESS_SLOPE, &excess));
    CHECK_OK(g, dpsm_stable_dt(g, &dt_stable));
    CHECK_OK(g, dpsm_get_heights(g, h));
    const double slope = max_face_slope(h, NULL, n, n, dx, dx);
    print_message("huge dt: at rest %g after t = %.3f in %.0f sub-steps (1e6/dt_stable = %.2e); "
                  "max slope %.9f vs tan(theta) %.9f; mass drift %.1e\n",
                  at_rest, t_rest, substeps, 1e6 / dt_stable, slope, tan(theta),
                  fabs(read_ledger(g).total - m0) / m0);
    assert_true(at_rest == 1.0);
    assert_true(substeps < 1e5);
    assert_true(fabs(t_rest - substeps * (1e6 / ceil(1e6 / dt_stable))) <= 1e-9 * t_rest);
    assert_true(excess <= tol * tan(theta));
    assert_true(slope <= tan(theta) * (1.0 + tol) * (1.0 + 1e-12));
    assert_true(fabs(read_ledger(g).total - m0) < 1e-13 * m0); /* the pile stays on the table */

    /* A second long step finds it at rest at once and changes nothing. */
    double *again = malloc(sizeof(double) * n * n);
    CHECK_OK(g, dpsm_step(g, 1e6));
    CHECK_OK(g, dpsm_get_heights(g, again));
    CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &substeps));
    assert_true(substeps == 0.0);
    assert_memory_equal(h, again, sizeof(double) * n * n);
    free(again);
    free(h);
    dpsm_destroy(g);
}

/* The paper's bound on one exchange: at the stable sub-step a steep pair never
 * exchanges so much that it ends below the angle of repose. */
static void test_one_substep_never_overshoots_the_angle(void **state) {
    (void)state;
    const double theta = deg(30.0), dx = 0.5;
    for (double jump = 0.3; jump < 1e4; jump *= 3.7) {
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, dpsm_create_1d(2, dx, &g));
        CHECK_OK(g, dpsm_set_repose_angle(g, theta));
        const double h0[2] = {jump, 0.0};
        double h[2], dt;
        CHECK_OK(g, dpsm_set_heights(g, h0));
        CHECK_OK(g, dpsm_stable_dt(g, &dt));
        CHECK_OK(g, dpsm_step(g, dt));
        CHECK_OK(g, dpsm_get_heights(g, h));
        const double slope_after = (h[0] - h[1]) / dx;
        if (jump > tan(theta) * dx) assert_true(slope_after >= tan(theta) * (1 - 1e-12));
        assert_true(h[0] <= h0[0] && h[1] >= h0[1]);
        assert_true(h[0] + h[1] == h0[0] + h0[1] || fabs(h[0] + h[1] - jump) < 1e-15 * jump);
        dpsm_destroy(g);
    }
}

/* Erosion (a negative source) and deposition in one run: the ledger closes. */
static void test_ledger_closes_with_erosion_and_deposition(void **state) {
    (void)state;
    const int64_t nx = 30, ny = 20;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(nx, ny, 0.2, 0.2, &g));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN));
    double *h = malloc(sizeof(double) * nx * ny), *q = malloc(sizeof(double) * nx * ny);
    rough_terrain(h, nx * ny, 3.0, 5u);
    rough_terrain(q, nx * ny, 1.0, 9u);
    for (int64_t c = 0; c < nx * ny; ++c) q[c] -= 0.5;
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_source(g, q));
    double worst = 0.0;
    for (int k = 0; k < 200; ++k) {
        CHECK_OK(g, dpsm_step(g, 0.05));
        if (k % 50 == 0) { /* the host deposits on a few cells between steps */
            CHECK_OK(g, dpsm_get_heights(g, h));
            h[3 + nx * 4] += 0.25;
            CHECK_OK(g, dpsm_set_heights(g, h));
        }
        worst = fmax(worst, ledger_residual(g));
    }
    const ledger_t l = read_ledger(g);
    print_message("erosion + deposition: worst ledger residual %.1e (total %.4f, sourced %.4f, external %.4f, "
                  "outflow %.4f)\n",
                  worst, l.total, l.sourced, l.external, l.outflow);
    assert_true(worst < 1e-12);
    assert_true(l.outflow > 0.0);
    free(h);
    free(q);
    dpsm_destroy(g);
}

/* Millions of sub-steps at a steady state under a source: every increment is
 * near the rounding level of the heights, the case where a plain h += dq
 * leaks mass half an ulp at a time. The ledger must not drift. */
static void test_ledger_does_not_drift_over_millions_of_substeps(void **state) {
    (void)state;
    const int64_t nx = 25;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_1d(nx, 0.04, &g));
    set_all_sides(g, DPSM_OPEN, 1);
    double q[25];
    for (int i = 0; i < nx; ++i) q[i] = 0.003 * (1 + i % 3);
    CHECK_OK(g, dpsm_set_source(g, q));
    double dt, substeps = 0.0, worst = 0.0, n;
    CHECK_OK(g, dpsm_stable_dt(g, &dt));
    for (int k = 0; k < 40; ++k) {
        CHECK_OK(g, dpsm_step(g, 50000 * dt));
        CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &n));
        substeps += n;
        worst = fmax(worst, ledger_residual(g));
    }
    print_message("%.0f sub-steps: worst ledger residual %.1e\n", substeps, worst);
    assert_true(substeps >= 2e6);
    assert_true(worst < 1e-14);
    dpsm_destroy(g);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mass_is_conserved_between_walls),
        cmocka_unit_test(test_no_new_extrema_without_source),
        cmocka_unit_test(test_open_table_steady_state_matches_eqs_15_16),
        cmocka_unit_test(test_filling_between_two_walls_fig_3c),
        cmocka_unit_test(test_steady_pile_on_square_open_table_fig_4a),
        cmocka_unit_test(test_pairwise_scheme_builds_a_pyramid),
        cmocka_unit_test(test_obstacle_stops_sand),
        cmocka_unit_test(test_open_cell_is_a_sink),
        cmocka_unit_test(test_huge_dt_stops_at_rest),
        cmocka_unit_test(test_one_substep_never_overshoots_the_angle),
        cmocka_unit_test(test_ledger_closes_with_erosion_and_deposition),
        cmocka_unit_test(test_ledger_does_not_drift_over_millions_of_substeps),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
