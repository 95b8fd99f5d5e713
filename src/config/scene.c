/* Builds the configured scene: the grid or mesh (mesh_scene.c), its
 * parameters and sides, the initial heights and the source, the mesh's edge
 * (mesh_edges.c). */
#include "config/config.h"
#include "config/netcdf_input.h"
#include "config/scene_parts.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int library_refuses(const struct config *c, const char *what, dpsm_grid *g, char *message, size_t size) {
    snprintf(message, size, "%s: %s: %s", c->path, what, dpsm_last_error(g));
    return 1;
}

/* The domain's centre, where a scene without initial.centre stands: the
 * middle of a grid (the axis of an axisymmetric one), of a mesh's nodes'
 * bounding box. */
static void domain_centre(const struct config *c, const struct config_scene *s, double centre[2]) {
    if (!s->has_mesh) {
        centre[0] = c->grid_kind == CONFIG_GRID_AXISYMMETRIC ? 0 : 0.5 * (double)c->nx * c->dx;
        centre[1] = c->grid_kind == CONFIG_GRID_2D ? 0.5 * (double)c->ny * c->dy : 0;
        return;
    }
    const struct config_mesh *m = &s->mesh;
    double low[2] = {INFINITY, INFINITY}, high[2] = {-INFINITY, -INFINITY};
    for (int64_t f = 0; f < m->face_count; ++f)
        for (int64_t k = m->face_node_start[f]; k < m->face_node_start[f + 1]; ++k) {
            const int64_t n = m->face_nodes[k];
            low[0] = fmin(low[0], m->node_x[n]), high[0] = fmax(high[0], m->node_x[n]);
            low[1] = fmin(low[1], m->node_y[n]), high[1] = fmax(high[1], m->node_y[n]);
        }
    centre[0] = 0.5 * (low[0] + high[0]);
    centre[1] = 0.5 * (low[1] + high[1]);
}

int scene_heights_sign(const struct config *c, const char *file, const char *variable, int positive,
                       unsigned long line, const char *key, double *values, int64_t count, char *message, size_t size) {
    char said[400], key_path[64];
    const int sign = netcdf_field_sign(file, variable, said, sizeof said);
    snprintf(key_path, sizeof key_path, "%s.positive", key);
    if (positive == 0 && sign < 0)
        return scene_refuse(c, line, key, message, size,
                            "%s: \"%s\" holds depths, positive down (%s), and dpsm's heights are elevations, "
                            "positive up: say %s: down to take their negative, or give an elevation",
                            file, variable, said, key_path);
    if (positive != 0 && sign != 0 && positive != sign)
        return scene_refuse(c, line, key_path, message, size,
                            "%s says %s, and %s says \"%s\" is positive %s (%s): which is it?", key_path,
                            positive > 0 ? "up" : "down", file, variable, sign > 0 ? "up" : "down", said);
    if (positive < 0)
        for (int64_t k = 0; k < count; ++k) values[k] = -values[k];
    return 0;
}

/* A field's values from a file: a grid's netCDF variable, or a mesh file's
 * variable where the cells are (faces of a mesh, nodes of a dual mesh). */
static int field_from_file(const struct config *c, const struct config_scene *s, const struct config_field *field,
                           const char *key, double *values, char *message, size_t size) {
    if (!s->has_mesh) {
        if (c->grid_kind == CONFIG_GRID_2D)
            return netcdf_read_field(field->file, field->variable, 2, (size_t)c->ny, (size_t)c->nx, values, message,
                                     size);
        return netcdf_read_field(field->file, field->variable, 1, (size_t)s->cell_count, 1, values, message, size);
    }
    double *read = NULL;
    int64_t count = 0;
    enum config_location where;
    if (scene_read_mesh_values(c, s, field->file, field->variable, field->line, key, &read, &count, &where, message,
                               size))
        return 1;
    const enum config_location cells = s->cells_at_nodes ? CONFIG_AT_NODES : CONFIG_AT_FACES;
    if (where != cells || count != s->cell_count) {
        free(read);
        static const char *const places[] = {"nodes", "faces", "edges"};
        if (where == CONFIG_AT_NODES)
            return scene_refuse(c, field->line, key, message, size,
                                "%s: \"%s\" lies on the mesh's nodes (%lld values, one per node), and the cells of "
                                "grid.kind: mesh are its faces (%lld); for values at the nodes say grid.kind: dual_mesh, "
                                "whose cells are the nodes (the median dual of the triangles)",
                                field->file, field->variable, (long long)count, (long long)s->mesh.face_count);
        return scene_refuse(c, field->line, key, message, size,
                            "%s: \"%s\" lies on the mesh's %s (%lld values), and the cells of grid.kind: %s are its "
                            "%s (%lld)%s",
                            field->file, field->variable, places[where], (long long)count,
                            s->cells_at_nodes ? "dual_mesh" : "mesh", s->cells_at_nodes ? "nodes" : "faces",
                            (long long)s->cell_count,
                            where == CONFIG_AT_FACES ? "; for values on the faces say grid.kind: mesh" : "");
    }
    memcpy(values, read, (size_t)count * sizeof *values);
    free(read);
    return 0;
}

/* A column or a cone: where each cell's centre lies from the scene's centre
 * (in metres on a geographic mesh, whose centres are in degrees). A scene
 * that puts sand on no cell is refused. */
static int field_from_scene(const struct config *c, const struct config_scene *s, const struct config_field *field,
                            const char *key, double *values, char *message, size_t size) {
    const int64_t n = s->cell_count;
    double *xy = malloc((size_t)(2 * n) * sizeof *xy), centre[2];
    if (!xy) {
        snprintf(message, size, "%s: out of memory", c->path);
        return 1;
    }
    if (dpsm_get_cell_centres(s->grid, xy, NULL) != DPSM_OK) {
        free(xy);
        return library_refuses(c, key, s->grid, message, size);
    }
    if (field->has_centre) centre[0] = field->centre[0], centre[1] = field->centre[1];
    else domain_centre(c, s, centre);
    const int geographic = s->geographic;
    int64_t nearest = 0, sanded = 0;
    double nearest_r = INFINITY;
    for (int64_t k = 0; k < n; ++k) {
        const double r = geographic ? scene_sphere_distance(centre[0], centre[1], xy[2 * k], xy[2 * k + 1])
                                    : hypot(xy[2 * k] - centre[0], xy[2 * k + 1] - centre[1]);
        if (field->kind == CONFIG_FIELD_COLUMN) values[k] = r <= field->radius ? field->height : 0;
        else values[k] = r < field->radius ? field->height * (1 - r / field->radius) : 0;
        sanded += field->kind == CONFIG_FIELD_COLUMN ? r <= field->radius : r < field->radius;
        if (r < nearest_r) nearest_r = r, nearest = k;
    }
    int failed = 0;
    if (sanded == 0) {
        double low[2] = {INFINITY, INFINITY}, high[2] = {-INFINITY, -INFINITY};
        for (int64_t k = 0; k < n; ++k)
            for (int a = 0; a < 2; ++a) low[a] = fmin(low[a], xy[2 * k + a]), high[a] = fmax(high[a], xy[2 * k + a]);
        failed = scene_refuse(
            c, field->line, key, message, size,
            "the %s puts sand on no cell: no cell's centre lies within its radius; its centre (%g, %g)%s lies %g%s "
            "from the nearest cell's centre (%g, %g), and the cells' centres span [%g, %g] x [%g, %g]; give "
            "%s.centre: [x, y] where the sand should stand, or a larger radius",
            field->kind == CONFIG_FIELD_COLUMN ? "column" : "cone", centre[0], centre[1], field->has_centre ? "" : " (the domain's centre)", nearest_r,
            geographic ? " m" : "", xy[2 * nearest], xy[2 * nearest + 1], low[0], high[0], low[1], high[1], key);
    }
    free(xy);
    return failed;
}

static int fill_field(const struct config *c, const struct config_scene *s, const struct config_field *field,
                      const char *key, double *values, char *message, size_t size) {
    if (field->kind == CONFIG_FIELD_CONSTANT) {
        for (int64_t k = 0; k < s->cell_count; ++k) values[k] = field->value;
        return 0;
    }
    /* Heights (not a source's rates) may come as depths. */
    if (field->kind == CONFIG_FIELD_FILE)
        return field_from_file(c, s, field, key, values, message, size) ||
               (field == &c->initial && scene_heights_sign(c, field->file, field->variable, field->positive,
                                                           field->line, key, values, s->cell_count, message, size));
    return field_from_scene(c, s, field, key, values, message, size);
}

static int create_grid(const struct config *c, struct config_scene *s, char *message, size_t size) {
    if (c->grid_kind == CONFIG_GRID_MESH || c->grid_kind == CONFIG_GRID_DUAL_MESH)
        return scene_create_mesh(c, s, message, size);
    int status;
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
    if (size) message[0] = '\0';
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
    if (!failed) failed = fill_field(c, &s, &c->initial, "initial", heights, message, size);
    if (!failed && dpsm_set_heights(s.grid, heights) != DPSM_OK)
        failed = library_refuses(c, "initial", s.grid, message, size);
    if (!failed && c->source.kind != CONFIG_FIELD_NONE) {
        s.source = malloc((size_t)s.cell_count * sizeof *s.source);
        if (!s.source) failed = 1, snprintf(message, size, "%s: out of memory", c->path);
        if (!failed) failed = fill_field(c, &s, &c->source, "source", s.source, message, size);
        if (!failed && dpsm_set_source(s.grid, s.source) != DPSM_OK)
            failed = library_refuses(c, "source", s.grid, message, size);
    }
    if (!failed) failed = scene_set_edges(c, &s, message, size);
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
    free(scene->face_cells);
    free(scene->levels);
    memset(scene, 0, sizeof *scene);
}
