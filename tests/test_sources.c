/* Sources in closed form (src/structured/tiled_sweep.hpp, "Lazy sources"): a source that
 * cannot make a face steep within a step is applied as h + q dt, which must
 * give the heights that sub-stepping gives. Sub-stepping is what a host gets
 * by calling dpsm_step once per stable sub-step: each call is then a single
 * sub-step, whose source is added in that sub-step. So every test compares
 * one call of n sub-steps with n calls of one, through the public API. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "test_support.h"

static const double kTheta = 3.14159265358979323846 / 6.0;

/* A 2D grid whose stable sub-step is 64/63.5 of 2^-10, so that a call of
 * dt = 2^-4 takes 64 sub-steps of exactly 2^-10 and a call of 2^-10 one. */
static dpsm_grid *dyadic_grid(int64_t nx, int64_t ny) {
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(nx, ny, 1.0, 1.0, &g));
    CHECK_OK(g, dpsm_set_repose_angle(g, kTheta));
    const double stable = 64.0 / 63.5 / 1024.0;
    CHECK_OK(g, dpsm_set_mobility(g, 1.0 / (4.0 * cos(kTheta) * stable)));
    CHECK_OK(g, dpsm_set_threads(g, 1));
    return g;
}

/* A gentle plane (slope 1/16 along x and y, far below the angle of repose),
 * a steep block that collapses, and a source of multiples of 1/64 on every
 * cell, erosion and deposition: every height and every source increment is
 * a dyadic number, so that h + q dt is exact however it is summed. */
static void dyadic_scene(dpsm_grid *g, int64_t nx, int64_t ny, double *h, double *q) {
    for (int64_t j = 0; j < ny; ++j)
        for (int64_t i = 0; i < nx; ++i) {
            h[i + nx * j] = (double)(i + j) / 16.0 + (labs(i - 20) < 3 && labs(j - 30) < 3 ? 4.0 : 0.0);
            q[i + nx * j] = (double)((i * 7 + j * 3) % 16 - 8) / 64.0;
        }
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_source(g, q));
}

/* Steps `calls` calls of dt each; with `moved`, marks every cell one of whose
 * faces carried sand in any of them (recording face fluxes). */
static void step_calls(dpsm_grid *g, int calls, double dt, int64_t nx, int64_t ny, uint8_t *moved) {
    double *fx = NULL, *fy = NULL;
    if (moved) {
        CHECK_OK(g, dpsm_set_face_flux_recording(g, 1));
        fx = calloc((size_t)((nx + 1) * ny), sizeof *fx);
        fy = calloc((size_t)(nx * (ny + 1)), sizeof *fy);
    }
    for (int k = 0; k < calls; ++k) {
        CHECK_OK(g, dpsm_step(g, dt));
        if (!moved) continue;
        CHECK_OK(g, dpsm_get_face_fluxes(g, fx, fy));
        for (int64_t j = 0; j < ny; ++j)
            for (int64_t i = 0; i < nx; ++i)
                moved[i + nx * j] |= fx[i + (nx + 1) * j] != 0.0 || fx[i + 1 + (nx + 1) * j] != 0.0 ||
                                     fy[i + nx * j] != 0.0 || fy[i + nx * (j + 1)] != 0.0;
    }
    free(fx);
    free(fy);
}

/* Where no face carries sand, one call of 64 sub-steps gives, bit for bit,
 * the heights of 64 calls of one sub-step; elsewhere the same to round-off.
 * And it computes far fewer cells than 64 sub-steps of the whole grid. */
static void test_closed_form_bit_for_bit_where_no_face_moves(void **state) {
    (void)state;
    enum { NX = 96, NY = 80 };
    double *h = malloc(sizeof(double) * NX * NY), *q = malloc(sizeof(double) * NX * NY);
    double *one = malloc(sizeof(double) * NX * NY), *many = malloc(sizeof(double) * NX * NY);
    uint8_t *moved = calloc(NX * NY, 1);
    dpsm_grid *a = dyadic_grid(NX, NY), *b = dyadic_grid(NX, NY);
    dyadic_scene(a, NX, NY, h, q);
    dyadic_scene(b, NX, NY, h, q);
    CHECK_OK(a, dpsm_step(a, 1.0 / 16.0));
    REQUIRE(step_info_of(a, DPSM_INFO_SUBSTEPS) == 64.0, "the call took %g sub-steps, not 64",
            step_info_of(a, DPSM_INFO_SUBSTEPS));
    const double updates = step_info_of(a, DPSM_INFO_CELL_UPDATES);
    step_calls(b, 64, 1.0 / 1024.0, NX, NY, moved);
    CHECK_OK(a, dpsm_get_heights(a, one));
    CHECK_OK(b, dpsm_get_heights(b, many));
    size_t quiet = 0, differ = 0;
    double worst = 0.0;
    for (size_t c = 0; c < (size_t)NX * NY; ++c) {
        if (!moved[c]) {
            ++quiet;
            differ += memcmp(&one[c], &many[c], sizeof(double)) != 0;
        }
        worst = fmax(worst, fabs(one[c] - many[c]) / fmax(1.0, fabs(many[c])));
    }
    print_message("%zu of %d cells never moved; %g cell updates for 64 sub-steps of %d cells (%.1f %%); "
                  "largest difference %.2e\n",
                  quiet, NX * NY, updates, NX * NY, 100.0 * updates / (64.0 * NX * NY), worst);
    REQUIRE(quiet > (size_t)(NX * NY) * 8 / 10 && quiet < (size_t)NX * NY, "%zu quiet cells", quiet);
    REQUIRE(differ == 0, "%zu cells where no face moved differ from sub-stepping", differ);
    REQUIRE(worst < 1e-13, "the moving cells differ from sub-stepping by %.3e", worst);
    REQUIRE(updates < 0.25 * 64.0 * NX * NY, "%g cell updates: the quiet cells were sub-stepped", updates);
    const ledger_t la = read_ledger(a), lb = read_ledger(b);
    REQUIRE(fabs(la.sourced - lb.sourced) <= 1e-13 * fabs(lb.sourced) && ledger_residual(a) < 1e-13,
            "sourced %.17g against %.17g, ledger residual %.2e", la.sourced, lb.sourced, ledger_residual(a));
    dpsm_destroy(a);
    dpsm_destroy(b);
    free(h);
    free(q);
    free(one);
    free(many);
    free(moved);
}

/* A plain scene with figures that round: one call and many agree to
 * round-off everywhere, and both ledgers close. On 1D, axisymmetric and 2D
 * grids, with an open side. */
static void compare_one_call_with_many(dpsm_grid *a, dpsm_grid *b, int64_t cells, int calls) {
    double sdt;
    CHECK_OK(a, dpsm_stable_dt(a, &sdt));
    const double dt = (calls - 0.5) * sdt;
    CHECK_OK(a, dpsm_step(a, dt));
    for (int k = 0; k < calls; ++k) CHECK_OK(b, dpsm_step(b, dt / calls));
    double *ha = malloc(sizeof(double) * (size_t)cells), *hb = malloc(sizeof(double) * (size_t)cells);
    CHECK_OK(a, dpsm_get_heights(a, ha));
    CHECK_OK(b, dpsm_get_heights(b, hb));
    double worst = 0.0;
    for (int64_t c = 0; c < cells; ++c) worst = fmax(worst, fabs(ha[c] - hb[c]) / fmax(1.0, fabs(hb[c])));
    REQUIRE(worst < 1e-12, "one call and %d differ by %.3e", calls, worst);
    REQUIRE(ledger_residual(a) < 1e-13 && ledger_residual(b) < 1e-13, "ledger residuals %.2e and %.2e",
            ledger_residual(a), ledger_residual(b));
    REQUIRE(fabs(mass_of(a, DPSM_MASS_SOURCED) - mass_of(b, DPSM_MASS_SOURCED)) <=
                1e-12 * fabs(mass_of(b, DPSM_MASS_SOURCED)),
            "sourced %.17g against %.17g", mass_of(a, DPSM_MASS_SOURCED), mass_of(b, DPSM_MASS_SOURCED));
    free(ha);
    free(hb);
}

static void gentle_scene(dpsm_grid *g, int64_t nx, int64_t ny) {
    double *h = malloc(sizeof(double) * (size_t)(nx * ny)), *q = malloc(sizeof(double) * (size_t)(nx * ny));
    for (int64_t j = 0; j < ny; ++j)
        for (int64_t i = 0; i < nx; ++i) {
            h[i + nx * j] = 0.3 + 0.01 * sin(0.3 * (double)i) + 0.013 * cos(0.21 * (double)j) +
                            (labs(i - nx / 3) < 3 && labs(j - ny / 2) < 3 ? 2.7 : 0.0);
            q[i + nx * j] = 0.037 * sin(0.11 * (double)(i + 2 * j)) + 0.011;
        }
    CHECK_OK(g, dpsm_set_repose_angle(g, kTheta));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN));
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_source(g, q));
    free(h);
    free(q);
}

static void test_closed_form_to_round_off(void **state) {
    (void)state;
    for (int kind = 0; kind < 3; ++kind) {
        const int64_t nx = kind == 2 ? 100 : 300, ny = kind == 2 ? 70 : 1;
        dpsm_grid *a = NULL, *b = NULL;
        if (kind == 0) {
            CHECK_OK(NULL, dpsm_create_1d(nx, 0.1, &a));
            CHECK_OK(NULL, dpsm_create_1d(nx, 0.1, &b));
        } else if (kind == 1) {
            CHECK_OK(NULL, dpsm_create_axisymmetric(nx, 0.1, &a));
            CHECK_OK(NULL, dpsm_create_axisymmetric(nx, 0.1, &b));
        } else {
            CHECK_OK(NULL, dpsm_create_2d(nx, ny, 0.1, 0.13, &a));
            CHECK_OK(NULL, dpsm_create_2d(nx, ny, 0.1, 0.13, &b));
        }
        gentle_scene(a, nx, ny);
        gentle_scene(b, nx, ny);
        compare_one_call_with_many(a, b, nx * ny, 40);
        dpsm_destroy(a);
        dpsm_destroy(b);
    }
}

/* A source that makes a face steep only half-way through the step: the
 * step must find it (at the end of the step) and sub-step it, as the calls
 * of one sub-step do; it is driven, so it takes every sub-step and does not
 * report rest. */
static void test_source_that_steepens_within_the_step(void **state) {
    (void)state;
    enum { NX = 40, NY = 30 };
    double h[NX * NY], q[NX * NY], one[NX * NY], many[NX * NY];
    dpsm_grid *a = dyadic_grid(NX, NY), *b = dyadic_grid(NX, NY);
    for (int c = 0; c < NX * NY; ++c) {
        h[c] = 1.0;
        q[c] = 0.0;
    }
    /* tan(30 deg) = 0.577 of a cell's height difference; at 2^-4 the cell is
     * 1.0 higher, steep from about 0.58 of the way. */
    q[17 + NX * 12] = 16.0;
    for (dpsm_grid *g = a; g; g = g == a ? b : NULL) {
        CHECK_OK(g, dpsm_set_heights(g, h));
        CHECK_OK(g, dpsm_set_source(g, q));
    }
    CHECK_OK(a, dpsm_step(a, 1.0 / 16.0));
    REQUIRE(step_info_of(a, DPSM_INFO_SUBSTEPS) == 64.0 && step_info_of(a, DPSM_INFO_AT_REST) == 0.0,
            "%g sub-steps, at rest %g", step_info_of(a, DPSM_INFO_SUBSTEPS), step_info_of(a, DPSM_INFO_AT_REST));
    step_calls(b, 64, 1.0 / 1024.0, NX, NY, NULL);
    CHECK_OK(a, dpsm_get_heights(a, one));
    CHECK_OK(b, dpsm_get_heights(b, many));
    double worst = 0.0;
    for (int c = 0; c < NX * NY; ++c) worst = fmax(worst, fabs(one[c] - many[c]));
    REQUIRE(worst < 1e-13, "the steepened source differs from sub-stepping by %.3e", worst);
    REQUIRE(max_of(many, NX * NY) < 2.0 - 0.05, "the source cell did not avalanche (top %.6f)",
            max_of(many, NX * NY));
    dpsm_destroy(a);
    dpsm_destroy(b);
}

/* Erosion beside an open cell (the fuzzer's ledger_2x1_bed_erosion): the
 * sand first slides into the open cell until its face rests, then the
 * erosion digs it below the open cell's level, so that face steepens the
 * other way and sand flows back. Judged at the start of the step, before
 * the sand moved, the source could steepen nothing (1.501 less the erosion
 * of the step stays within tan(theta) dx of the open cell); the step must
 * judge it again once the sand has moved. One call of n sub-steps against
 * n calls of one (about 14 time units), on a line and on a 2D row; the
 * ledger closes. */
static void test_source_that_steepens_after_sand_moved(void **state) {
    (void)state;
    for (int dim = 1; dim <= 2; ++dim) {
        double one[2], many[2];
        const int n = dim == 1 ? 100 : 200; /* the 2D sub-step is half the 1D one */
        for (int calls = 1; calls <= n; calls += n - 1) {
            dpsm_grid *g = NULL;
            if (dim == 1)
                CHECK_OK(NULL, dpsm_create_1d(2, 0.5, &g));
            else
                CHECK_OK(NULL, dpsm_create_2d(2, 1, 0.5, 0.5, &g));
            const double h[2] = {0.0, 1.501}, q[2] = {0.0, -0.1};
            const uint8_t kinds[2] = {DPSM_CELL_OPEN, DPSM_CELL_SAND};
            CHECK_OK(g, dpsm_set_heights(g, h));
            CHECK_OK(g, dpsm_set_cell_kinds(g, kinds));
            CHECK_OK(g, dpsm_set_source(g, q));
            double stable;
            CHECK_OK(g, dpsm_stable_dt(g, &stable));
            const double dt = 0.999 * stable * n / calls;
            for (int k = 0; k < calls; ++k) CHECK_OK(g, dpsm_step(g, dt));
            if (calls == 1)
                REQUIRE(step_info_of(g, DPSM_INFO_SUBSTEPS) == n, "dim %d: %g sub-steps", dim,
                        step_info_of(g, DPSM_INFO_SUBSTEPS));
            else
                REQUIRE(step_info_of(g, DPSM_INFO_SUBSTEPS) == 1.0, "dim %d: a call of %g sub-steps", dim,
                        step_info_of(g, DPSM_INFO_SUBSTEPS));
            CHECK_OK(g, dpsm_get_heights(g, calls == 1 ? one : many));
            REQUIRE(fabs(ledger_residual(g)) < 1e-13, "dim %d, %d calls: the ledger is %.3g open", dim, calls,
                    ledger_residual(g));
            dpsm_destroy(g);
        }
        REQUIRE(fabs(one[1] - many[1]) < 1e-12, "dim %d: one call leaves %.17g, sub-stepping %.17g", dim, one[1],
                many[1]);
        /* Dug below the open cell: held by the inflow at about tan(theta) dx and a little more. */
        REQUIRE(many[1] < -0.2, "dim %d: the sand cell ends at %.6f, not below the open cell", dim, many[1]);
    }
}

/* The scene: a source of 1e-300 in a corner cell of the benchmark
 * cone does not turn off the early stop: the same sub-steps as without it,
 * the same heights but in that corner, where the source lands in closed
 * form. On a line too. */
static void test_negligible_source_costs_nothing(void **state) {
    (void)state;
    for (int dim = 1; dim <= 2; ++dim) {
        const int64_t n = 101, cells = dim == 2 ? n * n : n;
        double *h = calloc((size_t)cells, sizeof *h), *q = calloc((size_t)cells, sizeof *q);
        double *with = malloc(sizeof(double) * (size_t)cells), *without = malloc(sizeof(double) * (size_t)cells);
        for (int64_t c = 0; c < cells; ++c) {
            const double r = dim == 2 ? hypot((double)(c % n - 50), (double)(c / n - 50)) : fabs((double)(c - 50));
            h[c] = fmax(0.0, 40.0 - 1.5 * r);
        }
        q[0] = 1e-300;
        double substeps[2];
        for (int s = 0; s < 2; ++s) {
            dpsm_grid *g = NULL;
            if (dim == 2)
                CHECK_OK(NULL, dpsm_create_2d(n, n, 1.0, 1.0, &g));
            else
                CHECK_OK(NULL, dpsm_create_1d(n, 1.0, &g));
            CHECK_OK(g, dpsm_set_repose_angle(g, 33.0 * 3.14159265358979323846 / 180.0));
            set_all_sides(g, DPSM_OPEN, dim);
            CHECK_OK(g, dpsm_set_heights(g, h));
            if (s) CHECK_OK(g, dpsm_set_source(g, q));
            CHECK_OK(g, dpsm_set_max_substeps(g, 100)); /* not a driven scene: not limited */
            CHECK_OK(g, dpsm_step(g, 1e6));
            substeps[s] = step_info_of(g, DPSM_INFO_SUBSTEPS);
            REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) == 1.0, "dim %d: not at rest", dim);
            /* The source acted over all of dt; without it the step ended at rest. */
            const double time = step_info_of(g, DPSM_INFO_TIME_INTEGRATED);
            REQUIRE(s ? time == 1e6 : time < 1e4, "dim %d: time integrated %g", dim, time);
            CHECK_OK(g, dpsm_get_heights(g, s ? with : without));
            dpsm_destroy(g);
        }
        REQUIRE(substeps[1] == substeps[0], "dim %d: %g sub-steps with the source, %g without", dim, substeps[1],
                substeps[0]);
        REQUIRE(memcmp(with + 1, without + 1, sizeof(double) * (size_t)(cells - 1)) == 0,
                "dim %d: the source changed cells it does not act on", dim);
        REQUIRE(fabs(with[0] - (without[0] + 1e-300 * 1e6)) <= 1e-12 * 1e-294, "dim %d: the corner holds %.17g",
                dim, with[0]);
        free(h);
        free(q);
        free(with);
        free(without);
    }
}

/* Only a source that makes a face steep within the step can keep sand
 * flowing, so only it is held to dpsm_set_max_substeps(). */
static void test_work_limit_only_for_a_driving_source(void **state) {
    (void)state;
    enum { NX = 50, NY = 40 };
    double h[NX * NY], q[NX * NY];
    for (int c = 0; c < NX * NY; ++c) {
        h[c] = 2.0;
        q[c] = 0.01;
    }
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(NX, NY, 1.0, 1.0, &g));
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_source(g, q));
    CHECK_OK(g, dpsm_set_max_substeps(g, 10));
    double sdt;
    CHECK_OK(g, dpsm_stable_dt(g, &sdt));
    CHECK_OK(g, dpsm_step(g, 100.0 * sdt)); /* a uniform source between walls steepens nothing */
    REQUIRE(step_info_of(g, DPSM_INFO_SUBSTEPS) == 0.0, "%g sub-steps", step_info_of(g, DPSM_INFO_SUBSTEPS));
    double after[NX * NY];
    CHECK_OK(g, dpsm_get_heights(g, after));
    REQUIRE(fabs(after[0] - (2.0 + 0.01 * 100.0 * sdt)) < 1e-14, "height %.17g", after[0]);
    q[NX / 2 + NX * (NY / 2)] = 100.0;
    CHECK_OK(g, dpsm_set_source(g, q));
    REQUIRE(dpsm_step(g, 100.0 * sdt) == DPSM_ERR_WORK_LIMIT, "a driving source was not limited");
    double again[NX * NY];
    CHECK_OK(g, dpsm_get_heights(g, again));
    REQUIRE(memcmp(after, again, sizeof after) == 0, "the refused step changed the heights");
    CHECK_OK(g, dpsm_step(g, 9.5 * sdt));
    REQUIRE(step_info_of(g, DPSM_INFO_SUBSTEPS) == 10.0, "%g sub-steps", step_info_of(g, DPSM_INFO_SUBSTEPS));
    dpsm_destroy(g);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_closed_form_bit_for_bit_where_no_face_moves),
        cmocka_unit_test(test_closed_form_to_round_off),
        cmocka_unit_test(test_source_that_steepens_within_the_step),
        cmocka_unit_test(test_source_that_steepens_after_sand_moved),
        cmocka_unit_test(test_negligible_source_costs_nothing),
        cmocka_unit_test(test_work_limit_only_for_a_driving_source),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
