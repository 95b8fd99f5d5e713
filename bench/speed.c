/* The speed benchmarks of dpsm-bench: throughput, sparse, idle, cone, deposits, physics. Each
 * times dpsm through its public API and, in the same run, the plain reference
 * loop of reference.c on the same scene, and prints CSV (a log on stderr). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "reference.h"
#include "vectorised.h"

static const double kPi = 3.14159265358979323846;
static const double kTheta = 30.0 * 3.14159265358979323846 / 180.0;

/* A surface where every face is steeper than the angle of repose: a plane of
 * slope (2, 1.5) with ripples, on an open table. */
void steep_surface(double *h, int64_t n) {
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i)
            h[i + n * j] = 2.0 * (double)i + 1.5 * (double)j + 0.3 * sin(0.7 * (double)i) * cos(0.3 * (double)j);
}

static dpsm_grid *make_grid(int64_t n, const double *h, int threads, int open) {
    dpsm_grid *g = NULL;
    CHECK(NULL, dpsm_create_2d(n, n, 1.0, 1.0, &g));
    /* Throughput and sparse time sub-steps; idle sets the default back. */
    CHECK(g, dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE));
    CHECK(g, dpsm_set_repose_angle(g, kTheta));
    CHECK(g, dpsm_set_threads(g, threads));
    for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side)
        CHECK(g, dpsm_set_boundary(g, side, open ? DPSM_OPEN : DPSM_WALL));
    CHECK(g, dpsm_set_heights(g, h));
    return g;
}

static dpsm_grid *open_table(int64_t n, const double *h, int threads) { return make_grid(n, h, threads, 1); }

/* Something a benchmark adds to a scene, given its size and heights (NULL: nothing). */
typedef void (*scene_setup)(dpsm_grid *g, int64_t n, const double *h);

/* Seconds per sub-step of dpsm on a fully active n x n surface, with `setup`'s additions. */
static double seconds_per_substep_of(int64_t n, const double *h, int threads, int substeps, scene_setup setup,
                                     double *updates) {
    dpsm_grid *g = open_table(n, h, threads);
    if (setup) setup(g, n, h);
    double dt;
    CHECK(g, dpsm_stable_dt(g, &dt));
    CHECK(g, dpsm_step(g, 4.0 * dt)); /* warm up: workspaces, pages, the active set */
    const double t0 = now_seconds();
    CHECK(g, dpsm_step(g, substeps * dt));
    const double seconds = now_seconds() - t0;
    double taken;
    CHECK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &taken));
    CHECK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, updates));
    if (taken != substeps) fprintf(stderr, "dpsm-bench: warning: %g sub-steps instead of %d\n", taken, substeps);
    dpsm_destroy(g);
    return seconds / taken;
}

static double dpsm_seconds_per_substep(int64_t n, const double *h, int threads, int substeps, double *updates) {
    return seconds_per_substep_of(n, h, threads, substeps, NULL, updates);
}

/* The fully active scene of throughput and physics: the steep surface h on
 * an n x n open table, dpsm's stable sub-step dt, and the plain reference
 * loop, timed (ref_rate, cells per second) over ref_steps sub-steps of dt,
 * after which ref holds its state. */
typedef struct {
    int64_t n;
    double cells, dt, ref_rate;
    int ref_steps;
    double *h;
    reference_grid ref;
} active_scene;

static int active_scene_init(active_scene *s, int64_t n) {
    s->n = n;
    s->cells = (double)n * (double)n;
    s->h = xcalloc((size_t)(n * n), sizeof(double));
    steep_surface(s->h, n);
    if (!reference_init(&s->ref, n, n, 1.0, 1.0, 1.0, kTheta, DPSM_DEFAULT_REST_TOLERANCE, s->h)) return 0;
    dpsm_grid *g = open_table(n, s->h, 1);
    CHECK(g, dpsm_stable_dt(g, &s->dt));
    dpsm_destroy(g);
    s->ref_steps = n <= 512 ? 20 : n <= 2048 ? 3 : 2;
    const double t0 = now_seconds();
    for (int k = 0; k < s->ref_steps; ++k) reference_substep(&s->ref, s->dt);
    s->ref_rate = s->cells * s->ref_steps / (now_seconds() - t0);
    return 1;
}

static void active_scene_free(active_scene *s) {
    reference_free(&s->ref);
    free(s->h);
}

int cmd_throughput(int argc, char **argv) {
    int64_t sizes[8] = {512, 2048, 4096};
    int count = 3;
    if (argc > 0) {
        count = 0;
        for (int k = 0; k < argc && count < 8; ++k) sizes[count++] = atoll(argv[k]);
    }
    printf("n,threads,mcells_per_s,reference_mcells_per_s,ratio,vectorised_mcells_per_s\n");
    for (int k = 0; k < count; ++k) {
        /* The reference: a few sub-steps, and a check that it computes what dpsm does. */
        active_scene scene;
        if (!active_scene_init(&scene, sizes[k])) return 1;
        const int64_t n = scene.n;
        const double cells = scene.cells, dt = scene.dt, ref_rate = scene.ref_rate, *h = scene.h;
        const int ref_steps = scene.ref_steps;
        const reference_grid *ref = &scene.ref;
        dpsm_grid *g = open_table(n, h, 0);
        CHECK(g, dpsm_step(g, ref_steps * dt));
        double *got = xcalloc((size_t)(n * n), sizeof(double)), worst = 0.0;
        CHECK(g, dpsm_get_heights(g, got));
        for (int64_t j = 0; j < n; ++j)
            for (int64_t i = 0; i < n; ++i)
                worst = fmax(worst, fabs(got[i + n * j] - reference_height(ref, i, j)) /
                                        fmax(1.0, fabs(reference_height(ref, i, j))));
        fprintf(stderr, "n = %lld: dpsm and the reference differ by at most %.2e (relative) after %d sub-steps\n",
                (long long)n, worst, ref_steps);
        free(got);
        dpsm_destroy(g);

        const int substeps = n <= 512 ? 400 : n <= 2048 ? 40 : 12;
        double vectorised[2], difference = 0.0;
        for (int threads = 1; threads <= 2; ++threads)
            vectorised[threads - 1] = vectorised_mcells_per_s(n, h, kTheta, DPSM_DEFAULT_REST_TOLERANCE, dt, threads,
                                                              substeps, ref, ref_steps, &difference);
        fprintf(stderr, "n = %lld: the vectorised loop and the reference differ by at most %.2e (relative) after %d "
                "sub-steps, away from the edges\n", (long long)n, difference, ref_steps);

        for (int threads = 1; threads <= 2; ++threads) {
            double updates;
            const double per_substep = dpsm_seconds_per_substep(n, h, threads, substeps, &updates);
            const double rate = cells / per_substep;
            printf("%lld,%d,%.1f,%.1f,%.2f,%.1f\n", (long long)n, threads, rate / 1e6, ref_rate / 1e6, rate / ref_rate,
                   vectorised[threads - 1]);
            fflush(stdout);
        }
        active_scene_free(&scene);
    }
    return 0;
}

/* A dune field at rest between walls: long gentle ripples below the angle of repose. */
static void dune_bed(double *h, int64_t n) {
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i)
            h[i + n * j] = 3.0 + 2.0 * sin(2.0 * kPi * (double)i / 400.0) * cos(2.0 * kPi * (double)j / 700.0);
}

/* The slip faces of the sparse benchmark, on a lattice over the dune field:
 * compact lee slopes face_w x face_h cells, slightly steeper than the angle
 * of repose, descending in +x. Adds them to h; where brink is not NULL,
 * marks their upwind three columns there. Returns how many were placed. */
static int64_t add_slip_faces(double *h, unsigned char *brink, int64_t n, double fraction) {
    const int64_t face_w = 40, face_h = 24;
    const int64_t faces = (int64_t)(fraction * (double)n * (double)n / (double)(face_w * face_h));
    const int64_t per_row = (int64_t)ceil(sqrt((double)faces));
    const int64_t pitch = n / (per_row + 1);
    int64_t placed = 0;
    unsigned seed = 12345u;
    for (int64_t a = 0; a < per_row && placed < faces; ++a)
        for (int64_t b = 0; b < per_row && placed < faces; ++b, ++placed) {
            seed = seed * 1664525u + 1013904223u;
            const int64_t i0 = (a + 1) * pitch - face_w / 2 + (int64_t)(seed >> 28) - 8;
            const int64_t j0 = (b + 1) * pitch - face_h / 2;
            for (int64_t j = j0; j < j0 + face_h; ++j)
                for (int64_t i = i0; i < i0 + face_w; ++i) {
                    h[i + n * j] += 1.15 * tan(kTheta) * (double)(i0 + face_w - i);
                    if (brink && i < i0 + 3) brink[i + n * j] = 1;
                }
        }
    return placed * face_w * face_h;
}

int cmd_sparse(int argc, char **argv) {
    const int64_t n = argc > 0 ? atoll(argv[0]) : 4096;
    const double target = argc > 1 ? atof(argv[1]) : 0.01; /* fraction of cells on slip faces */
    const int threads = argc > 2 ? atoi(argv[2]) : 0;      /* 0: the OpenMP default */
    const double cells = (double)n * (double)n;
    double *h = xcalloc((size_t)(n * n), sizeof(double)), *q = xcalloc((size_t)(n * n), sizeof(double));
    dune_bed(h, n);
    /* Slip faces: compact lee slopes 40 x 24 cells, slightly steeper than the
     * angle of repose, fed at their brink by deposition (the wind's sand), so
     * that they keep avalanching. Placed on a regular lattice, jittered. */
    unsigned char *brink = xcalloc((size_t)(n * n), 1);
    const int64_t slip = add_slip_faces(h, brink, n, target);
    for (int64_t c = 0; c < n * n; ++c) q[c] = brink[c] ? 0.2 : 0.0;
    free(brink);
    /* Best of three runs of each, the sparse scene afresh every time: on a
     * shared machine the fastest run is the one least disturbed. */
    const int substeps = 40;
    double sparse_per_substep = INFINITY, updates = 0.0;
    for (int run = 0; run < 3; ++run) {
        dpsm_grid *g = make_grid(n, h, threads, 0);
        CHECK(g, dpsm_set_source(g, q));
        double dt;
        CHECK(g, dpsm_stable_dt(g, &dt));
        CHECK(g, dpsm_step(g, 8.0 * dt)); /* warm up */
        const double t0 = now_seconds();
        CHECK(g, dpsm_step(g, substeps * dt));
        sparse_per_substep = fmin(sparse_per_substep, (now_seconds() - t0) / substeps);
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &updates));
        dpsm_destroy(g);
    }

    steep_surface(h, n);
    double full_updates, full_per_substep = INFINITY;
    for (int run = 0; run < 3; ++run)
        full_per_substep = fmin(full_per_substep, dpsm_seconds_per_substep(n, h, threads, 8, &full_updates));
    printf("n,slip_face_fraction,cells_visited_fraction,sparse_s_per_substep,full_s_per_substep,ratio\n");
    printf("%lld,%.4f,%.4f,%.3e,%.3e,%.4f\n", (long long)n, (double)slip / cells,
           updates / (substeps * cells), sparse_per_substep, full_per_substep, sparse_per_substep / full_per_substep);
    free(h);
    free(q);
    return 0;
}

int cmd_idle(int argc, char **argv) {
    const int64_t n = argc > 0 ? atoll(argv[0]) : 4096;
    const int calls = 200;
    double *h = xcalloc((size_t)(n * n), sizeof(double));
    dune_bed(h, n);
    dpsm_grid *g = make_grid(n, h, 0, 0);
    CHECK(g, dpsm_set_relaxation(g, DPSM_RELAX_AUTO)); /* the default: a host's plain dpsm_step */
    CHECK(g, dpsm_step(g, 1.0));                        /* looks at every tile once and finds rest */
    const double t0 = now_seconds();
    for (int k = 0; k < calls; ++k) CHECK(g, dpsm_step(g, 1.0));
    const double idle = (now_seconds() - t0) / calls;
    double updates;
    CHECK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &updates));
    dpsm_destroy(g);
    steep_surface(h, n);
    double full_updates;
    const double full = dpsm_seconds_per_substep(n, h, 0, 4, &full_updates);
    printf("n,idle_s_per_step,cell_updates,full_s_per_substep,ratio\n");
    printf("%lld,%.3e,%.0f,%.3e,%.2e\n", (long long)n, idle, updates, full, idle / full);
    free(h);
    return 0;
}

/* A host's deposits: `count` heaps of 10 x 10 cells, 4 high, dropped one
 * after another along a line of an n x n surface at rest, each stepped to
 * rest (dt = 50 until DPSM_INFO_AT_REST), `rounds` times over (the piles
 * grow), by the default (time-accurate) and relaxed to rest
 * (DPSM_RELAX_TO_REST). Prints the seconds (best of three), the sub-steps
 * or flux evaluations and the cells computed, and how far the two deposits
 * end apart (L1, of the deposited volume). */
int cmd_deposits(int argc, char **argv) {
    const int64_t n = argc > 0 ? atoll(argv[0]) : 4096;
    const int count = argc > 1 ? atoi(argv[1]) : 40, rounds = argc > 2 ? atoi(argv[2]) : 1;
    if (n < 256 || count < 1 || 100 + 50 * (int64_t)count > n - 20 || rounds < 1) {
        fprintf(stderr, "dpsm-bench deposits: n >= 256, 1 <= count <= (n - 120) / 50, rounds >= 1\n");
        return 1;
    }
    double *h = xcalloc((size_t)(n * n), sizeof(double)), *out[2];
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) h[i + n * j] = 0.2 * sin(0.01 * (double)i) * cos(0.013 * (double)j);
    double heap[100];
    for (int c = 0; c < 100; ++c) heap[c] = 4.0;
    const int relaxations[2] = {DPSM_RELAX_AUTO, DPSM_RELAX_TO_REST};
    printf("method,n,deposits,rounds,seconds,substeps,cell_updates\n");
    for (int k = 0; k < 2; ++k) {
        double seconds = INFINITY, substeps = 0.0, updates = 0.0;
        out[k] = xcalloc((size_t)(n * n), sizeof(double));
        for (int run = 0; run < 3; ++run) {
            dpsm_grid *g = make_grid(n, h, 0, 0);
            CHECK(g, dpsm_set_relaxation(g, relaxations[k]));
            CHECK(g, dpsm_step(g, 1.0)); /* looks at every tile once and finds rest */
            double t = 0.0, s = 0.0, u = 0.0;
            for (int d = 0; d < count * rounds; ++d) {
                CHECK(g, dpsm_add_heights_region(g, 100 + 50 * (d % count), n / 2, 10, 10, heap));
                const double t0 = now_seconds();
                double rest = 0.0;
                for (int guard = 0; rest == 0.0 && guard < 100000; ++guard) {
                    CHECK(g, dpsm_step(g, 50.0));
                    double info;
                    CHECK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &info));
                    s += info;
                    CHECK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &info));
                    u += info;
                    CHECK(g, dpsm_get_step_info(g, DPSM_INFO_AT_REST, &rest));
                }
                t += now_seconds() - t0;
            }
            if (t < seconds) {
                seconds = t;
                substeps = s;
                updates = u;
            }
            CHECK(g, dpsm_get_heights(g, out[k]));
            dpsm_destroy(g);
        }
        printf("%s,%lld,%d,%d,%.4f,%.0f,%.4g\n", k ? "dpsm-to-rest" : "dpsm-default", (long long)n, count, rounds,
               seconds, substeps, updates);
    }
    double apart = 0.0;
    for (int64_t c = 0; c < n * n; ++c) apart += fabs(out[0][c] - out[1][c]);
    fprintf(stderr, "dpsm-bench deposits: the two deposits end %.3f %% apart (L1, of the deposited volume)\n",
            100.0 * apart / (100.0 * 4.0 * count * rounds));
    free(out[0]);
    free(out[1]);
    free(h);
    return 0;
}

/* The scene dune models use: a cone 40 high with slope 1.5 on 101^2 cells of
 * width 1, relaxed to 33 degrees. Exact top of the volume-conserving cone at
 * the angle of repose: 22.89. Also the reference loop run to rest. */
int cmd_cone(int argc, char **argv) {
    const double tolerance = argc > 0 ? atof(argv[0]) : DPSM_DEFAULT_REST_TOLERANCE;
    const int fast_runs = argc > 1 ? atoi(argv[1]) : 10;
    if (fast_runs < 1) {
        fprintf(stderr, "dpsm-bench cone: runs must be at least 1, not %s\n", argv[1]);
        return 1;
    }
    const int64_t n = 101;
    const double theta = 33.0 * kPi / 180.0, exact_top = 22.89;
    double *h = xcalloc((size_t)(n * n), sizeof(double));
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) h[i + n * j] = fmax(0.0, 40.0 - 1.5 * hypot((double)(i - 50), (double)(j - 50)));
    printf("method,tolerance,seconds,substeps,top,top_error_percent\n");

    /* dpsm's time-accurate sub-steps (the default), then its fast relaxation
     * to rest (DPSM_RELAX_TO_REST); the best of three runs, and of fast_runs (10) for the
     * relaxation to rest, whose few hundredths of a second a busy machine
     * disturbs the most. */
    double dt = 0.0;
    for (int relaxation = DPSM_RELAX_TIME_ACCURATE; relaxation <= DPSM_RELAX_TO_REST; ++relaxation) {
        double seconds = INFINITY, substeps = 0.0, rest = 0.0, top = 0.0;
        const int runs = relaxation == DPSM_RELAX_TO_REST ? fast_runs : 3;
        for (int run = 0; run < runs; ++run) {
            dpsm_grid *g = open_table(n, h, 0);
            CHECK(g, dpsm_set_repose_angle(g, theta));
            CHECK(g, dpsm_set_rest_tolerance(g, tolerance));
            CHECK(g, dpsm_set_relaxation(g, relaxation));
            const double t0 = now_seconds();
            CHECK(g, dpsm_step(g, 1e6));
            seconds = fmin(seconds, now_seconds() - t0);
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &substeps));
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_AT_REST, &rest));
            double *out = xcalloc((size_t)(n * n), sizeof(double));
            CHECK(g, dpsm_get_heights(g, out));
            top = 0.0;
            for (int64_t c = 0; c < n * n; ++c) top = fmax(top, out[c]);
            free(out);
            CHECK(g, dpsm_stable_dt(g, &dt));
            dpsm_destroy(g);
        }
        printf("%s,%g,%.4f,%.0f,%.3f,%.3f\n", relaxation == DPSM_RELAX_TO_REST ? "dpsm-to-rest" : "dpsm", tolerance,
               seconds, substeps, top, 100.0 * (top - exact_top) / exact_top);
        if (rest != 1.0) fprintf(stderr, "dpsm-bench: warning: dpsm did not reach rest\n");
    }

    reference_grid ref;
    if (!reference_init(&ref, n, n, 1.0, 1.0, 1.0, theta, tolerance, h)) return 1;
    const double t1 = now_seconds();
    int64_t steps = 0;
    while (reference_substep(&ref, dt) > 0.0 && steps < 10000000) ++steps;
    const double ref_seconds = now_seconds() - t1;
    double ref_top = 0.0;
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) ref_top = fmax(ref_top, reference_height(&ref, i, j));
    printf("reference,%g,%.4f,%lld,%.3f,%.3f\n", tolerance, ref_seconds, (long long)steps, ref_top,
           100.0 * (ref_top - exact_top) / exact_top);
    reference_free(&ref);
    free(h);
    return 0;
}

/* A host's wind on a dune field: the sparse benchmark's field and slip faces
 * (about 1 % of the cells), and a source on every cell, as a dune model's
 * sand flux gives it: erosion on the slopes that rise downwind (stoss),
 * deposition where they fall (lee), q = -0.05 dh/dx, and the sand that
 * reaches a slip face's brink deposited there (0.2). Times one call of 64
 * stable sub-steps (after a call that warms up), with and without setting
 * the source before it as a host does every step, against 64 fully active
 * sub-steps and 64 sub-steps of the reference loop; best of three runs, the
 * scene afresh each time. */
int cmd_wind(int argc, char **argv) {
    const int64_t n = argc > 0 ? atoll(argv[0]) : 2048;
    const int threads = argc > 1 ? atoi(argv[1]) : 0; /* 0: the OpenMP default */
    const int substeps = 64;
    const double cells = (double)n * (double)n;
    double *h = xcalloc((size_t)(n * n), sizeof(double)), *q = xcalloc((size_t)(n * n), sizeof(double));
    unsigned char *brink = xcalloc((size_t)(n * n), 1);
    dune_bed(h, n);
    const int64_t slip = add_slip_faces(h, brink, n, 0.01);
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) {
            const int64_t w = i > 0 ? i - 1 : i, e = i + 1 < n ? i + 1 : i;
            q[i + n * j] = brink[i + n * j] ? 0.2 : -0.05 * (h[e + n * j] - h[w + n * j]) / (double)(e - w);
        }
    double call = INFINITY, call_with_source = INFINITY, updates = 0.0, taken = 0.0;
    for (int run = 0; run < 3; ++run) {
        dpsm_grid *g = make_grid(n, h, threads, 0);
        CHECK(g, dpsm_set_relaxation(g, DPSM_RELAX_AUTO)); /* the default: a host's plain dpsm_step */
        CHECK(g, dpsm_set_source(g, q));
        double dt;
        CHECK(g, dpsm_stable_dt(g, &dt));
        CHECK(g, dpsm_step(g, substeps * dt)); /* warm up */
        double t0 = now_seconds();
        CHECK(g, dpsm_step(g, substeps * dt));
        call = fmin(call, now_seconds() - t0);
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &updates));
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &taken));
        t0 = now_seconds();
        CHECK(g, dpsm_set_source(g, q));
        CHECK(g, dpsm_step(g, substeps * dt));
        call_with_source = fmin(call_with_source, now_seconds() - t0);
        dpsm_destroy(g);
    }
    reference_grid ref;
    steep_surface(h, n);
    if (!reference_init(&ref, n, n, 1.0, 1.0, 1.0, kTheta, DPSM_DEFAULT_REST_TOLERANCE, h)) return 1;
    double dt = 0.0;
    {
        dpsm_grid *g = open_table(n, h, threads);
        CHECK(g, dpsm_stable_dt(g, &dt));
        dpsm_destroy(g);
    }
    const double r0 = now_seconds();
    reference_substep(&ref, dt);
    const double reference = now_seconds() - r0;
    reference_free(&ref);
    double full = INFINITY, full_updates;
    for (int run = 0; run < 3; ++run) full = fmin(full, dpsm_seconds_per_substep(n, h, threads, 8, &full_updates));
    printf("n,slip_face_fraction,substeps,cells_visited_fraction,call_s,call_with_source_s,full_s,ratio,"
           "ratio_with_source,reference_s,ratio_to_reference\n");
    printf("%lld,%.4f,%.0f,%.4f,%.3e,%.3e,%.3e,%.4f,%.4f,%.3e,%.4f\n", (long long)n, (double)slip / cells, taken,
           updates / (substeps * cells), call, call_with_source, substeps * full, call / (substeps * full),
           call_with_source / (substeps * full), substeps * reference, call / (substeps * reference));
    free(h);
    free(q);
    free(brink);
    return 0;
}

/* Short calls: a host whose time step holds one stable sub-step calls
 * dpsm_step once per sub-step. On a fully active n^2 surface, the seconds per
 * sub-step of 64 calls of one sub-step against one call of 58 sub-steps
 * (the time-accurate steps and the default), on 1 and 2 threads; and the
 * reference loop's. Best of three runs each. */
int cmd_short(int argc, char **argv) {
    const int64_t n = argc > 0 ? atoll(argv[0]) : 2048;
    const double cells = (double)n * (double)n;
    double *h = xcalloc((size_t)(n * n), sizeof(double));
    steep_surface(h, n);
    reference_grid ref;
    if (!reference_init(&ref, n, n, 1.0, 1.0, 1.0, kTheta, DPSM_DEFAULT_REST_TOLERANCE, h)) return 1;
    printf("n,threads,long_mcells_per_s,default_long_mcells_per_s,short_mcells_per_s,short_over_long,"
           "default_over_time_accurate,reference_mcells_per_s\n");
    double reference = 0.0;
    for (int threads = 1; threads <= 2; ++threads) {
        double per[3] = {INFINITY, INFINITY, INFINITY}; /* long time-accurate, long default, short */
        for (int run = 0; run < 3; ++run)
            for (int kind = 0; kind < 3; ++kind) {
                dpsm_grid *g = open_table(n, h, threads);
                if (kind == 1) CHECK(g, dpsm_set_relaxation(g, DPSM_RELAX_AUTO));
                double dt;
                CHECK(g, dpsm_stable_dt(g, &dt));
                CHECK(g, dpsm_step(g, 4.0 * dt)); /* warm up */
                const int calls = kind == 2 ? 64 : 1, each = kind == 2 ? 1 : 58;
                const double t0 = now_seconds();
                for (int c = 0; c < calls; ++c) CHECK(g, dpsm_step(g, each * dt));
                per[kind] = fmin(per[kind], (now_seconds() - t0) / (calls * each));
                dpsm_destroy(g);
            }
        if (threads == 1) {
            double dt = 0.0;
            dpsm_grid *g = open_table(n, h, 1);
            CHECK(g, dpsm_stable_dt(g, &dt));
            dpsm_destroy(g);
            const double t0 = now_seconds();
            reference_substep(&ref, dt);
            reference = now_seconds() - t0;
        }
        printf("%lld,%d,%.1f,%.1f,%.1f,%.3f,%.3f,%.1f\n", (long long)n, threads, cells / per[0] / 1e6,
               cells / per[1] / 1e6, cells / per[2] / 1e6, per[2] / per[0], per[1] / per[0], cells / reference / 1e6);
        fflush(stdout);
    }
    reference_free(&ref);
    free(h);
    return 0;
}

/* ---- dpsm-bench physics: what each feature of real scenes costs --------- */

static void flat_bed(dpsm_grid *g, int64_t n, double level) {
    double *zb = xcalloc((size_t)(n * n), sizeof(double));
    for (int64_t c = 0; c < n * n; ++c) zb[c] = level;
    CHECK(g, dpsm_set_bedrock(g, zb));
    free(zb);
}
/* A bed 100 below the lowest cell: never reached, so every face flows as on the plain scene. */
static void bed_far_below(dpsm_grid *g, int64_t n, const double *h) {
    (void)h;
    flat_bed(g, n, -100.0);
}
/* A bed of zeros, the level of the surface's lowest corner and of the open sides. */
static void bed_of_zeros(dpsm_grid *g, int64_t n, const double *h) {
    (void)h;
    flat_bed(g, n, 0.0);
}
/* An angle field that is the scene's own angle everywhere. */
static void uniform_angle_field(dpsm_grid *g, int64_t n, const double *h) {
    (void)h;
    double *theta = xcalloc((size_t)(n * n), sizeof(double));
    for (int64_t c = 0; c < n * n; ++c) theta[c] = kTheta;
    CHECK(g, dpsm_set_repose_angle_field(g, theta));
    free(theta);
}
static void exponent_1_25(dpsm_grid *g, int64_t n, const double *h) {
    (void)n, (void)h;
    CHECK(g, dpsm_set_flux_exponent(g, 1.25));
}
static void exponent_1_5(dpsm_grid *g, int64_t n, const double *h) {
    (void)n, (void)h;
    CHECK(g, dpsm_set_flux_exponent(g, 1.5));
}
static void exponent_2(dpsm_grid *g, int64_t n, const double *h) {
    (void)n, (void)h;
    CHECK(g, dpsm_set_flux_exponent(g, 2.0));
}
/* A static angle of 35 degrees on the 30-degree scene (whose faces are all steeper). */
static void static_angle_35(dpsm_grid *g, int64_t n, const double *h) {
    (void)n, (void)h;
    CHECK(g, dpsm_set_static_angle(g, 35.0 * kPi / 180.0));
}

/* The fully active surface of `throughput`, plain and with each feature, on 1
 * and 2 threads. The scenes take turns within each of `runs` rounds, so that
 * a busy spell of the machine falls on all of them; each row gives the best
 * and the slowest round, the cost against the plain scene (its best time over
 * the plain scene's best) and the range of that cost round by round. A scene
 * named after the runs is run alone (for a profiler; no cost against plain). */
int cmd_physics(int argc, char **argv) {
    const int64_t n = argc > 0 ? atoll(argv[0]) : 2048;
    const int runs = argc > 1 ? atoi(argv[1]) : 3;
    const char *only = argc > 2 ? argv[2] : NULL;
    if (n < 64 || runs < 1) {
        fprintf(stderr, "dpsm-bench physics: n >= 64, runs >= 1\n");
        return 1;
    }
    static const struct {
        const char *name;
        scene_setup setup;
    } scenes[] = {{"plain", NULL},
                  {"bed-100-below", bed_far_below},
                  {"bed-of-zeros", bed_of_zeros},
                  {"angle-field-uniform", uniform_angle_field},
                  {"exponent-1.5", exponent_1_5},
                  {"exponent-2", exponent_2},
                  {"exponent-1.25", exponent_1_25},
                  {"static-angle-35", static_angle_35}};
    enum { kScenes = sizeof scenes / sizeof scenes[0] };
    int chosen[kScenes], any = 0;
    for (int k = 0; k < kScenes; ++k) any += chosen[k] = !only || !strcmp(only, scenes[k].name);
    if (!any) {
        fprintf(stderr, "dpsm-bench physics: no scene named %s\n", only);
        return 1;
    }
    active_scene scene; /* and the plain reference loop on it */
    if (!active_scene_init(&scene, n)) return 1;
    const double cells = scene.cells, ref_rate = scene.ref_rate, *h = scene.h;

    const int substeps = n <= 512 ? 400 : n <= 2048 ? 40 : 12;
    double best[kScenes][2], slowest[kScenes][2], cost_lo[kScenes][2], cost_hi[kScenes][2];
    for (int run = 0; run < runs; ++run)
        for (int threads = 1; threads <= 2; ++threads) {
            double plain = NAN;
            for (int k = 0; k < kScenes; ++k) {
                if (!chosen[k]) continue;
                double updates;
                const double t = seconds_per_substep_of(n, h, threads, substeps, scenes[k].setup, &updates);
                if (k == 0) plain = t;
                double *b = &best[k][threads - 1], *w = &slowest[k][threads - 1];
                double *lo = &cost_lo[k][threads - 1], *hi = &cost_hi[k][threads - 1];
                *b = run == 0 ? t : fmin(*b, t);
                *w = run == 0 ? t : fmax(*w, t);
                *lo = run == 0 ? t / plain : fmin(*lo, t / plain);
                *hi = run == 0 ? t / plain : fmax(*hi, t / plain);
            }
        }
    const char *scalar = getenv("DPSM_SCALAR_PHYSICS");
    const char *kernel = scalar && *scalar && *scalar != '0' ? "scalar" : "vector";
    printf("n,scene,threads,physics_kernel,mcells_per_s,slowest_mcells_per_s,cost_vs_plain,cost_vs_plain_lo,"
           "cost_vs_plain_hi,reference_mcells_per_s,ratio_to_reference\n");
    for (int threads = 1; threads <= 2; ++threads)
        for (int k = 0; k < kScenes; ++k) {
            const int t = threads - 1;
            if (!chosen[k]) continue;
            const double rate = cells / best[k][t];
            printf("%lld,%s,%d,%s,%.1f,%.1f,%.3f,%.3f,%.3f,%.1f,%.2f\n", (long long)n, scenes[k].name, threads,
                   k == 0 ? "none" : kernel, rate / 1e6, cells / slowest[k][t] / 1e6,
                   chosen[0] ? best[k][t] / best[0][t] : NAN,
                   cost_lo[k][t], cost_hi[k][t], ref_rate / 1e6, rate / ref_rate);
        }
    active_scene_free(&scene);
    return 0;
}
