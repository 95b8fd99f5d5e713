/* dpsm-bench-mpi-mesh: a distributed triangle mesh partitioned by METIS, its
 * time per fully active sub-step, the share of it that communication takes,
 * and a rank's memory against a serial mesh of its owned cells. Run under
 * mpiexec (bench/run_mpi_scaling.sh); prints one CSV line on rank 0 (a log on
 * stderr). Never run by the tests.
 *
 *   mpiexec -n P dpsm-bench-mpi-mesh N [STEPS [LAYERS]]   2 N^2 triangles (N = 708: 1,002,528 cells)
 *
 * The scene is fully active (a plane steeper than the angle of repose with
 * ripples, the domain edge open), so every sub-step moves sand everywhere.
 * Each dpsm_step is 4 sub-steps; one OpenMP thread per rank. Times are the
 * slowest rank's (MPI_Wtime after a barrier), the best of 3 runs of STEPS
 * steps. Each line also gives every rank's owned cells stepped alone, as a
 * serial mesh, all ranks at once: the compute without communication under the
 * same sharing of the cores; the communication's share is what the
 * distributed part takes beyond that. Machine-independent counts go beside:
 * owned and ghost cells, neighbouring ranks, and the messages and bytes a
 * rank sent per sub-step (DPSM_INFO_MESSAGES_SENT, DPSM_INFO_BYTES_SENT).
 * LAYERS (default 2, the least dpsm needs) is the depth of each rank's ghost
 * layer in faces: a deeper one lets the ranks take several sub-steps per
 * exchange (DPSM_INFO_SUBSTEPS_PER_EXCHANGE, in the line) at the price of
 * stepping the ghosts near their parts too (the cell updates per sub-step).
 *
 *   mpiexec -n P dpsm-bench-mpi-mesh N STEPS corner|centre
 *
 * runs the local scene instead: a steep cone near a corner or at the centre
 * (where METIS's parts meet), the rest of the mesh flat and at rest, against
 * the fully active scene in the same run; it
 * prints per rank the cells visited and the messages sent per sub-step, and
 * how many ranks did neither (local_run).
 *
 *   mpiexec -n P dpsm-bench-mpi-mesh N STEPS graded
 *
 * grades the lattice (nodes drawn towards one corner: cells about 55 times
 * smaller across there than at the other), puts the cone on the coarse cells
 * and steps it STEPS calls of 4096 of the default's sub-steps each, with
 * local time steps (DPSM_RELAX_LOCAL_STEPS) and with the default's global
 * sub-step, on the same parts in the same run (graded_run): seconds, ticks
 * evaluated, cell updates and messages per call of each, and the L1
 * difference of the two deposits over the volume moved.
 */
#include <malloc.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <metis.h>
#include <mpi.h>

#include <dpsm/dpsm.h>
#include <dpsm/dpsm_mpi.h>

static int rank_, size_;

#define CHECK(g, call)                                                                                        \
    do {                                                                                                      \
        int status_ = (call);                                                                                 \
        if (status_ != DPSM_OK) {                                                                             \
            fprintf(stderr, "dpsm-bench-mpi-mesh (rank %d): %s failed: %s\n", rank_, #call, dpsm_last_error(g)); \
            MPI_Abort(MPI_COMM_WORLD, 1);                                                                     \
        }                                                                                                     \
    } while (0)

static void *xcalloc(size_t n, size_t size) {
    void *p = calloc(n ? n : 1, size);
    if (!p) {
        fprintf(stderr, "dpsm-bench-mpi-mesh: out of memory\n");
        MPI_Abort(MPI_COMM_WORLD, 2);
    }
    return p;
}

/* The bytes the allocator hands out now (glibc): a part's memory is the
 * difference before and after it is made and stepped once. */
static double heap_bytes(void) {
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
    struct mallinfo2 m = mallinfo2();
    return (double)m.uordblks + (double)m.hblkhd;
#else
    return 0.0;
#endif
}

typedef struct {
    int64_t n, nnodes, ncells;
    double *node_xy;
    int64_t *cell_nodes;  /* 3 per triangle */
    int64_t *adj_start, *adj;
} mesh_t;

/* 2 n^2 triangles over an n x n square lattice of unit spacing, with the
 * triangles' neighbours across edges (computed from the lattice). */
static mesh_t triangles(int64_t n) {
    mesh_t m = {n, (n + 1) * (n + 1), 2 * n * n, NULL, NULL, NULL, NULL};
    m.node_xy = xcalloc((size_t)(2 * m.nnodes), sizeof(double));
    for (int64_t j = 0; j <= n; ++j)
        for (int64_t i = 0; i <= n; ++i) {
            m.node_xy[2 * (i + (n + 1) * j)] = (double)i;
            m.node_xy[2 * (i + (n + 1) * j) + 1] = (double)j + 0.3 * (double)(i % 2);
        }
    m.cell_nodes = xcalloc((size_t)(3 * m.ncells), sizeof(int64_t));
    m.adj_start = xcalloc((size_t)m.ncells + 1, sizeof(int64_t));
    m.adj = xcalloc((size_t)(3 * m.ncells), sizeof(int64_t));
    /* square (i, j) holds lower triangle 2 s (a, b, e) and upper 2 s + 1 (a, e, d) */
    for (int64_t j = 0; j < n; ++j)
        for (int64_t i = 0; i < n; ++i) {
            const int64_t s = i + n * j, a = i + (n + 1) * j, b = a + 1, d = a + n + 1, e = d + 1;
            int64_t *lo = m.cell_nodes + 6 * s;
            lo[0] = a, lo[1] = b, lo[2] = e, lo[3] = a, lo[4] = e, lo[5] = d;
        }
    int64_t k = 0;
    for (int64_t c = 0; c < m.ncells; ++c) {
        const int64_t s = c / 2, i = s % n, j = s / n;
        m.adj_start[c] = k;
        if (c % 2 == 0) {  /* lower: upper of its square, the square below's upper, the square right's upper */
            m.adj[k++] = c + 1;
            if (j > 0) m.adj[k++] = 2 * (s - n) + 1;
            if (i + 1 < n) m.adj[k++] = 2 * (s + 1) + 1;
        } else {           /* upper: lower of its square, the square above's lower, the square left's lower */
            m.adj[k++] = c - 1;
            if (j + 1 < n) m.adj[k++] = 2 * (s + n);
            if (i > 0) m.adj[k++] = 2 * (s - 1);
        }
    }
    m.adj_start[m.ncells] = k;
    return m;
}

/* The scenes: fully active (a plane steeper than the angle of repose with
 * ripples, the domain edge open), or local (a steep cone of radius 30 at
 * (pile_x, pile_y), the rest flat and at rest). */
static int local_scene;
static double pile_x = 60.0, pile_y = 60.0;

static double height(const mesh_t *m, int64_t c) {
    double x = 0.0, y = 0.0;
    for (int k = 0; k < 3; ++k) x += m->node_xy[2 * m->cell_nodes[3 * c + k]], y += m->node_xy[2 * m->cell_nodes[3 * c + k] + 1];
    x /= 3.0, y /= 3.0;
    if (local_scene) return fmax(0.0, 3.0 * (30.0 - hypot(x - pile_x, y - pile_y)));
    return 1.2 * x + 0.3 * sin(0.7 * y) + 0.2 * sin(1.3 * x + 0.4 * y);
}

typedef struct {
    int64_t owned, ghosts, ncells;
    int64_t *global;
    int *owner;
} part_t;

/* The cells METIS gives this rank and `layers` layers of ghosts around them. */
static part_t part_of(const mesh_t *m, const int *owner, int layers) {
    part_t p = {0, 0, 0, NULL, NULL};
    int *depth = xcalloc((size_t)m->ncells, sizeof(int));
    for (int64_t c = 0; c < m->ncells; ++c) depth[c] = owner[c] == rank_ ? 0 : -1;
    for (int d = 1; d <= layers; ++d)
        for (int64_t c = 0; c < m->ncells; ++c)
            if (depth[c] == d - 1)
                for (int64_t k = m->adj_start[c]; k < m->adj_start[c + 1]; ++k)
                    if (depth[m->adj[k]] < 0) depth[m->adj[k]] = d;
    for (int64_t c = 0; c < m->ncells; ++c) p.ncells += depth[c] >= 0, p.owned += depth[c] == 0;
    p.ghosts = p.ncells - p.owned;
    p.global = xcalloc((size_t)p.ncells, sizeof(int64_t));
    p.owner = xcalloc((size_t)p.ncells, sizeof(int));
    int64_t k = 0;
    for (int64_t c = 0; c < m->ncells; ++c)
        if (depth[c] >= 0) p.global[k] = c, p.owner[k] = owner[c], ++k;
    free(depth);
    return p;
}

/* A mesh of the listed global cells (polygons over the nodes they use). */
static dpsm_grid *make_grid(const mesh_t *m, const part_t *p, int distributed, int owned_only) {
    const int64_t n = owned_only ? p->owned : p->ncells;
    int64_t *cells = xcalloc((size_t)n, sizeof(int64_t)), *ids = xcalloc((size_t)n, sizeof(int64_t));
    int *owner = xcalloc((size_t)n, sizeof(int));
    int64_t k = 0;
    for (int64_t j = 0; j < p->ncells; ++j)
        if (!owned_only || p->owner[j] == rank_) cells[k] = p->global[j], ids[k] = p->global[j], owner[k] = p->owner[j], ++k;
    int64_t *node_local = xcalloc((size_t)m->nnodes, sizeof(int64_t));
    for (int64_t v = 0; v < m->nnodes; ++v) node_local[v] = -1;
    int64_t nnodes = 0;
    int64_t *start = xcalloc((size_t)n + 1, sizeof(int64_t)), *nodes = xcalloc((size_t)(3 * n), sizeof(int64_t));
    double *xy = xcalloc((size_t)(6 * n), sizeof(double));
    for (int64_t c = 0; c < n; ++c) {
        start[c + 1] = 3 * (c + 1);
        for (int j = 0; j < 3; ++j) {
            const int64_t v = m->cell_nodes[3 * cells[c] + j];
            if (node_local[v] < 0) {
                node_local[v] = nnodes;
                xy[2 * nnodes] = m->node_xy[2 * v], xy[2 * nnodes + 1] = m->node_xy[2 * v + 1];
                ++nnodes;
            }
            nodes[3 * c + j] = node_local[v];
        }
    }
    dpsm_grid *g = NULL;
    if (distributed)
        CHECK(NULL, dpsm_create_mesh_mpi(MPI_COMM_WORLD, nnodes, xy, n, start, nodes, ids, owner, &g));
    else
        CHECK(NULL, dpsm_create_mesh(nnodes, xy, n, start, nodes, &g));
    double *h = xcalloc((size_t)n, sizeof(double));
    for (int64_t c = 0; c < n; ++c) h[c] = height(m, cells[c]);
    CHECK(g, dpsm_set_heights(g, h));
    CHECK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN));
    CHECK(g, dpsm_set_threads(g, 1));
    free(cells), free(ids), free(owner), free(node_local), free(start), free(nodes), free(xy), free(h);
    return g;
}

/* What this rank did per sub-step over the timed steps (dpsm_get_step_info). */
typedef struct {
    double cell_updates, messages, bytes, substeps_per_exchange;
} traffic_t;

/* The slowest rank's seconds per sub-step, best of 3 runs of `steps` steps;
 * `did`: this rank's figures per sub-step over all runs. */
static double time_substeps(dpsm_grid *g, int steps, double *substeps_per_step, double *moving, traffic_t *did) {
    double dt = 0.0;
    CHECK(g, dpsm_stable_dt(g, &dt));
    double best = INFINITY, all_substeps = 0.0;
    traffic_t sum = {0.0, 0.0, 0.0, 0.0};
    for (int run = 0; run < 3; ++run) {
        double substeps = 0.0;
        MPI_Barrier(MPI_COMM_WORLD);
        const double t0 = MPI_Wtime();
        for (int s = 0; s < steps; ++s) {
            CHECK(g, dpsm_step(g, 4.0 * dt));
            double k = 0.0, rest = 0.0, v = 0.0;
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &k));
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_AT_REST, &rest));
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_RANK_CELL_UPDATES, &v));
            sum.cell_updates += v;
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_MESSAGES_SENT, &v));
            sum.messages += v;
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_BYTES_SENT, &v));
            sum.bytes += v;
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS_PER_EXCHANGE, &sum.substeps_per_exchange));
            substeps += k;
            *moving = rest == 0.0;
        }
        double t = (MPI_Wtime() - t0) / substeps;
        MPI_Allreduce(MPI_IN_PLACE, &t, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
        if (t < best) best = t;
        *substeps_per_step = substeps / steps;
        all_substeps += substeps;
    }
    if (did) {
        did->cell_updates = sum.cell_updates / all_substeps;
        did->messages = sum.messages / all_substeps;
        did->bytes = sum.bytes / all_substeps;
        did->substeps_per_exchange = sum.substeps_per_exchange;
    }
    return best;
}

/* The local scene: a cone on the distributed mesh, against the same scene
 * with the active set off and the fully active scene, on the same parts in
 * the same run. One CSV line: the time per sub-step of each, and per rank
 * (largest and smallest) the cells visited, messages and bytes sent per
 * sub-step; idle ranks visited and sent nothing over all timed steps. */
static void local_run(const mesh_t *m, const part_t *p, int steps, const char *where) {
    double per_step = 0.0, moving = 0.0, dt = 0.0;
    local_scene = 0;
    dpsm_grid *g = make_grid(m, p, 1, 0);
    CHECK(g, dpsm_stable_dt(g, &dt));
    CHECK(g, dpsm_step(g, dt));
    const double active = time_substeps(g, 1, &per_step, &moving, NULL);
    dpsm_destroy(g);
    local_scene = 1;
    /* The same scene with the active set off (every sub-step visits every
     * owned cell, as distributed meshes did before): the same results. */
    setenv("DPSM_VISIT_ALL_CELLS", "1", 1);
    g = make_grid(m, p, 1, 0);
    CHECK(g, dpsm_step(g, dt));
    const double every_cell = time_substeps(g, steps, &per_step, &moving, NULL);
    dpsm_destroy(g);
    unsetenv("DPSM_VISIT_ALL_CELLS");
    g = make_grid(m, p, 1, 0);
    CHECK(g, dpsm_step(g, dt));  /* a new grid looks at every cell once */
    traffic_t did;
    const double local = time_substeps(g, steps, &per_step, &moving, &did);
    dpsm_destroy(g);
    double most[3] = {did.cell_updates, did.messages, did.bytes}, least[3] = {did.cell_updates, did.messages, did.bytes};
    MPI_Allreduce(MPI_IN_PLACE, most, 3, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    MPI_Allreduce(MPI_IN_PLACE, least, 3, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
    int idle = did.cell_updates == 0.0 && did.messages == 0.0, idle_ranks = 0;
    MPI_Allreduce(&idle, &idle_ranks, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
    if (rank_ == 0) {
        fprintf(stderr, "dpsm-bench-mpi-mesh, a pile at the %s: %d ranks, %lld cells, %.0f sub-steps a step, still moving: %s\n",
                where, size_, (long long)m->ncells, per_step, moving != 0.0 ? "yes" : "NO");
        printf("pile,ranks,cells,seconds_per_substep,every_cell_seconds_per_substep,active_seconds_per_substep,"
               "ratio_to_every_cell,idle_ranks,cell_updates_per_substep_max,cell_updates_per_substep_min,"
               "messages_per_substep_max,messages_per_substep_min,bytes_per_substep_max\n");
        printf("%s,%d,%lld,%.6e,%.6e,%.6e,%.4f,%d,%.0f,%.0f,%.2f,%.2f,%.0f\n", where, size_, (long long)m->ncells, local,
               every_cell, active, local / every_cell, idle_ranks, most[0], least[0], most[1], least[1], most[2]);
    }
}

/* The graded scene (see the header): local time steps against the global
 * sub-step, STEPS calls each; one CSV line. */
static void graded_run(const mesh_t *m, const part_t *p, int steps) {
    local_scene = 1;
    pile_x = pile_y = 0.8 * (double)m->n;
    double totals[2][4] = {{0}};  /* seconds, ticks evaluated, cell updates (all ranks), messages (this rank) */
    double *h[2] = {xcalloc((size_t)p->ncells, sizeof(double)), xcalloc((size_t)p->ncells, sizeof(double))};
    double *h0 = xcalloc((size_t)p->ncells, sizeof(double));
    double dt = 0.0;
    for (int local = 0; local < 2; ++local) {
        dpsm_grid *g = make_grid(m, p, 1, 0);
        if (local) CHECK(g, dpsm_set_relaxation(g, DPSM_RELAX_LOCAL_STEPS));
        CHECK(g, dpsm_get_heights(g, h0));
        CHECK(g, dpsm_stable_dt(g, &dt));
        CHECK(g, dpsm_set_max_substeps(g, 1 << 20));
        for (int s = 0; s < steps; ++s) {
            MPI_Barrier(MPI_COMM_WORLD);
            const double t0 = MPI_Wtime();
            CHECK(g, dpsm_step(g, 4096.0 * dt));
            double t = MPI_Wtime() - t0, v = 0.0;
            MPI_Allreduce(MPI_IN_PLACE, &t, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
            totals[local][0] += t;
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS_EVALUATED, &v));
            totals[local][1] += v;
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &v));
            totals[local][2] += v;
            CHECK(g, dpsm_get_step_info(g, DPSM_INFO_MESSAGES_SENT, &v));
            totals[local][3] += v;
        }
        CHECK(g, dpsm_get_heights(g, h[local]));
        dpsm_destroy(g);
    }
    /* Over the owned cells, areas from the nodes (the parts hold the same cells). */
    double sums[2] = {0.0, 0.0}, messages[2] = {totals[0][3], totals[1][3]};
    for (int64_t k = 0; k < p->ncells; ++k) {
        if (p->owner[k] != rank_) continue;
        const int64_t *v = m->cell_nodes + 3 * p->global[k];
        const double *a = m->node_xy + 2 * v[0], *b = m->node_xy + 2 * v[1], *c = m->node_xy + 2 * v[2];
        const double area = 0.5 * fabs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
        sums[0] += fabs(h[1][k] - h[0][k]) * area;
        sums[1] += 0.5 * fabs(h[0][k] - h0[k]) * area;
    }
    MPI_Allreduce(MPI_IN_PLACE, sums, 2, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    MPI_Allreduce(MPI_IN_PLACE, messages, 2, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    if (rank_ == 0) {
        fprintf(stderr, "dpsm-bench-mpi-mesh, a pile on the coarse cells of a graded mesh: %d ranks, %lld cells, %d calls "
                        "of 4096 global sub-steps\n", size_, (long long)m->ncells, steps);
        printf("scene,ranks,cells,calls,global_seconds_per_call,local_seconds_per_call,seconds_ratio,global_ticks_per_call,"
               "local_ticks_per_call,global_cell_updates_per_call,local_cell_updates_per_call,updates_ratio,"
               "global_messages_per_call_max_rank,local_messages_per_call_max_rank,l1_difference_over_moved\n");
        printf("graded,%d,%lld,%d,%.4e,%.4e,%.4f,%.0f,%.0f,%.4e,%.4e,%.5f,%.1f,%.1f,%.3e\n", size_, (long long)m->ncells, steps,
               totals[0][0] / steps, totals[1][0] / steps, totals[1][0] / totals[0][0], totals[0][1] / steps,
               totals[1][1] / steps, totals[0][2] / steps, totals[1][2] / steps, totals[1][2] / totals[0][2],
               messages[0] / steps, messages[1] / steps, sums[1] > 0.0 ? sums[0] / sums[1] : 0.0);
    }
    free(h[0]), free(h[1]), free(h0);
}

int main(int argc, char **argv) {
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    if (argc < 2) {
        if (rank_ == 0) fprintf(stderr, "usage: mpiexec -n P dpsm-bench-mpi-mesh N [STEPS [LAYERS|corner|centre|graded]]\n");
        MPI_Finalize();
        return 2;
    }
    const int64_t n = atoll(argv[1]);
    const int steps = argc > 2 ? atoi(argv[2]) : 5;
    mesh_t m = triangles(n);
    const int graded = argc > 3 && strcmp(argv[3], "graded") == 0;
    if (graded) {
        /* Nodes drawn towards (0, 0): spacing 4 / expm1(4) there, 4 e^4 / expm1(4) at the far corner. */
        for (int64_t k = 0; k < 2 * m.nnodes; ++k)
            m.node_xy[k] = (double)n * expm1(4.0 * m.node_xy[k] / (double)n) / expm1(4.0);
    }

    /* METIS on rank 0, the partition to every rank. */
    int *owner = xcalloc((size_t)m.ncells, sizeof(int));
    if (size_ > 1 && rank_ == 0) {
        idx_t nvtxs = (idx_t)m.ncells, ncon = 1, nparts = size_, objval = 0;
        idx_t *xadj = xcalloc((size_t)m.ncells + 1, sizeof(idx_t)), *adjncy = xcalloc((size_t)m.adj_start[m.ncells], sizeof(idx_t));
        idx_t *part = xcalloc((size_t)m.ncells, sizeof(idx_t));
        for (int64_t c = 0; c <= m.ncells; ++c) xadj[c] = (idx_t)m.adj_start[c];
        for (int64_t k = 0; k < m.adj_start[m.ncells]; ++k) adjncy[k] = (idx_t)m.adj[k];
        idx_t options[METIS_NOPTIONS];
        METIS_SetDefaultOptions(options);
        if (METIS_PartGraphKway(&nvtxs, &ncon, xadj, adjncy, NULL, NULL, NULL, &nparts, NULL, NULL, options, &objval,
                                part) != METIS_OK)
            MPI_Abort(MPI_COMM_WORLD, 3);
        for (int64_t c = 0; c < m.ncells; ++c) owner[c] = (int)part[c];
        free(xadj), free(adjncy), free(part);
    }
    MPI_Bcast(owner, (int)m.ncells, MPI_INT, 0, MPI_COMM_WORLD);
    const int local = argc > 3 && (strcmp(argv[3], "corner") == 0 || strcmp(argv[3], "centre") == 0);
    const int layers = argc > 3 && !local && !graded ? atoi(argv[3]) : graded ? 1 : 2;
    if (layers < 1) {
        if (rank_ == 0) fprintf(stderr, "dpsm-bench-mpi-mesh: LAYERS is %s, not a number of layers from 1\n", argv[3]);
        MPI_Finalize();
        return 2;
    }
    part_t p = part_of(&m, owner, layers);

    if (local || graded) {
        if (strcmp(argv[3], "centre") == 0) pile_x = pile_y = 0.5 * (double)n;
        if (graded)
            graded_run(&m, &p, steps);
        else
            local_run(&m, &p, steps, argv[3]);
        free(owner), free(p.global), free(p.owner);
        free(m.node_xy), free(m.cell_nodes), free(m.adj_start), free(m.adj);
        MPI_Finalize();
        return 0;
    }
    /* The ranks that own this rank's ghosts (and, layers being alike, hold its cells as ghosts). */
    int64_t neighbours = 0;
    {
        char *to = xcalloc((size_t)size_, 1);
        for (int64_t k = 0; k < p.ncells; ++k)
            if (p.owner[k] != rank_) to[p.owner[k]] = 1;
        for (int r = 0; r < size_; ++r) neighbours += to[r];
        free(to);
    }

    const double before = heap_bytes();
    dpsm_grid *g = make_grid(&m, &p, 1, 0);
    double dt = 0.0;
    CHECK(g, dpsm_stable_dt(g, &dt));
    CHECK(g, dpsm_step(g, dt));
    const double part_bytes = heap_bytes() - before;
    double per_step = 0.0, moving = 0.0, moving_alone = 0.0, per_step_alone = 0.0;
    traffic_t did;
    const double distributed = time_substeps(g, steps, &per_step, &moving, &did);
    dpsm_destroy(g);
    const double before_alone = heap_bytes();
    dpsm_grid *alone = make_grid(&m, &p, 0, 1);
    CHECK(alone, dpsm_stable_dt(alone, &dt));
    CHECK(alone, dpsm_step(alone, dt));
    const double alone_bytes = heap_bytes() - before_alone;
    const double compute = time_substeps(alone, steps, &per_step_alone, &moving_alone, NULL);
    dpsm_destroy(alone);

    /* The largest figures over the ranks (the slowest rank sets the pace). */
    double v[9] = {(double)p.owned, (double)p.ghosts, (double)neighbours, did.messages, did.bytes,
                   part_bytes / alone_bytes, moving, moving_alone, did.cell_updates};
    MPI_Allreduce(MPI_IN_PLACE, v, 9, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    double ratio_min = part_bytes / alone_bytes;
    MPI_Allreduce(MPI_IN_PLACE, &ratio_min, 1, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
    if (rank_ == 0) {
        fprintf(stderr, "dpsm-bench-mpi-mesh: %d ranks, %lld cells, %.0f sub-steps a step, still moving at the end: %s\n",
                size_, (long long)m.ncells, per_step, v[6] != 0.0 && v[7] != 0.0 ? "yes" : "NO (not fully active)");
        printf("ranks,cells,owned_max,ghosts_max,neighbours_max,messages_per_substep_max,bytes_per_substep_max,"
               "seconds_per_substep,alone_seconds_per_substep,communication_share,memory_ratio_min,memory_ratio_max,"
               "layers,substeps_per_exchange,cell_updates_per_substep_max\n");
        printf("%d,%lld,%.0f,%.0f,%.0f,%.3f,%.0f,%.6e,%.6e,%.3f,%.3f,%.3f,%d,%g,%.0f\n", size_, (long long)m.ncells,
               v[0], v[1], v[2], v[3], v[4], distributed, compute, 1.0 - compute / distributed, ratio_min, v[5],
               layers, did.substeps_per_exchange, v[8]);
    }
    free(owner), free(p.global), free(p.owner);
    free(m.node_xy), free(m.cell_nodes), free(m.adj_start), free(m.adj);
    MPI_Finalize();
    return 0;
}
