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
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <dpsm/dpsm.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* ------------------------------------------------------------------------ */
/* Reading the input                                                         */
/* ------------------------------------------------------------------------ */

typedef struct {
    const uint8_t *p;
    size_t n, at;
} reader_t;

static unsigned u8(reader_t *r) { return r->at < r->n ? r->p[r->at++] : 0u; }
static unsigned u16(reader_t *r) { return u8(r) | (u8(r) << 8); }
static int more(const reader_t *r) { return r->at < r->n; }

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
/* Failing loudly                                                            */
/* ------------------------------------------------------------------------ */

static const char *g_op = "?"; /* the operation under way, for messages */
static long g_opcount;

/* DPSM_FUZZ_TRACE=1: one line per call on stderr (to see what an input does). */
static int trace_on(void) {
    static int on = -1;
    if (on < 0) {
        const char *e = getenv("DPSM_FUZZ_TRACE");
        on = e && *e && *e != '0';
    }
    return on;
}
static void trace(const char *fmt, ...) {
    if (!trace_on()) return;
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "  [%ld] ", g_opcount);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\n");
}

static void die(const char *fmt, ...) {
    va_list ap;
    fprintf(stderr, "\ndpsm fuzz: check failed in operation %ld (%s): ", g_opcount, g_op);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\n");
    abort();
}

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
#ifdef DPSM_INFO_CELL_UPDATES
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
                                             "CELL_UPDATES", "?", "?", "?"};
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
            const int v = values[u8(r) % COUNT(values)];
            ON_BOTH(s, v >= 0 ? DPSM_OK : DPSM_ERR_INVALID_VALUE, g_op, dpsm_set_threads(g_, v));
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
    if (at_rest == 1.0 && !drives) {
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
    switch (b >= kLaterOps ? 25 + (b - kLaterOps) % 4 : b % 25) {
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

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    reader_t r = {data, size, 0};
    g_work = 0.0;
    g_opcount = 0;
    memset(g_slots, 0, sizeof g_slots);
    while (more(&r) && g_opcount < 400) {
        ++g_opcount;
        /* Bytes from kLaterOps on name the operations added later, so that
         * older inputs (the corpus' regression_* files) replay as they did. */
        const unsigned byte = u8(&r), op = byte >= kLaterOps ? 25 : byte % 25;
        if (op < 2)
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
