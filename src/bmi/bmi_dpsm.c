/* dpsm as a BMI 2.0 component: initialize from the YAML configuration, time
 * in seconds, the variables and their values. The grid functions are in
 * bmi_grids.c; docs/guide_bmi.md is the user's view of all of it. */
#include "bmi/component.h"

#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double kDegreesPerRadian = 180 / 3.14159265358979323846;

struct variable_info {
    const char *name;
    const char *units; /* as UDUNITS-2 parses them */
    enum place place;
    int input, output;
    const char *former; /* the name before 0.1's release, still understood (not listed) */
};

/* The names are CSDMS Standard Names: the registry's own where it has one
 * (land_surface__elevation, bedrock_surface__elevation), else built by its
 * rules from quantities and operators its names use (docs/guide_bmi.md
 * lists which). The bed is an input only: with no bed set there is nothing
 * to read, and BMI lists as outputs what can be read after initialize. */
static const struct variable_info kVariables[VAR_COUNT] = {
    [VAR_ELEVATION] = {"land_surface__elevation", "m", PLACE_CELLS, 1, 1, NULL},
    [VAR_BEDROCK] = {"bedrock_surface__elevation", "m", PLACE_CELLS, 1, 0, NULL},
    [VAR_DEPOSITION_RATE] = {"land_surface_sediment_deposition__net_volume_flux", "m s-1", PLACE_CELLS, 1, 0,
                             "land_surface__net_deposition_rate"},
    [VAR_REPOSE_ANGLE] = {"land_surface_sediment__repose_angle", "degree", PLACE_CELLS, 1, 1,
                          "sediment__angle_of_repose"},
    [VAR_FLUX_X] = {"land_surface_sediment_flowing__x_component_of_volume_rate", "m3 s-1", PLACE_FLUX_X, 0, 1,
                    "land_surface_sediment__x_component_of_avalanche_volume_flux"},
    [VAR_FLUX_Y] = {"land_surface_sediment_flowing__y_component_of_volume_rate", "m3 s-1", PLACE_FLUX_Y, 0, 1,
                    "land_surface_sediment__y_component_of_avalanche_volume_flux"},
    [VAR_FLUX_EDGES] = {"land_surface_sediment_flowing__volume_rate", "m3 s-1", PLACE_EDGES, 0, 1,
                        "land_surface_sediment__avalanche_volume_flux"},
    [VAR_TOTAL_VOLUME] = {"land_surface_sediment__volume", "m3", PLACE_SCALAR, 0, 1,
                          "land_surface_sediment__total_volume"},
    [VAR_SOURCED_VOLUME] = {"land_surface_sediment_deposition__domain_time_integral_of_net_volume_flux", "m3",
                            PLACE_SCALAR, 0, 1, "land_surface_sediment__sourced_volume"},
    [VAR_OUTFLOW_VOLUME] = {"land_surface_sediment_flowing_sink__time_integral_of_volume_rate", "m3", PLACE_SCALAR, 0, 1,
                            "land_surface_sediment__outflow_volume"},
    [VAR_EXTERNAL_VOLUME] = {"land_surface_sediment_source__time_integral_of_volume_rate", "m3",
                             PLACE_SCALAR, 0, 1, "land_surface_sediment__external_volume"},
    [VAR_UNMET_VOLUME] = {"land_surface_sediment_erosion~unmet__domain_time_integral_of_volume_flux", "m3",
                          PLACE_SCALAR, 0, 1, "land_surface_sediment__unmet_erosion_volume"},
};

/* The ledger figure behind each scalar. */
static const int kMassQuantity[VAR_COUNT] = {
    [VAR_TOTAL_VOLUME] = DPSM_MASS_TOTAL,       [VAR_SOURCED_VOLUME] = DPSM_MASS_SOURCED,
    [VAR_OUTFLOW_VOLUME] = DPSM_MASS_OUTFLOW,   [VAR_EXTERNAL_VOLUME] = DPSM_MASS_EXTERNAL,
    [VAR_UNMET_VOLUME] = DPSM_MASS_UNMET,
};

int component_fail(const char *function, const char *format, ...) {
    fprintf(stderr, "dpsm bmi: %s: ", function);
    va_list args;
    va_start(args, format);
    vfprintf(stderr, format, args);
    va_end(args);
    fputc('\n', stderr);
    return BMI_FAILURE;
}

struct component *component_of(Bmi *self, const char *function) {
    if (!self) {
        component_fail(function, "the Bmi table is NULL");
        return NULL;
    }
    if (!self->data) component_fail(function, "the component is not initialized (call initialize first)");
    return self->data;
}

int component_place(const struct component *c, enum variable v) {
    enum place p = kVariables[v].place;
    return component_grid_of(c, p) < 0 ? -1 : (int)p;
}

int component_grid_of(const struct component *c, enum place p) {
    int mesh = c->scene.has_mesh, two_d = c->config.grid_kind == CONFIG_GRID_2D;
    switch (p) {
    case PLACE_CELLS: return 0;
    case PLACE_FLUX_X: return mesh ? -1 : 1;
    case PLACE_FLUX_Y: return two_d ? 2 : -1;
    case PLACE_EDGES: return mesh ? 1 : -1;
    case PLACE_SCALAR: return two_d ? 3 : 2;
    }
    return -1;
}

int component_place_of_grid(const struct component *c, int grid) {
    if (grid < 0) return -1;
    for (int p = PLACE_CELLS; p <= PLACE_SCALAR; ++p)
        if (component_grid_of(c, (enum place)p) == grid) return p;
    return -1;
}

/* The variable called `name` that this component has, or -1 (with a message). */
static int find_variable(const struct component *c, const char *name, const char *function) {
    if (!name) return component_fail(function, "the variable name is NULL"), -1;
    for (int v = 0; v < VAR_COUNT; ++v)
        if ((strcmp(kVariables[v].name, name) == 0 || (kVariables[v].former && strcmp(kVariables[v].former, name) == 0)) &&
            component_place(c, (enum variable)v) >= 0)
            return v;
    component_fail(function, "no variable \"%s\" (get_input_var_names and get_output_var_names list them)", name);
    return -1;
}

static int64_t place_size(const struct component *c, enum place p) {
    switch (p) {
    case PLACE_CELLS: return c->scene.cell_count;
    case PLACE_FLUX_X: return (c->nx + 1) * c->ny;
    case PLACE_FLUX_Y: return c->nx * (c->ny + 1);
    case PLACE_EDGES: return c->scene.mesh.edge_count;
    case PLACE_SCALAR: return 1;
    }
    return 0;
}

/* Heights and the ledger as the library holds them now. */
static void refresh(struct component *c) {
    dpsm_get_heights(c->scene.grid, c->values[VAR_ELEVATION]);
    for (int v = VAR_TOTAL_VOLUME; v <= VAR_UNMET_VOLUME; ++v)
        dpsm_get_mass(c->scene.grid, kMassQuantity[v], c->values[v]);
}

static void release(struct component *c) {
    config_scene_free(&c->scene);
    for (int v = 0; v < VAR_COUNT; ++v) free(c->values[v]);
    free(c->carried_x);
    free(c->carried_y);
    free(c);
}

static int initialize(Bmi *self, const char *config_file) {
    if (!self) return component_fail("initialize", "the Bmi table is NULL");
    if (self->data) return component_fail("initialize", "already initialized (call finalize first)");
    if (!config_file) return component_fail("initialize", "the configuration path is NULL");
    struct component *c = calloc(1, sizeof *c);
    if (!c) return component_fail("initialize", "out of memory");
    char message[CONFIG_MESSAGE_MAX];
    if (config_read(config_file, &c->config, message, sizeof message) ||
        config_build(&c->config, &c->scene, message, sizeof message)) {
        free(c);
        return component_fail("initialize", "%s", message);
    }
    dpsm_get_shape(c->scene.grid, &c->nx, &c->ny);
    if (c->scene.has_mesh) c->nx = c->scene.cell_count, c->ny = 1;
    int failed = dpsm_set_face_flux_recording(c->scene.grid, 1) != DPSM_OK;
    for (int v = 0; v < VAR_COUNT && !failed; ++v) {
        int place = component_place(c, (enum variable)v);
        if (place < 0) continue;
        c->sizes[v] = place_size(c, (enum place)place);
        /* BMI counts bytes in an int. */
        if (c->sizes[v] > INT_MAX / (int64_t)sizeof(double)) {
            component_fail("initialize", "%s: %s would hold %lld values, more than BMI's int byte counts allow",
                           config_file, kVariables[v].name, (long long)c->sizes[v]);
            release(c);
            return BMI_FAILURE;
        }
        c->values[v] = calloc((size_t)c->sizes[v], sizeof(double));
        failed = c->values[v] == NULL;
    }
    if (!failed) {
        /* On a mesh every library face (a dual's halves on the domain edge too); the BMI edges are the first. */
        c->carried_x = calloc((size_t)(c->scene.has_mesh ? c->scene.face_count : c->sizes[VAR_FLUX_X]), sizeof(double));
        c->carried_y = c->sizes[VAR_FLUX_Y] ? calloc((size_t)c->sizes[VAR_FLUX_Y], sizeof(double)) : NULL;
        failed = !c->carried_x || (c->sizes[VAR_FLUX_Y] && !c->carried_y);
    }
    if (failed) {
        release(c);
        return component_fail("initialize", "%s: out of memory", config_file);
    }
    if (c->scene.source) memcpy(c->values[VAR_DEPOSITION_RATE], c->scene.source, (size_t)c->scene.cell_count * 8);
    double angle = c->config.has_repose_angle ? c->config.repose_angle_degrees
                                              : DPSM_DEFAULT_REPOSE_ANGLE * kDegreesPerRadian;
    for (int64_t k = 0; k < c->scene.cell_count; ++k) c->values[VAR_REPOSE_ANGLE][k] = angle;
    refresh(c);
    self->data = c;
    return BMI_SUCCESS;
}

static int finalize(Bmi *self) {
    struct component *c = component_of(self, "finalize");
    if (!c) return BMI_FAILURE;
    release(c);
    self->data = NULL;
    return BMI_SUCCESS;
}

/* One dpsm_step of `dt`, adding what each face carried to the sums. */
static int step(struct component *c, double dt, const char *function) {
    char message[CONFIG_MESSAGE_MAX];
    if (config_scene_before_step(&c->scene, message, sizeof message))
        return component_fail(function, "at t = %.17g s: %s", c->time, message);
    if (dpsm_step(c->scene.grid, dt) != DPSM_OK)
        return component_fail(function, "at t = %.17g s: %s", c->time, dpsm_last_error(c->scene.grid));
    int64_t nx_faces = c->scene.has_mesh ? c->scene.face_count : c->sizes[VAR_FLUX_X];
    double *fx = malloc((size_t)nx_faces * sizeof *fx);
    double *fy = c->carried_y ? malloc((size_t)c->sizes[VAR_FLUX_Y] * sizeof *fy) : NULL;
    if (!fx || (c->carried_y && !fy) || dpsm_get_face_fluxes(c->scene.grid, fx, fy) != DPSM_OK) {
        free(fx), free(fy);
        return component_fail(function, "cannot read the face fluxes: %s", dpsm_last_error(c->scene.grid));
    }
    for (int64_t k = 0; k < nx_faces; ++k) c->carried_x[k] += fx[k];
    for (int64_t k = 0; fy && k < c->sizes[VAR_FLUX_Y]; ++k) c->carried_y[k] += fy[k];
    free(fx), free(fy);
    return BMI_SUCCESS;
}

/* Steps from the current time to `then` in time steps and a final partial
 * one that lands exactly on `then`; the fluxes become what the faces
 * carried over the whole advance divided by its duration. */
static int advance_to(struct component *c, double then, const char *function) {
    double start = c->time, dt = c->config.time_step;
    int64_t nx_faces = c->scene.has_mesh ? c->scene.face_count : c->sizes[VAR_FLUX_X];
    memset(c->carried_x, 0, (size_t)nx_faces * sizeof(double));
    if (c->carried_y) memset(c->carried_y, 0, (size_t)c->sizes[VAR_FLUX_Y] * sizeof(double));
    int status = BMI_SUCCESS;
    while (c->time < then) {
        /* A remainder below a millionth of a step joins the last step rather
         * than making a step of its own that only rounding asked for. */
        int last = then - c->time <= dt * (1 + 1e-6);
        double this_dt = last ? then - c->time : dt;
        if ((status = step(c, this_dt, function)) != BMI_SUCCESS) break;
        c->time = last ? then : c->time + dt;
    }
    double duration = c->time - start;
    enum variable fx = c->scene.has_mesh ? VAR_FLUX_EDGES : VAR_FLUX_X;
    for (int64_t k = 0; k < c->sizes[fx]; ++k) c->values[fx][k] = duration > 0 ? c->carried_x[k] / duration : 0;
    for (int64_t k = 0; c->carried_y && k < c->sizes[VAR_FLUX_Y]; ++k)
        c->values[VAR_FLUX_Y][k] = duration > 0 ? c->carried_y[k] / duration : 0;
    refresh(c);
    return status;
}

static int update(Bmi *self) {
    struct component *c = component_of(self, "update");
    if (!c) return BMI_FAILURE;
    double end = c->config.time_end, then = c->time + c->config.time_step;
    /* The last step before the end time is shortened to land on it; past
     * the end, update keeps taking whole steps. */
    if (c->time < end && then >= end - 1e-6 * c->config.time_step) then = end;
    return advance_to(c, then, "update");
}

static int update_until(Bmi *self, double then) {
    struct component *c = component_of(self, "update_until");
    if (!c) return BMI_FAILURE;
    if (!isfinite(then) || then < c->time)
        return component_fail("update_until", "time %.17g s is not finite or lies before the current time %.17g s",
                              then, c->time);
    return advance_to(c, then, "update_until");
}

static int get_component_name(Bmi *self, char *name) {
    (void)self;
    if (!name) return component_fail("get_component_name", "name is NULL");
    snprintf(name, BMI_MAX_COMPONENT_NAME, "dpsm");
    return BMI_SUCCESS;
}

static int count_items(Bmi *self, int *count, int inputs, const char *function) {
    struct component *c = component_of(self, function);
    if (!c) return BMI_FAILURE;
    if (!count) return component_fail(function, "count is NULL");
    *count = 0;
    for (int v = 0; v < VAR_COUNT; ++v)
        if (component_place(c, (enum variable)v) >= 0 && (inputs ? kVariables[v].input : kVariables[v].output))
            ++*count;
    return BMI_SUCCESS;
}

static int list_items(Bmi *self, char **names, int inputs, const char *function) {
    struct component *c = component_of(self, function);
    if (!c) return BMI_FAILURE;
    if (!names) return component_fail(function, "names is NULL");
    int n = 0;
    for (int v = 0; v < VAR_COUNT; ++v)
        if (component_place(c, (enum variable)v) >= 0 && (inputs ? kVariables[v].input : kVariables[v].output)) {
            if (!names[n]) return component_fail(function, "names[%d] is NULL", n);
            snprintf(names[n++], BMI_MAX_VAR_NAME, "%s", kVariables[v].name);
        }
    return BMI_SUCCESS;
}

static int get_input_item_count(Bmi *self, int *count) { return count_items(self, count, 1, "get_input_item_count"); }
static int get_output_item_count(Bmi *self, int *count) { return count_items(self, count, 0, "get_output_item_count"); }
static int get_input_var_names(Bmi *self, char **names) { return list_items(self, names, 1, "get_input_var_names"); }
static int get_output_var_names(Bmi *self, char **names) { return list_items(self, names, 0, "get_output_var_names"); }

/* The component and the variable `name` for a function that writes to `out`. */
static struct component *lookup(Bmi *self, const char *name, const void *out, const char *function, int *v) {
    struct component *c = component_of(self, function);
    if (!c || (*v = find_variable(c, name, function)) < 0) return NULL;
    if (!out) {
        component_fail(function, "the output pointer for \"%s\" is NULL", name);
        return NULL;
    }
    return c;
}

static int get_var_grid(Bmi *self, const char *name, int *grid) {
    int v;
    struct component *c = lookup(self, name, grid, "get_var_grid", &v);
    if (!c) return BMI_FAILURE;
    *grid = component_grid_of(c, kVariables[v].place);
    return BMI_SUCCESS;
}

static int get_var_type(Bmi *self, const char *name, char *type) {
    int v;
    if (!lookup(self, name, type, "get_var_type", &v)) return BMI_FAILURE;
    snprintf(type, BMI_MAX_TYPE_NAME, "double");
    return BMI_SUCCESS;
}

static int get_var_units(Bmi *self, const char *name, char *units) {
    int v;
    if (!lookup(self, name, units, "get_var_units", &v)) return BMI_FAILURE;
    snprintf(units, BMI_MAX_UNITS_NAME, "%s", kVariables[v].units);
    return BMI_SUCCESS;
}

static int get_var_itemsize(Bmi *self, const char *name, int *size) {
    int v;
    if (!lookup(self, name, size, "get_var_itemsize", &v)) return BMI_FAILURE;
    *size = (int)sizeof(double);
    return BMI_SUCCESS;
}

static int get_var_nbytes(Bmi *self, const char *name, int *nbytes) {
    int v;
    struct component *c = lookup(self, name, nbytes, "get_var_nbytes", &v);
    if (!c) return BMI_FAILURE;
    *nbytes = (int)(c->sizes[v] * (int64_t)sizeof(double));
    return BMI_SUCCESS;
}

static int get_var_location(Bmi *self, const char *name, char *location) {
    int v;
    struct component *c = lookup(self, name, location, "get_var_location", &v);
    if (!c) return BMI_FAILURE;
    const char *where = "node";
    /* On a mesh the cells are its faces; on a dual mesh its nodes. */
    if (c->scene.has_mesh && !c->scene.cells_at_nodes && kVariables[v].place == PLACE_CELLS) where = "face";
    if (kVariables[v].place == PLACE_EDGES) where = "edge";
    snprintf(location, BMI_MAX_TYPE_NAME, "%s", where);
    return BMI_SUCCESS;
}

static int get_time(Bmi *self, double *time, int which, const char *function) {
    struct component *c = component_of(self, function);
    if (!c) return BMI_FAILURE;
    if (!time) return component_fail(function, "the output pointer is NULL");
    *time = which == 0 ? c->time : which == 1 ? 0.0 : which == 2 ? c->config.time_end : c->config.time_step;
    return BMI_SUCCESS;
}

static int get_current_time(Bmi *self, double *time) { return get_time(self, time, 0, "get_current_time"); }
static int get_start_time(Bmi *self, double *time) { return get_time(self, time, 1, "get_start_time"); }
static int get_end_time(Bmi *self, double *time) { return get_time(self, time, 2, "get_end_time"); }
static int get_time_step(Bmi *self, double *time_step) { return get_time(self, time_step, 3, "get_time_step"); }

static int get_time_units(Bmi *self, char *units) {
    (void)self;
    if (!units) return component_fail("get_time_units", "units is NULL");
    snprintf(units, BMI_MAX_UNITS_NAME, "s");
    return BMI_SUCCESS;
}

/* The bed has no value until a host sets one: no made-up heights (it is an
 * input, not listed as an output). */
static int readable(const struct component *c, int v, const char *function) {
    if (v == VAR_BEDROCK && !c->has_bedrock)
        return component_fail(function, "bedrock_surface__elevation has no value: no bed was set (it is an input; "
                                        "set_value first)");
    return BMI_SUCCESS;
}

static int get_value_ptr(Bmi *self, const char *name, void **dest_ptr) {
    int v;
    struct component *c = lookup(self, name, dest_ptr, "get_value_ptr", &v);
    if (!c || readable(c, v, "get_value_ptr")) return BMI_FAILURE;
    *dest_ptr = c->values[v];
    return BMI_SUCCESS;
}

static int get_value(Bmi *self, const char *name, void *dest) {
    int v;
    struct component *c = lookup(self, name, dest, "get_value", &v);
    if (!c || readable(c, v, "get_value")) return BMI_FAILURE;
    memcpy(dest, c->values[v], (size_t)c->sizes[v] * sizeof(double));
    return BMI_SUCCESS;
}

static int check_indices(const struct component *c, int v, const int *inds, int count, const char *function) {
    if (count < 0) return component_fail(function, "count = %d is negative", count);
    if (count > 0 && !inds) return component_fail(function, "inds is NULL");
    for (int k = 0; k < count; ++k)
        if (inds[k] < 0 || inds[k] >= c->sizes[v])
            return component_fail(function, "inds[%d] = %d lies outside %s's %lld values (from 0)", k, inds[k],
                                  kVariables[v].name, (long long)c->sizes[v]);
    return BMI_SUCCESS;
}

static int get_value_at_indices(Bmi *self, const char *name, void *dest, int *inds, int count) {
    int v;
    struct component *c = lookup(self, name, dest, "get_value_at_indices", &v);
    if (!c || readable(c, v, "get_value_at_indices") || check_indices(c, v, inds, count, "get_value_at_indices"))
        return BMI_FAILURE;
    double *out = dest;
    for (int k = 0; k < count; ++k) out[k] = c->values[v][inds[k]];
    return BMI_SUCCESS;
}

/* Hands a whole input field to the library; on success it becomes the
 * variable's value, on failure nothing changes. */
static int apply(struct component *c, int v, const double *field, const char *function) {
    int64_t n = c->scene.cell_count;
    dpsm_grid *g = c->scene.grid;
    int status;
    if (v == VAR_ELEVATION) status = dpsm_set_heights(g, field);
    else if (v == VAR_BEDROCK) status = dpsm_set_bedrock(g, field);
    else if (v == VAR_DEPOSITION_RATE) status = dpsm_set_source(g, field);
    else {
        double *radians = malloc((size_t)n * sizeof *radians);
        if (!radians) return component_fail(function, "out of memory");
        for (int64_t k = 0; k < n; ++k) radians[k] = field[k] / kDegreesPerRadian;
        status = dpsm_set_repose_angle_field(g, radians);
        free(radians);
    }
    if (status != DPSM_OK) return component_fail(function, "%s: %s", kVariables[v].name, dpsm_last_error(g));
    if (v != VAR_ELEVATION) memmove(c->values[v], field, (size_t)n * sizeof(double));
    if (v == VAR_BEDROCK) c->has_bedrock = 1;
    refresh(c); /* a bed lifts the sand below it; heights book external volume */
    return BMI_SUCCESS;
}

static int settable(const struct component *c, int v, const char *function) {
    (void)c;
    if (!kVariables[v].input)
        return component_fail(function, "%s is an output only; the inputs are %s, %s, %s and %s", kVariables[v].name,
                              kVariables[VAR_ELEVATION].name, kVariables[VAR_BEDROCK].name,
                              kVariables[VAR_DEPOSITION_RATE].name, kVariables[VAR_REPOSE_ANGLE].name);
    return BMI_SUCCESS;
}

static int set_value(Bmi *self, const char *name, void *src) {
    int v;
    struct component *c = lookup(self, name, src, "set_value", &v);
    if (!c || settable(c, v, "set_value")) return BMI_FAILURE;
    return apply(c, v, src, "set_value");
}

static int set_value_at_indices(Bmi *self, const char *name, int *inds, int count, void *src) {
    int v;
    struct component *c = lookup(self, name, src, "set_value_at_indices", &v);
    if (!c || settable(c, v, "set_value_at_indices") || check_indices(c, v, inds, count, "set_value_at_indices"))
        return BMI_FAILURE;
    if (v == VAR_BEDROCK && !c->has_bedrock)
        return component_fail("set_value_at_indices", "no bed was set yet: set bedrock_surface__elevation whole first");
    double *field = malloc((size_t)c->sizes[v] * sizeof *field);
    if (!field) return component_fail("set_value_at_indices", "out of memory");
    memcpy(field, c->values[v], (size_t)c->sizes[v] * sizeof *field);
    const double *values = src;
    for (int k = 0; k < count; ++k) field[inds[k]] = values[k];
    int status = apply(c, v, field, "set_value_at_indices");
    free(field);
    return status;
}

Bmi *register_bmi_dpsm(Bmi *model) {
    if (!model) return NULL;
    model->data = NULL;
    model->initialize = initialize;
    model->update = update;
    model->update_until = update_until;
    model->finalize = finalize;
    model->get_component_name = get_component_name;
    model->get_input_item_count = get_input_item_count;
    model->get_output_item_count = get_output_item_count;
    model->get_input_var_names = get_input_var_names;
    model->get_output_var_names = get_output_var_names;
    model->get_var_grid = get_var_grid;
    model->get_var_type = get_var_type;
    model->get_var_units = get_var_units;
    model->get_var_itemsize = get_var_itemsize;
    model->get_var_nbytes = get_var_nbytes;
    model->get_var_location = get_var_location;
    model->get_current_time = get_current_time;
    model->get_start_time = get_start_time;
    model->get_end_time = get_end_time;
    model->get_time_units = get_time_units;
    model->get_time_step = get_time_step;
    model->get_value = get_value;
    model->get_value_ptr = get_value_ptr;
    model->get_value_at_indices = get_value_at_indices;
    model->set_value = set_value;
    model->set_value_at_indices = set_value_at_indices;
    component_register_grids(model);
    return model;
}

Bmi *register_bmi(Bmi *model) { return register_bmi_dpsm(model); }
