/* A straightforward vectorised loop for the isotropic scheme, to show what the
 * obvious fast code reaches on this machine next to dpsm (dpsm-bench
 * throughput prints it as vectorised_mcells_per_s). Two passes per sub-step
 * over a row-major grid with a frame of one cell: the fluxes of every x and y
 * face into two arrays (each face once, the dead zone as a select, a square
 * root and a division per face, the loop vectorised by the compiler and
 * threaded with OpenMP), then the update of every cell. The frame cells are
 * walls: only faces between cells of the domain carry sand, so it agrees with
 * the reference loop (open sides) away from the edges, which is checked. */
#include "vectorised.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "bench_util.h"

typedef struct {
    int64_t n, w;
    double tan_theta, threshold, dt;
    double *h, *next, *fx, *fy;
} vgrid;

/* The fluxes of row j (x faces between i and i + 1, y faces between j and j + 1),
 * in the frame's coordinates (cells 1 .. n). */
static inline void row_fluxes(const vgrid *g, int64_t j) {
    const int64_t w = g->w, n = g->n;
    const double *hc = g->h + w * j, *hu = g->h + w * (j + 1), *hd = g->h + w * (j - 1), *huu = g->h + w * (j + 2);
    double *fx = g->fx + w * j, *fy = g->fy + w * j;
    const double s = g->tan_theta, threshold = g->threshold;
    const int y_face = j < n; /* the face to row j + 1 lies in the domain */
#pragma omp simd
    for (int64_t i = 1; i <= n; ++i) {
        const double gn = hc[i + 1] - hc[i], gt = 0.25 * (hu[i] + hu[i + 1] - hd[i] - hd[i + 1]);
        const double g2 = gn * gn + gt * gt, gm = sqrt(g2);
        const double f = gm > threshold ? (gm - s) / (gm * sqrt(1.0 + g2)) : 0.0;
        fx[i] = i < n ? f * gn : 0.0;
        const double un = hu[i] - hc[i], ut = 0.25 * (hc[i + 1] + hu[i + 1] - hc[i - 1] - hu[i - 1]);
        const double u2 = un * un + ut * ut, um = sqrt(u2);
        const double fu = um > threshold ? (um - s) / (um * sqrt(1.0 + u2)) : 0.0;
        fy[i] = y_face ? fu * un : 0.0;
    }
    (void)huu;
}

static inline void row_update(const vgrid *g, int64_t j) {
    const int64_t w = g->w, n = g->n;
    const double *h = g->h + w * j, *fx = g->fx + w * j, *fy = g->fy + w * j, *fyd = g->fy + w * (j - 1);
    double *next = g->next + w * j;
    const double dt = g->dt;
#pragma omp simd
    for (int64_t i = 1; i <= n; ++i) next[i] = h[i] + dt * (fx[i] - fx[i - 1] + fy[i] - fyd[i]);
}

/* The frame's transverse slopes read beyond the domain: its cells copy their
 * neighbours inside, so a frame row or column adds no slope across the edge. */
static void fill_frame(vgrid *g) {
    const int64_t w = g->w, n = g->n;
    memcpy(g->h, g->h + w, sizeof(double) * (size_t)w);
    memcpy(g->h + w * (n + 1), g->h + w * n, sizeof(double) * (size_t)w);
    for (int64_t j = 0; j < w; ++j) {
        g->h[w * j] = g->h[w * j + 1];
        g->h[w * j + n + 1] = g->h[w * j + n];
    }
}

/* The sub-steps, defined twice, once built for AVX-512: OpenMP outlines the
 * parallel regions before the compiler inlines, so a body shared by an inline
 * function would not be built with the target attribute. */
#define DEFINE_SUBSTEPS(name, attributes)                                  \
    attributes static void name(vgrid *g, int substeps, int threads) {     \
        (void)threads;                                                     \
        for (int s = 0; s < substeps; ++s) {                               \
            fill_frame(g);                                                 \
            _Pragma("omp parallel for num_threads(threads) schedule(static)") \
            for (int64_t j = 1; j <= g->n; ++j) row_fluxes(g, j);          \
            _Pragma("omp parallel for num_threads(threads) schedule(static)") \
            for (int64_t j = 1; j <= g->n; ++j) row_update(g, j);          \
            double *t = g->h;                                              \
            g->h = g->next;                                                \
            g->next = t;                                                   \
        }                                                                  \
    }

DEFINE_SUBSTEPS(substeps_generic, )

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
DEFINE_SUBSTEPS(substeps_avx512, __attribute__((target("avx512f,avx512dq,fma"))))
static int has_avx512(void) {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq");
}
#else
static void substeps_avx512(vgrid *g, int substeps, int threads) { substeps_generic(g, substeps, threads); }
static int has_avx512(void) { return 0; }
#endif

double vectorised_mcells_per_s(int64_t n, const double *h, double theta, double tolerance, double dt, int threads,
                               int substeps, const reference_grid *check, int check_substeps, double *difference) {
    vgrid g;
    g.n = n;
    g.w = n + 2;
    g.tan_theta = tan(theta);
    g.threshold = g.tan_theta * (1.0 + tolerance);
    g.dt = dt;
    const size_t cells = (size_t)(g.w * g.w);
    g.h = xcalloc(cells, sizeof(double));
    g.next = xcalloc(cells, sizeof(double));
    g.fx = xcalloc(cells, sizeof(double));
    g.fy = xcalloc(cells, sizeof(double));
    void (*run)(vgrid *, int, int) = has_avx512() ? substeps_avx512 : substeps_generic;

    /* First the check: check_substeps sub-steps against the reference, away from the edges. */
    for (int64_t j = 0; j < n; ++j) memcpy(g.h + g.w * (j + 1) + 1, h + n * j, sizeof(double) * (size_t)n);
    run(&g, check_substeps, threads);
    const int64_t margin = 2 * check_substeps + 2;
    double worst = 0.0;
    for (int64_t j = margin; j < n - margin; ++j)
        for (int64_t i = margin; i < n - margin; ++i) {
            const double want = reference_height(check, i, j);
            worst = fmax(worst, fabs(g.h[g.w * (j + 1) + i + 1] - want) / fmax(1.0, fabs(want)));
        }
    *difference = worst;

    for (int64_t j = 0; j < n; ++j) memcpy(g.h + g.w * (j + 1) + 1, h + n * j, sizeof(double) * (size_t)n);
    run(&g, 2, threads); /* warm up: pages, threads */
    const double t0 = now_seconds();
    run(&g, substeps, threads);
    const double seconds = now_seconds() - t0;
    free(g.h);
    free(g.next);
    free(g.fx);
    free(g.fy);
    return (double)n * (double)n * substeps / seconds / 1e6;
}
