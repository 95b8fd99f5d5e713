/* Regressions of library bugs found by the stress suite and the fuzzer at
 * extreme inputs, one test each (ctest stress_regressions). Heights, sources,
 * cell sizes and mobilities whose slopes or masses would overflow are now
 * refused at the API (the supported range in dpsm.h), and a sweep judges motion
 * by the sand faces carry, not by heights that change. Cases that used to hang
 * run in a child process with a time limit.
 *
 * All of them lie outside the range the suite and the fuzzer use (heights up
 * to 1e6, spacings 1e-3 .. 1e3, dt from 1e-300): see docs/guarantees.md,
 * "Known limits". */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>

#include <dpsm/dpsm.h>

static dpsm_grid *grid_2d(int64_t nx, int64_t ny, double d) {
    dpsm_grid *g = NULL;
    assert_int_equal(dpsm_create_2d(nx, ny, d, d, &g), DPSM_OK);
    return g;
}

static dpsm_grid *grid_1d(int64_t nx, double d) {
    dpsm_grid *g = NULL;
    assert_int_equal(dpsm_create_1d(nx, d, &g), DPSM_OK);
    return g;
}

static double info(const dpsm_grid *g, int item) {
    double v = 0.0;
    assert_int_equal(dpsm_get_step_info(g, item, &v), DPSM_OK);
    return v;
}

/* Runs body(arg) in a child process; fails if it takes more than `seconds`. */
static void within(unsigned seconds, void (*body)(void), const char *what) {
    fflush(NULL);
    const pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        alarm(seconds);
        body();
        _exit(0);
    }
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    if (WIFSIGNALED(status) && WTERMSIG(status) == SIGALRM) fail_msg("%s: still running after %u s (a hang)", what, seconds);
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}

/* 1. A face slope whose square overflows (|dh|/d above ~1.3e154) on a 2D grid:
 * the AVX-512 kernel (rsqrt of +inf refined by Newton steps) gives NaN
 * heights; the generic one (DPSM_NO_AVX512=1) computes a flux of 0 and reports
 * the surface at rest with a slope of 1e160. src/structured/tile_kernel_impl.hpp,
 * face_flux: u = gn*gn + gt*gt overflows. */
static void test_2d_slope_square_overflows(void **state) {
    (void)state;
    dpsm_grid *g = grid_2d(2, 1, 1.0);
    double h[2] = {1e160, 0.0};
    if (dpsm_set_heights(g, h) != DPSM_OK) { /* refused: outside the supported range, fine */
        assert_true(strstr(dpsm_last_error(g), "supported range") != NULL);
        dpsm_destroy(g);
        return;
    }
    assert_int_equal(dpsm_step(g, 1.0), DPSM_OK);
    assert_int_equal(dpsm_get_heights(g, h), DPSM_OK);
    print_message("2D {1e160, 0} after dpsm_step(1): h = {%g, %g}, AT_REST %g\n", h[0], h[1], info(g, DPSM_INFO_AT_REST));
    assert_true(isfinite(h[0]) && isfinite(h[1]));
    assert_true(h[1] > 0.0); /* sand moved down the slope */
    dpsm_destroy(g);
}

/* 2. The same in 1D (src/model/face_law.hpp, slide_flux: (s - tan) / sqrt(1 + s*s)
 * is 0 once s*s overflows): nothing moves, yet every sub-step counts as
 * motion, so the surface never rests. */
static void test_1d_slope_square_overflows(void **state) {
    (void)state;
    dpsm_grid *g = grid_1d(2, 1.0);
    double h[2] = {1e160, 0.0};
    if (dpsm_set_heights(g, h) != DPSM_OK) { /* refused: outside the supported range, fine */
        assert_true(strstr(dpsm_last_error(g), "supported range") != NULL);
        dpsm_destroy(g);
        return;
    }
    assert_int_equal(dpsm_step(g, 1.0), DPSM_OK);
    assert_int_equal(dpsm_get_heights(g, h), DPSM_OK);
    print_message("1D {1e160, 0} after dpsm_step(1): h = {%g, %g}, AT_REST %g\n", h[0], h[1], info(g, DPSM_INFO_AT_REST));
    assert_true(h[1] > 0.0);
    dpsm_destroy(g);
}

/* 2b. ... so a step of dt = 1e12 on it runs ~1.7e12 sub-steps: a hang. */
static void step_stuck_1d(void) {
    dpsm_grid *g = NULL;
    dpsm_create_1d(2, 1.0, &g);
    double h[2] = {1e160, 0.0};
    dpsm_set_heights(g, h);
    dpsm_step(g, 1e12);
    dpsm_destroy(g);
}
static void test_1d_slope_square_overflows_hangs(void **state) {
    (void)state;
    within(10, step_stuck_1d, "1D {1e160, 0}, dpsm_step(1e12)");
}

/* 3. A height difference that overflows (DBL_MAX - (-DBL_MAX)): NaN heights. */
static void test_1d_height_difference_overflows(void **state) {
    (void)state;
    dpsm_grid *g = grid_1d(2, 1.0);
    double h[2] = {DBL_MAX, -DBL_MAX};
    if (dpsm_set_heights(g, h) != DPSM_OK) { /* refused: outside the supported range, fine */
        assert_true(strstr(dpsm_last_error(g), "supported range") != NULL);
        dpsm_destroy(g);
        return;
    }
    assert_int_equal(dpsm_step(g, 1.0), DPSM_OK);
    assert_int_equal(dpsm_get_heights(g, h), DPSM_OK);
    print_message("1D {DBL_MAX, -DBL_MAX} after dpsm_step(1): h = {%g, %g}\n", h[0], h[1]);
    assert_true(isfinite(h[0]) && isfinite(h[1]));
    dpsm_destroy(g);
}

/* 4. A spacing whose square underflows (dx = 1e-160): stable_dt is 0 and the
 * 2D step writes NaN (src/stepping/stepper.cpp, stable_dt; dt / 0 sub-steps). Either
 * dpsm_create_2d refuses such a spacing or the step stays finite. */
static void test_2d_tiny_spacing(void **state) {
    (void)state;
    dpsm_grid *g = NULL;
    if (dpsm_create_2d(2, 1, 1e-160, 1e-160, &g) != DPSM_OK) return; /* refused: fine */
    double dt = -1.0, h[2] = {1.0, 0.0};
    assert_int_equal(dpsm_stable_dt(g, &dt), DPSM_OK);
    assert_int_equal(dpsm_set_heights(g, h), DPSM_OK);
    assert_int_equal(dpsm_step(g, 1.0), DPSM_OK);
    assert_int_equal(dpsm_get_heights(g, h), DPSM_OK);
    print_message("2D dx = 1e-160: stable_dt %g, after dpsm_step(1): h = {%g, %g}\n", dt, h[0], h[1]);
    assert_true(dt > 0.0);
    assert_true(isfinite(h[0]) && isfinite(h[1]));
    dpsm_destroy(g);
}

/* 5. The same in 1D (dx = 1e-155: slope 1e155, its square overflows, the
 * sub-step is subnormal): dpsm_step(1) never returns. */
static void step_tiny_spacing_1d(void) {
    dpsm_grid *g = NULL;
    if (dpsm_create_1d(2, 1e-155, &g) != DPSM_OK) return;
    double h[2] = {1.0, 0.0};
    dpsm_set_heights(g, h);
    dpsm_step(g, 1.0);
    dpsm_destroy(g);
}
static void test_1d_tiny_spacing_hangs(void **state) {
    (void)state;
    within(10, step_tiny_spacing_1d, "1D dx = 1e-155, dpsm_step(1)");
}

/* 6. A spacing whose cell area overflows (2D, dx = dy = 1e200): the ledger
 * reads NaN (0 * inf) as soon as heights are set (src/model/grid.cpp, cell_area). */
static void test_2d_huge_spacing_mass(void **state) {
    (void)state;
    dpsm_grid *g = NULL;
    if (dpsm_create_2d(2, 1, 1e200, 1e200, &g) != DPSM_OK) return; /* refused: fine */
    double h[2] = {1.0, 0.0}, total = 0.0, external = 0.0;
    assert_int_equal(dpsm_set_heights(g, h), DPSM_OK);
    assert_int_equal(dpsm_get_mass(g, DPSM_MASS_TOTAL, &total), DPSM_OK);
    assert_int_equal(dpsm_get_mass(g, DPSM_MASS_EXTERNAL, &external), DPSM_OK);
    print_message("2D dx = dy = 1e200: total %g, external %g\n", total, external);
    assert_true(isfinite(total) && isfinite(external));
    dpsm_destroy(g);
}

/* 7. A dt so small that every increment rounds to 0 (dt = 5e-324) on a 2D
 * ramp steeper than the angle of repose: the step reports rest and the active
 * set goes cold, so every later step, of any dt, does nothing; the ramp stays
 * supercritical for good. 1D and axisymmetric grids move on. The 2D sweep
 * takes "no cell changed" for "no face carried sand" (src/structured/tile_kernel_impl.hpp:
 * moved/hot from increment != 0). */
static void test_2d_denormal_dt_freezes_the_surface(void **state) {
    (void)state;
    dpsm_grid *g = grid_2d(8, 8, 1.0);
    double h[64], top_before, top_after;
    for (int c = 0; c < 64; ++c) h[c] = 0.7 * (c % 8); /* slope 0.7 > tan(30 deg) */
    top_before = h[7];
    assert_int_equal(dpsm_set_heights(g, h), DPSM_OK);
    assert_int_equal(dpsm_step(g, 4.9406564584124654e-324), DPSM_OK);
    assert_int_equal(dpsm_step(g, 1.0), DPSM_OK);
    assert_int_equal(dpsm_get_heights(g, h), DPSM_OK);
    top_after = h[7];
    print_message("2D ramp of slope 0.7: after dpsm_step(5e-324), dpsm_step(1): top %.6f (was %.6f), AT_REST %g, "
                  "MAX_EXCESS_SLOPE %g\n",
                  top_after, top_before, info(g, DPSM_INFO_AT_REST), info(g, DPSM_INFO_MAX_EXCESS_SLOPE));
    assert_true(top_after < top_before);
    dpsm_destroy(g);
}

/* 8. (Semantics, minor.) Sand running steadily between two open cells through
 * a sand cell: no height changes (net outflow 0), but both faces carry sand
 * 0.42 above tan(theta). 2D and 1D steps must agree: not at rest, the same
 * excess. (The 2D step used to report rest and let its active set go cold.) */
static void test_through_flow_rest_2d_vs_1d(void **state) {
    (void)state;
    double h[3] = {3.0, 2.0, 1.0};
    const uint8_t kinds[3] = {DPSM_CELL_OPEN, DPSM_CELL_SAND, DPSM_CELL_OPEN};
    dpsm_grid *a = grid_2d(3, 1, 1.0), *b = grid_1d(3, 1.0);
    dpsm_grid *both[2] = {a, b};
    for (int k = 0; k < 2; ++k) {
        assert_int_equal(dpsm_set_heights(both[k], h), DPSM_OK);
        assert_int_equal(dpsm_set_cell_kinds(both[k], kinds), DPSM_OK);
        assert_int_equal(dpsm_step(both[k], 1.0), DPSM_OK);
        assert_int_equal(dpsm_step(both[k], 1.0), DPSM_OK);
    }
    print_message("through-flow: 2D AT_REST %g excess %g; 1D AT_REST %g excess %g\n", info(a, DPSM_INFO_AT_REST),
                  info(a, DPSM_INFO_MAX_EXCESS_SLOPE), info(b, DPSM_INFO_AT_REST), info(b, DPSM_INFO_MAX_EXCESS_SLOPE));
    assert_true(info(a, DPSM_INFO_AT_REST) == info(b, DPSM_INFO_AT_REST));
    assert_true(info(a, DPSM_INFO_MAX_EXCESS_SLOPE) == info(b, DPSM_INFO_MAX_EXCESS_SLOPE));
    dpsm_destroy(a);
    dpsm_destroy(b);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_2d_slope_square_overflows),
        cmocka_unit_test(test_1d_slope_square_overflows),
        cmocka_unit_test(test_1d_slope_square_overflows_hangs),
        cmocka_unit_test(test_1d_height_difference_overflows),
        cmocka_unit_test(test_2d_tiny_spacing),
        cmocka_unit_test(test_1d_tiny_spacing_hangs),
        cmocka_unit_test(test_2d_huge_spacing_mass),
        cmocka_unit_test(test_2d_denormal_dt_freezes_the_surface),
        cmocka_unit_test(test_through_flow_rest_2d_vs_1d),
    };
    return cmocka_run_group_tests_name("known bugs", tests, NULL, NULL);
}
