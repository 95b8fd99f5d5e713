/* The readers of mesh files behind config_read_mesh() (mesh_file.c): one file
 * per format, and what they share. Each fills a struct config_mesh whose
 * arrays it allocates, or writes "<path>: <problem>" into `message` and
 * returns 1 (the caller frees what was filled). */
#ifndef DPSM_CONFIG_MESH_READERS_H
#define DPSM_CONFIG_MESH_READERS_H

#include "config/config.h"

/* netcdf_input.c: UGRID 1.0. */
int ugrid_read_mesh(const char *path, const char *topology, struct config_mesh *mesh, char *message, size_t size);
/* A netCDF variable of one dimension; where it lies on `mesh` (by its
 * dimension's name, its `location` attribute, or its length). */
int ugrid_read_variable(const struct config_mesh *mesh, const char *path, const char *variable,
                        enum config_location cells_at, int64_t cells, double **values, int64_t *count,
                        enum config_location *where, char *message, size_t size);

/* gmsh_reader.c: gmsh 2.2 and 4.1 ASCII. */
int gmsh_read_mesh(const char *path, struct config_mesh *mesh, char *message, size_t size);

/* selafin_reader.c: TELEMAC's Selafin (2D; single or double precision). */
int selafin_read_mesh(const char *path, struct config_mesh *mesh, char *message, size_t size);
int selafin_read_variable(const char *path, const char *variable, double **values, int64_t *count, char *message,
                          size_t size);

/* mesh_faces.c: the faces of a planar mesh given by its nodes and edges,
 * as D-Flow FM builds them from a net file without faces: every cycle of
 * 3 to 6 edges that bounds a region holding no other edge, counter-
 * clockwise, in the order their first edge appears in the file. Dangling
 * edges are left out. */
int mesh_faces_from_edges(const char *path, const double *x, const double *y, int64_t node_count,
                          const int64_t *edge_nodes, int64_t edge_count, int64_t **face_start, int64_t **face_nodes,
                          int64_t *face_count, char *message, size_t size);

/* Adds a group of `count` edges (2 nodes each, from 0) to the mesh. */
int mesh_add_group(struct config_mesh *mesh, const char *name, long number, const int64_t *edge_nodes, int64_t count,
                   const char *path, char *message, size_t size);

#endif
