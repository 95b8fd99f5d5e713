/* The study of larger steps (dpsm-bench steps): what reaches rest with a given
 * error in the least time. Compares, on the cone scene and the column
 * collapse, dpsm's explicit sub-steps at the stability limit (the default,
 * time accurate) at several rest tolerances with
 *  - the paper's bounded exchange taken to its limit (dt -> infinity: every
 *    face moves its share of the sand that brings it to the angle of repose,
 *    each sweep, a relaxation without a time scale), and
 *  - Runge-Kutta-Chebyshev super-time-stepping (10, 20, 40 stages), whose
 *    steps are about 0.33 s^2 explicit sub-steps long,
 * both written here as plain loops on the isotropic scheme. "sweeps" counts
 * rate evaluations (explicit: sub-steps). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "reference.h"

static const double kPi = 3.14159265358979323846;

typedef struct {
    const char *name;
    int64_t n;
    double dx, theta, exact_top;
    void (*fill)(double *h, int64_t n, double dx);
} scene;

static void fill_cone(double *h, int64_t n, double dx) {
    (void)dx;
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) h[i + n * j] = fmax(0.0, 40.0 - 1.5 * hypot((double)(i - n / 2), (double)(j - n / 2)));
}

static void fill_column(double *h, int64_t n, double dx) {
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) {
            const double x = (i - n / 2) * dx, y = (j - n / 2) * dx;
            h[i + n * j] = x * x + y * y <= 1.0 ? 0.5 : 0.0;
        }
}

static double top_of(const double *h, int64_t cells) {
    double t = 0.0;
    for (int64_t c = 0; c < cells; ++c) t = fmax(t, h[c]);
    return t;
}

/* The bounded exchange at dt -> infinity on the isotropic scheme, open sides:
 * each face moves a quarter of the normal difference that separates it from
 * the angle of repose (given its transverse slope), so no cell gives more than
 * it has to; sweeps until no face exceeds the rest threshold. */
static int64_t relax(double *h, int64_t n, double dx, double theta, double tolerance) {
    const double alpha = tan(theta), threshold = alpha * (1.0 + tolerance);
    const int64_t w = n + 2;
    double *p = xcalloc((size_t)(w * w), sizeof(double)), *d = xcalloc((size_t)(w * w), sizeof(double));
#define P(i, j) p[((j) + 1) * w + (i) + 1]
#define D(i, j) d[((j) + 1) * w + (i) + 1]
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) P(i, j) = h[i + n * j];
    int64_t sweeps = 0;
    for (;; ++sweeps) {
        double worst = 0.0;
        memset(d, 0, sizeof(double) * (size_t)(w * w));
        for (int64_t j = -1; j < n; ++j)
            for (int64_t i = -1; i < n; ++i)
                for (int dir = 0; dir < 2; ++dir) {
                    const int64_t i2 = i + (dir == 0), j2 = j + (dir == 1);
                    if (i2 >= n || j2 >= n || (dir == 0 && (j < 0)) || (dir == 1 && (i < 0))) continue;
                    if ((i < 0 || j < 0) && (i2 < 0 || j2 < 0)) continue;
                    const double gn = (P(i, j) - P(i2, j2)) / dx;
                    double ta, tb;
                    if (dir == 0) {
                        ta = (i >= 0 && i < n) ? (P(i, j + 1) - P(i, j - 1)) / (2 * dx) : 0.0;
                        tb = (i2 >= 0 && i2 < n) ? (P(i2, j2 + 1) - P(i2, j2 - 1)) / (2 * dx) : 0.0;
                    } else {
                        ta = (j >= 0 && j < n) ? (P(i + 1, j) - P(i - 1, j)) / (2 * dx) : 0.0;
                        tb = (j2 >= 0 && j2 < n) ? (P(i2 + 1, j2) - P(i2 - 1, j2)) / (2 * dx) : 0.0;
                    }
                    const double gt = 0.5 * (ta + tb), g = sqrt(gn * gn + gt * gt);
                    if (!(g > threshold)) continue;
                    worst = fmax(worst, g - alpha);
                    const double target = sqrt(fmax(0.0, alpha * alpha - gt * gt));
                    const double move = 0.25 * 0.5 * dx * (fabs(gn) - target) * (gn > 0 ? 1.0 : -1.0);
                    if (i >= 0 && j >= 0) D(i, j) -= move;
                    if (i2 >= 0 && j2 >= 0 && i2 < n && j2 < n) D(i2, j2) += move;
                }
        if (worst == 0.0 || sweeps > 10000000) break;
        for (int64_t j = 0; j < n; ++j)
            for (int64_t i = 0; i < n; ++i) P(i, j) += D(i, j);
    }
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) h[i + n * j] = P(i, j);
#undef P
#undef D
    free(p);
    free(d);
    return sweeps;
}

/* Runge-Kutta-Chebyshev (second order, damping 2/13; Sommeijer, Shampine and
 * Verwer 1997) steps of s stages, each step s^2 * 0.65 / 2 explicit sub-steps
 * long, on the reference loop's rates, to rest. Returns the rate evaluations. */
static int64_t rkc_to_rest(double *h, int64_t n, double dx, double theta, double tolerance, int s, int *at_rest) {
    reference_grid r;
    if (!reference_init(&r, n, n, dx, dx, 1.0, theta, tolerance, h)) exit(1);
    const int64_t cells = n * n;
    double *y0 = xcalloc((size_t)cells, sizeof(double)), *f0 = xcalloc((size_t)cells, sizeof(double));
    double *yjm1 = xcalloc((size_t)cells, sizeof(double)), *yjm2 = xcalloc((size_t)cells, sizeof(double));
    double *fj = xcalloc((size_t)cells, sizeof(double)), *yj = xcalloc((size_t)cells, sizeof(double));
    /* Chebyshev T_j, T_j', T_j'' at w0, and the method's coefficients. */
    const double eps = 2.0 / 13.0, w0 = 1.0 + eps / ((double)s * s);
    double T[64], dT[64], ddT[64], b[64];
    T[0] = 1; T[1] = w0; dT[0] = 0; dT[1] = 1; ddT[0] = 0; ddT[1] = 0;
    for (int j = 2; j <= s; ++j) {
        T[j] = 2 * w0 * T[j - 1] - T[j - 2];
        dT[j] = 2 * T[j - 1] + 2 * w0 * dT[j - 1] - dT[j - 2];
        ddT[j] = 4 * dT[j - 1] + 2 * w0 * ddT[j - 1] - ddT[j - 2];
    }
    const double w1 = dT[s] / ddT[s];
    for (int j = 2; j <= s; ++j) b[j] = ddT[j] / (dT[j] * dT[j]);
    b[0] = b[1] = b[2];
    const double beta = (w0 + 1.0) * ddT[s] / dT[s];
    const double lambda_max = 8.0 * cos(theta) / (dx * dx); /* nu = 1, dx = dy */
    const double tau = 0.95 * beta / lambda_max;
    int64_t evaluations = 0;
    *at_rest = 0;
    /* At most as many rate evaluations as the explicit scheme's sub-steps at
     * tolerance 1e-6 on the cone, twice over: beyond that it has not paid. */
    for (int step = 0; evaluations < 14000; ++step) {
        for (int64_t c = 0; c < cells; ++c) y0[c] = reference_height(&r, c % n, c / n);
        const double excess = reference_rates(&r, f0);
        ++evaluations;
        if (excess == 0.0) {
            *at_rest = 1;
            break;
        }
        for (int64_t c = 0; c < cells; ++c) {
            yjm2[c] = y0[c];
            yjm1[c] = y0[c] + b[1] * w1 * tau * f0[c];
        }
        for (int j = 2; j <= s; ++j) {
            for (int64_t c = 0; c < cells; ++c) reference_set_height(&r, c % n, c / n, yjm1[c]);
            reference_rates(&r, fj);
            ++evaluations;
            const double mu = 2 * b[j] * w0 / b[j - 1], nu = -b[j] / b[j - 2];
            const double mut = 2 * b[j] * w1 / b[j - 1], gamt = -(1.0 - b[j - 1] * T[j - 1]) * mut;
            for (int64_t c = 0; c < cells; ++c)
                yj[c] = (1 - mu - nu) * y0[c] + mu * yjm1[c] + nu * yjm2[c] + mut * tau * fj[c] + gamt * tau * f0[c];
            double *t = yjm2; yjm2 = yjm1; yjm1 = yj; yj = t;
        }
        for (int64_t c = 0; c < cells; ++c) reference_set_height(&r, c % n, c / n, yjm1[c]);
    }
    for (int64_t c = 0; c < cells; ++c) h[c] = reference_height(&r, c % n, c / n);
    reference_free(&r);
    free(y0); free(f0); free(yjm1); free(yjm2); free(fj); free(yj);
    return evaluations;
}

int cmd_steps(int argc, char **argv) {
    (void)argc;
    (void)argv;
    const scene scenes[] = {
        {"cone", 101, 1.0, 33.0 * kPi / 180.0, 22.89, fill_cone},
        /* column a = 0.5 at 30 deg: a truncated cone, top stays at h0 = 0.5; its
         * runout is the quantity that moves, the top is checked for damage. */
        {"column", 128, 4.0 / 128, 30.0 * kPi / 180.0, 0.5, fill_column},
    };
    const double tolerances[] = {1e-6, 1e-3, 1e-2};
    printf("scene,method,tolerance,seconds,sweeps,top,top_error_percent,volume_change,at_rest\n");
    for (size_t s = 0; s < sizeof scenes / sizeof *scenes; ++s) {
        const scene *sc = &scenes[s];
        const int64_t n = sc->n, cells = n * n;
        double *h0 = xcalloc((size_t)cells, sizeof(double)), *h = xcalloc((size_t)cells, sizeof(double));
        sc->fill(h0, n, sc->dx);
        double v0 = 0.0;
        for (int64_t c = 0; c < cells; ++c) v0 += h0[c];
        for (size_t t = 0; t < sizeof tolerances / sizeof *tolerances; ++t) {
            dpsm_grid *g = NULL;
            CHECK(NULL, dpsm_create_2d(n, n, sc->dx, sc->dx, &g));
            CHECK(g, dpsm_set_repose_angle(g, sc->theta));
            CHECK(g, dpsm_set_rest_tolerance(g, tolerances[t]));
            for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side) CHECK(g, dpsm_set_boundary(g, side, DPSM_OPEN));
            CHECK(g, dpsm_set_heights(g, h0));
            const double t0 = now_seconds();
            CHECK(g, dpsm_step(g, 1e6));
            const double seconds = now_seconds() - t0;
            double substeps;
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &substeps));
            CHECK(g, dpsm_get_heights(g, h));
            double v = 0.0;
            for (int64_t c = 0; c < cells; ++c) v += h[c];
            const double top = top_of(h, cells);
            double rest;
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_AT_REST, &rest));
            printf("%s,explicit,%g,%.4f,%.0f,%.4f,%.3f,%.1e,%d\n", sc->name, tolerances[t], seconds, substeps, top,
                   100.0 * (top - sc->exact_top) / sc->exact_top, fabs(v - v0) / v0, rest == 1.0);
            dpsm_destroy(g);

            memcpy(h, h0, sizeof(double) * (size_t)cells);
            const double t1 = now_seconds();
            const int64_t sweeps = relax(h, n, sc->dx, sc->theta, tolerances[t]);
            const double relax_seconds = now_seconds() - t1;
            v = 0.0;
            for (int64_t c = 0; c < cells; ++c) v += h[c];
            const double relax_top = top_of(h, cells);
            printf("%s,bounded-exchange,%g,%.4f,%lld,%.4f,%.3f,%.1e,1\n", sc->name, tolerances[t], relax_seconds,
                   (long long)sweeps, relax_top, 100.0 * (relax_top - sc->exact_top) / sc->exact_top, fabs(v - v0) / v0);
            for (int stages = 10; stages <= 40; stages *= 2) {
                memcpy(h, h0, sizeof(double) * (size_t)cells);
                const double t2 = now_seconds();
                int at_rest;
                const int64_t evaluations = rkc_to_rest(h, n, sc->dx, sc->theta, tolerances[t], stages, &at_rest);
                const double rkc_seconds = now_seconds() - t2;
                v = 0.0;
                for (int64_t c = 0; c < cells; ++c) v += h[c];
                const double rkc_top = top_of(h, cells);
                printf("%s,rkc-%d,%g,%.4f,%lld,%.4f,%.3f,%.1e,%d\n", sc->name, stages, tolerances[t], rkc_seconds,
                       (long long)evaluations, rkc_top, 100.0 * (rkc_top - sc->exact_top) / sc->exact_top,
                       fabs(v - v0) / v0, at_rest);
            }
            fflush(stdout);
        }
        free(h0);
        free(h);
    }
    return 0;
}
