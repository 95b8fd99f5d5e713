/* Distributed grids (dpsm_mpi.h) against serial runs of the same scenes.
 *
 * Run under mpiexec with any number of ranks. For every scene and every
 * decomposition of its global grid into one block per rank (strips along x,
 * strips along y, a px x py grid of blocks, uneven blocks, blocks narrower
 * than the 5-cell halo), each rank runs the scene on its block of a
 * distributed grid and, alone, on a serial grid of the whole scene, and
 * requires after every step:
 *   - its block's heights equal the serial heights bit for bit;
 *   - the step information (sub-steps, time integrated, rest, largest excess
 *     slope) equals the serial figures, on every rank;
 *   - the four mass figures and what left through each side equal the
 *     serial ones to 1e-12 of the mass; the ledger closes;
 *   - where the scene records face fluxes, the block's faces (both of its
 *     edges included) carried what the serial grid's did, bit for bit.
 * Then bad decompositions and disagreeing ranks must fail on every rank with
 * a message naming the problem.
 *
 * Every failed check prints rank, scene, decomposition and the first
 * differing cell; the program exits non-zero when any rank saw a failure.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mpi.h>

#include <dpsm/dpsm.h>
#include <dpsm/dpsm_mpi.h>

#include "mpi_check.h"

typedef struct {
    int64_t i0, j0, ni, nj;
} block_t;

/* ---- decompositions ------------------------------------------------------ */

enum { STRIPS_X, STRIPS_Y, GRID_2D, UNEVEN, NARROW, N_DECOMPOSITIONS };
static const char *const decomposition_names[] = {"strips along x", "strips along y", "px x py blocks",
                                                  "uneven blocks", "blocks narrower than the halo"};

/* The k-th of n parts of [0, n_cells): uneven on purpose (the first parts larger). */
static void split(int64_t n_cells, int n, int k, int64_t *start, int64_t *count) {
    int64_t base = n_cells / n, extra = n_cells % n;
    *start = k * base + (k < extra ? k : extra);
    *count = base + (k < extra ? 1 : 0);
}

/* This rank's block of an nx x ny grid under decomposition `kind`. */
static block_t block_of(int kind, int rank, int size, int64_t nx, int64_t ny) {
    block_t b = {0, 0, nx, ny};
    if (size == 1) return b;
    switch (kind) {
        case STRIPS_X: split(nx, size, rank, &b.i0, &b.ni); break;
        case STRIPS_Y: split(ny, size, rank, &b.j0, &b.nj); break;
        case GRID_2D: {
            int px = 1;
            for (int p = 1; p * p <= size; ++p)
                if (size % p == 0) px = p;
            int py = size / px;
            split(nx, px, rank % px, &b.i0, &b.ni);
            split(ny, py, rank / px, &b.j0, &b.nj);
            break;
        }
        case UNEVEN: {
            /* Blocks that do not line up: the first half of the ranks split a
             * left part in rows at one place, the rest a right part at others. */
            int64_t cut = nx / 3 + 7;
            int left = size / 2, right = size - left;
            if (rank < left) {
                b.ni = cut;
                int64_t start, count;
                split(ny, left, rank, &start, &count);
                b.j0 = start;
                b.nj = count;
                if (left > 1 && rank == 0) b.nj += 9; /* move the row boundary off the even split */
                if (left > 1 && rank == 1) {
                    b.j0 += 9;
                    b.nj -= 9;
                }
            } else {
                b.i0 = cut;
                b.ni = nx - cut;
                int64_t start, count;
                split(ny, right, rank - left, &start, &count);
                b.j0 = start;
                b.nj = count;
            }
            break;
        }
        case NARROW: {
            /* Ranks but the last own strips of 1, 2, 3 ... columns (fewer than
             * the halo's 5), the last rank the rest. */
            int64_t at = 0;
            for (int r = 0; r < rank; ++r) at += 1 + r % 4;
            b.i0 = at;
            b.ni = rank == size - 1 ? nx - at : 1 + rank % 4;
            break;
        }
    }
    return b;
}

/* ---- scenes -------------------------------------------------------------- */

typedef struct {
    const char *name;
    int64_t nx, ny;
    double dx, dy;
    int sides[4];
    int scheme;
    double theta;
    int steps;
    double dt_in_stable_steps; /* dt of each dpsm_step, in units of dpsm_stable_dt */
    double *h, *q;             /* nx*ny; q may be NULL */
    uint8_t *kinds;            /* may be NULL */
    /* Between steps: the host adds a bump here (global cells), and later sets new kinds. */
    int bump_before_step;
    block_t bump;
    int new_kinds_before_step;
    uint8_t *new_kinds;
    /* When > 0: the bump is a spike of this height, 2 cells inside rank 1's
     * block, on a surface at rest: only the tiles near it may move, and
     * across the blocks' edge only the neighbour's activity can wake them. */
    double spike;
    /* The physics of real scenes (0 / NULL: not used). */
    double *bed, *theta_field;
    double exponent, static_angle;
    /* What a host couples: the levels beyond each side of the global domain
     * (NULL: none; ny values for the x sides, nx for the y sides), new ones
     * for the first side before step `levels_before_step`, face fluxes. */
    double *side_levels[4];
    int levels_before_step;
    double *new_levels;
    int record;
} scene_t;

static double *zeros(int64_t n) { return calloc((size_t)n, sizeof(double)); }

/* A column of height h0 and radius r0 centred at (cx, cy), in cells. */
static void add_column(double *h, int64_t nx, int64_t ny, double cx, double cy, double r0, double h0) {
    for (int64_t j = 0; j < ny; ++j)
        for (int64_t i = 0; i < nx; ++i) {
            double x = (double)i + 0.5 - cx, y = (double)j + 0.5 - cy;
            if (x * x + y * y <= r0 * r0) h[i + nx * j] += h0;
        }
}

static scene_t collapse_open(void) {
    scene_t s = {"collapsing column, open sides", 150, 131, 1.0, 1.0, {DPSM_OPEN, DPSM_OPEN, DPSM_OPEN, DPSM_OPEN},
                 DPSM_SCHEME_ISOTROPIC, 0.55, 6, 60.0, NULL, NULL, NULL, 0, {0, 0, 0, 0}, 0, NULL, 0.0, NULL, NULL, 0.0, 0.0, {NULL, NULL, NULL, NULL}, 0, NULL, 0};
    s.h = zeros(s.nx * s.ny);
    add_column(s.h, s.nx, s.ny, 66.0, 60.5, 24.0, 30.0);
    s.bump_before_step = 3;
    s.bump = (block_t){30, 20, 50, 40};
    return s;
}

static scene_t source_walls(void) {
    scene_t s = {"source straddling blocks, walls and an open side", 97, 140, 0.5, 0.7,
                 {DPSM_WALL, DPSM_OPEN, DPSM_WALL, DPSM_WALL}, DPSM_SCHEME_ISOTROPIC, 0.6, 8, 25.0,
                 NULL, NULL, NULL, 0, {0, 0, 0, 0}, 0, NULL, 0.0, NULL, NULL, 0.0, 0.0, {NULL, NULL, NULL, NULL}, 0, NULL, 0};
    s.h = zeros(s.nx * s.ny);
    s.q = zeros(s.nx * s.ny);
    for (int64_t j = 0; j < s.ny; ++j)
        for (int64_t i = 0; i < s.nx; ++i) {
            s.h[i + s.nx * j] = 0.01 * (double)((i * 7 + j * 13) % 11);
            if (i >= 20 && i < 60 && j >= 50 && j < 90) s.q[i + s.nx * j] = 0.3 + 0.01 * (double)(i % 5);
        }
    return s;
}

static scene_t obstacles(void) {
    scene_t s = {"walls and sinks straddling blocks, pairwise scheme", 140, 100, 1.0, 1.0,
                 {DPSM_WALL, DPSM_WALL, DPSM_OPEN, DPSM_WALL}, DPSM_SCHEME_PAIRWISE, 0.5, 6, 40.0,
                 NULL, NULL, NULL, 0, {0, 0, 0, 0}, 0, NULL, 0.0, NULL, NULL, 0.0, 0.0, {NULL, NULL, NULL, NULL}, 0, NULL, 0};
    int64_t n = s.nx * s.ny;
    s.h = zeros(n);
    s.kinds = calloc((size_t)n, 1);
    s.new_kinds = calloc((size_t)n, 1);
    add_column(s.h, s.nx, s.ny, 50.0, 50.0, 30.0, 25.0);
    add_column(s.h, s.nx, s.ny, 100.0, 40.0, 15.0, 12.0);
    for (int64_t j = 0; j < s.ny; ++j)
        for (int64_t i = 0; i < s.nx; ++i) {
            uint8_t k = DPSM_CELL_SAND;
            if (i >= 45 && i < 75 && j >= 48 && j < 53) k = DPSM_CELL_WALL;    /* a wall across blocks */
            if ((i - 70) * (i - 70) + (j - 70) * (j - 70) < 40) k = DPSM_CELL_OPEN; /* a sink */
            if (i == 1 || j == 98) k = DPSM_CELL_WALL;                        /* thin walls along edges */
            s.kinds[i + s.nx * j] = k;
            s.new_kinds[i + s.nx * j] = k;
            if (i >= 20 && i < 90 && j == 30) s.new_kinds[i + s.nx * j] = DPSM_CELL_OPEN; /* a new trench */
        }
    for (int64_t c = 0; c < n; ++c)
        if (s.kinds[c] == DPSM_CELL_OPEN) s.h[c] = 1.5; /* sinks held at 1.5 */
    s.new_kinds_before_step = 3;
    s.record = 1;
    return s;
}

static scene_t spike_near_edge(void) {
    scene_t s = {"a spike near a block's edge on a surface at rest", 140, 120, 1.0, 1.0,
                 {DPSM_WALL, DPSM_WALL, DPSM_WALL, DPSM_WALL}, DPSM_SCHEME_ISOTROPIC, 0.6, 6, 10.0,
                 NULL, NULL, NULL, 0, {0, 0, 0, 0}, 0, NULL, 0.0, NULL, NULL, 0.0, 0.0, {NULL, NULL, NULL, NULL}, 0, NULL, 0};
    s.h = zeros(s.nx * s.ny);
    for (int64_t j = 0; j < s.ny; ++j)
        for (int64_t i = 0; i < s.nx; ++i) s.h[i + s.nx * j] = 0.3 * (double)((i + j) % 2); /* at rest: slope 0.3 < tan 0.6 */
    s.bump_before_step = 1;
    s.spike = 8.0;
    return s;
}

/* Erosion on thin sand over sloping rock, patches of two angles, exponent 1.5
 * and hysteresis, all straddling the blocks: the bed's cap, the faces' angles
 * and the moving cells must cross the blocks' edges as in a serial run. */
static scene_t physics(void) {
    scene_t s = {"bed, erosion, angle field, exponent 1.5, hysteresis", 130, 110, 0.5, 0.5,
                 {DPSM_OPEN, DPSM_WALL, DPSM_WALL, DPSM_WALL}, DPSM_SCHEME_ISOTROPIC, 0.55, 8, 30.0,
                 NULL, NULL, NULL, 0, {0, 0, 0, 0}, 0, NULL, 0.0, NULL, NULL, 1.5, 0.62, {NULL, NULL, NULL, NULL}, 0, NULL, 0};
    const int64_t n = s.nx * s.ny;
    s.h = zeros(n);
    s.q = zeros(n);
    s.bed = zeros(n);
    s.theta_field = zeros(n);
    for (int64_t j = 0; j < s.ny; ++j)
        for (int64_t i = 0; i < s.nx; ++i) {
            const int64_t c = i + s.nx * j;
            s.bed[c] = 0.4 * 0.5 * (double)i;
            s.h[c] = s.bed[c] + 0.05 + 0.01 * (double)((i * 7 + j * 3) % 5);
            s.theta_field[c] = ((i / 17 + j / 23) % 2) ? 0.5 : 0.65;
            if (i >= 50 && i < 80 && j >= 40 && j < 70) s.q[c] = -0.3; /* more than the sand there */
        }
    add_column(s.h, s.nx, s.ny, 64.0, 55.0, 12.0, 4.0);
    add_column(s.h, s.nx, s.ny, 100.0, 80.0, 8.0, 3.0);
    s.record = 1;
    return s;
}

/* Sand flows in from a raised side whose level varies along it, out to a
 * lower side and to an open side at 0, past a wall side with levels of its
 * own; the raised side's levels change mid-run; every face recorded. */
static scene_t side_levels(void) {
    scene_t s = {"levels beyond the sides, inflow and outflow, face fluxes", 120, 100, 1.0, 1.0,
                 {DPSM_OPEN, DPSM_OPEN, DPSM_WALL, DPSM_OPEN}, DPSM_SCHEME_ISOTROPIC, 0.55, 6, 30.0,
                 NULL, NULL, NULL, 0, {0, 0, 0, 0}, 0, NULL, 0.0, NULL, NULL, 0.0, 0.0, {NULL, NULL, NULL, NULL}, 0, NULL, 0};
    s.h = zeros(s.nx * s.ny);
    add_column(s.h, s.nx, s.ny, 70.0, 45.0, 20.0, 15.0);
    s.side_levels[DPSM_XMIN] = zeros(s.ny);
    s.new_levels = zeros(s.ny);
    for (int64_t j = 0; j < s.ny; ++j) {
        s.side_levels[DPSM_XMIN][j] = 6.0 + 0.5 * (double)(j % 7);
        s.new_levels[j] = 2.0 + 0.25 * (double)(j % 5);
    }
    s.side_levels[DPSM_YMIN] = zeros(s.nx);
    s.side_levels[DPSM_YMAX] = zeros(s.nx);
    for (int64_t i = 0; i < s.nx; ++i) {
        s.side_levels[DPSM_YMIN][i] = 9.0; /* a wall side: no effect */
        s.side_levels[DPSM_YMAX][i] = 0.5 + 0.01 * (double)i;
    }
    s.levels_before_step = 3;
    s.record = 1;
    return s;
}

static void free_scene(scene_t *s) {
    for (int side = 0; side < 4; ++side) free(s->side_levels[side]);
    free(s->new_levels);
    free(s->bed);
    free(s->theta_field);
    free(s->h);
    free(s->q);
    free(s->kinds);
    free(s->new_kinds);
}

/* Copies the block b of a global nx-wide array (element size `size`). */
static void *sub_array(const void *global, size_t size, int64_t nx, block_t b) {
    char *out = malloc((size_t)(b.ni * b.nj) * size);
    for (int64_t j = 0; j < b.nj; ++j)
        memcpy(out + (size_t)(j * b.ni) * size, (const char *)global + (size_t)(b.i0 + nx * (b.j0 + j)) * size,
               (size_t)b.ni * size);
    return out;
}

/* Sets the levels beyond `side` on g: block b's part of the global `levels`
 * (its rows for an x side, its columns for a y side). A block that does not
 * touch the side passes levels of 1000 instead, which must be ignored. */
static void set_side_levels(dpsm_grid *g, const scene_t *s, int side, const double *levels, block_t b) {
    const int touches = side == DPSM_XMIN   ? b.i0 == 0
                        : side == DPSM_XMAX ? b.i0 + b.ni == s->nx
                        : side == DPSM_YMIN ? b.j0 == 0
                                            : b.j0 + b.nj == s->ny;
    const int64_t n = side <= DPSM_XMAX ? b.nj : b.ni;
    double *mine = malloc((size_t)n * sizeof(double));
    for (int64_t k = 0; k < n; ++k) mine[k] = touches ? levels[(side <= DPSM_XMAX ? b.j0 : b.i0) + k] : 1000.0;
    OK(g, dpsm_set_side_levels(g, side, mine));
    free(mine);
}

/* Sets up g (the whole scene when b is the whole grid, else its block b). */
static void set_scene(dpsm_grid *g, const scene_t *s, block_t b) {
    for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side)
        if (s->side_levels[side]) set_side_levels(g, s, side, s->side_levels[side], b);
    if (s->record) OK(g, dpsm_set_face_flux_recording(g, 1));
    for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side) OK(g, dpsm_set_boundary(g, side, s->sides[side]));
    OK(g, dpsm_set_scheme(g, s->scheme));
    OK(g, dpsm_set_repose_angle(g, s->theta));
    if (s->kinds) {
        uint8_t *k = sub_array(s->kinds, 1, s->nx, b);
        OK(g, dpsm_set_cell_kinds(g, k));
        free(k);
    }
    double *h = sub_array(s->h, sizeof(double), s->nx, b);
    OK(g, dpsm_set_heights(g, h));
    free(h);
    if (s->bed) {
        double *zb = sub_array(s->bed, sizeof(double), s->nx, b);
        OK(g, dpsm_set_bedrock(g, zb));
        free(zb);
    }
    if (s->theta_field) {
        double *theta = sub_array(s->theta_field, sizeof(double), s->nx, b);
        OK(g, dpsm_set_repose_angle_field(g, theta));
        free(theta);
    }
    if (s->exponent > 0) OK(g, dpsm_set_flux_exponent(g, s->exponent));
    if (s->static_angle > 0) OK(g, dpsm_set_static_angle(g, s->static_angle));
    if (s->q) {
        double *q = sub_array(s->q, sizeof(double), s->nx, b);
        OK(g, dpsm_set_source(g, q));
        free(q);
    }
}

/* The host's changes before step `step`, on the part of them in block b. */
static void host_changes(dpsm_grid *g, const scene_t *s, block_t b, int step) {
    if (s->bump_before_step == step) {
        int64_t i0 = s->bump.i0 > b.i0 ? s->bump.i0 : b.i0, j0 = s->bump.j0 > b.j0 ? s->bump.j0 : b.j0;
        int64_t i1 = s->bump.i0 + s->bump.ni < b.i0 + b.ni ? s->bump.i0 + s->bump.ni : b.i0 + b.ni;
        int64_t j1 = s->bump.j0 + s->bump.nj < b.j0 + b.nj ? s->bump.j0 + s->bump.nj : b.j0 + b.nj;
        if (i1 > i0 && j1 > j0) {
            double *dh = malloc((size_t)((i1 - i0) * (j1 - j0)) * sizeof(double));
            for (int64_t j = j0; j < j1; ++j)
                for (int64_t i = i0; i < i1; ++i)
                    dh[(i - i0) + (i1 - i0) * (j - j0)] = s->spike > 0 ? s->spike : 0.05 * (double)((i + 3 * j) % 40);
            OK(g, dpsm_add_heights_region(g, i0 - b.i0, j0 - b.j0, i1 - i0, j1 - j0, dh));
            free(dh);
        }
    }
    if (s->new_kinds && s->new_kinds_before_step == step) {
        uint8_t *k = sub_array(s->new_kinds, 1, s->nx, b);
        OK(g, dpsm_set_cell_kinds(g, k));
        free(k);
    }
    if (s->new_levels && s->levels_before_step == step) set_side_levels(g, s, DPSM_XMIN, s->new_levels, b);
}

/* The same figure on every rank: its smallest and largest agree. */
static int same_on_every_rank(double x) {
    double lo = x, hi = x;
    MPI_Allreduce(MPI_IN_PLACE, &lo, 1, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
    MPI_Allreduce(MPI_IN_PLACE, &hi, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    return lo == hi;
}

/* What left through each side: global figures, as the serial grid's to 1e-12
 * of the mass, the same on every rank. */
static void compare_side_outflows(const dpsm_grid *g, const dpsm_grid *serial, const char *what) {
    double scale = 0.0;
    for (int q = DPSM_MASS_TOTAL; q <= DPSM_MASS_OUTFLOW; ++q) {
        double m = 0.0;
        OK(serial, dpsm_get_mass(serial, q, &m));
        scale += fabs(m);
    }
    for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side) {
        double a = 0.0, b = 0.0;
        OK(g, dpsm_get_side_outflow(g, side, &a));
        OK(serial, dpsm_get_side_outflow(serial, side, &b));
        require(fabs(a - b) <= 1e-12 * scale, "%s: side %d took %.17g distributed, %.17g serial", what, side, a, b);
        require(same_on_every_rank(a), "%s: side %d's outflow differs between ranks", what, side);
    }
}

/* The block's faces against the serial grid's same faces, bit for bit. */
static void compare_face_fluxes(const dpsm_grid *g, const dpsm_grid *serial, const scene_t *s, block_t b,
                                const char *what) {
    const size_t nfx = (size_t)((b.ni + 1) * b.nj), nfy = (size_t)(b.ni * (b.nj + 1));
    const size_t sfx = (size_t)((s->nx + 1) * s->ny), sfy = (size_t)(s->nx * (s->ny + 1));
    double *x = malloc(nfx * sizeof(double)), *y = malloc(nfy * sizeof(double));
    double *sx = malloc(sfx * sizeof(double)), *sy = malloc(sfy * sizeof(double));
    OK(g, dpsm_get_face_fluxes(g, x, y));
    OK(serial, dpsm_get_face_fluxes(serial, sx, sy));
    int64_t differ = 0, carried = 0;
    for (int64_t j = 0; j < b.nj; ++j)
        for (int64_t i = 0; i <= b.ni; ++i) {
            const double mine = x[i + (b.ni + 1) * j], ref = sx[(b.i0 + i) + (s->nx + 1) * (b.j0 + j)];
            differ += memcmp(&mine, &ref, sizeof(double)) != 0;
            carried += ref != 0.0;
        }
    for (int64_t j = 0; j <= b.nj; ++j)
        for (int64_t i = 0; i < b.ni; ++i) {
            const double mine = y[i + b.ni * j], ref = sy[(b.i0 + i) + s->nx * (b.j0 + j)];
            differ += memcmp(&mine, &ref, sizeof(double)) != 0;
            carried += ref != 0.0;
        }
    require(differ == 0, "%s: %lld of the block's faces carried other than the serial grid's (of %lld that carried sand)",
            what, (long long)differ, (long long)carried);
    free(x);
    free(y);
    free(sx);
    free(sy);
}

static void compare_step_info(const dpsm_grid *g, const dpsm_grid *serial, const char *what) {
    const int items[] = {DPSM_INFO_SUBSTEPS, DPSM_INFO_TIME_INTEGRATED, DPSM_INFO_AT_REST, DPSM_INFO_MAX_EXCESS_SLOPE};
    const char *names[] = {"sub-steps", "time integrated", "at rest", "largest excess slope"};
    for (int k = 0; k < 4; ++k) {
        double a = -1, b = -2;
        OK(g, dpsm_get_step_info(g, items[k], &a));
        OK(serial, dpsm_get_step_info(serial, items[k], &b));
        require(a == b, "%s: step info %s is %.17g distributed, %.17g serial", what, names[k], a, b);
    }
    double per_exchange = -1.0;
    OK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS_PER_EXCHANGE, &per_exchange));
    require(per_exchange == 1.0, "%s: a distributed 2D grid exchanged its halo every %g sub-steps, not every one", what,
            per_exchange);
}

static void compare_mass(const dpsm_grid *g, const dpsm_grid *serial, const char *what) {
    const int q[] = {DPSM_MASS_TOTAL, DPSM_MASS_SOURCED, DPSM_MASS_EXTERNAL, DPSM_MASS_OUTFLOW};
    const char *names[] = {"total", "sourced", "external", "outflow"};
    double a[4], b[4];
    for (int k = 0; k < 4; ++k) {
        OK(g, dpsm_get_mass(g, q[k], &a[k]));
        OK(serial, dpsm_get_mass(serial, q[k], &b[k]));
    }
    double scale = fabs(b[0]) + fabs(b[1]) + fabs(b[2]) + fabs(b[3]);
    for (int k = 0; k < 4; ++k)
        require(fabs(a[k] - b[k]) <= 1e-12 * scale, "%s: mass %s is %.17g distributed, %.17g serial (scale %g)", what,
                names[k], a[k], b[k], scale);
    double residual = fabs(a[0] - (a[1] + a[2] - a[3]));
    require(residual <= 1e-12 * scale, "%s: the global ledger does not close: residual %g of %g", what, residual, scale);
    /* Every rank must hold the same global figures. */
    double lo[4], hi[4];
    MPI_Allreduce(a, lo, 4, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
    MPI_Allreduce(a, hi, 4, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    for (int k = 0; k < 4; ++k)
        require(lo[k] == hi[k], "%s: mass %s differs between ranks (%.17g .. %.17g)", what, names[k], lo[k], hi[k]);
}

/* Runs scene s on decomposition `kind` and on a serial grid; returns the
 * largest |difference| of heights seen (0 when bit for bit). */
static void run_scene(const scene_t *s, int kind) {
    char what[256];
    block_t b = block_of(kind, rank_, size_, s->nx, s->ny);
    block_t whole = {0, 0, s->nx, s->ny};
    scene_t placed = *s;
    if (s->spike > 0) {
        block_t near = block_of(kind, size_ > 1 ? 1 : 0, size_, s->nx, s->ny);
        placed.bump = (block_t){near.i0 + 2 < s->nx - 2 ? near.i0 + 2 : s->nx - 2,
                                near.j0 + 2 < s->ny - 2 ? near.j0 + 2 : s->ny - 2, 2, 2};
        s = &placed;
    }
    dpsm_grid *g = NULL, *serial = NULL;
    int status = dpsm_create_2d_mpi(MPI_COMM_WORLD, s->nx, s->ny, b.i0, b.j0, b.ni, b.nj, s->dx, s->dy, &g);
    snprintf(what, sizeof what, "%s, %s, block [%lld, %lld) x [%lld, %lld)", s->name, decomposition_names[kind],
             (long long)b.i0, (long long)(b.i0 + b.ni), (long long)b.j0, (long long)(b.j0 + b.nj));
    require(status == DPSM_OK, "%s: dpsm_create_2d_mpi: %s: %s", what, dpsm_status_string(status), dpsm_last_error(NULL));
    if (status != DPSM_OK) return;
    OK(NULL, dpsm_create_2d(s->nx, s->ny, s->dx, s->dy, &serial));
    /* A distributed grid steps in time by default; its serial twin must too. */
    OK(serial, dpsm_set_relaxation(serial, DPSM_RELAX_TIME_ACCURATE));
    set_scene(g, s, b);
    set_scene(serial, s, whole);

    int64_t shape_x = 0, shape_y = 0;
    OK(g, dpsm_get_shape(g, &shape_x, &shape_y));
    require(shape_x == b.ni && shape_y == b.nj, "%s: dpsm_get_shape gives %lld x %lld", what, (long long)shape_x,
            (long long)shape_y);
    compare_mass(g, serial, what);

    double stable = 0;
    OK(serial, dpsm_stable_dt(serial, &stable));
    const double dt = s->dt_in_stable_steps * stable;
    double *mine = malloc((size_t)(b.ni * b.nj) * sizeof(double));
    double *ref = malloc((size_t)(b.ni * b.nj) * sizeof(double));
    int moved_any = 0;
    for (int step = 0; step < s->steps; ++step) {
        char at[320];
        snprintf(at, sizeof at, "%s, step %d", what, step);
        host_changes(g, s, b, step);
        host_changes(serial, s, whole, step);
        OK(g, dpsm_step(g, dt));
        OK(serial, dpsm_step(serial, dt));
        OK(g, dpsm_get_heights(g, mine));
        OK(serial, dpsm_get_heights_region(serial, b.i0, b.j0, b.ni, b.nj, ref));
        int64_t differ = 0, first = -1;
        double worst = 0.0;
        for (int64_t c = 0; c < b.ni * b.nj; ++c)
            if (memcmp(&mine[c], &ref[c], sizeof(double)) != 0) {
                if (first < 0) first = c;
                ++differ;
                if (fabs(mine[c] - ref[c]) > worst) worst = fabs(mine[c] - ref[c]);
            }
        require(differ == 0,
                "%s: %lld cells differ from the serial run (largest |difference| %g); first: global cell (%lld, %lld)"
                " is %.17g, serially %.17g",
                at, (long long)differ, worst, first < 0 ? -1LL : (long long)(b.i0 + first % b.ni),
                first < 0 ? -1LL : (long long)(b.j0 + first / b.ni), first < 0 ? 0.0 : mine[first],
                first < 0 ? 0.0 : ref[first]);
        compare_step_info(g, serial, at);
        compare_mass(g, serial, at);
        compare_side_outflows(g, serial, at);
        if (s->record) compare_face_fluxes(g, serial, s, b, at);
        double substeps = 0;
        OK(serial, dpsm_get_step_info(serial, DPSM_INFO_SUBSTEPS, &substeps));
        if (substeps > 0) moved_any = 1;
    }
    require(moved_any, "%s: the scene never moved: it tests nothing", what);
    /* Over a limit of 10 sub-steps, a step of 11 fails where the scene may flow
     * for ever (a source, held levels that differ: open cells, open sides) and
     * is taken otherwise, as on the serial grid. */
    OK(g, dpsm_set_max_substeps(g, 10));
    OK(serial, dpsm_set_max_substeps(serial, 10));
    const int limited = dpsm_step(g, 10.5 * stable), serial_limited = dpsm_step(serial, 10.5 * stable);
    require(limited == serial_limited, "%s: a step over the limit: %s distributed (%s), %s serial", what,
            dpsm_status_string(limited), dpsm_last_error(g), dpsm_status_string(serial_limited));
    free(mine);
    free(ref);
    dpsm_destroy(serial);
    dpsm_destroy(g);
}

/* ---- bad input ----------------------------------------------------------- */

/* Every rank must get a non-zero status and a message containing `needle`. */
static void expect_create_fails(const char *what, int64_t nxg, int64_t nyg, block_t b, int null_out,
                                const char *needle) {
    dpsm_grid *g = (dpsm_grid *)&g; /* not NULL: the call must set it to NULL */
    int status = dpsm_create_2d_mpi(MPI_COMM_WORLD, nxg, nyg, b.i0, b.j0, b.ni, b.nj, 1.0, 1.0, null_out ? NULL : &g);
    const char *msg = dpsm_last_error(NULL);
    require(status != DPSM_OK, "%s: dpsm_create_2d_mpi succeeded", what);
    require(strstr(msg, needle) != NULL, "%s: the message \"%s\" does not name the problem (\"%s\")", what, msg, needle);
    if (!null_out) require(g == NULL, "%s: *out is not NULL after a failure", what);
    if (status == DPSM_OK && !null_out) dpsm_destroy(g);
    int all = 0, mine = status != DPSM_OK;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    require(all == 1, "%s: some rank did not fail", what);
    if (rank_ == 0) printf("  refused on every rank: %s: %s\n", what, msg);
}

static void bad_decompositions(void) {
    const int64_t nx = 40, ny = 30;
    block_t good = block_of(STRIPS_X, rank_, size_, nx, ny);
    /* A gap: the last rank's block loses its last column (or the only rank's). */
    block_t gap = good;
    if (rank_ == size_ - 1) gap.ni -= 1;
    expect_create_fails("a gap", nx, ny, gap, 0, "cover");
    /* A block outside the grid. */
    block_t outside = good;
    if (rank_ == 0) outside.i0 = -1;
    expect_create_fails("a block outside the grid", nx, ny, outside, 0, "does not lie in the global grid");
    /* A NULL out on one rank. */
    expect_create_fails("out NULL on rank 0", nx, ny, good, rank_ == 0, "out is NULL on rank 0");
    if (rank_ == 0) {
        /* rank 0 alone cannot read the message when its out is NULL: it is the same string */
    }
    /* A zero-sized block. */
    block_t empty = good;
    if (rank_ == 0) empty.ni = 0;
    expect_create_fails("an empty block", nx, ny, empty, 0, "must be at least 1");
    if (size_ >= 2) {
        /* An overlap: rank 1's block starts one column early. */
        block_t overlap = good;
        if (rank_ == 1) {
            overlap.i0 -= 1;
            overlap.ni += 1;
        }
        expect_create_fails("an overlap", nx, ny, overlap, 0, "overlap");
        /* The ranks disagree on the global size. */
        expect_create_fails("a wrong global size on the last rank", rank_ == size_ - 1 ? nx + 1 : nx, ny, good, 0,
                            "disagree on the global grid");
    }
    /* Not MPI_COMM_NULL. */
    dpsm_grid *g = NULL;
    int status = dpsm_create_2d_mpi(MPI_COMM_NULL, nx, ny, good.i0, good.j0, good.ni, good.nj, 1.0, 1.0, &g);
    require(status != DPSM_OK && strstr(dpsm_last_error(NULL), "MPI_COMM_NULL") != NULL,
            "MPI_COMM_NULL: status %d, message %s", status, dpsm_last_error(NULL));
}

/* Ranks that step different dt or with different parameters fail alike, and
 * the grid is unchanged: a step with agreeing ranks then matches serial. */
static void disagreeing_ranks(void) {
    if (size_ < 2) return;
    const int64_t nx = 60, ny = 50;
    block_t b = block_of(GRID_2D, rank_, size_, nx, ny);
    dpsm_grid *g = NULL;
    OK(NULL, dpsm_create_2d_mpi(MPI_COMM_WORLD, nx, ny, b.i0, b.j0, b.ni, b.nj, 1.0, 1.0, &g));
    if (!g) return;
    double *h = calloc((size_t)(b.ni * b.nj), sizeof(double));
    for (int64_t c = 0; c < b.ni * b.nj; ++c) h[c] = (double)((c * 37) % 17);
    OK(g, dpsm_set_heights(g, h));
    int status = dpsm_step(g, rank_ == 1 ? 2.0 : 1.0);
    require(status == DPSM_ERR_INVALID_VALUE && strstr(dpsm_last_error(g), "differ in dt") != NULL,
            "different dt: status %s, message \"%s\"", dpsm_status_string(status), dpsm_last_error(g));
    OK(g, dpsm_set_repose_angle(g, rank_ == 0 ? 0.5 : 0.6));
    status = dpsm_step(g, 1.0);
    require(status == DPSM_ERR_INVALID_VALUE && strstr(dpsm_last_error(g), "repose angle") != NULL,
            "different repose angles: status %s, message \"%s\"", dpsm_status_string(status), dpsm_last_error(g));
    if (rank_ == 0) printf("  refused on every rank: %s\n", dpsm_last_error(g));
    double *after = calloc((size_t)(b.ni * b.nj), sizeof(double));
    OK(g, dpsm_get_heights(g, after));
    require(memcmp(h, after, (size_t)(b.ni * b.nj) * sizeof(double)) == 0, "a refused step changed the heights");
    OK(g, dpsm_set_repose_angle(g, 0.6));
    OK(g, dpsm_step(g, 1.0));
    free(h);
    free(after);
    dpsm_destroy(g);
}

/* A rank whose own arguments are refused does not leave the others waiting
 * in a collective call: a dt that is NaN on one rank only, or a NULL pointer
 * or an unknown quantity given to dpsm_get_mass on one rank only, fails on
 * every rank, the refusing one with its own reason. Nothing changes, and the
 * stable sub-step (set by the smallest angle of all blocks) stays the same on
 * every rank after a refused step. */
static void refusing_rank(void) {
    if (size_ < 2) return;
    const int64_t nx = 60, ny = 50;
    block_t b = block_of(GRID_2D, rank_, size_, nx, ny);
    dpsm_grid *g = NULL;
    OK(NULL, dpsm_create_2d_mpi(MPI_COMM_WORLD, nx, ny, b.i0, b.j0, b.ni, b.nj, 1.0, 1.0, &g));
    if (!g) return;
    const size_t cells = (size_t)(b.ni * b.nj);
    double *h = calloc(cells, sizeof(double)), *theta = calloc(cells, sizeof(double)),
           *after = calloc(cells, sizeof(double));
    for (size_t c = 0; c < cells; ++c) {
        h[c] = (double)((c * 37) % 17);
        theta[c] = rank_ == 0 ? 0.5 : 0.6; /* each block's own smallest angle differs */
    }
    OK(g, dpsm_set_heights(g, h));
    OK(g, dpsm_set_repose_angle_field(g, theta));
    OK(g, dpsm_step(g, 1.0));
    OK(g, dpsm_get_heights(g, h));
    double sdt = 0.0, sdt_after = 0.0, mass = 0.0, mass_after = 0.0;
    OK(g, dpsm_stable_dt(g, &sdt));
    OK(g, dpsm_get_mass(g, DPSM_MASS_TOTAL, &mass));
    require(same_on_every_rank(sdt), "stable_dt differs between ranks after a step");

    int status = dpsm_step(g, rank_ == 1 ? NAN : 1.0);
    const char *want = rank_ == 1 ? "not finite" : "another rank";
    require(status == DPSM_ERR_INVALID_VALUE && strstr(dpsm_last_error(g), want) != NULL,
            "NaN dt on rank 1 only: status %s, message \"%s\"", dpsm_status_string(status), dpsm_last_error(g));
    if (rank_ == 0) printf("  a rank's dt refused, on every rank: %s\n", dpsm_last_error(g));
    status = dpsm_step(g, rank_ == 1 ? 2.0 : 1.0);
    require(status == DPSM_ERR_INVALID_VALUE, "different dt: status %s", dpsm_status_string(status));
    /* The fast relaxation to rest is not for distributed grids: on one rank it fails the step on all. */
    if (rank_ == 1) OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TO_REST));
    status = dpsm_step(g, 1.0);
    require(rank_ == 1 ? status == DPSM_ERR_NOT_APPLICABLE && strstr(dpsm_last_error(g), "distributed grids") != NULL
                       : status == DPSM_ERR_INVALID_VALUE && strstr(dpsm_last_error(g), "another rank") != NULL,
            "DPSM_RELAX_TO_REST on rank 1 only: status %s, message \"%s\"", dpsm_status_string(status),
            dpsm_last_error(g));
    if (rank_ == 1) OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE));
    /* A source on rank 1 that would carry a height beyond the supported range: refused on every rank. */
    double *q = calloc(cells, sizeof(double));
    if (rank_ == 1) q[0] = 1e49;
    OK(g, dpsm_set_source(g, q));
    status = dpsm_step(g, 1e3);
    want = rank_ == 1 ? "supported range" : "another rank";
    require(status == DPSM_ERR_INVALID_VALUE && strstr(dpsm_last_error(g), want) != NULL,
            "a source beyond the range on rank 1 only: status %s, message \"%s\"", dpsm_status_string(status),
            dpsm_last_error(g));
    if (rank_ == 0) printf("  a rank's source beyond the range refused, on every rank: %s\n", dpsm_last_error(g));
    OK(g, dpsm_set_source(g, NULL));
    free(q);
    OK(g, dpsm_get_heights(g, after));
    require(memcmp(h, after, cells * sizeof(double)) == 0, "a refused step changed the heights");
    OK(g, dpsm_stable_dt(g, &sdt_after));
    require(sdt_after == sdt && same_on_every_rank(sdt_after),
            "stable_dt after refused steps: %.17g, before %.17g (or it differs between ranks)", sdt_after, sdt);

    double *out = rank_ == 0 ? NULL : &mass_after;
    status = dpsm_get_mass(g, DPSM_MASS_TOTAL, out);
    require(rank_ == 0 ? status == DPSM_ERR_NULL_POINTER
                       : status == DPSM_ERR_INVALID_VALUE && strstr(dpsm_last_error(g), "another rank") != NULL,
            "NULL value on rank 0 only: status %s, message \"%s\"", dpsm_status_string(status), dpsm_last_error(g));
    status = dpsm_get_mass(g, rank_ == 1 ? 99 : DPSM_MASS_TOTAL, &mass_after);
    require(rank_ == 1 ? status == DPSM_ERR_UNKNOWN_ENUM : status == DPSM_ERR_INVALID_VALUE,
            "unknown quantity on rank 1 only: status %s, message \"%s\"", dpsm_status_string(status),
            dpsm_last_error(g));
    if (rank_ == 0) printf("  a rank's dpsm_get_mass refused, on every rank: %s\n", dpsm_last_error(g));
    OK(g, dpsm_get_mass(g, DPSM_MASS_TOTAL, &mass_after));
    require(mass_after == mass, "the global mass after refused calls: %.17g, before %.17g", mass_after, mass);
    OK(g, dpsm_step(g, 1.0)); /* all agree again */
    free(h);
    free(theta);
    free(after);
    dpsm_destroy(g);
}

/* The physics setters work, but every rank must use the same features: a
 * bed on some ranks only is refused by the next step, on every rank. */
static void physics_agreement(void) {
    const int64_t nx = 40, ny = 30;
    block_t b = block_of(GRID_2D, rank_, size_, nx, ny);
    dpsm_grid *g = NULL;
    OK(NULL, dpsm_create_2d_mpi(MPI_COMM_WORLD, nx, ny, b.i0, b.j0, b.ni, b.nj, 1.0, 1.0, &g));
    if (!g) return;
    if (size_ > 1) {
        double *zeros_here = calloc((size_t)(b.ni * b.nj), sizeof(double));
        if (rank_ == 0) OK(g, dpsm_set_bedrock(g, zeros_here));
        const int status = dpsm_step(g, 1.0);
        require(status == DPSM_ERR_INVALID_VALUE && strstr(dpsm_last_error(g), "bed") != NULL,
                "a bed on rank 0 only: status %s, message \"%s\"", dpsm_status_string(status), dpsm_last_error(g));
        if (rank_ != 0) OK(g, dpsm_set_bedrock(g, zeros_here));
        OK(g, dpsm_step(g, 1.0)); /* agreed now */
        free(zeros_here);
    }
    dpsm_destroy(g);
}

/* A block takes one thread unless OMP_NUM_THREADS or dpsm_set_threads says
 * otherwise (an MPI host runs a rank per core); a serial grid keeps OpenMP's
 * default. */
static void thread_defaults(void) {
    const int64_t nx = 40, ny = 30;
    block_t b = block_of(GRID_2D, rank_, size_, nx, ny);
    dpsm_grid *g = NULL, *serial = NULL;
    OK(NULL, dpsm_create_2d_mpi(MPI_COMM_WORLD, nx, ny, b.i0, b.j0, b.ni, b.nj, 1.0, 1.0, &g));
    OK(NULL, dpsm_create_2d(nx, ny, 1.0, 1.0, &serial));
    if (!g || !serial) return;
    const char *env = getenv("OMP_NUM_THREADS");
    char saved[64] = "";
    if (env) snprintf(saved, sizeof saved, "%s", env);
    int n = 0;
    unsetenv("OMP_NUM_THREADS");
    OK(g, dpsm_get_threads(g, &n));
    require(n == 1, "a block without OMP_NUM_THREADS takes %d threads, not 1", n);
    OK(serial, dpsm_get_threads(serial, &n));
    require(n >= 1, "a serial grid takes %d threads", n);
    setenv("OMP_NUM_THREADS", "3", 1);
    OK(g, dpsm_get_threads(g, &n));
    require(n >= 1, "a block with OMP_NUM_THREADS takes %d threads (OpenMP's count)", n);
    unsetenv("OMP_NUM_THREADS");
    OK(g, dpsm_set_threads(g, 2));
    OK(g, dpsm_get_threads(g, &n));
    require(n == 2, "a block asked for 2 threads takes %d", n);
    OK(g, dpsm_step(g, 1.0));
    if (env) setenv("OMP_NUM_THREADS", saved, 1);
    dpsm_destroy(g);
    dpsm_destroy(serial);
}

/* ---- restart files ------------------------------------------------------- */

/* This rank's file of save `name` (the rank count in the name: the runs on 1,
 * 2 and 4 ranks may share the directory at the same time). */
static void restart_path(char *out, size_t n, const char *name, int rank) {
    snprintf(out, n, "dpsm_mpi_%s.%dof%d.dpsm", name, rank, size_);
}

/* Every rank must fail with a status in `statuses` (or any non-zero status when
 * that is 0), *out NULL, and a message containing `needle`. */
static void expect_load_fails(MPI_Comm comm, const char *path, int null_out, int status_wanted, const char *needle,
                              const char *what) {
    dpsm_grid *g = (dpsm_grid *)&g; /* not NULL: the call must set it to NULL */
    const int status = dpsm_load_mpi(comm, path, null_out ? NULL : &g);
    const char *msg = dpsm_last_error(NULL);
    require(status != DPSM_OK && (status_wanted == 0 || status == status_wanted),
            "%s: dpsm_load_mpi returned %s (wanted %s): %s", what, dpsm_status_string(status),
            status_wanted ? dpsm_status_string(status_wanted) : "a failure", msg);
    require(strstr(msg, needle) != NULL, "%s: the message \"%s\" does not name the problem (\"%s\")", what, msg, needle);
    if (!null_out) require(g == NULL, "%s: *out is not NULL after a failure", what);
    if (rank_ == 0 && status != DPSM_OK) printf("    %s: %s\n", what, msg);
}

/* Two grids of block b record the same fluxes on its faces, bit for bit (or
 * neither records them). */
static void compare_block_faces(const dpsm_grid *a, const dpsm_grid *b, block_t blk, const char *what) {
    const size_t nfx = (size_t)((blk.ni + 1) * blk.nj), nfy = (size_t)(blk.ni * (blk.nj + 1));
    double *xa = malloc(nfx * sizeof(double)), *xb = malloc(nfx * sizeof(double));
    double *ya = malloc(nfy * sizeof(double)), *yb = malloc(nfy * sizeof(double));
    const int sa = dpsm_get_face_fluxes(a, xa, ya), sb = dpsm_get_face_fluxes(b, xb, yb);
    require(sa == sb, "%s: face fluxes %s saved, %s loaded", what, dpsm_status_string(sa), dpsm_status_string(sb));
    if (sa == DPSM_OK)
        require(memcmp(xa, xb, nfx * sizeof(double)) == 0 && memcmp(ya, yb, nfy * sizeof(double)) == 0,
                "%s: the face fluxes differ between the saved grid and the loaded one", what);
    free(xa);
    free(xb);
    free(ya);
    free(yb);
}

/* Compares two distributed grids: heights bit for bit, every mass figure,
 * what left through each side and the step information exactly, the face
 * fluxes after a step; the cells a step computed (its cost, not the state)
 * only when `with_cost`: a loaded grid visits every tile once. */
static void compare_grids(const dpsm_grid *a, const dpsm_grid *b, block_t blk, int with_cost, const char *what) {
    const size_t cells = (size_t)(blk.ni * blk.nj);
    double *ha = malloc(cells * sizeof(double)), *hb = malloc(cells * sizeof(double));
    OK(a, dpsm_get_heights(a, ha));
    OK(b, dpsm_get_heights(b, hb));
    size_t differ = 0;
    for (size_t c = 0; c < cells; ++c) differ += memcmp(&ha[c], &hb[c], sizeof(double)) != 0;
    require(differ == 0, "%s: %zu of %zu cells differ between the saved grid and the loaded one", what, differ, cells);
    const int q[] = {DPSM_MASS_TOTAL, DPSM_MASS_SOURCED, DPSM_MASS_EXTERNAL, DPSM_MASS_OUTFLOW, DPSM_MASS_UNMET};
    for (int k = 0; k < 5; ++k) {
        double ma = -1, mb = -2;
        OK(a, dpsm_get_mass(a, q[k], &ma));
        OK(b, dpsm_get_mass(b, q[k], &mb));
        require(memcmp(&ma, &mb, sizeof ma) == 0, "%s: mass quantity %d is %.17g saved, %.17g loaded", what, q[k], ma, mb);
    }
    for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side) {
        double sa = -1, sb = -2;
        OK(a, dpsm_get_side_outflow(a, side, &sa));
        OK(b, dpsm_get_side_outflow(b, side, &sb));
        require(memcmp(&sa, &sb, sizeof sa) == 0, "%s: side %d took %.17g saved, %.17g loaded", what, side, sa, sb);
    }
    /* The fluxes are not saved: after a step they are the same again. */
    if (!with_cost) compare_block_faces(a, b, blk, what);
    const int items[] = {DPSM_INFO_SUBSTEPS, DPSM_INFO_TIME_INTEGRATED, DPSM_INFO_AT_REST, DPSM_INFO_MAX_EXCESS_SLOPE,
                         DPSM_INFO_CELL_UPDATES};
    for (int k = 0; k < (with_cost ? 5 : 4); ++k) {
        double ia = -1, ib = -2;
        OK(a, dpsm_get_step_info(a, items[k], &ia));
        OK(b, dpsm_get_step_info(b, items[k], &ib));
        require(ia == ib, "%s: step info %d is %.17g saved, %.17g loaded", what, items[k], ia, ib);
    }
    free(ha);
    free(hb);
}

/* Runs scene s on decomposition `kind` for 3 steps, saves it (this rank's
 * file: `path`), loads it and requires the loaded grid to continue bit for
 * bit for 4 more steps with the host's changes. Returns the saved grid (NULL
 * if it could not be made) and its dt. */
static dpsm_grid *saved_and_continued(const scene_t *s, int kind, const char *name, char *path, size_t path_size,
                                      double *dt) {
    char what[200];
    snprintf(what, sizeof what, "restart of %s, %s", s->name, decomposition_names[kind]);
    block_t b = block_of(kind, rank_, size_, s->nx, s->ny);
    const long failures_before = failures_;
    dpsm_grid *g = NULL, *loaded = NULL;
    OK(NULL, dpsm_create_2d_mpi(MPI_COMM_WORLD, s->nx, s->ny, b.i0, b.j0, b.ni, b.nj, s->dx, s->dy, &g));
    if (!g) return NULL;
    set_scene(g, s, b);
    double stable = 0;
    OK(g, dpsm_stable_dt(g, &stable));
    *dt = s->dt_in_stable_steps * stable;
    for (int step = 0; step < 3; ++step) OK(g, dpsm_step(g, *dt));
    restart_path(path, path_size, name, rank_);
    OK(g, dpsm_save(g, path));
    OK(NULL, dpsm_load_mpi(MPI_COMM_WORLD, path, &loaded));
    if (!loaded) return g;
    compare_grids(g, loaded, b, 1, what);
    for (int step = 3; step < 7; ++step) {
        host_changes(g, s, b, step);
        host_changes(loaded, s, b, step);
        OK(g, dpsm_step(g, *dt));
        OK(loaded, dpsm_step(loaded, *dt));
        char at[260];
        snprintf(at, sizeof at, "%s, step %d after the load", what, step);
        compare_grids(g, loaded, b, 0, at);
    }
    double substeps = 0;
    OK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &substeps));
    require(substeps > 0, "%s: the scene was at rest after the load: it tests nothing", what);
    long mine = failures_ - failures_before, total = 0;
    MPI_Allreduce(&mine, &total, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
    if (rank_ == 0) printf("  %s: %s\n", what, total == 0 ? "continues bit for bit for 4 steps" : "FAILED");
    dpsm_destroy(loaded);
    return g;
}

/* dpsm_save on a distributed grid writes one file per rank, dpsm_load_mpi
 * reads them back, and the loaded grid continues bit for bit: heights, all
 * five mass figures, what left through each side, the face fluxes and the
 * step information, for several steps with the host's changes (new side
 * levels among them), on every decomposition. Then every wrong set of files
 * is refused on every rank, and a save that fails on one rank fails on all. */
static void restart_files(void) {
    scene_t s = physics(); /* bed, erosion, angle field, exponent 1.5, hysteresis, a source */
    s.bump_before_step = 4;
    s.bump = (block_t){40, 30, 30, 30};
    scene_t levels = side_levels(); /* new levels before step 3: after the load */
    char path[256], other[256];
    double dt = 0.0;
    for (int kind = 0; kind < N_DECOMPOSITIONS; ++kind) {
        dpsm_destroy(saved_and_continued(&levels, kind, "levels", path, sizeof path, &dt));
        dpsm_grid *g = saved_and_continued(&s, kind, "restart", path, sizeof path, &dt);
        if (!g) continue;
        if (kind != GRID_2D) {
            dpsm_destroy(g);
            continue;
        }
        /* A block file is not a grid of its own. */
        dpsm_grid *serial = (dpsm_grid *)&serial;
        int status = dpsm_load(path, &serial);
        require(status == DPSM_ERR_NOT_APPLICABLE && serial == NULL && strstr(dpsm_last_error(NULL), "dpsm_load_mpi"),
                "dpsm_load of a block file: %s: %s", dpsm_status_string(status), dpsm_last_error(NULL));
        if (rank_ == 0) printf("    dpsm_load of a block file: %s\n", dpsm_last_error(NULL));
        /* Not a block file. */
        dpsm_grid *own = NULL;
        restart_path(other, sizeof other, "serial", rank_);
        OK(NULL, dpsm_create_2d(8, 8, 1.0, 1.0, &own));
        OK(own, dpsm_save(own, other));
        dpsm_destroy(own);
        expect_load_fails(MPI_COMM_WORLD, other, 0, DPSM_ERR_NOT_APPLICABLE, "grid of its own", "a serial file");
        /* One rank's file missing: that rank says why, the others name it. */
        restart_path(other, sizeof other, "missing", rank_);
        if (size_ > 1) {
            expect_load_fails(MPI_COMM_WORLD, rank_ == 1 ? other : path, 0, DPSM_ERR_IO,
                              rank_ == 1 ? "cannot open" : "rank 1 could not load", "rank 1's file missing");
            /* A NULL path or out on one rank. */
            expect_load_fails(MPI_COMM_WORLD, rank_ == 0 ? NULL : path, 0, DPSM_ERR_NULL_POINTER,
                              rank_ == 0 ? "path is NULL" : "rank 0 could not load", "a NULL path on rank 0");
            expect_load_fails(MPI_COMM_WORLD, path, rank_ == size_ - 1, DPSM_ERR_NULL_POINTER,
                              rank_ == size_ - 1 ? "out is NULL" : "could not load", "a NULL out on the last rank");
            /* Each rank given the next rank's file. */
            restart_path(other, sizeof other, "restart", (rank_ + 1) % size_);
            expect_load_fails(MPI_COMM_WORLD, other, 0, DPSM_ERR_INVALID_VALUE, "holds the block of rank",
                              "files shifted by one rank");
            /* One byte changed in rank 1's file. */
            restart_path(other, sizeof other, "corrupt", rank_);
            if (rank_ == 1) {
                FILE *in = fopen(path, "rb"), *out = fopen(other, "wb");
                int c, at = 0;
                while (in && out && (c = fgetc(in)) != EOF) fputc(at++ == 500 ? c ^ 0x10 : c, out);
                if (in) fclose(in);
                if (out) fclose(out);
            }
            expect_load_fails(MPI_COMM_WORLD, rank_ == 1 ? other : path, 0, DPSM_ERR_BAD_FILE,
                              rank_ == 1 ? "checksum mismatch" : "rank 1 could not load", "a byte changed in rank 1's file");
            /* Files of two saves mixed: rank 0 keeps the first save's file. */
            OK(g, dpsm_step(g, dt));
            restart_path(other, sizeof other, "second", rank_);
            OK(g, dpsm_save(g, other));
            expect_load_fails(MPI_COMM_WORLD, rank_ == 0 ? path : other, 0, DPSM_ERR_BAD_FILE, "not the blocks of one save",
                              "files of two saves");
            /* Loaded on fewer ranks than saved. */
            MPI_Comm half;
            MPI_Comm_split(MPI_COMM_WORLD, rank_ < size_ / 2, rank_, &half);
            if (rank_ < size_ / 2)
                expect_load_fails(half, path, 0, DPSM_ERR_INVALID_SIZE, "saved on", "half the ranks");
            MPI_Comm_free(&half);
            /* A save that fails on one rank fails on every rank. */
            restart_path(other, sizeof other, "no_such_directory/x", rank_);
            const char *target = rank_ == 1 ? other : path;
            status = dpsm_save(g, target);
            require(status == DPSM_ERR_IO &&
                        strstr(dpsm_last_error(g), rank_ == 1 ? "cannot write" : "rank 1 of the distributed grid"),
                    "a save failing on rank 1: %s: %s", dpsm_status_string(status), dpsm_last_error(g));
            if (rank_ == 0) printf("    a save failing on rank 1: %s\n", dpsm_last_error(g));
            /* Every rank given the same path: they write over each other. */
            restart_path(other, sizeof other, "shared", 0);
            status = dpsm_save(g, other);
            require(status == DPSM_ERR_IO, "one path for every rank: %s: %s", dpsm_status_string(status),
                    dpsm_last_error(g));
            /* Which rank finds it depends on the order of the writes: the one
             * whose file another rank replaced, or whose rename found the
             * temporary file gone; the others name that rank. */
            const char *msg = dpsm_last_error(g);
            require(strstr(msg, "same file") || strstr(msg, "cannot") || strstr(msg, "of the distributed grid could not"),
                    "one path for every rank: the message names neither the problem nor a rank: %s", msg);
            if (rank_ == 0) printf("    one path for every rank: %s\n", msg);
            MPI_Barrier(MPI_COMM_WORLD);
            if (rank_ == 0) remove(other);
            status = dpsm_save(g, rank_ == 0 ? NULL : path);
            require(status == DPSM_ERR_NULL_POINTER && strstr(dpsm_last_error(g), rank_ == 0 ? "path is NULL" : "rank 0"),
                    "a NULL path on rank 0: %s: %s", dpsm_status_string(status), dpsm_last_error(g));
            /* The grid still steps after the failed saves (no rank was left behind). */
            OK(g, dpsm_step(g, dt));
        }
        dpsm_destroy(g);
        restart_path(other, sizeof other, "serial", rank_);
        remove(other);
        restart_path(other, sizeof other, "second", rank_);
        remove(other);
        restart_path(other, sizeof other, "corrupt", rank_);
        remove(other);
    }
    restart_path(path, sizeof path, "restart", rank_);
    remove(path);
    restart_path(path, sizeof path, "levels", rank_);
    remove(path);
    free_scene(&s);
    free_scene(&levels);
}

int main(int argc, char **argv) {
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    if (rank_ == 0) printf("test_mpi on %d ranks\n", size_);

    scene_t (*scenes[])(void) = {collapse_open, source_walls, obstacles, spike_near_edge, physics, side_levels};
    for (size_t k = 0; k < sizeof scenes / sizeof scenes[0]; ++k) {
        scene_t s = scenes[k]();
        for (int kind = 0; kind < N_DECOMPOSITIONS; ++kind) {
            long before = failures_;
            run_scene(&s, kind);
            long total = 0, mine = failures_ - before;
            MPI_Allreduce(&mine, &total, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
            if (rank_ == 0)
                printf("  %s: %s: %s\n", s.name, decomposition_names[kind],
                       total == 0 ? "heights bit for bit, mass to 1e-12" : "FAILED");
        }
        free_scene(&s);
    }
    bad_decompositions();
    disagreeing_ranks();
    refusing_rank();
    physics_agreement();
    thread_defaults();
    restart_files();

    long total = 0, all_checks = 0;
    MPI_Allreduce(&failures_, &total, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
    MPI_Allreduce(&checks_, &all_checks, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
    if (rank_ == 0) printf("%ld checks on %d ranks, %ld failed\n", all_checks, size_, total);
    MPI_Finalize();
    return total == 0 ? 0 : 1;
}
