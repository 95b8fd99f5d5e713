/* Meshes as production codes write them (issue 36): the constructors'
 * checks that real files meet, meshes in longitude and latitude, and where
 * each cell lies.
 *
 *  - a graph whose cell centre lies on a face's midpoint (a right
 *    triangle's circumcentre, Delft3D FM's mesh2d_face_x/y) is made, on
 *    the domain edge and inside; a cell missing a face is refused with a
 *    message that says where the face is missing and which faces it has;
 *  - two cells' nodes at the same point are refused, naming both nodes;
 *  - dpsm_get_cell_centres gives each cell's centre and area, on every kind
 *    of grid and mesh, and the areas are those of the ledger;
 *  - a geographic mesh measures on the sphere: the octant's area is
 *    pi R^2 / 2, a patch of cells has the same stable sub-step and the same
 *    heights wherever its projection is centred, a mesh of 1 km cells in
 *    degrees steps with sub-steps of its metres, and a restart file keeps
 *    it bit for bit. */
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

#include "test_support.h"

static const double kPi = 3.14159265358979323846;
static const double kEarthRadius = 6371008.8;

/* A failed create: the status, *out NULL, and a message holding `what`. */
#define EXPECT_CREATE_FAIL(call, out, code, what)                                                                   \
    do {                                                                                                            \
        (out) = (dpsm_grid *)&(out);                                                                                \
        const int status_ = (call);                                                                                 \
        REQUIRE(status_ == (code), "%s returned %s, expected %s (%s)", #call, dpsm_status_string(status_),          \
                dpsm_status_string(code), dpsm_last_error(NULL));                                                   \
        REQUIRE((out) == NULL, "%s left *out set", #call);                                                          \
        REQUIRE(strstr(dpsm_last_error(NULL), (what)) != NULL, "message '%s' does not hold '%s'",                   \
                dpsm_last_error(NULL), (what));                                                                     \
    } while (0)

static double sum_of(const double *v, int64_t n) {
    double s = 0.0;
    for (int64_t k = 0; k < n; ++k) s += v[k];
    return s;
}

/* ------------------------------------------------------------------------ */
/* The graph constructor and Delft3D FM's circumcentres                       */
/* ------------------------------------------------------------------------ */

/* The unit square split by its diagonals into 4 right triangles (bottom,
 * right, top, left), each with its right angle at the square's centre: its
 * circumcentre, the cell centre Delft3D FM writes, is the midpoint of its
 * hypotenuse, which lies on the domain edge. Faces: the 4 legs between
 * neighbouring triangles, then the 4 hypotenuses. */
static void test_graph_right_triangles_on_the_edge(void **state) {
    (void)state;
    const double cell_xy[8] = {0.5, 0.0, 1.0, 0.5, 0.5, 1.0, 0.0, 0.5};
    const double area[4] = {0.25, 0.25, 0.25, 0.25};
    const int64_t face_cells[16] = {0, 1, 1, 2, 2, 3, 3, 0, 0, -1, 1, -1, 2, -1, 3, -1};
    const double face_xy[16] = {0.75, 0.25, 0.75, 0.75, 0.25, 0.75, 0.25, 0.25,
                                0.5,  0.0,  1.0,  0.5,  0.5,  1.0,  0.0,  0.5};
    const double leg = sqrt(0.5);
    const double length[8] = {leg, leg, leg, leg, 1.0, 1.0, 1.0, 1.0};
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_graph(4, cell_xy, area, 8, face_cells, face_xy, length, &g));
    double dt = 0.0;
    CHECK_OK(g, dpsm_stable_dt(g, &dt));
    REQUIRE(dt > 1e-3 && isfinite(dt), "stable dt %g: the faces at the centres must have a sound distance", dt);
    /* A pile on the bottom triangle slides into the others and, with the
     * edge open, out through the hypotenuses: the ledger closes, sand left. */
    const double h[4] = {4.0, 0.0, 0.0, 0.0};
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN));
    CHECK_OK(g, dpsm_step(g, 1.0));
    double after[4];
    CHECK_OK(g, dpsm_get_heights(g, after));
    REQUIRE(after[0] < 4.0 && after[1] > 0.0 && after[3] > 0.0, "the pile did not slide: %g %g %g %g", after[0],
            after[1], after[2], after[3]);
    REQUIRE(mass_of(g, DPSM_MASS_OUTFLOW) > 0.0, "nothing left through the open hypotenuses");
    REQUIRE(ledger_residual(g) < 1e-13, "the ledger does not close: %g", ledger_residual(g));
    dpsm_destroy(g);

    /* A centre on a face of a cell that is not a triangle: refused. */
    const double square_xy[2] = {0.5, 0.0};
    const double square_area[1] = {1.0};
    const int64_t square_faces[8] = {0, -1, 0, -1, 0, -1, 0, -1};
    const double square_mid[8] = {0.5, 0.0, 1.0, 0.5, 0.5, 1.0, 0.0, 0.5};
    const double square_length[4] = {1.0, 1.0, 1.0, 1.0};
    EXPECT_CREATE_FAIL(dpsm_create_graph(1, square_xy, square_area, 4, square_faces, square_mid, square_length, &g), g,
                       DPSM_ERR_INVALID_VALUE, "face 0 (cell 0 and the domain edge) has its midpoint at the cell's centre");
    REQUIRE(strstr(dpsm_last_error(NULL), "has 4 faces") != NULL, "%s", dpsm_last_error(NULL));
}

/* The circumcentre of the triangle (a, b, c). */
static void circumcentre(const double *a, const double *b, const double *c, double *out) {
    const double bx = b[0] - a[0], by = b[1] - a[1], cx = c[0] - a[0], cy = c[1] - a[1];
    const double d = 2.0 * (bx * cy - by * cx);
    out[0] = a[0] + (cy * (bx * bx + by * by) - by * (cx * cx + cy * cy)) / d;
    out[1] = a[1] + (bx * (cx * cx + cy * cy) - cx * (bx * bx + by * by)) / d;
}

/* A right triangle (0,0), (1,0), (0,1) and a triangle on its hypotenuse
 * that is not right: the first centre lies on the face between them. Its
 * faces close it (the face lies towards the cell across it), and the graph
 * steps as the same triangles given as polygons do, to round-off. */
static void test_graph_right_triangle_inside(void **state) {
    (void)state;
    const double p[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1.3, 1.1}};
    double c0[2], c1[2];
    circumcentre(p[0], p[1], p[2], c0);
    circumcentre(p[1], p[3], p[2], c1);
    REQUIRE(fabs(c0[0] - 0.5) < 1e-15 && fabs(c0[1] - 0.5) < 1e-15, "the right triangle's circumcentre is (%g, %g)",
            c0[0], c0[1]);
    const double cell_xy[4] = {c0[0], c0[1], c1[0], c1[1]};
    const double area[2] = {0.5, 0.5 * fabs((p[3][0] - p[1][0]) * (p[2][1] - p[1][1]) - (p[3][1] - p[1][1]) * (p[2][0] - p[1][0]))};
    /* Face 0 the hypotenuse, then the other four on the edge. */
    const int64_t face_cells[10] = {0, 1, 0, -1, 0, -1, 1, -1, 1, -1};
    const double face_xy[10] = {0.5, 0.5, 0.5, 0.0, 0.0, 0.5, 0.5 * (p[1][0] + p[3][0]), 0.5 * (p[1][1] + p[3][1]),
                                0.5 * (p[3][0] + p[2][0]), 0.5 * (p[3][1] + p[2][1])};
    const double length[5] = {sqrt(2.0), 1.0, 1.0, hypot(p[3][0] - p[1][0], p[3][1] - p[1][1]),
                              hypot(p[3][0] - p[2][0], p[3][1] - p[2][1])};
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_graph(2, cell_xy, area, 5, face_cells, face_xy, length, &g));
    const double h[2] = {3.0, 0.0};
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_step(g, 1.0));
    double after[2];
    CHECK_OK(g, dpsm_get_heights(g, after));
    REQUIRE(after[1] > 0.0 && fabs(after[0] * area[0] + after[1] * area[1] - 1.5) < 1e-14,
            "the sand moved across the hypotenuse and kept its volume: %.17g %.17g", after[0], after[1]);
    dpsm_destroy(g);
}

/* A cell whose faces leave a side open is refused with where the face is
 * missing and the faces it has. */
static void test_graph_missing_face_is_named(void **state) {
    (void)state;
    /* Two unit squares; the right one's face on x = 2 left out. */
    const double cell_xy[4] = {0.5, 0.5, 1.5, 0.5};
    const double area[2] = {1.0, 1.0};
    const int64_t face_cells[12] = {0, 1, 0, -1, 0, -1, 0, -1, 1, -1, 1, -1};
    const double face_xy[12] = {1.0, 0.5, 0.5, 0.0, 0.0, 0.5, 0.5, 1.0, 1.5, 0.0, 1.5, 1.0};
    const double length[6] = {1, 1, 1, 1, 1, 1};
    dpsm_grid *g = NULL;
    EXPECT_CREATE_FAIL(dpsm_create_graph(2, cell_xy, area, 6, face_cells, face_xy, length, &g), g,
                       DPSM_ERR_INVALID_VALUE, "the faces of cell 1 (3 of them: faces 0, 4, 5) do not close it");
    REQUIRE(strstr(dpsm_last_error(NULL), "no face lies between 270 and 90 degrees") != NULL &&
                strstr(dpsm_last_error(NULL), "a face is missing there") != NULL,
            "the message does not say where: %s", dpsm_last_error(NULL));
    /* From 1, as a Fortran host names them. */
    int64_t from_one[12];
    for (int k = 0; k < 12; ++k) from_one[k] = face_cells[k] + 1;
    EXPECT_CREATE_FAIL(dpsm_create_graph_indexed(1, 2, cell_xy, area, 6, from_one, face_xy, length, &g), g,
                       DPSM_ERR_INVALID_VALUE, "the faces of cell 2 (3 of them: faces 1, 5, 6) do not close it");
}

/* ------------------------------------------------------------------------ */
/* Coincident nodes                                                          */
/* ------------------------------------------------------------------------ */

/* Two unit squares side by side, each with nodes of its own: the shared
 * edge's nodes appear twice (1 and 4 at (1, 0), 2 and 7 at (1, 1)), so the
 * edge between the squares would be two domain edges. */
static void test_coincident_nodes_are_refused(void **state) {
    (void)state;
    const double xy[16] = {0, 0, 1, 0, 1, 1, 0, 1, 1, 0, 2, 0, 2, 1, 1, 1};
    const int64_t start[3] = {0, 4, 8};
    const int64_t nodes[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    dpsm_grid *g = NULL;
    EXPECT_CREATE_FAIL(dpsm_create_mesh(8, xy, 2, start, nodes, &g), g, DPSM_ERR_INVALID_VALUE,
                       "dpsm_create_mesh: nodes 1 and 4 lie at the same point (1, 0), used by cells 0 and 1");
    REQUIRE(strstr(dpsm_last_error(NULL), "give the cells one node there") != NULL, "%s", dpsm_last_error(NULL));
    const int64_t start1[3] = {1, 5, 9};
    int64_t nodes1[8];
    for (int k = 0; k < 8; ++k) nodes1[k] = nodes[k] + 1;
    EXPECT_CREATE_FAIL(dpsm_create_mesh_indexed(1, 8, xy, 2, start1, nodes1, &g), g, DPSM_ERR_INVALID_VALUE,
                       "nodes 2 and 5 lie at the same point (1, 0), used by cells 1 and 2");
    /* Shared nodes: the same squares are one mesh with an interior face. */
    const double shared_xy[12] = {0, 0, 1, 0, 2, 0, 0, 1, 1, 1, 2, 1};
    const int64_t shared[8] = {0, 1, 4, 3, 1, 2, 5, 4};
    CHECK_OK(NULL, dpsm_create_mesh(6, shared_xy, 2, start, shared, &g));
    int64_t nfaces = 0;
    CHECK_OK(g, dpsm_get_face_count(g, &nfaces));
    REQUIRE(nfaces == 7, "%lld faces", (long long)nfaces);
    dpsm_destroy(g);
    /* A node at another's place that no cell uses is harmless. */
    const double spare_xy[14] = {0, 0, 1, 0, 2, 0, 0, 1, 1, 1, 2, 1, 1, 1};
    CHECK_OK(NULL, dpsm_create_mesh(7, spare_xy, 2, start, shared, &g));
    dpsm_destroy(g);
    /* The dual: two triangles over the unit square, node 3 again as node 4. */
    const double tri_xy[10] = {0, 0, 1, 0, 1, 1, 0, 1, 1, 1};
    const int64_t tris[6] = {0, 1, 2, 0, 4, 3};
    EXPECT_CREATE_FAIL(dpsm_create_dual_mesh(5, tri_xy, 2, tris, &g), g, DPSM_ERR_INVALID_VALUE,
                       "dpsm_create_dual_mesh: nodes 2 and 4 lie at the same point (1, 1), used by triangles 0 and 1");
}

/* ------------------------------------------------------------------------ */
/* Where each cell lies                                                      */
/* ------------------------------------------------------------------------ */

/* The centres and areas of every kind; the areas weigh the ledger. */
static void test_cell_centres(void **state) {
    (void)state;
    double xy[16], area[8];
    dpsm_grid *g = NULL;
    /* A square and a triangle: centroids (0.5, 0.5) and (4/3, 1/3). */
    const double mesh_xy[10] = {0, 0, 1, 0, 1, 1, 0, 1, 2, 0};
    const int64_t start[3] = {0, 4, 7};
    const int64_t nodes[7] = {0, 1, 2, 3, 1, 4, 2};
    CHECK_OK(NULL, dpsm_create_mesh(5, mesh_xy, 2, start, nodes, &g));
    CHECK_OK(g, dpsm_get_cell_centres(g, xy, area));
    REQUIRE(fabs(xy[0] - 0.5) < 1e-15 && fabs(xy[1] - 0.5) < 1e-15 && fabs(xy[2] - 4.0 / 3) < 1e-15 &&
                fabs(xy[3] - 1.0 / 3) < 1e-15,
            "centroids (%g, %g) (%g, %g)", xy[0], xy[1], xy[2], xy[3]);
    REQUIRE(fabs(area[0] - 1.0) < 1e-15 && fabs(area[1] - 0.5) < 1e-15, "areas %g %g", area[0], area[1]);
    const double ones[2] = {1.0, 1.0};
    CHECK_OK(g, dpsm_set_heights(g, ones));
    REQUIRE(fabs(mass_of(g, DPSM_MASS_TOTAL) - sum_of(area, 2)) < 1e-15, "the areas are not the ledger's");
    double only_area[2] = {0, 0};
    CHECK_OK(g, dpsm_get_cell_centres(g, NULL, only_area));
    REQUIRE(only_area[1] == area[1], "area alone");
    double only_xy[4] = {0, 0, 0, 0};
    CHECK_OK(g, dpsm_get_cell_centres(g, only_xy, NULL));
    REQUIRE(only_xy[2] == xy[2], "centres alone");
    REQUIRE(dpsm_get_cell_centres(g, NULL, NULL) == DPSM_ERR_NULL_POINTER &&
                strstr(dpsm_last_error(g), "dpsm_get_cell_centres: cell_xy and cell_area are both NULL"),
            "%s", dpsm_last_error(g));
    REQUIRE(dpsm_get_cell_centres(NULL, xy, area) == DPSM_ERR_NULL_POINTER, "a NULL grid");
    dpsm_destroy(g);

    /* A graph: the host's centres and areas. */
    const double cell_xy[4] = {0.4, 0.6, 1.5, 0.5};
    const double cell_area[2] = {1.25, 0.75};
    const int64_t face_cells[14] = {0, 1, 0, -1, 0, -1, 0, -1, 1, -1, 1, -1, 1, -1};
    const double face_xy[14] = {1, 0.5, 0.5, 0, 0, 0.5, 0.5, 1, 1.5, 0, 2, 0.5, 1.5, 1};
    const double length[7] = {1, 1, 1, 1, 1, 1, 1};
    CHECK_OK(NULL, dpsm_create_graph(2, cell_xy, cell_area, 7, face_cells, face_xy, length, &g));
    CHECK_OK(g, dpsm_get_cell_centres(g, xy, area));
    REQUIRE(memcmp(xy, cell_xy, sizeof cell_xy) == 0 && memcmp(area, cell_area, sizeof cell_area) == 0,
            "a graph gives back its host's centres and areas");
    dpsm_destroy(g);

    /* A dual: each node, a third of its triangles. */
    const double dual_xy[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    const int64_t tris[6] = {0, 1, 2, 0, 2, 3};
    CHECK_OK(NULL, dpsm_create_dual_mesh(4, dual_xy, 2, tris, &g));
    CHECK_OK(g, dpsm_get_cell_centres(g, xy, area));
    REQUIRE(memcmp(xy, dual_xy, sizeof dual_xy) == 0, "a dual's cells stand at its nodes");
    REQUIRE(fabs(area[0] - 1.0 / 3) < 1e-15 && fabs(area[1] - 1.0 / 6) < 1e-15 && fabs(sum_of(area, 4) - 1.0) < 1e-15,
            "dual areas %g %g %g %g", area[0], area[1], area[2], area[3]);
    dpsm_destroy(g);

    /* Grids: 2D, 1D, axisymmetric. */
    CHECK_OK(NULL, dpsm_create_2d(3, 2, 0.5, 2.0, &g));
    CHECK_OK(g, dpsm_get_cell_centres(g, xy, area));
    REQUIRE(xy[2 * 5] == 1.25 && xy[2 * 5 + 1] == 3.0 && area[5] == 1.0, "2D cell (2, 1): (%g, %g) area %g",
            xy[10], xy[11], area[5]);
    dpsm_destroy(g);
    CHECK_OK(NULL, dpsm_create_1d(4, 0.25, &g));
    CHECK_OK(g, dpsm_get_cell_centres(g, xy, area));
    REQUIRE(xy[6] == 0.875 && xy[7] == 0.0 && area[3] == 0.25, "1D cell 3: (%g, %g) length %g", xy[6], xy[7], area[3]);
    dpsm_destroy(g);
    CHECK_OK(NULL, dpsm_create_axisymmetric(3, 2.0, &g));
    CHECK_OK(g, dpsm_get_cell_centres(g, xy, area));
    const double h3[3] = {1.0, 1.0, 1.0};
    CHECK_OK(g, dpsm_set_heights(g, h3));
    REQUIRE(xy[4] == 5.0 && fabs(area[2] - 2 * kPi * 5.0 * 2.0) < 1e-12 &&
                fabs(mass_of(g, DPSM_MASS_TOTAL) - sum_of(area, 3)) < 1e-12,
            "axisymmetric ring 2 at r = %g, area %g", xy[4], area[2]);
    dpsm_destroy(g);
}

/* ------------------------------------------------------------------------ */
/* Meshes in longitude and latitude                                          */
/* ------------------------------------------------------------------------ */

/* The octant between (0, 0), (90, 0) and (0, 90): pi R^2 / 2. */
static void test_geographic_octant(void **state) {
    (void)state;
    const double lonlat[6] = {0, 0, 90, 0, 0, 90};
    const int64_t start[2] = {0, 3};
    const int64_t nodes[3] = {0, 1, 2};
    dpsm_grid *g = NULL;
    double area[3], xy[6];
    CHECK_OK(NULL, dpsm_create_mesh_geographic(0, 3, lonlat, 1, start, nodes, &g));
    CHECK_OK(g, dpsm_get_cell_centres(g, xy, area));
    const double octant = kPi * kEarthRadius * kEarthRadius / 2;
    REQUIRE(fabs(area[0] - octant) < 1e-12 * octant, "the octant's area %.17g, expected %.17g", area[0], octant);
    /* Its centre: the direction (1, 1, 1), 35.26 degrees up at 45 east (to the plane's centroid's precision). */
    REQUIRE(fabs(xy[0] - 45.0) < 1e-9 && xy[1] > 30.0 && xy[1] < 40.0, "centre (%g, %g)", xy[0], xy[1]);
    dpsm_destroy(g);
    CHECK_OK(NULL, dpsm_create_dual_mesh_geographic(0, 3, lonlat, 1, nodes, &g));
    CHECK_OK(g, dpsm_get_cell_centres(g, xy, area));
    REQUIRE(fabs(sum_of(area, 3) - octant) < 1e-12 * octant && fabs(area[1] - octant / 3) < 1e-12 * octant,
            "the dual's cells share the octant: %.17g", sum_of(area, 3));
    REQUIRE(memcmp(xy, lonlat, sizeof lonlat) == 0, "the dual's cells stand at their nodes, in degrees");
    dpsm_destroy(g);
}

/* An n x n patch of quads `step` degrees wide from (lon0, lat0); with
 * `mirror` a second, unconnected patch at (-lon0, lat0) too, which moves the
 * projection's centre far from the first. Cells of the first patch first. */
static dpsm_grid *patch(int n, double lon0, double lat0, double step, int mirror) {
    const int copies = mirror ? 2 : 1;
    const int64_t per = (int64_t)(n + 1) * (n + 1), cells = (int64_t)n * n;
    double *lonlat = calloc((size_t)(2 * per * copies), sizeof(double));
    int64_t *start = calloc((size_t)(cells * copies + 1), sizeof(int64_t));
    int64_t *nodes = calloc((size_t)(4 * cells * copies), sizeof(int64_t));
    for (int c = 0; c < copies; ++c) {
        for (int j = 0; j <= n; ++j)
            for (int i = 0; i <= n; ++i) {
                const int64_t k = c * per + i + (n + 1) * j;
                lonlat[2 * k] = (c ? -lon0 - n * step : lon0) + i * step;
                lonlat[2 * k + 1] = lat0 + j * step;
            }
        for (int64_t q = 0; q < cells; ++q) {
            const int64_t i = q % n, j = q / n, n0 = c * per + i + (n + 1) * j, at = c * cells + q;
            const int64_t corner[4] = {n0, n0 + 1, n0 + n + 2, n0 + n + 1};
            for (int k = 0; k < 4; ++k) nodes[4 * at + k] = corner[k];
            start[at + 1] = 4 * (at + 1);
        }
    }
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_mesh_geographic(0, per * copies, lonlat, cells * copies, start, nodes, &g));
    free(lonlat), free(start), free(nodes);
    return g;
}

/* The same cells, on a mesh whose projection is centred on them and on one
 * whose centre lies 25 degrees away (scale factor 1.05): the same areas,
 * the same stable sub-step (distances on the sphere) and, after a collapse,
 * the same heights (gradients over offsets measured on the sphere). */
static void test_geographic_patch_does_not_depend_on_the_projection(void **state) {
    (void)state;
    const int n = 12;
    const double lon0 = 25.0, lat0 = 20.0, step = 0.01;
    dpsm_grid *alone = patch(n, lon0, lat0, step, 0), *far = patch(n, lon0, lat0, step, 1);
    const int64_t cells = (int64_t)n * n;
    double *xy = calloc((size_t)(4 * cells), sizeof(double)), *area = calloc((size_t)(2 * cells), sizeof(double));
    double *far_xy = calloc((size_t)(4 * cells), sizeof(double)), *far_area = calloc((size_t)(2 * cells), sizeof(double));
    CHECK_OK(alone, dpsm_get_cell_centres(alone, xy, area));
    CHECK_OK(far, dpsm_get_cell_centres(far, far_xy, far_area));
    double worst_area = 0.0, worst_centre = 0.0;
    for (int64_t c = 0; c < cells; ++c) {
        worst_area = fmax(worst_area, fabs(far_area[c] - area[c]) / area[c]);
        worst_centre = fmax(worst_centre, fmax(fabs(far_xy[2 * c] - xy[2 * c]), fabs(far_xy[2 * c + 1] - xy[2 * c + 1])));
    }
    REQUIRE(worst_area < 1e-9, "areas differ by %g", worst_area);
    REQUIRE(worst_centre < 1e-6 * step, "centres differ by %g degrees", worst_centre);
    /* A cell 0.01 degrees (1.1 km by 1.04 km) wide: its area on the sphere. */
    const double expected = kEarthRadius * kEarthRadius * (step * kPi / 180) *
                            (sin((lat0 + step) * kPi / 180) - sin(lat0 * kPi / 180));
    REQUIRE(fabs(area[0] - expected) < 1e-6 * expected, "a cell's area %.17g m2, the zone's %.17g", area[0], expected);
    double dt_alone = 0.0, dt_far = 0.0;
    CHECK_OK(alone, dpsm_stable_dt(alone, &dt_alone));
    CHECK_OK(far, dpsm_stable_dt(far, &dt_far));
    REQUIRE(fabs(dt_far - dt_alone) < 1e-9 * dt_alone, "stable dt %.17g alone, %.17g far from the centre", dt_alone,
            dt_far);
    /* Degrees are not metres: a 1 km cell steps with sub-steps of about (1 km)^2. */
    REQUIRE(dt_alone > 1e4, "stable dt %g s on 1 km cells (nu = 1)", dt_alone);
    /* A cone 4 km high and 4.4 km wide (slope 0.9) collapses. */
    double *h = calloc((size_t)(2 * cells), sizeof(double)), *h_far = calloc((size_t)(2 * cells), sizeof(double));
    for (int64_t c = 0; c < cells; ++c) {
        const double dx = (xy[2 * c] - (lon0 + 0.5 * n * step)) * cos(lat0 * kPi / 180), dy = xy[2 * c + 1] - (lat0 + 0.5 * n * step);
        h[c] = fmax(0.0, 1e5 * (0.04 - hypot(dx, dy)));
    }
    memcpy(h_far, h, sizeof(double) * (size_t)cells);
    CHECK_OK(alone, dpsm_set_heights(alone, h));
    CHECK_OK(far, dpsm_set_heights(far, h_far));
    CHECK_OK(alone, dpsm_step(alone, 50 * dt_alone));
    CHECK_OK(far, dpsm_step(far, 50 * dt_alone));
    CHECK_OK(alone, dpsm_get_heights(alone, h));
    CHECK_OK(far, dpsm_get_heights(far, h_far));
    double worst = 0.0, moved = 0.0, top = 0.0;
    for (int64_t c = 0; c < cells; ++c) top = fmax(top, h[c]);
    for (int64_t c = 0; c < cells; ++c) worst = fmax(worst, fabs(h_far[c] - h[c]));
    for (int64_t c = 0; c < cells; ++c) {
        const double dx = (xy[2 * c] - (lon0 + 0.5 * n * step)) * cos(lat0 * kPi / 180), dy = xy[2 * c + 1] - (lat0 + 0.5 * n * step);
        moved = fmax(moved, fabs(h[c] - fmax(0.0, 1e5 * (0.04 - hypot(dx, dy)))));
    }
    print_message("geographic patch: stable dt %.6g s; after 50 of them the cone moved by up to %.4g m; the mesh "
                  "centred 25 degrees away differs by %.3g m (%.3g of the height %.4g m)\n",
                  dt_alone, moved, worst, worst / top, top);
    REQUIRE(moved > 1.0, "the cone did not move (%g m)", moved);
    /* What is left are the chords' directions in the plane, off by d r / (4 R^2)
     * (2e-5 rad): 1.4e-5 of the height. Measured in planar offsets the
     * gradients would differ by the scale factor, 1.2e-2 of it. */
    REQUIRE(worst < 1e-4 * top, "the heights depend on the projection's centre: %g m of %g", worst, top);
    free(xy), free(area), free(far_xy), free(far_area), free(h), free(h_far);
    dpsm_destroy(alone);
    dpsm_destroy(far);
}

static void test_geographic_refusals_and_restart(void **state) {
    (void)state;
    double lonlat[8] = {10, 50, 10.01, 50, 10.01, 50.01, 10, 50.01};
    const int64_t start[2] = {1, 5};
    const int64_t nodes[4] = {1, 2, 3, 4};
    dpsm_grid *g = NULL;
    lonlat[5] = 90.5;
    EXPECT_CREATE_FAIL(dpsm_create_mesh_geographic(1, 4, lonlat, 1, start, nodes, &g), g, DPSM_ERR_INVALID_VALUE,
                       "dpsm_create_mesh_geographic: node_lonlat(2, 3) (latitude of node 3) = 90.5 is not within [-90, 90]");
    lonlat[5] = 50.01;
    lonlat[0] = 600;
    EXPECT_CREATE_FAIL(dpsm_create_mesh_geographic(1, 4, lonlat, 1, start, nodes, &g), g, DPSM_ERR_INVALID_VALUE,
                       "node_lonlat(1, 1) (longitude of node 1) = 600 is not within [-540, 540]");
    lonlat[0] = NAN;
    EXPECT_CREATE_FAIL(dpsm_create_mesh_geographic(1, 4, lonlat, 1, start, nodes, &g), g, DPSM_ERR_INVALID_VALUE,
                       "node_lonlat(1, 1)");
    lonlat[0] = 10;
    const double across[10] = {10, 50, 10.01, 50, 10.01, 50.01, 10, 50.01, -170, -50};
    EXPECT_CREATE_FAIL(dpsm_create_mesh_geographic(1, 5, across, 1, start, nodes, &g), g, DPSM_ERR_INVALID_VALUE,
                       "node 5 (-170, -50) lies ");
    REQUIRE(strstr(dpsm_last_error(NULL), "within 90 degrees of arc of their centre"), "%s", dpsm_last_error(NULL));
    EXPECT_CREATE_FAIL(dpsm_create_mesh_geographic(2, 4, lonlat, 1, start, nodes, &g), g, DPSM_ERR_INVALID_VALUE,
                       "start_index = 2");
    /* The median dual's geographic constructor, counting from 0. */
    const int64_t triangles[6] = {0, 1, 2, 0, 2, 3}, beyond[6] = {0, 1, 2, 0, 2, 7};
    lonlat[5] = 90.5;
    EXPECT_CREATE_FAIL(dpsm_create_dual_mesh_geographic(0, 4, lonlat, 2, triangles, &g), g, DPSM_ERR_INVALID_VALUE,
                       "dpsm_create_dual_mesh_geographic: node_lonlat[5] (latitude of node 2) = 90.5 is not within [-90, 90]");
    lonlat[5] = 50.01;
    EXPECT_CREATE_FAIL(dpsm_create_dual_mesh_geographic(2, 4, lonlat, 2, triangles, &g), g, DPSM_ERR_INVALID_VALUE,
                       "start_index = 2");
    EXPECT_CREATE_FAIL(dpsm_create_dual_mesh_geographic(0, 4, lonlat, 2, beyond, &g), g, DPSM_ERR_INVALID_VALUE,
                       "triangle_nodes[5] (triangle 1) = 7 is not a node index in [0, 3]");
    EXPECT_CREATE_FAIL(dpsm_create_dual_mesh_geographic(0, 4, NULL, 2, triangles, &g), g, DPSM_ERR_NULL_POINTER,
                       "node_lonlat is NULL");
    REQUIRE(dpsm_create_dual_mesh_geographic(0, 4, lonlat, 2, triangles, NULL) == DPSM_ERR_NULL_POINTER,
            "a NULL out is not refused");

    /* A restart file keeps the mesh in degrees: the loaded copy steps bit for bit. */
    CHECK_OK(NULL, dpsm_create_mesh_geographic(1, 4, lonlat, 1, start, nodes, &g));
    const int64_t tri_nodes[6] = {0, 1, 2, 0, 2, 3};
    dpsm_grid *dual = NULL;
    CHECK_OK(NULL, dpsm_create_dual_mesh_geographic(0, 4, lonlat, 2, tri_nodes, &dual));
    const double h[4] = {3000.0, 0.0, 0.0, 0.0};
    CHECK_OK(dual, dpsm_set_heights(dual, h));
    char path[64];
    snprintf(path, sizeof path, "/tmp/dpsm_test_geo_%ld.dpsm", (long)getpid());
    CHECK_OK(dual, dpsm_save(dual, path));
    FILE *f = fopen(path, "rb");
    unsigned char header[12] = {0};
    REQUIRE(f && fread(header, 1, 12, f) == 12, "cannot read %s", path);
    fclose(f);
    REQUIRE(header[8] == 8, "a geographic mesh is saved as version %u, not 8", header[8]);
    dpsm_grid *loaded = NULL;
    CHECK_OK(NULL, dpsm_load(path, &loaded));
    unlink(path);
    double dt = 0.0, dt_loaded = 0.0;
    CHECK_OK(dual, dpsm_stable_dt(dual, &dt));
    CHECK_OK(loaded, dpsm_stable_dt(loaded, &dt_loaded));
    REQUIRE(dt == dt_loaded, "stable dt %.17g, loaded %.17g", dt, dt_loaded);
    CHECK_OK(dual, dpsm_step(dual, 20 * dt));
    CHECK_OK(loaded, dpsm_step(loaded, 20 * dt));
    double a[4], b[4];
    CHECK_OK(dual, dpsm_get_heights(dual, a));
    CHECK_OK(loaded, dpsm_get_heights(loaded, b));
    REQUIRE(memcmp(a, b, sizeof a) == 0 && a[0] < 3000.0, "the loaded mesh steps otherwise: %.17g vs %.17g", a[0], b[0]);
    dpsm_destroy(loaded);
    dpsm_destroy(dual);
    dpsm_destroy(g);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_graph_right_triangles_on_the_edge),
        cmocka_unit_test(test_graph_right_triangle_inside),
        cmocka_unit_test(test_graph_missing_face_is_named),
        cmocka_unit_test(test_coincident_nodes_are_refused),
        cmocka_unit_test(test_cell_centres),
        cmocka_unit_test(test_geographic_octant),
        cmocka_unit_test(test_geographic_patch_does_not_depend_on_the_projection),
        cmocka_unit_test(test_geographic_refusals_and_restart),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
