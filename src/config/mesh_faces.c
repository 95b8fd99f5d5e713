/* The faces of a planar mesh given by nodes and edges only (a Delft3D FM net
 * file without face_node_connectivity): each edge is walked on both sides,
 * turning at every node to the next edge clockwise from the one it came
 * along, so that the face stays on the left. A walk that closes after 3 to
 * 6 edges around a positive area is a face, as D-Flow FM finds its cells;
 * the outer boundary (walked clockwise) and larger rings (holes, islands,
 * the space around a separate part) are not. */
#include "config/mesh_readers.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* D-Flow FM's largest cell. */
#define MAX_FACE_NODES 6

struct unique_edge {
    int64_t lo, hi, first; /* first: its first place in the file */
};

static int by_nodes(const void *a, const void *b) {
    const struct unique_edge *x = a, *y = b;
    if (x->lo != y->lo) return x->lo < y->lo ? -1 : 1;
    if (x->hi != y->hi) return x->hi < y->hi ? -1 : 1;
    return (x->first > y->first) - (x->first < y->first);
}

static int by_first(const void *a, const void *b) {
    const struct unique_edge *x = a, *y = b;
    return (x->first > y->first) - (x->first < y->first);
}

/* A half-edge around its origin: the angle it leaves at, and its number. */
struct spoke {
    double angle;
    int64_t half;
};

static int by_angle(const void *a, const void *b) {
    const struct spoke *x = a, *y = b;
    if (x->angle != y->angle) return x->angle < y->angle ? -1 : 1;
    return (x->half > y->half) - (x->half < y->half);
}

int mesh_faces_from_edges(const char *path, const double *x, const double *y, int64_t node_count,
                          const int64_t *edge_nodes, int64_t edge_count, int64_t **face_start, int64_t **face_nodes,
                          int64_t *face_count, char *message, size_t size) {
    *face_start = NULL, *face_nodes = NULL, *face_count = 0;
    struct unique_edge *edges = malloc((size_t)(edge_count > 0 ? edge_count : 1) * sizeof *edges);
    int64_t *degree = calloc((size_t)node_count + 1, sizeof *degree);
    if (!edges || !degree) {
        free(edges), free(degree);
        snprintf(message, size, "%s: out of memory building faces from edges", path);
        return 1;
    }
    int64_t n = 0;
    for (int64_t e = 0; e < edge_count; ++e) {
        const int64_t a = edge_nodes[2 * e], b = edge_nodes[2 * e + 1];
        if (a == b) continue;
        edges[n++] = (struct unique_edge){a < b ? a : b, a < b ? b : a, e};
    }
    qsort(edges, (size_t)n, sizeof *edges, by_nodes);
    int64_t unique = 0;
    for (int64_t k = 0; k < n; ++k)
        if (unique == 0 || edges[k].lo != edges[unique - 1].lo || edges[k].hi != edges[unique - 1].hi)
            edges[unique++] = edges[k];
    qsort(edges, (size_t)unique, sizeof *edges, by_first);
    /* Dangling edges bound no face: drop nodes of one edge until none is left. */
    char *gone = calloc((size_t)(unique > 0 ? unique : 1), 1);
    for (int64_t e = 0; e < unique; ++e) ++degree[edges[e].lo], ++degree[edges[e].hi];
    for (int changed = 1; changed;) {
        changed = 0;
        for (int64_t e = 0; e < unique; ++e)
            if (!gone[e] && (degree[edges[e].lo] == 1 || degree[edges[e].hi] == 1)) {
                gone[e] = 1, changed = 1;
                --degree[edges[e].lo], --degree[edges[e].hi];
            }
    }
    /* The spokes of each node (half-edge 2e from lo to hi, 2e + 1 back), by angle. */
    int64_t *start = calloc((size_t)node_count + 1, sizeof *start);
    struct spoke *spokes = malloc((size_t)(2 * unique + 1) * sizeof *spokes);
    int64_t *place = malloc((size_t)(2 * unique + 1) * sizeof *place); /* a half-edge's place among its origin's spokes */
    char *walked = calloc((size_t)(2 * unique + 1), 1);
    int64_t *ring = malloc((size_t)(2 * unique + 1) * sizeof *ring);
    int64_t *out_start = malloc((size_t)(2 * unique + 2) * sizeof *out_start);
    int64_t *out_nodes = malloc((size_t)(MAX_FACE_NODES * 2 * unique + 1) * sizeof *out_nodes);
    if (!gone || !start || !spokes || !place || !walked || !ring || !out_start || !out_nodes) {
        free(edges), free(degree), free(gone), free(start), free(spokes), free(place), free(walked), free(ring);
        free(out_start), free(out_nodes);
        snprintf(message, size, "%s: out of memory building faces from edges", path);
        return 1;
    }
    for (int64_t e = 0; e < unique; ++e)
        if (!gone[e]) ++start[edges[e].lo + 1], ++start[edges[e].hi + 1];
    for (int64_t v = 0; v < node_count; ++v) start[v + 1] += start[v];
    int64_t *fill = degree; /* reused: the next free spoke of each node */
    for (int64_t v = 0; v < node_count; ++v) fill[v] = start[v];
    for (int64_t e = 0; e < unique; ++e) {
        if (gone[e]) continue;
        const int64_t a = edges[e].lo, b = edges[e].hi;
        spokes[fill[a]++] = (struct spoke){atan2(y[b] - y[a], x[b] - x[a]), 2 * e};
        spokes[fill[b]++] = (struct spoke){atan2(y[a] - y[b], x[a] - x[b]), 2 * e + 1};
    }
    for (int64_t v = 0; v < node_count; ++v) {
        qsort(spokes + start[v], (size_t)(start[v + 1] - start[v]), sizeof *spokes, by_angle);
        for (int64_t k = start[v]; k < start[v + 1]; ++k) place[spokes[k].half] = k;
    }
#define ORIGIN(h) ((h) % 2 ? edges[(h) / 2].hi : edges[(h) / 2].lo)
#define TARGET(h) ((h) % 2 ? edges[(h) / 2].lo : edges[(h) / 2].hi)
    int64_t faces = 0, used = 0;
    out_start[0] = 0;
    for (int64_t h0 = 0; h0 < 2 * unique; ++h0) {
        if (gone[h0 / 2] || walked[h0]) continue;
        int64_t length = 0, h = h0;
        do {
            walked[h] = 1;
            ring[length++] = ORIGIN(h);
            /* At the target, the spoke clockwise next after the one back. */
            const int64_t v = TARGET(h), back = place[h ^ 1];
            const int64_t next = back == start[v] ? start[v + 1] - 1 : back - 1;
            h = spokes[next].half;
        } while (h != h0 && length <= 2 * unique);
        if (length < 3 || length > MAX_FACE_NODES) continue;
        double area = 0.0;
        int repeated = 0;
        for (int64_t k = 0; k < length; ++k) {
            const int64_t p = ring[k], q = ring[(k + 1) % length];
            area += (x[p] - x[ring[0]]) * (y[q] - y[ring[0]]) - (x[q] - x[ring[0]]) * (y[p] - y[ring[0]]);
            for (int64_t j = 0; j < k; ++j) repeated |= ring[j] == p;
        }
        if (!(area > 0.0) || repeated) continue;
        memcpy(out_nodes + used, ring, (size_t)length * sizeof *ring);
        used += length;
        out_start[++faces] = used;
    }
#undef ORIGIN
#undef TARGET
    free(edges), free(degree), free(gone), free(start), free(spokes), free(place), free(walked), free(ring);
    if (faces == 0) {
        free(out_start), free(out_nodes);
        snprintf(message, size, "%s: its %lld edges bound no face of 3 to %d nodes: there is no cell to build",
                 path, (long long)edge_count, MAX_FACE_NODES);
        return 1;
    }
    *face_start = out_start, *face_nodes = out_nodes, *face_count = faces;
    return 0;
}

int mesh_add_group(struct config_mesh *mesh, const char *name, long number, const int64_t *edge_nodes, int64_t count,
                   const char *path, char *message, size_t size) {
    struct config_mesh_group *groups = realloc(mesh->groups, (size_t)(mesh->group_count + 1) * sizeof *groups);
    int64_t *copy = malloc((size_t)(2 * (count > 0 ? count : 1)) * sizeof *copy);
    if (groups) mesh->groups = groups;
    if (!groups || !copy) {
        free(copy);
        snprintf(message, size, "%s: out of memory reading its boundary groups", path);
        return 1;
    }
    struct config_mesh_group *g = &mesh->groups[mesh->group_count++];
    memset(g, 0, sizeof *g);
    snprintf(g->name, sizeof g->name, "%s", name ? name : "");
    g->number = number;
    g->edge_count = count;
    g->edge_nodes = copy;
    memcpy(copy, edge_nodes, (size_t)(2 * count) * sizeof *copy);
    return 0;
}
