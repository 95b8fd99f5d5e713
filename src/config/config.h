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

enum config_grid_kind { CONFIG_GRID_1D, CONFIG_GRID_2D, CONFIG_GRID_AXISYMMETRIC, CONFIG_GRID_MESH };
enum config_field_kind { CONFIG_FIELD_NONE, CONFIG_FIELD_CONSTANT, CONFIG_FIELD_COLUMN, CONFIG_FIELD_CONE,
                         CONFIG_FIELD_FILE };

/* The sides a configuration may name, in the order of DPSM_XMIN ..
 * DPSM_MESH_EDGE; a side left out keeps the library's default. */
#define CONFIG_SIDES 5
#define CONFIG_SIDE_DEFAULT (-1)

/* A field over the cells: a constant, a built-in scene or a netCDF variable. */
struct config_field {
    enum config_field_kind kind;
    double value;  /* CONFIG_FIELD_CONSTANT */
    double radius; /* CONFIG_FIELD_COLUMN, CONFIG_FIELD_CONE */
    double height;
    char file[CONFIG_PATH_MAX]; /* CONFIG_FIELD_FILE: resolved against the configuration's folder */
    char variable[CONFIG_NAME_MAX];
};

struct config {
    char path[CONFIG_PATH_MAX]; /* the configuration file, as given */
    enum config_grid_kind grid_kind;
    int64_t nx, ny; /* ny == 1 on 1d and axisymmetric grids; nr is nx */
    double dx, dy;  /* dy == dx on 1d and axisymmetric grids */
    char mesh_file[CONFIG_PATH_MAX];
    int has_repose_angle;
    double repose_angle_degrees;
    int has_mobility;
    double mobility;
    int boundary[CONFIG_SIDES]; /* DPSM_OPEN, DPSM_WALL or CONFIG_SIDE_DEFAULT */
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

/* An unstructured mesh as UGRID holds it, with node indices from 0: what
 * the BMI grid functions answer with. Edges are the library's faces in its
 * order (dpsm_get_mesh_faces()); `face_*` are the cells. */
struct config_mesh {
    int64_t node_count, face_count, edge_count;
    double *node_x, *node_y;
    int64_t *face_node_start; /* face_count + 1 offsets into face_nodes */
    int64_t *face_nodes;
    int64_t *face_edges; /* as face_nodes: edge k of a face joins its nodes k and k+1 */
    int64_t *edge_nodes; /* 2 per edge */
};

/* Reads a UGRID 1.0 mesh (a mesh_topology variable of topology_dimension 2,
 * node_coordinates, face_node_connectivity with start_index and _FillValue). */
int config_read_mesh(const char *path, struct config_mesh *mesh, char *message, size_t message_size);
void config_mesh_free(struct config_mesh *mesh);

/* The configured scene: the grid with everything the file sets, the mesh
 * when there is one, and the source it was given (NULL when none). */
struct config_scene {
    dpsm_grid *grid;
    int64_t cell_count;
    int has_mesh;
    struct config_mesh mesh;
    double *source;
};

int config_build(const struct config *config, struct config_scene *scene, char *message, size_t message_size);
void config_scene_free(struct config_scene *scene);

#ifdef __cplusplus
}
#endif

#endif
