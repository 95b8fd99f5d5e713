/* The fast relaxation to rest (dpsm_set_relaxation(g, DPSM_RELAX_TO_REST)):
 * it reaches the rest that the time-accurate sub-steps reach, to a fraction
 * of a per cent, in far fewer flux evaluations; the state is truly at rest
 * (a time-accurate step after it does nothing); mass is kept and booked;
 * results do not depend on the threads; a restart file keeps the setting;
 * what it does not support is refused before anything changes. */
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

/* The cone of the performance page: 40 high, slope 1.5, on 101^2 cells of
 * width 1, relaxed at 33 degrees with open sides. */
enum { N = 101 };
static void cone(double *h) {
    for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) h[i + N * j] = fmax(0.0, 40.0 - 1.5 * hypot(i - N / 2, j - N / 2));
}

/* Twelve cones that meet, a wall across part of them, one open side: piles
 * whose deposit depends on the path, with masks and outflow. */
static void cones_and_wall(double *h, uint8_t *kinds) {
    unsigned seed = 7u;
    memset(h, 0, sizeof(double) * N * N);
    for (int p = 0; p < 12; ++p) {
        double v[4];
        for (int k = 0; k < 4; ++k) {
            seed = seed * 1664525u + 1013904223u;
            v[k] = (double)(seed >> 8) / (double)(1u << 24);
        }
        for (int j = 0; j < N; ++j)
            for (int i = 0; i < N; ++i)
                h[i + N * j] = fmax(h[i + N * j], 5.0 + 20.0 * v[2] - (1.0 + v[3]) * hypot(i - 15.0 - 70.0 * v[0],
                                                                                          j - 15.0 - 70.0 * v[1]));
    }
    for (int c = 0; c < N * N; ++c) kinds[c] = DPSM_CELL_SAND;
    for (int j = 20; j < 75; ++j) kinds[40 + N * j] = DPSM_CELL_WALL;
}

static dpsm_grid *grid_of(const double *h, const uint8_t *kinds, int open_sides, int threads) {
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(N, N, 1.0, 1.0, &g));
    CHECK_OK(g, dpsm_set_repose_angle(g, 33.0 * kPi / 180.0));
    CHECK_OK(g, dpsm_set_threads(g, threads));
    for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side)
        CHECK_OK(g, dpsm_set_boundary(g, side, side < open_sides ? DPSM_OPEN : DPSM_WALL));
    if (kinds) CHECK_OK(g, dpsm_set_cell_kinds(g, kinds));
    CHECK_OK(g, dpsm_set_heights(g, h));
    return g;
}

/* L1 difference of a and b over the volume of b. */
static double l1_share(const double *a, const double *b) {
    double d = 0.0, v = 0.0;
    for (int c = 0; c < N * N; ++c) {
        d += fabs(a[c] - b[c]);
        v += fabs(b[c]);
    }
    return d / v;
}

/* Relaxes the same scene both ways; checks the fast rest against the
 * time-accurate one and that it is a rest of the model's own. */
static void compare_with_time_accurate(const double *h0, const uint8_t *kinds, int open_sides, double tolerance,
                                       double max_l1, const char *name) {
    dpsm_grid *accurate = grid_of(h0, kinds, open_sides, 0), *fast = grid_of(h0, kinds, open_sides, 0);
    CHECK_OK(accurate, dpsm_set_relaxation(accurate, DPSM_RELAX_TIME_ACCURATE));
    CHECK_OK(accurate, dpsm_set_rest_tolerance(accurate, tolerance));
    CHECK_OK(fast, dpsm_set_rest_tolerance(fast, tolerance));
    CHECK_OK(fast, dpsm_set_relaxation(fast, DPSM_RELAX_TO_REST));
    CHECK_OK(accurate, dpsm_step(accurate, 1e6));
    CHECK_OK(fast, dpsm_step(fast, 1e6));
    REQUIRE(step_info_of(accurate, DPSM_INFO_AT_REST) == 1.0, "%s: the time-accurate run did not rest", name);
    REQUIRE(step_info_of(fast, DPSM_INFO_AT_REST) == 1.0, "%s: the fast relaxation did not rest", name);
    const double evaluations = step_info_of(fast, DPSM_INFO_SUBSTEPS), substeps = step_info_of(accurate, DPSM_INFO_SUBSTEPS);
    REQUIRE(evaluations * 4.0 < substeps, "%s: %g evaluations against %g sub-steps: not fast", name, evaluations,
            substeps);
    REQUIRE(step_info_of(fast, DPSM_INFO_TIME_INTEGRATED) == 0.0 && step_info_of(fast, DPSM_INFO_MAX_EXCESS_SLOPE) == 0.0,
            "%s: time integrated %g, largest excess %g", name, step_info_of(fast, DPSM_INFO_TIME_INTEGRATED),
            step_info_of(fast, DPSM_INFO_MAX_EXCESS_SLOPE));
    double *a = malloc(sizeof(double) * N * N), *b = malloc(sizeof(double) * N * N);
    CHECK_OK(accurate, dpsm_get_heights(accurate, a));
    CHECK_OK(fast, dpsm_get_heights(fast, b));
    const double l1 = l1_share(b, a);
    print_message("%s, tolerance %g: %g evaluations (time accurate: %g sub-steps), deposit %.3f %% from the "
                  "time-accurate one (L1), top %.4f against %.4f\n",
                  name, tolerance, evaluations, substeps, 100.0 * l1, max_of(b, N * N), max_of(a, N * N));
    REQUIRE(l1 <= max_l1, "%s: the deposit is %.3f %% from the time-accurate one, more than %.2f %%", name, 100.0 * l1,
            100.0 * max_l1);
    for (int c = 0; c < N * N; ++c) REQUIRE(isfinite(b[c]), "%s: h[%d] = %g", name, c, b[c]);
    if (kinds)
        for (int c = 0; c < N * N; ++c)
            if (kinds[c] == DPSM_CELL_WALL) REQUIRE(b[c] == h0[c], "%s: wall cell %d moved", name, c);
    /* Mass: the ledger closes, and what left is what the time-accurate run lost, to round-off. */
    const double total = mass_of(fast, DPSM_MASS_TOTAL);
    REQUIRE(ledger_residual(fast) <= 1e-13, "%s: ledger residual %g", name, ledger_residual(fast));
    REQUIRE(fabs(mass_of(fast, DPSM_MASS_OUTFLOW) - mass_of(accurate, DPSM_MASS_OUTFLOW)) <= 5e-3 * total + 1e-12 * total,
            "%s: outflow %.17g, time accurate %.17g", name, mass_of(fast, DPSM_MASS_OUTFLOW),
            mass_of(accurate, DPSM_MASS_OUTFLOW));
    if (open_sides == 0)
        REQUIRE(fabs(mass_of(fast, DPSM_MASS_OUTFLOW)) <= 1e-13 * total, "%s: %g left a closed domain", name,
                mass_of(fast, DPSM_MASS_OUTFLOW));
    /* At rest by the model's own criterion: a time-accurate step does nothing. */
    CHECK_OK(fast, dpsm_set_relaxation(fast, DPSM_RELAX_TIME_ACCURATE));
    CHECK_OK(fast, dpsm_step(fast, 1e3));
    REQUIRE(step_info_of(fast, DPSM_INFO_SUBSTEPS) == 0.0 && step_info_of(fast, DPSM_INFO_AT_REST) == 1.0,
            "%s: a time-accurate step after the fast rest took %g sub-steps", name, step_info_of(fast, DPSM_INFO_SUBSTEPS));
    free(a);
    free(b);
    dpsm_destroy(accurate);
    dpsm_destroy(fast);
}

static void test_cone_rests_fast_and_right(void **state) {
    (void)state;
    double *h = malloc(sizeof(double) * N * N);
    cone(h);
    compare_with_time_accurate(h, NULL, 4, 1e-6, 0.002, "cone");
    compare_with_time_accurate(h, NULL, 4, 1e-3, 0.002, "cone");
    /* The top against the exact cone at the angle of repose. */
    dpsm_grid *g = grid_of(h, NULL, 4, 0);
    CHECK_OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TO_REST));
    CHECK_OK(g, dpsm_step(g, 1.0));
    CHECK_OK(g, dpsm_get_heights(g, h));
    const double top = max_of(h, N * N);
    print_message("cone: top %.4f, exact 22.89 (%+.2f %%)\n", top, 100.0 * (top - 22.89) / 22.89);
    REQUIRE(fabs(top - 22.89) <= 0.005 * 22.89, "cone: top %.4f, more than 0.5 %% from 22.89", top);
    dpsm_destroy(g);
    free(h);
}

static void test_meeting_cones_walls_and_outflow(void **state) {
    (void)state;
    double *h = malloc(sizeof(double) * N * N);
    uint8_t *kinds = malloc(N * N);
    cones_and_wall(h, kinds);
    compare_with_time_accurate(h, kinds, 1, 1e-6, 0.003, "meeting cones, a wall, one open side");
    compare_with_time_accurate(h, kinds, 0, 1e-6, 0.003, "meeting cones, a wall, closed");
    free(h);
    free(kinds);
}

/* Requires two grids' heights and step information to agree bit for bit,
 * the cell updates only `with_cost` (a loaded grid looks at every tile once
 * more, which costs work but changes no result). */
static void require_same_state(dpsm_grid *g, dpsm_grid *other, int with_cost, const char *what) {
    double *a = malloc(sizeof(double) * N * N), *b = malloc(sizeof(double) * N * N);
    CHECK_OK(g, dpsm_get_heights(g, a));
    CHECK_OK(other, dpsm_get_heights(other, b));
    REQUIRE(memcmp(a, b, sizeof(double) * N * N) == 0, "%s: heights differ", what);
    for (int item = DPSM_INFO_SUBSTEPS; item <= (with_cost ? DPSM_INFO_CELL_UPDATES : DPSM_INFO_MAX_EXCESS_SLOPE); ++item)
        REQUIRE(step_info_of(g, item) == step_info_of(other, item), "%s: step info %d is %g and %g", what, item,
                step_info_of(g, item), step_info_of(other, item));
    free(a);
    free(b);
}

/* Steps both grids by dt; their heights and step information must then agree
 * bit for bit (not the cells visited: the active sets may differ). */
static void require_same_step(dpsm_grid *g, dpsm_grid *other, double dt, const char *what) {
    CHECK_OK(g, dpsm_step(g, dt));
    CHECK_OK(other, dpsm_step(other, dt));
    require_same_state(g, other, 0, what);
}

/* The same heights bit for bit on 1, 2 and 3 threads. */
static void test_independent_of_threads(void **state) {
    (void)state;
    double *h = malloc(sizeof(double) * N * N), *out[3];
    uint8_t *kinds = malloc(N * N);
    cones_and_wall(h, kinds);
    for (int t = 0; t < 3; ++t) {
        dpsm_grid *g = grid_of(h, kinds, 1, t + 1);
        CHECK_OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TO_REST));
        CHECK_OK(g, dpsm_step(g, 1.0));
        REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) == 1.0, "threads %d: not at rest", t + 1);
        out[t] = malloc(sizeof(double) * N * N);
        CHECK_OK(g, dpsm_get_heights(g, out[t]));
        dpsm_destroy(g);
    }
    for (int t = 1; t < 3; ++t)
        REQUIRE(memcmp(out[0], out[t], sizeof(double) * N * N) == 0, "1 and %d threads differ", t + 1);
    for (int t = 0; t < 3; ++t) free(out[t]);
    free(h);
    free(kinds);
}

/* Out of flux evaluations: the step succeeds, says it is not at rest, and
 * the ledger closes; a time-accurate grid set back afterwards steps as one
 * that never relaxed to rest. */
static void test_limit_and_switching_back(void **state) {
    (void)state;
    double *h = malloc(sizeof(double) * N * N), *a = malloc(sizeof(double) * N * N);
    cone(h);
    dpsm_grid *g = grid_of(h, NULL, 4, 0), *never = grid_of(h, NULL, 4, 0);
    CHECK_OK(never, dpsm_set_relaxation(never, DPSM_RELAX_TIME_ACCURATE));
    CHECK_OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TO_REST));
    CHECK_OK(g, dpsm_set_max_substeps(g, 10));
    CHECK_OK(g, dpsm_step(g, 1.0));
    REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) == 0.0 && step_info_of(g, DPSM_INFO_SUBSTEPS) == 10.0,
            "with a limit of 10: at rest %g after %g evaluations", step_info_of(g, DPSM_INFO_AT_REST),
            step_info_of(g, DPSM_INFO_SUBSTEPS));
    REQUIRE(step_info_of(g, DPSM_INFO_MAX_EXCESS_SLOPE) > 0.0, "not at rest, but no excess slope");
    REQUIRE(ledger_residual(g) <= 1e-13, "ledger residual %g", ledger_residual(g));
    CHECK_OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE));
    CHECK_OK(g, dpsm_set_max_substeps(g, 100000000));
    CHECK_OK(g, dpsm_get_heights(g, a));
    CHECK_OK(never, dpsm_set_heights(never, a));
    require_same_step(g, never, 5.0, "set back to DPSM_RELAX_TIME_ACCURATE, it steps differently");
    dpsm_destroy(g);
    dpsm_destroy(never);
    free(h);
    free(a);
}

/* A host's time-accurate steps leave residuals wherever sand moved; then a
 * new pile far from there is relaxed to rest. Afterwards the grid steps as one
 * that only has its heights (no residual is left anywhere, not only where the
 * relaxation acted), and the ledger closes. */
static void test_after_time_accurate_steps(void **state) {
    (void)state;
    double *h = malloc(sizeof(double) * N * N), *a = malloc(sizeof(double) * N * N);
    for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) h[i + N * j] = fmax(0.0, 8.0 - 1.5 * hypot(i - 20.0, j - 20.0));
    dpsm_grid *g = grid_of(h, NULL, 4, 0);
    CHECK_OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE));
    CHECK_OK(g, dpsm_step(g, 1e6));
    REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) == 1.0, "the first pile did not rest");
    CHECK_OK(g, dpsm_step(g, 1.0)); /* at rest: the active set forgets the pile */
    REQUIRE(step_info_of(g, DPSM_INFO_SUBSTEPS) == 0.0, "the first pile moved again");
    enum { M = 21 };
    double column[M * M];
    for (int j = 0; j < M; ++j)
        for (int i = 0; i < M; ++i) column[i + M * j] = fmax(0.0, 15.0 - 2.0 * hypot(i - M / 2, j - M / 2));
    CHECK_OK(g, dpsm_add_heights_region(g, 65, 65, M, M, column));
    CHECK_OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TO_REST));
    CHECK_OK(g, dpsm_step(g, 1.0));
    REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) == 1.0, "the new pile did not rest");
    REQUIRE(ledger_residual(g) <= 1e-13, "ledger residual %g", ledger_residual(g));
    CHECK_OK(g, dpsm_get_heights(g, a));
    REQUIRE(a[20 + N * 20] < 8.0 && a[75 + N * 75] < 15.0 && a[75 + N * 75] > 5.0, "tops %g and %g", a[20 + N * 20],
            a[75 + N * 75]);
    /* Knocked out of rest on both piles (dpsm_add_heights_region clears the
     * residuals of its block only), both grids must step alike. */
    dpsm_grid *fresh = grid_of(a, NULL, 4, 0);
    CHECK_OK(fresh, dpsm_set_relaxation(fresh, DPSM_RELAX_TIME_ACCURATE));
    double knock[5 * 5];
    for (int c = 0; c < 5 * 5; ++c) knock[c] = 6.0;
    for (int pile = 0; pile < 2; ++pile) {
        CHECK_OK(g, dpsm_add_heights_region(g, 18 + 55 * pile, 18 + 55 * pile, 5, 5, knock));
        CHECK_OK(fresh, dpsm_add_heights_region(fresh, 18 + 55 * pile, 18 + 55 * pile, 5, 5, knock));
    }
    CHECK_OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE));
    require_same_step(g, fresh, 5.0, "after the relaxation, the grid steps unlike a fresh one");
    dpsm_destroy(g);
    dpsm_destroy(fresh);
    free(h);
    free(a);
}

/* A pile in the corner of a large grid costs its own cells: it relaxes bit
 * for bit as on a grid just large enough for it, visiting the same cells
 * (DPSM_INFO_CELL_UPDATES counts those, not the grid's), and once it rests a
 * step takes no evaluation at all. */
static void test_pile_in_a_large_grid_costs_its_cells(void **state) {
    (void)state;
    enum { SMALL = 192, LARGE = 1024 };
    dpsm_grid *g[2];
    double *corner[2], updates[2], evaluations[2];
    const int64_t n[2] = {SMALL, LARGE};
    for (int k = 0; k < 2; ++k) {
        CHECK_OK(NULL, dpsm_create_2d(n[k], n[k], 1.0, 1.0, &g[k]));
        CHECK_OK(g[k], dpsm_set_repose_angle(g[k], 33.0 * kPi / 180.0));
        CHECK_OK(g[k], dpsm_set_relaxation(g[k], DPSM_RELAX_TO_REST));
        CHECK_OK(g[k], dpsm_step(g[k], 1.0)); /* flat: looks at every tile once */
        enum { M = 61 };
        double *pile = malloc(sizeof(double) * M * M);
        for (int j = 0; j < M; ++j)
            for (int i = 0; i < M; ++i) pile[i + M * j] = fmax(0.0, 30.0 - 1.5 * hypot(i - M / 2, j - M / 2));
        CHECK_OK(g[k], dpsm_add_heights_region(g[k], 10, 10, M, M, pile));
        free(pile);
        CHECK_OK(g[k], dpsm_step(g[k], 1.0));
        REQUIRE(step_info_of(g[k], DPSM_INFO_AT_REST) == 1.0, "%lld^2: the pile did not rest", (long long)n[k]);
        REQUIRE(ledger_residual(g[k]) <= 1e-13, "%lld^2: ledger residual %g", (long long)n[k], ledger_residual(g[k]));
        updates[k] = step_info_of(g[k], DPSM_INFO_CELL_UPDATES);
        evaluations[k] = step_info_of(g[k], DPSM_INFO_SUBSTEPS);
        corner[k] = malloc(sizeof(double) * SMALL * SMALL);
        CHECK_OK(g[k], dpsm_get_heights_region(g[k], 0, 0, SMALL, SMALL, corner[k]));
    }
    REQUIRE(memcmp(corner[0], corner[1], sizeof(double) * SMALL * SMALL) == 0,
            "the pile rests differently in a larger grid");
    REQUIRE(evaluations[0] == evaluations[1] && evaluations[0] > 10.0, "evaluations %g and %g", evaluations[0],
            evaluations[1]);
    REQUIRE(updates[0] == updates[1] && updates[1] <= evaluations[1] * 9.0 * 64.0 * 64.0,
            "cells visited: %g on %d^2, %g on %d^2 in %g evaluations", updates[0], SMALL, updates[1], LARGE,
            evaluations[1]);
    /* Nothing left out of the corner: the rest of the large grid is as flat as it was. */
    double *rest_of_it = malloc(sizeof(double) * LARGE * (LARGE - SMALL));
    CHECK_OK(g[1], dpsm_get_heights_region(g[1], 0, SMALL, LARGE, LARGE - SMALL, rest_of_it));
    for (int64_t c = 0; c < (int64_t)LARGE * (LARGE - SMALL); ++c)
        REQUIRE(rest_of_it[c] == 0.0, "sand at cell %lld beyond the corner", (long long)c);
    free(rest_of_it);
    CHECK_OK(g[1], dpsm_step(g[1], 1.0));
    REQUIRE(step_info_of(g[1], DPSM_INFO_AT_REST) == 1.0 && step_info_of(g[1], DPSM_INFO_SUBSTEPS) == 0.0 &&
                step_info_of(g[1], DPSM_INFO_CELL_UPDATES) == 0.0,
            "at rest, a step took %g evaluations over %g cells", step_info_of(g[1], DPSM_INFO_SUBSTEPS),
            step_info_of(g[1], DPSM_INFO_CELL_UPDATES));
    for (int k = 0; k < 2; ++k) {
        dpsm_destroy(g[k]);
        free(corner[k]);
    }
}

/* Lone tall spikes on cells ten times longer in y than in x: the stages and
 * momentum undershoot the floor of open sides there. The relaxation must not
 * leave that: it steps the scene in time instead, from the same start, and
 * ends exactly where time-accurate steps to rest end. */
static void test_falls_back_where_it_would_leave_new_extremes(void **state) {
    (void)state;
    enum { SX = 48, SY = 43 };
    double h[SX * SY], a[SX * SY], b[SX * SY];
    unsigned r = 1u;
    for (int c = 0; c < SX * SY; ++c) {
        r = r * 1664525u + 1013904223u;
        const double u = (double)(r >> 8) / 16777216.0;
        r = r * 1664525u + 1013904223u;
        h[c] = u < 0.05 ? 60.0 * (double)(r >> 8) / 16777216.0 : 0.0;
    }
    dpsm_grid *g[2];
    const int relaxation[2] = {DPSM_RELAX_TO_REST, DPSM_RELAX_TIME_ACCURATE};
    for (int k = 0; k < 2; ++k) {
        CHECK_OK(NULL, dpsm_create_2d(SX, SY, 0.5, 5.0, &g[k]));
        for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side) CHECK_OK(g[k], dpsm_set_boundary(g[k], side, DPSM_OPEN));
        CHECK_OK(g[k], dpsm_set_heights(g[k], h));
        CHECK_OK(g[k], dpsm_set_relaxation(g[k], relaxation[k]));
        CHECK_OK(g[k], dpsm_step(g[k], k == 0 ? 1.0 : 1e300));
        REQUIRE(step_info_of(g[k], DPSM_INFO_AT_REST) == 1.0, "relaxation %d: not at rest", relaxation[k]);
    }
    REQUIRE(step_info_of(g[0], DPSM_INFO_TIME_INTEGRATED) > 0.0 &&
                step_info_of(g[0], DPSM_INFO_TIME_INTEGRATED) == step_info_of(g[1], DPSM_INFO_TIME_INTEGRATED) &&
                step_info_of(g[0], DPSM_INFO_SUBSTEPS) == step_info_of(g[1], DPSM_INFO_SUBSTEPS),
            "not stepped in time: %g in %g sub-steps, time-accurate %g in %g",
            step_info_of(g[0], DPSM_INFO_TIME_INTEGRATED), step_info_of(g[0], DPSM_INFO_SUBSTEPS),
            step_info_of(g[1], DPSM_INFO_TIME_INTEGRATED), step_info_of(g[1], DPSM_INFO_SUBSTEPS));
    REQUIRE(step_info_of(g[0], DPSM_INFO_CELL_UPDATES) > step_info_of(g[1], DPSM_INFO_CELL_UPDATES),
            "the relaxation's own work is not counted");
    CHECK_OK(g[0], dpsm_get_heights(g[0], a));
    CHECK_OK(g[1], dpsm_get_heights(g[1], b));
    REQUIRE(memcmp(a, b, sizeof a) == 0, "the fallback ends elsewhere than time-accurate steps");
    for (int c = 0; c < SX * SY; ++c) REQUIRE(a[c] >= 0.0, "h[%d] = %g below the floor", c, a[c]);
    REQUIRE(ledger_residual(g[0]) <= 1e-13, "ledger residual %g", ledger_residual(g[0]));
    REQUIRE(memcmp(&(double){mass_of(g[0], DPSM_MASS_OUTFLOW)}, &(double){mass_of(g[1], DPSM_MASS_OUTFLOW)},
                   sizeof(double)) == 0,
            "outflow %.17g against %.17g", mass_of(g[0], DPSM_MASS_OUTFLOW), mass_of(g[1], DPSM_MASS_OUTFLOW));
    for (int k = 0; k < 2; ++k) dpsm_destroy(g[k]);
}

/* A restart file keeps the setting, and the loaded grid continues bit for bit. */
static void test_restart_keeps_it(void **state) {
    (void)state;
    double *h = malloc(sizeof(double) * N * N), *a = malloc(sizeof(double) * N * N), *b = malloc(sizeof(double) * N * N);
    cone(h);
    dpsm_grid *g = grid_of(h, NULL, 4, 0), *loaded = NULL;
    CHECK_OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TO_REST));
    CHECK_OK(g, dpsm_set_max_substeps(g, 40));
    CHECK_OK(g, dpsm_step(g, 1.0));
    const char *path = "test_relax_to_rest.dpsm";
    CHECK_OK(g, dpsm_save(g, path));
    CHECK_OK(NULL, dpsm_load(path, &loaded));
    remove(path);
    CHECK_OK(g, dpsm_set_max_substeps(g, 100000000));
    CHECK_OK(loaded, dpsm_set_max_substeps(loaded, 100000000));
    CHECK_OK(g, dpsm_step(g, 1.0));
    CHECK_OK(loaded, dpsm_step(loaded, 1.0));
    REQUIRE(step_info_of(loaded, DPSM_INFO_TIME_INTEGRATED) == 0.0, "the loaded grid stepped in time: it lost the setting");
    CHECK_OK(g, dpsm_get_heights(g, a));
    CHECK_OK(loaded, dpsm_get_heights(loaded, b));
    REQUIRE(memcmp(a, b, sizeof(double) * N * N) == 0, "the loaded grid relaxed differently");
    REQUIRE(step_info_of(g, DPSM_INFO_SUBSTEPS) == step_info_of(loaded, DPSM_INFO_SUBSTEPS), "evaluations %g and %g",
            step_info_of(g, DPSM_INFO_SUBSTEPS), step_info_of(loaded, DPSM_INFO_SUBSTEPS));
    dpsm_destroy(g);
    dpsm_destroy(loaded);
    free(h);
    free(a);
    free(b);
}

/* What it does not support is refused by dpsm_step with
 * DPSM_ERR_NOT_APPLICABLE, naming it, before anything changes. */
static void require_refused(dpsm_grid *g, int64_t cells, const char *phrase) {
    CHECK_OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TO_REST));
    double *before = malloc(sizeof(double) * (size_t)cells), *after = malloc(sizeof(double) * (size_t)cells);
    CHECK_OK(g, dpsm_get_heights(g, before));
    const double outflow = mass_of(g, DPSM_MASS_OUTFLOW);
    const int status = dpsm_step(g, 1.0);
    const char *message = dpsm_last_error(g);
    REQUIRE(status == DPSM_ERR_NOT_APPLICABLE, "%s: dpsm_step returned %s (%s)", phrase, dpsm_status_string(status),
            message);
    REQUIRE(strstr(message, phrase) != NULL && strstr(message, "DPSM_RELAX_TO_REST") != NULL,
            "the message does not name '%s': %s", phrase, message);
    CHECK_OK(g, dpsm_get_heights(g, after));
    REQUIRE(memcmp(before, after, sizeof(double) * (size_t)cells) == 0 && mass_of(g, DPSM_MASS_OUTFLOW) == outflow,
            "%s: the refused step changed the grid", phrase);
    free(before);
    free(after);
}

/* A small steep scene with one thing the relaxation does not support, by
 * number (0 .. kUnsupported - 1); names it in *phrase. */
enum { M = 12, kUnsupported = 10 };
static dpsm_grid *unsupported_scene(int feature, const char **phrase) {
    double h[M * M], q[M * M], zb[M * M], theta[M * M];
    uint8_t kinds[M * M];
    for (int c = 0; c < M * M; ++c) {
        h[c] = (double)(c % 7);
        q[c] = 0.01;
        zb[c] = -1.0;
        theta[c] = 0.5 + 0.01 * (c % 3);
        kinds[c] = DPSM_CELL_SAND;
    }
    dpsm_grid *g = NULL;
    if (feature == 0) {
        CHECK_OK(NULL, dpsm_create_1d(M, 1.0, &g));
    } else if (feature == 1) {
        CHECK_OK(NULL, dpsm_create_axisymmetric(M, 1.0, &g));
    } else {
        CHECK_OK(NULL, dpsm_create_2d(M, M, 1.0, 1.0, &g));
    }
    CHECK_OK(g, dpsm_set_heights(g, h));
    switch (feature) {
        case 0:
        case 1: *phrase = "1D or axisymmetric"; break;
        case 2: CHECK_OK(g, dpsm_set_bedrock(g, zb)); *phrase = "a bed"; break;
        case 3: CHECK_OK(g, dpsm_set_static_angle(g, 0.7)); *phrase = "a static angle"; break;
        case 4: CHECK_OK(g, dpsm_set_source(g, q)); *phrase = "an active source"; break;
        case 5: CHECK_OK(g, dpsm_set_repose_angle_field(g, theta)); *phrase = "an angle field"; break;
        case 6: CHECK_OK(g, dpsm_set_flux_exponent(g, 1.5)); *phrase = "a flux exponent other than 1"; break;
        case 7: CHECK_OK(g, dpsm_set_scheme(g, DPSM_SCHEME_PAIRWISE)); *phrase = "the pairwise scheme"; break;
        case 8: {
            kinds[0] = kinds[M * M - 1] = DPSM_CELL_OPEN;
            CHECK_OK(g, dpsm_set_cell_kinds(g, kinds));
            double low = 0.0, high = 3.0;
            CHECK_OK(g, dpsm_set_heights_region(g, 0, 0, 1, 1, &low));
            CHECK_OK(g, dpsm_set_heights_region(g, M - 1, M - 1, 1, 1, &high));
            *phrase = "open cells and open sides held at different levels";
            break;
        }
        default: {
            /* Two open sides, one held above the other (dpsm_set_side_levels). */
            double levels[M];
            for (int k = 0; k < M; ++k) levels[k] = 2.0;
            CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMIN, DPSM_OPEN));
            CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN));
            CHECK_OK(g, dpsm_set_side_levels(g, DPSM_XMAX, levels));
            *phrase = "open cells and open sides held at different levels";
        }
    }
    return g;
}

static void test_unsupported_scenes_refused(void **state) {
    (void)state;
    for (int feature = 0; feature < kUnsupported; ++feature) {
        const char *phrase = NULL;
        dpsm_grid *g = unsupported_scene(feature, &phrase);
        require_refused(g, feature < 2 ? M : M * M, phrase);
        dpsm_destroy(g);
    }
}

/* The default, DPSM_RELAX_AUTO, steps every scene the relaxation does not
 * support exactly as DPSM_RELAX_TIME_ACCURATE does, in time. */
static void test_auto_steps_the_others_in_time(void **state) {
    (void)state;
    double a[M * M], b[M * M];
    for (int feature = 0; feature < kUnsupported; ++feature) {
        const char *phrase = NULL;
        dpsm_grid *automatic = unsupported_scene(feature, &phrase), *timed = unsupported_scene(feature, &phrase);
        CHECK_OK(timed, dpsm_set_relaxation(timed, DPSM_RELAX_TIME_ACCURATE));
        for (int k = 0; k < 3; ++k) {
            CHECK_OK(automatic, dpsm_step(automatic, 0.05));
            CHECK_OK(timed, dpsm_step(timed, 0.05));
            REQUIRE(step_info_of(automatic, DPSM_INFO_TIME_INTEGRATED) == step_info_of(timed, DPSM_INFO_TIME_INTEGRATED) &&
                        step_info_of(automatic, DPSM_INFO_SUBSTEPS) == step_info_of(timed, DPSM_INFO_SUBSTEPS),
                    "%s: time %g in %g sub-steps, time-accurate %g in %g", phrase,
                    step_info_of(automatic, DPSM_INFO_TIME_INTEGRATED), step_info_of(automatic, DPSM_INFO_SUBSTEPS),
                    step_info_of(timed, DPSM_INFO_TIME_INTEGRATED), step_info_of(timed, DPSM_INFO_SUBSTEPS));
        }
        REQUIRE(step_info_of(timed, DPSM_INFO_SUBSTEPS) > 0.0, "%s: the scene did not move", phrase);
        CHECK_OK(automatic, dpsm_get_heights(automatic, a));
        CHECK_OK(timed, dpsm_get_heights(timed, b));
        REQUIRE(memcmp(a, b, sizeof(double) * (feature < 2 ? M : M * M)) == 0, "%s: heights differ", phrase);
        dpsm_destroy(automatic);
        dpsm_destroy(timed);
    }
}

/* A grid left at the default steps in time exactly as DPSM_RELAX_TIME_ACCURATE
 * does, whatever dt: a dt of a few sub-steps, one long enough for the cone to
 * come to rest (it integrates the time that took, in as many sub-steps), a
 * source on and off; the work counted is the same too (no relaxation is
 * tried). The cone relaxed to rest (DPSM_RELAX_TO_REST) is another deposit,
 * reached in far fewer evaluations. A restart file (of version 3) keeps the
 * default. */
static void test_auto_steps_in_time(void **state) {
    (void)state;
    double *h = malloc(sizeof(double) * N * N), *q = calloc(N * N, sizeof(double));
    cone(h);
    for (int j = 40; j < 50; ++j)
        for (int i = 20; i < 30; ++i) q[i + N * j] = 0.5;
    dpsm_grid *automatic = grid_of(h, NULL, 4, 0), *to_rest = grid_of(h, NULL, 4, 0), *timed = grid_of(h, NULL, 4, 0);
    CHECK_OK(to_rest, dpsm_set_relaxation(to_rest, DPSM_RELAX_TO_REST));
    CHECK_OK(timed, dpsm_set_relaxation(timed, DPSM_RELAX_TIME_ACCURATE));
    double sdt = 0.0;
    CHECK_OK(timed, dpsm_stable_dt(timed, &sdt));
    const double short_dts[2] = {8.0 * sdt, 40.0 * sdt};
    for (int k = 0; k < 2; ++k) {
        CHECK_OK(automatic, dpsm_step(automatic, short_dts[k]));
        CHECK_OK(timed, dpsm_step(timed, short_dts[k]));
        REQUIRE(step_info_of(automatic, DPSM_INFO_TIME_INTEGRATED) == short_dts[k],
                "a dt of %g sub-steps: the default integrated %g of %g", short_dts[k] / sdt,
                step_info_of(automatic, DPSM_INFO_TIME_INTEGRATED), short_dts[k]);
        require_same_state(automatic, timed, 1, "a short dt: the default against DPSM_RELAX_TIME_ACCURATE");
    }
    double *partway = malloc(sizeof(double) * N * N);
    CHECK_OK(automatic, dpsm_get_heights(automatic, partway));
    CHECK_OK(to_rest, dpsm_set_heights(to_rest, partway));
    free(partway);
    CHECK_OK(automatic, dpsm_step(automatic, 1e6));
    CHECK_OK(timed, dpsm_step(timed, 1e6));
    CHECK_OK(to_rest, dpsm_step(to_rest, 1e6));
    REQUIRE(step_info_of(automatic, DPSM_INFO_TIME_INTEGRATED) > 0.0 &&
                step_info_of(automatic, DPSM_INFO_TIME_INTEGRATED) < 1e6 &&
                step_info_of(automatic, DPSM_INFO_AT_REST) == 1.0,
            "the default did not step the cone in time to rest: time %g, at rest %g",
            step_info_of(automatic, DPSM_INFO_TIME_INTEGRATED), step_info_of(automatic, DPSM_INFO_AT_REST));
    require_same_state(automatic, timed, 1, "to rest: the default against DPSM_RELAX_TIME_ACCURATE");
    REQUIRE(step_info_of(to_rest, DPSM_INFO_SUBSTEPS) * 4.0 < step_info_of(automatic, DPSM_INFO_SUBSTEPS),
            "the default took %g sub-steps, the relaxation to rest %g evaluations: the default relaxed",
            step_info_of(automatic, DPSM_INFO_SUBSTEPS), step_info_of(to_rest, DPSM_INFO_SUBSTEPS));

    dpsm_grid *reloaded = NULL;
    const char *path = "test_relax_auto.dpsm";
    CHECK_OK(automatic, dpsm_set_source(automatic, q));
    CHECK_OK(timed, dpsm_set_source(timed, q));
    for (int k = 0; k < 3; ++k) {
        CHECK_OK(automatic, dpsm_step(automatic, 2.0));
        CHECK_OK(timed, dpsm_step(timed, 2.0));
        REQUIRE(step_info_of(automatic, DPSM_INFO_TIME_INTEGRATED) == 2.0, "with a source, the default integrated %g",
                step_info_of(automatic, DPSM_INFO_TIME_INTEGRATED));
        require_same_state(automatic, timed, 1, "with a source, the default against DPSM_RELAX_TIME_ACCURATE");
    }
    CHECK_OK(automatic, dpsm_set_source(automatic, NULL));
    CHECK_OK(timed, dpsm_set_source(timed, NULL));
    CHECK_OK(automatic, dpsm_save(automatic, path));
    unsigned char header[12];
    FILE *file = fopen(path, "rb");
    REQUIRE(file && fread(header, 1, sizeof header, file) == sizeof header, "cannot read %s back", path);
    fclose(file);
    REQUIRE(header[8] == 3 && header[9] == 0 && header[10] == 0 && header[11] == 0,
            "a grid at the default is saved as version %u, not 3", (unsigned)header[8]);
    CHECK_OK(NULL, dpsm_load(path, &reloaded));
    remove(path);
    CHECK_OK(automatic, dpsm_step(automatic, 1e6));
    CHECK_OK(timed, dpsm_step(timed, 1e6));
    CHECK_OK(reloaded, dpsm_step(reloaded, 1e6));
    REQUIRE(step_info_of(automatic, DPSM_INFO_TIME_INTEGRATED) > 0.0 && step_info_of(automatic, DPSM_INFO_SUBSTEPS) > 0.0,
            "with the source off, the default did not step in time");
    require_same_state(automatic, timed, 1, "source off: the default against DPSM_RELAX_TIME_ACCURATE");
    require_same_state(automatic, reloaded, 0, "source off: the default against its restart");
    REQUIRE(ledger_residual(automatic) <= 1e-13, "ledger residual %g", ledger_residual(automatic));
    /* Set explicitly, the default is the default. */
    CHECK_OK(to_rest, dpsm_set_relaxation(to_rest, DPSM_RELAX_AUTO));
    dpsm_destroy(automatic);
    dpsm_destroy(to_rest);
    dpsm_destroy(timed);
    dpsm_destroy(reloaded);
    free(h);
    free(q);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cone_rests_fast_and_right),
        cmocka_unit_test(test_meeting_cones_walls_and_outflow),
        cmocka_unit_test(test_independent_of_threads),
        cmocka_unit_test(test_limit_and_switching_back),
        cmocka_unit_test(test_after_time_accurate_steps),
        cmocka_unit_test(test_pile_in_a_large_grid_costs_its_cells),
        cmocka_unit_test(test_falls_back_where_it_would_leave_new_extremes),
        cmocka_unit_test(test_restart_keeps_it),
        cmocka_unit_test(test_unsupported_scenes_refused),
        cmocka_unit_test(test_auto_steps_the_others_in_time),
        cmocka_unit_test(test_auto_steps_in_time),
    };
    return cmocka_run_group_tests_name("relax to rest", tests, NULL, NULL);
}
