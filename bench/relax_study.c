/* The study of larger steps (dpsm-bench steps): what reaches rest with a given
 * error in the least time. Compares, on the cone scene and the column
 * collapse (and, for the methods with momentum, twelve cones that meet),
 * dpsm's explicit sub-steps at the stability limit (the default, time
 * accurate) at several rest tolerances with
 *  - the paper's bounded exchange taken to its limit (dt -> infinity: every
 *    face moves its share of the sand that brings it to the angle of repose,
 *    each sweep, a relaxation without a time scale), and
 *  - Runge-Kutta-Chebyshev super-time-stepping (10, 20, 40 stages), whose
 *    steps are about 0.33 s^2 explicit sub-steps long,
 *  - explicit sub-steps with momentum (Nesterov's, restarted when a step
 *    works against the rates, its factor capped at 0.9 and 0.95; or uncapped
 *    and also restarted when 20 % or 30 % of the momentum is coasting, in
 *    cells no face acts on),
 *  - Runge-Kutta-Chebyshev steps whose stages ramp up from 2 to 20, which
 *    follow the flow's path, until the largest excess slope falls below 0.02
 *    (or until the flowing region stops growing), then momentum for the
 *    tail, restarted also when 90 % of a step's motion coasts,
 *  - the limit of backward Euler as dt -> infinity, the L2 projection of the
 *    surface onto the surfaces whose every face is no steeper than the angle
 *    of repose, solved by FISTA on its dual (a first-order solver),
 *  - the same projection by Newton's method on a penalty (tau/2) sum
 *    (|g_f| - tan(theta))_+^2, tau raised a thousandfold per stage from 1,
 *    each Newton step solved by conjugate gradients without a
 *    preconditioner, with a backtracking line search,
 *  - nested iteration from coarser grids (1 and 2 levels): rest on a grid of
 *    cells twice as wide first, its change added to the finer surface, then
 *    the explicit sub-steps there ("sweeps" in sub-steps of the finest grid),
 * all written here as plain loops on the isotropic scheme. "sweeps" counts
 * rate evaluations (explicit: sub-steps; projection: applications of the
 * face gradients and their transpose). Each row also gives the deposit's L1
 * difference from the explicit scheme's: the deposit depends on the path. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "reference.h"
#include "relax_study.h"

static const double kPi = 3.14159265358979323846;

typedef struct {
    const char *name;
    int64_t n;
    double dx, theta, exact_top;
    void (*fill)(double *h, int64_t n, double dx);
    double (*exact)(double r, double theta); /* the exact deposit at distance r from the centre; NULL: none known */
    int momentum_only; /* run only the explicit scheme and the methods with momentum (whose path differs) */
} scene;

void fill_cone(double *h, int64_t n, double dx) {
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

/* Twelve overlapping cones of different heights and slopes, at places drawn
 * by a fixed generator: piles that meet, so that the deposit depends on the
 * path more than a lone cone's does. */
static void fill_cones(double *h, int64_t n, double dx) {
    (void)dx;
    unsigned seed = 7u;
    memset(h, 0, sizeof(double) * (size_t)(n * n));
    for (int p = 0; p < 12; ++p) {
        double v[4];
        for (int k = 0; k < 4; ++k) {
            seed = seed * 1664525u + 1013904223u;
            v[k] = (double)(seed >> 8) / (double)(1u << 24);
        }
        const double cx = 15.0 + 70.0 * v[0], cy = 15.0 + 70.0 * v[1], top = 5.0 + 20.0 * v[2], slope = 1.0 + v[3];
        for (int64_t j = 0; j < n; ++j)
            for (int64_t i = 0; i < n; ++i)
                h[i + n * j] = fmax(h[i + n * j], top - slope * hypot((double)i - cx, (double)j - cy));
    }
}

double top_of(const double *h, int64_t cells) {
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

void rkc_setup(rkc_coefficients *k, int s) {
    double dT[64], ddT[64];
    k->s = s;
    k->w0 = 1.0 + (2.0 / 13.0) / ((double)s * s);
    k->T[0] = 1; k->T[1] = k->w0; dT[0] = 0; dT[1] = 1; ddT[0] = 0; ddT[1] = 0;
    for (int j = 2; j <= s; ++j) {
        k->T[j] = 2 * k->w0 * k->T[j - 1] - k->T[j - 2];
        dT[j] = 2 * k->T[j - 1] + 2 * k->w0 * dT[j - 1] - dT[j - 2];
        ddT[j] = 4 * dT[j - 1] + 2 * k->w0 * ddT[j - 1] - ddT[j - 2];
    }
    k->w1 = dT[s] / ddT[s];
    for (int j = 2; j <= s; ++j) k->b[j] = ddT[j] / (dT[j] * dT[j]);
    k->b[0] = k->b[1] = k->b[2];
    k->beta = (k->w0 + 1.0) * ddT[s] / dT[s];
}

/* Scratch of an RKC step on `cells` cells. */
typedef struct {
    double *y0, *f0, *yjm1, *yjm2, *fj, *yj;
} rkc_work;

static void rkc_alloc(rkc_work *w, int64_t cells) {
    double **arrays[] = {&w->y0, &w->f0, &w->yjm1, &w->yjm2, &w->fj, &w->yj};
    for (size_t a = 0; a < sizeof arrays / sizeof *arrays; ++a) *arrays[a] = xcalloc((size_t)cells, sizeof(double));
}

static void rkc_free(rkc_work *w) {
    free(w->y0); free(w->f0); free(w->yjm1); free(w->yjm2); free(w->fj); free(w->yj);
}

/* One RKC step of length tau from the heights in r, whose rates f0 the caller
 * has just evaluated into w->f0; leaves the result in r. Returns the rate
 * evaluations it made (s - 1). */
static int64_t rkc_step(reference_grid *r, const rkc_coefficients *k, double tau, rkc_work *w) {
    const int64_t n = r->nx, cells = r->nx * r->ny;
    for (int64_t c = 0; c < cells; ++c) {
        w->y0[c] = reference_height(r, c % n, c / n);
        w->yjm2[c] = w->y0[c];
        w->yjm1[c] = w->y0[c] + k->b[1] * k->w1 * tau * w->f0[c];
    }
    for (int j = 2; j <= k->s; ++j) {
        for (int64_t c = 0; c < cells; ++c) reference_set_height(r, c % n, c / n, w->yjm1[c]);
        reference_rates(r, w->fj);
        const double mu = 2 * k->b[j] * k->w0 / k->b[j - 1], nu = -k->b[j] / k->b[j - 2];
        const double mut = 2 * k->b[j] * k->w1 / k->b[j - 1], gamt = -(1.0 - k->b[j - 1] * k->T[j - 1]) * mut;
        for (int64_t c = 0; c < cells; ++c)
            w->yj[c] = (1 - mu - nu) * w->y0[c] + mu * w->yjm1[c] + nu * w->yjm2[c] + mut * tau * w->fj[c] +
                       gamt * tau * w->f0[c];
        double *t = w->yjm2; w->yjm2 = w->yjm1; w->yjm1 = w->yj; w->yj = t;
    }
    for (int64_t c = 0; c < cells; ++c) reference_set_height(r, c % n, c / n, w->yjm1[c]);
    return k->s - 1;
}

/* Runge-Kutta-Chebyshev steps of s stages, each 0.95 of its stable length
 * (about s^2 * 0.65 / 2 explicit sub-steps), on the reference loop's rates,
 * to rest. Returns the rate evaluations. */
static int64_t rkc_to_rest(double *h, int64_t n, double dx, double theta, double tolerance, int s, int *at_rest) {
    reference_grid r;
    if (!reference_init(&r, n, n, dx, dx, 1.0, theta, tolerance, h)) exit(1);
    rkc_coefficients k;
    rkc_setup(&k, s);
    rkc_work w;
    rkc_alloc(&w, n * n);
    const double lambda_max = 8.0 * cos(theta) / (dx * dx); /* nu = 1, dx = dy */
    const double tau = 0.95 * k.beta / lambda_max;
    int64_t evaluations = 0;
    *at_rest = 0;
    /* At most as many rate evaluations as the explicit scheme's sub-steps at
     * tolerance 1e-6 on the cone, twice over: beyond that it has not paid. */
    while (evaluations < 14000) {
        const double excess = reference_rates(&r, w.f0);
        ++evaluations;
        if (excess == 0.0) {
            *at_rest = 1;
            break;
        }
        evaluations += rkc_step(&r, &k, tau, &w);
    }
    for (int64_t c = 0; c < n * n; ++c) h[c] = reference_height(&r, c % n, c / n);
    reference_free(&r);
    rkc_free(&w);
    return evaluations;
}

/* The flow's own path first, in few evaluations, then momentum for the last
 * small motions: Runge-Kutta-Chebyshev steps whose stages ramp up, s_k =
 * min(20, 2 + k), each 0.9 of its stable length, until the largest excess
 * slope of the faces that carry sand is below `switch_excess` (or, when
 * switch_excess is 0, until a step wakes no face that never carried sand
 * before: the flowing region has stopped growing). Then explicit sub-steps
 * with momentum (Nesterov's, beta = k / (k + 3), uncapped), restarted when a
 * step works against the rates or when more than 90 % of its motion lies in
 * cells on which no face acts (sand coasting past the angle of repose). At
 * rest when the rates vanish at a point reached without momentum. Momentum
 * changes the path, and the deposit depends on the path; it is given only the
 * tail, where little sand is left to move. Returns the rate evaluations. */
static int64_t rkc_then_momentum(double *h, int64_t n, double dx, double theta, double tolerance, double switch_excess,
                                 int *at_rest) {
    reference_grid r;
    if (!reference_init(&r, n, n, dx, dx, 1.0, theta, tolerance, h)) exit(1);
    const int64_t cells = n * n;
    rkc_work w;
    rkc_alloc(&w, cells);
    const double dt = dx * dx / (4.0 * cos(theta)); /* nu = 1, dx = dy: the explicit limit, 2 / lambda_max */
    unsigned char *carried = xcalloc((size_t)cells, 1); /* cells with a rate ever: where sand has flowed */
    int64_t evaluations = 0;
    *at_rest = 0;
    for (int step = 0; evaluations < 14000; ++step) {
        const double excess = reference_rates(&r, w.f0);
        ++evaluations;
        if (excess == 0.0) {
            *at_rest = 1;
            break;
        }
        int64_t fresh = 0;
        for (int64_t c = 0; c < cells; ++c)
            if (w.f0[c] != 0.0 && !carried[c]) {
                carried[c] = 1;
                ++fresh;
            }
        if (switch_excess > 0.0 ? excess < switch_excess : step >= 2 && fresh == 0) {
            --evaluations; /* the momentum phase's first evaluation is this one */
            break;
        }
        rkc_coefficients k;
        rkc_setup(&k, step + 2 < 20 ? step + 2 : 20);
        evaluations += rkc_step(&r, &k, 0.9 * k.beta * dt / 2.0, &w);
    }
    double *x = w.y0, *x_prev = w.yjm1, *y = w.yjm2, *rate = w.fj;
    for (int64_t c = 0; c < cells; ++c) x[c] = x_prev[c] = reference_height(&r, c % n, c / n);
    for (int64_t k = 0; !*at_rest && evaluations < 14000;) {
        const double beta = (double)k / (double)(k + 3);
        for (int64_t c = 0; c < cells; ++c) {
            y[c] = x[c] + beta * (x[c] - x_prev[c]);
            reference_set_height(&r, c % n, c / n, y[c]);
        }
        const double excess = reference_rates(&r, rate);
        ++evaluations;
        if (excess == 0.0) {
            memcpy(x, y, sizeof(double) * (size_t)cells);
            memcpy(x_prev, y, sizeof(double) * (size_t)cells);
            *at_rest = k == 0;
            k = 0;
            continue;
        }
        double along = 0.0, motion = 0.0, coasting = 0.0;
        for (int64_t c = 0; c < cells; ++c) {
            const double next = y[c] + dt * rate[c], moved = fabs(next - x[c]);
            along += rate[c] * (next - x[c]);
            motion += moved;
            if (rate[c] == 0.0) coasting += moved;
            x_prev[c] = x[c];
            x[c] = next;
        }
        if (along < 0.0 || coasting > 0.9 * motion) {
            memcpy(x_prev, x, sizeof(double) * (size_t)cells);
            k = 0;
        } else {
            ++k;
        }
    }
    memcpy(h, x, sizeof(double) * (size_t)cells);
    reference_free(&r);
    rkc_free(&w);
    free(carried);
    return evaluations;
}

/* Explicit sub-steps at the stability limit with momentum: y = x + beta (x -
 * x_prev), x_next = y + dt rate(y), beta = k / (k + 3) capped at beta_max,
 * k reset to 0 when the step works against the rates (O'Donoghue and Candes'
 * gradient restart) or when y is at rest. With coasting > 0, also reset when
 * more than that share of the momentum |x - x_prev| lies in cells on which
 * no face acts at y: sand carried on by momentum alone, past the angle of
 * repose. At rest when the rates vanish at a point reached without momentum.
 * Returns the rate evaluations. */
static int64_t momentum_to_rest(double *h, int64_t n, double dx, double theta, double tolerance, double beta_max,
                                double coasting, int *at_rest) {
    reference_grid r;
    if (!reference_init(&r, n, n, dx, dx, 1.0, theta, tolerance, h)) exit(1);
    const int64_t cells = n * n;
    double *x = xcalloc((size_t)cells, sizeof(double)), *x_prev = xcalloc((size_t)cells, sizeof(double));
    double *y = xcalloc((size_t)cells, sizeof(double)), *rate = xcalloc((size_t)cells, sizeof(double));
    memcpy(x, h, sizeof(double) * (size_t)cells);
    memcpy(x_prev, h, sizeof(double) * (size_t)cells);
    const double dt = dx * dx / (4.0 * cos(theta)); /* nu = 1, dx = dy: the explicit limit */
    int64_t evaluations = 0, k = 0;
    *at_rest = 0;
    while (evaluations < 14000) {
        const double beta = fmin(beta_max, (double)k / (double)(k + 3));
        for (int64_t c = 0; c < cells; ++c) {
            y[c] = x[c] + beta * (x[c] - x_prev[c]);
            reference_set_height(&r, c % n, c / n, y[c]);
        }
        const double excess = reference_rates(&r, rate);
        ++evaluations;
        if (excess == 0.0) {
            memcpy(x, y, sizeof(double) * (size_t)cells);
            if (k == 0) {
                *at_rest = 1;
                break;
            }
            memcpy(x_prev, y, sizeof(double) * (size_t)cells);
            k = 0;
            continue;
        }
        double along = 0.0, momentum = 0.0, coasting_momentum = 0.0;
        for (int64_t c = 0; c < cells; ++c) {
            const double m = fabs(x[c] - x_prev[c]);
            momentum += m;
            if (rate[c] == 0.0) coasting_momentum += m;
        }
        for (int64_t c = 0; c < cells; ++c) {
            const double next = y[c] + dt * rate[c];
            along += rate[c] * (next - x[c]);
            x_prev[c] = x[c];
            x[c] = next;
        }
        if (along < 0.0 || (coasting > 0.0 && coasting_momentum > coasting * momentum)) {
            memcpy(x_prev, x, sizeof(double) * (size_t)cells);
            k = 0;
        } else {
            ++k;
        }
    }
    memcpy(h, x, sizeof(double) * (size_t)cells);
    reference_free(&r);
    free(x);
    free(x_prev);
    free(y);
    free(rate);
    return evaluations;
}

/* The face gradients of the isotropic scheme as the reference loop takes
 * them (a frame of zeros beyond the open sides, no transverse slope there):
 * face f of direction d joins cell a = (i, j) to b = its neighbour in +x (d = 0)
 * or +y (d = 1), for i (d = 0) or j (d = 1) from -1 to n - 1; its normal part
 * is (h_b - h_a) / dx, its transverse part the mean of a's and b's central
 * differences across it. */
typedef struct {
    int64_t n;
    double dx;
} face_grid;

static int64_t face_index(const face_grid *f, int d, int64_t i, int64_t j) {
    return d == 0 ? (i + 1) + (f->n + 1) * j : (j + 1) + (f->n + 1) * i;
}

static double cell_at(const face_grid *f, const double *h, int64_t i, int64_t j) {
    return (i < 0 || j < 0 || i >= f->n || j >= f->n) ? 0.0 : h[i + f->n * j];
}

static int inside(const face_grid *f, int64_t i, int64_t j) { return i >= 0 && j >= 0 && i < f->n && j < f->n; }

/* g = G h: normal[d][face], transverse[d][face]. */
static void face_gradients(const face_grid *f, const double *h, double *normal[2], double *transverse[2]) {
    const int64_t n = f->n;
    const double inv = 1.0 / f->dx, half = 0.5 / f->dx;
    for (int d = 0; d < 2; ++d)
        for (int64_t j = (d == 0 ? 0 : -1); j < n; ++j)
            for (int64_t i = (d == 0 ? -1 : 0); i < n; ++i) {
                const int64_t i2 = i + (d == 0), j2 = j + (d == 1), e = face_index(f, d, i, j);
                normal[d][e] = (cell_at(f, h, i2, j2) - cell_at(f, h, i, j)) * inv;
                double t = 0.0;
                for (int side = 0; side < 2; ++side) {
                    const int64_t a = side ? i2 : i, b = side ? j2 : j;
                    if (!inside(f, a, b)) continue;
                    t += d == 0 ? cell_at(f, h, a, b + 1) - cell_at(f, h, a, b - 1)
                                : cell_at(f, h, a + 1, b) - cell_at(f, h, a - 1, b);
                }
                transverse[d][e] = 0.5 * half * t;
            }
}

static void add_to(const face_grid *f, double *out, int64_t i, int64_t j, double v) {
    if (inside(f, i, j)) out[i + f->n * j] += v;
}

/* out = G^T p, the transpose of face_gradients. */
static void face_gradients_transposed(const face_grid *f, double *normal[2], double *transverse[2], double *out) {
    const int64_t n = f->n;
    const double inv = 1.0 / f->dx, half = 0.5 / f->dx;
    memset(out, 0, sizeof(double) * (size_t)(n * n));
    for (int d = 0; d < 2; ++d)
        for (int64_t j = (d == 0 ? 0 : -1); j < n; ++j)
            for (int64_t i = (d == 0 ? -1 : 0); i < n; ++i) {
                const int64_t i2 = i + (d == 0), j2 = j + (d == 1), e = face_index(f, d, i, j);
                add_to(f, out, i2, j2, normal[d][e] * inv);
                add_to(f, out, i, j, -normal[d][e] * inv);
                const double t = 0.5 * half * transverse[d][e];
                for (int side = 0; side < 2; ++side) {
                    const int64_t a = side ? i2 : i, b = side ? j2 : j;
                    if (!inside(f, a, b)) continue;
                    if (d == 0) {
                        add_to(f, out, a, b + 1, t);
                        add_to(f, out, a, b - 1, -t);
                    } else {
                        add_to(f, out, a + 1, b, t);
                        add_to(f, out, a - 1, b, -t);
                    }
                }
            }
}

/* The L2 projection of h onto {every face gradient no longer than tan(theta)}:
 * h = h0 - G^T p with p minimising 1/2 |h0 - G^T p|^2 + tan(theta) sum |p_f|,
 * by FISTA (step 1 / |G|^2, |G|^2 <= 8 / dx^2). Stops when no face exceeds
 * the rest threshold or after max_iterations. Returns the iterations; the
 * projection keeps the volume (the set does not change when a constant is
 * added; here the frame's zeros break that only beyond the open sides). */
static int64_t project_to_rest(double *h, int64_t n, double dx, double theta, double tolerance, int64_t max_iterations,
                               int *at_rest) {
    const face_grid f = {n, dx};
    const int64_t cells = n * n, faces = (n + 1) * n;
    const double alpha = tan(theta), threshold = alpha * (1.0 + tolerance), step = dx * dx / 8.5;
    double *h0 = xcalloc((size_t)cells, sizeof(double));
    memcpy(h0, h, sizeof(double) * (size_t)cells);
    double *p[2][2], *p_prev[2][2], *q[2][2], *g[2][2];
    for (int d = 0; d < 2; ++d)
        for (int c = 0; c < 2; ++c) {
            p[d][c] = xcalloc((size_t)faces, sizeof(double));
            p_prev[d][c] = xcalloc((size_t)faces, sizeof(double));
            q[d][c] = xcalloc((size_t)faces, sizeof(double));
            g[d][c] = xcalloc((size_t)faces, sizeof(double));
        }
    double t_k = 1.0;
    int64_t it = 0;
    *at_rest = 0;
    for (; it < max_iterations; ++it) {
        /* Every 50 iterations: is h = h0 - G^T p at rest? */
        if (it % 50 == 0) {
            double *pn[2] = {p[0][0], p[1][0]}, *pt[2] = {p[0][1], p[1][1]};
            double *gn[2] = {g[0][0], g[1][0]}, *gt[2] = {g[0][1], g[1][1]};
            face_gradients_transposed(&f, pn, pt, h);
            for (int64_t c = 0; c < cells; ++c) h[c] = h0[c] - h[c];
            face_gradients(&f, h, gn, gt);
            double worst = 0.0;
            for (int d = 0; d < 2; ++d)
                for (int64_t e = 0; e < faces; ++e) worst = fmax(worst, hypot(g[d][0][e], g[d][1][e]));
            if (worst <= threshold) {
                *at_rest = 1;
                break;
            }
        }
        double *qn[2] = {q[0][0], q[1][0]}, *qt[2] = {q[0][1], q[1][1]};
        double *gn[2] = {g[0][0], g[1][0]}, *gt[2] = {g[0][1], g[1][1]};
        face_gradients_transposed(&f, qn, qt, h);
        for (int64_t c = 0; c < cells; ++c) h[c] = h0[c] - h[c];
        face_gradients(&f, h, gn, gt);
        const double t_next = 0.5 * (1.0 + sqrt(1.0 + 4.0 * t_k * t_k)), w = (t_k - 1.0) / t_next;
        t_k = t_next;
        for (int d = 0; d < 2; ++d)
            for (int64_t e = 0; e < faces; ++e) {
                const double a = q[d][0][e] + step * g[d][0][e], b = q[d][1][e] + step * g[d][1][e];
                const double m = hypot(a, b), shrink = m > step * alpha ? 1.0 - step * alpha / m : 0.0;
                p_prev[d][0][e] = p[d][0][e];
                p_prev[d][1][e] = p[d][1][e];
                p[d][0][e] = shrink * a;
                p[d][1][e] = shrink * b;
                q[d][0][e] = p[d][0][e] + w * (p[d][0][e] - p_prev[d][0][e]);
                q[d][1][e] = p[d][1][e] + w * (p[d][1][e] - p_prev[d][1][e]);
            }
    }
    double *pn[2] = {p[0][0], p[1][0]}, *pt[2] = {p[0][1], p[1][1]};
    face_gradients_transposed(&f, pn, pt, h);
    for (int64_t c = 0; c < cells; ++c) h[c] = h0[c] - h[c];
    for (int d = 0; d < 2; ++d)
        for (int c = 0; c < 2; ++c) {
            free(p[d][c]);
            free(p_prev[d][c]);
            free(q[d][c]);
            free(g[d][c]);
        }
    free(h0);
    return it;
}

/* Newton's method for the projection, on the penalty
 * F(h) = 1/2 |h - h0|^2 + tau/2 sum_f (|g_f| - tan(theta))_+^2, whose
 * minimiser tends to the projection as tau grows: stages of tau = 1, 1e3,
 * 1e6, ... until no face exceeds the rest threshold; in each, Newton steps
 * (conjugate gradients on the Hessian I + tau G^T D G to a relative residual
 * of 0.1, a backtracking line search) until the gradient has fallen by 1e3.
 * Returns the Hessian and gradient evaluations (each one application of G and
 * one of G^T, like a sweep). */
typedef struct {
    face_grid f;
    int64_t cells, faces;
    double alpha, tau;
    const double *h0;
    double *g[2][2], *p[2][2];          /* face gradients, face work */
    double *unit[2][2], *weight[2];     /* per active face: g / |g|, (|g| - alpha) / |g| */
    uint8_t *active[2];
} penalty;

static void penalty_gradients(penalty *w, const double *h) {
    double *gn[2] = {w->g[0][0], w->g[1][0]}, *gt[2] = {w->g[0][1], w->g[1][1]};
    face_gradients(&w->f, h, gn, gt);
}

static double penalty_value(penalty *w, const double *h) {
    penalty_gradients(w, h);
    double value = 0.0;
    for (int64_t c = 0; c < w->cells; ++c) value += 0.5 * (h[c] - w->h0[c]) * (h[c] - w->h0[c]);
    for (int d = 0; d < 2; ++d)
        for (int64_t e = 0; e < w->faces; ++e) {
            const double m = hypot(w->g[d][0][e], w->g[d][1][e]);
            if (m > w->alpha) value += 0.5 * w->tau * (m - w->alpha) * (m - w->alpha);
        }
    return value;
}

/* out = grad F(h); remembers the active faces and their D for the Hessian. */
static void penalty_gradient(penalty *w, const double *h, double *out) {
    penalty_gradients(w, h);
    for (int d = 0; d < 2; ++d)
        for (int64_t e = 0; e < w->faces; ++e) {
            const double gn = w->g[d][0][e], gt = w->g[d][1][e], m = hypot(gn, gt);
            w->active[d][e] = m > w->alpha;
            if (w->active[d][e]) {
                const double k = w->tau * (m - w->alpha) / m;
                w->p[d][0][e] = k * gn;
                w->p[d][1][e] = k * gt;
                w->unit[d][0][e] = gn / m;
                w->unit[d][1][e] = gt / m;
                w->weight[d][e] = (m - w->alpha) / m;
            } else {
                w->p[d][0][e] = w->p[d][1][e] = 0.0;
            }
        }
    double *pn[2] = {w->p[0][0], w->p[1][0]}, *pt[2] = {w->p[0][1], w->p[1][1]};
    face_gradients_transposed(&w->f, pn, pt, out);
    for (int64_t c = 0; c < w->cells; ++c) out[c] += h[c] - w->h0[c];
}

/* out = (I + tau G^T D G) v, D = u u^T + weight (I - u u^T) on active faces. */
static void penalty_hessian(penalty *w, const double *v, double *out) {
    penalty_gradients(w, v);
    for (int d = 0; d < 2; ++d)
        for (int64_t e = 0; e < w->faces; ++e) {
            if (!w->active[d][e]) {
                w->p[d][0][e] = w->p[d][1][e] = 0.0;
                continue;
            }
            const double a = w->unit[d][0][e], b = w->unit[d][1][e], gn = w->g[d][0][e], gt = w->g[d][1][e];
            const double along = a * gn + b * gt, k = w->weight[d][e];
            w->p[d][0][e] = w->tau * (along * a + k * (gn - along * a));
            w->p[d][1][e] = w->tau * (along * b + k * (gt - along * b));
        }
    double *pn[2] = {w->p[0][0], w->p[1][0]}, *pt[2] = {w->p[0][1], w->p[1][1]};
    face_gradients_transposed(&w->f, pn, pt, out);
    for (int64_t c = 0; c < w->cells; ++c) out[c] += v[c];
}

static int64_t newton_to_rest(double *h, int64_t n, double dx, double theta, double tolerance, int *at_rest) {
    penalty w;
    w.f.n = n;
    w.f.dx = dx;
    w.cells = n * n;
    w.faces = (n + 1) * n;
    w.alpha = tan(theta);
    const size_t cells = (size_t)w.cells, faces = (size_t)w.faces;
    double *h0 = xcalloc(cells, sizeof(double));
    memcpy(h0, h, sizeof(double) * cells);
    w.h0 = h0;
    for (int d = 0; d < 2; ++d) {
        for (int c = 0; c < 2; ++c) {
            w.g[d][c] = xcalloc(faces, sizeof(double));
            w.p[d][c] = xcalloc(faces, sizeof(double));
            w.unit[d][c] = xcalloc(faces, sizeof(double));
        }
        w.weight[d] = xcalloc(faces, sizeof(double));
        w.active[d] = xcalloc(faces, 1);
    }
    double *grad = xcalloc(cells, sizeof(double)), *step = xcalloc(cells, sizeof(double));
    double *res = xcalloc(cells, sizeof(double)), *dir = xcalloc(cells, sizeof(double));
    double *hd = xcalloc(cells, sizeof(double)), *trial = xcalloc(cells, sizeof(double));
    const double threshold = w.alpha * (1.0 + tolerance);
    int64_t evaluations = 0;
    *at_rest = 0;
    for (w.tau = 1.0; w.tau < 1e16 && !*at_rest; w.tau *= 1e3) {
        double first = -1.0;
        for (int k = 0; k < 30; ++k) {
            penalty_gradient(&w, h, grad);
            ++evaluations;
            double norm = 0.0;
            for (size_t c = 0; c < cells; ++c) norm += grad[c] * grad[c];
            norm = sqrt(norm);
            if (first < 0.0) first = norm;
            if (norm <= 1e-3 * first) break;
            /* Conjugate gradients on H step = -grad, to a relative residual of 0.1. */
            double rr = 0.0;
            for (size_t c = 0; c < cells; ++c) {
                step[c] = 0.0;
                res[c] = dir[c] = -grad[c];
                rr += res[c] * res[c];
            }
            const double rr0 = rr;
            for (int it = 0; it < 5000 && rr > 1e-2 * rr0; ++it) {
                penalty_hessian(&w, dir, hd);
                ++evaluations;
                double curvature = 0.0;
                for (size_t c = 0; c < cells; ++c) curvature += dir[c] * hd[c];
                const double a = rr / curvature;
                double next = 0.0;
                for (size_t c = 0; c < cells; ++c) {
                    step[c] += a * dir[c];
                    res[c] -= a * hd[c];
                    next += res[c] * res[c];
                }
                for (size_t c = 0; c < cells; ++c) dir[c] = res[c] + (next / rr) * dir[c];
                rr = next;
            }
            /* Backtracking (Armijo) on F; F was left at the Hessian's gradients, so evaluate afresh. */
            const double f0 = penalty_value(&w, h);
            double slope = 0.0, t = 1.0;
            for (size_t c = 0; c < cells; ++c) slope += grad[c] * step[c];
            for (int ls = 0; ls < 40; ++ls, t *= 0.5) {
                for (size_t c = 0; c < cells; ++c) trial[c] = h[c] + t * step[c];
                ++evaluations;
                if (penalty_value(&w, trial) <= f0 + 1e-4 * t * slope) break;
            }
            memcpy(h, trial, sizeof(double) * cells);
        }
        penalty_gradients(&w, h);
        double worst = 0.0;
        for (int d = 0; d < 2; ++d)
            for (int64_t e = 0; e < w.faces; ++e) worst = fmax(worst, hypot(w.g[d][0][e], w.g[d][1][e]));
        *at_rest = worst <= threshold;
    }
    for (int d = 0; d < 2; ++d) {
        for (int c = 0; c < 2; ++c) {
            free(w.g[d][c]);
            free(w.p[d][c]);
            free(w.unit[d][c]);
        }
        free(w.weight[d]);
        free(w.active[d]);
    }
    free(h0);
    free(grad);
    free(step);
    free(res);
    free(dir);
    free(hd);
    free(trial);
    return evaluations;
}

/* Explicit sub-steps of the reference loop on h (n x n, open sides) until
 * rest; adds the work, in cells, to *cell_updates. */
static void explicit_rest(double *h, int64_t n, double dx, double theta, double tolerance, double *cell_updates) {
    reference_grid r;
    if (!reference_init(&r, n, n, dx, dx, 1.0, theta, tolerance, h)) exit(1);
    const double dt = dx * dx / (4.0 * cos(theta));
    int64_t substeps = 1;
    while (reference_substep(&r, dt) != 0.0 && substeps < 1000000) ++substeps;
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) h[i + n * j] = reference_height(&r, i, j);
    reference_free(&r);
    *cell_updates += (double)substeps * (double)(n * n);
}

/* Nested iteration: the surface averaged onto cells twice as wide (a coarse
 * cell holds the mass of its four), brought to rest there (recursively, from
 * `levels` coarser grids), the change added back to each of its four fine
 * cells (which keeps the mass), then explicit sub-steps to rest here. */
static void cascade_to_rest(double *h, int64_t n, double dx, double theta, double tolerance, int levels,
                            double *cell_updates) {
    if (levels > 0 && n >= 16) {
        const int64_t nc = (n + 1) / 2;
        double *coarse = xcalloc((size_t)(nc * nc), sizeof(double)), *start = xcalloc((size_t)(nc * nc), sizeof(double));
        for (int64_t j = 0; j < n; ++j)
            for (int64_t i = 0; i < n; ++i) coarse[i / 2 + nc * (j / 2)] += 0.25 * h[i + n * j];
        memcpy(start, coarse, sizeof(double) * (size_t)(nc * nc));
        cascade_to_rest(coarse, nc, 2.0 * dx, theta, tolerance, levels - 1, cell_updates);
        for (int64_t j = 0; j < n; ++j)
            for (int64_t i = 0; i < n; ++i) {
                const int64_t c = i / 2 + nc * (j / 2);
                h[i + n * j] += coarse[c] - start[c];
            }
        free(coarse);
        free(start);
    }
    explicit_rest(h, n, dx, theta, tolerance, cell_updates);
}

/* The exact deposits, at a cell's centre: the cone's (a cone of slope
 * tan(theta) with the volume of the cone 40 high of slope 1.5) and the
 * column's (a truncated cone of height 0.5 whose foot lies at
 * r_f = (a + sqrt(4 alpha^2 - a^2 / 3)) / (2 alpha), a = 0.5, radius 1). */
double exact_cone(double r, double theta) {
    const double alpha = tan(theta), foot = (40.0 / 1.5) * cbrt(1.5 / alpha);
    return fmax(0.0, alpha * (foot - r));
}

static double exact_column(double r, double theta) {
    const double alpha = tan(theta), a = 0.5, foot = (a + sqrt(4.0 * alpha * alpha - a * a / 3.0)) / (2.0 * alpha);
    return fmin(0.5, fmax(0.0, alpha * (foot - r)));
}

/* Prints a row: the top against the exact top, the deposit's L1 difference
 * from the exact deposit over the exact deposit's volume (nan when none is
 * known), and its L1 difference from the explicit scheme's deposit (the flow's
 * own path, same tolerance) over that deposit's volume. */
static void report(const scene *sc, const char *method, double tolerance, double seconds, double sweeps,
                   const double *h, const double *explicit_h, double v0, int at_rest) {
    const int64_t n = sc->n, cells = n * n;
    double v = 0.0, difference = 0.0, exact_volume = 0.0, from_explicit = 0.0, explicit_volume = 0.0;
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) {
            const int64_t c = i + n * j;
            v += h[c];
            from_explicit += fabs(h[c] - explicit_h[c]);
            explicit_volume += explicit_h[c];
            if (!sc->exact) continue;
            const double want = sc->exact(hypot((double)(i - n / 2), (double)(j - n / 2)) * sc->dx, sc->theta);
            difference += fabs(h[c] - want);
            exact_volume += want;
        }
    const double top = top_of(h, cells);
    printf("%s,%s,%g,%.4f,%.0f,%.4f,%.3f,%.2f,%.3f,%.1e,%d\n", sc->name, method, tolerance, seconds, sweeps, top,
           100.0 * (top - sc->exact_top) / sc->exact_top, sc->exact ? 100.0 * difference / exact_volume : NAN,
           100.0 * from_explicit / explicit_volume, fabs(v - v0) / v0, at_rest);
    fflush(stdout);
}

int cmd_steps(int argc, char **argv) {
    (void)argc;
    (void)argv;
    const scene scenes[] = {
        {"cone", 101, 1.0, 33.0 * kPi / 180.0, 22.89, fill_cone, exact_cone, 0},
        /* column a = 0.5 at 30 deg: a truncated cone, top stays at h0 = 0.5; its
         * runout is the quantity that moves, the top is checked for damage. */
        {"column", 128, 4.0 / 128, 30.0 * kPi / 180.0, 0.5, fill_column, exact_column, 0},
        /* No exact deposit: the methods with momentum against the flow's own. */
        {"cones", 101, 1.0, 33.0 * kPi / 180.0, 0.0, fill_cones, NULL, 1},
    };
    const double tolerances[] = {1e-6, 1e-3, 1e-2};
    printf("scene,method,tolerance,seconds,sweeps,top,top_error_percent,deposit_error_percent,"
           "difference_from_explicit_percent,volume_change,at_rest\n");
    for (size_t s = 0; s < sizeof scenes / sizeof *scenes; ++s) {
        scene sc = scenes[s];
        const int64_t n = sc.n, cells = n * n;
        double *h0 = xcalloc((size_t)cells, sizeof(double)), *h = xcalloc((size_t)cells, sizeof(double));
        double *explicit_h = xcalloc((size_t)cells, sizeof(double));
        sc.fill(h0, n, sc.dx);
        if (sc.exact_top == 0.0) sc.exact_top = top_of(h0, cells); /* no exact top: against the initial one */
        double v0 = 0.0;
        for (int64_t c = 0; c < cells; ++c) v0 += h0[c];
        for (size_t t = 0; t < sizeof tolerances / sizeof *tolerances; ++t) {
            const double tol = tolerances[t];
            dpsm_grid *g = NULL;
            CHECK(NULL, dpsm_create_2d(n, n, sc.dx, sc.dx, &g));
            CHECK(g, dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE));
            CHECK(g, dpsm_set_repose_angle(g, sc.theta));
            CHECK(g, dpsm_set_rest_tolerance(g, tol));
            for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side) CHECK(g, dpsm_set_boundary(g, side, DPSM_OPEN));
            CHECK(g, dpsm_set_heights(g, h0));
            double t0 = now_seconds();
            CHECK(g, dpsm_step(g, 1e6));
            double seconds = now_seconds() - t0, substeps, rest;
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &substeps));
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_AT_REST, &rest));
            CHECK(g, dpsm_get_heights(g, explicit_h));
            dpsm_destroy(g);
            report(&sc, "explicit", tol, seconds, substeps, explicit_h, explicit_h, v0, rest == 1.0);

            char method[40];
            int at_rest;
            if (!sc.momentum_only) {
                memcpy(h, h0, sizeof(double) * (size_t)cells);
                t0 = now_seconds();
                const int64_t sweeps = relax(h, n, sc.dx, sc.theta, tol);
                report(&sc, "bounded-exchange", tol, now_seconds() - t0, (double)sweeps, h, explicit_h, v0, 1);
                for (int stages = 10; stages <= 40; stages *= 2) {
                    memcpy(h, h0, sizeof(double) * (size_t)cells);
                    t0 = now_seconds();
                    const int64_t evaluations = rkc_to_rest(h, n, sc.dx, sc.theta, tol, stages, &at_rest);
                    snprintf(method, sizeof method, "rkc-%d", stages);
                    report(&sc, method, tol, now_seconds() - t0, (double)evaluations, h, explicit_h, v0, at_rest);
                }
            }
            /* Capped at 0.9 and 0.95; uncapped with the coasting restart at 20 % and 30 %. */
            const double caps[] = {0.9, 0.95, 1.0, 1.0}, coasting[] = {0.0, 0.0, 0.2, 0.3};
            for (size_t m = 0; m < sizeof caps / sizeof *caps; ++m) {
                memcpy(h, h0, sizeof(double) * (size_t)cells);
                t0 = now_seconds();
                const int64_t evaluations =
                    momentum_to_rest(h, n, sc.dx, sc.theta, tol, caps[m], coasting[m], &at_rest);
                if (coasting[m] > 0.0)
                    snprintf(method, sizeof method, "momentum-coasting-%g", coasting[m]);
                else
                    snprintf(method, sizeof method, "momentum-%g", caps[m]);
                report(&sc, method, tol, now_seconds() - t0, (double)evaluations, h, explicit_h, v0, at_rest);
            }
            /* The flow's path by RKC, momentum for the tail: switched at an
             * excess slope of 5 % of tan(theta) (as dpsm's DPSM_RELAX_TO_REST),
             * and when the flowing region stops growing. */
            const double switches[] = {0.05 * tan(sc.theta), 0.0};
            for (size_t m = 0; m < sizeof switches / sizeof *switches; ++m) {
                memcpy(h, h0, sizeof(double) * (size_t)cells);
                t0 = now_seconds();
                const int64_t evaluations = rkc_then_momentum(h, n, sc.dx, sc.theta, tol, switches[m], &at_rest);
                report(&sc, switches[m] > 0.0 ? "rkc-then-momentum" : "rkc-then-momentum-front", tol,
                       now_seconds() - t0, (double)evaluations, h, explicit_h, v0, at_rest);
            }
            if (sc.momentum_only) continue;
            for (int levels = 1; levels <= 2; ++levels) {
                memcpy(h, h0, sizeof(double) * (size_t)cells);
                t0 = now_seconds();
                double updates = 0.0;
                cascade_to_rest(h, n, sc.dx, sc.theta, tol, levels, &updates);
                snprintf(method, sizeof method, "cascade-%d", levels);
                report(&sc, method, tol, now_seconds() - t0, updates / (double)cells, h, explicit_h, v0, 1);
            }
            memcpy(h, h0, sizeof(double) * (size_t)cells);
            t0 = now_seconds();
            const int64_t iterations = project_to_rest(h, n, sc.dx, sc.theta, tol, 5000, &at_rest);
            report(&sc, "projection", tol, now_seconds() - t0, (double)iterations, h, explicit_h, v0, at_rest);
            memcpy(h, h0, sizeof(double) * (size_t)cells);
            t0 = now_seconds();
            const int64_t newton = newton_to_rest(h, n, sc.dx, sc.theta, tol, &at_rest);
            report(&sc, "projection-newton", tol, now_seconds() - t0, (double)newton, h, explicit_h, v0, at_rest);
        }
        free(h0);
        free(h);
        free(explicit_h);
    }
    return 0;
}
