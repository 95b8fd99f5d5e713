/* A fuzzer of the MPI constructors of dpsm_mpi.h (libFuzzer's entry point,
 * LLVMFuzzerTestOneInput), on one rank: MPI_COMM_SELF, or MPI_COMM_WORLD of a
 * singleton (a program started without mpiexec). fuzz_api.c covers the rest
 * of the C API; this harness links libdpsm_mpi.
 *
 * The input is a program of up to kMaxOperations operations, each one byte of
 * opcode (its value modulo 4) followed by its arguments:
 *
 *   0  a 2D block:  how, defect, nx, ny, dx, dy, then a scene (below)
 *   1  a graph:     how, defect, mesh (nx, ny, lattice, seed 2 bytes), then a scene
 *   2  polygons:    as the graph
 *   3  a load that must fail (or, once in eight, succeed): how, which, where
 *
 * `how`: bit 0 picks the `_f` variant (MPI_Comm_c2f, indices and global ids
 * from 1), bit 1 MPI_COMM_WORLD instead of MPI_COMM_SELF. `defect`: below
 * 0xc0 none; else (defect & 0x3f) picks one defect of that constructor's table
 * below (NULL out or arrays, MPI_COMM_NULL, counts of 0 or less, global ids
 * below the base, repeated, beyond the count, owners out of range, faces
 * naming cells out of range, polygons with bad node indices, blocks off the
 * grid or not covering it, bad spacings), whose status is the one expected.
 *
 * Every call must keep the contract:
 *   - a refused call returns the expected status, leaves *out NULL and a
 *     message in dpsm_last_error(NULL) that names the function;
 *   - a grid made has the expected shape; it gets heights (and maybe a source
 *     and an open edge), and then steps, each checked against a serial twin
 *     (dpsm_create_2d, dpsm_create_graph or dpsm_create_mesh over the same
 *     local arrays, from 0) that gets the same calls: the same status, heights
 *     bit for bit (dpsm_mpi.h: a distributed grid equals the serial one), all
 *     finite, a ledger that closes to 1e-12 of the largest mass figure, the
 *     same total mass to 1e-12;
 *   - saved with dpsm_save and loaded with dpsm_load_mpi (or _f) it reads back
 *     bit for bit and, after one more step of both, still matches; dpsm_load
 *     refuses the file of a block with DPSM_ERR_NOT_APPLICABLE.
 * Each input spends at most kWorkBudget cell sub-steps.
 * A violated check prints what it saw and calls abort(), which libFuzzer (or
 * the replay driver, fuzz_replay.c) reports with the input. DPSM_FUZZ_TRACE=1
 * prints one line per call. */
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <mpi.h>

#include <dpsm/dpsm.h>
#include <dpsm/dpsm_mpi.h>

#define FUZZ_NAME "dpsm fuzz_mpi"
#include "fuzz_support.h"

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

enum { kMaxOperations = 16 };
static const double kWorkBudget = 2e6; /* cell sub-steps per input */

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

static double g_work; /* cell sub-steps spent on this input */

static void *copy_of(const void *src, size_t bytes) {
    void *p = xcalloc(bytes, 1);
    memcpy(p, src, bytes);
    return p;
}

/* The restart files of this process, removed after each input. */
static const char *temp_path(int which) {
    static char paths[2][512];
    if (!paths[which][0]) {
        const char *dir = getenv("TMPDIR");
        snprintf(paths[which], sizeof paths[which], "%s/dpsm-fuzz-mpi-%ld-%d.dpsm", dir && *dir ? dir : "/tmp",
                 (long)getpid(), which);
    }
    return paths[which];
}

/* ------------------------------------------------------------------------ */
/* MPI                                                                       */
/* ------------------------------------------------------------------------ */

static void finalize_mpi(void) {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized) MPI_Finalize();
}

static void ensure_mpi(void) {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (initialized) return;
    if (MPI_Init(NULL, NULL) != MPI_SUCCESS) die("MPI_Init failed");
    int size = 0;
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    if (size != 1) die("run this harness on one rank (MPI_COMM_WORLD has %d)", size);
    atexit(finalize_mpi);
}

int LLVMFuzzerInitialize(int *argc, char ***argv) {
    (void)argc;
    (void)argv;
    ensure_mpi();
    return 0;
}

/* A communicator and the variant that takes it: `how` bit 0 the _f variant,
 * bit 1 MPI_COMM_WORLD; `null_comm` MPI_COMM_NULL (a defect). */
typedef struct {
    int fortran;
    MPI_Comm comm;
} caller_t;

static caller_t caller_of(unsigned how, int null_comm) {
    caller_t c = {(int)(how & 1u), (how & 2u) ? MPI_COMM_WORLD : MPI_COMM_SELF};
    if (null_comm) c.comm = MPI_COMM_NULL;
    return c;
}

/* ------------------------------------------------------------------------ */
/* The contract of a call                                                    */
/* ------------------------------------------------------------------------ */

static void check_refused(int st, int want, dpsm_grid *made, const char *fn, const char *what) {
    trace("%s (%s) -> %s", fn, what, dpsm_status_string(st));
    if (st != want)
        die("%s with %s returned %s, expected %s (%s)", fn, what, dpsm_status_string(st), dpsm_status_string(want),
            dpsm_last_error(NULL));
    if (st == DPSM_OK) {
        if (!made) die("%s succeeded but left *out NULL", fn);
        if (*dpsm_last_error(NULL)) die("%s succeeded but left the message \"%s\"", fn, dpsm_last_error(NULL));
        return;
    }
    if (made) die("%s failed (%s) but did not set *out to NULL", fn, what);
    const char *msg = dpsm_last_error(NULL);
    if (!msg || !*msg) die("%s failed with %s (%s) and no message", fn, dpsm_status_string(st), what);
    if (!strstr(msg, fn)) die("%s failed with the message \"%s\", which does not name it", fn, msg);
}

/* What a scene needs to know of a grid made: its cells and their areas. */
typedef struct {
    dpsm_grid *g, *serial;
    caller_t caller;
    int64_t n, nx, ny; /* local cells; the shape dpsm_get_shape must give */
    double *area;
    int edge; /* a side to open: DPSM_XMIN.. on a block, DPSM_MESH_EDGE on a mesh */
    const int64_t *serial_of; /* the twin's cell of each local cell (a mesh's global id); NULL: the same */
} made_t;

/* Per-cell values to the serial twin, and its heights back, through serial_of. */
static int set_on_serial(const made_t *m, int (*set)(dpsm_grid *, const double *), const double *local) {
    if (!m->serial_of) return set(m->serial, local);
    double *v = xcalloc((size_t)m->n, sizeof(double));
    for (int64_t c = 0; c < m->n; ++c) v[m->serial_of[c]] = local[c];
    const int st = set(m->serial, v);
    free(v);
    return st;
}

static void read_serial_heights(const made_t *m, double *local) {
    double *v = xcalloc((size_t)m->n, sizeof(double));
    if (dpsm_get_heights(m->serial, v) != DPSM_OK) die("dpsm_get_heights on the serial twin failed");
    for (int64_t c = 0; c < m->n; ++c) local[c] = v[m->serial_of ? m->serial_of[c] : c];
    free(v);
}

static const double kHeights[] = {0.0, 1.0, -1.0, 0.25, 3.0, 10.0, 100.0, 1e3, 1e-9, -3.0, 7.0, 30.0, -0.0, 0.5};
static const double kSources[] = {0.0, 1e-3, -1e-3, 0.1, -0.1, 1.0, 1e-9, 0.0};
static const double kDtFactors[] = {1e-6, 0.1, 0.5, 1.0, 2.0, 4.0, 10.0, 50.0, 0.999, 3.7};
enum { kMaxSubsteps = 2000 };

static void read_heights(const dpsm_grid *g, double *h, const char *whose) {
    if (dpsm_get_heights(g, h) != DPSM_OK) die("dpsm_get_heights on %s failed: %s", whose, dpsm_last_error(g));
}

static void same_heights(const double *a, const double *b, int64_t n, const char *what) {
    for (int64_t c = 0; c < n; ++c)
        if (memcmp(&a[c], &b[c], sizeof(double)) != 0)
            die("%s: height %lld differs: %.17g vs %.17g", what, (long long)c, a[c], b[c]);
}

static void check_state(const made_t *m, const double *h) {
    double mass[4], gross = 0.0;
    for (int64_t c = 0; c < m->n; ++c) {
        if (!isfinite(h[c])) die("height %lld is %g", (long long)c, h[c]);
        gross += fabs(h[c]) * m->area[c];
    }
    for (int q = 0; q < 4; ++q) {
        if (dpsm_get_mass(m->g, q, &mass[q]) != DPSM_OK) die("dpsm_get_mass failed: %s", dpsm_last_error(m->g));
        if (!isfinite(mass[q])) die("mass figure %d is %g", q, mass[q]);
    }
    double scale = fmax(gross, 1e-300);
    for (int q = 0; q < 4; ++q) scale = fmax(scale, fabs(mass[q]));
    const double residual = fabs(mass[0] - (mass[1] + mass[2] - mass[3]));
    if (residual > 1e-12 * scale)
        die("the ledger does not close: total %.17g, sourced %.17g, external %.17g, outflow %.17g: residual %.3g",
            mass[0], mass[1], mass[2], mass[3], residual);
    double serial_total = 0.0;
    if (dpsm_get_mass(m->serial, DPSM_MASS_TOTAL, &serial_total) != DPSM_OK) die("dpsm_get_mass on the twin failed");
    if (fabs(serial_total - mass[0]) > 1e-12 * scale)
        die("the total mass is %.17g, the serial twin's %.17g", mass[0], serial_total);
}

/* One step of the grid and its serial twin, `dt` on both: the same status,
 * and on success the same heights. */
static void step_both(made_t *m, double dt, double *h, double *hs) {
    g_op = "dpsm_step";
    read_heights(m->g, hs, "the grid");
    const int st = dpsm_step(m->g, dt), sst = dpsm_step(m->serial, dt);
    trace("dpsm_step(%.17g) -> %s (serial: %s)", dt, dpsm_status_string(st), dpsm_status_string(sst));
    if (st != sst)
        die("dpsm_step returned %s, the serial twin %s (%s | %s)", dpsm_status_string(st), dpsm_status_string(sst),
            dpsm_last_error(m->g), dpsm_last_error(m->serial));
    read_heights(m->g, h, "the grid");
    if (st != DPSM_OK) {
        if (st != DPSM_ERR_WORK_LIMIT) die("dpsm_step returned %s: %s", dpsm_status_string(st), dpsm_last_error(m->g));
        if (!strstr(dpsm_last_error(m->g), "dpsm_step")) die("dpsm_step failed with \"%s\"", dpsm_last_error(m->g));
        same_heights(hs, h, m->n, "a refused step changed the heights");
        g_work += (double)m->n;
        return;
    }
    if (*dpsm_last_error(m->g)) die("dpsm_step succeeded but left the message \"%s\"", dpsm_last_error(m->g));
    double substeps = 0.0, serial_substeps = 0.0;
    dpsm_get_step_info(m->g, DPSM_INFO_SUBSTEPS, &substeps);
    dpsm_get_step_info(m->serial, DPSM_INFO_SUBSTEPS, &serial_substeps);
    if (substeps != serial_substeps) die("%g sub-steps, the serial twin %g", substeps, serial_substeps);
    g_work += (double)m->n * (substeps + 1.0);
    read_serial_heights(m, hs);
    same_heights(h, hs, m->n, "the grid and its serial twin after a step");
    check_state(m, h);
}

/* The grid through dpsm_save and dpsm_load_mpi: the same heights, and after
 * one more step of both, still the same. */
static void check_restart(made_t *m, double dt, double *h, double *hs) {
    const char *path = temp_path(0);
    const char *fn = m->caller.fortran ? "dpsm_load_mpi_f" : "dpsm_load_mpi";
    g_op = "dpsm_save";
    if (dpsm_save(m->g, path) != DPSM_OK) die("dpsm_save(%s) failed: %s", path, dpsm_last_error(m->g));
    g_op = fn;
    dpsm_grid *copy = (dpsm_grid *)&copy; /* not NULL: the call must set it */
    const int st = m->caller.fortran ? dpsm_load_mpi_f(MPI_Comm_c2f(m->caller.comm), path, &copy)
                                     : dpsm_load_mpi(m->caller.comm, path, &copy);
    check_refused(st, DPSM_OK, copy, fn, "the file just saved");
    int64_t sx = 0, sy = 0;
    if (dpsm_get_shape(copy, &sx, &sy) != DPSM_OK || sx != m->nx || sy != m->ny)
        die("the loaded grid's shape is %lld x %lld, not %lld x %lld", (long long)sx, (long long)sy,
            (long long)m->nx, (long long)m->ny);
    read_heights(m->g, h, "the grid");
    read_heights(copy, hs, "the loaded grid");
    same_heights(h, hs, m->n, "the grid and the one loaded from its restart file");
    g_op = "dpsm_load";
    dpsm_grid *serial_copy = (dpsm_grid *)&serial_copy;
    const int serial_st = dpsm_load(path, &serial_copy);
    check_refused(serial_st, DPSM_ERR_NOT_APPLICABLE, serial_copy, "dpsm_load", "the file of a block");
    const int a = dpsm_step(m->g, dt), b = dpsm_step(copy, dt);
    if (a != b) die("after a restart: dpsm_step returned %s, on the loaded grid %s", dpsm_status_string(a),
                    dpsm_status_string(b));
    if (dpsm_step(m->serial, dt) != a) die("after a restart: the serial twin's step returned another status");
    read_heights(m->g, h, "the grid");
    read_heights(copy, hs, "the loaded grid");
    same_heights(h, hs, m->n, "the grid and the one loaded from its restart file, after a step");
    read_serial_heights(m, hs);
    same_heights(h, hs, m->n, "the grid and its serial twin after a restart and a step");
    double substeps = 0.0;
    dpsm_get_step_info(m->g, DPSM_INFO_SUBSTEPS, &substeps);
    g_work += 3.0 * (double)m->n * (substeps + 1.0);
    dpsm_destroy(copy);
}

/* The scene on a grid made: heights (and a source, an open edge) from the
 * input, steps, a restart; then both grids are destroyed.
 * Bytes: mode, v, w, edge, source, steps, then one dt factor per step; on a
 * mesh, bit 0 of edge / 12 steps both with DPSM_RELAX_LOCAL_STEPS and bit 1
 * gives both a static angle of 37 degrees. */
static void run_scene(made_t *m, reader_t *r) {
    int64_t sx = 0, sy = 0;
    g_op = "dpsm_get_shape";
    if (dpsm_get_shape(m->g, &sx, &sy) != DPSM_OK || sx != m->nx || sy != m->ny)
        die("the new grid's shape is %lld x %lld, not %lld x %lld", (long long)sx, (long long)sy, (long long)m->nx,
            (long long)m->ny);
    double *h = xcalloc((size_t)m->n, sizeof(double)), *hs = xcalloc((size_t)m->n, sizeof(double));
    const unsigned mode = u8(r);
    const double v = kHeights[u8(r) % COUNT(kHeights)], w = kHeights[u8(r) % COUNT(kHeights)];
    for (int64_t c = 0; c < m->n; ++c) {
        switch (mode % 5) {
            case 0: h[c] = v; break;
            case 1: h[c] = c % 2 ? v : w; break;
            case 2: h[c] = v + w * (double)(c % (m->nx > 1 ? m->nx : 7)); break;
            case 3: h[c] = c == (int64_t)(mode / 5 % (unsigned)m->n) ? v : w; break;
            default: h[c] = kHeights[u8(r) % COUNT(kHeights)]; break;
        }
    }
    g_op = "dpsm_set_heights";
    if (dpsm_set_heights(m->g, h) != DPSM_OK || set_on_serial(m, dpsm_set_heights, h) != DPSM_OK)
        die("dpsm_set_heights failed: %s", dpsm_last_error(m->g));
    const unsigned edge = u8(r), source = u8(r);
    g_op = "dpsm_set_boundary";
    if (edge % 3 == 1) {
        const int side = m->edge == DPSM_MESH_EDGE ? DPSM_MESH_EDGE : (int)(edge / 3 % 4);
        if (dpsm_set_boundary(m->g, side, DPSM_OPEN) != DPSM_OK || dpsm_set_boundary(m->serial, side, DPSM_OPEN) != DPSM_OK)
            die("dpsm_set_boundary(%d, open) failed: %s", side, dpsm_last_error(m->g));
    }
    if (m->edge == DPSM_MESH_EDGE && edge / 12 % 2 == 1) {
        /* Local time steps on the part and its twin. */
        g_op = "dpsm_set_relaxation";
        if (dpsm_set_relaxation(m->g, DPSM_RELAX_LOCAL_STEPS) != DPSM_OK ||
            dpsm_set_relaxation(m->serial, DPSM_RELAX_LOCAL_STEPS) != DPSM_OK)
            die("dpsm_set_relaxation(local steps) failed: %s", dpsm_last_error(m->g));
    }
    if (m->edge == DPSM_MESH_EDGE && edge / 24 % 2 == 1) {
        g_op = "dpsm_set_static_angle";
        const double angle = 37.0 * 3.14159265358979323846 / 180.0;
        if (dpsm_set_static_angle(m->g, angle) != DPSM_OK || dpsm_set_static_angle(m->serial, angle) != DPSM_OK)
            die("dpsm_set_static_angle failed: %s", dpsm_last_error(m->g));
    }
    if (source % 4 == 1) {
        g_op = "dpsm_set_source";
        double *q = xcalloc((size_t)m->n, sizeof(double));
        for (int64_t c = 0; c < m->n; ++c) q[c] = kSources[(source / 4 + (unsigned)c * (edge | 1u)) % COUNT(kSources)];
        if (dpsm_set_source(m->g, q) != DPSM_OK || set_on_serial(m, dpsm_set_source, q) != DPSM_OK)
            die("dpsm_set_source failed: %s", dpsm_last_error(m->g));
        free(q);
    }
    g_op = "dpsm_set_max_substeps";
    if (dpsm_set_max_substeps(m->g, kMaxSubsteps) != DPSM_OK || dpsm_set_max_substeps(m->serial, kMaxSubsteps) != DPSM_OK)
        die("dpsm_set_max_substeps failed: %s", dpsm_last_error(m->g));
    read_heights(m->g, h, "the grid");
    check_state(m, h);
    double stable = 0.0, dt = 0.0;
    if (dpsm_stable_dt(m->g, &stable) != DPSM_OK || !(stable > 0.0)) die("dpsm_stable_dt gave %g", stable);
    const unsigned steps = 1 + u8(r) % 4;
    for (unsigned k = 0; k < steps && g_work < kWorkBudget; ++k) {
        dt = kDtFactors[u8(r) % COUNT(kDtFactors)] * stable;
        step_both(m, dt, h, hs);
    }
    if (dt > 0.0 && g_work < kWorkBudget) check_restart(m, dt, h, hs);
    g_op = "dpsm_destroy";
    dpsm_destroy(m->g);
    dpsm_destroy(m->serial);
    free(h);
    free(hs);
}

/* ------------------------------------------------------------------------ */
/* 2D blocks                                                                 */
/* ------------------------------------------------------------------------ */

static const double kSpacings[] = {1.0, 0.5, 2.0, 0.1, 10.0, 0.25, 3.0, 0.37};
static const double kSpacingsBad[] = {0.0, -0.0, -1.0, NAN, INFINITY, -INFINITY, 1e-60, 1e60};

static void op_block(reader_t *r) {
    const unsigned how = u8(r), defect_byte = u8(r);
    const int defect = (defect_byte & 0xc0) == 0xc0 ? (int)(defect_byte & 0x3f) % 9 : -1;
    int64_t nx = 1 + u8(r) % 12, ny = 1 + u8(r) % 12;
    double dx = kSpacings[u8(r) % COUNT(kSpacings)], dy = kSpacings[u8(r) % COUNT(kSpacings)];
    const unsigned pick = u8(r);
    int64_t nxg = nx, nyg = ny, i0 = 0, j0 = 0;
    int null_out = 0, want = defect < 0 ? DPSM_OK : DPSM_ERR_INVALID_SIZE;
    const char *what = "none";
    static const int64_t kBadCounts[] = {0, -1, INT64_MIN, -64};
    static const int64_t kBadOffsets[] = {1, -1, INT64_MIN, INT64_MAX};
    switch (defect) {
        case 0: what = "a NULL out"; want = DPSM_ERR_NULL_POINTER; null_out = 1; break;
        case 1: what = "MPI_COMM_NULL"; want = DPSM_ERR_INVALID_VALUE; break;
        case 2:
            what = "a global count below 1";
            if (pick % 2) nxg = kBadCounts[pick / 2 % COUNT(kBadCounts)];
            else nyg = kBadCounts[pick / 2 % COUNT(kBadCounts)];
            break;
        case 3: what = "a block smaller than the grid"; if (pick % 2) nxg += 1; else nyg += 1; break;
        case 4: what = "a block larger than the grid"; if (pick % 2) nxg -= 1; else nyg -= 1; break;
        case 5:
            what = "a block off the grid";
            if (pick % 2) i0 = kBadOffsets[pick / 2 % COUNT(kBadOffsets)];
            else j0 = kBadOffsets[pick / 2 % COUNT(kBadOffsets)];
            break;
        case 6:
            what = "a block count below 1";
            if (pick % 2) nx = kBadCounts[pick / 2 % COUNT(kBadCounts)];
            else ny = kBadCounts[pick / 2 % COUNT(kBadCounts)];
            break;
        case 7:
            what = "a bad spacing";
            want = DPSM_ERR_INVALID_VALUE;
            if (pick % 2) dx = kSpacingsBad[pick / 2 % COUNT(kSpacingsBad)];
            else dy = kSpacingsBad[pick / 2 % COUNT(kSpacingsBad)];
            break;
        case 8: what = "a grid too large to address"; nxg = nx = INT64_MAX / 2; break;
        default: break;
    }
    const caller_t caller = caller_of(how, defect == 1);
    const char *fn = caller.fortran ? "dpsm_create_2d_mpi_f" : "dpsm_create_2d_mpi";
    g_op = fn;
    dpsm_grid *g = (dpsm_grid *)&g; /* not NULL: a failure must set NULL */
    dpsm_grid **out = null_out ? NULL : &g;
    const int st = caller.fortran
                       ? dpsm_create_2d_mpi_f(MPI_Comm_c2f(caller.comm), nxg, nyg, i0, j0, nx, ny, dx, dy, out)
                       : dpsm_create_2d_mpi(caller.comm, nxg, nyg, i0, j0, nx, ny, dx, dy, out);
    if (null_out) g = NULL;
    check_refused(st, want, g, fn, what);
    if (st != DPSM_OK) return;
    made_t m = {g, NULL, caller, nx * ny, nx, ny, NULL, DPSM_XMIN, NULL};
    g_op = "dpsm_create_2d";
    if (dpsm_create_2d(nx, ny, dx, dy, &m.serial) != DPSM_OK) die("the serial twin: %s", dpsm_last_error(NULL));
    m.area = xcalloc((size_t)m.n, sizeof(double));
    for (int64_t c = 0; c < m.n; ++c) m.area[c] = dx * dy;
    run_scene(&m, r);
    free(m.area);
}

/* ------------------------------------------------------------------------ */
/* Meshes: a jittered lattice of quads or triangles in a shuffled order      */
/* ------------------------------------------------------------------------ */

typedef struct {
    int64_t nnodes, ncells, nfaces;
    double *node_xy;
    int64_t *cell_start, *cell_nodes; /* polygons, local cells, CSR */
    double *cell_xy, *area;           /* per local cell */
    int64_t *face_cells;              /* per face: two local cells (-1: the domain edge) */
    double *face_xy, *face_length;
    int64_t *global_id;
    int *owner;
} part_t;

static void part_free(part_t *p) {
    free(p->node_xy);
    free(p->cell_start);
    free(p->cell_nodes);
    free(p->cell_xy);
    free(p->area);
    free(p->face_cells);
    free(p->face_xy);
    free(p->face_length);
    free(p->global_id);
    free(p->owner);
    memset(p, 0, sizeof *p);
}

static void shuffle(int64_t *v, int64_t n, prng_t *p) {
    for (int64_t k = n - 1; k > 0; --k) {
        const int64_t j = (int64_t)prng_below(p, (unsigned)(k + 1)), t = v[k];
        v[k] = v[j], v[j] = t;
    }
}

/* nx x ny squares (each a quad, or two triangles when `triangles`, on a
 * diagonal picked at random), cells and nodes numbered in a random local
 * order, global ids a random permutation, every cell owned by rank 0. */
static void part_build(part_t *m, int64_t nx, int64_t ny, int triangles, prng_t *p) {
    memset(m, 0, sizeof *m);
    const int64_t nxn = nx + 1, nyn = ny + 1, per = triangles ? 2 : 1;
    m->nnodes = nxn * nyn;
    m->ncells = nx * ny * per;
    int64_t *node_of = xcalloc((size_t)m->nnodes, sizeof(int64_t)), *cell_of = xcalloc((size_t)m->ncells, sizeof(int64_t));
    for (int64_t k = 0; k < m->nnodes; ++k) node_of[k] = k;
    for (int64_t k = 0; k < m->ncells; ++k) cell_of[k] = k;
    shuffle(node_of, m->nnodes, p); /* lattice node k is local node node_of[k] */
    shuffle(cell_of, m->ncells, p); /* lattice polygon k is local cell cell_of[k] */
    m->node_xy = xcalloc((size_t)(2 * m->nnodes), sizeof(double));
    for (int64_t j = 0; j < nyn; ++j)
        for (int64_t i = 0; i < nxn; ++i) {
            const int64_t n = node_of[i + nxn * j];
            m->node_xy[2 * n] = (double)i + 0.2 * (prng_unit(p) - 0.5);
            m->node_xy[2 * n + 1] = (double)j + 0.2 * (prng_unit(p) - 0.5);
        }
    /* The lattice's polygons, by lattice number; then in local order. */
    int64_t (*poly)[4] = xcalloc((size_t)m->ncells, sizeof *poly);
    int *count = xcalloc((size_t)m->ncells, sizeof(int));
    for (int64_t j = 0, k = 0; j < ny; ++j)
        for (int64_t i = 0; i < nx; ++i) {
            const int64_t a = node_of[i + nxn * j], b = node_of[i + 1 + nxn * j];
            const int64_t c = node_of[i + 1 + nxn * (j + 1)], d = node_of[i + nxn * (j + 1)];
            if (!triangles) {
                poly[k][0] = a, poly[k][1] = b, poly[k][2] = c, poly[k][3] = d, count[k++] = 4;
            } else if (prng_below(p, 2)) {
                poly[k][0] = a, poly[k][1] = b, poly[k][2] = c, count[k++] = 3;
                poly[k][0] = a, poly[k][1] = c, poly[k][2] = d, count[k++] = 3;
            } else {
                poly[k][0] = a, poly[k][1] = b, poly[k][2] = d, count[k++] = 3;
                poly[k][0] = b, poly[k][1] = c, poly[k][2] = d, count[k++] = 3;
            }
        }
    int64_t *lattice_of = xcalloc((size_t)m->ncells, sizeof(int64_t));
    for (int64_t k = 0; k < m->ncells; ++k) lattice_of[cell_of[k]] = k;
    m->cell_start = xcalloc((size_t)(m->ncells + 1), sizeof(int64_t));
    m->cell_nodes = xcalloc((size_t)(4 * m->ncells), sizeof(int64_t));
    m->cell_xy = xcalloc((size_t)(2 * m->ncells), sizeof(double));
    m->area = xcalloc((size_t)m->ncells, sizeof(double));
    for (int64_t c = 0, at = 0; c < m->ncells; ++c) {
        const int64_t k = lattice_of[c];
        double twice = 0.0, mx = 0.0, my = 0.0;
        for (int e = 0; e < count[k]; ++e) {
            const int64_t u = poly[k][e], v = poly[k][(e + 1) % count[k]];
            const double px = m->node_xy[2 * u], py = m->node_xy[2 * u + 1];
            const double qx = m->node_xy[2 * v], qy = m->node_xy[2 * v + 1];
            const double cross = px * qy - py * qx;
            twice += cross, mx += (px + qx) * cross, my += (py + qy) * cross;
            m->cell_nodes[at++] = u;
        }
        m->cell_start[c + 1] = at;
        m->area[c] = 0.5 * twice;
        m->cell_xy[2 * c] = mx / (3.0 * twice), m->cell_xy[2 * c + 1] = my / (3.0 * twice);
    }
    /* Faces: each edge once, the cells on either side (-1 beyond the domain edge). */
    int64_t *face_of_edge = xcalloc((size_t)(m->nnodes * m->nnodes), sizeof(int64_t));
    const int64_t most = m->cell_start[m->ncells];
    m->face_cells = xcalloc((size_t)(2 * most), sizeof(int64_t));
    m->face_xy = xcalloc((size_t)(2 * most), sizeof(double));
    m->face_length = xcalloc((size_t)most, sizeof(double));
    for (int64_t c = 0; c < m->ncells; ++c)
        for (int64_t e = m->cell_start[c]; e < m->cell_start[c + 1]; ++e) {
            const int64_t u = m->cell_nodes[e], v = m->cell_nodes[e + 1 < m->cell_start[c + 1] ? e + 1 : m->cell_start[c]];
            int64_t *slot = &face_of_edge[(u < v ? u : v) * m->nnodes + (u < v ? v : u)];
            if (*slot) {
                m->face_cells[2 * (*slot - 1) + 1] = c;
                continue;
            }
            const int64_t f = m->nfaces++;
            *slot = f + 1;
            m->face_cells[2 * f] = c, m->face_cells[2 * f + 1] = -1;
            const double ux = m->node_xy[2 * u], uy = m->node_xy[2 * u + 1], vx = m->node_xy[2 * v], vy = m->node_xy[2 * v + 1];
            m->face_xy[2 * f] = 0.5 * (ux + vx), m->face_xy[2 * f + 1] = 0.5 * (uy + vy);
            m->face_length[f] = hypot(vx - ux, vy - uy);
        }
    for (int64_t f = 0; f < m->nfaces; ++f) /* interior faces either way round */
        if (m->face_cells[2 * f + 1] >= 0 && prng_below(p, 2)) {
            const int64_t t = m->face_cells[2 * f];
            m->face_cells[2 * f] = m->face_cells[2 * f + 1], m->face_cells[2 * f + 1] = t;
        }
    m->global_id = xcalloc((size_t)m->ncells, sizeof(int64_t));
    m->owner = xcalloc((size_t)m->ncells, sizeof(int));
    for (int64_t c = 0; c < m->ncells; ++c) m->global_id[c] = c;
    shuffle(m->global_id, m->ncells, p);
    free(face_of_edge);
    free(lattice_of);
    free(count);
    free(poly);
    free(node_of);
    free(cell_of);
}

/* The serial twin's mesh: the part's cells in the order of their global ids
 * (dpsm_mpi.h: sums over a cell's faces follow the global ids, which a serial
 * mesh has not; its own cell numbers stand for them). Faces and nodes as
 * they are. */
static void in_global_order(const part_t *p, part_t *q) {
    memset(q, 0, sizeof *q);
    q->nnodes = p->nnodes, q->ncells = p->ncells, q->nfaces = p->nfaces;
    q->node_xy = copy_of(p->node_xy, sizeof(double) * (size_t)(2 * p->nnodes));
    q->cell_xy = xcalloc((size_t)(2 * p->ncells), sizeof(double));
    q->area = xcalloc((size_t)p->ncells, sizeof(double));
    q->cell_start = xcalloc((size_t)(p->ncells + 1), sizeof(int64_t));
    q->cell_nodes = xcalloc((size_t)p->cell_start[p->ncells], sizeof(int64_t));
    int64_t *local_of = xcalloc((size_t)p->ncells, sizeof(int64_t));
    for (int64_t c = 0; c < p->ncells; ++c) local_of[p->global_id[c]] = c;
    for (int64_t k = 0, at = 0; k < p->ncells; ++k) {
        const int64_t c = local_of[k];
        q->cell_xy[2 * k] = p->cell_xy[2 * c], q->cell_xy[2 * k + 1] = p->cell_xy[2 * c + 1];
        q->area[k] = p->area[c];
        for (int64_t e = p->cell_start[c]; e < p->cell_start[c + 1]; ++e) q->cell_nodes[at++] = p->cell_nodes[e];
        q->cell_start[k + 1] = at;
    }
    q->face_cells = xcalloc((size_t)(2 * p->nfaces), sizeof(int64_t));
    for (int64_t k = 0; k < 2 * p->nfaces; ++k)
        q->face_cells[k] = p->face_cells[k] < 0 ? -1 : p->global_id[p->face_cells[k]];
    q->face_xy = copy_of(p->face_xy, sizeof(double) * (size_t)(2 * p->nfaces));
    q->face_length = copy_of(p->face_length, sizeof(double) * (size_t)p->nfaces);
    free(local_of);
}

/* The index arrays of a copy from 1 (the domain edge's -1 becomes 0); the
 * extremes stay, out of range either way. */
static void from_one(int64_t *v, int64_t n) {
    for (int64_t k = 0; v && k < n; ++k)
        if (v[k] != INT64_MIN && v[k] != INT64_MAX) ++v[k];
}

/* The defects of both mesh constructors (0..8), then each one's own (9..14). */
enum { kCommonDefects = 9, kMeshDefects = 15 };

static void op_mesh(reader_t *r, int graph) {
    const unsigned how = u8(r), defect_byte = u8(r);
    const int defect = (defect_byte & 0xc0) == 0xc0 ? (int)(defect_byte & 0x3f) % kMeshDefects : -1;
    const int64_t nx = 1 + u8(r) % 6;
    int64_t ny = 1 + u8(r) % 6;
    const int triangles = (int)(u8(r) % 2);
    if (!triangles && nx * ny == 1) ny = 2; /* two cells at least: a defect may repeat another cell's id */
    prng_t p = {0x9E3779B97F4A7C15ULL ^ ((uint64_t)u16(r) * 0x100000001B3ULL + 1u)};
    const unsigned pick = u8(r);
    part_t base_part, m;
    part_build(&base_part, nx, ny, triangles, &p);
    /* The arrays handed over: copies, so that a defect touches only them. */
    m = base_part;
    m.node_xy = copy_of(base_part.node_xy, sizeof(double) * (size_t)(2 * m.nnodes));
    m.cell_start = copy_of(base_part.cell_start, sizeof(int64_t) * (size_t)(m.ncells + 1));
    m.cell_nodes = copy_of(base_part.cell_nodes, sizeof(int64_t) * (size_t)m.cell_start[m.ncells]);
    m.cell_xy = copy_of(base_part.cell_xy, sizeof(double) * (size_t)(2 * m.ncells));
    m.area = copy_of(base_part.area, sizeof(double) * (size_t)m.ncells);
    m.face_cells = copy_of(base_part.face_cells, sizeof(int64_t) * (size_t)(2 * m.nfaces));
    m.face_xy = copy_of(base_part.face_xy, sizeof(double) * (size_t)(2 * m.nfaces));
    m.face_length = copy_of(base_part.face_length, sizeof(double) * (size_t)m.nfaces);
    m.global_id = copy_of(base_part.global_id, sizeof(int64_t) * (size_t)m.ncells);
    m.owner = copy_of(base_part.owner, sizeof(int) * (size_t)m.ncells);
    const caller_t caller = caller_of(how, defect == 1);
    const int64_t base = caller.fortran;
    if (caller.fortran) {
        from_one(m.global_id, m.ncells);
        from_one(m.cell_nodes, m.cell_start[m.ncells]);
        from_one(m.cell_start, m.ncells + 1);
        from_one(m.face_cells, 2 * m.nfaces);
    }
    const int64_t cell = (int64_t)prng_below(&p, (unsigned)m.ncells), other = (cell + 1) % m.ncells;
    const int64_t face = (int64_t)prng_below(&p, (unsigned)m.nfaces);
    int64_t ncells = m.ncells, nfaces = m.nfaces, nnodes = m.nnodes;
    int null_out = 0, want = DPSM_ERR_INVALID_VALUE;
    const char *what = "none";
    static const double kBadValues[] = {NAN, INFINITY, -INFINITY, 1e51};
    switch (defect) {
        case 0: what = "a NULL out"; want = DPSM_ERR_NULL_POINTER; null_out = 1; break;
        case 1: what = "MPI_COMM_NULL"; break;
        case 2: {
            static const int64_t bad[] = {0, -1, INT64_MIN};
            what = "ncells below 1";
            want = DPSM_ERR_INVALID_SIZE;
            ncells = bad[pick % COUNT(bad)];
            break;
        }
        case 3: what = "a NULL global_id"; want = DPSM_ERR_NULL_POINTER; free(m.global_id); m.global_id = NULL; break;
        case 4: what = "a NULL owner"; want = DPSM_ERR_NULL_POINTER; free(m.owner); m.owner = NULL; break;
        case 5: what = "a global id below the base"; m.global_id[cell] = pick % 2 ? base - 1 : INT64_MIN; break;
        case 6: what = "a global id twice"; m.global_id[cell] = m.global_id[other]; break;
        case 7: {
            const int64_t beyond[] = {base + m.ncells, base + m.ncells + 5, INT64_MAX};
            what = "a global id beyond the count (a gap)";
            if (m.ncells == 1 || pick % 4 != 3) m.global_id[cell] = beyond[pick % 3];
            else m.global_id[cell] = beyond[0], m.global_id[other] = beyond[1]; /* two gaps */
            break;
        }
        case 8: {
            static const int bad[] = {1, -1, INT_MAX, INT_MIN};
            what = "an owner not a rank of the communicator";
            m.owner[pick % 2 ? cell : 0] = bad[pick / 2 % COUNT(bad)];
            break;
        }
        default: break;
    }
    if (defect >= kCommonDefects && graph) {
        switch (defect) {
            case 9: {
                const int64_t bad[] = {base + m.ncells, base - 2, INT64_MIN, INT64_MAX};
                what = "a face naming a cell out of range";
                m.face_cells[2 * face + pick % 2] = bad[pick / 2 % COUNT(bad)];
                break;
            }
            case 10: what = "a face joining a cell to itself"; m.face_cells[2 * face + 1] = m.face_cells[2 * face]; break;
            case 11: {
                static const double bad[] = {0.0, -0.0, -1.0, NAN, INFINITY, 1e51};
                what = "a bad cell area";
                m.area[cell] = bad[pick % COUNT(bad)];
                break;
            }
            case 12:
                what = "a NULL array";
                want = DPSM_ERR_NULL_POINTER;
                switch (pick % 5) {
                    case 0: free(m.cell_xy); m.cell_xy = NULL; break;
                    case 1: free(m.area); m.area = NULL; break;
                    case 2: free(m.face_cells); m.face_cells = NULL; break;
                    case 3: free(m.face_xy); m.face_xy = NULL; break;
                    default: free(m.face_length); m.face_length = NULL; break;
                }
                break;
            case 13: what = "nfaces below 1"; want = DPSM_ERR_INVALID_SIZE; nfaces = pick % 2 ? 0 : -1; break;
            default:
                what = "a coordinate not finite or out of range";
                if (pick % 2) m.cell_xy[2 * cell + pick / 2 % 2] = kBadValues[pick / 4 % 4];
                else m.face_xy[2 * face + pick / 2 % 2] = kBadValues[pick / 4 % 4];
                break;
        }
    } else if (defect >= kCommonDefects) {
        const int64_t k0 = m.cell_start[cell] - base, count = m.cell_start[cell + 1] - m.cell_start[cell];
        switch (defect) {
            case 9:
                what = "a node index out of range";
                m.cell_nodes[k0 + pick % (unsigned)count] = pick / 4 % 2 ? base + m.nnodes : base - 1;
                break;
            case 10: what = "cell_start[0] not the base"; m.cell_start[0] = pick % 2 ? base + 1 : base - 1; break;
            case 11:
                what = "a NULL array";
                want = DPSM_ERR_NULL_POINTER;
                switch (pick % 3) {
                    case 0: free(m.node_xy); m.node_xy = NULL; break;
                    case 1: free(m.cell_start); m.cell_start = NULL; break;
                    default: free(m.cell_nodes); m.cell_nodes = NULL; break;
                }
                break;
            case 12: what = "nnodes below 1"; want = DPSM_ERR_INVALID_SIZE; nnodes = pick % 2 ? 0 : -1; break;
            case 13:
                what = "a coordinate not finite or out of range";
                m.node_xy[pick % (unsigned)(2 * m.nnodes)] = kBadValues[pick / 16 % 4];
                break;
            default: what = "a node repeated in consecutive places"; m.cell_nodes[k0 + 1] = m.cell_nodes[k0]; break;
        }
    }
    if (defect < 0) want = DPSM_OK;
    const char *fn = graph ? (caller.fortran ? "dpsm_create_graph_mpi_f" : "dpsm_create_graph_mpi")
                           : (caller.fortran ? "dpsm_create_mesh_mpi_f" : "dpsm_create_mesh_mpi");
    g_op = fn;
    dpsm_grid *g = (dpsm_grid *)&g; /* not NULL: a failure must set NULL */
    dpsm_grid **out = null_out ? NULL : &g;
    const MPI_Fint fcomm = MPI_Comm_c2f(caller.comm);
    int st;
    if (graph)
        st = caller.fortran ? dpsm_create_graph_mpi_f(fcomm, ncells, m.global_id, m.owner, m.cell_xy, m.area, nfaces,
                                                      m.face_cells, m.face_xy, m.face_length, out)
                            : dpsm_create_graph_mpi(caller.comm, ncells, m.global_id, m.owner, m.cell_xy, m.area,
                                                    nfaces, m.face_cells, m.face_xy, m.face_length, out);
    else
        st = caller.fortran ? dpsm_create_mesh_mpi_f(fcomm, nnodes, m.node_xy, ncells, m.cell_start, m.cell_nodes,
                                                     m.global_id, m.owner, out)
                            : dpsm_create_mesh_mpi(caller.comm, nnodes, m.node_xy, ncells, m.cell_start, m.cell_nodes,
                                                   m.global_id, m.owner, out);
    if (null_out) g = NULL;
    trace("%s: %lld x %lld %s, %lld cells, %lld faces", fn, (long long)nx, (long long)ny,
          triangles ? "triangles" : "quads", (long long)base_part.ncells, (long long)base_part.nfaces);
    check_refused(st, want, g, fn, what);
    if (st == DPSM_OK) {
        made_t made = {g, NULL, caller, base_part.ncells, base_part.ncells, 1, base_part.area, DPSM_MESH_EDGE,
                       base_part.global_id};
        const char *serial_fn = graph ? "dpsm_create_graph" : "dpsm_create_mesh";
        part_t twin;
        in_global_order(&base_part, &twin);
        g_op = serial_fn;
        const int sst = graph ? dpsm_create_graph(twin.ncells, twin.cell_xy, twin.area, twin.nfaces, twin.face_cells,
                                                  twin.face_xy, twin.face_length, &made.serial)
                              : dpsm_create_mesh(twin.nnodes, twin.node_xy, twin.ncells, twin.cell_start,
                                                 twin.cell_nodes, &made.serial);
        if (sst != DPSM_OK) die("the serial twin (%s): %s", serial_fn, dpsm_last_error(NULL));
        part_free(&twin);
        run_scene(&made, r);
    }
    part_free(&m);
    part_free(&base_part);
}

/* ------------------------------------------------------------------------ */
/* Loads that must fail                                                      */
/* ------------------------------------------------------------------------ */

/* Writes the restart file of a small block grid (rank 0 of MPI_COMM_SELF) to `path`. */
static void save_block(const char *path, int64_t nx, int64_t ny) {
    dpsm_grid *g = NULL;
    g_op = "dpsm_create_2d_mpi";
    if (dpsm_create_2d_mpi(MPI_COMM_SELF, nx, ny, 0, 0, nx, ny, 1.0, 1.0, &g) != DPSM_OK)
        die("a block for a restart file: %s", dpsm_last_error(NULL));
    double *h = xcalloc((size_t)(nx * ny), sizeof(double));
    for (int64_t c = 0; c < nx * ny; ++c) h[c] = (double)(c % 5);
    if (dpsm_set_heights(g, h) != DPSM_OK || dpsm_save(g, path) != DPSM_OK)
        die("saving a block: %s", dpsm_last_error(g));
    free(h);
    dpsm_destroy(g);
}

static unsigned char *read_file(const char *path, long *size) {
    FILE *f = fopen(path, "rb");
    if (!f || fseek(f, 0, SEEK_END) != 0 || (*size = ftell(f)) <= 0 || fseek(f, 0, SEEK_SET) != 0)
        die("cannot read back %s", path);
    unsigned char *bytes = xcalloc((size_t)*size, 1);
    if (fread(bytes, 1, (size_t)*size, f) != (size_t)*size) die("cannot read back %s", path);
    fclose(f);
    return bytes;
}

static void write_file(const char *path, const unsigned char *bytes, long size) {
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(bytes, 1, (size_t)size, f) != (size_t)size || fclose(f) != 0) die("cannot write %s", path);
}

/* Bytes: how, which, where (2 bytes). */
static void op_load(reader_t *r) {
    const unsigned how = u8(r), which = u8(r) % 8, where = u16(r);
    const char *path = temp_path(1);
    const caller_t caller = caller_of(how, which == 6);
    const char *fn = caller.fortran ? "dpsm_load_mpi_f" : "dpsm_load_mpi", *what = "?";
    const char *load_path = path;
    int want = DPSM_OK, null_out = 0;
    remove(path);
    switch (which) {
        case 0: what = "a NULL path"; want = DPSM_ERR_NULL_POINTER; load_path = NULL; break;
        case 1: what = "a NULL out"; want = DPSM_ERR_NULL_POINTER; null_out = 1; save_block(path, 3, 2); break;
        case 2: what = "a file that is not there"; want = DPSM_ERR_IO; break;
        case 3: {
            dpsm_grid *serial = NULL;
            what = "the file of a serial grid";
            want = DPSM_ERR_NOT_APPLICABLE;
            if (dpsm_create_2d(3, 2, 1.0, 1.0, &serial) != DPSM_OK || dpsm_save(serial, path) != DPSM_OK)
                die("saving a serial grid: %s", dpsm_last_error(serial));
            dpsm_destroy(serial);
            break;
        }
        case 4:
        case 5: {
            long size = 0;
            save_block(path, 1 + where % 4, 1 + where / 4 % 3);
            unsigned char *bytes = read_file(path, &size);
            const long at = (long)(where % (unsigned)size);
            if (which == 4) {
                what = "a file with a byte changed";
                bytes[at] ^= (unsigned char)(1u << (where / 16 % 8));
                write_file(path, bytes, size);
            } else {
                what = "a truncated file";
                write_file(path, bytes, at);
            }
            want = DPSM_ERR_BAD_FILE;
            free(bytes);
            break;
        }
        case 6: what = "MPI_COMM_NULL"; want = DPSM_ERR_INVALID_VALUE; save_block(path, 3, 2); break;
        default: what = "a good file"; save_block(path, 1 + where % 5, 1 + where / 5 % 5); break;
    }
    g_op = fn;
    dpsm_grid *g = (dpsm_grid *)&g;
    dpsm_grid **out = null_out ? NULL : &g;
    const int st = caller.fortran ? dpsm_load_mpi_f(MPI_Comm_c2f(caller.comm), load_path, out)
                                  : dpsm_load_mpi(caller.comm, load_path, out);
    if (null_out) g = NULL;
    check_refused(st, want, g, fn, what);
    if (st == DPSM_OK) {
        double stable = 0.0;
        if (dpsm_stable_dt(g, &stable) != DPSM_OK || dpsm_step(g, stable) != DPSM_OK)
            die("a loaded grid did not step: %s", dpsm_last_error(g));
        dpsm_destroy(g);
    }
    remove(path);
}

/* ------------------------------------------------------------------------ */

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    ensure_mpi();
    reader_t r = {data, size, 0};
    g_work = 0.0;
    g_opcount = 0;
    while (more(&r) && g_opcount < kMaxOperations && g_work < kWorkBudget) {
        ++g_opcount;
        switch (u8(&r) % 4) {
            case 0: op_block(&r); break;
            case 1: op_mesh(&r, 1); break;
            case 2: op_mesh(&r, 0); break;
            default: op_load(&r); break;
        }
    }
    remove(temp_path(0));
    remove(temp_path(1));
    return 0;
}
