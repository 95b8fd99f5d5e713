/* gmsh meshes, MSH 2.2 and 4.1 in ASCII (the formats gmsh writes by
 * default and with -format msh22): the 2D elements are the cells, in the
 * file's order (triangles, quadrangles, and the corners of higher-order
 * ones); the lines carry the physical groups of the boundary curves, by
 * number and, where $PhysicalNames gives one, by name. Only the nodes the
 * cells use are kept, in the order of their tags; z is not read. */
#include "config/mesh_readers.h"

#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The file in memory, read line by line (each line ends in '\0'). */
struct text {
    const char *path;
    char *data;
    size_t size, at;
    long line;
    char *message;
    size_t message_size;
};

static int fail(struct text *t, const char *format, const char *what) {
    char detail[512];
    snprintf(detail, sizeof detail, format, what);
    snprintf(t->message, t->message_size, "%s:%ld: %s", t->path, t->line, detail);
    return 1;
}

/* The next line with something on it, or NULL at the end. */
static char *next_line(struct text *t) {
    while (t->at < t->size) {
        char *line = t->data + t->at;
        char *end = memchr(line, '\n', t->size - t->at);
        size_t length = end ? (size_t)(end - line) : t->size - t->at;
        t->at += length + (end ? 1 : 0);
        ++t->line;
        line[length] = '\0';
        if (length && line[length - 1] == '\r') line[length - 1] = '\0';
        char *p = line;
        while (isspace((unsigned char)*p)) ++p;
        if (*p) return p;
    }
    return NULL;
}

/* Reads up to `max` integers from a line; returns how many. */
static int integers(const char *line, long long *out, int max) {
    int n = 0;
    const char *p = line;
    while (n < max) {
        char *end;
        errno = 0;
        long long v = strtoll(p, &end, 10);
        if (end == p || errno) break;
        out[n++] = v;
        p = end;
        while (isspace((unsigned char)*p)) ++p;
        if (*p == '\0') break;
    }
    return n;
}

/* The element types gmsh numbers: nodes, dimension, corners (0: not a cell or line). */
struct element_type {
    int nodes, dimension, corners;
};

static struct element_type type_of(long long type) {
    switch (type) {
        case 1: return (struct element_type){2, 1, 2};
        case 8: return (struct element_type){3, 1, 2};
        case 26: return (struct element_type){4, 1, 2};
        case 27: return (struct element_type){5, 1, 2};
        case 28: return (struct element_type){6, 1, 2};
        case 15: return (struct element_type){1, 0, 0};
        case 2: return (struct element_type){3, 2, 3};
        case 9: return (struct element_type){6, 2, 3};
        case 20: return (struct element_type){9, 2, 3};
        case 21: return (struct element_type){10, 2, 3};
        case 22: return (struct element_type){12, 2, 3};
        case 23: return (struct element_type){15, 2, 3};
        case 24: return (struct element_type){15, 2, 3};
        case 25: return (struct element_type){21, 2, 3};
        case 3: return (struct element_type){4, 2, 4};
        case 10: return (struct element_type){9, 2, 4};
        case 16: return (struct element_type){8, 2, 4};
        case 36: return (struct element_type){16, 2, 4};
        case 37: return (struct element_type){25, 2, 4};
        case 38: return (struct element_type){36, 2, 4};
        case 4: case 5: case 6: case 7: case 11: case 12: case 13: case 14: case 17: case 18: case 19: case 29:
        case 30: case 31: return (struct element_type){0, 3, 0};
        default: return (struct element_type){0, -1, 0};
    }
}

/* A growing array of int64_t or of doubles. */
struct list {
    void *items;
    size_t count, room, item_size;
};

static int push(struct list *l, const void *item) {
    if (l->count == l->room) {
        size_t room = l->room ? 2 * l->room : 256;
        void *items = realloc(l->items, room * l->item_size);
        if (!items) return 1;
        l->items = items, l->room = room;
    }
    memcpy((char *)l->items + l->count * l->item_size, item, l->item_size);
    ++l->count;
    return 0;
}

struct node {
    long long tag;
    double x, y;
    int64_t index; /* its place among the kept nodes, -1 until a cell uses it */
};

static int by_tag(const void *a, const void *b) {
    const struct node *x = a, *y = b;
    return (x->tag > y->tag) - (x->tag < y->tag);
}

/* An entity's physical groups (MSH 4.1's $Entities). */
struct entity {
    int dimension;
    long long tag;
    int count;
    long long physical[8];
};

/* One edge of a line element in a physical group. */
struct tagged_edge {
    long long physical;
    long long a, b; /* node tags */
};

struct reading {
    struct list nodes, names_dim, names_tag, names_text, entities, cell_start, cell_tags, edges;
    int version; /* 2 or 4 */
};

static struct node *find_node(struct reading *r, long long tag) {
    struct node key = {tag, 0, 0, 0};
    return bsearch(&key, r->nodes.items, r->nodes.count, sizeof key, by_tag);
}

static int read_physical_names(struct text *t, struct reading *r) {
    char *line = next_line(t);
    long long n;
    if (!line || integers(line, &n, 1) != 1 || n < 0) return fail(t, "%s", "$PhysicalNames: expected a count");
    for (long long k = 0; k < n; ++k) {
        line = next_line(t);
        long long dim_tag[2];
        const char *quote = line ? strchr(line, '"') : NULL;
        const char *close = quote ? strchr(quote + 1, '"') : NULL;
        if (!line || integers(line, dim_tag, 2) != 2 || !close)
            return fail(t, "%s", "$PhysicalNames: expected: dimension tag \"name\"");
        char name[CONFIG_NAME_MAX];
        snprintf(name, sizeof name, "%.*s", (int)(close - quote - 1), quote + 1);
        int dimension = (int)dim_tag[0];
        if (push(&r->names_dim, &dimension) || push(&r->names_tag, &dim_tag[1]) || push(&r->names_text, name))
            return fail(t, "%s", "out of memory");
    }
    return 0;
}

static int read_entities(struct text *t, struct reading *r) {
    char *line = next_line(t);
    long long counts[4];
    if (!line || integers(line, counts, 4) != 4) return fail(t, "%s", "$Entities: expected four counts");
    for (int d = 0; d < 4; ++d)
        for (long long k = 0; k < counts[d]; ++k) {
            line = next_line(t);
            if (!line) return fail(t, "%s", "$Entities: the file ends inside the section");
            /* tag, then 3 (points) or 6 (others) coordinates, then the physical tags. */
            char *p = line, *end;
            struct entity e = {d, strtoll(p, &end, 10), 0, {0}};
            p = end;
            for (int c = 0; c < (d == 0 ? 3 : 6); ++c) {
                strtod(p, &end);
                if (end == p) return fail(t, "%s", "$Entities: a bounding box is short");
                p = end;
            }
            long long n = strtoll(p, &end, 10);
            if (end == p || n < 0) return fail(t, "%s", "$Entities: expected the number of physical tags");
            p = end;
            for (long long j = 0; j < n; ++j) {
                long long tag = strtoll(p, &end, 10);
                if (end == p) return fail(t, "%s", "$Entities: a physical tag is missing");
                p = end;
                if (e.count < 8) e.physical[e.count++] = tag < 0 ? -tag : tag;
            }
            if (push(&r->entities, &e)) return fail(t, "%s", "out of memory");
        }
    return 0;
}

static int read_nodes(struct text *t, struct reading *r) {
    char *line = next_line(t);
    long long head[4];
    if (r->version == 2) {
        if (!line || integers(line, head, 1) != 1 || head[0] < 0) return fail(t, "%s", "$Nodes: expected a count");
        for (long long k = 0; k < head[0]; ++k) {
            line = next_line(t);
            char *end;
            struct node n = {0, 0, 0, -1};
            n.tag = line ? strtoll(line, &end, 10) : 0;
            if (!line || end == line) return fail(t, "%s", "$Nodes: expected: tag x y z");
            char *p = end;
            n.x = strtod(p, &end);
            if (end == p) return fail(t, "%s", "$Nodes: expected: tag x y z");
            p = end;
            n.y = strtod(p, &end);
            if (end == p) return fail(t, "%s", "$Nodes: expected: tag x y z");
            if (push(&r->nodes, &n)) return fail(t, "%s", "out of memory");
        }
    } else {
        if (!line || integers(line, head, 4) != 4) return fail(t, "%s", "$Nodes: expected: blocks nodes min max");
        for (long long b = 0; b < head[0]; ++b) {
            long long block[4];
            line = next_line(t);
            if (!line || integers(line, block, 4) != 4)
                return fail(t, "%s", "$Nodes: expected: dimension tag parametric count");
            const size_t first = r->nodes.count;
            for (long long k = 0; k < block[3]; ++k) {
                long long tag;
                line = next_line(t);
                if (!line || integers(line, &tag, 1) != 1) return fail(t, "%s", "$Nodes: expected a node tag");
                struct node n = {tag, 0, 0, -1};
                if (push(&r->nodes, &n)) return fail(t, "%s", "out of memory");
            }
            for (long long k = 0; k < block[3]; ++k) {
                line = next_line(t);
                char *end, *p = line;
                struct node *n = (struct node *)r->nodes.items + first + k;
                n->x = line ? strtod(p, &end) : 0;
                if (!line || end == p) return fail(t, "%s", "$Nodes: expected: x y z");
                p = end;
                n->y = strtod(p, &end);
                if (end == p) return fail(t, "%s", "$Nodes: expected: x y z");
            }
        }
    }
    qsort(r->nodes.items, r->nodes.count, sizeof(struct node), by_tag);
    for (size_t k = 1; k < r->nodes.count; ++k)
        if (((struct node *)r->nodes.items)[k].tag == ((struct node *)r->nodes.items)[k - 1].tag) {
            char tag[32];
            snprintf(tag, sizeof tag, "%lld", ((struct node *)r->nodes.items)[k].tag);
            return fail(t, "$Nodes: node tag %s is given twice", tag);
        }
    return 0;
}

/* One element: a cell (its corners' tags pushed) or a line of physical groups. */
static int element(struct text *t, struct reading *r, long long type, const long long *nodes, int count,
                   const long long *physical, int physical_count) {
    const struct element_type kind = type_of(type);
    char what[64];
    snprintf(what, sizeof what, "%lld", type);
    if (kind.dimension < 0) return fail(t, "element type %s is not one gmsh writes for meshes", what);
    if (kind.dimension == 3)
        return fail(t, "element type %s is a volume: dpsm takes 2D meshes (triangles, quadrangles)", what);
    if (count < kind.nodes) return fail(t, "an element of type %s lists too few nodes", what);
    if (kind.dimension == 2) {
        for (int k = 0; k < kind.corners; ++k)
            if (push(&r->cell_tags, &nodes[k])) return fail(t, "%s", "out of memory");
        int64_t end = (int64_t)r->cell_tags.count;
        return push(&r->cell_start, &end) ? fail(t, "%s", "out of memory") : 0;
    }
    if (kind.dimension == 1)
        for (int k = 0; k < physical_count; ++k) {
            struct tagged_edge e = {physical[k], nodes[0], nodes[1]};
            if (push(&r->edges, &e)) return fail(t, "%s", "out of memory");
        }
    return 0;
}

static int read_elements(struct text *t, struct reading *r) {
    long long values[128];
    char *line = next_line(t);
    if (r->version == 2) {
        long long n;
        if (!line || integers(line, &n, 1) != 1 || n < 0) return fail(t, "%s", "$Elements: expected a count");
        for (long long k = 0; k < n; ++k) {
            line = next_line(t);
            int got = line ? integers(line, values, 128) : 0;
            if (got < 3 || got < 3 + values[2]) return fail(t, "%s", "$Elements: expected: tag type tags... nodes");
            const long long type = values[1], ntags = values[2];
            const int nodes = got - 3 - (int)ntags;
            long long physical = ntags >= 1 ? values[3] : 0;
            if (element(t, r, type, values + 3 + ntags, nodes, &physical, physical != 0)) return 1;
        }
        return 0;
    }
    long long head[4];
    if (!line || integers(line, head, 4) != 4) return fail(t, "%s", "$Elements: expected: blocks elements min max");
    for (long long b = 0; b < head[0]; ++b) {
        long long block[4];
        line = next_line(t);
        if (!line || integers(line, block, 4) != 4)
            return fail(t, "%s", "$Elements: expected: dimension tag type count");
        const struct entity *entity = NULL;
        for (size_t e = 0; e < r->entities.count; ++e) {
            const struct entity *candidate = (const struct entity *)r->entities.items + e;
            if (candidate->dimension == block[0] && candidate->tag == block[1]) entity = candidate;
        }
        for (long long k = 0; k < block[3]; ++k) {
            line = next_line(t);
            int got = line ? integers(line, values, 128) : 0;
            if (got < 2) return fail(t, "%s", "$Elements: expected: tag nodes...");
            if (element(t, r, block[2], values + 1, got - 1, entity ? entity->physical : NULL,
                        entity ? entity->count : 0))
                return 1;
        }
    }
    return 0;
}

static int skip_section(struct text *t, const char *name) {
    char end[128];
    snprintf(end, sizeof end, "$End%s", name);
    for (char *line; (line = next_line(t));)
        if (strncmp(line, end, strlen(end)) == 0) return 0;
    return fail(t, "the section $%s does not end", name);
}

static int expect_end(struct text *t, const char *name) {
    char *line = next_line(t);
    char end[128];
    snprintf(end, sizeof end, "$End%s", name);
    if (!line || strncmp(line, end, strlen(end)) != 0) return fail(t, "expected %s", end);
    return 0;
}

/* The kept nodes, the cells over them and the groups of edges. */
static int assemble(struct text *t, struct reading *r, struct config_mesh *mesh) {
    const int64_t cells = (int64_t)r->cell_start.count - 1, corners = (int64_t)r->cell_tags.count;
    if (cells < 1) return fail(t, "%s", "the mesh has no 2D elements (triangles or quadrangles)");
    mesh->face_count = cells;
    mesh->face_node_start = malloc((size_t)(cells + 1) * sizeof(int64_t));
    mesh->face_nodes = malloc((size_t)corners * sizeof(int64_t));
    mesh->node_x = malloc(r->nodes.count * sizeof(double) + 1);
    mesh->node_y = malloc(r->nodes.count * sizeof(double) + 1);
    if (!mesh->face_node_start || !mesh->face_nodes || !mesh->node_x || !mesh->node_y)
        return fail(t, "%s", "out of memory");
    memcpy(mesh->face_node_start, r->cell_start.items, (size_t)(cells + 1) * sizeof(int64_t));
    /* The nodes the cells use, in the order of their tags (gmsh writes them
     * ascending): first marked, then numbered. */
    const long long *tags = r->cell_tags.items;
    for (int64_t k = 0; k < corners; ++k) {
        struct node *n = find_node(r, tags[k]);
        if (!n) {
            char tag[32];
            snprintf(tag, sizeof tag, "%lld", tags[k]);
            return fail(t, "a cell names node %s, which $Nodes does not list", tag);
        }
        n->index = 0;
    }
    int64_t kept = 0;
    for (size_t k = 0; k < r->nodes.count; ++k) {
        struct node *n = (struct node *)r->nodes.items + k;
        if (n->index < 0) continue;
        n->index = kept;
        mesh->node_x[kept] = n->x, mesh->node_y[kept] = n->y;
        ++kept;
    }
    mesh->node_count = kept;
    for (int64_t k = 0; k < corners; ++k) mesh->face_nodes[k] = find_node(r, tags[k])->index;
    /* One group per physical tag of the lines, in the order of the tags. */
    const struct tagged_edge *edges = r->edges.items;
    int64_t *pairs = malloc((r->edges.count + 1) * 2 * sizeof *pairs);
    if (!pairs) return fail(t, "%s", "out of memory");
    long long done_below = -1;
    for (;;) {
        long long next = -1;
        for (size_t e = 0; e < r->edges.count; ++e)
            if (edges[e].physical > done_below && (next < 0 || edges[e].physical < next)) next = edges[e].physical;
        if (next < 0) break;
        int64_t n = 0;
        for (size_t e = 0; e < r->edges.count; ++e) {
            if (edges[e].physical != next) continue;
            const struct node *a = find_node(r, edges[e].a), *b = find_node(r, edges[e].b);
            /* A line off the cells (a curve nothing meshes against) opens nothing. */
            if (!a || !b || a->index < 0 || b->index < 0) continue;
            pairs[2 * n] = a->index, pairs[2 * n + 1] = b->index, ++n;
        }
        const char *name = "";
        for (size_t k = 0; k < r->names_dim.count; ++k)
            if (((int *)r->names_dim.items)[k] == 1 && ((long long *)r->names_tag.items)[k] == next)
                name = (const char *)r->names_text.items + k * CONFIG_NAME_MAX;
        if (mesh_add_group(mesh, name, (long)next, pairs, n, t->path, t->message, t->message_size)) {
            free(pairs);
            return 1;
        }
        done_below = next;
    }
    free(pairs);
    return 0;
}

int gmsh_read_mesh(const char *path, struct config_mesh *mesh, char *message, size_t size) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(message, size, "%s: cannot open: %s", path, strerror(errno));
        return 1;
    }
    struct text t = {path, NULL, 0, 0, 0, message, size};
    fseek(f, 0, SEEK_END);
    long length = ftell(f);
    fseek(f, 0, SEEK_SET);
    t.data = malloc((size_t)(length > 0 ? length : 0) + 1);
    if (!t.data || (length > 0 && fread(t.data, 1, (size_t)length, f) != (size_t)length)) {
        fclose(f);
        free(t.data);
        snprintf(message, size, "%s: cannot read the file", path);
        return 1;
    }
    fclose(f);
    t.size = (size_t)(length > 0 ? length : 0);
    snprintf(mesh->format, sizeof mesh->format, "gmsh");
    struct reading r;
    memset(&r, 0, sizeof r);
    r.nodes.item_size = sizeof(struct node);
    r.names_dim.item_size = sizeof(int);
    r.names_tag.item_size = sizeof(long long);
    r.names_text.item_size = CONFIG_NAME_MAX;
    r.entities.item_size = sizeof(struct entity);
    r.cell_start.item_size = sizeof(int64_t);
    r.cell_tags.item_size = sizeof(long long);
    r.edges.item_size = sizeof(struct tagged_edge);
    int64_t zero = 0;
    int failed = push(&r.cell_start, &zero);
    char *line = next_line(&t);
    if (!line || strncmp(line, "$MeshFormat", 11) != 0) failed = fail(&t, "%s", "not a gmsh mesh: it does not begin with $MeshFormat");
    if (!failed) {
        line = next_line(&t);
        double version = 0;
        int file_type = -1;
        if (!line || sscanf(line, "%lf %d", &version, &file_type) != 2) {
            failed = fail(&t, "%s", "$MeshFormat: expected: version file-type data-size");
        } else if (file_type != 0) {
            failed = fail(&t, "%s", "a binary gmsh file: dpsm reads ASCII ones (save with Mesh.Binary = 0)");
        } else if (version >= 2.0 && version < 3.0) {
            r.version = 2;
        } else if (version > 4.05 && version < 4.15) {
            r.version = 4;
        } else {
            char v[32];
            snprintf(v, sizeof v, "%g", version);
            failed = fail(&t, "MSH version %s: dpsm reads 2.2 and 4.1 (save with -format msh22 or msh41)", v);
        }
        if (!failed) failed = expect_end(&t, "MeshFormat");
    }
    int have_nodes = 0, have_elements = 0;
    while (!failed && (line = next_line(&t))) {
        if (line[0] != '$') {
            failed = fail(&t, "expected a section ($Nodes, $Elements, ...), got \"%.40s\"", line);
        } else if (strcmp(line, "$PhysicalNames") == 0) {
            failed = read_physical_names(&t, &r) || expect_end(&t, "PhysicalNames");
        } else if (strcmp(line, "$Entities") == 0 && r.version == 4) {
            failed = read_entities(&t, &r) || expect_end(&t, "Entities");
        } else if (strcmp(line, "$Nodes") == 0) {
            failed = read_nodes(&t, &r) || expect_end(&t, "Nodes");
            have_nodes = 1;
        } else if (strcmp(line, "$Elements") == 0) {
            if (!have_nodes) failed = fail(&t, "%s", "$Elements before $Nodes");
            else failed = read_elements(&t, &r) || expect_end(&t, "Elements");
            have_elements = 1;
        } else {
            failed = skip_section(&t, line + 1);
        }
    }
    if (!failed && (!have_nodes || !have_elements))
        failed = fail(&t, "%s", have_nodes ? "the file has no $Elements" : "the file has no $Nodes");
    if (!failed) failed = assemble(&t, &r, mesh);
    free(t.data);
    free(r.nodes.items), free(r.names_dim.items), free(r.names_tag.items), free(r.names_text.items);
    free(r.entities.items), free(r.cell_start.items), free(r.cell_tags.items), free(r.edges.items);
    return failed;
}
