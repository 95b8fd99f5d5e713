/* Small mesh files in the formats production codes write, for the tests of
 * the readers (issue 36): each writer makes a file as the code's own tools
 * lay it out, with a handful of cells whose numbers the tests know. */
#ifndef DPSM_TESTS_MESH_FILES_H
#define DPSM_TESTS_MESH_FILES_H

/* Delft3D FM's 1D2D net file: topologies network1d and mesh1d (1D) and
 * mesh2d (2D), with `second_2d` another 2D topology "mesh2d_refined" too.
 * mesh2d: 12 nodes (i*10, j*10), i < 4, j < 3 (units m); 8 faces from 1,
 * fill -2147483647: 4 squares (columns 0 and 1), then the 2 squares of column
 * 2 split into 4 right triangles; mesh2d_face_x/y circumcentres;
 * mesh2d_face_z (location face) = 20 + face, mesh2d_node_z (location node)
 * = 5 + node, mesh2d_edge_nodes; boundary_node_connectivity over the 8
 * boundary edges with mesh2d_bnd_type (flag_values 1 2, flag_meanings
 * "inflow outflow"): inflow the 2 edges on x = 0, outflow the 2 on x = 30. */
#define NET_NODES 12
#define NET_FACES 8
int write_net_1d2d(const char *path, int second_2d);

/* A net file with nodes and edges only (int64 edges from 0, fill -1, as
 * D-Flow FM's own test data): the 12 nodes above, the lattice's 17 edges,
 * the diagonals of the column-2 squares, and a dangling edge to a 13th
 * node; mesh2d_node_z (location node) = node. Faces: 4 squares and 4
 * triangles. */
#define NET_EDGES_NODES 13
int write_net_nodes_edges(const char *path);

/* TELEMAC Selafin: 16 nodes on a 4 x 4 lattice of 10 m (IPARAM origin 1000,
 * 2000), 18 triangles (IKLE from 1), a date record, variables VELOCITY U
 * (0) and BOTTOM (2 + node), single or double precision, big-endian. */
#define SELAFIN_NODES 16
#define SELAFIN_TRIANGLES 18
int write_selafin(const char *path, int double_precision);

/* gmsh: 9 nodes on a 3 x 3 lattice of 1 (tags from 1, given unsorted in
 * 4.1), 8 triangles, boundary curves as physical groups: 1 "inflow" (y = 0),
 * 2 (x = 2, no name), 3 "outflow" (y = 2), 4 (x = 0); 4.1 or 2.2. */
#define GMSH_NODES 9
#define GMSH_TRIANGLES 8
int write_gmsh(const char *path, int version);

/* An ADCIRC-like mesh in longitude and latitude: 25 nodes on a 5 x 5
 * lattice of 0.01 degrees from (-80, 30), 32 triangles, node variable
 * depth_bed = -10 - node (location node). With `attributes`,
 * standard_name longitude/latitude and units degrees_east/north, and
 * ADCIRC's depth = 10 + node (standard_name depth_below_geoid: positive
 * down); without, none of these. */
#define LONLAT_NODES 25
#define LONLAT_TRIANGLES 32
int write_lonlat(const char *path, int attributes);

#endif
