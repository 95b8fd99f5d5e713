/* The C conformance host of the dpsm BMI component: it loads libdpsm_bmi.so
 * with dlopen() as NextGen does, takes the registration function with
 * dlsym(), and calls only the function table, checking every function
 * against the BMI 2.0 specification and docs/guide_bmi.md: names, types,
 * units, sizes, both grid types, time, values in and out, and refusals.
 *
 *   usage: bmi_host <path of libdpsm_bmi.so>
 *
 * It writes its configurations and the UGRID mesh into a temporary folder. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#include <dlfcn.h>
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

#include <dpsm/bmi.h>

#include "mesh_files.h"
#include "ugrid_file.h"

#if defined(DPSM_TEST_UDUNITS)
#include <udunits2.h>
#endif

static const char *library_path;
static void *library;
static Bmi *(*registration)(Bmi *);
static char folder[256];

static const char *write_text(const char *name, const char *text) {
    static char path[512];
    snprintf(path, sizeof path, "%s/%s", folder, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    return path;
}

/* A fresh table from the library's registration function, initialized with `config`. */
static Bmi *start(const char *name, const char *config) {
    Bmi *model = calloc(1, sizeof *model);
    assert_non_null(model);
    assert_ptr_equal(registration(model), model);
    assert_null(model->data);
    const char *path = write_text(name, config);
    assert_int_equal(model->initialize(model, path), BMI_SUCCESS);
    assert_non_null(model->data);
    return model;
}

static void stop(Bmi *model) {
    assert_int_equal(model->finalize(model), BMI_SUCCESS);
    assert_null(model->data);
    free(model);
}

/* ---- the 2d grid ----------------------------------------------------- */

static const char kGrid2d[] = "grid: {kind: 2d, nx: 8, ny: 6, dx: 0.5, dy: 0.25}\n"
                              "repose_angle: 30\n"
                              "boundaries: {xmin: wall, xmax: wall, ymin: wall, ymax: wall}\n"
                              "initial: {scene: column, radius: 0.8, height: 2.0}\n"
                              "time: {step: 0.1, end: 0.35}\n";
#define NX 8
#define NY 6

static const char *const kInputs[] = {"land_surface__elevation", "bedrock_surface__elevation",
                                      "land_surface_sediment_deposition__net_volume_flux", "land_surface_sediment__repose_angle"};
/* The bed is an input only: with no bed set there is nothing to read. */
static const char *const kOutputs2d[] = {"land_surface__elevation",
                                         "land_surface_sediment__repose_angle",
                                         "land_surface_sediment_flowing__x_component_of_volume_rate",
                                         "land_surface_sediment_flowing__y_component_of_volume_rate",
                                         "land_surface_sediment__volume",
                                         "land_surface_sediment_deposition__domain_time_integral_of_net_volume_flux",
                                         "land_surface_sediment_flowing_sink__time_integral_of_volume_rate",
                                         "land_surface_sediment_source__time_integral_of_volume_rate",
                                         "land_surface_sediment_erosion~unmet__domain_time_integral_of_volume_flux"};

struct expected_variable {
    const char *name, *units, *location;
    int grid;
};

static const struct expected_variable kVariables2d[] = {
    {"land_surface__elevation", "m", "node", 0},
    {"bedrock_surface__elevation", "m", "node", 0},
    {"land_surface_sediment_deposition__net_volume_flux", "m s-1", "node", 0},
    {"land_surface_sediment__repose_angle", "degree", "node", 0},
    {"land_surface_sediment_flowing__x_component_of_volume_rate", "m3 s-1", "node", 1},
    {"land_surface_sediment_flowing__y_component_of_volume_rate", "m3 s-1", "node", 2},
    {"land_surface_sediment__volume", "m3", "node", 3},
    {"land_surface_sediment_deposition__domain_time_integral_of_net_volume_flux", "m3", "node", 3},
    {"land_surface_sediment_flowing_sink__time_integral_of_volume_rate", "m3", "node", 3},
    {"land_surface_sediment_source__time_integral_of_volume_rate", "m3", "node", 3},
    {"land_surface_sediment_erosion~unmet__domain_time_integral_of_volume_flux", "m3", "node", 3},
};

static void check_names(Bmi *m, int inputs, const char *const *expected, int n) {
    int count = -1;
    assert_int_equal((inputs ? m->get_input_item_count : m->get_output_item_count)(m, &count), BMI_SUCCESS);
    assert_int_equal(count, n);
    char **names = malloc((size_t)n * sizeof *names);
    for (int k = 0; k < n; ++k) names[k] = calloc(BMI_MAX_VAR_NAME, 1);
    assert_int_equal((inputs ? m->get_input_var_names : m->get_output_var_names)(m, names), BMI_SUCCESS);
    for (int k = 0; k < n; ++k) {
        assert_string_equal(names[k], expected[k]);
        free(names[k]);
    }
    free(names);
}

/* Type, units, item size, bytes (= item size times the values of its
 * location), location and grid of one variable. */
static void check_variable(Bmi *m, const struct expected_variable *v, int values) {
    char text[BMI_MAX_UNITS_NAME];
    int grid = -1, itemsize = 0, nbytes = 0;
    assert_int_equal(m->get_var_grid(m, v->name, &grid), BMI_SUCCESS);
    assert_int_equal(grid, v->grid);
    assert_int_equal(m->get_var_type(m, v->name, text), BMI_SUCCESS);
    assert_string_equal(text, "double");
    assert_int_equal(m->get_var_units(m, v->name, text), BMI_SUCCESS);
    assert_string_equal(text, v->units);
    assert_int_equal(m->get_var_location(m, v->name, text), BMI_SUCCESS);
    assert_string_equal(text, v->location);
    assert_int_equal(m->get_var_itemsize(m, v->name, &itemsize), BMI_SUCCESS);
    assert_int_equal(itemsize, (int)sizeof(double));
    assert_int_equal(m->get_var_nbytes(m, v->name, &nbytes), BMI_SUCCESS);
    assert_int_equal(nbytes, itemsize * values);
}

/* Every variable the component lists: its name in tests/bmi/standard_names.txt
 * (which test_bmi.py checks against the CSDMS registry's rules) with the
 * units given there, which UDUNITS-2 parses; every output readable. */
static void check_conventions(Bmi *m) {
    FILE *f = fopen(DPSM_STANDARD_NAMES_FILE, "r");
    assert_non_null(f);
    char known[32][BMI_MAX_VAR_NAME], known_units[32][BMI_MAX_UNITS_NAME], line[512];
    int nknown = 0;
    while (fgets(line, sizeof line, f) && nknown < 32) {
        char name[BMI_MAX_VAR_NAME], units[BMI_MAX_UNITS_NAME];
        if (sscanf(line, "variable %255s | %63[^|]|", name, units) == 2) {
            size_t n = strlen(units);
            while (n > 0 && units[n - 1] == ' ') units[--n] = '\0';
            snprintf(known[nknown], BMI_MAX_VAR_NAME, "%s", name);
            snprintf(known_units[nknown++], BMI_MAX_UNITS_NAME, "%s", units);
        }
    }
    fclose(f);
    assert_true(nknown >= 12);
#if defined(DPSM_TEST_UDUNITS)
    ut_set_error_message_handler(ut_ignore);
    ut_system *units_system = ut_read_xml(NULL);
    assert_non_null(units_system);
#endif
    for (int inputs = 0; inputs < 2; ++inputs) {
        int count = 0;
        assert_int_equal((inputs ? m->get_input_item_count : m->get_output_item_count)(m, &count), BMI_SUCCESS);
        char **names = malloc((size_t)count * sizeof *names);
        for (int k = 0; k < count; ++k) names[k] = calloc(BMI_MAX_VAR_NAME, 1);
        assert_int_equal((inputs ? m->get_input_var_names : m->get_output_var_names)(m, names), BMI_SUCCESS);
        for (int k = 0; k < count; ++k) {
            char units[BMI_MAX_UNITS_NAME];
            assert_int_equal(m->get_var_units(m, names[k], units), BMI_SUCCESS);
            int found = -1;
            for (int j = 0; j < nknown; ++j)
                if (strcmp(known[j], names[k]) == 0) found = j;
            if (found < 0) fail_msg("%s is not in tests/bmi/standard_names.txt", names[k]);
            assert_string_equal(units, known_units[found]);
#if defined(DPSM_TEST_UDUNITS)
            ut_unit *unit = ut_parse(units_system, units, UT_ASCII);
            if (!unit) fail_msg("UDUNITS-2 does not parse the units \"%s\" of %s", units, names[k]);
            ut_free(unit);
#endif
            if (!inputs) { /* every output readable after initialize */
                int nbytes = 0;
                assert_int_equal(m->get_var_nbytes(m, names[k], &nbytes), BMI_SUCCESS);
                double *values = malloc((size_t)nbytes);
                void *ptr = NULL;
                if (m->get_value(m, names[k], values) != BMI_SUCCESS || m->get_value_ptr(m, names[k], &ptr) != BMI_SUCCESS)
                    fail_msg("the output %s cannot be read after initialize", names[k]);
                free(values);
            }
            free(names[k]);
        }
        free(names);
    }
#if defined(DPSM_TEST_UDUNITS)
    ut_free_system(units_system);
#endif
}

static void check_rectilinear(Bmi *m, int grid, int rank, const int *shape, const double *spacing,
                              const double *origin) {
    char type[BMI_MAX_TYPE_NAME];
    int got_rank = -1, size = -1, nodes = -1, got_shape[2] = {0, 0};
    double got_spacing[2] = {0, 0}, got_origin[2] = {0, 0};
    assert_int_equal(m->get_grid_type(m, grid, type), BMI_SUCCESS);
    assert_string_equal(type, "uniform_rectilinear");
    assert_int_equal(m->get_grid_rank(m, grid, &got_rank), BMI_SUCCESS);
    assert_int_equal(got_rank, rank);
    assert_int_equal(m->get_grid_shape(m, grid, got_shape), BMI_SUCCESS);
    assert_int_equal(m->get_grid_spacing(m, grid, got_spacing), BMI_SUCCESS);
    assert_int_equal(m->get_grid_origin(m, grid, got_origin), BMI_SUCCESS);
    int product = 1;
    for (int d = 0; d < rank; ++d) {
        assert_int_equal(got_shape[d], shape[d]);
        assert_true(got_spacing[d] == spacing[d]);
        assert_true(got_origin[d] == origin[d]);
        product *= shape[d];
    }
    assert_int_equal(m->get_grid_size(m, grid, &size), BMI_SUCCESS);
    assert_int_equal(size, product);
    assert_int_equal(m->get_grid_node_count(m, grid, &nodes), BMI_SUCCESS);
    assert_int_equal(nodes, product);
    /* The nodes along x (the last dimension) and y (the first). */
    double x[64], y[64], z[64];
    assert_int_equal(m->get_grid_x(m, grid, x), BMI_SUCCESS);
    for (int k = 0; k < shape[rank - 1]; ++k) assert_true(fabs(x[k] - (origin[rank - 1] + k * spacing[rank - 1])) < 1e-15);
    if (rank == 2) {
        assert_int_equal(m->get_grid_y(m, grid, y), BMI_SUCCESS);
        for (int k = 0; k < shape[0]; ++k) assert_true(fabs(y[k] - (origin[0] + k * spacing[0])) < 1e-15);
    } else {
        assert_int_equal(m->get_grid_y(m, grid, y), BMI_FAILURE);
    }
    assert_int_equal(m->get_grid_z(m, grid, z), BMI_FAILURE);
    /* Edges and faces belong to unstructured grids. */
    int count;
    assert_int_equal(m->get_grid_edge_count(m, grid, &count), BMI_FAILURE);
    assert_int_equal(m->get_grid_face_count(m, grid, &count), BMI_FAILURE);
    assert_int_equal(m->get_grid_edge_nodes(m, grid, got_shape), BMI_FAILURE);
}

static void check_scalar_grid(Bmi *m, int grid) {
    char type[BMI_MAX_TYPE_NAME];
    int rank = -1, size = -1;
    assert_int_equal(m->get_grid_type(m, grid, type), BMI_SUCCESS);
    assert_string_equal(type, "scalar");
    assert_int_equal(m->get_grid_rank(m, grid, &rank), BMI_SUCCESS);
    assert_int_equal(rank, 0);
    assert_int_equal(m->get_grid_size(m, grid, &size), BMI_SUCCESS);
    assert_int_equal(size, 1);
}

static void check_no_grid(Bmi *m, int grid) {
    char type[BMI_MAX_TYPE_NAME];
    int rank;
    assert_int_equal(m->get_grid_type(m, grid, type), BMI_FAILURE);
    assert_int_equal(m->get_grid_rank(m, grid, &rank), BMI_FAILURE);
    assert_int_equal(m->get_grid_size(m, grid, &rank), BMI_FAILURE);
}

static double scalar(Bmi *m, const char *name) {
    double value = NAN;
    assert_int_equal(m->get_value(m, name, &value), BMI_SUCCESS);
    return value;
}

static void registration_and_information_2d(void **state) {
    (void)state;
    Bmi *m = start("grid2d.yaml", kGrid2d);
    char name[BMI_MAX_COMPONENT_NAME];
    assert_int_equal(m->get_component_name(m, name), BMI_SUCCESS);
    assert_string_equal(name, "dpsm");
    check_names(m, 1, kInputs, 4);
    check_names(m, 0, kOutputs2d, 9);
    check_conventions(m);
    int sizes[] = {NX * NY, NX * NY, NX * NY, NX * NY, (NX + 1) * NY, NX * (NY + 1), 1, 1, 1, 1, 1};
    for (size_t v = 0; v < sizeof kVariables2d / sizeof kVariables2d[0]; ++v) {
        check_variable(m, &kVariables2d[v], sizes[v]);
        /* nbytes == itemsize * grid size on these grids */
        int grid, size, nbytes;
        m->get_var_grid(m, kVariables2d[v].name, &grid);
        m->get_grid_size(m, grid, &size);
        m->get_var_nbytes(m, kVariables2d[v].name, &nbytes);
        assert_int_equal(nbytes, 8 * size);
    }
    check_rectilinear(m, 0, 2, (int[]){NY, NX}, (double[]){0.25, 0.5}, (double[]){0.125, 0.25});
    check_rectilinear(m, 1, 2, (int[]){NY, NX + 1}, (double[]){0.25, 0.5}, (double[]){0.125, 0});
    check_rectilinear(m, 2, 2, (int[]){NY + 1, NX}, (double[]){0.25, 0.5}, (double[]){0, 0.25});
    check_scalar_grid(m, 3);
    check_no_grid(m, 4);
    check_no_grid(m, -1);

    double t = -1;
    char units[BMI_MAX_UNITS_NAME];
    assert_int_equal(m->get_start_time(m, &t), BMI_SUCCESS);
    assert_true(t == 0);
    assert_int_equal(m->get_current_time(m, &t), BMI_SUCCESS);
    assert_true(t == 0);
    assert_int_equal(m->get_end_time(m, &t), BMI_SUCCESS);
    assert_true(t == 0.35);
    assert_int_equal(m->get_time_step(m, &t), BMI_SUCCESS);
    assert_true(t == 0.1);
    assert_int_equal(m->get_time_units(m, units), BMI_SUCCESS);
    assert_string_equal(units, "s");
    stop(m);
}

static void time_lands_on_the_end(void **state) {
    (void)state;
    Bmi *m = start("grid2d.yaml", kGrid2d);
    double t, expected[] = {0.1, 0.2, 0.30000000000000004, 0.35};
    for (int k = 0; k < 4; ++k) {
        assert_int_equal(m->update(m), BMI_SUCCESS);
        assert_int_equal(m->get_current_time(m, &t), BMI_SUCCESS);
        assert_true(fabs(t - expected[k]) < 1e-15);
    }
    assert_true(t == 0.35); /* exactly the end time */
    stop(m);

    m = start("grid2d.yaml", kGrid2d);
    double end;
    m->get_end_time(m, &end);
    assert_int_equal(m->update_until(m, end), BMI_SUCCESS);
    m->get_current_time(m, &t);
    assert_true(t == end);
    assert_int_equal(m->update_until(m, 1.0), BMI_SUCCESS);
    m->get_current_time(m, &t);
    assert_true(t == 1.0);
    assert_int_equal(m->update_until(m, 1.0), BMI_SUCCESS); /* no time to go: nothing moves */
    assert_int_equal(m->update_until(m, 0.5), BMI_FAILURE); /* the past */
    assert_int_equal(m->update_until(m, NAN), BMI_FAILURE);
    m->get_current_time(m, &t);
    assert_true(t == 1.0);
    stop(m);
}

static void values_in_and_out_2d(void **state) {
    (void)state;
    Bmi *m = start("grid2d.yaml", kGrid2d);
    double h[NX * NY], h2[NX * NY], *ptr = NULL;
    assert_int_equal(m->get_value(m, "land_surface__elevation", h), BMI_SUCCESS);
    double volume = 0;
    for (int k = 0; k < NX * NY; ++k) volume += h[k] * 0.5 * 0.25;
    assert_true(volume > 0);
    assert_true(fabs(scalar(m, "land_surface_sediment__volume") - volume) < 1e-12);
    assert_int_equal(m->get_value_ptr(m, "land_surface__elevation", (void **)&ptr), BMI_SUCCESS);
    assert_memory_equal(ptr, h, sizeof h);

    /* Fluxes read 0 before the first update. */
    double fx[(NX + 1) * NY], fy[NX * (NY + 1)];
    assert_int_equal(m->get_value(m, "land_surface_sediment_flowing__x_component_of_volume_rate", fx), BMI_SUCCESS);
    assert_int_equal(m->get_value(m, "land_surface_sediment_flowing__y_component_of_volume_rate", fy), BMI_SUCCESS);
    for (int k = 0; k < (NX + 1) * NY; ++k) assert_true(fx[k] == 0);

    /* One update of the collapsing column: what the faces carried, times the
     * duration, is each cell's change of volume (walls all round, no source),
     * and the pointer from before shows the new heights. */
    assert_int_equal(m->update(m), BMI_SUCCESS);
    assert_int_equal(m->get_value(m, "land_surface__elevation", h2), BMI_SUCCESS);
    assert_memory_equal(ptr, h2, sizeof h2);
    assert_int_equal(m->get_value(m, "land_surface_sediment_flowing__x_component_of_volume_rate", fx), BMI_SUCCESS);
    assert_int_equal(m->get_value(m, "land_surface_sediment_flowing__y_component_of_volume_rate", fy), BMI_SUCCESS);
    double moved = 0;
    for (int j = 0; j < NY; ++j)
        for (int i = 0; i < NX; ++i) {
            double in = fx[i + (NX + 1) * j] - fx[i + 1 + (NX + 1) * j] + fy[i + NX * j] - fy[i + NX * (j + 1)];
            double change = (h2[i + NX * j] - h[i + NX * j]) * 0.5 * 0.25;
            assert_true(fabs(in * 0.1 - change) < 1e-12);
            moved += fabs(change);
        }
    assert_true(moved > 1e-3);
    assert_true(fabs(scalar(m, "land_surface_sediment__volume") - volume) < 1e-12);

    /* set_value then get_value; get_value_at_indices; set_value_at_indices. */
    for (int k = 0; k < NX * NY; ++k) h[k] = 0.01 * k;
    assert_int_equal(m->set_value(m, "land_surface__elevation", h), BMI_SUCCESS);
    assert_int_equal(m->get_value(m, "land_surface__elevation", h2), BMI_SUCCESS);
    assert_memory_equal(h, h2, sizeof h);
    assert_memory_equal(ptr, h, sizeof h);
    int inds[] = {0, 7, 47, 20};
    double picked[4];
    assert_int_equal(m->get_value_at_indices(m, "land_surface__elevation", picked, inds, 4), BMI_SUCCESS);
    for (int k = 0; k < 4; ++k) assert_true(picked[k] == h[inds[k]]);
    double put[] = {1.5, 2.5};
    assert_int_equal(m->set_value_at_indices(m, "land_surface__elevation", inds, 2, put), BMI_SUCCESS);
    m->get_value(m, "land_surface__elevation", h2);
    h[0] = 1.5, h[7] = 2.5;
    assert_memory_equal(h, h2, sizeof h);

    /* The bed: no value before one is set, then what was set. */
    double bed[NX * NY];
    assert_int_equal(m->get_value(m, "bedrock_surface__elevation", bed), BMI_FAILURE);
    assert_int_equal(m->get_value_ptr(m, "bedrock_surface__elevation", (void **)&ptr), BMI_FAILURE);
    assert_int_equal(m->get_value_at_indices(m, "bedrock_surface__elevation", picked, inds, 1), BMI_FAILURE);
    for (int k = 0; k < NX * NY; ++k) bed[k] = -1 + 0.001 * k;
    assert_int_equal(m->set_value(m, "bedrock_surface__elevation", bed), BMI_SUCCESS);
    double bed2[NX * NY];
    assert_int_equal(m->get_value(m, "bedrock_surface__elevation", bed2), BMI_SUCCESS);
    assert_memory_equal(bed, bed2, sizeof bed);

    /* The angle: uniform 30 degrees until a field is set. */
    double angle[NX * NY];
    assert_int_equal(m->get_value(m, "land_surface_sediment__repose_angle", angle), BMI_SUCCESS);
    for (int k = 0; k < NX * NY; ++k) assert_true(fabs(angle[k] - 30) < 1e-12);
    for (int k = 0; k < NX * NY; ++k) angle[k] = 20 + 0.2 * k;
    assert_int_equal(m->set_value(m, "land_surface_sediment__repose_angle", angle), BMI_SUCCESS);
    double angle2[NX * NY];
    m->get_value(m, "land_surface_sediment__repose_angle", angle2);
    assert_memory_equal(angle, angle2, sizeof angle);
    angle[3] = 95; /* refused as a whole: nothing changes */
    assert_int_equal(m->set_value(m, "land_surface_sediment__repose_angle", angle), BMI_FAILURE);
    m->get_value(m, "land_surface_sediment__repose_angle", angle);
    assert_memory_equal(angle, angle2, sizeof angle);

    /* The source: deposits over the next update, booked as sourced volume. */
    double q[NX * NY], q2[NX * NY];
    for (int k = 0; k < NX * NY; ++k) q[k] = 0.02;
    assert_int_equal(m->set_value(m, "land_surface_sediment_deposition__net_volume_flux", q), BMI_SUCCESS);
    m->get_value(m, "land_surface_sediment_deposition__net_volume_flux", q2);
    assert_memory_equal(q, q2, sizeof q);
    double sourced = scalar(m, "land_surface_sediment_deposition__domain_time_integral_of_net_volume_flux");
    assert_int_equal(m->update(m), BMI_SUCCESS);
    assert_true(fabs(scalar(m, "land_surface_sediment_deposition__domain_time_integral_of_net_volume_flux") - sourced - 0.02 * 0.1 * NX * NY * 0.125) < 1e-12);
    double total = scalar(m, "land_surface_sediment__volume");
    double ledger = scalar(m, "land_surface_sediment_deposition__domain_time_integral_of_net_volume_flux") +
                    scalar(m, "land_surface_sediment_source__time_integral_of_volume_rate") -
                    scalar(m, "land_surface_sediment_flowing_sink__time_integral_of_volume_rate");
    assert_true(fabs(total - ledger) < 1e-10);
    assert_true(scalar(m, "land_surface_sediment_erosion~unmet__domain_time_integral_of_volume_flux") == 0);
    double *total_ptr;
    assert_int_equal(m->get_value_ptr(m, "land_surface_sediment__volume", (void **)&total_ptr), BMI_SUCCESS);
    assert_true(*total_ptr == total);
    stop(m);
}

static void bad_input_fails_without_harm(void **state) {
    (void)state;
    /* Before initialize, and a configuration that is refused. */
    Bmi blank;
    memset(&blank, 0, sizeof blank);
    registration(&blank);
    double t;
    int n;
    assert_int_equal(blank.update(&blank), BMI_FAILURE);
    assert_int_equal(blank.get_current_time(&blank, &t), BMI_FAILURE);
    assert_int_equal(blank.get_input_item_count(&blank, &n), BMI_FAILURE);
    assert_int_equal(blank.finalize(&blank), BMI_FAILURE);
    assert_int_equal(blank.initialize(&blank, NULL), BMI_FAILURE);
    const char *bad = write_text("bad.yaml", "grid: {kind: 2d, nx: sixty, ny: 4, dx: 1, dy: 1}\n");
    assert_int_equal(blank.initialize(&blank, bad), BMI_FAILURE);
    assert_null(blank.data);
    char missing[512];
    snprintf(missing, sizeof missing, "%s/nowhere.yaml", folder);
    assert_int_equal(blank.initialize(&blank, missing), BMI_FAILURE);
    assert_null(registration(NULL));

    Bmi *m = start("grid2d.yaml", kGrid2d);
    const char *path = write_text("grid2d.yaml", kGrid2d);
    assert_int_equal(m->initialize(m, path), BMI_FAILURE); /* twice */
    double h[NX * NY], before[NX * NY], v[4];
    m->get_value(m, "land_surface__elevation", before);
    char text[BMI_MAX_UNITS_NAME];
    int grid;
    void *ptr;
    assert_int_equal(m->get_var_grid(m, "surface__elevation", &grid), BMI_FAILURE);
    assert_int_equal(m->get_var_units(m, "nothing", text), BMI_FAILURE);
    assert_int_equal(m->get_var_type(m, NULL, text), BMI_FAILURE);
    assert_int_equal(m->get_var_type(m, "land_surface__elevation", NULL), BMI_FAILURE);
    assert_int_equal(m->get_value(m, "nothing", h), BMI_FAILURE);
    assert_int_equal(m->get_value(m, NULL, h), BMI_FAILURE);
    assert_int_equal(m->get_value(m, "land_surface__elevation", NULL), BMI_FAILURE);
    assert_int_equal(m->get_value_ptr(m, "nothing", &ptr), BMI_FAILURE);
    assert_int_equal(m->get_value_ptr(m, "land_surface__elevation", NULL), BMI_FAILURE);
    assert_int_equal(m->get_var_grid(m, "land_surface_sediment_flowing__volume_rate", &grid), BMI_FAILURE);
    int outside[] = {0, NX * NY}, negative[] = {-1};
    assert_int_equal(m->get_value_at_indices(m, "land_surface__elevation", v, outside, 2), BMI_FAILURE);
    assert_int_equal(m->get_value_at_indices(m, "land_surface__elevation", v, negative, 1), BMI_FAILURE);
    assert_int_equal(m->get_value_at_indices(m, "land_surface__elevation", v, NULL, 1), BMI_FAILURE);
    assert_int_equal(m->get_value_at_indices(m, "land_surface__elevation", v, outside, -1), BMI_FAILURE);
    double put[] = {5, 5};
    assert_int_equal(m->set_value_at_indices(m, "land_surface__elevation", outside, 2, put), BMI_FAILURE);
    assert_int_equal(m->set_value(m, "land_surface__elevation", NULL), BMI_FAILURE);
    assert_int_equal(m->set_value(m, "land_surface_sediment__volume", put), BMI_FAILURE); /* an output */
    for (int k = 0; k < NX * NY; ++k) h[k] = 1;
    h[5] = NAN;
    assert_int_equal(m->set_value(m, "land_surface__elevation", h), BMI_FAILURE);
    h[5] = INFINITY;
    assert_int_equal(m->set_value(m, "land_surface_sediment_deposition__net_volume_flux", h), BMI_FAILURE);
    assert_int_equal(m->set_value_at_indices(m, "bedrock_surface__elevation", negative + 0, 0, put), BMI_FAILURE);
    double after[NX * NY];
    m->get_value(m, "land_surface__elevation", after);
    assert_memory_equal(before, after, sizeof before);
    assert_int_equal(m->get_component_name(m, NULL), BMI_FAILURE);
    assert_int_equal(m->get_input_var_names(m, NULL), BMI_FAILURE);
    assert_int_equal(m->get_current_time(m, NULL), BMI_FAILURE);
    assert_int_equal(m->get_grid_shape(m, 0, NULL), BMI_FAILURE);
    assert_int_equal(m->get_grid_x(m, 7, h), BMI_FAILURE);
    stop(m);
}

/* ---- the 1d grid: grid numbers skip what it lacks --------------------- */

static void grids_of_a_1d_grid(void **state) {
    (void)state;
    Bmi *m = start("grid1d.yaml", "grid: {kind: 1d, nx: 10, dx: 0.2}\n"
                                  "initial: {scene: cone, radius: 0.5, height: 1}\n"
                                  "source: {constant: 0.001}\n"
                                  "time: {step: 0.5, end: 1.2}\n");
    int count;
    assert_int_equal(m->get_output_item_count(m, &count), BMI_SUCCESS);
    assert_int_equal(count, 8);
    check_conventions(m);
    check_variable(m, &(struct expected_variable){"land_surface__elevation", "m", "node", 0}, 10);
    check_variable(
        m, &(struct expected_variable){"land_surface_sediment_flowing__x_component_of_volume_rate", "m3 s-1", "node", 1},
        11);
    check_variable(m, &(struct expected_variable){"land_surface_sediment__volume", "m3", "node", 2}, 1);
    int grid;
    assert_int_equal(m->get_var_grid(m, "land_surface_sediment_flowing__y_component_of_volume_rate", &grid),
                     BMI_FAILURE);
    check_rectilinear(m, 0, 1, (int[]){10}, (double[]){0.2}, (double[]){0.1});
    check_rectilinear(m, 1, 1, (int[]){11}, (double[]){0.2}, (double[]){0});
    check_scalar_grid(m, 2);
    check_no_grid(m, 3);
    double q[10];
    assert_int_equal(m->get_value(m, "land_surface_sediment_deposition__net_volume_flux", q), BMI_SUCCESS);
    assert_true(q[0] == 0.001 && q[9] == 0.001);
    double t;
    assert_int_equal(m->update_until(m, 1.2), BMI_SUCCESS);
    m->get_current_time(m, &t);
    assert_true(t == 1.2);
    stop(m);
}

/* ---- the unstructured mesh ----------------------------------------- */

static const char kMesh[] = "grid: {kind: mesh, file: bed.nc}\n"
                            "initial: {scene: cone, radius: 1.5, height: 3}\n"
                            "time: {step: 0.05, end: 0.12}\n";

static void mesh_grid_and_values(void **state) {
    (void)state;
    char file[512];
    snprintf(file, sizeof file, "%s/bed.nc", folder);
    assert_int_equal(write_ugrid_test_mesh(file, 1), 0);
    Bmi *m = start("mesh.yaml", kMesh);
    int count;
    assert_int_equal(m->get_output_item_count(m, &count), BMI_SUCCESS);
    assert_int_equal(count, 8);
    check_conventions(m);
    const char *flux = "land_surface_sediment_flowing__volume_rate";
    check_variable(m, &(struct expected_variable){"land_surface__elevation", "m", "face", 0}, UGRID_TEST_FACES);
    check_variable(m, &(struct expected_variable){"land_surface_sediment__repose_angle", "degree", "face", 0}, UGRID_TEST_FACES);
    check_variable(m, &(struct expected_variable){flux, "m3 s-1", "edge", 1}, UGRID_TEST_EDGES);
    check_variable(m, &(struct expected_variable){"land_surface_sediment_flowing_sink__time_integral_of_volume_rate", "m3", "node", 2}, 1);
    int grid;
    assert_int_equal(m->get_var_grid(m, "land_surface_sediment_flowing__x_component_of_volume_rate", &grid),
                     BMI_FAILURE);
    check_scalar_grid(m, 2);
    check_no_grid(m, 3);

    int face_nodes[32], face_edges[32], edge_nodes[2 * UGRID_TEST_EDGES], per_face[UGRID_TEST_FACES];
    for (int g = 0; g <= 1; ++g) {
        char type[BMI_MAX_TYPE_NAME];
        int rank, size, nodes, edges, faces, shape[2];
        assert_int_equal(m->get_grid_type(m, g, type), BMI_SUCCESS);
        assert_string_equal(type, "unstructured");
        assert_int_equal(m->get_grid_rank(m, g, &rank), BMI_SUCCESS);
        assert_int_equal(rank, 2);
        assert_int_equal(m->get_grid_size(m, g, &size), BMI_SUCCESS);
        assert_int_equal(size, UGRID_TEST_NODES);
        assert_int_equal(m->get_grid_node_count(m, g, &nodes), BMI_SUCCESS);
        assert_int_equal(nodes, UGRID_TEST_NODES);
        assert_int_equal(m->get_grid_edge_count(m, g, &edges), BMI_SUCCESS);
        assert_int_equal(edges, UGRID_TEST_EDGES);
        assert_int_equal(m->get_grid_face_count(m, g, &faces), BMI_SUCCESS);
        assert_int_equal(faces, UGRID_TEST_FACES);
        assert_int_equal(m->get_grid_shape(m, g, shape), BMI_FAILURE);
        double x[UGRID_TEST_NODES], y[UGRID_TEST_NODES], z[UGRID_TEST_NODES];
        assert_int_equal(m->get_grid_x(m, g, x), BMI_SUCCESS);
        assert_int_equal(m->get_grid_y(m, g, y), BMI_SUCCESS);
        assert_int_equal(m->get_grid_z(m, g, z), BMI_FAILURE);
        for (int k = 0; k < UGRID_TEST_NODES; ++k) assert_true(x[k] == k % 3 && y[k] == k / 3);
    }
    /* UGRID's topology, from 0: faces as the file gives them, every edge of a
     * face joining two consecutive nodes of it. */
    assert_int_equal(m->get_grid_nodes_per_face(m, 0, per_face), BMI_SUCCESS);
    assert_int_equal(m->get_grid_face_nodes(m, 0, face_nodes), BMI_SUCCESS);
    assert_int_equal(m->get_grid_face_edges(m, 0, face_edges), BMI_SUCCESS);
    assert_int_equal(m->get_grid_edge_nodes(m, 0, edge_nodes), BMI_SUCCESS);
    int used[UGRID_TEST_EDGES] = {0};
    for (int f = 0, p = 0; f < UGRID_TEST_FACES; p += per_face[f], ++f) {
        int n = ugrid_test_face_nodes[f][3] < 0 ? 3 : 4;
        assert_int_equal(per_face[f], n);
        for (int k = 0; k < n; ++k) {
            assert_int_equal(face_nodes[p + k], ugrid_test_face_nodes[f][k]);
            int e = face_edges[p + k], u = face_nodes[p + k], w = face_nodes[p + (k + 1) % n];
            assert_in_range(e, 0, UGRID_TEST_EDGES - 1);
            assert_true((edge_nodes[2 * e] == u && edge_nodes[2 * e + 1] == w) ||
                        (edge_nodes[2 * e] == w && edge_nodes[2 * e + 1] == u));
            ++used[e];
        }
    }
    int interior = 0;
    for (int e = 0; e < UGRID_TEST_EDGES; ++e) {
        assert_in_range(used[e], 1, 2);
        interior += used[e] == 2;
    }
    assert_int_equal(interior, 5);

    /* Values: the flux on an edge runs from the first face that lists it to
     * the second (the faces' order); what the edges carried over an update
     * is each face's change of volume (the mesh's edge is a wall). */
    double h[UGRID_TEST_FACES], h2[UGRID_TEST_FACES], f[UGRID_TEST_EDGES];
    const double area[UGRID_TEST_FACES] = {1, 1, 1, 0.5, 0.5};
    const double pile[UGRID_TEST_FACES] = {3, 0, 0.5, 0, 1};
    assert_int_equal(m->set_value(m, "land_surface__elevation", (void *)pile), BMI_SUCCESS);
    assert_int_equal(m->get_value(m, "land_surface__elevation", h), BMI_SUCCESS);
    assert_memory_equal(h, pile, sizeof h);
    assert_int_equal(m->update(m), BMI_SUCCESS);
    assert_int_equal(m->get_value(m, "land_surface__elevation", h2), BMI_SUCCESS);
    assert_int_equal(m->get_value(m, flux, f), BMI_SUCCESS);
    int first_face[UGRID_TEST_EDGES];
    for (int e = 0; e < UGRID_TEST_EDGES; ++e) first_face[e] = -1;
    double in[UGRID_TEST_FACES] = {0};
    for (int face = 0, p = 0; face < UGRID_TEST_FACES; p += per_face[face], ++face)
        for (int k = 0; k < per_face[face]; ++k) {
            int e = face_edges[p + k];
            if (first_face[e] < 0) first_face[e] = face, in[face] -= f[e];
            else in[face] += f[e];
        }
    double moved = 0;
    for (int face = 0; face < UGRID_TEST_FACES; ++face) {
        assert_true(fabs(in[face] * 0.05 - (h2[face] - h[face]) * area[face]) < 1e-12);
        moved += fabs(h2[face] - h[face]);
    }
    assert_true(moved > 1e-4);
    double t;
    assert_int_equal(m->update_until(m, 0.12), BMI_SUCCESS);
    m->get_current_time(m, &t);
    assert_true(t == 0.12);
    int inds[] = {4, 0};
    double picked[2];
    assert_int_equal(m->get_value(m, "land_surface__elevation", h), BMI_SUCCESS);
    assert_int_equal(m->get_value_at_indices(m, "land_surface__elevation", picked, inds, 2), BMI_SUCCESS);
    assert_true(picked[0] == h[4] && picked[1] == h[0]);
    int outside[] = {UGRID_TEST_FACES};
    assert_int_equal(m->get_value_at_indices(m, "land_surface__elevation", picked, outside, 1), BMI_FAILURE);
    int edge_outside[] = {UGRID_TEST_EDGES};
    assert_int_equal(m->get_value_at_indices(m, flux, picked, edge_outside, 1), BMI_FAILURE);
    stop(m);
}

/* ---- a dual mesh: TELEMAC's bed at the nodes ----------------------- */

/* grid.kind: dual_mesh over a Selafin geometry: the cells are the file's
 * nodes (location node on the triangle mesh), the flux lies on the
 * triangles' edges, and the bed comes from the file by its name. */
static void dual_mesh_from_selafin(void **state) {
    (void)state;
    char file[512];
    snprintf(file, sizeof file, "%s/geo.slf", folder);
    assert_int_equal(write_selafin(file, 0), 0);
    Bmi *m = start("dual.yaml", "grid: {kind: dual_mesh, file: geo.slf}\n"
                                "initial: {file: geo.slf, variable: BOTTOM}\n"
                                "boundaries: {edge: open, level: cell}\n"
                                "time: {step: 10, end: 30}\n");
    check_conventions(m);
    const char *flux = "land_surface_sediment_flowing__volume_rate";
    /* 16 nodes, 18 triangles, 33 edges (9 squares: 12 + 12 sides, 9 diagonals). */
    check_variable(m, &(struct expected_variable){"land_surface__elevation", "m", "node", 0}, SELAFIN_NODES);
    check_variable(m, &(struct expected_variable){flux, "m3 s-1", "edge", 1}, 33);
    int nodes = 0, faces = 0, edges = 0;
    assert_int_equal(m->get_grid_node_count(m, 0, &nodes), BMI_SUCCESS);
    assert_int_equal(m->get_grid_face_count(m, 0, &faces), BMI_SUCCESS);
    assert_int_equal(m->get_grid_edge_count(m, 1, &edges), BMI_SUCCESS);
    assert_true(nodes == SELAFIN_NODES && faces == SELAFIN_TRIANGLES && edges == 33);
    double h[SELAFIN_NODES], x[SELAFIN_NODES];
    assert_int_equal(m->get_value(m, "land_surface__elevation", h), BMI_SUCCESS);
    assert_int_equal(m->get_grid_x(m, 0, x), BMI_SUCCESS);
    for (int n = 0; n < SELAFIN_NODES; ++n) assert_true(h[n] == 2.0 + n && x[n] == 1000.0 + 10.0 * (n % 4));
    /* A steep pile on node 5: it slides to its neighbours across the edges. */
    h[5] = 40.0;
    assert_int_equal(m->set_value(m, "land_surface__elevation", h), BMI_SUCCESS);
    assert_int_equal(m->update(m), BMI_SUCCESS);
    double f[33], after[SELAFIN_NODES];
    assert_int_equal(m->get_value(m, flux, f), BMI_SUCCESS);
    assert_int_equal(m->get_value(m, "land_surface__elevation", after), BMI_SUCCESS);
    double carried = 0;
    for (int e = 0; e < 33; ++e) assert_true(isfinite(f[e])), carried += fabs(f[e]);
    assert_true(after[5] < 40.0 && carried > 0);
    /* Edges by node pair, lower node first, in increasing order; the flux
     * runs from the lower node's cell to the higher's: out of node 5 along
     * each of its 6 edges. */
    int pairs[66], around = 0;
    assert_int_equal(m->get_grid_edge_nodes(m, 1, pairs), BMI_SUCCESS);
    for (int e = 0; e < 33; ++e) {
        assert_true(pairs[2 * e] < pairs[2 * e + 1]);
        if (e) assert_true(pairs[2 * e - 2] < pairs[2 * e] || (pairs[2 * e - 2] == pairs[2 * e] && pairs[2 * e - 1] < pairs[2 * e + 1]));
        if (pairs[2 * e] == 5) assert_true(f[e] > 0), ++around;
        if (pairs[2 * e + 1] == 5) assert_true(f[e] < 0), ++around;
    }
    assert_int_equal(around, 6);
    stop(m);
}

static int setup(void **state) {
    (void)state;
    snprintf(folder, sizeof folder, "%s/dpsm-bmi-host-XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    return mkdtemp(folder) ? 0 : -1;
}

static int teardown(void **state) {
    (void)state;
    char command[512];
    snprintf(command, sizeof command, "rm -rf '%s'", folder);
    return system(command) == 0 ? 0 : -1;
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: %s <path of libdpsm_bmi.so>\n", argv[0]);
        return 2;
    }
    library_path = argv[1];
    library = dlopen(library_path, RTLD_NOW | RTLD_LOCAL);
    if (!library) {
        fprintf(stderr, "bmi_host: cannot load %s: %s\n", library_path, dlerror());
        return 1;
    }
    /* NextGen's default name, and the component's own. */
    registration = (Bmi * (*)(Bmi *)) dlsym(library, "register_bmi");
    Bmi *(*own)(Bmi *) = (Bmi * (*)(Bmi *)) dlsym(library, "register_bmi_dpsm");
    if (!registration || !own) {
        fprintf(stderr, "bmi_host: %s lacks register_bmi or register_bmi_dpsm\n", library_path);
        return 1;
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(registration_and_information_2d),
        cmocka_unit_test(time_lands_on_the_end),
        cmocka_unit_test(values_in_and_out_2d),
        cmocka_unit_test(bad_input_fails_without_harm),
        cmocka_unit_test(grids_of_a_1d_grid),
        cmocka_unit_test(mesh_grid_and_values),
        cmocka_unit_test(dual_mesh_from_selafin),
    };
    int failed = cmocka_run_group_tests(tests, setup, teardown);
    registration = own; /* the same table through the component's own name */
    failed += cmocka_run_group_tests_name("register_bmi_dpsm", tests, setup, teardown);
    dlclose(library);
    return failed ? 1 : 0;
}
