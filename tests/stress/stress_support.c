#include "stress_support.h"

#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "test_support.h"

#ifndef DPSM_STRESS_SCALE_DEFAULT
#define DPSM_STRESS_SCALE_DEFAULT 1.0
#endif

static const double kTwoPi = 6.283185307179586476925;

stress_worst_t stress_worst;

#define OK(s, call) SCENE_OK(s, call)

void stress_worst_reset(stress_worst_t *w) {
    memset(w, 0, sizeof *w);
    w->ledger = 0.0;
    w->new_max_pairwise = w->new_min_pairwise = -INFINITY;
    w->new_max_isotropic = w->new_min_isotropic = -INFINITY;
    w->rest_slope = -INFINITY;
    w->fluxes = -INFINITY;
}

static void note(double *worst, char *where, double value, const char *name) {
    if (value > *worst) {
        *worst = value;
        snprintf(where, 160, "%s", name);
    }
}

void stress_worst_merge(const stress_worst_t *w) {
    note(&stress_worst.ledger, stress_worst.ledger_where, w->ledger, w->ledger_where);
    note(&stress_worst.new_max_pairwise, stress_worst.max_where, w->new_max_pairwise, w->max_where);
    note(&stress_worst.new_min_pairwise, stress_worst.min_where, w->new_min_pairwise, w->min_where);
    double iso = fmax(stress_worst.new_max_isotropic, stress_worst.new_min_isotropic);
    if (fmax(w->new_max_isotropic, w->new_min_isotropic) > iso) snprintf(stress_worst.iso_where, 160, "%s", w->iso_where);
    stress_worst.new_max_isotropic = fmax(stress_worst.new_max_isotropic, w->new_max_isotropic);
    stress_worst.new_min_isotropic = fmax(stress_worst.new_min_isotropic, w->new_min_isotropic);
    note(&stress_worst.rest_slope, stress_worst.rest_where, w->rest_slope, w->rest_where);
    note(&stress_worst.fluxes, stress_worst.fluxes_where, w->fluxes, w->fluxes_where);
    stress_worst.nonfinite += w->nonfinite;
    stress_worst.checks += w->checks;
    stress_worst.rest_checks += w->rest_checks;
}

/* -inf (nothing seen) prints as "n/a". */
static const char *fig(char *buf, double v) {
    if (v == -INFINITY)
        snprintf(buf, 32, "n/a");
    else
        snprintf(buf, 32, "%+.3e", v);
    return buf;
}

void stress_worst_print(const char *title, const stress_worst_t *w) {
    char a[32], b[32], c[32], d[32], e[32];
    print_message("%s: %ld states checked (%ld at rest), %ld non-finite heights\n", title, w->checks, w->rest_checks,
                  w->nonfinite);
    print_message("  worst ledger residual (relative)          %.3e  [%s]\n", w->ledger, w->ledger_where);
    print_message("  worst new max / min, pairwise, 1D, axisym %s / %s  [%s | %s]\n", fig(a, w->new_max_pairwise),
                  fig(b, w->new_min_pairwise), w->max_where, w->min_where);
    print_message("  worst new max / min, isotropic 2D         %s / %s  [%s]\n", fig(c, w->new_max_isotropic),
                  fig(d, w->new_min_isotropic), w->iso_where);
    print_message("  worst slope at rest / (tan(theta)(1+tol)) - 1: %s  [%s]\n", fig(e, w->rest_slope), w->rest_where);
    print_message("  worst face-flux balance of a cell (relative): %s  [%s]\n", fig(a, w->fluxes), w->fluxes_where);
    print_message("  (new max/min: relative to the largest |height|; <= 0 means none)\n");
}

double stress_scale(void) {
    const char *env = getenv("DPSM_STRESS_SCALE");
    double s = env && *env ? atof(env) : DPSM_STRESS_SCALE_DEFAULT;
    if (!(s > 0.0)) s = DPSM_STRESS_SCALE_DEFAULT;
    return s > 1.0 ? 1.0 : s;
}

int64_t scaled(int64_t n, int64_t lo) {
    const int64_t m = (int64_t)llround((double)n * stress_scale());
    return m < lo ? lo : m;
}

uint64_t rng_next(uint64_t *state) {
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

double rng_uniform(uint64_t *state) { return (double)(rng_next(state) >> 11) * (1.0 / 9007199254740992.0); }

/* ------------------------------------------------------------------------ */

static double cell_area(const scene_t *s, int64_t c) {
    if (s->geom == GEOM_AXI) return kTwoPi * ((double)c + 0.5) * s->dx * s->dx;
    if (s->geom == GEOM_1D) return s->dx;
    return s->dx * s->dy;
}

/* The faces along a side and the level beyond face k of it. */
static int64_t faces_along(const scene_t *s, int side) { return side <= DPSM_XMAX ? s->ny : s->nx; }
static double level_at(const scene_t *s, int side, int64_t k) { return s->levels[side] ? s->levels[side][k] : 0.0; }

void scene_create(scene_t *s, const char *name, int geom, int64_t nx, int64_t ny, double dx, double dy) {
    memset(s, 0, sizeof *s);
    snprintf(s->name, sizeof s->name, "%s", name);
    s->geom = geom;
    s->nx = nx;
    s->ny = geom == GEOM_2D ? ny : 1;
    s->n = s->nx * s->ny;
    s->dx = dx;
    s->dy = geom == GEOM_2D ? dy : 1.0;
    s->theta = DPSM_DEFAULT_REPOSE_ANGLE;
    s->tol = DPSM_DEFAULT_REST_TOLERANCE;
    s->scheme = geom == GEOM_2D ? DPSM_SCHEME_ISOTROPIC : DPSM_SCHEME_PAIRWISE;
    int st;
    if (geom == GEOM_1D)
        st = dpsm_create_1d(nx, dx, &s->g);
    else if (geom == GEOM_2D)
        st = dpsm_create_2d(nx, ny, dx, dy, &s->g);
    else
        st = dpsm_create_axisymmetric(nx, dx, &s->g);
    REQUIRE(st == DPSM_OK, "[%s] create: %s: %s", name, dpsm_status_string(st), dpsm_last_error(NULL));
    s->kinds = calloc((size_t)s->n, 1);
    s->h = calloc((size_t)s->n, sizeof(double));
    s->held = calloc((size_t)s->n, sizeof(double));
    REQUIRE(s->kinds && s->h && s->held, "out of memory");
    /* Every second scene records its face fluxes (the others keep the
     * kernels' in-place visits under stress). */
    static unsigned scenes_made;
    s->record = scenes_made++ % 2;
    if (s->record) OK(s, dpsm_set_face_flux_recording(s->g, 1));
}

void scene_destroy(scene_t *s) {
    dpsm_destroy(s->g);
    free(s->kinds);
    free(s->h);
    free(s->held);
    free(s->bed);
    free(s->tan_field);
    free(s->q);
    for (int side = 0; side < 4; ++side) free(s->levels[side]);
    memset(s, 0, sizeof *s);
}

void scene_set_scheme(scene_t *s, int scheme) {
    OK(s, dpsm_set_scheme(s->g, scheme));
    if (s->geom == GEOM_2D) s->scheme = scheme;
}

void scene_set_angle(scene_t *s, double theta) {
    OK(s, dpsm_set_repose_angle(s->g, theta));
    s->theta = theta;
}

void scene_set_tolerance(scene_t *s, double tol) {
    OK(s, dpsm_set_rest_tolerance(s->g, tol));
    s->tol = tol;
}

void scene_set_side(scene_t *s, int side, int open) {
    OK(s, dpsm_set_boundary(s->g, side, open ? DPSM_OPEN : DPSM_WALL));
    s->open[side] = open;
}

void scene_set_all_sides(scene_t *s, int open) {
    if (s->geom != GEOM_AXI) scene_set_side(s, DPSM_XMIN, open);
    scene_set_side(s, DPSM_XMAX, open);
    if (s->geom == GEOM_2D) {
        scene_set_side(s, DPSM_YMIN, open);
        scene_set_side(s, DPSM_YMAX, open);
    }
}

/* After a host change: the held heights, and the largest gross mass the
 * grid has held (every cell, sand or not: a cell that stops being sand takes
 * its mass off the ledger), the scale of the round-off the ledger may carry. */
static void refresh_held(scene_t *s) {
    OK(s, dpsm_get_heights(s->g, s->h));
    memcpy(s->held, s->h, sizeof(double) * (size_t)s->n);
    double gross = 0.0;
    for (int64_t c = 0; c < s->n; ++c) gross += fabs(s->h[c]) * cell_area(s, c);
    s->mass_scale = fmax(s->mass_scale, gross);
}

void scene_set_kinds(scene_t *s, const uint8_t *kinds) {
    OK(s, dpsm_set_cell_kinds(s->g, kinds));
    if (kinds)
        memcpy(s->kinds, kinds, (size_t)s->n);
    else
        memset(s->kinds, DPSM_CELL_SAND, (size_t)s->n);
    refresh_held(s);
}

void scene_set_heights(scene_t *s, const double *h) {
    OK(s, dpsm_set_heights(s->g, h));
    refresh_held(s);
}

/* A copy of n values (NULL for NULL). */
static double *copy_of(const double *values, int64_t n) {
    if (!values) return NULL;
    double *copy = malloc(sizeof(double) * (size_t)n);
    REQUIRE(copy != NULL, "out of memory");
    memcpy(copy, values, sizeof(double) * (size_t)n);
    return copy;
}

void scene_set_source(scene_t *s, const double *q) {
    OK(s, dpsm_set_source(s->g, q));
    s->source = 0;
    if (q)
        for (int64_t c = 0; c < s->n; ++c)
            if (s->kinds[c] == DPSM_CELL_SAND && q[c] != 0.0) s->source = 1;
    free(s->q);
    s->q = copy_of(q, s->n);
}

void scene_set_side_levels(scene_t *s, int side, const double *levels) {
    OK(s, dpsm_set_side_levels(s->g, side, levels));
    free(s->levels[side]);
    s->levels[side] = copy_of(levels, faces_along(s, side));
}

void scene_set_bed(scene_t *s, const double *zb) {
    OK(s, dpsm_set_bedrock(s->g, zb));
    free(s->bed);
    s->bed = copy_of(zb, s->n);
    refresh_held(s); /* a bed above a cell lifts it, held cells too */
}

void scene_set_angle_field(scene_t *s, const double *theta) {
    OK(s, dpsm_set_repose_angle_field(s->g, theta));
    free(s->tan_field);
    s->tan_field = NULL;
    if (!theta) return;
    s->tan_field = malloc(sizeof(double) * (size_t)s->n);
    REQUIRE(s->tan_field != NULL, "out of memory");
    for (int64_t c = 0; c < s->n; ++c) s->tan_field[c] = tan(theta[c]);
}

void scene_set_static_angle(scene_t *s, double theta) {
    OK(s, dpsm_set_static_angle(s->g, theta));
    s->tan_static = tan(theta);
}

void scene_set_flux_exponent(scene_t *s, double p) { OK(s, dpsm_set_flux_exponent(s->g, p)); }

double scene_ledger_residual(const scene_t *s) {
    double m[4];
    for (int q = 0; q < 4; ++q) OK(s, dpsm_get_mass(s->g, q, &m[q]));
    double scale = fmax(fmax(fabs(m[0]), fabs(m[1])), fmax(fabs(m[2]), fabs(m[3])));
    double gross = 0.0;
    for (int64_t c = 0; c < s->n; ++c)
        if (s->kinds[c] == DPSM_CELL_SAND) gross += fabs(s->h[c]) * cell_area(s, c);
    scale = fmax(scale, fmax(gross, s->mass_scale));
    if (scale == 0.0) return fabs(m[0] - (m[1] + m[2] - m[3]));
    return fabs(m[0] - (m[1] + m[2] - m[3])) / scale;
}

/* The rest threshold of the face between a and b (b < 0: outside, of kind kb):
 * tan(theta) (1 + tol), with an angle field the mean of the two cells' tan
 * (a sand cell's own where the other is not sand), and at least the static
 * angle's tan: at rest no cell is moving. */
static double face_threshold(const scene_t *s, int64_t a, int64_t b, int kb) {
    double tan_face = tan(s->theta);
    if (s->tan_field) {
        const int a_sand = s->kinds[a] == DPSM_CELL_SAND, b_sand = kb == DPSM_CELL_SAND;
        const double ta = a_sand ? s->tan_field[a] : s->tan_field[b];
        const double tb = b_sand ? s->tan_field[b] : ta;
        tan_face = 0.5 * (ta + tb);
    }
    return fmax(tan_face * (1.0 + s->tol), s->tan_static);
}

/* The largest |dh| / d over faces that can carry sand, relative to
 * tan(theta) (1 + tol), minus 1, with the rounding of the slope itself
 * allowed for. */
static double rest_excess(const scene_t *s, int64_t *where) {
    double worst = -INFINITY;
    /* The film of sand above the bed that dpsm leaves in place: tol tan of
     * the smallest angle times the smaller spacing (a little more, for the
     * rounding of the comparison). */
    double smallest_tan = tan(s->theta);
    if (s->tan_field)
        for (int64_t c = 0; c < s->n; ++c) smallest_tan = fmin(smallest_tan, s->tan_field[c]);
    const double spacing = s->geom == GEOM_2D ? fmin(s->dx, s->dy) : s->dx;
    const double film = s->tol * smallest_tan * spacing * (1.0 + 1e-9);
    const double *h = s->h;
    const uint8_t *k = s->kinds;
    /* face between cells a and b (b < 0: the outside of an open side, held at `outside`) */
#define FACE(a, b, d, outside)                                                                         \
    do {                                                                                               \
        const int64_t a_ = (a), b_ = (b);                                                              \
        const double hb_ = b_ < 0 ? (outside) : h[b_];                                                \
        const int kb_ = b_ < 0 ? DPSM_CELL_OPEN : k[b_];                                              \
        if (k[a_] == DPSM_CELL_WALL || kb_ == DPSM_CELL_WALL) break;                                  \
        if (k[a_] != DPSM_CELL_SAND && kb_ != DPSM_CELL_SAND) break;                                  \
        const double threshold = face_threshold(s, a_, b_, kb_);                                       \
        const int64_t up_ = h[a_] >= hb_ ? a_ : b_;                                                    \
        if (s->bed && up_ >= 0 && k[up_] == DPSM_CELL_SAND && h[up_] - s->bed[up_] <= film) break;     \
        const double slope_ = fabs(h[a_] - hb_) / (d);                                                \
        const double slack_ = 4.0 * DBL_EPSILON * fmax(fabs(h[a_]), fabs(hb_)) / (d);                 \
        const double r_ = (slope_ - slack_) / threshold - 1.0;                                        \
        if (r_ > worst) {                                                                              \
            worst = r_;                                                                                \
            *where = a_;                                                                               \
        }                                                                                              \
    } while (0)
    for (int64_t j = 0; j < s->ny; ++j)
        for (int64_t i = 0; i < s->nx; ++i) {
            const int64_t c = i + s->nx * j;
            if (i + 1 < s->nx) FACE(c, c + 1, s->dx, 0.0);
            if (j + 1 < s->ny) FACE(c, c + s->nx, s->dy, 0.0);
            if (i == 0 && s->open[DPSM_XMIN] && s->geom != GEOM_AXI) FACE(c, -1, s->dx, level_at(s, DPSM_XMIN, j));
            if (i == s->nx - 1 && s->open[DPSM_XMAX]) FACE(c, -1, s->dx, level_at(s, DPSM_XMAX, j));
            if (s->geom == GEOM_2D && j == 0 && s->open[DPSM_YMIN]) FACE(c, -1, s->dy, level_at(s, DPSM_YMIN, i));
            if (s->geom == GEOM_2D && j == s->ny - 1 && s->open[DPSM_YMAX])
                FACE(c, -1, s->dy, level_at(s, DPSM_YMAX, i));
        }
#undef FACE
    return worst;
}

static void check_state(scene_t *s, stress_worst_t *w, int stepped, double hi, double lo) {
    ++w->checks;
    OK(s, dpsm_get_heights(s->g, s->h));
    long bad = 0;
    int64_t first_bad = -1;
    for (int64_t c = 0; c < s->n; ++c)
        if (!isfinite(s->h[c])) {
            if (first_bad < 0) first_bad = c;
            ++bad;
        }
    w->nonfinite += bad;
    REQUIRE(bad == 0, "[%s] %ld heights are not finite, the first at cell %lld: %g", s->name, bad,
            (long long)first_bad, first_bad >= 0 ? s->h[first_bad] : 0.0);

    if (s->bed)
        for (int64_t c = 0; c < s->n; ++c)
            REQUIRE(s->kinds[c] != DPSM_CELL_SAND || s->h[c] >= s->bed[c],
                    "[%s] sand cell %lld at %.17g is below its bed %.17g", s->name, (long long)c, s->h[c], s->bed[c]);
    for (int64_t c = 0; c < s->n; ++c)
        if (s->kinds[c] != DPSM_CELL_SAND)
            REQUIRE(memcmp(&s->h[c], &s->held[c], sizeof(double)) == 0,
                    "[%s] the held height of %s cell %lld changed from %.17g to %.17g", s->name,
                    s->kinds[c] == DPSM_CELL_WALL ? "wall" : "open", (long long)c, s->held[c], s->h[c]);

    const double ledger = scene_ledger_residual(s);
    note(&w->ledger, w->ledger_where, ledger, s->name);
    if (!(ledger <= 1e-12)) {
        double m[4];
        for (int q = 0; q < 4; ++q) OK(s, dpsm_get_mass(s->g, q, &m[q]));
        REQUIRE(0,
                "[%s] the mass ledger does not close: relative residual %.3e (total %.17g, sourced %.17g, external "
                "%.17g, outflow %.17g)",
                s->name, ledger, m[0], m[1], m[2], m[3]);
    }

    if (stepped && !s->source) {
        double top = -INFINITY, bottom = INFINITY;
        for (int64_t c = 0; c < s->n; ++c)
            if (s->kinds[c] == DPSM_CELL_SAND) {
                top = fmax(top, s->h[c]);
                bottom = fmin(bottom, s->h[c]);
            }
        if (top != -INFINITY) {
            const double magnitude = fmax(fmax(fabs(hi), fabs(lo)), DBL_MIN);
            const double over = (top - hi) / magnitude, under = (lo - bottom) / magnitude;
            const int pairwise = s->geom != GEOM_2D || s->scheme == DPSM_SCHEME_PAIRWISE;
            if (pairwise) {
                note(&w->new_max_pairwise, w->max_where, over, s->name);
                note(&w->new_min_pairwise, w->min_where, under, s->name);
                REQUIRE(over <= 4 * DBL_EPSILON && under <= 4 * DBL_EPSILON,
                        "[%s] new extremum without a source: max %.17g over the bound %.17g, min %.17g under %.17g",
                        s->name, top, hi, bottom, lo);
            } else {
                if (fmax(over, under) > fmax(w->new_max_isotropic, w->new_min_isotropic))
                    snprintf(w->iso_where, 160, "%s", s->name);
                w->new_max_isotropic = fmax(w->new_max_isotropic, over);
                w->new_min_isotropic = fmax(w->new_min_isotropic, under);
                REQUIRE(over <= 4 * DBL_EPSILON && under <= 4 * DBL_EPSILON,
                        "[%s] isotropic scheme: new extremum without a source: max %.17g over the bound %.17g, "
                        "min %.17g under %.17g",
                        s->name, top, hi, bottom, lo);
            }
        }
    }
}

/* Calls held(level) for every level the scene holds: open cells' heights and
 * the levels beyond open sides; stops at the first that returns nonzero. */
static int for_held_levels(const scene_t *s, int (*held)(double level, void *state), void *state) {
    for (int side = 0; side < 4; ++side)
        if (s->open[side])
            for (int64_t k = 0; k < faces_along(s, side); ++k)
                if (held(level_at(s, side, k), state)) return 1;
    for (int64_t c = 0; c < s->n; ++c)
        if (s->kinds[c] == DPSM_CELL_OPEN && held(s->h[c], state)) return 1;
    return 0;
}

typedef struct {
    int have;
    double level, lo, hi;
} held_range_t;

static int differs(double level, void *state) {
    held_range_t *r = state;
    if (r->have && level != r->level) return 1;
    r->level = level;
    r->have = 1;
    return 0;
}

static int widen(double level, void *state) {
    held_range_t *r = state;
    r->hi = fmax(r->hi, level);
    r->lo = fmin(r->lo, level);
    return 0;
}

int scene_driven(const scene_t *s) {
    if (s->source) return 1;
    held_range_t range = {0, 0.0, 0.0, 0.0};
    return for_held_levels(s, differs, &range);
}

void scene_check(scene_t *s, stress_worst_t *w) { check_state(s, w, 0, 0.0, 0.0); }

/* What the face fluxes are checked against: the ledger's figures and each
 * side's account. */
typedef struct {
    double sourced, outflow, side[4];
} accounts_t;

static accounts_t accounts_of(const scene_t *s) {
    accounts_t a = {0.0, 0.0, {0.0, 0.0, 0.0, 0.0}};
    OK(s, dpsm_get_mass(s->g, DPSM_MASS_SOURCED, &a.sourced));
    OK(s, dpsm_get_mass(s->g, DPSM_MASS_OUTFLOW, &a.outflow));
    for (int side = 0; side < 4; ++side)
        if (dpsm_get_side_outflow(s->g, side, &a.side[side]) != DPSM_OK) a.side[side] = 0.0;
    return a;
}

/* The step that took the scene from h0 (and the accounts `before`) to s->h:
 * its fluxes against every sand cell, the walls, the sides and the outflow
 * (stress_support.h). */
static void check_fluxes(const scene_t *s, const double *h0, const accounts_t *before, stress_worst_t *w) {
    const accounts_t after = accounts_of(s);
    double time = 0.0, substeps = 0.0;
    OK(s, dpsm_get_step_info(s->g, DPSM_INFO_TIME_INTEGRATED, &time));
    OK(s, dpsm_get_step_info(s->g, DPSM_INFO_SUBSTEPS, &substeps));
    const double rel = 1e-11 + 16.0 * DBL_EPSILON * fmax(substeps, 1.0);
    const int64_t nfx = (s->nx + 1) * s->ny, nfy = s->geom == GEOM_2D ? s->nx * (s->ny + 1) : 0;
    double *fx = malloc(sizeof(double) * (size_t)nfx), *fy = malloc(sizeof(double) * (size_t)(nfy + 1));
    REQUIRE(fx && fy, "out of memory");
    OK(s, dpsm_get_face_fluxes(s->g, fx, nfy ? fy : NULL));
    double applied = 0.0, scale_all = fabs(before->sourced) + fabs(before->outflow) + fabs(after.outflow);
    double into_open = 0.0;
    for (int64_t j = 0; j < s->ny; ++j)
        for (int64_t i = 0; i < s->nx; ++i) {
            const int64_t c = i + s->nx * j, x = i + (s->nx + 1) * j, y = i + s->nx * j;
            double in = fx[x] - fx[x + 1], gross = fabs(fx[x]) + fabs(fx[x + 1]);
            if (nfy) {
                in += fy[y] - fy[y + s->nx];
                gross += fabs(fy[y]) + fabs(fy[y + s->nx]);
            }
            if (s->kinds[c] == DPSM_CELL_WALL) {
                REQUIRE(gross == 0.0, "[%s] the faces of wall cell %lld carried %g", s->name, (long long)c, gross);
                continue;
            }
            scale_all += gross;
            if (s->kinds[c] == DPSM_CELL_OPEN) {
                into_open += in;
                continue;
            }
            const double area = cell_area(s, c), q = s->q ? s->q[c] : 0.0;
            const double source = (s->h[c] - h0[c]) * area - in, want = q * time * area;
            const double scale = (fabs(h0[c]) + fabs(s->h[c])) * area + gross + fabs(want);
            const double tol = rel * scale + DBL_MIN;
            applied += source;
            scale_all += scale;
            if (s->bed && q < 0.0)
                REQUIRE(source >= want - tol && source <= tol,
                        "[%s] cell %lld on its bed lost %.17g to erosion that asked %.17g", s->name, (long long)c,
                        source, want);
            else {
                note(&w->fluxes, w->fluxes_where, fabs(source - want) / (scale + DBL_MIN), s->name);
                REQUIRE(fabs(source - want) <= tol,
                        "[%s] cell %lld changed by %.17g, its faces brought %.17g, its source %.17g (off by %.3g of %.3g)",
                        s->name, (long long)c, (s->h[c] - h0[c]) * area, in, want, source - want, scale);
            }
        }
    REQUIRE(fabs(applied - (after.sourced - before->sourced)) <= rel * scale_all + DBL_MIN,
            "[%s] the cells took %.17g from their sources, SOURCED grew by %.17g", s->name, applied,
            after.sourced - before->sourced);
    double sides = 0.0;
    for (int side = 0; side < 4; ++side) {
        double out = 0.0, gross = 0.0;
        for (int64_t k = 0; k < (side <= DPSM_XMAX || nfy ? faces_along(s, side) : 0); ++k) {
            const double v = side == DPSM_XMIN   ? -fx[(s->nx + 1) * k]
                             : side == DPSM_XMAX ? fx[s->nx + (s->nx + 1) * k]
                             : side == DPSM_YMIN ? -fy[k]
                                                 : fy[k + s->nx * s->ny];
            out += v;
            gross += fabs(v);
        }
        const double booked = after.side[side] - before->side[side];
        REQUIRE(s->open[side] || (gross == 0.0 && booked == 0.0), "[%s] wall side %d: faces %g, account %g", s->name,
                side, gross, booked);
        REQUIRE(fabs(out - booked) <= rel * (gross + fabs(before->side[side]) + fabs(after.side[side])) + DBL_MIN,
                "[%s] side %d: its faces carried %.17g out, its account took %.17g", s->name, side, out, booked);
        sides += booked;
        scale_all += gross + fabs(before->side[side]) + fabs(after.side[side]);
    }
    REQUIRE(fabs(after.outflow - before->outflow - sides - into_open) <= rel * scale_all + DBL_MIN,
            "[%s] OUTFLOW grew by %.17g; the sides took %.17g, the open cells %.17g", s->name,
            after.outflow - before->outflow, sides, into_open);
    free(fx);
    free(fy);
}

int scene_step(scene_t *s, double dt, stress_worst_t *w) {
    /* The bounds of the maximum principle, from the state before the step. */
    held_range_t range = {0, 0.0, INFINITY, -INFINITY};
    for (int64_t c = 0; c < s->n; ++c)
        if (s->kinds[c] != DPSM_CELL_WALL) widen(s->h[c], &range);
    for_held_levels(s, widen, &range);
    const double hi = range.hi, lo = range.lo;
    double *h0 = s->record ? copy_of(s->h, s->n) : NULL;
    const accounts_t before = s->record ? accounts_of(s) : (accounts_t){0.0, 0.0, {0.0, 0.0, 0.0, 0.0}};
    const int st = dpsm_step(s->g, dt);
    REQUIRE(st == DPSM_OK, "[%s] dpsm_step(%g) returned %s: %s", s->name, dt, dpsm_status_string(st),
            dpsm_last_error(s->g));
    check_state(s, w, 1, hi, lo);
    if (s->record) check_fluxes(s, h0, &before, w);
    free(h0);
    double at_rest = 0.0;
    OK(s, dpsm_get_step_info(s->g, DPSM_INFO_AT_REST, &at_rest));
    /* A driven scene may stand still while sand runs through it (2D reports
     * that as rest): the slope bound is for scenes that rest by themselves. */
    if (at_rest == 1.0 && !scene_driven(s)) {
        ++w->rest_checks;
        int64_t where = -1;
        const double excess = rest_excess(s, &where);
        if (excess > w->rest_slope) {
            w->rest_slope = excess;
            snprintf(w->rest_where, 160, "%s", s->name);
        }
        REQUIRE(excess <= 1e-12, "[%s] reported at rest with a face at cell %lld steeper than tan(theta)(1+tol) by %.3e",
                s->name, (long long)where, excess);
    }
    return at_rest == 1.0;
}

void scene_run_to_rest(scene_t *s, double dt, int max_calls, stress_worst_t *w) {
    for (int k = 0; k < max_calls; ++k)
        if (scene_step(s, dt, w)) return;
    REQUIRE(0, "[%s] not at rest after %d steps of %g", s->name, max_calls, dt);
}

/* Everything dpsm shows of a grid, to compare bit for bit. */
typedef struct {
    double *h;
    double mass[4], info[4], stable_dt;
} snap_t;

static void snap(dpsm_grid *g, int64_t ncells, snap_t *out) {
    out->h = malloc(sizeof(double) * (size_t)ncells);
    REQUIRE(out->h != NULL, "out of memory");
    REQUIRE(dpsm_get_heights(g, out->h) == DPSM_OK, "get_heights");
    for (int q = 0; q < 4; ++q) REQUIRE(dpsm_get_mass(g, q, &out->mass[q]) == DPSM_OK, "get_mass");
    for (int i = 0; i < 4; ++i) REQUIRE(dpsm_get_step_info(g, i, &out->info[i]) == DPSM_OK, "get_step_info");
    REQUIRE(dpsm_stable_dt(g, &out->stable_dt) == DPSM_OK, "stable_dt");
}

void expect_step_refused_on(dpsm_grid *g, int64_t ncells, const char *name, double dt, int status,
                            const char *needle) {
    snap_t a, b;
    snap(g, ncells, &a);
    const int st = dpsm_step(g, dt);
    const char *msg = dpsm_last_error(g);
    REQUIRE(st == status, "[%s] dpsm_step(%g) returned %s, expected %s (%s)", name, dt, dpsm_status_string(st),
            dpsm_status_string(status), msg);
    REQUIRE(strstr(msg, "dpsm_step") && strstr(msg, "dt") && strstr(msg, needle),
            "[%s] the message does not say what to do (%s): \"%s\"", name, needle, msg);
    snap(g, ncells, &b);
    const char *what = dpsm_status_string(status);
    REQUIRE(memcmp(a.h, b.h, sizeof(double) * (size_t)ncells) == 0, "[%s] after %s: heights changed", name, what);
    REQUIRE(memcmp(a.mass, b.mass, sizeof a.mass) == 0, "[%s] after %s: the ledger changed", name, what);
    REQUIRE(memcmp(a.info, b.info, sizeof a.info) == 0, "[%s] after %s: the step information changed", name, what);
    REQUIRE(memcmp(&a.stable_dt, &b.stable_dt, sizeof(double)) == 0, "[%s] after %s: stable_dt changed", name, what);
    free(a.h);
    free(b.h);
}

void expect_work_limit_on(dpsm_grid *g, int64_t ncells, const char *name, double dt) {
    expect_step_refused_on(g, ncells, name, dt, DPSM_ERR_WORK_LIMIT, "dpsm_set_max_substeps");
}
