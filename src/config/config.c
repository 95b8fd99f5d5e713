/* Reads the YAML run configuration with libyaml's document API: every node
 * keeps its line, so each refusal names the file, the line, the key path and
 * what was wrong, in the words of the person who wrote the file. */
#include "config/config.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>

struct reader {
    const char *path;
    yaml_document_t *document;
    char *message;
    size_t message_size;
};

static unsigned long line_of(const yaml_node_t *node) { return (unsigned long)node->start_mark.line + 1; }

/* Writes "file:line: key.path: problem" and returns 1, the failure status. */
static int refuse(struct reader *r, const yaml_node_t *node, const char *key_path, const char *format, ...) {
    int used = snprintf(r->message, r->message_size, "%s:%lu: %s: ", r->path, node ? line_of(node) : 1ul, key_path);
    if (used < 0 || (size_t)used >= r->message_size) return 1;
    va_list args;
    va_start(args, format);
    vsnprintf(r->message + used, r->message_size - (size_t)used, format, args);
    va_end(args);
    return 1;
}

static void join_key(char *out, size_t size, const char *parent, const char *key) {
    if (parent[0]) snprintf(out, size, "%s.%s", parent, key);
    else snprintf(out, size, "%s", key);
}

static const char *scalar_text(const yaml_node_t *node) { return (const char *)node->data.scalar.value; }

/* How a value that is not what was expected reads in a message. */
static void describe(const yaml_node_t *node, char *out, size_t size) {
    if (node->type == YAML_MAPPING_NODE) snprintf(out, size, "a mapping");
    else if (node->type == YAML_SEQUENCE_NODE) snprintf(out, size, "a list");
    else snprintf(out, size, "\"%s\"", scalar_text(node));
}

static yaml_node_t *lookup(struct reader *r, yaml_node_t *mapping, const char *key) {
    for (yaml_node_pair_t *pair = mapping->data.mapping.pairs.start; pair < mapping->data.mapping.pairs.top; ++pair) {
        yaml_node_t *k = yaml_document_get_node(r->document, pair->key);
        if (k && k->type == YAML_SCALAR_NODE && strcmp(scalar_text(k), key) == 0)
            return yaml_document_get_node(r->document, pair->value);
    }
    return NULL;
}

/* Refuses keys outside `allowed` (a NULL-terminated list), keys that are not
 * plain words and keys given twice; `what` says whose keys these are. */
static int check_keys(struct reader *r, yaml_node_t *mapping, const char *parent, const char *const *allowed,
                      const char *what) {
    for (yaml_node_pair_t *pair = mapping->data.mapping.pairs.start; pair < mapping->data.mapping.pairs.top; ++pair) {
        yaml_node_t *key = yaml_document_get_node(r->document, pair->key);
        if (key->type != YAML_SCALAR_NODE)
            return refuse(r, key, parent[0] ? parent : "(top level)", "a key must be a plain word");
        char key_path[512];
        join_key(key_path, sizeof key_path, parent, scalar_text(key));
        int known = 0;
        for (const char *const *a = allowed; *a; ++a) known |= strcmp(*a, scalar_text(key)) == 0;
        if (!known) {
            char list[512] = "";
            for (const char *const *a = allowed; *a; ++a) {
                strncat(list, *a, sizeof list - strlen(list) - 1);
                if (a[1]) strncat(list, ", ", sizeof list - strlen(list) - 1);
            }
            return refuse(r, key, key_path, "unknown key%s%s (expected one of: %s)", what ? " for " : "",
                          what ? what : "", list);
        }
        for (yaml_node_pair_t *earlier = mapping->data.mapping.pairs.start; earlier < pair; ++earlier) {
            yaml_node_t *other = yaml_document_get_node(r->document, earlier->key);
            if (other->type == YAML_SCALAR_NODE && strcmp(scalar_text(other), scalar_text(key)) == 0)
                return refuse(r, key, key_path, "given twice (first on line %lu)", line_of(other));
        }
    }
    return 0;
}

/* The value of a required key; refuses at the mapping's line when it is missing. */
static int require(struct reader *r, yaml_node_t *mapping, const char *parent, const char *key, yaml_node_t **value) {
    *value = lookup(r, mapping, key);
    if (*value) return 0;
    char key_path[512];
    join_key(key_path, sizeof key_path, parent, key);
    return refuse(r, mapping, key_path, "missing (a required key)");
}

static int expect_mapping(struct reader *r, yaml_node_t *node, const char *key_path) {
    if (node->type == YAML_MAPPING_NODE) return 0;
    char got[300];
    describe(node, got, sizeof got);
    return refuse(r, node, key_path, "expected a mapping of keys, got %s", got);
}

static int read_positive_integer(struct reader *r, yaml_node_t *mapping, const char *parent, const char *key,
                                 int64_t *out) {
    yaml_node_t *value;
    if (require(r, mapping, parent, key, &value)) return 1;
    char key_path[512], got[300];
    join_key(key_path, sizeof key_path, parent, key);
    describe(value, got, sizeof got);
    if (value->type != YAML_SCALAR_NODE) return refuse(r, value, key_path, "expected a positive integer, got %s", got);
    const char *text = scalar_text(value);
    char *end;
    errno = 0;
    long long parsed = strtoll(text, &end, 10);
    if (end == text || *end != '\0' || errno == ERANGE || parsed <= 0)
        return refuse(r, value, key_path, "expected a positive integer, got %s", got);
    *out = (int64_t)parsed;
    return 0;
}

/* A finite number; `positive` also refuses zero and negative ones. */
static int parse_number(struct reader *r, yaml_node_t *value, const char *key_path, int positive, double *out) {
    const char *expected = positive ? "a positive number" : "a number";
    char got[300];
    describe(value, got, sizeof got);
    if (value->type != YAML_SCALAR_NODE) return refuse(r, value, key_path, "expected %s, got %s", expected, got);
    const char *text = scalar_text(value);
    char *end;
    double parsed = strtod(text, &end);
    if (end == text || *end != '\0' || !isfinite(parsed) || (positive && !(parsed > 0)))
        return refuse(r, value, key_path, "expected %s, got %s", expected, got);
    *out = parsed;
    return 0;
}

static int read_number(struct reader *r, yaml_node_t *mapping, const char *parent, const char *key, int positive,
                       double *out) {
    yaml_node_t *value;
    if (require(r, mapping, parent, key, &value)) return 1;
    char key_path[512];
    join_key(key_path, sizeof key_path, parent, key);
    return parse_number(r, value, key_path, positive, out);
}

static int read_word(struct reader *r, yaml_node_t *mapping, const char *parent, const char *key, char *out,
                     size_t size, yaml_node_t **node) {
    yaml_node_t *value;
    if (require(r, mapping, parent, key, &value)) return 1;
    char key_path[512], got[300];
    join_key(key_path, sizeof key_path, parent, key);
    describe(value, got, sizeof got);
    if (value->type != YAML_SCALAR_NODE || scalar_text(value)[0] == '\0')
        return refuse(r, value, key_path, "expected a word or a file name, got %s", got);
    if (strlen(scalar_text(value)) >= size) return refuse(r, value, key_path, "longer than %zu characters", size - 1);
    snprintf(out, size, "%s", scalar_text(value));
    if (node) *node = value;
    return 0;
}

/* A file named in the configuration, taken from the configuration's folder
 * unless it is absolute: a configuration and its inputs move together. */
static int read_file_name(struct reader *r, yaml_node_t *mapping, const char *parent, const char *key, char *out) {
    char name[CONFIG_PATH_MAX];
    yaml_node_t *node;
    if (read_word(r, mapping, parent, key, name, sizeof name, &node)) return 1;
    const char *slash = strrchr(r->path, '/');
    int folder_length = name[0] == '/' || !slash ? 0 : (int)(slash - r->path + 1);
    if ((size_t)folder_length + strlen(name) >= CONFIG_PATH_MAX) {
        char key_path[512];
        join_key(key_path, sizeof key_path, parent, key);
        return refuse(r, node, key_path, "the path is too long");
    }
    snprintf(out, CONFIG_PATH_MAX, "%.*s%s", folder_length, r->path, name);
    return 0;
}

static int read_grid(struct reader *r, yaml_node_t *grid, struct config *c) {
    if (expect_mapping(r, grid, "grid")) return 1;
    char kind[32];
    yaml_node_t *kind_node;
    if (read_word(r, grid, "grid", "kind", kind, sizeof kind, &kind_node)) return 1;
    static const char *const keys_1d[] = {"kind", "nx", "dx", NULL};
    static const char *const keys_2d[] = {"kind", "nx", "ny", "dx", "dy", NULL};
    static const char *const keys_axisymmetric[] = {"kind", "nr", "dr", NULL};
    static const char *const keys_mesh[] = {"kind", "file", "topology", "coordinates", NULL};
    if (strcmp(kind, "1d") == 0) {
        c->grid_kind = CONFIG_GRID_1D;
        if (check_keys(r, grid, "grid", keys_1d, "a 1d grid") || read_positive_integer(r, grid, "grid", "nx", &c->nx) ||
            read_number(r, grid, "grid", "dx", 1, &c->dx))
            return 1;
        c->ny = 1;
        c->dy = c->dx;
    } else if (strcmp(kind, "2d") == 0) {
        c->grid_kind = CONFIG_GRID_2D;
        if (check_keys(r, grid, "grid", keys_2d, "a 2d grid") || read_positive_integer(r, grid, "grid", "nx", &c->nx) ||
            read_positive_integer(r, grid, "grid", "ny", &c->ny) || read_number(r, grid, "grid", "dx", 1, &c->dx) ||
            read_number(r, grid, "grid", "dy", 1, &c->dy))
            return 1;
    } else if (strcmp(kind, "axisymmetric") == 0) {
        c->grid_kind = CONFIG_GRID_AXISYMMETRIC;
        if (check_keys(r, grid, "grid", keys_axisymmetric, "an axisymmetric grid") ||
            read_positive_integer(r, grid, "grid", "nr", &c->nx) || read_number(r, grid, "grid", "dr", 1, &c->dx))
            return 1;
        c->ny = 1;
        c->dy = c->dx;
    } else if (strcmp(kind, "mesh") == 0 || strcmp(kind, "dual_mesh") == 0) {
        c->grid_kind = strcmp(kind, "mesh") == 0 ? CONFIG_GRID_MESH : CONFIG_GRID_DUAL_MESH;
        if (check_keys(r, grid, "grid", keys_mesh, c->grid_kind == CONFIG_GRID_MESH ? "a mesh" : "a dual mesh") ||
            read_file_name(r, grid, "grid", "file", c->mesh_file))
            return 1;
        if (lookup(r, grid, "topology") &&
            read_word(r, grid, "grid", "topology", c->topology, sizeof c->topology, NULL))
            return 1;
        if (lookup(r, grid, "coordinates")) {
            char word[32];
            yaml_node_t *node;
            if (read_word(r, grid, "grid", "coordinates", word, sizeof word, &node)) return 1;
            if (strcmp(word, "geographic") == 0) c->coordinates = CONFIG_COORDINATES_GEOGRAPHIC;
            else if (strcmp(word, "projected") == 0) c->coordinates = CONFIG_COORDINATES_PROJECTED;
            else
                return refuse(r, node, "grid.coordinates",
                              "expected geographic (longitude and latitude in degrees) or projected (metres), got "
                              "\"%s\"", word);
        }
    } else {
        return refuse(r, kind_node, "grid.kind", "expected 1d, 2d, axisymmetric, mesh or dual_mesh, got \"%s\"", kind);
    }
    c->grid_line = line_of(grid);
    return 0;
}

/* The optional `positive: up | down` of a field read from a file: whether
 * its values are elevations or depths (below a datum, which dpsm negates). */
static int read_positive(struct reader *r, yaml_node_t *mapping, const char *parent, int *positive) {
    *positive = 0;
    if (!lookup(r, mapping, "positive")) return 0;
    char word[32], key_path[64];
    yaml_node_t *node;
    if (read_word(r, mapping, parent, "positive", word, sizeof word, &node)) return 1;
    join_key(key_path, sizeof key_path, parent, "positive");
    if (strcmp(word, "up") == 0) *positive = 1;
    else if (strcmp(word, "down") == 0) *positive = -1;
    else
        return refuse(r, node, key_path,
                      "expected up (the values are elevations) or down (they are depths: dpsm takes their negative), "
                      "got \"%s\"", word);
    return 0;
}

/* boundaries.level: 0, cell, a number or {file, variable}. */
static int read_level(struct reader *r, yaml_node_t *node, struct config *c) {
    c->level_line = line_of(node);
    if (node->type == YAML_MAPPING_NODE) {
        static const char *const keys[] = {"file", "variable", "positive", NULL};
        c->level_kind = CONFIG_LEVEL_FILE;
        return check_keys(r, node, "boundaries.level", keys, "a field") ||
               read_file_name(r, node, "boundaries.level", "file", c->level_file) ||
               read_word(r, node, "boundaries.level", "variable", c->level_variable, sizeof c->level_variable, NULL) ||
               read_positive(r, node, "boundaries.level", &c->level_positive);
    }
    if (node->type == YAML_SCALAR_NODE && strcmp(scalar_text(node), "cell") == 0) {
        c->level_kind = CONFIG_LEVEL_CELL;
        return 0;
    }
    char got[300];
    describe(node, got, sizeof got);
    if (node->type != YAML_SCALAR_NODE)
        return refuse(r, node, "boundaries.level", "expected 0, cell, a number or {file, variable}, got %s", got);
    const char *text = scalar_text(node);
    char *end;
    double value = strtod(text, &end);
    if (end == text || *end != '\0' || !isfinite(value) || fabs(value) > 1e50)
        return refuse(r, node, "boundaries.level", "expected 0, cell, a number or {file, variable}, got %s", got);
    c->level_kind = CONFIG_LEVEL_NUMBER;
    c->level = value;
    return 0;
}

/* boundaries.open or .wall: a list of group names or numbers. */
static int read_groups(struct reader *r, yaml_node_t *node, const char *key, struct config *c) {
    char key_path[64], got[300];
    snprintf(key_path, sizeof key_path, "boundaries.%s", key);
    describe(node, got, sizeof got);
    if (node->type == YAML_SCALAR_NODE) { /* one name alone: a list of one */
        if (!scalar_text(node)[0]) return refuse(r, node, key_path, "expected a list of group names or numbers");
        snprintf(c->groups[0], CONFIG_NAME_MAX, "%s", scalar_text(node));
        c->group_lines[0] = line_of(node);
        c->group_count = 1;
        return 0;
    }
    if (node->type != YAML_SEQUENCE_NODE)
        return refuse(r, node, key_path, "expected a list of group names or numbers (gmsh physical groups, UGRID "
                                         "boundary tags), got %s", got);
    int n = 0;
    for (yaml_node_item_t *item = node->data.sequence.items.start; item < node->data.sequence.items.top; ++item) {
        yaml_node_t *entry = yaml_document_get_node(r->document, *item);
        char entry_path[96];
        snprintf(entry_path, sizeof entry_path, "%s[%d]", key_path, n);
        if (!entry || entry->type != YAML_SCALAR_NODE || !scalar_text(entry)[0])
            return refuse(r, entry ? entry : node, entry_path, "expected a group's name or number");
        if (n == CONFIG_GROUPS_MAX) return refuse(r, entry, entry_path, "more than %d groups", CONFIG_GROUPS_MAX);
        if (strlen(scalar_text(entry)) >= CONFIG_NAME_MAX)
            return refuse(r, entry, entry_path, "longer than %d characters", CONFIG_NAME_MAX - 1);
        snprintf(c->groups[n], CONFIG_NAME_MAX, "%s", scalar_text(entry));
        c->group_lines[n++] = line_of(entry);
    }
    if (n == 0) return refuse(r, node, key_path, "an empty list: name the groups, or leave the key out");
    c->group_count = n;
    return 0;
}

static int read_boundaries(struct reader *r, yaml_node_t *sides, struct config *c) {
    if (expect_mapping(r, sides, "boundaries")) return 1;
    static const char *const names[CONFIG_SIDES] = {"xmin", "xmax", "ymin", "ymax", "edge"};
    static const char *const keys_1d[] = {"xmin", "xmax", NULL};
    static const char *const keys_2d[] = {"xmin", "xmax", "ymin", "ymax", NULL};
    static const char *const keys_axisymmetric[] = {"xmax", NULL};
    static const char *const keys_mesh[] = {"edge", "level", "open", "wall", NULL};
    const char *const *allowed = c->grid_kind == CONFIG_GRID_1D             ? keys_1d
                                 : c->grid_kind == CONFIG_GRID_2D           ? keys_2d
                                 : c->grid_kind == CONFIG_GRID_AXISYMMETRIC ? keys_axisymmetric
                                                                            : keys_mesh;
    static const char *const kind_names[] = {"a 1d grid", "a 2d grid", "an axisymmetric grid (its xmin is the axis)",
                                             "a mesh", "a dual mesh"};
    c->boundaries_line = line_of(sides);
    if (check_keys(r, sides, "boundaries", allowed, kind_names[c->grid_kind])) return 1;
    for (int side = 0; side < CONFIG_SIDES; ++side) {
        if (!lookup(r, sides, names[side])) continue;
        char word[32];
        yaml_node_t *node;
        if (read_word(r, sides, "boundaries", names[side], word, sizeof word, &node)) return 1;
        if (strcmp(word, "wall") == 0) c->boundary[side] = DPSM_WALL;
        else if (strcmp(word, "open") == 0) c->boundary[side] = DPSM_OPEN;
        else {
            char key_path[64];
            join_key(key_path, sizeof key_path, "boundaries", names[side]);
            return refuse(r, node, key_path, "expected wall or open, got \"%s\"", word);
        }
    }
    yaml_node_t *node;
    if ((node = lookup(r, sides, "level")) && read_level(r, node, c)) return 1;
    yaml_node_t *open = lookup(r, sides, "open"), *wall = lookup(r, sides, "wall");
    int edge_open = c->boundary[DPSM_MESH_EDGE] == DPSM_OPEN;
    if (open && wall)
        return refuse(r, wall, "boundaries.wall", "give boundaries.open (with edge: wall, the default) or "
                                                  "boundaries.wall (with edge: open), not both");
    if (open && edge_open)
        return refuse(r, open, "boundaries.open", "the edge is open already (edge: open); name the groups that are "
                                                  "walls with boundaries.wall, or say edge: wall");
    if (wall && !edge_open)
        return refuse(r, wall, "boundaries.wall", "the edge is a wall already (edge: %s); say edge: open and name "
                                                  "the groups that are walls, or name the open ones with "
                                                  "boundaries.open",
                      c->boundary[DPSM_MESH_EDGE] == DPSM_WALL ? "wall" : "wall, the default");
    if (open || wall) {
        c->groups_open = open != NULL;
        if (read_groups(r, open ? open : wall, open ? "open" : "wall", c)) return 1;
    }
    if (node && !edge_open && !open)
        return refuse(r, node, "boundaries.level", "no edge is open (edge: wall%s): say edge: open, or open groups of "
                                                   "edges with boundaries.open, or leave the level out",
                      c->boundary[DPSM_MESH_EDGE] == DPSM_WALL ? "" : ", the default");
    return 0;
}

/* initial: {scene: column|cone, radius, height} | {constant} | {file, variable};
 * source: {constant} | {file, variable}. */
static int read_field(struct reader *r, yaml_node_t *node, const char *name, int scenes_allowed,
                      struct config_field *field) {
    if (expect_mapping(r, node, name)) return 1;
    static const char *const keys_scene[] = {"scene", "radius", "height", "centre", NULL};
    static const char *const keys_constant[] = {"constant", NULL};
    static const char *const keys_file[] = {"file", "variable", NULL};
    static const char *const keys_heights_file[] = {"file", "variable", "positive", NULL};
    if (scenes_allowed && lookup(r, node, "scene")) {
        char scene[32];
        yaml_node_t *scene_node;
        char key_path[64];
        join_key(key_path, sizeof key_path, name, "scene");
        if (check_keys(r, node, name, keys_scene, "a scene") ||
            read_word(r, node, name, "scene", scene, sizeof scene, &scene_node))
            return 1;
        if (strcmp(scene, "column") == 0) field->kind = CONFIG_FIELD_COLUMN;
        else if (strcmp(scene, "cone") == 0) field->kind = CONFIG_FIELD_CONE;
        else return refuse(r, scene_node, key_path, "expected column or cone, got \"%s\"", scene);
        field->line = line_of(node);
        yaml_node_t *centre = lookup(r, node, "centre");
        if (centre) {
            char centre_path[64], got[300];
            join_key(centre_path, sizeof centre_path, name, "centre");
            describe(centre, got, sizeof got);
            if (centre->type != YAML_SEQUENCE_NODE ||
                centre->data.sequence.items.top - centre->data.sequence.items.start != 2)
                return refuse(r, centre, centre_path, "expected [x, y], got %s", got);
            for (int k = 0; k < 2; ++k) {
                yaml_node_t *v = yaml_document_get_node(r->document, centre->data.sequence.items.start[k]);
                char item_path[80];
                snprintf(item_path, sizeof item_path, "%s[%d]", centre_path, k);
                if (parse_number(r, v, item_path, 0, &field->centre[k])) return 1;
            }
            field->has_centre = 1;
        }
        return read_number(r, node, name, "radius", 1, &field->radius) ||
               read_number(r, node, name, "height", 0, &field->height);
    }
    if (lookup(r, node, "constant")) {
        field->kind = CONFIG_FIELD_CONSTANT;
        return check_keys(r, node, name, keys_constant, "a constant") ||
               read_number(r, node, name, "constant", 0, &field->value);
    }
    if (lookup(r, node, "file")) {
        field->kind = CONFIG_FIELD_FILE;
        field->line = line_of(node);
        /* Heights (initial) may be stored as depths; a source is a rate. */
        return check_keys(r, node, name, scenes_allowed ? keys_heights_file : keys_file, "a file") ||
               read_file_name(r, node, name, "file", field->file) ||
               read_word(r, node, name, "variable", field->variable, sizeof field->variable, NULL) ||
               (scenes_allowed && read_positive(r, node, name, &field->positive));
    }
    return refuse(r, node, name, scenes_allowed ? "expected a scene (column or cone), a constant or a file"
                                                : "expected a constant or a file");
}

static int read_document(struct reader *r, struct config *c) {
    yaml_node_t *root = yaml_document_get_root_node(r->document);
    if (!root) return refuse(r, NULL, "(top level)", "the file holds no configuration");
    if (expect_mapping(r, root, "(top level)")) return 1;
    static const char *const top[] = {"grid", "repose_angle", "mobility", "boundaries", "initial",
                                      "source", "time",         "output",   NULL};
    if (check_keys(r, root, "", top, NULL)) return 1;

    yaml_node_t *node;
    if (require(r, root, "", "grid", &node) || read_grid(r, node, c)) return 1;
    if ((node = lookup(r, root, "repose_angle"))) {
        if (parse_number(r, node, "repose_angle", 1, &c->repose_angle_degrees)) return 1;
        if (!(c->repose_angle_degrees < 90))
            return refuse(r, node, "repose_angle", "expected degrees between 0 and 90, got \"%s\"", scalar_text(node));
        c->has_repose_angle = 1;
    }
    if ((node = lookup(r, root, "mobility"))) {
        if (parse_number(r, node, "mobility", 1, &c->mobility)) return 1;
        c->has_mobility = 1;
    }
    if ((node = lookup(r, root, "boundaries")) && read_boundaries(r, node, c)) return 1;
    if (require(r, root, "", "initial", &node) || read_field(r, node, "initial", 1, &c->initial)) return 1;
    if ((node = lookup(r, root, "source")) && read_field(r, node, "source", 0, &c->source)) return 1;

    static const char *const time_keys[] = {"step", "end", NULL};
    if (require(r, root, "", "time", &node) || expect_mapping(r, node, "time") ||
        check_keys(r, node, "time", time_keys, NULL) || read_number(r, node, "time", "step", 1, &c->time_step) ||
        read_number(r, node, "time", "end", 1, &c->time_end))
        return 1;

    static const char *const output_keys[] = {"file", "every", NULL};
    if ((node = lookup(r, root, "output"))) {
        if (expect_mapping(r, node, "output") || check_keys(r, node, "output", output_keys, NULL) ||
            read_file_name(r, node, "output", "file", c->output_file) ||
            read_number(r, node, "output", "every", 1, &c->output_every))
            return 1;
        c->has_output = 1;
    }
    return 0;
}

int config_read(const char *path, struct config *config, char *message, size_t message_size) {
    if (!path || !config) {
        snprintf(message, message_size, "config_read: no path or no configuration to fill");
        return 1;
    }
    struct config c;
    memset(&c, 0, sizeof c);
    for (int side = 0; side < CONFIG_SIDES; ++side) c.boundary[side] = CONFIG_SIDE_DEFAULT;
    c.source.kind = CONFIG_FIELD_NONE;
    if (strlen(path) >= sizeof c.path) {
        snprintf(message, message_size, "%.100s...: the path of the configuration is too long", path);
        return 1;
    }
    snprintf(c.path, sizeof c.path, "%s", path);

    FILE *file = fopen(path, "rb");
    if (!file) {
        snprintf(message, message_size, "%s: cannot open the configuration: %s", path, strerror(errno));
        return 1;
    }
    yaml_parser_t parser;
    yaml_document_t document;
    int status = 1;
    if (!yaml_parser_initialize(&parser)) {
        snprintf(message, message_size, "%s: out of memory starting the YAML reader", path);
        fclose(file);
        return 1;
    }
    yaml_parser_set_input_file(&parser, file);
    if (!yaml_parser_load(&parser, &document)) {
        snprintf(message, message_size, "%s:%lu: not valid YAML: %s", path,
                 (unsigned long)parser.problem_mark.line + 1, parser.problem ? parser.problem : "unreadable");
    } else {
        struct reader r = {c.path, &document, message, message_size};
        status = read_document(&r, &c);
        yaml_document_delete(&document);
    }
    yaml_parser_delete(&parser);
    fclose(file);
    if (status == 0) *config = c;
    return status;
}
