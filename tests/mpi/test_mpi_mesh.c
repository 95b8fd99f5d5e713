/* Distributed meshes (dpsm_create_mesh_mpi, dpsm_create_graph_mpi) against
 * serial meshes of the same scenes.
 *
 * Run under mpiexec with any number of ranks. The global mesh is a jittered
 * lattice of triangles (whose gradients read two rings of cells) or of quads
 * (one ring). Every rank owns the cells a partition gives it (METIS's, when
 * the test is built with METIS, a random one, and strips) and holds the cells
 * within two faces of them as ghosts (and, in a second run, within five or
 * seven faces: a deep layer, over which a rank takes several sub-steps per
 * exchange), in a shuffled local order, with deliberately wrong values in
 * the ghosts' slots of every array (edge faces included). Each rank
 * also runs the scene alone on a serial mesh of all cells and requires,
 * after every step:
 *   - its owned and ghost cells' heights equal the serial heights bit for bit;
 *   - the step information equals the serial figures;
 *   - the mass figures equal the serial ones to 1e-12 of the mass;
 *   - the faces of its owned cells carried what the serial faces did, bit for bit.
 *   - with a deep layer, several sub-steps per exchange and at most one
 *     message to each other rank per batch of sub-steps.
 * The same with local time steps (DPSM_RELAX_LOCAL_STEPS) on graded lattices.
 * Then a refusing rank and inconsistent partitions must fail on every rank
 * with a message naming the problem.
 */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mpi.h>

#include <dpsm/dpsm.h>
#include <dpsm/dpsm_mpi.h>

#ifdef DPSM_TEST_WITH_METIS
#include <metis.h>
#endif

#include "mpi_check.h"

static void *xcalloc(size_t n, size_t size) {
    void *p = calloc(n ? n : 1, size);
    if (!p) {
        fprintf(stderr, "out of memory\n");
        MPI_Abort(MPI_COMM_WORLD, 2);
    }
    return p;
}

/* ---- the global mesh ----------------------------------------------------- */

typedef struct {
    int64_t nnodes, ncells;
    double *node_xy;
    int64_t *cell_start, *cell_nodes;
    /* the dual graph: cells across each cell's edges */
    int64_t *adj_start, *adj;
    double size;  /* the domain is [0, size]^2 */
} mesh_t;

static uint64_t lcg_state;
static double uniform(void) {
    lcg_state = lcg_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(lcg_state >> 11) / 9007199254740992.0;
}

typedef struct {
    int64_t lo, hi, cell;
} edge_t;
static int edge_order(const void *a, const void *b) {
    const edge_t *x = a, *y = b;
    if (x->lo != y->lo) return x->lo < y->lo ? -1 : 1;
    if (x->hi != y->hi) return x->hi < y->hi ? -1 : 1;
    return x->cell < y->cell ? -1 : x->cell > y->cell;
}

/* n x n squares of a jittered lattice on [0, 1]^2, each split into two
 * triangles (triangles != 0) or kept whole. */
static mesh_t lattice(int n, int triangles) {
    mesh_t m = {0};
    m.size = 1.0;
    m.nnodes = (int64_t)(n + 1) * (n + 1);
    m.ncells = (int64_t)n * n * (triangles ? 2 : 1);
    m.node_xy = xcalloc((size_t)(2 * m.nnodes), sizeof(double));
    lcg_state = 12345;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const int inner = i > 0 && i < n && j > 0 && j < n;
            const double h = 1.0 / n;
            m.node_xy[2 * (i + (n + 1) * j)] = i * h + (inner ? (uniform() - 0.5) * 0.3 * h : 0.0);
            m.node_xy[2 * (i + (n + 1) * j) + 1] = j * h + (inner ? (uniform() - 0.5) * 0.3 * h : 0.0);
        }
    const int per = triangles ? 3 : 4;
    m.cell_start = xcalloc((size_t)m.ncells + 1, sizeof(int64_t));
    m.cell_nodes = xcalloc((size_t)(per * m.ncells), sizeof(int64_t));
    int64_t c = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int64_t a = i + (n + 1) * j, b = a + 1, d = a + (n + 1), e = d + 1;
            int64_t *v = m.cell_nodes + per * c;
            if (!triangles) {
                v[0] = a, v[1] = b, v[2] = e, v[3] = d;
                ++c;
            } else if ((i + j) % 2 == 0) {
                v[0] = a, v[1] = b, v[2] = e, v[3] = a, v[4] = e, v[5] = d;
                c += 2;
            } else {
                v[0] = a, v[1] = b, v[2] = d, v[3] = b, v[4] = e, v[5] = d;
                c += 2;
            }
        }
    for (int64_t k = 0; k <= m.ncells; ++k) m.cell_start[k] = per * k;
    /* The dual graph from shared edges. */
    edge_t *edges = xcalloc((size_t)(per * m.ncells), sizeof(edge_t));
    for (int64_t k = 0; k < m.ncells; ++k)
        for (int e = 0; e < per; ++e) {
            const int64_t u = m.cell_nodes[per * k + e], w = m.cell_nodes[per * k + (e + 1) % per];
            edges[per * k + e] = (edge_t){u < w ? u : w, u < w ? w : u, k};
        }
    qsort(edges, (size_t)(per * m.ncells), sizeof(edge_t), edge_order);
    int64_t *count = xcalloc((size_t)m.ncells + 1, sizeof(int64_t));
    for (int64_t k = 0; k + 1 < per * m.ncells; ++k)
        if (edges[k].lo == edges[k + 1].lo && edges[k].hi == edges[k + 1].hi)
            ++count[edges[k].cell + 1], ++count[edges[k + 1].cell + 1];
    m.adj_start = xcalloc((size_t)m.ncells + 1, sizeof(int64_t));
    for (int64_t k = 0; k < m.ncells; ++k) m.adj_start[k + 1] = m.adj_start[k] + count[k + 1];
    m.adj = xcalloc((size_t)m.adj_start[m.ncells], sizeof(int64_t));
    memset(count, 0, sizeof(int64_t) * (size_t)(m.ncells + 1));
    for (int64_t k = 0; k + 1 < per * m.ncells; ++k)
        if (edges[k].lo == edges[k + 1].lo && edges[k].hi == edges[k + 1].hi) {
            const int64_t x = edges[k].cell, y = edges[k + 1].cell;
            m.adj[m.adj_start[x] + count[x]++] = y;
            m.adj[m.adj_start[y] + count[y]++] = x;
        }
    free(edges);
    free(count);
    return m;
}

static void free_mesh(mesh_t *m) {
    free(m->node_xy), free(m->cell_start), free(m->cell_nodes), free(m->adj_start), free(m->adj);
}

/* The lattice with its nodes drawn towards x = 0 and y = 0: cells about 7
 * times smaller across at one corner than at the other, so that local time
 * steps (DPSM_RELAX_LOCAL_STEPS) step them in several classes. */
static mesh_t graded_lattice(int n, int triangles) {
    mesh_t m = lattice(n, triangles);
    const double a = 2.0;
    for (int64_t k = 0; k < 2 * m.nnodes; ++k) m.node_xy[k] = expm1(a * m.node_xy[k]) / expm1(a);
    return m;
}

static void centre(const mesh_t *m, int64_t c, double *x, double *y) {
    *x = *y = 0.0;
    const int64_t k0 = m->cell_start[c], k1 = m->cell_start[c + 1];
    for (int64_t k = k0; k < k1; ++k) *x += m->node_xy[2 * m->cell_nodes[k]], *y += m->node_xy[2 * m->cell_nodes[k] + 1];
    *x /= (double)(k1 - k0), *y /= (double)(k1 - k0);
}

/* A cell's centroid and area, as a finite-volume host computes them. */
static void centroid(const mesh_t *m, int64_t c, double *xy, double *area) {
    double twice = 0.0, mx = 0.0, my = 0.0;
    const int64_t k0 = m->cell_start[c], n = m->cell_start[c + 1] - k0;
    const double ox = m->node_xy[2 * m->cell_nodes[k0]], oy = m->node_xy[2 * m->cell_nodes[k0] + 1];
    for (int64_t j = 0; j < n; ++j) {
        const int64_t u = m->cell_nodes[k0 + j], w = m->cell_nodes[k0 + (j + 1) % n];
        const double px = m->node_xy[2 * u] - ox, py = m->node_xy[2 * u + 1] - oy;
        const double qx = m->node_xy[2 * w] - ox, qy = m->node_xy[2 * w + 1] - oy;
        const double cr = px * qy - py * qx;
        twice += cr, mx += cr * (px + qx) / 3.0, my += cr * (py + qy) / 3.0;
    }
    xy[0] = ox + mx / twice, xy[1] = oy + my / twice, *area = 0.5 * fabs(twice);
}

/* ---- partitions ---------------------------------------------------------- */

enum { PART_METIS, PART_RANDOM, PART_STRIPS, N_PARTITIONS };
static const char *const partition_names[] = {"METIS", "random", "strips"};

/* The owner of every cell; 0 when the partition is not available here. */
static int partition(const mesh_t *m, int kind, int *owner) {
    if (size_ == 1) {
        for (int64_t c = 0; c < m->ncells; ++c) owner[c] = 0;
        return 1;
    }
    switch (kind) {
        case PART_METIS: {
#ifdef DPSM_TEST_WITH_METIS
            idx_t nvtxs = (idx_t)m->ncells, ncon = 1, nparts = size_, objval = 0;
            idx_t *xadj = xcalloc((size_t)m->ncells + 1, sizeof(idx_t));
            idx_t *adjncy = xcalloc((size_t)m->adj_start[m->ncells], sizeof(idx_t));
            idx_t *part = xcalloc((size_t)m->ncells, sizeof(idx_t));
            for (int64_t c = 0; c <= m->ncells; ++c) xadj[c] = (idx_t)m->adj_start[c];
            for (int64_t k = 0; k < m->adj_start[m->ncells]; ++k) adjncy[k] = (idx_t)m->adj[k];
            idx_t options[METIS_NOPTIONS];
            METIS_SetDefaultOptions(options);
            options[METIS_OPTION_SEED] = 7;  /* the same partition on every rank */
            const int status = METIS_PartGraphKway(&nvtxs, &ncon, xadj, adjncy, NULL, NULL, NULL, &nparts, NULL, NULL,
                                                   options, &objval, part);
            require(status == METIS_OK, "METIS_PartGraphKway returned %d", status);
            for (int64_t c = 0; c < m->ncells; ++c) owner[c] = (int)part[c];
            free(xadj), free(adjncy), free(part);
            return 1;
#else
            return 0;
#endif
        }
        case PART_RANDOM:
            lcg_state = 99;
            for (int64_t c = 0; c < m->ncells; ++c) owner[c] = c < size_ ? (int)c : (int)(uniform() * size_) % size_;
            return 1;
        default:
            for (int64_t c = 0; c < m->ncells; ++c) {
                double x, y;
                centre(m, c, &x, &y);
                owner[c] = (int)(x / m->size * size_) % size_;
            }
            return 1;
    }
}

/* ---- a rank's part, as a host would hold it ------------------------------- */

typedef struct {
    int64_t ncells, nnodes;
    int64_t *global;     /* local cell -> global cell */
    int64_t *local;      /* global cell -> local cell, or -1 */
    int64_t *node_global;
    int64_t *global_id;  /* per local cell, as passed */
    int *owner;
    double *node_xy;
    int64_t *cell_start, *cell_nodes;
} part_t;

/* The cells `owner` gives this rank and the cells within `layers` faces of
 * them, in a shuffled order; their nodes, numbered as they are first met. */
static part_t part_of(const mesh_t *m, const int *owner, int layers) {
    part_t p = {0};
    p.local = xcalloc((size_t)m->ncells, sizeof(int64_t));
    int *depth = xcalloc((size_t)m->ncells, sizeof(int));
    for (int64_t c = 0; c < m->ncells; ++c) depth[c] = owner[c] == rank_ ? 0 : -1;
    for (int d = 1; d <= layers; ++d)
        for (int64_t c = 0; c < m->ncells; ++c)
            if (depth[c] == d - 1)
                for (int64_t k = m->adj_start[c]; k < m->adj_start[c + 1]; ++k)
                    if (depth[m->adj[k]] < 0) depth[m->adj[k]] = d;
    p.global = xcalloc((size_t)m->ncells, sizeof(int64_t));
    for (int64_t c = 0; c < m->ncells; ++c)
        if (depth[c] >= 0) p.global[p.ncells++] = c;
    lcg_state = 777 + (uint64_t)rank_;
    for (int64_t k = p.ncells - 1; k > 0; --k) {
        const int64_t j = (int64_t)(uniform() * (double)(k + 1)) % (k + 1);
        const int64_t t = p.global[k];
        p.global[k] = p.global[j], p.global[j] = t;
    }
    for (int64_t c = 0; c < m->ncells; ++c) p.local[c] = -1;
    for (int64_t k = 0; k < p.ncells; ++k) p.local[p.global[k]] = k;
    p.global_id = xcalloc((size_t)p.ncells, sizeof(int64_t));
    p.owner = xcalloc((size_t)p.ncells, sizeof(int));
    for (int64_t k = 0; k < p.ncells; ++k) p.global_id[k] = p.global[k], p.owner[k] = owner[p.global[k]];
    int64_t *node_local = xcalloc((size_t)m->nnodes, sizeof(int64_t));
    for (int64_t n = 0; n < m->nnodes; ++n) node_local[n] = -1;
    p.node_global = xcalloc((size_t)m->nnodes, sizeof(int64_t));
    p.cell_start = xcalloc((size_t)p.ncells + 1, sizeof(int64_t));
    p.cell_nodes = xcalloc((size_t)m->cell_start[m->ncells], sizeof(int64_t));
    for (int64_t k = 0; k < p.ncells; ++k) {
        const int64_t c = p.global[k];
        p.cell_start[k + 1] = p.cell_start[k] + (m->cell_start[c + 1] - m->cell_start[c]);
        for (int64_t j = m->cell_start[c]; j < m->cell_start[c + 1]; ++j) {
            const int64_t n = m->cell_nodes[j];
            if (node_local[n] < 0) node_local[n] = p.nnodes, p.node_global[p.nnodes++] = n;
            p.cell_nodes[p.cell_start[k] + (j - m->cell_start[c])] = node_local[n];
        }
    }
    p.node_xy = xcalloc((size_t)(2 * p.nnodes), sizeof(double));
    for (int64_t n = 0; n < p.nnodes; ++n)
        p.node_xy[2 * n] = m->node_xy[2 * p.node_global[n]], p.node_xy[2 * n + 1] = m->node_xy[2 * p.node_global[n] + 1];
    free(node_local);
    free(depth);
    return p;
}

static void free_part(part_t *p) {
    free(p->global), free(p->local), free(p->node_global), free(p->global_id), free(p->owner), free(p->node_xy);
    free(p->cell_start), free(p->cell_nodes);
}

/* The node pair of every face as the library lists them for polygons: as
 * faces first appear, cell by cell, edge by edge; global node numbers. */
static int64_t *face_nodes(int64_t ncells, const int64_t *cell_start, const int64_t *cell_nodes,
                           const int64_t *node_global, int64_t nfaces) {
    const int64_t total = cell_start[ncells];
    edge_t *edges = xcalloc((size_t)total, sizeof(edge_t));  /* .cell holds the edge's place k */
    for (int64_t c = 0; c < ncells; ++c)
        for (int64_t k = cell_start[c]; k < cell_start[c + 1]; ++k) {
            const int64_t next = k + 1 < cell_start[c + 1] ? k + 1 : cell_start[c];
            const int64_t u = node_global[cell_nodes[k]], w = node_global[cell_nodes[next]];
            edges[k] = (edge_t){u < w ? u : w, u < w ? w : u, k};
        }
    char *first = xcalloc((size_t)total, 1);
    int64_t *lo = xcalloc((size_t)total, sizeof(int64_t)), *hi = xcalloc((size_t)total, sizeof(int64_t));
    for (int64_t k = 0; k < total; ++k) lo[edges[k].cell] = edges[k].lo, hi[edges[k].cell] = edges[k].hi;
    qsort(edges, (size_t)total, sizeof(edge_t), edge_order);
    for (int64_t k = 0; k < total; ++k)
        if (k == 0 || edges[k].lo != edges[k - 1].lo || edges[k].hi != edges[k - 1].hi) first[edges[k].cell] = 1;
    int64_t *out = xcalloc((size_t)(2 * nfaces), sizeof(int64_t));
    int64_t f = 0;
    for (int64_t k = 0; k < total; ++k)
        if (first[k]) {
            if (f < nfaces) out[2 * f] = lo[k], out[2 * f + 1] = hi[k];
            ++f;
        }
    require(f == nfaces, "face_nodes found %lld faces, the library %lld", (long long)f, (long long)nfaces);
    free(edges), free(first), free(lo), free(hi);
    return out;
}

/* ---- scenes -------------------------------------------------------------- */

enum { SCENE_COLLAPSE, SCENE_SOURCES, SCENE_PHYSICS, SCENE_TO_REST, N_SCENES };
static const char *const scene_names[] = {"column collapse, open edge", "sources, walls, open cells, edge kinds, flux exponent",
                                          "bed, erosion, angle field, static angle, edge levels",
                                          "relaxation to rest"};

/* The scenes stepped with local time steps. */
static int local_steps_;

static double column(const mesh_t *m, int64_t c) {
    double x, y;
    centre(m, c, &x, &y);
    return hypot(x - 0.5, y - 0.5) < 0.22 ? 0.35 : 0.02;
}

/* A value per global cell of the scene (what: 0 heights, 1 kinds, 2 source, 3 bed, 4 angle). */
static double scene_value(const mesh_t *m, int scene, int what, int64_t c) {
    double x, y;
    centre(m, c, &x, &y);
    switch (what) {
        case 0: return scene == SCENE_PHYSICS ? 0.1 + column(m, c) : column(m, c);
        case 1:
            if (scene != SCENE_SOURCES) return DPSM_CELL_SAND;
            if (fabs(x - 0.3) < 0.03 && y > 0.2 && y < 0.7) return DPSM_CELL_WALL;
            if (hypot(x - 0.85, y - 0.2) < 0.06) return DPSM_CELL_OPEN;
            return DPSM_CELL_SAND;
        case 2:
            if (scene == SCENE_SOURCES) return hypot(x - 0.7, y - 0.7) < 0.1 ? 0.4 : 0.0;
            if (scene == SCENE_PHYSICS) return x < 0.25 ? -0.3 : (hypot(x - 0.6, y - 0.3) < 0.1 ? 0.5 : 0.0);
            return 0.0;
        case 3: return 0.05 + 0.05 * x;
        default: return (28.0 + 6.0 * y) * M_PI / 180.0;
    }
}

typedef struct {
    dpsm_grid *g;
    int64_t ncells, nfaces;
    const int64_t *global;  /* local -> global cell; NULL: the serial mesh */
    const int *owner;
    int64_t *face_nodes;    /* per face, its global node pair */
    const int64_t *face_cells;  /* per face, its two local cells (a part's only) */
} run_t;

/* Sets the scene on a grid; ghost slots get wrong but valid values. */
static void set_scene(const mesh_t *m, int scene, run_t *r) {
    double *v = xcalloc((size_t)r->ncells, sizeof(double));
    uint8_t *kinds = xcalloc((size_t)r->ncells, 1);
    const int serial = r->global == NULL;
#define FILL(what, wrong)                                                                  \
    for (int64_t k = 0; k < r->ncells; ++k) {                                              \
        const int64_t c = serial ? k : r->global[k];                                       \
        const int ghost = !serial && r->owner[k] != rank_;                                 \
        v[k] = ghost ? (wrong) : scene_value(m, scene, what, c);                           \
    }
    OK(r->g, dpsm_set_repose_angle(r->g, 30.0 * M_PI / 180.0));
    OK(r->g, dpsm_set_face_flux_recording(r->g, 1));
    if (scene == SCENE_PHYSICS) {
        FILL(3, 0.5)
        OK(r->g, dpsm_set_bedrock(r->g, v));
        FILL(4, 0.2)
        OK(r->g, dpsm_set_repose_angle_field(r->g, v));
        OK(r->g, dpsm_set_static_angle(r->g, 36.0 * M_PI / 180.0));
    }
    FILL(1, DPSM_CELL_WALL)
    for (int64_t k = 0; k < r->ncells; ++k) kinds[k] = (uint8_t)v[k];
    OK(r->g, dpsm_set_cell_kinds(r->g, kinds));
    FILL(0, 7.0)
    OK(r->g, dpsm_set_heights(r->g, v));
    FILL(2, 1.0)
    OK(r->g, dpsm_set_source(r->g, scene == SCENE_SOURCES || scene == SCENE_PHYSICS ? v : NULL));
#undef FILL
    if (scene == SCENE_COLLAPSE || scene == SCENE_TO_REST) OK(r->g, dpsm_set_boundary(r->g, DPSM_MESH_EDGE, DPSM_OPEN));
    if (scene == SCENE_SOURCES) OK(r->g, dpsm_set_flux_exponent(r->g, 1.5));
    if (scene == SCENE_SOURCES || scene == SCENE_PHYSICS) {
        /* per face: open on the left half of the domain edge, levels by x */
        uint8_t *edge = xcalloc((size_t)r->nfaces, 1);
        double *levels = xcalloc((size_t)r->nfaces, sizeof(double));
        for (int64_t f = 0; f < r->nfaces; ++f) {
            const double x = 0.5 * (m->node_xy[2 * r->face_nodes[2 * f]] + m->node_xy[2 * r->face_nodes[2 * f + 1]]);
            /* a ghost's edge face: its owner's kind and level count, not these */
            const int ghost = !serial && r->owner[r->face_cells[2 * f]] != rank_;
            edge[f] = (x < 0.5) != ghost ? DPSM_OPEN : DPSM_WALL;
            levels[f] = ghost ? 0.5 : scene == SCENE_PHYSICS ? 0.08 + 0.02 * x : 0.0;
        }
        OK(r->g, dpsm_set_edge_kinds(r->g, edge));
        OK(r->g, dpsm_set_side_levels(r->g, DPSM_MESH_EDGE, levels));
        free(edge), free(levels);
    }
    if (scene == SCENE_TO_REST) OK(r->g, dpsm_set_relaxation(r->g, DPSM_RELAX_TO_REST));
    if (local_steps_) OK(r->g, dpsm_set_relaxation(r->g, DPSM_RELAX_LOCAL_STEPS));
    free(v), free(kinds);
}

/* The faces' fluxes keyed by global node pairs, compared with the serial ones. */
static void compare_faces(const run_t *serial, const run_t *part, const int64_t *serial_cells, const int64_t *part_cells,
                          const char *where) {
    double *fs = xcalloc((size_t)serial->nfaces, sizeof(double)), *fp = xcalloc((size_t)part->nfaces, sizeof(double));
    OK(serial->g, dpsm_get_face_fluxes(serial->g, fs, NULL));
    OK(part->g, dpsm_get_face_fluxes(part->g, fp, NULL));
    long compared = 0;
    for (int64_t f = 0; f < part->nfaces; ++f) {
        const int64_t a = part_cells[2 * f], b = part_cells[2 * f + 1];
        if (part->owner[a] != rank_ && (b < 0 || part->owner[b] != rank_)) continue;  /* not a face of an owned cell */
        const int64_t ga = part->global[a], gb = b < 0 ? -1 : part->global[b];
        int64_t match = -1;
        for (int64_t s = 0; s < serial->nfaces && match < 0; ++s)
            if (serial->face_nodes[2 * s] == part->face_nodes[2 * f] &&
                serial->face_nodes[2 * s + 1] == part->face_nodes[2 * f + 1])
                match = s;
        if (match < 0) {
            require(0, "%s: face %lld of the part has no serial face", where, (long long)f);
            continue;
        }
        const double want = serial_cells[2 * match] == ga ? fs[match] : -fs[match];
        (void)gb;
        require(fp[f] == want, "%s: face %lld (global cells %lld, %lld) carried %.17g, the serial face %.17g", where,
                (long long)f, (long long)ga, (long long)gb, fp[f], want);
        ++compared;
    }
    require(compared > 0, "%s: no face compared", where);
    free(fs), free(fp);
}

/* The sub-steps between two exchanges of the last run_scene (the same on every rank). */
static double per_exchange_;
/* DPSM_MPI_SUBSTEPS_PER_EXCHANGE as set for the parts made (-1: not set). */
static int substeps_limit_ = -1;

/* Ghost layers that let a part take several sub-steps per exchange: a
 * sub-step reads 4 faces out (docs/guide_mpi.md). */
static const int kDeepLayers = 9;

/* A part with one or two layers of ghosts exchanges in every sub-step; with a deep
 * layer, several sub-steps per exchange: after the first step (where the
 * host's settings travel too) a rank sends at most one message to each other
 * rank per batch of sub-steps, the last batch possibly short, and one more
 * where the step ends at rest (relaxation: a last sub-step finds no sand
 * moving). */
static void check_exchanges(const dpsm_grid *part, int layers, int step, const char *at) {
    double per_exchange = -1.0, substeps = 0.0, messages = 0.0;
    OK(part, dpsm_get_step_info(part, DPSM_INFO_SUBSTEPS_PER_EXCHANGE, &per_exchange));
    OK(part, dpsm_get_step_info(part, DPSM_INFO_SUBSTEPS, &substeps));
    OK(part, dpsm_get_step_info(part, DPSM_INFO_MESSAGES_SENT, &messages));
    per_exchange_ = per_exchange;
    if (local_steps_) {
        require(per_exchange == 0.5, "%s: local time steps exchange every %g sub-steps, not in every tick", at,
                per_exchange);
        return;
    }
    if (substeps_limit_ >= 0) {
        const double want = substeps_limit_ == 0 ? 0.5 : substeps_limit_;
        require(per_exchange == want, "%s: DPSM_MPI_SUBSTEPS_PER_EXCHANGE=%d gave %g sub-steps per exchange", at,
                substeps_limit_, per_exchange);
        return;
    }
    if (size_ == 1) {
        require(per_exchange >= 1.0, "%s: one rank exchanges nothing, yet every %g sub-steps", at, per_exchange);
        return;
    }
    if (layers <= 2) {
        require(per_exchange <= 1.0, "%s: two layers of ghosts give %g sub-steps per exchange", at, per_exchange);
        return;
    }
    require(per_exchange >= 2.0, "%s: %d layers of ghosts give %g sub-steps per exchange, not several", at, layers,
            per_exchange);
    const double batches = ceil((substeps + 1.0) / fmax(per_exchange, 1.0));
    require(step == 0 || messages <= (size_ - 1) * batches,
            "%s: %g messages for %g sub-steps at %g per exchange to %d other ranks", at, messages, substeps,
            per_exchange, size_ - 1);
}

static void run_scene(const mesh_t *m, int scene, int kind, int graph, int layers) {
    int *owner = xcalloc((size_t)m->ncells, sizeof(int));
    if (!partition(m, kind, owner)) {
        free(owner);
        return;
    }
    part_t p = part_of(m, owner, layers);
    char where[256];
    snprintf(where, sizeof where, "%s, %s partition, %s, %d layers of ghosts", scene_names[scene],
             partition_names[kind], graph ? "graph" : "polygons", layers);
    run_t serial = {0}, part = {0};
    OK(NULL, dpsm_create_mesh(m->nnodes, m->node_xy, m->ncells, m->cell_start, m->cell_nodes, &serial.g));
    serial.ncells = m->ncells;
    OK(serial.g, dpsm_get_face_count(serial.g, &serial.nfaces));
    int64_t *all_nodes = xcalloc((size_t)m->nnodes, sizeof(int64_t));
    for (int64_t n = 0; n < m->nnodes; ++n) all_nodes[n] = n;
    serial.face_nodes = face_nodes(m->ncells, m->cell_start, m->cell_nodes, all_nodes, serial.nfaces);
    int64_t *serial_cells = xcalloc((size_t)(2 * serial.nfaces), sizeof(int64_t));
    OK(serial.g, dpsm_get_mesh_faces(serial.g, serial_cells));

    int status;
    if (!graph) {
        status = dpsm_create_mesh_mpi(MPI_COMM_WORLD, p.nnodes, p.node_xy, p.ncells, p.cell_start, p.cell_nodes,
                                      p.global_id, p.owner, &part.g);
    } else {
        /* The graph the serial mesh found, restricted to this rank: its faces
         * with a local cell on both sides (or the domain edge), from the
         * serial mesh's geometry as a host's finite-volume code holds it. */
        double *cell_xy = xcalloc((size_t)(2 * p.ncells), sizeof(double)), *area = xcalloc((size_t)p.ncells, sizeof(double));
        for (int64_t k = 0; k < p.ncells; ++k) centroid(m, p.global[k], &cell_xy[2 * k], &area[k]);
        int64_t nfaces = 0;
        int64_t *fc = xcalloc((size_t)(2 * serial.nfaces), sizeof(int64_t));
        double *fxy = xcalloc((size_t)(2 * serial.nfaces), sizeof(double)), *flen = xcalloc((size_t)serial.nfaces, sizeof(double));
        for (int64_t s = 0; s < serial.nfaces; ++s) {
            const int64_t a = serial_cells[2 * s], b = serial_cells[2 * s + 1];
            const int64_t la = p.local[a], lb = b < 0 ? -1 : p.local[b];
            if (la < 0 || (b >= 0 && lb < 0)) continue;
            if (b < 0 && owner[a] != rank_ && layers <= 2) continue;  /* a ghost's edge faces need not be given */
            const int64_t u = serial.face_nodes[2 * s], w = serial.face_nodes[2 * s + 1];
            fc[2 * nfaces] = la, fc[2 * nfaces + 1] = lb;
            fxy[2 * nfaces] = 0.5 * (m->node_xy[2 * u] + m->node_xy[2 * w]);
            fxy[2 * nfaces + 1] = 0.5 * (m->node_xy[2 * u + 1] + m->node_xy[2 * w + 1]);
            flen[nfaces] = hypot(m->node_xy[2 * w] - m->node_xy[2 * u], m->node_xy[2 * w + 1] - m->node_xy[2 * u + 1]);
            ++nfaces;
        }
        status = dpsm_create_graph_mpi(MPI_COMM_WORLD, p.ncells, p.global_id, p.owner, cell_xy, area, nfaces, fc, fxy,
                                       flen, &part.g);
        free(cell_xy), free(area), free(fc), free(fxy), free(flen);
        /* The serial reference of a graph is the serial graph of the same cells. */
        dpsm_destroy(serial.g);
        serial.g = NULL;
        {
            double *gxy = xcalloc((size_t)(2 * m->ncells), sizeof(double)), *garea = xcalloc((size_t)m->ncells, sizeof(double));
            double *sfxy = xcalloc((size_t)(2 * serial.nfaces), sizeof(double)), *sflen = xcalloc((size_t)serial.nfaces, sizeof(double));
            for (int64_t c = 0; c < m->ncells; ++c) centroid(m, c, &gxy[2 * c], &garea[c]);
            for (int64_t s = 0; s < serial.nfaces; ++s) {
                const int64_t u = serial.face_nodes[2 * s], w = serial.face_nodes[2 * s + 1];
                sfxy[2 * s] = 0.5 * (m->node_xy[2 * u] + m->node_xy[2 * w]);
                sfxy[2 * s + 1] = 0.5 * (m->node_xy[2 * u + 1] + m->node_xy[2 * w + 1]);
                sflen[s] = hypot(m->node_xy[2 * w] - m->node_xy[2 * u], m->node_xy[2 * w + 1] - m->node_xy[2 * u + 1]);
            }
            OK(NULL, dpsm_create_graph(m->ncells, gxy, garea, serial.nfaces, serial_cells, sfxy, sflen, &serial.g));
            free(gxy), free(garea), free(sfxy), free(sflen);
        }
    }
    require(status == DPSM_OK, "%s: creating the part returned %s: %s", where, dpsm_status_string(status),
            dpsm_last_error(NULL));
    if (status != DPSM_OK || !serial.g) goto done;
    part.ncells = p.ncells;
    part.global = p.global;
    part.owner = p.owner;
    OK(part.g, dpsm_get_face_count(part.g, &part.nfaces));
    int64_t *part_cells = xcalloc((size_t)(2 * part.nfaces), sizeof(int64_t));
    OK(part.g, dpsm_get_mesh_faces(part.g, part_cells));
    if (!graph) {
        part.face_nodes = face_nodes(p.ncells, p.cell_start, p.cell_nodes, p.node_global, part.nfaces);
    } else {
        /* a graph's faces: find each one's node pair from the serial face of its cells */
        part.face_nodes = xcalloc((size_t)(2 * part.nfaces), sizeof(int64_t));
        int64_t next = 0;
        for (int64_t s = 0; s < serial.nfaces; ++s) {
            const int64_t a = serial_cells[2 * s], b = serial_cells[2 * s + 1];
            const int64_t la = p.local[a], lb = b < 0 ? -1 : p.local[b];
            if (la < 0 || (b >= 0 && lb < 0) || (b < 0 && owner[a] != rank_ && layers <= 2)) continue;
            part.face_nodes[2 * next] = serial.face_nodes[2 * s], part.face_nodes[2 * next + 1] = serial.face_nodes[2 * s + 1];
            ++next;
        }
    }
    part.face_cells = part_cells;
    set_scene(m, scene, &serial);
    set_scene(m, scene, &part);
    double *hs = xcalloc((size_t)m->ncells, sizeof(double)), *hp = xcalloc((size_t)p.ncells, sizeof(double));
    const double dts[] = {0.02, 0.05, 0.05, 0.1, 0.003};
    /* Saved after the second step, read back, and the two then stepped alike. */
    dpsm_grid *loaded = NULL;
    char path[64];
    snprintf(path, sizeof path, "test_mpi_mesh.%d.dpsm", rank_);
    for (int step = 0; step < 5; ++step) {
        char at[300];
        snprintf(at, sizeof at, "%s, step %d", where, step + 1);
        if (step == 2 && kind != PART_RANDOM) {
            OK(part.g, dpsm_save(part.g, path));
            OK(NULL, dpsm_load_mpi(MPI_COMM_WORLD, path, &loaded));
            remove(path);
        }
        OK(serial.g, dpsm_step(serial.g, dts[step]));
        OK(part.g, dpsm_step(part.g, dts[step]));
        if (loaded) {
            double *hl = xcalloc((size_t)p.ncells, sizeof(double));
            OK(loaded, dpsm_step(loaded, dts[step]));
            OK(loaded, dpsm_get_heights(loaded, hl));
            long differ = 0;
            OK(serial.g, dpsm_get_heights(serial.g, hs));
            for (int64_t k = 0; k < p.ncells; ++k) differ += memcmp(&hl[k], &hs[p.global[k]], sizeof(double)) != 0;
            require(differ == 0, "%s: the part read back from its restart file: %ld cells differ from the serial mesh",
                    at, differ);
            double a = 0.0, b = 0.0;
            OK(part.g, dpsm_get_mass(part.g, DPSM_MASS_OUTFLOW, &a));
            OK(loaded, dpsm_get_mass(loaded, DPSM_MASS_OUTFLOW, &b));
            require(a == b, "%s: the part read back has outflow %.17g, the part %.17g", at, b, a);
            free(hl);
        }
        OK(serial.g, dpsm_get_heights(serial.g, hs));
        OK(part.g, dpsm_get_heights(part.g, hp));
        long differ = 0;
        int64_t first = -1;
        for (int64_t k = 0; k < p.ncells; ++k)
            if (memcmp(&hp[k], &hs[p.global[k]], sizeof(double)) != 0) {
                if (first < 0) first = k;
                ++differ;
            }
        require(differ == 0, "%s: %ld of %lld local cells differ from the serial mesh, first global cell %lld (%s): "
                "%.17g, serial %.17g", at, differ, (long long)p.ncells, first < 0 ? -1LL : (long long)p.global[first],
                first >= 0 && p.owner[first] == rank_ ? "owned" : "ghost", first < 0 ? 0.0 : hp[first],
                first < 0 ? 0.0 : hs[p.global[first]]);
        for (int item = DPSM_INFO_SUBSTEPS; item <= DPSM_INFO_MAX_EXCESS_SLOPE; ++item) {
            double a = 0.0, b = 0.0;
            OK(serial.g, dpsm_get_step_info(serial.g, item, &a));
            OK(part.g, dpsm_get_step_info(part.g, item, &b));
            require(a == b, "%s: step info %d is %.17g, serial %.17g", at, item, b, a);
        }
        if (local_steps_ && step == 0) {
            /* Several classes: the serial mesh's ticks did not all update every cell. */
            double updates = 0.0, ticks = 0.0;
            OK(serial.g, dpsm_get_step_info(serial.g, DPSM_INFO_CELL_UPDATES, &updates));
            OK(serial.g, dpsm_get_step_info(serial.g, DPSM_INFO_SUBSTEPS, &ticks));
            require(ticks > 1.0 && updates < 0.75 * ticks * (double)m->ncells,
                    "%s: %g cell updates in %g ticks of %lld cells: one class", at, updates, ticks,
                    (long long)m->ncells);
        }
        double total = 0.0;
        OK(serial.g, dpsm_get_mass(serial.g, DPSM_MASS_TOTAL, &total));
        for (int q = DPSM_MASS_TOTAL; q <= DPSM_MASS_UNMET; ++q) {
            double a = 0.0, b = 0.0;
            OK(serial.g, dpsm_get_mass(serial.g, q, &a));
            OK(part.g, dpsm_get_mass(part.g, q, &b));
            require(fabs(a - b) <= 1e-12 * fmax(1.0, fabs(total)), "%s: mass figure %d is %.17g, serial %.17g", at, q,
                    b, a);
        }
        double edge_s = 0.0, edge_p = 0.0;
        OK(serial.g, dpsm_get_side_outflow(serial.g, DPSM_MESH_EDGE, &edge_s));
        OK(part.g, dpsm_get_side_outflow(part.g, DPSM_MESH_EDGE, &edge_p));
        require(fabs(edge_s - edge_p) <= 1e-12 * fmax(1.0, fabs(total)), "%s: edge outflow %.17g, serial %.17g", at,
                edge_p, edge_s);
        if (scene != SCENE_TO_REST) compare_faces(&serial, &part, serial_cells, part_cells, at);
        check_exchanges(part.g, layers, step, at);
    }
    free(hs), free(hp), free(part_cells);
    dpsm_destroy(loaded);
done:
    dpsm_destroy(serial.g);
    dpsm_destroy(part.g);
    free(serial.face_nodes), free(part.face_nodes), free(serial_cells), free(all_nodes);
    free_part(&p);
    free(owner);
}

/* ---- a local pile: ranks at rest ------------------------------------------ */

/* How local_pile steps: the partition, the ghost layers, DPSM_RELAX_LOCAL_STEPS
 * or the default, the step's dt and the most steps. */
typedef struct {
    int kind, layers, local_steps;
    double dt;
    int most_steps;
} pile_run_t;

/* A small pile on a mesh: at x = `at`, closed edges, stepped in short steps
 * until it rests. Besides the heights (bit for bit with the serial mesh,
 * stepped alike, after every step) it checks what each rank did: the ranks'
 * cell updates add up to the step's; a rank whose cells lie beyond
 * `quiet_from` (where the pile never reaches) computes and sends nothing
 * after the first step (whose first sub-step looks at every cell); the rank
 * holding the pile visits fewer cells than its owned cells times the
 * sub-steps once the pile has mostly settled (the active set); and the step
 * after rest visits and sends nothing on any rank. Returns the messages this
 * rank sent over all steps. */
static double local_pile(const mesh_t *m, double at, double quiet_from, const char *where, pile_run_t how) {
    int *owner = xcalloc((size_t)m->ncells, sizeof(int));
    partition(m, how.kind, owner);
    part_t p = part_of(m, owner, how.layers);
    dpsm_grid *serial = NULL, *part = NULL;
    OK(NULL, dpsm_create_mesh(m->nnodes, m->node_xy, m->ncells, m->cell_start, m->cell_nodes, &serial));
    OK(NULL, dpsm_create_mesh_mpi(MPI_COMM_WORLD, p.nnodes, p.node_xy, p.ncells, p.cell_start, p.cell_nodes,
                                  p.global_id, p.owner, &part));
    double *hs = xcalloc((size_t)m->ncells, sizeof(double)), *hp = xcalloc((size_t)p.ncells, sizeof(double));
    for (int64_t c = 0; c < m->ncells; ++c) {
        double x, y;
        centre(m, c, &x, &y);
        hs[c] = fmax(0.0, 0.3 - 3.0 * hypot(x - at, y - 0.5));
    }
    for (int64_t k = 0; k < p.ncells; ++k) hp[k] = hs[p.global[k]];
    OK(serial, dpsm_set_heights(serial, hs));
    OK(part, dpsm_set_heights(part, hp));
    double x0 = 1.0, owned = 0.0, sent = 0.0;
    for (int64_t k = 0; k < p.ncells; ++k)
        if (p.owner[k] == rank_) {
            double x, y;
            centre(m, p.global[k], &x, &y);
            x0 = fmin(x0, x);
            owned += 1.0;
        }
    if (how.local_steps) {
        OK(serial, dpsm_set_relaxation(serial, DPSM_RELAX_LOCAL_STEPS));
        OK(part, dpsm_set_relaxation(part, DPSM_RELAX_LOCAL_STEPS));
    }
    int sparse_seen = 0, moving_rank = 0, rested = 0, step = 0;
    for (; step < how.most_steps && rested < 2; ++step) {
        char at_step[300];
        snprintf(at_step, sizeof at_step, "%s, step %d", where, step + 1);
        OK(serial, dpsm_step(serial, how.dt));
        OK(part, dpsm_step(part, how.dt));
        OK(serial, dpsm_get_heights(serial, hs));
        OK(part, dpsm_get_heights(part, hp));
        long differ = 0;
        for (int64_t k = 0; k < p.ncells; ++k) differ += memcmp(&hp[k], &hs[p.global[k]], sizeof(double)) != 0;
        require(differ == 0, "%s: %ld local cells differ from the serial mesh", at_step, differ);
        double info[DPSM_INFO_BYTES_SENT + 1], serial_info[DPSM_INFO_CELL_UPDATES + 1];
        for (int item = 0; item <= DPSM_INFO_BYTES_SENT; ++item) OK(part, dpsm_get_step_info(part, item, &info[item]));
        for (int item = 0; item <= DPSM_INFO_CELL_UPDATES; ++item)
            OK(serial, dpsm_get_step_info(serial, item, &serial_info[item]));
        for (int item = DPSM_INFO_SUBSTEPS; item <= DPSM_INFO_MAX_EXCESS_SLOPE; ++item)
            require(info[item] == serial_info[item], "%s: step info %d is %.17g, serial %.17g", at_step, item,
                    info[item], serial_info[item]);
        double all = 0.0;
        MPI_Allreduce(&info[DPSM_INFO_RANK_CELL_UPDATES], &all, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
        require(all == info[DPSM_INFO_CELL_UPDATES], "%s: the ranks' cell updates add up to %.17g, the step's are %.17g",
                at_step, all, info[DPSM_INFO_CELL_UPDATES]);
        require(info[DPSM_INFO_BYTES_SENT] >= 8.0 * info[DPSM_INFO_MESSAGES_SENT],
                "%s: %g messages of %g bytes", at_step, info[DPSM_INFO_MESSAGES_SENT], info[DPSM_INFO_BYTES_SENT]);
        sent += info[DPSM_INFO_MESSAGES_SENT];
        /* A new grid looks at every cell once, in the first sub-step. */
        if (x0 >= quiet_from && step > 0) {
            require(info[DPSM_INFO_RANK_CELL_UPDATES] == 0.0 && info[DPSM_INFO_MESSAGES_SENT] == 0.0,
                    "%s: this rank's strip (x from %.3f) lies far from the pile, yet it visited %g cells and sent %g "
                    "messages (%g bytes)", at_step, x0, info[DPSM_INFO_RANK_CELL_UPDATES],
                    info[DPSM_INFO_MESSAGES_SENT], info[DPSM_INFO_BYTES_SENT]);
        }
        if (rested)
            require(info[DPSM_INFO_SUBSTEPS] == 0.0 && info[DPSM_INFO_RANK_CELL_UPDATES] == 0.0 &&
                        info[DPSM_INFO_MESSAGES_SENT] == 0.0,
                    "%s, after rest: %g sub-steps, %g cells visited and %g messages here", at_step,
                    info[DPSM_INFO_SUBSTEPS], info[DPSM_INFO_RANK_CELL_UPDATES], info[DPSM_INFO_MESSAGES_SENT]);
        if (info[DPSM_INFO_RANK_CELL_UPDATES] > 0.0) moving_rank = 1;
        if (info[DPSM_INFO_RANK_CELL_UPDATES] > 0.0 && info[DPSM_INFO_RANK_CELL_UPDATES] < owned * info[DPSM_INFO_SUBSTEPS])
            sparse_seen = 1;
        if (info[DPSM_INFO_AT_REST] == 1.0 && step > 0) ++rested;
    }
    require(rested == 2, "%s: not at rest after %d steps of %g", where, step, how.dt);
    int any_sparse = 0, any_moving = 0;
    MPI_Allreduce(&sparse_seen, &any_sparse, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    MPI_Allreduce(&moving_rank, &any_moving, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    require(any_moving, "%s: no rank visited any cell", where);
    require(any_sparse, "%s: no rank ever visited fewer cells than all its own in every sub-step", where);
    free(hs), free(hp);
    dpsm_destroy(serial);
    dpsm_destroy(part);
    free_part(&p);
    free(owner);
    return sent;
}

/* ---- failures on every rank ---------------------------------------------- */

/* Every rank got `status` (not DPSM_OK) and the same one; rank 0's message contains `phrase`. */
static void require_failed_alike(const dpsm_grid *g, int status, const char *phrase, const char *what) {
    int lo = status, hi = status;
    MPI_Allreduce(MPI_IN_PLACE, &lo, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    MPI_Allreduce(MPI_IN_PLACE, &hi, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    require(status != DPSM_OK && lo == hi, "%s: status %s here, from %d to %d over the ranks", what,
            dpsm_status_string(status), lo, hi);
    const char *message = dpsm_last_error(g);
    require(strstr(message, phrase) != NULL, "%s: the message \"%s\" does not say \"%s\"", what, message, phrase);
}

static int create_part(const part_t *p, dpsm_grid **g) {
    return dpsm_create_mesh_mpi(MPI_COMM_WORLD, p->nnodes, p->node_xy, p->ncells, p->cell_start, p->cell_nodes,
                                p->global_id, p->owner, g);
}

static void inconsistent_partitions(void) {
    if (size_ < 2) return;
    mesh_t m = lattice(12, 1);
    int *owner = xcalloc((size_t)m.ncells, sizeof(int));
    partition(&m, PART_STRIPS, owner);
    dpsm_grid *g = NULL;
    int status;

    part_t p = part_of(&m, owner, 2);
    /* Rank 1 claims a ghost of rank 0 as its own. */
    int64_t changed = -1;
    if (rank_ == 1)
        for (int64_t k = 0; k < p.ncells && changed < 0; ++k)
            if (p.owner[k] == 0) changed = k, p.owner[k] = 1;
    status = create_part(&p, &g);
    require_failed_alike(NULL, status, "and by rank 1", "a cell owned twice");
    if (changed >= 0) p.owner[changed] = 0;

    /* Rank 0 names the wrong owner for a ghost. */
    changed = -1;
    if (rank_ == 0)
        for (int64_t k = 0; k < p.ncells && changed < 0; ++k)
            if (p.owner[k] == 1) changed = k, p.owner[k] = size_ > 2 ? 2 : 0;
    status = create_part(&p, &g);
    require_failed_alike(NULL, status, size_ > 2 ? "but rank 1 owns it" : "owned by rank 0 and by rank 1",
                         "a ghost's wrong owner");
    if (changed >= 0) p.owner[changed] = 1;

    /* A global id beyond the cells. */
    changed = -1;
    if (rank_ == size_ - 1)
        for (int64_t k = 0; k < p.ncells && changed < 0; ++k)
            if (p.owner[k] == rank_) changed = k, p.global_id[k] = m.ncells + 5;
    status = create_part(&p, &g);
    require_failed_alike(NULL, status, "without gaps", "a global id out of range");
    if (changed >= 0) p.global_id[changed] = p.global[changed];

    /* Restart files: each rank loads another rank's file: refused on every rank. */
    status = create_part(&p, &g);
    require(status == DPSM_OK, "the partition: %s", dpsm_last_error(NULL));
    char mine[64], other[64];
    snprintf(mine, sizeof mine, "test_mpi_mesh_other.%d.dpsm", rank_);
    snprintf(other, sizeof other, "test_mpi_mesh_other.%d.dpsm", (rank_ + 1) % size_);
    OK(g, dpsm_save(g, mine));
    dpsm_destroy(g);
    g = NULL;
    MPI_Barrier(MPI_COMM_WORLD);
    status = dpsm_load_mpi(MPI_COMM_WORLD, other, &g);
    require_failed_alike(NULL, status, "rank", "a rank loading another rank's file");
    require(g == NULL, "a refused load left a grid");
    status = dpsm_load(mine, &g);
    require(status == DPSM_ERR_NOT_APPLICABLE && g == NULL && strstr(dpsm_last_error(NULL), "dpsm_load_mpi"),
            "dpsm_load of a part of a distributed mesh: %s: %s", dpsm_status_string(status), dpsm_last_error(NULL));
    MPI_Barrier(MPI_COMM_WORLD);
    remove(mine);

    /* A NULL array on one rank. */
    status = dpsm_create_mesh_mpi(MPI_COMM_WORLD, p.nnodes, p.node_xy, p.ncells, p.cell_start, p.cell_nodes,
                                  rank_ == 1 ? NULL : p.global_id, p.owner, &g);
    require_failed_alike(NULL, status, "global_id is NULL", "a NULL global_id on rank 1");

    /* The same arrays again: it works, and a refusing rank fails the step on every rank. */
    status = create_part(&p, &g);
    require(status == DPSM_OK, "the restored partition: %s", dpsm_last_error(NULL));
    if (g) {
        double *h = xcalloc((size_t)p.ncells, sizeof(double));
        for (int64_t k = 0; k < p.ncells; ++k) h[k] = column(&m, p.global[k]);
        OK(g, dpsm_set_heights(g, h));
        status = dpsm_step(g, rank_ == 1 ? -1.0 : 0.05);
        int lo = status, hi = status;
        MPI_Allreduce(MPI_IN_PLACE, &lo, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
        MPI_Allreduce(MPI_IN_PLACE, &hi, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
        require(status != DPSM_OK && lo == hi, "a refusing rank: status %d here, %d to %d", status, lo, hi);
        double after = 0.0;
        OK(g, dpsm_get_heights(g, h));
        OK(g, dpsm_step(g, 0.05));
        OK(g, dpsm_get_mass(g, DPSM_MASS_TOTAL, &after));
        require(after > 0.0, "the step after a refused one");
        /* Ranks that differ in a parameter fail alike. */
        OK(g, dpsm_set_mobility(g, rank_ == 0 ? 2.0 : 1.0));
        status = dpsm_step(g, 0.05);
        require_failed_alike(g, status, "the mobility", "ranks that differ in the mobility");
        free(h);
        dpsm_destroy(g);
    }
    free_part(&p);
    free(owner);
    free_mesh(&m);
}

int main(int argc, char **argv) {
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    if (rank_ == 0) printf("test_mpi_mesh on %d ranks\n", size_);
    for (int shape = 0; shape < 2; ++shape) {
        mesh_t m = lattice(shape == 0 ? 14 : 12, shape == 0);
        for (int scene = 0; scene < N_SCENES; ++scene)
            for (int kind = 0; kind < N_PARTITIONS; ++kind)
                for (int graph = 0; graph < 2; ++graph)
                    for (int deep = 0; deep < 2; ++deep) {
                        /* One layer of ghosts (exchanges in every sub-step) and a deep layer (several sub-steps per exchange). */
                        const int layers = deep ? kDeepLayers : 1;
                        long before = failures_, mine, total = 0;
                        run_scene(&m, scene, kind, graph, layers);
                        mine = failures_ - before;
                        MPI_Allreduce(&mine, &total, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
                        if (rank_ == 0)
                            printf("  %s, %s: %s, %s partition, %d layers of ghosts (%g sub-steps per exchange): "
                                   "%s%s\n",
                                   shape == 0 ? "triangles" : "quads", scene_names[scene], graph ? "graph" : "polygons",
                                   partition_names[kind], layers, per_exchange_,
                                   total == 0 ? "heights bit for bit" : "FAILED", total == 0 ? "" : ", see above");
                    }
        if (shape == 0) {
            /* A deep layer held to fewer sub-steps per exchange by the environment, for comparisons. */
            for (substeps_limit_ = 0; substeps_limit_ <= 1; ++substeps_limit_) {
                char value[16];
                snprintf(value, sizeof value, "%d", substeps_limit_);
                setenv("DPSM_MPI_SUBSTEPS_PER_EXCHANGE", value, 1);
                const long before = failures_;
                run_scene(&m, SCENE_PHYSICS, PART_METIS, 0, kDeepLayers);
                long mine = failures_ - before, total = 0;
                MPI_Allreduce(&mine, &total, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
                if (rank_ == 0)
                    printf("  triangles, %s: %d layers of ghosts, DPSM_MPI_SUBSTEPS_PER_EXCHANGE=%s (%g sub-steps per "
                           "exchange): %s\n", scene_names[SCENE_PHYSICS], kDeepLayers, value, per_exchange_,
                           total == 0 ? "heights bit for bit" : "FAILED, see above");
            }
            unsetenv("DPSM_MPI_SUBSTEPS_PER_EXCHANGE");
            substeps_limit_ = -1;
        }
        free_mesh(&m);
    }
    {
        /* 1,152 triangles in strips; the pile spreads less than 0.2 from its centre. */
        mesh_t m = lattice(24, 1);
        const long before = failures_;
        const double quiet = size_ > 1 ? 1.0 - 1.0 / size_ : 2.0;
        const pile_run_t strips = {PART_STRIPS, 2, 0, 0.01, 60};
        local_pile(&m, 0.1, quiet > 0.45 ? quiet : 2.0, "a pile at x = 0.1, strips", strips);
        const double crossing = local_pile(&m, size_ > 1 ? 1.0 / size_ : 0.5, 2.0, "a pile across two strips", strips);
        double all = 0.0;
        MPI_Allreduce(&crossing, &all, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
        require(size_ == 1 || all > 0.0, "a pile across two strips: no rank sent a message");
        long mine = failures_ - before, failed = 0;
        MPI_Allreduce(&mine, &failed, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
        if (rank_ == 0)
            printf("  triangles: local piles in strips: %s\n",
                   failed ? "FAILED, see above" : "heights bit for bit, ranks far from the pile idle");
        free_mesh(&m);
    }
    {
        /* Local time steps on graded lattices: three scenes (the third
         * with its static angle), each partition, polygons and graphs,
         * one layer of ghosts and a deep one, bit for bit with the serial
         * mesh's local time steps. With a deep layer of ghosts on a graded
         * lattice some ghosts on the layer's rim hold as many faces as their
         * owners (mesh/mesh_parts.cpp, take_owners_edges). */
        /* Every tick exchanges, and the graded lattice's smallest cells set
         * the ticks: a selection of the runs above keeps the test short. */
        static const struct {
            int local, triangles, scene, kind, graph, layers;
        } runs[] = {
            {1, 1, SCENE_COLLAPSE, PART_METIS, 0, 1},   {1, 1, SCENE_COLLAPSE, PART_STRIPS, 0, kDeepLayers},
            {1, 1, SCENE_COLLAPSE, PART_RANDOM, 1, 1},  {1, 1, SCENE_COLLAPSE, PART_METIS, 1, kDeepLayers},
            {1, 1, SCENE_SOURCES, PART_METIS, 0, 1},    {1, 1, SCENE_SOURCES, PART_STRIPS, 0, kDeepLayers},
            {1, 1, SCENE_PHYSICS, PART_STRIPS, 0, 1},   {1, 1, SCENE_PHYSICS, PART_METIS, 0, kDeepLayers},
            {1, 0, SCENE_COLLAPSE, PART_STRIPS, 0, 1},  {1, 0, SCENE_SOURCES, PART_METIS, 1, kDeepLayers},
            {1, 0, SCENE_PHYSICS, PART_RANDOM, 0, 1},
            /* The default's sub-steps on the same deep strips: rim ghosts, batches of sub-steps. */
            {0, 1, SCENE_COLLAPSE, PART_STRIPS, 0, kDeepLayers},
        };
        mesh_t shapes[2] = {graded_lattice(12, 0), graded_lattice(14, 1)};
#ifdef DPSM_TESTS_UNDER_ASAN
        /* Under AddressSanitizer the first four runs (every exchange of a
         * tick, dense and sparse, both layers) and one pile: every tick
         * exchanges, and the rest would take a minute of the stage for code
         * that these runs pass through; the main stage runs them all. */
        const size_t run_count = 4;
#else
        const size_t run_count = sizeof runs / sizeof runs[0];
#endif
        for (size_t k = 0; k < run_count; ++k) {
            local_steps_ = runs[k].local;
            const long before = failures_;
            run_scene(&shapes[runs[k].triangles], runs[k].scene, runs[k].kind, runs[k].graph, runs[k].layers);
            long mine = failures_ - before, total = 0;
            MPI_Allreduce(&mine, &total, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
            if (rank_ == 0)
                printf("  graded %s, %s, %s: %s, %s partition, %d layers of ghosts: %s\n",
                       runs[k].triangles ? "triangles" : "quads", runs[k].local ? "local time steps" : "the default",
                       scene_names[runs[k].scene],
                       runs[k].graph ? "graph" : "polygons", partition_names[runs[k].kind], runs[k].layers,
                       total == 0 ? "heights bit for bit" : "FAILED, see above");
        }
        local_steps_ = 0;
        /* Piles to rest with local time steps, one layer of ghosts. On a
         * random partition most ghosts' gradients read cells beyond the
         * part: their owners' exchanges say when they change. */
        const long before = failures_;
        const pile_run_t strips = {PART_STRIPS, 1, 1, 0.05, 60};
        local_pile(&shapes[1], size_ > 1 ? 1.0 / size_ : 0.5, 2.0, "local time steps, a pile across two strips", strips);
#ifndef DPSM_TESTS_UNDER_ASAN
        const pile_run_t random = {PART_RANDOM, 1, 1, 0.05, 60};
        local_pile(&shapes[0], 0.15, size_ > 1 ? 0.45 : 2.0, "local time steps, a pile in one strip", strips);
        local_pile(&shapes[1], 0.1, 2.0, "local time steps, a pile on a random partition", random);
#endif
        long mine = failures_ - before, total = 0;
        MPI_Allreduce(&mine, &total, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
        if (rank_ == 0)
            printf("  graded quads and triangles, local time steps: piles to rest: %s\n", total == 0 ? "heights bit for bit, ranks far from the pile idle, then every rank "
                                                   "idle" : "FAILED, see above");
        free_mesh(&shapes[0]), free_mesh(&shapes[1]);
    }
    inconsistent_partitions();
    long total = 0, all_checks = 0;
    MPI_Allreduce(&failures_, &total, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
    MPI_Allreduce(&checks_, &all_checks, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
    if (rank_ == 0) printf("test_mpi_mesh: %ld checks on %d ranks, %ld failed\n", all_checks, size_, total);
    MPI_Finalize();
    return total == 0 ? 0 : 1;
}
