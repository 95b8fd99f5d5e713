/* Local time stepping on meshes whose cells span a factor of 8 in size
 * (dpsm-bench lts): what the smallest cell's pace costs today, and what
 * local time stepping would save, against a uniform mesh of the same cell
 * count.
 *
 * The meshes are quadtrees of squares on [-2.5, 2.5]^2, sizes h, 2h, 4h
 * and 8h by distance from a point (2:1 balanced; a large square's edge
 * beside two small ones carries their shared corner as a fifth node, so
 * every face joins two cells). Two placements of the fine cells: around the
 * column (refined where the sand moves) and around a far corner (refined
 * where it does not: a pipeline's or a building's surroundings). On each,
 * and on a uniform square mesh with as many cells, the column collapse of
 * mesh-accuracy (a = 0.5, 30 degrees, open edge) is stepped to rest in calls
 * of 0.05.
 *
 * Today every cell takes the mesh's one sub-step, the smallest cell's
 * stable bound (times 0.9). Local time stepping would let a cell take the
 * largest power-of-two multiple of that sub-step within its own bound. Its
 * cost is estimated, not run: per call, the cells whose height changed and
 * their neighbours (what an active set must visit) each take the call's
 * time over their class's sub-step, summed over the calls (a lower bound:
 * the class interfaces' bookkeeping is left out). A cell's own bound is its
 * area over the sum of its faces' length over centre distance (the
 * two-point part of what the engine uses, model/mesh.cpp); the mesh's
 * smallest such bound is printed against dpsm_stable_dt to show how close
 * that is. The counts are machine-independent; seconds are the library's
 * (1 thread), beside those of the uniform mesh in the same run. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "mesh_scenes.h"

static const double kPi = 3.14159265358979323846;
static const double kHalf = 2.5;

/* ---- the quadtree ---------------------------------------------------------- */

enum { kMostLevels = 12 };

typedef struct {
    int m;          /* lattice points per side less one: the domain is m fine cells wide */
    int levels;     /* the largest cells are 2^levels fine cells wide; m is a multiple of it */
    double h;       /* fine cell size */
    double px, py;  /* the refinement's centre */
    /* within radius[k] of the centre, cells of 2^k fine cells (k < levels); beyond the last, 2^levels */
    double radius[kMostLevels];
    int64_t count, capacity;
    int *i0, *j0, *size; /* leaves: lower-left lattice corner and size in fine cells */
} quadtree;

static int wanted_size(const quadtree *q, int i0, int j0, int size) {
    /* the distance from the centre to the nearest point of the square */
    const double x0 = -kHalf + i0 * q->h, y0 = -kHalf + j0 * q->h, w = size * q->h;
    const double dx = fmax(0.0, fmax(x0 - q->px, q->px - (x0 + w))), dy = fmax(0.0, fmax(y0 - q->py, q->py - (y0 + w)));
    const double r = hypot(dx, dy);
    for (int k = 0; k < q->levels; ++k)
        if (r < q->radius[k]) return 1 << k;
    return 1 << q->levels;
}

/* The quadtree's nodes: lattice points (i, j) numbered from 1 in the order
 * they are first met, in an open-addressed table (a lattice of the fine
 * cells would not fit at 512 fine cells a coarse cell). */
typedef struct {
    int64_t capacity, count;
    int64_t *key, *id;     /* key: i + (m + 1) j + 1, 0 for an empty slot */
    int64_t *node_i, *node_j;
} node_table;

static int64_t *node_slot(node_table *t, int64_t key) {
    uint64_t k = (uint64_t)key * 0x9E3779B97F4A7C15ull;
    for (int64_t at = (int64_t)(k >> 20) & (t->capacity - 1);; at = (at + 1) & (t->capacity - 1))
        if (t->key[at] == key || t->key[at] == 0) return &t->key[at];
}

/* The node at (i, j): its number from 1, or 0 where none is (add: make it). */
static int64_t node_at(node_table *t, int64_t side, int64_t i, int64_t j, int add) {
    int64_t *slot = node_slot(t, i + side * j + 1);
    const int64_t at = slot - t->key;
    if (*slot) return t->id[at];
    if (!add) return 0;
    *slot = i + side * j + 1;
    t->id[at] = ++t->count;
    t->node_i[t->count - 1] = i, t->node_j[t->count - 1] = j;
    return t->count;
}

static void add_leaf(quadtree *q, int i0, int j0, int size) {
    if (size > wanted_size(q, i0, j0, size)) {
        const int half = size / 2;
        add_leaf(q, i0, j0, half);
        add_leaf(q, i0 + half, j0, half);
        add_leaf(q, i0, j0 + half, half);
        add_leaf(q, i0 + half, j0 + half, half);
        return;
    }
    if (q->count == q->capacity) {
        q->capacity = q->capacity ? 2 * q->capacity : 1024;
        q->i0 = realloc(q->i0, sizeof(int) * (size_t)q->capacity);
        q->j0 = realloc(q->j0, sizeof(int) * (size_t)q->capacity);
        q->size = realloc(q->size, sizeof(int) * (size_t)q->capacity);
        if (!q->i0 || !q->j0 || !q->size) {
            fprintf(stderr, "out of memory\n");
            exit(1);
        }
    }
    q->i0[q->count] = i0, q->j0[q->count] = j0, q->size[q->count] = size;
    ++q->count;
}

/* The quadtree's leaves as polygons: each square's corners and every leaf
 * corner lying on its edges, counter-clockwise. */
static mesh_scene quadtree_scene(quadtree *q) {
    const int base = 1 << q->levels;
    for (int j = 0; j < q->m; j += base)
        for (int i = 0; i < q->m; i += base) add_leaf(q, i, j, base);
    const int64_t side = q->m + 1;
    node_table nodes = {0};
    nodes.capacity = 1024;
    while (nodes.capacity < 8 * q->count) nodes.capacity *= 2; /* at most 4 corners a leaf: half full at most */
    nodes.key = xcalloc((size_t)nodes.capacity, sizeof(int64_t));
    nodes.id = xcalloc((size_t)nodes.capacity, sizeof(int64_t));
    nodes.node_i = xcalloc((size_t)(4 * q->count), sizeof(int64_t));
    nodes.node_j = xcalloc((size_t)(4 * q->count), sizeof(int64_t));
    mesh_scene s;
    memset(&s, 0, sizeof s);
    s.kind = SCENE_QUADS;
    for (int64_t c = 0; c < q->count; ++c)
        for (int corner = 0; corner < 4; ++corner) {
            const int64_t i = q->i0[c] + (corner == 1 || corner == 2) * q->size[c];
            const int64_t j = q->j0[c] + (corner >= 2) * q->size[c];
            node_at(&nodes, side, i, j, 1);
        }
    s.nnodes = nodes.count;
    s.node_xy = xcalloc((size_t)(2 * s.nnodes), sizeof(double));
    for (int64_t k = 0; k < s.nnodes; ++k) {
        s.node_xy[2 * k] = -kHalf + (double)nodes.node_i[k] * q->h;
        s.node_xy[2 * k + 1] = -kHalf + (double)nodes.node_j[k] * q->h;
    }
    s.npolygons = s.cells = q->count;
    s.cell_start = xcalloc((size_t)s.cells + 1, sizeof(int64_t));
    s.cell_nodes = xcalloc((size_t)(32 * s.cells), sizeof(int64_t));
    s.cx = xcalloc((size_t)s.cells, sizeof(double));
    s.cy = xcalloc((size_t)s.cells, sizeof(double));
    s.area = xcalloc((size_t)s.cells, sizeof(double));
    int64_t k = 0;
    static const int walk[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
    for (int64_t c = 0; c < s.cells; ++c) {
        s.cell_start[c] = k;
        int64_t i = q->i0[c], j = q->j0[c];
        for (int edge = 0; edge < 4; ++edge)
            for (int step = 0; step < q->size[c]; ++step) {
                const int64_t node = node_at(&nodes, side, i, j, 0);
                if (node) s.cell_nodes[k++] = node - 1;
                i += walk[edge][0], j += walk[edge][1];
            }
        const double w = q->size[c] * q->h;
        s.cx[c] = -kHalf + q->i0[c] * q->h + 0.5 * w;
        s.cy[c] = -kHalf + q->j0[c] * q->h + 0.5 * w;
        s.area[c] = w * w;
    }
    s.cell_start[s.cells] = k;
    free(nodes.key), free(nodes.id), free(nodes.node_i), free(nodes.node_j);
    return s;
}

/* ---- the study ------------------------------------------------------------- */

typedef struct {
    const char *name;
    int64_t cells;
    double smallest, largest; /* cell sizes */
    double sub_dt, own_bound_ratio; /* dpsm_stable_dt; the two-point estimate of it over it */
    double substeps, rest_time, l1, seconds;
    double updates;      /* the library's cell updates (its active set) */
    double active_now;   /* cells an active set must visit, at the mesh's one sub-step */
    double active_lts;   /* the same cells, each at its own class's sub-step */
    double full_now, full_lts; /* every cell, at the one sub-step and at its class's */
    int classes[4];      /* cells per class: sub-step 1, 2, 4, 8+ times the smallest */
} lts_result;

/* Each cell's sub-step class: the largest power of two k with k times the
 * mesh's sub-step within the cell's own bound (capped at 64). */
static void own_classes(const mesh_scene *s, dpsm_grid *g, double *klass, double *ratio) {
    int64_t nfaces = 0;
    CHECK(g, dpsm_get_face_count(g, &nfaces));
    int64_t *faces = xcalloc((size_t)(2 * nfaces), sizeof(int64_t));
    CHECK(g, dpsm_get_mesh_faces(g, faces));
    double *sum = xcalloc((size_t)s->cells, sizeof(double));
    for (int64_t f = 0; f < nfaces; ++f) {
        const int64_t a = faces[2 * f], b = faces[2 * f + 1];
        const double wa = sqrt(s->area[a]);
        if (b < 0) {
            sum[a] += 1.0; /* length wa over the distance wa to the mirrored cell */
            continue;
        }
        const double length = fmin(wa, sqrt(s->area[b]));
        const double distance = hypot(s->cx[a] - s->cx[b], s->cy[a] - s->cy[b]);
        sum[a] += length / distance, sum[b] += length / distance;
    }
    double smallest = INFINITY;
    for (int64_t c = 0; c < s->cells; ++c) smallest = fmin(smallest, s->area[c] / sum[c]);
    for (int64_t c = 0; c < s->cells; ++c) {
        double k = 1.0;
        while (2.0 * k <= 64.0 && 2.0 * k * smallest <= s->area[c] / sum[c] * (1.0 + 1e-12)) k *= 2.0;
        klass[c] = k;
    }
    /* the library's sub-step is 0.9 / stiffness times its own smallest bound */
    double sub_dt = 0.0;
    CHECK(g, dpsm_stable_dt(g, &sub_dt));
    *ratio = 0.9 * smallest / (DPSM_DEFAULT_MOBILITY * cos(30.0 * kPi / 180.0)) / sub_dt; /* stiffness nu cos(theta) */
    free(faces);
    free(sum);
}

static lts_result run(const char *name, const mesh_scene *s, int relaxation) {
    lts_result r;
    memset(&r, 0, sizeof r);
    r.name = name;
    r.cells = s->cells;
    r.smallest = INFINITY;
    for (int64_t c = 0; c < s->cells; ++c) {
        r.smallest = fmin(r.smallest, sqrt(s->area[c]));
        r.largest = fmax(r.largest, sqrt(s->area[c]));
    }
    const double theta = 30.0 * kPi / 180.0, alpha = tan(theta);
    double *h = xcalloc((size_t)s->cells, sizeof(double)), *before = xcalloc((size_t)s->cells, sizeof(double));
    double *klass = xcalloc((size_t)s->cells, sizeof(double));
    unsigned char *active = xcalloc((size_t)s->cells, 1);
    scene_pour_column(s, h);
    dpsm_grid *g = NULL;
    CHECK(NULL, scene_create(s, &g));
    CHECK(g, dpsm_set_threads(g, 1));
    CHECK(g, dpsm_set_repose_angle(g, theta));
    CHECK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN));
    CHECK(g, dpsm_set_heights(g, h));
    CHECK(g, dpsm_set_relaxation(g, relaxation));
    CHECK(g, dpsm_stable_dt(g, &r.sub_dt));
    own_classes(s, g, klass, &r.own_bound_ratio);
    for (int64_t c = 0; c < s->cells; ++c) r.classes[klass[c] >= 8.0 ? 3 : klass[c] >= 4.0 ? 2 : klass[c] >= 2.0]++;
    int64_t nfaces = 0;
    CHECK(g, dpsm_get_face_count(g, &nfaces));
    int64_t *faces = xcalloc((size_t)(2 * nfaces), sizeof(int64_t));
    CHECK(g, dpsm_get_mesh_faces(g, faces));
    const double call = 0.05;
    double seconds = 0.0;
    while (r.rest_time < 20.0) {
        memcpy(before, h, sizeof(double) * (size_t)s->cells);
        const double t0 = now_seconds();
        CHECK(g, dpsm_step(g, call));
        seconds += now_seconds() - t0;
        double substeps = 0.0, integrated = 0.0, updates = 0.0, at_rest = 0.0;
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &substeps));
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_TIME_INTEGRATED, &integrated));
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &updates));
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_AT_REST, &at_rest));
        CHECK(g, dpsm_get_heights(g, h));
        r.substeps += substeps, r.updates += updates, r.rest_time += integrated;
        memset(active, 0, (size_t)s->cells);
        for (int64_t c = 0; c < s->cells; ++c) active[c] = h[c] != before[c];
        for (int64_t f = 0; f < nfaces; ++f) {
            const int64_t a = faces[2 * f], b = faces[2 * f + 1];
            if (b >= 0 && (active[a] & 1) != (active[b] & 1)) active[a] |= 2, active[b] |= 2;
        }
        for (int64_t c = 0; c < s->cells; ++c) {
            const double own = ceil(substeps / klass[c]);
            r.full_now += substeps, r.full_lts += own;
            if (active[c]) r.active_now += substeps, r.active_lts += own;
        }
        if (at_rest > 0.0) break;
    }
    r.seconds = seconds;
    r.l1 = scene_column_l1(s, h, alpha);
    dpsm_destroy(g);
    free(h), free(before), free(klass), free(active), free(faces);
    return r;
}

static void print_result(const lts_result *r, const lts_result *uniform) {
    printf("%-22s %7lld %6.4f-%6.4f %9.3e %5.3f %6.0f %5.2f %6.3f%% %7.2f %6.2f | %9.3e %9.3e %9.3e %9.3e %9.3e | %5.2f "
           "%5.2f %5.2f | %d/%d/%d/%d\n",
           r->name, (long long)r->cells, r->smallest, r->largest, r->sub_dt, r->own_bound_ratio, r->substeps,
           r->rest_time, 100.0 * r->l1, r->seconds, r->seconds / uniform->seconds, r->updates, r->active_now,
           r->active_lts, r->full_now, r->full_lts, r->updates / uniform->updates, r->active_lts / uniform->active_now,
           r->full_lts / uniform->full_now, r->classes[0], r->classes[1], r->classes[2], r->classes[3]);
}

int cmd_lts(int argc, char **argv) {
    const int m = argc > 0 ? atoi(argv[0]) : 256; /* fine cells across the domain */
    if (m < 64 || m % 8 != 0) {
        fprintf(stderr, "lts: the fine cells across (%d) must be a multiple of 8, at least 64\n", m);
        return 2;
    }
    printf("# local time stepping: quadtree meshes with cells of h..8h (h = %.5f) against uniform squares of the same "
           "count; column collapse (a = 0.5, 30 deg, open edge) in calls of 0.05 to rest, 1 thread\n",
           2.0 * kHalf / m);
    printf("# own/lib: the two-point estimate of the smallest cell's bound over dpsm_stable_dt; seconds/uni: against "
           "the uniform mesh of the same count, same run\n");
    printf("# cell updates: lib = the library's (its active set); active = changed cells and neighbours x sub-steps, at "
           "the one sub-step (now) and each at its class's (lts); full = every cell\n");
    printf("# ratios to the uniform mesh: lib/uni (library against library), lts/uni (active, lts against the uniform's "
           "active), full lts/uni; classes: cells whose own bound allows 1/2/4/8+ times the sub-step\n");
    printf("# \"the same, local steps\": the graded mesh stepped with DPSM_RELAX_LOCAL_STEPS (steps: the smallest "
           "class's ticks; its act/full columns measured at the ticks as for the others)\n");
    printf("%-22s %7s %13s %9s %5s %6s %5s %7s %7s %6s | %9s %9s %9s %9s %9s | %5s %5s %5s | %s\n", "mesh", "cells",
           "sizes", "sub_dt", "own/l", "steps", "rest", "L1", "seconds", "s/uni", "lib", "act now", "act lts",
           "full now", "full lts", "lib/u", "lts/u", "full", "classes");
    const double h = 2.0 * kHalf / m;
    const struct {
        const char *name;
        double px, py, r1;
    } placements[] = {{"graded, fine at pile", 0.0, 0.0, 1.6}, {"graded, fine at corner", kHalf, kHalf, 1.6}};
    for (size_t p = 0; p < sizeof placements / sizeof placements[0]; ++p) {
        quadtree q;
        memset(&q, 0, sizeof q);
        q.m = m, q.levels = 3, q.h = h, q.px = placements[p].px, q.py = placements[p].py;
        q.radius[0] = placements[p].r1, q.radius[1] = q.radius[0] + 0.4, q.radius[2] = q.radius[0] + 0.8;
        mesh_scene graded = quadtree_scene(&q);
        const int n = (int)lround(sqrt((double)graded.cells));
        mesh_scene uniform = scene_make(SCENE_QUADS, n, kHalf, 1u);
        const lts_result ru = run("uniform, same count", &uniform, DPSM_RELAX_AUTO);
        const lts_result rg = run(placements[p].name, &graded, DPSM_RELAX_AUTO);
        const lts_result rl = run("  the same, local steps", &graded, DPSM_RELAX_LOCAL_STEPS);
        print_result(&rg, &ru);
        print_result(&rl, &ru);
        print_result(&ru, &ru);
        printf("# %s: local time steps (DPSM_RELAX_LOCAL_STEPS) took %.4e cell updates, %.2f times the estimate of the "
               "active cells at their classes' sub-steps (act lts, %.4e) and %.2f times the global sub-step's; L1 %.3f%% "
               "against %.3f%%\n",
               placements[p].name, rl.updates, rl.updates / rg.active_lts, rg.active_lts, rl.updates / rg.updates,
               100.0 * rl.l1, 100.0 * rg.l1);
        scene_free(&graded);
        scene_free(&uniform);
        free(q.i0), free(q.j0), free(q.size);
    }
    return 0;
}

/* ---- the graded mesh of issue 34's targets ----------------------------------
 *
 * dpsm-bench mesh-graded [levels [coarse_across [seconds]]]: a quadtree of
 * squares from h to 2^levels h (default 9: h..512h) on [-2.5, 2.5]^2, the
 * coarse cells `coarse_across` (default 48) across; cells of h within 0.06
 * of (-1.25, 0), each coarser size in a band four of its cells wide beyond.
 * Three piles (cylinders of height half their radius, 30 degrees, closed
 * edge), each stepped alone to rest or for `seconds` (default 60) of
 * stepping, one thread:
 *   fine      radius 30 h at the fine region's centre;
 *   coarse    radius 8 coarse cells at (1.25, 0), far from the grading; also
 *             on a uniform mesh of the coarse squares (its reference);
 *   straddle  radius 40 h on the fine region's edge (fine cells and cells of
 *             2h to 8h).
 * Calls of 4096 of the mesh's sub-steps (the uniform mesh: calls of 0.05). A
 * run stopped by the budget reports the cell updates per unit of flow time,
 * and the coarse pile the updates projected to the uniform mesh's rest time
 * at that rate (an extrapolation, printed as one). Counts (sub-steps, cell
 * updates) do not depend on the machine; the seconds do. */

typedef struct {
    const char *name;
    double x, y, radius;
} pile;

typedef struct {
    double substeps, updates, flow_time, seconds;
    int calls, at_rest;
} pile_run;

static pile_run run_pile(const mesh_scene *s, const pile *p, double call, double budget, int relaxation) {
    pile_run r;
    memset(&r, 0, sizeof r);
    double *h = xcalloc((size_t)s->cells, sizeof(double));
    for (int64_t c = 0; c < s->cells; ++c) h[c] = hypot(s->cx[c] - p->x, s->cy[c] - p->y) < p->radius ? 0.5 * p->radius : 0.0;
    dpsm_grid *g = NULL;
    CHECK(NULL, scene_create(s, &g));
    CHECK(g, dpsm_set_threads(g, 1));
    CHECK(g, dpsm_set_repose_angle(g, 30.0 * kPi / 180.0));
    CHECK(g, dpsm_set_heights(g, h));
    CHECK(g, dpsm_set_relaxation(g, relaxation));
    while (r.seconds < budget) {
        const double t0 = now_seconds();
        CHECK(g, dpsm_step(g, call));
        r.seconds += now_seconds() - t0;
        double substeps = 0.0, integrated = 0.0, updates = 0.0, at_rest = 0.0;
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &substeps));
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_TIME_INTEGRATED, &integrated));
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &updates));
        CHECK(g, dpsm_get_step_info(g, DPSM_INFO_AT_REST, &at_rest));
        r.substeps += substeps, r.updates += updates, r.flow_time += integrated;
        ++r.calls;
        if (at_rest > 0.0) {
            r.at_rest = 1;
            break;
        }
    }
    dpsm_destroy(g);
    free(h);
    return r;
}

static void print_pile(const char *mesh, const mesh_scene *s, const pile *p, double sub_dt, const pile_run *r) {
    printf("%-13s %-8s %7lld %9.3e %6d %10.4e %-4s %10.4e %10.4e %10.4e %8.2f\n", mesh, p->name, (long long)s->cells,
           sub_dt, r->calls, r->flow_time, r->at_rest ? "yes" : "no", r->substeps, r->updates,
           r->updates / r->flow_time, r->seconds);
    fflush(stdout);
}

int cmd_mesh_graded(int argc, char **argv) {
    const int levels = argc > 0 ? atoi(argv[0]) : 9;
    const int across = argc > 1 ? atoi(argv[1]) : 48;
    const double budget = argc > 2 ? atof(argv[2]) : 60.0;
    if (levels < 1 || levels >= kMostLevels || across < 8 || !(budget > 0.0)) {
        fprintf(stderr, "mesh-graded: levels from 1 to %d, at least 8 coarse cells across, a positive budget\n",
                kMostLevels - 1);
        return 2;
    }
    quadtree q;
    memset(&q, 0, sizeof q);
    q.levels = levels;
    q.m = across << levels;
    q.h = 2.0 * kHalf / q.m;
    q.px = -1.25, q.py = 0.0;
    q.radius[0] = 0.06;
    for (int k = 1; k < levels; ++k) q.radius[k] = q.radius[k - 1] + 4.0 * (double)(1 << k) * q.h;
    mesh_scene graded = quadtree_scene(&q);
    mesh_scene uniform = scene_make(SCENE_QUADS, across, kHalf, 1u);
    const double coarse = (double)(1 << levels) * q.h;
    const pile fine = {"fine", q.px, q.py, 30.0 * q.h};
    const pile far = {"coarse", 1.25, 0.0, 8.0 * coarse};
    const pile straddle = {"straddle", q.px + q.radius[0], q.py, 40.0 * q.h};
    dpsm_grid *g = NULL;
    double graded_dt = 0.0, uniform_dt = 0.0;
    CHECK(NULL, scene_create(&graded, &g));
    CHECK(g, dpsm_set_repose_angle(g, 30.0 * kPi / 180.0));
    CHECK(g, dpsm_stable_dt(g, &graded_dt));
    dpsm_destroy(g);
    CHECK(NULL, scene_create(&uniform, &g));
    CHECK(g, dpsm_set_repose_angle(g, 30.0 * kPi / 180.0));
    CHECK(g, dpsm_stable_dt(g, &uniform_dt));
    dpsm_destroy(g);
    printf("# graded quadtree: %lld squares from h = %.4e to %d h = %.4e (fine within %.2f of (%.2f, %.2f)); uniform: "
           "%lld squares of %.4e; piles of height half their radius, 30 deg, closed edge, 1 thread; a run stops at rest "
           "or after %.0f s of stepping\n",
           (long long)graded.cells, q.h, 1 << levels, coarse, q.radius[0], q.px, q.py, (long long)uniform.cells,
           coarse, budget);
    printf("# graded: the global sub-step (DPSM_RELAX_AUTO), calls of 4096 sub-steps; graded-local: local time steps "
           "(DPSM_RELAX_LOCAL_STEPS), calls of 0.05 as on the uniform mesh, their substeps the smallest class's ticks\n");
    printf("%-13s %-8s %7s %9s %6s %10s %-4s %10s %10s %10s %8s\n", "mesh", "pile", "cells", "sub_dt", "calls",
           "flow_time", "rest", "substeps", "updates", "upd/time", "seconds");
    const double graded_call = 4096.0 * graded_dt;
    const pile_run uniform_coarse = run_pile(&uniform, &far, 0.05, budget, DPSM_RELAX_AUTO);
    print_pile("uniform", &uniform, &far, uniform_dt, &uniform_coarse);
    const pile *piles[3] = {&far, &fine, &straddle};
    pile_run global[3], local[3];
    for (int k = 0; k < 3; ++k) {
        global[k] = run_pile(&graded, piles[k], graded_call, budget, DPSM_RELAX_AUTO);
        print_pile("graded", &graded, piles[k], graded_dt, &global[k]);
        local[k] = run_pile(&graded, piles[k], 0.05, budget, DPSM_RELAX_LOCAL_STEPS);
        print_pile("graded-local", &graded, piles[k], graded_dt, &local[k]);
    }
    if (uniform_coarse.at_rest) {
        const double projected =
            global[0].at_rest ? global[0].updates : global[0].updates / global[0].flow_time * uniform_coarse.flow_time;
        printf("# coarse pile, global sub-step: the graded mesh %s %.4e cell updates to the uniform mesh's rest time "
               "(t = %.4g), %.1f times the uniform mesh's %.4e\n",
               global[0].at_rest ? "took" : "would take, at its measured rate (extrapolated),", projected,
               uniform_coarse.flow_time, projected / uniform_coarse.updates, uniform_coarse.updates);
    }
    /* issue 34's targets, with local time steps */
    printf("# targets, local time steps: coarse pile %.2f times the uniform mesh's cell updates (at most 2)%s; fine pile "
           "%.2f times the global sub-step's (at most 1); straddling %.2f times the sum of the two (at most 2)\n",
           local[0].updates / uniform_coarse.updates, local[0].at_rest ? "" : " (not at rest within the budget)",
           local[1].updates / global[1].updates, local[2].updates / (local[0].updates + local[1].updates));
    scene_free(&graded);
    scene_free(&uniform);
    free(q.i0), free(q.j0), free(q.size);
    return 0;
}

/* dpsm-bench lts-compare [m [levels]]: local time steps
 * (DPSM_RELAX_LOCAL_STEPS) against the global sub-step on the quadtree
 * meshes of cmd_lts, a column of height 0.5 on an open edge, calls of 0.05:
 * after every call, the L1 difference of the heights over the volume moved
 * so far (half the L1 change of the global run's heights); the ticks, the
 * cell updates and the seconds of each, and the mass of each at the end. */
int cmd_lts_compare(int argc, char **argv) {
    const int m = argc > 0 ? atoi(argv[0]) : 128;
    const int levels = argc > 1 ? atoi(argv[1]) : 3;
    if (m < 64 || m % (1 << levels) != 0 || levels < 1 || levels >= kMostLevels) {
        fprintf(stderr, "lts-compare: the fine cells across (%d) must be a multiple of 2^levels, at least 64\n", m);
        return 2;
    }
    const double h = 2.0 * kHalf / m;
    const struct {
        const char *name;
        double px, py, r1;
    } placements[] = {{"fine", 0.0, 0.0, 1.6}, {"coarse", kHalf, kHalf, 0.9}, {"straddling", 1.2, 0.0, 0.6}};
    printf("# local time steps against the global sub-step: quadtrees of h..%dh (h = %.5f), fine cells within r1 of "
           "(px, py), a column of radius 1 and height 0.5 at the origin, open edge, 30 deg, calls of 0.05, 1 thread\n",
           1 << levels, h);
    printf("%-11s %7s %5s %10s %10s | %9s %9s | %10s %10s | %7s %7s | %s\n", "pile", "cells", "calls", "worst_diff",
           "end_diff", "ticks_glo", "ticks_loc", "upd_glo", "upd_loc", "s_glo", "s_loc", "mass difference");
    for (size_t p = 0; p < sizeof placements / sizeof placements[0]; ++p) {
        quadtree q;
        memset(&q, 0, sizeof q);
        q.m = m, q.levels = levels, q.h = h, q.px = placements[p].px, q.py = placements[p].py;
        q.radius[0] = placements[p].r1;
        for (int k = 1; k < levels; ++k) q.radius[k] = q.radius[k - 1] + 4.0 * (double)(1 << k) * h;
        mesh_scene s = quadtree_scene(&q);
        double *h0 = xcalloc((size_t)s.cells, sizeof(double)), *hg = xcalloc((size_t)s.cells, sizeof(double)),
               *hl = xcalloc((size_t)s.cells, sizeof(double));
        scene_disk_fractions(&s, 1.0, h0);
        for (int64_t c = 0; c < s.cells; ++c) h0[c] *= 0.5;
        dpsm_grid *g[2] = {NULL, NULL};
        for (int k = 0; k < 2; ++k) {
            CHECK(NULL, scene_create(&s, &g[k]));
            CHECK(g[k], dpsm_set_threads(g[k], 1));
            CHECK(g[k], dpsm_set_repose_angle(g[k], 30.0 * kPi / 180.0));
            CHECK(g[k], dpsm_set_boundary(g[k], DPSM_MESH_EDGE, DPSM_OPEN));
            CHECK(g[k], dpsm_set_heights(g[k], h0));
        }
        CHECK(g[1], dpsm_set_relaxation(g[1], DPSM_RELAX_LOCAL_STEPS));
        double worst = 0.0, last = 0.0, ticks[2] = {0, 0}, updates[2] = {0, 0}, seconds[2] = {0, 0};
        int calls = 0;
        for (; calls < 400; ++calls) {
            double at_rest[2] = {0, 0};
            for (int k = 0; k < 2; ++k) {
                const double t0 = now_seconds();
                CHECK(g[k], dpsm_step(g[k], 0.05));
                seconds[k] += now_seconds() - t0;
                double sub = 0, upd = 0;
                CHECK(g[k], dpsm_get_step_info(g[k], DPSM_INFO_SUBSTEPS, &sub));
                CHECK(g[k], dpsm_get_step_info(g[k], DPSM_INFO_CELL_UPDATES, &upd));
                CHECK(g[k], dpsm_get_step_info(g[k], DPSM_INFO_AT_REST, &at_rest[k]));
                ticks[k] += sub, updates[k] += upd;
            }
            CHECK(g[0], dpsm_get_heights(g[0], hg));
            CHECK(g[1], dpsm_get_heights(g[1], hl));
            double diff = 0.0, moved = 0.0;
            for (int64_t c = 0; c < s.cells; ++c) {
                diff += fabs(hl[c] - hg[c]) * s.area[c];
                moved += fabs(hg[c] - h0[c]) * s.area[c];
            }
            moved *= 0.5;
            if (moved > 0.0) worst = fmax(worst, diff / moved), last = diff / moved;
            if (at_rest[0] > 0.0 && at_rest[1] > 0.0) break;
        }
        double mass[2];
        for (int k = 0; k < 2; ++k) CHECK(g[k], dpsm_get_mass(g[k], DPSM_MASS_TOTAL, &mass[k]));
        printf("%-11s %7lld %5d %10.3e %10.3e | %9.0f %9.0f | %10.4e %10.4e | %7.2f %7.2f | %.3e\n", placements[p].name,
               (long long)s.cells, calls + 1, worst, last, ticks[0], ticks[1], updates[0], updates[1], seconds[0],
               seconds[1], fabs(mass[1] - mass[0]) / mass[0]);
        fflush(stdout);
        dpsm_destroy(g[0]), dpsm_destroy(g[1]);
        free(h0), free(hg), free(hl);
        scene_free(&s);
        free(q.i0), free(q.j0), free(q.size);
    }
    return 0;
}
