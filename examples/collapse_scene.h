/* The scene of the mesh examples (mesh_collapse.c, mpi_mesh_collapse.c): a
 * sand column of radius 1 and height 0.5 on a square table of n x n squares
 * whose inner nodes are jittered, each square split along its shorter
 * diagonal into two triangles, and the exact deposit it collapses to (a
 * truncated cone, for the angle of repose theta). */
#ifndef DPSM_EXAMPLES_COLLAPSE_SCENE_H
#define DPSM_EXAMPLES_COLLAPSE_SCENE_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#define COLLAPSE_PI 3.14159265358979323846

static void *collapse_alloc(size_t n, size_t size) {
    void *p = calloc(n ? n : 1, size);
    if (!p) {
        fprintf(stderr, "out of memory\n");
        exit(1);
    }
    return p;
}

typedef struct {
    int64_t nnodes, ncells;
    double *xy;             /* 2 per node */
    int64_t *start, *nodes; /* the triangles: start[c] .. start[c + 1] in nodes, 3 each */
    double *height, *area;  /* per triangle: the column's cell average, the area */
    double *exact;          /* per triangle: the exact deposit at its centroid */
    double h0;              /* the column's height */
} collapse_scene;

/* The share of the triangle (p, q, r) inside the circle of radius 1, by 12^2 sub-triangles. */
static double collapse_inside_unit_circle(const double *p, const double *q, const double *r) {
    const int m = 12;
    int inside = 0;
    for (int i = 0; i < m; ++i)
        for (int j = 0; i + j < m; ++j)
            for (int up = 0; up < 2; ++up) {
                if (up && i + j == m - 1) continue;
                const double u = (i + (up ? 2.0 : 1.0) / 3.0) / m, v = (j + (up ? 2.0 : 1.0) / 3.0) / m;
                const double x = p[0] + u * (q[0] - p[0]) + v * (r[0] - p[0]);
                const double y = p[1] + u * (q[1] - p[1]) + v * (r[1] - p[1]);
                inside += x * x + y * y <= 1.0;
            }
    return (double)inside / (m * m);
}

static collapse_scene collapse_scene_make(int n, double theta) {
    collapse_scene s;
    const double alpha = tan(theta), half = 2.5, h = 2.0 * half / n;
    s.h0 = 0.5;
    /* the exact deposit's foot: r_f = (a + sqrt(4 alpha^2 - a^2/3)) / (2 alpha), a = 0.5 */
    const double foot = (s.h0 + sqrt(4.0 * alpha * alpha - s.h0 * s.h0 / 3.0)) / (2.0 * alpha);

    /* Nodes on the (n+1)^2 lattice, inner ones jittered by up to 0.3 h. */
    s.nnodes = (int64_t)(n + 1) * (n + 1);
    s.ncells = 2 * (int64_t)n * n;
    s.xy = collapse_alloc((size_t)(2 * s.nnodes), sizeof *s.xy);
    unsigned seed = 2026u;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const int64_t k = i + (int64_t)(n + 1) * j;
            seed = seed * 1103515245u + 12345u;
            const double jx = 0.3 * h * (((seed >> 8) & 0xFFFF) / 32768.0 - 1.0);
            seed = seed * 1103515245u + 12345u;
            const double jy = 0.3 * h * (((seed >> 8) & 0xFFFF) / 32768.0 - 1.0);
            s.xy[2 * k] = -half + i * h + (i > 0 && i < n ? jx : 0.0);
            s.xy[2 * k + 1] = -half + j * h + (j > 0 && j < n ? jy : 0.0);
        }
    s.start = collapse_alloc((size_t)s.ncells + 1, sizeof *s.start);
    s.nodes = collapse_alloc((size_t)(3 * s.ncells), sizeof *s.nodes);
    int64_t c = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int64_t a = i + (int64_t)(n + 1) * j, b = a + 1, cc = b + n + 1, d = a + n + 1;
            const double *xy = s.xy;
            const int ac_short = hypot(xy[2 * cc] - xy[2 * a], xy[2 * cc + 1] - xy[2 * a + 1]) <=
                                 hypot(xy[2 * d] - xy[2 * b], xy[2 * d + 1] - xy[2 * b + 1]);
            const int64_t tri[2][3] = {{a, b, ac_short ? cc : d}, {ac_short ? a : b, cc, d}};
            for (int t = 0; t < 2; ++t, ++c) {
                s.start[c] = 3 * c;
                for (int v = 0; v < 3; ++v) s.nodes[3 * c + v] = tri[t][v];
            }
        }
    s.start[s.ncells] = 3 * s.ncells;

    /* The column by cell averages, the exact deposit at each centroid. */
    s.height = collapse_alloc((size_t)s.ncells, sizeof *s.height);
    s.area = collapse_alloc((size_t)s.ncells, sizeof *s.area);
    s.exact = collapse_alloc((size_t)s.ncells, sizeof *s.exact);
    for (c = 0; c < s.ncells; ++c) {
        const double *p = s.xy + 2 * s.nodes[3 * c], *q = s.xy + 2 * s.nodes[3 * c + 1], *r = s.xy + 2 * s.nodes[3 * c + 2];
        s.area[c] = 0.5 * fabs((q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1]));
        s.height[c] = s.h0 * collapse_inside_unit_circle(p, q, r);
        const double radius = hypot((p[0] + q[0] + r[0]) / 3.0, (p[1] + q[1] + r[1]) / 3.0);
        s.exact[c] = fmin(s.h0, fmax(0.0, alpha * (foot - radius)));
    }
    return s;
}

static void collapse_scene_free(collapse_scene *s) {
    free(s->xy), free(s->start), free(s->nodes), free(s->height), free(s->area), free(s->exact);
}

#endif
