/* The sand column of mesh_collapse.c collapses on a triangle mesh
 * distributed over MPI ranks (docs/guide_mpi.md): a host's side of
 * dpsm_create_mesh_mpi().
 *
 * Every rank builds the whole mesh (a host reads its own); rank 0
 * partitions the triangles with METIS (their dual graph: triangles that
 * share an edge) and sends every rank the owners. Each rank then keeps what
 * a partitioned host holds: its own triangles and `layers` layers of ghosts
 * around them (2, the least dpsm needs on triangles; a deeper layer lets the
 * ranks take several sub-steps per exchange), ghosts first in this example's
 * local order, as polygons over its local nodes, with each cell's global id
 * and owner. It steps the collapse to rest and prints, on rank 0, what
 * dpsm-mesh-collapse prints for the same mesh (the same figures: a
 * distributed mesh equals the serial mesh numbered by global ids), then the
 * sub-steps per exchange and what each rank held and sent.
 *
 * usage: mpiexec -n P dpsm-mpi-mesh-collapse [n] [layers]      (defaults 60 2)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <metis.h>
#include <mpi.h>

#include <dpsm/dpsm.h>
#include <dpsm/dpsm_mpi.h>

#include "collapse_scene.h"

/* Every rank gets the same status from a collective call, so every rank stops alike. */
#define CHECK(call)                                                                                    \
    do {                                                                                               \
        int status_ = (call);                                                                          \
        if (status_ != DPSM_OK) {                                                                      \
            if (rank == 0)                                                                             \
                fprintf(stderr, "%s failed: %s: %s\n", #call, dpsm_status_string(status_),            \
                        dpsm_last_error(g));                                                           \
            MPI_Abort(MPI_COMM_WORLD, 1);                                                              \
        }                                                                                              \
    } while (0)

/* The owner of every triangle: METIS's k-way partition of the dual graph on
 * rank 0, broadcast. `xadj`, `adjncy`: the dual graph. */
static void partition(const collapse_scene *s, int ranks, const idx_t *xadj, const idx_t *adjncy, int *owner) {
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (rank == 0 && ranks > 1) {
        idx_t nvtxs = (idx_t)s->ncells, ncon = 1, nparts = ranks, cut = 0;
        idx_t *part = collapse_alloc((size_t)s->ncells, sizeof *part);
        idx_t options[METIS_NOPTIONS];
        METIS_SetDefaultOptions(options);
        if (METIS_PartGraphKway(&nvtxs, &ncon, (idx_t *)xadj, (idx_t *)adjncy, NULL, NULL, NULL, &nparts, NULL, NULL,
                                options, &cut, part) != METIS_OK) {
            fprintf(stderr, "METIS_PartGraphKway failed\n");
            MPI_Abort(MPI_COMM_WORLD, 1);
        }
        for (int64_t c = 0; c < s->ncells; ++c) owner[c] = (int)part[c];
        free(part);
    }
    MPI_Bcast(owner, (int)s->ncells, MPI_INT, 0, MPI_COMM_WORLD);
}

int main(int argc, char **argv) {
    MPI_Init(&argc, &argv);
    int rank = 0, ranks = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    dpsm_grid *g = NULL;
    const int n = argc > 1 ? atoi(argv[1]) : 60, layers = argc > 2 ? atoi(argv[2]) : 2;
    const double theta = 30.0 * COLLAPSE_PI / 180.0;
    if (n < 4 || layers < 1) {
        if (rank == 0) fprintf(stderr, "usage: mpiexec -n P dpsm-mpi-mesh-collapse [n >= 4] [layers >= 1]\n");
        MPI_Finalize();
        return 2;
    }
    collapse_scene scene = collapse_scene_make(n, theta);

    /* The dual graph (METIS numbers from 0), for the partition and the ghost layers. */
    idx_t ne = (idx_t)scene.ncells, nn = (idx_t)scene.nnodes, common = 2, numbering = 0;
    idx_t *eptr = collapse_alloc((size_t)scene.ncells + 1, sizeof *eptr);
    idx_t *eind = collapse_alloc((size_t)(3 * scene.ncells), sizeof *eind);
    for (int64_t c = 0; c <= scene.ncells; ++c) eptr[c] = (idx_t)scene.start[c];
    for (int64_t k = 0; k < 3 * scene.ncells; ++k) eind[k] = (idx_t)scene.nodes[k];
    idx_t *xadj = NULL, *adjncy = NULL;
    if (METIS_MeshToDual(&ne, &nn, eptr, eind, &common, &numbering, &xadj, &adjncy) != METIS_OK) {
        fprintf(stderr, "METIS_MeshToDual failed\n");
        MPI_Abort(MPI_COMM_WORLD, 1);
    }
    int *owner_of = collapse_alloc((size_t)scene.ncells, sizeof *owner_of);
    partition(&scene, ranks, xadj, adjncy, owner_of);

    /* This rank's part: each cell's distance in faces from an owned cell, up to `layers`. */
    int *depth = collapse_alloc((size_t)scene.ncells, sizeof *depth);
    for (int64_t c = 0; c < scene.ncells; ++c) depth[c] = owner_of[c] == rank ? 0 : -1;
    for (int d = 1; d <= layers; ++d)
        for (int64_t c = 0; c < scene.ncells; ++c)
            if (depth[c] == d - 1)
                for (idx_t k = xadj[c]; k < xadj[c + 1]; ++k)
                    if (depth[adjncy[k]] < 0) depth[adjncy[k]] = d;
    int64_t ncells = 0, owned = 0;
    for (int64_t c = 0; c < scene.ncells; ++c) ncells += depth[c] >= 0, owned += depth[c] == 0;
    int64_t *global_id = collapse_alloc((size_t)ncells, sizeof *global_id);
    int *owner = collapse_alloc((size_t)ncells, sizeof *owner);
    int64_t next = 0;
    for (int pass = 0; pass < 2; ++pass) /* the ghosts, then the owned cells */
        for (int64_t c = 0; c < scene.ncells; ++c)
            if (depth[c] >= 0 && (depth[c] == 0) == (pass == 1)) global_id[next] = c, owner[next] = owner_of[c], ++next;
    /* Its polygons over the nodes it uses, numbered locally. */
    int64_t *node_local = collapse_alloc((size_t)scene.nnodes, sizeof *node_local);
    for (int64_t v = 0; v < scene.nnodes; ++v) node_local[v] = -1;
    double *node_xy = collapse_alloc((size_t)(6 * ncells), sizeof *node_xy);
    int64_t *cell_start = collapse_alloc((size_t)ncells + 1, sizeof *cell_start);
    int64_t *cell_nodes = collapse_alloc((size_t)(3 * ncells), sizeof *cell_nodes);
    double *height = collapse_alloc((size_t)ncells, sizeof *height);
    int64_t nnodes = 0;
    for (int64_t k = 0; k < ncells; ++k) {
        const int64_t c = global_id[k];
        cell_start[k + 1] = 3 * (k + 1);
        for (int j = 0; j < 3; ++j) {
            const int64_t v = scene.nodes[3 * c + j];
            if (node_local[v] < 0) {
                node_local[v] = nnodes;
                node_xy[2 * nnodes] = scene.xy[2 * v], node_xy[2 * nnodes + 1] = scene.xy[2 * v + 1];
                ++nnodes;
            }
            cell_nodes[3 * k + j] = node_local[v];
        }
        height[k] = scene.height[c];
    }

    CHECK(dpsm_create_mesh_mpi(MPI_COMM_WORLD, nnodes, node_xy, ncells, cell_start, cell_nodes, global_id, owner, &g));
    CHECK(dpsm_set_repose_angle(g, theta));
    CHECK(dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN));
    CHECK(dpsm_set_heights(g, height)); /* the ghosts' values too: dpsm replaces them by their owners' */
    double t = 0.0, at_rest = 0.0, substeps = 0.0, messages = 0.0, bytes = 0.0, per_exchange = 0.0;
    while (at_rest == 0.0 && t < 100.0) {
        double integrated = 0.0, k = 0.0, sent = 0.0, sent_bytes = 0.0;
        CHECK(dpsm_step(g, 0.5));
        CHECK(dpsm_get_step_info(g, DPSM_INFO_AT_REST, &at_rest));
        CHECK(dpsm_get_step_info(g, DPSM_INFO_TIME_INTEGRATED, &integrated));
        CHECK(dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &k));
        CHECK(dpsm_get_step_info(g, DPSM_INFO_MESSAGES_SENT, &sent));
        CHECK(dpsm_get_step_info(g, DPSM_INFO_BYTES_SENT, &sent_bytes));
        CHECK(dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS_PER_EXCHANGE, &per_exchange));
        t += integrated, substeps += k, messages += sent, bytes += sent_bytes;
    }

    /* The L1 difference and the top over the owned cells of all ranks. */
    CHECK(dpsm_get_heights(g, height));
    double mine[2] = {0.0, 0.0}, all[2];
    for (int64_t k = 0; k < ncells; ++k)
        if (owner[k] == rank) {
            const int64_t c = global_id[k];
            mine[0] += fabs(height[k] - scene.exact[c]) * scene.area[c];
            mine[1] = fmax(mine[1], height[k]);
        }
    MPI_Reduce(&mine[0], &all[0], 1, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
    MPI_Reduce(&mine[1], &all[1], 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
    double total, sourced, external, outflow; /* global, the same on every rank */
    CHECK(dpsm_get_mass(g, DPSM_MASS_TOTAL, &total));
    CHECK(dpsm_get_mass(g, DPSM_MASS_SOURCED, &sourced));
    CHECK(dpsm_get_mass(g, DPSM_MASS_EXTERNAL, &external));
    CHECK(dpsm_get_mass(g, DPSM_MASS_OUTFLOW, &outflow));
    double held[4] = {(double)owned, (double)(ncells - owned), messages, bytes};
    double *every = rank == 0 ? collapse_alloc((size_t)(4 * ranks), sizeof *every) : NULL;
    MPI_Gather(held, 4, MPI_DOUBLE, every, 4, MPI_DOUBLE, 0, MPI_COMM_WORLD);
    if (rank == 0) {
        printf("column collapse on %lld jittered triangles, a = 0.5, theta = %.1f deg, over %d ranks (METIS), %d "
               "layers of ghosts\n", (long long)scene.ncells, theta * 180.0 / COLLAPSE_PI, ranks, layers);
        printf("  %s at t = %.2f\n", at_rest > 0.0 ? "at rest" : "still moving", t);
        printf("  top %.4f (exact %.4f), L1 difference from the exact deposit %.3f %% of the volume\n", all[1],
               scene.h0, 100.0 * all[0] / (COLLAPSE_PI * scene.h0));
        printf("  mass %.12g = external %.12g + sourced %.12g - outflow %.12g (off by %.1e)\n", total, external,
               sourced, outflow, fabs(total - (external + sourced - outflow)) / fabs(total));
        printf("  %.0f sub-steps, %g sub-steps per exchange\n", substeps, per_exchange);
        for (int r = 0; r < ranks; ++r)
            printf("  rank %d: %.0f cells owned, %.0f ghosts; sent %.0f messages (%.3f a sub-step), %.0f bytes\n", r,
                   every[4 * r], every[4 * r + 1], every[4 * r + 2], every[4 * r + 2] / substeps, every[4 * r + 3]);
    }
    dpsm_destroy(g);
    free(every), free(eptr), free(eind), free(owner_of), free(depth), free(global_id), free(owner);
    free(node_local), free(node_xy), free(cell_start), free(cell_nodes), free(height);
    METIS_Free(xadj), METIS_Free(adjncy);
    collapse_scene_free(&scene);
    MPI_Finalize();
    return at_rest > 0.0 ? 0 : 1;
}
