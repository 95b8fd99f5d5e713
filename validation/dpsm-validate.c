/* dpsm-validate: runs the validation scenes of docs/validation.md through the
 * public C API and writes their results as CSV.
 *
 *   dpsm-validate column-sweep OUTDIR [rings_per_r0]
 *       The axisymmetric column collapse (the paper's Section 5, Figs. 8-9,
 *       Tables 1-2, Eq. 17) for a = 0.10 ... 2.00 and theta = 21, 30 degrees:
 *       OUTDIR/column_sweep.csv
 *   dpsm-validate table-1d OUTDIR
 *       The paper's Figs. 2 and 3: 1D tables under sources, profiles at several
 *       times: OUTDIR/table_1d.csv
 *   dpsm-validate table-2d OUTDIR [n]
 *       The paper's Figs. 4 and 5: 2D tables under sources, walls and
 *       obstacles, final heights: OUTDIR/table_2d.csv
 *   dpsm-validate all OUTDIR
 *       All three.
 *
 * Each subcommand also prints a short log (run times, rest, mass balance) on
 * stderr. Nothing here reaches past include/dpsm/dpsm.h.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <dpsm/dpsm.h>

#define DPSM_TOOL_NAME "dpsm-validate"
#include "bench_util.h"

static const double kPi = 3.14159265358979323846;

static double deg(double d) { return d * kPi / 180.0; }

static FILE *open_csv(const char *dir, const char *name) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "dpsm-validate: cannot write %s: %s\n", path, strerror(errno));
        exit(1);
    }
    fprintf(stderr, "writing %s\n", path);
    return f;
}

static double mass(dpsm_grid *g, int quantity) {
    double v = 0.0;
    CHECK(g, dpsm_get_mass(g, quantity, &v));
    return v;
}

static double step_info(dpsm_grid *g, int item) {
    double v = 0.0;
    CHECK(g, dpsm_get_step_info(g, item, &v));
    return v;
}

/* Runs a scene without a source to rest with as few dpsm_step calls as it
 * takes (one, normally); returns the simulated time to rest and the total
 * number of sub-steps. */
static void run_to_rest(dpsm_grid *g, double *t_rest, double *substeps) {
    *t_rest = 0.0;
    *substeps = 0.0;
    for (int k = 0; k < 100; ++k) {
        CHECK(g, dpsm_step(g, 1e6));
        *t_rest += step_info(g, DPSM_INFO_TIME_INTEGRATED);
        *substeps += step_info(g, DPSM_INFO_SUBSTEPS);
        if (step_info(g, DPSM_INFO_AT_REST) > 0.0) return;
    }
    fprintf(stderr, "dpsm-validate: warning: the scene did not come to rest\n");
}

/* ---- exact final states of the axisymmetric column collapse ---------------- */

/* Foot radius r_f / r0 and final height h_f / r0 of the exact deposit of a
 * column of aspect ratio a at alpha = tan(theta) (DESIGN.md, Section 1). */
static void exact_deposit(double a, double alpha, double *rf_over_r0, double *hf_over_r0) {
    if (a <= sqrt(3.0) * alpha) {
        *rf_over_r0 = (a + sqrt(4.0 * alpha * alpha - a * a / 3.0)) / (2.0 * alpha);
        *hf_over_r0 = a;
    } else {
        *rf_over_r0 = cbrt(3.0 * a / alpha);
        *hf_over_r0 = alpha * *rf_over_r0;
    }
}

/* ---- column-sweep ---------------------------------------------------------- */

/* Where the deposit ends: the outermost ring with sand, extended down its flank
 * to h = 0. The flank slope is measured between that ring and the one inside
 * it (at rest it is the angle of repose to within the rest tolerance); where
 * the deposit is a single ring the angle of repose is used. Radii are ring
 * centres. */
static double foot_radius(const double *h, int64_t nr, double dr, double alpha, double threshold) {
    int64_t last = -1;
    for (int64_t i = 0; i < nr; ++i)
        if (h[i] > threshold) last = i;
    if (last < 0) return 0.0;
    const double r_last = ((double)last + 0.5) * dr;
    double slope = alpha;
    if (last > 0 && h[last - 1] > h[last]) slope = (h[last - 1] - h[last]) / dr;
    return r_last + h[last] / slope;
}

/* Potential energy of an axisymmetric deposit: sum over rings of
 * (h/2) * h * 2 pi r dr, centre-of-mass height times mass. */
static double potential_energy_axi(const double *h, int64_t nr, double dr) {
    double e = 0.0;
    for (int64_t i = 0; i < nr; ++i) e += 0.5 * h[i] * h[i] * 2.0 * kPi * ((double)i + 0.5) * dr * dr;
    return e;
}

static int cmd_column_sweep(int argc, char **argv) {
    if (argc < 1) {
        fprintf(stderr, "usage: dpsm-validate column-sweep OUTDIR [rings_per_r0]\n");
        return 2;
    }
    const char *dir = argv[0];
    const int rings_per_r0 = argc > 1 ? atoi(argv[1]) : 125;
    if (rings_per_r0 < 4) {
        fprintf(stderr, "dpsm-validate: rings_per_r0 must be at least 4\n");
        return 2;
    }
    const double r0 = 1.0, dr = r0 / rings_per_r0;
    /* The open outer side at 3.2 r0 lies beyond every deposit of the sweep
     * (the farthest, a = 2 at 21 degrees, ends at 2.50 r0): nothing leaves. */
    const int64_t nr = (int64_t)ceil(3.2 * rings_per_r0);
    const double thetas[] = {21.0, 30.0};
    FILE *f = open_csv(dir, "column_sweep.csv");
    fprintf(f, "theta_deg,a,hf_over_r0,runout_over_r0,energy_dissipated_fraction,hf_exact,runout_exact\n");
    fprintf(stderr, "column-sweep: %lld rings of dr = r0/%d, outer side open at %.3g r0\n", (long long)nr,
            rings_per_r0, (double)nr * dr / r0);
    double *h = xcalloc((size_t)nr, sizeof *h);
    const double t_start = now_seconds();
    double worst_hf = 0.0, worst_rf = 0.0, worst_outflow = 0.0;
    for (int k = 0; k < 2; ++k) {
        const double theta_deg = thetas[k], alpha = tan(deg(theta_deg));
        for (int m = 0; m <= 38; ++m) {
            const double a = 0.1 + 0.05 * m, h0 = a * r0;
            const double t0 = now_seconds();
            dpsm_grid *g = NULL;
            CHECK(NULL, dpsm_create_axisymmetric(nr, dr, &g));
            CHECK(g, dpsm_set_repose_angle(g, deg(theta_deg)));
            CHECK(g, dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN));
            for (int64_t i = 0; i < nr; ++i) h[i] = i < rings_per_r0 ? h0 : 0.0;
            CHECK(g, dpsm_set_heights(g, h));
            const double e0 = potential_energy_axi(h, nr, dr);
            const double v0 = mass(g, DPSM_MASS_TOTAL);
            double t_rest, substeps;
            run_to_rest(g, &t_rest, &substeps);
            CHECK(g, dpsm_get_heights(g, h));
            double hf = 0.0;
            for (int64_t i = 0; i < nr; ++i) hf = fmax(hf, h[i]);
            const double rf = foot_radius(h, nr, dr, alpha, 1e-12 * h0);
            const double e1 = potential_energy_axi(h, nr, dr);
            double rf_exact, hf_exact;
            exact_deposit(a, alpha, &rf_exact, &hf_exact);
            const double outflow = mass(g, DPSM_MASS_OUTFLOW) / v0;
            fprintf(f, "%g,%.2f,%.8f,%.8f,%.8f,%.8f,%.8f\n", theta_deg, a, hf / r0, (rf - r0) / r0, (e0 - e1) / e0,
                    hf_exact, rf_exact - 1.0);
            const double err_hf = (hf / r0 - hf_exact) / hf_exact, err_rf = (rf / r0 - rf_exact) / rf_exact;
            worst_hf = fmax(worst_hf, fabs(err_hf));
            worst_rf = fmax(worst_rf, fabs(err_rf));
            worst_outflow = fmax(worst_outflow, fabs(outflow));
            fprintf(stderr,
                    "  theta %2.0f a %.2f: h_f %.5f (exact %.5f, %+.2e) r_f %.5f (exact %.5f, %+.2e) rest at t = %.3g "
                    "after %.0f sub-steps, %.2f s\n",
                    theta_deg, a, hf / r0, hf_exact, err_hf, rf / r0, rf_exact, err_rf, t_rest, substeps,
                    now_seconds() - t0);
            dpsm_destroy(g);
        }
    }
    fprintf(stderr,
            "column-sweep: worst relative error h_f %.2e, r_f %.2e; worst outflow / volume %.1e; %.1f s in all\n",
            worst_hf, worst_rf, worst_outflow, now_seconds() - t_start);
    free(h);
    fclose(f);
    return 0;
}

/* ---- table-1d: the paper's Figs. 2 and 3 ------------------------------------ */

typedef struct {
    const char *name;
    int intervals;
    double lo[2], hi[2]; /* the source sub-intervals D_w */
    int left_open, right_open;
} scene_1d;

static const scene_1d kScenes1d[] = {
    /* Fig. 2: an open table at both ends. */
    {"fig2a", 1, {0.0, 0}, {1.0, 0}, 1, 1},
    {"fig2b", 1, {0.0, 0}, {0.4, 0}, 1, 1},
    {"fig2c", 2, {0.2, 0.8}, {0.4, 1.0}, 1, 1},
    {"fig2d", 2, {0.18, 0.78}, {0.22, 0.82}, 1, 1},
    /* Fig. 3: (a, b) open on the left, a wall on the right; (c, d) walls on both sides. */
    {"fig3a", 1, {0.3, 0}, {1.0, 0}, 1, 0},
    {"fig3b", 1, {0.0, 0}, {0.5, 0}, 1, 0},
    {"fig3c", 1, {0.45, 0}, {0.55, 0}, 0, 0},
    {"fig3d", 2, {0.25, 0.75}, {0.35, 0.85}, 0, 0},
};

static int cmd_table_1d(int argc, char **argv) {
    if (argc < 1) {
        fprintf(stderr, "usage: dpsm-validate table-1d OUTDIR\n");
        return 2;
    }
    const char *dir = argv[0];
    /* 100 cells of 0.01 on [0, 1]: every end of every D_w is a cell face. */
    const int64_t n = 100;
    const double dx = 1.0 / (double)n, q0 = 0.05, nu = 1.0, theta = deg(45.0);
    const double times[] = {1, 2, 5, 10, 15, 20, 30, 40, 60, 80, 120, 160};
    const int ntimes = (int)(sizeof times / sizeof times[0]);
    FILE *f = open_csv(dir, "table_1d.csv");
    fprintf(f, "scene,t,x,h\n");
    double *h = xcalloc((size_t)n, sizeof *h), *hprev = xcalloc((size_t)n, sizeof *hprev);
    double *q = xcalloc((size_t)n, sizeof *q);
    const double t_start = now_seconds();
    for (size_t s = 0; s < sizeof kScenes1d / sizeof kScenes1d[0]; ++s) {
        const scene_1d *sc = &kScenes1d[s];
        const double t0 = now_seconds();
        dpsm_grid *g = NULL;
        CHECK(NULL, dpsm_create_1d(n, dx, &g));
        CHECK(g, dpsm_set_repose_angle(g, theta));
        CHECK(g, dpsm_set_mobility(g, nu));
        CHECK(g, dpsm_set_boundary(g, DPSM_XMIN, sc->left_open ? DPSM_OPEN : DPSM_WALL));
        CHECK(g, dpsm_set_boundary(g, DPSM_XMAX, sc->right_open ? DPSM_OPEN : DPSM_WALL));
        for (int64_t i = 0; i < n; ++i) {
            const double x = ((double)i + 0.5) * dx;
            q[i] = 0.0;
            for (int k = 0; k < sc->intervals; ++k)
                if (x > sc->lo[k] && x < sc->hi[k]) q[i] = q0;
        }
        CHECK(g, dpsm_set_source(g, q));
        double t = 0.0;
        for (int64_t i = 0; i < n; ++i) fprintf(f, "%s,0,%.6f,0\n", sc->name, ((double)i + 0.5) * dx);
        double last_change = 0.0;
        for (int k = 0; k < ntimes; ++k) {
            CHECK(g, dpsm_get_heights(g, hprev));
            const double t_prev = t;
            /* Chunks of at most one time unit keep each call well under the
             * sub-step limit of a driven scene. */
            while (t < times[k]) {
                const double dt = fmin(1.0, times[k] - t);
                CHECK(g, dpsm_step(g, dt));
                t += dt;
            }
            t = times[k];
            CHECK(g, dpsm_get_heights(g, h));
            double change = 0.0;
            for (int64_t i = 0; i < n; ++i) {
                fprintf(f, "%s,%g,%.6f,%.10g\n", sc->name, t, ((double)i + 0.5) * dx, h[i]);
                change = fmax(change, fabs(h[i] - hprev[i]));
            }
            last_change = change / (t - t_prev);
        }
        const double total = mass(g, DPSM_MASS_TOTAL), sourced = mass(g, DPSM_MASS_SOURCED);
        const double outflow = mass(g, DPSM_MASS_OUTFLOW);
        fprintf(stderr,
                "  %s: t = %g, mass %.6g = sourced %.6g - outflow %.6g (residual %.1e), max |dh/dt| over the last "
                "interval %.2e (q = %g), %.2f s\n",
                sc->name, t, total, sourced, outflow, fabs(total - sourced + outflow) / sourced, last_change, q0,
                now_seconds() - t0);
        dpsm_destroy(g);
    }
    fprintf(stderr, "table-1d: %.1f s in all\n", now_seconds() - t_start);
    free(h);
    free(hprev);
    free(q);
    fclose(f);
    return 0;
}

/* ---- table-2d: the paper's Figs. 4 and 5 ------------------------------------ */

typedef struct {
    double x0, x1, y0, y1;
} rect;

typedef struct {
    const char *name;
    int scheme;
    double q; /* q / nu, with nu = 1 */
    int sources;
    rect source[2];
    /* Fig. 4: an open table (all four sides open). Fig. 5: a frame of one cell
     * around [0, 1]^2 of open cells held at 0 (the open table) except where a
     * wall rectangle covers it; wall rectangles inside are obstacles. */
    int framed;
    int walls;
    rect wall[3];
} scene_2d;

#define UNIT {0.0, 1.0, 0.0, 1.0}
static const scene_2d kScenes2d[] = {
    {"fig4a_isotropic", DPSM_SCHEME_ISOTROPIC, 0.5, 1, {UNIT}, 0, 0, {{0, 0, 0, 0}}},
    {"fig4a_pairwise", DPSM_SCHEME_PAIRWISE, 0.5, 1, {UNIT}, 0, 0, {{0, 0, 0, 0}}},
    {"fig4b_isotropic", DPSM_SCHEME_ISOTROPIC, 0.5, 1, {{0.45, 0.55, 0.45, 0.55}}, 0, 0, {{0, 0, 0, 0}}},
    {"fig4b_pairwise", DPSM_SCHEME_PAIRWISE, 0.5, 1, {{0.45, 0.55, 0.45, 0.55}}, 0, 0, {{0, 0, 0, 0}}},
    /* Fig. 5 (a, b): source everywhere; assumed: a wall along the middle half
     * of the side x = 0 (y in (0.25, 0.75)), the rest of the rim open. */
    {"fig5a", DPSM_SCHEME_ISOTROPIC, 0.5, 1, {UNIT}, 1, 1, {{-1.0, 0.0, 0.25, 0.75}}},
    {"fig5b", DPSM_SCHEME_ISOTROPIC, 0.05, 1, {UNIT}, 1, 1, {{-1.0, 0.0, 0.25, 0.75}}},
    /* Fig. 5 (c): source between two columns; assumed: two square columns of
     * side 0.1 level with the source, 0.05 to either side of it. */
    {"fig5c",
     DPSM_SCHEME_ISOTROPIC,
     0.5,
     1,
     {{0.35, 0.65, 0.7, 0.95}},
     1,
     2,
     {{0.2, 0.3, 0.775, 0.875}, {0.7, 0.8, 0.775, 0.875}}},
    /* Fig. 5 (d): central source; assumed: one square column of side 0.1 to
     * its left, so the flows round it meet behind it. */
    {"fig5d", DPSM_SCHEME_ISOTROPIC, 0.1, 1, {{0.4, 0.6, 0.4, 0.6}}, 1, 1, {{0.2, 0.3, 0.45, 0.55}}},
};

static int inside(const rect *r, double x, double y) { return x > r->x0 && x < r->x1 && y > r->y0 && y < r->y1; }

static int cmd_table_2d(int argc, char **argv) {
    if (argc < 1) {
        fprintf(stderr, "usage: dpsm-validate table-2d OUTDIR [n]\n");
        return 2;
    }
    const char *dir = argv[0];
    /* n = 80: cells of 0.0125, so every edge of every source and obstacle
     * rectangle is a cell face. */
    const int64_t n = argc > 1 ? atoi(argv[1]) : 80;
    if (n < 8) {
        fprintf(stderr, "dpsm-validate: n must be at least 8\n");
        return 2;
    }
    const double dx = 1.0 / (double)n, theta = deg(45.0), t_max = 200.0, chunk = 0.5;
    FILE *f = open_csv(dir, "table_2d.csv");
    fprintf(f, "scene,x,y,h\n");
    const double t_start = now_seconds();
    for (size_t s = 0; s < sizeof kScenes2d / sizeof kScenes2d[0]; ++s) {
        const scene_2d *sc = &kScenes2d[s];
        const double t0 = now_seconds();
        const int64_t m = sc->framed ? n + 2 : n, off = sc->framed ? 1 : 0;
        const size_t cells = (size_t)(m * m);
        double *h = xcalloc(cells, sizeof *h), *hprev = xcalloc(cells, sizeof *hprev);
        double *q = xcalloc(cells, sizeof *q);
        uint8_t *kind = xcalloc(cells, sizeof *kind);
        dpsm_grid *g = NULL;
        CHECK(NULL, dpsm_create_2d(m, m, dx, dx, &g));
        CHECK(g, dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE)); /* the paper's experiments, in time */
        CHECK(g, dpsm_set_repose_angle(g, theta));
        CHECK(g, dpsm_set_mobility(g, 1.0));
        CHECK(g, dpsm_set_scheme(g, sc->scheme));
        if (!sc->framed)
            for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side) CHECK(g, dpsm_set_boundary(g, side, DPSM_OPEN));
        for (int64_t j = 0; j < m; ++j)
            for (int64_t i = 0; i < m; ++i) {
                const size_t c = (size_t)(i + m * j);
                const double x = ((double)(i - off) + 0.5) * dx, y = ((double)(j - off) + 0.5) * dx;
                const int rim = sc->framed && (i == 0 || j == 0 || i == m - 1 || j == m - 1);
                kind[c] = rim ? DPSM_CELL_OPEN : DPSM_CELL_SAND;
                for (int k = 0; k < sc->walls; ++k)
                    if (inside(&sc->wall[k], x, y)) kind[c] = DPSM_CELL_WALL;
                for (int k = 0; k < sc->sources; ++k)
                    if (inside(&sc->source[k], x, y)) q[c] = sc->q;
            }
        CHECK(g, dpsm_set_cell_kinds(g, kind));
        CHECK(g, dpsm_set_source(g, q));
        /* Run until the surface is steady: the largest |dh/dt| over a chunk
         * below 1e-4 q (the last approach to the steady state is slow, and
         * changes the picture by less than 1e-3 of the pile's height), or
         * t_max. */
        double t = 0.0, rate = INFINITY;
        while (t < t_max) {
            CHECK(g, dpsm_get_heights(g, hprev));
            CHECK(g, dpsm_step(g, chunk));
            t += chunk;
            CHECK(g, dpsm_get_heights(g, h));
            rate = 0.0;
            for (size_t c = 0; c < cells; ++c) rate = fmax(rate, fabs(h[c] - hprev[c]) / chunk);
            if (rate < 1e-4 * sc->q) break;
        }
        for (int64_t j = 0; j < m; ++j)
            for (int64_t i = 0; i < m; ++i) {
                const size_t c = (size_t)(i + m * j);
                const double x = ((double)(i - off) + 0.5) * dx, y = ((double)(j - off) + 0.5) * dx;
                if (kind[c] == DPSM_CELL_WALL)
                    fprintf(f, "%s,%.6f,%.6f,nan\n", sc->name, x, y);
                else
                    fprintf(f, "%s,%.6f,%.6f,%.10g\n", sc->name, x, y, kind[c] == DPSM_CELL_OPEN ? 0.0 : h[c]);
            }
        double hmax = 0.0;
        for (size_t c = 0; c < cells; ++c)
            if (kind[c] == DPSM_CELL_SAND) hmax = fmax(hmax, h[c]);
        const double total = mass(g, DPSM_MASS_TOTAL), sourced = mass(g, DPSM_MASS_SOURCED);
        const double outflow = mass(g, DPSM_MASS_OUTFLOW);
        fprintf(stderr,
                "  %s: %lldx%lld cells, steady at t = %g (max |dh/dt| %.1e), max h %.5f, mass %.6g = sourced %.6g - "
                "outflow %.6g (residual %.1e), %.1f s\n",
                sc->name, (long long)m, (long long)m, t, rate, hmax, total, sourced, outflow,
                fabs(total - sourced + outflow) / sourced, now_seconds() - t0);
        dpsm_destroy(g);
        free(h);
        free(hprev);
        free(q);
        free(kind);
    }
    fprintf(stderr, "table-2d: %.1f s in all\n", now_seconds() - t_start);
    fclose(f);
    return 0;
}

/* ---- dispatch ---------------------------------------------------------------- */

static int cmd_all(int argc, char **argv);

static const command kCommands[] = {
    {"column-sweep", cmd_column_sweep, "OUTDIR [rings_per_r0]  axisymmetric column collapse -> column_sweep.csv"},
    {"table-1d", cmd_table_1d, "OUTDIR                  the paper's Figs. 2-3 -> table_1d.csv"},
    {"table-2d", cmd_table_2d, "OUTDIR [n]              the paper's Figs. 4-5 -> table_2d.csv"},
    {"all", cmd_all, "OUTDIR                  all of the above"},
};

static int cmd_all(int argc, char **argv) {
    if (argc < 1) {
        fprintf(stderr, "usage: dpsm-validate all OUTDIR\n");
        return 2;
    }
    for (int k = 0; k < 3; ++k) {
        const int rc = kCommands[k].run(1, argv);
        if (rc != 0) return rc;
    }
    return 0;
}

int main(int argc, char **argv) { return run_command(kCommands, sizeof kCommands / sizeof kCommands[0], argc, argv); }
