/* The demo: a sand column collapses on an open table (the paper's Section 5).
 *
 * A cylinder of radius r0 and height h0 = a*r0 is released on a square open
 * table and run to rest with one dpsm_step(). The final height and the runout
 * along an axis and a diagonal are printed next to the exact axisymmetric
 * deposit (a truncated cone for a <= sqrt(3) tan(theta), a cone above), and the
 * mass balance closes the report.
 *
 * usage: dpsm-demo [n] [aspect_ratio] [theta_degrees]      (defaults 128 0.5 30)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <dpsm/dpsm.h>

#define CHECK(call)                                                                         \
    do {                                                                                    \
        int status_ = (call);                                                               \
        if (status_ != DPSM_OK) {                                                           \
            fprintf(stderr, "%s failed: %s: %s\n", #call, dpsm_status_string(status_),     \
                    dpsm_last_error(g));                                                    \
            exit(1);                                                                        \
        }                                                                                   \
    } while (0)

/* Where the pile ends along the ray from the centre with direction (di, dj):
 * the outermost sand cell extrapolated down its flank at the angle of repose. */
static double runout_along(const double *h, int n, double dx, int di, int dj, double tan_theta) {
    const int c = n / 2;
    double foot = 0.0;
    for (int k = 0; c + k * di < n && c + k * dj < n; ++k) {
        const double hk = h[(c + k * di) + (size_t)n * (c + k * dj)];
        const double r = k * dx * sqrt((double)(di * di + dj * dj));
        if (hk > 1e-9) foot = r + hk / tan_theta;
    }
    return foot;
}

int main(int argc, char **argv) {
    const int n = argc > 1 ? atoi(argv[1]) : 128;
    const double a = argc > 2 ? atof(argv[2]) : 0.5;
    const double theta_deg = argc > 3 ? atof(argv[3]) : 30.0;
    const double pi = 3.14159265358979323846;
    const double theta = theta_deg * pi / 180.0, alpha = tan(theta);
    const double r0 = 1.0, h0 = a * r0;
    /* The table is wide enough to hold the deposit whatever the regime. */
    const double cone_rf = r0 * cbrt(3.0 * a / alpha);
    const double half_width = 1.25 * fmax(2.0 * r0, cone_rf);
    const double dx = 2.0 * half_width / n;
    dpsm_grid *g = NULL;

    CHECK(dpsm_create_2d(n, n, dx, dx, &g));
    CHECK(dpsm_set_repose_angle(g, theta));
    for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side) CHECK(dpsm_set_boundary(g, side, DPSM_OPEN));

    /* The column: every cell whose centre lies within r0 of the table centre,
     * which sits on the centre of cell (n/2, n/2). */
    double *h = calloc((size_t)n * n, sizeof *h);
    if (!h) return 1;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double x = (i - n / 2) * dx, y = (j - n / 2) * dx;
            if (x * x + y * y <= r0 * r0) h[i + (size_t)n * j] = h0;
        }
    CHECK(dpsm_set_heights(g, h));
    double volume0;
    CHECK(dpsm_get_mass(g, DPSM_MASS_TOTAL, &volume0));

    /* To rest: by default (DPSM_RELAX_AUTO) the step relaxes this scene
     * straight to rest; with DPSM_RELAX_TIME_ACCURATE it would take sub-steps
     * and stop once nothing moves. */
    CHECK(dpsm_step(g, 1e6));
    double substeps, at_rest, t_rest;
    CHECK(dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &substeps));
    CHECK(dpsm_get_step_info(g, DPSM_INFO_AT_REST, &at_rest));
    CHECK(dpsm_get_step_info(g, DPSM_INFO_TIME_INTEGRATED, &t_rest));
    CHECK(dpsm_get_heights(g, h));

    double hf = 0.0;
    for (size_t c = 0; c < (size_t)n * n; ++c) hf = fmax(hf, h[c]);
    const double run_axis = runout_along(h, n, dx, 1, 0, alpha);
    const double run_diag = runout_along(h, n, dx, 1, 1, alpha);

    /* Exact axisymmetric deposit of the column's own (discrete) volume. */
    const double regime_limit = sqrt(3.0) * alpha;
    double hf_exact, rf_exact;
    if (a <= regime_limit) {
        hf_exact = h0;
        rf_exact = r0 * (a + sqrt(4.0 * alpha * alpha - a * a / 3.0)) / (2.0 * alpha);
    } else {
        rf_exact = cone_rf;
        hf_exact = alpha * rf_exact;
    }

    double total, sourced, external, outflow;
    CHECK(dpsm_get_mass(g, DPSM_MASS_TOTAL, &total));
    CHECK(dpsm_get_mass(g, DPSM_MASS_SOURCED, &sourced));
    CHECK(dpsm_get_mass(g, DPSM_MASS_EXTERNAL, &external));
    CHECK(dpsm_get_mass(g, DPSM_MASS_OUTFLOW, &outflow));

    printf("dpsm %s: column collapse, a = %g, theta = %g deg, %dx%d cells, open table\n",
           dpsm_version_string(), a, theta_deg, n, n);
    if (t_rest == 0.0)
        printf("  at rest: %s, relaxed to rest in %.0f flux evaluations\n", at_rest > 0 ? "yes" : "no", substeps);
    else
        printf("  at rest: %s after t = %.4g (%.0f sub-steps)\n", at_rest > 0 ? "yes" : "no", t_rest, substeps);
    printf("  %-24s %12s %12s %10s\n", "", "dpsm", "exact", "rel. diff");
    printf("  %-24s %12.5f %12.5f %9.2f%%\n", "final height h_f/r0", hf / r0, hf_exact / r0,
           100.0 * (hf - hf_exact) / hf_exact);
    printf("  %-24s %12.5f %12.5f %9.2f%%\n", "runout r_f/r0, axis", run_axis / r0, rf_exact / r0,
           100.0 * (run_axis - rf_exact) / rf_exact);
    printf("  %-24s %12.5f %12.5f %9.2f%%\n", "runout r_f/r0, diagonal", run_diag / r0, rf_exact / r0,
           100.0 * (run_diag - rf_exact) / rf_exact);
    printf("  mass balance: total %.15g = sourced %.3g + external %.15g - outflow %.3g\n", total, sourced,
           external, outflow);
    printf("  ledger residual |total - (sourced + external - outflow)| / total = %.2e\n",
           fabs(total - (sourced + external - outflow)) / total);
    printf("  volume change during the collapse: %.2e (relative)\n", fabs(total - volume0) / volume0);

    free(h);
    dpsm_destroy(g);
    return 0;
}
