/* The study of time-accurate super-time-stepping (dpsm-bench sts): can a
 * method that keeps the flow's time bring the cone to rest in far fewer flux
 * evaluations than forward Euler's 6670 sub-steps, with its deposit, its
 * bounds, its mass and its honest rest intact, and stay within 1e-3 of
 * forward Euler call by call when a host steps it?
 *
 * Everything here is plain loops on the isotropic scheme of the reference
 * sub-step (reference.c): the face fluxes come from reference_flux_x/y, so
 * the flux law, the dead zone and the transverse slopes are the reference's.
 * One "evaluation" is one computation of every face flux of the grid (what
 * one forward Euler sub-step costs), whatever the method does with it.
 *
 * The stages of every Runge-Kutta method here are carried in face space:
 * a stage is Y_j = Y_0 + tau div(Phi_j), Phi_j a combination of face fluxes
 * of earlier stages, so each stage is a combination of mass-conserving
 * updates and what leaves through the open sides is the boundary faces' Phi. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "reference.h"
#include "relax_study.h"

static const double kPi = 3.14159265358979323846;
enum { kMaxStages = 200 };

/* ------------------------------------------------------------------------ */
/* The flow: face fluxes of a state, and the update they make.              */

typedef struct {
    reference_grid r;
    int64_t nx, ny, cells, faces; /* faces: (nx + 1) ny faces across x, then nx (ny + 1) across y */
    double dx, dy, dt_fe;         /* dt_fe: forward Euler's stable sub-step, 1 / (2 nu cos(theta) (1/dx^2 + 1/dy^2)) */
    int64_t evaluations;          /* every call of flow_fluxes */
    int64_t active;               /* faces that carried sand at the last evaluation */
} flow;

static void flow_init(flow *w, int64_t nx, int64_t ny, double dx, double theta, double tolerance, const double *h) {
    if (!reference_init(&w->r, nx, ny, dx, dx, 1.0, theta, tolerance, h)) exit(1);
    w->nx = nx;
    w->ny = ny;
    w->cells = nx * ny;
    w->faces = (nx + 1) * ny + nx * (ny + 1);
    w->dx = w->dy = dx;
    w->dt_fe = 1.0 / (2.0 * cos(theta) * (2.0 / (dx * dx)));
    w->evaluations = 0;
    w->active = 0;
}

static void flow_free(flow *w) { reference_free(&w->r); }

/* The face fluxes phi of the state y, each face once; returns the largest
 * slope excess of the faces that carry sand: 0 exactly when y is at rest. */
static double flow_fluxes(flow *w, const double *y, double *phi) {
    const int64_t nx = w->nx, ny = w->ny, across_x = (nx + 1) * ny;
    for (int64_t j = 0; j < ny; ++j)
        for (int64_t i = 0; i < nx; ++i) reference_set_height(&w->r, i, j, y[i + nx * j]);
    double excess = 0.0;
    int64_t active = 0;
    for (int64_t j = 0; j < ny; ++j)
        for (int64_t i = 0; i <= nx; ++i) {
            const double f = reference_flux_x(&w->r, i, j, &excess);
            phi[i + (nx + 1) * j] = f;
            active += f != 0.0;
        }
    for (int64_t j = 0; j <= ny; ++j)
        for (int64_t i = 0; i < nx; ++i) {
            const double f = reference_flux_y(&w->r, i, j, &excess);
            phi[across_x + i + nx * j] = f;
            active += f != 0.0;
        }
    ++w->evaluations;
    w->active = active;
    return excess;
}

/* out = y0 + tau div(phi): the heights after fluxes phi for a time tau (y0 NULL: 0, the rates times tau). */
static void flow_apply(const flow *w, const double *y0, const double *phi, double tau, double *out) {
    const int64_t nx = w->nx, ny = w->ny, across_x = (nx + 1) * ny;
    const double ax = tau / w->dx, ay = tau / w->dy;
    for (int64_t j = 0; j < ny; ++j)
        for (int64_t i = 0; i < nx; ++i) {
            const double *fx = phi + i + (nx + 1) * j, *fy = phi + across_x + i + nx * j;
            out[i + nx * j] = (y0 ? y0[i + nx * j] : 0.0) + (ax * (fx[0] - fx[1]) + ay * (fy[0] - fy[nx]));
        }
}

/* ------------------------------------------------------------------------ */
/* Super-time-stepping coefficients, all as one three-term recurrence on the
 * accumulated face fluxes: Phi_0 = 0, Phi_1 = mut[1] phi(Y_0),
 * Phi_j = mu[j] Phi_{j-1} + nu[j] Phi_{j-2} + mut[j] phi(Y_{j-1}) + gamt[j] phi(Y_0),
 * Y_j = Y_0 + tau div(Phi_j). (From the usual form Y_j = (1 - mu - nu) Y_0 +
 * mu Y_{j-1} + nu Y_{j-2} + mut tau F(Y_{j-1}) + gamt tau F(Y_0), F = div phi.) */

typedef enum { KIND_FE, KIND_RKC, KIND_RKL1, KIND_RKL2 } sts_kind;

typedef struct {
    int s;
    double stable; /* the longest stable step, in forward Euler sub-steps dt_fe (= 2 / lambda_max) */
    double mu[kMaxStages + 1], nu[kMaxStages + 1], mut[kMaxStages + 1], gamt[kMaxStages + 1];
} sts_coefficients;

/* RKC, second order, damping 2/13 (Sommeijer, Shampine and Verwer 1997), from relax_study.c's rkc_setup. */
static void setup_rkc(sts_coefficients *c, int s) {
    rkc_coefficients k;
    rkc_setup(&k, s);
    c->s = s;
    c->stable = k.beta / 2.0;
    c->mut[1] = k.b[1] * k.w1;
    for (int j = 2; j <= s; ++j) {
        c->mu[j] = 2.0 * k.b[j] * k.w0 / k.b[j - 1];
        c->nu[j] = -k.b[j] / k.b[j - 2];
        c->mut[j] = 2.0 * k.b[j] * k.w1 / k.b[j - 1];
        c->gamt[j] = -(1.0 - k.b[j - 1] * k.T[j - 1]) * c->mut[j];
    }
}

/* RKL1, first order (Meyer, Balsara and Aslam 2012): stable for s (s + 1) / 2 sub-steps. */
static void setup_rkl1(sts_coefficients *c, int s) {
    const double w1 = 2.0 / ((double)s * s + s);
    c->s = s;
    c->stable = 1.0 / w1;
    c->mut[1] = w1;
    for (int j = 2; j <= s; ++j) {
        c->mu[j] = (2.0 * j - 1.0) / j;
        c->nu[j] = (1.0 - j) / j;
        c->mut[j] = c->mu[j] * w1;
        c->gamt[j] = 0.0;
    }
}

/* RKL2, second order (Meyer, Balsara and Aslam 2014): stable for (s^2 + s - 2) / 4 sub-steps, s >= 2. */
static void setup_rkl2(sts_coefficients *c, int s) {
    double b[kMaxStages + 1];
    const double w1 = 4.0 / ((double)s * s + s - 2.0);
    for (int j = 0; j <= kMaxStages; ++j) b[j] = j < 2 ? 1.0 / 3.0 : (j * j + j - 2.0) / (2.0 * j * (j + 1.0));
    c->s = s;
    c->stable = 1.0 / w1;
    c->mut[1] = b[1] * w1;
    for (int j = 2; j <= s; ++j) {
        c->mu[j] = (2.0 * j - 1.0) / j * b[j] / b[j - 1];
        c->nu[j] = -(j - 1.0) / j * b[j] / b[j - 2];
        c->mut[j] = c->mu[j] * w1;
        c->gamt[j] = -(1.0 - b[j - 1]) * c->mut[j];
    }
}

static void setup_sts(sts_coefficients *c, sts_kind kind, int s) {
    if (kind == KIND_RKC) setup_rkc(c, s);
    else if (kind == KIND_RKL1) setup_rkl1(c, s);
    else setup_rkl2(c, s);
}

/* The fewest stages whose stable step spans m sub-steps (the least for the kind: RKC, RKL2 2; RKL1 1). */
static int stages_for(sts_kind kind, double m) {
    sts_coefficients c;
    for (int s = kind == KIND_RKL1 ? 1 : 2; s < (kind == KIND_RKC ? 63 : kMaxStages); ++s) {
        setup_sts(&c, kind, s);
        if (c.stable >= m) return s;
    }
    return kind == KIND_RKC ? 63 : kMaxStages - 1;
}

/* ------------------------------------------------------------------------ */
/* A method, and the state of one run of it.                                */

typedef struct {
    const char *name;
    sts_kind kind;
    int fixed_stages;   /* > 0: every step this many stages at 0.95 of its stable length (the old rkc-N) */
    double cap;         /* the longest step, in forward Euler sub-steps (an accuracy limit); 0: the call's length */
    int fallback;       /* a step that leaves a new extreme is taken again by forward Euler sub-steps */
    double tail_factor; /* > 0: forward Euler for good once the start's excess is below this many rest excesses */
    int stall_steps;    /* > 0: forward Euler for good once the excess has set no new low for this many steps */
    double fe_fraction; /* forward Euler's sub-step as a share of the stable one (0: 1); < 1 only to measure FE's own error */
    double accuracy;    /* > 0: steps chosen so that the trapezoid defect stays below this share of the step's motion */
    double floor_share; /* ... or of this share of the run's motion so far, if more (an absolute tolerance) */
    int no_reject;      /* accept every step (the control only sets the next length) */
} method;

typedef struct {
    flow w;
    double *y, *y0, *phi0, *phi, *acc_a, *acc_b, *stage, *save;
    double t, rest_time;
    int at_rest;
    int64_t steps, fallbacks, fallback_evaluations, violations;
    double worst_violation; /* the largest height beyond the step's start extremes and the held level 0 */
    int trace;          /* print a line per step */
    int64_t budget;     /* stop a call once this many evaluations are spent (0: no limit) */
    int fe_tail;        /* the method has handed over to forward Euler for good */
    double switch_time, least_excess;
    int stall;
    double last_tau;    /* the length of the last step taken (a super-step, or a forward Euler sub-step) */
    double fe_fraction; /* the method's, 1 by default */
    /* The step-size control: the last super-step's start, its rates, its length. */
    double *prev_y, *prev_rates, *rates;
    double prev_tau, tau_acc;
    int have_prev;
    int64_t rejections;
    double moved;       /* the run's motion so far, sum |y1 - y0| over its measured steps */
    unsigned char *crossed; /* the trace's diagnosis (NULL: none): faces that crossed the threshold within a step */
} run;

static void run_init(run *u, int64_t nx, int64_t ny, double dx, double theta, double tolerance, const double *h) {
    memset(u, 0, sizeof *u);
    flow_init(&u->w, nx, ny, dx, theta, tolerance, h);
    const size_t cells = (size_t)u->w.cells, faces = (size_t)u->w.faces;
    u->y = xcalloc(cells, sizeof(double));
    u->y0 = xcalloc(cells, sizeof(double));
    u->stage = xcalloc(cells, sizeof(double));
    u->save = xcalloc(cells, sizeof(double));
    u->phi0 = xcalloc(faces, sizeof(double));
    u->phi = xcalloc(faces, sizeof(double));
    u->acc_a = xcalloc(faces, sizeof(double));
    u->acc_b = xcalloc(faces, sizeof(double));
    u->prev_y = xcalloc(cells, sizeof(double));
    u->prev_rates = xcalloc(cells, sizeof(double));
    u->rates = xcalloc(cells, sizeof(double));
    memcpy(u->y, h, sizeof(double) * cells);
}

static void run_free(run *u) {
    flow_free(&u->w);
    free(u->y); free(u->y0); free(u->stage); free(u->save);
    free(u->phi0); free(u->phi); free(u->acc_a); free(u->acc_b);
    free(u->prev_y); free(u->prev_rates); free(u->rates);
}

/* Restarts a run from heights h at time t (for the per-call comparison from a common start). */
static void run_reset(run *u, const double *h, double t) {
    memcpy(u->y, h, sizeof(double) * (size_t)u->w.cells);
    u->t = t;
    u->at_rest = 0;
    u->fe_tail = 0;
    u->least_excess = 0.0;
    u->stall = 0;
    u->have_prev = 0; /* the step length it has learnt, tau_acc, stays */
}

static void extremes(const double *y, int64_t cells, double *lo, double *hi) {
    double a = 0.0, b = 0.0; /* the held level of the open sides */
    for (int64_t c = 0; c < cells; ++c) {
        a = fmin(a, y[c]);
        b = fmax(b, y[c]);
    }
    *lo = a;
    *hi = b;
}

/* How far y strays beyond [lo, hi] (0: within). */
static double violation(const double *y, int64_t cells, double lo, double hi) {
    double v = 0.0;
    for (int64_t c = 0; c < cells; ++c) v = fmax(v, fmax(lo - y[c], y[c] - hi));
    return v;
}

/* One forward Euler sub-step of tau from u->y, whose fluxes are in u->phi0. */
static void fe_substep(run *u, double tau) {
    flow_apply(&u->w, u->y, u->phi0, tau, u->stage);
    memcpy(u->y, u->stage, sizeof(double) * (size_t)u->w.cells);
}

/* Forward Euler over tau in ceil(tau / dt_fe) equal sub-steps from u->y,
 * whose fluxes (and their largest excess) are already in u->phi0 and excess
 * (the first evaluation). Stops at rest
 * (then sets u->at_rest and u->rest_time). Returns the time it covered. */
static double fe_span(run *u, double tau, double excess) {
    const double n = ceil(tau / (u->w.dt_fe * u->fe_fraction) * (1.0 - 1e-12));
    const double sub = tau / n;
    for (double k = 0; k < n; ++k) {
        if (k > 0) excess = flow_fluxes(&u->w, u->y, u->phi0);
        if (excess == 0.0) {
            u->at_rest = 1;
            u->rest_time = u->t + k * sub;
            return k * sub;
        }
        if (u->trace && (int64_t)(u->t / u->w.dt_fe + k) % 100 == 0)
            fprintf(stderr, "fe t %.6g excess %.3e active %lld\n", (u->t + k * sub) / u->w.dt_fe, excess,
                    (long long)u->w.active);
        fe_substep(u, sub);
        u->last_tau = sub;
    }
    return tau;
}

/* One super-time-step of tau with coefficients c from u->y (fluxes in
 * u->phi0); the result in u->y. */
static void sts_step(run *u, const sts_coefficients *c, double tau) {
    const int64_t cells = u->w.cells, faces = u->w.faces;
    double *prev = u->acc_a, *prev2 = u->acc_b; /* Phi_{j-1}, Phi_{j-2} */
    memcpy(u->y0, u->y, sizeof(double) * (size_t)cells);
    for (int64_t f = 0; f < faces; ++f) {
        prev2[f] = 0.0;
        prev[f] = c->mut[1] * u->phi0[f];
    }
    for (int j = 2; j <= c->s; ++j) {
        flow_apply(&u->w, u->y0, prev, tau, u->stage);
        flow_fluxes(&u->w, u->stage, u->phi);
        const double mu = c->mu[j], nu = c->nu[j], mut = c->mut[j], gamt = c->gamt[j];
        if (u->crossed) /* the diagnosis: faces whose stage is on the other side of the threshold from the start */
            for (int64_t f = 0; f < faces; ++f) u->crossed[f] |= (u->phi[f] != 0.0) != (u->phi0[f] != 0.0);
        for (int64_t f = 0; f < faces; ++f) /* Phi_j over Phi_{j-2}, which is not needed again */
            prev2[f] = mu * prev[f] + nu * prev2[f] + mut * u->phi[f] + gamt * u->phi0[f];
        double *t = prev; prev = prev2; prev2 = t;
    }
    flow_apply(&u->w, u->y0, prev, tau, u->y);
}

/* The step-size control, at the start of the step after a super-step, whose
 * fluxes are in u->phi0: the trapezoid defect of the last step, D = |y1 -
 * y0 - tau (F(y0) + F(y1)) / 2|_1 (for the exact flow -tau^3 y^(3) / 12: a
 * measure of a second-order step's error that needs no extra evaluation),
 * against the accuracy share of its motion |y1 - y0|_1. The next length is
 * tau (0.9 / ratio)^(1/3), within [0.2, 2] tau and at least a sub-step.
 * Returns 1 when the last step is rejected (ratio > 2, the step longer than
 * a sub-step and within this call: a state a host has seen is never taken
 * back): u->y and
 * u->t are then back at its start. */
static int control_step(run *u, const method *m, int may_reject) {
    if (m->accuracy <= 0.0) return 0;
    const int64_t cells = u->w.cells;
    if (u->tau_acc == 0.0) u->tau_acc = u->w.dt_fe; /* the first step: one sub-step's length */
    if (!u->have_prev) return 0;
    u->have_prev = 0;
    flow_apply(&u->w, NULL, u->phi0, 1.0, u->rates);
    double defect = 0.0, motion = 0.0;
    for (int64_t c = 0; c < cells; ++c) {
        const double change = u->y[c] - u->prev_y[c];
        u->rates[c] = change - 0.5 * u->prev_tau * (u->prev_rates[c] + u->rates[c]); /* the defect, per cell */
        motion += fabs(change);
    }
    /* Over 2 x 2 blocks: the checkerboard a step at the stability limit leaves
     * behind is no error of the flow's path, and would hide it. */
    const int64_t nx = u->w.nx;
    for (int64_t j = 0; j + 1 < u->w.ny; ++j)
        for (int64_t i = 0; i + 1 < nx; ++i) {
            const double *d = u->rates + i + nx * j;
            defect += fabs(0.25 * (d[0] + d[1] + d[nx] + d[nx + 1]));
        }
    u->moved += motion;
    const double allowed = m->accuracy * fmax(motion, m->floor_share * u->moved);
    const double ratio = allowed > 0.0 ? defect / allowed : 0.0;
    u->tau_acc = u->prev_tau * fmin(2.0, fmax(0.2, ratio > 0.0 ? cbrt(0.9 / ratio) : 2.0));
    u->tau_acc = fmax(u->tau_acc, u->w.dt_fe);
    if (ratio <= 2.0 || !may_reject || m->no_reject || u->prev_tau <= u->w.dt_fe * (1.0 + 1e-9)) return 0; /* nothing shorter to try */
    ++u->rejections;
    memcpy(u->y, u->prev_y, sizeof(double) * (size_t)cells);
    u->t -= u->prev_tau;
    return 1;
}

/* What control_step needs of a super-step of tau about to start from u->y (fluxes in u->phi0). */
static void remember_step(run *u, double tau) {
    memcpy(u->prev_y, u->y, sizeof(double) * (size_t)u->w.cells);
    flow_apply(&u->w, NULL, u->phi0, 1.0, u->prev_rates);
    u->prev_tau = tau;
    u->have_prev = 1;
}

/* The steps a call of dt is cut into, and their stages: equal steps no longer
 * than the method's cap (in sub-steps), each with the fewest stages whose
 * stable step spans it; or, for the old fixed-stage runs, steps of 0.95 of
 * the stable length. */
static void plan_call(const run *u, const method *m, double dt, double *tau, int *stages) {
    if (m->kind == KIND_FE) {
        *tau = dt;
        *stages = 1;
        return;
    }
    if (m->fixed_stages > 0) {
        sts_coefficients c;
        setup_sts(&c, m->kind, m->fixed_stages);
        *tau = fmin(dt, 0.95 * c.stable * u->w.dt_fe);
        *stages = m->fixed_stages;
        return;
    }
    double longest = m->cap > 0.0 ? m->cap * u->w.dt_fe : dt;
    if (m->accuracy > 0.0) longest = fmin(longest, u->tau_acc);
    /* Never longer than the most stages allowed can keep stable (a step
     * control without a cap grew past it on the cone and blew up). */
    sts_coefficients most;
    setup_sts(&most, m->kind, m->kind == KIND_RKC ? 63 : kMaxStages - 1);
    longest = fmin(longest, most.stable * u->w.dt_fe);
    *tau = dt / ceil(dt / longest * (1.0 - 1e-12));
    *stages = stages_for(m->kind, *tau / u->w.dt_fe * (1.0 - 1e-12));
}

/* One host call: advances u->y over dt (or to rest, when the fluxes of a
 * step's start vanish: then the time of that state is the rest time and the
 * rest of the call changes nothing). Returns whether the run is at rest. */
static int run_call(run *u, const method *m, double dt) {
    const double start = u->t, end = u->t + dt;
    u->fe_fraction = m->fe_fraction > 0.0 ? m->fe_fraction : 1.0;
    const int64_t cells = u->w.cells;
    while (!u->at_rest && end - u->t > 1e-12 * dt && (!u->budget || u->w.evaluations < u->budget)) {
        const double left = end - u->t;
        const double excess = flow_fluxes(&u->w, u->y, u->phi0);
        if (excess == 0.0) {
            u->at_rest = 1;
            u->rest_time = u->t;
            break;
        }
        if (control_step(u, m, u->t > start)) continue; /* rejected: back at its start, whose fluxes are evaluated again */
        /* The tail: where super-steps stop paying, forward Euler to rest. */
        const double rest_excess = u->w.r.threshold - u->w.r.tan_theta;
        if (u->least_excess == 0.0 || excess < u->least_excess) {
            u->least_excess = excess;
            u->stall = 0;
        } else {
            ++u->stall;
        }
        if (!u->fe_tail && ((m->tail_factor > 0.0 && excess < m->tail_factor * rest_excess) ||
                            (m->stall_steps > 0 && u->stall >= m->stall_steps))) {
            u->fe_tail = 1;
            u->switch_time = u->t;
        }
        double tau;
        int s;
        plan_call(u, m, left, &tau, &s);
        if (u->fe_tail) tau = left;
        if (m->kind == KIND_FE || u->fe_tail || s >= ceil(tau / u->w.dt_fe * (1.0 - 1e-12))) {
            /* No cheaper than forward Euler: take its sub-steps. */
            u->t += fe_span(u, tau, excess);
            if (m->accuracy > 0.0 && !u->fe_tail) u->tau_acc = fmax(u->tau_acc, 2.0 * tau); /* grow until super-steps pay */
            ++u->steps;
            continue;
        }
        sts_coefficients c;
        setup_sts(&c, m->kind, s);
        double lo, hi;
        extremes(u->y, cells, &lo, &hi);
        memcpy(u->save, u->y, sizeof(double) * (size_t)cells);
        const int64_t active = u->w.active;
        if (m->accuracy > 0.0) remember_step(u, tau);
        sts_step(u, &c, tau);
        const double v = violation(u->y, cells, lo, hi);
        if (u->trace)
            fprintf(stderr, "t %.6g s %d excess %.3e active %lld violation %.3e\n", u->t / u->w.dt_fe, s,
                    excess, (long long)active, v);
        if (v > 1e-12 * fmax(1.0, hi - lo)) {
            ++u->violations;
            u->worst_violation = fmax(u->worst_violation, v);
            if (m->fallback) {
                memcpy(u->y, u->save, sizeof(double) * (size_t)cells);
                const int64_t before = u->w.evaluations; /* u->phi0 still holds the start's fluxes */
                const double covered = fe_span(u, tau, excess);
                ++u->fallbacks;
                u->fallback_evaluations += u->w.evaluations - before;
                u->t += covered;
                ++u->steps;
                continue;
            }
        }
        u->t += tau;
        u->last_tau = tau;
        ++u->steps;
    }
    u->t = end;
    return u->at_rest;
}

/* ------------------------------------------------------------------------ */
/* The cone to rest.                                                         */

static const double kTheta = 33.0 * 3.14159265358979323846 / 180.0;
static const int64_t kBudget = 14000; /* twice forward Euler's evaluations on the cone: beyond that, no use */

typedef struct {
    double *h;          /* the deposit */
    double rest_time;   /* when it was found at rest (NAN: never) */
} deposit;

/* A run of method m on heights h0 (n x n cells of dx, open sides) by host
 * calls of call_dt until rest or the budget; the deposit in out. */
static void run_to_rest(run *u, const method *m, int64_t n, double dx, double tolerance, const double *h0,
                        double call_dt, double *seconds) {
    run_init(u, n, n, dx, kTheta, tolerance, h0);
    u->budget = kBudget;
    const double t0 = now_seconds();
    while (!run_call(u, m, call_dt) && u->w.evaluations < kBudget) {
    }
    *seconds = now_seconds() - t0;
}

static double volume(const double *h, int64_t cells) {
    double v = 0.0;
    for (int64_t c = 0; c < cells; ++c) v += h[c];
    return v;
}

/* The L1 difference of a and b over the volume of b, in percent. */
static double l1_percent(const double *a, const double *b, int64_t cells) {
    double d = 0.0;
    for (int64_t c = 0; c < cells; ++c) d += fabs(a[c] - b[c]);
    return 100.0 * d / volume(b, cells);
}

static void cone_header(void) {
    printf("scene,method,call_dt,tolerance,evaluations,seconds,top,top_error_percent,deposit_error_percent,"
           "from_fe_percent,at_rest,rest_time,fe_rest_time,rest_minus_fe_substeps,last_step_substeps,steps,"
           "switch_time,violations,worst_violation,fallbacks,fallback_evaluations,volume_change\n");
}

/* A row of the cone's table: the run u of method m against forward Euler's deposit fe (same calls). */
static void cone_row(const run *u, const method *m, double call_dt, double tolerance, double seconds,
                     const double *h0, const run *fe) {
    const int64_t n = u->w.nx, cells = u->w.cells;
    double *exact = xcalloc((size_t)cells, sizeof(double));
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) exact[i + n * j] = exact_cone(hypot((double)(i - n / 2), (double)(j - n / 2)), kTheta);
    const double top = top_of(u->y, cells), exact_top = 22.89, dt = u->w.dt_fe;
    const double rest = u->at_rest ? u->rest_time : NAN;
    printf("cone,%s,%g,%g,%lld,%.3f,%.4f,%.3f,%.3f,%.4f,%s,%.2f,%.2f,%.1f,%.1f,%lld,%.1f,%lld,%.2e,%lld,%lld,%.1e\n",
           m->name, call_dt, tolerance, (long long)u->w.evaluations, seconds, top,
           100.0 * (top - exact_top) / exact_top, l1_percent(u->y, exact, cells), l1_percent(u->y, fe->y, cells),
           u->at_rest ? "yes" : "no", rest, fe->rest_time, (rest - fe->rest_time) / dt, u->last_tau / dt,
           (long long)u->steps, u->fe_tail ? u->switch_time : NAN, (long long)u->violations, u->worst_violation,
           (long long)u->fallbacks, (long long)u->fallback_evaluations,
           fabs(volume(u->y, cells) - volume(h0, cells)) / volume(h0, cells));
    fflush(stdout);
    free(exact);
}

static void cone_study(const method *methods, size_t count, const double *calls, size_t call_count) {
    const int64_t n = 101;
    const double tolerance = 1e-6;
    double *h0 = xcalloc((size_t)(n * n), sizeof(double));
    fill_cone(h0, n, 1.0);
    cone_header();
    for (size_t k = 0; k < call_count; ++k) {
        const method fe_method = {.name = "fe", .kind = KIND_FE};
        run fe;
        double seconds;
        run_to_rest(&fe, &fe_method, n, 1.0, tolerance, h0, calls[k], &seconds);
        cone_row(&fe, &fe_method, calls[k], tolerance, seconds, h0, &fe);
        for (size_t i = 0; i < count; ++i) {
            run u;
            run_to_rest(&u, &methods[i], n, 1.0, tolerance, h0, calls[k], &seconds);
            cone_row(&u, &methods[i], calls[k], tolerance, seconds, h0, &fe);
            run_free(&u);
        }
        run_free(&fe);
    }
    free(h0);
}

/* ------------------------------------------------------------------------ */
/* Call by call: the column collapse and the steep plane.                   */

/* 101^2 cells of 0.02 (a 2.02 x 2.02 open table), a column 0.8 high on the
 * cells whose centre lies within 0.3 of the centre cell's. */
static void fill_collapse(double *h, int64_t n, double dx) {
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i)
            h[i + n * j] = hypot((double)(i - n / 2) * dx, (double)(j - n / 2) * dx) <= 0.3 + 1e-12 ? 0.8 : 0.0;
}

/* Sum |a - b| * area. */
static double l1_volume(const double *a, const double *b, int64_t cells, double area) {
    double d = 0.0;
    for (int64_t c = 0; c < cells; ++c) d += fabs(a[c] - b[c]);
    return d * area;
}

typedef struct {
    const char *name;
    int64_t n;
    double dx;
    const double *h0;
    double dt;     /* the host's call */
    int max_calls; /* at most this many calls; fewer when forward Euler rests first (then 3 more) */
} call_scene;

/* Forward Euler's states after every call (states[k]: after k calls, states[0]
 * the start) and each call's evaluations; returns the calls made (to rest, or
 * max_calls) and the first call after which it reported rest in *rest_call (0: never). */
static int fe_states(const call_scene *sc, double **states, int64_t *evaluations, int *rest_call) {
    const method fe_method = {.name = "fe", .kind = KIND_FE};
    const int64_t cells = sc->n * sc->n;
    run fe;
    run_init(&fe, sc->n, sc->n, sc->dx, kTheta, 1e-6, sc->h0);
    memcpy(states[0], sc->h0, sizeof(double) * (size_t)cells);
    *rest_call = 0;
    int k = 1;
    for (; k <= sc->max_calls; ++k) {
        const int64_t before = fe.w.evaluations;
        const int rest = run_call(&fe, &fe_method, sc->dt);
        evaluations[k] = fe.w.evaluations - before;
        memcpy(states[k], fe.y, sizeof(double) * (size_t)cells);
        if (rest) {
            *rest_call = k;
            break;
        }
    }
    run_free(&fe);
    return k < sc->max_calls ? k : sc->max_calls;
}

static void calls_header(void) {
    printf("scene,method,call_dt,call,t,moved_volume,diff_a,ratio_a,a_within_1e-3,call_moved_volume,diff_b,ratio_b,"
           "b_within_1e-3,evaluations_a,evaluations_b,fe_evaluations,fe_at_rest,method_at_rest\n"
           "# moved_volume = sum |h_FE(t_k) - h(0)| * area / 2; call_moved_volume = sum |h_FE(t_k) - h_FE(t_k-1)| * area / 2;\n"
           "# (a) both from t = 0, diff_a = sum |h(t_k) - h_FE(t_k)| * area; (b) from h_FE(t_k-1), one call.\n"
           "# Summary rows (call = all): t = seconds, ratio_a/ratio_b = the worst, b_within counts the calls\n"
           "# with call_moved_volume >= 1e-6 of the total moved volume only (the rest: b_within_all),\n"
           "# evaluations_a = total, fe_evaluations = forward Euler's total, then FE's rest call and the method's (0: never).\n");
}

/* Method m against forward Euler call by call: (a) both from t = 0, the L1
 * difference after call k over the volume moved by then; (b) from forward
 * Euler's state after call k - 1, one call, the L1 difference over that
 * call's moved volume. A row per call when per_call_rows, and a summary row. */
static void calls_study(const call_scene *sc, const method *methods, size_t count, int per_call_rows) {
    const int64_t cells = sc->n * sc->n;
    const double area = sc->dx * sc->dx, bound = 1e-3;
    double **states = xcalloc((size_t)sc->max_calls + 4, sizeof(double *));
    for (int k = 0; k <= sc->max_calls + 3; ++k) states[k] = xcalloc((size_t)cells, sizeof(double));
    int64_t *fe_evaluations = xcalloc((size_t)sc->max_calls + 4, sizeof(int64_t));
    int fe_rest = 0;
    const int calls = fe_states(sc, states, fe_evaluations, &fe_rest);
    /* Some calls past forward Euler's rest: the method may rest later. */
    const int last = fe_rest ? calls + 3 : calls;
    for (int k = calls + 1; k <= last; ++k) memcpy(states[k], states[calls], sizeof(double) * (size_t)cells);
    const double total_moved = l1_volume(states[calls], states[0], cells, area) / 2.0;
    for (size_t i = 0; i < count; ++i) {
        const method *m = &methods[i];
        run a, b;
        run_init(&a, sc->n, sc->n, sc->dx, kTheta, 1e-6, sc->h0);
        run_init(&b, sc->n, sc->n, sc->dx, kTheta, 1e-6, sc->h0);
        double worst_a = 0.0, worst_b = 0.0, worst_b_all = 0.0;
        int rest_a = 0, fails_a = 0, fails_b = 0, fails_b_all = 0;
        int64_t fe_total = 0;
        const double t0 = now_seconds();
        for (int k = 1; k <= last; ++k) {
            const int64_t before_a = a.w.evaluations;
            const int at_rest = run_call(&a, m, sc->dt);
            if (at_rest && !rest_a) rest_a = k;
            run_reset(&b, states[k - 1], (k - 1) * sc->dt);
            const int64_t before_b = b.w.evaluations;
            run_call(&b, m, sc->dt);
            const double moved = l1_volume(states[k], states[0], cells, area) / 2.0;
            const double call_moved = l1_volume(states[k], states[k - 1], cells, area) / 2.0;
            const double diff_a = l1_volume(a.y, states[k], cells, area), diff_b = l1_volume(b.y, states[k], cells, area);
            const double ratio_a = moved > 0.0 ? diff_a / moved : 0.0;
            const double ratio_b = call_moved > 0.0 ? diff_b / call_moved : (diff_b > 0.0 ? INFINITY : 0.0);
            const int counted = k <= calls; /* past forward Euler's rest nothing moves: (b) is 0 / 0 */
            const int sizeable = call_moved >= 1e-6 * total_moved;
            worst_a = fmax(worst_a, ratio_a);
            fails_a += ratio_a > bound;
            if (counted) {
                worst_b_all = fmax(worst_b_all, ratio_b);
                fails_b_all += ratio_b > bound;
                fe_total += fe_evaluations[k];
                if (sizeable) {
                    worst_b = fmax(worst_b, ratio_b);
                    fails_b += ratio_b > bound;
                }
            }
            if (per_call_rows)
                printf("%s,%s,%g,%d,%.4f,%.4e,%.4e,%.3e,%s,%.4e,%.4e,%.3e,%s,%lld,%lld,%lld,%s,%s\n", sc->name, m->name,
                       sc->dt, k, k * sc->dt, moved, diff_a, ratio_a, ratio_a <= bound ? "yes" : "no", call_moved, diff_b,
                       ratio_b, ratio_b <= bound || !counted ? "yes" : "no", (long long)(a.w.evaluations - before_a),
                       (long long)(b.w.evaluations - before_b), (long long)(counted ? fe_evaluations[k] : 0),
                       fe_rest && k >= fe_rest ? "yes" : "no", at_rest ? "yes" : "no");
        }
        printf("%s,%s,%g,all,%.3f,%.4e,,%.3e,%s,,,%.3e,%s (%d of %d fail; b_within_all: %s worst %.3e),%lld,,%lld,%d,%d\n",
               sc->name, m->name, sc->dt, now_seconds() - t0, total_moved, worst_a, fails_a ? "no" : "yes", worst_b,
               fails_b ? "no" : "yes", fails_b, calls, fails_b_all ? "no" : "yes", worst_b_all, (long long)a.w.evaluations,
               (long long)fe_total, fe_rest, rest_a);
        fflush(stdout);
        run_free(&a);
        run_free(&b);
    }
    for (int k = 0; k <= sc->max_calls + 3; ++k) free(states[k]);
    free(states);
    free(fe_evaluations);
}

/* The column collapse by calls of dt, to forward Euler's rest (t ~ 1.05) and 3 calls more. */
static void column_calls(const method *methods, size_t count, double dt, int per_call_rows) {
    const int64_t n = 101;
    double *h0 = xcalloc((size_t)(n * n), sizeof(double));
    fill_collapse(h0, n, 0.02);
    const call_scene sc = {"column", n, 0.02, h0, dt, (int)ceil(1.6 / dt)};
    calls_study(&sc, methods, count, per_call_rows);
    free(h0);
}

/* The steep plane (speed.c's, 256^2 cells of width 1, open sides): 10 calls
 * of `substeps` stable sub-steps of a fully active flow that lasts. */
static void steep_calls(const method *methods, size_t count, double substeps) {
    const int64_t n = 256;
    double *h0 = xcalloc((size_t)(n * n), sizeof(double));
    steep_surface(h0, n);
    const double dt_fe = 1.0 / (2.0 * cos(kTheta) * 2.0);
    const call_scene sc = {"steep", n, 1.0, h0, substeps * dt_fe * (1.0 - 1e-9), 10};
    calls_study(&sc, methods, count, 1);
    free(h0);
}

/* ------------------------------------------------------------------------ */
/* The maximum principle, empirically.                                       */

/* Rough terrain: 101^2 cells of width 1, heights uniform in [0, 10) with one
 * cell in 50 a spike 20 higher, from a fixed generator. */
static void fill_rough(double *h, int64_t n, double dx) {
    (void)dx;
    unsigned seed = 12345u;
    for (int64_t c = 0; c < n * n; ++c) {
        seed = seed * 1664525u + 1013904223u;
        const double v = (double)(seed >> 8) / (double)(1u << 24);
        seed = seed * 1664525u + 1013904223u;
        const int spike = (seed >> 8) % 50 == 0;
        h[c] = 10.0 * v + (spike ? 20.0 : 0.0);
    }
}

static void fill_steep(double *h, int64_t n, double dx) {
    (void)dx;
    steep_surface(h, n);
}

/* Each method on each scene without a fallback (calls of the scene's, to
 * rest or the budget): how many steps left a height beyond the step's start
 * extremes and the held level 0, and the worst such overshoot; then with the
 * fallback, the evaluations it cost. */
static void bounds_study(const method *methods, size_t count) {
    typedef struct {
        const char *name;
        int64_t n;
        double dx, dt;
        void (*fill)(double *h, int64_t n, double dx);
    } bounds_scene;
    const bounds_scene scenes[] = {
        {"cone", 101, 1.0, 1e6, fill_cone},
        {"column", 101, 0.02, 0.05, fill_collapse},
        {"steep", 256, 1.0, 58.0 * 0.25 / cos(kTheta) * (1.0 - 1e-9), fill_steep},
        {"rough", 101, 1.0, 1e6, fill_rough},
    };
    printf("scene,method,fallback,calls,evaluations,steps,violating_steps,worst_violation,worst_relative,fallbacks,"
           "fallback_evaluations,at_rest\n");
    for (size_t s = 0; s < sizeof scenes / sizeof *scenes; ++s) {
        const bounds_scene *sc = &scenes[s];
        const int64_t cells = sc->n * sc->n;
        double *h0 = xcalloc((size_t)cells, sizeof(double)), lo, hi;
        sc->fill(h0, sc->n, sc->dx);
        extremes(h0, cells, &lo, &hi);
        const int calls = !strcmp(sc->name, "column") ? 32 : !strcmp(sc->name, "steep") ? 10 : 1;
        for (size_t i = 0; i < count; ++i)
            for (int fallback = 0; fallback <= 1; ++fallback) {
                method m = methods[i];
                m.fallback = fallback;
                run u;
                run_init(&u, sc->n, sc->n, sc->dx, kTheta, 1e-6, h0);
                u.budget = kBudget;
                int k = 0;
                while (k < calls && !run_call(&u, &m, sc->dt)) ++k;
                printf("%s,%s,%d,%d,%lld,%lld,%lld,%.3e,%.3e,%lld,%lld,%s\n", sc->name, m.name, fallback, k,
                       (long long)u.w.evaluations, (long long)u.steps, (long long)u.violations, u.worst_violation,
                       u.worst_violation / (hi - lo), (long long)u.fallbacks, (long long)u.fallback_evaluations,
                       u.at_rest ? "yes" : "no");
                fflush(stdout);
                run_free(&u);
            }
        free(h0);
    }
}

/* ------------------------------------------------------------------------ */
/* The methods compared.                                                     */

static const method kMethods[] = {
    /* The old fixed-stage runs (relax_study.c's rkc-10, rkc-20). */
    {.name = "rkc-10-fixed", .kind = KIND_RKC, .fixed_stages = 10},
    {.name = "rkc-20-fixed", .kind = KIND_RKC, .fixed_stages = 20},
    /* Stages from the call: steps of at most 100 sub-steps, the fewest stages that span one. */
    {.name = "rkc-cap100", .kind = KIND_RKC, .cap = 100},
    {.name = "rkl1-cap100", .kind = KIND_RKL1, .cap = 100},
    {.name = "rkl2-cap100", .kind = KIND_RKL2, .cap = 100},
    {.name = "rkl2-cap100-tail3", .kind = KIND_RKL2, .cap = 100, .tail_factor = 3},
    {.name = "rkl2-cap100-stall5", .kind = KIND_RKL2, .cap = 100, .stall_steps = 5},
    {.name = "rkl2-cap20", .kind = KIND_RKL2, .cap = 20},
    /* The step from the trapezoid defect (1e-3 of the step's motion or of 1 % of the run's), no rejection. */
    {.name = "rkl2-acc-tail3", .kind = KIND_RKL2, .accuracy = 1e-3, .floor_share = 1e-2, .no_reject = 1, .tail_factor = 3},
    {.name = "rkl2-acc-tail10", .kind = KIND_RKL2, .accuracy = 1e-3, .floor_share = 1e-2, .no_reject = 1, .tail_factor = 10},
    {.name = "rkl2-acc-cap100-tail3", .kind = KIND_RKL2, .cap = 100, .accuracy = 1e-3, .floor_share = 1e-2, .no_reject = 1, .tail_factor = 3},
    {.name = "rkl2-acc-cap200-tail3", .kind = KIND_RKL2, .cap = 200, .accuracy = 1e-3, .floor_share = 1e-2, .no_reject = 1, .tail_factor = 3},
    {.name = "rkc-acc-cap100-tail3", .kind = KIND_RKC, .cap = 100, .accuracy = 1e-3, .floor_share = 1e-2, .no_reject = 1, .tail_factor = 3},
    /* The same control with rejection (and without the floor: relative to the step's motion alone). */
    {.name = "rkl2-acc3e-3-tail3", .kind = KIND_RKL2, .accuracy = 3e-3, .floor_share = 1e-2, .no_reject = 1, .tail_factor = 3},
    {.name = "rkl2-acc1e-2-tail3", .kind = KIND_RKL2, .accuracy = 1e-2, .floor_share = 1e-2, .no_reject = 1, .tail_factor = 3},
    {.name = "rkl2-acc1e-2-cap100-tail3", .kind = KIND_RKL2, .cap = 100, .accuracy = 1e-2, .floor_share = 1e-2, .no_reject = 1, .tail_factor = 3},
    {.name = "rkl2-acc-reject-tail3", .kind = KIND_RKL2, .accuracy = 1e-3, .floor_share = 1e-2, .tail_factor = 3},
    {.name = "rkl2-acc-nofloor-tail3", .kind = KIND_RKL2, .accuracy = 1e-3, .no_reject = 1, .tail_factor = 3},
};
static const size_t kMethodCount = sizeof kMethods / sizeof *kMethods;

/* The methods for the per-call and bounds studies: forward Euler at half its sub-step (the yardstick of forward
 * Euler's own time error), then those of kMethods that came to rest on the cone, by name. */
static const char *const kCallMethodNames[] = {
    "rkl2-cap20",           "rkl2-cap100-tail3",  "rkl2-acc-tail3",     "rkl2-acc-cap100-tail3",
    "rkl2-acc-cap200-tail3", "rkc-acc-cap100-tail3", "rkl2-acc3e-3-tail3", "rkl2-acc1e-2-tail3",
    "rkl2-acc1e-2-cap100-tail3",
};
static const size_t kCallMethodCount = 1 + sizeof kCallMethodNames / sizeof *kCallMethodNames;
static method kCallMethods[1 + sizeof kCallMethodNames / sizeof *kCallMethodNames];

static void choose_call_methods(void) {
    kCallMethods[0] = (method){.name = "fe-half", .kind = KIND_FE, .fe_fraction = 0.5};
    for (size_t k = 1; k < kCallMethodCount; ++k) {
        size_t m = 0;
        while (m < kMethodCount && strcmp(kMethods[m].name, kCallMethodNames[k - 1]) != 0) ++m;
        if (m == kMethodCount) {
            fprintf(stderr, "sts: no method named %s\n", kCallMethodNames[k - 1]);
            exit(1);
        }
        kCallMethods[k] = kMethods[m];
    }
}

/* dpsm-bench sts [cone | column [dt] | column-rows [dt] | steep | bounds | trace KIND STAGES [CAP]] */
int cmd_sts(int argc, char **argv) {
    const char *what = argc >= 1 ? argv[0] : "all";
    choose_call_methods();
    if (argc >= 1 && !strcmp(argv[0], "trace")) {
        /* dpsm-bench sts trace KIND STAGES [CAP]: one run on the cone with a line per step. */
        const int64_t n = 101;
        double *h = xcalloc((size_t)(n * n), sizeof(double));
        fill_cone(h, n, 1.0);
        method m = {.name = "trace", .kind = KIND_RKC};
        m.kind = argc > 1 ? (sts_kind)atoi(argv[1]) : KIND_RKC;
        m.fixed_stages = argc > 2 ? atoi(argv[2]) : 10;
        m.cap = argc > 3 ? atof(argv[3]) : 0.0;
        run u;
        run_init(&u, n, n, 1.0, kTheta, 1e-6, h);
        u.trace = 1;
        u.budget = 14000;
        run_call(&u, &m, 1e6);
        if (getenv("STS_DIAG")) {
            /* Where the faces that never settle lie, and whether the steps cycle. */
            const int64_t cells = n * n;
            double *hist[3];
            for (int k = 0; k < 3; ++k) hist[k] = xcalloc((size_t)cells, sizeof(double));
            u.crossed = xcalloc((size_t)u.w.faces, 1);
            for (int step = 0; step < 8; ++step) {
                memcpy(hist[2], hist[1], sizeof(double) * (size_t)cells);
                memcpy(hist[1], hist[0], sizeof(double) * (size_t)cells);
                memcpy(hist[0], u.y, sizeof(double) * (size_t)cells);
                const double excess = flow_fluxes(&u.w, u.y, u.phi0);
                double rmin = 1e9, rmax = 0, d1 = 0, d2 = 0, most = 0;
                int64_t where = -1;
                for (int64_t f = 0; f < u.w.faces; ++f) {
                    if (u.phi0[f] == 0.0) continue;
                    const int64_t across = (n + 1) * n;
                    double x, yy;
                    if (f < across) { x = f % (n + 1) - 0.5; yy = (double)(f / (n + 1)); }
                    else { x = (double)((f - across) % n); yy = (f - across) / n - 0.5; }
                    const double rad = hypot(x - n / 2, yy - n / 2);
                    rmin = fmin(rmin, rad); rmax = fmax(rmax, rad);
                    if (fabs(u.phi0[f]) > most) { most = fabs(u.phi0[f]); where = f; }
                }
                for (int64_t c = 0; c < cells; ++c) {
                    d1 = fmax(d1, fabs(u.y[c] - hist[1][c]));
                    d2 = fmax(d2, fabs(u.y[c] - hist[2][c]));
                }
                int64_t crossed = 0, crossed_active = 0;
                for (int64_t f = 0; f < u.w.faces; ++f) {
                    crossed += u.crossed[f];
                    crossed_active += u.crossed[f] && u.phi0[f] != 0.0;
                    u.crossed[f] = 0;
                }
                printf("last step: %lld faces crossed the threshold within the stages, %lld of them active now\n",
                       (long long)crossed, (long long)crossed_active);
                printf("excess %.3e active %lld radius %.1f..%.1f largest flux %.3e at face %lld; |y - y_prev| %.3e |y - y_prev2| %.3e\n",
                       excess, (long long)u.w.active, rmin, rmax, most, (long long)where, d1, d2);
                sts_coefficients c;
                setup_sts(&c, m.kind, m.fixed_stages);
                sts_step(&u, &c, 0.95 * c.stable * u.w.dt_fe);
            }
            for (int k = 0; k < 3; ++k) free(hist[k]);
            free(u.crossed);
            u.crossed = NULL;
        }
        printf("evaluations %lld rest %d at %.6g sub-steps, steps %lld, violations %lld worst %.3e top %.5f\n",
               (long long)u.w.evaluations, u.at_rest, u.rest_time / u.w.dt_fe, (long long)u.steps,
               (long long)u.violations, u.worst_violation, top_of(u.y, n * n));
        run_free(&u);
        free(h);
        return 0;
    }
    const int all = !strcmp(what, "all");
    if (all || !strcmp(what, "cone")) {
        const double calls[] = {1e6, 30.0}; /* one call to rest (as dpsm-bench cone), and calls of ~100 sub-steps */
        cone_study(kMethods, kMethodCount, calls, sizeof calls / sizeof *calls);
    }
    if (all || !strncmp(what, "column", 6)) {
        const int rows = !strcmp(what, "column-rows");
        calls_header();
        if (argc >= 2) {
            column_calls(kCallMethods, kCallMethodCount, atof(argv[1]), rows);
        } else {
            const double dts[] = {0.005, 0.05, 0.5};
            for (size_t k = 0; k < sizeof dts / sizeof *dts; ++k)
                column_calls(kCallMethods, kCallMethodCount, dts[k], rows || dts[k] == 0.05);
        }
    }
    if (all || !strcmp(what, "steep")) {
        calls_header();
        steep_calls(kCallMethods + 1, kCallMethodCount - 1, 58.0);
        steep_calls(kCallMethods + 1, kCallMethodCount - 1, 1.0);
    }
    if (all || !strcmp(what, "bounds")) bounds_study(kCallMethods + 1, kCallMethodCount - 1);
    (void)kPi;
    return 0;
}
