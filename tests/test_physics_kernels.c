/* The physics of real scenes on the vectorised tile kernels against the
 * scalar reference kernel (src/structured/tile_kernel_physics.cpp, the specification),
 * which DPSM_SCALAR_PHYSICS=1 chooses; the library reads it at every sweep,
 * so one process steps the same scene both ways. Each feature alone and in
 * combinations, on scenes with walls, open cells, open sides, deposition and
 * erosion beyond the sand, both schemes: heights agree to round-off, and so
 * do the ledger and the step's figures. The vectorised results also stay the
 * same bit for bit whatever the threads, the active set and whether tiles are
 * read and written in place. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "test_support.h"

static const double kDeg = 3.14159265358979323846 / 180.0;

enum { NX = 150, NY = 100, CELLS = NX * NY }; /* 3 x 2 tiles, edges and interiors */

/* What a scene uses. */
enum { BED = 1, ANGLE_FIELD = 2, EXPONENT = 4, STATIC_ANGLE = 8 };

typedef struct {
    const char *name;
    int features;
    double exponent; /* with EXPONENT */
} features_t;

/* What a run ends with. */
typedef struct {
    double h[CELLS];
    ledger_t ledger;
    double unmet, substeps, at_rest, max_excess;
} outcome_t;

/* Sets an environment switch of the library, or clears it. */
static void switch_to(const char *variable, int on) {
    if (on)
        setenv(variable, "1", 1);
    else
        unsetenv(variable);
}

/* A slope over a bed (thin sand on part of it, so that caps bind and cells
 * drain), two piles, a ramp between the angle of repose and the static angle,
 * a wall block, a patch of open cells, open sides at the low end and the top;
 * deposition on a pile and erosion that asks more than the sand holds; then
 * the sources stop and the scene relaxes. */
static void run_scene(const features_t *f, int scheme, int threads, outcome_t *out) {
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(NX, NY, 0.5, 0.5, &g));
    CHECK_OK(g, dpsm_set_scheme(g, scheme));
    CHECK_OK(g, dpsm_set_threads(g, threads));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMIN, DPSM_OPEN));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_YMAX, DPSM_OPEN));
    static double h[CELLS], zb[CELLS], theta[CELLS], q[CELLS];
    static uint8_t kinds[CELLS];
    for (int j = 0; j < NY; ++j)
        for (int i = 0; i < NX; ++i) {
            const int c = i + NX * j;
            zb[c] = 0.2 * i * 0.5 + 0.05 * sin(0.3 * j);
            const double sand = i < 75 ? 0.02 + 0.01 * sin(0.9 * i + 0.4 * j) : 0.4; /* thin at the low end */
            h[c] = zb[c] + sand + (abs(i - 40) < 6 && abs(j - 50) < 6 ? 3.0 : 0.0) +
                   (abs(i - 110) < 5 && abs(j - 25) < 5 ? 2.5 : 0.0);
            /* A ramp at 31.4 degrees (0.41 + the bed's 0.2), which only the
             * static angle holds, cut off by a cliff at j = 20. */
            if (j < 20 && i >= 80) h[c] += 0.41 * 0.5 * (i < 100 ? i - 80 : 20);
            theta[c] = (j < 50 ? 30.0 : 36.0) * kDeg + 2.0 * kDeg * sin(0.37 * i + 0.11 * j);
            kinds[c] = DPSM_CELL_SAND;
            if (i >= 60 && i < 66 && j >= 30 && j < 42) kinds[c] = DPSM_CELL_WALL;
            if (i >= 120 && i < 124 && j >= 70 && j < 73) kinds[c] = DPSM_CELL_OPEN;
            q[c] = 0.0;
            if (abs(i - 20) < 3 && abs(j - 80) < 3) q[c] = -0.5; /* far more than the thin sand there */
            if (abs(i - 110) < 2 && abs(j - 25) < 2) q[c] = 0.05;
        }
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_cell_kinds(g, kinds));
    if (f->features & BED) CHECK_OK(g, dpsm_set_bedrock(g, zb));
    if (f->features & ANGLE_FIELD) CHECK_OK(g, dpsm_set_repose_angle_field(g, theta));
    if (f->features & EXPONENT) CHECK_OK(g, dpsm_set_flux_exponent(g, f->exponent));
    if (f->features & STATIC_ANGLE) CHECK_OK(g, dpsm_set_static_angle(g, 33.0 * kDeg));
    CHECK_OK(g, dpsm_set_rest_tolerance(g, 1e-3)); /* p > 1 rests in bounded time */
    CHECK_OK(g, dpsm_set_source(g, q));
    for (int n = 0; n < 6; ++n) CHECK_OK(g, dpsm_step(g, 0.7));
    CHECK_OK(g, dpsm_set_source(g, NULL));
    for (int n = 0; n < 4; ++n) CHECK_OK(g, dpsm_step(g, 3.0));
    CHECK_OK(g, dpsm_get_heights(g, out->h));
    out->ledger = read_ledger(g);
    out->unmet = mass_of(g, DPSM_MASS_UNMET);
    out->substeps = step_info_of(g, DPSM_INFO_SUBSTEPS);
    out->at_rest = step_info_of(g, DPSM_INFO_AT_REST);
    out->max_excess = step_info_of(g, DPSM_INFO_MAX_EXCESS_SLOPE);
    REQUIRE(ledger_residual(g) < 1e-12, "%s: ledger residual %.3g", f->name, ledger_residual(g));
    if (f->features & BED)
        for (int c = 0; c < CELLS; ++c)
            REQUIRE(out->h[c] >= zb[c], "%s: cell %d at %.17g below its bed %.17g", f->name, c, out->h[c], zb[c]);
    dpsm_destroy(g);
}

static double relative_difference(double a, double b) { return fabs(a - b) / fmax(1.0, fmax(fabs(a), fabs(b))); }

/* The bound of agreement (relative, of heights O(1) to O(10) and of the
 * ledger's figures, after some hundreds of sub-steps). The kernels differ in
 * the last bits of a face's flux (the order of operations, the exponent's
 * power in lanes): 4e-16 seen. The AVX-512 kernels also take 1/sqrt(1 +
 * |grad h|^2) from a hardware estimate refined to 6e-9 (src/structured/simd.hpp), which
 * a steep face's flux carries: 1.2e-9 seen. The library runs them where the
 * CPU has AVX-512 (F, BW, VL, DQ) unless DPSM_NO_AVX512=1. A face on its
 * threshold would tell the kernels apart by a dead-zone decision; none of
 * these scenes' faces is. */
static double agreement_bound(void) {
    const char *ruled_out = getenv("DPSM_NO_AVX512");
    int estimate = !(ruled_out && *ruled_out && *ruled_out != '0');
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    __builtin_cpu_init();
    estimate = estimate && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
               __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq");
#else
    estimate = 1; /* whatever the CPU */
#endif
    return estimate ? 1e-8 : 1e-14;
}

/* Steps the scene on the vectorised and on the scalar kernel and compares. */
static void compare_kernels(const features_t *f, int scheme, int threads) {
    outcome_t *fast = malloc(sizeof *fast), *scalar = malloc(sizeof *scalar);
    switch_to("DPSM_SCALAR_PHYSICS", 0);
    run_scene(f, scheme, threads, fast);
    switch_to("DPSM_SCALAR_PHYSICS", 1);
    run_scene(f, scheme, threads, scalar);
    switch_to("DPSM_SCALAR_PHYSICS", 0);
    double worst = 0.0;
    int where = 0;
    for (int c = 0; c < CELLS; ++c) {
        const double d = relative_difference(fast->h[c], scalar->h[c]);
        if (d > worst) worst = d, where = c;
    }
    const double total = relative_difference(fast->ledger.total, scalar->ledger.total);
    const double sourced = relative_difference(fast->ledger.sourced, scalar->ledger.sourced);
    const double outflow = relative_difference(fast->ledger.outflow, scalar->ledger.outflow);
    const double unmet = relative_difference(fast->unmet, scalar->unmet);
    const double excess = relative_difference(fast->max_excess, scalar->max_excess);
    printf("%-28s %s, %d thread%s: heights within %.2e (cell %d), total %.1e, sourced %.1e, outflow %.1e, unmet %.1e "
           "(%.4g), %g sub-steps, largest excess %.1e\n",
           f->name, scheme == DPSM_SCHEME_ISOTROPIC ? "isotropic" : "pairwise ", threads, threads > 1 ? "s" : " ",
           worst, where, total, sourced, outflow, unmet, fast->unmet, fast->substeps, excess);
    const double bound = agreement_bound();
    REQUIRE(worst < bound, "%s: heights differ by %.3g at cell %d (%.17g vs %.17g)", f->name, worst, where,
            fast->h[where], scalar->h[where]);
    REQUIRE(total < bound && sourced < bound && outflow < bound && unmet < bound,
            "%s: ledgers differ: total %.3g, sourced %.3g, outflow %.3g, unmet %.3g", f->name, total, sourced, outflow,
            unmet);
    REQUIRE(fast->substeps == scalar->substeps && fast->at_rest == scalar->at_rest,
            "%s: %g sub-steps (at rest %g) vs %g (%g)", f->name, fast->substeps, fast->at_rest, scalar->substeps,
            scalar->at_rest);
    REQUIRE(excess < bound, "%s: largest excess %.17g vs %.17g", f->name, fast->max_excess, scalar->max_excess);
    if (f->features & BED) REQUIRE(fast->unmet > 0.0, "%s: the erosion must find bare rock", f->name);
    free(fast);
    free(scalar);
}

static const features_t kAlone[] = {
    {"bed", BED, 1.0},
    {"angle field", ANGLE_FIELD, 1.0},
    {"exponent 1.5", EXPONENT, 1.5},
    {"exponent 2", EXPONENT, 2.0},
    {"exponent 1.25", EXPONENT, 1.25},
    {"static angle", STATIC_ANGLE, 1.0},
};

static const features_t kTogether[] = {
    {"bed + angle field", BED | ANGLE_FIELD, 1.0},
    {"bed + exponent 1.5", BED | EXPONENT, 1.5},
    {"bed + static angle", BED | STATIC_ANGLE, 1.0},
    {"angle field + static angle", ANGLE_FIELD | STATIC_ANGLE, 1.0},
    {"angle field + exponent 2", ANGLE_FIELD | EXPONENT, 2.0},
    {"everything, exponent 1.25", BED | ANGLE_FIELD | EXPONENT | STATIC_ANGLE, 1.25},
};

static void test_each_feature_matches_the_scalar_kernel(void **state) {
    (void)state;
    for (size_t k = 0; k < sizeof kAlone / sizeof *kAlone; ++k)
        for (int scheme = DPSM_SCHEME_PAIRWISE; scheme <= DPSM_SCHEME_ISOTROPIC; ++scheme)
            compare_kernels(&kAlone[k], scheme, 1);
}

static void test_features_together_match_the_scalar_kernel(void **state) {
    (void)state;
    for (size_t k = 0; k < sizeof kTogether / sizeof *kTogether; ++k)
        for (int scheme = DPSM_SCHEME_PAIRWISE; scheme <= DPSM_SCHEME_ISOTROPIC; ++scheme)
            compare_kernels(&kTogether[k], scheme, 1);
}

/* On two threads the tiles are shared out, and still each path computes what it did on one. */
static void test_two_threads_match_the_scalar_kernel(void **state) {
    (void)state;
    compare_kernels(&kAlone[0], DPSM_SCHEME_ISOTROPIC, 2);
    compare_kernels(&kTogether[5], DPSM_SCHEME_ISOTROPIC, 2);
}

/* The vectorised kernels compute every face by the same arithmetic whether a
 * tile is masked or not, read and written in place or copied, visited whole
 * or in part: the heights are the same bit for bit on 1 and 2 threads, with
 * every tile visited (DPSM_VISIT_ALL_TILES=1) and every tile copied
 * (DPSM_COPY_TILES=1). The bed alone (a kernel of its own) and everything. */
static void test_vectorised_physics_independent_of_sweep(void **state) {
    (void)state;
    const features_t *scenes[] = {&kAlone[0], &kTogether[5]};
    const struct {
        int threads, visit_all, copy_tiles;
    } ways[] = {{2, 0, 0}, {1, 1, 0}, {1, 0, 1}, {2, 1, 1}};
    outcome_t *reference = malloc(sizeof *reference), *other = malloc(sizeof *other);
    for (size_t s = 0; s < sizeof scenes / sizeof *scenes; ++s) {
        run_scene(scenes[s], DPSM_SCHEME_ISOTROPIC, 1, reference);
        for (size_t k = 0; k < sizeof ways / sizeof *ways; ++k) {
            switch_to("DPSM_VISIT_ALL_TILES", ways[k].visit_all);
            switch_to("DPSM_COPY_TILES", ways[k].copy_tiles);
            run_scene(scenes[s], DPSM_SCHEME_ISOTROPIC, ways[k].threads, other);
            switch_to("DPSM_VISIT_ALL_TILES", 0);
            switch_to("DPSM_COPY_TILES", 0);
            REQUIRE(memcmp(other->h, reference->h, sizeof other->h) == 0,
                    "%s, threads %d, visit all %d, copy tiles %d: heights differ", scenes[s]->name, ways[k].threads,
                    ways[k].visit_all, ways[k].copy_tiles);
            REQUIRE(other->unmet == reference->unmet && other->ledger.outflow == reference->ledger.outflow &&
                        other->ledger.sourced == reference->ledger.sourced,
                    "%s, threads %d, visit all %d, copy tiles %d: ledgers differ", scenes[s]->name, ways[k].threads,
                    ways[k].visit_all, ways[k].copy_tiles);
        }
    }
    free(reference);
    free(other);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_each_feature_matches_the_scalar_kernel),
        cmocka_unit_test(test_features_together_match_the_scalar_kernel),
        cmocka_unit_test(test_two_threads_match_the_scalar_kernel),
        cmocka_unit_test(test_vectorised_physics_independent_of_sweep),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
