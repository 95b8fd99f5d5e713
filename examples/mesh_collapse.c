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

#include "collapse_scene.h"

#define CHECK(call)                                                                     \
    do {                                                                                \
        int status_ = (call);                                                           \
        if (status_ != DPSM_OK) {                                                       \
            fprintf(stderr, "%s failed: %s: %s\n", #call, dpsm_status_string(status_), \
                    dpsm_last_error(g));                                                \
            exit(1);                                                                    \
        }                                                                               \
    } while (0)

int main(int argc, char **argv) {
    const int n = argc > 1 ? atoi(argv[1]) : 60;
    const double theta = (argc > 2 ? atof(argv[2]) : 30.0) * COLLAPSE_PI / 180.0;
    if (n < 4 || !(theta > 0.0 && theta < 1.5)) {
        fprintf(stderr, "usage: dpsm-mesh-collapse [n >= 4] [theta_degrees]\n");
        return 2;
    }
    collapse_scene scene = collapse_scene_make(n, theta);
    const int64_t ncells = scene.ncells;
    double *height = scene.height;

    dpsm_grid *g = NULL;
    CHECK(dpsm_create_mesh(scene.nnodes, scene.xy, ncells, scene.start, scene.nodes, &g));
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
    for (int64_t c = 0; c < ncells; ++c) {
        difference += fabs(height[c] - scene.exact[c]) * scene.area[c];
        top = fmax(top, height[c]);
    }
    double total, sourced, external, outflow;
    CHECK(dpsm_get_mass(g, DPSM_MASS_TOTAL, &total));
    CHECK(dpsm_get_mass(g, DPSM_MASS_SOURCED, &sourced));
    CHECK(dpsm_get_mass(g, DPSM_MASS_EXTERNAL, &external));
    CHECK(dpsm_get_mass(g, DPSM_MASS_OUTFLOW, &outflow));
    printf("column collapse on %lld jittered triangles, a = 0.5, theta = %.1f deg\n", (long long)ncells,
           theta * 180.0 / COLLAPSE_PI);
    printf("  %s at t = %.2f\n", at_rest > 0.0 ? "at rest" : "still moving", t);
    printf("  top %.4f (exact %.4f), L1 difference from the exact deposit %.3f %% of the volume\n", top, scene.h0,
           100.0 * difference / (COLLAPSE_PI * scene.h0));
    printf("  mass %.12g = external %.12g + sourced %.12g - outflow %.12g (off by %.1e)\n", total, external, sourced,
           outflow, fabs(total - (external + sourced - outflow)) / fabs(total));
    dpsm_destroy(g);
    collapse_scene_free(&scene);
    return at_rest > 0.0 ? 0 : 1;
}
