/* dpsm-bench: benchmarks of dpsm through its public C API. Each subcommand
 * prints CSV on stdout (a log on stderr); none is run by the tests.
 *
 *   dpsm-bench work-precision [max_n [threads]]
 *       Run time against error of the column collapse (a = 0.5, theta = 30
 *       degrees, open table, run to rest): 2D grids 32^2 ... max_n^2 (default
 *       512) with both schemes, and the axisymmetric grid at 40 ... 1280 rings
 *       (fewer when max_n is smaller). CSV: scene,scheme,n,seconds,l1_error.
 *       threads (default 1) goes to dpsm_set_threads(); 0 is the library's
 *       default (one per core). One thread by default because timings on a
 *       shared machine are far steadier without OpenMP barriers.
 *
 *   dpsm-bench throughput [n ...]      fully active 2D surfaces (512, 2048, 4096)
 *   dpsm-bench sparse [n [fraction [threads]]]   a dune field with ~1 % of cells on slip faces
 *   dpsm-bench idle [n]                a surface at rest
 *   dpsm-bench cone [tolerance [runs]] a cone relaxed to rest (the dune models' scene)
 *   dpsm-bench deposits [n [count [rounds]]]  a host's small deposits, each stepped to rest
 *   dpsm-bench physics [n [runs [scene]]]  the fully active surface with each feature of real scenes
 *   dpsm-bench steps                   the study of larger steps (relax_study.c)
 * Each of these also times the plain reference loop of reference.c, so every
 * figure is also a ratio (speed.c).
 *
 * To add a subcommand: write `int cmd_NAME(int argc, char **argv)` (argv holds
 * the arguments after the subcommand's name) and add a row to kCommands below.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"

static const double kPi = 3.14159265358979323846;

/* Threads for the work-precision runs (its second argument; default 1). */
static int g_threads = 1;

/* Steps a scene without a source until it rests (one call, normally). */
static void run_to_rest(dpsm_grid *g) {
    for (int k = 0; k < 100; ++k) {
        double at_rest = 0.0;
        CHECK(g, dpsm_step(g, 1e6));
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_AT_REST, &at_rest));
        if (at_rest > 0.0) return;
    }
    fprintf(stderr, "dpsm-bench: warning: the scene did not come to rest\n");
}

/* ---- the column collapse and its exact deposit ------------------------------- */

typedef struct {
    double r0, h0, alpha, theta;
    double rf;     /* foot radius of the exact deposit */
    double rtop;   /* radius of its flat top (0 for a cone) */
    double hf;     /* its height */
} column;

static column make_column(double a, double theta_deg) {
    column c;
    c.r0 = 1.0;
    c.h0 = a * c.r0;
    c.theta = theta_deg * kPi / 180.0;
    c.alpha = tan(c.theta);
    if (a <= sqrt(3.0) * c.alpha) {
        c.rf = c.r0 * (a + sqrt(4.0 * c.alpha * c.alpha - a * a / 3.0)) / (2.0 * c.alpha);
        c.hf = c.h0;
    } else {
        c.rf = c.r0 * cbrt(3.0 * a / c.alpha);
        c.hf = c.alpha * c.rf;
    }
    c.rtop = c.rf - c.hf / c.alpha;
    return c;
}

/* The exact deposit at radius r: a truncated cone (or a cone). */
static double exact_height(const column *c, double r) {
    const double flank = c->alpha * (c->rf - r);
    return flank <= 0.0 ? 0.0 : fmin(c->hf, flank);
}

/* The fraction of the cell [x0, x0+dx] x [y0, y0+dx] inside the circle of
 * radius r about the origin: 1 or 0 away from the rim, sampled on a 64 x 64
 * lattice of points across it. */
static double disk_fraction(double x0, double y0, double dx, double r) {
    const double xn = fmax(0.0, fmax(x0, -(x0 + dx))), yn = fmax(0.0, fmax(y0, -(y0 + dx)));
    const double xf = fmax(fabs(x0), fabs(x0 + dx)), yf = fmax(fabs(y0), fabs(y0 + dx));
    if (xf * xf + yf * yf <= r * r) return 1.0;
    if (xn * xn + yn * yn >= r * r) return 0.0;
    const int ns = 64;
    int in = 0;
    for (int j = 0; j < ns; ++j)
        for (int i = 0; i < ns; ++i) {
            const double x = x0 + (i + 0.5) * dx / ns, y = y0 + (j + 0.5) * dx / ns;
            in += x * x + y * y <= r * r;
        }
    return (double)in / (ns * ns);
}

/* One 2D collapse on an n x n open table of half-width L centred on the
 * column; the column is given by cell averages (a rim cell holds h0 times the
 * fraction of it inside r0), so its volume is pi r0^2 h0 to sampling accuracy
 * on every grid. Returns the wall time of the run (grid creation to heights
 * read back) and the L1 error against the exact deposit. */
static void collapse_2d(const column *c, int n, int scheme, double *seconds, double *l1) {
    const double half_width = 1.25 * fmax(2.0 * c->r0, c->rf);
    const double dx = 2.0 * half_width / n;
    const size_t cells = (size_t)n * (size_t)n;
    double *h0 = xcalloc(cells, sizeof *h0), *h = xcalloc(cells, sizeof *h);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            h0[i + (size_t)n * j] = c->h0 * disk_fraction(i * dx - half_width, j * dx - half_width, dx, c->r0);

    const double t0 = now_seconds();
    dpsm_grid *g = NULL;
    CHECK(NULL, dpsm_create_2d(n, n, dx, dx, &g));
    CHECK(g, dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE)); /* the model's own path, against the exact deposit */
    CHECK(g, dpsm_set_threads(g, g_threads));
    CHECK(g, dpsm_set_repose_angle(g, c->theta));
    CHECK(g, dpsm_set_scheme(g, scheme));
    for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side) CHECK(g, dpsm_set_boundary(g, side, DPSM_OPEN));
    CHECK(g, dpsm_set_heights(g, h0));
    run_to_rest(g);
    CHECK(g, dpsm_get_heights(g, h));
    *seconds = now_seconds() - t0;

    double volume = 0.0, err = 0.0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double x = (i + 0.5) * dx - half_width, y = (j + 0.5) * dx - half_width;
            const size_t k = i + (size_t)n * j;
            volume += h0[k] * dx * dx;
            err += fabs(h[k] - exact_height(c, sqrt(x * x + y * y))) * dx * dx;
        }
    *l1 = err / volume;
    dpsm_destroy(g);
    free(h0);
    free(h);
}

/* One axisymmetric collapse: nr rings over [0, 2.5 r0], the outer side open. */
static void collapse_axisymmetric(const column *c, int nr, double *seconds, double *l1) {
    const double outer = 1.25 * fmax(2.0 * c->r0, c->rf);
    const double dr = outer / nr;
    double *h = xcalloc((size_t)nr, sizeof *h);
    const double t0 = now_seconds();
    dpsm_grid *g = NULL;
    CHECK(NULL, dpsm_create_axisymmetric(nr, dr, &g));
    CHECK(g, dpsm_set_threads(g, g_threads));
    CHECK(g, dpsm_set_repose_angle(g, c->theta));
    CHECK(g, dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN));
    for (int i = 0; i < nr; ++i) {
        const double r_in = i * dr, r_out = (i + 1) * dr;
        /* the ring's share inside r0, by area (1 except at most one ring) */
        const double inner = fmin(fmax(c->r0, r_in), r_out);
        h[i] = c->h0 * (inner * inner - r_in * r_in) / (r_out * r_out - r_in * r_in);
    }
    CHECK(g, dpsm_set_heights(g, h));
    run_to_rest(g);
    CHECK(g, dpsm_get_heights(g, h));
    *seconds = now_seconds() - t0;
    double err = 0.0;
    for (int i = 0; i < nr; ++i) {
        const double r = (i + 0.5) * dr;
        err += fabs(h[i] - exact_height(c, r)) * 2.0 * kPi * r * dr;
    }
    *l1 = err / (kPi * c->r0 * c->r0 * c->h0);
    dpsm_destroy(g);
    free(h);
}

static int cmd_work_precision(int argc, char **argv) {
    const int max_n = argc > 0 ? atoi(argv[0]) : 512;
    g_threads = argc > 1 ? atoi(argv[1]) : 1;
    if (max_n < 32 || g_threads < 0) {
        fprintf(stderr, "usage: dpsm-bench work-precision [max_n >= 32 [threads >= 0]]\n");
        return 2;
    }
    const column c = make_column(0.5, 30.0);
    fprintf(stderr,
            "work-precision: column collapse a = 0.5, theta = 30 deg; exact deposit a truncated cone of height %.4f,"
            " top radius %.4f, foot radius %.4f; threads %d\n",
            c.hf, c.rtop, c.rf, g_threads);
    printf("scene,scheme,n,seconds,l1_error\n");
    fflush(stdout);
    for (int n = 32; n <= max_n; n *= 2)
        for (int scheme = DPSM_SCHEME_PAIRWISE; scheme <= DPSM_SCHEME_ISOTROPIC; ++scheme) {
            double seconds, l1;
            collapse_2d(&c, n, scheme, &seconds, &l1);
            printf("column_2d,%s,%d,%.6f,%.6e\n", scheme == DPSM_SCHEME_PAIRWISE ? "pairwise" : "isotropic", n,
                   seconds, l1);
            fflush(stdout);
        }
    for (int nr = 40; nr <= 2 * max_n + 256 && nr <= 1280; nr *= 2) {
        double seconds, l1;
        collapse_axisymmetric(&c, nr, &seconds, &l1);
        printf("column_axisymmetric,axisymmetric,%d,%.6f,%.6e\n", nr, seconds, l1);
        fflush(stdout);
    }
    return 0;
}

/* ---- the relaxation modes on a host's time loop ------------------------------ */

/* The column collapse of the issue that made the default keep the flow's
 * time: 101^2 cells of 0.02, a column of radius 0.3 and height 0.8 on the
 * cells whose centre lies within it, 33 degrees, open sides, calls of
 * dt = 0.05 (about 420 stable sub-steps). For each mode: the call after
 * which rest is first reported, the summit after the third call (t = 0.15)
 * and the sub-steps or evaluations of 40 calls. */
static int cmd_modes(int argc, char **argv) {
    (void)argc;
    (void)argv;
    const int64_t n = 101;
    const double dx = 0.02;
    double *h = xcalloc((size_t)(n * n), sizeof(double));
    static const int modes[3] = {DPSM_RELAX_AUTO, DPSM_RELAX_TIME_ACCURATE, DPSM_RELAX_TO_REST};
    static const char *const names[3] = {"default", "time-accurate", "to-rest"};
    printf("mode,rest_after_call,rest_time,summit_at_0.15,substeps_in_40_calls\n");
    for (int m = 0; m < 3; ++m) {
        for (int64_t j = 0; j < n; ++j)
            for (int64_t i = 0; i < n; ++i)
                h[i + n * j] = hypot((double)(i - 50) * dx, (double)(j - 50) * dx) <= 0.3 ? 0.8 : 0.0;
        dpsm_grid *g = NULL;
        CHECK(NULL, dpsm_create_2d(n, n, dx, dx, &g));
        CHECK(g, dpsm_set_repose_angle(g, 33.0 * kPi / 180.0));
        CHECK(g, dpsm_set_relaxation(g, modes[m]));
        for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side) CHECK(g, dpsm_set_boundary(g, side, DPSM_OPEN));
        CHECK(g, dpsm_set_heights(g, h));
        int rest_call = 0;
        double summit = 0.0, substeps = 0.0;
        for (int call = 1; call <= 40; ++call) {
            double rest, s;
            CHECK(g, dpsm_step(g, 0.05));
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_AT_REST, &rest));
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &s));
            substeps += s;
            if (rest == 1.0 && rest_call == 0) rest_call = call;
            if (call == 3) CHECK(g, dpsm_get_heights_region(g, 50, 50, 1, 1, &summit));
        }
        printf("%s,%d,%.2f,%.4f,%.0f\n", names[m], rest_call, 0.05 * rest_call, summit, substeps);
        dpsm_destroy(g);
    }
    free(h);
    return 0;
}

/* ---- dispatch ---------------------------------------------------------------- */

static const command kCommands[] = {
    {"throughput", cmd_throughput, "[n ...]  fully active surfaces; CSV n,threads,mcells_per_s,reference_mcells_per_s,ratio"},
    {"sparse", cmd_sparse, "[n [fraction [threads]]]  ~1 % of cells on slip faces; cost of a sub-step against a fully active one"},
    {"idle", cmd_idle, "[n]  a surface at rest: seconds per dpsm_step against a fully active sub-step"},
    {"cone", cmd_cone,
     "[tolerance [runs]]  cone 40 high, slope 1.5, 101^2, to rest at 33 deg; seconds and top vs 22.89 (relaxed to rest:"
     " the best of runs, 10)"},
    {"deposits", cmd_deposits,
     "[n [count [rounds]]]  count (40) heaps of 10^2 cells dropped one by one on n^2 (4096^2) at rest, each stepped"
     " to rest, rounds (1) times over: time-accurate and by the default"},
    {"wind", cmd_wind,
     "[n [threads]]  a dune field (n^2, 2048^2) with ~1 % of cells on slip faces and a source on every cell: a call"
     " of 64 stable sub-steps against 64 fully active sub-steps and the reference loop's"},
    {"short", cmd_short,
     "[n]  fully active n^2 (2048^2): seconds per sub-step of calls of one sub-step against a call of 58, time-accurate"
     " and by the default, 1 and 2 threads"},
    {"modes", cmd_modes,
     "the column collapse in calls of 0.05 under each relaxation mode: when rest is reported, the summit at t = 0.15"},
    {"physics", cmd_physics,
     "[n [runs [scene]]]  the fully active n^2 (2048^2) surface plain and with a bed, an angle field, flux exponents, a"
     " static angle; 1 and 2 threads, best of runs (3); cost against the plain scene (DPSM_SCALAR_PHYSICS=1: the scalar"
     " kernel); a scene named: that one alone"},
    {"mesh", cmd_mesh,
     "[n [runs [kind]]]  about a million cells (n = 0: 708 for 1,002,528 jittered_triangles, 936 hexagons, 1000"
     " median_dual): a fully active sub-step on 1 and 2 threads against the plain face loop on the same cells; ridges"
     " on ~1 % of cells and a mesh at rest against a fully active sub-step"},
    {"mesh-wind", cmd_mesh_wind,
     "[n [threads [runs]]]  the wind scene on 2 n^2 (n = 708: 1,002,528) jittered triangles: ~1 % of cells on slip faces"
     " and a source on every cell; a call of 64 stable sub-steps against 64 fully active sub-steps and the plain face"
     " loop's, on threads (1), best of runs (3)"},
    {"mesh-accuracy", cmd_mesh_accuracy,
     "[threads [levels [mesh]]]  column collapse (a = 0.5, 30 deg) to rest on quadrilaterals, jittered triangles, hexagons,"
     " the median dual (and a gmsh disk) at about 4,000, 16,000, 65,000, 262,000 cells (levels, 4): L1 error, order, runout,"
     " rest time, settled time, beside the 2D grid of the same cell size and the mesh turned by 30 degrees; the cone on triangles;"
     " mesh `ridge`: a ridge between walls (64 cells a side, doubled each level) against the exact triangle and the grid;"
     " mesh `slope`: the same walls holding a triangle 1 % steeper than repose (the rest tail alone)"},
    {"mesh-plane", cmd_mesh_plane,
     "mesh n  a plane 1 % steeper than repose on n cells a side of the mesh (quadrilaterals, jittered_triangles,"
     " hexagons, median_dual): how fast one stable sub-step moves its inside, against the plane's flux over the cell size"},
    {"mesh-energies", cmd_mesh_energies,
     "mesh n energy [jitter]  the column collapse of mesh-accuracy under the gradient flow of one face or cell energy"
     " (faces: the library's; node-diamond; on median_dual also triangle-tangents, triangles, faces-and-triangles), explicit, no limiter, to"
     " rest: rest time and L1 error (not the library: a copy of its flow to try energies beside it)"},
    {"mesh-graded", cmd_mesh_graded,
     "[levels [coarse_across [seconds]]]  issue 34's graded mesh: squares from h to 2^levels h (9: 512 h), piles on the"
     " fine cells, on the coarse ones (and on a uniform mesh of them) and straddling the grading, each to rest or for"
     " `seconds` of stepping: sub-steps and cell updates"},
    {"lts-compare", cmd_lts_compare,
     "[m [levels]]  local time steps (DPSM_RELAX_LOCAL_STEPS) against the global sub-step on quadtrees of h..2^levels h"
     " (m = 128 fine cells across, 3), a column on the fine, the coarse and straddling cells: the L1 difference over the"
     " volume moved after every call, ticks, cell updates, seconds, mass"},
    {"lts", cmd_lts,
     "[m]  local time stepping study: quadtree meshes of cells h..8h (m = 256 fine cells across) against uniform"
     " squares of the same count, column collapse to rest: sub-steps, cell updates now and with local time steps"},
    {"steps", cmd_steps, "explicit sub-steps against the bounded exchange at dt -> infinity: time and error to rest"},
    {"sts", cmd_sts, "time-accurate super-time-stepping against forward Euler: cone, column per call, steep plane"},
    {"work-precision", cmd_work_precision,
     "[max_n [threads]]  column collapse (a = 0.5, 30 deg) to rest: 2D n^2 up to max_n^2 (default 512), both schemes,"
     " and axisymmetric; threads default 1; CSV scene,scheme,n,seconds,l1_error"},
};

int main(int argc, char **argv) { return run_command(kCommands, sizeof kCommands / sizeof kCommands[0], argc, argv); }
