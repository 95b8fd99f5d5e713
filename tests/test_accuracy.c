/* Accuracy against exact final states (the column collapse of the paper's
 * Section 5; formulas in DESIGN.md): the isotropic 2D scheme and the
 * axisymmetric grid converge to the exact deposit, the pairwise scheme does
 * not, and the paper's Eq. 17 energy dissipation is reproduced where it is
 * exact. Each test prints its error table with the observed orders. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "test_support.h"

static const double kPi = 3.14159265358979323846;

/* The exact deposit of a column of radius r0 = 1 and height a. */
typedef struct {
    double alpha, a, top_radius, foot_radius, height;
} deposit_t;

static deposit_t exact_deposit(double a, double theta) {
    deposit_t d = {tan(theta), a, 0.0, 0.0, 0.0};
    if (a <= sqrt(3.0) * d.alpha) { /* a truncated cone of height a */
        d.height = a;
        d.foot_radius = (a + sqrt(4.0 * d.alpha * d.alpha - a * a / 3.0)) / (2.0 * d.alpha);
        d.top_radius = d.foot_radius - a / d.alpha;
    } else { /* a cone of the column's volume */
        d.foot_radius = cbrt(3.0 * a / d.alpha);
        d.height = d.alpha * d.foot_radius;
    }
    return d;
}

static double deposit_height(const deposit_t *d, double r) {
    return fmax(0.0, fmin(d->height, d->alpha * (d->foot_radius - r)));
}

/* The fraction of the square [x0, x0+w] x [y0, y0+w] inside the unit circle,
 * by 16 x 16 sub-samples: the column's edge is drawn without a staircase. */
static double inside_fraction(double x0, double y0, double w) {
    int inside = 0;
    for (int b = 0; b < 16; ++b)
        for (int a = 0; a < 16; ++a) {
            const double x = x0 + (a + 0.5) * w / 16, y = y0 + (b + 0.5) * w / 16;
            inside += x * x + y * y <= 1.0;
        }
    return inside / 256.0;
}

typedef struct {
    double l1, height, runout_axis, runout_diagonal;
} collapse_error_t;

/* Where h falls to 0 along a ray of cell centres r_k: linear interpolation
 * between the last cell with sand and the first without, on the flank. */
static double foot_along(const double *h, const double *r, int count) {
    for (int k = 1; k < count; ++k)
        if (h[k] <= 0.0 && h[k - 1] > 0.0) {
            /* the flank through cells k-2 and k-1 meets 0 here */
            const double slope = k >= 2 ? (h[k - 2] - h[k - 1]) / (r[k - 1] - r[k - 2]) : 1.0;
            return r[k - 1] + h[k - 1] / slope;
        }
    return r[count - 1];
}

/* A 2D column collapse of aspect ratio a on an n x n open table [-W, W]^2
 * whose centre is a cell corner, run to rest; errors against the exact
 * deposit relative to it (L1 over the volume). */
static collapse_error_t collapse_2d(int64_t n, int scheme, double a, double theta) {
    const double W = 1.75, dx = 2.0 * W / n;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(n, n, dx, dx, &g));
    CHECK_OK(g, dpsm_set_scheme(g, scheme));
    CHECK_OK(g, dpsm_set_repose_angle(g, theta));
    set_all_sides(g, DPSM_OPEN, 2);
    double *h = malloc(sizeof(double) * n * n);
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) h[i + n * j] = a * inside_fraction(-W + i * dx, -W + j * dx, dx);
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_step(g, 1e6));
    double at_rest;
    CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_AT_REST, &at_rest));
    assert_true(at_rest == 1.0);
    assert_true(ledger_residual(g) < 1e-13);
    CHECK_OK(g, dpsm_get_heights(g, h));

    const deposit_t d = exact_deposit(a, theta);
    const double volume = kPi * a;
    collapse_error_t e = {0.0, 0.0, 0.0, 0.0};
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) {
            const double x = -W + (i + 0.5) * dx, y = -W + (j + 0.5) * dx;
            e.l1 += fabs(h[i + n * j] - deposit_height(&d, sqrt(x * x + y * y))) * dx * dx / volume;
            e.height = fmax(e.height, h[i + n * j]);
        }
    /* Rays from the cell next to the centre: along +x, and along the diagonal. */
    const int64_t c = n / 2, count = n / 2;
    double *ray_h = malloc(sizeof(double) * count), *ray_r = malloc(sizeof(double) * count);
    for (int64_t k = 0; k < count; ++k) {
        ray_h[k] = h[(c + k) + n * c];
        ray_r[k] = sqrt(pow((k + 0.5) * dx, 2) + pow(0.5 * dx, 2));
    }
    const double axis = foot_along(ray_h, ray_r, (int)count);
    for (int64_t k = 0; k < count; ++k) {
        ray_h[k] = h[(c + k) + n * (c + k)];
        ray_r[k] = sqrt(2.0) * (k + 0.5) * dx;
    }
    const double diagonal = foot_along(ray_h, ray_r, (int)count);
    e.height = (e.height - d.height) / d.height;
    e.runout_axis = (axis - d.foot_radius) / d.foot_radius;
    e.runout_diagonal = (diagonal - d.foot_radius) / d.foot_radius;
    free(ray_h);
    free(ray_r);
    free(h);
    dpsm_destroy(g);
    return e;
}

/* The isotropic scheme converges to the exact truncated cone: the L1 error
 * falls with every refinement and is at most 0.1 % at 128^2. */
static void test_isotropic_2d_collapse_converges(void **state) {
    (void)state;
    const double a = 0.5, theta = 30.0 * kPi / 180.0;
    const int64_t sizes[] = {32, 64, 128};
    collapse_error_t e[3];
    print_message("isotropic 2D column collapse, a = 0.5, theta = 30 deg:\n");
    print_message("  %6s %10s %6s %12s %14s %16s\n", "n", "L1/volume", "order", "height", "runout axis",
                  "runout diagonal");
    for (int k = 0; k < 3; ++k) {
        e[k] = collapse_2d(sizes[k], DPSM_SCHEME_ISOTROPIC, a, theta);
        const double order = k ? log(e[k - 1].l1 / e[k].l1) / log(2.0) : NAN;
        print_message("  %6d %9.4f%% %6.2f %+11.4f%% %+13.4f%% %+15.4f%%\n", (int)sizes[k], 100 * e[k].l1, order,
                      100 * e[k].height, 100 * e[k].runout_axis, 100 * e[k].runout_diagonal);
    }
    assert_true(e[1].l1 < e[0].l1 && e[2].l1 < e[1].l1);
    assert_true(e[2].l1 <= 1e-3);
    assert_true(log(e[0].l1 / e[2].l1) / log(4.0) > 0.9); /* at least first order over the range */
    assert_true(fabs(e[2].height) < 1e-3);
    assert_true(fabs(e[2].runout_axis) < 0.01 && fabs(e[2].runout_diagonal) < 0.01);
}

/* The pairwise scheme does not converge: its pyramid-like deposit stays
 * several percent off on every grid (DESIGN.md: about 7.5 %). */
static void test_pairwise_2d_collapse_does_not_converge(void **state) {
    (void)state;
    const double a = 0.5, theta = 30.0 * kPi / 180.0;
    const collapse_error_t coarse = collapse_2d(32, DPSM_SCHEME_PAIRWISE, a, theta);
    const collapse_error_t fine = collapse_2d(128, DPSM_SCHEME_PAIRWISE, a, theta);
    print_message("pairwise 2D column collapse: L1/volume %.2f%% at 32^2, %.2f%% at 128^2; runout along the "
                  "diagonal %+.2f%% at 128^2\n",
                  100 * coarse.l1, 100 * fine.l1, 100 * fine.runout_diagonal);
    assert_true(fine.l1 > 0.05 && coarse.l1 > 0.05);
    assert_true(fine.runout_diagonal < -0.05);
}

/* The axisymmetric column collapse, run to rest on nr rings over [0, 4 r0]
 * with r0 = 1 a whole number of rings. Returns the heights (caller frees). */
static double *collapse_axisymmetric(int64_t nr, double a, double theta, double *volume) {
    const double dr = 4.0 / nr;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_axisymmetric(nr, dr, &g));
    CHECK_OK(g, dpsm_set_repose_angle(g, theta));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN));
    double *h = calloc(nr, sizeof(double));
    for (int64_t i = 0; i < nr / 4; ++i) h[i] = a;
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_get_mass(g, DPSM_MASS_TOTAL, volume));
    CHECK_OK(g, dpsm_step(g, 1e6));
    double at_rest, total;
    CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_AT_REST, &at_rest));
    CHECK_OK(g, dpsm_get_mass(g, DPSM_MASS_TOTAL, &total));
    assert_true(at_rest == 1.0);
    assert_true(fabs(total - *volume) < 1e-13 * *volume); /* nothing reached the rim */
    CHECK_OK(g, dpsm_get_heights(g, h));
    dpsm_destroy(g);
    return h;
}

/* The cone case on the axisymmetric grid: the final height is within 0.2 %
 * of exact at 400 rings (it is already near the rest tolerance at 100, so
 * there is no refinement trend left to assert). The first ring
 * holds the pile's value at r = dr/2; its apex at r = 0 is that value carried
 * up the slope of the first face by half a ring (nothing for a flat top). */
static void test_axisymmetric_cone_height(void **state) {
    (void)state;
    const double a = 2.0, theta = 30.0 * kPi / 180.0;
    const deposit_t d = exact_deposit(a, theta);
    const int64_t sizes[] = {100, 200, 400};
    double err[3];
    print_message("axisymmetric cone, a = 2, theta = 30 deg (exact apex %.5f):\n", d.height);
    for (int k = 0; k < 3; ++k) {
        const double dr = 4.0 / sizes[k];
        double volume;
        double *h = collapse_axisymmetric(sizes[k], a, theta, &volume);
        const double apex = h[0] + 0.5 * (h[0] - h[1]);
        const double at_centre = deposit_height(&d, 0.5 * dr);
        err[k] = fabs(apex - d.height) / d.height;
        print_message("  nr = %4d: apex %.5f, error %.4f%%; first ring %.5f vs exact there %.5f (%.4f%%)\n",
                      (int)sizes[k], apex, 100 * err[k], h[0], at_centre, 100 * fabs(h[0] - at_centre) / at_centre);
        free(h);
    }
    assert_true(err[2] < 2e-3);
    assert_true(err[0] < 2e-4 && err[1] < 2e-4 && err[2] < 2e-4);
}

/* The truncated cone case on the axisymmetric grid converges in L1, and the
 * energy dissipated matches the paper's Eq. 17, exact for this case. */
static void test_axisymmetric_truncated_cone_and_eq_17(void **state) {
    (void)state;
    const double theta = 21.0 * kPi / 180.0, alpha = tan(theta);
    const int64_t sizes[] = {100, 200, 400};
    for (int which = 0; which < 2; ++which) {
        const double a = which ? 0.6 : 0.3;
        const deposit_t d = exact_deposit(a, theta);
        const double eq17 = a / (6.0 * sqrt(3.0) * alpha * alpha) * sqrt(12.0 * alpha * alpha - a * a);
        double l1[3], energy_err[3];
        print_message("axisymmetric truncated cone, a = %.1f, theta = 21 deg; Eq. 17 gives %.6f dissipated:\n", a,
                      eq17);
        for (int k = 0; k < 3; ++k) {
            const double dr = 4.0 / sizes[k];
            double volume, e0 = 0.0, e1 = 0.0;
            double *h = collapse_axisymmetric(sizes[k], a, theta, &volume);
            l1[k] = 0.0;
            for (int64_t i = 0; i < sizes[k]; ++i) {
                const double r = (i + 0.5) * dr, ring = 2.0 * kPi * r * dr;
                const double h0 = i < sizes[k] / 4 ? a : 0.0;
                l1[k] += fabs(h[i] - deposit_height(&d, r)) * ring / volume;
                e0 += 0.5 * h0 * h0 * ring;
                e1 += 0.5 * h[i] * h[i] * ring;
            }
            const double dissipated = (e0 - e1) / e0;
            energy_err[k] = fabs(dissipated - eq17) / eq17;
            print_message("  nr = %4d: L1/volume %.4f%%, height %.6f (exact %.6f), dissipated %.6f (Eq. 17 off by "
                          "%.4f%%)\n",
                          (int)sizes[k], 100 * l1[k], h[0], a, dissipated, 100 * energy_err[k]);
            free(h);
        }
        assert_true(l1[1] < l1[0] && l1[2] < l1[1]);
        assert_true(l1[2] < 2e-3);
        assert_true(energy_err[2] < 2e-3);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_isotropic_2d_collapse_converges),
        cmocka_unit_test(test_pairwise_2d_collapse_does_not_converge),
        cmocka_unit_test(test_axisymmetric_cone_height),
        cmocka_unit_test(test_axisymmetric_truncated_cone_and_eq_17),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
