#include "mesh_files.h"

#include <math.h>
#include <netcdf.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define TRY(call)                                                                                                     \
    do {                                                                                                              \
        int status_ = (call);                                                                                         \
        if (status_ != NC_NOERR) {                                                                                    \
            fprintf(stderr, "%s:%d: %s: %s\n", __FILE__, __LINE__, #call, nc_strerror(status_));                      \
            nc_close(file);                                                                                           \
            return status_;                                                                                           \
        }                                                                                                             \
    } while (0)

static int text(int file, int variable, const char *name, const char *value) {
    return nc_put_att_text(file, variable, name, strlen(value), value);
}

/* The 2D mesh of the net files: node n = i + 4 j at (10 i, 10 j). */
static const int kNetFaces[NET_FACES][4] = {{0, 1, 5, 4}, {4, 5, 9, 8},  {1, 2, 6, 5},  {5, 6, 10, 9},
                                            {2, 3, 7, -1}, {2, 7, 6, -1}, {6, 7, 11, -1}, {6, 11, 10, -1}};
static const int kNetEdges[][2] = {{0, 1}, {1, 2},  {2, 3},  {4, 5},  {5, 6},   {6, 7},  {8, 9},  {9, 10}, {10, 11},
                                   {0, 4}, {4, 8},  {1, 5},  {5, 9},  {2, 6},   {6, 10}, {3, 7},  {7, 11}, {2, 7},
                                   {6, 11}};
#define NET_EDGE_COUNT 19
/* Boundary edges and their tags: 1 inflow (x = 0), 2 outflow (x = 30), 0 closed. */
static const int kNetBoundary[][3] = {{0, 1, 0}, {1, 2, 0},  {2, 3, 0},  {3, 7, 2}, {7, 11, 2},
                                      {8, 9, 0}, {9, 10, 0}, {10, 11, 0}, {0, 4, 1}, {4, 8, 1}};
#define NET_BOUNDARY_COUNT 10

/* A 2D topology `name` of the net file's mesh, its variables prefixed by name. */
static int define_mesh2d(int file, const char *name, int *ids) {
    char dim_name[128], attribute[512], var[128];
    int node_dim, face_dim, width_dim, edge_dim, two_dim, boundary_dim, topology;
    snprintf(dim_name, sizeof dim_name, "%s_nNodes", name);
    TRY(nc_def_dim(file, dim_name, NET_NODES, &node_dim));
    snprintf(dim_name, sizeof dim_name, "%s_nFaces", name);
    TRY(nc_def_dim(file, dim_name, NET_FACES, &face_dim));
    snprintf(dim_name, sizeof dim_name, "max_n%s_face_nodes", name);
    TRY(nc_def_dim(file, dim_name, 4, &width_dim));
    snprintf(dim_name, sizeof dim_name, "%s_nEdges", name);
    TRY(nc_def_dim(file, dim_name, NET_EDGE_COUNT, &edge_dim));
    snprintf(dim_name, sizeof dim_name, "%s_nBoundaries", name);
    TRY(nc_def_dim(file, dim_name, NET_BOUNDARY_COUNT, &boundary_dim));
    if (nc_inq_dimid(file, "Two", &two_dim) != NC_NOERR) TRY(nc_def_dim(file, "Two", 2, &two_dim));
    TRY(nc_def_var(file, name, NC_INT, 0, NULL, &topology));
    TRY(text(file, topology, "cf_role", "mesh_topology"));
    TRY(text(file, topology, "long_name", "Topology data of 2D network"));
    int two = 2;
    TRY(nc_put_att_int(file, topology, "topology_dimension", NC_INT, 1, &two));
    snprintf(attribute, sizeof attribute, "%s_node_x %s_node_y", name, name);
    TRY(text(file, topology, "node_coordinates", attribute));
    snprintf(attribute, sizeof attribute, "%s_face_nodes", name);
    TRY(text(file, topology, "face_node_connectivity", attribute));
    snprintf(attribute, sizeof attribute, "%s_edge_nodes", name);
    TRY(text(file, topology, "edge_node_connectivity", attribute));
    snprintf(attribute, sizeof attribute, "%s_bnd_nodes", name);
    TRY(text(file, topology, "boundary_node_connectivity", attribute));
    snprintf(attribute, sizeof attribute, "%s_nFaces", name);
    TRY(text(file, topology, "face_dimension", attribute));
    snprintf(attribute, sizeof attribute, "%s_nEdges", name);
    TRY(text(file, topology, "edge_dimension", attribute));
    snprintf(attribute, sizeof attribute, "%s_face_x %s_face_y", name, name);
    TRY(text(file, topology, "face_coordinates", attribute));
    const char *axes[2] = {"x", "y"};
    for (int a = 0; a < 2; ++a) {
        snprintf(var, sizeof var, "%s_node_%s", name, axes[a]);
        TRY(nc_def_var(file, var, NC_DOUBLE, 1, &node_dim, &ids[a]));
        TRY(text(file, ids[a], "standard_name", a ? "projection_y_coordinate" : "projection_x_coordinate"));
        TRY(text(file, ids[a], "units", "m"));
        snprintf(var, sizeof var, "%s_face_%s", name, axes[a]);
        TRY(nc_def_var(file, var, NC_DOUBLE, 1, &face_dim, &ids[2 + a]));
        TRY(text(file, ids[2 + a], "units", "m"));
    }
    int dims[2] = {face_dim, width_dim}, fill = -2147483647, one = 1;
    snprintf(var, sizeof var, "%s_face_nodes", name);
    TRY(nc_def_var(file, var, NC_INT, 2, dims, &ids[4]));
    TRY(nc_put_att_int(file, ids[4], "_FillValue", NC_INT, 1, &fill));
    TRY(text(file, ids[4], "cf_role", "face_node_connectivity"));
    TRY(nc_put_att_int(file, ids[4], "start_index", NC_INT, 1, &one));
    int edge_dims[2] = {edge_dim, two_dim};
    snprintf(var, sizeof var, "%s_edge_nodes", name);
    TRY(nc_def_var(file, var, NC_INT, 2, edge_dims, &ids[5]));
    TRY(nc_put_att_int(file, ids[5], "start_index", NC_INT, 1, &one));
    snprintf(var, sizeof var, "%s_face_z", name);
    TRY(nc_def_var(file, var, NC_DOUBLE, 1, &face_dim, &ids[6]));
    TRY(text(file, ids[6], "location", "face"));
    TRY(text(file, ids[6], "mesh", name));
    TRY(text(file, ids[6], "units", "m"));
    snprintf(var, sizeof var, "%s_node_z", name);
    TRY(nc_def_var(file, var, NC_DOUBLE, 1, &node_dim, &ids[7]));
    TRY(text(file, ids[7], "location", "node"));
    TRY(text(file, ids[7], "mesh", name));
    int bnd_dims[2] = {boundary_dim, two_dim};
    snprintf(var, sizeof var, "%s_bnd_nodes", name);
    TRY(nc_def_var(file, var, NC_INT, 2, bnd_dims, &ids[8]));
    TRY(text(file, ids[8], "cf_role", "boundary_node_connectivity"));
    TRY(nc_put_att_int(file, ids[8], "start_index", NC_INT, 1, &one));
    snprintf(var, sizeof var, "%s_bnd_type", name);
    TRY(nc_def_var(file, var, NC_INT, 1, &boundary_dim, &ids[9]));
    int flags[2] = {1, 2};
    TRY(nc_put_att_int(file, ids[9], "flag_values", NC_INT, 2, flags));
    TRY(text(file, ids[9], "flag_meanings", "inflow outflow"));
    return NC_NOERR;
}

static int fill_mesh2d(int file, const int *ids) {
    double x[NET_NODES], y[NET_NODES], fx[NET_FACES], fy[NET_FACES], fz[NET_FACES], nz[NET_NODES];
    for (int n = 0; n < NET_NODES; ++n) x[n] = 10.0 * (n % 4), y[n] = 10.0 * (n / 4), nz[n] = 5.0 + n;
    int table[NET_FACES][4], edges[NET_EDGE_COUNT][2], bnd[NET_BOUNDARY_COUNT][2], tags[NET_BOUNDARY_COUNT];
    for (int f = 0; f < NET_FACES; ++f) {
        for (int k = 0; k < 4; ++k) table[f][k] = kNetFaces[f][k] < 0 ? -2147483647 : kNetFaces[f][k] + 1;
        fz[f] = 20.0 + f;
    }
    /* Circumcentres: the squares' centres, the right triangles' hypotenuses' midpoints. */
    const double centres[NET_FACES][2] = {{5, 5}, {5, 15}, {15, 5}, {15, 15}, {25, 5}, {25, 5}, {25, 15}, {25, 15}};
    for (int f = 0; f < NET_FACES; ++f) fx[f] = centres[f][0], fy[f] = centres[f][1];
    for (int e = 0; e < NET_EDGE_COUNT; ++e) edges[e][0] = kNetEdges[e][0] + 1, edges[e][1] = kNetEdges[e][1] + 1;
    for (int b = 0; b < NET_BOUNDARY_COUNT; ++b)
        bnd[b][0] = kNetBoundary[b][0] + 1, bnd[b][1] = kNetBoundary[b][1] + 1, tags[b] = kNetBoundary[b][2];
    TRY(nc_put_var_double(file, ids[0], x));
    TRY(nc_put_var_double(file, ids[1], y));
    TRY(nc_put_var_double(file, ids[2], fx));
    TRY(nc_put_var_double(file, ids[3], fy));
    TRY(nc_put_var_int(file, ids[4], &table[0][0]));
    TRY(nc_put_var_int(file, ids[5], &edges[0][0]));
    TRY(nc_put_var_double(file, ids[6], fz));
    TRY(nc_put_var_double(file, ids[7], nz));
    TRY(nc_put_var_int(file, ids[8], &bnd[0][0]));
    TRY(nc_put_var_int(file, ids[9], tags));
    return NC_NOERR;
}

int write_net_1d2d(const char *path, int second_2d) {
    int file;
    int status = nc_create(path, NC_CLOBBER, &file);
    if (status != NC_NOERR) return status;
    /* The 1D parts, as Delft3D FM writes them ahead of the 2D mesh. */
    int net_nodes, net_edges, two, network, mesh1d, nx, ny, net_edge_nodes, m1_nodes, branch, offset;
    TRY(nc_def_dim(file, "network1d_nNodes", 2, &net_nodes));
    TRY(nc_def_dim(file, "network1d_nEdges", 1, &net_edges));
    TRY(nc_def_dim(file, "Two", 2, &two));
    TRY(nc_def_dim(file, "mesh1d_nNodes", 3, &m1_nodes));
    TRY(nc_def_var(file, "mesh1d", NC_INT, 0, NULL, &mesh1d));
    TRY(text(file, mesh1d, "cf_role", "mesh_topology"));
    int one = 1;
    TRY(nc_put_att_int(file, mesh1d, "topology_dimension", NC_INT, 1, &one));
    TRY(text(file, mesh1d, "node_coordinates", "mesh1d_node_branch mesh1d_node_offset"));
    TRY(nc_def_var(file, "mesh1d_node_branch", NC_INT, 1, &m1_nodes, &branch));
    TRY(nc_def_var(file, "mesh1d_node_offset", NC_DOUBLE, 1, &m1_nodes, &offset));
    TRY(nc_def_var(file, "network1d", NC_INT, 0, NULL, &network));
    TRY(text(file, network, "cf_role", "mesh_topology"));
    TRY(nc_put_att_int(file, network, "topology_dimension", NC_INT, 1, &one));
    TRY(text(file, network, "node_coordinates", "network1d_node_x network1d_node_y"));
    TRY(text(file, network, "edge_node_connectivity", "network1d_edge_nodes"));
    TRY(nc_def_var(file, "network1d_node_x", NC_DOUBLE, 1, &net_nodes, &nx));
    TRY(nc_def_var(file, "network1d_node_y", NC_DOUBLE, 1, &net_nodes, &ny));
    int edge_dims[2] = {net_edges, two};
    TRY(nc_def_var(file, "network1d_edge_nodes", NC_INT, 2, edge_dims, &net_edge_nodes));
    int ids[10], more[10];
    TRY(define_mesh2d(file, "mesh2d", ids));
    if (second_2d) TRY(define_mesh2d(file, "mesh2d_refined", more));
    TRY(text(file, NC_GLOBAL, "Conventions", "CF-1.8 UGRID-1.0"));
    TRY(nc_enddef(file));
    const double net_x[2] = {-50, -10}, net_y[2] = {5, 5}, m1_offset[3] = {0, 20, 40};
    const int net_edge[2] = {1, 2}, m1_branch[3] = {1, 1, 1};
    TRY(nc_put_var_double(file, nx, net_x));
    TRY(nc_put_var_double(file, ny, net_y));
    TRY(nc_put_var_int(file, net_edge_nodes, net_edge));
    TRY(nc_put_var_int(file, branch, m1_branch));
    TRY(nc_put_var_double(file, offset, m1_offset));
    TRY(fill_mesh2d(file, ids));
    if (second_2d) TRY(fill_mesh2d(file, more));
    return nc_close(file);
}

int write_net_nodes_edges(const char *path) {
    int file, node_dim, edge_dim, two_dim, topology, x, y, z, edges;
    int status = nc_create(path, NC_CLOBBER | NC_NETCDF4, &file);
    if (status != NC_NOERR) return status;
    TRY(nc_def_dim(file, "mesh2d_nNodes", NET_EDGES_NODES, &node_dim));
    TRY(nc_def_dim(file, "mesh2d_nEdges", NET_EDGE_COUNT + 1, &edge_dim));
    TRY(nc_def_dim(file, "two", 2, &two_dim));
    TRY(nc_def_var(file, "mesh2d", NC_INT, 0, NULL, &topology));
    TRY(text(file, topology, "cf_role", "mesh_topology"));
    int two = 2;
    TRY(nc_put_att_int(file, topology, "topology_dimension", NC_INT, 1, &two));
    TRY(text(file, topology, "node_dimension", "mesh2d_nNodes"));
    TRY(text(file, topology, "edge_dimension", "mesh2d_nEdges"));
    TRY(text(file, topology, "edge_node_connectivity", "mesh2d_edge_nodes"));
    TRY(text(file, topology, "node_coordinates", "mesh2d_node_x mesh2d_node_y"));
    int dims[2] = {edge_dim, two_dim};
    TRY(nc_def_var(file, "mesh2d_edge_nodes", NC_INT64, 2, dims, &edges));
    long long fill = -1;
    TRY(nc_put_att_longlong(file, edges, "_FillValue", NC_INT64, 1, &fill));
    TRY(text(file, edges, "cf_role", "edge_node_connectivity"));
    int zero = 0;
    TRY(nc_put_att_int(file, edges, "start_index", NC_INT, 1, &zero));
    TRY(nc_def_var(file, "mesh2d_node_x", NC_DOUBLE, 1, &node_dim, &x));
    TRY(nc_def_var(file, "mesh2d_node_y", NC_DOUBLE, 1, &node_dim, &y));
    double nan_fill = NAN;
    TRY(nc_put_att_double(file, x, "_FillValue", NC_DOUBLE, 1, &nan_fill));
    TRY(nc_put_att_double(file, y, "_FillValue", NC_DOUBLE, 1, &nan_fill));
    TRY(text(file, x, "standard_name", "projection_x_coordinate"));
    TRY(text(file, y, "standard_name", "projection_y_coordinate"));
    TRY(nc_def_var(file, "mesh2d_node_z", NC_DOUBLE, 1, &node_dim, &z));
    TRY(text(file, z, "units", "m"));
    TRY(nc_enddef(file));
    double nx[NET_EDGES_NODES], ny[NET_EDGES_NODES], nz[NET_EDGES_NODES];
    for (int n = 0; n < NET_NODES; ++n) nx[n] = 10.0 * (n % 4), ny[n] = 10.0 * (n / 4), nz[n] = n;
    nx[12] = 40, ny[12] = 0, nz[12] = 12; /* the end of a dangling edge */
    long long table[NET_EDGE_COUNT + 1][2];
    for (int e = 0; e < NET_EDGE_COUNT; ++e) table[e][0] = kNetEdges[e][0], table[e][1] = kNetEdges[e][1];
    table[NET_EDGE_COUNT][0] = 3, table[NET_EDGE_COUNT][1] = 12;
    TRY(nc_put_var_double(file, x, nx));
    TRY(nc_put_var_double(file, y, ny));
    TRY(nc_put_var_double(file, z, nz));
    TRY(nc_put_var_longlong(file, edges, &table[0][0]));
    return nc_close(file);
}

/* Selafin: Fortran records, big-endian. */
static void put_word(FILE *f, uint32_t v) {
    const unsigned char b[4] = {(unsigned char)(v >> 24), (unsigned char)(v >> 16), (unsigned char)(v >> 8),
                                (unsigned char)v};
    fwrite(b, 1, 4, f);
}

static void put_real(FILE *f, double v, int double_precision) {
    if (double_precision) {
        uint64_t bits;
        memcpy(&bits, &v, 8);
        put_word(f, (uint32_t)(bits >> 32));
        put_word(f, (uint32_t)bits);
    } else {
        float single = (float)v;
        uint32_t bits;
        memcpy(&bits, &single, 4);
        put_word(f, bits);
    }
}

static void put_integers(FILE *f, const int32_t *v, int n) {
    put_word(f, (uint32_t)(4 * n));
    for (int k = 0; k < n; ++k) put_word(f, (uint32_t)v[k]);
    put_word(f, (uint32_t)(4 * n));
}

static void put_reals(FILE *f, const double *v, int n, int double_precision) {
    const uint32_t bytes = (uint32_t)(n * (double_precision ? 8 : 4));
    put_word(f, bytes);
    for (int k = 0; k < n; ++k) put_real(f, v[k], double_precision);
    put_word(f, bytes);
}

static void put_text(FILE *f, const char *text, int n) {
    put_word(f, (uint32_t)n);
    char padded[128];
    memset(padded, ' ', sizeof padded);
    memcpy(padded, text, strlen(text) < (size_t)n ? strlen(text) : (size_t)n);
    fwrite(padded, 1, (size_t)n, f);
    put_word(f, (uint32_t)n);
}

int write_selafin(const char *path, int double_precision) {
    FILE *f = fopen(path, "wb");
    if (!f) return 1;
    char title[81];
    snprintf(title, sizeof title, "%-72s%s", "DPSM TEST GEOMETRY", double_precision ? "SERAFIND" : "SERAFIN ");
    put_text(f, title, 80);
    const int32_t counts[2] = {2, 0};
    put_integers(f, counts, 2);
    put_text(f, "VELOCITY U      M/S             ", 32);
    put_text(f, "BOTTOM          M               ", 32);
    const int32_t iparam[10] = {1, 0, 1000, 2000, 0, 0, 1, 0, 0, 1};
    put_integers(f, iparam, 10);
    const int32_t date[6] = {2024, 6, 1, 0, 0, 0};
    put_integers(f, date, 6);
    const int32_t sizes[4] = {SELAFIN_TRIANGLES, SELAFIN_NODES, 3, 1};
    put_integers(f, sizes, 4);
    int32_t ikle[3 * SELAFIN_TRIANGLES], ipobo[SELAFIN_NODES];
    int t = 0;
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) {
            const int a = 1 + i + 4 * j, b = a + 1, c = b + 4, d = a + 4;
            ikle[3 * t] = a, ikle[3 * t + 1] = b, ikle[3 * t + 2] = c, ++t;
            ikle[3 * t] = a, ikle[3 * t + 1] = c, ikle[3 * t + 2] = d, ++t;
        }
    put_integers(f, ikle, 3 * SELAFIN_TRIANGLES);
    for (int n = 0; n < SELAFIN_NODES; ++n) ipobo[n] = 0;
    put_integers(f, ipobo, SELAFIN_NODES);
    double x[SELAFIN_NODES], y[SELAFIN_NODES], u[SELAFIN_NODES], bottom[SELAFIN_NODES];
    for (int n = 0; n < SELAFIN_NODES; ++n) x[n] = 10.0 * (n % 4), y[n] = 10.0 * (n / 4), u[n] = 0, bottom[n] = 2 + n;
    put_reals(f, x, SELAFIN_NODES, double_precision);
    put_reals(f, y, SELAFIN_NODES, double_precision);
    const double time = 0;
    put_reals(f, &time, 1, double_precision);
    put_reals(f, u, SELAFIN_NODES, double_precision);
    put_reals(f, bottom, SELAFIN_NODES, double_precision);
    return fclose(f) != 0;
}

int write_gmsh(const char *path, int version) {
    FILE *f = fopen(path, "w");
    if (!f) return 1;
    /* Triangles (a, b, c), (a, c, d) of each lattice square; a = 1 + i + 3 j. */
    int tris[GMSH_TRIANGLES][3], t = 0;
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
            const int a = 1 + i + 3 * j, b = a + 1, c = b + 3, d = a + 3;
            tris[t][0] = a, tris[t][1] = b, tris[t][2] = c, ++t;
            tris[t][0] = a, tris[t][1] = c, tris[t][2] = d, ++t;
        }
    /* The boundary curves: bottom, right, top, left, each two lines. */
    const int lines[4][2][2] = {{{1, 2}, {2, 3}}, {{3, 6}, {6, 9}}, {{9, 8}, {8, 7}}, {{7, 4}, {4, 1}}};
    fprintf(f, "$MeshFormat\n%s 0 8\n$EndMeshFormat\n", version == 4 ? "4.1" : "2.2");
    fprintf(f, "$PhysicalNames\n3\n1 1 \"inflow\"\n1 3 \"outflow\"\n2 10 \"domain\"\n$EndPhysicalNames\n");
    if (version == 4) {
        fprintf(f, "$Entities\n4 4 1 0\n");
        const double corner[4][2] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}};
        for (int p = 0; p < 4; ++p) fprintf(f, "%d %g %g 0 0\n", p + 1, corner[p][0], corner[p][1]);
        for (int c = 0; c < 4; ++c)
            fprintf(f, "%d 0 0 0 2 2 0 1 %d 2 %d -%d\n", c + 1, c + 1, c + 1, (c + 1) % 4 + 1);
        fprintf(f, "1 0 0 0 2 2 0 1 10 4 1 2 3 4\n$EndEntities\n");
        /* One block of nodes, their tags not in order. */
        const int order[GMSH_NODES] = {5, 1, 2, 3, 4, 6, 7, 8, 9};
        fprintf(f, "$Nodes\n1 9 1 9\n2 1 0 9\n");
        for (int k = 0; k < GMSH_NODES; ++k) fprintf(f, "%d\n", order[k]);
        for (int k = 0; k < GMSH_NODES; ++k) fprintf(f, "%d %d 0\n", (order[k] - 1) % 3, (order[k] - 1) / 3);
        fprintf(f, "$EndNodes\n$Elements\n5 16 1 16\n");
        int tag = 1;
        for (int c = 0; c < 4; ++c) {
            fprintf(f, "1 %d 1 2\n", c + 1);
            for (int l = 0; l < 2; ++l, ++tag) fprintf(f, "%d %d %d\n", tag, lines[c][l][0], lines[c][l][1]);
        }
        fprintf(f, "2 1 2 %d\n", GMSH_TRIANGLES);
        for (int k = 0; k < GMSH_TRIANGLES; ++k, ++tag) fprintf(f, "%d %d %d %d\n", tag, tris[k][0], tris[k][1], tris[k][2]);
        fprintf(f, "$EndElements\n");
    } else {
        fprintf(f, "$Nodes\n9\n");
        for (int n = 1; n <= GMSH_NODES; ++n) fprintf(f, "%d %d %d 0\n", n, (n - 1) % 3, (n - 1) / 3);
        fprintf(f, "$EndNodes\n$Elements\n16\n");
        int tag = 1;
        for (int c = 0; c < 4; ++c)
            for (int l = 0; l < 2; ++l, ++tag)
                fprintf(f, "%d 1 2 %d %d %d %d\n", tag, c + 1, c + 1, lines[c][l][0], lines[c][l][1]);
        for (int k = 0; k < GMSH_TRIANGLES; ++k, ++tag)
            fprintf(f, "%d 2 2 10 1 %d %d %d\n", tag, tris[k][0], tris[k][1], tris[k][2]);
        fprintf(f, "$EndElements\n");
    }
    return fclose(f) != 0;
}

int write_lonlat(const char *path, int attributes) {
    int file, node_dim, face_dim, three_dim, topology, x, y, faces, bed, depth = -1;
    int status = nc_create(path, NC_CLOBBER, &file);
    if (status != NC_NOERR) return status;
    TRY(nc_def_dim(file, "nMesh2_node", LONLAT_NODES, &node_dim));
    TRY(nc_def_dim(file, "nMesh2_face", LONLAT_TRIANGLES, &face_dim));
    TRY(nc_def_dim(file, "Three", 3, &three_dim));
    TRY(nc_def_var(file, "adcirc_mesh", NC_INT, 0, NULL, &topology));
    TRY(text(file, topology, "cf_role", "mesh_topology"));
    int two = 2, zero = 0;
    TRY(nc_put_att_int(file, topology, "topology_dimension", NC_INT, 1, &two));
    TRY(text(file, topology, "node_coordinates", "lon lat"));
    TRY(text(file, topology, "face_node_connectivity", "element"));
    TRY(nc_def_var(file, "lon", NC_DOUBLE, 1, &node_dim, &x));
    TRY(nc_def_var(file, "lat", NC_DOUBLE, 1, &node_dim, &y));
    if (attributes) {
        TRY(text(file, x, "standard_name", "longitude"));
        TRY(text(file, x, "units", "degrees_east"));
        TRY(text(file, y, "standard_name", "latitude"));
        TRY(text(file, y, "units", "degrees_north"));
    }
    int dims[2] = {face_dim, three_dim};
    TRY(nc_def_var(file, "element", NC_INT, 2, dims, &faces));
    TRY(nc_put_att_int(file, faces, "start_index", NC_INT, 1, &zero));
    TRY(nc_def_var(file, "depth_bed", NC_DOUBLE, 1, &node_dim, &bed));
    TRY(text(file, bed, "location", "node"));
    TRY(text(file, bed, "units", "m"));
    if (attributes) {
        TRY(nc_def_var(file, "depth", NC_DOUBLE, 1, &node_dim, &depth));
        TRY(text(file, depth, "location", "node"));
        TRY(text(file, depth, "standard_name", "depth_below_geoid"));
        TRY(text(file, depth, "units", "m"));
    }
    TRY(nc_enddef(file));
    double lon[LONLAT_NODES], lat[LONLAT_NODES], z[LONLAT_NODES];
    for (int n = 0; n < LONLAT_NODES; ++n) lon[n] = -80.0 + 0.01 * (n % 5), lat[n] = 30.0 + 0.01 * (n / 5), z[n] = -10.0 - n;
    int table[LONLAT_TRIANGLES][3], t = 0;
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) {
            const int a = i + 5 * j, b = a + 1, c = b + 5, d = a + 5;
            table[t][0] = a, table[t][1] = b, table[t][2] = c, ++t;
            table[t][0] = a, table[t][1] = c, table[t][2] = d, ++t;
        }
    TRY(nc_put_var_double(file, x, lon));
    TRY(nc_put_var_double(file, y, lat));
    TRY(nc_put_var_int(file, faces, &table[0][0]));
    TRY(nc_put_var_double(file, bed, z));
    for (int n = 0; n < LONLAT_NODES; ++n) z[n] = -z[n];
    if (attributes) TRY(nc_put_var_double(file, depth, z));
    return nc_close(file);
}
