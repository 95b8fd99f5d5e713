#define _POSIX_C_SOURCE 200809L /* strdup, strtok_r */
/* The netCDF inputs of a configuration: fields over the cells (initial
 * heights, a source) and UGRID 1.0 meshes, read with netCDF-C. */
#include "config/netcdf_input.h"
#include "config/mesh_readers.h"

#include <limits.h>
#include <math.h>
#include <netcdf.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

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

int netcdf_field_sign(const char *path, const char *variable, char *said, size_t size) {
    int file, id, sign = 0;
    said[0] = '\0';
    if (nc_open(path, NC_NOWRITE, &file) != NC_NOERR) return 0;
    if (nc_inq_varid(file, variable, &id) == NC_NOERR) {
        char positive[64], standard_name[256];
        text_attribute(file, id, "positive", positive, sizeof positive);
        text_attribute(file, id, "standard_name", standard_name, sizeof standard_name);
        if (strcasecmp(positive, "down") == 0 || strcasecmp(positive, "up") == 0) {
            sign = strcasecmp(positive, "down") == 0 ? -1 : 1;
            snprintf(said, size, "%.100s:positive = \"%.60s\"", variable, positive);
        } else if (strstr(standard_name, "depth")) {
            sign = -1;
            snprintf(said, size, "%.100s:standard_name = \"%.200s\"", variable, standard_name);
        } else if (strstr(standard_name, "elevation") || strstr(standard_name, "altitude") ||
                   strstr(standard_name, "height")) {
            sign = 1;
            snprintf(said, size, "%.100s:standard_name = \"%.200s\"", variable, standard_name);
        }
    }
    nc_close(file);
    return sign;
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

/* ---- UGRID 1.0 meshes ------------------------------------------------------ */

/* A variable's name, or "" when it has none (cannot happen in a good file). */
static void variable_name(int file, int variable, char *out, size_t size) {
    char name[NC_MAX_NAME + 1] = "";
    nc_inq_varname(file, variable, name);
    snprintf(out, size, "%s", name);
}

static void dimension_name(int file, int dimension, char *out, size_t size) {
    char name[NC_MAX_NAME + 1] = "";
    nc_inq_dimname(file, dimension, name);
    snprintf(out, size, "%s", name);
}

/* The mesh_topology variable to read: the one named `wanted`, else the only
 * one of topology_dimension 2. The messages name the topologies found. */
static int find_topology(int file, const char *path, const char *wanted, int *topology, char *message, size_t size) {
    int nvars = 0, count = 0, two_d = 0, chosen = -1, wanted_id = -1, wanted_dimension = 0;
    char found[768] = "", two_d_names[512] = "";
    nc_inq_nvars(file, &nvars);
    for (int v = 0; v < nvars; ++v) {
        char role[64], name[CONFIG_NAME_MAX], entry[CONFIG_NAME_MAX + 32];
        text_attribute(file, v, "cf_role", role, sizeof role);
        if (strcmp(role, "mesh_topology") != 0) continue;
        int dimension = 0;
        nc_get_att_int(file, v, "topology_dimension", &dimension);
        variable_name(file, v, name, sizeof name);
        snprintf(entry, sizeof entry, "%s%s (%dD)", count ? ", " : "", name, dimension);
        strncat(found, entry, sizeof found - strlen(found) - 1);
        ++count;
        if (dimension == 2) {
            snprintf(entry, sizeof entry, "%s%s", two_d ? ", " : "", name);
            strncat(two_d_names, entry, sizeof two_d_names - strlen(two_d_names) - 1);
            ++two_d;
            if (!wanted || !wanted[0]) chosen = v;
        }
        if (wanted && wanted[0] && strcmp(name, wanted) == 0) wanted_id = v, wanted_dimension = dimension;
    }
    if (wanted_id >= 0 && wanted_dimension != 2) {
        snprintf(message, size, "%s: topology \"%s\" has topology_dimension = %d; dpsm needs a 2D topology%s%s", path,
                 wanted, wanted_dimension, two_d ? ": " : " and the file has none", two_d_names);
        return 1;
    }
    if (wanted_id >= 0) {
        *topology = wanted_id;
        return 0;
    }
    if (count == 0) {
        snprintf(message, size, "%s: no UGRID mesh (no variable with cf_role = \"mesh_topology\")", path);
        return 1;
    }
    if (wanted && wanted[0]) {
        snprintf(message, size, "%s: no mesh topology \"%s\" (grid.topology); the file has %s", path, wanted, found);
        return 1;
    }
    if (two_d == 0) {
        snprintf(message, size, "%s: none of its mesh topologies is 2D (topology_dimension = 2): it has %s", path,
                 found);
        return 1;
    }
    if (two_d > 1) {
        snprintf(message, size, "%s: it has %d 2D mesh topologies (%s); choose one with grid.topology", path, two_d,
                 two_d_names);
        return 1;
    }
    *topology = chosen;
    return 0;
}

/* What a coordinate variable's attributes say: geographic, projected, or nothing. */
static enum config_coordinates coordinates_of(int file, int variable, char *said, size_t size) {
    char standard_name[128], units[128], grid_mapping[CONFIG_NAME_MAX], name[CONFIG_NAME_MAX];
    text_attribute(file, variable, "standard_name", standard_name, sizeof standard_name);
    text_attribute(file, variable, "units", units, sizeof units);
    text_attribute(file, variable, "grid_mapping", grid_mapping, sizeof grid_mapping);
    variable_name(file, variable, name, sizeof name);
    static const char *const degrees[] = {"degrees_east", "degree_east", "degrees_E", "degreesE", "degree_E",
                                          "degrees_north", "degree_north", "degrees_N", "degreesN", "degree_N",
                                          "degrees", "degree", NULL};
    static const char *const metres[] = {"m", "metre", "metres", "meter", "meters", NULL};
    if (strcmp(standard_name, "longitude") == 0 || strcmp(standard_name, "latitude") == 0) {
        snprintf(said, size, "%.100s:standard_name = \"%.100s\"", name, standard_name);
        return CONFIG_COORDINATES_GEOGRAPHIC;
    }
    for (const char *const *u = degrees; *u; ++u)
        if (strcmp(units, *u) == 0) {
            snprintf(said, size, "%.100s:units = \"%.100s\"", name, units);
            return CONFIG_COORDINATES_GEOGRAPHIC;
        }
    if (strncmp(standard_name, "projection_", 11) == 0) {
        snprintf(said, size, "%.100s:standard_name = \"%.100s\"", name, standard_name);
        return CONFIG_COORDINATES_PROJECTED;
    }
    for (const char *const *u = metres; *u; ++u)
        if (strcmp(units, *u) == 0) {
            snprintf(said, size, "%.100s:units = \"%.100s\"", name, units);
            return CONFIG_COORDINATES_PROJECTED;
        }
    int mapping;
    if (grid_mapping[0] && nc_inq_varid(file, grid_mapping, &mapping) == NC_NOERR) {
        char mapping_name[128];
        text_attribute(file, mapping, "grid_mapping_name", mapping_name, sizeof mapping_name);
        if (mapping_name[0]) {
            snprintf(said, size, "%.100s:grid_mapping_name = \"%.100s\"", grid_mapping, mapping_name);
            return strcmp(mapping_name, "latitude_longitude") == 0 ? CONFIG_COORDINATES_GEOGRAPHIC
                                                                   : CONFIG_COORDINATES_PROJECTED;
        }
    }
    if (units[0]) snprintf(said, size, "%.100s:units = \"%.100s\"", name, units);
    return CONFIG_COORDINATES_FROM_FILE;
}

/* A variable the topology names in `attribute` (the first of its names). */
static int linked_variable(int file, int topology, const char *attribute, int *id, char *name, size_t size) {
    char names[512];
    text_attribute(file, topology, attribute, names, sizeof names);
    char first[CONFIG_NAME_MAX] = "";
    if (sscanf(names, "%255s", first) != 1) return 1;
    snprintf(name, size, "%s", first);
    return nc_inq_varid(file, first, id) != NC_NOERR;
}

static int read_nodes(int file, int topology, const char *path, struct config_mesh *mesh, char *message, size_t size) {
    char names[512], x_name[256], y_name[256];
    text_attribute(file, topology, "node_coordinates", names, sizeof names);
    if (sscanf(names, "%255s %255s", x_name, y_name) != 2) {
        snprintf(message, size, "%s: mesh \"%s\" has no node_coordinates attribute naming two variables (x y)", path,
                 mesh->topology);
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
        if (axis == 0) dimension_name(file, dim, mesh->node_dimension, sizeof mesh->node_dimension);
        mesh->node_count = (int64_t)length;
        *coordinates[axis] = malloc((length ? length : 1) * sizeof(double));
        if (!*coordinates[axis]) {
            snprintf(message, size, "%s: out of memory", path);
            return 1;
        }
        int status = nc_get_var_double(file, id, *coordinates[axis]);
        if (status != NC_NOERR) return nc_refuse(message, size, path, coordinate_names[axis], status);
        /* Missing coordinates (the fill value) read as NaN: checked where a face uses the node. */
        double fill;
        if (nc_get_att_double(file, id, "_FillValue", &fill) == NC_NOERR)
            for (size_t k = 0; k < length; ++k)
                if ((*coordinates[axis])[k] == fill) (*coordinates[axis])[k] = NAN;
        char said[256] = "";
        enum config_coordinates kind = coordinates_of(file, id, said, sizeof said);
        if (kind != CONFIG_COORDINATES_FROM_FILE && mesh->coordinates == CONFIG_COORDINATES_FROM_FILE) {
            mesh->coordinates = kind;
            snprintf(mesh->coordinates_said, sizeof mesh->coordinates_said, "%s", said);
        } else if (!mesh->coordinates_said[0]) {
            snprintf(mesh->coordinates_said, sizeof mesh->coordinates_said, "%s", said);
        }
    }
    return 0;
}

/* A table of `rows` x `width` node indices (faces or edges): rows of the
 * dimension `row_dimension`, or the other way round; padded with _FillValue
 * (or values below start_index); into offsets and node indices from 0. */
static int read_table(int file, int id, const char *name, const char *path, const char *row_dimension,
                      int64_t node_count, int64_t **row_start, int64_t **nodes, int64_t *row_count, char *row_name,
                      size_t row_name_size, char *message, size_t size) {
    int ndims, dims[2];
    nc_inq_varndims(file, id, &ndims);
    if (ndims != 2) {
        snprintf(message, size, "%s: \"%s\" must have two dimensions", path, name);
        return 1;
    }
    nc_inq_vardimid(file, id, dims);
    char first[CONFIG_NAME_MAX], second[CONFIG_NAME_MAX];
    dimension_name(file, dims[0], first, sizeof first);
    dimension_name(file, dims[1], second, sizeof second);
    /* UGRID allows the table either way round: its rows are the dimension the topology names. */
    const int transposed = row_dimension && row_dimension[0] && strcmp(second, row_dimension) == 0 &&
                           strcmp(first, row_dimension) != 0;
    size_t rows, width;
    nc_inq_dimlen(file, dims[transposed ? 1 : 0], &rows);
    nc_inq_dimlen(file, dims[transposed ? 0 : 1], &width);
    snprintf(row_name, row_name_size, "%s", transposed ? second : first);
    long long start_index = 0, fill = NC_FILL_INT;
    int has_fill = nc_get_att_longlong(file, id, "_FillValue", &fill) == NC_NOERR;
    nc_get_att_longlong(file, id, "start_index", &start_index);
    if (start_index != 0 && start_index != 1) {
        snprintf(message, size, "%s: \"%s\": start_index is %lld, expected 0 or 1", path, name, start_index);
        return 1;
    }
    size_t entries = rows * width > 0 ? rows * width : 1;
    long long *table = malloc(entries * sizeof *table);
    *row_start = malloc((rows + 1) * sizeof(int64_t));
    *nodes = malloc(entries * sizeof(int64_t));
    if (!table || !*row_start || !*nodes) {
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
    (*row_start)[0] = 0;
    for (size_t f = 0; f < rows; ++f) {
        for (size_t k = 0; k < width; ++k) {
            long long node = transposed ? table[k * rows + f] : table[f * width + k];
            if ((has_fill && node == fill) || (!has_fill && node < start_index)) break;
            if (node < start_index || node - start_index >= node_count) {
                snprintf(message, size, "%s: \"%s\"(%zu, %zu) = %lld is not a node (%lld .. %lld)", path, name, f, k,
                         node, start_index, (long long)node_count - 1 + start_index);
                free(table);
                return 1;
            }
            (*nodes)[used++] = node - start_index;
        }
        (*row_start)[f + 1] = used;
    }
    free(table);
    *row_count = (int64_t)rows;
    return 0;
}

/* face_node_connectivity, or faces built from edge_node_connectivity. */
static int read_faces(int file, int topology, const char *path, struct config_mesh *mesh, char *message, size_t size) {
    char name[CONFIG_NAME_MAX], face_dimension[CONFIG_NAME_MAX], edge_dimension[CONFIG_NAME_MAX];
    int id;
    text_attribute(file, topology, "face_dimension", face_dimension, sizeof face_dimension);
    text_attribute(file, topology, "edge_dimension", edge_dimension, sizeof edge_dimension);
    /* The edges as the file lists them: for a variable on them, and for faces without a table. */
    if (!linked_variable(file, topology, "edge_node_connectivity", &id, name, sizeof name)) {
        int64_t *start = NULL;
        if (read_table(file, id, name, path, edge_dimension, mesh->node_count, &start, &mesh->file_edge_nodes,
                       &mesh->file_edge_count, mesh->edge_dimension, sizeof mesh->edge_dimension, message, size)) {
            free(start);
            return 1;
        }
        for (int64_t e = 0; e < mesh->file_edge_count; ++e)
            if (start[e + 1] - start[e] != 2) {
                snprintf(message, size, "%s: \"%s\": edge %lld has %lld nodes, not 2", path, name, (long long)e,
                         (long long)(start[e + 1] - start[e]));
                free(start);
                return 1;
            }
        free(start);
    }
    if (!linked_variable(file, topology, "face_node_connectivity", &id, name, sizeof name))
        return read_table(file, id, name, path, face_dimension, mesh->node_count, &mesh->face_node_start,
                          &mesh->face_nodes, &mesh->face_count, mesh->face_dimension, sizeof mesh->face_dimension,
                          message, size);
    if (!mesh->file_edge_nodes) {
        snprintf(message, size, "%s: mesh \"%s\" has neither face_node_connectivity nor edge_node_connectivity", path,
                 mesh->topology);
        return 1;
    }
    /* Nodes and edges only (D-Flow FM builds the faces itself): so do we. */
    for (int64_t e = 0; e < 2 * mesh->file_edge_count; ++e)
        if (!isfinite(mesh->node_x[mesh->file_edge_nodes[e]]) || !isfinite(mesh->node_y[mesh->file_edge_nodes[e]])) {
            snprintf(message, size, "%s: node %lld of edge %lld has no coordinates (the fill value)", path,
                     (long long)mesh->file_edge_nodes[e], (long long)(e / 2));
            return 1;
        }
    mesh->faces_from_edges = 1;
    if (face_dimension[0]) snprintf(mesh->face_dimension, sizeof mesh->face_dimension, "%s", face_dimension);
    return mesh_faces_from_edges(path, mesh->node_x, mesh->node_y, mesh->node_count, mesh->file_edge_nodes,
                                 mesh->file_edge_count, &mesh->face_node_start, &mesh->face_nodes, &mesh->face_count,
                                 message, size);
}

/* Boundary groups: the edges of boundary_node_connectivity, grouped by the
 * values of each integer variable on its dimension (named by flag_meanings
 * where it has them). */
static int read_boundaries(int file, int topology, const char *path, struct config_mesh *mesh, char *message,
                           size_t size) {
    char name[CONFIG_NAME_MAX], rows_name[CONFIG_NAME_MAX];
    int id;
    if (linked_variable(file, topology, "boundary_node_connectivity", &id, name, sizeof name)) return 0;
    int64_t *start = NULL, *nodes = NULL, count = 0;
    if (read_table(file, id, name, path, NULL, mesh->node_count, &start, &nodes, &count, rows_name, sizeof rows_name,
                   message, size)) {
        free(start), free(nodes);
        return 1;
    }
    int boundary_dim;
    nc_inq_dimid(file, rows_name, &boundary_dim);
    int nvars = 0, failed = 0;
    nc_inq_nvars(file, &nvars);
    int64_t *pairs = malloc((size_t)(2 * (count > 0 ? count : 1)) * sizeof *pairs);
    long long *tags = malloc((size_t)(count > 0 ? count : 1) * sizeof *tags);
    for (int v = 0; v < nvars && !failed && pairs && tags; ++v) {
        int ndims, dim;
        nc_type type;
        nc_inq_varndims(file, v, &ndims);
        nc_inq_vartype(file, v, &type);
        if (ndims != 1 || v == id || (type != NC_INT && type != NC_SHORT && type != NC_BYTE && type != NC_INT64))
            continue;
        nc_inq_vardimid(file, v, &dim);
        if (dim != boundary_dim || nc_get_var_longlong(file, v, tags) != NC_NOERR) continue;
        char meanings[2048] = "";
        long long values[64];
        size_t nvalues = 0;
        text_attribute(file, v, "flag_meanings", meanings, sizeof meanings);
        if (nc_inq_attlen(file, v, "flag_values", &nvalues) != NC_NOERR || nvalues > 64 ||
            nc_get_att_longlong(file, v, "flag_values", values) != NC_NOERR)
            nvalues = 0;
        /* One group per distinct tag, in the order of the tags. */
        long long done_below = LLONG_MIN;
        for (;;) {
            int64_t b = -1;
            for (int64_t e = 0; e < count; ++e)
                if (tags[e] > done_below && (b < 0 || tags[e] < tags[b])) b = e;
            if (b < 0 || failed) break;
            done_below = tags[b];
            int64_t n = 0;
            for (int64_t e = b; e < count; ++e)
                if (tags[e] == tags[b] && start[e + 1] - start[e] == 2)
                    pairs[2 * n] = nodes[start[e]], pairs[2 * n + 1] = nodes[start[e] + 1], ++n;
            char group_name[CONFIG_NAME_MAX] = "";
            for (size_t k = 0; k < nvalues; ++k)
                if (values[k] == tags[b]) { /* the k-th word of flag_meanings */
                    char *copy = strdup(meanings), *save = NULL, *word = strtok_r(copy, " ", &save);
                    for (size_t j = 0; word && j < k; ++j) word = strtok_r(NULL, " ", &save);
                    if (word) snprintf(group_name, sizeof group_name, "%s", word);
                    free(copy);
                }
            failed = mesh_add_group(mesh, group_name, (long)tags[b], pairs, n, path, message, size);
        }
    }
    free(pairs), free(tags), free(start), free(nodes);
    return failed;
}

int ugrid_read_mesh(const char *path, const char *topology_name, struct config_mesh *mesh, char *message,
                    size_t size) {
    int file, topology;
    if (open_file(path, &file, message, size)) return 1;
    snprintf(mesh->format, sizeof mesh->format, "UGRID");
    int status = find_topology(file, path, topology_name, &topology, message, size);
    if (!status) {
        variable_name(file, topology, mesh->topology, sizeof mesh->topology);
        status = read_nodes(file, topology, path, mesh, message, size) ||
                 read_faces(file, topology, path, mesh, message, size) ||
                 read_boundaries(file, topology, path, mesh, message, size);
    }
    nc_close(file);
    return status;
}

int ugrid_read_variable(const struct config_mesh *mesh, const char *path, const char *variable,
                        enum config_location cells_at, int64_t cells, double **values, int64_t *count,
                        enum config_location *where, char *message, size_t size) {
    int file, id, ndims, dim;
    if (open_file(path, &file, message, size)) return 1;
    if (nc_inq_varid(file, variable, &id) != NC_NOERR) {
        snprintf(message, size, "%s: no variable \"%s\" in the file", path, variable);
        nc_close(file);
        return 1;
    }
    nc_inq_varndims(file, id, &ndims);
    size_t length = 0;
    char dimension[CONFIG_NAME_MAX] = "", location[64];
    if (ndims == 1) {
        nc_inq_vardimid(file, id, &dim);
        nc_inq_dimlen(file, dim, &length);
        dimension_name(file, dim, dimension, sizeof dimension);
    }
    text_attribute(file, id, "location", location, sizeof location);
    /* Where the values lie: the mesh's own dimensions first, then the
     * location attribute, then the length (the cells when it is theirs). */
    int at = -1;
    if (mesh && mesh->node_dimension[0] && strcmp(dimension, mesh->node_dimension) == 0) at = CONFIG_AT_NODES;
    else if (mesh && mesh->face_dimension[0] && strcmp(dimension, mesh->face_dimension) == 0) at = CONFIG_AT_FACES;
    else if (mesh && mesh->edge_dimension[0] && strcmp(dimension, mesh->edge_dimension) == 0) at = CONFIG_AT_EDGES;
    else if (strcmp(location, "node") == 0) at = CONFIG_AT_NODES;
    else if (strcmp(location, "face") == 0) at = CONFIG_AT_FACES;
    else if (strcmp(location, "edge") == 0) at = CONFIG_AT_EDGES;
    else if ((int64_t)length == cells) at = (int)cells_at;
    else if (mesh && (int64_t)length == mesh->node_count) at = CONFIG_AT_NODES;
    else if (mesh && (int64_t)length == mesh->face_count) at = CONFIG_AT_FACES;
    else if (mesh && (int64_t)length == mesh->file_edge_count && length > 0) at = CONFIG_AT_EDGES;
    const int64_t expected = at == CONFIG_AT_NODES ? (mesh ? mesh->node_count : cells)
                             : at == CONFIG_AT_FACES ? (mesh ? mesh->face_count : cells)
                             : at == CONFIG_AT_EDGES ? (mesh ? mesh->file_edge_count : -1)
                                                     : -1;
    if (ndims != 1 || at < 0 || (int64_t)length != expected) {
        if (mesh)
            snprintf(message, size,
                     "%s: variable \"%s\": expected one dimension of the mesh's %lld nodes, %lld faces or %lld edges "
                     "(%s, %s, %s), got %d dimension%s%s%s of %zu",
                     path, variable, (long long)mesh->node_count, (long long)mesh->face_count,
                     (long long)mesh->file_edge_count, mesh->node_dimension[0] ? mesh->node_dimension : "node",
                     mesh->face_dimension[0] ? mesh->face_dimension : "face",
                     mesh->edge_dimension[0] ? mesh->edge_dimension : "edge", ndims, ndims == 1 ? "" : "s",
                     ndims == 1 ? " " : "", dimension, length);
        else
            snprintf(message, size, "%s: variable \"%s\": expected one dimension of %lld, one value per cell", path,
                     variable, (long long)cells);
        nc_close(file);
        return 1;
    }
    nc_close(file);
    *values = malloc((size_t)(length ? length : 1) * sizeof(double));
    if (!*values) {
        snprintf(message, size, "%s: out of memory", path);
        return 1;
    }
    if (netcdf_read_field(path, variable, 1, length, 1, *values, message, size)) {
        free(*values);
        *values = NULL;
        return 1;
    }
    *count = (int64_t)length;
    *where = (enum config_location)at;
    return 0;
}
