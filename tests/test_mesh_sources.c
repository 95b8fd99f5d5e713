/* Sources in closed form on meshes (issue 34). A source that cannot make a
 * face steep within a step takes no sub-steps: it is added as q dt at the
 * end, and only the faces a source can make steep are looked at:
 *
 *  - where no face carries sand, one call of 64 sub-steps gives, bit for
 *    bit, the heights of 64 calls of one sub-step (every figure dyadic, so
 *    that h + q dt is exact however it is summed); elsewhere the same to
 *    round-off; and it visits far fewer cells than 64 sub-steps of the mesh;
 *  - a source that makes a face steep within the step, and one that makes a
 *    face steep only after sand moved beside it and came to rest (erosion
 *    next to a collapsing column, alone and with sand moving elsewhere): one
 *    call and many agree to round-off, and visiting every cell changes no
 *    bit;
 *  - the same with an angle field and a flux exponent, which keep sources
 *    in closed form on meshes;
 *  - a face a source made steep at the very end of a call slides in the
 *    next, whatever that call's source;
 *  - a source of 1e-300 takes the sub-steps of none, and dt = 1e12 with it
 *    is accepted;
 *  - only a source that makes a face steep is held to dpsm_set_max_substeps;
 *  - two threads give the bits of one.
 * On triangles, hexagons, the median dual and quadrilaterals. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "mesh_scenes.h"
#include "test_support.h"

static const double kDeg = 3.14159265358979323846 / 180.0;
static const scene_kind kKinds[4] = {SCENE_TRIANGLES, SCENE_HEXAGONS, SCENE_DUAL, SCENE_QUADS};

/* With it, the meshes dyadic_mesh makes have an angle of repose per cell
 * (28 to 34 degrees across x) and a flux exponent of 1.5, which keep
 * sources in closed form. */
static int g_angle_field_and_exponent = 0;

/* The scene's mesh at 30 degrees, on one thread, with the mobility that
 * makes its stable sub-step 1025/1024 of 2^-10: a call of 2^-j (j from 0 to
 * 10) takes sub-steps of exactly 2^-10. */
static dpsm_grid *dyadic_mesh(const mesh_scene *s) {
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, scene_create(s, &g));
    CHECK_OK(g, dpsm_set_repose_angle(g, 30.0 * kDeg));
    CHECK_OK(g, dpsm_set_threads(g, 1));
    if (g_angle_field_and_exponent) {
        double *theta = malloc(sizeof(double) * (size_t)s->cells);
        for (int64_t c = 0; c < s->cells; ++c) theta[c] = (31.0 + 3.0 * s->cx[c] / 2.5) * kDeg;
        CHECK_OK(g, dpsm_set_repose_angle_field(g, theta));
        CHECK_OK(g, dpsm_set_flux_exponent(g, 1.5));
        free(theta);
    }
    double stable = 0.0;
    CHECK_OK(g, dpsm_stable_dt(g, &stable)); /* at the default mobility, to which it is inversely proportional */
    CHECK_OK(g, dpsm_set_mobility(g, DPSM_DEFAULT_MOBILITY * stable / (1025.0 / 1024.0 / 1024.0)));
    return g;
}

/* Steps `calls` calls of dt, recording face fluxes; marks in `moved` every
 * cell one of whose faces carried sand in any of them. */
static void step_calls(dpsm_grid *g, int64_t cells, int calls, double dt, uint8_t *moved) {
    int64_t nfaces = 0;
    CHECK_OK(g, dpsm_get_face_count(g, &nfaces));
    int64_t *faces = malloc(sizeof(int64_t) * (size_t)(2 * nfaces));
    double *fx = malloc(sizeof(double) * (size_t)nfaces);
    CHECK_OK(g, dpsm_get_mesh_faces(g, faces));
    CHECK_OK(g, dpsm_set_face_flux_recording(g, 1));
    for (int call = 0; call < calls; ++call) {
        CHECK_OK(g, dpsm_step(g, dt));
        CHECK_OK(g, dpsm_get_face_fluxes(g, fx, NULL));
        for (int64_t f = 0; f < nfaces; ++f) {
            if (fx[f] == 0.0) continue;
            for (int side = 0; side < 2; ++side)
                if (faces[2 * f + side] >= 0 && faces[2 * f + side] < cells) moved[faces[2 * f + side]] = 1;
        }
    }
    free(faces), free(fx);
}

/* A gentle surface in steps of 1/64, a block of 2 that collapses, and a
 * source of multiples of 1/64 on every cell, erosion and deposition. */
static void dyadic_scene(dpsm_grid *g, const mesh_scene *s) {
    double *h = malloc(sizeof(double) * (size_t)s->cells), *q = malloc(sizeof(double) * (size_t)s->cells);
    for (int64_t c = 0; c < s->cells; ++c) {
        h[c] = round(64.0 * 0.05 * (s->cx[c] + s->cy[c] + 5.0)) / 64.0 +
               (hypot(s->cx[c] - 0.8, s->cy[c] - 0.6) < 0.35 ? 2.0 : 0.0);
        q[c] = (double)((c * 7) % 16 - 8) / 64.0;
    }
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_source(g, q));
    free(h), free(q);
}

static void test_closed_form_bit_for_bit_where_no_face_moves(void **state) {
    (void)state;
    for (int k = 0; k < 4; ++k) {
        mesh_scene s = scene_make(kKinds[k], 40, 2.5, 3u);
        const int64_t n = s.cells;
        REQUIRE(n > 0, "no mesh");
        dpsm_grid *a = dyadic_mesh(&s), *b = dyadic_mesh(&s);
        dyadic_scene(a, &s);
        dyadic_scene(b, &s);
        uint8_t *moved = calloc((size_t)n, 1), *moved_once = calloc((size_t)n, 1);
        step_calls(a, n, 1, 1.0 / 16.0, moved_once);
        REQUIRE(step_info_of(a, DPSM_INFO_SUBSTEPS) == 64.0, "%s: the call took %g sub-steps, not 64",
                scene_name(kKinds[k]), step_info_of(a, DPSM_INFO_SUBSTEPS));
        const double updates = step_info_of(a, DPSM_INFO_CELL_UPDATES);
        step_calls(b, n, 64, 1.0 / 1024.0, moved);
        double *one = malloc(sizeof(double) * (size_t)n), *many = malloc(sizeof(double) * (size_t)n);
        CHECK_OK(a, dpsm_get_heights(a, one));
        CHECK_OK(b, dpsm_get_heights(b, many));
        int64_t quiet = 0, differ = 0;
        double worst = 0.0;
        for (int64_t c = 0; c < n; ++c) {
            if (!moved[c] && !moved_once[c]) {
                ++quiet;
                differ += memcmp(&one[c], &many[c], sizeof(double)) != 0;
            }
            worst = fmax(worst, fabs(one[c] - many[c]) / fmax(1.0, fabs(many[c])));
        }
        print_message("%s: %lld of %lld cells never moved; %g cell updates for 64 sub-steps (%.1f %%); largest "
                      "difference %.2e\n",
                      scene_name(kKinds[k]), (long long)quiet, (long long)n, updates,
                      100.0 * updates / (64.0 * (double)n), worst);
        REQUIRE(quiet > n * 8 / 10 && quiet < n, "%s: %lld quiet cells of %lld", scene_name(kKinds[k]),
                (long long)quiet, (long long)n);
        REQUIRE(differ == 0, "%s: %lld cells where no face moved differ from sub-stepping", scene_name(kKinds[k]),
                (long long)differ);
        REQUIRE(worst < 1e-13, "%s: the moving cells differ from sub-stepping by %.3e", scene_name(kKinds[k]), worst);
        REQUIRE(updates < 0.25 * 64.0 * (double)n, "%s: %g cell updates: the quiet cells were sub-stepped",
                scene_name(kKinds[k]), updates);
        const ledger_t la = read_ledger(a), lb = read_ledger(b);
        REQUIRE(fabs(la.sourced - lb.sourced) <= 1e-13 * fabs(lb.sourced) && ledger_residual(a) < 1e-13,
                "%s: sourced %.17g against %.17g, ledger residual %.2e", scene_name(kKinds[k]), la.sourced,
                lb.sourced, ledger_residual(a));
        free(one), free(many), free(moved), free(moved_once);
        dpsm_destroy(a), dpsm_destroy(b);
        scene_free(&s);
    }
}

/* The same scene stepped in one call of T and in 16 calls of T / 16 (the
 * same sub-steps of 2^-10): the heights agree to round-off, sand moved in
 * the one call (`what` names the scene), visiting every cell changes no bit
 * of it, and both ledgers close. */
typedef void (*scene_fn)(dpsm_grid *g, const mesh_scene *s);
static void one_call_against_many(const char *what, double T, scene_fn scene) {
    for (int k = 0; k < 4; ++k) {
        mesh_scene s = scene_make(kKinds[k], 24, 2.5, 5u);
        const int64_t n = s.cells;
        dpsm_grid *a = dyadic_mesh(&s), *b = dyadic_mesh(&s), *every = dyadic_mesh(&s);
        scene(a, &s);
        scene(b, &s);
        scene(every, &s);
        uint8_t *moved = calloc((size_t)n, 1), *ignored = calloc((size_t)n, 1);
        double *before = malloc(sizeof(double) * (size_t)n);
        CHECK_OK(a, dpsm_get_heights(a, before));
        step_calls(a, n, 1, T, moved);
        step_calls(b, n, 16, T / 16.0, ignored);
        /* The faces a source may make steep are the ones looked at: visiting every cell changes no bit. */
        setenv("DPSM_VISIT_ALL_CELLS", "1", 1);
        step_calls(every, n, 1, T, ignored);
        unsetenv("DPSM_VISIT_ALL_CELLS");
        double *one = malloc(sizeof(double) * (size_t)n), *many = malloc(sizeof(double) * (size_t)n);
        double *all = malloc(sizeof(double) * (size_t)n);
        CHECK_OK(a, dpsm_get_heights(a, one));
        CHECK_OK(b, dpsm_get_heights(b, many));
        CHECK_OK(every, dpsm_get_heights(every, all));
        REQUIRE(memcmp(one, all, sizeof(double) * (size_t)n) == 0 &&
                    step_info_of(a, DPSM_INFO_SUBSTEPS) == step_info_of(every, DPSM_INFO_SUBSTEPS),
                "%s, %s: the heights differ with every cell visited", scene_name(kKinds[k]), what);
        int64_t moving = 0;
        double worst = 0.0, change = 0.0;
        for (int64_t c = 0; c < n; ++c) {
            moving += moved[c];
            worst = fmax(worst, fabs(one[c] - many[c]));
            change = fmax(change, fabs(one[c] - before[c]));
        }
        print_message("%s, %s: %lld cells moved, %g sub-steps%s; one call against 16: %.2e (largest change %.3g)\n",
                      scene_name(kKinds[k]), what, (long long)moving, step_info_of(a, DPSM_INFO_SUBSTEPS),
                      step_info_of(a, DPSM_INFO_AT_REST) == 1.0 ? ", at rest" : "", worst, change);
        REQUIRE(moving > 0, "%s, %s: no sand moved", scene_name(kKinds[k]), what);
        REQUIRE(worst <= 1e-12 * change, "%s, %s: one call differs from 16 by %.3e", scene_name(kKinds[k]), what,
                worst);
        REQUIRE(ledger_residual(a) < 1e-13 && ledger_residual(b) < 1e-13, "%s, %s: ledger residuals %.2e, %.2e",
                scene_name(kKinds[k]), what, ledger_residual(a), ledger_residual(b));
        free(one), free(many), free(all), free(before), free(moved), free(ignored);
        dpsm_destroy(a), dpsm_destroy(b), dpsm_destroy(every);
        scene_free(&s);
    }
}

/* Flat, with a source on a disk that builds its rim steeper than the angle
 * of repose within the call. */
static void steepening_scene(dpsm_grid *g, const mesh_scene *s) {
    double *h = malloc(sizeof(double) * (size_t)s->cells), *q = calloc((size_t)s->cells, sizeof(double));
    for (int64_t c = 0; c < s->cells; ++c) {
        h[c] = 1.0;
        if (hypot(s->cx[c] + 0.5, s->cy[c] - 0.4) < 0.6) q[c] = 8.0;
    }
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_source(g, q));
    free(h), free(q);
}

/* A column that collapses towards a strip under erosion. The strip alone
 * keeps its edges below the angle of repose over the call (0.1 deep against
 * tan 30 times a cell of about 0.2), and the column lies beyond the cells
 * whose faces the strip's source moves: it is the column's sand, come to
 * rest at the strip's edge, that the erosion steepens later in the call. */
static void collapse_beside_erosion(dpsm_grid *g, const mesh_scene *s, double elsewhere) {
    double *h = malloc(sizeof(double) * (size_t)s->cells), *q = calloc((size_t)s->cells, sizeof(double));
    for (int64_t c = 0; c < s->cells; ++c) {
        h[c] = 2.0 + (hypot(s->cx[c] + 1.4, s->cy[c]) < 0.35 ? 0.6 : 0.0);
        if (s->cx[c] > -0.6 && s->cx[c] < 0.4) q[c] = -0.1;
        if (hypot(s->cx[c] - 1.6, s->cy[c] - 1.6) < 0.3) q[c] = elsewhere;
    }
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_source(g, q));
    free(h), free(q);
}
/* Alone: the call comes to rest before the erosion steepens the column's
 * foot, and must not end there. */
static void erosion_beside_a_collapse(dpsm_grid *g, const mesh_scene *s) { collapse_beside_erosion(g, s, 0.0); }
/* With a source that keeps sand moving far from it: the cells near the
 * strip where the column's sand came to rest must still be looked at. */
static void erosion_beside_a_collapse_moving_elsewhere(dpsm_grid *g, const mesh_scene *s) {
    collapse_beside_erosion(g, s, 2.0);
}

static void test_source_that_steepens_within_the_step(void **state) {
    (void)state;
    one_call_against_many("a source that steepens its rim", 1.0 / 16.0, steepening_scene);
}

/* The same with an angle field and a flux exponent. */
static void test_with_an_angle_field_and_an_exponent(void **state) {
    (void)state;
    g_angle_field_and_exponent = 1;
    one_call_against_many("a source that steepens its rim, angle field, exponent 1.5", 1.0 / 16.0, steepening_scene);
    one_call_against_many("erosion beside a collapse, angle field, exponent 1.5", 1.0, erosion_beside_a_collapse);
    g_angle_field_and_exponent = 0;
}

static void test_source_that_steepens_after_sand_moved(void **state) {
    (void)state;
    one_call_against_many("erosion beside a collapse", 1.0, erosion_beside_a_collapse);
    one_call_against_many("erosion beside a collapse, sand moving elsewhere", 1.0,
                          erosion_beside_a_collapse_moving_elsewhere);
}

/* A source that makes a disk's rim steep at the very end of a call (in the
 * closed form added after its one sub-step), and the host's next source,
 * which lowers the disk back to flat over the next call, or none: the rim is
 * steep at the start of that call (and with the source not at its end), yet
 * it must slide in its first sub-step, as it does with every cell visited. */
static void test_steep_at_a_call_end_slides_in_the_next(void **state) {
    (void)state;
    for (int k = 0; k < 4; ++k) {
        mesh_scene s = scene_make(kKinds[k], 24, 2.5, 7u);
        const int64_t n = s.cells;
        REQUIRE(n > 0, "no mesh");
        double *h = malloc(sizeof(double) * (size_t)n), *q = calloc((size_t)n, sizeof(double));
        for (int next = 0; next < 2; ++next) {
            double *heights[2];
            double moved[2] = {0.0, 0.0};
            for (int every = 0; every < 2; ++every) {
                if (every) setenv("DPSM_VISIT_ALL_CELLS", "1", 1);
                dpsm_grid *g = dyadic_mesh(&s);
                for (int64_t c = 0; c < n; ++c) {
                    h[c] = 1.0;
                    q[c] = hypot(s.cx[c] - 0.3, s.cy[c] + 0.2) < 0.7 ? 512.0 : 0.0;
                }
                CHECK_OK(g, dpsm_set_heights(g, h));
                CHECK_OK(g, dpsm_set_source(g, q));
                CHECK_OK(g, dpsm_step(g, 1.0 / 1024.0));
                for (int64_t c = 0; c < n; ++c) q[c] = -q[c];
                CHECK_OK(g, dpsm_set_source(g, next == 0 ? q : NULL));
                CHECK_OK(g, dpsm_step(g, 1.0 / 1024.0));
                moved[every] = step_info_of(g, DPSM_INFO_MAX_EXCESS_SLOPE);
                heights[every] = malloc(sizeof(double) * (size_t)n);
                CHECK_OK(g, dpsm_get_heights(g, heights[every]));
                dpsm_destroy(g);
                unsetenv("DPSM_VISIT_ALL_CELLS");
            }
            const char *then = next == 0 ? "the source lowering the disk" : "no source";
            REQUIRE(moved[1] > 0.0, "%s, %s: the rim did not slide with every cell visited", scene_name(kKinds[k]),
                    then);
            REQUIRE(memcmp(heights[0], heights[1], sizeof(double) * (size_t)n) == 0,
                    "%s, %s: the heights differ with every cell visited (excess slope %g against %g)",
                    scene_name(kKinds[k]), then, moved[0], moved[1]);
            free(heights[0]), free(heights[1]);
        }
        free(h), free(q);
        scene_free(&s);
    }
}

/* A cone on hexagons with an open edge, with and without a source of 1e-300
 * on a cell far from it: the same sub-steps, the same heights but in that
 * cell, where the source lands in closed form; the step integrates all of
 * dt with the source. And the scene: a mesh of four cells with a
 * source of 1e-300 accepts dt = 1e12, in no more sub-steps than without. */
static const double kQuadNodes[18] = {0, 0, 1, 0, 2, 0, 0, 1, 1, 1, 2, 1, 0, 2, 1, 2, 2, 2};
static const int64_t kQuadStart[5] = {0, 4, 8, 12, 16};
static const int64_t kQuadCells[16] = {0, 1, 4, 3, 1, 2, 5, 4, 3, 4, 7, 6, 4, 5, 8, 7};

static void test_negligible_source_costs_nothing(void **state) {
    (void)state;
    mesh_scene s = scene_make(SCENE_HEXAGONS, 30, 2.5, 1u);
    const int64_t n = s.cells;
    REQUIRE(n > 0, "no mesh");
    int64_t corner = 0;
    for (int64_t c = 0; c < n; ++c)
        if (s.cx[c] + s.cy[c] < s.cx[corner] + s.cy[corner]) corner = c;
    const size_t cells = (size_t)(n > 0 ? n : 1);
    double *h = malloc(sizeof(double) * cells), *q = calloc(cells, sizeof(double));
    double *with = malloc(sizeof(double) * cells), *without = malloc(sizeof(double) * cells);
    for (int64_t c = 0; c < n; ++c) h[c] = fmax(0.0, 2.0 - 1.5 * hypot(s.cx[c], s.cy[c]));
    q[corner] = 1e-300;
    double substeps[2], time[2];
    for (int with_source = 0; with_source < 2; ++with_source) {
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, scene_create(&s, &g));
        CHECK_OK(g, dpsm_set_repose_angle(g, 33.0 * kDeg));
        CHECK_OK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN));
        CHECK_OK(g, dpsm_set_heights(g, h));
        if (with_source) CHECK_OK(g, dpsm_set_source(g, q));
        CHECK_OK(g, dpsm_set_max_substeps(g, 1000)); /* not a driven scene: not limited */
        CHECK_OK(g, dpsm_step(g, 1e6));
        substeps[with_source] = step_info_of(g, DPSM_INFO_SUBSTEPS);
        time[with_source] = step_info_of(g, DPSM_INFO_TIME_INTEGRATED);
        REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) == 1.0, "source %d: not at rest", with_source);
        /* At rest, the next call visits nothing but the source's cell, where it lands. */
        CHECK_OK(g, dpsm_step(g, 1e6));
        REQUIRE(step_info_of(g, DPSM_INFO_SUBSTEPS) == 0.0 &&
                    step_info_of(g, DPSM_INFO_CELL_UPDATES) == (double)with_source,
                "source %d: %g sub-steps, %g cell updates in the call after rest", with_source,
                step_info_of(g, DPSM_INFO_SUBSTEPS), step_info_of(g, DPSM_INFO_CELL_UPDATES));
        CHECK_OK(g, dpsm_get_heights(g, with_source ? with : without));
        dpsm_destroy(g);
    }
    REQUIRE(substeps[0] > 0.0 && substeps[1] == substeps[0], "%g sub-steps with the source, %g without", substeps[1],
            substeps[0]);
    REQUIRE(time[1] == 1e6 && time[0] < 1e4, "time integrated %g with the source, %g without", time[1], time[0]);
    for (int64_t c = 0; c < n; ++c)
        if (c != corner)
            REQUIRE(memcmp(&with[c], &without[c], sizeof(double)) == 0, "cell %lld: %.17g with the source, %.17g",
                    (long long)c, with[c], without[c]);
    REQUIRE(fabs(with[corner] - (without[corner] + 2.0 * 1e-300 * 1e6)) <= 1e-12 * 1e-294, "the corner holds %.17g",
            with[corner]);

    double four[2][4];
    for (int with_source = 0; with_source < 2; ++with_source) {
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, dpsm_create_mesh(9, kQuadNodes, 4, kQuadStart, kQuadCells, &g));
        const double hq[4] = {1.0, 1.0, 1.0, 1.0}, qq[4] = {1e-300, 0.0, 0.0, 0.0};
        CHECK_OK(g, dpsm_set_heights(g, hq));
        if (with_source) CHECK_OK(g, dpsm_set_source(g, qq));
        CHECK_OK(g, dpsm_step(g, 1e12));
        substeps[with_source] = step_info_of(g, DPSM_INFO_SUBSTEPS);
        CHECK_OK(g, dpsm_get_heights(g, four[with_source]));
        dpsm_destroy(g);
    }
    REQUIRE(substeps[1] <= substeps[0], "four cells: %g sub-steps with the source, %g without", substeps[1],
            substeps[0]);
    REQUIRE(fabs(four[1][0] - (1.0 + 1e-288)) == 0.0 && four[1][1] == 1.0, "four cells: %.17g, %.17g", four[1][0],
            four[1][1]);
    free(h), free(q), free(with), free(without);
    scene_free(&s);
}

/* Only a source that makes a face steep within the step can keep sand
 * flowing, so only it is held to dpsm_set_max_substeps(). */
/* On two threads the sources' catch-up at a step's end is shared between
 * them (from 32,768 source cells): the same heights, ledger and cell
 * updates bit for bit as on one, a call after a call, while a bump slides
 * under a source on every cell. */
static void test_two_threads_the_same_bits(void **state) {
    (void)state;
    mesh_scene s = scene_make(SCENE_TRIANGLES, 130, 2.5, 11u);
    double *h = calloc((size_t)s.cells, sizeof(double)), *q = calloc((size_t)s.cells, sizeof(double));
    for (int64_t c = 0; c < s.cells; ++c) {
        h[c] = 3.0 + fmax(0.0, 0.4 - 1.5 * hypot(s.cx[c] - 0.5, s.cy[c] + 0.1));
        q[c] = 0.01 + 0.003 * sin(3.0 * s.cx[c]) * cos(2.0 * s.cy[c]);
    }
    dpsm_grid *g[2] = {NULL, NULL};
    double *out[2];
    for (int t = 0; t < 2; ++t) {
        CHECK_OK(NULL, scene_create(&s, &g[t]));
        CHECK_OK(g[t], dpsm_set_repose_angle(g[t], 30.0 * kDeg));
        CHECK_OK(g[t], dpsm_set_threads(g[t], t + 1));
        CHECK_OK(g[t], dpsm_set_heights(g[t], h));
        CHECK_OK(g[t], dpsm_set_source(g[t], q));
        out[t] = calloc((size_t)s.cells, sizeof(double));
    }
    double dt = 0.0;
    CHECK_OK(g[0], dpsm_stable_dt(g[0], &dt));
    for (int call = 0; call < 4; ++call) {
        double updates[2];
        for (int t = 0; t < 2; ++t) {
            CHECK_OK(g[t], dpsm_step(g[t], 6.0 * dt));
            CHECK_OK(g[t], dpsm_get_heights(g[t], out[t]));
            CHECK_OK(g[t], dpsm_get_step_info(g[t], DPSM_INFO_CELL_UPDATES, &updates[t]));
        }
        for (int64_t c = 0; c < s.cells; ++c)
            REQUIRE(memcmp(&out[0][c], &out[1][c], sizeof(double)) == 0,
                    "call %d, cell %lld: %.17g on one thread, %.17g on two", call, (long long)c, out[0][c], out[1][c]);
        REQUIRE(updates[0] == updates[1], "call %d: %g cell updates on one thread, %g on two", call, updates[0],
                updates[1]);
        REQUIRE(updates[0] >= (double)s.cells, "call %d: %g cell updates, fewer than the %lld source cells", call,
                updates[0], (long long)s.cells);
        const double total[2] = {mass_of(g[0], DPSM_MASS_TOTAL), mass_of(g[1], DPSM_MASS_TOTAL)};
        REQUIRE(memcmp(&total[0], &total[1], sizeof(double)) == 0, "call %d: the ledgers differ", call);
    }
    for (int t = 0; t < 2; ++t) dpsm_destroy(g[t]), free(out[t]);
    free(h), free(q);
    scene_free(&s);
}

static void test_work_limit_only_for_a_driving_source(void **state) {
    (void)state;
    mesh_scene s = scene_make(SCENE_TRIANGLES, 16, 2.5, 2u);
    const int64_t n = s.cells;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, scene_create(&s, &g));
    double *h = malloc(sizeof(double) * (size_t)n), *q = malloc(sizeof(double) * (size_t)n);
    double *after = malloc(sizeof(double) * (size_t)n), *again = malloc(sizeof(double) * (size_t)n);
    for (int64_t c = 0; c < n; ++c) h[c] = 2.0, q[c] = 0.01;
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_source(g, q));
    CHECK_OK(g, dpsm_set_max_substeps(g, 10));
    double sdt = 0.0;
    CHECK_OK(g, dpsm_stable_dt(g, &sdt));
    CHECK_OK(g, dpsm_step(g, 100.0 * sdt)); /* a uniform source between walls steepens nothing */
    REQUIRE(step_info_of(g, DPSM_INFO_SUBSTEPS) <= 1.0, "%g sub-steps", step_info_of(g, DPSM_INFO_SUBSTEPS));
    CHECK_OK(g, dpsm_get_heights(g, after));
    for (int64_t c = 0; c < n; ++c)
        REQUIRE(fabs(after[c] - (2.0 + 0.01 * 100.0 * sdt)) < 1e-14, "cell %lld: height %.17g", (long long)c,
                after[c]);
    q[n / 2] = 100.0;
    CHECK_OK(g, dpsm_set_source(g, q));
    REQUIRE(dpsm_step(g, 100.0 * sdt) == DPSM_ERR_WORK_LIMIT, "a driving source was not limited");
    CHECK_OK(g, dpsm_get_heights(g, again));
    REQUIRE(memcmp(after, again, sizeof(double) * (size_t)n) == 0, "the refused step changed the heights");
    CHECK_OK(g, dpsm_step(g, 9.5 * sdt));
    REQUIRE(step_info_of(g, DPSM_INFO_SUBSTEPS) == 10.0, "%g sub-steps", step_info_of(g, DPSM_INFO_SUBSTEPS));
    free(h), free(q), free(after), free(again);
    dpsm_destroy(g);
    scene_free(&s);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_closed_form_bit_for_bit_where_no_face_moves),
        cmocka_unit_test(test_source_that_steepens_within_the_step),
        cmocka_unit_test(test_source_that_steepens_after_sand_moved),
        cmocka_unit_test(test_with_an_angle_field_and_an_exponent),
        cmocka_unit_test(test_steep_at_a_call_end_slides_in_the_next),
        cmocka_unit_test(test_negligible_source_costs_nothing),
        cmocka_unit_test(test_work_limit_only_for_a_driving_source),
        cmocka_unit_test(test_two_threads_the_same_bits),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
