/* What config_build (scene.c) builds in parts: the mesh of a mesh file
 * (mesh_scene.c) and its edge's kinds and levels (mesh_edges.c). Each
 * returns 0 or writes a message for the person who wrote the configuration
 * ("dpsm.yaml:4: boundaries.open[1]: ...") and returns 1. */
#ifndef DPSM_CONFIG_SCENE_PARTS_H
#define DPSM_CONFIG_SCENE_PARTS_H

#include "config/config.h"

/* "<config>:<line>: <key>: " then the formatted rest; returns 1. */
#if defined(__GNUC__)
__attribute__((format(printf, 6, 7)))
#endif
int scene_refuse(const struct config *c, unsigned long line, const char *key, char *message, size_t size,
                 const char *format, ...);

/* Reads grid.file and makes the mesh (grid.kind: mesh) or the median dual
 * of its triangles (dual_mesh), in degrees or metres as grid.coordinates or
 * the file says; fills s->mesh with the BMI's edges and s->grid. */
int scene_create_mesh(const struct config *c, struct config_scene *s, char *message, size_t size);

/* Reads `variable` of `file` on the scene's mesh, at the nodes of a dual
 * mesh's cells or the faces of a mesh's; a failure is refused for `key` at
 * `line`. The caller frees *values and checks *where against its need. */
int scene_read_mesh_values(const struct config *c, const struct config_scene *s, const char *file,
                           const char *variable, unsigned long line, const char *key, double **values,
                           int64_t *count, enum config_location *where, char *message, size_t size);

/* The great-circle distance in metres between two points in degrees. */
double scene_sphere_distance(double lon0, double lat0, double lon1, double lat1);

/* Heights read from `file` for `key` (initial, boundaries.level): refuses
 * a variable whose attributes say it is a depth unless `<key>.positive:
 * down` says so too (and then negates the values), and a `positive` the
 * attributes contradict. */
int scene_heights_sign(const struct config *c, const char *file, const char *variable, int positive,
                       unsigned long line, const char *key, double *values, int64_t count, char *message, size_t size);

/* The mesh's edge after the heights are set: kinds (boundaries.edge, .open,
 * .wall) and levels (boundaries.level). */
int scene_set_edges(const struct config *c, struct config_scene *s, char *message, size_t size);

#endif
