#include "mesh_scenes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void *scene_alloc(size_t n, size_t size) {
    void *p = calloc(n ? n : 1, size);
    if (!p) {
        fprintf(stderr, "mesh_scenes: out of memory\n");
        exit(1);
    }
    return p;
}

/* A small deterministic generator, the same on every machine. */
static double uniform(unsigned *state) {
    *state = *state * 1103515245u + 12345u;
    return ((*state >> 8) & 0xFFFFFF) / 16777216.0;
}

const char *scene_name(scene_kind kind) {
    switch (kind) {
        case SCENE_QUADS: return "quadrilaterals";
        case SCENE_TRIANGLES: return "jittered_triangles";
        case SCENE_HEXAGONS: return "hexagons";
        case SCENE_DUAL: return "median_dual";
        case SCENE_GMSH_DISK: return "gmsh_disk";
    }
    return "?";
}

/* The lattice of (n+1)^2 nodes over the square, jittered inside by up to
 * `jitter` of the spacing along each axis (nodes on the sides move along
 * them only). */
static void lattice_nodes(mesh_scene *s, int n, double half, double jitter, unsigned seed) {
    const double h = 2.0 * half / n;
    s->nnodes = (int64_t)(n + 1) * (n + 1);
    s->node_xy = scene_alloc((size_t)(2 * s->nnodes), sizeof(double));
    unsigned state = seed ? seed : 1u;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            double x = -half + i * h, y = -half + j * h;
            const double jx = jitter * h * (2.0 * uniform(&state) - 1.0), jy = jitter * h * (2.0 * uniform(&state) - 1.0);
            if (i > 0 && i < n) x += jx;
            if (j > 0 && j < n) y += jy;
            const int64_t k = i + (int64_t)(n + 1) * j;
            s->node_xy[2 * k] = x, s->node_xy[2 * k + 1] = y;
        }
}

static double polygon_area(const double *xy, const int64_t *nodes, int64_t count, double *cx, double *cy) {
    double a2 = 0.0, mx = 0.0, my = 0.0;
    const double x0 = xy[2 * nodes[0]], y0 = xy[2 * nodes[0] + 1];
    for (int64_t k = 0; k < count; ++k) {
        const double px = xy[2 * nodes[k]] - x0, py = xy[2 * nodes[k] + 1] - y0;
        const double qx = xy[2 * nodes[(k + 1) % count]] - x0, qy = xy[2 * nodes[(k + 1) % count] + 1] - y0;
        const double w = px * qy - qx * py;
        a2 += w, mx += w * (px + qx) / 3.0, my += w * (py + qy) / 3.0;
    }
    *cx = x0 + mx / a2, *cy = y0 + my / a2;
    return 0.5 * fabs(a2);
}

static void polygon_cells(mesh_scene *s) {
    s->cells = s->npolygons;
    s->cx = scene_alloc((size_t)s->cells, sizeof(double));
    s->cy = scene_alloc((size_t)s->cells, sizeof(double));
    s->area = scene_alloc((size_t)s->cells, sizeof(double));
    for (int64_t c = 0; c < s->cells; ++c)
        s->area[c] = polygon_area(s->node_xy, s->cell_nodes + s->cell_start[c], s->cell_start[c + 1] - s->cell_start[c],
                                  &s->cx[c], &s->cy[c]);
}

static void make_lattice_polygons(mesh_scene *s, int n, int triangles) {
    const int64_t squares = (int64_t)n * n;
    s->npolygons = triangles ? 2 * squares : squares;
    s->cell_start = scene_alloc((size_t)s->npolygons + 1, sizeof(int64_t));
    s->cell_nodes = scene_alloc((size_t)(triangles ? 6 * squares : 4 * squares), sizeof(int64_t));
    int64_t p = 0, k = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int64_t a = i + (int64_t)(n + 1) * j, b = a + 1, c = b + (n + 1), d = a + (n + 1);
            if (!triangles) {
                s->cell_start[p++] = k;
                s->cell_nodes[k++] = a, s->cell_nodes[k++] = b, s->cell_nodes[k++] = c, s->cell_nodes[k++] = d;
                continue;
            }
            const double *xy = s->node_xy;
            const double ac = hypot(xy[2 * c] - xy[2 * a], xy[2 * c + 1] - xy[2 * a + 1]);
            const double bd = hypot(xy[2 * d] - xy[2 * b], xy[2 * d + 1] - xy[2 * b + 1]);
            const int64_t tri[2][3] = {{a, b, c}, {a, c, d}}, alt[2][3] = {{a, b, d}, {b, c, d}};
            for (int t = 0; t < 2; ++t) {
                s->cell_start[p++] = k;
                for (int v = 0; v < 3; ++v) s->cell_nodes[k++] = ac <= bd ? tri[t][v] : alt[t][v];
            }
        }
    s->cell_start[p] = k;
}

/* Triangles over the lattice jittered by up to `jitter` of the spacing along each
 * axis, each square split along its shorter diagonal (as a Delaunay
 * triangulation would); a node of a triangle with less than a quarter of the
 * unjittered area moves halfway back to its lattice place until none is
 * left, as a mesh generator keeps its triangles from slivers (whose small
 * sub-step would set the pace of the whole mesh). */
static void jittered_triangles(mesh_scene *s, int n, double half, double jitter, unsigned seed) {
    lattice_nodes(s, n, half, jitter, seed);
    const double h = 2.0 * half / n;
    for (int round = 0; round < 20; ++round) {
        free(s->cell_start), free(s->cell_nodes);
        make_lattice_polygons(s, n, 1);
        int moved = 0;
        for (int64_t t = 0; t < s->npolygons; ++t) {
            double cx, cy;
            if (polygon_area(s->node_xy, s->cell_nodes + 3 * t, 3, &cx, &cy) >= 0.125 * h * h) continue;
            for (int v = 0; v < 3; ++v) {
                const int64_t k = s->cell_nodes[3 * t + v];
                const int64_t i = k % (n + 1), j = k / (n + 1);
                s->node_xy[2 * k] = 0.5 * (s->node_xy[2 * k] + (-half + i * h));
                s->node_xy[2 * k + 1] = 0.5 * (s->node_xy[2 * k + 1] + (-half + j * h));
            }
            moved = 1;
        }
        if (!moved) break;
    }
}

/* Pointy-top hexagons of width w (flat sides left and right) whose centres lie
 * inside the square, with shared corners found by their lattice position. */
static void make_hexagons(mesh_scene *s, int n, double half) {
    const double w = 2.0 * half / n, r = w / sqrt(3.0), row = 1.5 * r;
    const int rows = (int)floor(2.0 * half / row);
    /* Corners lie on a lattice of x in steps of w/2 and y in steps of r/2. */
    const int64_t ncx = 2 * n + 4, ncy = 2 * (int64_t)rows * 3 + 8;
    int64_t *corner_id = scene_alloc((size_t)(ncx * ncy), sizeof(int64_t));
    for (int64_t k = 0; k < ncx * ncy; ++k) corner_id[k] = -1;
    s->npolygons = 0;
    const int64_t most = (int64_t)(n + 1) * (rows + 1);
    s->cell_start = scene_alloc((size_t)most + 1, sizeof(int64_t));
    s->cell_nodes = scene_alloc((size_t)(6 * most), sizeof(int64_t));
    s->node_xy = scene_alloc((size_t)(2 * ncx * ncy), sizeof(double));
    s->nnodes = 0;
    const double y0 = -0.5 * rows * row + 0.5 * row;
    int64_t k = 0;
    for (int j = 0; j < rows; ++j) {
        const double offset = (j % 2) ? 0.5 * w : 0.0;
        for (int i = 0; i < n + 1; ++i) {
            const double x = -half + 0.5 * w + offset + i * w - 0.5 * w, y = y0 + j * row;
            if (x - 0.5 * w < -half - 1e-12 || x + 0.5 * w > half + 1e-12) continue;
            s->cell_start[s->npolygons++] = k;
            for (int v = 0; v < 6; ++v) {
                /* corners at angles 30 + 60 v degrees */
                static const int dxh[6] = {1, 0, -1, -1, 0, 1}, dyq[6] = {1, 2, 1, -1, -2, -1};
                const double px = x + dxh[v] * 0.5 * w, py = y + dyq[v] * 0.5 * r;
                const int64_t ix = (int64_t)llround((px + half) / (0.5 * w)) + 1;
                const int64_t iy = (int64_t)llround((py - y0) / (0.5 * r)) + 4;
                int64_t *id = &corner_id[ix + ncx * iy];
                if (*id < 0) {
                    *id = s->nnodes++;
                    s->node_xy[2 * *id] = px, s->node_xy[2 * *id + 1] = py;
                }
                s->cell_nodes[k++] = *id;
            }
        }
    }
    s->cell_start[s->npolygons] = k;
    free(corner_id);
}

/* The median dual: node n's cell is made of, in each of its triangles, the
 * quadrilateral node, edge midpoint, centroid, other edge midpoint. */
static void dual_cells(mesh_scene *s) {
    s->cells = s->nnodes;
    s->cx = scene_alloc((size_t)s->cells, sizeof(double));
    s->cy = scene_alloc((size_t)s->cells, sizeof(double));
    s->area = scene_alloc((size_t)s->cells, sizeof(double));
    for (int64_t v = 0; v < s->nnodes; ++v) s->cx[v] = s->node_xy[2 * v], s->cy[v] = s->node_xy[2 * v + 1];
    for (int64_t t = 0; t < s->npolygons; ++t) {
        double cx, cy;
        const double a = polygon_area(s->node_xy, s->cell_nodes + 3 * t, 3, &cx, &cy);
        for (int v = 0; v < 3; ++v) s->area[s->cell_nodes[3 * t + v]] += a / 3.0;
    }
}

mesh_scene scene_read_msh(const char *path) {
    mesh_scene s;
    memset(&s, 0, sizeof s);
    s.kind = SCENE_GMSH_DISK;
    FILE *in = fopen(path, "r");
    if (!in) return s;
    char line[512];
    int64_t *id_to_node = NULL, max_id = 0;
    while (fgets(line, sizeof line, in)) {
        if (strncmp(line, "$Nodes", 6) == 0) {
            long long count = 0;
            if (fscanf(in, "%lld", &count) != 1) break;
            s.nnodes = count;
            s.node_xy = scene_alloc((size_t)(2 * count), sizeof(double));
            int64_t *ids = scene_alloc((size_t)count, sizeof(int64_t));
            for (long long k = 0; k < count; ++k) {
                long long id;
                double z;
                if (fscanf(in, "%lld %lf %lf %lf", &id, &s.node_xy[2 * k], &s.node_xy[2 * k + 1], &z) != 4) break;
                ids[k] = id;
                if (id > max_id) max_id = id;
            }
            id_to_node = scene_alloc((size_t)max_id + 1, sizeof(int64_t));
            for (long long k = 0; k < count; ++k) id_to_node[ids[k]] = k;
            free(ids);
        } else if (strncmp(line, "$Elements", 9) == 0 && id_to_node) {
            long long count = 0;
            if (fscanf(in, "%lld", &count) != 1) break;
            s.cell_start = scene_alloc((size_t)count + 1, sizeof(int64_t));
            s.cell_nodes = scene_alloc((size_t)(3 * count), sizeof(int64_t));
            if (!fgets(line, sizeof line, in)) break;
            for (long long k = 0; k < count; ++k) {
                if (!fgets(line, sizeof line, in)) break;
                long long id, type, tags, v[3];
                int used = 0;
                if (sscanf(line, "%lld %lld %lld%n", &id, &type, &tags, &used) != 3 || type != 2) continue;
                const char *rest = line + used;
                for (long long t = 0; t < tags; ++t) {
                    long long skip;
                    int more = 0;
                    sscanf(rest, "%lld%n", &skip, &more);
                    rest += more;
                }
                if (sscanf(rest, "%lld %lld %lld", &v[0], &v[1], &v[2]) != 3) continue;
                s.cell_start[s.npolygons] = 3 * s.npolygons;
                for (int j = 0; j < 3; ++j) s.cell_nodes[3 * s.npolygons + j] = id_to_node[v[j]];
                ++s.npolygons;
            }
            s.cell_start[s.npolygons] = 3 * s.npolygons;
        }
    }
    fclose(in);
    free(id_to_node);
    if (s.npolygons > 0) polygon_cells(&s);
    return s;
}

mesh_scene scene_make(scene_kind kind, int n, double half, unsigned seed) {
    return scene_make_jittered(kind, n, half, 0.3, seed);
}

mesh_scene scene_make_jittered(scene_kind kind, int n, double half, double jitter, unsigned seed) {
    mesh_scene s;
    memset(&s, 0, sizeof s);
    s.kind = kind;
    switch (kind) {
        case SCENE_GMSH_DISK: {
            const char *geo = getenv("DPSM_DISK_GEO");
            if (!geo) return s;
            char path[256], command[1024];
            snprintf(path, sizeof path, "/tmp/dpsm_disk_%d_%d.msh", n, (int)seed);
            snprintf(command, sizeof command, "gmsh -2 -format msh22 -setnumber h %.6f '%s' -o '%s' > /dev/null 2>&1",
                     7.0 / n, geo, path);
            if (system(command) != 0) return s;
            s = scene_read_msh(path);
            remove(path);
            (void)half;
            return s;
        }
        case SCENE_QUADS:
            lattice_nodes(&s, n, half, 0.0, seed);
            make_lattice_polygons(&s, n, 0);
            polygon_cells(&s);
            break;
        case SCENE_TRIANGLES:
            jittered_triangles(&s, n, half, jitter, seed);
            polygon_cells(&s);
            break;
        case SCENE_HEXAGONS:
            make_hexagons(&s, n, half);
            polygon_cells(&s);
            break;
        case SCENE_DUAL: {
            jittered_triangles(&s, n, half, jitter, seed);
            /* triangles as 3 nodes each, cell_start unused by the dual */
            dual_cells(&s);
            break;
        }
    }
    return s;
}

double scene_column_foot(double alpha) { return (0.5 + sqrt(4.0 * alpha * alpha - 0.25 / 3.0)) / (2.0 * alpha); }

double scene_column_height(double alpha, double r) { return fmin(0.5, fmax(0.0, alpha * (scene_column_foot(alpha) - r))); }

void scene_pour_column(const mesh_scene *s, double *h) {
    scene_disk_fractions(s, 1.0, h);
    for (int64_t c = 0; c < s->cells; ++c) h[c] *= 0.5;
}

double scene_column_l1(const mesh_scene *s, const double *h, double alpha) {
    double err = 0.0;
    for (int64_t c = 0; c < s->cells; ++c)
        err += fabs(h[c] - scene_column_height(alpha, hypot(s->cx[c], s->cy[c]))) * s->area[c];
    return err / (3.14159265358979323846 * 0.5);
}

int scene_create(const mesh_scene *s, dpsm_grid **out) {
    if (s->kind == SCENE_DUAL) return dpsm_create_dual_mesh(s->nnodes, s->node_xy, s->npolygons, s->cell_nodes, out);
    return dpsm_create_mesh(s->nnodes, s->node_xy, s->npolygons, s->cell_start, s->cell_nodes, out);
}

/* The share of the triangle (p, q, r) inside the disk, by 16^2 sub-triangles. */
static double triangle_fraction(const double p[2], const double q[2], const double r[2], double radius) {
    const double dp = hypot(p[0], p[1]), dq = hypot(q[0], q[1]), dr = hypot(r[0], r[1]);
    if (dp <= radius && dq <= radius && dr <= radius) return 1.0;
    const int m = 16;
    int inside = 0;
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m - i; ++j)
            for (int up = 0; up < 2; ++up) {
                if (up && i + j == m - 1) continue;
                /* barycentric centre of the sub-triangle */
                const double u = up ? (i + 2.0 / 3.0) / m : (i + 1.0 / 3.0) / m;
                const double v = up ? (j + 2.0 / 3.0) / m : (j + 1.0 / 3.0) / m;
                const double x = p[0] + u * (q[0] - p[0]) + v * (r[0] - p[0]);
                const double y = p[1] + u * (q[1] - p[1]) + v * (r[1] - p[1]);
                inside += x * x + y * y <= radius * radius;
            }
    return (double)inside / (m * m);
}

static double tri_area(const double p[2], const double q[2], const double r[2]) {
    return 0.5 * fabs((q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1]));
}

void scene_disk_fractions(const mesh_scene *s, double radius, double *share) {
    const double *xy = s->node_xy;
    if (s->kind != SCENE_DUAL) {
        for (int64_t c = 0; c < s->cells; ++c) {
            const int64_t k0 = s->cell_start[c], count = s->cell_start[c + 1] - k0;
            const double centre[2] = {s->cx[c], s->cy[c]};
            double inside = 0.0, total = 0.0;
            for (int64_t k = 0; k < count; ++k) {
                const double *p = xy + 2 * s->cell_nodes[k0 + k], *q = xy + 2 * s->cell_nodes[k0 + (k + 1) % count];
                const double a = tri_area(centre, p, q);
                inside += a * triangle_fraction(centre, p, q, radius);
                total += a;
            }
            share[c] = inside / total;
        }
        return;
    }
    /* The dual cell of a node: a quadrilateral in each of its triangles. */
    double *total = scene_alloc((size_t)s->cells, sizeof(double));
    for (int64_t c = 0; c < s->cells; ++c) share[c] = 0.0;
    for (int64_t t = 0; t < s->npolygons; ++t) {
        const int64_t *v = s->cell_nodes + 3 * t;
        for (int at = 0; at < 3; ++at) {
            const double *p = xy + 2 * v[at], *q = xy + 2 * v[(at + 1) % 3], *r = xy + 2 * v[(at + 2) % 3];
            const double mq[2] = {0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])};
            const double mr[2] = {0.5 * (p[0] + r[0]), 0.5 * (p[1] + r[1])};
            const double g[2] = {(p[0] + q[0] + r[0]) / 3.0, (p[1] + q[1] + r[1]) / 3.0};
            const double a1 = tri_area(p, mq, g), a2 = tri_area(p, g, mr);
            share[v[at]] += a1 * triangle_fraction(p, mq, g, radius) + a2 * triangle_fraction(p, g, mr, radius);
            total[v[at]] += a1 + a2;
        }
    }
    for (int64_t c = 0; c < s->cells; ++c) share[c] /= total[c];
    free(total);
}

void scene_rotate(mesh_scene *s, double angle) {
    const double c = cos(angle), n = sin(angle);
    for (int64_t k = 0; k < s->nnodes; ++k) {
        const double x = s->node_xy[2 * k], y = s->node_xy[2 * k + 1];
        s->node_xy[2 * k] = c * x - n * y, s->node_xy[2 * k + 1] = n * x + c * y;
    }
    for (int64_t k = 0; k < s->cells; ++k) {
        const double x = s->cx[k], y = s->cy[k];
        s->cx[k] = c * x - n * y, s->cy[k] = n * x + c * y;
    }
}

double scene_mean_size(const mesh_scene *s) {
    double total = 0.0;
    for (int64_t c = 0; c < s->cells; ++c) total += s->area[c];
    return sqrt(total / (double)s->cells);
}

void scene_free(mesh_scene *s) {
    free(s->node_xy), free(s->cell_start), free(s->cell_nodes), free(s->cx), free(s->cy), free(s->area);
    memset(s, 0, sizeof *s);
}
