/* The speed machinery changes no result: the active set (tiles skipped when
 * nothing near them can move), the number of threads, tiles read and written
 * in place, and region updates give the same heights and ledger, bit for bit,
 * as visiting every tile on one thread, through a buffer. Work is measured with DPSM_INFO_CELL_UPDATES, never with a clock. */
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

enum { NX = 260, NY = 140 };

/* DPSM_VISIT_ALL_TILES=1 makes the library visit every tile whole: the
 * reference the active set is compared with. */
static void visit_all_tiles(int on) {
    if (on)
        setenv("DPSM_VISIT_ALL_TILES", "1", 1);
    else
        unsetenv("DPSM_VISIT_ALL_TILES");
}

/* A scene that uses everything: a resting rough bed, three steep patches far
 * apart, a source patch, an obstacle, an open cell and two open sides. Its
 * steps are time-accurate while the source acts; once it is off, the last
 * step takes `relaxation` (DPSM_RELAX_TO_REST relaxes the isotropic scheme
 * to rest, and the pairwise scheme, which it refuses, is left time-accurate). */
static dpsm_grid *make_scene(int scheme, int threads) {
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(NX, NY, 0.5, 0.5, &g));
    CHECK_OK(g, dpsm_set_scheme(g, scheme));
    CHECK_OK(g, dpsm_set_threads(g, threads));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMIN, DPSM_OPEN));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_YMAX, DPSM_OPEN));
    double *h = malloc(sizeof(double) * NX * NY), *q = calloc(NX * NY, sizeof(double));
    uint8_t *kinds = calloc(NX * NY, 1);
    for (int j = 0; j < NY; ++j)
        for (int i = 0; i < NX; ++i) {
            double v = 0.1 + 0.1 * sin(0.05 * i) * cos(0.07 * j); /* gentle: at rest */
            if (abs(i - 40) < 4 && abs(j - 50) < 4) v += 3.0;     /* steep patches */
            if (abs(i - 200) < 3 && abs(j - 110) < 5) v += 2.0;
            if (abs(i - 240) < 2 && abs(j - 30) < 2) v += 4.0;
            h[i + NX * j] = v;
            if (abs(i - 120) < 4 && abs(j - 100) < 4) q[i + NX * j] = 0.3;
            if (i >= 150 && i < 160 && j >= 40 && j < 100) kinds[i + NX * j] = DPSM_CELL_WALL;
        }
    kinds[203 + NX * 110] = DPSM_CELL_OPEN;
    h[203 + NX * 110] = 0.0; /* a sink at the open sides' level: the scene comes to rest */
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_cell_kinds(g, kinds));
    CHECK_OK(g, dpsm_set_source(g, q));
    free(h);
    free(q);
    free(kinds);
    return g;
}

/* Runs the scene: steps, then the source off and a region edit, then rest.
 * Returns the heights (caller frees) and the ledger and the work done. */
static double *run_scene(int scheme, int relaxation, int threads, int visit_all, ledger_t *ledger,
                         double *updates) {
    visit_all_tiles(visit_all);
    dpsm_grid *g = make_scene(scheme, threads);
    double u, dt;
    *updates = 0.0;
    CHECK_OK(g, dpsm_stable_dt(g, &dt));
    for (int k = 0; k < 10; ++k) {
        CHECK_OK(g, dpsm_step(g, 7.3 * dt));
        CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &u));
        *updates += u;
    }
    CHECK_OK(g, dpsm_set_source(g, NULL));
    const double bump[6] = {3.0, 4.0, 3.5, 2.0, 5.0, 1.0};
    CHECK_OK(g, dpsm_add_heights_region(g, 250, 136, 3, 2, bump));
    if (scheme == DPSM_SCHEME_ISOTROPIC) CHECK_OK(g, dpsm_set_relaxation(g, relaxation));
    CHECK_OK(g, dpsm_step(g, 1e6));
    CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &u));
    *updates += u;
    double *h = malloc(sizeof(double) * NX * NY);
    CHECK_OK(g, dpsm_get_heights(g, h));
    *ledger = read_ledger(g);
    assert_true(ledger_residual(g) < 1e-13);
    dpsm_destroy(g);
    visit_all_tiles(0);
    return h;
}

static void assert_same_run(const double *a, const double *b, size_t cells, const ledger_t *la, const ledger_t *lb) {
    size_t differ = 0;
    for (size_t c = 0; c < cells; ++c) differ += memcmp(&a[c], &b[c], sizeof(double)) != 0;
    assert_int_equal(differ, 0);
    assert_memory_equal(la, lb, sizeof *la);
}

static const int kRelaxations[2] = {DPSM_RELAX_TIME_ACCURATE, DPSM_RELAX_TO_REST};

static void test_active_set_changes_no_result(void **state) {
    (void)state;
    for (int r = 0; r < 2; ++r)
    for (int scheme = DPSM_SCHEME_PAIRWISE; scheme <= DPSM_SCHEME_ISOTROPIC; ++scheme) {
        ledger_t skip, all;
        double work_skip, work_all;
        double *a = run_scene(scheme, kRelaxations[r], 1, 0, &skip, &work_skip);
        double *b = run_scene(scheme, kRelaxations[r], 1, 1, &all, &work_all);
        print_message("%s, %s: cell updates %.3g with the active set, %.3g visiting every tile (%.1f%%); outflow "
                      "%.6f\n",
                      scheme ? "isotropic" : "pairwise", r ? "to rest at the end" : "time-accurate", work_skip, work_all,
                      100.0 * work_skip / work_all, skip.outflow);
        assert_same_run(a, b, (size_t)NX * NY, &skip, &all);
        assert_true(work_skip < 0.5 * work_all); /* it did skip */
        assert_true(skip.outflow > 0.0);         /* the open side and cell took sand */
        free(a);
        free(b);
    }
}

/* Every tile visited, so that each sweep has enough cells (8 tiles' worth) for
 * the library to share it among threads. */
static void test_results_do_not_depend_on_threads(void **state) {
    (void)state;
    for (int r = 0; r < 2; ++r) {
        ledger_t l1, l2, l3;
        double w1, w2, w3;
        double *a = run_scene(DPSM_SCHEME_ISOTROPIC, kRelaxations[r], 1, 1, &l1, &w1);
        double *b = run_scene(DPSM_SCHEME_ISOTROPIC, kRelaxations[r], 2, 1, &l2, &w2);
        double *c = run_scene(DPSM_SCHEME_ISOTROPIC, kRelaxations[r], 3, 1, &l3, &w3);
        assert_same_run(a, b, (size_t)NX * NY, &l1, &l2);
        assert_same_run(a, c, (size_t)NX * NY, &l1, &l3);
        assert_true(w1 == w2 && w1 == w3);
        free(a);
        free(b);
        free(c);
    }
}

/* Where skipping is tightest: motion that starts at the corners and edges of
 * tiles (64 x 64 cells), fed by a thin source along a tile edge and woken by
 * host edits next to one, stepped in sweeps of 1 to 4 sub-steps. The heights
 * and ledger must match visiting every tile, bit for bit. */
static double *run_tile_edge_scene(int scheme, int visit_all, ledger_t *ledger) {
    visit_all_tiles(visit_all);
    enum { N = 200 };
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(N, N, 1.0, 1.0, &g));
    CHECK_OK(g, dpsm_set_scheme(g, scheme));
    CHECK_OK(g, dpsm_set_threads(g, 1));
    double *h = malloc(sizeof(double) * N * N), *q = calloc(N * N, sizeof(double));
    for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) {
            double v = 1.0 + 0.05 * sin(0.3 * i) * cos(0.2 * j);
            if (abs(i - 64) < 2 && abs(j - 64) < 2) v += 3.0; /* at a tile corner */
            if (i == 127 && j >= 30 && j < 34) v += 2.5;     /* on a tile edge */
            h[i + N * j] = v;
            if (i == 128 && j >= 150 && j < 152) q[i + N * j] = 0.4; /* just past a tile edge */
        }
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_source(g, q));
    double dt;
    CHECK_OK(g, dpsm_stable_dt(g, &dt));
    for (int k = 1; k <= 12; ++k) CHECK_OK(g, dpsm_step(g, (double)(k % 5) * dt + 0.5 * dt));
    const double bump[2] = {2.0, 3.0};
    CHECK_OK(g, dpsm_add_heights_region(g, 191, 63, 1, 2, bump)); /* the last row of a tile and the next */
    CHECK_OK(g, dpsm_set_source(g, NULL));
    CHECK_OK(g, dpsm_step(g, 1e6));
    CHECK_OK(g, dpsm_get_heights(g, h));
    *ledger = read_ledger(g);
    dpsm_destroy(g);
    free(q);
    visit_all_tiles(0);
    return h;
}

/* run(scheme, 0, ...) and run(scheme, 1, ...) give the same run, for both schemes. */
static void assert_switch_changes_nothing(double *(*run)(int scheme, int on, ledger_t *ledger), size_t cells) {
    for (int scheme = DPSM_SCHEME_PAIRWISE; scheme <= DPSM_SCHEME_ISOTROPIC; ++scheme) {
        ledger_t off_ledger, on_ledger;
        double *off = run(scheme, 0, &off_ledger);
        double *on = run(scheme, 1, &on_ledger);
        assert_same_run(off, on, cells, &off_ledger, &on_ledger);
        free(off);
        free(on);
    }
}

static void test_active_set_at_tile_edges(void **state) {
    (void)state;
    assert_switch_changes_nothing(run_tile_edge_scene, 200 * 200);
}

/* With hysteresis a cell can stop moving, and change its flag, in a sweep that
 * changes no height: the last sweep over a pile that came to rest. Between
 * sweeps the library keeps a scratch copy of the grid; the flags written by
 * that last sweep must survive a later sweep that visits other tiles only.
 * Piles of several sizes come to rest (so that motion ends at every sub-step
 * of a sweep), the host wakes a far tile, then sprinkles sand over the rested
 * piles: faces between the angles of repose and static move only next to a
 * moving cell, so a stale flag would change the result. */
static double *run_hysteresis_scene(int visit_all, ledger_t *ledger) {
    visit_all_tiles(visit_all);
    enum { W = 256, H = 64 };
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(W, H, 1.0, 1.0, &g));
    CHECK_OK(g, dpsm_set_threads(g, 1));
    CHECK_OK(g, dpsm_set_repose_angle(g, 30.0 * 3.14159265358979323846 / 180.0));
    CHECK_OK(g, dpsm_set_static_angle(g, 35.0 * 3.14159265358979323846 / 180.0));
    double *h = malloc(sizeof(double) * W * H);
    for (int c = 0; c < W * H; ++c) h[c] = 1.0;
    CHECK_OK(g, dpsm_set_heights(g, h));
    double *sprinkle = malloc(sizeof(double) * 48 * 48);
    for (int c = 0; c < 48 * 48; ++c) sprinkle[c] = 0.06 * (double)((c * 7919) % 5) / 4.0;
    for (int size = 4; size <= 11; ++size) {
        const int i0 = 8 + 24 * (size % 2), j0 = 8;  /* alternating places in the first tile */
        double pile[24 * 24];
        for (int j = 0; j < 24; ++j)
            for (int i = 0; i < 24; ++i) pile[i + 24 * j] = fmax(0.0, 1.2 * (size - hypot(i - 11.5, j - 11.5)));
        CHECK_OK(g, dpsm_add_heights_region(g, i0, j0, 24, 24, pile));
        CHECK_OK(g, dpsm_step(g, 1e6)); /* to rest */
        const double far[4] = {3.0, 2.0, 2.5, 3.5};
        CHECK_OK(g, dpsm_add_heights_region(g, 200 + size, 30, 2, 2, far));
        CHECK_OK(g, dpsm_step(g, 1e6)); /* sweeps only near the far tile */
        CHECK_OK(g, dpsm_add_heights_region(g, 0, 0, 48, 48, sprinkle));
        CHECK_OK(g, dpsm_step(g, 1e6));
    }
    CHECK_OK(g, dpsm_get_heights(g, h));
    *ledger = read_ledger(g);
    free(sprinkle);
    dpsm_destroy(g);
    visit_all_tiles(0);
    return h;
}

static void test_hysteresis_flags_survive_skipped_sweeps(void **state) {
    (void)state;
    ledger_t skip, all;
    double *a = run_hysteresis_scene(0, &skip);
    double *b = run_hysteresis_scene(1, &all);
    assert_same_run(a, b, 256 * 64, &skip, &all);
    free(a);
    free(b);
}

/* Tiles that every level computes whole and that need no ghosts are read
 * from the grid and written back in place, the others through a buffer: the
 * two must agree bit for bit (DPSM_COPY_TILES=1 sends every tile through the
 * buffer). A steep surface that flows everywhere, a source inside, sweeps of
 * 1 to 4 sub-steps, both schemes. */
static double *run_flowing_scene(int scheme, int copy_tiles, ledger_t *ledger) {
    if (copy_tiles)
        setenv("DPSM_COPY_TILES", "1", 1);
    else
        unsetenv("DPSM_COPY_TILES");
    enum { W = 300, H = 260 };
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(W, H, 0.8, 1.1, &g));
    CHECK_OK(g, dpsm_set_scheme(g, scheme));
    CHECK_OK(g, dpsm_set_threads(g, 1));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN));
    double *h = malloc(sizeof(double) * W * H), *q = calloc(W * H, sizeof(double));
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            h[i + W * j] = 1.3 * 0.8 * (W - i) + 0.4 * 1.1 * j + 0.6 * sin(0.21 * i) * cos(0.17 * j);
            if (abs(i - 150) < 20 && abs(j - 130) < 12) q[i + W * j] = 0.25;
        }
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_source(g, q));
    double dt;
    CHECK_OK(g, dpsm_stable_dt(g, &dt));
    const double substeps[] = {1.0, 2.0, 3.0, 4.0, 5.0, 7.3, 1.0, 11.0};
    for (size_t k = 0; k < sizeof substeps / sizeof *substeps; ++k) CHECK_OK(g, dpsm_step(g, substeps[k] * dt));
    REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) == 0.0, "the scene must still flow");
    CHECK_OK(g, dpsm_get_heights(g, h));
    *ledger = read_ledger(g);
    assert_true(ledger_residual(g) < 1e-13);
    dpsm_destroy(g);
    free(q);
    unsetenv("DPSM_COPY_TILES");
    return h;
}

static void test_tiles_in_place_match_copied_tiles(void **state) {
    (void)state;
    assert_switch_changes_nothing(run_flowing_scene, 300 * 260);
}

/* A surface at rest costs no cell update, however large; a few cells changed
 * by the host wake only the tiles around them. Both with time-accurate steps
 * and with the default, which relaxes this scene to rest. */
static void test_idle_and_local_updates(void **state) {
    (void)state;
    const int64_t n = 1024;
    double *h = malloc(sizeof(double) * n * n);
    for (int64_t c = 0; c < n * n; ++c) h[c] = 0.3 * sin(0.01 * (double)(c % n)) + 0.2 * cos(0.013 * (double)(c / n));
    for (int r = 0; r < 2; ++r) {
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, dpsm_create_2d(n, n, 1.0, 1.0, &g));
        CHECK_OK(g, dpsm_set_relaxation(g, kRelaxations[r]));
        CHECK_OK(g, dpsm_set_heights(g, h));
        double updates, substeps;
        CHECK_OK(g, dpsm_step(g, 10.0)); /* looks at every tile once: all at rest */
        CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &substeps));
        assert_true(substeps == 0.0); /* a sub-step or evaluation that finds rest is not counted */
        CHECK_OK(g, dpsm_step(g, 10.0));
        CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &updates));
        assert_true(updates == 0.0);

        const double pile[4] = {5.0, 6.0, 5.5, 7.0};
        CHECK_OK(g, dpsm_add_heights_region(g, 500, 600, 2, 2, pile));
        CHECK_OK(g, dpsm_step(g, 1e6));
        CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &updates));
        CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &substeps));
        print_message("%s: a 2x2 pile dropped on a %lldx%lld surface at rest: %.0f sub-steps, %.3g cell updates "
                      "(%.2f cells per sub-step, grid %lld)\n",
                      r ? "auto" : "time-accurate", (long long)n, (long long)n, substeps, updates, updates / substeps,
                      (long long)(n * n));
        assert_true(step_info_of(g, DPSM_INFO_AT_REST) == 1.0);
        assert_true(substeps > 0.0);
        assert_true(updates / substeps <= 9.0 * 64 * 64); /* at most the 3x3 tiles around it */
        CHECK_OK(g, dpsm_step(g, 1e6));
        CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &updates));
        assert_true(updates == 0.0);
        assert_true(ledger_residual(g) < 1e-13);
        dpsm_destroy(g);
    }
    free(h);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_active_set_changes_no_result),
        cmocka_unit_test(test_active_set_at_tile_edges),
        cmocka_unit_test(test_hysteresis_flags_survive_skipped_sweeps),
        cmocka_unit_test(test_results_do_not_depend_on_threads),
        cmocka_unit_test(test_tiles_in_place_match_copied_tiles),
        cmocka_unit_test(test_idle_and_local_updates),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
