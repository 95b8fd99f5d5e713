/* The speed benchmarks of dpsm-bench: throughput, sparse, idle, cone. Each
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
static void steep_surface(double *h, int64_t n) {
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

/* Seconds per sub-step of dpsm on a fully active n x n surface. */
static double dpsm_seconds_per_substep(int64_t n, const double *h, int threads, int substeps, double *updates) {
    dpsm_grid *g = open_table(n, h, threads);
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

int cmd_throughput(int argc, char **argv) {
    int64_t sizes[8] = {512, 2048, 4096};
    int count = 3;
    if (argc > 0) {
        count = 0;
        for (int k = 0; k < argc && count < 8; ++k) sizes[count++] = atoll(argv[k]);
    }
    printf("n,threads,mcells_per_s,reference_mcells_per_s,ratio,vectorised_mcells_per_s\n");
    for (int k = 0; k < count; ++k) {
        const int64_t n = sizes[k];
        const double cells = (double)n * (double)n;
        double *h = xcalloc((size_t)(n * n), sizeof(double));
        steep_surface(h, n);
        /* The reference: a few sub-steps, and a check that it computes what dpsm does. */
        reference_grid ref;
        if (!reference_init(&ref, n, n, 1.0, 1.0, 1.0, kTheta, DPSM_DEFAULT_REST_TOLERANCE, h)) return 1;
        dpsm_grid *g = open_table(n, h, 0);
        double dt;
        CHECK(g, dpsm_stable_dt(g, &dt));
        const int ref_steps = n <= 512 ? 20 : n <= 2048 ? 3 : 2;
        const double t0 = now_seconds();
        for (int s = 0; s < ref_steps; ++s) reference_substep(&ref, dt);
        const double ref_rate = cells * ref_steps / (now_seconds() - t0);
        CHECK(g, dpsm_step(g, ref_steps * dt));
        double *got = xcalloc((size_t)(n * n), sizeof(double)), worst = 0.0;
        CHECK(g, dpsm_get_heights(g, got));
        for (int64_t j = 0; j < n; ++j)
            for (int64_t i = 0; i < n; ++i)
                worst = fmax(worst, fabs(got[i + n * j] - reference_height(&ref, i, j)) /
                                        fmax(1.0, fabs(reference_height(&ref, i, j))));
        fprintf(stderr, "n = %lld: dpsm and the reference differ by at most %.2e (relative) after %d sub-steps\n",
                (long long)n, worst, ref_steps);
        free(got);
        dpsm_destroy(g);

        const int substeps = n <= 512 ? 400 : n <= 2048 ? 40 : 12;
        double vectorised[2], difference = 0.0;
        for (int threads = 1; threads <= 2; ++threads)
            vectorised[threads - 1] = vectorised_mcells_per_s(n, h, kTheta, DPSM_DEFAULT_REST_TOLERANCE, dt, threads,
                                                              substeps, &ref, ref_steps, &difference);
        fprintf(stderr, "n = %lld: the vectorised loop and the reference differ by at most %.2e (relative) after %d "
                "sub-steps, away from the edges\n", (long long)n, difference, ref_steps);
        reference_free(&ref);

        for (int threads = 1; threads <= 2; ++threads) {
            double updates;
            const double per_substep = dpsm_seconds_per_substep(n, h, threads, substeps, &updates);
            const double rate = cells / per_substep;
            printf("%lld,%d,%.1f,%.1f,%.2f,%.1f\n", (long long)n, threads, rate / 1e6, ref_rate / 1e6, rate / ref_rate,
                   vectorised[threads - 1]);
            fflush(stdout);
        }
        free(h);
    }
    return 0;
}

/* A dune field at rest between walls: long gentle ripples below the angle of repose. */
static void dune_bed(double *h, int64_t n) {
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i)
            h[i + n * j] = 3.0 + 2.0 * sin(2.0 * kPi * (double)i / 400.0) * cos(2.0 * kPi * (double)j / 700.0);
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
    const int64_t face_w = 40, face_h = 24;
    const int64_t faces = (int64_t)(target * cells / (double)(face_w * face_h));
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
                    const double lee = 1.15 * tan(kTheta) * (double)(i0 + face_w - i); /* steep ramp down in +x */
                    h[i + n * j] += lee;
                    if (i < i0 + 3) q[i + n * j] = 0.2; /* the brink */
                }
        }
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
    printf("%lld,%.4f,%.4f,%.3e,%.3e,%.4f\n", (long long)n, (double)placed * face_w * face_h / cells,
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
 * grow), time-accurate and by the default
 * (DPSM_RELAX_AUTO, which relaxes this scene to rest). Prints the seconds
 * (best of three), the sub-steps or flux evaluations and the cells computed,
 * and how far the two deposits end apart (L1, of the deposited volume). */
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
    const int relaxations[2] = {DPSM_RELAX_TIME_ACCURATE, DPSM_RELAX_AUTO};
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
        printf("%s,%lld,%d,%d,%.4f,%.0f,%.4g\n", k ? "dpsm-auto" : "dpsm-time-accurate", (long long)n, count, rounds,
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

    /* dpsm's time-accurate sub-steps, then its fast relaxation to rest (what
     * the default does here); the best of three runs, and of fast_runs (10) for the
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
