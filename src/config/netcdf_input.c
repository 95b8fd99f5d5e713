/* The netCDF inputs of a configuration: fields over the cells (initial
 * heights, a source) and UGRID 1.0 meshes, read with netCDF-C. */
#include "config/netcdf_input.h"

#include <math.h>
#include <netcdf.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int nc_refuse(char *message, size_t size, const char *path, const char *what, int status) {
    snprintf(message, size, "%s: %s: %s", path, what, nc_strerror(status));
    return 1;
}

/* A text attribute, or "" when the variable has none (or not as text). */
static void text_attribute(int file, int variable, const char *name, char *out, size_t size) {
    size_t length = 0;
    nc_type type;
    out[0] = '\0';
    if (nc_inq_att(file, variable, name, &type, &length) != NC_NOERR || type != NC_CHAR || length >= size) return;
    if (nc_get_att_text(file, variable, name, out) != NC_NOERR) out[0] = '\0';
    else out[length] = '\0';
}

static int open_file(const char *path, int *file, char *message, size_t size) {
    int status = nc_open(path, NC_NOWRITE, file);
    return status == NC_NOERR ? 0 : nc_refuse(message, size, path, "cannot open as netCDF", status);
}

int netcdf_read_field(const char *path, const char *variable, int rank, size_t length0, size_t length1, double *values,
                      char *message, size_t size) {
    int file, id, ndims, dims[NC_MAX_VAR_DIMS];
    if (open_file(path, &file, message, size)) return 1;
    int status = nc_inq_varid(file, variable, &id);
    if (status != NC_NOERR) {
        snprintf(message, size, "%s: no variable \"%s\" in the file", path, variable);
        nc_close(file);
        return 1;
    }
    nc_inq_varndims(file, id, &ndims);
    nc_inq_vardimid(file, id, dims);
    size_t lengths[2] = {0, 0};
    for (int d = 0; d < ndims && d < 2; ++d) nc_inq_dimlen(file, dims[d], &lengths[d]);
    if (ndims != rank || lengths[0] != length0 || (rank == 2 && lengths[1] != length1)) {
        if (rank == 2)
            snprintf(message, size, "%s: variable \"%s\": expected dimensions (y, x) of %zu x %zu, as the grid has", path,
                     variable, length0, length1);
        else
            snprintf(message, size, "%s: variable \"%s\": expected one dimension of %zu, one value per cell", path,
                     variable, length0);
        nc_close(file);
        return 1;
    }
    /* Missing data reads as the fill value: refused, never taken for a height. */
    double fill = NC_FILL_DOUBLE;
    nc_type type;
    if (nc_get_att_double(file, id, "_FillValue", &fill) != NC_NOERR && nc_inq_vartype(file, id, &type) == NC_NOERR &&
        type == NC_FLOAT)
        fill = NC_FILL_FLOAT;
    status = nc_get_var_double(file, id, values);
    nc_close(file);
    if (status != NC_NOERR) return nc_refuse(message, size, path, variable, status);
    size_t count = rank == 2 ? length0 * length1 : length0;
    for (size_t k = 0; k < count; ++k)
        if (values[k] == fill) {
            snprintf(message, size, "%s: variable \"%s\": value %zu (from 0) is missing (the fill value)", path, variable,
                     k);
            return 1;
        } else if (!isfinite(values[k]) || fabs(values[k]) > 1e50) {
            snprintf(message, size, "%s: variable \"%s\": value %zu (from 0) is %g, not a finite height or rate", path,
                     variable, k, values[k]);
            return 1;
        }
    return 0;
}

/* Finds the variable with cf_role = "mesh_topology" and topology_dimension 2. */
static int find_topology(int file, const char *path, int *topology, char *message, size_t size) {
    int nvars;
    nc_inq_nvars(file, &nvars);
    for (int v = 0; v < nvars; ++v) {
        char role[64];
        text_attribute(file, v, "cf_role", role, sizeof role);
        if (strcmp(role, "mesh_topology") != 0) continue;
        int dimension = 0;
        if (nc_get_att_int(file, v, "topology_dimension", &dimension) != NC_NOERR || dimension != 2) {
            snprintf(message, size, "%s: the mesh_topology variable has no topology_dimension = 2 (a 2D mesh of faces)",
                     path);
            return 1;
        }
        *topology = v;
        return 0;
    }
    snprintf(message, size, "%s: no UGRID mesh (no variable with cf_role = \"mesh_topology\")", path);
    return 1;
}

static int read_nodes(int file, int topology, const char *path, struct config_mesh *mesh, char *message, size_t size) {
    char names[512], x_name[256], y_name[256];
    text_attribute(file, topology, "node_coordinates", names, sizeof names);
    if (sscanf(names, "%255s %255s", x_name, y_name) != 2) {
        snprintf(message, size, "%s: the mesh has no node_coordinates attribute naming two variables (x y)", path);
        return 1;
    }
    const char *coordinate_names[2] = {x_name, y_name};
    double **coordinates[2] = {&mesh->node_x, &mesh->node_y};
    for (int axis = 0; axis < 2; ++axis) {
        int id, ndims, dim;
        size_t length;
        if (nc_inq_varid(file, coordinate_names[axis], &id) != NC_NOERR) {
            snprintf(message, size, "%s: node coordinate variable \"%s\" is missing", path, coordinate_names[axis]);
            return 1;
        }
        nc_inq_varndims(file, id, &ndims);
        if (ndims != 1) {
            snprintf(message, size, "%s: node coordinate variable \"%s\" must have one dimension", path,
                     coordinate_names[axis]);
            return 1;
        }
        nc_inq_vardimid(file, id, &dim);
        nc_inq_dimlen(file, dim, &length);
        if (axis == 1 && (int64_t)length != mesh->node_count) {
            snprintf(message, size, "%s: \"%s\" and \"%s\" differ in length", path, x_name, y_name);
            return 1;
        }
        mesh->node_count = (int64_t)length;
        *coordinates[axis] = malloc((length ? length : 1) * sizeof(double));
        if (!*coordinates[axis]) {
            snprintf(message, size, "%s: out of memory", path);
            return 1;
        }
        int status = nc_get_var_double(file, id, *coordinates[axis]);
        if (status != NC_NOERR) return nc_refuse(message, size, path, coordinate_names[axis], status);
    }
    return 0;
}

/* face_node_connectivity (faces x max nodes per face, padded with
 * _FillValue) into offsets and node indices from 0. */
static int read_faces(int file, int topology, const char *path, struct config_mesh *mesh, char *message, size_t size) {
    char name[256];
    int id, ndims, dims[2];
    text_attribute(file, topology, "face_node_connectivity", name, sizeof name);
    if (!name[0] || nc_inq_varid(file, name, &id) != NC_NOERR) {
        snprintf(message, size, "%s: the mesh has no face_node_connectivity variable", path);
        return 1;
    }
    nc_inq_varndims(file, id, &ndims);
    if (ndims != 2) {
        snprintf(message, size, "%s: \"%s\" must have two dimensions (faces, nodes per face)", path, name);
        return 1;
    }
    nc_inq_vardimid(file, id, dims);
    size_t faces, width;
    nc_inq_dimlen(file, dims[0], &faces);
    nc_inq_dimlen(file, dims[1], &width);
    long long start_index = 0, fill = NC_FILL_INT;
    int has_fill = nc_get_att_longlong(file, id, "_FillValue", &fill) == NC_NOERR;
    nc_get_att_longlong(file, id, "start_index", &start_index);
    if (start_index != 0 && start_index != 1) {
        snprintf(message, size, "%s: \"%s\": start_index is %lld, expected 0 or 1", path, name, start_index);
        return 1;
    }
    size_t entries = faces * width > 0 ? faces * width : 1;
    long long *table = malloc(entries * sizeof *table);
    mesh->face_node_start = malloc((faces + 1) * sizeof(int64_t));
    mesh->face_nodes = malloc(entries * sizeof(int64_t));
    if (!table || !mesh->face_node_start || !mesh->face_nodes) {
        free(table);
        snprintf(message, size, "%s: out of memory", path);
        return 1;
    }
    int status = nc_get_var_longlong(file, id, table);
    if (status != NC_NOERR) {
        free(table);
        return nc_refuse(message, size, path, name, status);
    }
    int64_t used = 0;
    mesh->face_node_start[0] = 0;
    for (size_t f = 0; f < faces; ++f) {
        for (size_t k = 0; k < width; ++k) {
            long long node = table[f * width + k];
            if ((has_fill && node == fill) || (!has_fill && node < start_index)) break;
            if (node < start_index || node - start_index >= mesh->node_count) {
                snprintf(message, size, "%s: \"%s\"(%zu, %zu) = %lld is not a node (%lld .. %lld)", path, name, f, k,
                         node, start_index, (long long)mesh->node_count - 1 + start_index);
                free(table);
                return 1;
            }
            mesh->face_nodes[used++] = node - start_index;
        }
        mesh->face_node_start[f + 1] = used;
    }
    free(table);
    mesh->face_count = (int64_t)faces;
    return 0;
}

int config_read_mesh(const char *path, struct config_mesh *mesh, char *message, size_t size) {
    memset(mesh, 0, sizeof *mesh);
    int file, topology;
    if (open_file(path, &file, message, size)) return 1;
    int status = find_topology(file, path, &topology, message, size) ||
                 read_nodes(file, topology, path, mesh, message, size) ||
                 read_faces(file, topology, path, mesh, message, size);
    nc_close(file);
    if (status) config_mesh_free(mesh);
    return status;
}

void config_mesh_free(struct config_mesh *mesh) {
    free(mesh->node_x);
    free(mesh->node_y);
    free(mesh->face_node_start);
    free(mesh->face_nodes);
    free(mesh->face_edges);
    free(mesh->edge_nodes);
    memset(mesh, 0, sizeof *mesh);
}
