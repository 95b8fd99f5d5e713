/* The grid functions of the dpsm BMI component. On a grid: grid 0 holds the
 * cells (uniform_rectilinear, its nodes at the cell centres), grids 1 and 2
 * the x and y faces, the last grid the scalars. On a mesh: grids 0 and 1
 * are the mesh (unstructured; cells on its faces, fluxes on its edges) and
 * grid 2 the scalars. */
#include "bmi/component.h"

#include <stdio.h>
#include <string.h>

/* The component and the place of `grid` for a function that writes to `out`. */
static struct component *grid_lookup(Bmi *self, int grid, const void *out, const char *function, int *place) {
    struct component *c = component_of(self, function);
    if (!c) return NULL;
    if ((*place = component_place_of_grid(c, grid)) < 0) {
        component_fail(function, "no grid %d (the variables' grids are 0 to %d)", grid,
                       component_grid_of(c, PLACE_SCALAR));
        return NULL;
    }
    if (!out) {
        component_fail(function, "the output pointer for grid %d is NULL", grid);
        return NULL;
    }
    return c;
}

static int unstructured(const struct component *c, int place) {
    return c->scene.has_mesh && (place == PLACE_CELLS || place == PLACE_EDGES);
}

/* A rectilinear grid's shape [ny, nx] (rank 2) or [nx] (rank 1), spacing and
 * origin, slowest dimension first. The nodes of the cell grid are the cell
 * centres; the face grids put theirs on the faces. */
struct rectilinear {
    int rank;
    int64_t shape[2];
    double spacing[2], origin[2];
};

static struct rectilinear rectilinear_of(const struct component *c, int place) {
    struct rectilinear r;
    double dx = c->config.dx, dy = c->config.dy;
    int two_d = c->config.grid_kind == CONFIG_GRID_2D;
    int64_t nx = c->nx + (place == PLACE_FLUX_X), ny = c->ny + (place == PLACE_FLUX_Y);
    double x0 = place == PLACE_FLUX_X ? 0 : dx / 2, y0 = place == PLACE_FLUX_Y ? 0 : dy / 2;
    if (two_d) {
        r = (struct rectilinear){2, {ny, nx}, {dy, dx}, {y0, x0}};
    } else {
        r = (struct rectilinear){1, {nx, 0}, {dx, 0}, {x0, 0}};
    }
    return r;
}

static int get_grid_rank(Bmi *self, int grid, int *rank) {
    int place;
    struct component *c = grid_lookup(self, grid, rank, "get_grid_rank", &place);
    if (!c) return BMI_FAILURE;
    if (place == PLACE_SCALAR) *rank = 0;
    else if (unstructured(c, place)) *rank = 2;
    else *rank = rectilinear_of(c, place).rank;
    return BMI_SUCCESS;
}

static int64_t node_count(const struct component *c, int place) {
    if (place == PLACE_SCALAR) return 1;
    if (unstructured(c, place)) return c->scene.mesh.node_count;
    struct rectilinear r = rectilinear_of(c, place);
    return r.rank == 2 ? r.shape[0] * r.shape[1] : r.shape[0];
}

static int get_grid_size(Bmi *self, int grid, int *size) {
    int place;
    struct component *c = grid_lookup(self, grid, size, "get_grid_size", &place);
    if (!c) return BMI_FAILURE;
    *size = (int)node_count(c, place);
    return BMI_SUCCESS;
}

static int get_grid_node_count(Bmi *self, int grid, int *count) {
    int place;
    struct component *c = grid_lookup(self, grid, count, "get_grid_node_count", &place);
    if (!c) return BMI_FAILURE;
    *count = (int)node_count(c, place);
    return BMI_SUCCESS;
}

static int get_grid_type(Bmi *self, int grid, char *type) {
    int place;
    struct component *c = grid_lookup(self, grid, type, "get_grid_type", &place);
    if (!c) return BMI_FAILURE;
    const char *name = place == PLACE_SCALAR ? "scalar" : unstructured(c, place) ? "unstructured" : "uniform_rectilinear";
    snprintf(type, BMI_MAX_TYPE_NAME, "%s", name);
    return BMI_SUCCESS;
}

/* The uniform rectilinear functions: shape, spacing, origin. */
static int rectilinear_property(Bmi *self, int grid, void *out, int what, const char *function) {
    int place;
    struct component *c = grid_lookup(self, grid, out, function, &place);
    if (!c) return BMI_FAILURE;
    if (place == PLACE_SCALAR) return BMI_SUCCESS; /* rank 0: nothing to write */
    if (unstructured(c, place))
        return component_fail(function, "grid %d is unstructured: it has nodes, edges and faces, no %s", grid,
                              what == 0 ? "shape" : what == 1 ? "spacing" : "origin");
    struct rectilinear r = rectilinear_of(c, place);
    for (int d = 0; d < r.rank; ++d) {
        if (what == 0) ((int *)out)[d] = (int)r.shape[d];
        else ((double *)out)[d] = what == 1 ? r.spacing[d] : r.origin[d];
    }
    return BMI_SUCCESS;
}

static int get_grid_shape(Bmi *self, int grid, int *shape) {
    return rectilinear_property(self, grid, shape, 0, "get_grid_shape");
}
static int get_grid_spacing(Bmi *self, int grid, double *spacing) {
    return rectilinear_property(self, grid, spacing, 1, "get_grid_spacing");
}
static int get_grid_origin(Bmi *self, int grid, double *origin) {
    return rectilinear_property(self, grid, origin, 2, "get_grid_origin");
}

/* Node coordinates: along each axis of a rectilinear grid (x the last
 * dimension, y the first), of every node of a mesh. */
static int coordinates(Bmi *self, int grid, double *out, int axis, const char *function) {
    int place;
    struct component *c = grid_lookup(self, grid, out, function, &place);
    if (!c) return BMI_FAILURE;
    if (place == PLACE_SCALAR) return component_fail(function, "grid %d holds scalars: it has no coordinates", grid);
    if (unstructured(c, place)) {
        if (axis == 2) return component_fail(function, "grid %d is a flat mesh: its nodes have x and y only", grid);
        const double *from = axis == 0 ? c->scene.mesh.node_x : c->scene.mesh.node_y;
        memcpy(out, from, (size_t)c->scene.mesh.node_count * sizeof(double));
        return BMI_SUCCESS;
    }
    struct rectilinear r = rectilinear_of(c, place);
    int dimension = r.rank - 1 - axis; /* x is the last dimension, y the one before */
    if (dimension < 0)
        return component_fail(function, "grid %d has %d dimension%s: no %s", grid, r.rank, r.rank == 1 ? "" : "s",
                              axis == 1 ? "y" : "z");
    for (int64_t k = 0; k < r.shape[dimension]; ++k) out[k] = r.origin[dimension] + (double)k * r.spacing[dimension];
    return BMI_SUCCESS;
}

static int get_grid_x(Bmi *self, int grid, double *x) { return coordinates(self, grid, x, 0, "get_grid_x"); }
static int get_grid_y(Bmi *self, int grid, double *y) { return coordinates(self, grid, y, 1, "get_grid_y"); }
static int get_grid_z(Bmi *self, int grid, double *z) { return coordinates(self, grid, z, 2, "get_grid_z"); }

/* The mesh of an unstructured grid, or NULL with a message. */
static const struct config_mesh *mesh_of(Bmi *self, int grid, const void *out, const char *function) {
    int place;
    struct component *c = grid_lookup(self, grid, out, function, &place);
    if (!c) return NULL;
    if (!unstructured(c, place)) {
        component_fail(function, "grid %d is not unstructured: edges and faces belong to a mesh's grids", grid);
        return NULL;
    }
    return &c->scene.mesh;
}

static int get_grid_edge_count(Bmi *self, int grid, int *count) {
    const struct config_mesh *m = mesh_of(self, grid, count, "get_grid_edge_count");
    if (!m) return BMI_FAILURE;
    *count = (int)m->edge_count;
    return BMI_SUCCESS;
}

static int get_grid_face_count(Bmi *self, int grid, int *count) {
    const struct config_mesh *m = mesh_of(self, grid, count, "get_grid_face_count");
    if (!m) return BMI_FAILURE;
    *count = (int)m->face_count;
    return BMI_SUCCESS;
}

static int get_grid_edge_nodes(Bmi *self, int grid, int *edge_nodes) {
    const struct config_mesh *m = mesh_of(self, grid, edge_nodes, "get_grid_edge_nodes");
    if (!m) return BMI_FAILURE;
    for (int64_t k = 0; k < 2 * m->edge_count; ++k) edge_nodes[k] = (int)m->edge_nodes[k];
    return BMI_SUCCESS;
}

static int get_grid_face_edges(Bmi *self, int grid, int *face_edges) {
    const struct config_mesh *m = mesh_of(self, grid, face_edges, "get_grid_face_edges");
    if (!m) return BMI_FAILURE;
    for (int64_t k = 0; k < m->face_node_start[m->face_count]; ++k) face_edges[k] = (int)m->face_edges[k];
    return BMI_SUCCESS;
}

static int get_grid_face_nodes(Bmi *self, int grid, int *face_nodes) {
    const struct config_mesh *m = mesh_of(self, grid, face_nodes, "get_grid_face_nodes");
    if (!m) return BMI_FAILURE;
    for (int64_t k = 0; k < m->face_node_start[m->face_count]; ++k) face_nodes[k] = (int)m->face_nodes[k];
    return BMI_SUCCESS;
}

static int get_grid_nodes_per_face(Bmi *self, int grid, int *nodes_per_face) {
    const struct config_mesh *m = mesh_of(self, grid, nodes_per_face, "get_grid_nodes_per_face");
    if (!m) return BMI_FAILURE;
    for (int64_t f = 0; f < m->face_count; ++f)
        nodes_per_face[f] = (int)(m->face_node_start[f + 1] - m->face_node_start[f]);
    return BMI_SUCCESS;
}

void component_register_grids(Bmi *model) {
    model->get_grid_rank = get_grid_rank;
    model->get_grid_size = get_grid_size;
    model->get_grid_type = get_grid_type;
    model->get_grid_shape = get_grid_shape;
    model->get_grid_spacing = get_grid_spacing;
    model->get_grid_origin = get_grid_origin;
    model->get_grid_x = get_grid_x;
    model->get_grid_y = get_grid_y;
    model->get_grid_z = get_grid_z;
    model->get_grid_node_count = get_grid_node_count;
    model->get_grid_edge_count = get_grid_edge_count;
    model->get_grid_face_count = get_grid_face_count;
    model->get_grid_edge_nodes = get_grid_edge_nodes;
    model->get_grid_face_edges = get_grid_face_edges;
    model->get_grid_face_nodes = get_grid_face_nodes;
    model->get_grid_nodes_per_face = get_grid_nodes_per_face;
}
