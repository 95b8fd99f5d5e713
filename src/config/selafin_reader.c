/* TELEMAC's Selafin (Serafin) files: Fortran unformatted sequential
 * records, each framed by its length in 4 bytes before and after, written
 * big-endian by TELEMAC (little-endian files from other tools are read too).
 * The header: an 80-character title, the numbers of variables, their names
 * and units (16 + 16 characters), IPARAM (10 integers; IPARAM(3) and (4) the
 * origin added to x and y, IPARAM(7) the planes of a 3D file, IPARAM(10) = 1
 * a date record follows), NELEM NPOIN NDP 1, IKLE (NDP nodes of each element,
 * from 1), IPOBO, X, Y; then per time frame the time and one record of NPOIN
 * values per variable. Reals are 4 bytes (SERAFIN) or 8 (SERAFIND), told by
 * the length of the X record. Variables are read from the first frame. */
#include "config/mesh_readers.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct selafin {
    const char *path;
    unsigned char *data;
    size_t size, at;
    int big_endian, real_size; /* 4 or 8 */
    int64_t elements, points, per_element;
    int variables;
    char names[256][17];
    size_t ikle_at, x_at, y_at; /* where IKLE, X and Y begin */
    double origin[2];
    char *message;
    size_t message_size;
};

static uint32_t word(const struct selafin *s, size_t at) {
    const unsigned char *b = s->data + at;
    return s->big_endian ? (uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 | (uint32_t)b[2] << 8 | b[3]
                         : (uint32_t)b[3] << 24 | (uint32_t)b[2] << 16 | (uint32_t)b[1] << 8 | b[0];
}

static double real_at(const struct selafin *s, size_t at) {
    if (s->real_size == 4) {
        uint32_t bits = word(s, at);
        float f;
        memcpy(&f, &bits, 4);
        return f;
    }
    uint64_t high = word(s, s->big_endian ? at : at + 4), low = word(s, s->big_endian ? at + 4 : at);
    uint64_t bits = high << 32 | low;
    double d;
    memcpy(&d, &bits, 8);
    return d;
}

static int refuse(struct selafin *s, const char *what) {
    snprintf(s->message, s->message_size, "%s: %s", s->path, what);
    return 1;
}

/* The next record: where its bytes begin and how many. */
static int record(struct selafin *s, size_t *begin, size_t *length, const char *what) {
    char detail[256];
    if (s->at + 4 > s->size) {
        snprintf(detail, sizeof detail, "the file ends before the record of %s (not a complete Selafin file)", what);
        return refuse(s, detail);
    }
    uint32_t n = word(s, s->at);
    if ((size_t)n + 8 > s->size - s->at) {
        snprintf(detail, sizeof detail, "the file ends inside the record of %s (it is cut short)", what);
        return refuse(s, detail);
    }
    if (word(s, s->at + 4 + n) != n) {
        snprintf(detail, sizeof detail, "the record of %s is broken at byte %zu (its length marks disagree)", what,
                 s->at);
        return refuse(s, detail);
    }
    *begin = s->at + 4;
    *length = n;
    s->at += 8 + (size_t)n;
    return 0;
}

static int load(const char *path, struct selafin *s, char *message, size_t size) {
    memset(s, 0, sizeof *s);
    s->path = path;
    s->message = message;
    s->message_size = size;
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(message, size, "%s: cannot open: %s", path, strerror(errno));
        return 1;
    }
    fseek(f, 0, SEEK_END);
    long length = ftell(f);
    fseek(f, 0, SEEK_SET);
    s->data = malloc((size_t)(length > 0 ? length : 0) + 1);
    if (!s->data || (length > 0 && fread(s->data, 1, (size_t)length, f) != (size_t)length)) {
        fclose(f);
        snprintf(message, size, "%s: cannot read the file", path);
        return 1;
    }
    fclose(f);
    s->size = (size_t)(length > 0 ? length : 0);
    if (s->size < 88) return refuse(s, "not a Selafin file: shorter than its title record");
    /* The title record is 80 bytes long: its length mark tells the byte order. */
    s->big_endian = 1;
    if (word(s, 0) != 80) {
        s->big_endian = 0;
        if (word(s, 0) != 80) return refuse(s, "not a Selafin file: its first record is not an 80-character title");
    }
    size_t at, n;
    if (record(s, &at, &n, "the title")) return 1;
    if (record(s, &at, &n, "the numbers of variables") || n != 8)
        return n != 8 ? refuse(s, "the record of the numbers of variables is not two integers") : 1;
    s->variables = (int)word(s, at);
    const int more = (int)word(s, at + 4);
    if (s->variables < 0 || more < 0 || s->variables + more > 256)
        return refuse(s, "its numbers of variables are not those of a Selafin file");
    for (int v = 0; v < s->variables + more; ++v) {
        if (record(s, &at, &n, "a variable's name")) return 1;
        if (v < s->variables) {
            int k = 0;
            for (; k < 16 && (size_t)k < n; ++k) s->names[v][k] = (char)s->data[at + (size_t)k];
            while (k > 0 && s->names[v][k - 1] == ' ') --k;
            s->names[v][k] = '\0';
        }
    }
    if (record(s, &at, &n, "IPARAM")) return 1;
    if (n != 40) return refuse(s, "IPARAM is not 10 integers");
    int32_t iparam[10];
    for (int k = 0; k < 10; ++k) iparam[k] = (int32_t)word(s, at + 4 * (size_t)k);
    if (iparam[6] > 1) {
        char detail[160];
        snprintf(detail, sizeof detail, "a 3D file (IPARAM(7) = %d planes): dpsm reads 2D Selafin files", iparam[6]);
        return refuse(s, detail);
    }
    s->origin[0] = iparam[2], s->origin[1] = iparam[3];
    if (iparam[9] == 1 && record(s, &at, &n, "the date")) return 1;
    if (record(s, &at, &n, "NELEM NPOIN NDP")) return 1;
    if (n != 16) return refuse(s, "the record NELEM NPOIN NDP 1 is not four integers");
    s->elements = (int32_t)word(s, at);
    s->points = (int32_t)word(s, at + 4);
    s->per_element = (int32_t)word(s, at + 8);
    if (s->elements < 1 || s->points < 1 || (s->per_element != 3 && s->per_element != 4)) {
        char detail[200];
        snprintf(detail, sizeof detail, "NELEM = %lld, NPOIN = %lld, NDP = %lld: dpsm reads 2D meshes of triangles "
                 "(NDP = 3) or quadrangles (NDP = 4)", (long long)s->elements, (long long)s->points,
                 (long long)s->per_element);
        return refuse(s, detail);
    }
    if (record(s, &at, &n, "IKLE")) return 1;
    if (n != (size_t)(s->elements * s->per_element) * 4) return refuse(s, "IKLE does not hold NELEM x NDP integers");
    s->ikle_at = at;
    if (record(s, &at, &n, "IPOBO")) return 1;
    if (record(s, &s->x_at, &n, "X")) return 1;
    if (n != (size_t)s->points * 4 && n != (size_t)s->points * 8) return refuse(s, "X does not hold NPOIN reals");
    s->real_size = (int)(n / (size_t)s->points);
    if (record(s, &s->y_at, &n, "Y")) return 1;
    if (n != (size_t)s->points * (size_t)s->real_size) return refuse(s, "Y does not hold NPOIN reals as X does");
    return 0; /* s->at: the first time frame */
}

int selafin_read_mesh(const char *path, struct config_mesh *mesh, char *message, size_t size) {
    struct selafin s;
    if (load(path, &s, message, size)) {
        free(s.data);
        return 1;
    }
    snprintf(mesh->format, sizeof mesh->format, "Selafin");
    const size_t at = s.ikle_at;
    mesh->node_count = s.points;
    mesh->face_count = s.elements;
    mesh->node_x = malloc((size_t)s.points * sizeof(double));
    mesh->node_y = malloc((size_t)s.points * sizeof(double));
    mesh->face_node_start = malloc((size_t)(s.elements + 1) * sizeof(int64_t));
    mesh->face_nodes = malloc((size_t)(s.elements * s.per_element) * sizeof(int64_t));
    if (!mesh->node_x || !mesh->node_y || !mesh->face_node_start || !mesh->face_nodes) {
        free(s.data);
        snprintf(message, size, "%s: out of memory", path);
        return 1;
    }
    for (int64_t p = 0; p < s.points; ++p) {
        mesh->node_x[p] = real_at(&s, s.x_at + (size_t)p * (size_t)s.real_size) + s.origin[0];
        mesh->node_y[p] = real_at(&s, s.y_at + (size_t)p * (size_t)s.real_size) + s.origin[1];
    }
    mesh->face_node_start[0] = 0;
    for (int64_t e = 0; e < s.elements; ++e) {
        for (int64_t k = 0; k < s.per_element; ++k) {
            const int64_t node = (int32_t)word(&s, at + 4 * (size_t)(e * s.per_element + k));
            if (node < 1 || node > s.points) {
                snprintf(message, size, "%s: IKLE: node %lld of element %lld is %lld, not a node (1 .. %lld)", path,
                         (long long)k + 1, (long long)e + 1, (long long)node, (long long)s.points);
                free(s.data);
                return 1;
            }
            mesh->face_nodes[e * s.per_element + k] = node - 1;
        }
        mesh->face_node_start[e + 1] = (e + 1) * s.per_element;
    }
    free(s.data);
    return 0;
}

int selafin_read_variable(const char *path, const char *variable, double **values, int64_t *count, char *message,
                          size_t size) {
    struct selafin s;
    if (load(path, &s, message, size)) {
        free(s.data);
        return 1;
    }
    int found = -1;
    char wanted[64];
    snprintf(wanted, sizeof wanted, "%s", variable);
    for (size_t k = strlen(wanted); k > 0 && wanted[k - 1] == ' '; --k) wanted[k - 1] = '\0';
    for (int v = 0; v < s.variables && found < 0; ++v) {
        int same = strlen(s.names[v]) == strlen(wanted);
        for (size_t k = 0; same && wanted[k]; ++k)
            same = toupper((unsigned char)wanted[k]) == toupper((unsigned char)s.names[v][k]);
        if (same) found = v;
    }
    if (found < 0) {
        char list[1024] = "";
        for (int v = 0; v < s.variables; ++v) {
            strncat(list, v ? ", " : "", sizeof list - strlen(list) - 1);
            strncat(list, s.names[v], sizeof list - strlen(list) - 1);
        }
        snprintf(message, size, "%s: no variable \"%s\"; the file has %s", path, variable,
                 s.variables ? list : "none (a geometry without values)");
        free(s.data);
        return 1;
    }
    size_t at, n;
    int failed = record(&s, &at, &n, "the first time frame");
    for (int v = 0; v <= found && !failed; ++v) {
        failed = record(&s, &at, &n, s.names[v]);
        if (!failed && n != (size_t)s.points * (size_t)s.real_size) {
            snprintf(message, size, "%s: the first frame's %s does not hold NPOIN = %lld values", path, s.names[v],
                     (long long)s.points);
            failed = 1;
        }
    }
    if (failed) {
        free(s.data);
        return 1;
    }
    *values = malloc((size_t)s.points * sizeof(double));
    if (!*values) {
        free(s.data);
        snprintf(message, size, "%s: out of memory", path);
        return 1;
    }
    for (int64_t p = 0; p < s.points; ++p) {
        (*values)[p] = real_at(&s, at + (size_t)p * (size_t)s.real_size);
        if (!(fabs((*values)[p]) <= 1e50)) {
            snprintf(message, size, "%s: %s at node %lld (from 1) is %g, not a finite value", path, s.names[found],
                     (long long)p + 1, (*values)[p]);
            free(*values), *values = NULL;
            free(s.data);
            return 1;
        }
    }
    *count = s.points;
    free(s.data);
    return 0;
}
