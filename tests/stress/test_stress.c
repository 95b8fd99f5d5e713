/* The numerical stress suite: the library driven far from the comfortable
 * middle, with every invariant of stress_support.h checked after every step
 * (finite heights, the ledger closing to 1e-12, no new extremum without a
 * source, held cells unchanged, no face steeper than the angle of repose at
 * rest):
 *
 *   time steps from 1e-12 to 1e12, with and without a source;
 *   height jumps from 1e-9 to 1e6 (vertical walls of sand);
 *   angles of repose from 0.5 to 89.5 degrees;
 *   random rough terrains, above and below the level of open sides;
 *   grids of 1x1, 1xN, Nx1 and long thin ones, 1D, 2D and axisymmetric;
 *   walls, obstacles, open cells and sources mixed;
 *   requests no method can finish in bounded work (DPSM_ERR_WORK_LIMIT, the
 *   grid unchanged);
 *   levels beyond the sides from 1e-3 to 1e6, above and below the sand,
 *   varying face by face, a bed set before the sand;
 *   100 000 small steps.
 *
 * Every second scene records its face fluxes and checks them after every
 * step. Each test prints its worst figures; the last prints the worst over all.
 * DPSM_STRESS_SCALE (environment, default from the build: 1, smaller under
 * sanitizers) scales the grid sizes and step counts. */
#include <float.h>
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

#include "stress_support.h"

static const double kPi = 3.14159265358979323846;
static double deg(double d) { return d * kPi / 180.0; }


static const char *geom_name(int geom, int scheme) {
    if (geom == GEOM_1D) return "1D";
    if (geom == GEOM_AXI) return "axisym";
    return scheme == DPSM_SCHEME_PAIRWISE ? "2D pairwise" : "2D isotropic";
}

/* The four kinds of grid the suites go through. */
typedef struct {
    int geom, scheme;
} flavour_t;
static const flavour_t kFlavours[] = {
    {GEOM_1D, DPSM_SCHEME_PAIRWISE},
    {GEOM_AXI, DPSM_SCHEME_PAIRWISE},
    {GEOM_2D, DPSM_SCHEME_PAIRWISE},
    {GEOM_2D, DPSM_SCHEME_ISOTROPIC},
};
#define NFLAVOURS ((int)(sizeof kFlavours / sizeof kFlavours[0]))

/* A scene on cells of dx by dx (by dy in make_scene_dy). */
static void make_scene_dy(scene_t *s, const flavour_t *f, int64_t nx, int64_t ny, double dx, double dy,
                          const char *fmt, ...) CMOCKA_PRINTF_ATTRIBUTE(7, 8);
static void vmake_scene(scene_t *s, const flavour_t *f, int64_t nx, int64_t ny, double dx, double dy, const char *fmt,
                        va_list ap) {
    char what[120], name[160];
    vsnprintf(what, sizeof what, fmt, ap);
    snprintf(name, sizeof name, "%s %lldx%lld: %s", geom_name(f->geom, f->scheme), (long long)nx,
             (long long)(f->geom == GEOM_2D ? ny : 1), what);
    scene_create(s, name, f->geom, nx, ny, dx, dy);
    if (f->geom == GEOM_2D) scene_set_scheme(s, f->scheme);
}
static void make_scene_dy(scene_t *s, const flavour_t *f, int64_t nx, int64_t ny, double dx, double dy,
                          const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vmake_scene(s, f, nx, ny, dx, dy, fmt, ap);
    va_end(ap);
}
static void make_scene(scene_t *s, const flavour_t *f, int64_t nx, int64_t ny, double dx, const char *fmt, ...)
    CMOCKA_PRINTF_ATTRIBUTE(6, 7);
static void make_scene(scene_t *s, const flavour_t *f, int64_t nx, int64_t ny, double dx, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vmake_scene(s, f, nx, ny, dx, dx, fmt, ap);
    va_end(ap);
}

/* Heights: a rough terrain (uniform noise of amplitude amp around offset)
 * plus a column of height top over the middle third. */
static double *terrain(const scene_t *s, double offset, double amp, double top, uint64_t seed) {
    double *h = malloc(sizeof(double) * (size_t)s->n);
    REQUIRE(h != NULL, "out of memory");
    for (int64_t j = 0; j < s->ny; ++j)
        for (int64_t i = 0; i < s->nx; ++i) {
            const int64_t c = i + s->nx * j;
            h[c] = offset + amp * (2.0 * rng_uniform(&seed) - 1.0);
            const int in_x = 3 * i >= s->nx && 3 * i < 2 * s->nx;
            const int in_y = s->ny == 1 || (3 * j >= s->ny && 3 * j < 2 * s->ny);
            if (s->geom == GEOM_AXI ? 3 * i < s->nx : in_x && in_y) h[c] += top;
        }
    return h;
}

static double stable(const scene_t *s) {
    double dt = 0.0;
    REQUIRE(dpsm_stable_dt(s->g, &dt) == DPSM_OK && dt > 0.0 && isfinite(dt), "[%s] stable_dt = %g", s->name, dt);
    return dt;
}

/* dpsm_step(dt) must fail with DPSM_ERR_WORK_LIMIT, say why, and change nothing. */
static void expect_work_limit(scene_t *s, double dt) { expect_work_limit_on(s->g, s->n, s->name, dt); }

static void finish_test(const char *title, const stress_worst_t *w) {
    stress_worst_print(title, w);
    stress_worst_merge(w);
}

/* ------------------------------------------------------------------------ */

/* Every decade of dt from 1e-12 to 1e12 on a collapsing pile over a rough
 * bed: without a source each step must finish (it stops at rest); with one,
 * each step either fits under the sub-step limit or fails at once. */
static void test_time_steps(void **state) {
    (void)state;
    stress_worst_t w;
    stress_worst_reset(&w);
    const int64_t n1 = scaled(48, 8), n2 = scaled(24, 6);
    for (int f = 0; f < NFLAVOURS; ++f)
        for (int open = 0; open < 2; ++open)
            for (int with_source = 0; with_source < 2; ++with_source)
                for (int e = -12; e <= 12; ++e) {
                    const double dt = pow(10.0, e);
                    const flavour_t *fl = &kFlavours[f];
                    const int64_t nx = fl->geom == GEOM_2D ? n2 : n1, ny = fl->geom == GEOM_2D ? n2 - 3 : 1;
                    scene_t s;
                    make_scene(&s, fl, nx, ny, 1.0, "dt = 1e%d, %s sides%s", e, open ? "open" : "wall",
                               with_source ? ", source" : "");
                    scene_set_all_sides(&s, open);
                    double *h = terrain(&s, 1.0, 0.5, 4.0, 1000u + (uint64_t)(e + 100 * f));
                    scene_set_heights(&s, h);
                    REQUIRE(dpsm_set_max_substeps(s.g, 20000) == DPSM_OK, "set_max_substeps");
                    if (with_source) {
                        for (int64_t c = 0; c < s.n; ++c) h[c] = (c % 3 == 0) ? 1e-3 : (c % 3 == 1 ? -2e-4 : 0.0);
                        scene_set_source(&s, h);
                    }
                    const double needed = ceil(dt / stable(&s));
                    for (int k = 0; k < 3; ++k) {
                        if (with_source && needed > 20000.0)
                            expect_work_limit(&s, dt);
                        else
                            scene_step(&s, dt, &w);
                    }
                    free(h);
                    scene_destroy(&s);
                }
    finish_test("time steps 1e-12 .. 1e12", &w);
}

/* A vertical wall of sand of height J (from 1e-9 to 1e6) next to a bed at 0,
 * on cells of 1 and on cells of J (the same slopes at every scale). Up to
 * 1e3 (cells of 1) it runs to rest in one call; higher walls are mobility
 * bound (a flux of at most nu) and take J * L / nu to fall, so they are
 * stepped a bounded time. */
static void test_height_jumps(void **state) {
    (void)state;
    stress_worst_t w;
    stress_worst_reset(&w);
    const double jumps[] = {1e-9, 1e-6, 1e-3, 1.0, 1e3, 1e6};
    const int64_t n1 = scaled(40, 8), n2 = scaled(20, 6);
    for (int f = 0; f < NFLAVOURS; ++f)
        for (size_t k = 0; k < sizeof jumps / sizeof jumps[0]; ++k)
            for (int cells_of_j = 0; cells_of_j < 2; ++cells_of_j)
                for (int open = 0; open < 2; ++open) {
                    const double J = jumps[k], dx = cells_of_j ? J : 1.0;
                    const flavour_t *fl = &kFlavours[f];
                    const int64_t nx = fl->geom == GEOM_2D ? n2 : n1, ny = fl->geom == GEOM_2D ? n2 : 1;
                    scene_t s;
                    make_scene(&s, fl, nx, ny, dx, "wall of sand J = %g, dx = %g, %s", J, dx,
                               open ? "open x max" : "walls");
                    scene_set_side(&s, DPSM_XMAX, open);
                    double *h = calloc((size_t)s.n, sizeof(double));
                    for (int64_t j = 0; j < s.ny; ++j)
                        for (int64_t i = 0; i < s.nx; ++i)
                            if (2 * i < s.nx && (s.ny == 1 || 2 * j < s.ny)) h[i + s.nx * j] = J;
                    scene_set_heights(&s, h);
                    if (J / dx <= 1e3) {
                        /* One call of a huge dt (time scales as dx^2): it must stop at rest. */
                        scene_run_to_rest(&s, 1e12 * fmax(1.0, dx * dx), 2, &w);
                    } else {
                        const double dt = 50.0 * stable(&s);
                        for (int n = 0; n < (int)scaled(20, 4); ++n) scene_step(&s, dt, &w);
                    }
                    free(h);
                    scene_destroy(&s);
                }
    finish_test("height jumps 1e-9 .. 1e6", &w);
}

/* Angles of repose from 0.5 to 89.5 degrees: a column some times tan(theta)
 * high collapses to rest; at 0.5 degrees it spreads over the whole grid, at
 * 89.5 it barely moves. Two rest tolerances. */
static void test_repose_angles(void **state) {
    (void)state;
    stress_worst_t w;
    stress_worst_reset(&w);
    const double angles[] = {0.5, 1.0, 2.0, 5.0, 15.0, 30.0, 45.0, 60.0, 75.0, 85.0, 88.0, 89.0, 89.5};
    const int64_t n1 = scaled(40, 8), n2 = scaled(24, 6);
    for (int f = 0; f < NFLAVOURS; ++f)
        for (size_t k = 0; k < sizeof angles / sizeof angles[0]; ++k)
            for (int variant = 0; variant < 2; ++variant) {
                const flavour_t *fl = &kFlavours[f];
                const double theta = deg(angles[k]), tol = variant ? 1e-9 : 1e-6;
                const int64_t nx = fl->geom == GEOM_2D ? n2 : n1, ny = fl->geom == GEOM_2D ? n2 + 1 : 1;
                scene_t s;
                make_scene(&s, fl, nx, ny, 1.0, "theta = %g deg, tol %g, %s", angles[k], tol,
                           variant ? "open" : "walls");
                scene_set_angle(&s, theta);
                scene_set_tolerance(&s, tol);
                scene_set_all_sides(&s, variant);
                const double top = fmax(1.0, 6.0 * tan(theta));
                double *h = terrain(&s, 0.0, 0.1 * top, top, 77u + k);
                if (variant)
                    for (int64_t c = 0; c < s.n; ++c) h[c] += 0.2 * top; /* above the outside */
                scene_set_heights(&s, h);
                scene_run_to_rest(&s, 1e12, 2, &w);
                free(h);
                scene_destroy(&s);
            }
    finish_test("angles of repose 0.5 .. 89.5 degrees", &w);
}

/* The physics of real scenes at their extremes, each checked by every
 * invariant after every step (the rest check by each face's own law):
 *  - a bed of rough rock at slope 3 (72 degrees) under sand 1e-9 to 10 thick,
 *    eroded at 1e3 per unit time on some columns (far more than is there) and
 *    fed on others, then to rest without the source;
 *  - an angle of repose per cell, drawn from 0.5 to 89.5 degrees;
 *  - flux exponents 1.5 and 2 on a wall of sand 1e6 high;
 *  - hysteresis with a static angle of 35 and of 89 degrees over 30. */
static void test_physics_extremes(void **state) {
    (void)state;
    stress_worst_t w;
    stress_worst_reset(&w);
    const int64_t n1 = scaled(60, 10), n2 = scaled(24, 6);
    for (int f = 0; f < NFLAVOURS; ++f)
        for (int variant = 0; variant < 5; ++variant) {
            const flavour_t *fl = &kFlavours[f];
            const int64_t nx = fl->geom == GEOM_2D ? n2 : n1, ny = fl->geom == GEOM_2D ? n2 + 3 : 1;
            static const char *const names[] = {"bed eroded beyond its sand", "angle field 0.5 .. 89.5 deg",
                                                "flux exponent 1.5, wall 1e6", "flux exponent 2, wall 1e6",
                                                "static angles 35 and 89 deg"};
            scene_t s;
            make_scene(&s, fl, nx, ny, 0.5, "%s", names[variant]);
            uint64_t r = 9090u + (uint64_t)(variant + 10 * f);
            double *h = terrain(&s, 0.0, 0.1, 4.0, r);
            if (variant == 0) {
                double *zb = malloc(sizeof(double) * (size_t)s.n), *q = calloc((size_t)s.n, sizeof(double));
                REQUIRE(zb && q, "out of memory");
                static const double layers[] = {1e-9, 1e-3, 1.0, 10.0};
                for (int64_t c = 0; c < s.n; ++c) {
                    const int64_t i = c % s.nx;
                    zb[c] = 3.0 * 0.5 * (double)(s.nx - i) + 0.2 * rng_uniform(&r);
                    h[c] = zb[c] + layers[(i / 3 + c / s.nx) % 4];
                    if (i % 5 == 2) q[c] = -1e3;
                    if (i % 7 == 4) q[c] = 0.1;
                }
                scene_set_side(&s, DPSM_XMAX, 1);
                scene_set_heights(&s, h);
                scene_set_bed(&s, zb);
                scene_set_source(&s, q);
                const double dt = stable(&s);
                for (int k = 0; k < 30; ++k) scene_step(&s, dt * (k % 3 == 0 ? 1.0 : k % 3 == 1 ? 10.0 : 100.0), &w);
                scene_set_source(&s, NULL);
                if (fl->geom != GEOM_2D || fl->scheme == DPSM_SCHEME_PAIRWISE) scene_run_to_rest(&s, 1e12, 2, &w);
                free(zb);
                free(q);
            } else if (variant == 1) {
                double *theta = malloc(sizeof(double) * (size_t)s.n);
                REQUIRE(theta != NULL, "out of memory");
                for (int64_t c = 0; c < s.n; ++c) theta[c] = deg(0.5 + 89.0 * rng_uniform(&r));
                scene_set_heights(&s, h);
                scene_set_angle_field(&s, theta);
                scene_run_to_rest(&s, 1e6 * stable(&s), 4, &w); /* bounded: a regression fails, not hangs */
                free(theta);
            } else if (variant == 2 || variant == 3) {
                for (int64_t c = 0; c < s.n; ++c) h[c] = (c % s.nx) < s.nx / 2 ? 1e6 : 0.0;
                scene_set_heights(&s, h);
                scene_set_flux_exponent(&s, variant == 2 ? 1.5 : 2.0);
                const double dt = stable(&s);
                for (int k = 0; k < 20; ++k) scene_step(&s, dt, &w);
                scene_step(&s, 1e3 * dt, &w);
            } else {
                scene_set_heights(&s, h);
                scene_set_static_angle(&s, deg(35.0));
                scene_run_to_rest(&s, 1e12, 2, &w);
                scene_set_static_angle(&s, deg(89.0)); /* the pile at rest under 35 degrees stays */
                scene_set_heights(&s, s.h);
                scene_run_to_rest(&s, 1e12, 1, &w);
            }
            free(h);
            scene_destroy(&s);
        }
    finish_test("physics of real scenes at their extremes", &w);
}

/* Random rough terrains: white noise of amplitude 1 and 10, a smooth field
 * with noise, above the level of open sides and below it (sand then comes in
 * from outside), a checkerboard of +-amp and lone spikes; on square cells and
 * on cells ten times wider or narrower in y. */
static void test_rough_terrains(void **state) {
    (void)state;
    stress_worst_t w;
    stress_worst_reset(&w);
    const int64_t n1 = scaled(200, 16), n2 = scaled(48, 8);
    const double aspects[] = {1.0, 0.1, 10.0};
    for (int f = 0; f < NFLAVOURS; ++f)
        for (size_t a = 0; a < (kFlavours[f].geom == GEOM_2D ? 3u : 1u); ++a)
            for (int seed = 0; seed < 8; ++seed) {
                const flavour_t *fl = &kFlavours[f];
                const int64_t nx = fl->geom == GEOM_2D ? n2 : n1, ny = fl->geom == GEOM_2D ? n2 - 5 : 1;
                const int open = seed & 1, below = seed == 5;
                const double amp = seed < 2 ? 1.0 : seed < 4 ? 10.0 : 3.0;
                const char *kind = seed < 4 ? "noise" : seed < 6 ? "hills and noise" : seed == 6 ? "checkerboard" : "spikes";
                scene_t s;
                make_scene_dy(&s, fl, nx, ny, 0.5, 0.5 * aspects[a], "%s seed %d amp %g, dy/dx %g, %s%s", kind, seed,
                              amp, aspects[a], open ? "open" : "walls", below ? ", below the outside" : "");
                scene_set_all_sides(&s, open);
                uint64_t r = 4242u + (uint64_t)(seed + 10 * f);
                double *h = terrain(&s, below ? -2.0 * amp : 0.0, amp, 0.0, r);
                for (int64_t j = 0; j < s.ny; ++j)
                    for (int64_t i = 0; i < s.nx; ++i) {
                        double *hc = &h[i + s.nx * j];
                        if (seed == 4 || seed == 5) *hc += 5.0 * sin(0.3 * (double)i) * cos(0.2 * (double)j + 1.0);
                        if (seed == 6) *hc = (i + j) % 2 ? amp : -amp;
                        if (seed == 7) *hc = rng_uniform(&r) < 0.05 ? 20.0 * amp * rng_uniform(&r) : 0.0;
                    }
                scene_set_heights(&s, h);
                /* Single sub-steps first (the maximum principle step by step), then to rest. */
                const double dt = stable(&s);
                for (int k = 0; k < 20; ++k) scene_step(&s, dt, &w);
                scene_run_to_rest(&s, 1e12, 2, &w);
                free(h);
                scene_destroy(&s);
            }
    finish_test("rough terrains", &w);
}

/* Levels beyond the sides, face by face at random within +-amp of a base
 * (amp from 1e-3 to 1e6, the base above or below the sand), on open sides and
 * on a wall side; a bed set before the sand on some scenes. Driven by the
 * levels that differ: bounded steps; then, where amp is small enough for sand
 * to get there in a few million sub-steps (the flux of a face is at most nu),
 * every level at the same base and no open cell: it must come to rest. */
static void test_side_levels(void **state) {
    (void)state;
    stress_worst_t w;
    stress_worst_reset(&w);
    const int64_t n1 = scaled(80, 10), n2 = scaled(40, 8);
    const double amps[] = {1e-3, 1.0, 30.0, 1e6};
    for (int f = 0; f < NFLAVOURS; ++f)
        for (int a = 0; a < 4; ++a)
            for (int below = 0; below < 2; ++below) {
                const flavour_t *fl = &kFlavours[f];
                const int64_t nx = fl->geom == GEOM_2D ? n2 : n1, ny = fl->geom == GEOM_2D ? n2 + 7 : 1;
                const double amp = amps[a], base = below ? -3.0 * amp : 2.0 * amp;
                scene_t s;
                make_scene(&s, fl, nx, ny, 0.5, "side levels +-%g around %g%s", amp, base,
                           a == 2 ? ", a bed set first" : "");
                uint64_t r = 777u + (uint64_t)(a + 10 * below + 100 * f);
                double *h = terrain(&s, 0.0, amp, 2.0 * amp, r);
                if (a == 2) { /* the bed first, on the fresh grid: it lifts the surface */
                    double *zb = malloc(sizeof(double) * (size_t)s.n);
                    REQUIRE(zb != NULL, "out of memory");
                    for (int64_t c = 0; c < s.n; ++c) {
                        zb[c] = h[c] - amp * rng_uniform(&r);
                        h[c] = fmax(h[c], zb[c]);
                    }
                    scene_set_bed(&s, zb);
                    free(zb);
                }
                scene_set_heights(&s, h);
                const int64_t longest = nx > ny ? nx : ny;
                double *levels = malloc(sizeof(double) * (size_t)longest);
                REQUIRE(levels != NULL, "out of memory");
                for (int side = DPSM_XMIN; side <= (fl->geom == GEOM_2D ? DPSM_YMAX : DPSM_XMAX); ++side) {
                    if (fl->geom == GEOM_AXI && side == DPSM_XMIN) continue;
                    for (int64_t k = 0; k < longest; ++k) levels[k] = base + amp * (2.0 * rng_uniform(&r) - 1.0);
                    scene_set_side_levels(&s, side, levels);
                    scene_set_side(&s, side, side != DPSM_XMAX || fl->geom == GEOM_AXI); /* XMAX a wall off disks */
                }
                const double dt = stable(&s);
                for (int k = 0; k < 15; ++k) scene_step(&s, dt * (k % 3 == 0 ? 1.0 : k % 3 == 1 ? 7.0 : 50.0), &w);
                for (int64_t k = 0; k < longest; ++k) levels[k] = base;
                for (int side = DPSM_XMIN; side <= (fl->geom == GEOM_2D ? DPSM_YMAX : DPSM_XMAX); ++side)
                    if (!(fl->geom == GEOM_AXI && side == DPSM_XMIN)) scene_set_side_levels(&s, side, levels);
                if (amp <= 1.0 && (fl->geom != GEOM_2D || fl->scheme == DPSM_SCHEME_PAIRWISE))
                    scene_run_to_rest(&s, 1e12, 2, &w);
                free(levels);
                free(h);
                scene_destroy(&s);
            }
    finish_test("side levels", &w);
}

/* 1x1, 1xN, Nx1, 2xN, long thin grids, tile edges (64), each side open or
 * not, with a pile to collapse, then a few steps with a source. */
static void test_grid_shapes(void **state) {
    (void)state;
    stress_worst_t w;
    stress_worst_reset(&w);
    const int64_t L = scaled(3000, 100);
    const int64_t shapes2d[][2] = {{1, 1}, {1, 2}, {2, 1}, {1, 300}, {300, 1}, {2, 500}, {500, 2},
                                   {3, L},  {L, 3}, {64, 1}, {65, 1},  {1, 65},   {65, 65}, {130, 67}};
    const int64_t lengths1d[] = {1, 2, 3, 1000};
    for (int open_mask = 0; open_mask < 4; ++open_mask) {
        for (size_t k = 0; k < sizeof shapes2d / sizeof shapes2d[0]; ++k)
            for (int scheme = 0; scheme < 2; ++scheme) {
                const flavour_t fl = {GEOM_2D, scheme};
                scene_t s;
                make_scene(&s, &fl, shapes2d[k][0], shapes2d[k][1], 1.0, "sides %d", open_mask);
                scene_set_side(&s, DPSM_XMIN, open_mask & 1);
                scene_set_side(&s, DPSM_YMAX, (open_mask >> 1) & 1);
                double *h = terrain(&s, 2.0, 0.5, 3.0, 99u + k);
                scene_set_heights(&s, h);
                scene_run_to_rest(&s, 1e12, 2, &w);
                for (int64_t c = 0; c < s.n; ++c) h[c] = c % 2 ? 0.01 : -0.005;
                scene_set_source(&s, h);
                for (int n = 0; n < 5; ++n) scene_step(&s, 10.0, &w);
                scene_set_source(&s, NULL);
                scene_run_to_rest(&s, 1e12, 2, &w);
                free(h);
                scene_destroy(&s);
            }
        for (size_t k = 0; k < sizeof lengths1d / sizeof lengths1d[0]; ++k)
            for (int geom = GEOM_1D; geom <= GEOM_AXI; geom += 2) {
                const flavour_t fl = {geom, 0};
                scene_t s;
                make_scene(&s, &fl, lengths1d[k], 1, 1.0, "sides %d", open_mask);
                if (geom == GEOM_1D) scene_set_side(&s, DPSM_XMIN, open_mask & 1);
                scene_set_side(&s, DPSM_XMAX, (open_mask >> 1) & 1);
                double *h = terrain(&s, 2.0, 0.5, 3.0, 7u + k);
                scene_set_heights(&s, h);
                scene_run_to_rest(&s, 1e12, 2, &w);
                for (int64_t c = 0; c < s.n; ++c) h[c] = c % 2 ? 0.01 : -0.005;
                scene_set_source(&s, h);
                for (int n = 0; n < 5; ++n) scene_step(&s, 10.0, &w);
                scene_set_source(&s, NULL);
                scene_run_to_rest(&s, 1e12, 2, &w);
                free(h);
                scene_destroy(&s);
            }
    }
    finish_test("grid shapes", &w);
}

/* Walls, obstacles, open cells (sinks at random levels) and sources mixed.
 * Driven (a source, or sinks at different levels): bounded steps. Then the
 * sinks all at 0 and no source: it must come to rest by itself. */
static void test_masks_and_sources(void **state) {
    (void)state;
    stress_worst_t w;
    stress_worst_reset(&w);
    const int64_t n1 = scaled(120, 12), n2 = scaled(70, 10);
    for (int f = 0; f < NFLAVOURS; ++f)
        for (int seed = 0; seed < 4; ++seed) {
            const flavour_t *fl = &kFlavours[f];
            const int64_t nx = fl->geom == GEOM_2D ? n2 : n1, ny = fl->geom == GEOM_2D ? n2 - 7 : 1;
            scene_t s;
            make_scene(&s, fl, nx, ny, 1.0, "masks and sources seed %d", seed);
            uint64_t r = 31337u + (uint64_t)(seed + 10 * f);
            scene_set_side(&s, DPSM_XMAX, seed & 1);
            if (fl->geom == GEOM_2D) scene_set_side(&s, DPSM_YMIN, (seed >> 1) & 1);
            uint8_t *kinds = malloc((size_t)s.n);
            double *h = terrain(&s, 3.0, 2.0, 6.0, r);
            double *q = malloc(sizeof(double) * (size_t)s.n);
            for (int64_t c = 0; c < s.n; ++c) {
                const double u = rng_uniform(&r);
                kinds[c] = u < 0.7 ? DPSM_CELL_SAND : u < 0.85 ? DPSM_CELL_WALL : DPSM_CELL_OPEN;
                q[c] = rng_uniform(&r) < 0.2 ? 0.05 * (rng_uniform(&r) - 0.3) : 0.0;
            }
            scene_set_heights(&s, h);
            scene_set_kinds(&s, kinds);
            scene_set_source(&s, q);
            const double dt = 3.0 * stable(&s);
            for (int n = 0; n < (int)scaled(60, 10); ++n) scene_step(&s, dt, &w);
            scene_set_source(&s, NULL); /* sinks at different levels: still driven */
            for (int n = 0; n < (int)scaled(30, 5); ++n) scene_step(&s, dt, &w);
            REQUIRE(dpsm_get_heights(s.g, h) == DPSM_OK, "get_heights");
            for (int64_t c = 0; c < s.n; ++c)
                if (kinds[c] == DPSM_CELL_OPEN) h[c] = 0.0;
            scene_set_heights(&s, h);
            scene_run_to_rest(&s, 1e12, 2, &w);
            /* Obstacles become sand again (bringing their heights on), then rest. */
            scene_set_kinds(&s, NULL);
            scene_run_to_rest(&s, 1e12, 2, &w);
            free(kinds);
            free(h);
            free(q);
            scene_destroy(&s);
        }
    finish_test("walls, obstacles, open cells and sources", &w);
}

/* A request no method here can finish in bounded work fails at once with
 * DPSM_ERR_WORK_LIMIT and a clear message, and changes nothing: a source
 * over dt = 1e12, sinks at different levels over 1e12 or 1e300, a dt one
 * sub-step over the limit; a step that fits still works afterwards. The
 * source over 1e300 would carry the sand beyond the supported range: that is
 * refused first, with DPSM_ERR_INVALID_VALUE. */
static void test_work_limit(void **state) {
    (void)state;
    stress_worst_t w;
    stress_worst_reset(&w);
    const int64_t sizes[][2] = {{1, 1}, {7, 5}, {100, 3}};
    for (int f = 0; f < NFLAVOURS; ++f)
        for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; ++k)
            for (int driver = 0; driver < 3; ++driver) {
                const flavour_t *fl = &kFlavours[f];
                scene_t s;
                make_scene(&s, fl, sizes[k][0], sizes[k][1], 1.0, "work limit, %s",
                           driver == 0 ? "source" : driver == 1 ? "sinks at two levels" : "sink above an open side");
                double *h = terrain(&s, 1.0, 0.5, 2.0, 5u + k);
                scene_set_heights(&s, h);
                if (driver == 0) {
                    /* A source raises the sand above the open side's level:
                     * it makes a face steep (a source that cannot is applied
                     * in closed form and is not limited). */
                    for (int64_t c = 0; c < s.n; ++c) h[c] = 1e-3;
                    scene_set_source(&s, h);
                    scene_set_side(&s, DPSM_XMAX, 1);
                } else {
                    uint8_t *kinds = calloc((size_t)s.n, 1);
                    if (driver == 1 && s.n >= 2) {
                        kinds[0] = kinds[s.n - 1] = DPSM_CELL_OPEN;
                        h[0] = 5.0;
                        h[s.n - 1] = -5.0;
                    } else {
                        kinds[0] = DPSM_CELL_OPEN;
                        h[0] = 3.0;
                        scene_set_side(&s, DPSM_XMAX, 1);
                    }
                    scene_set_heights(&s, h);
                    scene_set_kinds(&s, kinds);
                    free(kinds);
                }
                scene_step(&s, 0.5, &w);
                const double sdt = stable(&s);
                expect_work_limit(&s, 1e12);
                if (driver == 0) {
                    expect_step_refused_on(s.g, s.n, s.name, 1e300, DPSM_ERR_INVALID_VALUE, "supported range");
                    expect_step_refused_on(s.g, s.n, s.name, DBL_MAX, DPSM_ERR_INVALID_VALUE, "supported range");
                } else {
                    expect_work_limit(&s, 1e300);
                    expect_work_limit(&s, DBL_MAX);
                }
                REQUIRE(dpsm_set_max_substeps(s.g, 10) == DPSM_OK, "set_max_substeps");
                expect_work_limit(&s, 11.5 * sdt);
                scene_step(&s, 9.5 * sdt, &w);
                REQUIRE(dpsm_set_max_substeps(s.g, 1) == DPSM_OK, "set_max_substeps");
                expect_work_limit(&s, 2.0 * sdt);
                scene_step(&s, 0.999 * sdt, &w);
                free(h);
                scene_destroy(&s);
            }
    finish_test("work limit", &w);
}

/* 100 000 small steps with a source, sinks and open sides: the ledger must
 * still close to 1e-12 (it is checked after every step). */
static void test_many_small_steps(void **state) {
    (void)state;
    stress_worst_t w;
    stress_worst_reset(&w);
    const int64_t steps = scaled(100000, 2000);
    for (int f = 0; f < NFLAVOURS; ++f) {
        const flavour_t *fl = &kFlavours[f];
        const int64_t nx = fl->geom == GEOM_2D ? 20 : 60, ny = fl->geom == GEOM_2D ? 16 : 1;
        scene_t s;
        make_scene(&s, fl, nx, ny, 0.25, "%lld small steps", (long long)steps);
        scene_set_side(&s, DPSM_XMAX, 1);
        uint8_t *kinds = calloc((size_t)s.n, 1);
        kinds[s.n / 3] = DPSM_CELL_WALL;
        kinds[s.n / 2] = DPSM_CELL_OPEN;
        double *h = terrain(&s, 1.0, 0.3, 1.0, 123u + (uint64_t)f);
        scene_set_heights(&s, h);
        scene_set_kinds(&s, kinds);
        for (int64_t c = 0; c < s.n; ++c) h[c] = (c % 5 == 0) ? 0.02 : (c % 7 == 0 ? -0.004 : 0.0);
        scene_set_source(&s, h);
        const double dt = 0.37 * stable(&s);
        for (int64_t n = 0; n < steps; ++n) scene_step(&s, dt, &w);
        free(kinds);
        free(h);
        scene_destroy(&s);
    }
    finish_test("100 000 small steps", &w);
}

static void test_summary(void **state) {
    (void)state;
    stress_worst_print("stress suite, worst over all tests", &stress_worst);
    assert_int_equal(stress_worst.nonfinite, 0);
}

int main(int argc, char **argv) {
    if (argc > 1) cmocka_set_test_filter(argv[1]);
    stress_worst_reset(&stress_worst);
    print_message("stress scale %g (DPSM_STRESS_SCALE)\n", stress_scale());
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_time_steps),     cmocka_unit_test(test_height_jumps),
        cmocka_unit_test(test_repose_angles),  cmocka_unit_test(test_rough_terrains),
        cmocka_unit_test(test_grid_shapes),    cmocka_unit_test(test_masks_and_sources),
        cmocka_unit_test(test_physics_extremes), cmocka_unit_test(test_work_limit),     cmocka_unit_test(test_many_small_steps),
        cmocka_unit_test(test_side_levels),
        cmocka_unit_test(test_summary),
    };
    return cmocka_run_group_tests_name("stress", tests, NULL, NULL);
}
