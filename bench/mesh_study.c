/* The mesh engine's validation and speed (dpsm-bench mesh-accuracy, mesh).
 *
 * mesh-accuracy: the column collapse of the 2D validation (a = 0.5, 30
 * degrees, open table, the exact deposit a truncated cone) on every mesh
 * kind of mesh_scenes.h at four refinements, stepped in time to rest: the
 * L1 difference over the column's volume, the observed order, the runout in
 * 16 directions against the exact foot, the time at which it rested and the
 * time from which its deposit stayed within 1 % of the grid's error of where
 * it rested (settled); beside each, the same column on the 2D grid of
 * squares of the same mean size (the grid engine's error, rest time and
 * settled time) and, at the two coarsest levels, on the
 * same mesh turned by 30 degrees (the deposits' difference, cell by cell,
 * against the error); and the cone (40 high, slope 1.5, 33 degrees) on
 * jittered triangles, its top against 22.89. With `ridge` for the mesh: a
 * ridge across a square walled all round, on every kind against the exact
 * triangle and the grid's squares (rest times beside each other); with
 * `slope`, the same walls holding a triangle 1 % steeper than the angle of
 * repose: the rest tail alone.
 *
 * mesh: a fully active jittered triangle mesh (steep plane, every face over
 * the threshold) against the plain face loop below (one pass over faces
 * computing the gradient and flux, one over cells updating, in the host's
 * order); the sparse scene (slip faces on ~1 % of cells) and a mesh at rest,
 * each against a fully active sub-step. Beside the fully active rates: the
 * bytes a sub-step moves per cell update, counted from the engine's layout
 * (mesh_bytes.cpp), a triad's bandwidth in the same run, and the bound the
 * two set (triad / bytes) with the share of it the engine reaches.
 *
 * mesh-wind: the dune field of `wind` with a source on every cell. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "mesh_scenes.h"

#if defined(_OPENMP)
#include <omp.h>
#endif

static const double kPi = 3.14159265358979323846;

/* ---- accuracy -------------------------------------------------------------- */

typedef struct {
    double l1, runout_error, rest_time, top;
    /* The cone: its top cell's distance from the axis and the exact resting cone's height there. */
    double top_radius, exact_at_top;
    int at_rest;
    double seconds, cell_updates;
    int64_t cells;
    double size;
    /* The same column on the 2D grid of squares of this mean size, and on
     * this mesh turned by 30 degrees (the L1 difference of the deposits, cell
     * by cell, over the L1 error; NAN where not run). */
    int64_t grid_cells;
    double grid_l1, grid_rest_time, rotated;
    /* When the deposit settled (settled_time below), here and on the grid. */
    double settled_time, grid_settled_time;
} mesh_result;

/* The L1 difference of two deposits on cells of these areas. */
static double l1_difference(const double *a, const double *b, const double *area, int64_t cells) {
    double difference = 0.0;
    for (int64_t c = 0; c < cells; ++c) difference += fabs(a[c] - b[c]) * area[c];
    return difference;
}

/* The heights after every call of a run to rest, for settled_time. */
typedef struct {
    int64_t cells, calls, capacity;
    double *heights; /* calls x cells */
    double *times;   /* the time at the end of each call */
} deposit_track;

static void track_call(dpsm_grid *g, deposit_track *track, double t) {
    if (track->calls == track->capacity) {
        track->capacity = track->capacity ? 2 * track->capacity : 64;
        track->heights = realloc(track->heights, (size_t)(track->capacity * track->cells) * sizeof(double));
        track->times = realloc(track->times, (size_t)track->capacity * sizeof(double));
        if (!track->heights || !track->times) {
            fprintf(stderr, DPSM_TOOL_NAME ": out of memory\n");
            exit(1);
        }
    }
    CHECK(g, dpsm_get_heights(g, track->heights + track->calls * track->cells));
    track->times[track->calls++] = t;
}

/* The time from which the deposit stays within `tolerance` (an L1
 * difference over `volume`) of where it rests: when the flow ends to the
 * accuracy asked, whatever the rest tolerance makes the tail below it
 * last. */
static double settled_time(const deposit_track *track, const double *area, double volume, double tolerance) {
    if (track->calls == 0) return NAN;
    const double *rest = track->heights + (track->calls - 1) * track->cells;
    double settled = track->times[track->calls - 1];
    for (int64_t k = track->calls - 2; k >= 0; --k) {
        if (l1_difference(track->heights + k * track->cells, rest, area, track->cells) > tolerance * volume) break;
        settled = track->times[k];
    }
    return settled;
}

static void track_free(deposit_track *track) {
    free(track->heights);
    free(track->times);
}

/* Steps in calls of dt until the surface rests or t_end passes; with a
 * track, keeps the heights after every call. */
static void step_to_rest(dpsm_grid *g, double dt, double t_end, mesh_result *out, deposit_track *track) {
    double t = 0.0;
    out->at_rest = 0;
    out->cell_updates = 0.0;
    while (t < t_end) {
        CHECK(g, dpsm_step(g, dt));
        double at_rest = 0.0, integrated = 0.0, updates = 0.0;
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_AT_REST, &at_rest));
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_TIME_INTEGRATED, &integrated));
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &updates));
        out->cell_updates += updates;
        t += integrated;
        if (track) track_call(g, track, t);
        if (at_rest > 0.0) {
            out->at_rest = 1;
            break;
        }
    }
    out->rest_time = t;
}

/* The scene's mesh with its edge open, at angle theta, holding h. */
static dpsm_grid *open_mesh(const mesh_scene *s, double theta, int threads, const double *h) {
    dpsm_grid *g = NULL;
    CHECK(NULL, scene_create(s, &g));
    CHECK(g, dpsm_set_threads(g, threads));
    CHECK(g, dpsm_set_repose_angle(g, theta));
    CHECK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN));
    CHECK(g, dpsm_set_heights(g, h));
    return g;
}

/* The column (a = 0.5, 30 degrees, radius 1 about the origin) poured on the
 * scene's cells as cell averages; the square it stands on. */
static const double kColumnTheta = 30.0 * 3.14159265358979323846 / 180.0;
static double column_half(void) { return 1.25 * fmax(2.0, scene_column_foot(tan(kColumnTheta))); }
static double *poured_column(const mesh_scene *s) {
    double *h = xcalloc((size_t)s->cells, sizeof(double));
    scene_pour_column(s, h);
    return h;
}

/* The L1 error of the deposit h on the scene's cells over the column's
 * volume, its runout in 16 directions against the exact foot, its top. */
static void score_column(const mesh_scene *s, const double *h, mesh_result *r) {
    const double alpha = tan(kColumnTheta), foot = scene_column_foot(alpha);
    double top = 0.0, runout[16] = {0};
    for (int64_t c = 0; c < s->cells; ++c) {
        top = fmax(top, h[c]);
        if (h[c] > 1e-6) {
            const double angle = atan2(s->cy[c], s->cx[c]);
            const int sector = ((int)lround(angle / (2.0 * kPi / 16.0)) + 16) % 16;
            const double along = s->cx[c] * cos(sector * 2.0 * kPi / 16.0) + s->cy[c] * sin(sector * 2.0 * kPi / 16.0);
            /* within half a cell of the ray */
            const double across =
                fabs(-s->cx[c] * sin(sector * 2.0 * kPi / 16.0) + s->cy[c] * cos(sector * 2.0 * kPi / 16.0));
            if (across <= r->size && along > runout[sector]) runout[sector] = along;
        }
    }
    r->l1 = scene_column_l1(s, h, alpha);
    r->top = top;
    r->runout_error = 0.0;
    for (int k = 0; k < 16; ++k) r->runout_error = fmax(r->runout_error, fabs(runout[k] - foot));
}

/* A column's deposit settled when it stays within 1 % of the grid engine's
 * error (its L1 difference from the exact deposit on as many squares) of
 * where it rests: the same yardstick for the mesh and the grid. */
static const double kSettledShare = 0.01;

/* The column on the scene's mesh, stepped to rest; the deposit in h (with a
 * track, the heights after every call too). */
static void collapse_on_mesh(const mesh_scene *s, int threads, double *h, mesh_result *r, deposit_track *track) {
    double *poured = poured_column(s);
    const double t0 = now_seconds();
    dpsm_grid *g = open_mesh(s, kColumnTheta, threads, poured);
    step_to_rest(g, 0.1, 20.0, r, track);
    CHECK(g, dpsm_get_heights(g, h));
    r->seconds = now_seconds() - t0;
    dpsm_destroy(g);
    free(poured);
}

/* The 2D grid of n x n squares over [-half, half]^2, every side `side`
 * (DPSM_OPEN or DPSM_WALL), at the column's angle, holding h. */
static dpsm_grid *square_grid(int n, double half, int threads, int side, const double *h) {
    const double d = 2.0 * half / n;
    dpsm_grid *g = NULL;
    CHECK(NULL, dpsm_create_2d(n, n, d, d, &g));
    CHECK(g, dpsm_set_threads(g, threads));
    CHECK(g, dpsm_set_repose_angle(g, kColumnTheta));
    for (int which = DPSM_XMIN; which <= DPSM_YMAX; ++which) CHECK(g, dpsm_set_boundary(g, which, side));
    CHECK(g, dpsm_set_heights(g, h));
    return g;
}

/* The same column on the 2D grid of n x n squares over the same square,
 * every side open: the grid engine's L1 error and rest time. */
static void collapse_on_grid(int n, int threads, mesh_result *r) {
    mesh_scene squares = scene_make(SCENE_QUADS, n, column_half(), 1u); /* the grid's cells, x fastest */
    double *h = poured_column(&squares);
    dpsm_grid *g = square_grid(n, column_half(), threads, DPSM_OPEN, h);
    mesh_result grid;
    memset(&grid, 0, sizeof grid);
    grid.size = 2.0 * column_half() / n;
    deposit_track track = {.cells = squares.cells};
    step_to_rest(g, 0.1, 20.0, &grid, &track);
    CHECK(g, dpsm_get_heights(g, h));
    score_column(&squares, h, &grid);
    r->grid_cells = squares.cells;
    r->grid_l1 = grid.l1;
    r->grid_rest_time = grid.rest_time;
    r->grid_settled_time = settled_time(&track, squares.area, kPi * 0.5, kSettledShare * grid.l1);
    track_free(&track);
    dpsm_destroy(g);
    free(h);
    scene_free(&squares);
}

/* The column on `kind` at refinement n, beside the grid's; with `turned`,
 * also on the same mesh turned by 30 degrees about the column's axis. */
static mesh_result column_on(scene_kind kind, int n, int threads, int turned) {
    mesh_scene s = scene_make(kind, n, column_half(), 12345u);
    mesh_result r;
    memset(&r, 0, sizeof r);
    r.rotated = NAN;
    if (s.cells == 0) return r; /* gmsh or its .geo not found */
    r.cells = s.cells;
    r.size = scene_mean_size(&s);
    collapse_on_grid((int)lround(2.0 * column_half() / r.size), threads, &r);
    double *h = xcalloc((size_t)s.cells, sizeof(double));
    deposit_track track = {.cells = s.cells};
    collapse_on_mesh(&s, threads, h, &r, &track);
    score_column(&s, h, &r);
    /* against the grid's error: its column ran first */
    r.settled_time = settled_time(&track, s.area, kPi * 0.5, kSettledShare * r.grid_l1);
    track_free(&track);
    if (turned) {
        /* A turned copy of a mesh is the same mesh: only a choice bound to
         * the axes could make its deposit differ beyond rounding. */
        mesh_scene t = scene_make(kind, n, column_half(), 12345u);
        scene_rotate(&t, 30.0 * kPi / 180.0);
        double *ht = xcalloc((size_t)t.cells, sizeof(double));
        mesh_result rt = r;
        collapse_on_mesh(&t, threads, ht, &rt, NULL);
        r.rotated = l1_difference(h, ht, s.area, s.cells) / (kPi * 0.5) / r.l1;
        free(ht);
        scene_free(&t);
    }
    free(h);
    scene_free(&s);
    return r;
}

/* The cone of the dune models' scene: 40 high, slope 1.5, relaxed at 33 degrees. */
static mesh_result cone_on(scene_kind kind, int n, int threads) {
    const double theta = 33.0 * kPi / 180.0;
    mesh_scene s = scene_make(kind, n, 40.0, 777u);
    double *h = xcalloc((size_t)s.cells, sizeof(double));
    for (int64_t c = 0; c < s.cells; ++c) h[c] = fmax(0.0, 40.0 - 1.5 * hypot(s.cx[c], s.cy[c]));
    mesh_result r;
    memset(&r, 0, sizeof r);
    r.cells = s.cells;
    r.size = scene_mean_size(&s);
    const double t0 = now_seconds();
    dpsm_grid *g = open_mesh(&s, theta, threads, h);
    step_to_rest(g, 10.0, 1e5, &r, NULL);
    CHECK(g, dpsm_get_heights(g, h));
    r.seconds = now_seconds() - t0;
    int64_t highest = 0;
    for (int64_t c = 0; c < s.cells; ++c)
        if (h[c] > h[highest]) highest = c;
    r.top = h[highest];
    /* Heights are cell values at the centres: the deposit's highest cell can
     * be no higher than the exact cone at its centre, which lies off the
     * apex by as much as the mesh puts it. */
    const double alpha = tan(theta), volume = kPi / 3.0 * 40.0 * (40.0 / 1.5) * (40.0 / 1.5);
    const double apex = alpha * cbrt(3.0 * volume / (kPi * alpha));
    r.top_radius = hypot(s.cx[highest], s.cy[highest]);
    r.exact_at_top = apex - alpha * r.top_radius;
    dpsm_destroy(g);
    free(h);
    scene_free(&s);
    return r;
}

/* The ridge between walls: a bank 2 high and 1.2 wide across the square
 * (|x| < 0.6), walled all round, collapses to the exact triangle of slope
 * tan 30 degrees that holds its volume over the same cells (about 1.18
 * high, its toes near x = +-2.04); the same on the grid's squares of the mesh's mean size. The
 * runout: the farthest cell with sand against the exact toe. Along the walls only
 * a construction that drops the walls' part of the faces' energy would make
 * the cells beside them lag and rest last. */
static const double kRidgeHalf = 2.5;
static double ridge_height(double x) { return fabs(x) < 0.6 ? 2.0 : 0.0; }
/* The slope: the same walls, but the sand starts as a triangle 1 % steeper
 * than the angle of repose (toes at x = +-1.5), so the flow is the tail
 * alone: no front sweeps over the cells, and every face starts at the same
 * small excess. */
static double steep_slope_height(double x) { return fmax(0.0, tan(kColumnTheta) * 1.01 * (1.5 - fabs(x))); }
/* `volume`: the sand the cells were given (the bank's edges fall inside cells). */
static void score_ridge(const double *cx, const double *area, int64_t cells, const double *h, double volume,
                        mesh_result *r) {
    double reach = 0.0;
    for (int64_t c = 0; c < cells; ++c)
        if (h[c] > 1e-6) reach = fmax(reach, fabs(cx[c]));
    /* Its height: the triangle over these cells that holds that volume (by
     * bisection; the edges of a mesh need not be straight). */
    const double alpha = tan(kColumnTheta);
    double low = 0.0, high = 4.0;
    for (int k = 0; k < 100; ++k) {
        const double top = 0.5 * (low + high);
        double held = 0.0;
        for (int64_t c = 0; c < cells; ++c) held += fmax(0.0, top - alpha * fabs(cx[c])) * area[c];
        if (held < volume)
            low = top;
        else
            high = top;
    }
    const double top = 0.5 * (low + high), toe = top / alpha;
    double err = 0.0;
    for (int64_t c = 0; c < cells; ++c) err += fabs(h[c] - fmax(0.0, top - alpha * fabs(cx[c]))) * area[c];
    r->l1 = err / volume;
    r->runout_error = fabs(reach - toe);
}

/* The sand of `height` on cells cx with areas `area`, into h; its volume. */
static double poured_ridge(double (*height)(double), const double *cx, const double *area, int64_t cells, double *h) {
    double volume = 0.0;
    for (int64_t c = 0; c < cells; ++c) {
        h[c] = height(cx[c]);
        volume += h[c] * area[c];
    }
    return volume;
}

static mesh_result ridge_on(scene_kind kind, int n, int threads, double (*height)(double)) {
    mesh_scene s = scene_make(kind, n, kRidgeHalf, 12345u);
    mesh_result r;
    memset(&r, 0, sizeof r);
    r.rotated = NAN;
    if (s.cells == 0) return r;
    r.cells = s.cells;
    r.size = scene_mean_size(&s);
    double *h = xcalloc((size_t)s.cells, sizeof(double));
    double volume = poured_ridge(height, s.cx, s.area, s.cells, h);
    const double t0 = now_seconds();
    dpsm_grid *g = open_mesh(&s, kColumnTheta, threads, h);
    CHECK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_WALL));
    step_to_rest(g, 0.1, 40.0, &r, NULL);
    CHECK(g, dpsm_get_heights(g, h));
    r.seconds = now_seconds() - t0;
    score_ridge(s.cx, s.area, s.cells, h, volume, &r);
    dpsm_destroy(g);
    free(h);
    /* The grid of squares of the same mean size. */
    const int m = (int)lround(2.0 * kRidgeHalf / r.size);
    mesh_scene squares = scene_make(SCENE_QUADS, m, kRidgeHalf, 1u); /* the grid's cells, x fastest */
    h = xcalloc((size_t)squares.cells, sizeof(double));
    volume = poured_ridge(height, squares.cx, squares.area, squares.cells, h);
    g = square_grid(m, kRidgeHalf, threads, DPSM_WALL, h);
    mesh_result grid;
    memset(&grid, 0, sizeof grid);
    step_to_rest(g, 0.1, 40.0, &grid, NULL);
    CHECK(g, dpsm_get_heights(g, h));
    score_ridge(squares.cx, squares.area, squares.cells, h, volume, &grid);
    r.grid_cells = squares.cells;
    r.grid_l1 = grid.l1;
    r.grid_rest_time = grid.rest_time;
    dpsm_destroy(g);
    free(h);
    scene_free(&squares);
    scene_free(&s);
    return r;
}

/* The ridge (or the slope) on every kind but the gmsh disk (whose edge is a
 * circle, not walls a straight ridge can cross), `levels` refinements from
 * 64 cells a side. */
static void ridge_rows(int threads, int levels, const char *scene, double (*height)(double)) {
    static const scene_kind kinds[] = {SCENE_QUADS, SCENE_TRIANGLES, SCENE_HEXAGONS, SCENE_DUAL};
    for (size_t k = 0; k < sizeof kinds / sizeof *kinds; ++k) {
        double previous = 0.0;
        for (int level = 0; level < levels; ++level) {
            const mesh_result r = ridge_on(kinds[k], 64 << level, threads, height);
            const double order = level > 0 ? log2(previous / r.l1) : NAN;
            printf("%s,%s,%lld,%.5f,%.4e,%.2f,%.2f,%d,%.3f,%.4g,%.3f,%lld,%.4e,%.3f,%.3f,,,,\n", scene,
                   scene_name(kinds[k]), (long long)r.cells, r.size, r.l1, order, r.runout_error / r.size, r.at_rest,
                   r.rest_time, r.cell_updates, r.seconds, (long long)r.grid_cells, r.grid_l1, r.grid_rest_time,
                   r.rest_time / r.grid_rest_time);
            fflush(stdout);
            previous = r.l1;
        }
    }
}

int cmd_mesh_accuracy(int argc, char **argv) {
    const int threads = argc > 0 ? atoi(argv[0]) : 0;
    const int levels = argc > 1 ? atoi(argv[1]) : 4;
    /* one mesh kind (its name) or "columns", without the cone; "cone": the cone alone; "ridge": the ridge
     * between walls alone, "slope": the slope 1 % steeper than repose between them (neither run otherwise) */
    const char *only = argc > 2 ? argv[2] : NULL;
    /* about 4,000, 16,000, 65,000 and 262,000 cells on each kind */
    static const struct {
        scene_kind kind;
        int n;
    } kinds[] = {{SCENE_QUADS, 64}, {SCENE_TRIANGLES, 45}, {SCENE_HEXAGONS, 59}, {SCENE_DUAL, 64}, {SCENE_GMSH_DISK, 64}};
    fprintf(stderr, "mesh-accuracy: column collapse a = 0.5, 30 deg, open edges; exact foot %.4f; threads %d\n",
            scene_column_foot(tan(kColumnTheta)), threads);
    printf("scene,mesh,cells,mean_size,l1_error,order,runout_error_cells,at_rest,rest_time,cell_updates,seconds,"
           "grid_cells,grid_l1_error,grid_rest_time,rest_time_ratio,turned_difference,settled_time,grid_settled_time,"
           "settled_time_ratio\n");
    fflush(stdout);
    if (only && strcmp(only, "ridge") == 0) {
        ridge_rows(threads, levels, "ridge_between_walls", ridge_height);
        return 0;
    }
    if (only && strcmp(only, "slope") == 0) {
        ridge_rows(threads, levels, "slope_between_walls", steep_slope_height);
        return 0;
    }
    for (size_t k = 0; k < sizeof kinds / sizeof *kinds; ++k) {
        if (only && strcmp(only, "columns") != 0 && strcmp(only, scene_name(kinds[k].kind)) != 0) continue;
        double previous = 0.0;
        for (int level = 0; level < levels; ++level) {
            const int n = kinds[k].n << level;
            /* The turned copy at the two coarsest levels: it doubles a level's cost. */
            const mesh_result r = column_on(kinds[k].kind, n, threads, level < 2);
            if (r.cells == 0) {
                fprintf(stderr, "mesh-accuracy: %s skipped: gmsh not found or DPSM_DISK_GEO (bench/data/disk.geo) not set\n",
                        scene_name(kinds[k].kind));
                break;
            }
            const double order = level > 0 ? log2(previous / r.l1) : NAN;
            printf("column,%s,%lld,%.5f,%.4e,%.2f,%.2f,%d,%.3f,%.4g,%.3f,%lld,%.4e,%.3f,%.3f,%.2e,%.2f,%.2f,%.3f\n",
                   scene_name(kinds[k].kind), (long long)r.cells, r.size, r.l1, order, r.runout_error / r.size,
                   r.at_rest, r.rest_time, r.cell_updates, r.seconds, (long long)r.grid_cells, r.grid_l1,
                   r.grid_rest_time, r.rest_time / r.grid_rest_time, r.rotated, r.settled_time, r.grid_settled_time,
                   r.settled_time / r.grid_settled_time);
            fflush(stdout);
            previous = r.l1;
        }
    }
    if (only && strcmp(only, "cone") != 0) return 0;
    const mesh_result cone = cone_on(SCENE_TRIANGLES, 72, threads);
    printf("cone,%s,%lld,%.5f,top %.4f against 22.89 (%+.3f %%); its cell %.3f off the axis where the exact cone is "
           "%.4f (%+.3f %%),,,%d,%.3f,%.4g,%.3f,,,,,,,,\n",
           scene_name(SCENE_TRIANGLES), (long long)cone.cells, cone.size, cone.top, 100.0 * (cone.top / 22.89 - 1.0),
           cone.top_radius, cone.exact_at_top, 100.0 * (cone.top / cone.exact_at_top - 1.0),
           cone.at_rest, cone.rest_time, cone.cell_updates, cone.seconds);
    return 0;
}

/* ---- speed ------------------------------------------------------------------ */

/* The plain face loop: the mesh as the host holds it (its cell order), the
 * faces found from the polygons' edges, each face's slope from the two-point
 * difference and the least-squares gradients of its cells computed on the
 * spot, the fluxes added to both cells, then every cell updated. */
typedef struct {
    int64_t cells, faces;
    int64_t *fa, *fb;                 /* faces' cells, fb = -1 on the edge */
    double *d, *ortho, *tx, *ty;      /* distance, length over distance, tangent */
    int64_t *nb_start, *nb;           /* each cell's neighbours */
    double *wx, *wy;                  /* least-squares weights per neighbour */
    double *area, *rate;
} plain_mesh;

typedef struct {
    int64_t lo, hi, cell;
} edge_use;

static int edge_order(const void *l, const void *r) {
    const edge_use *a = l, *b = r;
    if (a->lo != b->lo) return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi) return a->hi < b->hi ? -1 : 1;
    return a->cell < b->cell ? -1 : a->cell > b->cell;
}

/* Face f of the plain loop: cells a and b (-1: the edge), its length, and
 * the line from a's centre to b's (on the edge: to a's mirror image across
 * the face's midpoint (mx, my)). */
static void plain_face(plain_mesh *p, const mesh_scene *s, int64_t *degree, int64_t a, int64_t b, double len, double mx,
                       double my) {
    const int64_t f = p->faces++;
    const double ex = b >= 0 ? s->cx[b] - s->cx[a] : 2.0 * (mx - s->cx[a]);
    const double ey = b >= 0 ? s->cy[b] - s->cy[a] : 2.0 * (my - s->cy[a]);
    p->fa[f] = a, p->fb[f] = b, p->d[f] = hypot(ex, ey), p->ortho[f] = len / p->d[f];
    p->tx[f] = -ey / p->d[f], p->ty[f] = ex / p->d[f];
    if (b >= 0) ++degree[a], ++degree[b];
}

/* The plain loop's faces from the scene's polygons: each shared edge a face
 * between its two polygons, each other edge a face on the domain edge. On
 * the median dual (whose cells are the triangles' nodes) each triangle edge
 * is a face between its two nodes, running from one triangle's centroid to
 * the edge's midpoint to the other's, and each half of an edge on the
 * domain edge a face of its node there. */
static plain_mesh plain_from(const mesh_scene *s) {
    plain_mesh p;
    memset(&p, 0, sizeof p);
    p.cells = s->cells;
    const int dual = s->kind == SCENE_DUAL;
    const int64_t polygons = dual ? s->npolygons : s->cells;
    const int64_t uses = dual ? 3 * s->npolygons : s->cell_start[s->cells];
    edge_use *e = xcalloc((size_t)uses, sizeof *e);
    for (int64_t c = 0; c < polygons; ++c) {
        const int64_t first = dual ? 3 * c : s->cell_start[c], end = dual ? 3 * c + 3 : s->cell_start[c + 1];
        for (int64_t k = first; k < end; ++k) {
            const int64_t u = s->cell_nodes[k], v = s->cell_nodes[k + 1 < end ? k + 1 : first];
            e[k].lo = u < v ? u : v, e[k].hi = u < v ? v : u, e[k].cell = c;
        }
    }
    qsort(e, (size_t)uses, sizeof *e, edge_order);
    const size_t most = 2 * (size_t)uses; /* the dual's edge on the domain edge gives two faces */
    p.fa = xcalloc(most, sizeof(int64_t)), p.fb = xcalloc(most, sizeof(int64_t));
    p.d = xcalloc(most, sizeof(double)), p.ortho = xcalloc(most, sizeof(double));
    p.tx = xcalloc(most, sizeof(double)), p.ty = xcalloc(most, sizeof(double));
    int64_t *degree = xcalloc((size_t)s->cells + 1, sizeof(int64_t));
    const double *xy = s->node_xy;
    for (int64_t k = 0; k < uses;) {
        const int shared = k + 1 < uses && e[k + 1].lo == e[k].lo && e[k + 1].hi == e[k].hi;
        const int64_t lo = e[k].lo, hi = e[k].hi;
        const double len = hypot(xy[2 * hi] - xy[2 * lo], xy[2 * hi + 1] - xy[2 * lo + 1]);
        const double mx = 0.5 * (xy[2 * hi] + xy[2 * lo]), my = 0.5 * (xy[2 * hi + 1] + xy[2 * lo + 1]);
        if (!dual) {
            plain_face(&p, s, degree, e[k].cell, shared ? e[k + 1].cell : -1, len, mx, my);
        } else if (shared) {
            double dual_len = 0.0;
            for (int side = 0; side < 2; ++side) {
                const int64_t *t = s->cell_nodes + 3 * e[k + side].cell;
                const double gx = (xy[2 * t[0]] + xy[2 * t[1]] + xy[2 * t[2]]) / 3.0;
                const double gy = (xy[2 * t[0] + 1] + xy[2 * t[1] + 1] + xy[2 * t[2] + 1]) / 3.0;
                dual_len += hypot(gx - mx, gy - my);
            }
            plain_face(&p, s, degree, lo, hi, dual_len, mx, my);
        } else {
            plain_face(&p, s, degree, lo, -1, 0.5 * len, 0.5 * (mx + xy[2 * lo]), 0.5 * (my + xy[2 * lo + 1]));
            plain_face(&p, s, degree, hi, -1, 0.5 * len, 0.5 * (mx + xy[2 * hi]), 0.5 * (my + xy[2 * hi + 1]));
        }
        k += shared ? 2 : 1;
    }
    free(e);
    p.nb_start = xcalloc((size_t)s->cells + 1, sizeof(int64_t));
    for (int64_t c = 0; c < s->cells; ++c) p.nb_start[c + 1] = p.nb_start[c] + degree[c];
    p.nb = xcalloc((size_t)p.nb_start[s->cells] + 1, sizeof(int64_t));
    for (int64_t c = 0; c < s->cells; ++c) degree[c] = p.nb_start[c];
    for (int64_t f = 0; f < p.faces; ++f)
        if (p.fb[f] >= 0) p.nb[degree[p.fa[f]]++] = p.fb[f], p.nb[degree[p.fb[f]]++] = p.fa[f];
    free(degree);
    const int64_t links = p.nb_start[s->cells];
    p.wx = xcalloc((size_t)links + 1, sizeof(double)), p.wy = xcalloc((size_t)links + 1, sizeof(double));
    for (int64_t c = 0; c < s->cells; ++c) {
        double sxx = 0, sxy = 0, syy = 0;
        for (int64_t k = p.nb_start[c]; k < p.nb_start[c + 1]; ++k) {
            const double dx = s->cx[p.nb[k]] - s->cx[c], dy = s->cy[p.nb[k]] - s->cy[c], w = 1.0 / (dx * dx + dy * dy);
            sxx += w * dx * dx, sxy += w * dx * dy, syy += w * dy * dy;
        }
        const double det = sxx * syy - sxy * sxy;
        if (!(det > 1e-6 * (sxx + syy) * (sxx + syy))) continue;
        for (int64_t k = p.nb_start[c]; k < p.nb_start[c + 1]; ++k) {
            const double dx = s->cx[p.nb[k]] - s->cx[c], dy = s->cy[p.nb[k]] - s->cy[c], w = 1.0 / (dx * dx + dy * dy);
            p.wx[k] = w * (syy * dx - sxy * dy) / det, p.wy[k] = w * (sxx * dy - sxy * dx) / det;
        }
    }
    p.area = s->area;
    p.rate = xcalloc((size_t)s->cells, sizeof(double));
    return p;
}

static void plain_gradient(const plain_mesh *p, const double *h, int64_t c, double *gx, double *gy) {
    double x = 0, y = 0;
    for (int64_t k = p->nb_start[c]; k < p->nb_start[c + 1]; ++k) {
        const double dh = h[p->nb[k]] - h[c];
        x += p->wx[k] * dh, y += p->wy[k] * dh;
    }
    *gx = x, *gy = y;
}

/* One sub-step of the plain loop with open edges held at 0. */
static void plain_substep(const plain_mesh *p, double *h, double dt, double tan_theta) {
    memset(p->rate, 0, sizeof(double) * (size_t)p->cells);
    for (int64_t f = 0; f < p->faces; ++f) {
        const int64_t a = p->fa[f], b = p->fb[f];
        double gax, gay, gbx = 0, gby = 0;
        plain_gradient(p, h, a, &gax, &gay);
        if (b >= 0) plain_gradient(p, h, b, &gbx, &gby);
        const double hb = b >= 0 ? h[b] : 0.0;
        const double normal = (h[a] - hb) / p->d[f];
        const double tangential = b >= 0 ? 0.5 * ((gax + gbx) * p->tx[f] + (gay + gby) * p->ty[f]) : gax * p->tx[f] + gay * p->ty[f];
        const double slope = sqrt(normal * normal + tangential * tangential);
        if (!(slope > tan_theta)) continue;
        const double flux = (slope - tan_theta) / sqrt(1.0 + slope * slope) / slope * p->ortho[f] * (h[a] - hb);
        p->rate[a] -= flux;
        if (b >= 0) p->rate[b] += flux;
    }
    for (int64_t c = 0; c < p->cells; ++c) h[c] += dt * p->rate[c] / p->area[c];
}

static void plain_free(plain_mesh *p) {
    free(p->fa), free(p->fb), free(p->d), free(p->ortho), free(p->tx), free(p->ty), free(p->nb_start), free(p->nb),
        free(p->wx), free(p->wy), free(p->rate);
}

/* Over `substeps` steps of one sub-step each from the grid's heights: the
 * cells whose heights changed and the cells the library visited, per
 * sub-step (what the sparse step visits against what moves). */
static void visited_and_changed(dpsm_grid *g, int64_t cells, int substeps, double *visited, double *changed) {
    double dt = 0.0;
    CHECK(g, dpsm_stable_dt(g, &dt));
    double *before = xcalloc((size_t)cells, sizeof(double)), *after = xcalloc((size_t)cells, sizeof(double));
    CHECK(g, dpsm_get_heights(g, before));
    *visited = *changed = 0.0;
    for (int k = 0; k < substeps; ++k) {
        double updates = 0.0;
        CHECK(g, dpsm_step(g, dt));
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &updates));
        CHECK(g, dpsm_get_heights(g, after));
        for (int64_t c = 0; c < cells; ++c) *changed += after[c] != before[c];
        *visited += updates;
        double *swap = before;
        before = after, after = swap;
    }
    *visited /= substeps, *changed /= substeps;
    free(before), free(after);
}

/* bench/mesh_bytes.cpp: the bytes a fully active sub-step moves per cell update, from the engine's layout. */
double bench_mesh_bytes_per_update(const dpsm_grid *g, FILE *log);

/* A STREAM-like triad a = b + s c over arrays of 256 MB on `threads`
 * threads, best of five: bytes read and written (24 a point) per second. */
static double triad_bytes_per_second(int threads) {
    const int64_t n = 32 * 1024 * 1024;
    double *a = xcalloc((size_t)n, sizeof(double)), *b = xcalloc((size_t)n, sizeof(double)),
           *c = xcalloc((size_t)n, sizeof(double));
    (void)threads;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int64_t i = 0; i < n; ++i) a[i] = 0.0, b[i] = 1.0, c[i] = 2.0;
    double best = 1e300;
    for (int run = 0; run < 5; ++run) {
        const double t0 = now_seconds();
#pragma omp parallel for num_threads(threads) schedule(static)
        for (int64_t i = 0; i < n; ++i) a[i] = b[i] + 3.0 * c[i];
        best = fmin(best, now_seconds() - t0);
    }
    if (a[n / 2] != 7.0) fprintf(stderr, "triad: a wrong sum\n");
    free(a), free(b), free(c);
    return 24.0 * (double)n / best;
}

static double seconds_per_substep(dpsm_grid *g, int substeps, double *updates) {
    double dt = 0.0;
    CHECK(g, dpsm_stable_dt(g, &dt));
    const double t0 = now_seconds();
    CHECK(g, dpsm_step(g, substeps * dt));
    const double seconds = now_seconds() - t0;
    double taken = 0.0;
    CHECK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &taken));
    CHECK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, updates));
    *updates /= taken > 0 ? taken : 1.0;
    return seconds / (taken > 0 ? taken : 1.0);
}

int cmd_mesh(int argc, char **argv) {
    /* The kinds of mesh, each with the n that makes about a million cells. */
    static const struct {
        scene_kind kind;
        int n;
    } kinds[] = {{SCENE_TRIANGLES, 708}, {SCENE_HEXAGONS, 936}, {SCENE_DUAL, 1000}};
    size_t which = 0;
    if (argc > 2) {
        while (which < sizeof kinds / sizeof *kinds && strcmp(argv[2], scene_name(kinds[which].kind)) != 0) ++which;
        if (which == sizeof kinds / sizeof *kinds) {
            fprintf(stderr, "mesh: no mesh kind '%s' (jittered_triangles, hexagons or median_dual)\n", argv[2]);
            return 2;
        }
    }
    const int n = argc > 0 && atoi(argv[0]) > 0 ? atoi(argv[0]) : kinds[which].n; /* 0: about a million cells */
    const int runs = argc > 1 ? atoi(argv[1]) : 3;
    const double tan_theta = tan(30.0 * kPi / 180.0);
    const char *mesh = scene_name(kinds[which].kind);
    mesh_scene s = scene_make(kinds[which].kind, n, 1.0, 4242u);
    fprintf(stderr, "mesh: %lld cells of %s; fully active (a plane of slope 10 draining over open edges),"
                    " sparse (ridges on ~1 %% of cells), idle; best of %d\n", (long long)s.cells, mesh, runs);
    double *h = xcalloc((size_t)s.cells, sizeof(double)), *plain_h = xcalloc((size_t)s.cells, sizeof(double));
    for (int64_t c = 0; c < s.cells; ++c) h[c] = 30.0 + 10.0 * (s.cx[c] + 0.3 * s.cy[c]);
    dpsm_grid *g = NULL;
    CHECK(NULL, scene_create(&s, &g));
    CHECK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN));
    double dt = 0.0;
    CHECK(g, dpsm_stable_dt(g, &dt));
    plain_mesh p = plain_from(&s);
    const double bytes = bench_mesh_bytes_per_update(g, stderr);
    printf("mesh,scene,threads,seconds_per_substep,mcells_per_s,reference_mcells_per_s,ratio,cells_visited_per_substep,"
           "bytes_per_update,triad_gb_per_s,bound_mcells_per_s,share_of_bound\n");
    const int substeps = 20;
    double plain_best = 1e300;
    for (int run = 0; run < runs; ++run) {
        memcpy(plain_h, h, sizeof(double) * (size_t)s.cells);
        const double t0 = now_seconds();
        for (int k = 0; k < substeps; ++k) plain_substep(&p, plain_h, dt, tan_theta);
        plain_best = fmin(plain_best, (now_seconds() - t0) / substeps);
    }
    double active_best[3] = {1e300, 1e300, 1e300};
    for (int threads = 1; threads <= 2; ++threads) {
        CHECK(g, dpsm_set_threads(g, threads));
        double updates = 0.0;
        for (int run = 0; run < runs; ++run) {
            CHECK(g, dpsm_set_heights(g, h));
            active_best[threads] = fmin(active_best[threads], seconds_per_substep(g, substeps, &updates));
        }
        /* The triad in the same run, beside it: the bound the layout's bytes set on this machine. */
        const double triad = triad_bytes_per_second(threads), rate = s.cells / active_best[threads];
        printf("%s,fully_active,%d,%.6f,%.1f,%.1f,%.2f,%.0f,%.0f,%.1f,%.1f,%.3f\n", mesh, threads, active_best[threads],
               rate / 1e6, s.cells / plain_best / 1e6, plain_best / active_best[threads], updates, bytes, triad / 1e9,
               triad / bytes / 1e6, rate / (triad / bytes));
        fflush(stdout);
    }
    /* Sparse: flat ground with ridges on about 1 % of the cells. */
    for (int64_t c = 0; c < s.cells; ++c) {
        const double band = fabs(fmod(s.cy[c] + 1.0, 0.5) - 0.25);
        h[c] = band < 0.0025 ? 0.02 : 0.0;
    }
    for (int threads = 1; threads <= 2; ++threads) {
        CHECK(g, dpsm_set_threads(g, threads));
        double best = 1e300, updates = 0.0;
        for (int run = 0; run < runs; ++run) {
            CHECK(g, dpsm_set_heights(g, h));
            CHECK(g, dpsm_step(g, dt)); /* the host's edit is looked at once */
            best = fmin(best, seconds_per_substep(g, substeps, &updates));
        }
        double visited = 0.0, changed = 0.0;
        CHECK(g, dpsm_set_heights(g, h));
        CHECK(g, dpsm_step(g, dt));
        visited_and_changed(g, s.cells, substeps, &visited, &changed);
        printf("%s,sparse,%d,%.6f,,,%.4f of fully active,%.0f (%.2f %% of cells; %.0f changed a sub-step: visited %.2f times)\n",
               mesh, threads, best, best / active_best[threads], updates, 100.0 * updates / s.cells, changed,
               visited / changed);
        fflush(stdout);
    }
    /* Idle: the same mesh at rest (a gentle plane; the edge closed, or the
     * plane would drain over it). */
    for (int64_t c = 0; c < s.cells; ++c) h[c] = 0.1 * s.cx[c];
    CHECK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_WALL));
    CHECK(g, dpsm_set_heights(g, h));
    CHECK(g, dpsm_step(g, dt));
    double best = 1e300;
    for (int run = 0; run < runs * 100; ++run) {
        const double t0 = now_seconds();
        CHECK(g, dpsm_step(g, dt));
        best = fmin(best, now_seconds() - t0);
    }
    printf("%s,idle,2,%.9f,,,%.6f of fully active,0\n", mesh, best, best / active_best[2]);
    plain_free(&p);
    dpsm_destroy(g);
    free(h), free(plain_h);
    scene_free(&s);
    return 0;
}

/* mesh-wind: the grid's wind scene (dpsm-bench wind) on a mesh. A dune field
 * on 2 n^2 jittered triangles, in the grid's units of cells (d, the side of
 * the squares the triangles split): compact slip faces on ~1 % of the cells,
 * 40 x 24 squares each, 1.15 tan(theta) steep; a source on every cell,
 * erosion on the stoss slopes (0.05 of the x slope) and deposition on the
 * three columns at each brink (0.2), per sub-step what the grid's scene
 * puts on per grid sub-step. A call of 64 stable sub-steps against 64
 * fully active sub-steps (the steep plane of `mesh`) and the plain face
 * loop's; cells visited beside the seconds. */
int cmd_mesh_wind(int argc, char **argv) {
    const int n = argc > 0 ? atoi(argv[0]) : 708;
    const int threads = argc > 1 ? atoi(argv[1]) : 1;
    const int runs = argc > 2 ? atoi(argv[2]) : 3;
    const int substeps = 64;
    const double theta = 30.0 * kPi / 180.0, tan_theta = tan(theta);
    mesh_scene s = scene_make(SCENE_TRIANGLES, n, 1.0, 4242u);
    const double d = 2.0 / n;
    double *h = xcalloc((size_t)s.cells, sizeof(double)), *q = xcalloc((size_t)s.cells, sizeof(double));
    double *plane = xcalloc((size_t)s.cells, sizeof(double)), *plain_h = xcalloc((size_t)s.cells, sizeof(double));
    unsigned char *brink = xcalloc((size_t)s.cells, 1), *slip = xcalloc((size_t)s.cells, 1);
    /* The dune bed, and its slope along x (in heights per cell). */
    const double kx = 2.0 * kPi / 400.0, ky = 2.0 * kPi / 700.0;
    for (int64_t c = 0; c < s.cells; ++c) {
        const double i = (s.cx[c] + 1.0) / d, j = (s.cy[c] + 1.0) / d;
        h[c] = d * (3.0 + 2.0 * sin(kx * i) * cos(ky * j));
    }
    /* Slip faces on a lattice, as add_slip_faces in speed.c. */
    const int face_w = 40, face_h = 24;
    const int64_t faces = (int64_t)(0.01 * (double)n * (double)n / (double)(face_w * face_h));
    const int64_t per_row = (int64_t)ceil(sqrt((double)faces));
    const int64_t pitch = n / (per_row + 1);
    unsigned seed = 12345u;
    int64_t placed = 0;
    for (int64_t a = 0; a < per_row && placed < faces; ++a)
        for (int64_t b = 0; b < per_row && placed < faces; ++b, ++placed) {
            seed = seed * 1664525u + 1013904223u;
            const double i0 = (double)((a + 1) * pitch - face_w / 2 + (int64_t)(seed >> 28) - 8);
            const double j0 = (double)((b + 1) * pitch - face_h / 2);
            for (int64_t c = 0; c < s.cells; ++c) {
                const double i = (s.cx[c] + 1.0) / d, j = (s.cy[c] + 1.0) / d;
                if (i < i0 || i >= i0 + face_w || j < j0 || j >= j0 + face_h) continue;
                h[c] += 1.15 * tan_theta * d * (i0 + face_w - i);
                slip[c] = 1;
                if (i < i0 + 3) brink[c] = 1;
            }
        }
    int64_t on_slip = 0;
    for (int64_t c = 0; c < s.cells; ++c) on_slip += slip[c];
    /* The grid's stable sub-step on cells of 1, to put on per sub-step what the grid's scene does. */
    double grid_dt = 0.0, mesh_dt = 0.0;
    {
        dpsm_grid *g = NULL;
        CHECK(NULL, dpsm_create_2d(4, 4, 1.0, 1.0, &g));
        CHECK(g, dpsm_set_repose_angle(g, theta));
        CHECK(g, dpsm_stable_dt(g, &grid_dt));
        dpsm_destroy(g);
    }
    dpsm_grid *g = NULL;
    CHECK(NULL, scene_create(&s, &g));
    CHECK(g, dpsm_set_repose_angle(g, theta));
    CHECK(g, dpsm_set_threads(g, threads));
    CHECK(g, dpsm_stable_dt(g, &mesh_dt));
    const double per_substep = grid_dt * d / mesh_dt;
    for (int64_t c = 0; c < s.cells; ++c) {
        const double i = (s.cx[c] + 1.0) / d, j = (s.cy[c] + 1.0) / d;
        const double slope_x = 2.0 * kx * cos(kx * i) * cos(ky * j); /* of the bed, in cells */
        q[c] = per_substep * (brink[c] ? 0.2 : -0.05 * slope_x);
    }
    fprintf(stderr,
            "mesh-wind: %lld jittered triangles, %.2f %% on slip faces, a source on every cell; a call of %d stable"
            " sub-steps on %d thread(s), best of %d\n",
            (long long)s.cells, 100.0 * (double)on_slip / (double)s.cells, substeps, threads, runs);
    /* The fully active sub-step: the steep plane of `mesh` draining over open edges. */
    for (int64_t c = 0; c < s.cells; ++c) plane[c] = 30.0 + 10.0 * (s.cx[c] + 0.3 * s.cy[c]);
    double full = 1e300, full_updates = 0.0;
    CHECK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN));
    for (int run = 0; run < runs; ++run) {
        CHECK(g, dpsm_set_heights(g, plane));
        full = fmin(full, seconds_per_substep(g, 20, &full_updates));
    }
    CHECK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_WALL));
    /* The plain face loop, in the same run. */
    plain_mesh p = plain_from(&s);
    double plain = 1e300;
    for (int run = 0; run < runs; ++run) {
        memcpy(plain_h, plane, sizeof(double) * (size_t)s.cells);
        const double t0 = now_seconds();
        for (int k = 0; k < 20; ++k) plain_substep(&p, plain_h, mesh_dt, tan_theta);
        plain = fmin(plain, (now_seconds() - t0) / 20.0);
    }
    /* The call: after a first call (the host's edit looked at once), a second of 64 sub-steps. */
    double call = 1e300, updates = 0.0, taken = 0.0;
    for (int run = 0; run < runs; ++run) {
        CHECK(g, dpsm_set_heights(g, h));
        CHECK(g, dpsm_set_source(g, q));
        CHECK(g, dpsm_step(g, substeps * mesh_dt));
        const double t0 = now_seconds();
        CHECK(g, dpsm_step(g, substeps * mesh_dt));
        call = fmin(call, now_seconds() - t0);
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &updates));
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &taken));
    }
    printf("cells,threads,slip_face_fraction,substeps,cells_visited_fraction,call_s,full_s,ratio,plain_s,"
           "full_over_plain\n");
    printf("%lld,%d,%.4f,%.0f,%.4f,%.3e,%.3e,%.4f,%.3e,%.2f\n", (long long)s.cells, threads,
           (double)on_slip / (double)s.cells, taken, updates / (substeps * (double)s.cells), call, substeps * full,
           call / (substeps * full), substeps * plain, full / plain);
    plain_free(&p);
    dpsm_destroy(g);
    free(h), free(q), free(plane), free(plain_h), free(brink), free(slip);
    scene_free(&s);
    return 0;
}
