/* Mesh files as production codes write them: which reader takes a file
 * (by its first bytes), and a variable of the file with where it lies. */
#include "config/mesh_readers.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum format { FORMAT_UNKNOWN, FORMAT_NETCDF, FORMAT_GMSH, FORMAT_SELAFIN };

/* The format by the file's first bytes: netCDF's "CDF" (classic) or HDF5's
 * signature (netCDF-4), gmsh's "$MeshFormat", Selafin's title record (80
 * in 4 bytes, either byte order). */
static int format_of(const char *path, enum format *format, char *message, size_t size) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(message, size, "%s: cannot open the mesh file: %s", path, strerror(errno));
        return 1;
    }
    unsigned char head[32] = {0};
    size_t got = fread(head, 1, sizeof head, f);
    fclose(f);
    size_t skip = 0;
    while (skip < got && (head[skip] == ' ' || head[skip] == '\n' || head[skip] == '\r' || head[skip] == '\t')) ++skip;
    if (got >= 4 && memcmp(head, "CDF", 3) == 0) *format = FORMAT_NETCDF;
    else if (got >= 8 && memcmp(head, "\x89HDF\r\n\x1a\n", 8) == 0) *format = FORMAT_NETCDF;
    else if (got - skip >= 11 && memcmp(head + skip, "$MeshFormat", 11) == 0) *format = FORMAT_GMSH;
    else if (got >= 4 && ((head[0] == 0 && head[1] == 0 && head[2] == 0 && head[3] == 80) ||
                          (head[0] == 80 && head[1] == 0 && head[2] == 0 && head[3] == 0)))
        *format = FORMAT_SELAFIN;
    else *format = FORMAT_UNKNOWN;
    return 0;
}

int config_read_mesh(const char *path, const char *topology, struct config_mesh *mesh, char *message, size_t size) {
    memset(mesh, 0, sizeof *mesh);
    enum format format;
    if (format_of(path, &format, message, size)) return 1;
    if (topology && topology[0] && format != FORMAT_NETCDF) {
        snprintf(message, size, "%s: grid.topology names a UGRID mesh topology, and this is not a netCDF file", path);
        return 1;
    }
    int status;
    switch (format) {
        case FORMAT_NETCDF: status = ugrid_read_mesh(path, topology, mesh, message, size); break;
        case FORMAT_GMSH: status = gmsh_read_mesh(path, mesh, message, size); break;
        case FORMAT_SELAFIN: status = selafin_read_mesh(path, mesh, message, size); break;
        default:
            snprintf(message, size, "%s: not a mesh file dpsm reads: neither netCDF (UGRID), gmsh (.msh, ASCII) nor "
                     "Selafin (.slf)", path);
            status = 1;
    }
    if (status) config_mesh_free(mesh);
    return status;
}

int config_read_mesh_variable(const struct config_mesh *mesh, const char *path, const char *variable,
                              enum config_location cells_at, double **values, int64_t *count,
                              enum config_location *where, char *message, size_t size) {
    *values = NULL;
    enum format format;
    if (format_of(path, &format, message, size)) return 1;
    const int64_t cells = cells_at == CONFIG_AT_NODES ? mesh->node_count : mesh->face_count;
    if (format == FORMAT_SELAFIN) {
        *where = CONFIG_AT_NODES;
        if (selafin_read_variable(path, variable, values, count, message, size)) return 1;
        if (*count != mesh->node_count) {
            snprintf(message, size, "%s: variable \"%s\" has %lld values, one per node of a mesh of %lld nodes, and "
                     "the mesh has %lld", path, variable, (long long)*count, (long long)*count,
                     (long long)mesh->node_count);
            free(*values), *values = NULL;
            return 1;
        }
        return 0;
    }
    if (format == FORMAT_NETCDF) {
        /* The mesh's own file names its dimensions; another file is placed by
         * its location attribute or its length. */
        return ugrid_read_variable(mesh, path, variable, cells_at, cells, values, count, where, message, size);
    }
    snprintf(message, size, "%s: variables are read from netCDF and Selafin files, and this is %s", path,
             format == FORMAT_GMSH ? "a gmsh mesh (whose $NodeData dpsm does not read)" : "neither");
    return 1;
}

void config_mesh_free(struct config_mesh *mesh) {
    free(mesh->node_x);
    free(mesh->node_y);
    free(mesh->face_node_start);
    free(mesh->face_nodes);
    free(mesh->face_edges);
    free(mesh->edge_nodes);
    free(mesh->file_edge_nodes);
    for (int g = 0; g < mesh->group_count; ++g) free(mesh->groups[g].edge_nodes);
    free(mesh->groups);
    memset(mesh, 0, sizeof *mesh);
}
