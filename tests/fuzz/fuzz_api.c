/* A fuzzer of the whole C API (libFuzzer's entry point, LLVMFuzzerTestOneInput).
 *
 * The input bytes are read as a program: each operation is one byte of
 * opcode followed by its arguments (a grid slot, sizes, indices, a choice of
 * value from the tables below, array patterns). Up to three grids live at
 * once. Each grid has a twin that receives only the calls that succeeded on
 * it, so that a failed call that changed hidden state (a parameter, a mask, the
 * active set) shows up as a difference in a later step.
 *
 * After every operation:
 *   - the status is one dpsm documents for that function and, where the
 *     arguments decide it, exactly the expected one (a value out of range, a
 *     block off the grid, a step over the sub-step limit in a scene that may
 *     flow forever, ...); never DPSM_ERR_INTERNAL;
 *   - a failed call left a message naming the function and changed nothing
 *     (heights, ledger, what left through each side, face fluxes, step
 *     information, stable step: bit for bit); a successful one cleared the
 *     message;
 *   - every height is finite; the ledger closes to 1e-12 of the largest mass
 *     figure; the grid and its twin are bit-identical;
 *   - after a step without a source: no new extremum (sand, held levels of
 *     open cells, the levels beyond open sides), held cells unchanged; at rest (and
 *     not driven, without a bed, an angle field or a static angle, which
 *     change what rest means): no face steeper than tan(theta) (1 + tol);
 *   - with a bed: no height below it after any operation, and the height
 *     setters refuse heights below it; a bed set above a cell lifts it, and
 *     the sand added is booked as external;
 *   - where face fluxes are recorded, after every step: each sand cell's
 *     faces bring its change of height times its area less what its source
 *     added (with a bed: erosion at most what was asked, as SOURCED and
 *     UNMET book it); walls' faces carry nothing; each side's faces carry
 *     what dpsm_get_side_outflow says it took; the sides and the open cells
 *     make up DPSM_MASS_OUTFLOW;
 *   - every fourth operation, when it is a step: the grid saved before it
 *     (dpsm_save) and loaded (dpsm_load) reads back bit for bit, and after the
 *     same step matches the grid bit for bit (all but the cell updates, which
 *     count the work of looking at every tile once more after a load).
 * Opcode kMeshOp (251) builds an unstructured mesh of its own instead (op_mesh:
 * polygons, a finite-volume graph or a median dual over a jittered lattice,
 * sometimes with one defect the constructor must refuse with the exact
 * status, sometimes with its indices from 1 through the _indexed
 * constructors), runs a few calls and steps on it with checks of their own
 * (ledger, no new extremum, face fluxes against the harness's own cell areas,
 * restart bit for bit, the same mesh from 0 bit for bit) and destroys it; its
 * comment tells its bytes.
 * A violated check prints what it saw and calls abort(), which libFuzzer (or
 * the replay driver, fuzz_replay.c) reports with the input.
 *
 * Values stay in the range where the library is meant to work (heights up to
 * 1e6, spacings 1e-3 .. 1e3, mobility 1e-6 .. 1e6, dt from 1e-300). With
 * DPSM_FUZZ_EXTREME=1 in the environment it also tries the far ends of double
 * (heights to DBL_MAX, spacings 1e-200 and 1e200, dt = 5e-324, huge dt on
 * scenes that rest by themselves), where the library is known to fail
 * (docs/guarantees.md, "Known limits"). */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <dpsm/dpsm.h>

#define FUZZ_NAME "dpsm fuzz"
#include "fuzz_support.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* ------------------------------------------------------------------------ */
/* Reading the input (fuzz_support.h: the bytes, failing loudly)            */
/* ------------------------------------------------------------------------ */

static int extreme_mode(void) {
    static int mode = -1;
    if (mode < 0) {
        const char *e = getenv("DPSM_FUZZ_EXTREME");
        mode = e && *e && *e != '0';
    }
    return mode;
}

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

/* Picks from a table of ordinary values, or (when the byte's top bit is set)
 * from a table of hostile ones. */
static double pick(reader_t *r, const double *ok, size_t nok, const double *bad, size_t nbad) {
    const unsigned b = u8(r);
    if ((b & 0x80) && nbad) return bad[(b & 0x7f) % nbad];
    return ok[b % nok];
}

/* Opcode bytes (and NULL-grid choices) from here on name what was added
 * later (the coupling of issue 17); below it they keep their meaning. */
enum { kLaterOps = 250 };

static const double kNaN = NAN;
static const double kInf = INFINITY;

static const double kSpacings[] = {1.0, 0.5, 2.0, 0.1, 10.0, 0.25, 3.0, 1e-3, 1e3, 0.37};
static const double kSpacingsBad[] = {0.0, -0.0, -1.0, NAN, INFINITY, -INFINITY, -1e-300};
static const double kSpacingsExtreme[] = {1e-200, 1e200, 1e-155, 1e150, DBL_MIN, DBL_MAX};

static const double kHeights[] = {0.0, 1.0, -1.0, 0.25, 3.0, 10.0, 100.0, 1e3, 1e-9, -1e3, 1e6, -0.0, 5e-324,
                                  0.5, 2.0, -3.0, 7.0, 1e-3, 30.0, -1e6};
static const double kHeightsExtreme[] = {1e150, -1e150, 1e300, -1e300, DBL_MAX, -DBL_MAX};

static const double kSources[] = {0.0, 1e-3, -1e-3, 0.1, -0.1, 1.0, -1.0, 10.0, 1e-9, 0.0, 0.0, 0.0};

static const double kAngles[] = {0.5235987755982988, 0.1, 1.0, 0.00872664625997165, 1.562069680534925,
                                 1e-6, 1.5707963267948963, 0.7853981633974483, 1.3, 0.3};
static const double kAnglesBad[] = {0.0, -0.1, 1.5707963267948966, 2.0, 3.14159, NAN, INFINITY, -INFINITY};

static const double kMobilities[] = {1.0, 0.5, 2.0, 1e-6, 1e6, 1e-3, 1e3, 0.1};
static const double kPositiveBad[] = {0.0, -0.0, -1.0, NAN, INFINITY, -INFINITY, -1e-300};

static const double kExponents[] = {1.0, 1.5, 2.0, 1.25, 1.0000000001, DPSM_MAX_FLUX_EXPONENT};
static const double kExponentsBad[] = {0.5, 0.999, 2.0000001, 3.0, 0.0, -1.0, NAN, INFINITY, -INFINITY};

static const double kTolerances[] = {1e-6, 1e-9, 1e-3, 1e-15, 0.1, 1.0, 1e3, 1e-12};

static const double kDtFactors[] = {1e-12, 1e-6, 0.1, 0.5, 1.0, 1.5, 2.0, 4.0, 10.0, 100.0, 1000.0, 0.999, 3.7};
static const double kDtBad[] = {0.0, -0.0, -1.0, NAN, INFINITY, -INFINITY, -1e-300};

/* ------------------------------------------------------------------------ */
/* Grids and what the harness knows about them                               */
/* ------------------------------------------------------------------------ */

enum { GEOM_1D = 1, GEOM_2D = 2, GEOM_AXI = 3 };
#define NSLOTS 3
#define MAX_CELLS 4900

typedef struct {
    dpsm_grid *g, *twin;
    int geom;
    int64_t nx, ny, n;
    double dx, dy, theta, tol;
    int64_t max_substeps;
    int open[4];
    uint8_t *kinds;
    double *source; /* NULL: none */
    double *bed;    /* NULL: none */
    double *tan_field; /* tan of each cell's angle of repose; NULL: uniform */
    double tan_static; /* hysteresis; 0: none */
    int scheme;        /* DPSM_SCHEME_* */
    double exponent;   /* the flux exponent */
    double mass_scale;
    double *levels[4]; /* beyond each side, as set; NULL: 0 */
    int record;        /* face fluxes recorded */
    int relaxed;       /* the last step may have relaxed to rest (then no fluxes) */
} slot_t;

/* The step information items this header knows (a newer header may add some). */
#if defined(DPSM_INFO_SUBSTEPS_EVALUATED)
#define NINFO (DPSM_INFO_SUBSTEPS_EVALUATED + 1)
#elif defined(DPSM_INFO_SUBSTEPS_PER_EXCHANGE)
#define NINFO (DPSM_INFO_SUBSTEPS_PER_EXCHANGE + 1)
#elif defined(DPSM_INFO_BYTES_SENT)
#define NINFO (DPSM_INFO_BYTES_SENT + 1)
#elif defined(DPSM_INFO_CELL_UPDATES)
#define NINFO (DPSM_INFO_CELL_UPDATES + 1)
#else
#define NINFO (DPSM_INFO_MAX_EXCESS_SLOPE + 1)
#endif

typedef struct {
    int64_t nx, ny;
    double *h;
    double mass[4], info[NINFO], stable_dt;
    int side_status[4];  /* dpsm_get_side_outflow: DPSM_OK on the sides the grid has */
    double side[4];      /* what left through each side */
    int fluxes_status;   /* dpsm_get_face_fluxes: DPSM_OK where recorded */
    double *fx, *fy;     /* (nx+1)*ny and nx*(ny+1) faces (fy: 2D only) */
} snap_t;

static slot_t g_slots[NSLOTS];
static double g_work; /* cell sub-steps spent on this input */
static const double kWorkBudget = 3e6;

static void snap(const dpsm_grid *g, const slot_t *s, snap_t *out) {
    out->h = malloc(sizeof(double) * (size_t)s->n);
    if (!out->h) die("out of memory");
    if (dpsm_get_shape(g, &out->nx, &out->ny) != DPSM_OK) die("get_shape failed: %s", dpsm_last_error(g));
    if (dpsm_get_heights(g, out->h) != DPSM_OK) die("get_heights failed: %s", dpsm_last_error(g));
    for (int q = 0; q < 4; ++q)
        if (dpsm_get_mass(g, q, &out->mass[q]) != DPSM_OK) die("get_mass failed");
    for (int i = 0; i < NINFO; ++i)
        if (dpsm_get_step_info(g, i, &out->info[i]) != DPSM_OK) die("get_step_info failed");
    if (dpsm_stable_dt(g, &out->stable_dt) != DPSM_OK) die("stable_dt failed");
    for (int side = 0; side < 4; ++side) {
        out->side[side] = 0.0;
        out->side_status[side] = dpsm_get_side_outflow(g, side, &out->side[side]);
    }
    out->fx = calloc((size_t)((s->nx + 1) * s->ny), sizeof(double));
    out->fy = calloc((size_t)(s->nx * (s->ny + 1)), sizeof(double));
    if (!out->fx || !out->fy) die("out of memory");
    out->fluxes_status = dpsm_get_face_fluxes(g, out->fx, s->geom == GEOM_2D ? out->fy : NULL);
    /* Those may have failed (a side the grid does not have, no fluxes
     * recorded): a last call that succeeds leaves the message empty, as the
     * snapshot found it. */
    if (dpsm_get_shape(g, &out->nx, &out->ny) != DPSM_OK) die("get_shape failed: %s", dpsm_last_error(g));
}

static void unsnap(snap_t *s) {
    free(s->h);
    free(s->fx);
    free(s->fy);
    s->h = s->fx = s->fy = NULL;
}

/* Bit for bit the same snapshots; the face fluxes only `with_fluxes` (a grid
 * just loaded from a restart file reads 0 on every face until its next step). */
static void same_but_fluxes(const slot_t *s, const snap_t *a, const snap_t *b, int with_fluxes, const char *what) {
    if (a->nx != b->nx || a->ny != b->ny) die("%s: the shape changed", what);
    for (int64_t c = 0; c < s->n; ++c)
        if (memcmp(&a->h[c], &b->h[c], sizeof(double)) != 0)
            die("%s: height %lld differs: %.17g vs %.17g", what, (long long)c, a->h[c], b->h[c]);
    static const char *const mass_names[4] = {"TOTAL", "SOURCED", "EXTERNAL", "OUTFLOW"};
    for (int q = 0; q < 4; ++q)
        if (memcmp(&a->mass[q], &b->mass[q], sizeof(double)) != 0)
            die("%s: mass %s differs: %.17g vs %.17g", what, mass_names[q], a->mass[q], b->mass[q]);
    static const char *const info_names[] = {"SUBSTEPS", "TIME_INTEGRATED", "AT_REST", "MAX_EXCESS_SLOPE",
                                             "CELL_UPDATES", "RANK_CELL_UPDATES", "MESSAGES_SENT", "BYTES_SENT",
                                             "SUBSTEPS_PER_EXCHANGE"};
    for (int i = 0; i < NINFO; ++i)
        if (memcmp(&a->info[i], &b->info[i], sizeof(double)) != 0)
            die("%s: step info %s differs: %.17g vs %.17g", what, info_names[i], a->info[i], b->info[i]);
    if (memcmp(&a->stable_dt, &b->stable_dt, sizeof(double)) != 0)
        die("%s: stable_dt differs: %.17g vs %.17g", what, a->stable_dt, b->stable_dt);
    for (int side = 0; side < 4; ++side)
        if (a->side_status[side] != b->side_status[side] || memcmp(&a->side[side], &b->side[side], sizeof(double)) != 0)
            die("%s: side %d's outflow differs: %.17g (%s) vs %.17g (%s)", what, side, a->side[side],
                dpsm_status_string(a->side_status[side]), b->side[side], dpsm_status_string(b->side_status[side]));
    if (!with_fluxes) return;
    if (a->fluxes_status != b->fluxes_status)
        die("%s: dpsm_get_face_fluxes %s vs %s", what, dpsm_status_string(a->fluxes_status),
            dpsm_status_string(b->fluxes_status));
    const size_t nfx = (size_t)((s->nx + 1) * s->ny), nfy = s->geom == GEOM_2D ? (size_t)(s->nx * (s->ny + 1)) : 0;
    if (memcmp(a->fx, b->fx, nfx * sizeof(double)) != 0 || memcmp(a->fy, b->fy, nfy * sizeof(double)) != 0)
        die("%s: the face fluxes differ", what);
}

static void same(const slot_t *s, const snap_t *a, const snap_t *b, const char *what) {
    same_but_fluxes(s, a, b, 1, what);
}

static double cell_area(const slot_t *s, int64_t c) {
    if (s->geom == GEOM_AXI) return 6.283185307179586476925 * ((double)c + 0.5) * s->dx * s->dx;
    return s->geom == GEOM_1D ? s->dx : s->dx * s->dy;
}

static int any_side_open(const slot_t *s) { return s->open[0] || s->open[1] || s->open[2] || s->open[3]; }

/* The sides a grid has (not the y sides of a line, not the axis), the faces
 * along each, and the level held beyond face k of a side. */
static int has_side(const slot_t *s, int side) {
    if (side >= DPSM_YMIN) return s->geom == GEOM_2D;
    return !(s->geom == GEOM_AXI && side == DPSM_XMIN);
}
static int64_t faces_along(const slot_t *s, int side) { return side <= DPSM_XMAX ? s->ny : s->nx; }
static double level_at(const slot_t *s, int side, int64_t k) { return s->levels[side] ? s->levels[side][k] : 0.0; }

static int source_active(const slot_t *s) {
    if (!s->source) return 0;
    for (int64_t c = 0; c < s->n; ++c)
        if (s->kinds[c] == DPSM_CELL_SAND && s->source[c] != 0.0) return 1;
    return 0;
}

/* As dpsm_step documents: a source acts, or held levels differ (open cells,
 * and the levels beyond open sides). */
static int driven_without_source(const slot_t *s, const double *h);
static int driven(const slot_t *s, const double *h) { return source_active(s) || driven_without_source(s, h); }

/* Held levels that differ. */
static int driven_without_source(const slot_t *s, const double *h) {
    int have = 0;
    double level = 0.0;
#define HELD_AT(v)                                  \
    do {                                            \
        if (have && (v) != level) return 1;         \
        level = (v);                                \
        have = 1;                                   \
    } while (0)
    for (int side = 0; side < 4; ++side)
        if (s->open[side])
            for (int64_t k = 0; k < faces_along(s, side); ++k) HELD_AT(level_at(s, side, k));
    for (int64_t c = 0; c < s->n; ++c)
        if (s->kinds[c] == DPSM_CELL_OPEN) HELD_AT(h[c]);
#undef HELD_AT
    return 0;
}

/* On a grid without the physics of real scenes and a step of bounded length,
 * a source is applied in closed form where it cannot make a face steep
 * (dpsm_step), and only a face that is steep at the end of the step under
 * the sources alone, beside a source, drives the step. Returns 1 where such
 * a face surely is steep, 0 where none surely is, and -1 where the library's
 * margins for rounding leave it open. */
static int source_steep_at_end(const slot_t *s, const double *h, double T) {
    const double tan_theta = tan(s->theta), threshold = tan_theta * (1.0 + s->tol);
    int surely = 0;
    double largest = 0.0, magnitude = 0.0; /* of the heights; of any face's slope, now or at T */
#define LATER(c) (s->kinds[c] == DPSM_CELL_SAND && s->source ? h[c] + s->source[c] * T : h[c])
#define SOURCED(c) (s->kinds[c] == DPSM_CELL_SAND && s->source && s->source[c] != 0.0)
    for (int64_t c = 0; c < s->n; ++c) largest = fmax(largest, fmax(fabs(h[c]), fabs(LATER(c))));
    if (!isfinite(largest)) return -1;
    /* A face between cells a and b (b < 0: the level `outside` beyond a side), d apart. */
#define FACE(a, b, outside, d)                                                                            \
    do {                                                                                                  \
        const int64_t a_ = (a), b_ = (b);                                                                 \
        if (s->kinds[a_] == DPSM_CELL_WALL || (b_ >= 0 && s->kinds[b_] == DPSM_CELL_WALL)) break;         \
        const double now_ = fabs(h[a_] - (b_ >= 0 ? h[b_] : (outside))) / (d);                            \
        const double later_ = fabs(LATER(a_) - (b_ >= 0 ? LATER(b_) : (outside))) / (d);                  \
        magnitude = fmax(magnitude, fmax(now_, later_));                                                  \
        if ((SOURCED(a_) || (b_ >= 0 && SOURCED(b_))) && later_ > threshold * (1.0 + 1e-9) + 1e-300) \
            surely = 1;                                                                                   \
    } while (0)
    const int two_d = s->geom == GEOM_2D;
    for (int64_t j = 0; j < s->ny; ++j)
        for (int64_t i = 0; i < s->nx; ++i) {
            const int64_t c = i + s->nx * j;
            if (i + 1 < s->nx) FACE(c, c + 1, 0.0, s->dx);
            if (two_d && j + 1 < s->ny) FACE(c, c + s->nx, 0.0, s->dy);
        }
    for (int64_t k = 0; k < s->ny; ++k) {
        if (s->open[DPSM_XMIN] && has_side(s, DPSM_XMIN)) FACE(s->nx * k, -1, level_at(s, DPSM_XMIN, k), s->dx);
        if (s->open[DPSM_XMAX]) FACE(s->nx - 1 + s->nx * k, -1, level_at(s, DPSM_XMAX, k), s->dx);
    }
    for (int64_t k = 0; two_d && k < s->nx; ++k) {
        if (s->open[DPSM_YMIN]) FACE(k, -1, level_at(s, DPSM_YMIN, k), s->dy);
        if (s->open[DPSM_YMAX]) FACE(k + s->nx * (s->ny - 1), -1, level_at(s, DPSM_YMAX, k), s->dy);
    }
#undef FACE
#undef SOURCED
#undef LATER
    if (surely) return 1;
    /* No face surely steep; none can be where every slope lies below the lowest threshold the library may take
     * (half of tan(theta)), the isotropic scheme's transverse part included. Beyond two open sides (a corner)
     * the transverse part reads levels this does not model. */
    const int corner = two_d && (s->open[DPSM_XMIN] || s->open[DPSM_XMAX]) && (s->open[DPSM_YMIN] || s->open[DPSM_YMAX]);
    const double bound = two_d && s->scheme == DPSM_SCHEME_ISOTROPIC ? sqrt(2.0) * magnitude : magnitude;
    if (!corner && bound < 0.5 * tan_theta * (1.0 - 1e-9) && 64.0 * DBL_EPSILON * largest < 0.25 * tan_theta * fmin(s->dx, s->dy))
        return 0;
    return -1;
}

/* The invariants of any state. */
static void check_state(slot_t *s, const snap_t *now) {
    for (int64_t c = 0; c < s->n; ++c)
        if (!isfinite(now->h[c])) die("height %lld is %g", (long long)c, now->h[c]);
    for (int q = 0; q < 4; ++q)
        if (!isfinite(now->mass[q])) die("mass figure %d is %g", q, now->mass[q]);
    double gross = 0.0, sand_gross = 0.0;
    for (int64_t c = 0; c < s->n; ++c) {
        const double m = fabs(now->h[c]) * cell_area(s, c);
        gross += m;
        if (s->kinds[c] == DPSM_CELL_SAND) sand_gross += m;
    }
    double scale = fmax(fmax(s->mass_scale, sand_gross), 1e-300);
    for (int q = 0; q < 4; ++q) scale = fmax(scale, fabs(now->mass[q]));
    const double residual = fabs(now->mass[0] - (now->mass[1] + now->mass[2] - now->mass[3]));
    if (residual > 1e-12 * scale)
        die("the ledger does not close: total %.17g, sourced %.17g, external %.17g, outflow %.17g: residual %.3g "
            "(%.3g relative)",
            now->mass[0], now->mass[1], now->mass[2], now->mass[3], residual, residual / scale);
    if (!(now->stable_dt > 0.0)) die("stable_dt = %g", now->stable_dt);
    if (s->bed)
        for (int64_t c = 0; c < s->n; ++c)
            if (now->h[c] < s->bed[c])
                die("height %lld is %.17g, below its bed %.17g", (long long)c, now->h[c], s->bed[c]);
    (void)gross;
}

/* After host changes: what the ledger's round-off is relative to. */
static void note_mass_scale(slot_t *s, const snap_t *now) {
    double gross = 0.0;
    for (int64_t c = 0; c < s->n; ++c) gross += fabs(now->h[c]) * cell_area(s, c);
    s->mass_scale = fmax(s->mass_scale, gross);
}

static void compare_twin(slot_t *s, const snap_t *main_snap) {
    snap_t t;
    snap(s->twin, s, &t);
    same(s, main_snap, &t, "the grid and its twin");
    unsnap(&t);
}

/* A failed call: a documented status, the function named in the message,
 * nothing changed. */
static void check_failed(slot_t *s, const dpsm_grid *g, const snap_t *before, int status, const char *fn) {
    if (status == DPSM_ERR_INTERNAL) die("%s: DPSM_ERR_INTERNAL: %s", fn, dpsm_last_error(g));
    if (status < 0 || status > DPSM_ERR_BAD_FILE) die("%s: unknown status %d", fn, status);
    const char *msg = dpsm_last_error(g);
    if (!msg || !*msg) die("%s failed with %s and no message", fn, dpsm_status_string(status));
    if (!strstr(msg, fn)) die("%s failed with the message \"%s\", which does not name it", fn, msg);
    if (s && before) {
        snap_t after;
        snap(s->g, s, &after);
        same(s, before, &after, "a failed call changed the grid");
        unsnap(&after);
    }
}

static void expect_status(int got, int want, const char *fn, const dpsm_grid *g) {
    trace("%s -> %s", fn, dpsm_status_string(got));
    if (got != want)
        die("%s returned %s, expected %s (%s)", fn, dpsm_status_string(got), dpsm_status_string(want),
            dpsm_last_error(g));
}

/* Runs `call` on the slot's grid; on success runs it on the twin too. */
#define ON_BOTH(s, want, fn, call_on)                                                                   \
    do {                                                                                                \
        snap_t before_;                                                                                 \
        snap((s)->g, (s), &before_);                                                                    \
        const dpsm_grid *target_ = (s)->g;                                                              \
        dpsm_grid *g_ = (s)->g;                                                                         \
        const int st_ = (call_on);                                                                      \
        expect_status(st_, (want), (fn), target_);                                                      \
        if (st_ != DPSM_OK) {                                                                           \
            check_failed((s), target_, &before_, st_, (fn));                                            \
        } else {                                                                                        \
            if (*dpsm_last_error(target_)) die("%s succeeded but left the message \"%s\"", (fn),         \
                                               dpsm_last_error(target_));                               \
            g_ = (s)->twin;                                                                             \
            const int tw_ = (call_on);                                                                  \
            if (tw_ != DPSM_OK) die("%s failed on the twin: %s", (fn), dpsm_last_error((s)->twin));     \
        }                                                                                               \
        unsnap(&before_);                                                                               \
    } while (0)

static void destroy_slot(slot_t *s) {
    dpsm_destroy(s->g);
    dpsm_destroy(s->twin);
    free(s->kinds);
    free(s->source);
    free(s->bed);
    free(s->tan_field);
    for (int side = 0; side < 4; ++side) free(s->levels[side]);
    memset(s, 0, sizeof *s);
}

/* ------------------------------------------------------------------------ */
/* Arrays                                                                    */
/* ------------------------------------------------------------------------ */

static double height_value(reader_t *r) {
    const unsigned b = u8(r);
    if (extreme_mode() && (b & 0xc0) == 0xc0) return kHeightsExtreme[b % COUNT(kHeightsExtreme)];
    return kHeights[b % COUNT(kHeights)];
}

/* Fills n values by a pattern from the input. Returns 1 if it planted a
 * non-finite value (the call must then fail with DPSM_ERR_INVALID_VALUE). */
static int fill(reader_t *r, double *a, int64_t n, int64_t nx, int source) {
    const unsigned mode = u8(r);
    const double v = source ? kSources[u8(r) % COUNT(kSources)] : height_value(r);
    const double w = source ? kSources[u8(r) % COUNT(kSources)] : height_value(r);
    for (int64_t c = 0; c < n; ++c) {
        const int64_t i = c % nx, j = c / nx;
        switch (mode % 6) {
            case 0: a[c] = v; break;
            case 1: a[c] = (i + j) % 2 ? v : w; break;
            case 2: a[c] = (2 * i > nx - 1 && i < nx - 1) ? v : w; break;
            case 3: a[c] = v + w * (double)i; break;
            case 4: a[c] = source ? kSources[u8(r) % COUNT(kSources)] : height_value(r); break;
            default: a[c] = c == (int64_t)(u8(r) % (unsigned)n) ? v : w; break;
        }
        if (!isfinite(a[c])) a[c] = 0.0; /* v + w * i may overflow in extreme mode */
    }
    if ((mode & 0xc0) == 0xc0 && n > 0) {
        static const double bad[] = {NAN, INFINITY, -INFINITY};
        a[u16(r) % (unsigned)n] = bad[u8(r) % 3];
        return 1;
    }
    return 0;
}

/* ------------------------------------------------------------------------ */
/* Operations                                                                */
/* ------------------------------------------------------------------------ */

static slot_t *pick_slot(reader_t *r) {
    slot_t *s = &g_slots[u8(r) % NSLOTS];
    return s->g ? s : NULL;
}

static int64_t size_value(reader_t *r, int *bad) {
    const unsigned b = u8(r);
    *bad = 0;
    if (b < 160) return 1 + b % 9;
    if (b < 230) return 60 + b % 12; /* across the 64-cell tile edge */
    static const int64_t hostile[] = {0, -1, INT64_MIN, -64, INT64_MAX, INT64_MAX / 64 + 1};
    const int64_t v = hostile[b % COUNT(hostile)];
    *bad = 1;
    return v;
}

static double spacing_value(reader_t *r) {
    const unsigned b = u8(r);
    if (extreme_mode() && (b & 0xe0) == 0xe0) return kSpacingsExtreme[b % COUNT(kSpacingsExtreme)];
    if (b & 0x80 && (b & 0x40)) return kSpacingsBad[b % COUNT(kSpacingsBad)];
    return kSpacings[b % COUNT(kSpacings)];
}

static int valid_positive(double v) { return isfinite(v) && v > 0.0; }

static void op_create(reader_t *r) {
    g_op = "create";
    slot_t *s = &g_slots[u8(r) % NSLOTS];
    if (s->g) destroy_slot(s);
    const int geom = 1 + (int)(u8(r) % 3);
    int bad_nx, bad_ny;
    int64_t nx = size_value(r, &bad_nx), ny = geom == GEOM_2D ? size_value(r, &bad_ny) : 1;
    if (geom != GEOM_2D) bad_ny = 0;
    const double dx = spacing_value(r), dy = geom == GEOM_2D ? spacing_value(r) : 1.0;
    const int null_out = u8(r) == 0xff;
    if (!bad_nx && !bad_ny && nx * ny > MAX_CELLS) ny = MAX_CELLS / nx; /* keep inputs fast */
    int want = DPSM_OK;
    if (null_out)
        want = DPSM_ERR_NULL_POINTER;
    else if (bad_nx || bad_ny)
        want = DPSM_ERR_INVALID_SIZE;
    else if (!valid_positive(dx) || !valid_positive(dy))
        want = DPSM_ERR_INVALID_VALUE;
    const char *fn = geom == GEOM_1D ? "dpsm_create_1d" : geom == GEOM_2D ? "dpsm_create_2d" : "dpsm_create_axisymmetric";
    dpsm_grid *made[2] = {(dpsm_grid *)&made, (dpsm_grid *)&made}; /* not NULL: a failure must set NULL */
    for (int k = 0; k < (want == DPSM_OK ? 2 : 1); ++k) {
        dpsm_grid **out = null_out ? NULL : &made[k];
        int st;
        if (geom == GEOM_1D)
            st = dpsm_create_1d(nx, dx, out);
        else if (geom == GEOM_2D)
            st = dpsm_create_2d(nx, ny, dx, dy, out);
        else
            st = dpsm_create_axisymmetric(nx, dx, out);
        expect_status(st, want, fn, NULL);
        if (st != DPSM_OK) {
            check_failed(NULL, NULL, NULL, st, fn);
            if (!null_out && made[k] != NULL) die("%s failed but did not set *out to NULL", fn);
            return;
        }
        if (*dpsm_last_error(NULL)) die("%s succeeded but left the message \"%s\"", fn, dpsm_last_error(NULL));
    }
    s->g = made[0];
    s->twin = made[1];
    /* op_step models the time-accurate steps; op_relax sets the relaxation to
     * rest for one step and back (the default, DPSM_RELAX_AUTO, picks one of
     * the two per step: tests/test_relax_to_rest.c checks that choice). */
    for (int k = 0; k < 2; ++k)
        if (dpsm_set_relaxation(made[k], DPSM_RELAX_TIME_ACCURATE) != DPSM_OK)
            die("dpsm_set_relaxation(TIME_ACCURATE) failed: %s", dpsm_last_error(made[k]));
    s->geom = geom;
    s->nx = nx;
    s->ny = ny;
    s->n = nx * ny;
    s->dx = dx;
    s->dy = geom == GEOM_2D ? dy : 1.0;
    s->theta = DPSM_DEFAULT_REPOSE_ANGLE;
    s->tol = DPSM_DEFAULT_REST_TOLERANCE;
    s->max_substeps = DPSM_DEFAULT_MAX_SUBSTEPS;
    s->scheme = DPSM_SCHEME_ISOTROPIC;
    s->exponent = 1.0;
    s->kinds = calloc((size_t)s->n, 1);
    if (!s->kinds) die("out of memory");
    int64_t sx, sy;
    if (dpsm_get_shape(s->g, &sx, &sy) != DPSM_OK || sx != nx || sy != ny)
        die("the new grid's shape is not %lld x %lld", (long long)nx, (long long)ny);
}

static void op_parameter(reader_t *r, unsigned which) {
    slot_t *s = pick_slot(r);
    if (!s) return;
    switch (which) {
        case 0: {
            g_op = "dpsm_set_repose_angle";
            const double v = pick(r, kAngles, COUNT(kAngles), kAnglesBad, COUNT(kAnglesBad));
            const int ok = isfinite(v) && v > 0.0 && v < 0.5 * 3.14159265358979323846;
            ON_BOTH(s, ok ? DPSM_OK : DPSM_ERR_INVALID_VALUE, g_op, dpsm_set_repose_angle(g_, v));
            if (ok) s->theta = v;
            break;
        }
        case 1: {
            g_op = "dpsm_set_mobility";
            const double v = pick(r, kMobilities, COUNT(kMobilities), kPositiveBad, COUNT(kPositiveBad));
            ON_BOTH(s, valid_positive(v) ? DPSM_OK : DPSM_ERR_INVALID_VALUE, g_op, dpsm_set_mobility(g_, v));
            break;
        }
        case 2: {
            g_op = "dpsm_set_scheme";
            static const int schemes[] = {0, 1, 0, 1, 2, -1, 1000, INT32_MIN};
            const int v = schemes[u8(r) % COUNT(schemes)];
            ON_BOTH(s, v == 0 || v == 1 ? DPSM_OK : DPSM_ERR_UNKNOWN_ENUM, g_op, dpsm_set_scheme(g_, v));
            if (v == 0 || v == 1) s->scheme = v;
            break;
        }
        case 3: {
            g_op = "dpsm_set_boundary";
            const unsigned b = u8(r);
            const int side = (int)(b % 6) - 1, kind = (int)((b / 6) % 4) - 1;
            int want = DPSM_OK;
            if (side < 0 || side > DPSM_MESH_EDGE || kind < 0 || kind > 1)
                want = DPSM_ERR_UNKNOWN_ENUM;
            else if (side == DPSM_MESH_EDGE || (s->geom != GEOM_2D && side >= 2) || (s->geom == GEOM_AXI && side == DPSM_XMIN))
                want = DPSM_ERR_NOT_APPLICABLE;
            ON_BOTH(s, want, g_op, dpsm_set_boundary(g_, side, kind));
            if (want == DPSM_OK) s->open[side] = kind == DPSM_OPEN;
            break;
        }
        case 4: {
            g_op = "dpsm_set_rest_tolerance";
            const double v = pick(r, kTolerances, COUNT(kTolerances), kPositiveBad, COUNT(kPositiveBad));
            ON_BOTH(s, valid_positive(v) ? DPSM_OK : DPSM_ERR_INVALID_VALUE, g_op, dpsm_set_rest_tolerance(g_, v));
            if (valid_positive(v)) s->tol = v;
            break;
        }
        case 5: {
            g_op = "dpsm_set_max_substeps";
            static const int64_t values[] = {1, 2, 10, 1000, 100000, DPSM_DEFAULT_MAX_SUBSTEPS, INT64_MAX, 0, -1,
                                             INT64_MIN};
            const int64_t v = values[u8(r) % COUNT(values)];
            ON_BOTH(s, v >= 1 ? DPSM_OK : DPSM_ERR_INVALID_VALUE, g_op, dpsm_set_max_substeps(g_, v));
            if (v >= 1) s->max_substeps = v;
            break;
        }
        default: {
            g_op = "dpsm_set_threads";
            static const int values[] = {0, 1, 2, 3, 1, 2, -1, INT32_MIN};
            const unsigned pick_byte = u8(r);
            const int v = values[pick_byte % COUNT(values)];
            ON_BOTH(s, v >= 0 ? DPSM_OK : DPSM_ERR_INVALID_VALUE, g_op, dpsm_set_threads(g_, v));
            /* The index base from the same byte (no byte of its own, so the
             * corpus keeps its meaning): it changes messages only. */
            static const int bases[] = {0, 1, 1, 0, 2, -1, 0, INT32_MAX};
            const int base = bases[(pick_byte / COUNT(values)) % COUNT(bases)];
            g_op = "dpsm_set_index_base";
            ON_BOTH(s, base == 0 || base == 1 ? DPSM_OK : DPSM_ERR_INVALID_VALUE, g_op, dpsm_set_index_base(g_, base));
            if (dpsm_set_index_base(NULL, base) != DPSM_ERR_NULL_POINTER) die("dpsm_set_index_base accepted a NULL grid");
            /* What a step will use: 1 on a line's serial sweep, else what was asked, else OpenMP's default. */
            int n = 0;
            g_op = "dpsm_get_threads";
            ON_BOTH(s, DPSM_OK, g_op, dpsm_get_threads(g_, &n));
            if (s->geom != GEOM_2D ? n != 1 : v > 0 ? n != v : n < 1) die("dpsm_get_threads says %d after %d", n, v);
            if (dpsm_get_threads(s->g, NULL) != DPSM_ERR_NULL_POINTER) die("dpsm_get_threads accepted a NULL n");
            /* What kind of grid it is: the constructor's, through any restart. */
            int kind = 0;
            g_op = "dpsm_get_grid_kind";
            ON_BOTH(s, DPSM_OK, g_op, dpsm_get_grid_kind(g_, &kind));
            const int want = s->geom == GEOM_2D ? DPSM_GRID_2D : s->geom == GEOM_AXI ? DPSM_GRID_AXISYMMETRIC : DPSM_GRID_1D;
            if (kind != want) die("dpsm_get_grid_kind says %d, not %d", kind, want);
            if (dpsm_get_grid_kind(s->g, NULL) != DPSM_ERR_NULL_POINTER) die("dpsm_get_grid_kind accepted a NULL kind");
            break;
        }
    }
}

static void op_kinds(reader_t *r) {
    g_op = "dpsm_set_cell_kinds";
    slot_t *s = pick_slot(r);
    if (!s) return;
    const unsigned mode = u8(r);
    uint8_t *k = NULL;
    int want = DPSM_OK;
    if (mode % 8 != 0) {
        k = malloc((size_t)s->n);
        if (!k) die("out of memory");
        for (int64_t c = 0; c < s->n; ++c) {
            const unsigned b = mode % 8 == 1 ? u8(r) : (unsigned)(c * 7 + mode) % 13;
            k[c] = b < 9 ? DPSM_CELL_SAND : b < 11 ? DPSM_CELL_WALL : DPSM_CELL_OPEN;
        }
        if ((mode & 0xe0) == 0xe0) {
            static const uint8_t bad[] = {3, 4, 200, 255};
            k[u16(r) % (unsigned)s->n] = bad[u8(r) % 4];
            want = DPSM_ERR_UNKNOWN_ENUM;
        }
    }
    ON_BOTH(s, want, g_op, dpsm_set_cell_kinds(g_, k));
    if (want == DPSM_OK) {
        if (k)
            memcpy(s->kinds, k, (size_t)s->n);
        else
            memset(s->kinds, 0, (size_t)s->n);
    }
    free(k);
}

static void op_heights(reader_t *r) {
    g_op = "dpsm_set_heights";
    slot_t *s = pick_slot(r);
    if (!s) return;
    double *h = malloc(sizeof(double) * (size_t)s->n);
    if (!h) die("out of memory");
    const int planted = fill(r, h, s->n, s->nx, 0);
    const int null_array = u8(r) == 0xfe;
    const double *arg = null_array ? NULL : h;
    int want = null_array ? DPSM_ERR_NULL_POINTER : planted ? DPSM_ERR_INVALID_VALUE : DPSM_OK;
    if (want == DPSM_OK && s->bed)
        for (int64_t c = 0; c < s->n; ++c)
            if (h[c] < s->bed[c]) want = DPSM_ERR_INVALID_VALUE;
    ON_BOTH(s, want, g_op, dpsm_set_heights(g_, arg));
    free(h);
}

static void op_source(reader_t *r) {
    g_op = "dpsm_set_source";
    slot_t *s = pick_slot(r);
    if (!s) return;
    double *q = malloc(sizeof(double) * (size_t)s->n);
    if (!q) die("out of memory");
    const int none = u8(r) % 4 == 0;
    const int planted = none ? 0 : fill(r, q, s->n, s->nx, 1);
    const int want = planted ? DPSM_ERR_INVALID_VALUE : DPSM_OK;
    const double *arg = none ? NULL : q;
    ON_BOTH(s, want, g_op, dpsm_set_source(g_, arg));
    if (want == DPSM_OK) {
        free(s->source);
        s->source = none ? NULL : q;
        if (!none) q = NULL;
    }
    free(q);
}

/* Block arguments: mostly on the grid, sometimes off it. */
static void block_args(reader_t *r, const slot_t *s, int64_t *i0, int64_t *j0, int64_t *ni, int64_t *nj, int *bad) {
    const unsigned b = u8(r);
    *i0 = (int64_t)(u8(r) % (unsigned)s->nx);
    *j0 = (int64_t)(u8(r) % (unsigned)s->ny);
    *ni = 1 + (int64_t)(u8(r) % (unsigned)(s->nx - *i0));
    *nj = 1 + (int64_t)(u8(r) % (unsigned)(s->ny - *j0));
    *bad = 0;
    if ((b & 0xc0) == 0xc0) {
        static const int64_t wild[] = {-1, 0, 1, INT64_MAX, INT64_MIN, 64, -64, INT64_MAX - 1};
        switch (b % 4) {
            case 0: *i0 = wild[u8(r) % COUNT(wild)]; break;
            case 1: *j0 = wild[u8(r) % COUNT(wild)]; break;
            case 2: *ni = wild[u8(r) % COUNT(wild)]; break;
            default: *nj = wild[u8(r) % COUNT(wild)]; break;
        }
        *bad = !(*ni >= 1 && *nj >= 1 && *i0 >= 0 && *j0 >= 0 && *i0 <= s->nx - *ni && *j0 <= s->ny - *nj);
    }
}

static void op_region(reader_t *r, unsigned which) {
    slot_t *s = pick_slot(r);
    if (!s) return;
    int64_t i0, j0, ni, nj;
    int bad;
    block_args(r, s, &i0, &j0, &ni, &nj, &bad);
    const int64_t m = bad ? 1 : ni * nj;
    double *v = malloc(sizeof(double) * (size_t)m);
    if (!v) die("out of memory");
    const int planted = fill(r, v, m, bad ? 1 : ni, 0);
    const int null_array = u8(r) == 0xfd;
    double *arg = null_array ? NULL : v;
    int want = bad ? DPSM_ERR_INVALID_SIZE : null_array ? DPSM_ERR_NULL_POINTER : DPSM_OK;
    if (which == 0) {
        g_op = "dpsm_set_heights_region";
        if (want == DPSM_OK && planted) want = DPSM_ERR_INVALID_VALUE;
        if (want == DPSM_OK && s->bed)
            for (int64_t k = 0; k < m; ++k)
                if (v[k] < s->bed[(i0 + k % ni) + s->nx * (j0 + k / ni)]) want = DPSM_ERR_INVALID_VALUE;
        ON_BOTH(s, want, g_op, dpsm_set_heights_region(g_, i0, j0, ni, nj, arg));
    } else if (which == 1) {
        g_op = "dpsm_add_heights_region";
        if (want == DPSM_OK && planted) want = DPSM_ERR_INVALID_VALUE;
        if (want == DPSM_OK) { /* a sum that overflows fails too */
            snap_t now;
            snap(s->g, s, &now);
            for (int64_t k = 0; k < m; ++k) {
                const int64_t c = (i0 + k % ni) + s->nx * (j0 + k / ni);
                if (!isfinite(now.h[c] + v[k])) want = DPSM_ERR_INVALID_VALUE;
                if (s->bed && now.h[c] + v[k] < s->bed[c]) want = DPSM_ERR_INVALID_VALUE;
            }
            unsnap(&now);
        }
        ON_BOTH(s, want, g_op, dpsm_add_heights_region(g_, i0, j0, ni, nj, arg));
    } else {
        g_op = "dpsm_get_heights_region";
        ON_BOTH(s, want, g_op, dpsm_get_heights_region(g_, i0, j0, ni, nj, arg));
        if (want == DPSM_OK) {
            snap_t now;
            snap(s->g, s, &now);
            for (int64_t k = 0; k < m; ++k) {
                const double expected = now.h[(i0 + k % ni) + s->nx * (j0 + k / ni)];
                if (memcmp(&v[k], &expected, sizeof(double)) != 0)
                    die("get_heights_region value %lld is %.17g, the grid has %.17g", (long long)k, v[k], expected);
            }
            unsnap(&now);
        }
    }
    free(v);
}

/* The rest threshold of the face between cell a and b (b < 0: the outside,
 * of kind kb), as dpsm_step documents it: tan(theta) (1 + tol), with an angle
 * field the mean of the two cells' tan (the sand cell's own where the other
 * is not sand), and at least the static angle's tan (at rest no cell moves). */
static double face_threshold(const slot_t *s, int64_t a, int64_t b, int kb) {
    double tan_face = tan(s->theta);
    if (s->tan_field) {
        const double ta = s->kinds[a] == DPSM_CELL_SAND ? s->tan_field[a] : s->tan_field[b];
        tan_face = 0.5 * (ta + (kb == DPSM_CELL_SAND ? s->tan_field[b] : ta));
    }
    return fmax(tan_face * (1.0 + s->tol), s->tan_static);
}

/* The largest face slope over its rest threshold, minus 1. With a bed, faces
 * whose upper cell holds no more than the film of sand dpsm leaves in place
 * (tol tan(smallest angle) times the smaller spacing) carry nothing. */
static double rest_excess(const slot_t *s, const double *h) {
    double worst = -INFINITY, smallest_tan = tan(s->theta);
    if (s->tan_field)
        for (int64_t c = 0; c < s->n; ++c) smallest_tan = fmin(smallest_tan, s->tan_field[c]);
    const double film = s->tol * smallest_tan * (s->geom == GEOM_2D ? fmin(s->dx, s->dy) : s->dx) * (1.0 + 1e-9);
    for (int64_t j = 0; j < s->ny; ++j)
        for (int64_t i = 0; i < s->nx; ++i) {
            const int64_t c = i + s->nx * j;
            for (int f = 0; f < 6; ++f) {
                int64_t b;
                double d, outside = 0.0;
                if (f == 0 && i + 1 < s->nx) b = c + 1, d = s->dx;
                else if (f == 1 && j + 1 < s->ny) b = c + s->nx, d = s->dy;
                else if (f == 2 && i == 0 && s->open[DPSM_XMIN] && s->geom != GEOM_AXI)
                    b = -1, d = s->dx, outside = level_at(s, DPSM_XMIN, j);
                else if (f == 3 && i == s->nx - 1 && s->open[DPSM_XMAX])
                    b = -1, d = s->dx, outside = level_at(s, DPSM_XMAX, j);
                else if (f == 4 && j == 0 && s->geom == GEOM_2D && s->open[DPSM_YMIN])
                    b = -1, d = s->dy, outside = level_at(s, DPSM_YMIN, i);
                else if (f == 5 && j == s->ny - 1 && s->geom == GEOM_2D && s->open[DPSM_YMAX])
                    b = -1, d = s->dy, outside = level_at(s, DPSM_YMAX, i);
                else continue;
                const int kb = b < 0 ? DPSM_CELL_OPEN : s->kinds[b];
                const double hb = b < 0 ? outside : h[b];
                if (s->kinds[c] == DPSM_CELL_WALL || kb == DPSM_CELL_WALL) continue;
                if (s->kinds[c] != DPSM_CELL_SAND && kb != DPSM_CELL_SAND) continue;
                const int64_t up = h[c] >= hb ? c : b;
                if (s->bed && up >= 0 && s->kinds[up] == DPSM_CELL_SAND && h[up] - s->bed[up] <= film) continue;
                const double slope = fabs(h[c] - hb) / d;
                const double slack = 4.0 * DBL_EPSILON * fmax(fabs(h[c]), fabs(hb)) / d;
                worst = fmax(worst, (slope - slack) / face_threshold(s, c, b, kb) - 1.0);
            }
        }
    return worst;
}

/* The restart file of this process: one at a time, replaced by each save. */
static const char *restart_path(void) {
    static char path[512];
    if (!path[0]) {
        const char *dir = getenv("TMPDIR");
        snprintf(path, sizeof path, "%s/dpsm-fuzz-%ld.dpsm", dir && *dir ? dir : "/tmp", (long)getpid());
    }
    return path;
}

/* The slot's grid through a restart file: it must read back exactly as
 * `before`, step information included. */
static dpsm_grid *restart_copy(slot_t *s, const snap_t *before) {
    const char *path = restart_path();
    if (dpsm_save(s->g, path) != DPSM_OK) die("dpsm_save(%s) failed: %s", path, dpsm_last_error(s->g));
    if (*dpsm_last_error(s->g)) die("dpsm_save succeeded but left a message");
    dpsm_grid *copy = NULL;
    if (dpsm_load(path, &copy) != DPSM_OK || !copy) die("dpsm_load(%s) failed: %s", path, dpsm_last_error(NULL));
    snap_t loaded;
    snap(copy, s, &loaded);
    same_but_fluxes(s, before, &loaded, 0, "a grid loaded from a restart file");
    unsnap(&loaded);
    return copy;
}

/* The loaded grid after the same step as the slot's grid. */
static void check_restart_continues(slot_t *s, dpsm_grid *copy, double dt, const snap_t *after) {
    if (dpsm_step(copy, dt) != DPSM_OK) die("the loaded grid's step failed: %s", dpsm_last_error(copy));
    snap_t stepped;
    snap(copy, s, &stepped);
#ifdef DPSM_INFO_CELL_UPDATES
    stepped.info[DPSM_INFO_CELL_UPDATES] = after->info[DPSM_INFO_CELL_UPDATES];
#endif
#ifdef DPSM_INFO_RANK_CELL_UPDATES
    stepped.info[DPSM_INFO_RANK_CELL_UPDATES] = after->info[DPSM_INFO_RANK_CELL_UPDATES];
#endif
    same(s, after, &stepped, "a grid loaded from a restart file, after a step");
    unsnap(&stepped);
}

/* After a step that succeeded on the slot's grid: the same step on its twin,
 * the state invariants, and held cells as they were. Snaps the grid. */
static void after_step(slot_t *s, double dt, const snap_t *before, snap_t *after) {
    if (*dpsm_last_error(s->g)) die("dpsm_step succeeded but left the message \"%s\"", dpsm_last_error(s->g));
    if (dpsm_step(s->twin, dt) != DPSM_OK) die("the twin's step failed: %s", dpsm_last_error(s->twin));
    snap(s->g, s, after);
    check_state(s, after);
    for (int64_t c = 0; c < s->n; ++c)
        if (s->kinds[c] != DPSM_CELL_SAND && memcmp(&after->h[c], &before->h[c], sizeof(double)) != 0)
            die("the held height of cell %lld changed from %.17g to %.17g", (long long)c, before->h[c], after->h[c]);
}

/* After a step that recorded its face fluxes (`after` read them): what each
 * sand cell's faces brought is its change of height times its area less what
 * its source added (with a bed, erosion takes at most what it asked for, and
 * the sources took what SOURCED and UNMET say); walls' faces carry nothing;
 * each side's faces carry what that side's account took; the sides and the
 * open cells make up OUTFLOW. Face volumes are plain sums over the sub-steps:
 * they agree to the round-off of that many additions. */
static void check_fluxes(const slot_t *s, const snap_t *before, const snap_t *after) {
    const double time = after->info[DPSM_INFO_TIME_INTEGRATED];
    const double rel = 1e-11 + 16.0 * DBL_EPSILON * fmax(after->info[DPSM_INFO_SUBSTEPS], 1.0);
    const int two_d = s->geom == GEOM_2D;
    double applied = 0.0, asked = 0.0, scale_all = 0.0, into_open = 0.0;
    for (int64_t j = 0; j < s->ny; ++j)
        for (int64_t i = 0; i < s->nx; ++i) {
            const int64_t c = i + s->nx * j, xl = i + (s->nx + 1) * j, yl = i + s->nx * j;
            double in = after->fx[xl] - after->fx[xl + 1];
            double gross = fabs(after->fx[xl]) + fabs(after->fx[xl + 1]);
            if (two_d) {
                in += after->fy[yl] - after->fy[yl + s->nx];
                gross += fabs(after->fy[yl]) + fabs(after->fy[yl + s->nx]);
            }
            if (s->kinds[c] == DPSM_CELL_WALL) {
                if (gross != 0.0) die("the faces of wall cell %lld carried %g", (long long)c, gross);
                continue;
            }
            if (s->kinds[c] == DPSM_CELL_OPEN) {
                into_open += in;
                scale_all += gross;
                continue;
            }
            const double area = cell_area(s, c), q = s->source ? s->source[c] : 0.0;
            const double source = (after->h[c] - before->h[c]) * area - in, want = q * time * area;
            const double scale = (fabs(before->h[c]) + fabs(after->h[c])) * area + gross + fabs(want);
            const double tol = rel * scale + DBL_MIN;
            asked += want;
            applied += source;
            scale_all += scale;
            if (s->bed && q < 0.0) {
                if (source < want - tol || source > tol)
                    die("cell %lld on its bed lost %.17g to erosion that asked %.17g", (long long)c, source, want);
            } else if (fabs(source - want) > tol) {
                die("cell %lld changed by %.17g, its faces brought %.17g, its source %.17g: off by %.3g of %.3g",
                    (long long)c, (after->h[c] - before->h[c]) * area, in, want, source - want, scale);
            }
        }
    const double sourced = after->mass[1] - before->mass[1];
    const double totals = fabs(before->mass[1]) + fabs(before->mass[3]) + fabs(after->mass[3]);
    if (fabs(applied - sourced) > rel * (scale_all + totals) + DBL_MIN)
        die("the cells took %.17g from their sources, SOURCED grew by %.17g", applied, sourced);
    double sides = 0.0;
    for (int side = 0; side < 4; ++side) {
        if (!has_side(s, side)) continue;
        double out = 0.0, gross = 0.0;
        for (int64_t k = 0; k < faces_along(s, side); ++k) {
            const double v = side == DPSM_XMIN   ? -after->fx[(s->nx + 1) * k]
                             : side == DPSM_XMAX ? after->fx[s->nx + (s->nx + 1) * k]
                             : side == DPSM_YMIN ? -after->fy[k]
                                                 : after->fy[k + s->nx * s->ny];
            out += v;
            gross += fabs(v);
        }
        const double booked = after->side[side] - before->side[side];
        if (!s->open[side] && (gross != 0.0 || booked != 0.0))
            die("wall side %d: its faces carried %g, its account took %g", side, gross, booked);
        if (fabs(out - booked) > rel * (gross + fabs(before->side[side]) + fabs(after->side[side])) + DBL_MIN)
            die("side %d: its faces carried %.17g out, its account took %.17g", side, out, booked);
        sides += booked;
        scale_all += gross + fabs(before->side[side]) + fabs(after->side[side]);
    }
    const double outflow = after->mass[3] - before->mass[3];
    if (fabs(outflow - sides - into_open) > rel * (scale_all + totals) + DBL_MIN)
        die("OUTFLOW grew by %.17g; the sides took %.17g, the open cells %.17g", outflow, sides, into_open);
}

static void op_step(reader_t *r) {
    g_op = "dpsm_step";
    slot_t *s = pick_slot(r);
    if (!s) return;
    snap_t before;
    snap(s->g, s, &before);
    const unsigned b = u8(r);
    const int drives = driven(s, before.h);
    double dt;
    if ((b & 0xe0) == 0xe0)
        dt = kDtBad[b % COUNT(kDtBad)];
    else if ((b & 0xe0) == 0xc0) {
        /* 5e-324: every increment rounds to 0; the 2D sweep then takes a
         * supercritical surface for one at rest (docs/guarantees.md). */
        static const double absolute[] = {1e12, 1e300, DBL_MAX, 1e-300, 1e-12, 5e-324};
        dt = absolute[b % (COUNT(absolute) - (extreme_mode() ? 0 : 1))];
    } else
        dt = before.stable_dt * kDtFactors[b % COUNT(kDtFactors)];

    int want = DPSM_OK, either = 0;
    double needed = 0.0;
    if (!valid_positive(dt)) {
        want = DPSM_ERR_INVALID_VALUE;
    } else {
        needed = ceil(dt / before.stable_dt);
        const double limit = (double)s->max_substeps;
        const int bounded = needed <= 9007199254740992.0;
        int limited = drives;
        /* A source alone drives only where it keeps a face steep to the end of the step. */
        if (drives && source_active(s) && bounded && !driven_without_source(s, before.h) && !s->bed && !s->tan_field &&
            s->exponent == 1.0 && s->tan_static == 0.0) {
            const int steep = source_steep_at_end(s, before.h, dt);
            limited = steep != 0;
            if (steep < 0 && needed > limit) either = 1;
        }
        if (limited && (!bounded || needed > limit)) want = DPSM_ERR_WORK_LIMIT;
        if (limited && fabs(needed - limit) <= 1.0) either = 1; /* rounding of dt / stable_dt */
        /* Bounded work: a scene at rest by itself stops early, but how early
         * depends on the scene; keep to steps whose sub-steps we can afford. */
        const double cost = fmin(needed, 1e18) * (double)s->n;
        if ((want == DPSM_OK || either) && g_work + cost > kWorkBudget && !extreme_mode()) {
            unsnap(&before);
            return;
        }
        if (want == DPSM_OK || either) g_work += cost;
        /* A source that would carry a sand cell beyond the supported range within dt: refused first. */
        for (int64_t c = 0; s->source && c < s->n; ++c)
            if (s->kinds[c] == DPSM_CELL_SAND && s->source[c] != 0.0 && !(s->bed && s->source[c] < 0.0) &&
                !(fabs(before.h[c] + s->source[c] * dt) <= 1e50)) {
                want = DPSM_ERR_INVALID_VALUE;
                either = 0;
                break;
            }
    }

    double hi = -INFINITY, lo = INFINITY;
    for (int64_t c = 0; c < s->n; ++c)
        if (s->kinds[c] != DPSM_CELL_WALL) {
            hi = fmax(hi, before.h[c]);
            lo = fmin(lo, before.h[c]);
        }
    for (int side = 0; side < 4; ++side)
        if (s->open[side])
            for (int64_t k = 0; k < faces_along(s, side); ++k) {
                hi = fmax(hi, level_at(s, side, k));
                lo = fmin(lo, level_at(s, side, k));
            }

    dpsm_grid *restored = g_opcount % 4 == 1 && want == DPSM_OK ? restart_copy(s, &before) : NULL;
    const int st = dpsm_step(s->g, dt);
    trace("dpsm_step(%g = %g stable steps) on %lld x %lld, %s", dt, dt / before.stable_dt, (long long)s->nx,
          (long long)s->ny, drives ? "driven" : "not driven");
    if (either && (st == DPSM_OK || st == DPSM_ERR_WORK_LIMIT)) want = st;
    expect_status(st, want, g_op, s->g);
    if (st != DPSM_OK) {
        if (st == DPSM_ERR_WORK_LIMIT && !strstr(dpsm_last_error(s->g), "dpsm_set_max_substeps"))
            die("the work-limit message does not say how to raise the limit: %s", dpsm_last_error(s->g));
        check_failed(s, s->g, &before, st, g_op);
        dpsm_destroy(restored);
        unsnap(&before);
        return;
    }
    snap_t after;
    after_step(s, dt, &before, &after);
    s->relaxed = 0;
    if (s->record) {
        if (after.fluxes_status != DPSM_OK)
            die("face fluxes are recorded, but after a step dpsm_get_face_fluxes says %s",
                dpsm_status_string(after.fluxes_status));
        check_fluxes(s, &before, &after);
    }
    if (!source_active(s) && hi >= lo) {
        const double magnitude = fmax(fmax(fabs(hi), fabs(lo)), DBL_MIN);
        for (int64_t c = 0; c < s->n; ++c) {
            if (s->kinds[c] != DPSM_CELL_SAND) continue;
            if ((after.h[c] - hi) / magnitude > 4 * DBL_EPSILON || (lo - after.h[c]) / magnitude > 4 * DBL_EPSILON)
                die("new extremum without a source at cell %lld: %.17g outside [%.17g, %.17g] (scheme %s)",
                    (long long)c, after.h[c], lo, hi, s->geom == GEOM_2D ? "2D" : "1D/axisymmetric");
        }
    }
    const double at_rest = after.info[DPSM_INFO_AT_REST];
    if (at_rest != 0.0 && at_rest != 1.0) die("AT_REST = %g", at_rest);
    /* With a source too: rest is reported only once no source can make a face steep before the step's end. */
    if (at_rest == 1.0) {
        const double excess = rest_excess(s, after.h);
        if (excess > 1e-12) die("reported at rest with a face steeper than tan(theta)(1+tol) by %.3g", excess);
    }
    const double substeps = after.info[DPSM_INFO_SUBSTEPS];
    if (!(substeps >= 0.0) || (at_rest == 0.0 && substeps != fmax(needed, 1.0)))
        die("SUBSTEPS = %g, AT_REST = %g, for %g needed", substeps, at_rest, needed);
    if (at_rest == 0.0 && after.info[DPSM_INFO_TIME_INTEGRATED] != dt)
        die("TIME_INTEGRATED = %.17g, dt = %.17g, not at rest", after.info[DPSM_INFO_TIME_INTEGRATED], dt);
    if (!(after.info[DPSM_INFO_MAX_EXCESS_SLOPE] >= 0.0)) die("MAX_EXCESS_SLOPE = %g", after.info[DPSM_INFO_MAX_EXCESS_SLOPE]);
    /* Found at rest: no face carried sand in the sub-step that found it. */
    if (at_rest == 1.0 && after.info[DPSM_INFO_MAX_EXCESS_SLOPE] != 0.0)
        die("MAX_EXCESS_SLOPE = %.17g at rest", after.info[DPSM_INFO_MAX_EXCESS_SLOPE]);
    compare_twin(s, &after);
    if (restored) {
        check_restart_continues(s, restored, dt, &after);
        dpsm_destroy(restored);
    }
    unsnap(&after);
    unsnap(&before);
}

/* One step relaxed to rest (dpsm_set_relaxation(g, DPSM_RELAX_TO_REST)) on
 * the grid and its twin, with at most as many flux evaluations as the work
 * budget allows, then back to time-accurate steps. Where dpsm.h says the
 * relaxation does not apply it is refused with DPSM_ERR_NOT_APPLICABLE and
 * the grid is unchanged. Otherwise it succeeds whatever dt is and either
 * integrates no time in at most the allowed evaluations, or (where the
 * relaxation would have left new extremes or lost mass to rounding) steps in
 * time to rest in at most as many sub-steps; either way, not at rest means
 * the allowance ran out. It keeps held cells, and at rest (and not driven) leaves no
 * face steeper than tan(theta) (1 + tol); the state invariants and the twin
 * are checked after every operation. */
static void op_relax(reader_t *r) {
    g_op = "dpsm_step";
    slot_t *s = pick_slot(r);
    if (!s) return;
    const unsigned b = u8(r);
    const double dt = (b & 0xe0) == 0xe0 ? kDtBad[b % COUNT(kDtBad)] : 1.0;
    const double left = kWorkBudget - g_work;
    const int64_t cap = (int64_t)fmin(fmin(1000.0, (double)s->max_substeps), floor(left / (double)s->n));
    if (cap < 1 && !extreme_mode()) return;
    const int64_t limit = cap < 1 ? 1 : cap;
    for (int k = 0; k < 2; ++k) {
        dpsm_grid *g = k == 0 ? s->g : s->twin;
        if (dpsm_set_relaxation(g, DPSM_RELAX_TO_REST) != DPSM_OK || dpsm_set_max_substeps(g, limit) != DPSM_OK)
            die("setting up the relaxation failed: %s", dpsm_last_error(g));
    }
    snap_t before;
    snap(s->g, s, &before);
    /* Held levels that differ, among open cells or from open sides' 0. */
    const int levels_differ = driven(s, before.h) && !source_active(s);
    int want = DPSM_OK;
    if (!valid_positive(dt))
        want = DPSM_ERR_INVALID_VALUE;
    else if (s->geom != GEOM_2D || s->scheme != DPSM_SCHEME_ISOTROPIC || s->bed || s->tan_field ||
             s->exponent != 1.0 || s->tan_static > 0.0 || source_active(s) || levels_differ)
        want = DPSM_ERR_NOT_APPLICABLE;
    const int st = dpsm_step(s->g, dt);
    trace("dpsm_step(%g) relaxed to rest, at most %lld evaluations, on %lld x %lld", dt, (long long)limit,
          (long long)s->nx, (long long)s->ny);
    expect_status(st, want, g_op, s->g);
    if (st != DPSM_OK) {
        check_failed(s, s->g, &before, st, g_op);
    } else {
        g_work += (double)limit * (double)s->n;
        snap_t after;
        after_step(s, dt, &before, &after);
        s->relaxed = 1; /* or, where it fell back, stepped in time: fluxes or none */
        const double evaluations = after.info[DPSM_INFO_SUBSTEPS], at_rest = after.info[DPSM_INFO_AT_REST];
        const double time = after.info[DPSM_INFO_TIME_INTEGRATED];
        if (!(time >= 0.0) || !(evaluations >= 0.0 && evaluations <= (double)limit))
            die("SUBSTEPS = %g (time %g) relaxed to rest, with at most %lld allowed", evaluations, time,
                (long long)limit);
        if (at_rest != 0.0 && at_rest != 1.0) die("AT_REST = %g", at_rest);
        if (at_rest == 1.0 && after.info[DPSM_INFO_MAX_EXCESS_SLOPE] != 0.0)
            die("MAX_EXCESS_SLOPE = %.17g at rest", after.info[DPSM_INFO_MAX_EXCESS_SLOPE]);
        if (at_rest == 0.0 && (evaluations != (double)limit || !(after.info[DPSM_INFO_MAX_EXCESS_SLOPE] >= 0.0)))
            die("not at rest after %g of %lld evaluations, largest excess %g", evaluations, (long long)limit,
                after.info[DPSM_INFO_MAX_EXCESS_SLOPE]);
        if (at_rest == 1.0 && !driven(s, after.h)) {
            const double excess = rest_excess(s, after.h);
            if (excess > 1e-12) die("relaxed to rest with a face steeper than tan(theta)(1+tol) by %.3g", excess);
        }
        compare_twin(s, &after);
        unsnap(&after);
    }
    unsnap(&before);
    for (int k = 0; k < 2; ++k) {
        dpsm_grid *g = k == 0 ? s->g : s->twin;
        if (dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE) != DPSM_OK ||
            dpsm_set_max_substeps(g, s->max_substeps) != DPSM_OK)
            die("restoring the time-accurate steps failed: %s", dpsm_last_error(g));
    }
}

/* After dpsm_set_bedrock(zb) succeeded on a grid that was `before`: every
 * cell below its bed was lifted to it, every other cell kept its height, and
 * the sand added to sand cells was booked as external mass. */
static void check_lifted_to_bed(slot_t *s, const snap_t *before, const double *zb) {
    snap_t after;
    snap(s->g, s, &after);
    double lifted = 0.0, scale = 0.0;
    for (int64_t c = 0; c < s->n; ++c) {
        const double want = before->h[c] < zb[c] ? zb[c] : before->h[c];
        if (memcmp(&after.h[c], &want, sizeof(double)) != 0)
            die("cell %lld is %.17g after a bed of %.17g under a surface at %.17g", (long long)c, after.h[c], zb[c],
                before->h[c]);
        if (s->kinds[c] == DPSM_CELL_SAND) {
            lifted += (want - before->h[c]) * cell_area(s, c);
            scale += fabs(want) * cell_area(s, c);
        }
    }
    const double booked = after.mass[DPSM_MASS_EXTERNAL] - before->mass[DPSM_MASS_EXTERNAL];
    if (fabs(booked - lifted) > 1e-12 * fmax(fmax(scale, s->mass_scale), fabs(before->mass[DPSM_MASS_EXTERNAL])))
        die("the bed lifted %.17g onto sand cells, EXTERNAL grew by %.17g", lifted, booked);
    unsnap(&after);
}

/* The physics of real scenes: a bed under the sand, an angle of repose per
 * cell, the flux exponent, the static angle. */
static void op_physics(reader_t *r) {
    slot_t *s = pick_slot(r);
    if (!s) return;
    const unsigned which = u8(r);
    switch (which % 4) {
        case 0: {
            g_op = "dpsm_set_bedrock";
            const unsigned mode = u8(r);
            if (mode % 4 == 0) {
                ON_BOTH(s, DPSM_OK, g_op, dpsm_set_bedrock(g_, NULL));
                free(s->bed);
                s->bed = NULL;
                break;
            }
            /* A bed some depth below the surface, or with one cell above it
             * (mode 0x40), which lifts that cell to it. */
            double *zb = malloc(sizeof(double) * (size_t)s->n);
            if (!zb) die("out of memory");
            const int planted = fill(r, zb, s->n, s->nx, 0);
            snap_t now;
            snap(s->g, s, &now);
            int want = planted ? DPSM_ERR_INVALID_VALUE : DPSM_OK;
            for (int64_t c = 0; c < s->n; ++c) zb[c] = now.h[c] - fabs(zb[c]);
            if ((mode & 0xc0) == 0x40) {
                const int64_t c = (int64_t)(u16(r) % (unsigned)s->n);
                if (isfinite(zb[c])) zb[c] = now.h[c] + 0.5 * fabs(now.h[c]) + 1e-3;
            }
            for (int64_t c = 0; c < s->n; ++c)
                if (!(fabs(zb[c]) <= 1e50)) want = DPSM_ERR_INVALID_VALUE;
            ON_BOTH(s, want, g_op, dpsm_set_bedrock(g_, zb));
            if (want == DPSM_OK) {
                check_lifted_to_bed(s, &now, zb);
                free(s->bed);
                s->bed = zb;
                zb = NULL;
            }
            unsnap(&now);
            free(zb);
            break;
        }
        case 1: {
            g_op = "dpsm_set_repose_angle_field";
            const unsigned mode = u8(r);
            if (mode % 4 == 0) {
                ON_BOTH(s, DPSM_OK, g_op, dpsm_set_repose_angle_field(g_, NULL));
                free(s->tan_field);
                s->tan_field = NULL;
                break;
            }
            double *theta = malloc(sizeof(double) * (size_t)s->n);
            if (!theta) die("out of memory");
            const double a = kAngles[u8(r) % COUNT(kAngles)], b = kAngles[u8(r) % COUNT(kAngles)];
            for (int64_t c = 0; c < s->n; ++c) theta[c] = (c % s->nx) * 2 < s->nx ? a : b;
            int want = DPSM_OK;
            if ((mode & 0xc0) == 0x40) {
                theta[u16(r) % (unsigned)s->n] = kAnglesBad[u8(r) % COUNT(kAnglesBad)];
                want = DPSM_ERR_INVALID_VALUE;
            }
            ON_BOTH(s, want, g_op, dpsm_set_repose_angle_field(g_, theta));
            if (want == DPSM_OK) {
                if (!s->tan_field && !(s->tan_field = malloc(sizeof(double) * (size_t)s->n))) die("out of memory");
                for (int64_t c = 0; c < s->n; ++c) s->tan_field[c] = tan(theta[c]);
            }
            free(theta);
            break;
        }
        case 2: {
            g_op = "dpsm_set_flux_exponent";
            const double p = pick(r, kExponents, COUNT(kExponents), kExponentsBad, COUNT(kExponentsBad));
            const int ok = p >= 1.0 && p <= DPSM_MAX_FLUX_EXPONENT;
            ON_BOTH(s, ok ? DPSM_OK : DPSM_ERR_INVALID_VALUE, g_op, dpsm_set_flux_exponent(g_, p));
            if (ok) s->exponent = p;
            break;
        }
        default: {
            g_op = "dpsm_set_static_angle";
            const double v = pick(r, kAngles, COUNT(kAngles), kAnglesBad, COUNT(kAnglesBad));
            const int ok = isfinite(v) && v > 0.0 && v < 0.5 * 3.14159265358979323846;
            ON_BOTH(s, ok ? DPSM_OK : DPSM_ERR_INVALID_VALUE, g_op, dpsm_set_static_angle(g_, v));
            if (ok) s->tan_static = tan(v);
            break;
        }
    }
}

/* What a host couples: the levels beyond a side (refused for unknown sides,
 * sides the grid does not have, levels not finite or out of range), what left
 * through a side, the recording of face fluxes and their reader (refused for
 * NULL or extra arrays, recording off, after a relaxation to rest). */
static void op_coupling(reader_t *r) {
    slot_t *s = pick_slot(r);
    if (!s) return;
    const unsigned which = u8(r), b = u8(r);
    const int side = (int)(b % 6) - 1;
    const int known = side >= DPSM_XMIN && side <= DPSM_YMAX;
    /* DPSM_MESH_EDGE is a side of meshes only. */
    const int side_status = side == DPSM_MESH_EDGE ? DPSM_ERR_NOT_APPLICABLE
                            : !known               ? DPSM_ERR_UNKNOWN_ENUM
                            : has_side(s, side)    ? DPSM_OK
                                                   : DPSM_ERR_NOT_APPLICABLE;
    switch (which % 4) {
        case 0: {
            g_op = "dpsm_set_side_levels";
            const int64_t n = known ? faces_along(s, side) : 1;
            double *levels = NULL;
            int want = side_status;
            if (u8(r) % 4 != 0) {
                if (!(levels = malloc(sizeof(double) * (size_t)n))) die("out of memory");
                const int planted = fill(r, levels, n, n, 0);
                for (int64_t k = 0; k < n; ++k)
                    if (want == DPSM_OK && (planted || !(fabs(levels[k]) <= 1e50))) want = DPSM_ERR_INVALID_VALUE;
            }
            ON_BOTH(s, want, g_op, dpsm_set_side_levels(g_, side, levels));
            if (want == DPSM_OK) {
                free(s->levels[side]);
                s->levels[side] = levels;
                levels = NULL;
            }
            free(levels);
            break;
        }
        case 1: {
            g_op = "dpsm_get_side_outflow";
            double value = 0.0;
            const int null_out = (b & 0x80) != 0;
            ON_BOTH(s, null_out ? DPSM_ERR_NULL_POINTER : side_status, g_op,
                    dpsm_get_side_outflow(g_, side, null_out ? NULL : &value));
            break;
        }
        case 2: {
            g_op = "dpsm_set_face_flux_recording";
            static const int values[] = {0, 1, 1, 2, -1, INT32_MAX};
            const int on = values[b % COUNT(values)];
            ON_BOTH(s, on == 0 || on == 1 ? DPSM_OK : DPSM_ERR_INVALID_VALUE, g_op, dpsm_set_face_flux_recording(g_, on));
            if (on == 0) s->record = 0;
            if (on == 1 && !s->record) s->record = 1, s->relaxed = 0;
            break;
        }
        default: {
            g_op = "dpsm_get_face_fluxes";
            double *fx = malloc(sizeof(double) * (size_t)((s->nx + 1) * s->ny));
            double *fy = malloc(sizeof(double) * (size_t)(s->nx * (s->ny + 1)));
            if (!fx || !fy) die("out of memory");
            /* b % 3: the arrays the grid takes; 1: no fx; 2: the other fy (none in 2D, one on a line). */
            const int two_d = s->geom == GEOM_2D, variant = (int)(b % 3);
            double *x = variant == 1 ? NULL : fx, *y = (variant == 2) == two_d ? NULL : fy;
            int want = DPSM_OK;
            if (!x || (two_d && !y)) want = DPSM_ERR_NULL_POINTER;
            else if (!two_d && y) want = DPSM_ERR_INVALID_VALUE;
            else if (!s->record) want = DPSM_ERR_NOT_APPLICABLE;
            snap_t now;
            snap(s->g, s, &now);
            if (want == DPSM_OK && s->relaxed) want = now.fluxes_status; /* relaxed, or fell back to steps */
            ON_BOTH(s, want, g_op, dpsm_get_face_fluxes(g_, x, y));
            if (want == DPSM_OK &&
                (memcmp(fx, now.fx, sizeof(double) * (size_t)((s->nx + 1) * s->ny)) != 0 ||
                 (two_d && memcmp(fy, now.fy, sizeof(double) * (size_t)(s->nx * (s->ny + 1))) != 0)))
                die("two reads of the face fluxes differ");
            unsnap(&now);
            free(fx);
            free(fy);
            break;
        }
    }
}

static void op_getters(reader_t *r) {
    g_op = "getters";
    slot_t *s = pick_slot(r);
    if (!s) return;
    const unsigned b = u8(r);
    snap_t before;
    snap(s->g, s, &before);
    double value = 0.0;
    int st;
    switch (b % 6) {
        case 0: {
            g_op = "dpsm_get_mass";
            static const int quantities[] = {-1, 0, 1, 2, 3, 4, 1000, INT32_MIN};
            const int q = quantities[u8(r) % COUNT(quantities)];
            const int null_out = (b & 0x80) != 0;
            st = dpsm_get_mass(s->g, q, null_out ? NULL : &value);
            expect_status(st, null_out ? DPSM_ERR_NULL_POINTER : (q >= 0 && q <= DPSM_MASS_UNMET) ? DPSM_OK : DPSM_ERR_UNKNOWN_ENUM,
                          g_op, s->g);
            break;
        }
        case 1: {
            g_op = "dpsm_get_step_info";
            static const int items[] = {-1, 0, 1, 2, 3, NINFO - 1, NINFO, 1000, INT32_MIN};
            const int item = items[u8(r) % COUNT(items)];
            const int null_out = (b & 0x80) != 0;
            st = dpsm_get_step_info(s->g, item, null_out ? NULL : &value);
            expect_status(st,
                          null_out                         ? DPSM_ERR_NULL_POINTER
                          : (item >= 0 && item < NINFO) ? DPSM_OK
                                                           : DPSM_ERR_UNKNOWN_ENUM,
                          g_op, s->g);
            break;
        }
        case 2: {
            g_op = "dpsm_get_shape";
            int64_t nx, ny;
            const unsigned which = u8(r) % 3;
            st = dpsm_get_shape(s->g, which == 1 ? NULL : &nx, which == 2 ? NULL : &ny);
            expect_status(st, which ? DPSM_ERR_NULL_POINTER : DPSM_OK, g_op, s->g);
            break;
        }
        case 3:
            g_op = "dpsm_stable_dt";
            st = dpsm_stable_dt(s->g, NULL);
            expect_status(st, DPSM_ERR_NULL_POINTER, g_op, s->g);
            break;
        case 4:
            g_op = "dpsm_get_heights";
            st = dpsm_get_heights(s->g, NULL);
            expect_status(st, DPSM_ERR_NULL_POINTER, g_op, s->g);
            break;
        default:
            g_op = "dpsm_get_heights_region";
            st = dpsm_get_heights_region(s->g, 0, 0, 1, 1, NULL);
            expect_status(st, DPSM_ERR_NULL_POINTER, g_op, s->g);
            break;
    }
    if (st != DPSM_OK) check_failed(s, s->g, &before, st, g_op);
    unsnap(&before);
}

/* Every function with a NULL grid; the version and status strings. */
static void op_null_grid(reader_t *r) {
    g_op = "NULL grid";
    const unsigned b = u8(r);
    double d = 0.0, h[1] = {0.0};
    int64_t a, c;
    int st;
    const char *fn;
    switch (b >= kLaterOps ? 25 + (b - kLaterOps) % 6 : b % 25) {
        case 0: st = dpsm_set_repose_angle(NULL, 0.5), fn = "dpsm_set_repose_angle"; break;
        case 1: st = dpsm_set_mobility(NULL, 1.0), fn = "dpsm_set_mobility"; break;
        case 2: st = dpsm_set_scheme(NULL, 0), fn = "dpsm_set_scheme"; break;
        case 3: st = dpsm_set_boundary(NULL, 0, 0), fn = "dpsm_set_boundary"; break;
        case 4: st = dpsm_set_cell_kinds(NULL, NULL), fn = "dpsm_set_cell_kinds"; break;
        case 5: st = dpsm_set_heights(NULL, h), fn = "dpsm_set_heights"; break;
        case 6: st = dpsm_get_heights(NULL, h), fn = "dpsm_get_heights"; break;
        case 7: st = dpsm_set_heights_region(NULL, 0, 0, 1, 1, h), fn = "dpsm_set_heights_region"; break;
        case 8: st = dpsm_add_heights_region(NULL, 0, 0, 1, 1, h), fn = "dpsm_add_heights_region"; break;
        case 9: st = dpsm_get_heights_region(NULL, 0, 0, 1, 1, h), fn = "dpsm_get_heights_region"; break;
        case 10: st = dpsm_set_source(NULL, NULL), fn = "dpsm_set_source"; break;
        case 11: st = dpsm_stable_dt(NULL, &d), fn = "dpsm_stable_dt"; break;
        case 12: st = dpsm_step(NULL, 1.0), fn = "dpsm_step"; break;
        case 13: st = dpsm_get_mass(NULL, 0, &d), fn = "dpsm_get_mass"; break;
        case 14: st = dpsm_get_step_info(NULL, 0, &d), fn = "dpsm_get_step_info"; break;
        case 15: st = dpsm_get_shape(NULL, &a, &c), fn = "dpsm_get_shape"; break;
        case 16: st = dpsm_set_rest_tolerance(NULL, 1e-6), fn = "dpsm_set_rest_tolerance"; break;
        case 17: st = dpsm_set_max_substeps(NULL, 10), fn = "dpsm_set_max_substeps"; break;
        case 18: st = dpsm_set_threads(NULL, 1), fn = "dpsm_set_threads"; break;
        case 19: st = dpsm_set_bedrock(NULL, NULL), fn = "dpsm_set_bedrock"; break;
        case 20: st = dpsm_set_repose_angle_field(NULL, NULL), fn = "dpsm_set_repose_angle_field"; break;
        case 21: st = dpsm_set_flux_exponent(NULL, 1.0), fn = "dpsm_set_flux_exponent"; break;
        case 22: st = dpsm_set_static_angle(NULL, 0.6), fn = "dpsm_set_static_angle"; break;
        case 23: st = dpsm_set_relaxation(NULL, DPSM_RELAX_TO_REST), fn = "dpsm_set_relaxation"; break;
        case 25: st = dpsm_set_side_levels(NULL, DPSM_XMIN, NULL), fn = "dpsm_set_side_levels"; break;
        case 26: st = dpsm_get_side_outflow(NULL, DPSM_XMIN, &d), fn = "dpsm_get_side_outflow"; break;
        case 27: st = dpsm_set_face_flux_recording(NULL, 1), fn = "dpsm_set_face_flux_recording"; break;
        case 28: st = dpsm_get_face_fluxes(NULL, h, NULL), fn = "dpsm_get_face_fluxes"; break;
        case 29: {
            int n = 0;
            if (dpsm_get_grid_kind(NULL, &n) != DPSM_ERR_NULL_POINTER ||
                !strstr(dpsm_last_error(NULL), "dpsm_get_grid_kind"))
                die("dpsm_get_grid_kind(NULL) was not refused naming itself: \"%s\"", dpsm_last_error(NULL));
            st = dpsm_get_threads(NULL, &n), fn = "dpsm_get_threads";
            break;
        }
        case 30: {
            double xy[2] = {0.0, 0.0};
            st = dpsm_get_cell_centres(NULL, xy, h), fn = "dpsm_get_cell_centres";
            break;
        }
        default: {
            dpsm_destroy(NULL);
            const int code = (int)(int8_t)u8(r);
            const char *name = dpsm_status_string(code);
            if (!name || !*name) die("dpsm_status_string(%d) is empty", code);
            if (!dpsm_version_string() || dpsm_version_number() != DPSM_VERSION_NUMBER) die("version mismatch");
            return;
        }
    }
    expect_status(st, DPSM_ERR_NULL_POINTER, fn, NULL);
    check_failed(NULL, NULL, NULL, st, fn);
}

static void op_destroy(reader_t *r) {
    g_op = "dpsm_destroy";
    slot_t *s = pick_slot(r);
    if (s) destroy_slot(s);
}

/* ------------------------------------------------------------------------ */
/* Meshes                                                                    */
/* ------------------------------------------------------------------------ */

/* op_mesh (opcode kMeshOp): a mesh of its own, built, exercised and destroyed
 * within the operation (it takes no slot). Its bytes:
 *
 *   kind      % 3: dpsm_create_mesh, dpsm_create_graph, dpsm_create_dual_mesh;
 *             / 3 % 3: a lattice of quads, of triangles, or of both mixed
 *             (the dual always takes triangles); / 9 % 3, the numbering:
 *             0 those constructors, from 0; 1 their _indexed forms with
 *             start_index 1 on the arrays shifted to count from 1 (the
 *             domain edge 0), 2 their _indexed forms with start_index 0
 *   nx, ny    2 + b % 7 squares a side
 *   dx, dy    kMeshSpacings[b % 5]
 *   jitter    (b % 5) * 0.06 of the spacing, each node (below 1/4: every
 *             cell stays convex and well shaped)
 *   seed      u16: the generator of the jitter, of the diagonals, of each
 *             polygon's orientation and first node, of a graph's face order
 *             and of the defect's place
 *   defect    b >= 0xc0: plant defect (b & 0x3f) % n (mesh_construct lists
 *             them), which the constructor must refuse with the exact status
 *             and *out NULL; otherwise the mesh must be made
 *   nops      b % 16: the operations on the mesh that follow (none on a
 *             refused one), each an opcode byte (% 10, see mesh_operation)
 *             and its arguments.
 *
 * A made mesh must have the shape (ncells, 1) and the faces this harness
 * derives from what it gave (for polygons: in order of first appearance,
 * cell by cell, edge by edge; a graph's faces as given; the dual's by node
 * pair, then the halves of the boundary edges), from 1 with 0 on the domain
 * edge when made from 1. With numbering 1 or 2 a twin made by the plain
 * constructor from 0 takes every call that succeeds on the mesh and must
 * match it bit for bit after every operation (heights, ledger, edge outflow,
 * stable step); with numbering 1 the _indexed constructor must first refuse
 * a start index other than 0 and 1 (kBadStarts[seed % 4]) with
 * DPSM_ERR_INVALID_VALUE and *out NULL, and a mesh loaded from a restart file
 * must list its faces from 1 too. Its cell areas (shoelace; a
 * third of each node's triangles for the dual) must make up DPSM_MASS_TOTAL.
 * After every operation: heights finite, the ledger closes to 1e-9 of the
 * largest mass seen. After every step: held cells unchanged; without a
 * source and with every held level equal (open edge faces, open cells) no
 * sand cell leaves the range of the sand and the held levels before it;
 * with face fluxes recorded, each sand cell's faces bring its change of
 * height times its area less its source (to 1e-9 of the largest face
 * volume), wall cells' faces and wall edge faces carry nothing, the open edge
 * faces carry what dpsm_get_side_outflow(DPSM_MESH_EDGE) booked, and with the
 * open cells make up OUTFLOW; where the step's byte asks, a copy through
 * dpsm_save/dpsm_load takes the same step to bit-identical heights and
 * ledger. A step of a scene that may flow for ever (a source on a sand cell,
 * held levels that differ) needing more sub-steps than the limit must fail
 * with DPSM_ERR_WORK_LIMIT and change nothing. */
enum { kMeshOp = 251 };
enum { MESH_POLYGONS = 0, MESH_GRAPH = 1, MESH_DUAL = 2 };
#define MESH_MAX_SUBSTEPS 20000

static const double kMeshSpacings[] = {1.0, 0.5, 2.0, 0.25, 4.0};
static const double kMeshHeights[] = {0.0, 1.0, 3.0, 10.0, -1.0, 0.5, 30.0, 100.0, -3.0, 1e3, 0.25, 7.0};
static const double kMeshSources[] = {0.0, 1e-3, -1e-3, 0.1, -0.1, 1.0, 0.0, 1e-9};

/* A mesh as this harness built it, in the host's numbering. */
typedef struct {
    int kind;
    int64_t nnodes;
    double *node_xy;
    int64_t npoly;                    /* the lattice's polygons (the dual's triangles) */
    int64_t *poly_start, *poly_nodes; /* CSR, as given to dpsm_create_mesh */
    int64_t ncells;
    double *area, *cx, *cy;           /* per cell */
    int64_t nfaces;
    int64_t *face_cells;              /* the faces the library must list */
    double *face_xy, *face_length;    /* graph: as given */
} mesh_t;

static void mesh_free(mesh_t *m) {
    free(m->node_xy);
    free(m->poly_start);
    free(m->poly_nodes);
    free(m->area);
    free(m->cx);
    free(m->cy);
    free(m->face_cells);
    free(m->face_xy);
    free(m->face_length);
    memset(m, 0, sizeof *m);
}

/* Twice the signed area of polygon k, and its centroid. */
static double polygon_geometry(const mesh_t *m, int64_t k, double *gx, double *gy) {
    const int64_t k0 = m->poly_start[k], count = m->poly_start[k + 1] - k0;
    const double ox = m->node_xy[2 * m->poly_nodes[k0]], oy = m->node_xy[2 * m->poly_nodes[k0] + 1];
    double twice = 0.0, mx = 0.0, my = 0.0;
    for (int64_t e = 0; e < count; ++e) {
        const int64_t u = m->poly_nodes[k0 + e], v = m->poly_nodes[k0 + (e + 1) % count];
        const double px = m->node_xy[2 * u] - ox, py = m->node_xy[2 * u + 1] - oy;
        const double qx = m->node_xy[2 * v] - ox, qy = m->node_xy[2 * v + 1] - oy;
        const double w = px * qy - py * qx;
        twice += w;
        mx += w / 3.0 * (px + qx);
        my += w / 3.0 * (py + qy);
    }
    *gx = ox + mx / twice;
    *gy = oy + my / twice;
    return twice;
}

/* The jittered lattice and its polygons: quads, triangles (either diagonal)
 * or both, each polygon in either orientation and from any first node. */
static void mesh_build(mesh_t *m, int kind, int lattice, int64_t nx, int64_t ny, double dx, double dy, double jitter,
                       prng_t *p) {
    memset(m, 0, sizeof *m);
    m->kind = kind;
    const int64_t nxn = nx + 1, nyn = ny + 1;
    m->nnodes = nxn * nyn;
    m->node_xy = xcalloc((size_t)(2 * m->nnodes), sizeof(double));
    for (int64_t j = 0; j < nyn; ++j)
        for (int64_t i = 0; i < nxn; ++i) {
            const int64_t n = i + nxn * j;
            m->node_xy[2 * n] = ((double)i + jitter * (2.0 * prng_unit(p) - 1.0)) * dx;
            m->node_xy[2 * n + 1] = ((double)j + jitter * (2.0 * prng_unit(p) - 1.0)) * dy;
        }
    m->poly_start = xcalloc((size_t)(2 * nx * ny + 1), sizeof(int64_t));
    m->poly_nodes = xcalloc((size_t)(6 * nx * ny), sizeof(int64_t));
    int64_t np = 0, at = 0;
    for (int64_t j = 0; j < ny; ++j)
        for (int64_t i = 0; i < nx; ++i) {
            const int64_t n00 = i + nxn * j, n10 = n00 + 1, n01 = n00 + nxn, n11 = n01 + 1;
            const int quad = kind != MESH_DUAL && (lattice == 0 || (lattice == 2 && prng_below(p, 2)));
            int64_t v[2][4];
            int counts[2], pieces;
            if (quad) {
                pieces = 1, counts[0] = 4;
                v[0][0] = n00, v[0][1] = n10, v[0][2] = n11, v[0][3] = n01;
            } else if (prng_below(p, 2)) {
                pieces = 2, counts[0] = counts[1] = 3;
                v[0][0] = n00, v[0][1] = n10, v[0][2] = n11;
                v[1][0] = n00, v[1][1] = n11, v[1][2] = n01;
            } else {
                pieces = 2, counts[0] = counts[1] = 3;
                v[0][0] = n00, v[0][1] = n10, v[0][2] = n01;
                v[1][0] = n10, v[1][1] = n11, v[1][2] = n01;
            }
            for (int k = 0; k < pieces; ++k) {
                const int c = counts[k], reverse = prng_below(p, 4) == 0, first = (int)prng_below(p, (unsigned)c);
                for (int e = 0; e < c; ++e) {
                    const int s = reverse ? (first - e + 2 * c) % c : (first + e) % c;
                    m->poly_nodes[at++] = v[k][s];
                }
                m->poly_start[++np] = at;
            }
        }
    m->npoly = np;
}

/* A face map over node pairs: index + 1 of the face of edge (lo, hi), 0: none. */
static int64_t *edge_slot(int64_t *map, int64_t nnodes, int64_t u, int64_t v) {
    const int64_t lo = u < v ? u : v, hi = u < v ? v : u;
    return &map[lo * nnodes + hi];
}

/* The cells, areas and faces the library must find. */
static void mesh_derive(mesh_t *m, prng_t *p) {
    int64_t *map = xcalloc((size_t)(m->nnodes * m->nnodes), sizeof(int64_t));
    if (m->kind != MESH_DUAL) {
        m->ncells = m->npoly;
        m->area = xcalloc((size_t)m->ncells, sizeof(double));
        m->cx = xcalloc((size_t)m->ncells, sizeof(double));
        m->cy = xcalloc((size_t)m->ncells, sizeof(double));
        m->face_cells = xcalloc((size_t)(2 * m->poly_start[m->npoly]), sizeof(int64_t));
        m->face_xy = xcalloc((size_t)(2 * m->poly_start[m->npoly]), sizeof(double));
        m->face_length = xcalloc((size_t)m->poly_start[m->npoly], sizeof(double));
        for (int64_t c = 0; c < m->ncells; ++c) {
            m->area[c] = 0.5 * fabs(polygon_geometry(m, c, &m->cx[c], &m->cy[c]));
            const int64_t k0 = m->poly_start[c], count = m->poly_start[c + 1] - k0;
            for (int64_t e = 0; e < count; ++e) {
                const int64_t u = m->poly_nodes[k0 + e], v = m->poly_nodes[k0 + (e + 1) % count];
                int64_t *slot = edge_slot(map, m->nnodes, u, v);
                if (*slot) {
                    m->face_cells[2 * (*slot - 1) + 1] = c;
                    continue;
                }
                const int64_t f = m->nfaces++;
                *slot = f + 1;
                m->face_cells[2 * f] = c, m->face_cells[2 * f + 1] = -1;
                const double ux = m->node_xy[2 * u], uy = m->node_xy[2 * u + 1];
                const double vx = m->node_xy[2 * v], vy = m->node_xy[2 * v + 1];
                m->face_xy[2 * f] = 0.5 * (ux + vx), m->face_xy[2 * f + 1] = 0.5 * (uy + vy);
                m->face_length[f] = hypot(vx - ux, vy - uy);
            }
        }
        if (m->kind == MESH_GRAPH) {
            /* The host's own order: faces shuffled, interior faces either way round. */
            for (int64_t f = m->nfaces - 1; f > 0; --f) {
                const int64_t g = (int64_t)prng_below(p, (unsigned)(f + 1));
                int64_t tc[2] = {m->face_cells[2 * f], m->face_cells[2 * f + 1]};
                double txy[2] = {m->face_xy[2 * f], m->face_xy[2 * f + 1]}, tl = m->face_length[f];
                m->face_cells[2 * f] = m->face_cells[2 * g], m->face_cells[2 * f + 1] = m->face_cells[2 * g + 1];
                m->face_xy[2 * f] = m->face_xy[2 * g], m->face_xy[2 * f + 1] = m->face_xy[2 * g + 1];
                m->face_length[f] = m->face_length[g];
                m->face_cells[2 * g] = tc[0], m->face_cells[2 * g + 1] = tc[1];
                m->face_xy[2 * g] = txy[0], m->face_xy[2 * g + 1] = txy[1];
                m->face_length[g] = tl;
            }
            for (int64_t f = 0; f < m->nfaces; ++f)
                if (m->face_cells[2 * f + 1] >= 0 && prng_below(p, 2)) {
                    const int64_t t = m->face_cells[2 * f];
                    m->face_cells[2 * f] = m->face_cells[2 * f + 1], m->face_cells[2 * f + 1] = t;
                }
        }
    } else {
        /* One cell per node, a third of each of its triangles; faces by node
         * pair, then each boundary edge's two halves, the lower node's first. */
        m->ncells = m->nnodes;
        m->area = xcalloc((size_t)m->ncells, sizeof(double));
        m->cx = xcalloc((size_t)m->ncells, sizeof(double));
        m->cy = xcalloc((size_t)m->ncells, sizeof(double));
        for (int64_t n = 0; n < m->nnodes; ++n) m->cx[n] = m->node_xy[2 * n], m->cy[n] = m->node_xy[2 * n + 1];
        for (int64_t t = 0; t < m->npoly; ++t) {
            const int64_t *v = m->poly_nodes + 3 * t;
            const double px = m->node_xy[2 * v[0]], py = m->node_xy[2 * v[0] + 1];
            const double qx = m->node_xy[2 * v[1]] - px, qy = m->node_xy[2 * v[1] + 1] - py;
            const double rx = m->node_xy[2 * v[2]] - px, ry = m->node_xy[2 * v[2] + 1] - py;
            const double area = 0.5 * fabs(qx * ry - qy * rx);
            for (int k = 0; k < 3; ++k) {
                m->area[v[k]] += area / 3.0;
                ++*edge_slot(map, m->nnodes, v[k], v[(k + 1) % 3]);
            }
        }
        int64_t edges = 0, boundary = 0;
        for (int64_t k = 0; k < m->nnodes * m->nnodes; ++k)
            if (map[k]) ++edges, boundary += map[k] == 1;
        m->face_cells = xcalloc((size_t)(2 * (edges + 2 * boundary)), sizeof(int64_t));
        for (int64_t lo = 0; lo < m->nnodes; ++lo)
            for (int64_t hi = lo + 1; hi < m->nnodes; ++hi)
                if (map[lo * m->nnodes + hi]) {
                    m->face_cells[2 * m->nfaces] = lo, m->face_cells[2 * m->nfaces + 1] = hi;
                    ++m->nfaces;
                }
        for (int64_t lo = 0; lo < m->nnodes; ++lo)
            for (int64_t hi = lo + 1; hi < m->nnodes; ++hi)
                if (map[lo * m->nnodes + hi] == 1) {
                    m->face_cells[2 * m->nfaces] = lo, m->face_cells[2 * m->nfaces + 1] = -1;
                    m->face_cells[2 * m->nfaces + 2] = hi, m->face_cells[2 * m->nfaces + 3] = -1;
                    m->nfaces += 2;
                }
    }
    free(map);
}

static const char *const kMeshFunctions[] = {"dpsm_create_mesh", "dpsm_create_graph", "dpsm_create_dual_mesh"};
static const char *const kIndexedFunctions[] = {"dpsm_create_mesh_indexed", "dpsm_create_graph_indexed",
                                                "dpsm_create_dual_mesh_indexed"};
static const int kBadStarts[] = {2, -1, INT_MAX, INT_MIN};

/* The n index values of v (NULL: none) counted from 1 instead of 0 (the
 * domain edge's -1 becomes 0); the extremes stay, out of range either way. */
static void count_from_one(int64_t *v, size_t n) {
    if (!v) return;
    for (size_t k = 0; k < n; ++k)
        if (v[k] != INT64_MIN && v[k] != INT64_MAX) ++v[k];
}

/* Calls the constructor on a copy of the mesh's arrays with defect `defect`
 * planted (-1: none): the plain one (indexed 0) or its _indexed form with
 * `start_index`, on the arrays counted from 1 unless start_index is 0.
 * Returns the status; *want receives the one expected. */
static int mesh_construct(const mesh_t *m, int defect, prng_t *p, dpsm_grid **grid, int *want, const char **what,
                          int indexed, int start_index) {
    const int64_t total = m->poly_start[m->npoly];
    /* Room for one more polygon or node (the defects that add one). */
    double *xy = xcalloc((size_t)(2 * m->nnodes + 2), sizeof(double));
    memcpy(xy, m->node_xy, sizeof(double) * (size_t)(2 * m->nnodes));
    int64_t *start = xcalloc((size_t)(m->npoly + 2), sizeof(int64_t));
    memcpy(start, m->poly_start, sizeof(int64_t) * (size_t)(m->npoly + 1));
    int64_t *nodes = xcalloc((size_t)(total + 4), sizeof(int64_t));
    memcpy(nodes, m->poly_nodes, sizeof(int64_t) * (size_t)total);
    int64_t nnodes = m->nnodes, npoly = m->npoly, ncells = m->ncells, nfaces = m->nfaces;
    double *cell_xy = xcalloc((size_t)(2 * m->ncells), sizeof(double)), *area = xcalloc((size_t)m->ncells, sizeof(double));
    for (int64_t c = 0; c < m->ncells; ++c) cell_xy[2 * c] = m->cx[c], cell_xy[2 * c + 1] = m->cy[c], area[c] = m->area[c];
    int64_t *fc = xcalloc((size_t)(2 * m->nfaces), sizeof(int64_t));
    memcpy(fc, m->face_cells, sizeof(int64_t) * (size_t)(2 * m->nfaces));
    double *fxy = NULL, *flen = NULL;
    if (m->kind == MESH_GRAPH) {
        fxy = xcalloc((size_t)(2 * m->nfaces), sizeof(double));
        flen = xcalloc((size_t)m->nfaces, sizeof(double));
        memcpy(fxy, m->face_xy, sizeof(double) * (size_t)(2 * m->nfaces));
        memcpy(flen, m->face_length, sizeof(double) * (size_t)m->nfaces);
    }
    static const double kBadCoordinates[] = {NAN, INFINITY, -INFINITY, 1e51};
    const int64_t cell = (int64_t)prng_below(p, (unsigned)(m->kind == MESH_DUAL ? m->npoly : m->ncells));
    const int64_t k0 = start[cell], count = start[cell + 1] - k0; /* polygon (triangle) `cell` */
    int null_out = 0;
    *want = DPSM_OK;
    *what = "none";
    if (defect >= 0 && m->kind == MESH_POLYGONS) {
        *want = DPSM_ERR_INVALID_VALUE;
        switch (defect % 11) {
            case 0: *what = "node index out of range"; nodes[k0 + prng_below(p, (unsigned)count)] = prng_below(p, 2) ? nnodes : -1; break;
            case 1: /* a b a (b): two distinct nodes */
                *what = "fewer than 3 distinct nodes";
                for (int64_t e = 2; e < count; ++e) nodes[k0 + e] = nodes[k0 + e - 2];
                break;
            case 2: *what = "a cell of 2 nodes in cell_start"; start[1] = 2; break;
            case 3: { /* every node of the cell on one line */
                *what = "collinear nodes";
                const double ox = xy[2 * nodes[k0]], oy = xy[2 * nodes[k0] + 1];
                const double ux = 0.3 + prng_unit(p), uy = prng_unit(p) - 0.5;
                for (int64_t e = 1; e < count; ++e) xy[2 * nodes[k0 + e]] = ox + (double)e * ux, xy[2 * nodes[k0 + e] + 1] = oy + (double)e * uy;
                break;
            }
            case 4: *what = "a coordinate not finite or out of range"; xy[prng_below(p, (unsigned)(2 * nnodes))] = kBadCoordinates[prng_below(p, 4)]; break;
            case 5: *what = "cell_start[0] not the start index"; start[0] = prng_below(p, 2) ? 1 : -1; break;
            case 6: /* the cell again: its interior edges then belong to 3 cells */
                *what = "an edge of 3 cells";
                for (int64_t e = 0; e < count; ++e) nodes[total + e] = nodes[k0 + e];
                start[npoly + 1] = total + count;
                ++npoly;
                break;
            case 7: *what = "a node repeated in consecutive places"; nodes[k0 + 1] = nodes[k0]; break;
            case 8: *what = "a count below 1"; *want = DPSM_ERR_INVALID_SIZE; if (prng_below(p, 2)) nnodes = 0; else npoly = -(int64_t)prng_below(p, 2); break;
            case 9: *what = "a NULL array"; *want = DPSM_ERR_NULL_POINTER; switch (prng_below(p, 3)) { case 0: free(xy); xy = NULL; break; case 1: free(start); start = NULL; break; default: free(nodes); nodes = NULL; } break;
            default: *what = "a NULL out"; *want = DPSM_ERR_NULL_POINTER; null_out = 1; break;
        }
    } else if (defect >= 0 && m->kind == MESH_GRAPH) {
        *want = DPSM_ERR_INVALID_VALUE;
        const int64_t f = (int64_t)prng_below(p, (unsigned)nfaces);
        int64_t interior = -1; /* an interior face from f on */
        for (int64_t k = 0; k < nfaces && interior < 0; ++k)
            if (fc[2 * ((f + k) % nfaces) + 1] >= 0) interior = (f + k) % nfaces;
        switch (defect % 11) {
            case 0: *what = "a face joining a cell to itself"; fc[2 * f + 1] = fc[2 * f]; break;
            case 1: {
                *what = "a face cell out of range";
                static const int64_t wild[] = {-1, -2, 0, INT64_MIN, INT64_MAX};
                const unsigned w = prng_below(p, 5);
                if (w == 0) fc[2 * f] = -1;
                else if (w == 1) fc[2 * f + 1] = -2;
                else if (w == 2) fc[2 * f + prng_below(p, 2)] = ncells;
                else fc[2 * f] = wild[w];
                break;
            }
            case 2: { static const double bad[] = {0.0, -0.0, -1.0, NAN, INFINITY, 1e51}; *what = "a bad face length"; flen[f] = bad[prng_below(p, 6)]; break; }
            case 3: { static const double bad[] = {0.0, -0.0, -1.0, NAN, INFINITY, 1e51}; *what = "a bad cell area"; area[prng_below(p, (unsigned)ncells)] = bad[prng_below(p, 6)]; break; }
            case 4: {
                *what = "coincident centres";
                const int64_t a = fc[2 * interior], b = fc[2 * interior + 1];
                cell_xy[2 * b] = cell_xy[2 * a], cell_xy[2 * b + 1] = cell_xy[2 * a + 1];
                break;
            }
            case 5: { /* cell 0 (a corner) without its faces on the domain edge */
                *what = "a cell its faces do not close";
                int64_t kept = 0;
                for (int64_t k = 0; k < nfaces; ++k) {
                    if ((fc[2 * k] == 0 && fc[2 * k + 1] < 0) || (fc[2 * k + 1] == 0 && fc[2 * k] < 0)) continue;
                    fc[2 * kept] = fc[2 * k], fc[2 * kept + 1] = fc[2 * k + 1];
                    fxy[2 * kept] = fxy[2 * k], fxy[2 * kept + 1] = fxy[2 * k + 1], flen[kept] = flen[k];
                    ++kept;
                }
                nfaces = kept;
                break;
            }
            case 6:
                *what = "a coordinate not finite or out of range";
                if (prng_below(p, 2)) cell_xy[prng_below(p, (unsigned)(2 * ncells))] = kBadCoordinates[prng_below(p, 4)];
                else fxy[prng_below(p, (unsigned)(2 * nfaces))] = kBadCoordinates[prng_below(p, 4)];
                break;
            case 7: { /* an edge face with its midpoint at its cell's centre */
                int64_t e = -1;
                for (int64_t k = 0; k < nfaces && e < 0; ++k)
                    if (fc[2 * ((f + k) % nfaces) + 1] < 0) e = (f + k) % nfaces;
                fxy[2 * e] = cell_xy[2 * fc[2 * e]], fxy[2 * e + 1] = cell_xy[2 * fc[2 * e] + 1];
                /* A triangle's centre may lie on its face on the domain edge
                 * (a right triangle's circumcentre, as Delft3D FM writes it):
                 * made, the face facing the gap its other faces leave; any
                 * other cell's is refused. */
                int64_t faces_of_cell = 0;
                for (int64_t k = 0; k < nfaces; ++k) faces_of_cell += fc[2 * k] == fc[2 * e] || fc[2 * k + 1] == fc[2 * e];
                *what = faces_of_cell == 3 ? "an edge face at its triangle's centre (accepted)"
                                           : "an edge face at its cell's centre";
                if (faces_of_cell == 3) *want = DPSM_OK;
                break;
            }
            case 8: *what = "a count below 1"; *want = DPSM_ERR_INVALID_SIZE; if (prng_below(p, 2)) ncells = 0; else nfaces = -(int64_t)prng_below(p, 2); break;
            case 9: {
                *what = "a NULL array";
                *want = DPSM_ERR_NULL_POINTER;
                switch (prng_below(p, 5)) {
                    case 0: free(cell_xy); cell_xy = NULL; break;
                    case 1: free(area); area = NULL; break;
                    case 2: free(fc); fc = NULL; break;
                    case 3: free(fxy); fxy = NULL; break;
                    default: free(flen); flen = NULL; break;
                }
                break;
            }
            default: *what = "a NULL out"; *want = DPSM_ERR_NULL_POINTER; null_out = 1; break;
        }
    } else if (defect >= 0) {
        *want = DPSM_ERR_INVALID_VALUE;
        int64_t *tri = nodes + 3 * cell;
        switch (defect % 9) {
            case 0: {
                *what = "a triangle with a repeated node";
                const unsigned k = prng_below(p, 3);
                tri[k] = tri[(k + 1 + prng_below(p, 2)) % 3];
                break;
            }
            case 1: /* a node no triangle names */
                *what = "a node in no triangle";
                xy[2 * nnodes] = -1.0 - prng_unit(p), xy[2 * nnodes + 1] = -1.0;
                ++nnodes;
                break;
            case 2: *what = "node index out of range"; tri[prng_below(p, 3)] = prng_below(p, 2) ? nnodes : -1; break;
            case 3: /* the third node on the line of the other two */
                *what = "collinear nodes";
                xy[2 * tri[2]] = 0.5 * (xy[2 * tri[0]] + xy[2 * tri[1]]);
                xy[2 * tri[2] + 1] = 0.5 * (xy[2 * tri[0] + 1] + xy[2 * tri[1] + 1]);
                break;
            case 4: *what = "a coordinate not finite or out of range"; xy[prng_below(p, (unsigned)(2 * nnodes))] = kBadCoordinates[prng_below(p, 4)]; break;
            case 5: /* the triangle again: its interior edges then belong to 3 triangles */
                *what = "an edge of 3 triangles";
                for (int k = 0; k < 3; ++k) nodes[3 * npoly + k] = tri[k];
                ++npoly;
                break;
            case 6: *what = "a count below 1"; *want = DPSM_ERR_INVALID_SIZE; if (prng_below(p, 2)) nnodes = 0; else npoly = -(int64_t)prng_below(p, 2); break;
            case 7: *what = "a NULL array"; *want = DPSM_ERR_NULL_POINTER; if (prng_below(p, 2)) { free(xy); xy = NULL; } else { free(nodes); nodes = NULL; } break;
            default: *what = "a NULL out"; *want = DPSM_ERR_NULL_POINTER; null_out = 1; break;
        }
    }
    if (indexed && start_index != 0) { /* every index array, the defect's too, from 1 */
        count_from_one(start, start ? (size_t)(m->npoly + 2) : 0);
        count_from_one(nodes, nodes ? (size_t)(total + 4) : 0);
        count_from_one(fc, fc ? (size_t)(2 * m->nfaces) : 0);
    }
    if (indexed && start_index != 0 && start_index != 1 && !null_out) {
        *want = DPSM_ERR_INVALID_VALUE;
        *what = "a start index other than 0 and 1";
    }
    *grid = (dpsm_grid *)grid; /* not NULL: a failure must set NULL */
    dpsm_grid **out = null_out ? NULL : grid;
    int st;
    if (m->kind == MESH_POLYGONS)
        st = indexed ? dpsm_create_mesh_indexed(start_index, nnodes, xy, npoly, start, nodes, out)
                     : dpsm_create_mesh(nnodes, xy, npoly, start, nodes, out);
    else if (m->kind == MESH_GRAPH)
        st = indexed ? dpsm_create_graph_indexed(start_index, ncells, cell_xy, area, nfaces, fc, fxy, flen, out)
                     : dpsm_create_graph(ncells, cell_xy, area, nfaces, fc, fxy, flen, out);
    else
        st = indexed ? dpsm_create_dual_mesh_indexed(start_index, nnodes, xy, npoly, nodes, out)
                     : dpsm_create_dual_mesh(nnodes, xy, npoly, nodes, out);
    if (null_out) *grid = NULL;
    free(xy);
    free(start);
    free(nodes);
    free(cell_xy);
    free(area);
    free(fc);
    free(fxy);
    free(flen);
    return st;
}

/* What the harness knows of a live mesh. */
typedef struct {
    const mesh_t *m;
    dpsm_grid *g;
    dpsm_grid *twin;    /* the same mesh from 0 when g counts from 1 or came from an _indexed constructor; or NULL */
    uint8_t *kinds;     /* per cell */
    uint8_t *edge_open; /* per face: open edge faces */
    double *levels;     /* per face */
    double *source;     /* per cell; NULL: none */
    int record;         /* face fluxes recorded */
    int hold;           /* a static angle above the angle of repose */
    int64_t max_substeps;
    double mass_scale;
    prng_t *p;
} mesh_state_t;

typedef struct {
    double *h;
    double mass[5], edge_out, stable_dt;
} msnap_t;

static void mesh_snap(const mesh_state_t *ms, msnap_t *s) {
    s->h = xcalloc((size_t)ms->m->ncells, sizeof(double));
    const dpsm_grid *g = ms->g;
    if (dpsm_get_heights(g, s->h) != DPSM_OK) die("dpsm_get_heights failed on a mesh: %s", dpsm_last_error(g));
    for (int q = 0; q < 5; ++q)
        if (dpsm_get_mass(g, q, &s->mass[q]) != DPSM_OK) die("dpsm_get_mass failed on a mesh");
    if (dpsm_get_side_outflow(g, DPSM_MESH_EDGE, &s->edge_out) != DPSM_OK)
        die("dpsm_get_side_outflow(DPSM_MESH_EDGE) failed on a mesh: %s", dpsm_last_error(g));
    if (dpsm_stable_dt(g, &s->stable_dt) != DPSM_OK || !(s->stable_dt > 0.0)) die("dpsm_stable_dt failed on a mesh");
}

static void mesh_same(const mesh_state_t *ms, const msnap_t *a, const msnap_t *b, const char *what) {
    for (int64_t c = 0; c < ms->m->ncells; ++c)
        if (memcmp(&a->h[c], &b->h[c], sizeof(double)) != 0)
            die("%s: the height of cell %lld differs: %.17g vs %.17g", what, (long long)c, a->h[c], b->h[c]);
    for (int q = 0; q < 5; ++q)
        if (memcmp(&a->mass[q], &b->mass[q], sizeof(double)) != 0)
            die("%s: mass figure %d differs: %.17g vs %.17g", what, q, a->mass[q], b->mass[q]);
    if (memcmp(&a->edge_out, &b->edge_out, sizeof(double)) != 0)
        die("%s: the edge's outflow differs: %.17g vs %.17g", what, a->edge_out, b->edge_out);
    if (memcmp(&a->stable_dt, &b->stable_dt, sizeof(double)) != 0)
        die("%s: stable_dt differs: %.17g vs %.17g", what, a->stable_dt, b->stable_dt);
}

/* Finite heights; the ledger closes; the sand cells' heights times the
 * harness's own areas make up TOTAL. */
static void mesh_check_state(mesh_state_t *ms, const msnap_t *s) {
    const mesh_t *m = ms->m;
    double gross = 0.0, total = 0.0;
    for (int64_t c = 0; c < m->ncells; ++c) {
        if (!isfinite(s->h[c])) die("the height of mesh cell %lld is %g", (long long)c, s->h[c]);
        gross += fabs(s->h[c]) * m->area[c];
        if (ms->kinds[c] == DPSM_CELL_SAND) total += s->h[c] * m->area[c];
    }
    for (int q = 0; q < 5; ++q)
        if (!isfinite(s->mass[q])) die("mass figure %d is %g", q, s->mass[q]);
    ms->mass_scale = fmax(ms->mass_scale, gross);
    double scale = fmax(1.0, ms->mass_scale);
    for (int q = 0; q < 4; ++q) scale = fmax(scale, fabs(s->mass[q]));
    const double residual = fabs(s->mass[0] - (s->mass[1] + s->mass[2] - s->mass[3]));
    if (residual > 1e-9 * scale)
        die("the mesh's ledger does not close: total %.17g, sourced %.17g, external %.17g, outflow %.17g: residual "
            "%.3g of %.3g",
            s->mass[0], s->mass[1], s->mass[2], s->mass[3], residual, scale);
    if (fabs(s->mass[0] - total) > 1e-9 * scale)
        die("DPSM_MASS_TOTAL is %.17g, the sand cells' heights times their areas %.17g", s->mass[0], total);
}

static void mesh_expect(mesh_state_t *ms, int st, int want, const char *fn, const msnap_t *before) {
    expect_status(st, want, fn, ms->g);
    if (st != DPSM_OK) {
        check_failed(NULL, ms->g, NULL, st, fn);
        msnap_t after;
        mesh_snap(ms, &after);
        mesh_same(ms, before, &after, "a failed call changed the mesh");
        free(after.h);
    } else if (*dpsm_last_error(ms->g)) {
        die("%s succeeded but left the message \"%s\"", fn, dpsm_last_error(ms->g));
    }
}

/* `call` names the mesh ms->g; once it succeeds it is made on the twin too. */
#define MESH_CALL(ms, want, fn, call)                                                              \
    do {                                                                                           \
        msnap_t before_;                                                                           \
        mesh_snap((ms), &before_);                                                                 \
        g_op = (fn);                                                                               \
        const int st_ = (call);                                                                    \
        mesh_expect((ms), st_, (want), (fn), &before_);                                            \
        free(before_.h);                                                                           \
        if (st_ == DPSM_OK && (ms)->twin) {                                                        \
            dpsm_grid *const mesh_ = (ms)->g;                                                      \
            (ms)->g = (ms)->twin;                                                                  \
            const int twin_st_ = (call);                                                           \
            (ms)->g = mesh_;                                                                       \
            if (twin_st_ != DPSM_OK) die("%s failed on the twin from 0: %s", (fn), dpsm_last_error((ms)->twin)); \
        }                                                                                          \
    } while (0)

/* The twin from 0 matches the mesh bit for bit. */
static void mesh_check_twin(const mesh_state_t *ms, const msnap_t *now) {
    if (!ms->twin) return;
    mesh_state_t other = *ms;
    other.g = ms->twin;
    msnap_t twin;
    mesh_snap(&other, &twin);
    mesh_same(ms, now, &twin, "the mesh and its twin from 0");
    free(twin.h);
}

static int mesh_source_active(const mesh_state_t *ms) {
    if (!ms->source) return 0;
    for (int64_t c = 0; c < ms->m->ncells; ++c)
        if (ms->kinds[c] == DPSM_CELL_SAND && ms->source[c] != 0.0) return 1;
    return 0;
}

/* A source surely makes a face steep at the end of a step of dt under the
 * sources alone: a face between a sand cell with a source and a sand or open
 * cell whose two-point slope alone (a lower bound of the face's slope) is
 * then beyond the default angle's threshold. Only such a source must be held
 * to the sub-step limit; one that is not surely steep may or may not be (its
 * gradients' part decides). */
static int mesh_source_surely_steep(const mesh_state_t *ms, const double *h, double dt) {
    if (!ms->source) return 0;
    const mesh_t *m = ms->m;
    double *xy = xcalloc((size_t)(2 * m->ncells), sizeof(double));
    if (dpsm_get_cell_centres(ms->g, xy, NULL) != DPSM_OK) die("dpsm_get_cell_centres failed on a mesh");
    const double threshold = tan(DPSM_DEFAULT_REPOSE_ANGLE) * (1.0 + DPSM_DEFAULT_REST_TOLERANCE) * (1.0 + 1e-6);
    int steep = 0;
    for (int64_t f = 0; f < m->nfaces && !steep; ++f) {
        const int64_t a = m->face_cells[2 * f], b = m->face_cells[2 * f + 1];
        if (b < 0) continue;
        const uint8_t ka = ms->kinds[a], kb = ms->kinds[b];
        if (ka == DPSM_CELL_WALL || kb == DPSM_CELL_WALL || (ka != DPSM_CELL_SAND && kb != DPSM_CELL_SAND)) continue;
        const double qa = ka == DPSM_CELL_SAND ? ms->source[a] : 0.0, qb = kb == DPSM_CELL_SAND ? ms->source[b] : 0.0;
        if (qa == 0.0 && qb == 0.0) continue;
        const double d = hypot(xy[2 * a] - xy[2 * b], xy[2 * a + 1] - xy[2 * b + 1]);
        steep = fabs((h[a] + qa * dt) - (h[b] + qb * dt)) > threshold * d;
    }
    free(xy);
    return steep;
}

/* The held levels (open edge faces, open cells): their range; 0 if none. */
static int mesh_held_range(const mesh_state_t *ms, const double *h, double *lo, double *hi) {
    int any = 0;
    for (int64_t f = 0; f < ms->m->nfaces; ++f)
        if (ms->m->face_cells[2 * f + 1] < 0 && ms->edge_open[f]) {
            const double v = ms->levels[f];
            *lo = any ? fmin(*lo, v) : v, *hi = any ? fmax(*hi, v) : v, any = 1;
        }
    for (int64_t c = 0; c < ms->m->ncells; ++c)
        if (ms->kinds[c] == DPSM_CELL_OPEN) *lo = any ? fmin(*lo, h[c]) : h[c], *hi = any ? fmax(*hi, h[c]) : h[c], any = 1;
    return any;
}

/* Per cell values by a pattern: constant, a central pile, a ramp in x, or
 * each its own; (mode & 0xc0) == 0xc0 plants a NaN or infinity (returns 1). */
static int mesh_fill(reader_t *r, const mesh_state_t *ms, double *a, const double *table, size_t ntable) {
    const mesh_t *m = ms->m;
    const unsigned mode = u8(r);
    const double v = table[u8(r) % ntable], w = table[u8(r) % ntable];
    double x0 = m->cx[0], x1 = x0, y0 = m->cy[0], y1 = y0;
    for (int64_t c = 0; c < m->ncells; ++c)
        x0 = fmin(x0, m->cx[c]), x1 = fmax(x1, m->cx[c]), y0 = fmin(y0, m->cy[c]), y1 = fmax(y1, m->cy[c]);
    for (int64_t c = 0; c < m->ncells; ++c) {
        const double u = (m->cx[c] - x0) / (x1 - x0), t = (m->cy[c] - y0) / (y1 - y0);
        switch (mode % 4) {
            case 0: a[c] = v; break;
            case 1: a[c] = fabs(u - 0.5) < 0.25 && fabs(t - 0.5) < 0.25 ? v : w; break;
            case 2: a[c] = v + w * u; break;
            default: a[c] = table[prng_below(ms->p, (unsigned)ntable)]; break;
        }
    }
    if ((mode & 0xc0) == 0xc0) {
        static const double bad[] = {NAN, INFINITY, -INFINITY};
        a[prng_below(ms->p, (unsigned)m->ncells)] = bad[u8(r) % 3];
        return 1;
    }
    return 0;
}

/* One step of the mesh and every check after it. */
static void mesh_step(mesh_state_t *ms, reader_t *r) {
    const mesh_t *m = ms->m;
    const unsigned b = u8(r);
    const double dt = 1e-3 * pow(10.0, 4.0 * (double)(b & 0x7f) / 127.0); /* 1e-3 .. 10 */
    const int through_restart = (b & 0x80) != 0;
    msnap_t before;
    mesh_snap(ms, &before);
    const int sourced = mesh_source_active(ms);
    double held_lo = 0.0, held_hi = 0.0;
    const int held = mesh_held_range(ms, before.h, &held_lo, &held_hi);
    /* A source drives only where it keeps a face steep to the end of the step (sources in closed form; not with
     * a static angle, under which a source always drives). */
    const int held_apart = held && held_lo != held_hi;
    const int limited = held_apart || (sourced && (ms->hold || mesh_source_surely_steep(ms, before.h, dt)));
    const double needed = ceil(dt / before.stable_dt), limit = (double)ms->max_substeps;
    int want = limited && needed > limit ? DPSM_ERR_WORK_LIMIT : DPSM_OK;
    const int either = (limited && fabs(needed - limit) <= 1.0) || (sourced && !limited && needed > limit - 1.0);
    /* Bounded work: a scene at rest by itself stops early, but how early depends on it. */
    const double cost = (want == DPSM_OK || either ? fmax(needed, 1.0) : 1.0) * (double)m->ncells *
                        ((through_restart ? 2 : 1) + (ms->twin ? 1 : 0));
    if (g_work + cost > kWorkBudget) {
        free(before.h);
        return;
    }
    g_work += cost;
    double lo = held ? held_lo : INFINITY, hi = held ? held_hi : -INFINITY;
    for (int64_t c = 0; c < m->ncells; ++c)
        if (ms->kinds[c] == DPSM_CELL_SAND) lo = fmin(lo, before.h[c]), hi = fmax(hi, before.h[c]);

    dpsm_grid *copy = NULL;
    if (through_restart) {
        g_op = "dpsm_save";
        const char *path = restart_path();
        if (dpsm_save(ms->g, path) != DPSM_OK) die("dpsm_save(%s) of a mesh failed: %s", path, dpsm_last_error(ms->g));
        g_op = "dpsm_load";
        if (dpsm_load(path, &copy) != DPSM_OK || !copy) die("dpsm_load(%s) of a mesh failed: %s", path, dpsm_last_error(NULL));
        int64_t sx = 0, sy = 0, nf = 0;
        int kind = 0;
        if (dpsm_get_shape(copy, &sx, &sy) != DPSM_OK || sx != m->ncells || sy != 1 ||
            dpsm_get_face_count(copy, &nf) != DPSM_OK || nf != m->nfaces ||
            dpsm_get_grid_kind(copy, &kind) != DPSM_OK || kind != DPSM_GRID_MESH)
            die("the loaded mesh is %lld x %lld with %lld faces, not %lld x 1 with %lld", (long long)sx, (long long)sy,
                (long long)nf, (long long)m->ncells, (long long)m->nfaces);
        mesh_state_t other = *ms;
        other.g = copy;
        msnap_t loaded;
        mesh_snap(&other, &loaded);
        mesh_same(ms, &before, &loaded, "a mesh loaded from a restart file");
        free(loaded.h);
        /* The file keeps the mesh's numbering: its faces as the mesh lists them. */
        int64_t *fa = xcalloc((size_t)(2 * nf), sizeof(int64_t)), *fb = xcalloc((size_t)(2 * nf), sizeof(int64_t));
        if (dpsm_get_mesh_faces(ms->g, fa) != DPSM_OK || dpsm_get_mesh_faces(copy, fb) != DPSM_OK ||
            memcmp(fa, fb, sizeof(int64_t) * (size_t)(2 * nf)) != 0)
            die("the loaded mesh lists other faces (or numbers them otherwise) than the saved one");
        free(fa);
        free(fb);
    }
    g_op = "dpsm_step";
    const int st = dpsm_step(ms->g, dt);
    trace("dpsm_step(%g = %g stable steps) on a mesh of %lld cells, %s", dt, dt / before.stable_dt,
          (long long)m->ncells, limited ? "driven" : "not driven");
    if (either && (st == DPSM_OK || st == DPSM_ERR_WORK_LIMIT)) want = st;
    mesh_expect(ms, st, want, "dpsm_step", &before);
    if (ms->twin && dpsm_step(ms->twin, dt) != st)
        die("the twin from 0's step returned %s, the mesh's %s", dpsm_last_error(ms->twin), dpsm_status_string(st));
    if (st != DPSM_OK) {
        if (copy && dpsm_step(copy, dt) != st) die("the loaded mesh's step did not fail as the mesh's did");
        dpsm_destroy(copy);
        free(before.h);
        return;
    }
    msnap_t after;
    mesh_snap(ms, &after);
    mesh_check_state(ms, &after);
    double info[5];
    for (int i = 0; i < 5; ++i)
        if (dpsm_get_step_info(ms->g, i, &info[i]) != DPSM_OK) die("dpsm_get_step_info failed on a mesh");
    for (int64_t c = 0; c < m->ncells; ++c) {
        if (ms->kinds[c] != DPSM_CELL_SAND && memcmp(&after.h[c], &before.h[c], sizeof(double)) != 0)
            die("the held height of mesh cell %lld changed from %.17g to %.17g", (long long)c, before.h[c], after.h[c]);
        if (!sourced && !(held && held_lo != held_hi) && ms->kinds[c] == DPSM_CELL_SAND && hi >= lo) {
            const double magnitude = fmax(fmax(fabs(hi), fabs(lo)), DBL_MIN);
            if ((after.h[c] - hi) / magnitude > 4 * DBL_EPSILON || (lo - after.h[c]) / magnitude > 4 * DBL_EPSILON)
                die("new extremum on a mesh without a source: cell %lld at %.17g outside [%.17g, %.17g]", (long long)c,
                    after.h[c], lo, hi);
        }
    }
    if (ms->record) {
        g_op = "dpsm_get_face_fluxes";
        double *fx = xcalloc((size_t)m->nfaces, sizeof(double));
        const int fst = dpsm_get_face_fluxes(ms->g, fx, NULL);
        if (fst != DPSM_OK) die("face fluxes are recorded, but after a step on a mesh: %s (%s)", dpsm_status_string(fst), dpsm_last_error(ms->g));
        double *in = xcalloc((size_t)m->ncells, sizeof(double)), *gross = xcalloc((size_t)m->ncells, sizeof(double));
        double largest = 0.0, edge = 0.0, edge_gross = 0.0;
        for (int64_t f = 0; f < m->nfaces; ++f) {
            const int64_t a = m->face_cells[2 * f], c = m->face_cells[2 * f + 1];
            const double v = fx[f];
            if (!isfinite(v)) die("face %lld carried %g", (long long)f, v);
            largest = fmax(largest, fabs(v));
            in[a] -= v, gross[a] += fabs(v);
            if (c >= 0) {
                in[c] += v, gross[c] += fabs(v);
                if (v != 0.0 && (ms->kinds[a] == DPSM_CELL_WALL || ms->kinds[c] == DPSM_CELL_WALL ||
                                 (ms->kinds[a] != DPSM_CELL_SAND && ms->kinds[c] != DPSM_CELL_SAND)))
                    die("face %lld between cells %lld and %lld (kinds %d, %d) carried %g", (long long)f, (long long)a,
                        (long long)c, ms->kinds[a], ms->kinds[c], v);
            } else {
                if (v != 0.0 && (!ms->edge_open[f] || ms->kinds[a] == DPSM_CELL_WALL))
                    die("edge face %lld (%s, cell %lld of kind %d) carried %g", (long long)f,
                        ms->edge_open[f] ? "open" : "a wall", (long long)a, ms->kinds[a], v);
                edge += v, edge_gross += fabs(v);
            }
        }
        const double rel_steps = 16.0 * DBL_EPSILON * fmax(info[DPSM_INFO_SUBSTEPS], 1.0);
        const double time = info[DPSM_INFO_TIME_INTEGRATED];
        double into_open = 0.0, scale_all = 0.0;
        for (int64_t c = 0; c < m->ncells; ++c) {
            if (ms->kinds[c] == DPSM_CELL_OPEN) into_open += in[c];
            if (ms->kinds[c] != DPSM_CELL_SAND) continue;
            const double q = ms->source ? ms->source[c] * time * m->area[c] : 0.0;
            const double change = (after.h[c] - before.h[c]) * m->area[c] - q;
            const double tol = 1e-9 * largest + rel_steps * ((fabs(before.h[c]) + fabs(after.h[c])) * m->area[c] + fabs(q) + gross[c]) + DBL_MIN;
            scale_all += (fabs(before.h[c]) + fabs(after.h[c])) * m->area[c] + fabs(q) + gross[c];
            if (fabs(change - in[c]) > tol)
                die("mesh cell %lld (area %.17g) changed by %.17g less its source %.17g; its faces brought %.17g: off "
                    "by %.3g, largest face %.3g",
                    (long long)c, m->area[c], (after.h[c] - before.h[c]) * m->area[c], q, in[c], change - in[c], largest);
        }
        const double booked = after.edge_out - before.edge_out;
        const double edge_tol = 1e-9 * fmax(largest, edge_gross) + rel_steps * (edge_gross + fabs(before.edge_out) + fabs(after.edge_out)) + DBL_MIN;
        if (fabs(edge - booked) > edge_tol)
            die("the mesh's edge faces carried %.17g out, dpsm_get_side_outflow(DPSM_MESH_EDGE) grew by %.17g", edge, booked);
        const double outflow = after.mass[3] - before.mass[3];
        const double out_tol = 1e-9 * fmax(largest, 1e-300) * (double)m->nfaces +
                               rel_steps * (scale_all + fabs(before.mass[3]) + fabs(after.mass[3])) + DBL_MIN;
        if (fabs(outflow - booked - into_open) > out_tol)
            die("OUTFLOW grew by %.17g; the edge took %.17g, the open cells %.17g", outflow, booked, into_open);
        free(fx);
        free(in);
        free(gross);
    }
    if (copy) {
        g_op = "dpsm_step (loaded mesh)";
        if (dpsm_step(copy, dt) != DPSM_OK) die("the loaded mesh's step failed: %s", dpsm_last_error(copy));
        mesh_state_t other = *ms;
        other.g = copy;
        msnap_t stepped;
        mesh_snap(&other, &stepped);
        mesh_same(ms, &after, &stepped, "a mesh loaded from a restart file, after a step");
        free(stepped.h);
        dpsm_destroy(copy);
    }
    free(after.h);
    free(before.h);
}

/* One operation on a live mesh: its opcode byte % 10, then its arguments. */
static void mesh_operation(mesh_state_t *ms, reader_t *r) {
    const mesh_t *m = ms->m;
    const int64_t n = m->ncells, nf = m->nfaces;
    const unsigned op = u8(r) % 10;
    switch (op) {
        case 0: { /* heights: mode, v, w (kMeshHeights), [a byte for the bad value] */
            double *h = xcalloc((size_t)n, sizeof(double));
            const int planted = mesh_fill(r, ms, h, kMeshHeights, COUNT(kMeshHeights));
            MESH_CALL(ms, planted ? DPSM_ERR_INVALID_VALUE : DPSM_OK, "dpsm_set_heights", dpsm_set_heights(ms->g, h));
            free(h);
            break;
        }
        case 1: { /* source: b (% 3 == 0: none), then as heights (kMeshSources) */
            const int none = u8(r) % 3 == 0;
            double *q = xcalloc((size_t)n, sizeof(double));
            const int planted = none ? 0 : mesh_fill(r, ms, q, kMeshSources, COUNT(kMeshSources));
            MESH_CALL(ms, planted ? DPSM_ERR_INVALID_VALUE : DPSM_OK, "dpsm_set_source", dpsm_set_source(ms->g, none ? NULL : q));
            if (!planted) {
                free(ms->source);
                ms->source = none ? NULL : q;
                if (!none) q = NULL;
            }
            free(q);
            break;
        }
        case 2: { /* cell kinds: b % 4: 0 NULL (all sand), 1 mostly sand, 2 one open cell, 3 one wall; b >= 0xe0 plants a bad kind */
            const unsigned b = u8(r);
            uint8_t *k = NULL;
            int want = DPSM_OK;
            if (b % 4) {
                k = xcalloc((size_t)n, 1);
                for (int64_t c = 0; c < n; ++c) {
                    const unsigned x = prng_below(ms->p, 10);
                    k[c] = b % 4 != 1 ? DPSM_CELL_SAND : x < 8 ? DPSM_CELL_SAND : x < 9 ? DPSM_CELL_WALL : DPSM_CELL_OPEN;
                }
                if (b % 4 >= 2) k[prng_below(ms->p, (unsigned)n)] = b % 4 == 2 ? DPSM_CELL_OPEN : DPSM_CELL_WALL;
                if (b >= 0xe0) {
                    static const uint8_t bad[] = {3, 4, 200, 255};
                    k[prng_below(ms->p, (unsigned)n)] = bad[b % 4];
                    want = DPSM_ERR_UNKNOWN_ENUM;
                }
            }
            MESH_CALL(ms, want, "dpsm_set_cell_kinds", dpsm_set_cell_kinds(ms->g, k));
            if (want == DPSM_OK) {
                if (k) memcpy(ms->kinds, k, (size_t)n);
                else memset(ms->kinds, DPSM_CELL_SAND, (size_t)n);
            }
            free(k);
            break;
        }
        case 3: { /* dpsm_set_boundary: b % 8: 0 open, 1 wall, 2 a grid's side, 3 side 5, 4 a bad kind, else open/wall */
            const unsigned b = u8(r);
            int side = DPSM_MESH_EDGE, kind = b % 2 ? DPSM_WALL : DPSM_OPEN, want = DPSM_OK;
            if (b % 8 == 2) side = (int)(b / 8 % 4), want = DPSM_ERR_NOT_APPLICABLE;
            else if (b % 8 == 3) side = 5, want = DPSM_ERR_UNKNOWN_ENUM;
            else if (b % 8 == 4) kind = 2, want = DPSM_ERR_UNKNOWN_ENUM;
            MESH_CALL(ms, want, "dpsm_set_boundary", dpsm_set_boundary(ms->g, side, kind));
            if (want == DPSM_OK)
                for (int64_t f = 0; f < nf; ++f) ms->edge_open[f] = m->face_cells[2 * f + 1] < 0 && kind == DPSM_OPEN;
            break;
        }
        case 4: { /* dpsm_set_edge_kinds: b % 4: 0 NULL, 1 all open, else each edge face at random; interior faces
                   * get any value (ignored); b >= 0xe0 plants a bad kind on an edge face */
            const unsigned b = u8(r);
            uint8_t *k = NULL;
            int want = DPSM_OK;
            if (b % 4) {
                k = xcalloc((size_t)nf, 1);
                for (int64_t f = 0; f < nf; ++f)
                    k[f] = m->face_cells[2 * f + 1] >= 0 ? (uint8_t)prng_next(ms->p)
                           : b % 4 == 1 || prng_below(ms->p, 2) ? DPSM_OPEN : DPSM_WALL;
                if (b >= 0xe0) {
                    int64_t f = (int64_t)prng_below(ms->p, (unsigned)nf);
                    while (m->face_cells[2 * f + 1] >= 0) f = (f + 1) % nf;
                    k[f] = (uint8_t)(2 + b % 200);
                    want = DPSM_ERR_UNKNOWN_ENUM;
                }
            }
            MESH_CALL(ms, want, "dpsm_set_edge_kinds", dpsm_set_edge_kinds(ms->g, k));
            if (want == DPSM_OK)
                for (int64_t f = 0; f < nf; ++f) ms->edge_open[f] = m->face_cells[2 * f + 1] < 0 && k && k[f] == DPSM_OPEN;
            free(k);
            break;
        }
        case 5: { /* dpsm_set_side_levels(DPSM_MESH_EDGE): b % 4: 0 NULL, 1 all one level, 2 one face
                   * apart, 3 each its own; b >= 0xe0 plants a bad level on an edge face; levels from kMeshHeights */
            const unsigned b = u8(r);
            const double v = kMeshHeights[u8(r) % COUNT(kMeshHeights)], w = kMeshHeights[u8(r) % COUNT(kMeshHeights)];
            double *levels = NULL;
            int want = DPSM_OK;
            if (b % 4) {
                levels = xcalloc((size_t)nf, sizeof(double));
                for (int64_t f = 0; f < nf; ++f)
                    levels[f] = b % 4 == 3 ? kMeshHeights[prng_below(ms->p, COUNT(kMeshHeights))] : v;
                if (b % 4 == 2) levels[prng_below(ms->p, (unsigned)nf)] = w;
                if (b >= 0xe0) {
                    static const double bad[] = {NAN, INFINITY, -INFINITY, 1e51};
                    int64_t f = (int64_t)prng_below(ms->p, (unsigned)nf);
                    while (m->face_cells[2 * f + 1] >= 0) f = (f + 1) % nf;
                    levels[f] = bad[b % 4];
                    want = DPSM_ERR_INVALID_VALUE;
                }
            }
            MESH_CALL(ms, want, "dpsm_set_side_levels", dpsm_set_side_levels(ms->g, DPSM_MESH_EDGE, levels));
            if (want == DPSM_OK)
                for (int64_t f = 0; f < nf; ++f) ms->levels[f] = levels ? levels[f] : 0.0;
            free(levels);
            break;
        }
        case 6: { /* face fluxes: b % 4: 0 recording off, 1 on, 2 read with an fy, 3 read with a NULL fx */
            const unsigned b = u8(r);
            if (b % 4 < 2) {
                MESH_CALL(ms, DPSM_OK, "dpsm_set_face_flux_recording", dpsm_set_face_flux_recording(ms->g, (int)(b % 4)));
                ms->record = (int)(b % 4);
            } else {
                double *fx = xcalloc((size_t)nf, sizeof(double)), fy[1];
                MESH_CALL(ms, b % 4 == 2 ? DPSM_ERR_INVALID_VALUE : DPSM_ERR_NULL_POINTER, "dpsm_get_face_fluxes",
                          dpsm_get_face_fluxes(ms->g, b % 4 == 2 ? fx : NULL, b % 4 == 2 ? fy : NULL));
                MESH_CALL(ms, ms->record ? DPSM_OK : DPSM_ERR_NOT_APPLICABLE, "dpsm_get_face_fluxes",
                          dpsm_get_face_fluxes(ms->g, fx, NULL));
                free(fx);
            }
            break;
        }
        case 7: { /* what a mesh does not have: blocks of cells, a grid's sides */
            const unsigned b = u8(r);
            double v[4] = {1.0, 1.0, 1.0, 1.0}, out = 0.0;
            const int64_t i0 = (int64_t)(b % 3), ni = 1 + (int64_t)(b / 3 % 2);
            MESH_CALL(ms, DPSM_ERR_NOT_APPLICABLE, "dpsm_set_heights_region", dpsm_set_heights_region(ms->g, i0, 0, ni, 1, v));
            MESH_CALL(ms, DPSM_ERR_NOT_APPLICABLE, "dpsm_add_heights_region", dpsm_add_heights_region(ms->g, i0, 0, ni, 1, v));
            MESH_CALL(ms, DPSM_ERR_NOT_APPLICABLE, "dpsm_get_heights_region", dpsm_get_heights_region(ms->g, i0, 0, ni, 1, v));
            MESH_CALL(ms, DPSM_ERR_NOT_APPLICABLE, "dpsm_get_side_outflow", dpsm_get_side_outflow(ms->g, (int)(b % 4), &out));
            MESH_CALL(ms, DPSM_ERR_UNKNOWN_ENUM, "dpsm_get_side_outflow", dpsm_get_side_outflow(ms->g, 5 + (int)(b % 3), &out));
            MESH_CALL(ms, DPSM_ERR_NOT_APPLICABLE, "dpsm_set_side_levels", dpsm_set_side_levels(ms->g, (int)(b % 4), v));
            /* Where each cell lies: the harness's own centroids (a graph's
             * centres, the dual's nodes) and areas, in the host's order. */
            double *xy = xcalloc((size_t)(2 * n), sizeof(double)), *area = xcalloc((size_t)n, sizeof(double));
            /* Either array may be NULL; both NULL is refused. */
            MESH_CALL(ms, (b & 24) == 24 ? DPSM_ERR_NULL_POINTER : DPSM_OK, "dpsm_get_cell_centres",
                      dpsm_get_cell_centres(ms->g, b & 8 ? NULL : xy, b & 16 ? NULL : area));
            MESH_CALL(ms, DPSM_ERR_NULL_POINTER, "dpsm_get_cell_centres", dpsm_get_cell_centres(ms->g, NULL, NULL));
            for (int64_t c = 0; c < n; ++c) {
                const double scale = fmax(fabs(m->cx[c]) + fabs(m->cy[c]), 1.0);
                if (!(b & 8) && (fabs(xy[2 * c] - m->cx[c]) > 1e-12 * scale || fabs(xy[2 * c + 1] - m->cy[c]) > 1e-12 * scale))
                    die("dpsm_get_cell_centres: cell %lld at (%.17g, %.17g), the harness has (%.17g, %.17g)", (long long)c,
                        xy[2 * c], xy[2 * c + 1], m->cx[c], m->cy[c]);
                if (!(b & 16) && fabs(area[c] - m->area[c]) > 1e-12 * m->area[c])
                    die("dpsm_get_cell_centres: cell %lld has area %.17g, the harness %.17g", (long long)c, area[c],
                        m->area[c]);
            }
            free(xy);
            free(area);
            /* The mesh functions without a mesh. */
            int64_t count = 0;
            static const char *const names[] = {"dpsm_get_face_count", "dpsm_get_mesh_faces", "dpsm_set_edge_kinds"};
            for (int k = 0; k < 3; ++k) {
                g_op = names[k];
                const int got = k == 0 ? dpsm_get_face_count(NULL, &count)
                                : k == 1 ? dpsm_get_mesh_faces(NULL, &count) : dpsm_set_edge_kinds(NULL, NULL);
                expect_status(got, DPSM_ERR_NULL_POINTER, g_op, NULL);
                check_failed(NULL, NULL, NULL, got, g_op);
            }
            break;
        }
        case 8: { /* b < 0x80: dpsm_set_max_substeps; else b & 2: dpsm_set_static_angle, b & 4: 37 degrees, or
                     * 17 (the angle of repose then); else dpsm_set_relaxation, b & 1: local time steps, or the default */
            static const int64_t values[] = {1, 3, 50, MESH_MAX_SUBSTEPS};
            const unsigned b = u8(r);
            if ((b & 0x82) == 0x82) {
                const double angle = (b & 4 ? 37.0 : 17.0) * 3.14159265358979323846 / 180.0;
                MESH_CALL(ms, DPSM_OK, "dpsm_set_static_angle", dpsm_set_static_angle(ms->g, angle));
                ms->hold = angle > DPSM_DEFAULT_REPOSE_ANGLE;
                break;
            }
            if (b & 0x80) {
                const int relaxation = b & 1 ? DPSM_RELAX_LOCAL_STEPS : DPSM_RELAX_AUTO;
                MESH_CALL(ms, DPSM_OK, "dpsm_set_relaxation", dpsm_set_relaxation(ms->g, relaxation));
                break;
            }
            const int64_t v = values[b % COUNT(values)];
            MESH_CALL(ms, DPSM_OK, "dpsm_set_max_substeps", dpsm_set_max_substeps(ms->g, v));
            ms->max_substeps = v;
            break;
        }
        default:
            mesh_step(ms, r);
            break;
    }
    msnap_t now;
    mesh_snap(ms, &now);
    mesh_check_state(ms, &now);
    mesh_check_twin(ms, &now);
    free(now.h);
}

static void op_mesh(reader_t *r) {
    g_op = "mesh";
    const unsigned kind_byte = u8(r);
    const int kind = (int)(kind_byte % 3), lattice = kind == MESH_DUAL ? 1 : (int)(kind_byte / 3 % 3);
    const int numbering = (int)(kind_byte / 9 % 3), indexed = numbering != 0, base = numbering == 1;
    const int64_t nx = 2 + (int64_t)(u8(r) % 7), ny = 2 + (int64_t)(u8(r) % 7);
    const double dx = kMeshSpacings[u8(r) % COUNT(kMeshSpacings)], dy = kMeshSpacings[u8(r) % COUNT(kMeshSpacings)];
    const double jitter = 0.06 * (double)(u8(r) % 5);
    const unsigned seed = u16(r);
    const unsigned defect_byte = u8(r), nops = u8(r) % 16;
    prng_t p = {0x9E3779B97F4A7C15ULL ^ ((uint64_t)seed * 0x100000001B3ULL + 1u)};
    mesh_t m;
    mesh_build(&m, kind, lattice, nx, ny, dx, dy, jitter, &p);
    mesh_derive(&m, &p);
    const int defect = (defect_byte & 0xc0) == 0xc0 ? (int)(defect_byte & 0x3f) : -1;
    const char *fn = indexed ? kIndexedFunctions[kind] : kMeshFunctions[kind], *what;
    dpsm_grid *g;
    int want;
    g_op = fn;
    const prng_t p0 = p; /* the twin and the bad start index take copies: p goes on as without them */
    if (base) {
        prng_t q = p0;
        const int bad = kBadStarts[seed % 4];
        const int bst = mesh_construct(&m, -1, &q, &g, &want, &what, 1, bad);
        trace("%s(start_index = %d) -> %s", fn, bad, dpsm_status_string(bst));
        if (bst != DPSM_ERR_INVALID_VALUE || g != NULL)
            die("%s(start_index = %d) returned %s (*out %s), expected DPSM_ERR_INVALID_VALUE and NULL", fn, bad,
                dpsm_status_string(bst), g ? "set" : "NULL");
        check_failed(NULL, NULL, NULL, bst, fn);
        if (!strstr(dpsm_last_error(NULL), "start_index"))
            die("%s refused start_index = %d with \"%s\", which does not name it", fn, bad, dpsm_last_error(NULL));
    }
    const int st = mesh_construct(&m, defect, &p, &g, &want, &what, indexed, base);
    trace("%s (%lld x %lld %s, from %d, defect: %s) -> %s", fn, (long long)nx, (long long)ny,
          lattice == 0 ? "quads" : lattice == 1 ? "triangles" : "mixed", base, what, dpsm_status_string(st));
    if (st != want)
        die("%s with %s returned %s, expected %s (%s)", fn, what, dpsm_status_string(st), dpsm_status_string(want),
            dpsm_last_error(NULL));
    if (st != DPSM_OK) {
        check_failed(NULL, NULL, NULL, st, fn);
        if (g != NULL) die("%s failed (%s) but did not set *out to NULL", fn, what);
        mesh_free(&m);
        return;
    }
    if (*dpsm_last_error(NULL)) die("%s succeeded but left the message \"%s\"", fn, dpsm_last_error(NULL));
    if (defect >= 0) {
        /* A planted "defect" the library accepts (a triangle's centre on its
         * edge face): its geometry is no longer the harness's, so only a
         * step with the ledger closing and the heights finite. */
        double dt = 0.0, total = 0.0, sourced = 0.0, external = 0.0, outflow = 0.0;
        double *h = xcalloc((size_t)m.ncells, sizeof(double));
        for (int64_t c = 0; c < m.ncells; ++c) h[c] = (double)(c % 3);
        if (dpsm_stable_dt(g, &dt) != DPSM_OK || !(dt > 0.0) || !isfinite(dt)) die("%s: stable dt %g", what, dt);
        if (dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN) != DPSM_OK || dpsm_set_heights(g, h) != DPSM_OK ||
            dpsm_step(g, 10.0 * dt) != DPSM_OK || dpsm_get_heights(g, h) != DPSM_OK)
            die("%s: a step failed: %s", what, dpsm_last_error(g));
        for (int64_t c = 0; c < m.ncells; ++c)
            if (!isfinite(h[c])) die("%s: h[%lld] = %g after a step", what, (long long)c, h[c]);
        dpsm_get_mass(g, DPSM_MASS_TOTAL, &total), dpsm_get_mass(g, DPSM_MASS_SOURCED, &sourced);
        dpsm_get_mass(g, DPSM_MASS_EXTERNAL, &external), dpsm_get_mass(g, DPSM_MASS_OUTFLOW, &outflow);
        if (fabs(total - (sourced + external - outflow)) > 1e-9 * fmax(fabs(external), 1.0))
            die("%s: the ledger does not close (%g vs %g)", what, total, sourced + external - outflow);
        free(h);
        dpsm_destroy(g);
        mesh_free(&m);
        return;
    }
    /* The shape, and the faces the harness expects. */
    int64_t sx = 0, sy = 0, nf = 0;
    if (dpsm_get_shape(g, &sx, &sy) != DPSM_OK || sx != m.ncells || sy != 1)
        die("the mesh's shape is %lld x %lld, not %lld x 1", (long long)sx, (long long)sy, (long long)m.ncells);
    if (dpsm_get_face_count(g, &nf) != DPSM_OK || nf != m.nfaces)
        die("the mesh has %lld faces, not %lld", (long long)nf, (long long)m.nfaces);
    int grid_kind = 0;
    if (dpsm_get_grid_kind(g, &grid_kind) != DPSM_OK || grid_kind != DPSM_GRID_MESH)
        die("a mesh's kind is %d", grid_kind);
    int64_t *faces = xcalloc((size_t)(2 * nf), sizeof(int64_t));
    uint8_t *seen = xcalloc((size_t)m.ncells, 1);
    if (dpsm_get_mesh_faces(g, faces) != DPSM_OK) die("dpsm_get_mesh_faces failed: %s", dpsm_last_error(g));
    for (int64_t f = 0; f < nf; ++f) {
        const int64_t a = faces[2 * f] - base, b = faces[2 * f + 1] - base; /* from 0 */
        if (a < 0 || a >= m.ncells || b < -1 || b >= m.ncells || a == b)
            die("face %lld joins cells %lld and %lld of %lld", (long long)f, (long long)a, (long long)b, (long long)m.ncells);
        if (a != m.face_cells[2 * f] || b != m.face_cells[2 * f + 1])
            die("face %lld joins cells %lld and %lld; the harness expected %lld and %lld", (long long)f, (long long)a,
                (long long)b, (long long)m.face_cells[2 * f], (long long)m.face_cells[2 * f + 1]);
        seen[a] = 1;
        if (b >= 0) seen[b] = 1;
    }
    for (int64_t c = 0; c < m.ncells; ++c)
        if (!seen[c]) die("mesh cell %lld is in no face", (long long)c);
    free(faces);
    free(seen);
    {
        static const char *const names[] = {"dpsm_get_face_count", "dpsm_get_mesh_faces"};
        for (int k = 0; k < 2; ++k) {
            g_op = names[k];
            const int got = k == 0 ? dpsm_get_face_count(g, NULL) : dpsm_get_mesh_faces(g, NULL);
            expect_status(got, DPSM_ERR_NULL_POINTER, g_op, g);
            check_failed(NULL, g, NULL, got, g_op);
        }
    }
    mesh_state_t ms = {0};
    ms.m = &m;
    ms.g = g;
    ms.p = &p;
    if (indexed) {
        prng_t q = p0;
        int twin_want;
        const char *twin_what;
        g_op = kMeshFunctions[kind];
        if (mesh_construct(&m, -1, &q, &ms.twin, &twin_want, &twin_what, 0, 0) != DPSM_OK)
            die("the twin from 0 could not be made: %s", dpsm_last_error(NULL));
        if (dpsm_set_max_substeps(ms.twin, MESH_MAX_SUBSTEPS) != DPSM_OK) die("dpsm_set_max_substeps failed on the twin");
        msnap_t now;
        mesh_snap(&ms, &now);
        mesh_check_twin(&ms, &now);
        free(now.h);
    }
    ms.kinds = xcalloc((size_t)m.ncells, 1);
    ms.edge_open = xcalloc((size_t)m.nfaces, 1);
    ms.levels = xcalloc((size_t)m.nfaces, sizeof(double));
    ms.max_substeps = MESH_MAX_SUBSTEPS;
    g_op = "dpsm_set_max_substeps";
    if (dpsm_set_max_substeps(g, MESH_MAX_SUBSTEPS) != DPSM_OK) die("dpsm_set_max_substeps failed on a mesh");
    for (unsigned k = 0; k < nops && more(r); ++k) mesh_operation(&ms, r);
    dpsm_destroy(g);
    dpsm_destroy(ms.twin);
    free(ms.kinds);
    free(ms.edge_open);
    free(ms.levels);
    free(ms.source);
    mesh_free(&m);
}

/* ------------------------------------------------------------------------ */
/* Where cells lie, and meshes in degrees (issue 36)                         */
/* ------------------------------------------------------------------------ */

/* op_geometry (opcode kGeoOp): its first byte b.
 *
 *   b % 2 == 0: dpsm_get_cell_centres on a grid slot (a slot byte, then a
 *   byte: bit 0 no xy, bit 1 no area, both refused with
 *   DPSM_ERR_NULL_POINTER and nothing changed), against the harness's own
 *   cell centres ((i + 1/2) dx, (j + 1/2) dy; 0 for y in 1D) and the areas
 *   of its ledger, bit for bit.
 *
 *   b % 2 == 1: a mesh in longitude and latitude, built, checked and
 *   destroyed: (b / 2) % 2 quads (dpsm_create_mesh_geographic) or
 *   triangles (dpsm_create_dual_mesh_geographic), then nx, ny (2 + byte % 6),
 *   the spacing kGeoSpacings[byte % 5] degrees, the corner's latitude
 *   kGeoLatitudes[byte % 6] and longitude kGeoLongitudes[byte % 4], the start
 *   index (byte % 2) and a defect byte (>= 0xc0: (byte & 0x3f) % 4 of: a
 *   latitude beyond 90, a longitude beyond 540, a NaN coordinate, a node on
 *   the far side of the globe; each refused with DPSM_ERR_INVALID_VALUE,
 *   *out NULL and a message naming the function). A made mesh: its cells'
 *   areas (dpsm_get_cell_centres) are the spherical areas the harness
 *   computes itself by l'Huilier's theorem, to 1e-6; each centre lies in
 *   its cell's box of longitudes and latitudes; a stable sub-step finite
 *   and positive; a step from a pile on a wall edge keeps the ledger closed
 *   (to 1e-9), makes no new extremum, and a copy through dpsm_save and
 *   dpsm_load takes the same step to the same heights bit for bit. */
enum { kGeoOp = 252 };
static const double kGeoSpacings[] = {1e-3, 0.01, 0.1, 1.0, 5.0};
static const double kGeoLatitudes[] = {-89.0, -45.0, 0.0, 30.0, 60.0, 84.0};
static const double kGeoLongitudes[] = {-180.0, 0.0, 179.5, 359.0};

typedef struct {
    double x, y, z;
} unit_t;

static unit_t unit_of(double lon, double lat) {
    const double d = 3.14159265358979323846 / 180.0;
    return (unit_t){cos(lat * d) * cos(lon * d), cos(lat * d) * sin(lon * d), sin(lat * d)};
}

static double arc(unit_t a, unit_t b) {
    const double cx = a.y * b.z - a.z * b.y, cy = a.z * b.x - a.x * b.z, cz = a.x * b.y - a.y * b.x;
    return atan2(sqrt(cx * cx + cy * cy + cz * cz), a.x * b.x + a.y * b.y + a.z * b.z);
}

/* The area of a spherical triangle on the Earth's mean sphere, by l'Huilier. */
static double spherical_triangle(unit_t a, unit_t b, unit_t c) {
    const double x = arc(b, c), y = arc(c, a), z = arc(a, b), s = 0.5 * (x + y + z);
    const double t = tan(0.5 * s) * tan(0.5 * (s - x)) * tan(0.5 * (s - y)) * tan(0.5 * (s - z));
    const double r = 6371008.8;
    return 4.0 * atan(sqrt(fmax(t, 0.0))) * r * r;
}

static void op_cell_centres_on_a_grid(reader_t *r) {
    g_op = "dpsm_get_cell_centres";
    slot_t *s = pick_slot(r);
    const unsigned b = u8(r);
    if (!s) return;
    const int no_xy = (b & 1) != 0, no_area = (b & 2) != 0;
    snap_t before;
    snap(s->g, s, &before);
    double *xy = xcalloc((size_t)(2 * s->n), sizeof(double)), *area = xcalloc((size_t)s->n, sizeof(double));
    const int st = dpsm_get_cell_centres(s->g, no_xy ? NULL : xy, no_area ? NULL : area);
    expect_status(st, no_xy && no_area ? DPSM_ERR_NULL_POINTER : DPSM_OK, g_op, s->g);
    if (st != DPSM_OK) check_failed(s, s->g, &before, st, g_op);
    for (int64_t c = 0; st == DPSM_OK && c < s->n; ++c) {
        const double x = ((double)(c % s->nx) + 0.5) * s->dx;
        const double y = s->geom == GEOM_2D ? ((double)(c / s->nx) + 0.5) * s->dy : 0.0;
        if (!no_xy && (xy[2 * c] != x || xy[2 * c + 1] != y))
            die("dpsm_get_cell_centres: cell %lld at (%.17g, %.17g), expected (%.17g, %.17g)", (long long)c, xy[2 * c],
                xy[2 * c + 1], x, y);
        if (!no_area && area[c] != cell_area(s, c))
            die("dpsm_get_cell_centres: cell %lld has area %.17g, expected %.17g", (long long)c, area[c],
                cell_area(s, c));
    }
    free(xy);
    free(area);
    unsnap(&before);
}

static void op_geographic_mesh(reader_t *r, unsigned b) {
    const int dual = (b / 2) % 2;
    const char *fn = dual ? "dpsm_create_dual_mesh_geographic" : "dpsm_create_mesh_geographic";
    g_op = fn;
    const int64_t nx = 2 + u8(r) % 6, ny = 2 + u8(r) % 6;
    const double step = kGeoSpacings[u8(r) % COUNT(kGeoSpacings)];
    double lat0 = kGeoLatitudes[u8(r) % COUNT(kGeoLatitudes)];
    const double lon0 = kGeoLongitudes[u8(r) % COUNT(kGeoLongitudes)];
    const int base = (int)(u8(r) % 2);
    const unsigned defect_byte = u8(r);
    if (lat0 + (double)ny * step > 89.9) lat0 = 89.9 - (double)ny * step; /* the lattice stays off the pole */
    const int64_t nnodes = (nx + 1) * (ny + 1), nquads = nx * ny;
    double *lonlat = xcalloc((size_t)(2 * nnodes), sizeof(double));
    for (int64_t j = 0; j <= ny; ++j)
        for (int64_t i = 0; i <= nx; ++i) {
            lonlat[2 * (i + (nx + 1) * j)] = lon0 + (double)i * step;
            lonlat[2 * (i + (nx + 1) * j) + 1] = lat0 + (double)j * step;
        }
    int64_t *start = xcalloc((size_t)(nquads + 1), sizeof(int64_t)), *nodes = xcalloc((size_t)(6 * nquads), sizeof(int64_t));
    for (int64_t q = 0; q < nquads; ++q) {
        const int64_t i = q % nx, j = q / nx, n0 = i + (nx + 1) * j;
        const int64_t corner[4] = {n0, n0 + 1, n0 + nx + 2, n0 + nx + 1};
        start[q + 1] = 4 * (q + 1) + base;
        if (!dual) {
            for (int k = 0; k < 4; ++k) nodes[4 * q + k] = corner[k] + base;
        } else {
            const int64_t tri[6] = {corner[0], corner[1], corner[2], corner[0], corner[2], corner[3]};
            for (int k = 0; k < 6; ++k) nodes[6 * q + k] = tri[k] + base;
        }
    }
    start[0] = base;
    int want = DPSM_OK;
    const char *what = "none";
    if ((defect_byte & 0xc0) == 0xc0) {
        want = DPSM_ERR_INVALID_VALUE;
        const int64_t k = (int64_t)(defect_byte % (unsigned)nnodes);
        switch ((defect_byte & 0x3f) % 4) {
            case 0: what = "a latitude beyond 90"; lonlat[2 * k + 1] = 90.5; break;
            case 1: what = "a longitude beyond 540"; lonlat[2 * k] = 541.0; break;
            case 2: what = "a NaN coordinate"; lonlat[2 * k + (defect_byte & 1)] = NAN; break;
            default: what = "a node on the far side of the globe"; lonlat[2 * k] = lon0 + 180.0, lonlat[2 * k + 1] = -lat0; break;
        }
    }
    dpsm_grid *g = (dpsm_grid *)&g;
    const int64_t ncells = dual ? nnodes : nquads;
    const int st = dual ? dpsm_create_dual_mesh_geographic(base, nnodes, lonlat, 2 * nquads, nodes, &g)
                        : dpsm_create_mesh_geographic(base, nnodes, lonlat, nquads, start, nodes, &g);
    trace("%s (%lld x %lld at %g, %g by %g degrees, from %d, defect: %s) -> %s", fn, (long long)nx, (long long)ny, lon0,
          lat0, step, base, what, dpsm_status_string(st));
    if (st != want) die("%s with %s returned %s, expected %s (%s)", fn, what, dpsm_status_string(st), dpsm_status_string(want), dpsm_last_error(NULL));
    if (st != DPSM_OK) {
        check_failed(NULL, NULL, NULL, st, fn);
        if (g != NULL) die("%s failed (%s) but did not set *out to NULL", fn, what);
    } else {
        /* The harness's own areas: each quad two spherical triangles (the
         * dual: a third of each triangle to each of its nodes). */
        double *expected = xcalloc((size_t)ncells, sizeof(double)), *xy = xcalloc((size_t)(2 * ncells), sizeof(double));
        double *area = xcalloc((size_t)ncells, sizeof(double)), *h = xcalloc((size_t)ncells, sizeof(double));
        double *h2 = xcalloc((size_t)ncells, sizeof(double));
        for (int64_t q = 0; q < nquads; ++q) {
            const int64_t *v = nodes + (dual ? 6 : 4) * q;
            const int64_t t[6] = {v[0], v[1], v[2], v[0], v[2], dual ? v[5] : v[3]};
            for (int half = 0; half < 2; ++half) {
                const int64_t a = t[3 * half] - base, bb = t[3 * half + 1] - base, c = t[3 * half + 2] - base;
                const double e = spherical_triangle(unit_of(lonlat[2 * a], lonlat[2 * a + 1]),
                                                    unit_of(lonlat[2 * bb], lonlat[2 * bb + 1]),
                                                    unit_of(lonlat[2 * c], lonlat[2 * c + 1]));
                if (dual) expected[a] += e / 3.0, expected[bb] += e / 3.0, expected[c] += e / 3.0;
                else expected[q] += e;
            }
        }
        if (dpsm_get_cell_centres(g, xy, area) != DPSM_OK) die("%s: dpsm_get_cell_centres failed: %s", fn, dpsm_last_error(g));
        for (int64_t c = 0; c < ncells; ++c) {
            if (!(fabs(area[c] - expected[c]) <= 1e-6 * expected[c]))
                die("%s: cell %lld has area %.17g m2, l'Huilier's %.17g", fn, (long long)c, area[c], expected[c]);
            /* The centre: within the cell's box (a dual's: its node). */
            const int64_t i = dual ? c % (nx + 1) : c % nx, j = dual ? c / (nx + 1) : c / nx;
            const double slack = dual ? 1e-9 : 1e-9 + 0.0;
            const double lo_lon = lon0 + (double)i * step - slack, hi_lon = lon0 + (double)(i + (dual ? 0 : 1)) * step + slack;
            const double lo_lat = lat0 + (double)j * step - slack, hi_lat = lat0 + (double)(j + (dual ? 0 : 1)) * step + slack;
            if (!(xy[2 * c] >= lo_lon && xy[2 * c] <= hi_lon && xy[2 * c + 1] >= lo_lat && xy[2 * c + 1] <= hi_lat))
                die("%s: cell %lld stands at (%.17g, %.17g), outside [%.17g, %.17g] x [%.17g, %.17g]", fn, (long long)c,
                    xy[2 * c], xy[2 * c + 1], lo_lon, hi_lon, lo_lat, hi_lat);
            h[c] = c == ncells / 2 ? 1e3 * step : 0.0; /* a pile steep at any spacing */
        }
        double dt = 0.0;
        if (dpsm_stable_dt(g, &dt) != DPSM_OK || !(dt > 0.0) || !isfinite(dt)) die("%s: stable dt %g", fn, dt);
        char path[64];
        const char *dir = getenv("TMPDIR");
        snprintf(path, sizeof path, "%s/dpsm-fuzz-geo-%ld.dpsm", dir && *dir ? dir : "/tmp", (long)getpid());
        dpsm_grid *copy = NULL;
        if (dpsm_set_heights(g, h) != DPSM_OK || dpsm_save(g, path) != DPSM_OK || dpsm_load(path, &copy) != DPSM_OK)
            die("%s: set, save or load failed: %s / %s", fn, dpsm_last_error(g), dpsm_last_error(NULL));
        remove(path);
        if (dpsm_step(g, 2.0 * dt) != DPSM_OK || dpsm_step(copy, 2.0 * dt) != DPSM_OK)
            die("%s: a step failed: %s / %s", fn, dpsm_last_error(g), dpsm_last_error(copy));
        dpsm_get_heights(g, h);
        dpsm_get_heights(copy, h2);
        double total, sourced, external, outflow;
        dpsm_get_mass(g, DPSM_MASS_TOTAL, &total), dpsm_get_mass(g, DPSM_MASS_SOURCED, &sourced);
        dpsm_get_mass(g, DPSM_MASS_EXTERNAL, &external), dpsm_get_mass(g, DPSM_MASS_OUTFLOW, &outflow);
        if (fabs(total - (sourced + external - outflow)) > 1e-9 * fabs(external))
            die("%s: the ledger does not close: %.17g vs %.17g", fn, total, sourced + external - outflow);
        for (int64_t c = 0; c < ncells; ++c) {
            if (!(h[c] >= 0.0 && h[c] <= 1e3 * step)) die("%s: h[%lld] = %.17g left [0, %g]", fn, (long long)c, h[c], 1e3 * step);
            if (memcmp(&h[c], &h2[c], sizeof(double)) != 0)
                die("%s: the loaded copy steps cell %lld to %.17g, the mesh to %.17g", fn, (long long)c, h2[c], h[c]);
        }
        dpsm_destroy(copy);
        dpsm_destroy(g);
        free(expected), free(xy), free(area), free(h), free(h2);
    }
    free(lonlat), free(start), free(nodes);
}

static void op_geometry(reader_t *r) {
    const unsigned b = u8(r);
    if (b % 2 == 0) op_cell_centres_on_a_grid(r);
    else op_geographic_mesh(r, b);
}

/* ------------------------------------------------------------------------ */

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    reader_t r = {data, size, 0};
    g_work = 0.0;
    g_opcount = 0;
    memset(g_slots, 0, sizeof g_slots);
    while (more(&r) && g_opcount < 400) {
        ++g_opcount;
        /* Bytes from kLaterOps on name the operations added later, so that
         * older inputs (the corpus' regression_* files) replay as they did. */
        const unsigned byte = u8(&r),
                       op = byte == kMeshOp ? 26 : byte == kGeoOp ? 27 : byte >= kLaterOps ? 25 : byte % 25;
        if (op == 26)
            op_mesh(&r);
        else if (op == 27)
            op_geometry(&r);
        else if (op < 2)
            op_create(&r);
        else if (op < 9)
            op_parameter(&r, op - 2);
        else if (op == 9)
            op_kinds(&r);
        else if (op < 12)
            op_heights(&r);
        else if (op < 15)
            op_region(&r, op - 12);
        else if (op == 15)
            op_source(&r);
        else if (op < 20)
            op_step(&r);
        else if (op == 20)
            op_getters(&r);
        else if (op == 21)
            op_null_grid(&r);
        else if (op == 22)
            op_destroy(&r);
        else if (op == 23)
            op_physics(&r);
        else if (op == 24)
            op_relax(&r);
        else
            op_coupling(&r);
        /* Every live grid: the state invariants and the twin. */
        for (int k = 0; k < NSLOTS; ++k) {
            slot_t *s = &g_slots[k];
            if (!s->g) continue;
            snap_t now;
            snap(s->g, s, &now);
            note_mass_scale(s, &now);
            check_state(s, &now);
            compare_twin(s, &now);
            unsnap(&now);
        }
    }
    for (int k = 0; k < NSLOTS; ++k)
        if (g_slots[k].g) destroy_slot(&g_slots[k]);
    remove(restart_path());
    return 0;
}
