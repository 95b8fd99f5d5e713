/* A sand column collapses on a triangle mesh (docs/guide_meshes.md).
 *
 * The program builds its own mesh: a square table of n x n squares whose
 * inner nodes are jittered, each square split along its shorter diagonal
 * into two triangles, handed to dpsm as polygons over shared nodes
 * (dpsm_create_mesh). A column of radius 1 and height 0.5 is poured on it by
 * cell averages, the table's edge is open, and the mesh is stepped to rest.
 * It prints the L1 difference from the exact deposit (a truncated cone) over
 * the column's volume, and the mass balance.
 *
 * usage: dpsm-mesh-collapse [n] [theta_degrees]      (defaults 60 30)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <dpsm/dpsm.h>

#define CHECK(call)                                                                     \
    do {                                                                                \
        int status_ = (call);                                                           \
        if (status_ != DPSM_OK) {                                                       \
            fprintf(stderr, "%s failed: %s: %s\n", #call, dpsm_status_string(status_), \
                    dpsm_last_error(g));                                                \
            exit(1);                                                                    \
        }                                                                               \
    } while (0)

static void *alloc(size_t n, size_t size) {
    void *p = calloc(n, size);
    if (!p) {
        fprintf(stderr, "out of memory\n");
        exit(1);
    }
    return p;
}

/* The share of the triangle (p, q, r) inside the circle of radius 1, by 12^2 sub-triangles. */
static double inside_unit_circle(const double *p, const double *q, const double *r) {
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

int main(int argc, char **argv) {
    const int n = argc > 1 ? atoi(argv[1]) : 60;
    const double theta = (argc > 2 ? atof(argv[2]) : 30.0) * 3.14159265358979323846 / 180.0;
    if (n < 4 || !(theta > 0.0 && theta < 1.5)) {
        fprintf(stderr, "usage: dpsm-mesh-collapse [n >= 4] [theta_degrees]\n");
        return 2;
    }
    const double alpha = tan(theta), half = 2.5, h = 2.0 * half / n, h0 = 0.5;
    /* the exact deposit's foot: r_f = (a + sqrt(4 alpha^2 - a^2/3)) / (2 alpha), a = 0.5 */
    const double foot = (h0 + sqrt(4.0 * alpha * alpha - h0 * h0 / 3.0)) / (2.0 * alpha);

    /* Nodes on the (n+1)^2 lattice, inner ones jittered by up to 0.3 h. */
    const int64_t nnodes = (int64_t)(n + 1) * (n + 1), ncells = 2 * (int64_t)n * n;
    double *xy = alloc((size_t)(2 * nnodes), sizeof *xy);
    unsigned seed = 2026u;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const int64_t k = i + (int64_t)(n + 1) * j;
            seed = seed * 1103515245u + 12345u;
            const double jx = 0.3 * h * (((seed >> 8) & 0xFFFF) / 32768.0 - 1.0);
            seed = seed * 1103515245u + 12345u;
            const double jy = 0.3 * h * (((seed >> 8) & 0xFFFF) / 32768.0 - 1.0);
            xy[2 * k] = -half + i * h + (i > 0 && i < n ? jx : 0.0);
            xy[2 * k + 1] = -half + j * h + (j > 0 && j < n ? jy : 0.0);
        }
    int64_t *start = alloc((size_t)ncells + 1, sizeof *start), *nodes = alloc((size_t)(3 * ncells), sizeof *nodes);
    int64_t c = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int64_t a = i + (int64_t)(n + 1) * j, b = a + 1, cc = b + n + 1, d = a + n + 1;
            const int ac_short = hypot(xy[2 * cc] - xy[2 * a], xy[2 * cc + 1] - xy[2 * a + 1]) <=
                                 hypot(xy[2 * d] - xy[2 * b], xy[2 * d + 1] - xy[2 * b + 1]);
            const int64_t tri[2][3] = {{a, b, ac_short ? cc : d}, {ac_short ? a : b, cc, d}};
            for (int t = 0; t < 2; ++t, ++c) {
                start[c] = 3 * c;
                for (int v = 0; v < 3; ++v) nodes[3 * c + v] = tri[t][v];
            }
        }
    start[ncells] = 3 * ncells;

    /* The column by cell averages, the exact deposit at each centroid. */
    double *height = alloc((size_t)ncells, sizeof *height), *area = alloc((size_t)ncells, sizeof *area);
    double *exact = alloc((size_t)ncells, sizeof *exact);
    for (c = 0; c < ncells; ++c) {
        const double *p = xy + 2 * nodes[3 * c], *q = xy + 2 * nodes[3 * c + 1], *r = xy + 2 * nodes[3 * c + 2];
        area[c] = 0.5 * fabs((q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1]));
        height[c] = h0 * inside_unit_circle(p, q, r);
        const double radius = hypot((p[0] + q[0] + r[0]) / 3.0, (p[1] + q[1] + r[1]) / 3.0);
        exact[c] = fmin(h0, fmax(0.0, alpha * (foot - radius)));
    }

    dpsm_grid *g = NULL;
    CHECK(dpsm_create_mesh(nnodes, xy, ncells, start, nodes, &g));
    CHECK(dpsm_set_repose_angle(g, theta));
    CHECK(dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN));
    CHECK(dpsm_set_heights(g, height));
    double t = 0.0, at_rest = 0.0;
    while (at_rest == 0.0 && t < 100.0) {
        double integrated = 0.0;
        CHECK(dpsm_step(g, 0.5));
        CHECK(dpsm_get_step_info(g, DPSM_INFO_AT_REST, &at_rest));
        CHECK(dpsm_get_step_info(g, DPSM_INFO_TIME_INTEGRATED, &integrated));
        t += integrated;
    }
    CHECK(dpsm_get_heights(g, height));
    double difference = 0.0, top = 0.0;
    for (c = 0; c < ncells; ++c) {
        difference += fabs(height[c] - exact[c]) * area[c];
        top = fmax(top, height[c]);
    }
    double total, sourced, external, outflow;
    CHECK(dpsm_get_mass(g, DPSM_MASS_TOTAL, &total));
    CHECK(dpsm_get_mass(g, DPSM_MASS_SOURCED, &sourced));
    CHECK(dpsm_get_mass(g, DPSM_MASS_EXTERNAL, &external));
    CHECK(dpsm_get_mass(g, DPSM_MASS_OUTFLOW, &outflow));
    printf("column collapse on %lld jittered triangles, a = 0.5, theta = %.1f deg\n", (long long)ncells,
           theta * 180.0 / 3.14159265358979323846);
    printf("  %s at t = %.2f\n", at_rest > 0.0 ? "at rest" : "still moving", t);
    printf("  top %.4f (exact %.4f), L1 difference from the exact deposit %.3f %% of the volume\n", top, h0,
           100.0 * difference / (3.14159265358979323846 * h0));
    printf("  mass %.12g = external %.12g + sourced %.12g - outflow %.12g (off by %.1e)\n", total, external, sourced,
           outflow, fabs(total - (external + sourced - outflow)) / fabs(total));
    dpsm_destroy(g);
    free(xy), free(start), free(nodes), free(height), free(area), free(exact);
    return at_rest > 0.0 ? 0 : 1;
}
