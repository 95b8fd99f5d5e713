/* What sets the slow tail of the mesh engine's flow on irregular meshes
 * (issue 33; docs/guide_meshes.md, "What is not there yet"):
 *
 * dpsm-bench mesh-plane KIND N: a plane 1 % steeper than the angle of
 * repose on the library's mesh, one stable sub-step; how far the cells four
 * cells or more from the edge move, against the plane's flux over the cell
 * size. A consistent step leaves a plane's inside as it is.
 *
 * dpsm-bench mesh-energies KIND N ENERGY [JITTER]: the column collapse of
 * mesh-accuracy (a = 0.5, 30 degrees) under the gradient flow of one of seven
 * face or cell energies, explicit, with no limiter, to rest: when it rests
 * and its L1 difference from the exact deposit at the cells' centres over
 * the volume. Not the library: a small copy of its flow that runs in seconds,
 * so that other energies can be tried beside it. With the library's energy
 * (`faces`) it rests when the library does (the median dual of 4,225 cells
 * at t = 4.46 in both). The energies, each a sum of Phi(|G|) over regions
 * that tile the domain, Phi' the slide flux:
 *   faces             the library's: per face, its diamond, G = the two-point
 *                     slope along the centres plus the mean of the cells'
 *                     least-squares gradients across it;
 *   node-diamond      per face, its diamond with one value per node (a
 *                     least-squares plane through the cells around it; a
 *                     triangle's centroid on the dual: its nodes' mean):
 *                     the two-point slope plus the nodes' difference;
 *   triangle-tangents the median dual only: as `faces`, the part across the
 *                     face from the two triangles' own linear gradients;
 *   triangles         the median dual only: per triangle, the linear
 *                     interpolant's gradient (finite elements, lumped mass);
 *   faces-and-triangles  the median dual only: half of `faces` and half of
 *                     `triangles`;
 *   cells             per cell, its area, G = its least-squares gradient;
 *   faces-and-cells   half of `faces` and half of `cells`.
 * JITTER (0.3, the benchmark's) moves the lattice's inner nodes of the
 * triangles and the dual. Faces on the domain edge carry nothing here: the
 * column never reaches it. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "mesh_scenes.h"

static const double kTheta = 30.0 * 3.14159265358979323846 / 180.0;
static const double kTolerance = 1e-6;

typedef enum {
    ENERGY_FACES,
    ENERGY_NODE_DIAMOND,
    ENERGY_TRIANGLE_TANGENTS,
    ENERGY_TRIANGLES,
    ENERGY_FACES_AND_TRIANGLES,
    ENERGY_CELLS,
    ENERGY_FACES_AND_CELLS
} energy_kind;
static const char *const kEnergyNames[] = {"faces", "node-diamond", "triangle-tangents", "triangles",
                                           "faces-and-triangles", "cells", "faces-and-cells"};
enum { kEnergies = 7 };

/* A face between cells a and b: e the unit vector from a to b, t across it,
 * d the distance, n the normal times the length (from a to b), orthogonal =
 * n . e; its ends v1, v2 (nodes, or on the dual the triangles' centroids) in
 * the order that turns n from v2 - v1. */
typedef struct {
    int64_t a, b, v1, v2;
    double ex, ey, tx, ty, d, nx, ny, orthogonal;
} study_face;

typedef struct {
    mesh_scene s;
    int64_t faces;
    study_face *face;
    /* ends: their positions, and the cells around each with a weight */
    int64_t ends;
    double *end_x, *end_y;
    int64_t *end_start, *end_cell;
    double *end_weight;
    /* each cell's least-squares gradient over the cells across its faces */
    int64_t *grad_start, *grad_cell;
    double *grad_wx, *grad_wy;
} study_mesh;

static int compare_edges(const void *l, const void *r) {
    const int64_t *u = l, *w = r;
    if (u[0] != w[0]) return u[0] < w[0] ? -1 : 1;
    if (u[1] != w[1]) return u[1] < w[1] ? -1 : 1;
    return 0;
}

/* The faces between two cells: polygon edges held by two cells (ends: the
 * edge's nodes), or on the dual the triangle edges held by two triangles
 * (cells: the edge's nodes; ends: the triangles' centroids). */
static void find_faces(study_mesh *m) {
    const mesh_scene *s = &m->s;
    const int dual = s->kind == SCENE_DUAL;
    const int64_t edges = dual ? 3 * s->npolygons : s->cell_start[s->npolygons];
    int64_t(*edge)[3] = xcalloc((size_t)edges, sizeof *edge);
    for (int64_t p = 0, k = 0; p < s->npolygons; ++p) {
        const int64_t k0 = dual ? 3 * p : s->cell_start[p], k1 = dual ? 3 * p + 3 : s->cell_start[p + 1];
        for (int64_t j = k0; j < k1; ++j, ++k) {
            const int64_t u = s->cell_nodes[j], w = s->cell_nodes[j + 1 < k1 ? j + 1 : k0];
            edge[k][0] = u < w ? u : w, edge[k][1] = u < w ? w : u, edge[k][2] = p;
        }
    }
    qsort(edge, (size_t)edges, sizeof *edge, compare_edges);
    m->face = xcalloc((size_t)edges, sizeof(study_face));
    m->faces = 0;
    for (int64_t k = 0; k + 1 < edges; ++k) {
        if (compare_edges(edge[k], edge[k + 1]) != 0) continue;
        study_face *f = &m->face[m->faces++];
        if (dual)
            f->a = edge[k][0], f->b = edge[k][1], f->v1 = edge[k][2], f->v2 = edge[k + 1][2];
        else
            f->a = edge[k][2], f->b = edge[k + 1][2], f->v1 = edge[k][0], f->v2 = edge[k][1];
        ++k;
    }
    free(edge);
}

/* The ends' positions and the cells around each, with the weights of a
 * least-squares plane through them evaluated at the end. */
static void find_ends(study_mesh *m) {
    const mesh_scene *s = &m->s;
    if (s->kind == SCENE_DUAL) {
        m->ends = s->npolygons;
        m->end_x = xcalloc((size_t)m->ends, sizeof(double)), m->end_y = xcalloc((size_t)m->ends, sizeof(double));
        m->end_start = xcalloc((size_t)m->ends + 1, sizeof(int64_t));
        m->end_cell = xcalloc((size_t)(3 * m->ends), sizeof(int64_t));
        m->end_weight = xcalloc((size_t)(3 * m->ends), sizeof(double));
        for (int64_t t = 0; t < m->ends; ++t) {
            m->end_start[t + 1] = 3 * (t + 1);
            for (int i = 0; i < 3; ++i) {
                const int64_t p = s->cell_nodes[3 * t + i];
                m->end_cell[3 * t + i] = p, m->end_weight[3 * t + i] = 1.0 / 3.0;
                m->end_x[t] += s->node_xy[2 * p] / 3.0, m->end_y[t] += s->node_xy[2 * p + 1] / 3.0;
            }
        }
        return;
    }
    m->ends = s->nnodes;
    m->end_x = xcalloc((size_t)m->ends, sizeof(double)), m->end_y = xcalloc((size_t)m->ends, sizeof(double));
    for (int64_t v = 0; v < m->ends; ++v) m->end_x[v] = s->node_xy[2 * v], m->end_y[v] = s->node_xy[2 * v + 1];
    m->end_start = xcalloc((size_t)m->ends + 1, sizeof(int64_t));
    for (int64_t k = 0; k < s->cell_start[s->npolygons]; ++k) ++m->end_start[s->cell_nodes[k] + 1];
    for (int64_t v = 0; v < m->ends; ++v) m->end_start[v + 1] += m->end_start[v];
    m->end_cell = xcalloc((size_t)m->end_start[m->ends], sizeof(int64_t));
    m->end_weight = xcalloc((size_t)m->end_start[m->ends], sizeof(double));
    int64_t *fill = xcalloc((size_t)m->ends, sizeof(int64_t));
    memcpy(fill, m->end_start, (size_t)m->ends * sizeof(int64_t));
    for (int64_t p = 0; p < s->npolygons; ++p)
        for (int64_t k = s->cell_start[p]; k < s->cell_start[p + 1]; ++k) m->end_cell[fill[s->cell_nodes[k]]++] = p;
    free(fill);
    for (int64_t v = 0; v < m->ends; ++v) {
        const int64_t k0 = m->end_start[v], k1 = m->end_start[v + 1];
        /* The plane's value at the end: the first row of (X^T X)^-1 X^T, X's rows (1, dx, dy). */
        double a[3][3] = {{0.0}};
        for (int64_t k = k0; k < k1; ++k) {
            const double r[3] = {1.0, s->cx[m->end_cell[k]] - m->end_x[v], s->cy[m->end_cell[k]] - m->end_y[v]};
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) a[i][j] += r[i] * r[j];
        }
        const double c00 = a[1][1] * a[2][2] - a[1][2] * a[2][1], c01 = a[0][2] * a[2][1] - a[0][1] * a[2][2],
                     c02 = a[0][1] * a[1][2] - a[0][2] * a[1][1];
        const double det = a[0][0] * c00 + a[1][0] * c01 + a[2][0] * c02;
        const int fits = k1 - k0 >= 3 && fabs(det) > 1e-12 * a[0][0] * a[1][1] * a[2][2];
        for (int64_t k = k0; k < k1; ++k) {
            const double r[3] = {1.0, s->cx[m->end_cell[k]] - m->end_x[v], s->cy[m->end_cell[k]] - m->end_y[v]};
            m->end_weight[k] = fits ? (c00 * r[0] + c01 * r[1] + c02 * r[2]) / det : 1.0 / (double)(k1 - k0);
        }
    }
}

/* Each face's geometry, and each cell's least-squares gradient weights (by
 * inverse distance squared over the cells across its faces, as the library's). */
static void find_geometry(study_mesh *m) {
    const mesh_scene *s = &m->s;
    for (int64_t k = 0; k < m->faces; ++k) {
        study_face *f = &m->face[k];
        const double dx = s->cx[f->b] - s->cx[f->a], dy = s->cy[f->b] - s->cy[f->a];
        f->d = hypot(dx, dy), f->ex = dx / f->d, f->ey = dy / f->d, f->tx = -f->ey, f->ty = f->ex;
        f->nx = m->end_y[f->v2] - m->end_y[f->v1], f->ny = -(m->end_x[f->v2] - m->end_x[f->v1]);
        if (f->nx * f->ex + f->ny * f->ey < 0.0) {
            const int64_t v = f->v1;
            f->v1 = f->v2, f->v2 = v, f->nx = -f->nx, f->ny = -f->ny;
        }
        f->orthogonal = f->nx * f->ex + f->ny * f->ey;
    }
    const int64_t cells = s->cells;
    m->grad_start = xcalloc((size_t)cells + 1, sizeof(int64_t));
    for (int64_t k = 0; k < m->faces; ++k) ++m->grad_start[m->face[k].a + 1], ++m->grad_start[m->face[k].b + 1];
    for (int64_t c = 0; c < cells; ++c) m->grad_start[c + 1] += m->grad_start[c];
    const size_t entries = (size_t)m->grad_start[cells];
    m->grad_cell = xcalloc(entries, sizeof(int64_t));
    m->grad_wx = xcalloc(entries, sizeof(double)), m->grad_wy = xcalloc(entries, sizeof(double));
    int64_t *fill = xcalloc((size_t)cells, sizeof(int64_t));
    memcpy(fill, m->grad_start, (size_t)cells * sizeof(int64_t));
    for (int64_t k = 0; k < m->faces; ++k)
        m->grad_cell[fill[m->face[k].a]++] = m->face[k].b, m->grad_cell[fill[m->face[k].b]++] = m->face[k].a;
    free(fill);
    for (int64_t c = 0; c < cells; ++c) {
        double sxx = 0.0, sxy = 0.0, syy = 0.0;
        for (int64_t k = m->grad_start[c]; k < m->grad_start[c + 1]; ++k) {
            const double dx = s->cx[m->grad_cell[k]] - s->cx[c], dy = s->cy[m->grad_cell[k]] - s->cy[c];
            const double w = 1.0 / (dx * dx + dy * dy);
            sxx += w * dx * dx, sxy += w * dx * dy, syy += w * dy * dy;
        }
        const double det = sxx * syy - sxy * sxy;
        if (!(det > 1e-6 * (sxx + syy) * (sxx + syy))) continue;
        for (int64_t k = m->grad_start[c]; k < m->grad_start[c + 1]; ++k) {
            const double dx = s->cx[m->grad_cell[k]] - s->cx[c], dy = s->cy[m->grad_cell[k]] - s->cy[c];
            const double w = 1.0 / (dx * dx + dy * dy);
            m->grad_wx[k] = w * (syy * dx - sxy * dy) / det, m->grad_wy[k] = w * (sxx * dy - sxy * dx) / det;
        }
    }
}

/* The gradients of triangle t's linear basis functions (the dual's triangles). */
static void triangle_basis(const mesh_scene *s, int64_t t, double bx[3], double by[3], double *area) {
    const int64_t *q = s->cell_nodes + 3 * t;
    double x[3], y[3];
    for (int i = 0; i < 3; ++i) x[i] = s->node_xy[2 * q[i]], y[i] = s->node_xy[2 * q[i] + 1];
    const double twice = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
    for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3, k = (i + 2) % 3;
        bx[i] = (y[j] - y[k]) / twice, by[i] = (x[k] - x[j]) / twice;
    }
    *area = 0.5 * fabs(twice);
}

/* g = Phi'(s) / s where the slope s is steep, else 0; the largest s - threshold in *worst. */
static double law(double slope, double *worst) {
    const double tan_theta = tan(kTheta);
    *worst = fmax(*worst, slope - tan_theta * (1.0 + kTolerance));
    if (!(slope > tan_theta * (1.0 + kTolerance))) return 0.0;
    return (slope - tan_theta) / sqrt(1.0 + slope * slope) / slope;
}

typedef struct {
    double *gx, *gy, *pull_x, *pull_y, *end_h, *end_pull;
} study_scratch;

/* dE/dh of the energy into de; returns the largest excess slope over the threshold. */
static double energy_derivative(const study_mesh *m, energy_kind energy, const double *h, double *de,
                                const study_scratch *w) {
    const mesh_scene *s = &m->s;
    double worst = -1.0;
    memset(de, 0, (size_t)s->cells * sizeof(double));
    /* faces-and-triangles, faces-and-cells: half of each energy, so that a plane's is still exact */
    const double share = energy == ENERGY_FACES_AND_TRIANGLES || energy == ENERGY_FACES_AND_CELLS ? 0.5 : 1.0;
    const int cells_too = energy == ENERGY_CELLS || energy == ENERGY_FACES_AND_CELLS;
    if (energy == ENERGY_TRIANGLES || energy == ENERGY_FACES_AND_TRIANGLES) {
        for (int64_t t = 0; t < s->npolygons; ++t) {
            double bx[3], by[3], area, gx = 0.0, gy = 0.0;
            triangle_basis(s, t, bx, by, &area);
            for (int i = 0; i < 3; ++i) gx += h[s->cell_nodes[3 * t + i]] * bx[i], gy += h[s->cell_nodes[3 * t + i]] * by[i];
            const double g = law(hypot(gx, gy), &worst);
            for (int i = 0; i < 3; ++i) de[s->cell_nodes[3 * t + i]] += share * area * g * (gx * bx[i] + gy * by[i]);
        }
        if (energy == ENERGY_TRIANGLES) return worst;
        energy = ENERGY_FACES;
    }
    if (energy == ENERGY_FACES_AND_CELLS) energy = ENERGY_FACES;
    for (int64_t c = 0; c < s->cells; ++c) {
        double x = 0.0, y = 0.0;
        for (int64_t k = m->grad_start[c]; k < m->grad_start[c + 1]; ++k) {
            const double dh = h[m->grad_cell[k]] - h[c];
            x += m->grad_wx[k] * dh, y += m->grad_wy[k] * dh;
        }
        w->gx[c] = x, w->gy[c] = y, w->pull_x[c] = w->pull_y[c] = 0.0;
    }
    for (int64_t v = 0; v < m->ends; ++v) {
        double x = 0.0;
        for (int64_t k = m->end_start[v]; k < m->end_start[v + 1]; ++k) x += m->end_weight[k] * h[m->end_cell[k]];
        w->end_h[v] = x, w->end_pull[v] = 0.0;
    }
    for (int64_t k = 0; k < m->faces && energy != ENERGY_CELLS; ++k) {
        const study_face *f = &m->face[k];
        const double along = (h[f->b] - h[f->a]) / f->d;
        double across = 0.0, b1x[3], b1y[3], b2x[3], b2y[3], area;
        if (energy == ENERGY_FACES)
            across = 0.5 * ((w->gx[f->a] + w->gx[f->b]) * f->tx + (w->gy[f->a] + w->gy[f->b]) * f->ty);
        else if (energy == ENERGY_NODE_DIAMOND)
            /* The diamond's slope across: ((h_b - h_a) n.t + (h_v2 - h_v1) d) / (orthogonal d). */
            across = ((h[f->b] - h[f->a]) * (f->nx * f->tx + f->ny * f->ty) + (w->end_h[f->v2] - w->end_h[f->v1]) * f->d) /
                     (f->orthogonal * f->d);
        else {
            triangle_basis(s, f->v1, b1x, b1y, &area);
            triangle_basis(s, f->v2, b2x, b2y, &area);
            for (int i = 0; i < 3; ++i)
                across += 0.5 * h[s->cell_nodes[3 * f->v1 + i]] * (b1x[i] * f->tx + b1y[i] * f->ty) +
                          0.5 * h[s->cell_nodes[3 * f->v2 + i]] * (b2x[i] * f->tx + b2y[i] * f->ty);
        }
        const double g = law(hypot(along, across), &worst);
        if (g == 0.0) continue;
        /* dE_f/d(along) and dE_f/d(across), E_f = V Phi, V = orthogonal d / 2 */
        const double volume = share * 0.5 * f->orthogonal * f->d, by_along = volume * g * along, by_across = volume * g * across;
        if (energy == ENERGY_NODE_DIAMOND) {
            const double skewed = by_across * (f->nx * f->tx + f->ny * f->ty) / (f->orthogonal * f->d);
            de[f->b] += by_along / f->d + skewed, de[f->a] -= by_along / f->d + skewed;
            w->end_pull[f->v2] += by_across / f->orthogonal, w->end_pull[f->v1] -= by_across / f->orthogonal;
            continue;
        }
        de[f->b] += by_along / f->d, de[f->a] -= by_along / f->d;
        if (energy == ENERGY_FACES) {
            /* Half of it on each cell's gradient along t. */
            const double px = 0.5 * by_across * f->tx, py = 0.5 * by_across * f->ty;
            w->pull_x[f->a] += px, w->pull_y[f->a] += py, w->pull_x[f->b] += px, w->pull_y[f->b] += py;
        } else {
            for (int i = 0; i < 3; ++i) {
                de[s->cell_nodes[3 * f->v1 + i]] += 0.5 * by_across * (b1x[i] * f->tx + b1y[i] * f->ty);
                de[s->cell_nodes[3 * f->v2 + i]] += 0.5 * by_across * (b2x[i] * f->tx + b2y[i] * f->ty);
            }
        }
    }
    /* A cell's part of E asks of its own gradient what a face's asks of its cells' along t. */
    if (cells_too)
        for (int64_t c = 0; c < s->cells; ++c) {
            const double g = law(hypot(w->gx[c], w->gy[c]), &worst), volume = share * s->area[c];
            w->pull_x[c] += volume * g * w->gx[c], w->pull_y[c] += volume * g * w->gy[c];
        }
    if (energy == ENERGY_FACES || energy == ENERGY_CELLS)
        for (int64_t c = 0; c < s->cells; ++c)
            for (int64_t k = m->grad_start[c]; k < m->grad_start[c + 1]; ++k) {
                const double p = m->grad_wx[k] * w->pull_x[c] + m->grad_wy[k] * w->pull_y[c];
                de[m->grad_cell[k]] += p, de[c] -= p;
            }
    if (energy == ENERGY_NODE_DIAMOND)
        for (int64_t v = 0; v < m->ends; ++v)
            for (int64_t k = m->end_start[v]; k < m->end_start[v + 1]; ++k)
                de[m->end_cell[k]] += m->end_weight[k] * w->end_pull[v];
    return worst;
}

static int kind_named(const char *name, scene_kind *kind) {
    static const scene_kind kinds[] = {SCENE_QUADS, SCENE_TRIANGLES, SCENE_HEXAGONS, SCENE_DUAL};
    for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; ++k)
        if (strcmp(name, scene_name(kinds[k])) == 0) return *kind = kinds[k], 1;
    fprintf(stderr, "unknown mesh %s (quadrilaterals, jittered_triangles, hexagons, median_dual)\n", name);
    return 0;
}

int cmd_mesh_energies(int argc, char **argv) {
    scene_kind kind;
    if (argc < 3 || !kind_named(argv[0], &kind)) {
        fprintf(stderr, "usage: mesh-energies MESH N ENERGY [JITTER]\n");
        return 2;
    }
    const int n = atoi(argv[1]);
    int energy = -1;
    for (int e = 0; e < kEnergies; ++e)
        if (strcmp(argv[2], kEnergyNames[e]) == 0) energy = e;
    const int dual_only = energy >= ENERGY_TRIANGLE_TANGENTS && energy <= ENERGY_FACES_AND_TRIANGLES;
    if (n < 4 || energy < 0 || (dual_only && kind != SCENE_DUAL)) {
        fprintf(stderr, "mesh-energies: N at least 4; ENERGY faces, node-diamond, cells, faces-and-cells, or on "
                        "median_dual also triangle-tangents, triangles, faces-and-triangles\n");
        return 2;
    }
    const double jitter = argc > 3 ? atof(argv[3]) : 0.3;
    const double alpha = tan(kTheta), foot = scene_column_foot(alpha);
    study_mesh m;
    memset(&m, 0, sizeof m);
    m.s = scene_make_jittered(kind, n, 1.25 * fmax(2.0, foot), jitter, 12345u);
    const mesh_scene *s = &m.s;
    find_faces(&m);
    find_ends(&m);
    find_geometry(&m);
    /* Half the library's stable bound: there is no limiter here. */
    double *conductance = xcalloc((size_t)s->cells, sizeof(double));
    for (int64_t k = 0; k < m.faces; ++k) {
        const double c = hypot(m.face[k].nx, m.face[k].ny) / m.face[k].d;
        conductance[m.face[k].a] += c, conductance[m.face[k].b] += c;
    }
    double bound = INFINITY;
    for (int64_t c = 0; c < s->cells; ++c)
        if (conductance[c] > 0.0) bound = fmin(bound, s->area[c] / conductance[c]);
    const double dt = 0.45 * bound / cos(kTheta);
    double *h = xcalloc((size_t)s->cells, sizeof(double)), *de = xcalloc((size_t)s->cells, sizeof(double));
    study_scratch w = {xcalloc((size_t)s->cells, sizeof(double)), xcalloc((size_t)s->cells, sizeof(double)),
                       xcalloc((size_t)s->cells, sizeof(double)), xcalloc((size_t)s->cells, sizeof(double)),
                       xcalloc((size_t)m.ends, sizeof(double)),   xcalloc((size_t)m.ends, sizeof(double))};
    scene_pour_column(s, h);
    double t = 0.0;
    long steps = 0;
    while (energy_derivative(&m, (energy_kind)energy, h, de, &w) > 0.0 && t < 20.0) {
        for (int64_t c = 0; c < s->cells; ++c) h[c] -= dt * de[c] / s->area[c];
        t += dt, ++steps;
    }
    printf("mesh,cells,energy,jitter,at_rest,rest_time,steps,l1_error\n");
    printf("%s,%lld,%s,%.2f,%d,%.3f,%ld,%.4e\n", scene_name(kind), (long long)s->cells, kEnergyNames[energy], jitter,
           t < 20.0, t, steps, scene_column_l1(s, h, alpha));
    free(conductance), free(h), free(de);
    free(w.gx), free(w.gy), free(w.pull_x), free(w.pull_y), free(w.end_h), free(w.end_pull);
    free(m.face), free(m.end_x), free(m.end_y), free(m.end_start), free(m.end_cell), free(m.end_weight);
    free(m.grad_start), free(m.grad_cell), free(m.grad_wx), free(m.grad_wy);
    scene_free(&m.s);
    return 0;
}

int cmd_mesh_plane(int argc, char **argv) {
    scene_kind kind;
    if (argc < 2 || !kind_named(argv[0], &kind)) {
        fprintf(stderr, "usage: mesh-plane MESH N\n");
        return 2;
    }
    const double half = 2.0, excess = 0.01, alpha = tan(kTheta);
    mesh_scene s = scene_make(kind, atoi(argv[1]), half, 12345u);
    const double size = scene_mean_size(&s), slope = alpha * (1.0 + excess);
    double *h = xcalloc((size_t)s.cells, sizeof(double)), *after = xcalloc((size_t)s.cells, sizeof(double));
    for (int64_t c = 0; c < s.cells; ++c) h[c] = 10.0 + slope * (cos(0.3) * s.cx[c] + sin(0.3) * s.cy[c]);
    dpsm_grid *g = NULL;
    CHECK(NULL, scene_create(&s, &g));
    CHECK(g, dpsm_set_repose_angle(g, kTheta));
    CHECK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN));
    CHECK(g, dpsm_set_heights(g, h));
    double dt = 0.0;
    CHECK(g, dpsm_stable_dt(g, &dt));
    CHECK(g, dpsm_step(g, dt));
    CHECK(g, dpsm_get_heights(g, after));
    double largest = 0.0, sum = 0.0;
    int64_t inside = 0;
    for (int64_t c = 0; c < s.cells; ++c) {
        if (fabs(s.cx[c]) > half - 4.0 * size || fabs(s.cy[c]) > half - 4.0 * size) continue;
        const double rate = fabs(after[c] - h[c]) / dt;
        largest = fmax(largest, rate), sum += rate, ++inside;
    }
    const double flux = (slope - alpha) / sqrt(1.0 + slope * slope);
    printf("mesh,cells,mean_size,largest_rate,mean_rate,flux_over_size\n");
    printf("%s,%lld,%.4f,%.3e,%.3e,%.3e\n", scene_name(kind), (long long)s.cells, size, largest, sum / (double)inside,
           flux / size);
    dpsm_destroy(g);
    free(h), free(after);
    scene_free(&s);
    return 0;
}
