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
    static const char *const keys_mesh[] = {"kind", "file", NULL};
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
    } else if (strcmp(kind, "mesh") == 0) {
        c->grid_kind = CONFIG_GRID_MESH;
        if (check_keys(r, grid, "grid", keys_mesh, "a mesh") || read_file_name(r, grid, "grid", "file", c->mesh_file))
            return 1;
    } else {
        return refuse(r, kind_node, "grid.kind", "expected 1d, 2d, axisymmetric or mesh, got \"%s\"", kind);
    }
    return 0;
}

static int read_boundaries(struct reader *r, yaml_node_t *sides, struct config *c) {
    if (expect_mapping(r, sides, "boundaries")) return 1;
    static const char *const names[CONFIG_SIDES] = {"xmin", "xmax", "ymin", "ymax", "edge"};
    static const char *const keys_1d[] = {"xmin", "xmax", NULL};
    static const char *const keys_2d[] = {"xmin", "xmax", "ymin", "ymax", NULL};
    static const char *const keys_axisymmetric[] = {"xmax", NULL};
    static const char *const keys_mesh[] = {"edge", NULL};
    const char *const *allowed = c->grid_kind == CONFIG_GRID_1D             ? keys_1d
                                 : c->grid_kind == CONFIG_GRID_2D           ? keys_2d
                                 : c->grid_kind == CONFIG_GRID_AXISYMMETRIC ? keys_axisymmetric
                                                                            : keys_mesh;
    static const char *const kind_names[] = {"a 1d grid", "a 2d grid", "an axisymmetric grid (its xmin is the axis)",
                                             "a mesh"};
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
    return 0;
}

/* initial: {scene: column|cone, radius, height} | {constant} | {file, variable};
 * source: {constant} | {file, variable}. */
static int read_field(struct reader *r, yaml_node_t *node, const char *name, int scenes_allowed,
                      struct config_field *field) {
    if (expect_mapping(r, node, name)) return 1;
    static const char *const keys_scene[] = {"scene", "radius", "height", NULL};
    static const char *const keys_constant[] = {"constant", NULL};
    static const char *const keys_file[] = {"file", "variable", NULL};
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
        return check_keys(r, node, name, keys_file, "a file") || read_file_name(r, node, name, "file", field->file) ||
               read_word(r, node, name, "variable", field->variable, sizeof field->variable, NULL);
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
