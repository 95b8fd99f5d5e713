/* The mesh of a configuration: grid.file read (mesh_file.c), its coordinates
 * told (grid.coordinates, else the file's attributes, else refused when they
 * look like degrees), the library's mesh made from it, and the edges the BMI
 * components list, numbered as the library numbers its faces. */
#include "config/scene_parts.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int scene_refuse(const struct config *c, unsigned long line, const char *key, char *message, size_t size,
                 const char *format, ...) {
    int used = snprintf(message, size, "%s:%lu: %s: ", c->path, line ? line : 1ul, key);
    if (used < 0 || (size_t)used >= size) return 1;
    va_list args;
    va_start(args, format);
    vsnprintf(message + used, size - (size_t)used, format, args);
    va_end(args);
    return 1;
}

int scene_read_mesh_values(const struct config *c, const struct config_scene *s, const char *file,
                           const char *variable, unsigned long line, const char *key, double **values,
                           int64_t *count, enum config_location *where, char *message, size_t size) {
    char reading[CONFIG_MESSAGE_MAX];
    if (config_read_mesh_variable(&s->mesh, file, variable, s->cells_at_nodes ? CONFIG_AT_NODES : CONFIG_AT_FACES,
                                  values, count, where, reading, sizeof reading))
        return scene_refuse(c, line, key, message, size, "%s", reading);
    return 0;
}

double scene_sphere_distance(double lon0, double lat0, double lon1, double lat1) {
    const double d = 3.14159265358979323846 / 180.0;
    const double a = sin(0.5 * (lat1 - lat0) * d), b = sin(0.5 * (lon1 - lon0) * d);
    const double h = a * a + cos(lat0 * d) * cos(lat1 * d) * b * b;
    return 2.0 * 6371008.8 * asin(fmin(1.0, sqrt(h)));
}

/* Whether the mesh is in degrees: grid.coordinates, else what the file's
 * attributes say, else projected unless every node lies within [-180, 180]
 * x [-90, 90], which is refused: such numbers may be degrees or metres, and
 * taking one for the other moves sand a hundred thousand times too fast or
 * too slow. Only the nodes the faces use count. */
static int decide_coordinates(const struct config *c, const struct config_mesh *m, int *geographic, char *message,
                              size_t size) {
    const char *file = c->mesh_file;
    double low[2] = {INFINITY, INFINITY}, high[2] = {-INFINITY, -INFINITY};
    for (int64_t f = 0; f < m->face_count; ++f)
        for (int64_t k = m->face_node_start[f]; k < m->face_node_start[f + 1]; ++k) {
            const int64_t n = m->face_nodes[k];
            if (!isfinite(m->node_x[n]) || !isfinite(m->node_y[n]))
                return scene_refuse(c, c->grid_line, "grid.file", message, size,
                                    "%s: node %lld of face %lld (both from 0) has no coordinates (a fill value or NaN)",
                                    file, (long long)n, (long long)f);
            low[0] = fmin(low[0], m->node_x[n]), high[0] = fmax(high[0], m->node_x[n]);
            low[1] = fmin(low[1], m->node_y[n]), high[1] = fmax(high[1], m->node_y[n]);
        }
    if (c->coordinates != CONFIG_COORDINATES_FROM_FILE) {
        *geographic = c->coordinates == CONFIG_COORDINATES_GEOGRAPHIC;
        const enum config_coordinates other =
            *geographic ? CONFIG_COORDINATES_PROJECTED : CONFIG_COORDINATES_GEOGRAPHIC;
        if (m->coordinates == other)
            return scene_refuse(c, c->grid_line, "grid.coordinates", message, size,
                                "%s: grid.coordinates says %s, and the file says its nodes are %s (%s): which is it?",
                                file, *geographic ? "geographic" : "projected",
                                *geographic ? "projected" : "in degrees", m->coordinates_said);
        return 0;
    }
    if (m->coordinates != CONFIG_COORDINATES_FROM_FILE) {
        *geographic = m->coordinates == CONFIG_COORDINATES_GEOGRAPHIC;
        return 0;
    }
    if (low[0] >= -180.0 && high[0] <= 180.0 && low[1] >= -90.0 && high[1] <= 90.0)
        return scene_refuse(c, c->grid_line, "grid", message, size,
                            "%s: its nodes all lie within [-180, 180] x [-90, 90] (x from %g to %g, y from %g to %g) "
                            "and the file does not say what they are (%s): they look like degrees of longitude and "
                            "latitude. Say which they are: grid.coordinates: geographic (longitude and latitude in "
                            "degrees) or grid.coordinates: projected (metres)",
                            file, low[0], high[0], low[1], high[1],
                            m->coordinates_said[0] ? m->coordinates_said : "no units or standard_name");
    *geographic = 0;
    return 0;
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

/* The file's faces' edges (half_edges, `halves` of them, sorted by node pair). */
static struct half_edge *sorted_halves(const struct config_mesh *mesh, int64_t *halves) {
    *halves = mesh->face_node_start[mesh->face_count];
    struct half_edge *edges = malloc((size_t)(*halves > 0 ? *halves : 1) * sizeof *edges);
    if (!edges) return NULL;
    for (int64_t f = 0; f < mesh->face_count; ++f) {
        int64_t begin = mesh->face_node_start[f], n = mesh->face_node_start[f + 1] - begin;
        for (int64_t k = 0; k < n; ++k) {
            int64_t a = mesh->face_nodes[begin + k], b = mesh->face_nodes[begin + (k + 1) % n];
            edges[begin + k] = (struct half_edge){a < b ? a : b, a < b ? b : a, begin + k};
        }
    }
    qsort(edges, (size_t)*halves, sizeof *edges, by_nodes_then_position);
    return edges;
}

/* Numbers the edges as the library numbers its faces (as they first appear,
 * face by face, edge by edge in each face's node order), fills face_edges
 * and edge_nodes, and checks the numbering against dpsm_get_mesh_faces(). */
static int number_edges(const struct config *c, struct config_mesh *mesh, dpsm_grid *g, char *message, size_t size) {
    int64_t halves;
    struct half_edge *edges = sorted_halves(mesh, &halves);
    int64_t *first_position = malloc((size_t)(halves > 0 ? halves : 1) * sizeof *first_position);
    int64_t *edge_of_first = malloc((size_t)(halves > 0 ? halves : 1) * sizeof *edge_of_first);
    mesh->face_edges = malloc((size_t)(halves > 0 ? halves : 1) * sizeof(int64_t));
    if (!edges || !first_position || !edge_of_first || !mesh->face_edges) {
        free(edges), free(first_position), free(edge_of_first);
        snprintf(message, size, "%s: out of memory numbering the mesh's edges", c->path);
        return 1;
    }
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

/* The edges of a dual mesh's triangles by node pair, lower node first: the
 * library's first faces, each between its two nodes' cells (the halves of
 * the boundary edges follow them). */
static int number_dual_edges(const struct config *c, struct config_mesh *mesh, dpsm_grid *g, char *message,
                             size_t size) {
    int64_t halves;
    struct half_edge *edges = sorted_halves(mesh, &halves);
    mesh->face_edges = malloc((size_t)(halves > 0 ? halves : 1) * sizeof(int64_t));
    mesh->edge_nodes = malloc((size_t)(2 * (halves > 0 ? halves : 1)) * sizeof(int64_t));
    if (!edges || !mesh->face_edges || !mesh->edge_nodes) {
        free(edges);
        snprintf(message, size, "%s: out of memory numbering the mesh's edges", c->path);
        return 1;
    }
    int64_t count = 0;
    for (int64_t s = 0; s < halves;) {
        int64_t e = s;
        while (e < halves && edges[e].low == edges[s].low && edges[e].high == edges[s].high) ++e;
        for (int64_t k = s; k < e; ++k) mesh->face_edges[edges[k].position] = count;
        mesh->edge_nodes[2 * count] = edges[s].low, mesh->edge_nodes[2 * count + 1] = edges[s].high;
        ++count;
        s = e;
    }
    free(edges);
    mesh->edge_count = count;
    int64_t library_count = 0;
    dpsm_get_face_count(g, &library_count);
    int64_t *library_cells = malloc((size_t)(2 * (library_count > 0 ? library_count : 1)) * sizeof(int64_t));
    int same = library_cells && library_count >= count && dpsm_get_mesh_faces(g, library_cells) == DPSM_OK;
    for (int64_t e = 0; same && e < count; ++e)
        same = library_cells[2 * e] == mesh->edge_nodes[2 * e] && library_cells[2 * e + 1] == mesh->edge_nodes[2 * e + 1];
    free(library_cells);
    if (!same) {
        snprintf(message, size, "%s: the dual mesh's edges do not match the library's faces (a library change?)",
                 c->path);
        return 1;
    }
    return 0;
}

int scene_create_mesh(const struct config *c, struct config_scene *s, char *message, size_t size) {
    char reading[CONFIG_MESSAGE_MAX];
    if (config_read_mesh(c->mesh_file, c->topology, &s->mesh, reading, sizeof reading))
        return scene_refuse(c, c->grid_line, "grid.file", message, size, "%s", reading);
    s->has_mesh = 1;
    struct config_mesh *m = &s->mesh;
    int geographic = 0;
    if (decide_coordinates(c, m, &geographic, message, size)) return 1;
    s->geographic = geographic;
    /* dpsm takes interleaved (x, y); the mesh keeps them apart, as UGRID and BMI do. */
    double *xy = malloc((size_t)(2 * m->node_count) * sizeof *xy);
    if (!xy) {
        snprintf(message, size, "%s: out of memory", c->path);
        return 1;
    }
    for (int64_t k = 0; k < m->node_count; ++k) {
        /* A node no face uses may lack coordinates: it is not read. */
        xy[2 * k] = isfinite(m->node_x[k]) ? m->node_x[k] : 0.0;
        xy[2 * k + 1] = isfinite(m->node_y[k]) ? m->node_y[k] : 0.0;
    }
    int status;
    if (c->grid_kind == CONFIG_GRID_DUAL_MESH) {
        int64_t *triangles = malloc((size_t)(3 * (m->face_count > 0 ? m->face_count : 1)) * sizeof *triangles);
        if (!triangles) {
            free(xy);
            snprintf(message, size, "%s: out of memory", c->path);
            return 1;
        }
        for (int64_t f = 0; f < m->face_count; ++f) {
            const int64_t begin = m->face_node_start[f], n = m->face_node_start[f + 1] - begin;
            if (n != 3) {
                free(xy), free(triangles);
                return scene_refuse(c, c->grid_line, "grid.kind", message, size,
                                    "dual_mesh makes the median dual of triangles, and face %lld (from 0) of %s has %lld "
                                    "nodes; a mesh of polygons takes grid.kind: mesh (values on its faces)",
                                    (long long)f, c->mesh_file, (long long)n);
            }
            for (int k = 0; k < 3; ++k) triangles[3 * f + k] = m->face_nodes[begin + k];
        }
        status = geographic ? dpsm_create_dual_mesh_geographic(0, m->node_count, xy, m->face_count, triangles, &s->grid)
                            : dpsm_create_dual_mesh(m->node_count, xy, m->face_count, triangles, &s->grid);
        free(triangles);
        s->cells_at_nodes = 1;
        s->cell_count = m->node_count;
    } else {
        status = geographic ? dpsm_create_mesh_geographic(0, m->node_count, xy, m->face_count, m->face_node_start,
                                                          m->face_nodes, &s->grid)
                            : dpsm_create_mesh(m->node_count, xy, m->face_count, m->face_node_start, m->face_nodes,
                                               &s->grid);
        s->cell_count = m->face_count;
    }
    free(xy);
    if (status != DPSM_OK)
        return scene_refuse(c, c->grid_line, "grid.file", message, size,
                            "%s: the mesh is not usable (its nodes and faces counted from 0 in the file's order): %s",
                            c->mesh_file, dpsm_last_error(NULL));
    dpsm_get_face_count(s->grid, &s->face_count);
    return c->grid_kind == CONFIG_GRID_DUAL_MESH ? number_dual_edges(c, m, s->grid, message, size)
                                                 : number_edges(c, m, s->grid, message, size);
}
