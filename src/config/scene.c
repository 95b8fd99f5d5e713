/* Builds the configured scene: the grid or mesh, its parameters and sides,
 * the initial heights and the source. */
#include "config/config.h"
#include "config/netcdf_input.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int library_refuses(const struct config *c, const char *what, dpsm_grid *g, char *message, size_t size) {
    snprintf(message, size, "%s: %s: %s", c->path, what, dpsm_last_error(g));
    return 1;
}

/* One half-edge of a face: its node pair (lower first) and where it appears. */
struct half_edge {
    int64_t low, high, position;
};

static int by_nodes_then_position(const void *a, const void *b) {
    const struct half_edge *x = a, *y = b;
    if (x->low != y->low) return x->low < y->low ? -1 : 1;
    if (x->high != y->high) return x->high < y->high ? -1 : 1;
    return (x->position > y->position) - (x->position < y->position);
}

/* Numbers the edges as the library numbers its faces (as they first appear,
 * face by face, edge by edge in each face's node order), fills face_edges
 * and edge_nodes, and checks the numbering against dpsm_get_mesh_faces(). */
static int number_edges(const struct config *c, struct config_mesh *mesh, dpsm_grid *g, char *message, size_t size) {
    int64_t halves = mesh->face_node_start[mesh->face_count];
    struct half_edge *edges = malloc((size_t)halves * sizeof *edges);
    int64_t *first_position = malloc((size_t)halves * sizeof *first_position);
    int64_t *edge_of_first = malloc((size_t)halves * sizeof *edge_of_first);
    mesh->face_edges = malloc((size_t)halves * sizeof(int64_t));
    if (!edges || !first_position || !edge_of_first || !mesh->face_edges) {
        free(edges), free(first_position), free(edge_of_first);
        snprintf(message, size, "%s: out of memory numbering the mesh's edges", c->path);
        return 1;
    }
    for (int64_t f = 0; f < mesh->face_count; ++f) {
        int64_t begin = mesh->face_node_start[f], n = mesh->face_node_start[f + 1] - begin;
        for (int64_t k = 0; k < n; ++k) {
            int64_t a = mesh->face_nodes[begin + k], b = mesh->face_nodes[begin + (k + 1) % n];
            edges[begin + k] = (struct half_edge){a < b ? a : b, a < b ? b : a, begin + k};
        }
    }
    qsort(edges, (size_t)halves, sizeof *edges, by_nodes_then_position);
    /* Each run of equal node pairs is one edge; it takes its number from the
     * position where it first appears. */
    for (int64_t p = 0; p < halves; ++p) edge_of_first[p] = -1;
    for (int64_t s = 0; s < halves;) {
        int64_t e = s;
        while (e < halves && edges[e].low == edges[s].low && edges[e].high == edges[s].high) ++e;
        for (int64_t k = s; k < e; ++k) first_position[edges[k].position] = edges[s].position;
        edge_of_first[edges[s].position] = 0;
        s = e;
    }
    int64_t count = 0;
    for (int64_t p = 0; p < halves; ++p)
        if (edge_of_first[p] == 0) edge_of_first[p] = count++;
    for (int64_t p = 0; p < halves; ++p) mesh->face_edges[p] = edge_of_first[first_position[p]];
    free(edges), free(first_position), free(edge_of_first);

    mesh->edge_count = count;
    mesh->edge_nodes = malloc((size_t)(2 * count) * sizeof(int64_t));
    int64_t *edge_cells = malloc((size_t)(2 * count) * sizeof(int64_t));
    int64_t library_count = 0;
    dpsm_get_face_count(g, &library_count);
    if (!mesh->edge_nodes || !edge_cells || library_count != count) {
        free(edge_cells);
        snprintf(message, size, "%s: the mesh has %lld edges, the library %lld faces", c->path, (long long)count,
                 (long long)library_count);
        return 1;
    }
    int64_t *library_cells = malloc((size_t)(2 * count) * sizeof(int64_t));
    for (int64_t e = 0; e < 2 * count; ++e) edge_cells[e] = -1;
    for (int64_t f = 0; f < mesh->face_count; ++f) {
        int64_t begin = mesh->face_node_start[f], n = mesh->face_node_start[f + 1] - begin;
        for (int64_t k = 0; k < n; ++k) {
            int64_t e = mesh->face_edges[begin + k];
            if (edge_cells[2 * e] < 0) {
                edge_cells[2 * e] = f;
                mesh->edge_nodes[2 * e] = mesh->face_nodes[begin + k];
                mesh->edge_nodes[2 * e + 1] = mesh->face_nodes[begin + (k + 1) % n];
            } else {
                edge_cells[2 * e + 1] = f;
            }
        }
    }
    int same = library_cells && dpsm_get_mesh_faces(g, library_cells) == DPSM_OK &&
               memcmp(library_cells, edge_cells, (size_t)(2 * count) * sizeof(int64_t)) == 0;
    free(library_cells);
    free(edge_cells);
    if (!same) {
        snprintf(message, size, "%s: the mesh's edges do not match the library's faces (a library change?)", c->path);
        return 1;
    }
    return 0;
}

/* Cell centres and the domain's centre, for the built-in scenes. */
static void cell_centres(const struct config *c, const struct config_scene *s, double *x, double *y, double centre[2]) {
    if (!s->has_mesh) {
        for (int64_t j = 0; j < c->ny; ++j)
            for (int64_t i = 0; i < c->nx; ++i) {
                x[i + c->nx * j] = ((double)i + 0.5) * c->dx;
                y[i + c->nx * j] = c->grid_kind == CONFIG_GRID_2D ? ((double)j + 0.5) * c->dy : 0;
            }
        centre[0] = c->grid_kind == CONFIG_GRID_AXISYMMETRIC ? 0 : 0.5 * (double)c->nx * c->dx;
        centre[1] = c->grid_kind == CONFIG_GRID_2D ? 0.5 * (double)c->ny * c->dy : 0;
        return;
    }
    const struct config_mesh *m = &s->mesh;
    double low[2] = {INFINITY, INFINITY}, high[2] = {-INFINITY, -INFINITY};
    for (int64_t n = 0; n < m->node_count; ++n) {
        low[0] = fmin(low[0], m->node_x[n]), high[0] = fmax(high[0], m->node_x[n]);
        low[1] = fmin(low[1], m->node_y[n]), high[1] = fmax(high[1], m->node_y[n]);
    }
    centre[0] = 0.5 * (low[0] + high[0]);
    centre[1] = 0.5 * (low[1] + high[1]);
    for (int64_t f = 0; f < m->face_count; ++f) { /* the polygon's centroid */
        int64_t begin = m->face_node_start[f], n = m->face_node_start[f + 1] - begin;
        double area = 0, cx = 0, cy = 0, x0 = m->node_x[m->face_nodes[begin]], y0 = m->node_y[m->face_nodes[begin]];
        for (int64_t k = 0; k < n; ++k) {
            int64_t a = m->face_nodes[begin + k], b = m->face_nodes[begin + (k + 1) % n];
            double xa = m->node_x[a] - x0, ya = m->node_y[a] - y0, xb = m->node_x[b] - x0, yb = m->node_y[b] - y0;
            double cross = xa * yb - xb * ya;
            area += cross;
            cx += (xa + xb) * cross;
            cy += (ya + yb) * cross;
        }
        x[f] = x0 + cx / (3 * area);
        y[f] = y0 + cy / (3 * area);
    }
}

static int fill_field(const struct config *c, const struct config_scene *s, const struct config_field *field,
                      double *values, char *message, size_t size) {
    int64_t n = s->cell_count;
    if (field->kind == CONFIG_FIELD_CONSTANT) {
        for (int64_t k = 0; k < n; ++k) values[k] = field->value;
        return 0;
    }
    if (field->kind == CONFIG_FIELD_FILE) {
        if (c->grid_kind == CONFIG_GRID_2D)
            return netcdf_read_field(field->file, field->variable, 2, (size_t)c->ny, (size_t)c->nx, values, message,
                                     size);
        return netcdf_read_field(field->file, field->variable, 1, (size_t)n, 1, values, message, size);
    }
    double *x = malloc((size_t)n * sizeof *x), *y = malloc((size_t)n * sizeof *y), centre[2];
    if (!x || !y) {
        free(x), free(y);
        snprintf(message, size, "%s: out of memory", c->path);
        return 1;
    }
    cell_centres(c, s, x, y, centre);
    for (int64_t k = 0; k < n; ++k) {
        double r = hypot(x[k] - centre[0], y[k] - centre[1]);
        if (field->kind == CONFIG_FIELD_COLUMN) values[k] = r <= field->radius ? field->height : 0;
        else values[k] = r < field->radius ? field->height * (1 - r / field->radius) : 0;
    }
    free(x), free(y);
    return 0;
}

static int create_grid(const struct config *c, struct config_scene *s, char *message, size_t size) {
    int status;
    if (c->grid_kind == CONFIG_GRID_MESH) {
        if (config_read_mesh(c->mesh_file, &s->mesh, message, size)) return 1;
        s->has_mesh = 1;
        /* dpsm takes interleaved (x, y); the mesh keeps them apart, as UGRID and BMI do. */
        double *xy = malloc((size_t)(2 * s->mesh.node_count) * sizeof *xy);
        if (!xy) {
            snprintf(message, size, "%s: out of memory", c->path);
            return 1;
        }
        for (int64_t k = 0; k < s->mesh.node_count; ++k) xy[2 * k] = s->mesh.node_x[k], xy[2 * k + 1] = s->mesh.node_y[k];
        status = dpsm_create_mesh(s->mesh.node_count, xy, s->mesh.face_count, s->mesh.face_node_start,
                                  s->mesh.face_nodes, &s->grid);
        free(xy);
        if (status != DPSM_OK) {
            snprintf(message, size, "%s: the mesh is not usable: %s", c->mesh_file, dpsm_last_error(NULL));
            return 1;
        }
        s->cell_count = s->mesh.face_count;
        return number_edges(c, &s->mesh, s->grid, message, size);
    }
    if (c->grid_kind == CONFIG_GRID_1D) status = dpsm_create_1d(c->nx, c->dx, &s->grid);
    else if (c->grid_kind == CONFIG_GRID_2D) status = dpsm_create_2d(c->nx, c->ny, c->dx, c->dy, &s->grid);
    else status = dpsm_create_axisymmetric(c->nx, c->dx, &s->grid);
    if (status != DPSM_OK) return library_refuses(c, "grid", NULL, message, size);
    s->cell_count = c->nx * c->ny;
    return 0;
}

int config_build(const struct config *c, struct config_scene *scene, char *message, size_t size) {
    struct config_scene s;
    memset(&s, 0, sizeof s);
    double *heights = NULL;
    int failed = create_grid(c, &s, message, size);
    if (!failed && c->has_repose_angle && dpsm_set_repose_angle(s.grid, c->repose_angle_degrees * (3.14159265358979323846 / 180)) != DPSM_OK)
        failed = library_refuses(c, "repose_angle", s.grid, message, size);
    if (!failed && c->has_mobility && dpsm_set_mobility(s.grid, c->mobility) != DPSM_OK)
        failed = library_refuses(c, "mobility", s.grid, message, size);
    for (int side = 0; side < CONFIG_SIDES && !failed; ++side)
        if (c->boundary[side] != CONFIG_SIDE_DEFAULT && dpsm_set_boundary(s.grid, side, c->boundary[side]) != DPSM_OK)
            failed = library_refuses(c, "boundaries", s.grid, message, size);
    if (!failed) {
        heights = malloc((size_t)s.cell_count * sizeof *heights);
        if (!heights) failed = 1, snprintf(message, size, "%s: out of memory", c->path);
    }
    if (!failed) failed = fill_field(c, &s, &c->initial, heights, message, size);
    if (!failed && dpsm_set_heights(s.grid, heights) != DPSM_OK)
        failed = library_refuses(c, "initial", s.grid, message, size);
    if (!failed && c->source.kind != CONFIG_FIELD_NONE) {
        s.source = malloc((size_t)s.cell_count * sizeof *s.source);
        if (!s.source) failed = 1, snprintf(message, size, "%s: out of memory", c->path);
        if (!failed) failed = fill_field(c, &s, &c->source, s.source, message, size);
        if (!failed && dpsm_set_source(s.grid, s.source) != DPSM_OK)
            failed = library_refuses(c, "source", s.grid, message, size);
    }
    free(heights);
    if (failed) {
        config_scene_free(&s);
        return 1;
    }
    *scene = s;
    return 0;
}

void config_scene_free(struct config_scene *scene) {
    dpsm_destroy(scene->grid);
    config_mesh_free(&scene->mesh);
    free(scene->source);
    memset(scene, 0, sizeof *scene);
}
