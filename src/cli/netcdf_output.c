/* The output of `dpsm run`: snapshots of the surface and the ledger's time
 * series in one netCDF file (CF conventions; UGRID 1.0 on meshes). */
#include "cli/netcdf_output.h"

#include <netcdf.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const kLedgerNames[OUTPUT_LEDGER_FIGURES] = {
    "total_volume", "sourced_volume", "external_volume", "outflow_volume", "unmet_erosion_volume"};
static const char *const kLedgerMeanings[OUTPUT_LEDGER_FIGURES] = {
    "volume of sand on the sand cells",
    "volume added by the source since the start",
    "volume set from outside since the start (the initial heights included)",
    "volume that left through open sides and open cells since the start",
    "erosion asked for by the source that found no sand, since the start"};

#define TRY(call)                                                                                                     \
    do {                                                                                                              \
        int status_ = (call);                                                                                         \
        if (status_ != NC_NOERR) return fail(out, #call, status_, message, size);                                     \
    } while (0)

static int fail(struct output *out, const char *what, int status, char *message, size_t size) {
    snprintf(message, size, "%s: cannot write (%s): %s", out->path, what, nc_strerror(status));
    return 1;
}

static int text(int file, int variable, const char *name, const char *value) {
    return nc_put_att_text(file, variable, name, strlen(value), value);
}

/* Coordinates of a structured grid: cell centres along x (and y). */
static int define_grid(struct output *out, const struct config *c, int *space_dims, int *ndims, char *message,
                       size_t size) {
    int x_dim, y_dim;
    TRY(nc_def_dim(out->file, "x", (size_t)c->nx, &x_dim));
    TRY(nc_def_var(out->file, "x", NC_DOUBLE, 1, &x_dim, &out->x_var));
    TRY(text(out->file, out->x_var, "units", "m"));
    TRY(text(out->file, out->x_var, "axis", "X"));
    TRY(text(out->file, out->x_var, "long_name",
             c->grid_kind == CONFIG_GRID_AXISYMMETRIC ? "radius of the cell centres" : "x of the cell centres"));
    if (c->grid_kind != CONFIG_GRID_2D) {
        space_dims[0] = x_dim;
        *ndims = 1;
        return 0;
    }
    TRY(nc_def_dim(out->file, "y", (size_t)c->ny, &y_dim));
    TRY(nc_def_var(out->file, "y", NC_DOUBLE, 1, &y_dim, &out->y_var));
    TRY(text(out->file, out->y_var, "units", "m"));
    TRY(text(out->file, out->y_var, "axis", "Y"));
    TRY(text(out->file, out->y_var, "long_name", "y of the cell centres"));
    space_dims[0] = y_dim, space_dims[1] = x_dim;
    *ndims = 2;
    return 0;
}

/* The UGRID mesh topology: nodes, faces (the cells) from 0, padded with -1. */
static int define_mesh(struct output *out, const struct config_scene *s, int *space_dims, int *ndims, char *message,
                       size_t size) {
    const struct config_mesh *m = &s->mesh;
    int node_dim, face_dim, width_dim, topology;
    int64_t width = 0;
    for (int64_t f = 0; f < m->face_count; ++f)
        if (m->face_node_start[f + 1] - m->face_node_start[f] > width) width = m->face_node_start[f + 1] - m->face_node_start[f];
    out->mesh_width = width;
    TRY(nc_def_dim(out->file, "node", (size_t)m->node_count, &node_dim));
    TRY(nc_def_dim(out->file, "cell", (size_t)m->face_count, &face_dim));
    TRY(nc_def_dim(out->file, "max_cell_nodes", (size_t)width, &width_dim));
    TRY(nc_def_var(out->file, "mesh", NC_INT, 0, NULL, &topology));
    TRY(text(out->file, topology, "cf_role", "mesh_topology"));
    TRY(text(out->file, topology, "long_name", "the mesh of the cells"));
    int dimension = 2, start = 0, fill = -1;
    TRY(nc_put_att_int(out->file, topology, "topology_dimension", NC_INT, 1, &dimension));
    TRY(text(out->file, topology, "node_coordinates", "mesh_node_x mesh_node_y"));
    TRY(text(out->file, topology, "face_node_connectivity", "mesh_face_nodes"));
    TRY(text(out->file, topology, "face_dimension", "cell"));
    TRY(nc_def_var(out->file, "mesh_node_x", NC_DOUBLE, 1, &node_dim, &out->x_var));
    TRY(nc_def_var(out->file, "mesh_node_y", NC_DOUBLE, 1, &node_dim, &out->y_var));
    if (s->geographic) {
        TRY(text(out->file, out->x_var, "units", "degrees_east"));
        TRY(text(out->file, out->x_var, "standard_name", "longitude"));
        TRY(text(out->file, out->y_var, "units", "degrees_north"));
        TRY(text(out->file, out->y_var, "standard_name", "latitude"));
    } else {
        TRY(text(out->file, out->x_var, "units", "m"));
        TRY(text(out->file, out->y_var, "units", "m"));
    }
    TRY(text(out->file, out->x_var, "long_name", "x of the mesh nodes"));
    TRY(text(out->file, out->y_var, "long_name", "y of the mesh nodes"));
    int dims[2] = {face_dim, width_dim};
    TRY(nc_def_var(out->file, "mesh_face_nodes", NC_INT, 2, dims, &out->faces_var));
    TRY(text(out->file, out->faces_var, "cf_role", "face_node_connectivity"));
    TRY(nc_put_att_int(out->file, out->faces_var, "_FillValue", NC_INT, 1, &fill));
    TRY(nc_put_att_int(out->file, out->faces_var, "start_index", NC_INT, 1, &start));
    /* The cells: the faces, or the nodes of a dual mesh. */
    space_dims[0] = s->cells_at_nodes ? node_dim : face_dim;
    *ndims = 1;
    return 0;
}

static int write_coordinates(struct output *out, const struct config *c, const struct config_scene *s, char *message,
                             size_t size) {
    if (s->has_mesh) {
        const struct config_mesh *m = &s->mesh;
        TRY(nc_put_var_double(out->file, out->x_var, m->node_x));
        TRY(nc_put_var_double(out->file, out->y_var, m->node_y));
        int *table = malloc((size_t)(m->face_count * out->mesh_width) * sizeof *table);
        if (!table) return fail(out, "memory for the faces", NC_ENOMEM, message, size);
        for (int64_t f = 0; f < m->face_count; ++f)
            for (int64_t k = 0; k < out->mesh_width; ++k) {
                int64_t p = m->face_node_start[f] + k;
                table[f * out->mesh_width + k] = p < m->face_node_start[f + 1] ? (int)m->face_nodes[p] : -1;
            }
        int status = nc_put_var_int(out->file, out->faces_var, table);
        free(table);
        TRY(status);
        return 0;
    }
    int64_t longest = c->nx > c->ny ? c->nx : c->ny;
    double *centres = malloc((size_t)longest * sizeof *centres);
    if (!centres) return fail(out, "memory for the coordinates", NC_ENOMEM, message, size);
    for (int64_t i = 0; i < c->nx; ++i) centres[i] = ((double)i + 0.5) * c->dx;
    int status = nc_put_var_double(out->file, out->x_var, centres);
    if (status == NC_NOERR && c->grid_kind == CONFIG_GRID_2D) {
        for (int64_t j = 0; j < c->ny; ++j) centres[j] = ((double)j + 0.5) * c->dy;
        status = nc_put_var_double(out->file, out->y_var, centres);
    }
    free(centres);
    TRY(status);
    return 0;
}

int output_open(struct output *out, const struct config *c, const struct config_scene *s, const char *history,
                char *message, size_t size) {
    memset(out, 0, sizeof *out);
    out->path = c->output_file;
    out->cells = (size_t)s->cell_count;
    int status = nc_create(out->path, NC_CLOBBER | NC_64BIT_OFFSET, &out->file);
    if (status != NC_NOERR) return fail(out, "create", status, message, size);
    out->open = 1;
    TRY(text(out->file, NC_GLOBAL, "Conventions", s->has_mesh ? "CF-1.8 UGRID-1.0" : "CF-1.8"));
    TRY(text(out->file, NC_GLOBAL, "title", "dpsm run: a granular surface by the Degenerate Parabolic Sliding Model"));
    TRY(text(out->file, NC_GLOBAL, "source", "dpsm " DPSM_VERSION_STRING));
    TRY(text(out->file, NC_GLOBAL, "history", history));
    int time_dim, space_dims[2] = {0, 0}, ndims = 0;
    TRY(nc_def_dim(out->file, "time", NC_UNLIMITED, &time_dim));
    TRY(nc_def_var(out->file, "time", NC_DOUBLE, 1, &time_dim, &out->time_var));
    TRY(text(out->file, out->time_var, "units", "s"));
    TRY(text(out->file, out->time_var, "long_name", "simulated time since the start of the run"));
    TRY(text(out->file, out->time_var, "axis", "T"));
    if (s->has_mesh ? define_mesh(out, s, space_dims, &ndims, message, size)
                    : define_grid(out, c, space_dims, &ndims, message, size))
        return 1;
    int dims[3] = {time_dim, space_dims[0], space_dims[1]};
    TRY(nc_def_var(out->file, "h", NC_DOUBLE, ndims + 1, dims, &out->h_var));
    TRY(text(out->file, out->h_var, "units", "m"));
    TRY(text(out->file, out->h_var, "long_name", "height of the granular surface"));
    if (s->has_mesh) {
        TRY(text(out->file, out->h_var, "mesh", "mesh"));
        TRY(text(out->file, out->h_var, "location", s->cells_at_nodes ? "node" : "face"));
    } else {
        TRY(text(out->file, out->h_var, "coordinates", c->grid_kind == CONFIG_GRID_2D ? "y x" : "x"));
    }
    for (int k = 0; k < OUTPUT_LEDGER_FIGURES; ++k) {
        TRY(nc_def_var(out->file, kLedgerNames[k], NC_DOUBLE, 1, &time_dim, &out->ledger_vars[k]));
        TRY(text(out->file, out->ledger_vars[k], "units", "m3"));
        TRY(text(out->file, out->ledger_vars[k], "long_name", kLedgerMeanings[k]));
    }
    TRY(nc_enddef(out->file));
    return write_coordinates(out, c, s, message, size);
}

int output_snapshot(struct output *out, double time, const double *heights, const double ledger[OUTPUT_LEDGER_FIGURES],
                    char *message, size_t size) {
    size_t start[3] = {out->snapshots, 0, 0}, one = 1;
    size_t count[3] = {1, 0, 0};
    int ndims;
    nc_inq_varndims(out->file, out->h_var, &ndims);
    int dims[3];
    nc_inq_vardimid(out->file, out->h_var, dims);
    for (int d = 1; d < ndims; ++d) nc_inq_dimlen(out->file, dims[d], &count[d]);
    TRY(nc_put_vara_double(out->file, out->time_var, start, &one, &time));
    TRY(nc_put_vara_double(out->file, out->h_var, start, count, heights));
    for (int k = 0; k < OUTPUT_LEDGER_FIGURES; ++k)
        TRY(nc_put_vara_double(out->file, out->ledger_vars[k], start, &one, &ledger[k]));
    TRY(nc_sync(out->file));
    ++out->snapshots;
    return 0;
}

int output_close(struct output *out, char *message, size_t size) {
    if (!out->open) return 0;
    out->open = 0;
    TRY(nc_close(out->file));
    return 0;
}
