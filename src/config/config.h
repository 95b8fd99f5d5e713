/* The run configuration shared by the C BMI component and `dpsm run`: one
 * YAML file (docs/guide_bmi.md lists its keys) read into a plain struct,
 * then built into a dpsm grid with its initial heights, source and sides.
 *
 * Nothing here is public: libdpsm_bmi and the dpsm program link it, and
 * neither exports these names. Every function returns 0 on success and
 * otherwise writes a message for the person who wrote the file into
 * `message` ("dpsm.yaml:4: grid.nx: expected a positive integer, got
 * \"sixty\""), leaving its outputs empty. */
#ifndef DPSM_CONFIG_CONFIG_H
#define DPSM_CONFIG_CONFIG_H

#include <stddef.h>
#include <stdint.h>

#include <dpsm/dpsm.h>

#ifdef __cplusplus
extern "C" {
#endif

#define CONFIG_PATH_MAX 4096
#define CONFIG_NAME_MAX 256
#define CONFIG_MESSAGE_MAX 1024

/* CONFIG_GRID_MESH: the file's faces are the cells; CONFIG_GRID_DUAL_MESH:
 * the median dual of the file's triangles, one cell per node. */
enum config_grid_kind { CONFIG_GRID_1D, CONFIG_GRID_2D, CONFIG_GRID_AXISYMMETRIC, CONFIG_GRID_MESH,
                        CONFIG_GRID_DUAL_MESH };
/* grid.coordinates: left to the file (its attributes), or said. */
enum config_coordinates { CONFIG_COORDINATES_FROM_FILE, CONFIG_COORDINATES_PROJECTED, CONFIG_COORDINATES_GEOGRAPHIC };
/* boundaries.level on a mesh: not given, a number (0 included), each edge
 * face its cell's level (set before every step), or a field of a file. */
enum config_level_kind { CONFIG_LEVEL_NONE, CONFIG_LEVEL_NUMBER, CONFIG_LEVEL_CELL, CONFIG_LEVEL_FILE };
enum config_field_kind { CONFIG_FIELD_NONE, CONFIG_FIELD_CONSTANT, CONFIG_FIELD_COLUMN, CONFIG_FIELD_CONE,
                         CONFIG_FIELD_FILE };

/* The sides a configuration may name, in the order of DPSM_XMIN ..
 * DPSM_MESH_EDGE; a side left out keeps the library's default. */
#define CONFIG_SIDES 5
#define CONFIG_SIDE_DEFAULT (-1)
/* The boundary groups a configuration may name in boundaries.open or .wall. */
#define CONFIG_GROUPS_MAX 64

/* A field over the cells: a constant, a built-in scene or a netCDF variable. */
struct config_field {
    enum config_field_kind kind;
    double value;  /* CONFIG_FIELD_CONSTANT */
    double radius; /* CONFIG_FIELD_COLUMN, CONFIG_FIELD_CONE */
    double height;
    int has_centre; /* initial.centre given; else the centre of the domain */
    double centre[2];
    unsigned long line; /* where the field is, for refusals found later */
    char file[CONFIG_PATH_MAX]; /* CONFIG_FIELD_FILE: resolved against the configuration's folder */
    char variable[CONFIG_NAME_MAX];
    int positive; /* the file's `positive:` key: 1 up (an elevation), -1 down (a depth: negated), 0 not given */
};

struct config {
    char path[CONFIG_PATH_MAX]; /* the configuration file, as given */
    enum config_grid_kind grid_kind;
    int64_t nx, ny; /* ny == 1 on 1d and axisymmetric grids; nr is nx */
    double dx, dy;  /* dy == dx on 1d and axisymmetric grids */
    char mesh_file[CONFIG_PATH_MAX];
    char topology[CONFIG_NAME_MAX]; /* grid.topology, "" when not given */
    enum config_coordinates coordinates;
    unsigned long grid_line;
    int has_repose_angle;
    double repose_angle_degrees;
    int has_mobility;
    double mobility;
    int boundary[CONFIG_SIDES]; /* DPSM_OPEN, DPSM_WALL or CONFIG_SIDE_DEFAULT */
    unsigned long boundaries_line;
    /* A mesh's edge: boundaries.level, and the groups of edges that
     * boundaries.open (on a wall edge) or .wall (on an open one) names, by
     * name or by number, each with its line. */
    enum config_level_kind level_kind;
    double level;
    char level_file[CONFIG_PATH_MAX], level_variable[CONFIG_NAME_MAX];
    int level_positive; /* as config_field.positive */
    unsigned long level_line;
    int group_count, groups_open;
    char groups[CONFIG_GROUPS_MAX][CONFIG_NAME_MAX];
    unsigned long group_lines[CONFIG_GROUPS_MAX];
    struct config_field initial;
    struct config_field source; /* CONFIG_FIELD_NONE when the file has no source */
    double time_step, time_end;
    int has_output;
    char output_file[CONFIG_PATH_MAX];
    double output_every;
};

/* Reads and checks the YAML file at `path` (relative file names in it are
 * taken from the file's folder). */
int config_read(const char *path, struct config *config, char *message, size_t message_size);

/* Where the values of a file's variable lie. */
enum config_location { CONFIG_AT_NODES, CONFIG_AT_FACES, CONFIG_AT_EDGES };

/* A group of edges a mesh file names: a gmsh physical curve, a UGRID
 * boundary tag. `name` is "" when the file gives only the number. */
struct config_mesh_group {
    char name[CONFIG_NAME_MAX];
    long number;
    int64_t edge_count;
    int64_t *edge_nodes; /* 2 per edge, nodes from 0 */
};

/* An unstructured mesh as a file holds it (UGRID netCDF, gmsh, Selafin),
 * node indices from 0: what the BMI grid functions answer with. Edges are
 * the library's faces in its order (dpsm_get_mesh_faces()) on a mesh; on a
 * dual mesh the triangles' edges, by node pair, which are the first of the
 * library's faces; `face_*` are the file's faces (the cells of a mesh, the
 * triangles of a dual mesh). */
struct config_mesh {
    int64_t node_count, face_count, edge_count;
    double *node_x, *node_y;
    int64_t *face_node_start; /* face_count + 1 offsets into face_nodes */
    int64_t *face_nodes;
    int64_t *face_edges; /* as face_nodes: edge k of a face joins its nodes k and k+1 */
    int64_t *edge_nodes; /* 2 per edge */

    /* What the file says (mesh_file.c). */
    char format[16];                  /* "UGRID", "gmsh" or "Selafin" */
    char topology[CONFIG_NAME_MAX];   /* UGRID: the mesh_topology read */
    int faces_from_edges;             /* UGRID: its faces were built from its nodes and edges */
    enum config_coordinates coordinates; /* what the file's attributes say (FROM_FILE: nothing) */
    char coordinates_said[256];       /* which attribute said it, for messages */
    int group_count;
    struct config_mesh_group *groups;
    /* UGRID: the dimensions of its nodes, faces and edges (by which a
     * variable of the file is placed), and its edges as the file lists them. */
    char node_dimension[CONFIG_NAME_MAX], face_dimension[CONFIG_NAME_MAX], edge_dimension[CONFIG_NAME_MAX];
    int64_t file_edge_count;
    int64_t *file_edge_nodes;
};

/* Reads a mesh file, chosen by its content (netCDF's signature, gmsh's
 * $MeshFormat, Selafin's records): a UGRID 1.0 topology of dimension 2 (the
 * one named `topology`, or the only 2D one), its faces from
 * face_node_connectivity or built from edge_node_connectivity; a gmsh 2.2 or
 * 4.1 ASCII mesh with its physical curves; a 2D Selafin geometry. */
int config_read_mesh(const char *path, const char *topology, struct config_mesh *mesh, char *message,
                     size_t message_size);
void config_mesh_free(struct config_mesh *mesh);

/* The values of `variable` in the file at `path` (the mesh's own file or
 * another: netCDF or Selafin), and where they lie on `mesh`: a UGRID
 * variable by its dimension or `location` attribute, a Selafin variable
 * (its first time frame) at the nodes, a variable of a plain netCDF file
 * with one dimension of `cells` values on the cells (`cells_at` says
 * where). Missing and non-finite values are refused. *values is malloc'ed. */
int config_read_mesh_variable(const struct config_mesh *mesh, const char *path, const char *variable,
                              enum config_location cells_at, double **values, int64_t *count,
                              enum config_location *where, char *message, size_t message_size);
/* The configured scene: the grid with everything the file sets, the mesh
 * when there is one, and the source it was given (NULL when none). */
struct config_scene {
    dpsm_grid *grid;
    int64_t cell_count;
    int has_mesh;
    int cells_at_nodes; /* a dual mesh: the cells are the mesh's nodes */
    int geographic;     /* a mesh in degrees: cell centres are longitude and latitude */
    struct config_mesh mesh;
    double *source;
    /* boundaries.level: cell. The levels beyond the edge follow the edge
     * faces' cells: config_scene_before_step sets them. */
    int levels_follow_cells;
    int64_t face_count;
    int64_t *face_cells; /* 2 per face (dpsm_get_mesh_faces) */
    double *levels;
};

int config_build(const struct config *config, struct config_scene *scene, char *message, size_t message_size);
/* What the scene needs before each dpsm_step (boundaries.level: cell sets
 * each open edge face's level to its cell's height); 0 or a message. */
int config_scene_before_step(struct config_scene *scene, char *message, size_t message_size);
void config_scene_free(struct config_scene *scene);

#ifdef __cplusplus
}
#endif

#endif
