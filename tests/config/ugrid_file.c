#include "ugrid_file.h"

#include <netcdf.h>
#include <string.h>

const int ugrid_test_face_nodes[UGRID_TEST_FACES][4] = {
    {0, 1, 4, 3}, {1, 2, 5, 4}, {3, 4, 7, 6}, {4, 5, 8, -1}, {4, 8, 7, -1}};

#define TRY(call)                                                                                                     \
    do {                                                                                                              \
        int status_ = (call);                                                                                         \
        if (status_ != NC_NOERR) {                                                                                    \
            nc_close(file);                                                                                           \
            return status_;                                                                                           \
        }                                                                                                             \
    } while (0)

int write_ugrid_test_mesh(const char *path, int start_index) {
    int file, node_dim, face_dim, width_dim, mesh, x, y, faces;
    int status = nc_create(path, NC_CLOBBER, &file);
    if (status != NC_NOERR) return status;
    TRY(nc_def_dim(file, "nMesh2_node", UGRID_TEST_NODES, &node_dim));
    TRY(nc_def_dim(file, "nMesh2_face", UGRID_TEST_FACES, &face_dim));
    TRY(nc_def_dim(file, "nMaxMesh2_face_nodes", 4, &width_dim));
    TRY(nc_def_var(file, "Mesh2", NC_INT, 0, NULL, &mesh));
    TRY(nc_put_att_text(file, mesh, "cf_role", strlen("mesh_topology"), "mesh_topology"));
    int dimension = 2;
    TRY(nc_put_att_int(file, mesh, "topology_dimension", NC_INT, 1, &dimension));
    TRY(nc_put_att_text(file, mesh, "node_coordinates", strlen("Mesh2_node_x Mesh2_node_y"), "Mesh2_node_x Mesh2_node_y"));
    TRY(nc_put_att_text(file, mesh, "face_node_connectivity", strlen("Mesh2_face_nodes"), "Mesh2_face_nodes"));
    TRY(nc_def_var(file, "Mesh2_node_x", NC_DOUBLE, 1, &node_dim, &x));
    TRY(nc_def_var(file, "Mesh2_node_y", NC_DOUBLE, 1, &node_dim, &y));
    /* Projected coordinates say so: without units, numbers within +-90 would be taken for degrees. */
    TRY(nc_put_att_text(file, x, "units", 1, "m"));
    TRY(nc_put_att_text(file, y, "units", 1, "m"));
    int dims[2] = {face_dim, width_dim};
    TRY(nc_def_var(file, "Mesh2_face_nodes", NC_INT, 2, dims, &faces));
    int fill = -999;
    TRY(nc_put_att_int(file, faces, "_FillValue", NC_INT, 1, &fill));
    TRY(nc_put_att_int(file, faces, "start_index", NC_INT, 1, &start_index));
    TRY(nc_enddef(file));
    double node_x[UGRID_TEST_NODES], node_y[UGRID_TEST_NODES];
    for (int n = 0; n < UGRID_TEST_NODES; ++n) node_x[n] = n % 3, node_y[n] = n / 3;
    int table[UGRID_TEST_FACES][4];
    for (int f = 0; f < UGRID_TEST_FACES; ++f)
        for (int k = 0; k < 4; ++k)
            table[f][k] = ugrid_test_face_nodes[f][k] < 0 ? fill : ugrid_test_face_nodes[f][k] + start_index;
    TRY(nc_put_var_double(file, x, node_x));
    TRY(nc_put_var_double(file, y, node_y));
    TRY(nc_put_var_int(file, faces, &table[0][0]));
    return nc_close(file);
}

int write_field_file(const char *path, const char *name, int rank, const char *const *dims, const size_t *lengths,
                     const double *values) {
    int file, dim_ids[2], variable;
    int status = nc_create(path, NC_CLOBBER, &file);
    if (status != NC_NOERR) return status;
    for (int d = 0; d < rank; ++d) TRY(nc_def_dim(file, dims[d], lengths[d], &dim_ids[d]));
    TRY(nc_def_var(file, name, NC_DOUBLE, rank, dim_ids, &variable));
    TRY(nc_enddef(file));
    TRY(nc_put_var_double(file, variable, values));
    return nc_close(file);
}
