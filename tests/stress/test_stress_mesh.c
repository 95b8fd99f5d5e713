/* The numerical stress suite on unstructured meshes (ctest stress_mesh): the
 * mesh engine driven far from the comfortable middle, on four kinds of mesh
 * built here (bench/mesh_scenes.c): jittered triangles without slivers
 * (dpsm_create_mesh), hexagons (dpsm_create_mesh), the same hexagons as a
 * finite-volume graph (dpsm_create_graph) and the median dual of the
 * triangles (dpsm_create_dual_mesh). The scenes:
 *
 *   time steps from 1e-12 to 1e12, with and without a source; a step that
 *   needs more sub-steps than the limit in a scene that may flow for ever
 *   fails with DPSM_ERR_WORK_LIMIT and changes nothing, bit for bit;
 *   height jumps from 1e-9 to 1e6 (a vertical wall of sand), on cells of 1
 *   and on cells of the jump's size;
 *   angles of repose from 0.5 to 89.5 degrees, two rest tolerances;
 *   random rough terrains, with open domain edges (every face, or some faces
 *   and not others: dpsm_set_edge_kinds) held at levels above and below the
 *   sand that differ face by face, then all at one level, to rest;
 *   walls, open cells and sources mixed; erosion (far more than there is)
 *   and deposition over a bed;
 *   many small steps;
 *   local time steps (DPSM_RELAX_LOCAL_STEPS) on graded meshes: time steps,
 *   rough terrains under open edges, walls, sinks and sources, a bed.
 *
 * After every step one function (check_step) checks: every height finite;
 * the ledger closes (TOTAL = SOURCED + EXTERNAL - OUTFLOW to 1e-12 of the
 * largest mass); without a source no sand cell leaves the range of the sand
 * and the held levels (open cells, open edge faces) before the step (no new
 * extremum, docs/guarantees.md "Meshes"); wall and open cells keep their
 * heights bit for bit; no sand below the bed; on every second scene, which
 * records its face fluxes, each sand cell's change of height times its area
 * equals its faces' fluxes plus its source times the step, within its
 * allowance: 1e-9 of the largest face (or source) volume, and 16 ulps of its
 * heights times its area, which is all a step of 1e-12 can change a height
 * by (with a bed, erosion takes at most what it asked), faces of walls and
 * closed edge faces carry nothing, the open edge faces carry what
 * DPSM_MESH_EDGE booked and, with the open cells, what OUTFLOW booked; when the step reports
 * DPSM_INFO_AT_REST, DPSM_INFO_MAX_EXCESS_SLOPE (|grad h| - tan(theta) over
 * the faces that carried sand in the last sub-step: 0 at rest, dpsm.h) is
 * within the rest tolerance, and on the meshes whose faces are orthogonal to
 * the line between their cells (hexagons, the graph), where a face's part
 * across it is its two-point slope, no face between two cells that can carry
 * sand is steeper than tan(theta) (1 + tol) by its two-point slope alone.
 *
 * Each test prints its worst figures; the last prints the worst over all.
 * DPSM_STRESS_SCALE scales the meshes' cells per side and the step counts as
 * it scales the grids of test_stress.c. */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

/* bench/mesh_scenes.h and stress_support.h both name a function scene_create:
 * the copy of mesh_scenes.c linked here is compiled with this name
 * (tests/stress/CMakeLists.txt). */
#define scene_create mesh_scene_create
#include "mesh_scenes.h"
#undef scene_create

#include "stress_support.h"
#include "test_support.h"

static const double kPi = 3.14159265358979323846;
static double deg(double d) { return d * kPi / 180.0; }

static void *zeroed(size_t n, size_t size) {
    void *p = calloc(n ? n : 1, size);
    REQUIRE(p != NULL, "out of memory");
    return p;
}

static double *copy_of(const double *v, int64_t n) {
    if (!v) return NULL;
    double *c = zeroed((size_t)n, sizeof(double));
    memcpy(c, v, sizeof(double) * (size_t)n);
    return c;
}

/* ------------------------------------------------------------------------ */
/* Meshes                                                                    */
/* ------------------------------------------------------------------------ */

enum { MESH_TRIANGLES, MESH_HEXAGONS, MESH_GRAPH, MESH_DUAL, NKINDS };
static const char *const kKindNames[NKINDS] = {"jittered triangles", "hexagons", "hexagons as a graph", "median dual"};

typedef struct {
    int kind;
    mesh_scene geo; /* polygons or, for the dual, its triangles; cells' centres and areas */
    /* The graph: faces as dpsm_create_graph takes them. */
    int64_t gfaces;
    int64_t *gcells;
    double *gxy, *glen;
} mesh_t;

typedef struct {
    int64_t lo, hi, cell;
    double x, y, len;
} edge_t;

static int edge_order(const void *pa, const void *pb) {
    const edge_t *a = pa, *b = pb;
    if (a->lo != b->lo) return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi) return a->hi < b->hi ? -1 : 1;
    return (a->cell > b->cell) - (a->cell < b->cell);
}

/* The finite-volume graph of a polygon mesh: a face for each edge shared by
 * two polygons, one on the domain edge for each edge of one polygon. */
static void make_graph(mesh_t *m) {
    const mesh_scene *p = &m->geo;
    const int64_t nedges = p->cell_start[p->npolygons];
    edge_t *e = zeroed((size_t)nedges, sizeof(edge_t));
    for (int64_t c = 0; c < p->npolygons; ++c) {
        const int64_t k0 = p->cell_start[c], count = p->cell_start[c + 1] - k0;
        for (int64_t k = 0; k < count; ++k) {
            const int64_t u = p->cell_nodes[k0 + k], v = p->cell_nodes[k0 + (k + 1) % count];
            const double *pu = p->node_xy + 2 * u, *pv = p->node_xy + 2 * v;
            e[k0 + k] = (edge_t){u < v ? u : v, u < v ? v : u, c, 0.5 * (pu[0] + pv[0]), 0.5 * (pu[1] + pv[1]),
                                 hypot(pv[0] - pu[0], pv[1] - pu[1])};
        }
    }
    qsort(e, (size_t)nedges, sizeof *e, edge_order);
    m->gcells = zeroed(2 * (size_t)nedges, sizeof(int64_t));
    m->gxy = zeroed(2 * (size_t)nedges, sizeof(double));
    m->glen = zeroed((size_t)nedges, sizeof(double));
    int64_t f = 0;
    for (int64_t k = 0; k < nedges; ++f) {
        const int shared = k + 1 < nedges && e[k + 1].lo == e[k].lo && e[k + 1].hi == e[k].hi;
        m->gcells[2 * f] = e[k].cell;
        m->gcells[2 * f + 1] = shared ? e[k + 1].cell : -1;
        m->gxy[2 * f] = e[k].x, m->gxy[2 * f + 1] = e[k].y, m->glen[f] = e[k].len;
        k += shared ? 2 : 1;
    }
    m->gfaces = f;
    free(e);
}

static dpsm_grid *mesh_create(const mesh_t *m);

/* A mesh of about n cells along each side of [-half, half]^2. Graded: its
 * nodes moved by u -> half sinh(2.5 u / half) / sinh(2.5) along x and y, so
 * that its cells grow about 2.5 times from the centre to the edges (their
 * stable bounds about 6 times: local time steps take several classes), its
 * cells' centres and areas as dpsm finds them. */
static mesh_t mesh_make(int kind, int n, double half, unsigned seed, int graded) {
    mesh_t m;
    memset(&m, 0, sizeof m);
    m.kind = kind;
    static const scene_kind geo[NKINDS] = {SCENE_TRIANGLES, SCENE_HEXAGONS, SCENE_HEXAGONS, SCENE_DUAL};
    m.geo = scene_make(geo[kind], n, half, seed);
    REQUIRE(m.geo.cells > 0, "no cells in a %s mesh of n = %d", kKindNames[kind], n);
    if (graded) {
        for (int64_t k = 0; k < 2 * m.geo.nnodes; ++k)
            m.geo.node_xy[k] = half * sinh(2.5 * m.geo.node_xy[k] / half) / sinh(2.5);
        mesh_t polygons = m;
        polygons.kind = kind == MESH_GRAPH ? MESH_HEXAGONS : kind;
        dpsm_grid *g = mesh_create(&polygons);
        double *xy = zeroed(2 * (size_t)m.geo.cells, sizeof(double));
        REQUIRE(dpsm_get_cell_centres(g, xy, m.geo.area) == DPSM_OK, "%s", dpsm_last_error(g));
        for (int64_t c = 0; c < m.geo.cells; ++c) m.geo.cx[c] = xy[2 * c], m.geo.cy[c] = xy[2 * c + 1];
        free(xy);
        dpsm_destroy(g);
    }
    if (kind == MESH_GRAPH) make_graph(&m);
    return m;
}

static void mesh_free(mesh_t *m) {
    scene_free(&m->geo);
    free(m->gcells), free(m->gxy), free(m->glen);
    memset(m, 0, sizeof *m);
}

static dpsm_grid *mesh_create(const mesh_t *m) {
    dpsm_grid *g = NULL;
    const mesh_scene *p = &m->geo;
    int st;
    if (m->kind == MESH_GRAPH) {
        double *xy = zeroed(2 * (size_t)p->cells, sizeof(double));
        for (int64_t c = 0; c < p->cells; ++c) xy[2 * c] = p->cx[c], xy[2 * c + 1] = p->cy[c];
        st = dpsm_create_graph(p->cells, xy, p->area, m->gfaces, m->gcells, m->gxy, m->glen, &g);
        free(xy);
    } else {
        st = mesh_scene_create(p, &g);
    }
    REQUIRE(st == DPSM_OK, "creating a %s mesh: %s: %s", kKindNames[m->kind], dpsm_status_string(st),
            dpsm_last_error(NULL));
    return g;
}

/* ------------------------------------------------------------------------ */
/* The worst figures                                                         */
/* ------------------------------------------------------------------------ */

enum { FIG_LEDGER, FIG_NEW_MAX, FIG_NEW_MIN, FIG_FLUXES, FIG_REST_EXCESS, FIG_REST_TWO_POINT, NFIGS };
static const char *const kFigNames[NFIGS] = {
    "ledger residual / largest mass",
    "new max over the bound / largest |height|",
    "new min under the bound / largest |height|",
    "cell change against its faces and source / allowance",
    "MAX_EXCESS_SLOPE at rest / (tol tan(theta))",
    "two-point slope at rest / (tan(theta)(1+tol)) - 1",
};

typedef struct {
    double fig[NFIGS];
    char where[NFIGS][160];
    long checks, rest_checks, flux_checks, work_limits;
} mesh_worst_t;

static mesh_worst_t all_worst;

static void worst_reset(mesh_worst_t *w) {
    memset(w, 0, sizeof *w);
    for (int k = 0; k < NFIGS; ++k) w->fig[k] = -INFINITY;
}

static void note(mesh_worst_t *w, int k, double value, const char *name) {
    if (value > w->fig[k]) {
        w->fig[k] = value;
        snprintf(w->where[k], sizeof w->where[k], "%s", name);
    }
}

static void finish_test(const char *title, const mesh_worst_t *w) {
    print_message("%s: %ld states checked (%ld at rest, %ld with face fluxes), %ld work limits\n", title, w->checks,
                  w->rest_checks, w->flux_checks, w->work_limits);
    for (int k = 0; k < NFIGS; ++k) {
        if (w->fig[k] == -INFINITY)
            print_message("  worst %-66s n/a\n", kFigNames[k]);
        else
            print_message("  worst %-66s %+.3e  [%s]\n", kFigNames[k], w->fig[k], w->where[k]);
        note(&all_worst, k, w->fig[k], w->where[k]);
    }
    all_worst.checks += w->checks;
    all_worst.rest_checks += w->rest_checks;
    all_worst.flux_checks += w->flux_checks;
    all_worst.work_limits += w->work_limits;
}

/* ------------------------------------------------------------------------ */
/* Scenes                                                                    */
/* ------------------------------------------------------------------------ */

/* A mesh together with what the test knows about it. */
typedef struct {
    char name[160];
    dpsm_grid *g;
    const mesh_t *mesh;
    int64_t n, nf;
    const double *area;
    int64_t *faces;     /* 2 nf: a, b; b < 0 on the domain edge */
    double *dist;       /* per face between two cells: the distance between their centres */
    double longest;     /* the largest of them */
    int orthogonal;     /* faces orthogonal to the line between their cells (the rest check's two-point bound) */
    uint8_t *kinds;     /* cell kinds */
    uint8_t *edge_open; /* per face: an open face of the domain edge */
    double *levels;     /* per face: the level beyond it */
    double *q, *bed;    /* NULL: none */
    int source;         /* a nonzero source on some sand cell */
    double theta, tol;
    double *h, *held;   /* heights after the last check; of wall and open cells at the last host change */
    double mass_scale;  /* the largest gross mass at a host change */
    int record;
} mscene_t;

/* After a host change: the held heights and the largest gross mass. */
static void refresh_held(mscene_t *s) {
    SCENE_OK(s, dpsm_get_heights(s->g, s->h));
    memcpy(s->held, s->h, sizeof(double) * (size_t)s->n);
    double gross = 0.0;
    for (int64_t c = 0; c < s->n; ++c) gross += fabs(s->h[c]) * s->area[c];
    s->mass_scale = fmax(s->mass_scale, gross);
}

static void ms_create(mscene_t *s, const mesh_t *m, const char *fmt, ...) CMOCKA_PRINTF_ATTRIBUTE(3, 4);
static void ms_create(mscene_t *s, const mesh_t *m, const char *fmt, ...) {
    memset(s, 0, sizeof *s);
    char what[120];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    snprintf(s->name, sizeof s->name, "%s, %lld cells: %s", kKindNames[m->kind], (long long)m->geo.cells, what);
    s->mesh = m;
    s->g = mesh_create(m);
    s->n = m->geo.cells;
    s->area = m->geo.area;
    SCENE_OK(s, dpsm_get_face_count(s->g, &s->nf));
    s->faces = zeroed((size_t)(2 * s->nf), sizeof(int64_t));
    SCENE_OK(s, dpsm_get_mesh_faces(s->g, s->faces));
    s->dist = zeroed((size_t)s->nf, sizeof(double));
    for (int64_t f = 0; f < s->nf; ++f) {
        const int64_t a = s->faces[2 * f], b = s->faces[2 * f + 1];
        if (b >= 0) s->dist[f] = hypot(m->geo.cx[b] - m->geo.cx[a], m->geo.cy[b] - m->geo.cy[a]);
        s->longest = fmax(s->longest, s->dist[f]);
    }
    s->orthogonal = m->kind == MESH_HEXAGONS || m->kind == MESH_GRAPH;
    s->kinds = zeroed((size_t)s->n, 1);
    s->edge_open = zeroed((size_t)s->nf, 1);
    s->levels = zeroed((size_t)s->nf, sizeof(double));
    s->h = zeroed((size_t)s->n, sizeof(double));
    s->held = zeroed((size_t)s->n, sizeof(double));
    s->theta = DPSM_DEFAULT_REPOSE_ANGLE;
    s->tol = DPSM_DEFAULT_REST_TOLERANCE;
    /* Every second scene records its face fluxes (the others step without). */
    static unsigned made;
    s->record = made++ % 2 == 0;
    if (s->record) SCENE_OK(s, dpsm_set_face_flux_recording(s->g, 1));
}

static void ms_destroy(mscene_t *s) {
    dpsm_destroy(s->g);
    free(s->faces), free(s->dist), free(s->kinds), free(s->edge_open), free(s->levels);
    free(s->q), free(s->bed), free(s->h), free(s->held);
    memset(s, 0, sizeof *s);
}

static void ms_set_angle(mscene_t *s, double theta) {
    SCENE_OK(s, dpsm_set_repose_angle(s->g, theta));
    s->theta = theta;
}

static void ms_set_tolerance(mscene_t *s, double tol) {
    SCENE_OK(s, dpsm_set_rest_tolerance(s->g, tol));
    s->tol = tol;
}

/* Every edge face open or closed at once (dpsm_set_boundary). */
static void ms_set_edge(mscene_t *s, int open) {
    SCENE_OK(s, dpsm_set_boundary(s->g, DPSM_MESH_EDGE, open ? DPSM_OPEN : DPSM_WALL));
    for (int64_t f = 0; f < s->nf; ++f) s->edge_open[f] = open && s->faces[2 * f + 1] < 0;
}

/* Edge faces open where open[f] (dpsm_set_edge_kinds); interior faces get a
 * kind the library must ignore. */
static void ms_set_edge_kinds(mscene_t *s, const uint8_t *open) {
    uint8_t *k = zeroed((size_t)s->nf, 1);
    for (int64_t f = 0; f < s->nf; ++f) {
        const int edge = s->faces[2 * f + 1] < 0;
        k[f] = edge ? (open[f] ? DPSM_OPEN : DPSM_WALL) : 77;
        s->edge_open[f] = edge && open[f];
    }
    SCENE_OK(s, dpsm_set_edge_kinds(s->g, k));
    free(k);
}

static void ms_set_levels(mscene_t *s, const double *levels) {
    SCENE_OK(s, dpsm_set_side_levels(s->g, DPSM_MESH_EDGE, levels));
    for (int64_t f = 0; f < s->nf; ++f) s->levels[f] = levels ? levels[f] : 0.0;
}

static void ms_set_kinds(mscene_t *s, const uint8_t *kinds) {
    SCENE_OK(s, dpsm_set_cell_kinds(s->g, kinds));
    if (kinds)
        memcpy(s->kinds, kinds, (size_t)s->n);
    else
        memset(s->kinds, DPSM_CELL_SAND, (size_t)s->n);
    refresh_held(s);
}

static void ms_set_heights(mscene_t *s, const double *h) {
    SCENE_OK(s, dpsm_set_heights(s->g, h));
    refresh_held(s);
}

static void ms_set_source(mscene_t *s, const double *q) {
    SCENE_OK(s, dpsm_set_source(s->g, q));
    free(s->q);
    s->q = copy_of(q, s->n);
    s->source = 0;
    if (q)
        for (int64_t c = 0; c < s->n; ++c) s->source |= s->kinds[c] == DPSM_CELL_SAND && q[c] != 0.0;
}

static void ms_set_bed(mscene_t *s, const double *zb) {
    SCENE_OK(s, dpsm_set_bedrock(s->g, zb));
    free(s->bed);
    s->bed = copy_of(zb, s->n);
    refresh_held(s);
}

static double stable(const mscene_t *s) {
    double dt = 0.0;
    REQUIRE(dpsm_stable_dt(s->g, &dt) == DPSM_OK && dt > 0.0 && isfinite(dt), "[%s] stable_dt = %g", s->name, dt);
    return dt;
}

/* The held levels: open cells' heights and the levels beyond open edge faces. */
static void held_range(const mscene_t *s, double *lo, double *hi) {
    for (int64_t c = 0; c < s->n; ++c)
        if (s->kinds[c] == DPSM_CELL_OPEN) *lo = fmin(*lo, s->h[c]), *hi = fmax(*hi, s->h[c]);
    for (int64_t f = 0; f < s->nf; ++f)
        if (s->edge_open[f]) *lo = fmin(*lo, s->levels[f]), *hi = fmax(*hi, s->levels[f]);
}

/* Whether the scene may flow for ever: a source, or held levels that differ. */
static int driven(const mscene_t *s) {
    double lo = INFINITY, hi = -INFINITY;
    held_range(s, &lo, &hi);
    return s->source || (lo < hi);
}

/* What a step starts from. */
typedef struct {
    double *h;
    double lo, hi; /* the range of the sand and the held levels */
    ledger_t ledger;
    double edge_outflow;
} start_t;

static void start_of(const mscene_t *s, start_t *st) {
    st->h = copy_of(s->h, s->n);
    st->lo = INFINITY, st->hi = -INFINITY;
    for (int64_t c = 0; c < s->n; ++c)
        if (s->kinds[c] == DPSM_CELL_SAND) st->lo = fmin(st->lo, s->h[c]), st->hi = fmax(st->hi, s->h[c]);
    held_range(s, &st->lo, &st->hi);
    st->ledger = read_ledger(s->g);
    SCENE_OK(s, dpsm_get_side_outflow(s->g, DPSM_MESH_EDGE, &st->edge_outflow));
}

/* Every invariant of the state a step reached from `st` (the file's head). */
static void check_step(mscene_t *s, const start_t *st, mesh_worst_t *w) {
    ++w->checks;
    SCENE_OK(s, dpsm_get_heights(s->g, s->h));
    const double *h = s->h, *h0 = st->h;
    for (int64_t c = 0; c < s->n; ++c)
        REQUIRE(isfinite(h[c]), "[%s] cell %lld is not finite: %g", s->name, (long long)c, h[c]);

    /* Held cells keep their heights; no sand below the bed. */
    for (int64_t c = 0; c < s->n; ++c) {
        if (s->kinds[c] != DPSM_CELL_SAND)
            REQUIRE(memcmp(&h[c], &s->held[c], sizeof(double)) == 0,
                    "[%s] the height of %s cell %lld changed from %.17g to %.17g",
                    s->name, s->kinds[c] == DPSM_CELL_WALL ? "wall" : "open", (long long)c, s->held[c], h[c]);
        else if (s->bed)
            REQUIRE(h[c] >= s->bed[c], "[%s] sand cell %lld at %.17g is below its bed %.17g", s->name, (long long)c,
                    h[c], s->bed[c]);
    }

    /* The ledger, against the largest mass: its figures, the gross mass of
     * the sand now and what host changes put on the mesh. */
    const ledger_t l = read_ledger(s->g);
    double scale = fmax(fmax(fabs(l.total), fabs(l.sourced)), fmax(fabs(l.external), fabs(l.outflow)));
    double gross = 0.0;
    for (int64_t c = 0; c < s->n; ++c)
        if (s->kinds[c] == DPSM_CELL_SAND) gross += fabs(h[c]) * s->area[c];
    scale = fmax(fmax(scale, gross), s->mass_scale);
    const double residual = fabs(l.total - (l.sourced + l.external - l.outflow));
    const double ledger = scale > 0.0 ? residual / scale : residual;
    note(w, FIG_LEDGER, ledger, s->name);
    REQUIRE(ledger <= 1e-12,
            "[%s] the ledger does not close: %.3e of the largest mass (total %.17g, sourced %.17g, external %.17g, "
            "outflow %.17g)",
            s->name, ledger, l.total, l.sourced, l.external, l.outflow);

    /* No new extremum without a source. */
    if (!s->source) {
        double top = -INFINITY, bottom = INFINITY;
        int64_t at_top = -1, at_bottom = -1;
        for (int64_t c = 0; c < s->n; ++c) {
            if (s->kinds[c] != DPSM_CELL_SAND) continue;
            if (h[c] > top) top = h[c], at_top = c;
            if (h[c] < bottom) bottom = h[c], at_bottom = c;
        }
        if (at_top >= 0) {
            const double magnitude = fmax(fmax(fabs(st->hi), fabs(st->lo)), DBL_MIN);
            const double over = (top - st->hi) / magnitude, under = (st->lo - bottom) / magnitude;
            note(w, FIG_NEW_MAX, over, s->name);
            note(w, FIG_NEW_MIN, under, s->name);
            REQUIRE(over <= 4 * DBL_EPSILON && under <= 4 * DBL_EPSILON,
                    "[%s] a new extremum without a source: cell %lld at %.17g (was %.17g), cell %lld at %.17g (was "
                    "%.17g), outside [%.17g, %.17g] before the step",
                    s->name, (long long)at_top, top, h0[at_top], (long long)at_bottom, bottom, h0[at_bottom], st->lo,
                    st->hi);
        }
    }

    /* The face fluxes against every cell's change, the edge and the outflow. */
    if (s->record) {
        ++w->flux_checks;
        double time = 0.0;
        SCENE_OK(s, dpsm_get_step_info(s->g, DPSM_INFO_TIME_INTEGRATED, &time));
        double *fx = zeroed((size_t)s->nf, sizeof(double)), *in = zeroed((size_t)s->n, sizeof(double));
        SCENE_OK(s, dpsm_get_face_fluxes(s->g, fx, NULL));
        double largest = 0.0, edge = 0.0, into_open = 0.0;
        for (int64_t f = 0; f < s->nf; ++f) {
            const int64_t a = s->faces[2 * f], b = s->faces[2 * f + 1];
            const int ka = s->kinds[a], kb = b >= 0 ? s->kinds[b] : -1;
            const int carries = b >= 0 ? (ka != DPSM_CELL_WALL && kb != DPSM_CELL_WALL &&
                                          (ka == DPSM_CELL_SAND || kb == DPSM_CELL_SAND))
                                       : (ka == DPSM_CELL_SAND && s->edge_open[f]);
            REQUIRE(carries || fx[f] == 0.0, "[%s] face %lld (cells %lld, %lld) carried %.17g; it can carry nothing",
                    s->name, (long long)f, (long long)a, (long long)b, fx[f]);
            largest = fmax(largest, fabs(fx[f]));
            in[a] -= fx[f];
            if (b >= 0) in[b] += fx[f];
            if (b < 0) edge += fx[f];
            if (ka == DPSM_CELL_OPEN) into_open -= fx[f];
            if (kb == DPSM_CELL_OPEN) into_open += fx[f];
        }
        double volume = largest;
        for (int64_t c = 0; c < s->n; ++c)
            if (s->q && s->kinds[c] == DPSM_CELL_SAND) volume = fmax(volume, fabs(s->q[c] * time * s->area[c]));
        for (int64_t c = 0; c < s->n; ++c) {
            if (s->kinds[c] != DPSM_CELL_SAND) continue;
            const double change = (h[c] - h0[c]) * s->area[c], want = (s->q ? s->q[c] : 0.0) * time * s->area[c];
            const double took = change - in[c]; /* what the source added */
            const double tol = 1e-9 * volume + 16 * DBL_EPSILON * (fabs(h0[c]) + fabs(h[c])) * s->area[c] + DBL_MIN;
            if (s->bed && want < 0.0) {
                REQUIRE(took >= want - tol && took <= tol,
                        "[%s] cell %lld on its bed lost %.17g to erosion that asked %.17g", s->name, (long long)c, took,
                        want);
                continue;
            }
            note(w, FIG_FLUXES, fabs(took - want) / tol, s->name);
            REQUIRE(fabs(took - want) <= tol,
                    "[%s] cell %lld: its volume changed by %.17g, its faces brought %.17g, its source %.17g (off by "
                    "%.3g; largest face volume %.3g)",
                    s->name, (long long)c, change, in[c], want, took - want, largest);
        }
        double edge_outflow = 0.0;
        SCENE_OK(s, dpsm_get_side_outflow(s->g, DPSM_MESH_EDGE, &edge_outflow));
        const double booked = edge_outflow - st->edge_outflow, outflow = l.outflow - st->ledger.outflow;
        const double tol = 1e-9 * fmax(volume, DBL_MIN) +
                           16 * DBL_EPSILON * (fabs(edge_outflow) + fabs(st->edge_outflow) + fabs(l.outflow) +
                                               fabs(st->ledger.outflow));
        REQUIRE(fabs(edge - booked) <= tol, "[%s] the edge's faces carried %.17g out, DPSM_MESH_EDGE booked %.17g",
                s->name, edge, booked);
        REQUIRE(fabs(outflow - edge - into_open) <= tol,
                "[%s] OUTFLOW grew by %.17g; the edge took %.17g, the open cells %.17g", s->name, outflow, edge,
                into_open);
        free(fx), free(in);
    }

    /* At rest. */
    double at_rest = 0.0;
    SCENE_OK(s, dpsm_get_step_info(s->g, DPSM_INFO_AT_REST, &at_rest));
    if (at_rest == 1.0) {
        ++w->rest_checks;
        const double tol = s->tol, tan_theta = tan(s->theta);
        double excess = 0.0;
        SCENE_OK(s, dpsm_get_step_info(s->g, DPSM_INFO_MAX_EXCESS_SLOPE, &excess));
        note(w, FIG_REST_EXCESS, excess / (tol * tan_theta), s->name);
        REQUIRE(excess <= tol * tan_theta,
                "[%s] at rest with DPSM_INFO_MAX_EXCESS_SLOPE %.17g over tol tan(theta) %.3g",
                s->name, excess, tol * tan_theta);
        if (s->orthogonal) {
            /* A face's part across it is its two-point slope: one steeper than
             * tan(theta)(1 + tol) carries sand (docs/guarantees.md, "Meshes") unless it cannot: a wall, two held cells, sand on
             * its bed thinner than the film dpsm leaves. */
            const double threshold = tan_theta * (1.0 + tol), film = 2.0 * tol * tan_theta * s->longest;
            for (int64_t f = 0; f < s->nf; ++f) {
                const int64_t a = s->faces[2 * f], b = s->faces[2 * f + 1];
                if (b < 0) continue;
                const int ka = s->kinds[a], kb = s->kinds[b];
                if (ka == DPSM_CELL_WALL || kb == DPSM_CELL_WALL || (ka != DPSM_CELL_SAND && kb != DPSM_CELL_SAND))
                    continue;
                const int64_t up = h[a] >= h[b] ? a : b;
                if (s->bed && s->kinds[up] == DPSM_CELL_SAND && h[up] - s->bed[up] <= film) continue;
                const double slack = 4.0 * DBL_EPSILON * fmax(fabs(h[a]), fabs(h[b])) / s->dist[f];
                const double r = (fabs(h[a] - h[b]) / s->dist[f] - slack) / threshold - 1.0;
                note(w, FIG_REST_TWO_POINT, r, s->name);
                REQUIRE(r <= 1e-9,
                        "[%s] at rest, face %lld between cells %lld and %lld is steeper than tan(theta)(1+tol) by "
                        "%.3e: heights %.17g and %.17g, %.17g apart",
                        s->name, (long long)f, (long long)a, (long long)b, r, h[a], h[b], s->dist[f]);
            }
        }
    }
}

/* Steps dt (it must succeed) and checks everything; returns 1 at rest. */
static int ms_step(mscene_t *s, double dt, mesh_worst_t *w) {
    start_t st;
    start_of(s, &st);
    const int status = dpsm_step(s->g, dt);
    REQUIRE(status == DPSM_OK, "[%s] dpsm_step(%g) returned %s: %s", s->name, dt, dpsm_status_string(status),
            dpsm_last_error(s->g));
    check_step(s, &st, w);
    free(st.h);
    return step_info_of(s->g, DPSM_INFO_AT_REST) == 1.0;
}

static void ms_run_to_rest(mscene_t *s, double dt, int max_calls, mesh_worst_t *w) {
    for (int k = 0; k < max_calls; ++k)
        if (ms_step(s, dt, w)) return;
    REQUIRE(0, "[%s] not at rest after %d steps of %g", s->name, max_calls, dt);
}

static void ms_expect_work_limit(mscene_t *s, double dt, mesh_worst_t *w) {
    expect_work_limit_on(s->g, s->n, s->name, dt);
    ++w->work_limits;
}

/* Heights: uniform noise of amplitude amp about offset, plus top within
 * radius of (x0, 0). */
static double *terrain(const mscene_t *s, double offset, double amp, double top, double radius, double x0,
                       uint64_t seed) {
    double *h = zeroed((size_t)s->n, sizeof(double));
    const double *cx = s->mesh->geo.cx, *cy = s->mesh->geo.cy;
    for (int64_t c = 0; c < s->n; ++c) {
        h[c] = offset + amp * (2.0 * rng_uniform(&seed) - 1.0);
        if (hypot(cx[c] - x0, cy[c]) < radius) h[c] += top;
    }
    return h;
}

/* The cells along each side of a mesh of the kind. */
static int cells_along(int kind, int64_t n) {
    /* about n^2 cells on each kind: m along a side makes 2 m^2 triangles,
     * 1.12 m^2 hexagons, (m + 1)^2 cells of the dual */
    static const double per_side[NKINDS] = {0.71, 0.94, 0.94, 1.0};
    const int m = (int)llround(per_side[kind] * (double)n);
    return m < 3 ? 3 : m;
}

static mesh_t make_mesh(int kind, int64_t n, double half, unsigned seed) {
    return mesh_make(kind, cells_along(kind, n), half, seed, 0);
}

/* ------------------------------------------------------------------------ */
/* The scenes                                                                */
/* ------------------------------------------------------------------------ */

/* Every second decade of dt from 1e-12 to 1e12 on a collapsing pile over a
 * rough bed, edges closed or open: without a source each step finishes (it
 * stops at rest); with one, each step either fits under the sub-step limit
 * or fails at once with DPSM_ERR_WORK_LIMIT, the mesh unchanged. */
static void test_time_steps(void **state) {
    (void)state;
    mesh_worst_t w;
    worst_reset(&w);
    const int64_t n = scaled(20, 5);
    const int64_t limit = 2000;
    for (int kind = 0; kind < NKINDS; ++kind) {
        mesh_t m = make_mesh(kind, n, 2.5, 3u + (unsigned)kind);
        for (int open = 0; open < 2; ++open)
            for (int with_source = 0; with_source < 2; ++with_source)
                for (int e = -12; e <= 12; e += 2) {
                    const double dt = pow(10.0, e);
                    mscene_t s;
                    ms_create(&s, &m, "dt = 1e%d, edge %s%s", e, open ? "open" : "closed",
                              with_source ? ", source" : "");
                    ms_set_edge(&s, open);
                    double *h = terrain(&s, 1.0, 0.3, 1.5, 0.8, 0.0, 1000u + (uint64_t)(e + 100 * kind));
                    ms_set_heights(&s, h);
                    SCENE_OK(&s, dpsm_set_max_substeps(s.g, limit));
                    if (with_source) {
                        for (int64_t c = 0; c < s.n; ++c) h[c] = c % 3 == 0 ? 1e-3 : (c % 3 == 1 ? -2e-4 : 0.0);
                        ms_set_source(&s, h);
                    }
                    const double needed = ceil(dt / stable(&s));
                    for (int k = 0; k < 3; ++k) {
                        if (with_source && needed > (double)limit)
                            ms_expect_work_limit(&s, dt, &w);
                        else
                            ms_step(&s, dt, &w);
                    }
                    free(h);
                    ms_destroy(&s);
                }
        mesh_free(&m);
    }
    finish_test("meshes: time steps 1e-12 .. 1e12", &w);
}

/* A vertical wall of sand of height J (1e-9 to 1e6) over half the mesh beside
 * a floor at 0, on cells of about 1 and of about J (the same slopes at every
 * scale), edges closed or open. Where J is at most 10 cells high it runs to
 * rest in one call; higher walls are mobility bound (a face carries at most
 * about nu) and are stepped a bounded time. */
static void test_height_jumps(void **state) {
    (void)state;
    mesh_worst_t w;
    worst_reset(&w);
    const double jumps[] = {1e-9, 1e-6, 1e-3, 1.0, 1e3, 1e6};
    const int64_t n = scaled(16, 5);
    for (int kind = 0; kind < NKINDS; ++kind)
        for (int cells_of_j = 0; cells_of_j < 2; ++cells_of_j)
            for (size_t k = 0; k < sizeof jumps / sizeof jumps[0]; ++k) {
                const double J = jumps[k], size = cells_of_j ? J : 1.0;
                if (cells_of_j && J == 1.0) continue; /* the same as cells of 1 */
                mesh_t m = make_mesh(kind, n, 0.5 * size * (double)n, 7u);
                for (int open = 0; open < 2; ++open) {
                    mscene_t s;
                    ms_create(&s, &m, "wall of sand J = %g, cells of %g, edge %s", J, size, open ? "open" : "closed");
                    ms_set_edge(&s, open);
                    double *h = zeroed((size_t)s.n, sizeof(double));
                    for (int64_t c = 0; c < s.n; ++c) h[c] = m.geo.cx[c] < 0.0 ? J : 0.0;
                    ms_set_heights(&s, h);
                    if (J / size <= 10.0) {
                        ms_run_to_rest(&s, 1e12 * size * size, 2, &w);
                    } else {
                        const double dt = 50.0 * stable(&s);
                        for (int step = 0; step < (int)scaled(12, 3); ++step) ms_step(&s, dt, &w);
                    }
                    free(h);
                    ms_destroy(&s);
                }
                mesh_free(&m);
            }
    finish_test("meshes: height jumps 1e-9 .. 1e6", &w);
}

/* Angles of repose from 0.5 to 89.5 degrees: a column some times tan(theta)
 * high collapses to rest, at rest tolerances of 1e-9 and 1e-3, edges closed
 * or open (the sand above the outside). */
static void test_repose_angles(void **state) {
    (void)state;
    mesh_worst_t w;
    worst_reset(&w);
    const double angles[] = {0.5, 2.0, 15.0, 30.0, 45.0, 60.0, 75.0, 85.0, 89.0, 89.5};
    const int64_t n = scaled(16, 5);
    for (int kind = 0; kind < NKINDS; ++kind) {
        mesh_t m = make_mesh(kind, n, 2.5, 11u + (unsigned)kind);
        for (size_t k = 0; k < sizeof angles / sizeof angles[0]; ++k)
            for (int variant = 0; variant < 2; ++variant) {
                const double theta = deg(angles[k]), tol = variant ? 1e-3 : 1e-9;
                mscene_t s;
                ms_create(&s, &m, "theta = %g deg, tol %g, edge %s", angles[k], tol, variant ? "open" : "closed");
                ms_set_angle(&s, theta);
                ms_set_tolerance(&s, tol);
                ms_set_edge(&s, variant);
                const double top = fmax(1.0, 3.0 * tan(theta));
                double *h = terrain(&s, variant ? 0.2 * top : 0.0, 0.05 * top, top, 0.8, 0.3, 77u + k);
                ms_set_heights(&s, h);
                ms_run_to_rest(&s, 1e12, 2, &w);
                free(h);
                ms_destroy(&s);
            }
        mesh_free(&m);
    }
    finish_test("meshes: angles of repose 0.5 .. 89.5 degrees", &w);
}

/* Random rough terrains (noise, hills, spikes; amplitudes 1e-3 to 1e6) under
 * open edges held at levels that differ face by face within +-amp of a base
 * above or below the sand, every edge face open or some open and some closed
 * (dpsm_set_edge_kinds): a driven scene, so dt = 1e12 fails with
 * DPSM_ERR_WORK_LIMIT and bounded steps are taken; then every level at the
 * base: to rest (up to amplitude 1). */
static void test_rough_terrains(void **state) {
    (void)state;
    mesh_worst_t w;
    worst_reset(&w);
    const int64_t n = scaled(16, 5);
    for (int kind = 0; kind < NKINDS; ++kind) {
        mesh_t m = make_mesh(kind, n, 2.5, 21u + (unsigned)kind);
        for (int seed = 0; seed < 8; ++seed) {
            static const double amps[8] = {0.3, 0.3, 1.0, 1.0, 1.0, 1.0, 1e6, 1e-3};
            const int mixed = seed & 1, below = (seed >> 1) & 1, spikes = seed == 4 || seed == 5;
            const double amp = amps[seed], base = below ? -3.0 * amp : 2.0 * amp;
            mscene_t s;
            ms_create(&s, &m, "%s amp %g, levels +-%g about %g, %s edge", spikes ? "spikes" : "noise and hills", amp,
                      amp, base, mixed ? "mixed" : "open");
            uint64_t r = 4242u + (uint64_t)(seed + 10 * kind);
            double *h = terrain(&s, 0.0, amp, 0.0, 0.0, 0.0, r);
            for (int64_t c = 0; c < s.n; ++c) {
                const double x = m.geo.cx[c], y = m.geo.cy[c];
                if (spikes)
                    h[c] = rng_uniform(&r) < 0.05 ? 20.0 * amp * rng_uniform(&r) : 0.0;
                else
                    h[c] += 2.0 * amp * sin(1.3 * x) * cos(0.9 * y + 1.0);
            }
            ms_set_heights(&s, h);
            double *levels = zeroed((size_t)s.nf, sizeof(double));
            uint8_t *open = zeroed((size_t)s.nf, 1);
            for (int64_t f = 0; f < s.nf; ++f) {
                levels[f] = base + amp * (2.0 * rng_uniform(&r) - 1.0);
                open[f] = !mixed || rng_uniform(&r) < 0.5;
            }
            ms_set_levels(&s, levels);
            if (mixed)
                ms_set_edge_kinds(&s, open);
            else
                ms_set_edge(&s, 1);
            REQUIRE(driven(&s), "[%s] the levels should differ", s.name);
            ms_expect_work_limit(&s, 1e12, &w);
            const double dt = stable(&s);
            for (int k = 0; k < 12; ++k) ms_step(&s, dt * (k % 3 == 0 ? 1.0 : k % 3 == 1 ? 7.0 : 40.0), &w);
            /* Every level at the base: to rest, where the sand can get there
             * in bounded work (a face carries at most about nu). */
            for (int64_t f = 0; f < s.nf; ++f) levels[f] = base;
            ms_set_levels(&s, levels);
            if (amp <= 1.0) ms_run_to_rest(&s, 1e12, 2, &w);
            free(h), free(levels), free(open);
            ms_destroy(&s);
        }
        mesh_free(&m);
    }
    finish_test("meshes: rough terrains, open edges above and below", &w);
}

/* Walls, open cells (sinks at random levels) and sources mixed, some edge
 * faces open: driven, bounded steps; then no source, every sink and the
 * edge at 0: to rest; then every cell sand again: to rest. And a bed of
 * rough rock at slope 1.5 under sand 1e-9 to 2 thick, eroded at 1e3 per unit
 * time on some cells (far more than is there) and fed on others, then to
 * rest without the source. */
static void test_masks_sources_and_bed(void **state) {
    (void)state;
    mesh_worst_t w;
    worst_reset(&w);
    const int64_t n = scaled(32, 6);
    for (int kind = 0; kind < NKINDS; ++kind) {
        mesh_t m = make_mesh(kind, n, 2.5, 31u + (unsigned)kind);
        for (int seed = 0; seed < 3; ++seed) {
            mscene_t s;
            ms_create(&s, &m, "walls, sinks and sources, seed %d", seed);
            uint64_t r = 31337u + (uint64_t)(seed + 10 * kind);
            double *h = terrain(&s, 1.0, 0.5, 1.5, 0.9, 0.0, r), *q = zeroed((size_t)s.n, sizeof(double));
            uint8_t *kinds = zeroed((size_t)s.n, 1), *open = zeroed((size_t)s.nf, 1);
            for (int64_t c = 0; c < s.n; ++c) {
                const double u = rng_uniform(&r);
                kinds[c] = u < 0.7 ? DPSM_CELL_SAND : u < 0.85 ? DPSM_CELL_WALL : DPSM_CELL_OPEN;
                if (kinds[c] == DPSM_CELL_OPEN) h[c] = 2.0 * rng_uniform(&r) - 0.5;
                q[c] = rng_uniform(&r) < 0.2 ? 0.05 * (rng_uniform(&r) - 0.3) : 0.0;
            }
            for (int64_t f = 0; f < s.nf; ++f) open[f] = (seed & 1) && rng_uniform(&r) < 0.5;
            ms_set_edge_kinds(&s, open);
            ms_set_heights(&s, h);
            ms_set_kinds(&s, kinds);
            ms_set_source(&s, q);
            ms_expect_work_limit(&s, 1e12, &w);
            const double dt = 3.0 * stable(&s);
            for (int k = 0; k < (int)scaled(40, 8); ++k) ms_step(&s, dt, &w);
            ms_set_source(&s, NULL); /* sinks at different levels: still driven */
            ms_expect_work_limit(&s, 1e12, &w);
            for (int k = 0; k < (int)scaled(20, 4); ++k) ms_step(&s, dt, &w);
            SCENE_OK(&s, dpsm_get_heights(s.g, h));
            for (int64_t c = 0; c < s.n; ++c)
                if (kinds[c] == DPSM_CELL_OPEN) h[c] = 0.0;
            ms_set_heights(&s, h);
            ms_run_to_rest(&s, 1e12, 2, &w);
            ms_set_kinds(&s, NULL); /* walls and sinks become sand, bringing their heights */
            ms_run_to_rest(&s, 1e12, 2, &w);
            free(h), free(q), free(kinds), free(open);
            ms_destroy(&s);
        }
        /* Erosion and deposition over a bed, the edge at x > 2 open. */
        mscene_t s;
        ms_create(&s, &m, "bed at slope 1.5 eroded beyond its sand");
        uint64_t r = 9090u + (uint64_t)kind;
        double *zb = zeroed((size_t)s.n, sizeof(double)), *h = zeroed((size_t)s.n, sizeof(double));
        double *q = zeroed((size_t)s.n, sizeof(double));
        uint8_t *open = zeroed((size_t)s.nf, 1);
        static const double layers[] = {1e-9, 1e-3, 0.3, 2.0};
        for (int64_t c = 0; c < s.n; ++c) {
            zb[c] = 1.5 * (2.5 - m.geo.cx[c]) + 0.1 * rng_uniform(&r);
            h[c] = zb[c] + layers[rng_next(&r) % 4];
            const double u = rng_uniform(&r);
            q[c] = u < 0.2 ? -1e3 : u < 0.35 ? 0.1 : 0.0;
        }
        for (int64_t f = 0; f < s.nf; ++f) open[f] = m.geo.cx[s.faces[2 * f]] > 2.0;
        ms_set_edge_kinds(&s, open);
        ms_set_bed(&s, zb);
        ms_set_heights(&s, h);
        ms_set_source(&s, q);
        const double dt = stable(&s);
        for (int k = 0; k < 24; ++k) ms_step(&s, dt * (k % 3 == 0 ? 1.0 : k % 3 == 1 ? 10.0 : 100.0), &w);
        REQUIRE(mass_of(s.g, DPSM_MASS_UNMET) > 0.0, "[%s] erosion beyond the sand left nothing unmet", s.name);
        ms_set_source(&s, NULL);
        ms_run_to_rest(&s, 1e12, 2, &w);
        free(zb), free(h), free(q), free(open);
        ms_destroy(&s);
        mesh_free(&m);
    }
    finish_test("meshes: walls, open cells, sources and a bed", &w);
}

/* Local time steps (DPSM_RELAX_LOCAL_STEPS) on graded meshes: a pile over a
 * rough bed at every sixth decade of dt from 1e-12 to 1e12, edge closed or
 * open, with a source (each step fits under the limit or fails at once with
 * DPSM_ERR_WORK_LIMIT), then to rest; a rough terrain under open edge faces
 * at levels that differ, some faces closed, then to rest; walls, sinks and
 * sources, then to rest; a bed eroded far beyond its sand, then to rest. */
static void test_local_time_steps(void **state) {
    (void)state;
    mesh_worst_t w;
    worst_reset(&w);
    const int64_t n = scaled(12, 5);
    for (int kind = 0; kind < NKINDS; ++kind) {
        mesh_t m = mesh_make(kind, cells_along(kind, n), 2.5, 51u + (unsigned)kind, 1);
        for (int e = -12; e <= 12; e += 6) {
            const int open = (e / 6 + kind) & 1;
            {
                const double dt = pow(10.0, e);
                mscene_t s;
                ms_create(&s, &m, "local steps, graded, dt = 1e%d, edge %s, source", e, open ? "open" : "closed");
                SCENE_OK(&s, dpsm_set_relaxation(s.g, DPSM_RELAX_LOCAL_STEPS));
                SCENE_OK(&s, dpsm_set_max_substeps(s.g, 2000));
                ms_set_edge(&s, open);
                double *h = terrain(&s, 1.0, 0.3, 1.5, 0.8, 0.0, 5000u + (uint64_t)(e + 100 * kind));
                ms_set_heights(&s, h);
                for (int64_t c = 0; c < s.n; ++c) h[c] = c % 3 == 0 ? 1e-3 : (c % 3 == 1 ? -2e-4 : 0.0);
                ms_set_source(&s, h);
                for (int k = 0; k < 3; ++k) {
                    if (ceil(dt / stable(&s)) > 2000.0)
                        ms_expect_work_limit(&s, dt, &w);
                    else
                        ms_step(&s, dt, &w);
                }
                ms_set_source(&s, NULL);
                ms_run_to_rest(&s, 1e12, 2, &w);
                free(h);
                ms_destroy(&s);
            }
        }
        {
            const int seed = kind & 1;
            const double amp = seed ? 1.0 : 0.3, base = seed ? -3.0 : 0.6;
            mscene_t s;
            ms_create(&s, &m, "local steps, graded, terrain amp %g, levels +-%g about %g, mixed edge", amp, amp, base);
            SCENE_OK(&s, dpsm_set_relaxation(s.g, DPSM_RELAX_LOCAL_STEPS));
            uint64_t r = 6060u + (uint64_t)(seed + 10 * kind);
            double *h = terrain(&s, 0.0, amp, 0.0, 0.0, 0.0, r);
            for (int64_t c = 0; c < s.n; ++c) h[c] += 2.0 * amp * sin(1.3 * m.geo.cx[c]) * cos(0.9 * m.geo.cy[c] + 1.0);
            ms_set_heights(&s, h);
            double *levels = zeroed((size_t)s.nf, sizeof(double));
            uint8_t *open = zeroed((size_t)s.nf, 1);
            for (int64_t f = 0; f < s.nf; ++f) {
                levels[f] = base + amp * (2.0 * rng_uniform(&r) - 1.0);
                open[f] = rng_uniform(&r) < 0.5;
            }
            ms_set_levels(&s, levels);
            ms_set_edge_kinds(&s, open);
            ms_expect_work_limit(&s, 1e12, &w);
            const double dt = stable(&s);
            for (int k = 0; k < 12; ++k) ms_step(&s, dt * (k % 3 == 0 ? 1.0 : k % 3 == 1 ? 7.0 : 40.0), &w);
            for (int64_t f = 0; f < s.nf; ++f) levels[f] = base;
            ms_set_levels(&s, levels);
            ms_run_to_rest(&s, 1e12, 2, &w);
            free(h), free(levels), free(open);
            ms_destroy(&s);
        }
        {
            mscene_t s;
            ms_create(&s, &m, "local steps, graded, walls, sinks and sources");
            SCENE_OK(&s, dpsm_set_relaxation(s.g, DPSM_RELAX_LOCAL_STEPS));
            uint64_t r = 7070u + (uint64_t)kind;
            double *h = terrain(&s, 1.0, 0.5, 1.5, 0.9, 0.0, r), *q = zeroed((size_t)s.n, sizeof(double));
            uint8_t *kinds = zeroed((size_t)s.n, 1);
            for (int64_t c = 0; c < s.n; ++c) {
                const double u = rng_uniform(&r);
                kinds[c] = u < 0.7 ? DPSM_CELL_SAND : u < 0.85 ? DPSM_CELL_WALL : DPSM_CELL_OPEN;
                if (kinds[c] == DPSM_CELL_OPEN) h[c] = 0.0;
                q[c] = rng_uniform(&r) < 0.2 ? 0.05 * (rng_uniform(&r) - 0.3) : 0.0;
            }
            ms_set_heights(&s, h);
            ms_set_kinds(&s, kinds);
            ms_set_source(&s, q);
            const double dt = 3.0 * stable(&s);
            for (int k = 0; k < (int)scaled(30, 6); ++k) ms_step(&s, dt, &w);
            ms_set_source(&s, NULL);
            ms_run_to_rest(&s, 1e12, 2, &w);
            free(h), free(q), free(kinds);
            ms_destroy(&s);
        }
        {
            /* Over a bed at slope 0.5, eroded far beyond its sand on some cells. */
            mscene_t s;
            ms_create(&s, &m, "local steps, graded, bed eroded beyond its sand");
            SCENE_OK(&s, dpsm_set_relaxation(s.g, DPSM_RELAX_LOCAL_STEPS));
            uint64_t r = 8080u + (uint64_t)kind;
            double *zb = zeroed((size_t)s.n, sizeof(double)), *h = zeroed((size_t)s.n, sizeof(double));
            double *q = zeroed((size_t)s.n, sizeof(double));
            for (int64_t c = 0; c < s.n; ++c) {
                zb[c] = 0.5 * (2.5 - m.geo.cx[c]) + 0.1 * rng_uniform(&r);
                h[c] = zb[c] + (rng_uniform(&r) < 0.5 ? 1e-3 : 0.6);
                const double u = rng_uniform(&r);
                q[c] = u < 0.2 ? -1e3 : u < 0.35 ? 0.1 : 0.0;
            }
            ms_set_bed(&s, zb);
            ms_set_heights(&s, h);
            ms_set_source(&s, q);
            const double dt = stable(&s);
            for (int k = 0; k < 12; ++k) ms_step(&s, dt * (k % 3 == 0 ? 1.0 : k % 3 == 1 ? 10.0 : 100.0), &w);
            REQUIRE(mass_of(s.g, DPSM_MASS_UNMET) > 0.0, "[%s] erosion beyond the sand left nothing unmet", s.name);
            ms_set_source(&s, NULL);
            ms_run_to_rest(&s, 1e12, 2, &w);
            free(zb), free(h), free(q);
            ms_destroy(&s);
        }
        mesh_free(&m);
    }
    finish_test("meshes: local time steps on graded meshes", &w);
}

/* Many small steps with a source, a wall, a sink and an open edge: the
 * ledger must still close to 1e-12 after each. */
static void test_many_small_steps(void **state) {
    (void)state;
    mesh_worst_t w;
    worst_reset(&w);
    const int64_t steps = scaled(10000, 1000);
    for (int kind = 0; kind < NKINDS; ++kind) {
        mesh_t m = make_mesh(kind, 12, 1.0, 41u + (unsigned)kind);
        mscene_t s;
        ms_create(&s, &m, "%lld small steps", (long long)steps);
        ms_set_edge(&s, 1);
        uint8_t *kinds = zeroed((size_t)s.n, 1);
        kinds[s.n / 3] = DPSM_CELL_WALL;
        kinds[s.n / 2] = DPSM_CELL_OPEN;
        double *h = terrain(&s, 1.0, 0.3, 0.5, 0.4, 0.0, 123u + (uint64_t)kind);
        ms_set_heights(&s, h);
        ms_set_kinds(&s, kinds);
        for (int64_t c = 0; c < s.n; ++c) h[c] = c % 5 == 0 ? 0.02 : (c % 7 == 0 ? -0.004 : 0.0);
        ms_set_source(&s, h);
        const double dt = 0.37 * stable(&s);
        for (int64_t k = 0; k < steps; ++k) ms_step(&s, dt, &w);
        free(kinds), free(h);
        ms_destroy(&s);
        mesh_free(&m);
    }
    finish_test("meshes: many small steps", &w);
}

static void test_summary(void **state) {
    (void)state;
    mesh_worst_t w = all_worst;
    worst_reset(&all_worst);
    finish_test("stress suite on meshes, worst over all tests", &w);
}

int main(int argc, char **argv) {
    if (argc > 1) cmocka_set_test_filter(argv[1]);
    worst_reset(&all_worst);
    print_message("stress scale %g (DPSM_STRESS_SCALE)\n", stress_scale());
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_time_steps),       cmocka_unit_test(test_height_jumps),
        cmocka_unit_test(test_repose_angles),    cmocka_unit_test(test_rough_terrains),
        cmocka_unit_test(test_masks_sources_and_bed), cmocka_unit_test(test_local_time_steps),
        cmocka_unit_test(test_many_small_steps),
        cmocka_unit_test(test_summary),
    };
    return cmocka_run_group_tests_name("stress_mesh", tests, NULL, NULL);
}
