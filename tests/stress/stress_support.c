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

#define OK(s, call)                                                                                            \
    do {                                                                                                       \
        const int st_ = (call);                                                                                \
        REQUIRE(st_ == DPSM_OK, "[%s] %s returned %s: %s", (s)->name, #call, dpsm_status_string(st_),        \
                dpsm_last_error((s)->g));                                                                      \
    } while (0)

void stress_worst_reset(stress_worst_t *w) {
    memset(w, 0, sizeof *w);
    w->ledger = 0.0;
    w->new_max_pairwise = w->new_min_pairwise = -INFINITY;
    w->new_max_isotropic = w->new_min_isotropic = -INFINITY;
    w->rest_slope = -INFINITY;
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

static int any_side_open(const scene_t *s) { return s->open[0] || s->open[1] || s->open[2] || s->open[3]; }

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
}

void scene_destroy(scene_t *s) {
    dpsm_destroy(s->g);
    free(s->kinds);
    free(s->h);
    free(s->held);
    free(s->bed);
    free(s->tan_field);
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

void scene_set_source(scene_t *s, const double *q) {
    OK(s, dpsm_set_source(s->g, q));
    s->source = 0;
    if (q)
        for (int64_t c = 0; c < s->n; ++c)
            if (s->kinds[c] == DPSM_CELL_SAND && q[c] != 0.0) s->source = 1;
}

void scene_set_bed(scene_t *s, const double *zb) {
    OK(s, dpsm_set_bedrock(s->g, zb));
    free(s->bed);
    s->bed = NULL;
    if (!zb) return;
    s->bed = malloc(sizeof(double) * (size_t)s->n);
    REQUIRE(s->bed != NULL, "out of memory");
    memcpy(s->bed, zb, sizeof(double) * (size_t)s->n);
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
    /* face between cells a and b (b < 0: the outside of an open side, at 0) */
#define FACE(a, b, d)                                                                                  \
    do {                                                                                               \
        const int64_t a_ = (a), b_ = (b);                                                              \
        const double hb_ = b_ < 0 ? 0.0 : h[b_];                                                      \
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
            if (i + 1 < s->nx) FACE(c, c + 1, s->dx);
            if (j + 1 < s->ny) FACE(c, c + s->nx, s->dy);
            if (i == 0 && s->open[DPSM_XMIN] && s->geom != GEOM_AXI) FACE(c, -1, s->dx);
            if (i == s->nx - 1 && s->open[DPSM_XMAX]) FACE(c, -1, s->dx);
            if (s->geom == GEOM_2D && j == 0 && s->open[DPSM_YMIN]) FACE(c, -1, s->dy);
            if (s->geom == GEOM_2D && j == s->ny - 1 && s->open[DPSM_YMAX]) FACE(c, -1, s->dy);
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

int scene_driven(const scene_t *s) {
    if (s->source) return 1;
    int have = any_side_open(s);
    double level = 0.0;
    for (int64_t c = 0; c < s->n; ++c) {
        if (s->kinds[c] != DPSM_CELL_OPEN) continue;
        if (have && s->h[c] != level) return 1;
        level = s->h[c];
        have = 1;
    }
    return 0;
}

void scene_check(scene_t *s, stress_worst_t *w) { check_state(s, w, 0, 0.0, 0.0); }

int scene_step(scene_t *s, double dt, stress_worst_t *w) {
    /* The bounds of the maximum principle, from the state before the step. */
    double hi = -INFINITY, lo = INFINITY;
    for (int64_t c = 0; c < s->n; ++c)
        if (s->kinds[c] != DPSM_CELL_WALL) {
            hi = fmax(hi, s->h[c]);
            lo = fmin(lo, s->h[c]);
        }
    if (any_side_open(s)) {
        hi = fmax(hi, 0.0);
        lo = fmin(lo, 0.0);
    }
    const int st = dpsm_step(s->g, dt);
    REQUIRE(st == DPSM_OK, "[%s] dpsm_step(%g) returned %s: %s", s->name, dt, dpsm_status_string(st),
            dpsm_last_error(s->g));
    check_state(s, w, 1, hi, lo);
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
