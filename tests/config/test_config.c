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
                                                   "boundaries: {edge: open}\n"
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
                   3, "grid.kind: expected 1d, 2d, axisymmetric or mesh, got \"3d\"");
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
    assert_int_not_equal(config_read_mesh(file, &mesh, message, sizeof message), 0);
    assert_non_null(strstr(message, "plain.nc: no UGRID mesh (no variable with cf_role = \"mesh_topology\")"));
    assert_null(mesh.node_x);
    in_folder(file, sizeof file, "nothing.nc");
    assert_int_not_equal(config_read_mesh(file, &mesh, message, sizeof message), 0);
    assert_non_null(strstr(message, "nothing.nc: cannot open as netCDF"));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(column_configuration_is_read_and_built, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(one_d_cone_and_axisymmetric_constant, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(fields_from_netcdf_files, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(mesh_from_a_ugrid_file, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(refusals_name_the_line_and_the_key, make_folder, remove_folder),
        cmocka_unit_test_setup_teardown(bad_mesh_files_are_refused, make_folder, remove_folder),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
