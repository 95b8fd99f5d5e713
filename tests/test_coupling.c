/* What a host needs to couple (issue 17): the volume each face carried, what
 * left through each side, a level beyond each open side; a bed set before the
 * sand; a default step that keeps the flow's time. Each test asserts what
 * dpsm.h promises, on every kind of grid where it applies:
 *
 *  - face fluxes: for every sand cell, what its faces brought in less what
 *    they took out is its change of height times its area less what its
 *    source added (with a bed: less what the source could apply, which
 *    DPSM_MASS_SOURCED and DPSM_MASS_UNMET tell); the faces of an open side
 *    add up to what the side took in the step, the faces next to open cells
 *    to what those took; faces of walls carry nothing; a step at rest, and
 *    tiles a step did not visit, read 0;
 *  - side levels: a sheet at the outside's level stays as it is; a higher
 *    outside fills an empty domain up to the angle of repose, and the inflow
 *    booked is the mass gained; levels on a wall side act once it is open;
 *    the sides and the open cells make up DPSM_MASS_OUTFLOW, in the
 *    relaxation to rest too;
 *  - the bed: set on a fresh grid it lifts the surface and books the sand
 *    as external; above some cells of a pile it lifts those only;
 *  - the default step integrates dt, as DPSM_RELAX_TIME_ACCURATE does. */
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

static const double kPi = 3.14159265358979323846;
static const double kDeg = 3.14159265358979323846 / 180.0;

/* ------------------------------------------------------------------------ */
/* Scenes and the balance of a step                                          */
/* ------------------------------------------------------------------------ */

enum { LINE = 1, PLANE = 2, AXI = 3 };
static const char *const kKindNames[4] = {"", "1D", "2D", "axisymmetric"};

/* A grid and what the test set on it (the library keeps its own copies). */
typedef struct {
    dpsm_grid *g;
    int kind; /* LINE, PLANE or AXI */
    int64_t nx, ny, n;
    double dx, dy;
    uint8_t *kinds; /* as set */
    double *q;      /* as set; all 0 without a source */
    double *zb;     /* NULL: no bed */
    int open[4];
} scene_t;

static scene_t scene_new(int kind, int64_t nx, int64_t ny, double dx, double dy) {
    scene_t s = {0};
    s.kind = kind;
    s.nx = nx;
    s.ny = kind == PLANE ? ny : 1;
    s.n = s.nx * s.ny;
    s.dx = dx;
    s.dy = kind == PLANE ? dy : 1.0;
    if (kind == LINE) CHECK_OK(NULL, dpsm_create_1d(nx, dx, &s.g));
    if (kind == PLANE) CHECK_OK(NULL, dpsm_create_2d(nx, ny, dx, dy, &s.g));
    if (kind == AXI) CHECK_OK(NULL, dpsm_create_axisymmetric(nx, dx, &s.g));
    s.kinds = calloc((size_t)s.n, 1);
    s.q = calloc((size_t)s.n, sizeof(double));
    assert_non_null(s.kinds);
    assert_non_null(s.q);
    CHECK_OK(s.g, dpsm_set_face_flux_recording(s.g, 1));
    return s;
}

static void scene_free(scene_t *s) {
    dpsm_destroy(s->g);
    free(s->kinds);
    free(s->q);
    free(s->zb);
}

static void scene_open(scene_t *s, int side, double level) {
    double levels[512];
    const int64_t faces = s->kind != PLANE ? 1 : side <= DPSM_XMAX ? s->ny : s->nx;
    assert_true(faces <= 512);
    for (int64_t k = 0; k < faces; ++k) levels[k] = level;
    CHECK_OK(s->g, dpsm_set_boundary(s->g, side, DPSM_OPEN));
    CHECK_OK(s->g, dpsm_set_side_levels(s->g, side, levels));
    s->open[side] = 1;
}

static void scene_set_kinds(scene_t *s) { CHECK_OK(s->g, dpsm_set_cell_kinds(s->g, s->kinds)); }
static void scene_set_source(scene_t *s) { CHECK_OK(s->g, dpsm_set_source(s->g, s->q)); }
static void scene_set_bed(scene_t *s, const double *zb) {
    free(s->zb);
    s->zb = malloc(sizeof(double) * (size_t)s->n);
    assert_non_null(s->zb);
    memcpy(s->zb, zb, sizeof(double) * (size_t)s->n);
    CHECK_OK(s->g, dpsm_set_bedrock(s->g, zb));
}

static double cell_area(const scene_t *s, int64_t c) {
    if (s->kind == AXI) return kPi * (double)(2 * c + 1) * s->dx * s->dx;
    return s->dx * s->dy;
}

/* The four sides a grid has. */
static int has_side(const scene_t *s, int side) {
    if (side >= DPSM_YMIN) return s->kind == PLANE;
    return !(s->kind == AXI && side == DPSM_XMIN);
}

static double outflow_of_side(const dpsm_grid *g, int side) {
    double v = 0.0;
    CHECK_OK(g, dpsm_get_side_outflow(g, side, &v));
    return v;
}
static double side_outflow(const scene_t *s, int side) { return outflow_of_side(s->g, side); }

/* A step's faces: x faces (nx+1)*ny, y faces nx*(ny+1) (none on a line). */
typedef struct {
    double *x, *y;
    size_t nfx, nfy;
} faces_t;

static faces_t read_faces(const scene_t *s) {
    faces_t f;
    f.nfx = (size_t)((s->nx + 1) * s->ny);
    f.nfy = s->kind == PLANE ? (size_t)(s->nx * (s->ny + 1)) : 0;
    f.x = malloc(sizeof(double) * f.nfx);
    f.y = malloc(sizeof(double) * (f.nfy ? f.nfy : 1));
    assert_non_null(f.x);
    assert_non_null(f.y);
    CHECK_OK(s->g, dpsm_get_face_fluxes(s->g, f.x, s->kind == PLANE ? f.y : NULL));
    return f;
}

static void faces_free(faces_t *f) {
    free(f->x);
    free(f->y);
}

/* The faces of cell (i, j): low x, high x, low y, high y (y: -1 on a line). */
static void faces_of(const scene_t *s, int64_t i, int64_t j, int64_t at[4]) {
    at[0] = i + (s->nx + 1) * j;
    at[1] = at[0] + 1;
    at[2] = s->kind == PLANE ? i + s->nx * j : -1;
    at[3] = s->kind == PLANE ? i + s->nx * (j + 1) : -1;
}

/* What the faces of cell (i, j) brought in, and the sum of their magnitudes. */
static double net_in(const scene_t *s, const faces_t *f, int64_t i, int64_t j, double *gross) {
    int64_t at[4];
    faces_of(s, i, j, at);
    double in = f->x[at[0]] - f->x[at[1]];
    *gross = fabs(f->x[at[0]]) + fabs(f->x[at[1]]);
    if (at[2] >= 0) {
        in += f->y[at[2]] - f->y[at[3]];
        *gross += fabs(f->y[at[2]]) + fabs(f->y[at[3]]);
    }
    return in;
}

/* The volume the faces of a side carried out of the domain. */
static double carried_out(const scene_t *s, const faces_t *f, int side, double *gross) {
    double out = 0.0;
    *gross = 0.0;
    const int64_t along = side <= DPSM_XMAX ? s->ny : s->nx;
    for (int64_t k = 0; k < along; ++k) {
        double v;
        if (side == DPSM_XMIN) v = -f->x[(s->nx + 1) * k];
        else if (side == DPSM_XMAX) v = f->x[s->nx + (s->nx + 1) * k];
        else if (side == DPSM_YMIN) v = -f->y[k];
        else v = f->y[k + s->nx * s->ny];
        out += v;
        *gross += fabs(v);
    }
    return out;
}

/* Round-off of sums of figures of magnitude `scale`. */
static double roundoff(double scale) { return 1e-13 * scale + 1e-300; }

/* The worst balance of a sand cell seen so far, relative to its figures. */
static double g_worst_cell;

/* What a step showed: its fluxes checked against what it did. */
typedef struct {
    double moved;    /* sum of |face| over all faces */
    double inflow;   /* what came in through the sides (minus what left) */
    int at_rest;
} step_seen_t;

/* Steps the scene by dt and checks the step's fluxes against the change of
 * every sand cell, the sides' and open cells' outflow, the walls, and the
 * source applied (with a bed, within what it asked and as booked). */
static step_seen_t step_and_check(scene_t *s, double dt, const char *what) {
    const int64_t n = s->n;
    double *h0 = malloc(sizeof(double) * (size_t)n), *h1 = malloc(sizeof(double) * (size_t)n);
    assert_non_null(h0);
    assert_non_null(h1);
    CHECK_OK(s->g, dpsm_get_heights(s->g, h0));
    double side0[4] = {0};
    for (int side = 0; side < 4; ++side)
        if (has_side(s, side)) side0[side] = side_outflow(s, side);
    const double outflow0 = mass_of(s->g, DPSM_MASS_OUTFLOW), sourced0 = mass_of(s->g, DPSM_MASS_SOURCED);
    const double unmet0 = mass_of(s->g, DPSM_MASS_UNMET);

    CHECK_OK(s->g, dpsm_step(s->g, dt));
    CHECK_OK(s->g, dpsm_get_heights(s->g, h1));
    faces_t f = read_faces(s);
    const double time = step_info_of(s->g, DPSM_INFO_TIME_INTEGRATED);
    step_seen_t seen = {0};
    seen.at_rest = step_info_of(s->g, DPSM_INFO_AT_REST) == 1.0;
    for (size_t k = 0; k < f.nfx; ++k) seen.moved += fabs(f.x[k]);
    for (size_t k = 0; k < f.nfy; ++k) seen.moved += fabs(f.y[k]);

    /* Cell by cell: sand cells balance, held cells keep their height, and
     * walls' faces carry nothing. */
    double applied = 0.0, applied_scale = 0.0, asked = 0.0, into_open_cells = 0.0, open_gross = 0.0;
    for (int64_t j = 0; j < s->ny; ++j)
        for (int64_t i = 0; i < s->nx; ++i) {
            const int64_t c = i + s->nx * j;
            double gross = 0.0;
            const double in = net_in(s, &f, i, j, &gross);
            if (s->kinds[c] == DPSM_CELL_WALL) {
                REQUIRE(gross == 0.0, "%s: the faces of wall cell (%lld, %lld) carried %g", what, (long long)i,
                        (long long)j, gross);
                continue;
            }
            if (s->kinds[c] == DPSM_CELL_OPEN) {
                REQUIRE(memcmp(&h0[c], &h1[c], sizeof(double)) == 0, "%s: open cell %lld moved", what, (long long)c);
                into_open_cells += in;
                open_gross += gross;
                continue;
            }
            const double area = cell_area(s, c), change = (h1[c] - h0[c]) * area;
            const double source = change - in, want = s->q[c] * time * area;
            const double scale = fmax(fabs(h0[c]), fabs(h1[c])) * area + gross + fabs(want);
            asked += want;
            applied += source;
            applied_scale += scale;
            if (!s->zb || s->q[c] >= 0.0) g_worst_cell = fmax(g_worst_cell, fabs(source - want) / scale);
            if (!s->zb || s->q[c] >= 0.0)
                REQUIRE(fabs(source - want) <= roundoff(scale),
                        "%s: cell (%lld, %lld) changed by %.17g, its faces brought %.17g, its source %.17g: off by %.3g "
                        "(%.3g of the cell's figures)",
                        what, (long long)i, (long long)j, change, in, want, source - want, (source - want) / scale);
            else /* erosion on a bed: at most what was asked, none added */
                REQUIRE(source >= want - roundoff(scale) && source <= roundoff(scale),
                        "%s: eroding cell (%lld, %lld) on its bed lost %.17g to its source, which asked %.17g", what,
                        (long long)i, (long long)j, source, want);
        }
    const double sourced = mass_of(s->g, DPSM_MASS_SOURCED) - sourced0;
    const double unmet = mass_of(s->g, DPSM_MASS_UNMET) - unmet0;
    const double totals = fabs(sourced0) + fabs(unmet0);
    REQUIRE(fabs(applied - sourced) <= roundoff(applied_scale + totals),
            "%s: the cells took %.17g from their sources, SOURCED grew by %.17g", what, applied, sourced);
    REQUIRE(fabs(sourced - unmet - asked) <= roundoff(applied_scale + totals),
            "%s: SOURCED grew by %.17g, UNMET by %.17g, the sources asked %.17g", what, sourced, unmet, asked);

    /* Side by side: open sides' faces carry what the side took, walls' nothing.
     * What the ledger booked in the step is the difference of two running
     * totals: it is known to their round-off. */
    double sides = 0.0, sides_gross = 0.0, sides_total = 0.0;
    for (int side = 0; side < 4; ++side) {
        if (!has_side(s, side)) continue;
        double gross = 0.0;
        const double out = carried_out(s, &f, side, &gross), booked = side_outflow(s, side) - side0[side];
        if (!s->open[side])
            REQUIRE(gross == 0.0 && booked == 0.0, "%s: wall side %d: faces carried %g, booked %g", what, side, gross,
                    booked);
        REQUIRE(fabs(out - booked) <= roundoff(gross + fabs(side0[side]) + fabs(booked)),
                "%s: side %d: its faces carried %.17g out, dpsm_get_side_outflow grew by %.17g", what, side, out, booked);
        sides += booked;
        sides_gross += gross;
        sides_total += fabs(side0[side]);
    }
    seen.inflow = -sides;
    /* The sides and the open cells make DPSM_MASS_OUTFLOW. */
    const double outflow = mass_of(s->g, DPSM_MASS_OUTFLOW) - outflow0;
    REQUIRE(fabs(outflow - (sides + into_open_cells)) <=
                roundoff(sides_gross + open_gross + fabs(outflow0) + fabs(outflow) + sides_total),
            "%s: OUTFLOW grew by %.17g; the sides took %.17g, the open cells %.17g", what, outflow, sides,
            into_open_cells);
    REQUIRE(ledger_residual(s->g) <= 1e-13, "%s: ledger residual %g", what, ledger_residual(s->g));
    faces_free(&f);
    free(h0);
    free(h1);
    return seen;
}

/* ------------------------------------------------------------------------ */
/* Face fluxes                                                               */
/* ------------------------------------------------------------------------ */

/* A scene with everything a host couples: a pile and a ramp, a wall cell, an
 * open cell, two open sides held at different levels (sand comes in through
 * one), a bed under a thin layer where the source erodes faster than sand
 * lies there, and a deposit. 2D grids have a wall block and an open cell. */
static scene_t rich_scene(int kind, int scheme) {
    const int64_t nx = kind == PLANE ? 150 : 40, ny = 90; /* 2D: tiles with and without masks */
    scene_t s = scene_new(kind, nx, ny, 0.1, 0.12);
    CHECK_OK(s.g, dpsm_set_repose_angle(s.g, 32.0 * kDeg));
    if (kind == PLANE) CHECK_OK(s.g, dpsm_set_scheme(s.g, scheme));
    double *h = malloc(sizeof(double) * (size_t)s.n), *zb = malloc(sizeof(double) * (size_t)s.n);
    assert_non_null(h);
    assert_non_null(zb);
    for (int64_t j = 0; j < s.ny; ++j)
        for (int64_t i = 0; i < s.nx; ++i) {
            const int64_t c = i + s.nx * j;
            const double r = kind == PLANE ? hypot((double)i - 18.0, (double)j - 12.0) : fabs((double)i - 22.0);
            const double r2 = kind == PLANE ? hypot((double)i - 100.0, (double)j - 60.0) : 1e9; /* far from masks */
            h[c] = 0.1 + fmax(0.0, 1.5 - 0.25 * r) + fmax(0.0, 1.0 - 0.2 * r2) + 0.02 * (double)(i % 3);
            zb[c] = h[c] - (i < 8 ? 0.004 : 5.0); /* a thin layer by the low side */
            if (i >= 2 && i < 6) s.q[c] = -0.4;  /* erosion that outruns the thin layer */
            if (i >= 24 && i < 27) s.q[c] = 0.3;  /* deposition */
        }
    const int64_t wall = kind == PLANE ? 12 + s.nx * 5 : 12, open_cell = kind == PLANE ? 26 + s.nx * 20 : 34;
    s.kinds[wall] = DPSM_CELL_WALL;
    if (kind == PLANE)
        for (int64_t j = 14; j < 18; ++j) s.kinds[8 + s.nx * j] = DPSM_CELL_WALL;
    s.kinds[open_cell] = DPSM_CELL_OPEN;
    s.q[wall] = 1.0; /* sources on held cells: ignored */
    s.q[open_cell] = -1.0;
    h[open_cell] = 0.15;
    CHECK_OK(s.g, dpsm_set_heights(s.g, h));
    scene_set_kinds(&s);
    scene_set_bed(&s, zb);
    scene_set_source(&s);
    scene_open(&s, DPSM_XMAX, 0.0);
    if (kind != AXI) scene_open(&s, DPSM_XMIN, 0.6); /* above the cells there: sand comes in */
    if (kind == PLANE) scene_open(&s, DPSM_YMAX, 0.05);
    free(h);
    free(zb);
    return s;
}

static void check_rich_scene(int kind, int scheme, const char *name) {
    scene_t s = rich_scene(kind, scheme);
    double sdt = 0.0;
    CHECK_OK(s.g, dpsm_stable_dt(s.g, &sdt));
    const double dts[] = {0.5 * sdt, 3.0 * sdt, 40.0 * sdt, 400.0 * sdt};
    double moved = 0.0, inflow = 0.0;
    for (size_t k = 0; k < sizeof dts / sizeof *dts; ++k) {
        const step_seen_t seen = step_and_check(&s, dts[k], name);
        moved += seen.moved;
        inflow += seen.inflow;
    }
    /* The source off and the bed gone: the same checks on the slide alone. */
    memset(s.q, 0, sizeof(double) * (size_t)s.n);
    CHECK_OK(s.g, dpsm_set_source(s.g, NULL));
    free(s.zb);
    s.zb = NULL;
    CHECK_OK(s.g, dpsm_set_bedrock(s.g, NULL));
    for (int k = 0; k < 3; ++k) moved += step_and_check(&s, 25.0 * sdt, name).moved;
    printf("%s: faces carried %.4g in all, %.4g came in through the sides, UNMET %.4g; cells balance to %.2g\n", name,
           moved, inflow, mass_of(s.g, DPSM_MASS_UNMET), g_worst_cell);
    REQUIRE(moved > 0.0 && mass_of(s.g, DPSM_MASS_UNMET) > 0.0, "%s: the scene did not exercise the fluxes and the bed",
            name);
    scene_free(&s);
}

static void test_fluxes_balance_1d(void **state) {
    (void)state;
    check_rich_scene(LINE, DPSM_SCHEME_PAIRWISE, "1D");
}

static void test_fluxes_balance_2d_pairwise(void **state) {
    (void)state;
    check_rich_scene(PLANE, DPSM_SCHEME_PAIRWISE, "2D pairwise");
}

static void test_fluxes_balance_2d_isotropic(void **state) {
    (void)state;
    check_rich_scene(PLANE, DPSM_SCHEME_ISOTROPIC, "2D isotropic");
}

static void test_fluxes_balance_axisymmetric(void **state) {
    (void)state;
    check_rich_scene(AXI, DPSM_SCHEME_PAIRWISE, "axisymmetric");
}

/* A pile comes to rest; the step after it moves nothing, and every face of
 * that step reads exactly 0 (on every kind of grid). */
static void test_fluxes_zero_at_rest(void **state) {
    (void)state;
    for (int kind = LINE; kind <= AXI; ++kind) {
        scene_t s = scene_new(kind, 20, 16, 0.1, 0.1);
        double h[20 * 16] = {0};
        for (int64_t j = 0; j < s.ny; ++j) h[10 + s.nx * j] = 1.0;
        CHECK_OK(s.g, dpsm_set_heights(s.g, h));
        scene_open(&s, DPSM_XMAX, 0.0);
        const step_seen_t flowing = step_and_check(&s, 1e3, kKindNames[kind]);
        REQUIRE(flowing.moved > 0.0 && flowing.at_rest, "%s: the pile did not flow to rest", kKindNames[kind]);
        const step_seen_t resting = step_and_check(&s, 1.0, kKindNames[kind]);
        REQUIRE(resting.at_rest && resting.moved == 0.0, "%s: a step at rest carried %g", kKindNames[kind],
                resting.moved);
        scene_free(&s);
    }
}

/* A large 2D grid with a small pile: only the faces near it carry sand. Once
 * that pile has rested, a step that moves another pile far away leaves the
 * first pile's faces at 0 (the step did not visit its tiles). */
static void test_fluxes_of_tiles_not_visited_read_zero(void **state) {
    (void)state;
    enum { NX = 400, NY = 300 };
    scene_t s = scene_new(PLANE, NX, NY, 0.1, 0.1);
    double pile[5 * 5];
    for (int k = 0; k < 25; ++k) pile[k] = 2.0;
    CHECK_OK(s.g, dpsm_set_heights_region(s.g, 20, 30, 5, 5, pile));
    REQUIRE(step_and_check(&s, 1e3, "first pile").at_rest, "the first pile did not rest");
    faces_t first = read_faces(&s);
    CHECK_OK(s.g, dpsm_set_heights_region(s.g, 350, 250, 5, 5, pile));
    const step_seen_t second = step_and_check(&s, 1e3, "second pile");
    REQUIRE(second.at_rest && second.moved > 0.0, "the second pile did not flow to rest");
    faces_t f = read_faces(&s);
    size_t carried_first = 0;
    /* Faces away from the second pile read 0; the first pile's did carry sand. */
    for (int64_t j = 0; j < NY; ++j)
        for (int64_t i = 0; i <= NX; ++i) {
            const size_t at = (size_t)(i + (NX + 1) * j);
            if (first.x[at] != 0.0) ++carried_first;
            if (i < 300 || j < 200) REQUIRE(f.x[at] == 0.0, "x face (%lld, %lld) far from the moving pile reads %g",
                                           (long long)i, (long long)j, f.x[at]);
        }
    for (int64_t j = 0; j <= NY; ++j)
        for (int64_t i = 0; i < NX; ++i)
            if (i < 300 || j < 200)
                REQUIRE(f.y[i + NX * j] == 0.0, "y face (%lld, %lld) far from the moving pile reads %g", (long long)i,
                        (long long)j, f.y[i + NX * j]);
    REQUIRE(carried_first > 20, "the first pile's faces carried nothing (%zu)", carried_first);
    faces_free(&first);
    faces_free(&f);
    scene_free(&s);
}

/* ------------------------------------------------------------------------ */
/* Side levels                                                               */
/* ------------------------------------------------------------------------ */

/* A flat sheet at the level held beyond every open side (and every open
 * cell) loses nothing: outflow exactly 0, heights unchanged bit for bit, and
 * the step reports rest, however long it is. */
static void test_sheet_at_the_outside_level_stays(void **state) {
    (void)state;
    for (int kind = LINE; kind <= AXI; ++kind) {
        const double level = 0.75;
        scene_t s = scene_new(kind, 12, 9, 0.2, 0.3);
        double h[12 * 9], after[12 * 9];
        for (int c = 0; c < 12 * 9; ++c) h[c] = level;
        s.kinds[5] = DPSM_CELL_OPEN;
        scene_set_kinds(&s);
        CHECK_OK(s.g, dpsm_set_heights(s.g, h));
        for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side)
            if (has_side(&s, side)) scene_open(&s, side, level);
        const step_seen_t seen = step_and_check(&s, 1e6, kKindNames[kind]);
        CHECK_OK(s.g, dpsm_get_heights(s.g, after));
        REQUIRE(memcmp(h, after, sizeof(double) * (size_t)s.n) == 0, "%s: the sheet moved", kKindNames[kind]);
        REQUIRE(mass_of(s.g, DPSM_MASS_OUTFLOW) == 0.0 && seen.moved == 0.0 && seen.at_rest,
                "%s: outflow %g, faces carried %g, at rest %d", kKindNames[kind], mass_of(s.g, DPSM_MASS_OUTFLOW),
                seen.moved, seen.at_rest);
        scene_free(&s);
    }
}

/* An empty domain (a wall on every side but one) beside a higher outside:
 * sand comes in until the surface rises from the side at the angle of
 * repose, h = level - tan(theta) * distance from the outside node, within
 * the rest tolerance's share of that slope; the inflow booked is the mass
 * gained. Levels set while the side was a wall did nothing until it opened. */
static void check_fill(int kind, int side, const char *name) {
    const double level = 0.8, tol = 1e-3, theta = 30.0 * kDeg, dx = 0.05;
    scene_t s = scene_new(kind, 40, 6, dx, dx);
    CHECK_OK(s.g, dpsm_set_repose_angle(s.g, theta));
    CHECK_OK(s.g, dpsm_set_rest_tolerance(s.g, tol));
    double levels[40];
    for (int k = 0; k < 40; ++k) levels[k] = level;
    CHECK_OK(s.g, dpsm_set_side_levels(s.g, side, levels)); /* still a wall */
    const step_seen_t walled = step_and_check(&s, 1e3, name);
    REQUIRE(walled.at_rest && walled.moved == 0.0 && mass_of(s.g, DPSM_MASS_TOTAL) == 0.0,
            "%s: levels on a wall side moved sand (%g)", name, walled.moved);
    CHECK_OK(s.g, dpsm_set_boundary(s.g, side, DPSM_OPEN));
    s.open[side] = 1;
    step_seen_t seen = {0};
    double inflow = 0.0;
    for (int k = 0; k < 50 && !seen.at_rest; ++k) {
        seen = step_and_check(&s, 2.0, name);
        inflow += seen.inflow;
    }
    REQUIRE(seen.at_rest, "%s: not at rest", name);
    const double total = mass_of(s.g, DPSM_MASS_TOTAL);
    REQUIRE(total > 0.0 && fabs(inflow - total) <= 1e-12 * total && fabs(-side_outflow(&s, side) - total) <= 1e-12 * total,
            "%s: gained %.17g, inflow seen %.17g, booked %.17g", name, total, inflow, -side_outflow(&s, side));
    double h[40 * 6];
    CHECK_OK(s.g, dpsm_get_heights(s.g, h));
    const double slope = tan(theta);
    double worst = 0.0;
    for (int64_t j = 0; j < s.ny; ++j)
        for (int64_t i = 0; i < s.nx; ++i) {
            const int64_t k = side == DPSM_XMIN ? i : s.nx - 1 - i; /* cells from the side */
            const double distance = (double)(k + 1) * dx, exact = level - slope * distance;
            const double got = h[i + s.nx * j];
            if (exact > 2.0 * slope * dx) {
                /* No face steeper than tan(theta) (1 + tol), none shallower than
                 * tan(theta) where sand still came in. */
                worst = fmax(worst, fabs(got - exact) / (slope * distance));
                REQUIRE(got <= exact + 1e-12 && got >= level - slope * (1.0 + tol) * distance - 1e-12,
                        "%s: cell %lld from the side is at %.17g, the slope from the outside gives %.17g", name,
                        (long long)k, got, exact);
            } else if (exact < -2.0 * slope * dx) {
                REQUIRE(got == 0.0, "%s: cell %lld, beyond the foot, is at %g", name, (long long)k, got);
            }
        }
    printf("%s: filled %.6g from a level of %g, the profile within %.3g of the slope (tol %g)\n", name, total, level,
           worst, tol);
    scene_free(&s);
}

static void test_higher_outside_fills_to_the_angle_of_repose(void **state) {
    (void)state;
    check_fill(LINE, DPSM_XMIN, "1D, from XMIN");
    check_fill(LINE, DPSM_XMAX, "1D, from XMAX");
    check_fill(PLANE, DPSM_XMIN, "2D, from XMIN");
}

/* An axisymmetric table sunk below a ring held at a level: sand comes in
 * from the rim down to the angle of repose. */
static void test_higher_outside_fills_an_axisymmetric_table(void **state) {
    (void)state;
    check_fill(AXI, DPSM_XMAX, "axisymmetric, from the rim");
}

/* The relaxation to rest books each side's part too: a cone on a grid with
 * two open sides at 0, relaxed to rest, splits its outflow between them as
 * the time-accurate steps do (the deposits agree to a fraction of a per
 * cent), and the sides make up DPSM_MASS_OUTFLOW. Held levels that are all
 * alike, but not 0, are allowed; held levels that differ are refused. */
static void test_side_outflow_in_the_relaxation_to_rest(void **state) {
    (void)state;
    enum { N = 61 };
    double *h = malloc(sizeof(double) * N * N);
    for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) h[i + N * j] = fmax(0.0, 25.0 - 1.5 * hypot(i - 42.0, j - 18.0));
    dpsm_grid *g[2];
    for (int k = 0; k < 2; ++k) {
        CHECK_OK(NULL, dpsm_create_2d(N, N, 1.0, 1.0, &g[k]));
        CHECK_OK(g[k], dpsm_set_repose_angle(g[k], 33.0 * kDeg));
        CHECK_OK(g[k], dpsm_set_boundary(g[k], DPSM_XMAX, DPSM_OPEN));
        CHECK_OK(g[k], dpsm_set_boundary(g[k], DPSM_YMIN, DPSM_OPEN));
        CHECK_OK(g[k], dpsm_set_heights(g[k], h));
        CHECK_OK(g[k], dpsm_set_relaxation(g[k], k == 0 ? DPSM_RELAX_TO_REST : DPSM_RELAX_TIME_ACCURATE));
        CHECK_OK(g[k], dpsm_step(g[k], 1e6));
        REQUIRE(step_info_of(g[k], DPSM_INFO_AT_REST) == 1.0, "grid %d did not rest", k);
    }
    double side[2][4];
    for (int k = 0; k < 2; ++k)
        for (int s = 0; s < 4; ++s) side[k][s] = outflow_of_side(g[k], s);
    const double relaxed = mass_of(g[0], DPSM_MASS_OUTFLOW), total = mass_of(g[0], DPSM_MASS_TOTAL) + relaxed;
    printf("relaxed to rest: XMAX %.6g (time accurate %.6g), YMIN %.6g (%.6g), OUTFLOW %.6g\n", side[0][DPSM_XMAX],
           side[1][DPSM_XMAX], side[0][DPSM_YMIN], side[1][DPSM_YMIN], relaxed);
    REQUIRE(side[0][DPSM_XMIN] == 0.0 && side[0][DPSM_YMAX] == 0.0, "a wall side took sand in the relaxation");
    REQUIRE(side[0][DPSM_XMAX] > 0.0 && side[0][DPSM_YMIN] > 0.0, "an open side took nothing in the relaxation");
    REQUIRE(fabs(side[0][DPSM_XMAX] + side[0][DPSM_YMIN] - relaxed) <= 1e-12 * total,
            "the sides took %.17g and %.17g, OUTFLOW is %.17g", side[0][DPSM_XMAX], side[0][DPSM_YMIN], relaxed);
    for (int s = DPSM_XMAX; s <= DPSM_YMIN; ++s)
        REQUIRE(fabs(side[0][s] - side[1][s]) <= 1e-2 * side[1][s], "side %d: relaxed %.6g, time accurate %.6g", s,
                side[0][s], side[1][s]);
    for (int k = 0; k < 2; ++k) dpsm_destroy(g[k]);

    /* Every held level alike, though not 0: relaxed; one side apart: refused. */
    dpsm_grid *lifted = NULL;
    CHECK_OK(NULL, dpsm_create_2d(N, N, 1.0, 1.0, &lifted));
    double levels[N];
    for (int k = 0; k < N; ++k) levels[k] = 0.5;
    for (int c = 0; c < N * N; ++c) h[c] += 0.5;
    CHECK_OK(lifted, dpsm_set_heights(lifted, h));
    CHECK_OK(lifted, dpsm_set_relaxation(lifted, DPSM_RELAX_TO_REST));
    for (int s = DPSM_XMAX; s <= DPSM_YMIN; ++s) {
        CHECK_OK(lifted, dpsm_set_boundary(lifted, s, DPSM_OPEN));
        CHECK_OK(lifted, dpsm_set_side_levels(lifted, s, levels));
    }
    CHECK_OK(lifted, dpsm_step(lifted, 1.0));
    REQUIRE(step_info_of(lifted, DPSM_INFO_AT_REST) == 1.0 && step_info_of(lifted, DPSM_INFO_TIME_INTEGRATED) == 0.0,
            "held levels all at 0.5: not relaxed to rest");
    REQUIRE(fabs(outflow_of_side(lifted, DPSM_XMAX) + outflow_of_side(lifted, DPSM_YMIN) - mass_of(lifted, DPSM_MASS_OUTFLOW)) <=
                1e-12 * total,
            "held at 0.5: the sides do not make up OUTFLOW");
    levels[N / 2] = 0.6;
    CHECK_OK(lifted, dpsm_set_side_levels(lifted, DPSM_YMIN, levels));
    const int status = dpsm_step(lifted, 1.0);
    REQUIRE(status == DPSM_ERR_NOT_APPLICABLE && strstr(dpsm_last_error(lifted), "held at different levels"),
            "one face of a side held apart: %s (%s)", dpsm_status_string(status), dpsm_last_error(lifted));
    dpsm_destroy(lifted);
    free(h);
}

/* ------------------------------------------------------------------------ */
/* The bed set before the sand                                               */
/* ------------------------------------------------------------------------ */

/* On a fresh grid (every height 0) a bed above 0 lifts the surface to it,
 * wall and open cells too; the sand added to sand cells is booked as
 * external mass. Heights at or above the bed are then accepted. */
static void test_bed_before_heights(void **state) {
    (void)state;
    for (int kind = LINE; kind <= AXI; ++kind) {
        scene_t s = scene_new(kind, 9, 7, 0.3, 0.2);
        double zb[9 * 7], h[9 * 7], got[9 * 7];
        double lifted = 0.0;
        s.kinds[2] = DPSM_CELL_WALL;
        s.kinds[4] = DPSM_CELL_OPEN;
        scene_set_kinds(&s);
        for (int64_t c = 0; c < s.n; ++c) {
            zb[c] = 0.5 + 0.1 * (double)(c % 5) - (c == 6 ? 0.7 : 0.0); /* one cell's bed below 0 */
            if (s.kinds[c] == DPSM_CELL_SAND) lifted += fmax(zb[c], 0.0) * cell_area(&s, c);
        }
        scene_set_bed(&s, zb);
        CHECK_OK(s.g, dpsm_get_heights(s.g, got));
        for (int64_t c = 0; c < s.n; ++c) {
            const double want = fmax(zb[c], 0.0);
            REQUIRE(memcmp(&got[c], &want, sizeof(double)) == 0, "%s: cell %lld is at %.17g on a bed at %.17g",
                    kKindNames[kind], (long long)c, got[c], zb[c]);
        }
        REQUIRE(fabs(mass_of(s.g, DPSM_MASS_EXTERNAL) - lifted) <= 1e-14 * lifted &&
                    fabs(mass_of(s.g, DPSM_MASS_TOTAL) - lifted) <= 1e-14 * lifted,
                "%s: the bed lifted %.17g; EXTERNAL %.17g, TOTAL %.17g", kKindNames[kind], lifted,
                mass_of(s.g, DPSM_MASS_EXTERNAL), mass_of(s.g, DPSM_MASS_TOTAL));
        for (int64_t c = 0; c < s.n; ++c) h[c] = zb[c] + 0.25 * (double)(c % 3);
        CHECK_OK(s.g, dpsm_set_heights(s.g, h));
        REQUIRE(ledger_residual(s.g) <= 1e-14, "%s: ledger residual %g", kKindNames[kind], ledger_residual(s.g));
        scene_free(&s);
    }
}

/* A bed above some cells of a pile lifts those cells to it and no other;
 * EXTERNAL grows by the sand added to sand cells. */
static void test_bed_above_some_cells_lifts_those(void **state) {
    (void)state;
    for (int kind = LINE; kind <= AXI; ++kind) {
        scene_t s = scene_new(kind, 9, 7, 0.3, 0.2);
        double h[9 * 7], zb[9 * 7], got[9 * 7], lifted = 0.0;
        for (int64_t c = 0; c < s.n; ++c) {
            h[c] = 1.0 + 0.37 * (double)(c % 4);
            zb[c] = c % 3 == 1 ? h[c] + 0.2 : h[c] - 1.0;
            if (c % 3 == 1) lifted += 0.2 * cell_area(&s, c);
        }
        CHECK_OK(s.g, dpsm_set_heights(s.g, h));
        const double external = mass_of(s.g, DPSM_MASS_EXTERNAL);
        scene_set_bed(&s, zb);
        CHECK_OK(s.g, dpsm_get_heights(s.g, got));
        for (int64_t c = 0; c < s.n; ++c) {
            const double want = c % 3 == 1 ? zb[c] : h[c];
            REQUIRE(memcmp(&got[c], &want, sizeof(double)) == 0, "%s: cell %lld at %.17g, expected %.17g",
                    kKindNames[kind], (long long)c, got[c], want);
        }
        REQUIRE(fabs(mass_of(s.g, DPSM_MASS_EXTERNAL) - external - lifted) <= 1e-13 * external,
                "%s: EXTERNAL grew by %.17g, the bed lifted %.17g", kKindNames[kind],
                mass_of(s.g, DPSM_MASS_EXTERNAL) - external, lifted);
        REQUIRE(ledger_residual(s.g) <= 1e-14, "%s: ledger residual %g", kKindNames[kind], ledger_residual(s.g));
        scene_free(&s);
    }
}

/* ------------------------------------------------------------------------ */
/* The default step keeps the flow's time                                    */
/* ------------------------------------------------------------------------ */

/* Steps a grid left at the default and one set to DPSM_RELAX_TIME_ACCURATE
 * call by call: they agree bit for bit after every call; each call
 * integrates dt while the surface flows; the default reports rest no
 * earlier than the time-accurate steps. Returns the calls made. */
static int default_against_time_accurate(dpsm_grid *automatic, dpsm_grid *timed, int64_t n, double dt, int calls,
                                         const char *name) {
    CHECK_OK(timed, dpsm_set_relaxation(timed, DPSM_RELAX_TIME_ACCURATE));
    double *a = malloc(sizeof(double) * (size_t)n), *b = malloc(sizeof(double) * (size_t)n);
    int k = 0;
    for (; k < calls; ++k) {
        CHECK_OK(automatic, dpsm_step(automatic, dt));
        CHECK_OK(timed, dpsm_step(timed, dt));
        CHECK_OK(automatic, dpsm_get_heights(automatic, a));
        CHECK_OK(timed, dpsm_get_heights(timed, b));
        REQUIRE(memcmp(a, b, sizeof(double) * (size_t)n) == 0, "%s, call %d: the default's heights differ", name, k);
        for (int item = DPSM_INFO_SUBSTEPS; item <= DPSM_INFO_CELL_UPDATES; ++item)
            REQUIRE(step_info_of(automatic, item) == step_info_of(timed, item), "%s, call %d: step info %d: %g vs %g",
                    name, k, item, step_info_of(automatic, item), step_info_of(timed, item));
        const int rests = step_info_of(automatic, DPSM_INFO_AT_REST) == 1.0;
        if (!rests)
            REQUIRE(step_info_of(automatic, DPSM_INFO_TIME_INTEGRATED) == dt,
                    "%s, call %d: flowing, the default integrated %.17g of %.17g", name, k,
                    step_info_of(automatic, DPSM_INFO_TIME_INTEGRATED), dt);
        if (rests) break;
    }
    free(a);
    free(b);
    return k;
}

/* The column collapse: 101^2 cells of 0.02, a column of radius 0.3 and
 * height 0.8 in the middle, 33 degrees, open sides, dt = 0.05 per call. */
static dpsm_grid *column_collapse(void) {
    enum { N = 101 };
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(N, N, 0.02, 0.02, &g));
    CHECK_OK(g, dpsm_set_repose_angle(g, 33.0 * kDeg));
    set_all_sides(g, DPSM_OPEN, 2);
    double *h = calloc(N * N, sizeof(double));
    for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i)
            if (hypot((i - N / 2) * 0.02, (j - N / 2) * 0.02) <= 0.3 + 1e-12) h[i + N * j] = 0.8;
    CHECK_OK(g, dpsm_set_heights(g, h));
    free(h);
    return g;
}

static void test_default_keeps_the_flow_time_column(void **state) {
    (void)state;
    dpsm_grid *automatic = column_collapse(), *timed = column_collapse();
    const int calls = default_against_time_accurate(automatic, timed, 101 * 101, 0.05, 400, "column collapse");
    printf("column collapse: at rest after %d calls of 0.05\n", calls + 1);
    REQUIRE(calls > 0 && calls < 400, "the collapse rested at call %d", calls);
    dpsm_destroy(automatic);
    dpsm_destroy(timed);
}

static void test_default_keeps_the_flow_time_under_a_source(void **state) {
    (void)state;
    enum { N = 40 };
    double q[N * N] = {0};
    for (int j = 18; j < 22; ++j)
        for (int i = 18; i < 22; ++i) q[i + N * j] = 2.0;
    dpsm_grid *g[2];
    for (int k = 0; k < 2; ++k) {
        CHECK_OK(NULL, dpsm_create_2d(N, N, 0.05, 0.05, &g[k]));
        set_all_sides(g[k], DPSM_OPEN, 2);
        CHECK_OK(g[k], dpsm_set_source(g[k], q));
    }
    const int calls = default_against_time_accurate(g[0], g[1], N * N, 0.02, 30, "pile under a source");
    REQUIRE(calls == 30, "under a source the default reported rest at call %d", calls);
    for (int k = 0; k < 2; ++k) CHECK_OK(g[k], dpsm_set_source(g[k], NULL));
    default_against_time_accurate(g[0], g[1], N * N, 0.02, 400, "the pile after the source");
    for (int k = 0; k < 2; ++k) dpsm_destroy(g[k]);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fluxes_balance_1d),
        cmocka_unit_test(test_fluxes_balance_2d_pairwise),
        cmocka_unit_test(test_fluxes_balance_2d_isotropic),
        cmocka_unit_test(test_fluxes_balance_axisymmetric),
        cmocka_unit_test(test_fluxes_zero_at_rest),
        cmocka_unit_test(test_fluxes_of_tiles_not_visited_read_zero),
        cmocka_unit_test(test_sheet_at_the_outside_level_stays),
        cmocka_unit_test(test_higher_outside_fills_to_the_angle_of_repose),
        cmocka_unit_test(test_higher_outside_fills_an_axisymmetric_table),
        cmocka_unit_test(test_side_outflow_in_the_relaxation_to_rest),
        cmocka_unit_test(test_bed_before_heights),
        cmocka_unit_test(test_bed_above_some_cells_lifts_those),
        cmocka_unit_test(test_default_keeps_the_flow_time_column),
        cmocka_unit_test(test_default_keeps_the_flow_time_under_a_source),
    };
    return cmocka_run_group_tests_name("coupling", tests, NULL, NULL);
}
