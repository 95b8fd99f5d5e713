/* The thread rule of dpsm.h: a handle is used by one thread at a time, any
 * number of handles may be used at once. Four threads each drive their own
 * grid (2D isotropic and pairwise with dpsm_set_threads(g, 2), so that the
 * OpenMP sweep runs inside each of them; 1D; axisymmetric) through the same
 * scene as a serial reference run on one thread, and must end bit-identical to
 * it (results do not depend on threads). Meanwhile each thread makes calls
 * fail on its own handle and without one, and checks that it reads back its
 * own message (per handle, and per thread for dpsm_last_error(NULL)).
 *
 * Built also under ThreadSanitizer (scripts/sanitize tsan). CMocka's
 * assertions are not thread safe: workers record what went wrong and the main
 * thread checks it. */
#include <math.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include <dpsm/dpsm.h>

#define NTHREADS 4

typedef struct {
    int id;       /* which scene */
    int threads;  /* dpsm_set_threads */
    int rounds;   /* repetitions of the error checks */
    int64_t nx, ny, n;
    double *h;    /* final heights */
    double mass[4];
    double substeps; /* of the last step */
    char error[512]; /* empty: all went well */
    pthread_barrier_t *barrier;
    int waits; /* barrier waits so far: a job that fails early still makes them all */
} job_t;

static const char *const kSceneNames[NTHREADS] = {"2D isotropic 150x130", "2D pairwise 140x90, masks",
                                                  "1D 4000", "axisymmetric 3000"};

static uint64_t rng_next(uint64_t *state) {
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static double rng_uniform(uint64_t *state) { return (double)(rng_next(state) >> 11) * (1.0 / 9007199254740992.0); }

static void job_fail(job_t *job, const char *fmt, ...) {
    if (job->error[0]) return; /* keep the first */
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(job->error, sizeof job->error, fmt, ap);
    va_end(ap);
}

#define JOB_OK(job, g, call)                                                                                 \
    do {                                                                                                     \
        const int st_ = (call);                                                                              \
        if (st_ != DPSM_OK) {                                                                                \
            job_fail((job), "%s: %s returned %s: %s", kSceneNames[(job)->id], #call, dpsm_status_string(st_), \
                     dpsm_last_error(g));                                                                    \
            goto done;                                                                                       \
        }                                                                                                    \
    } while (0)

/* A failing call on the handle, and a failing create without one, with a
 * message particular to this thread: each must read back its own. */
static void check_own_errors(job_t *job, dpsm_grid *g, int round) {
    char want[64];
    const double bad_mobility = -(double)(1000 * job->id + round + 1);
    if (dpsm_set_mobility(g, bad_mobility) != DPSM_ERR_INVALID_VALUE)
        job_fail(job, "%s: dpsm_set_mobility(%g) did not fail", kSceneNames[job->id], bad_mobility);
    const int64_t bad_nx = -(int64_t)(1000 * job->id + round + 7);
    dpsm_grid *none = NULL;
    if (dpsm_create_1d(bad_nx, 1.0, &none) != DPSM_ERR_INVALID_SIZE || none != NULL)
        job_fail(job, "dpsm_create_1d(%lld) did not fail", (long long)bad_nx);
    if (job->barrier) {
        pthread_barrier_wait(job->barrier); /* every thread has failed its calls */
        ++job->waits;
    }
    snprintf(want, sizeof want, "nu = %g ", bad_mobility);
    if (!strstr(dpsm_last_error(g), want))
        job_fail(job, "%s: the handle's message is \"%s\", not about \"%s\"", kSceneNames[job->id], dpsm_last_error(g),
                 want);
    snprintf(want, sizeof want, "nx = %lld ", (long long)bad_nx);
    if (!strstr(dpsm_last_error(NULL), want))
        job_fail(job, "%s: this thread's message is \"%s\", not about \"%s\"", kSceneNames[job->id],
                 dpsm_last_error(NULL), want);
    if (job->barrier) {
        pthread_barrier_wait(job->barrier); /* every thread has read its messages */
        ++job->waits;
    }
}

/* The scenes: a collapse over a rough bed, steps with a source, steps without. */
static void *run_job(void *arg) {
    job_t *job = arg;
    dpsm_grid *g = NULL;
    double *h = NULL, *q = NULL;
    uint8_t *kinds = NULL;
    uint64_t r = 2024u + (uint64_t)job->id;
    int st;
    switch (job->id) {
        case 0: st = dpsm_create_2d(150, 130, 1.0, 1.0, &g); break;
        case 1: st = dpsm_create_2d(140, 90, 0.5, 0.7, &g); break;
        case 2: st = dpsm_create_1d(4000, 0.1, &g); break;
        default: st = dpsm_create_axisymmetric(3000, 0.1, &g); break;
    }
    if (st != DPSM_OK) {
        job_fail(job, "%s: create: %s", kSceneNames[job->id], dpsm_last_error(NULL));
        goto done;
    }
    JOB_OK(job, g, dpsm_get_shape(g, &job->nx, &job->ny));
    job->n = job->nx * job->ny;
    h = malloc(sizeof(double) * (size_t)job->n);
    q = malloc(sizeof(double) * (size_t)job->n);
    kinds = calloc((size_t)job->n, 1);
    if (!h || !q || !kinds) {
        job_fail(job, "out of memory");
        goto done;
    }
    JOB_OK(job, g, dpsm_set_threads(g, job->threads));
    if (job->id == 1) JOB_OK(job, g, dpsm_set_scheme(g, DPSM_SCHEME_PAIRWISE));
    JOB_OK(job, g, dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN));
    for (int64_t c = 0; c < job->n; ++c) {
        const int64_t i = c % job->nx, j = c / job->nx;
        const double x = (double)i / (double)job->nx, y = (double)j / (double)job->ny;
        h[c] = 0.5 * rng_uniform(&r) + ((fabs(x - 0.4) < 0.15 && fabs(y - 0.5) < 0.2) ? 6.0 : 0.0);
        q[c] = (i + j) % 7 == 0 ? 0.01 : 0.0;
        if (job->id == 1 && rng_uniform(&r) < 0.05) kinds[c] = rng_uniform(&r) < 0.5 ? DPSM_CELL_WALL : DPSM_CELL_OPEN;
        if (kinds[c] == DPSM_CELL_OPEN) h[c] = 0.0; /* sinks at the level of the open side: rest is possible */
    }
    JOB_OK(job, g, dpsm_set_heights(g, h));
    JOB_OK(job, g, dpsm_set_cell_kinds(g, kinds));
    for (int k = 0; k < 6; ++k) JOB_OK(job, g, dpsm_step(g, 0.7));
    for (int round = 0; round < job->rounds; ++round) check_own_errors(job, g, round);
    JOB_OK(job, g, dpsm_set_source(g, q));
    for (int k = 0; k < 6; ++k) JOB_OK(job, g, dpsm_step(g, 0.3));
    JOB_OK(job, g, dpsm_set_source(g, NULL));
    for (int k = 0; k < 4; ++k) JOB_OK(job, g, dpsm_step(g, 5.0));
    JOB_OK(job, g, dpsm_get_heights(g, h));
    for (int m = 0; m < 4; ++m) JOB_OK(job, g, dpsm_get_mass(g, m, &job->mass[m]));
    JOB_OK(job, g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &job->substeps));
    job->h = h;
    h = NULL;
done:
    while (job->barrier && job->waits < 2 * job->rounds) { /* do not leave the others waiting */
        pthread_barrier_wait(job->barrier);
        ++job->waits;
    }
    free(h);
    free(q);
    free(kinds);
    dpsm_destroy(g);
    return NULL;
}

/* Many small grids created, stepped and destroyed by every thread at once. */
static void *churn(void *arg) {
    job_t *job = arg;
    uint64_t r = 77u + (uint64_t)job->id;
    for (int k = 0; k < 200 && !job->error[0]; ++k) {
        dpsm_grid *g = NULL;
        const int64_t nx = 1 + (int64_t)(rng_next(&r) % 70), ny = 1 + (int64_t)(rng_next(&r) % 70);
        const int st = k % 3 == 0 ? dpsm_create_1d(nx, 1.0, &g)
                       : k % 3 == 1 ? dpsm_create_2d(nx, ny, 1.0, 1.0, &g)
                                    : dpsm_create_axisymmetric(nx, 1.0, &g);
        if (st != DPSM_OK) {
            job_fail(job, "churn: create: %s", dpsm_last_error(NULL));
            return NULL;
        }
        int64_t sx, sy;
        if (dpsm_get_shape(g, &sx, &sy) != DPSM_OK) job_fail(job, "churn: get_shape: %s", dpsm_last_error(g));
        double *h = calloc((size_t)(sx * sy), sizeof(double));
        if (!h) {
            job_fail(job, "out of memory");
            dpsm_destroy(g);
            return NULL;
        }
        h[(sx * sy) / 2] = 10.0;
        if (dpsm_set_threads(g, 1 + k % 2) != DPSM_OK || dpsm_set_heights(g, h) != DPSM_OK ||
            dpsm_step(g, 5.0) != DPSM_OK || dpsm_get_heights(g, h) != DPSM_OK)
            job_fail(job, "churn: %s", dpsm_last_error(g));
        free(h);
        dpsm_destroy(g);
    }
    return NULL;
}

static void free_jobs(job_t *jobs, int n) {
    for (int k = 0; k < n; ++k) free(jobs[k].h);
}

/* The four scenes on four threads at once (twice, with the scenes swapped
 * among threads), each against its serial reference. */
static void test_four_grids_four_threads(void **state) {
    (void)state;
    job_t ref[NTHREADS];
    memset(ref, 0, sizeof ref);
    for (int k = 0; k < NTHREADS; ++k) {
        ref[k].id = k;
        ref[k].threads = 1;
        ref[k].rounds = 1;
        run_job(&ref[k]);
        if (ref[k].error[0]) fail_msg("serial reference: %s", ref[k].error);
    }
    for (int pass = 0; pass < 2; ++pass) {
        pthread_barrier_t barrier;
        assert_int_equal(pthread_barrier_init(&barrier, NULL, NTHREADS), 0);
        job_t jobs[NTHREADS];
        pthread_t tid[NTHREADS];
        memset(jobs, 0, sizeof jobs);
        for (int t = 0; t < NTHREADS; ++t) {
            jobs[t].id = (t + pass) % NTHREADS;
            jobs[t].threads = 2;
            jobs[t].rounds = 3;
            jobs[t].barrier = &barrier;
            assert_int_equal(pthread_create(&tid[t], NULL, run_job, &jobs[t]), 0);
        }
        for (int t = 0; t < NTHREADS; ++t) assert_int_equal(pthread_join(tid[t], NULL), 0);
        pthread_barrier_destroy(&barrier);
        for (int t = 0; t < NTHREADS; ++t) {
            const job_t *got = &jobs[t], *want = &ref[jobs[t].id];
            if (got->error[0]) fail_msg("thread %d: %s", t, got->error);
            assert_non_null(got->h);
            assert_true(got->n == want->n);
            int64_t differ = 0, first = -1;
            for (int64_t c = 0; c < got->n; ++c)
                if (memcmp(&got->h[c], &want->h[c], sizeof(double)) != 0) {
                    if (first < 0) first = c;
                    ++differ;
                }
            if (differ)
                fail_msg("%s on thread %d (2 OpenMP threads): %lld heights differ from the serial run, the first at "
                         "cell %lld: %.17g vs %.17g",
                         kSceneNames[got->id], t, (long long)differ, (long long)first, got->h[first],
                         want->h[first]);
            assert_memory_equal(got->mass, want->mass, sizeof got->mass);
            print_message("pass %d, thread %d, %-26s bit-identical to the serial run (%g sub-steps in its last step)\n",
                          pass, t, kSceneNames[got->id], got->substeps);
        }
        free_jobs(jobs, NTHREADS);
    }
    free_jobs(ref, NTHREADS);
}

static void test_create_and_destroy_from_four_threads(void **state) {
    (void)state;
    job_t jobs[NTHREADS];
    pthread_t tid[NTHREADS];
    memset(jobs, 0, sizeof jobs);
    for (int t = 0; t < NTHREADS; ++t) {
        jobs[t].id = t;
        assert_int_equal(pthread_create(&tid[t], NULL, churn, &jobs[t]), 0);
    }
    for (int t = 0; t < NTHREADS; ++t) assert_int_equal(pthread_join(tid[t], NULL), 0);
    for (int t = 0; t < NTHREADS; ++t)
        if (jobs[t].error[0]) fail_msg("thread %d: %s", t, jobs[t].error);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_four_grids_four_threads),
        cmocka_unit_test(test_create_and_destroy_from_four_threads),
    };
    return cmocka_run_group_tests_name("threads", tests, NULL, NULL);
}
