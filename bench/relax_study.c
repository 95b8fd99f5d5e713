/* The study of larger steps (dpsm-bench steps): what reaches rest with a given
 * error in the least time. Compares, on the cone scene and the column
 * collapse, dpsm's explicit sub-steps at the stability limit (the default,
 * time accurate) at several rest tolerances with the paper's bounded exchange
 * taken to its limit (dt -> infinity: every face moves its share of the sand
 * that brings it to the angle of repose, each sweep, a relaxation without a
 * time scale, written here as a plain loop on the isotropic scheme). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"

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
    printf("scene,method,tolerance,seconds,sweeps,top,top_error_percent,volume_change\n");
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
            printf("%s,explicit,%g,%.4f,%.0f,%.4f,%.3f,%.1e\n", sc->name, tolerances[t], seconds, substeps, top,
                   100.0 * (top - sc->exact_top) / sc->exact_top, fabs(v - v0) / v0);
            dpsm_destroy(g);

            memcpy(h, h0, sizeof(double) * (size_t)cells);
            const double t1 = now_seconds();
            const int64_t sweeps = relax(h, n, sc->dx, sc->theta, tolerances[t]);
            const double relax_seconds = now_seconds() - t1;
            v = 0.0;
            for (int64_t c = 0; c < cells; ++c) v += h[c];
            const double relax_top = top_of(h, cells);
            printf("%s,bounded-exchange,%g,%.4f,%lld,%.4f,%.3f,%.1e\n", sc->name, tolerances[t], relax_seconds,
                   (long long)sweeps, relax_top, 100.0 * (relax_top - sc->exact_top) / sc->exact_top, fabs(v - v0) / v0);
            fflush(stdout);
        }
        free(h0);
        free(h);
    }
    return 0;
}
