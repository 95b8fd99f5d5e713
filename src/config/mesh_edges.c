/* A mesh's edge as the configuration states it: which faces are open
 * (boundaries.edge, and the groups of edges boundaries.open or .wall names:
 * gmsh physical curves, UGRID boundary tags) and the level beyond them
 * (boundaries.level: a number, each face's own cell, a field of a file).
 * An open edge without a level whose cells do not all stand at 0 is
 * refused: the level 0 beyond it would drain or flood a real bed. */
#include "config/scene_parts.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The node pair (of the file's mesh) of each library face on the domain
 * edge: on a mesh the face's edge; on a dual mesh the boundary edge a half
 * lies on (the halves follow the edges, two per boundary edge, in the order
 * of the edges, the lower node's half first). -1 for interior faces. */
static int edge_pairs(const struct config_scene *s, const int64_t *face_cells, int64_t *pairs, int64_t *triangle) {
    const struct config_mesh *m = &s->mesh;
    for (int64_t f = 0; f < s->face_count; ++f) pairs[2 * f] = pairs[2 * f + 1] = -1, triangle[f] = -1;
    if (!s->cells_at_nodes) {
        for (int64_t f = 0; f < s->face_count; ++f)
            if (face_cells[2 * f + 1] < 0) {
                pairs[2 * f] = m->edge_nodes[2 * f], pairs[2 * f + 1] = m->edge_nodes[2 * f + 1];
                triangle[f] = face_cells[2 * f];
            }
        return 0;
    }
    /* Triangles per edge: the boundary edges have one. */
    int64_t *uses = calloc((size_t)(m->edge_count > 0 ? m->edge_count : 1), sizeof *uses);
    int64_t *owner = calloc((size_t)(m->edge_count > 0 ? m->edge_count : 1), sizeof *owner);
    if (!uses || !owner) {
        free(uses), free(owner);
        return 1;
    }
    for (int64_t t = 0; t < m->face_count; ++t)
        for (int64_t k = m->face_node_start[t]; k < m->face_node_start[t + 1]; ++k)
            ++uses[m->face_edges[k]], owner[m->face_edges[k]] = t;
    int64_t f = m->edge_count;
    for (int64_t e = 0; e < m->edge_count; ++e)
        for (int half = 0; uses[e] == 1 && half < 2 && f < s->face_count; ++half, ++f)
            pairs[2 * f] = m->edge_nodes[2 * e], pairs[2 * f + 1] = m->edge_nodes[2 * e + 1], triangle[f] = owner[e];
    free(uses), free(owner);
    return f != s->face_count;
}

/* The groups named by one entry of boundaries.open or .wall: a name, or a
 * number (a group of that number, or named so). */
static int matches(const struct config_mesh_group *g, const char *entry) {
    if (g->name[0] && strcmp(g->name, entry) == 0) return 1;
    char *end;
    long number = strtol(entry, &end, 10);
    return *end == '\0' && end != entry && number == g->number;
}

static void list_groups(const struct config_mesh *m, char *out, size_t size) {
    out[0] = '\0';
    for (int k = 0; k < m->group_count; ++k) {
        char entry[CONFIG_NAME_MAX + 40];
        if (m->groups[k].name[0])
            snprintf(entry, sizeof entry, "%s%s (%ld)", k ? ", " : "", m->groups[k].name, m->groups[k].number);
        else
            snprintf(entry, sizeof entry, "%s%ld", k ? ", " : "", m->groups[k].number);
        strncat(out, entry, size - strlen(out) - 1);
    }
}

/* Marks the faces of the named groups as `kind`. */
static int mark_groups(const struct config *c, const struct config_scene *s, const int64_t *pairs, uint8_t *kinds,
                       int kind, char *message, size_t size) {
    const struct config_mesh *m = &s->mesh;
    const char *key = c->groups_open ? "boundaries.open" : "boundaries.wall";
    for (int entry = 0; entry < c->group_count; ++entry) {
        char key_path[64];
        snprintf(key_path, sizeof key_path, "%s[%d]", key, entry);
        int found = 0;
        for (int k = 0; k < m->group_count; ++k) {
            const struct config_mesh_group *g = &m->groups[k];
            if (!matches(g, c->groups[entry])) continue;
            found = 1;
            for (int64_t e = 0; e < g->edge_count; ++e) {
                const int64_t a = g->edge_nodes[2 * e] < g->edge_nodes[2 * e + 1] ? g->edge_nodes[2 * e] : g->edge_nodes[2 * e + 1];
                const int64_t b = g->edge_nodes[2 * e] < g->edge_nodes[2 * e + 1] ? g->edge_nodes[2 * e + 1] : g->edge_nodes[2 * e];
                int hit = 0;
                for (int64_t f = 0; f < s->face_count; ++f) {
                    const int64_t p = pairs[2 * f] < pairs[2 * f + 1] ? pairs[2 * f] : pairs[2 * f + 1];
                    const int64_t q = pairs[2 * f] < pairs[2 * f + 1] ? pairs[2 * f + 1] : pairs[2 * f];
                    if (p == a && q == b) kinds[f] = (uint8_t)kind, hit = 1;
                }
                if (!hit)
                    return scene_refuse(c, c->group_lines[entry], key_path, message, size,
                                        "group \"%s\" of %s holds the edge between nodes %lld and %lld (from 0), which "
                                        "is not on the mesh's domain edge: only edge faces open or close",
                                        c->groups[entry], c->mesh_file, (long long)a, (long long)b);
            }
        }
        if (!found) {
            char groups[1024];
            list_groups(m, groups, sizeof groups);
            return scene_refuse(c, c->group_lines[entry], key_path, message, size, "no group \"%s\" in %s; %s%s",
                                c->groups[entry], c->mesh_file,
                                m->group_count ? "it has (name (number), or the number alone): "
                                               : "it has no groups of edges (gmsh physical curves, UGRID boundary tags)",
                                groups);
        }
    }
    return 0;
}

/* The levels of boundaries.level: {file, variable}, one per face. */
static int levels_from_file(const struct config *c, struct config_scene *s, const int64_t *pairs,
                            const int64_t *triangle, double *levels, char *message, size_t size) {
    double *values = NULL;
    int64_t count = 0;
    enum config_location where;
    if (scene_read_mesh_values(c, s, c->level_file, c->level_variable, c->level_line, "boundaries.level", &values,
                               &count, &where, message, size))
        return 1;
    const struct config_mesh *m = &s->mesh;
    int failed = 0;
    for (int64_t f = 0; f < s->face_count && !failed; ++f) {
        levels[f] = 0.0;
        if (pairs[2 * f] < 0) continue;
        if (where == CONFIG_AT_NODES) {
            /* A face of a mesh: the mean of its nodes; a half of a dual: its own node. */
            levels[f] = s->cells_at_nodes ? values[s->face_cells[2 * f]]
                                          : 0.5 * (values[pairs[2 * f]] + values[pairs[2 * f + 1]]);
        } else if (where == CONFIG_AT_FACES) {
            levels[f] = values[triangle[f]];
        } else {
            int64_t e = 0;
            for (; e < m->file_edge_count; ++e) {
                const int64_t a = m->file_edge_nodes[2 * e], b = m->file_edge_nodes[2 * e + 1];
                if ((a == pairs[2 * f] && b == pairs[2 * f + 1]) || (b == pairs[2 * f] && a == pairs[2 * f + 1])) break;
            }
            if (e == m->file_edge_count)
                failed = scene_refuse(c, c->level_line, "boundaries.level", message, size,
                                      "%s: \"%s\" lies on the file's edges, and none is the edge between nodes %lld "
                                      "and %lld (from 0), on the domain edge",
                                      c->level_file, c->level_variable, (long long)pairs[2 * f],
                                      (long long)pairs[2 * f + 1]);
            else levels[f] = values[e];
        }
    }
    free(values);
    return failed;
}

int scene_set_edges(const struct config *c, struct config_scene *s, char *message, size_t size) {
    if (!s->has_mesh) return 0;
    const int64_t n = s->face_count;
    s->face_cells = malloc((size_t)(2 * n) * sizeof *s->face_cells);
    s->levels = calloc((size_t)n, sizeof *s->levels);
    int64_t *pairs = malloc((size_t)(2 * n) * sizeof *pairs), *triangle = malloc((size_t)n * sizeof *triangle);
    uint8_t *kinds = malloc((size_t)n);
    double *heights = malloc((size_t)s->cell_count * sizeof *heights);
    int failed = !s->face_cells || !s->levels || !pairs || !triangle || !kinds || !heights;
    if (failed) snprintf(message, size, "%s: out of memory", c->path);
    if (!failed) failed = dpsm_get_mesh_faces(s->grid, s->face_cells) != DPSM_OK ||
                          dpsm_get_heights(s->grid, heights) != DPSM_OK || edge_pairs(s, s->face_cells, pairs, triangle);
    if (failed && !message[0]) snprintf(message, size, "%s: the mesh's faces: %s", c->path, dpsm_last_error(s->grid));
    /* Kinds: the edge's, then the named groups the other way. */
    const int edge = c->boundary[DPSM_MESH_EDGE] == DPSM_OPEN ? DPSM_OPEN : DPSM_WALL;
    int any_open = 0;
    if (!failed) {
        for (int64_t f = 0; f < n; ++f) kinds[f] = (uint8_t)edge;
        if (c->group_count)
            failed = mark_groups(c, s, pairs, kinds, c->groups_open ? DPSM_OPEN : DPSM_WALL, message, size);
        for (int64_t f = 0; f < n && !failed; ++f) any_open |= s->face_cells[2 * f + 1] < 0 && kinds[f] == DPSM_OPEN;
        if (!failed && c->group_count && dpsm_set_edge_kinds(s->grid, kinds) != DPSM_OK)
            failed = scene_refuse(c, c->boundaries_line, "boundaries", message, size, "%s", dpsm_last_error(s->grid));
    }
    /* Levels. */
    if (!failed && any_open) {
        switch (c->level_kind) {
            case CONFIG_LEVEL_NONE: {
                /* Level 0 beyond the open faces, as the paper's table: only
                 * where their cells stand at 0 too; else it is asked for. */
                int64_t worst = -1;
                for (int64_t f = 0; f < n; ++f)
                    if (s->face_cells[2 * f + 1] < 0 && kinds[f] == DPSM_OPEN &&
                        (worst < 0 || fabs(heights[s->face_cells[2 * f]]) > fabs(heights[s->face_cells[2 * worst]])))
                        worst = f;
                const double h = heights[s->face_cells[2 * worst]];
                if (h != 0.0)
                    failed = scene_refuse(
                        c, c->boundaries_line, "boundaries", message, size,
                        "the edge is open and no boundaries.level is given, so the level beyond it would be 0, but "
                        "its cells stand up to %g m from 0 (cell %lld, from 0): sand would %s through it. Say what "
                        "lies beyond: boundaries.level: cell (each edge face at its cell's level: nothing leaves "
                        "unless sand slides out), a number, {file: F, variable: V}, or 0 for the paper's table",
                        h, (long long)s->face_cells[2 * worst], h > 0 ? "drain" : "flood in");
                break;
            }
            case CONFIG_LEVEL_NUMBER:
                for (int64_t f = 0; f < n; ++f) s->levels[f] = c->level;
                if (dpsm_set_side_levels(s->grid, DPSM_MESH_EDGE, s->levels) != DPSM_OK)
                    failed = scene_refuse(c, c->level_line, "boundaries.level", message, size, "%s",
                                          dpsm_last_error(s->grid));
                break;
            case CONFIG_LEVEL_CELL:
                s->levels_follow_cells = 1;
                failed = config_scene_before_step(s, message, size);
                break;
            case CONFIG_LEVEL_FILE:
                failed = levels_from_file(c, s, pairs, triangle, s->levels, message, size) ||
                         scene_heights_sign(c, c->level_file, c->level_variable, c->level_positive, c->level_line,
                                            "boundaries.level", s->levels, n, message, size);
                if (!failed && dpsm_set_side_levels(s->grid, DPSM_MESH_EDGE, s->levels) != DPSM_OK)
                    failed = scene_refuse(c, c->level_line, "boundaries.level", message, size, "%s: \"%s\": %s",
                                          c->level_file, c->level_variable, dpsm_last_error(s->grid));
                break;
        }
    }
    free(pairs), free(triangle), free(kinds), free(heights);
    return failed;
}

int config_scene_before_step(struct config_scene *s, char *message, size_t size) {
    if (!s->levels_follow_cells) return 0;
    double *heights = malloc((size_t)s->cell_count * sizeof *heights);
    if (!heights || dpsm_get_heights(s->grid, heights) != DPSM_OK) {
        free(heights);
        snprintf(message, size, "the heights for the edge's levels: %s", dpsm_last_error(s->grid));
        return 1;
    }
    for (int64_t f = 0; f < s->face_count; ++f)
        s->levels[f] = s->face_cells[2 * f + 1] < 0 ? heights[s->face_cells[2 * f]] : 0.0;
    free(heights);
    if (dpsm_set_side_levels(s->grid, DPSM_MESH_EDGE, s->levels) != DPSM_OK) {
        snprintf(message, size, "the edge's levels: %s", dpsm_last_error(s->grid));
        return 1;
    }
    return 0;
}
