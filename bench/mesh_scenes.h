/* Meshes of a square for the mesh validation, the tests and the examples:
 * quadrilaterals, jittered triangles (Delaunay-like: each jittered square is
 * split along its shorter diagonal), hexagons (the Voronoi mesh of a
 * triangular lattice) and the median dual of the jittered triangles; and the
 * share of a cell inside a disk, to pour a column by cell averages. */
#ifndef DPSM_MESH_SCENES_H
#define DPSM_MESH_SCENES_H

#include <stdint.h>

#include <dpsm/dpsm.h>

typedef enum { SCENE_QUADS, SCENE_TRIANGLES, SCENE_HEXAGONS, SCENE_DUAL, SCENE_GMSH_DISK } scene_kind;

typedef struct {
    scene_kind kind;
    int64_t nnodes;
    double *node_xy;     /* 2 * nnodes */
    int64_t npolygons;   /* polygons (or triangles of the dual) */
    int64_t *cell_start; /* npolygons + 1 */
    int64_t *cell_nodes;
    /* The cells dpsm makes of it (the dual: one per node), with their
     * centres (the dual: the node) and areas. */
    int64_t cells;
    double *cx, *cy, *area;
} mesh_scene;

/* n cells (the dual: n triangles' nodes) along each side of [-half, half]^2;
 * SCENE_GMSH_DISK: the disk of radius 2.5 of bench/data/disk.geo meshed by
 * gmsh with triangles of size 7 / n (gmsh must be on the PATH and
 * DPSM_DISK_GEO name the .geo file; an empty scene, cells == 0, otherwise). */
mesh_scene scene_make(scene_kind kind, int n, double half, unsigned seed);
/* The same with the lattice's inner nodes of the triangles and the dual
 * jittered by up to `jitter` of the spacing (scene_make: 0.3). */
mesh_scene scene_make_jittered(scene_kind kind, int n, double half, double jitter, unsigned seed);
/* Reads the triangles of a gmsh file in the MSH 2.2 ASCII format. */
mesh_scene scene_read_msh(const char *path);
/* Creates the dpsm mesh of the scene (dpsm_create_mesh or dpsm_create_dual_mesh). */
int scene_create(const mesh_scene *s, dpsm_grid **out);
/* The column collapse's exact deposit (a column of radius 1 and height 0.5
 * slid to rest at slope alpha): the foot of the truncated cone that keeps
 * the column's volume. */
double scene_column_foot(double alpha);
/* That deposit's height at radius r. */
double scene_column_height(double alpha, double r);
/* The column poured on the scene's cells as cell averages, into h. */
void scene_pour_column(const mesh_scene *s, double *h);
/* The L1 difference of h on the scene's cells from the exact deposit, over the column's volume. */
double scene_column_l1(const mesh_scene *s, const double *h, double alpha);
/* The share of every cell inside the disk of radius r about the origin. */
void scene_disk_fractions(const mesh_scene *s, double r, double *share);
/* Turns the scene by `angle` radians about the origin: its nodes and its
 * cells' centres (the same cells, in the same order). */
void scene_rotate(mesh_scene *s, double angle);
/* The mean cell size: the square root of the mean area. */
double scene_mean_size(const mesh_scene *s);
const char *scene_name(scene_kind kind);
void scene_free(mesh_scene *s);

#endif
