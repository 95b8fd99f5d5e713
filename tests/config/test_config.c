/* The run configuration (src/config/): good files read and built into the
 * scene they describe; bad ones refused with the file, the line and the key
 * path of the problem. Each test writes its files into a fresh folder. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
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

#include "config/config.h"
#include "mesh_files.h"
#include "ugrid_file.h"

static char folder[256];

static int make_folder(void **state) {
    (void)state;
    snprintf(folder, sizeof folder, "%s/dpsm-config-XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    return mkdtemp(folder) ? 0 : -1;
}

static int remove_folder(void **state) {
    (void)state;
    char command[512];
    snprintf(command, sizeof command, "rm -rf '%s'", folder);
    return system(command) == 0 ? 0 : -1;
}

/* Writes `text` to <folder>/<name> and returns the path (static storage). */
static const char *write_text(const char *name, const char *text) {
    static char path[512];
    snprintf(path, sizeof path, "%s/%s", folder, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    return path;
}

static void in_folder(char *out, size_t size, const char *name) { snprintf(out, size, "%s/%s", folder, name); }

/* Reads `text` as dpsm.yaml, expects a refusal and a message that ends as
 * "dpsm.yaml:<line>: <rest>" says. */
static void expect_refusal(const char *text, int line, const char *rest) {
    const char *path = write_text("dpsm.yaml", text);
    struct config c;
    char message[CONFIG_MESSAGE_MAX] = "";
    assert_int_not_equal(config_read(path, &c, message, sizeof message), 0);
    char expected[CONFIG_MESSAGE_MAX];
    snprintf(expected, sizeof expected, "%s:%d: %s", path, line, rest);
    if (strncmp(message, expected, strlen(expected)) != 0)
        fail_msg("message\n  %s\nexpected to begin with\n  %s", message, expected);
}

static const char kColumn[] = "grid: {kind: 2d, nx: 64, ny: 48, dx: 0.05, dy: 0.05}\n"
                              "repose_angle: 30\n"
                              "mobility: 1.0\n"
                              "boundaries: {xmin: wall, xmax: open, ymin: wall, ymax: open}\n"
                              "initial: {scene: column, radius: 0.6, height: 0.5}\n"
                              "time: {step: 0.05, end: 1.0}\n"
                              "output: {file: out.nc, every: 0.25}\n";

static void column_configuration_is_read_and_built(void **state) {
    (void)state;
    struct config c;
    char message[CONFIG_MESSAGE_MAX] = "";
    const char *path = write_text("column.yaml", kColumn);
    assert_int_equal(config_read(path, &c, message, sizeof message), 0);
    assert_int_equal(c.grid_kind, CONFIG_GRID_2D);
    assert_int_equal(c.nx, 64);
    assert_int_equal(c.ny, 48);
    assert_true(c.dx == 0.05 && c.dy == 0.05);
    assert_true(c.has_repose_angle && c.repose_angle_degrees == 30);
    assert_true(c.has_mobility && c.mobility == 1.0);
    assert_int_equal(c.boundary[DPSM_XMIN], DPSM_WALL);
    assert_int_equal(c.boundary[DPSM_XMAX], DPSM_OPEN);
    assert_int_equal(c.boundary[DPSM_YMIN], DPSM_WALL);
    assert_int_equal(c.boundary[DPSM_YMAX], DPSM_OPEN);
    assert_int_equal(c.boundary[DPSM_MESH_EDGE], CONFIG_SIDE_DEFAULT);
    assert_int_equal(c.initial.kind, CONFIG_FIELD_COLUMN);
    assert_int_equal(c.source.kind, CONFIG_FIELD_NONE);
    assert_true(c.time_step == 0.05 && c.time_end == 1.0);
    char out[512];
    in_folder(out, sizeof out, "out.nc"); /* named from the configuration's folder */
    assert_true(c.has_output && c.output_every == 0.25);
    assert_string_equal(c.output_file, out);

    struct config_scene s;
    assert_int_equal(config_build(&c, &s, message, sizeof message), 0);
    assert_int_equal(s.cell_count, 64 * 48);
    assert_null(s.source);
    double h[64 * 48];
    assert_int_equal(dpsm_get_heights(s.grid, h), DPSM_OK);
    /* The centre is (1.6, 1.2): cell (31, 23) has its centre 0.025 from it in
     * x and y; cell (44, 23) lies 0.6255 away, outside the radius 0.6, cell
     * (43, 23) 0.5755 away, inside. */
    assert_true(h[31 + 64 * 23] == 0.5);
    assert_true(h[44 + 64 * 23] == 0.0);
    assert_true(h[43 + 64 * 23] == 0.5);
    assert_true(h[0] == 0.0);
    double volume = 0;
    for (int k = 0; k < 64 * 48; ++k) volume += h[k] * 0.05 * 0.05;
    double total;
    assert_int_equal(dpsm_get_mass(s.grid, DPSM_MASS_TOTAL, &total), DPSM_OK);
    assert_true(fabs(total - volume) < 1e-12);
    /* The column's area is near pi r^2. */
    assert_true(fabs(volume / 0.5 - 3.14159265358979 * 0.36) < 0.02);
    config_scene_free(&s);
}

static void one_d_cone_and_axisymmetric_constant(void **state) {
    (void)state;
    struct config c;
    struct config_scene s;
    char message[CONFIG_MESSAGE_MAX] = "";
    const char *path = write_text("cone.yaml", "grid:\n"
                                               "  kind: 1d\n"
                                               "  nx: 10\n"
                                               "  dx: 0.1\n"
                                               "boundaries: {xmin: open}\n"
                                               "initial: {scene: cone, radius: 0.5, height: 1}\n"
                                               "source: {constant: 0.25}\n"
                                               "time: {step: 0.1, end: 0.3}\n");
    assert_int_equal(config_read(path, &c, message, sizeof message), 0);
    assert_int_equal(c.grid_kind, CONFIG_GRID_1D);
    assert_int_equal(c.boundary[DPSM_XMIN], DPSM_OPEN);
    assert_int_equal(c.boundary[DPSM_XMAX], CONFIG_SIDE_DEFAULT);
    assert_int_equal(config_build(&c, &s, message, sizeof message), 0);
    double h[10];
    dpsm_get_heights(s.grid, h);
    /* centre 0.5; cell 4 at 0.45: 1 - 0.05/0.5 */
    assert_true(fabs(h[4] - 0.9) < 1e-12 && fabs(h[5] - 0.9) < 1e-12);
    assert_true(fabs(h[0] - 0.1) < 1e-12);
    assert_non_null(s.source);
    assert_true(s.source[0] == 0.25 && s.source[9] == 0.25);
    config_scene_free(&s);

    path = write_text("axi.yaml", "grid: {kind: axisymmetric, nr: 8, dr: 0.5}\n"
                                  "boundaries: {xmax: wall}\n"
                                  "initial: {scene: column, radius: 1.0, height: 2}\n"
                                  "time: {step: 1, end: 2}\n");
    assert_int_equal(config_read(path, &c, message, sizeof message), 0);
    assert_int_equal(c.grid_kind, CONFIG_GRID_AXISYMMETRIC);
    assert_int_equal(c.nx, 8);
    assert_int_equal(config_build(&c, &s, message, sizeof message), 0);
    double r[8];
    dpsm_get_heights(s.grid, r);
    /* radii 0.25, 0.75 inside; 1.25 outside */
    assert_true(r[0] == 2 && r[1] == 2 && r[2] == 0);
    config_scene_free(&s);
}

static void fields_from_netcdf_files(void **state) {
    (void)state;
    double h[3 * 4], q[3 * 4];
    for (int k = 0; k < 12; ++k) h[k] = 0.1 * k, q[k] = -0.01 * k;
    char file[512];
    in_folder(file, sizeof file, "fields.nc");
    const char *dims[2] = {"y", "x"};
    size_t lengths[2] = {3, 4};
    assert_int_equal(write_field_file(file, "h", 2, dims, lengths, h), 0);
    char q_file[512];
    in_folder(q_file, sizeof q_file, "q.nc");
    assert_int_equal(write_field_file(q_file, "q", 2, dims, lengths, q), 0);
    const char *path = write_text("files.yaml", "grid: {kind: 2d, nx: 4, ny: 3, dx: 1, dy: 2}\n"
                                                "initial: {file: fields.nc, variable: h}\n"
                                                "source: {file: q.nc, variable: q}\n"
                                                "time: {step: 1, end: 3}\n");
    struct config c;
    struct config_scene s;
    char message[CONFIG_MESSAGE_MAX] = "";
    assert_int_equal(config_read(path, &c, message, sizeof message), 0);
    assert_string_equal(c.initial.file, file);
    assert_string_equal(c.initial.variable, "h");
    assert_int_equal(config_build(&c, &s, message, sizeof message), 0);
    double got[12];
    dpsm_get_heights(s.grid, got);
    assert_memory_equal(got, h, sizeof h);
    assert_memory_equal(s.source, q, sizeof q);
    config_scene_free(&s);

    /* The same variable against a grid of another shape, and a missing variable. */
    path = write_text("files.yaml", "grid: {kind: 2d, nx: 3, ny: 4, dx: 1, dy: 2}\n"
                                    "initial: {file: fields.nc, variable: h}\n"
                                    "time: {step: 1, end: 3}\n");
    assert_int_equal(config_read(path, &c, message, sizeof message), 0);
    assert_int_not_equal(config_build(&c, &s, message, sizeof message), 0);
    assert_non_null(strstr(message, "fields.nc: variable \"h\": expected dimensions (y, x) of 4 x 3"));
    assert_null(s.grid);
    path = write_text("files.yaml", "grid: {kind: 2d, nx: 4, ny: 3, dx: 1, dy: 2}\n"
                                    "initial: {file: fields.nc, variable: height}\n"
                                    "time: {step: 1, end: 3}\n");
    assert_int_equal(config_read(path, &c, message, sizeof message), 0);
    assert_int_not_equal(config_build(&c, &s, message, sizeof message), 0);
    assert_non_null(strstr(message, "fields.nc: no variable \"height\""));
    /* Missing data (the default fill value) and values beyond the range. */
    h[5] = 9.969209968386869e36;
    assert_int_equal(write_field_file(file, "h", 2, dims, lengths, h), 0);
    path = write_text("files.yaml", "grid: {kind: 2d, nx: 4, ny: 3, dx: 1, dy: 2}\n"
                                    "initial: {file: fields.nc, variable: h}\n"
                                    "time: {step: 1, end: 3}\n");
    assert_int_equal(config_read(path, &c, message, sizeof message), 0);
    assert_int_not_equal(config_build(&c, &s, message, sizeof message), 0);
    assert_non_null(strstr(message, "fields.nc: variable \"h\": value 5 (from 0) is missing (the fill value)"));
    h[5] = 1e51;
    assert_int_equal(write_field_file(file, "h", 2, dims, lengths, h), 0);
    assert_int_not_equal(config_build(&c, &s, message, sizeof message), 0);
    assert_non_null(strstr(message, "fields.nc: variable \"h\": value 5 (from 0) is 1e+51, not a finite height or rate"));
    path = write_text("files.yaml", "grid: {kind: 2d, nx: 4, ny: 3, dx: 1, dy: 2}\n"
                                    "initial: {file: nowhere.nc, variable: h}\n"
                                    "time: {step: 1, end: 3}\n");
    assert_int_equal(config_read(path, &c, message, sizeof message), 0);
    assert_int_not_equal(config_build(&c, &s, message, sizeof message), 0);
    assert_non_null(strstr(message, "nowhere.nc: cannot open as netCDF"));
}

static void mesh_from_a_ugrid_file(void **state) {
    (void)state;
    for (int start_index = 0; start_index <= 1; ++start_index) {
        char file[512];
        in_folder(file, sizeof file, "bed.nc");
        assert_int_equal(write_ugrid_test_mesh(file, start_index), 0);
        const char *path = write_text("mesh.yaml", "grid: {kind: mesh, file: bed.nc}\n"
                                                   "boundaries: {edge: open, level: 0}\n"
                                                   "initial: {scene: cone, radius: 2, height: 1}\n"
                                                   "time: {step: 0.5, end: 1}\n");
        struct config c;
        struct config_scene s;
        char message[CONFIG_MESSAGE_MAX] = "";
        assert_int_equal(config_read(path, &c, message, sizeof message), 0);
        assert_int_equal(c.grid_kind, CONFIG_GRID_MESH);
        assert_int_equal(c.boundary[DPSM_MESH_EDGE], DPSM_OPEN);
        if (config_build(&c, &s, message, sizeof message) != 0) fail_msg("%s", message);
        assert_true(s.has_mesh);
        assert_int_equal(s.cell_count, UGRID_TEST_FACES);
        const struct config_mesh *m = &s.mesh;
        assert_int_equal(m->node_count, UGRID_TEST_NODES);
        assert_int_equal(m->face_count, UGRID_TEST_FACES);
        assert_int_equal(m->edge_count, UGRID_TEST_EDGES);
        for (int f = 0; f < UGRID_TEST_FACES; ++f) {
            int n = ugrid_test_face_nodes[f][3] < 0 ? 3 : 4;
            assert_int_equal(m->face_node_start[f + 1] - m->face_node_start[f], n);
            for (int k = 0; k < n; ++k) {
                int64_t p = m->face_node_start[f] + k;
                assert_int_equal(m->face_nodes[p], ugrid_test_face_nodes[f][k]);
                /* edge k of face f joins its nodes k and k+1, either way round */
                int64_t e = m->face_edges[p], a = m->edge_nodes[2 * e], b = m->edge_nodes[2 * e + 1];
                int64_t u = ugrid_test_face_nodes[f][k], v = ugrid_test_face_nodes[f][(k + 1) % n];
                assert_true((a == u && b == v) || (a == v && b == u));
            }
        }
        assert_true(m->node_x[5] == 2 && m->node_y[5] == 1);
        /* Centre (1, 1); the first square's centroid (0.5, 0.5) is sqrt(0.5) away. */
        double h[UGRID_TEST_FACES];
        dpsm_get_heights(s.grid, h);
        assert_true(fabs(h[0] - (1 - sqrt(0.5) / 2)) < 1e-12);
        config_scene_free(&s);
    }
}

static void refusals_name_the_line_and_the_key(void **state) {
    (void)state;
    expect_refusal("grid: {kind: 2d, nx: 64, ny: 48, dx: 0.05, dy: 0.05}\n"
                   "initial: {constant: 0}\n"
                   "tme: {step: 0.05, end: 1.0}\n",
                   3, "tme: unknown key (expected one of: grid, repose_angle, mobility, boundaries, initial, source, "
                      "time, output)");
    expect_refusal("grid:\n"
                   "  kind: 2d\n"
                   "  nx: 64\n"
                   "  ny: 48\n"
                   "  nz: 3\n"
                   "  dx: 0.05\n",
                   5, "grid.nz: unknown key for a 2d grid (expected one of: kind, nx, ny, dx, dy)");
    expect_refusal("# a comment\n"
                   "grid:\n"
                   "  kind: 2d\n"
                   "  nx: sixty\n",
                   4, "grid.nx: expected a positive integer, got \"sixty\"");
    expect_refusal("grid:\n"
                   "  kind: 2d\n"
                   "  nx: 64\n"
                   "  ny: -48\n",
                   4, "grid.ny: expected a positive integer, got \"-48\"");
    expect_refusal("grid: {kind: 2d, nx: 2.5, ny: 48, dx: 0.05, dy: 0.05}\n", 1,
                   "grid.nx: expected a positive integer, got \"2.5\"");
    expect_refusal("\n\ngrid:\n  kind: 2d\n  nx: 64\n  ny: 48\n  dx: 0.05\n  dy: [0.05]\n", 8,
                   "grid.dy: expected a positive number, got a list");
    expect_refusal("repose_angle: 30\n"
                   "initial: {constant: 0}\n"
                   "time: {step: 0.05, end: 1.0}\n",
                   1, "grid: missing (a required key)");
    expect_refusal("repose_angle: 30\n"
                   "grid:\n"
                   "  kind: 3d\n",
                   3, "grid.kind: expected 1d, 2d, axisymmetric, mesh or dual_mesh, got \"3d\"");
    /* A missing key is reported where its mapping begins. */
    expect_refusal("grid:\n"
                   "  kind: 1d\n"
                   "  nx: 4\n",
                   2, "grid.dx: missing (a required key)");
    expect_refusal("grid: {kind: 1d, nx: 4, dx: 1}\n"
                   "boundaries:\n"
                   "  xmin: open\n"
                   "  ymin: wall\n",
                   4, "boundaries.ymin: unknown key for a 1d grid (expected one of: xmin, xmax)");
    expect_refusal("grid: {kind: axisymmetric, nr: 4, dr: 1}\n"
                   "boundaries: {xmin: open}\n",
                   2, "boundaries.xmin: unknown key for an axisymmetric grid");
    expect_refusal("grid: {kind: 1d, nx: 4, dx: 1}\n"
                   "boundaries: {xmin: porous}\n",
                   2, "boundaries.xmin: expected wall or open, got \"porous\"");
    expect_refusal("grid: {kind: 1d, nx: 4, dx: 1}\n"
                   "repose_angle: 95\n",
                   2, "repose_angle: expected degrees between 0 and 90, got \"95\"");
    expect_refusal("grid: {kind: 1d, nx: 4, dx: 1}\n"
                   "mobility: -1\n",
                   2, "mobility: expected a positive number, got \"-1\"");
    expect_refusal("grid: {kind: 1d, nx: 4, dx: 1}\n"
                   "initial: {scene: pyramid, radius: 1, height: 1}\n",
                   2, "initial.scene: expected column or cone, got \"pyramid\"");
    expect_refusal("grid: {kind: 1d, nx: 4, dx: 1}\n"
                   "initial: {scene: cone, radius: 1}\n",
                   2, "initial.height: missing");
    expect_refusal("grid: {kind: 1d, nx: 4, dx: 1}\n"
                   "initial: {constant: 0}\n"
                   "source: {scene: cone, radius: 1, height: 1}\n",
                   3, "source: expected a constant or a file");
    expect_refusal("grid: {kind: 1d, nx: 4, dx: 1}\n"
                   "initial: {constant: 0}\n"
                   "time:\n"
                   "  step: 0\n"
                   "  end: 1\n",
                   4, "time.step: expected a positive number, got \"0\"");
    expect_refusal("grid: {kind: 1d, nx: 4, dx: 1}\n"
                   "initial: {constant: nan}\n",
                   2, "initial.constant: expected a number, got \"nan\"");
    expect_refusal("grid: {kind: 1d, nx: 4, dx: 1}\n"
                   "initial: {constant: 0}\n"
                   "time: {step: 1, end: 2}\n"
                   "output: {file: out.nc}\n",
                   4, "output.every: missing");
    expect_refusal("grid: {kind: 1d, nx: 4, dx: 1}\n"
                   "grid: {kind: 1d, nx: 4, dx: 1}\n",
                   2, "grid: given twice (first on line 1)");
    expect_refusal("grid: {kind: 1d, nx: 4, dx: 1\n"
                   "initial: {constant: 0}\n",
                   2, "not valid YAML");
    expect_refusal("- grid\n", 1, "(top level): expected a mapping of keys, got a list");
    expect_refusal("", 1, "(top level): the file holds no configuration");

    struct config c;
    char message[CONFIG_MESSAGE_MAX] = "";
    char missing[512];
    in_folder(missing, sizeof missing, "missing.yaml");
    assert_int_not_equal(config_read(missing, &c, message, sizeof message), 0);
    assert_non_null(strstr(message, "missing.yaml: cannot open the configuration"));
}

static void bad_mesh_files_are_refused(void **state) {
    (void)state;
    char file[512];
    in_folder(file, sizeof file, "plain.nc");
    const char *dims[1] = {"x"};
    size_t lengths[1] = {2};
    double v[2] = {0, 1};
    assert_int_equal(write_field_file(file, "h", 1, dims, lengths, v), 0);
    struct config_mesh mesh;
    char message[CONFIG_MESSAGE_MAX] = "";
    assert_int_not_equal(config_read_mesh(file, NULL, &mesh, message, sizeof message), 0);
    assert_non_null(strstr(message, "plain.nc: no UGRID mesh (no variable with cf_role = \"mesh_topology\")"));
    assert_null(mesh.node_x);
    in_folder(file, sizeof file, "nothing.nc");
    assert_int_not_equal(config_read_mesh(file, NULL, &mesh, message, sizeof message), 0);
    assert_non_null(strstr(message, "nothing.nc: cannot open the mesh file"));
}

/* ---- issue 36: files of production codes, boundaries, scenes ------------- */

/* Reads and builds `text` as dpsm.yaml; fails the test with the message if either refuses. */
static void build(const char *text, struct config *c, struct config_scene *s) {
    const char *path = write_text("dpsm.yaml", text);
    char message[CONFIG_MESSAGE_MAX] = "";
    if (config_read(path, c, message, sizeof message) || config_build(c, s, message, sizeof message))
        fail_msg("%s", message);
}

/* Reads and builds `text`; expects a refusal whose message holds every one of `parts` (NULL-ended). */
static void expect_build_refusal(const char *text, const char *const *parts) {
    const char *path = write_text("dpsm.yaml", text);
    struct config c;
    struct config_scene s;
    char message[CONFIG_MESSAGE_MAX] = "";
    if (config_read(path, &c, message, sizeof message) == 0) {
        if (config_build(&c, &s, message, sizeof message) == 0) {
            config_scene_free(&s);
            fail_msg("built, expected a refusal holding \"%s\"", parts[0]);
        }
        assert_null(s.grid);
    }
    for (const char *const *p = parts; *p; ++p)
        if (!strstr(message, *p)) fail_msg("message\n  %s\ndoes not hold\n  %s", message, *p);
}

#define REFUSED(text, ...) expect_build_refusal(text, (const char *const[]){__VA_ARGS__, NULL})

static void write_in_folder(const char *name, int (*writer)(const char *, int), int option) {
    char file[512];
    in_folder(file, sizeof file, name);
    assert_int_equal(writer(file, option), 0);
}

static int write_edges_only(const char *path, int unused) {
    (void)unused;
    return write_net_nodes_edges(path);
}

/* The library's faces that lie on the mesh's edge x = `at` (their nodes' x). */
static int on_line(const struct config_scene *s, int64_t face, double at) {
    const struct config_mesh *m = &s->mesh;
    return s->face_cells[2 * face + 1] < 0 && m->node_x[m->edge_nodes[2 * face]] == at &&
           m->node_x[m->edge_nodes[2 * face + 1]] == at;
}

/* Delft3D FM's 1D2D net file: the 2D topology read by name or alone, the
 * messages naming the topologies found, face and node variables. */
static void net_files_of_delft3d_fm(void **state) {
    (void)state;
    write_in_folder("net.nc", write_net_1d2d, 0);
    write_in_folder("two.nc", write_net_1d2d, 1);
    struct config c;
    struct config_scene s;
    build("grid: {kind: mesh, file: net.nc}\n"
          "initial: {file: net.nc, variable: mesh2d_face_z}\n"
          "time: {step: 1, end: 1}\n", &c, &s);
    assert_string_equal(s.mesh.topology, "mesh2d");
    assert_string_equal(s.mesh.format, "UGRID");
    assert_int_equal(s.cell_count, NET_FACES);
    assert_int_equal(s.mesh.edge_count, 19);
    double h[NET_FACES];
    dpsm_get_heights(s.grid, h);
    for (int f = 0; f < NET_FACES; ++f) assert_true(h[f] == 20.0 + f);
    assert_int_equal(s.mesh.group_count, 3); /* 0 (closed), inflow (1), outflow (2) */
    assert_string_equal(s.mesh.groups[1].name, "inflow");
    assert_int_equal(s.mesh.groups[1].number, 1);
    assert_int_equal(s.mesh.groups[1].edge_count, 2);
    config_scene_free(&s);
    build("grid: {kind: mesh, file: two.nc, topology: mesh2d_refined}\n"
          "initial: {constant: 1}\n"
          "time: {step: 1, end: 1}\n", &c, &s);
    assert_string_equal(s.mesh.topology, "mesh2d_refined");
    config_scene_free(&s);
    REFUSED("grid: {kind: mesh, file: two.nc}\ninitial: {constant: 1}\ntime: {step: 1, end: 1}\n",
            "dpsm.yaml:1: grid.file: ", "two.nc: it has 2 2D mesh topologies (mesh2d, mesh2d_refined); choose one with "
                                        "grid.topology");
    REFUSED("grid: {kind: mesh, file: net.nc, topology: mesh1d}\ninitial: {constant: 1}\ntime: {step: 1, end: 1}\n",
            "net.nc: topology \"mesh1d\" has topology_dimension = 1; dpsm needs a 2D topology: mesh2d");
    REFUSED("grid: {kind: mesh, file: net.nc, topology: mesh3d}\ninitial: {constant: 1}\ntime: {step: 1, end: 1}\n",
            "net.nc: no mesh topology \"mesh3d\" (grid.topology); the file has mesh1d (1D), network1d (1D), mesh2d (2D)");
    /* Values at the nodes on a mesh whose cells are its faces: refused, naming dual_mesh. */
    REFUSED("grid: {kind: mesh, file: net.nc}\ninitial: {file: net.nc, variable: mesh2d_node_z}\n"
            "time: {step: 1, end: 1}\n",
            "dpsm.yaml:2: initial: ", "\"mesh2d_node_z\" lies on the mesh's nodes (12 values, one per node)",
            "say grid.kind: dual_mesh");
    REFUSED("grid: {kind: dual_mesh, file: net.nc}\ninitial: {constant: 1}\ntime: {step: 1, end: 1}\n",
            "dual_mesh makes the median dual of triangles, and face 0 (from 0) of ", "has 4 nodes");
}

/* A net file of nodes and edges: its faces built from the edges. */
static void faces_from_nodes_and_edges(void **state) {
    (void)state;
    write_in_folder("edges.nc", write_edges_only, 0);
    struct config c;
    struct config_scene s;
    build("grid: {kind: mesh, file: edges.nc}\n"
          "initial: {scene: cone, centre: [15, 10], radius: 12, height: 5}\n"
          "time: {step: 1, end: 1}\n", &c, &s);
    assert_true(s.mesh.faces_from_edges);
    assert_int_equal(s.cell_count, 8); /* 4 squares, 4 triangles; the dangling edge bounds none */
    double area[8], total = 0;
    assert_int_equal(dpsm_get_cell_centres(s.grid, NULL, area), DPSM_OK);
    for (int k = 0; k < 8; ++k) total += area[k];
    assert_true(fabs(total - 600.0) < 1e-9);
    double h[8];
    dpsm_get_heights(s.grid, h);
    assert_true(h[0] > 0.0); /* the square (0, 0)-(10, 10) lies 11.2 m from (15, 10): inside the cone */
    config_scene_free(&s);
    REFUSED("grid: {kind: mesh, file: edges.nc}\ninitial: {file: edges.nc, variable: mesh2d_node_z}\n"
            "time: {step: 1, end: 1}\n",
            "\"mesh2d_node_z\" lies on the mesh's nodes (13 values, one per node)", "grid.kind: dual_mesh");
}

static void selafin_files(void **state) {
    (void)state;
    for (int precision = 0; precision < 2; ++precision) {
        write_in_folder("geo.slf", write_selafin, precision);
        struct config c;
        struct config_scene s;
        build("grid: {kind: dual_mesh, file: geo.slf}\n"
              "initial: {file: geo.slf, variable: BOTTOM}\n"
              "time: {step: 1, end: 1}\n", &c, &s);
        assert_string_equal(s.mesh.format, "Selafin");
        assert_true(s.cells_at_nodes);
        assert_int_equal(s.cell_count, SELAFIN_NODES);
        assert_int_equal(s.mesh.face_count, SELAFIN_TRIANGLES);
        double h[SELAFIN_NODES], xy[2 * SELAFIN_NODES];
        dpsm_get_heights(s.grid, h);
        dpsm_get_cell_centres(s.grid, xy, NULL);
        for (int n = 0; n < SELAFIN_NODES; ++n) {
            assert_true(h[n] == 2.0 + n);
            /* IPARAM's origin (1000, 2000) is added to the nodes. */
            assert_true(xy[2 * n] == 1000.0 + 10.0 * (n % 4) && xy[2 * n + 1] == 2000.0 + 10.0 * (n / 4));
        }
        config_scene_free(&s);
        build("grid: {kind: mesh, file: geo.slf}\ninitial: {constant: 1}\ntime: {step: 1, end: 1}\n", &c, &s);
        assert_int_equal(s.cell_count, SELAFIN_TRIANGLES);
        config_scene_free(&s);
    }
    REFUSED("grid: {kind: mesh, file: geo.slf}\ninitial: {file: geo.slf, variable: BOTTOM}\ntime: {step: 1, end: 1}\n",
            "\"BOTTOM\" lies on the mesh's nodes (16 values, one per node)", "say grid.kind: dual_mesh");
    REFUSED("grid: {kind: dual_mesh, file: geo.slf}\ninitial: {file: geo.slf, variable: bed}\n"
            "time: {step: 1, end: 1}\n",
            "geo.slf: no variable \"bed\"; the file has VELOCITY U, BOTTOM");
    /* A Selafin file cut short. */
    char file[512];
    in_folder(file, sizeof file, "geo.slf");
    FILE *f = fopen(file, "r+b");
    assert_non_null(f);
    assert_int_equal(ftruncate(fileno(f), 400), 0);
    fclose(f);
    REFUSED("grid: {kind: dual_mesh, file: geo.slf}\ninitial: {constant: 0}\ntime: {step: 1, end: 1}\n",
            "geo.slf: the file ends inside the record of IKLE");
}

static void gmsh_files(void **state) {
    (void)state;
    for (int version = 2; version <= 4; version += 2) {
        write_in_folder("river.msh", write_gmsh, version);
        REFUSED("grid: {kind: mesh, file: river.msh}\ninitial: {constant: 1}\ntime: {step: 1, end: 1}\n",
                "dpsm.yaml:1: grid: ", "river.msh: its nodes all lie within [-180, 180] x [-90, 90]",
                "they look like degrees", "grid.coordinates: geographic", "grid.coordinates: projected");
        struct config c;
        struct config_scene s;
        build("grid: {kind: mesh, file: river.msh, coordinates: projected}\n"
              "initial: {constant: 1}\n"
              "time: {step: 1, end: 1}\n", &c, &s);
        assert_string_equal(s.mesh.format, "gmsh");
        assert_int_equal(s.cell_count, GMSH_TRIANGLES);
        assert_int_equal(s.mesh.node_count, GMSH_NODES);
        assert_int_equal(s.mesh.group_count, 4);
        assert_string_equal(s.mesh.groups[0].name, "inflow");
        assert_string_equal(s.mesh.groups[1].name, "");
        assert_int_equal(s.mesh.groups[1].number, 2);
        assert_string_equal(s.mesh.groups[2].name, "outflow");
        for (int g = 0; g < 4; ++g) assert_int_equal(s.mesh.groups[g].edge_count, 2);
        config_scene_free(&s);
        build("grid: {kind: dual_mesh, file: river.msh, coordinates: projected}\n"
              "initial: {constant: 1}\n"
              "time: {step: 1, end: 1}\n", &c, &s);
        assert_int_equal(s.cell_count, GMSH_NODES);
        config_scene_free(&s);
    }
}

/* Opening groups of edges by name and number, and the levels beyond them. */
static void boundaries_a_host_can_state(void **state) {
    (void)state;
    write_in_folder("net.nc", write_net_1d2d, 0);
    write_in_folder("river.msh", write_gmsh, 4);
    struct config c;
    struct config_scene s;
    char message[CONFIG_MESSAGE_MAX];
    /* The inflow group (x = 0) open at level 10, the rest walls: sand comes in there only
     * (a slope of 1 over the 10 m from each cell to its mirror image). */
    const char *by_name = "grid: {kind: mesh, file: net.nc}\n"
                          "boundaries: {edge: wall, open: [inflow], level: 10}\n"
                          "initial: {constant: 0}\n"
                          "time: {step: 1, end: 1}\n";
    for (int pass = 0; pass < 2; ++pass) {
        build(pass ? "grid: {kind: mesh, file: net.nc}\n"
                     "boundaries: {edge: wall, open: [1], level: 10}\n"
                     "initial: {constant: 0}\n"
                     "time: {step: 1, end: 1}\n"
                   : by_name,
              &c, &s);
        assert_int_equal(dpsm_set_face_flux_recording(s.grid, 1), DPSM_OK);
        assert_int_equal(config_scene_before_step(&s, message, sizeof message), 0);
        assert_int_equal(dpsm_step(s.grid, 100.0), DPSM_OK);
        double fluxes[64], outflow;
        assert_int_equal(dpsm_get_face_fluxes(s.grid, fluxes, NULL), DPSM_OK);
        dpsm_get_mass(s.grid, DPSM_MASS_OUTFLOW, &outflow);
        assert_true(outflow < 0.0); /* it came in */
        int into = 0;
        for (int64_t f = 0; f < s.face_count; ++f) {
            if (s.face_cells[2 * f + 1] >= 0) continue;
            if (on_line(&s, f, 0.0)) into += fluxes[f] < 0.0; /* from outside into the cell */
            else assert_true(fluxes[f] == 0.0);
        }
        assert_int_equal(into, 2);
        config_scene_free(&s);
    }
    /* The reverse: an open edge with the groups named as walls. */
    build("grid: {kind: mesh, file: net.nc}\n"
          "boundaries: {edge: open, wall: [inflow, outflow, 0], level: 10}\n"
          "initial: {constant: 0}\n"
          "time: {step: 1, end: 1}\n", &c, &s);
    assert_int_equal(dpsm_step(s.grid, 100.0), DPSM_OK);
    double outflow;
    dpsm_get_mass(s.grid, DPSM_MASS_OUTFLOW, &outflow);
    assert_true(outflow == 0.0); /* every edge face is in a group named a wall */
    config_scene_free(&s);
    /* A level that follows the cells: nothing leaves a bed at rest 20 m up. */
    for (int follow = 0; follow < 2; ++follow) {
        build(follow ? "grid: {kind: mesh, file: net.nc}\n"
                       "boundaries: {edge: open, level: cell}\n"
                       "initial: {file: net.nc, variable: mesh2d_face_z}\n"
                       "time: {step: 1, end: 1}\n"
                     : "grid: {kind: mesh, file: net.nc}\n"
                       "boundaries: {edge: open, level: 0}\n"
                       "initial: {file: net.nc, variable: mesh2d_face_z}\n"
                       "time: {step: 1, end: 1}\n",
              &c, &s);
        assert_int_equal(s.levels_follow_cells, follow);
        assert_int_equal(config_scene_before_step(&s, message, sizeof message), 0);
        assert_int_equal(dpsm_step(s.grid, 100.0), DPSM_OK);
        dpsm_get_mass(s.grid, DPSM_MASS_OUTFLOW, &outflow);
        if (follow) assert_true(outflow == 0.0);
        else assert_true(outflow > 100.0); /* a level of 0 drains the bed */
        config_scene_free(&s);
    }
    /* Levels from a field of the file: the mean of each edge face's nodes. */
    build("grid: {kind: mesh, file: net.nc}\n"
          "boundaries: {edge: wall, open: [outflow], level: {file: net.nc, variable: mesh2d_node_z}}\n"
          "initial: {constant: 0}\n"
          "time: {step: 1, end: 1}\n", &c, &s);
    for (int64_t f = 0; f < s.face_count; ++f)
        if (on_line(&s, f, 30.0)) {
            const int64_t a = s.mesh.edge_nodes[2 * f], b = s.mesh.edge_nodes[2 * f + 1];
            assert_true(s.levels[f] == 0.5 * ((5.0 + a) + (5.0 + b)));
        }
    config_scene_free(&s);
    /* gmsh physical groups, by name and number; on the dual mesh each half of an edge. */
    build("grid: {kind: dual_mesh, file: river.msh, coordinates: projected}\n"
          "boundaries: {edge: wall, open: [outflow, 2], level: 3}\n"
          "initial: {constant: 0}\n"
          "time: {step: 1, end: 1}\n", &c, &s);
    assert_int_equal(dpsm_set_face_flux_recording(s.grid, 1), DPSM_OK);
    assert_int_equal(dpsm_step(s.grid, 10.0), DPSM_OK);
    double fluxes[64];
    assert_int_equal(dpsm_get_face_fluxes(s.grid, fluxes, NULL), DPSM_OK);
    int opened = 0;
    for (int64_t f = 0; f < s.face_count; ++f) {
        if (s.face_cells[2 * f + 1] >= 0) continue;
        const double x = s.mesh.node_x[s.face_cells[2 * f]], y = s.mesh.node_y[s.face_cells[2 * f]];
        /* The halves on y = 2 (outflow) and x = 2 (group 2); a corner's node has one of each. */
        const int open = y == 2.0 || x == 2.0;
        if (fluxes[f] != 0.0) assert_true(open), ++opened;
    }
    assert_int_equal(opened, 8);
    config_scene_free(&s);
    /* Refusals. */
    REFUSED("grid: {kind: mesh, file: net.nc}\nboundaries: {edge: wall, open: [inflow, harbour]}\n"
            "initial: {constant: 0}\ntime: {step: 1, end: 1}\n",
            "dpsm.yaml:2: boundaries.open[1]: no group \"harbour\" in ",
            "it has (name (number), or the number alone): 0, inflow (1), outflow (2)");
    REFUSED("grid: {kind: mesh, file: net.nc}\nboundaries: {edge: open}\n"
            "initial: {file: net.nc, variable: mesh2d_face_z}\ntime: {step: 1, end: 1}\n",
            "dpsm.yaml:2: boundaries: the edge is open and no boundaries.level is given",
            "its cells stand up to 27 m from 0", "sand would drain through it", "boundaries.level: cell");
    REFUSED("grid: {kind: mesh, file: net.nc}\nboundaries: {edge: wall, open: [outflow], level: {file: net.nc, "
            "variable: nothing}}\ninitial: {constant: 0}\ntime: {step: 1, end: 1}\n",
            "dpsm.yaml:2: boundaries.level: ", "net.nc: no variable \"nothing\"");
    expect_refusal("grid: {kind: mesh, file: net.nc}\nboundaries: {edge: open, open: [inflow]}\n", 2,
                   "boundaries.open: the edge is open already (edge: open)");
    expect_refusal("grid: {kind: mesh, file: net.nc}\nboundaries: {wall: [inflow]}\n", 2,
                   "boundaries.wall: the edge is a wall already (edge: wall, the default)");
    expect_refusal("grid: {kind: mesh, file: net.nc}\nboundaries: {edge: wall, level: cell}\n", 2,
                   "boundaries.level: no edge is open (edge: wall)");
    expect_refusal("grid: {kind: mesh, file: net.nc}\nboundaries: {edge: open, level: sea}\n", 2,
                   "boundaries.level: expected 0, cell, a number or {file, variable}, got \"sea\"");
    expect_refusal("grid: {kind: mesh, file: net.nc, coordinates: cartesian}\n", 1,
                   "grid.coordinates: expected geographic (longitude and latitude in degrees) or projected (metres)");
    expect_refusal("grid: {kind: 2d, nx: 4, ny: 4, dx: 1, dy: 1}\nboundaries: {xmin: open, level: 1}\n", 2,
                   "boundaries.level: unknown key for a 2d grid");
}

/* Scenes where the host wants them; a scene that puts sand on no cell. */
static void scenes_with_a_centre(void **state) {
    (void)state;
    write_in_folder("net.nc", write_net_1d2d, 0);
    struct config c;
    struct config_scene s;
    build("grid: {kind: mesh, file: net.nc}\n"
          "initial: {scene: column, centre: [25, 15], radius: 4, height: 2}\n"
          "time: {step: 1, end: 1}\n", &c, &s);
    double h[NET_FACES];
    dpsm_get_heights(s.grid, h);
    /* Only the triangles around (25, 15) have their centroids within 4 m. */
    for (int f = 0; f < NET_FACES; ++f) assert_true(h[f] == (f == 6 || f == 7 ? 2.0 : 0.0));
    config_scene_free(&s);
    REFUSED("grid: {kind: mesh, file: net.nc}\n"
            "initial: {scene: cone, centre: [500, 15], radius: 4, height: 2}\n"
            "time: {step: 1, end: 1}\n",
            "dpsm.yaml:2: initial: the cone puts sand on no cell: no cell's centre lies within its radius",
            "its centre (500, 15) lies", "give initial.centre: [x, y]");
    REFUSED("grid: {kind: 2d, nx: 4, ny: 4, dx: 1, dy: 1}\n"
            "initial: {scene: column, radius: 0.2, height: 1}\n"
            "time: {step: 1, end: 1}\n",
            "initial: the column puts sand on no cell", "its centre (2, 2) (the domain's centre)");
    expect_refusal("grid: {kind: 2d, nx: 4, ny: 4, dx: 1, dy: 1}\n"
                   "initial: {scene: column, centre: [1], radius: 1, height: 1}\n",
                   2, "initial.centre: expected [x, y], got a list");
}

/* Longitude and latitude: from the file's attributes, or said; refused when
 * they only look like degrees. */
static void meshes_in_degrees(void **state) {
    (void)state;
    write_in_folder("adcirc.nc", write_lonlat, 1);
    write_in_folder("bare.nc", write_lonlat, 0);
    struct config c;
    struct config_scene s;
    build("grid: {kind: dual_mesh, file: adcirc.nc}\n"
          "initial: {file: adcirc.nc, variable: depth_bed}\n"
          "time: {step: 60, end: 60}\n", &c, &s);
    assert_true(s.geographic);
    assert_int_equal(s.cell_count, LONLAT_NODES);
    double area[LONLAT_NODES], total = 0, dt = 0;
    dpsm_get_cell_centres(s.grid, NULL, area);
    for (int n = 0; n < LONLAT_NODES; ++n) total += area[n];
    /* 0.04 degrees square at 30 N: R^2 dlon (sin lat1 - sin lat0), about 4.4 km by 3.8 km. */
    const double d = 3.14159265358979323846 / 180, r = 6371008.8;
    const double expected = r * r * 0.04 * d * (sin(30.04 * d) - sin(30.0 * d));
    assert_true(fabs(total - expected) < 1e-4 * expected);
    dpsm_stable_dt(s.grid, &dt);
    assert_true(dt > 1e4); /* cells of a kilometre, not of 0.01 */
    config_scene_free(&s);
    REFUSED("grid: {kind: dual_mesh, file: bare.nc}\ninitial: {constant: 0}\ntime: {step: 1, end: 1}\n",
            "bare.nc: its nodes all lie within [-180, 180] x [-90, 90]", "they look like degrees",
            "grid.coordinates: geographic");
    build("grid: {kind: dual_mesh, file: bare.nc, coordinates: geographic}\n"
          "initial: {scene: cone, centre: [-79.98, 30.02], radius: 1500, height: 800}\n"
          "time: {step: 60, end: 60}\n", &c, &s);
    double h[LONLAT_NODES];
    dpsm_get_heights(s.grid, h);
    assert_true(h[12] == 800.0); /* the node at the centre */
    assert_true(h[0] == 0.0);    /* 3 km away */
    config_scene_free(&s);
    /* ADCIRC's depth is positive down: refused as heights unless said, then negated. */
    REFUSED("grid: {kind: dual_mesh, file: adcirc.nc}\ninitial: {file: adcirc.nc, variable: depth}\n"
            "time: {step: 1, end: 1}\n",
            "dpsm.yaml:2: initial: ", "adcirc.nc: \"depth\" holds depths, positive down (depth:standard_name = "
            "\"depth_below_geoid\"), and dpsm's heights are elevations, positive up: say initial.positive: down");
    build("grid: {kind: dual_mesh, file: adcirc.nc}\n"
          "initial: {file: adcirc.nc, variable: depth, positive: down}\n"
          "boundaries: {edge: open, level: {file: adcirc.nc, variable: depth, positive: down}}\n"
          "time: {step: 60, end: 60}\n", &c, &s);
    dpsm_get_heights(s.grid, h);
    for (int n = 0; n < LONLAT_NODES; ++n) assert_true(h[n] == -10.0 - n);
    int64_t faces = 0;
    dpsm_get_face_count(s.grid, &faces);
    for (int64_t f = 0; f < faces; ++f)
        if (s.face_cells[2 * f + 1] < 0) assert_true(s.levels[f] == h[s.face_cells[2 * f]]);
    config_scene_free(&s);
    REFUSED("grid: {kind: dual_mesh, file: adcirc.nc}\ninitial: {file: adcirc.nc, variable: depth, positive: up}\n"
            "time: {step: 1, end: 1}\n",
            "dpsm.yaml:2: initial.positive: initial.positive says up, and ",
            "adcirc.nc says \"depth\" is positive down (depth:standard_name = \"depth_below_geoid\"): which is it?");
    REFUSED("grid: {kind: dual_mesh, file: adcirc.nc}\ninitial: {constant: 0}\n"
            "boundaries: {edge: open, level: {file: adcirc.nc, variable: depth}}\ntime: {step: 1, end: 1}\n",
            "boundaries.level: ", "say boundaries.level.positive: down");
    expect_refusal("grid: {kind: dual_mesh, file: adcirc.nc}\ninitial: {file: adcirc.nc, variable: depth, positive: "
                   "downwards}\n",
                   2, "initial.positive: expected up (the values are elevations) or down");
    REFUSED("grid: {kind: dual_mesh, file: adcirc.nc, coordinates: projected}\ninitial: {constant: 0}\n"
            "time: {step: 1, end: 1}\n",
            "dpsm.yaml:1: grid.coordinates: ", "adcirc.nc: grid.coordinates says projected, and the file says its "
                                                "nodes are in degrees (lon:standard_name = \"longitude\"): which is it?");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(column_configuration_is_read_and_built, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(one_d_cone_and_axisymmetric_constant, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(fields_from_netcdf_files, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(mesh_from_a_ugrid_file, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(refusals_name_the_line_and_the_key, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(bad_mesh_files_are_refused, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(net_files_of_delft3d_fm, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(faces_from_nodes_and_edges, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(selafin_files, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(gmsh_files, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(boundaries_a_host_can_state, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(scenes_with_a_centre, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(meshes_in_degrees, make_folder, remove_folder),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
