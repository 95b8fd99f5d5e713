/* Unstructured meshes (issue 18): the three constructors with their normal
 * and bad inputs, the functions of dpsm.h on a mesh, and the numerics:
 *
 *  - a mesh keeps the host's cell order whatever order the library keeps
 *    inside: the same mesh given in another order gives the same heights,
 *    cell by cell, bit for bit;
 *  - a graph of the cells of a polygon mesh steps as the polygons do;
 *  - exact states: a plane below the angle of repose does not move, a flat
 *    surface under a uniform source rises by q dt everywhere, and a plane at
 *    exactly the angle of repose rests on every kind of mesh;
 *  - the column on the mesh turned by 30 degrees gives the same deposit, cell
 *    by cell, to round-off;
 *  - the column collapse conserves mass to round-off, makes no new extremum,
 *    and comes to rest, and lays no sand beyond the toe of its deposit;
 *  - the active set changes no bit (DPSM_VISIT_ALL_CELLS=1 visits every cell);
 *  - face fluxes add up to each cell's change of height, and the edge's faces
 *    to the outflow. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "mesh_scenes.h"
#include "test_support.h"

static const double kDeg = 3.14159265358979323846 / 180.0;

/* A failed create: the status, *out left NULL, and a message naming `what`. */
#define EXPECT_CREATE_FAIL(call, out, code, fn, what)                                                               \
    do {                                                                                                            \
        (out) = (dpsm_grid *)&(out);                                                                                \
        const int status_ = (call);                                                                                 \
        REQUIRE(status_ == (code), "%s returned %s, expected %s (%s)", #call, dpsm_status_string(status_),          \
                dpsm_status_string(code), dpsm_last_error(NULL));                                                   \
        REQUIRE((out) == NULL, "%s left *out set", #call);                                                          \
        REQUIRE(strstr(dpsm_last_error(NULL), (fn)) != NULL, "message '%s' does not name %s", dpsm_last_error(NULL), \
                (fn));                                                                                              \
        REQUIRE(strstr(dpsm_last_error(NULL), (what)) != NULL, "message '%s' does not name '%s'",                   \
                dpsm_last_error(NULL), (what));                                                                     \
    } while (0)

/* A failed call on a mesh: the status and a message naming `what`. */
#define EXPECT_FAIL_ON(g, call, code, what)                                                                   \
    do {                                                                                                      \
        const int status_ = (call);                                                                           \
        REQUIRE(status_ == (code), "%s returned %s, expected %s (%s)", #call, dpsm_status_string(status_),    \
                dpsm_status_string(code), dpsm_last_error(g));                                                \
        REQUIRE(strstr(dpsm_last_error(g), (what)) != NULL, "message '%s' does not name '%s'", dpsm_last_error(g), \
                (what));                                                                                      \
    } while (0)

/* A 2 x 2 square of unit quads: nodes 0..8 row by row. */
static const double kQuadNodes[18] = {0, 0, 1, 0, 2, 0, 0, 1, 1, 1, 2, 1, 0, 2, 1, 2, 2, 2};
static const int64_t kQuadStart[5] = {0, 4, 8, 12, 16};
static const int64_t kQuadCells[16] = {0, 1, 4, 3, 1, 2, 5, 4, 3, 4, 7, 6, 4, 5, 8, 7};

static double *column_heights(const mesh_scene *s, double radius, double height) {
    double *h = calloc((size_t)s->cells, sizeof(double));
    scene_disk_fractions(s, radius, h);
    for (int64_t c = 0; c < s->cells; ++c) h[c] *= height;
    return h;
}

/* ------------------------------------------------------------------------ */
/* Constructors                                                              */
/* ------------------------------------------------------------------------ */

static void test_create_mesh_quads(void **state) {
    (void)state;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_mesh(9, kQuadNodes, 4, kQuadStart, kQuadCells, &g));
    int64_t nx = 0, ny = 0, nfaces = 0;
    CHECK_OK(g, dpsm_get_shape(g, &nx, &ny));
    REQUIRE(nx == 4 && ny == 1, "shape (%lld, %lld), expected (4, 1)", (long long)nx, (long long)ny);
    CHECK_OK(g, dpsm_get_face_count(g, &nfaces));
    REQUIRE(nfaces == 12, "%lld faces, expected 4 interior and 8 on the edge", (long long)nfaces);
    int64_t faces[24];
    CHECK_OK(g, dpsm_get_mesh_faces(g, faces));
    int interior = 0, edge = 0;
    for (int f = 0; f < 12; ++f) {
        REQUIRE(faces[2 * f] >= 0 && faces[2 * f] < 4, "face %d: a = %lld", f, (long long)faces[2 * f]);
        if (faces[2 * f + 1] < 0) {
            ++edge;
            continue;
        }
        ++interior;
        /* the two cells of an interior face are neighbours of the 2 x 2 square: they differ in one coordinate */
        const int64_t a = faces[2 * f], b = faces[2 * f + 1];
        REQUIRE((a % 2 == b % 2) != (a / 2 == b / 2), "face %d joins cells %lld and %lld, not neighbours", f,
                (long long)a, (long long)b);
        /* the host's order: faces appear cell by cell, so a face's a is the first cell that has it */
        REQUIRE(a < b, "face %d: a = %lld after b = %lld", f, (long long)a, (long long)b);
    }
    REQUIRE(interior == 4 && edge == 8, "%d interior and %d edge faces", interior, edge);
    /* The faces are numbered as they first appear: cell 0's four first. */
    for (int f = 0; f < 4; ++f) REQUIRE(faces[2 * f] == 0, "face %d belongs to cell %lld, not 0", f, (long long)faces[2 * f]);
    dpsm_destroy(g);
}

static void test_create_graph_and_dual(void **state) {
    (void)state;
    /* Two unit squares side by side as a graph: 1 interior face, 6 edges. */
    const double cell_xy[4] = {0.5, 0.5, 1.5, 0.5}, area[2] = {1, 1};
    const int64_t face_cells[14] = {0, 1, 0, -1, 0, -1, 0, -1, 1, -1, 1, -1, 1, -1};
    const double face_xy[14] = {1, 0.5, 0, 0.5, 0.5, 0, 0.5, 1, 2, 0.5, 1.5, 0, 1.5, 1};
    const double length[7] = {1, 1, 1, 1, 1, 1, 1};
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_graph(2, cell_xy, area, 7, face_cells, face_xy, length, &g));
    int64_t nx = 0, ny = 0, nfaces = 0, got[14];
    CHECK_OK(g, dpsm_get_shape(g, &nx, &ny));
    REQUIRE(nx == 2 && ny == 1, "graph shape (%lld, %lld)", (long long)nx, (long long)ny);
    CHECK_OK(g, dpsm_get_face_count(g, &nfaces));
    REQUIRE(nfaces == 7, "%lld faces", (long long)nfaces);
    CHECK_OK(g, dpsm_get_mesh_faces(g, got));
    REQUIRE(memcmp(got, face_cells, sizeof got) == 0, "a graph's faces come back as the host gave them");
    dpsm_destroy(g);

    /* The dual of two triangles over 4 nodes: a cell per node, 5 edges and 4 boundary edges in halves. */
    const double nodes[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    const int64_t tris[6] = {0, 1, 2, 0, 2, 3};
    CHECK_OK(NULL, dpsm_create_dual_mesh(4, nodes, 2, tris, &g));
    CHECK_OK(g, dpsm_get_shape(g, &nx, &ny));
    REQUIRE(nx == 4, "the dual has one cell per node, not %lld", (long long)nx);
    CHECK_OK(g, dpsm_get_face_count(g, &nfaces));
    REQUIRE(nfaces == 13, "the dual has %lld faces, expected 5 + 8", (long long)nfaces);
    /* The areas are a third of each node's triangles: a uniform height of 1 has the square's volume. */
    const double ones[4] = {1, 1, 1, 1};
    CHECK_OK(g, dpsm_set_heights(g, ones));
    REQUIRE(fabs(mass_of(g, DPSM_MASS_TOTAL) - 1.0) < 1e-15, "the dual's cells cover the square: volume %.17g",
            mass_of(g, DPSM_MASS_TOTAL));
    dpsm_destroy(g);
}

static void test_bad_meshes(void **state) {
    (void)state;
    dpsm_grid *g = NULL;
    const char *fn = "dpsm_create_mesh";
    EXPECT_CREATE_FAIL(dpsm_create_mesh(9, NULL, 4, kQuadStart, kQuadCells, &g), g, DPSM_ERR_NULL_POINTER, fn, "node_xy");
    EXPECT_CREATE_FAIL(dpsm_create_mesh(9, kQuadNodes, 4, NULL, kQuadCells, &g), g, DPSM_ERR_NULL_POINTER, fn, "cell_start");
    EXPECT_CREATE_FAIL(dpsm_create_mesh(9, kQuadNodes, 4, kQuadStart, NULL, &g), g, DPSM_ERR_NULL_POINTER, fn, "cell_nodes");
    REQUIRE(dpsm_create_mesh(9, kQuadNodes, 4, kQuadStart, kQuadCells, NULL) == DPSM_ERR_NULL_POINTER, "out NULL");
    EXPECT_CREATE_FAIL(dpsm_create_mesh(0, kQuadNodes, 4, kQuadStart, kQuadCells, &g), g, DPSM_ERR_INVALID_SIZE, fn, "nnodes");
    EXPECT_CREATE_FAIL(dpsm_create_mesh(9, kQuadNodes, 0, kQuadStart, kQuadCells, &g), g, DPSM_ERR_INVALID_SIZE, fn, "ncells");
    int64_t cells[16];
    memcpy(cells, kQuadCells, sizeof cells);
    cells[6] = 9; /* cell 1's third node */
    EXPECT_CREATE_FAIL(dpsm_create_mesh(9, kQuadNodes, 4, kQuadStart, cells, &g), g, DPSM_ERR_INVALID_VALUE, fn, "cell_nodes[6]");
    memcpy(cells, kQuadCells, sizeof cells);
    cells[9] = 3, cells[10] = 4; /* cell 2 becomes 3, 3, 4, 6 ... with a repeated node in a row */
    EXPECT_CREATE_FAIL(dpsm_create_mesh(9, kQuadNodes, 4, kQuadStart, cells, &g), g, DPSM_ERR_INVALID_VALUE, fn, "cell 2");
    /* fewer than 3 distinct nodes */
    const int64_t start2[2] = {0, 4};
    const int64_t two[4] = {0, 1, 0, 1};
    EXPECT_CREATE_FAIL(dpsm_create_mesh(9, kQuadNodes, 1, start2, two, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "fewer than 3 distinct");
    /* zero area: three nodes on a line */
    const int64_t start3[2] = {0, 3};
    const int64_t line[3] = {0, 1, 2};
    EXPECT_CREATE_FAIL(dpsm_create_mesh(9, kQuadNodes, 1, start3, line, &g), g, DPSM_ERR_INVALID_VALUE, fn, "zero area");
    /* an edge shared by three cells: three triangles on the edge 0-1 */
    const double fan[8] = {0, 0, 1, 0, 0.5, 1, 0.5, -1};
    const int64_t fan_start[4] = {0, 3, 6, 9};
    const int64_t fan_cells[9] = {0, 1, 2, 0, 1, 3, 1, 0, 2};
    EXPECT_CREATE_FAIL(dpsm_create_mesh(4, fan, 3, fan_start, fan_cells, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "shared by 3 cells");
    double bad_nodes[18];
    memcpy(bad_nodes, kQuadNodes, sizeof bad_nodes);
    bad_nodes[7] = NAN; /* y of node 3 */
    EXPECT_CREATE_FAIL(dpsm_create_mesh(9, bad_nodes, 4, kQuadStart, kQuadCells, &g), g, DPSM_ERR_INVALID_VALUE, fn, "node 3");
    int64_t bad_start[5] = {1, 4, 8, 12, 16};
    EXPECT_CREATE_FAIL(dpsm_create_mesh(9, kQuadNodes, 4, bad_start, kQuadCells, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "cell_start[0]");

    fn = "dpsm_create_graph";
    const double cell_xy[4] = {0.5, 0.5, 1.5, 0.5}, area[2] = {1, 1};
    int64_t face_cells[14] = {0, 1, 0, -1, 0, -1, 0, -1, 1, -1, 1, -1, 1, -1};
    const double face_xy[14] = {1, 0.5, 0, 0.5, 0.5, 0, 0.5, 1, 2, 0.5, 1.5, 0, 1.5, 1};
    double length[7] = {1, 1, 1, 1, 1, 1, 1};
    face_cells[9] = 2;
    EXPECT_CREATE_FAIL(dpsm_create_graph(2, cell_xy, area, 7, face_cells, face_xy, length, &g), g, DPSM_ERR_INVALID_VALUE,
                       fn, "face 4");
    face_cells[9] = -1, face_cells[1] = 0;
    EXPECT_CREATE_FAIL(dpsm_create_graph(2, cell_xy, area, 7, face_cells, face_xy, length, &g), g, DPSM_ERR_INVALID_VALUE,
                       fn, "to itself");
    face_cells[1] = 1;
    const double same_xy[4] = {0.5, 0.5, 0.5, 0.5};
    EXPECT_CREATE_FAIL(dpsm_create_graph(2, same_xy, area, 7, face_cells, face_xy, length, &g), g,
                       DPSM_ERR_INVALID_VALUE, fn, "coincide");
    const double no_area[2] = {1, 0};
    EXPECT_CREATE_FAIL(dpsm_create_graph(2, cell_xy, no_area, 7, face_cells, face_xy, length, &g), g,
                       DPSM_ERR_INVALID_VALUE, fn, "cell 1");
    length[3] = -1;
    EXPECT_CREATE_FAIL(dpsm_create_graph(2, cell_xy, area, 7, face_cells, face_xy, length, &g), g, DPSM_ERR_INVALID_VALUE,
                       fn, "face_length[3]");
    length[3] = 1;
    /* cell 1 without its faces on the right: not closed */
    EXPECT_CREATE_FAIL(dpsm_create_graph(2, cell_xy, area, 4, face_cells, face_xy, length, &g), g, DPSM_ERR_INVALID_VALUE,
                       fn, "do not close");
    EXPECT_CREATE_FAIL(dpsm_create_graph(2, cell_xy, area, 7, NULL, face_xy, length, &g), g, DPSM_ERR_NULL_POINTER, fn,
                       "face_cells");

    fn = "dpsm_create_dual_mesh";
    const double nodes[10] = {0, 0, 1, 0, 1, 1, 0, 1, 5, 5};
    const int64_t tris[6] = {0, 1, 2, 0, 2, 3};
    EXPECT_CREATE_FAIL(dpsm_create_dual_mesh(5, nodes, 2, tris, &g), g, DPSM_ERR_INVALID_VALUE, fn, "node 4");
    const int64_t flat[3] = {0, 1, 1};
    EXPECT_CREATE_FAIL(dpsm_create_dual_mesh(4, nodes, 1, flat, &g), g, DPSM_ERR_INVALID_VALUE, fn, "triangle 0");
    const int64_t out_of_range[6] = {0, 1, 2, 0, 2, 7};
    EXPECT_CREATE_FAIL(dpsm_create_dual_mesh(4, nodes, 2, out_of_range, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "triangle_nodes[5]");
    EXPECT_CREATE_FAIL(dpsm_create_dual_mesh(4, NULL, 2, tris, &g), g, DPSM_ERR_NULL_POINTER, fn, "node_xy");
}

/* ------------------------------------------------------------------------ */
/* The functions of dpsm.h on a mesh                                         */
/* ------------------------------------------------------------------------ */

static void test_mesh_functions(void **state) {
    (void)state;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_mesh(9, kQuadNodes, 4, kQuadStart, kQuadCells, &g));
    double h[4] = {1, 2, 3, 4};
    EXPECT_FAIL_ON(g, dpsm_set_heights_region(g, 0, 0, 1, 1, h), DPSM_ERR_NOT_APPLICABLE, "mesh");
    EXPECT_FAIL_ON(g, dpsm_add_heights_region(g, 0, 0, 1, 1, h), DPSM_ERR_NOT_APPLICABLE, "mesh");
    EXPECT_FAIL_ON(g, dpsm_get_heights_region(g, 0, 0, 1, 1, h), DPSM_ERR_NOT_APPLICABLE, "mesh");
    EXPECT_FAIL_ON(g, dpsm_set_boundary(g, DPSM_XMIN, DPSM_OPEN), DPSM_ERR_NOT_APPLICABLE, "DPSM_MESH_EDGE");
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN));
    double bad[4] = {1, 2, NAN, 4};
    EXPECT_FAIL_ON(g, dpsm_set_heights(g, bad), DPSM_ERR_INVALID_VALUE, "cell 2");
    uint8_t kinds[4] = {0, 0, 7, 0};
    EXPECT_FAIL_ON(g, dpsm_set_cell_kinds(g, kinds), DPSM_ERR_UNKNOWN_ENUM, "cell 2");
    uint8_t edges[12];
    memset(edges, DPSM_WALL, sizeof edges);
    int64_t faces[24];
    CHECK_OK(g, dpsm_get_mesh_faces(g, faces));
    int64_t an_edge = -1, an_interior = -1;
    for (int f = 0; f < 12; ++f) {
        if (faces[2 * f + 1] < 0 && an_edge < 0) an_edge = f;
        if (faces[2 * f + 1] >= 0 && an_interior < 0) an_interior = f;
    }
    edges[an_interior] = 99; /* ignored: not on the edge */
    CHECK_OK(g, dpsm_set_edge_kinds(g, edges));
    edges[an_edge] = 5;
    char face_name[32];
    snprintf(face_name, sizeof face_name, "face %lld", (long long)an_edge);
    EXPECT_FAIL_ON(g, dpsm_set_edge_kinds(g, edges), DPSM_ERR_UNKNOWN_ENUM, face_name);
    CHECK_OK(g, dpsm_set_edge_kinds(g, NULL));
    double fy[4];
    CHECK_OK(g, dpsm_set_face_flux_recording(g, 1));
    double fx[12];
    EXPECT_FAIL_ON(g, dpsm_get_face_fluxes(g, fx, fy), DPSM_ERR_INVALID_VALUE, "fy must be NULL");
    CHECK_OK(g, dpsm_get_face_fluxes(g, fx, NULL));
    double levels[12] = {0};
    levels[an_edge] = INFINITY;
    EXPECT_FAIL_ON(g, dpsm_set_side_levels(g, DPSM_MESH_EDGE, levels), DPSM_ERR_INVALID_VALUE, face_name);
    EXPECT_FAIL_ON(g, dpsm_set_side_levels(g, DPSM_XMAX, levels), DPSM_ERR_NOT_APPLICABLE, "DPSM_MESH_EDGE");
    double v = 0.0;
    CHECK_OK(g, dpsm_get_side_outflow(g, DPSM_MESH_EDGE, &v));
    EXPECT_FAIL_ON(g, dpsm_get_face_count(g, NULL), DPSM_ERR_NULL_POINTER, "nfaces");
    EXPECT_FAIL_ON(g, dpsm_get_mesh_faces(g, NULL), DPSM_ERR_NULL_POINTER, "face_cells");
    dpsm_destroy(g);

    /* The mesh functions on a grid. */
    CHECK_OK(NULL, dpsm_create_2d(4, 4, 1.0, 1.0, &g));
    int64_t n = 0;
    EXPECT_FAIL_ON(g, dpsm_get_face_count(g, &n), DPSM_ERR_NOT_APPLICABLE, "not a mesh");
    EXPECT_FAIL_ON(g, dpsm_get_mesh_faces(g, faces), DPSM_ERR_NOT_APPLICABLE, "not a mesh");
    EXPECT_FAIL_ON(g, dpsm_set_edge_kinds(g, edges), DPSM_ERR_NOT_APPLICABLE, "not a mesh");
    dpsm_destroy(g);
    REQUIRE(dpsm_get_face_count(NULL, &n) == DPSM_ERR_NULL_POINTER, "NULL grid");
    REQUIRE(dpsm_get_mesh_faces(NULL, faces) == DPSM_ERR_NULL_POINTER, "NULL grid");
    REQUIRE(dpsm_set_edge_kinds(NULL, edges) == DPSM_ERR_NULL_POINTER, "NULL grid");
}

/* ------------------------------------------------------------------------ */
/* Indices from 1: the _indexed constructors                                 */
/* ------------------------------------------------------------------------ */

/* The n x n cells of scene_make(SCENE_QUADS, n, half, ...) as a graph,
 * built from the lattice: x faces, y faces, the four sides (from 0). */
typedef struct {
    int64_t ncells, nfaces;
    int64_t *face_cells;
    double *cell_xy, *area, *face_xy, *length;
} quad_graph;

static quad_graph quad_graph_make(int n, double half) {
    const double dx = 2.0 * half / n;
    quad_graph q;
    q.ncells = (int64_t)n * n;
    q.nfaces = 2 * (int64_t)(n + 1) * n;
    q.face_cells = calloc((size_t)(2 * q.nfaces), sizeof(int64_t));
    q.face_xy = calloc((size_t)(2 * q.nfaces), sizeof(double));
    q.length = calloc((size_t)q.nfaces, sizeof(double));
    q.cell_xy = calloc((size_t)(2 * q.ncells), sizeof(double));
    q.area = calloc((size_t)q.ncells, sizeof(double));
    for (int64_t c = 0; c < q.ncells; ++c) {
        q.cell_xy[2 * c] = -half + (c % n + 0.5) * dx, q.cell_xy[2 * c + 1] = -half + (c / n + 0.5) * dx;
        q.area[c] = dx * dx;
    }
    int64_t f = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i <= n; ++i, ++f) { /* the face on the low x side of cell (i, j) */
            const int64_t left = i > 0 ? (i - 1) + (int64_t)n * j : -1, right = i < n ? i + (int64_t)n * j : -1;
            q.face_cells[2 * f] = left >= 0 ? left : right;
            q.face_cells[2 * f + 1] = left >= 0 ? right : -1;
            q.face_xy[2 * f] = -half + i * dx, q.face_xy[2 * f + 1] = -half + (j + 0.5) * dx, q.length[f] = dx;
        }
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i < n; ++i, ++f) {
            const int64_t below = j > 0 ? i + (int64_t)n * (j - 1) : -1, above = j < n ? i + (int64_t)n * j : -1;
            q.face_cells[2 * f] = below >= 0 ? below : above;
            q.face_cells[2 * f + 1] = below >= 0 ? above : -1;
            q.face_xy[2 * f] = -half + (i + 0.5) * dx, q.face_xy[2 * f + 1] = -half + j * dx, q.length[f] = dx;
        }
    return q;
}

static void quad_graph_free(quad_graph *q) {
    free(q->face_cells), free(q->face_xy), free(q->length), free(q->cell_xy), free(q->area);
}


/* A copy of n indices counting from 1 instead of 0 (the domain edge's -1 becomes 0). */
static int64_t *from_one(const int64_t *v, int64_t n) {
    int64_t *w = malloc(sizeof(int64_t) * (size_t)(n > 0 ? n : 1));
    for (int64_t k = 0; k < n; ++k) w[k] = v[k] + 1;
    return w;
}

/* The format version of a restart file (its bytes 8 to 11, little-endian). */
static unsigned file_version(const char *path) {
    unsigned char bytes[12] = {0};
    FILE *f = fopen(path, "rb");
    REQUIRE(f != NULL, "cannot open %s", path);
    const size_t got = fread(bytes, 1, sizeof bytes, f);
    fclose(f);
    REQUIRE(got == sizeof bytes, "%s is shorter than 12 bytes", path);
    return bytes[8] | (unsigned)bytes[9] << 8 | (unsigned)bytes[10] << 16 | (unsigned)bytes[11] << 24;
}

/* The scene's mesh with its indices counting from `base`, through the
 * _indexed constructors (on copies counting from 1 for base 1). */
static int scene_create_from(const mesh_scene *s, int base, dpsm_grid **out) {
    const int64_t nidx = s->kind == SCENE_DUAL ? 3 * s->npolygons : s->cell_start[s->npolygons];
    int64_t *nodes = base ? from_one(s->cell_nodes, nidx) : NULL, *start = base ? from_one(s->cell_start, s->npolygons + 1) : NULL;
    const int64_t *n = base ? nodes : s->cell_nodes, *st = base ? start : s->cell_start;
    const int status = s->kind == SCENE_DUAL ? dpsm_create_dual_mesh_indexed(base, s->nnodes, s->node_xy, s->npolygons, n, out)
                                             : dpsm_create_mesh_indexed(base, s->nnodes, s->node_xy, s->npolygons, st, n, out);
    free(nodes), free(start);
    return status;
}

/* `one` (indices from `base`) is the mesh `zero` (from 0) is: the same
 * shape and faces (its cells `base` more, base - 1 on the domain edge), the
 * same stable step, and the same heights, ledger and face fluxes, bit for
 * bit, after the same steps with the same edge kinds and levels. Destroys
 * both. */
static void require_same_mesh(dpsm_grid *zero, dpsm_grid *one, int base, const double *h, const char *what) {
    int64_t nx0, ny0, nx1, ny1, nf0, nf1;
    CHECK_OK(zero, dpsm_get_shape(zero, &nx0, &ny0));
    CHECK_OK(one, dpsm_get_shape(one, &nx1, &ny1));
    CHECK_OK(zero, dpsm_get_face_count(zero, &nf0));
    CHECK_OK(one, dpsm_get_face_count(one, &nf1));
    REQUIRE(nx0 == nx1 && ny0 == ny1 && nf0 == nf1, "%s: %lld x %lld with %lld faces from 0, %lld x %lld with %lld from %d",
            what, (long long)nx0, (long long)ny0, (long long)nf0, (long long)nx1, (long long)ny1, (long long)nf1, base);
    int64_t *f0 = calloc((size_t)(2 * nf0), sizeof(int64_t)), *f1 = calloc((size_t)(2 * nf0), sizeof(int64_t));
    CHECK_OK(zero, dpsm_get_mesh_faces(zero, f0));
    CHECK_OK(one, dpsm_get_mesh_faces(one, f1));
    int edges = 0;
    for (int64_t k = 0; k < 2 * nf0; ++k) {
        REQUIRE(f1[k] == f0[k] + base, "%s: face_cells[%lld] is %lld from 0 but %lld from %d", what, (long long)k,
                (long long)f0[k], (long long)f1[k], base);
        edges += f1[k] == base - 1;
    }
    REQUIRE(edges > 0 && f1[0] >= base, "%s: from %d, the domain edge is %d (%d faces on it)", what, base, base - 1,
            edges);
    double dt0, dt1;
    CHECK_OK(zero, dpsm_stable_dt(zero, &dt0));
    CHECK_OK(one, dpsm_stable_dt(one, &dt1));
    REQUIRE(dt0 == dt1, "%s: stable step %.17g from 0, %.17g from %d", what, dt0, dt1, base);
    uint8_t *kinds = malloc((size_t)nf0);
    double *levels = calloc((size_t)nf0, sizeof(double));
    for (int64_t f = 0; f < nf0; ++f) kinds[f] = f % 2 ? DPSM_OPEN : DPSM_WALL, levels[f] = 0.5 * (double)(f % 3);
    dpsm_grid *both[2] = {zero, one};
    for (int k = 0; k < 2; ++k) {
        CHECK_OK(both[k], dpsm_set_repose_angle(both[k], 30.0 * kDeg));
        CHECK_OK(both[k], dpsm_set_edge_kinds(both[k], kinds));
        CHECK_OK(both[k], dpsm_set_side_levels(both[k], DPSM_MESH_EDGE, levels));
        CHECK_OK(both[k], dpsm_set_face_flux_recording(both[k], 1));
        CHECK_OK(both[k], dpsm_set_heights(both[k], h));
        for (int call = 0; call < 5; ++call) CHECK_OK(both[k], dpsm_step(both[k], 0.1));
    }
    double *h0 = calloc((size_t)nx0, sizeof(double)), *h1 = calloc((size_t)nx0, sizeof(double));
    double *x0 = calloc((size_t)nf0, sizeof(double)), *x1 = calloc((size_t)nf0, sizeof(double));
    CHECK_OK(zero, dpsm_get_heights(zero, h0));
    CHECK_OK(one, dpsm_get_heights(one, h1));
    CHECK_OK(zero, dpsm_get_face_fluxes(zero, x0, NULL));
    CHECK_OK(one, dpsm_get_face_fluxes(one, x1, NULL));
    REQUIRE(memcmp(h0, h1, sizeof(double) * (size_t)nx0) == 0, "%s: the heights differ after the same steps", what);
    REQUIRE(memcmp(x0, x1, sizeof(double) * (size_t)nf0) == 0, "%s: the face fluxes differ", what);
    REQUIRE(mass_of(zero, DPSM_MASS_OUTFLOW) == mass_of(one, DPSM_MASS_OUTFLOW) && mass_of(zero, DPSM_MASS_OUTFLOW) != 0.0,
            "%s: outflow %.17g from 0, %.17g from %d", what, mass_of(zero, DPSM_MASS_OUTFLOW),
            mass_of(one, DPSM_MASS_OUTFLOW), base);
    free(f0), free(f1), free(kinds), free(levels), free(h0), free(h1), free(x0), free(x1);
    dpsm_destroy(zero), dpsm_destroy(one);
}

static void test_indexed_same_as_from_zero(void **state) {
    (void)state;
    /* Polygons and the dual: the plain constructor, _indexed(0) and _indexed(1). */
    const scene_kind kinds[2] = {SCENE_TRIANGLES, SCENE_DUAL};
    for (int k = 0; k < 2; ++k) {
        mesh_scene s = scene_make(kinds[k], 12, 2.5, 5u);
        double *h = column_heights(&s, 1.0, 0.8);
        for (int base = 0; base < 2; ++base) {
            dpsm_grid *plain = NULL, *indexed = NULL;
            CHECK_OK(NULL, scene_create(&s, &plain));
            CHECK_OK(NULL, scene_create_from(&s, base, &indexed));
            require_same_mesh(plain, indexed, base, h, scene_name(kinds[k]));
        }
        free(h);
        scene_free(&s);
    }
    /* The graph. */
    const int n = 10;
    mesh_scene s = scene_make(SCENE_QUADS, n, 2.5, 1u);
    quad_graph q = quad_graph_make(n, 2.5);
    int64_t *cells1 = from_one(q.face_cells, 2 * q.nfaces);
    dpsm_grid *zero = NULL, *one = NULL;
    CHECK_OK(NULL, dpsm_create_graph(q.ncells, q.cell_xy, q.area, q.nfaces, q.face_cells, q.face_xy, q.length, &zero));
    CHECK_OK(NULL, dpsm_create_graph_indexed(1, q.ncells, q.cell_xy, q.area, q.nfaces, cells1, q.face_xy, q.length, &one));
    /* A restart file keeps the graph as given, from 1 (the mesh record's
     * face_cells as the host's, the file of version 6). */
    char path[64];
    snprintf(path, sizeof path, "test_mesh_graph_%d.dpsm", (int)getpid());
    CHECK_OK(one, dpsm_save(one, path));
    REQUIRE(file_version(path) == 6u, "a graph from 1 is saved as version %u, not 6", file_version(path));
    dpsm_grid *loaded = NULL;
    CHECK_OK(NULL, dpsm_load(path, &loaded));
    remove(path);
    int64_t *fa = calloc((size_t)(2 * q.nfaces), sizeof(int64_t)), *fb = calloc((size_t)(2 * q.nfaces), sizeof(int64_t));
    CHECK_OK(one, dpsm_get_mesh_faces(one, fa));
    CHECK_OK(loaded, dpsm_get_mesh_faces(loaded, fb));
    REQUIRE(memcmp(fa, fb, sizeof(int64_t) * (size_t)(2 * q.nfaces)) == 0 && memcmp(fa, cells1, sizeof(int64_t) * 2) == 0,
            "the loaded graph lists other faces than the saved one from 1");
    free(fa), free(fb);
    dpsm_destroy(loaded);
    double *h = column_heights(&s, 1.0, 0.8);
    require_same_mesh(zero, one, 1, h, "graph");
    free(h), free(cells1);
    quad_graph_free(&q);
    scene_free(&s);
}

/* The message of the last failure (on g; NULL: of a constructor) names `what`. */
static void require_named(const dpsm_grid *g, const char *what) {
    REQUIRE(strstr(dpsm_last_error(g), what) != NULL, "message '%s' does not name '%s'", dpsm_last_error(g), what);
}

static void test_indexed_bad_inputs(void **state) {
    (void)state;
    dpsm_grid *g = NULL;
    int64_t *start1 = from_one(kQuadStart, 5), *cells1 = from_one(kQuadCells, 16);
    const double cell_xy[4] = {0.5, 0.5, 1.5, 0.5}, area[2] = {1, 1};
    const int64_t face_cells[14] = {0, 1, 0, -1, 0, -1, 0, -1, 1, -1, 1, -1, 1, -1};
    const double face_xy[14] = {1, 0.5, 0, 0.5, 0.5, 0, 0.5, 1, 2, 0.5, 1.5, 0, 1.5, 1};
    double length[7] = {1, 1, 1, 1, 1, 1, 1};
    int64_t *fc1 = from_one(face_cells, 14);
    const double nodes[10] = {0, 0, 1, 0, 1, 1, 0, 1, 5, 5};
    const int64_t tris[6] = {0, 1, 2, 0, 2, 3};
    int64_t *tris1 = from_one(tris, 6);

    /* A start index other than 0 and 1, with arrays good from either. */
    const int bad_starts[2] = {2, -1};
    for (int k = 0; k < 2; ++k) {
        char named[32];
        snprintf(named, sizeof named, "start_index = %d", bad_starts[k]);
        EXPECT_CREATE_FAIL(dpsm_create_mesh_indexed(bad_starts[k], 9, kQuadNodes, 4, start1, cells1, &g), g,
                           DPSM_ERR_INVALID_VALUE, "dpsm_create_mesh_indexed", named);
        require_named(NULL, "neither 0");
        require_named(NULL, "nor 1");
        EXPECT_CREATE_FAIL(dpsm_create_graph_indexed(bad_starts[k], 2, cell_xy, area, 7, fc1, face_xy, length, &g), g,
                           DPSM_ERR_INVALID_VALUE, "dpsm_create_graph_indexed", named);
        require_named(NULL, "nor 1");
        EXPECT_CREATE_FAIL(dpsm_create_dual_mesh_indexed(bad_starts[k], 4, nodes, 2, tris1, &g), g,
                           DPSM_ERR_INVALID_VALUE, "dpsm_create_dual_mesh_indexed", named);
        require_named(NULL, "nor 1");
    }
    REQUIRE(dpsm_create_mesh_indexed(1, 9, kQuadNodes, 4, start1, cells1, NULL) == DPSM_ERR_NULL_POINTER, "out NULL");
    /* Arrays from 0 given as from 1, and the other way round. */
    const char *fn = "dpsm_create_mesh_indexed";
    EXPECT_CREATE_FAIL(dpsm_create_mesh_indexed(1, 9, kQuadNodes, 4, kQuadStart, kQuadCells, &g), g,
                       DPSM_ERR_INVALID_VALUE, fn, "cell_start(1) = 0 must be 1");
    EXPECT_CREATE_FAIL(dpsm_create_mesh_indexed(0, 9, kQuadNodes, 4, start1, cells1, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "cell_start[0] = 1 must be 0");

    /* Polygons from 1: messages count from 1 and quote the host's values. */
    int64_t cells[16];
    memcpy(cells, cells1, sizeof cells);
    cells[6] = 10; /* cell 2's third node: node 10 of 9 */
    EXPECT_CREATE_FAIL(dpsm_create_mesh_indexed(1, 9, kQuadNodes, 4, start1, cells, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "cell_nodes(7) = 10 is not a node index in [1, 9]");
    cells[6] = 0;
    EXPECT_CREATE_FAIL(dpsm_create_mesh_indexed(1, 9, kQuadNodes, 4, start1, cells, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "cell_nodes(7) = 0 is not a node index in [1, 9]");
    cells[6] = INT64_MIN; /* no overflow on the way to 0-based */
    EXPECT_CREATE_FAIL(dpsm_create_mesh_indexed(1, 9, kQuadNodes, 4, start1, cells, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "cell_nodes(7) = -9223372036854775808 is not");
    memcpy(cells, cells1, sizeof cells);
    cells[9] = 4, cells[10] = 5; /* cell 3 becomes 4, 4, 5, 7: a node repeated in a row */
    EXPECT_CREATE_FAIL(dpsm_create_mesh_indexed(1, 9, kQuadNodes, 4, start1, cells, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "cell 3 repeats node 4");
    const int64_t short_start[5] = {1, 5, 9, 13, 15};
    EXPECT_CREATE_FAIL(dpsm_create_mesh_indexed(1, 9, kQuadNodes, 4, short_start, cells1, &g), g,
                       DPSM_ERR_INVALID_VALUE, fn, "cell 4 has 2 nodes (cell_start(4) = 13, cell_start(5) = 15)");
    const int64_t start2[2] = {1, 5}, two[4] = {1, 2, 1, 2};
    EXPECT_CREATE_FAIL(dpsm_create_mesh_indexed(1, 9, kQuadNodes, 1, start2, two, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "cell 1 has fewer than 3 distinct nodes");
    const int64_t start3[2] = {1, 4}, line[3] = {1, 2, 3};
    EXPECT_CREATE_FAIL(dpsm_create_mesh_indexed(1, 9, kQuadNodes, 1, start3, line, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "cell 1 has zero area");
    const double fan[8] = {0, 0, 1, 0, 0.5, 1, 0.5, -1};
    const int64_t fan_start[4] = {1, 4, 7, 10}, fan_cells[9] = {1, 2, 3, 1, 2, 4, 2, 1, 3};
    EXPECT_CREATE_FAIL(dpsm_create_mesh_indexed(1, 4, fan, 3, fan_start, fan_cells, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "the edge between nodes 1 and 2 is shared by 3 cells (1, 2, 3)");
    double bad_nodes[18];
    memcpy(bad_nodes, kQuadNodes, sizeof bad_nodes);
    bad_nodes[7] = NAN; /* y of the host's node 4 */
    EXPECT_CREATE_FAIL(dpsm_create_mesh_indexed(1, 9, bad_nodes, 4, start1, cells1, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "node_xy(2, 4) (y of node 4)");

    /* The graph from 1: face_cells(2, f) positions, 0 the domain edge. */
    fn = "dpsm_create_graph_indexed";
    int64_t fc[14];
    memcpy(fc, fc1, sizeof fc);
    fc[9] = 3; /* face 5's b: cell 3 of 2 */
    EXPECT_CREATE_FAIL(dpsm_create_graph_indexed(1, 2, cell_xy, area, 7, fc, face_xy, length, &g), g,
                       DPSM_ERR_INVALID_VALUE, fn, "face 5: face_cells(2, 5) = 3 is not a cell index in [1, 2] nor 0 (the domain edge)");
    fc[9] = -1; /* C's domain edge is no index from 1 */
    EXPECT_CREATE_FAIL(dpsm_create_graph_indexed(1, 2, cell_xy, area, 7, fc, face_xy, length, &g), g,
                       DPSM_ERR_INVALID_VALUE, fn, "face_cells(2, 5) = -1 is not a cell index");
    fc[9] = 0, fc[2] = 0; /* face 2's a on the domain edge */
    EXPECT_CREATE_FAIL(dpsm_create_graph_indexed(1, 2, cell_xy, area, 7, fc, face_xy, length, &g), g,
                       DPSM_ERR_INVALID_VALUE, fn, "face 2: face_cells(1, 2) = 0 is not a cell index in [1, 2]");
    fc[2] = INT64_MAX;
    EXPECT_CREATE_FAIL(dpsm_create_graph_indexed(1, 2, cell_xy, area, 7, fc, face_xy, length, &g), g,
                       DPSM_ERR_INVALID_VALUE, fn, "face_cells(1, 2) = 9223372036854775807 is not");
    memcpy(fc, fc1, sizeof fc);
    fc[1] = 1;
    EXPECT_CREATE_FAIL(dpsm_create_graph_indexed(1, 2, cell_xy, area, 7, fc, face_xy, length, &g), g,
                       DPSM_ERR_INVALID_VALUE, fn, "face 1 joins cell 1 to itself");
    const double no_area[2] = {1, 0};
    EXPECT_CREATE_FAIL(dpsm_create_graph_indexed(1, 2, cell_xy, no_area, 7, fc1, face_xy, length, &g), g,
                       DPSM_ERR_INVALID_VALUE, fn, "cell_area(2) (cell 2) = 0");
    length[3] = -1;
    EXPECT_CREATE_FAIL(dpsm_create_graph_indexed(1, 2, cell_xy, area, 7, fc1, face_xy, length, &g), g,
                       DPSM_ERR_INVALID_VALUE, fn, "face_length(4) (face 4) = -1");
    length[3] = 1;
    EXPECT_CREATE_FAIL(dpsm_create_graph_indexed(1, 2, cell_xy, area, 4, fc1, face_xy, length, &g), g,
                       DPSM_ERR_INVALID_VALUE, fn, "the faces of cell 2 (");
    require_named(NULL, "domain edges with b = 0");

    /* The dual from 1: nodes and triangles from 1. */
    fn = "dpsm_create_dual_mesh_indexed";
    EXPECT_CREATE_FAIL(dpsm_create_dual_mesh_indexed(1, 5, nodes, 2, tris1, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "node 5 belongs to no triangle");
    const int64_t flat[3] = {1, 2, 2};
    EXPECT_CREATE_FAIL(dpsm_create_dual_mesh_indexed(1, 4, nodes, 1, flat, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "triangle 1 has fewer than 3 distinct nodes");
    const int64_t out_of_range[6] = {1, 2, 3, 1, 3, 8};
    EXPECT_CREATE_FAIL(dpsm_create_dual_mesh_indexed(1, 4, nodes, 2, out_of_range, &g), g, DPSM_ERR_INVALID_VALUE, fn,
                       "triangle_nodes(3, 2) (triangle 2) = 8 is not a node index in [1, 4]");
    free(start1), free(cells1), free(fc1), free(tris1);
}

/* A mesh from 1 names its cells and faces from 1 after its constructor too,
 * and lists its faces from 1. */
static void test_indexed_later_messages(void **state) {
    (void)state;
    dpsm_grid *g = NULL;
    int64_t *start1 = from_one(kQuadStart, 5), *cells1 = from_one(kQuadCells, 16);
    CHECK_OK(NULL, dpsm_create_mesh_indexed(1, 9, kQuadNodes, 4, start1, cells1, &g));
    int64_t faces[24];
    CHECK_OK(g, dpsm_get_mesh_faces(g, faces));
    /* Faces as they first appear, cell by cell (test_create_mesh_quads): cell 1's four first. */
    int64_t an_edge = -1;
    for (int f = 0; f < 12; ++f) {
        REQUIRE(faces[2 * f] >= 1 && faces[2 * f] <= 4 && faces[2 * f + 1] >= 0 && faces[2 * f + 1] <= 4,
                "face %d joins %lld and %lld: not cells from 1 and 0 for the edge", f, (long long)faces[2 * f],
                (long long)faces[2 * f + 1]);
        if (f < 4) REQUIRE(faces[2 * f] == 1, "face %d belongs to cell %lld, not 1", f, (long long)faces[2 * f]);
        if (faces[2 * f + 1] == 0 && f > 4 && an_edge < 0) an_edge = f;
    }
    uint8_t edges[12];
    memset(edges, DPSM_WALL, sizeof edges);
    edges[an_edge] = 5;
    char named[64];
    snprintf(named, sizeof named, "kinds(%lld) (face %lld, on the domain edge) = 5", (long long)an_edge + 1,
             (long long)an_edge + 1);
    EXPECT_FAIL_ON(g, dpsm_set_edge_kinds(g, edges), DPSM_ERR_UNKNOWN_ENUM, named);
    double levels[12] = {0};
    levels[an_edge] = INFINITY;
    snprintf(named, sizeof named, "levels(%lld) (face %lld) is +Inf", (long long)an_edge + 1, (long long)an_edge + 1);
    EXPECT_FAIL_ON(g, dpsm_set_side_levels(g, DPSM_MESH_EDGE, levels), DPSM_ERR_INVALID_VALUE, named);
    double h[4] = {1, 2, NAN, 4};
    EXPECT_FAIL_ON(g, dpsm_set_heights(g, h), DPSM_ERR_INVALID_VALUE, "h(3) (cell 3) is NaN");
    uint8_t kinds[4] = {0, 0, 7, 0};
    EXPECT_FAIL_ON(g, dpsm_set_cell_kinds(g, kinds), DPSM_ERR_UNKNOWN_ENUM, "kinds(3) (cell 3) = 7");
    double theta[4] = {0.5, 0.5, 0.5, 2.0};
    EXPECT_FAIL_ON(g, dpsm_set_repose_angle_field(g, theta), DPSM_ERR_INVALID_VALUE, "theta_radians(4) (cell 4) = 2");
    const double bed[4] = {0, 3, 0, 0};
    CHECK_OK(g, dpsm_set_bedrock(g, bed));
    h[2] = 3;
    EXPECT_FAIL_ON(g, dpsm_set_heights(g, h), DPSM_ERR_INVALID_VALUE, "h(2) puts cell 2 at 2, below its bed");
    dpsm_destroy(g);
    free(start1), free(cells1);
}

/* ------------------------------------------------------------------------ */
/* Numerics                                                                  */
/* ------------------------------------------------------------------------ */

/* A column on the scene's mesh (its indices from `base`: 0 through the
 * plain constructors, 1 through the _indexed ones). */
static dpsm_grid *column_mesh(const mesh_scene *s, int open, int base) {
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, base ? scene_create_from(s, base, &g) : scene_create(s, &g));
    CHECK_OK(g, dpsm_set_repose_angle(g, 30.0 * kDeg));
    if (open) CHECK_OK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN));
    double *h = column_heights(s, 1.0, 0.5);
    CHECK_OK(g, dpsm_set_heights(g, h));
    free(h);
    return g;
}

static void test_column_rests_with_mass_and_bounds(void **state) {
    (void)state;
    const scene_kind kinds[4] = {SCENE_QUADS, SCENE_TRIANGLES, SCENE_HEXAGONS, SCENE_DUAL};
    for (int k = 0; k < 4; ++k) {
        mesh_scene s = scene_make(kinds[k], 24, 2.5, 7u);
        dpsm_grid *g = column_mesh(&s, 0, 0);
        const double before = mass_of(g, DPSM_MASS_TOTAL);
        int rested = 0;
        double *h = calloc((size_t)s.cells, sizeof(double));
        for (int call = 0; call < 200 && !rested; ++call) {
            CHECK_OK(g, dpsm_step(g, 0.05));
            rested = step_info_of(g, DPSM_INFO_AT_REST) > 0.0;
            CHECK_OK(g, dpsm_get_heights(g, h));
            REQUIRE(max_of(h, (size_t)s.cells) <= 0.5 && min_of(h, (size_t)s.cells) >= 0.0,
                    "%s: a new extremum: heights in [%.17g, %.17g]", scene_name(kinds[k]), min_of(h, (size_t)s.cells),
                    max_of(h, (size_t)s.cells));
        }
        REQUIRE(rested, "%s: the column collapse did not rest within t = 10", scene_name(kinds[k]));
        const double after = mass_of(g, DPSM_MASS_TOTAL);
        REQUIRE(fabs(after - before) <= 1e-13 * before, "%s: mass %.17g became %.17g", scene_name(kinds[k]), before,
                after);
        REQUIRE(ledger_residual(g) < 1e-13, "%s: the ledger does not close: %g", scene_name(kinds[k]), ledger_residual(g));
        /* at rest, a later step changes nothing */
        double *again = calloc((size_t)s.cells, sizeof(double));
        CHECK_OK(g, dpsm_step(g, 1.0));
        CHECK_OK(g, dpsm_get_heights(g, again));
        REQUIRE(memcmp(h, again, sizeof(double) * (size_t)s.cells) == 0, "%s: a step at rest moved sand",
                scene_name(kinds[k]));
        REQUIRE(step_info_of(g, DPSM_INFO_CELL_UPDATES) == 0.0, "%s: a step at rest visited %g cells",
                scene_name(kinds[k]), step_info_of(g, DPSM_INFO_CELL_UPDATES));
        free(again);
        free(h);
        dpsm_destroy(g);
        scene_free(&s);
    }
}

/* A rough surface (random heights) on skewed cells, stepped at the stable
 * sub-step: every sand cell stays within the range of the heights before each
 * step (the flux's factor held within the sub-step's bound). */
static void test_no_new_extremum_on_rough_surfaces(void **state) {
    (void)state;
    const scene_kind kinds[3] = {SCENE_TRIANGLES, SCENE_DUAL, SCENE_HEXAGONS};
    for (int k = 0; k < 3; ++k) {
        mesh_scene s = scene_make(kinds[k], 24, 1.0, 17u);
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, scene_create(&s, &g));
        double *h = calloc((size_t)s.cells, sizeof(double));
        unsigned seed = 99u;
        for (int64_t c = 0; c < s.cells; ++c) {
            seed = seed * 1103515245u + 12345u;
            h[c] = 0.12 * ((seed >> 8) & 0xFFFF) / 65536.0; /* slopes near where the flux law is stiffest */
        }
        CHECK_OK(g, dpsm_set_heights(g, h));
        double dt = 0.0;
        CHECK_OK(g, dpsm_stable_dt(g, &dt));
        for (int step = 0; step < 30; ++step) {
            const double lo = min_of(h, (size_t)s.cells), hi = max_of(h, (size_t)s.cells);
            CHECK_OK(g, dpsm_step(g, dt));
            CHECK_OK(g, dpsm_get_heights(g, h));
            REQUIRE(min_of(h, (size_t)s.cells) >= lo && max_of(h, (size_t)s.cells) <= hi,
                    "%s, step %d: heights [%.17g, %.17g] left [%.17g, %.17g]", scene_name(kinds[k]), step,
                    min_of(h, (size_t)s.cells), max_of(h, (size_t)s.cells), lo, hi);
        }
        free(h);
        dpsm_destroy(g);
        scene_free(&s);
    }
}

static void test_exact_states(void **state) {
    (void)state;
    mesh_scene s = scene_make(SCENE_TRIANGLES, 16, 1.0, 3u);
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, scene_create(&s, &g));
    CHECK_OK(g, dpsm_set_repose_angle(g, 30.0 * kDeg));
    /* A plane at 0.9 tan(theta) in a direction of no face in particular. */
    double *h = calloc((size_t)s.cells, sizeof(double)), *after = calloc((size_t)s.cells, sizeof(double));
    const double slope = 0.9 * tan(30.0 * kDeg);
    for (int64_t c = 0; c < s.cells; ++c) h[c] = 2.0 + slope * (0.6 * s.cx[c] + 0.8 * s.cy[c]);
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_step(g, 1.0));
    CHECK_OK(g, dpsm_get_heights(g, after));
    REQUIRE(memcmp(h, after, sizeof(double) * (size_t)s.cells) == 0, "a plane below the angle of repose moved");
    REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) > 0.0, "a plane below the angle of repose is not at rest");
    /* A flat surface under a uniform source rises by q dt everywhere. */
    double *q = calloc((size_t)s.cells, sizeof(double)), *flat = calloc((size_t)s.cells, sizeof(double));
    for (int64_t c = 0; c < s.cells; ++c) q[c] = 0.25, flat[c] = 1.0;
    CHECK_OK(g, dpsm_set_heights(g, flat));
    CHECK_OK(g, dpsm_set_source(g, q));
    CHECK_OK(g, dpsm_step(g, 2.0));
    CHECK_OK(g, dpsm_get_heights(g, after));
    for (int64_t c = 0; c < s.cells; ++c)
        REQUIRE(fabs(after[c] - 1.5) < 1e-14, "cell %lld: %.17g after a uniform source of 0.25 over 2, expected 1.5",
                (long long)c, after[c]);
    REQUIRE(ledger_residual(g) < 1e-14, "ledger %g", ledger_residual(g));
    free(q), free(flat), free(h), free(after);
    dpsm_destroy(g);
    scene_free(&s);
}

/* A plane at exactly the angle of repose, in a direction of no face in
 * particular, is a rest state on every kind of mesh: a step leaves it as it
 * was, bit for bit (the reconstructed slope of a plane is exact, so no face
 * may find it steeper than the threshold). */
static void test_plane_at_the_angle_of_repose_rests(void **state) {
    (void)state;
    const scene_kind kinds[4] = {SCENE_QUADS, SCENE_TRIANGLES, SCENE_HEXAGONS, SCENE_DUAL};
    for (int k = 0; k < 4; ++k) {
        mesh_scene s = scene_make(kinds[k], 16, 1.0, 5u);
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, scene_create(&s, &g));
        CHECK_OK(g, dpsm_set_repose_angle(g, 30.0 * kDeg));
        CHECK_OK(g, dpsm_set_rest_tolerance(g, 1e-6));
        double *h = calloc((size_t)s.cells, sizeof(double)), *after = calloc((size_t)s.cells, sizeof(double));
        const double slope = tan(30.0 * kDeg);
        for (int64_t c = 0; c < s.cells; ++c) h[c] = 2.0 + slope * (0.6 * s.cx[c] + 0.8 * s.cy[c]);
        CHECK_OK(g, dpsm_set_heights(g, h));
        CHECK_OK(g, dpsm_step(g, 1.0));
        CHECK_OK(g, dpsm_get_heights(g, after));
        REQUIRE(memcmp(h, after, sizeof(double) * (size_t)s.cells) == 0, "%s: a plane at the angle of repose moved",
                scene_name(kinds[k]));
        REQUIRE(step_info_of(g, DPSM_INFO_AT_REST) > 0.0, "%s: a plane at the angle of repose is not at rest",
                scene_name(kinds[k]));
        free(h), free(after);
        dpsm_destroy(g);
        scene_free(&s);
    }
}

/* A slope that runs along a wall drains as it does away from one: a ridge
 * across a mesh of squares walled on every side (and across a row of wall
 * cells through its middle) collapses the same in every row, the rows
 * beside the walls included. A face between a sand cell and a wall carries
 * nothing, but the slope along it counts in the faces' energy; without it
 * the rows beside a wall lag (by 6e-3 of the ridge's height here) and rest
 * last. */
static void test_slope_along_a_wall_drains_as_away_from_it(void **state) {
    (void)state;
    const int n = 24;
    mesh_scene s = scene_make(SCENE_QUADS, n, 1.0, 3u);
    for (int wall_row = 0; wall_row < 2; ++wall_row) {
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, scene_create(&s, &g));
        CHECK_OK(g, dpsm_set_repose_angle(g, 30.0 * kDeg));
        CHECK_OK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_WALL));
        double *h = calloc((size_t)s.cells, sizeof(double)), *after = calloc((size_t)s.cells, sizeof(double));
        uint8_t *kinds = calloc((size_t)s.cells, 1);
        /* The row of wall cells: those whose centres lie in the band |y| < spacing / 2 (no
         * centre lies on y = 0 for even n, so the band takes the row just above it). */
        const double spacing = 2.0 / n;
        for (int64_t c = 0; c < s.cells; ++c) {
            h[c] = fabs(s.cx[c]) < 0.3 ? 1.0 : 0.0;
            if (wall_row && s.cy[c] > 0.0 && s.cy[c] < spacing) kinds[c] = DPSM_CELL_WALL;
        }
        CHECK_OK(g, dpsm_set_cell_kinds(g, kinds));
        CHECK_OK(g, dpsm_set_heights(g, h));
        for (int call = 0; call < 10; ++call) CHECK_OK(g, dpsm_step(g, 0.05));
        CHECK_OK(g, dpsm_get_heights(g, after));
        /* Every sand cell against the sand cell of its column nearest y = -0.5 (a row with sand on both sides). */
        double largest = 0.0, moved = 0.0;
        for (int64_t c = 0; c < s.cells; ++c) {
            if (kinds[c] == DPSM_CELL_WALL) continue;
            int64_t reference = -1;
            for (int64_t o = 0; o < s.cells; ++o)
                if (fabs(s.cx[o] - s.cx[c]) < 1e-9 &&
                    (reference < 0 || fabs(s.cy[o] + 0.5) < fabs(s.cy[reference] + 0.5)))
                    reference = o;
            largest = fmax(largest, fabs(after[c] - after[reference]));
            moved = fmax(moved, fabs(after[c] - h[c]));
        }
        REQUIRE(moved > 0.1, "the ridge did not collapse (largest change %g)", moved);
        REQUIRE(largest <= 1e-12, "%s: the rows differ by up to %.3g after the same collapse",
                wall_row ? "walled edges and a row of wall cells" : "walled edges", largest);
        free(h), free(after), free(kinds);
        dpsm_destroy(g);
    }
    scene_free(&s);
}

/* The same on hexagons, whose cells meet a straight wall at an angle:
 * there the slope on a cell's side of a wall face is the cell's whole
 * gradient, not its part along the face. A ridge across 24 x 24 hexagons
 * walled all round drains as on the grid engine's 24 x 24 cells: after 4
 * time units its largest excess slope is 0.91 times the grid's (with the
 * slope along the wall faces alone, 4.4 times: the cells beside the walls
 * lag). */
static void test_ridge_between_walls_drains_as_on_the_grid(void **state) {
    (void)state;
    const int n = 24;
    const double half = 2.5, spacing = 2.0 * half / n;
    double excess[2] = {0.0, 0.0};
    mesh_scene s = scene_make(SCENE_HEXAGONS, n, half, 3u);
    for (int on_grid = 0; on_grid < 2; ++on_grid) {
        dpsm_grid *g = NULL;
        const int64_t cells = on_grid ? (int64_t)n * n : s.cells;
        double *h = calloc((size_t)cells, sizeof(double));
        if (on_grid) {
            CHECK_OK(NULL, dpsm_create_2d(n, n, spacing, spacing, &g));
            for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side) CHECK_OK(g, dpsm_set_boundary(g, side, DPSM_WALL));
            for (int64_t c = 0; c < cells; ++c) h[c] = fabs(-half + (c % n + 0.5) * spacing) < 0.6 ? 2.0 : 0.0;
        } else {
            CHECK_OK(NULL, scene_create(&s, &g));
            CHECK_OK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_WALL));
            for (int64_t c = 0; c < cells; ++c) h[c] = fabs(s.cx[c]) < 0.6 ? 2.0 : 0.0;
        }
        CHECK_OK(g, dpsm_set_repose_angle(g, 30.0 * kDeg));
        CHECK_OK(g, dpsm_set_heights(g, h));
        for (int call = 0; call < 40; ++call) CHECK_OK(g, dpsm_step(g, 0.1));
        excess[on_grid] = step_info_of(g, DPSM_INFO_MAX_EXCESS_SLOPE);
        free(h);
        dpsm_destroy(g);
    }
    scene_free(&s);
    print_message("ridge between walls at t = 4: largest excess slope %.3g on hexagons, %.3g on the grid\n", excess[0], excess[1]);
    REQUIRE(excess[1] > 0.0, "the grid's ridge rested before t = 4: the scene tests nothing");
    REQUIRE(excess[0] <= 1.5 * excess[1], "hexagons: the largest excess slope at t = 4 is %.3g, %.2f times the grid's %.3g",
            excess[0], excess[0] / excess[1], excess[1]);
}

/* The column on a copy of the mesh turned by 30 degrees about the column's
 * axis is the same scene: the heights agree cell by cell to round-off on
 * every kind of mesh (the library orders the turned mesh's cells otherwise,
 * so sums are taken in another order; only a choice bound to the axes could
 * make the deposits differ by more). */
static void test_turned_mesh_same_deposit(void **state) {
    (void)state;
    const scene_kind kinds[4] = {SCENE_QUADS, SCENE_TRIANGLES, SCENE_HEXAGONS, SCENE_DUAL};
    for (int k = 0; k < 4; ++k) {
        mesh_scene s = scene_make(kinds[k], 24, 2.5, 7u), t = scene_make(kinds[k], 24, 2.5, 7u);
        scene_rotate(&t, 30.0 * kDeg);
        double *h[2];
        const mesh_scene *scenes[2] = {&s, &t};
        for (int which = 0; which < 2; ++which) {
            dpsm_grid *g = NULL;
            CHECK_OK(NULL, scene_create(scenes[which], &g));
            CHECK_OK(g, dpsm_set_repose_angle(g, 30.0 * kDeg));
            CHECK_OK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN));
            /* the heights from the unturned centres: each cell holds the same sand on both */
            double *start = column_heights(&s, 1.0, 0.5);
            CHECK_OK(g, dpsm_set_heights(g, start));
            free(start);
            for (int call = 0; call < 40; ++call) CHECK_OK(g, dpsm_step(g, 0.05));
            h[which] = calloc((size_t)s.cells, sizeof(double));
            CHECK_OK(g, dpsm_get_heights(g, h[which]));
            dpsm_destroy(g);
        }
        double largest = 0.0, moved = 0.0;
        double *start = column_heights(&s, 1.0, 0.5);
        for (int64_t c = 0; c < s.cells; ++c) {
            largest = fmax(largest, fabs(h[0][c] - h[1][c]));
            moved = fmax(moved, fabs(h[0][c] - start[c]));
        }
        REQUIRE(moved > 0.05, "%s: the column did not slide (largest change %g)", scene_name(kinds[k]), moved);
        REQUIRE(largest <= 1e-12, "%s: the turned mesh's deposit differs by up to %.3g (cell by cell)",
                scene_name(kinds[k]), largest);
        free(start), free(h[0]), free(h[1]);
        scene_free(&s), scene_free(&t);
    }
}

/* The foot of the exact deposit of the column (radius 1, height 0.5, 30
 * degrees): a truncated cone that keeps the volume. */
static double column_foot(void) {
    return scene_column_foot(tan(30.0 * kDeg));
}

/* The column (open edge) on the scene's mesh stepped to rest: its heights,
 * which the caller frees. */
static double *column_at_rest(const mesh_scene *s) {
    dpsm_grid *g = column_mesh(s, 1, 0);
    int rested = 0;
    for (int call = 0; call < 400 && !rested; ++call) {
        CHECK_OK(g, dpsm_step(g, 0.05));
        rested = step_info_of(g, DPSM_INFO_AT_REST) > 0.0;
    }
    REQUIRE(rested, "%s, %lld cells: the column did not rest by t = 20", scene_name(s->kind), (long long)s->cells);
    double *h = calloc((size_t)s->cells, sizeof(double));
    CHECK_OK(g, dpsm_get_heights(g, h));
    dpsm_destroy(g);
    return h;
}

/* The column at rest: its L1 difference from the exact deposit over the
 * column's volume. */
static double column_error(const mesh_scene *s) {
    const double pi = 3.14159265358979323846, alpha = tan(30.0 * kDeg), foot = column_foot();
    double *h = column_at_rest(s), error = 0.0;
    for (int64_t c = 0; c < s->cells; ++c)
        error += fabs(h[c] - fmin(0.5, fmax(0.0, alpha * (foot - hypot(s->cx[c], s->cy[c]))))) * s->area[c];
    free(h);
    return error / (pi * 0.5);
}

/* The deposit converges: on every kind of mesh, halving the cells' size
 * divides the error by at least 2 (an order-1 method's factor). */
static void test_error_falls_with_the_cells(void **state) {
    (void)state;
#ifdef DPSM_TESTS_UNDER_ASAN
    /* A numerical claim, checked in the main stage; under AddressSanitizer its
     * eight runs to rest would take 45 s of the stage for passes that
     * test_column_rests_with_mass_and_bounds already runs. */
    skip();
#endif
    const scene_kind kinds[4] = {SCENE_QUADS, SCENE_TRIANGLES, SCENE_HEXAGONS, SCENE_DUAL};
    for (int k = 0; k < 4; ++k) {
        double error[2];
        for (int level = 0; level < 2; ++level) {
            mesh_scene s = scene_make(kinds[k], 24 << level, 2.5, 7u);
            error[level] = column_error(&s);
            scene_free(&s);
        }
        printf("  %s: L1 error over the volume %.4f %% at 24, %.4f %% at 48 (order %.2f)\n", scene_name(kinds[k]),
               100.0 * error[0], 100.0 * error[1], log2(error[0] / error[1]));
        REQUIRE(error[1] * 2.0 <= error[0], "%s: halving the cells took the error from %.4g only to %.4g",
                scene_name(kinds[k]), error[0], error[1]);
    }
}

/* The column collapse on every kind of mesh lays no sand beyond the toe of
 * its deposit: no cell whose centre lies more than half a cell beyond the
 * exact foot holds any (at most 0.03 today). The gradient flow's pair terms
 * reach across faces that are not steep; before a cell at rest in a hollow
 * refused them, they left films 0.79 to 1.10 cells beyond the foot on every
 * kind (from 1e-35 on hexagons to 7e-4 on the median dual). */
static void test_no_sand_beyond_the_toe(void **state) {
    (void)state;
#ifdef DPSM_TESTS_UNDER_ASAN
    /* A numerical claim, checked in the main stage; the limiter's code runs
     * under AddressSanitizer in every other column of this file. */
    skip();
#endif
    const double foot = column_foot();
    const scene_kind kinds[4] = {SCENE_QUADS, SCENE_TRIANGLES, SCENE_HEXAGONS, SCENE_DUAL};
    for (int k = 0; k < 4; ++k) {
        mesh_scene s = scene_make(kinds[k], 24, 2.5, 7u);
        double *h = column_at_rest(&s);
        const double size = scene_mean_size(&s);
        double farthest = -1e300, film = 0.0;
        for (int64_t c = 0; c < s.cells; ++c) {
            const double beyond = (hypot(s.cx[c], s.cy[c]) - foot) / size;
            if (h[c] > 0.0 && beyond > farthest) farthest = beyond, film = h[c];
        }
        printf("  %s: the farthest sand %.2f cells beyond the foot (%.3g)\n", scene_name(kinds[k]), farthest, film);
        REQUIRE(farthest <= 0.5, "%s: sand of %.3g lies %.2f cells beyond the foot", scene_name(kinds[k]), film,
                farthest);
        free(h);
        scene_free(&s);
    }
}

/* The same mesh with its cells given in reverse order steps to the same heights, cell by cell. */
static void test_host_order(void **state) {
    (void)state;
    mesh_scene s = scene_make(SCENE_TRIANGLES, 20, 2.5, 11u);
    const int64_t n = s.cells;
    int64_t *start = calloc((size_t)n + 1, sizeof(int64_t)), *nodes = calloc((size_t)s.cell_start[n], sizeof(int64_t));
    int64_t k = 0;
    for (int64_t c = 0; c < n; ++c) {
        const int64_t from = n - 1 - c;
        start[c] = k;
        /* and each cell's nodes turned the other way */
        for (int64_t v = s.cell_start[from + 1] - 1; v >= s.cell_start[from]; --v) nodes[k++] = s.cell_nodes[v];
    }
    start[n] = k;
    double *h = column_heights(&s, 1.0, 0.5), *reversed = calloc((size_t)n, sizeof(double));
    for (int64_t c = 0; c < n; ++c) reversed[c] = h[n - 1 - c];
    dpsm_grid *a = NULL, *b = NULL;
    CHECK_OK(NULL, dpsm_create_mesh(s.nnodes, s.node_xy, n, s.cell_start, s.cell_nodes, &a));
    CHECK_OK(NULL, dpsm_create_mesh(s.nnodes, s.node_xy, n, start, nodes, &b));
    CHECK_OK(a, dpsm_set_repose_angle(a, 30.0 * kDeg));
    CHECK_OK(b, dpsm_set_repose_angle(b, 30.0 * kDeg));
    CHECK_OK(a, dpsm_set_heights(a, h));
    CHECK_OK(b, dpsm_set_heights(b, reversed));
    for (int call = 0; call < 5; ++call) {
        CHECK_OK(a, dpsm_step(a, 0.1));
        CHECK_OK(b, dpsm_step(b, 0.1));
    }
    CHECK_OK(a, dpsm_get_heights(a, h));
    CHECK_OK(b, dpsm_get_heights(b, reversed));
    for (int64_t c = 0; c < n; ++c)
        REQUIRE(fabs(h[c] - reversed[n - 1 - c]) <= 1e-12, "cell %lld: %.17g against %.17g given in reverse order",
                (long long)c, h[c], reversed[n - 1 - c]);
    free(start), free(nodes), free(h), free(reversed);
    dpsm_destroy(a), dpsm_destroy(b);
    scene_free(&s);
}

/* The cells of a quad mesh as a graph step as the polygons do. */
static void test_graph_steps_as_polygons(void **state) {
    (void)state;
    const int n = 20;
    const double half = 2.5;
    mesh_scene s = scene_make(SCENE_QUADS, n, half, 1u);
    quad_graph q = quad_graph_make(n, half);
    dpsm_grid *poly = NULL, *graph = NULL;
    CHECK_OK(NULL, scene_create(&s, &poly));
    CHECK_OK(NULL, dpsm_create_graph(q.ncells, q.cell_xy, s.area, q.nfaces, q.face_cells, q.face_xy, q.length, &graph));
    double *h = column_heights(&s, 1.0, 0.5), *hg = calloc((size_t)s.cells, sizeof(double));
    dpsm_grid *both[2] = {poly, graph};
    for (int k = 0; k < 2; ++k) {
        CHECK_OK(both[k], dpsm_set_repose_angle(both[k], 30.0 * kDeg));
        CHECK_OK(both[k], dpsm_set_boundary(both[k], DPSM_MESH_EDGE, DPSM_OPEN));
        CHECK_OK(both[k], dpsm_set_heights(both[k], h));
        for (int call = 0; call < 10; ++call) CHECK_OK(both[k], dpsm_step(both[k], 0.1));
    }
    CHECK_OK(poly, dpsm_get_heights(poly, h));
    CHECK_OK(graph, dpsm_get_heights(graph, hg));
    for (int64_t c = 0; c < s.cells; ++c)
        REQUIRE(fabs(h[c] - hg[c]) <= 1e-12, "cell %lld: polygons %.17g, graph %.17g", (long long)c, h[c], hg[c]);
    REQUIRE(fabs(mass_of(poly, DPSM_MASS_OUTFLOW) - mass_of(graph, DPSM_MASS_OUTFLOW)) <= 1e-12,
            "outflow: polygons %.17g, graph %.17g", mass_of(poly, DPSM_MASS_OUTFLOW), mass_of(graph, DPSM_MASS_OUTFLOW));
    free(h), free(hg);
    quad_graph_free(&q);
    dpsm_destroy(poly), dpsm_destroy(graph);
    scene_free(&s);
}

/* A small pile on a plane just below the angle of repose, a host's edit and
 * a source on a patch, stepped with the active set and with every cell
 * visited. The active region stays a small part of the mesh, so that the
 * steps run on the active set's lists; on the plane a face's slope is decided
 * by its tangential part too, so a cell must wake the cells whose gradients
 * read it (with only the changed cells woken, the heights differ). */
static void run_active_scene_on(dpsm_grid *g, const mesh_scene *s, double *h_out, double *ledger_out) {
    const double tan_theta = tan(30.0 * kDeg);
    CHECK_OK(g, dpsm_set_repose_angle(g, 30.0 * kDeg));
    double *h = calloc((size_t)s->cells, sizeof(double)), *q = calloc((size_t)s->cells, sizeof(double));
    for (int64_t c = 0; c < s->cells; ++c) {
        const double r = hypot(s->cx[c] + 1.0, s->cy[c] + 1.0);
        h[c] = 3.0 + 0.97 * tan_theta * (0.8 * s->cx[c] + 0.6 * s->cy[c]) + (r < 0.3 ? 0.3 : 0.0);
        if (hypot(s->cx[c] - 1.2, s->cy[c] - 0.8) < 0.15) q[c] = 0.4;
    }
    CHECK_OK(g, dpsm_set_heights(g, h));
    for (int call = 0; call < 12; ++call) {
        if (call == 4) {
            CHECK_OK(g, dpsm_get_heights(g, h));
            for (int64_t c = 0; c < s->cells; ++c)
                if (hypot(s->cx[c] - 0.5, s->cy[c] + 1.5) < 0.12) h[c] += 0.2;
            CHECK_OK(g, dpsm_set_heights(g, h));
        }
        if (call == 7) CHECK_OK(g, dpsm_set_source(g, q));
        CHECK_OK(g, dpsm_step(g, 0.03));
    }
    CHECK_OK(g, dpsm_get_heights(g, h_out));
    ledger_out[0] = mass_of(g, DPSM_MASS_TOTAL);
    ledger_out[1] = mass_of(g, DPSM_MASS_OUTFLOW);
    ledger_out[2] = mass_of(g, DPSM_MASS_SOURCED);
    free(h), free(q);
    dpsm_destroy(g);
}

static void run_active_scene(const mesh_scene *s, double *h_out, double *ledger_out) {
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, scene_create(s, &g));
    run_active_scene_on(g, s, h_out, ledger_out);
}

/* The active scene on each mesh kind with and without an environment switch
 * (the two runs in a and b, their ledgers in la and lb); calls check(...) per
 * kind. */
typedef void (*switch_check)(const char *what, const double *a, const double *b, int64_t n, const double *la,
                             const double *lb);
static void run_with_and_without(const char *variable, int n, unsigned seed, const char *what, switch_check check) {
    const scene_kind kinds[3] = {SCENE_TRIANGLES, SCENE_DUAL, SCENE_HEXAGONS};
    for (int k = 0; k < 3; ++k) {
        mesh_scene s = scene_make(kinds[k], n, 2.5, seed);
        double *a = calloc((size_t)s.cells, sizeof(double)), *b = calloc((size_t)s.cells, sizeof(double));
        double la[3], lb[3];
        run_active_scene(&s, a, la);
        setenv(variable, "1", 1);
        run_active_scene(&s, b, lb);
        unsetenv(variable);
        char name[96];
        snprintf(name, sizeof name, "%s, %s", scene_name(kinds[k]), what);
        check(name, a, b, s.cells, la, lb);
        free(a), free(b);
        scene_free(&s);
    }
}

static void same_bits_and_ledger(const char *what, const double *a, const double *b, int64_t n, const double *la,
                                 const double *lb) {
    for (int64_t c = 0; c < n; ++c)
        REQUIRE(memcmp(&a[c], &b[c], sizeof(double)) == 0, "%s: cell %lld: %.17g against %.17g", what, (long long)c,
                b[c], a[c]);
    REQUIRE(memcmp(la, lb, 3 * sizeof(double)) == 0, "%s: the ledger differs", what);
}

static void test_active_set_same_bits(void **state) {
    (void)state;
    run_with_and_without("DPSM_VISIT_ALL_CELLS", 60, 5u, "every cell visited", same_bits_and_ledger);
}

/* The sub-step's face passes in vector lanes (mesh/face_lanes.hpp) against
 * the scalar functions alone (DPSM_SCALAR_MESH=1): the same heights, face
 * fluxes and ledger bit for bit, on every mesh kind, in every scene the
 * lanes take (open edge faces held at levels, closed ones, wall and open
 * cells, flux exponent 2) and in those they leave in part to scalar code (an
 * angle field, a bed), on one thread and, on a mesh large enough for them,
 * on two. A steep plane keeps every cell moving, so every sub-step is dense;
 * a steep bump on a flat table moves a few cells, so sub-steps are sparse
 * (the lanes over a list of faces). With sources the heights a face reads
 * are the stored ones plus what the source added since (sources in closed
 * form), in lanes too. */
typedef struct {
    int edge;      /* DPSM_OPEN: levels beyond the edge; DPSM_WALL: closed */
    int cells;     /* wall and open cells in the plane */
    double power;  /* flux exponent */
    int field;     /* an angle field */
    int bed;       /* a bed under the plane */
    int threads;
    int bump;      /* a steep bump on a flat table instead of the plane: sparse sub-steps */
    int source;    /* a source on every cell: the heights read lag behind the stored ones */
} lanes_scene;

static void plane_in_lanes(const mesh_scene *s, const lanes_scene *scene, int scalar, double *h_out,
                           double *fluxes_out, double *ledger_out, double *update_share) {
    if (scalar) setenv("DPSM_SCALAR_MESH", "1", 1);
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, scene_create(s, &g));
    CHECK_OK(g, dpsm_set_repose_angle(g, 30.0 * kDeg));
    CHECK_OK(g, dpsm_set_threads(g, scene->threads));
    CHECK_OK(g, dpsm_set_flux_exponent(g, scene->power));
    CHECK_OK(g, dpsm_set_face_flux_recording(g, 1));
    int64_t nfaces = 0;
    CHECK_OK(g, dpsm_get_face_count(g, &nfaces));
    double *levels = calloc((size_t)nfaces, sizeof(double));
    /* beside the bump's table, levels at the table's height: the edge at rest */
    for (int64_t f = 0; f < nfaces; ++f) levels[f] = scene->bump ? 3.0 : 0.25 * (double)(f % 5);
    CHECK_OK(g, dpsm_set_side_levels(g, DPSM_MESH_EDGE, levels));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, scene->edge));
    double *h = calloc((size_t)s->cells, sizeof(double)), *angle = calloc((size_t)s->cells, sizeof(double));
    uint8_t *kinds = calloc((size_t)s->cells, 1);
    for (int64_t c = 0; c < s->cells; ++c) {
        h[c] = 3.0 + 1.5 * s->cx[c] + 0.8 * s->cy[c] + 0.3 * sin(7.0 * s->cx[c] * s->cy[c]);
        /* on two threads, wide enough that the lists are shared (kListItemsForThreads) */
        if (scene->bump)
            h[c] = 3.0 + fmax(0.0, (scene->threads > 1 ? 0.45 : 0.25) - 1.5 * hypot(s->cx[c] - 0.5, s->cy[c] + 0.1));
        /* with a source, a pile just below the angle of repose; or a flat
         * shelf beside the plane, whose cells take no sub-step while the
         * plane's keep the sub-steps dense */
        if (scene->bump && scene->source) h[c] = 3.0 + fmax(0.0, 0.2 - 0.55 * hypot(s->cx[c] - 0.5, s->cy[c] + 0.1));
        if (!scene->bump && scene->source && s->cx[c] > 0.4) h[c] = 5.0;
        angle[c] = (28.0 + 4.0 * (double)(c % 3)) * kDeg;
        if (scene->cells && hypot(s->cx[c] - 0.3, s->cy[c] + 0.2) < 0.25) kinds[c] = DPSM_CELL_WALL;
        if (scene->cells && hypot(s->cx[c] + 0.6, s->cy[c] - 0.5) < 0.15) kinds[c] = DPSM_CELL_OPEN;
    }
    CHECK_OK(g, dpsm_set_cell_kinds(g, kinds));
    if (scene->field) CHECK_OK(g, dpsm_set_repose_angle_field(g, angle));
    CHECK_OK(g, dpsm_set_heights(g, h));
    if (scene->source) {
        /* On the pile, one on its top: the top's faces turn steep one by
         * one, each reading heights its cells' sources moved since they
         * last took a sub-step. */
        double *q = calloc((size_t)s->cells, sizeof(double));
        for (int64_t c = 0; c < s->cells; ++c)
            q[c] = !scene->bump                                     ? 0.5 + 0.3 * sin(5.0 * s->cx[c])
                   : hypot(s->cx[c] - 0.5, s->cy[c] + 0.1) < 0.12 ? 1.7
                                                                   : 0.0;
        CHECK_OK(g, dpsm_set_source(g, q));
        free(q);
    }
    if (scene->bed) {
        double *bed = calloc((size_t)s->cells, sizeof(double));
        for (int64_t c = 0; c < s->cells; ++c) bed[c] = h[c] - (s->cx[c] > 0.2 ? 0.02 : 0.5);
        CHECK_OK(g, dpsm_set_bedrock(g, bed));
        free(bed);
    }
    double dt = 0.0;
    CHECK_OK(g, dpsm_stable_dt(g, &dt));
    double updates = 0.0, substeps = 0.0;
    for (int call = 0; call < 3; ++call) {
        CHECK_OK(g, dpsm_step(g, 4.0 * dt));
        double call_updates = 0.0, call_substeps = 0.0;
        CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &call_updates));
        CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &call_substeps));
        updates += call_updates, substeps += call_substeps;
    }
    *update_share = updates / (substeps * (double)s->cells);
    CHECK_OK(g, dpsm_get_heights(g, h_out));
    CHECK_OK(g, dpsm_get_face_fluxes(g, fluxes_out, NULL));
    ledger_out[0] = mass_of(g, DPSM_MASS_TOTAL);
    ledger_out[1] = mass_of(g, DPSM_MASS_OUTFLOW);
    free(h), free(angle), free(kinds), free(levels);
    dpsm_destroy(g);
    unsetenv("DPSM_SCALAR_MESH");
}

static void test_face_pass_in_lanes_same_bits(void **state) {
    (void)state;
    const scene_kind kinds[4] = {SCENE_QUADS, SCENE_TRIANGLES, SCENE_HEXAGONS, SCENE_DUAL};
    enum { kScenes = 11 };
    const lanes_scene scenes[kScenes] = {
        {DPSM_OPEN, 0, 1.0, 0, 0, 1, 0}, {DPSM_WALL, 1, 1.0, 0, 0, 1, 0}, {DPSM_OPEN, 1, 2.0, 0, 0, 1, 0},
        {DPSM_OPEN, 1, 1.0, 1, 0, 1, 0}, {DPSM_OPEN, 1, 1.0, 0, 1, 1, 0}, {DPSM_OPEN, 1, 1.0, 0, 0, 2, 0},
        {DPSM_OPEN, 0, 1.0, 0, 0, 1, 1}, {DPSM_WALL, 1, 2.0, 0, 0, 1, 1}, {DPSM_OPEN, 0, 1.0, 0, 0, 2, 1},
        {DPSM_OPEN, 1, 1.0, 0, 0, 1, 0, 1}, {DPSM_OPEN, 0, 1.0, 0, 0, 1, 1, 1}};
    const char *names[kScenes] = {"open edge at levels",
                                  "closed edge, wall and open cells",
                                  "flux exponent 2",
                                  "angle field (faces in scalar code)",
                                  "bed (faces and limited fluxes in scalar code)",
                                  "two threads",
                                  "a bump, sparse",
                                  "a bump, sparse, walls, exponent 2",
                                  "a bump, sparse, two threads",
                                  "sources, a shelf lagging",
                                  "a bump, sparse, sources lagging"};
    for (int k = 0; k < 4; ++k)
        for (int n = 0; n < kScenes; ++n) {
            /* Two threads share a pass from 32,768 cells (kCellsForThreads): one mesh that large. */
            if (scenes[n].threads > 1 && kinds[k] != SCENE_TRIANGLES) continue;
            mesh_scene s = scene_make(kinds[k], scenes[n].threads > 1 ? 130 : scenes[n].bump ? 40 : 20, 1.0, 9u);
            int64_t nfaces = 0;
            {
                dpsm_grid *g = NULL;
                CHECK_OK(NULL, scene_create(&s, &g));
                CHECK_OK(g, dpsm_get_face_count(g, &nfaces));
                dpsm_destroy(g);
            }
            double *h[2], *flux[2], ledger[2][2], update_share[2];
            for (int scalar = 0; scalar < 2; ++scalar) {
                h[scalar] = calloc((size_t)s.cells, sizeof(double));
                flux[scalar] = calloc((size_t)nfaces, sizeof(double));
                plane_in_lanes(&s, &scenes[n], scalar, h[scalar], flux[scalar], ledger[scalar], &update_share[scalar]);
            }
            const char *kind = scene_name(kinds[k]);
            for (int64_t c = 0; c < s.cells; ++c)
                REQUIRE(memcmp(&h[0][c], &h[1][c], sizeof(double)) == 0,
                        "%s, %s: cell %lld: %.17g in lanes, %.17g in scalar code", kind, names[n], (long long)c,
                        h[0][c], h[1][c]);
            for (int64_t f = 0; f < nfaces; ++f)
                REQUIRE(memcmp(&flux[0][f], &flux[1][f], sizeof(double)) == 0,
                        "%s, %s: face %lld carried %.17g in lanes, %.17g in scalar code", kind, names[n],
                        (long long)f, flux[0][f], flux[1][f]);
            REQUIRE(memcmp(ledger[0], ledger[1], sizeof ledger[0]) == 0, "%s, %s: the ledger differs", kind,
                    names[n]);
            /* The plane moved sand everywhere, the bump on few cells in sparse
             * sub-steps: a comparison of surfaces at rest would prove nothing. */
            double moved = 0.0;
            for (int64_t f = 0; f < nfaces; ++f) moved += flux[0][f] != 0.0;
            if (scenes[n].bump) {
                REQUIRE(moved >= 20.0 && update_share[0] < 0.2,
                        "%s, %s: %.0f faces carried sand, %.3f of the cells updated a sub-step", kind, names[n],
                        moved, update_share[0]);
            } else {
                REQUIRE(moved > 0.5 * (double)nfaces, "%s, %s: %.0f of %lld faces carried sand", kind, names[n],
                        moved, (long long)nfaces);
            }
            for (int scalar = 0; scalar < 2; ++scalar) free(h[scalar]), free(flux[scalar]);
            scene_free(&s);
        }
}

/* The sparse step's passes over its lists run on the threads where the
 * lists are long (mesh/mesh_engine.cpp, for_each_item). Ridges on a mesh of
 * about 80,000 cells collapse in sub-steps that each change a few thousand
 * cells: on one thread and on two, the same heights bit for bit, and on each
 * the same as with every cell visited. And the sparse step visits what moves
 * (issue 34): over the sub-steps, the cells visited at most 2.5 times those
 * whose heights changed. */
static void ridges_on(const mesh_scene *s, int threads, int calls, double spacing, double *h_out, double *visited,
                      double *changed) {
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, scene_create(s, &g));
    CHECK_OK(g, dpsm_set_repose_angle(g, 30.0 * kDeg));
    CHECK_OK(g, dpsm_set_threads(g, threads));
    double *h = calloc((size_t)s->cells, sizeof(double)), *after = calloc((size_t)s->cells, sizeof(double));
    for (int64_t c = 0; c < s->cells; ++c)
        if (fabs(remainder(s->cy[c] - 0.5, spacing)) < 0.02) h[c] = 0.05; /* ridges `spacing` apart through y = 0.5 */
    CHECK_OK(g, dpsm_set_heights(g, h));
    double dt = 0.0;
    CHECK_OK(g, dpsm_stable_dt(g, &dt));
    CHECK_OK(g, dpsm_step(g, dt)); /* the host's heights: every cell looked at once */
    CHECK_OK(g, dpsm_get_heights(g, h));
    *visited = *changed = 0.0;
    for (int call = 0; call < calls; ++call) {
        double updates = 0.0, substeps = 0.0;
        CHECK_OK(g, dpsm_step(g, dt));
        CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, &updates));
        CHECK_OK(g, dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, &substeps));
        REQUIRE(substeps == 1.0, "ridges, call %d: %g sub-steps, expected 1", call + 1, substeps);
        CHECK_OK(g, dpsm_get_heights(g, after));
        for (int64_t c = 0; c < s->cells; ++c) *changed += after[c] != h[c];
        *visited += updates;
        memcpy(h, after, sizeof(double) * (size_t)s->cells);
    }
    memcpy(h_out, h, sizeof(double) * (size_t)s->cells);
    free(h), free(after);
    dpsm_destroy(g);
}

static void test_sparse_step_on_threads(void **state) {
    (void)state;
    const scene_kind kinds[2] = {SCENE_TRIANGLES, SCENE_DUAL};
    const int calls = 12;
    for (int k = 0; k < 2; ++k) {
        mesh_scene s = scene_make(kinds[k], kinds[k] == SCENE_DUAL ? 283 : 200, 1.0, 11u);
        const size_t n = (size_t)s.cells;
        double *one = calloc(n, sizeof(double)), *two = calloc(n, sizeof(double)), *all = calloc(n, sizeof(double));
        double visited = 0.0, changed = 0.0, v2 = 0.0, c2 = 0.0, va = 0.0, ca = 0.0;
        ridges_on(&s, 1, calls, 1.0, one, &visited, &changed);
        ridges_on(&s, 2, calls, 1.0, two, &v2, &c2);
        setenv("DPSM_VISIT_ALL_CELLS", "1", 1);
        ridges_on(&s, 2, calls, 1.0, all, &va, &ca);
        unsetenv("DPSM_VISIT_ALL_CELLS");
        const char *name = scene_name(kinds[k]);
        /* The lists long enough for the threads, and the step sparse (it
         * takes the plain passes over a quarter of the cells). */
        REQUIRE(v2 / calls > 4096.0 && v2 / calls < 0.25 * (double)n,
                "%s, %lld cells: %.0f cells visited a sub-step on two threads; the test wants the sparse step "
                "over more than 4096", name, (long long)s.cells, v2 / calls);
        REQUIRE(visited == v2, "%s: %.0f cells visited on one thread, %.0f on two", name, visited, v2);
        for (size_t c = 0; c < n; ++c) {
            REQUIRE(memcmp(&one[c], &two[c], sizeof(double)) == 0, "%s: cell %zu: %.17g on two threads, %.17g on one",
                    name, c, two[c], one[c]);
            REQUIRE(memcmp(&one[c], &all[c], sizeof(double)) == 0,
                    "%s: cell %zu: %.17g with every cell visited, %.17g with the active set", name, c, all[c], one[c]);
        }
        REQUIRE(visited <= 2.5 * changed, "%s: %.0f cells visited a sub-step, %.0f changed: %.2f times", name,
                visited / calls, changed / calls, visited / changed);
        print_message("%s, %lld cells: %.0f cells visited a sub-step, %.0f changed (%.2f times)\n", name,
                      (long long)s.cells, visited / calls, changed / calls, visited / changed);
        free(one), free(two), free(all);
        scene_free(&s);
    }
    /* Ridges closer together: a sub-step looks at more than an eighth of the
     * cells, and takes the lists on any number of threads where they are
     * fewer than a quarter (mesh_engine.cpp, kDenseShare), as the plain
     * passes do: the same cells visited on two threads as on one. */
    mesh_scene s = scene_make(SCENE_TRIANGLES, 200, 1.0, 11u);
    const size_t n = (size_t)s.cells;
    double *one = calloc(n, sizeof(double)), *two = calloc(n, sizeof(double));
    double visited = 0.0, changed = 0.0, v2 = 0.0, c2 = 0.0;
    ridges_on(&s, 1, calls, 0.5, one, &visited, &changed);
    ridges_on(&s, 2, calls, 0.5, two, &v2, &c2);
    print_message("ridges 0.5 apart, %lld cells: %.0f cells visited a sub-step on one thread (%.3f of the cells), "
                  "%.0f on two\n", (long long)s.cells, visited / calls, visited / calls / (double)n, v2 / calls);
    REQUIRE(visited / calls > 0.125 * (double)n && visited / calls < 0.25 * (double)n,
            "ridges 0.5 apart: %.0f of %zu cells visited a sub-step; the test wants between an eighth and a quarter",
            visited / calls, n);
    REQUIRE(visited == v2, "ridges 0.5 apart: %.0f cells visited on one thread, %.0f on two", visited, v2);
    for (size_t c = 0; c < n; ++c)
        REQUIRE(memcmp(&one[c], &two[c], sizeof(double)) == 0, "ridges 0.5 apart: cell %zu: %.17g on two threads, "
                "%.17g on one", c, two[c], one[c]);
    free(one), free(two);
    scene_free(&s);
}

/* What a cell's sums read is ordered by the host's cell numbers (and on the
 * domain edge by the faces' midpoints), never by the library's internal
 * order or the order the host lists faces in: a distributed mesh, whose ranks
 * each order their part their own way, must add the same terms in the same
 * order as one serial mesh. So the cells in the host's order instead of along
 * the Hilbert curve (DPSM_MESH_HOST_ORDER=1), on every mesh kind, and a graph
 * whose faces are listed backwards, each the other way round, step to the
 * same heights bit for bit; the ledger's sums over faces may round
 * differently. */
static void compare_runs(const char *what, const double *a, const double *b, int64_t n, const double *la,
                         const double *lb) {
    for (int64_t c = 0; c < n; ++c)
        REQUIRE(memcmp(&a[c], &b[c], sizeof(double)) == 0, "%s: cell %lld: %.17g against %.17g", what, (long long)c,
                b[c], a[c]);
    for (int q = 0; q < 3; ++q)
        REQUIRE(fabs(la[q] - lb[q]) <= 1e-13 * fmax(1.0, fabs(la[q])), "%s: ledger figure %d: %.17g against %.17g",
                what, q, lb[q], la[q]);
}

static void test_sums_ordered_by_host_numbers(void **state) {
    (void)state;
    run_with_and_without("DPSM_MESH_HOST_ORDER", 40, 9u, "cells in the host's order", compare_runs);
    const int n = 40;
    mesh_scene s = scene_make(SCENE_QUADS, n, 2.5, 1u);
    quad_graph q = quad_graph_make(n, 2.5);
    int64_t *faces = calloc((size_t)(2 * q.nfaces), sizeof(int64_t));
    double *mid = calloc((size_t)(2 * q.nfaces), sizeof(double)), *length = calloc((size_t)q.nfaces, sizeof(double));
    for (int64_t f = 0; f < q.nfaces; ++f) {
        const int64_t from = q.nfaces - 1 - f, a = q.face_cells[2 * from], b = q.face_cells[2 * from + 1];
        faces[2 * f] = b >= 0 ? b : a, faces[2 * f + 1] = b >= 0 ? a : -1;
        mid[2 * f] = q.face_xy[2 * from], mid[2 * f + 1] = q.face_xy[2 * from + 1], length[f] = q.length[from];
    }
    double *a = calloc((size_t)s.cells, sizeof(double)), *b = calloc((size_t)s.cells, sizeof(double));
    double la[3], lb[3];
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_graph(q.ncells, q.cell_xy, q.area, q.nfaces, q.face_cells, q.face_xy, q.length, &g));
    run_active_scene_on(g, &s, a, la);
    CHECK_OK(NULL, dpsm_create_graph(q.ncells, q.cell_xy, q.area, q.nfaces, faces, mid, length, &g));
    run_active_scene_on(g, &s, b, lb);
    compare_runs("a graph's faces listed backwards and turned", a, b, s.cells, la, lb);
    free(a), free(b), free(faces), free(mid), free(length);
    quad_graph_free(&q);
    scene_free(&s);
}

static void test_fluxes_match_height_changes(void **state) {
    (void)state;
    mesh_scene s = scene_make(SCENE_HEXAGONS, 20, 2.5, 1u);
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, scene_create(&s, &g));
    CHECK_OK(g, dpsm_set_repose_angle(g, 30.0 * kDeg));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN));
    CHECK_OK(g, dpsm_set_face_flux_recording(g, 1));
    /* A steep ridge across the edge, so that sand leaves too. */
    double *h = calloc((size_t)s.cells, sizeof(double)), *after = calloc((size_t)s.cells, sizeof(double));
    for (int64_t c = 0; c < s.cells; ++c) h[c] = fmax(0.0, 1.5 - 1.2 * fabs(s.cy[c] - 0.3 * s.cx[c]));
    CHECK_OK(g, dpsm_set_heights(g, h));
    int64_t nfaces = 0;
    CHECK_OK(g, dpsm_get_face_count(g, &nfaces));
    int64_t *faces = calloc((size_t)(2 * nfaces), sizeof(int64_t));
    double *fx = calloc((size_t)nfaces, sizeof(double)), *net = calloc((size_t)s.cells, sizeof(double));
    CHECK_OK(g, dpsm_get_mesh_faces(g, faces));
    const double outflow_before = mass_of(g, DPSM_MASS_OUTFLOW);
    CHECK_OK(g, dpsm_step(g, 0.2));
    CHECK_OK(g, dpsm_get_heights(g, after));
    CHECK_OK(g, dpsm_get_face_fluxes(g, fx, NULL));
    double edge = 0.0, scale = 0.0;
    for (int64_t f = 0; f < nfaces; ++f) {
        const int64_t a = faces[2 * f], b = faces[2 * f + 1];
        net[a] -= fx[f];
        if (b >= 0)
            net[b] += fx[f];
        else
            edge += fx[f];
        scale = fmax(scale, fabs(fx[f]));
    }
    REQUIRE(scale > 0.0, "nothing moved");
    for (int64_t c = 0; c < s.cells; ++c)
        REQUIRE(fabs(net[c] - (after[c] - h[c]) * s.area[c]) <= 1e-12 * scale,
                "cell %lld: its faces carried %.17g, its volume changed by %.17g", (long long)c, net[c],
                (after[c] - h[c]) * s.area[c]);
    const double outflow = mass_of(g, DPSM_MASS_OUTFLOW) - outflow_before;
    double side = 0.0;
    CHECK_OK(g, dpsm_get_side_outflow(g, DPSM_MESH_EDGE, &side));
    REQUIRE(outflow > 0.0 && fabs(edge - outflow) <= 1e-12 * scale, "the edge's faces carried %.17g, outflow %.17g",
            edge, outflow);
    REQUIRE(fabs(side - mass_of(g, DPSM_MASS_OUTFLOW)) <= 1e-15 * fabs(side), "DPSM_MESH_EDGE's outflow %.17g",
            side);
    free(h), free(after), free(faces), free(fx), free(net);
    dpsm_destroy(g);
    scene_free(&s);
}

/* A mesh saved in the middle of a run and loaded again continues bit for bit
 * as the one that was not saved, on each constructor's mesh, with indices
 * from 0 (format version 5) and from 1 (version 6: the loaded mesh counts
 * from 1 as the saved one did). */
static void test_restart_on_meshes(void **state) {
    (void)state;
    const scene_kind kinds[5] = {SCENE_TRIANGLES, SCENE_HEXAGONS, SCENE_DUAL, SCENE_HEXAGONS, SCENE_DUAL};
    const int bases[5] = {0, 0, 0, 1, 1};
    char path[64];
    snprintf(path, sizeof path, "test_mesh_restart_%d.dpsm", (int)getpid());
    for (int k = 0; k < 5; ++k) {
        mesh_scene s = scene_make(kinds[k], 20, 2.5, 9u);
        dpsm_grid *a = column_mesh(&s, 0, bases[k]), *b = NULL;
        int64_t nfaces = 0;
        CHECK_OK(a, dpsm_get_face_count(a, &nfaces));
        int64_t *faces = calloc((size_t)(2 * nfaces), sizeof(int64_t));
        CHECK_OK(a, dpsm_get_mesh_faces(a, faces));
        /* some edge faces open at a level, a source, a wall cell */
        uint8_t *edges = malloc((size_t)nfaces);
        double *levels = calloc((size_t)nfaces, sizeof(double));
        for (int64_t f = 0; f < nfaces; ++f) {
            edges[f] = (f % 3 == 0) ? DPSM_OPEN : DPSM_WALL;
            levels[f] = 0.2 * (double)(f % 5); /* higher than the empty cells beside: sand comes in */
        }
        CHECK_OK(a, dpsm_set_edge_kinds(a, edges));
        CHECK_OK(a, dpsm_set_side_levels(a, DPSM_MESH_EDGE, levels));
        double *q = calloc((size_t)s.cells, sizeof(double));
        uint8_t *cell_kinds = calloc((size_t)s.cells, 1);
        q[s.cells / 3] = 0.5;
        cell_kinds[s.cells / 2] = DPSM_CELL_WALL;
        CHECK_OK(a, dpsm_set_source(a, q));
        CHECK_OK(a, dpsm_set_cell_kinds(a, cell_kinds));
        CHECK_OK(a, dpsm_set_face_flux_recording(a, 1));
        CHECK_OK(a, dpsm_step(a, 0.2));
        CHECK_OK(a, dpsm_save(a, path));
        REQUIRE(file_version(path) == 5u + (unsigned)bases[k], "%s from %d: a file of version %u", scene_name(kinds[k]),
                bases[k], file_version(path));
        CHECK_OK(NULL, dpsm_load(path, &b));
        int64_t nx = 0, ny = 0, nf = 0;
        CHECK_OK(b, dpsm_get_shape(b, &nx, &ny));
        CHECK_OK(b, dpsm_get_face_count(b, &nf));
        REQUIRE(nx == s.cells && ny == 1 && nf == nfaces, "%s: the loaded mesh has %lld cells and %lld faces",
                scene_name(kinds[k]), (long long)nx, (long long)nf);
        int64_t *faces_b = calloc((size_t)(2 * nfaces), sizeof(int64_t));
        CHECK_OK(b, dpsm_get_mesh_faces(b, faces_b));
        REQUIRE(memcmp(faces, faces_b, sizeof(int64_t) * (size_t)(2 * nfaces)) == 0, "%s: the faces differ after loading",
                scene_name(kinds[k]));
        int64_t an_edge = 0;
        while (faces_b[2 * an_edge + 1] != bases[k] - 1) ++an_edge;
        /* The loaded mesh names its faces from the saved one's start index. */
        edges[an_edge] = 7;
        char named[48];
        snprintf(named, sizeof named, "(face %lld, on the domain edge) = 7", (long long)(an_edge + bases[k]));
        EXPECT_FAIL_ON(b, dpsm_set_edge_kinds(b, edges), DPSM_ERR_UNKNOWN_ENUM, named);
        for (int call = 0; call < 3; ++call) {
            CHECK_OK(a, dpsm_step(a, 0.2));
            CHECK_OK(b, dpsm_step(b, 0.2));
        }
        double *ha = calloc((size_t)s.cells, sizeof(double)), *hb = calloc((size_t)s.cells, sizeof(double));
        CHECK_OK(a, dpsm_get_heights(a, ha));
        CHECK_OK(b, dpsm_get_heights(b, hb));
        REQUIRE(memcmp(ha, hb, sizeof(double) * (size_t)s.cells) == 0, "%s: a loaded mesh steps differently",
                scene_name(kinds[k]));
        double *fa = calloc((size_t)nfaces, sizeof(double)), *fb = calloc((size_t)nfaces, sizeof(double));
        CHECK_OK(a, dpsm_get_face_fluxes(a, fa, NULL));
        CHECK_OK(b, dpsm_get_face_fluxes(b, fb, NULL));
        REQUIRE(memcmp(fa, fb, sizeof(double) * (size_t)nfaces) == 0, "%s: face fluxes differ", scene_name(kinds[k]));
        const int quantities[5] = {DPSM_MASS_TOTAL, DPSM_MASS_SOURCED, DPSM_MASS_EXTERNAL, DPSM_MASS_OUTFLOW, DPSM_MASS_UNMET};
        for (int m = 0; m < 5; ++m)
            REQUIRE(mass_of(a, quantities[m]) == mass_of(b, quantities[m]), "%s: ledger figure %d differs",
                    scene_name(kinds[k]), quantities[m]);
        double side_a = 0, side_b = 0;
        CHECK_OK(a, dpsm_get_side_outflow(a, DPSM_MESH_EDGE, &side_a));
        CHECK_OK(b, dpsm_get_side_outflow(b, DPSM_MESH_EDGE, &side_b));
        REQUIRE(side_a == side_b && side_a != 0.0, "%s: edge outflow %.17g and %.17g", scene_name(kinds[k]), side_a, side_b);
        free(faces), free(faces_b), free(edges), free(levels), free(q), free(cell_kinds), free(ha), free(hb), free(fa),
            free(fb);
        dpsm_destroy(a), dpsm_destroy(b);
        scene_free(&s);
    }
    remove(path);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_create_mesh_quads),
        cmocka_unit_test(test_create_graph_and_dual),
        cmocka_unit_test(test_bad_meshes),
        cmocka_unit_test(test_mesh_functions),
        cmocka_unit_test(test_indexed_same_as_from_zero),
        cmocka_unit_test(test_indexed_bad_inputs),
        cmocka_unit_test(test_indexed_later_messages),
        cmocka_unit_test(test_column_rests_with_mass_and_bounds),
        cmocka_unit_test(test_no_new_extremum_on_rough_surfaces),
        cmocka_unit_test(test_exact_states),
        cmocka_unit_test(test_plane_at_the_angle_of_repose_rests),
        cmocka_unit_test(test_slope_along_a_wall_drains_as_away_from_it),
        cmocka_unit_test(test_ridge_between_walls_drains_as_on_the_grid),
        cmocka_unit_test(test_turned_mesh_same_deposit),
        cmocka_unit_test(test_error_falls_with_the_cells),
        cmocka_unit_test(test_no_sand_beyond_the_toe),
        cmocka_unit_test(test_host_order),
        cmocka_unit_test(test_graph_steps_as_polygons),
        cmocka_unit_test(test_active_set_same_bits),
        cmocka_unit_test(test_face_pass_in_lanes_same_bits),
        cmocka_unit_test(test_sparse_step_on_threads),
        cmocka_unit_test(test_sums_ordered_by_host_numbers),
        cmocka_unit_test(test_fluxes_match_height_changes),
        cmocka_unit_test(test_restart_on_meshes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
