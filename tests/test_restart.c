/* Restart files (dpsm_save, dpsm_load): a grid saved mid-run and loaded
 * continues bit for bit, for every kind of grid and every feature at once;
 * every changed byte and every truncation of a file is refused with
 * DPSM_ERR_BAD_FILE and no grid; files that cannot be read or written give
 * DPSM_ERR_IO naming the path; a failed save leaves the old file as it was.
 * Each test prints the figures it checks (file sizes, bytes tried). */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "test_support.h"

static const double kPi = 3.14159265358979323846;

/* Offsets of version 1 of the format (docs/guide_restart.md). */
enum {
    kOffsetVersion = 8,
    kOffsetNx = 20,
    kOffsetRepose = 52,
    kOffsetFlags = 112,
    kHeaderChecksum = 216,
    kHeaderBytes = 220,
};

static char dir[256];

static int make_dir(void **state) {
    (void)state;
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/dpsm-restart-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    return mkdtemp(dir) ? 0 : -1;
}

static int remove_dir(void **state) {
    (void)state;
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd) == 0 ? 0 : -1;
}

static void path_of(char *out, size_t size, const char *name) { snprintf(out, size, "%s/%s", dir, name); }

static unsigned char *read_file(const char *path, size_t *size) {
    FILE *f = fopen(path, "rb");
    REQUIRE(f != NULL, "cannot open %s: %s", path, strerror(errno));
    fseek(f, 0, SEEK_END);
    const long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *bytes = malloc((size_t)n + 1);
    REQUIRE(fread(bytes, 1, (size_t)n, f) == (size_t)n, "cannot read %s", path);
    fclose(f);
    *size = (size_t)n;
    return bytes;
}

static void write_file(const char *path, const unsigned char *bytes, size_t size) {
    FILE *f = fopen(path, "wb");
    REQUIRE(f != NULL, "cannot create %s: %s", path, strerror(errno));
    REQUIRE(fwrite(bytes, 1, size, f) == size, "cannot write %s", path);
    REQUIRE(fclose(f) == 0, "cannot close %s", path);
}

/* The standard CRC-32 (zlib's), written here again so that the test checks
 * the format, not the library against itself. */
static uint32_t crc32_of(const unsigned char *bytes, size_t n) {
    uint32_t c = 0xffffffffu;
    for (size_t k = 0; k < n; ++k) {
        c ^= bytes[k];
        for (int b = 0; b < 8; ++b) c = (c & 1u) ? 0xedb88320u ^ (c >> 1) : c >> 1;
    }
    return ~c;
}

static uint32_t get_u32(const unsigned char *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static void put_u32(unsigned char *p, uint32_t v) {
    for (int k = 0; k < 4; ++k) p[k] = (unsigned char)(v >> (8 * k));
}

static void put_f64(unsigned char *p, double v) {
    uint64_t bits;
    memcpy(&bits, &v, sizeof bits);
    for (int k = 0; k < 8; ++k) p[k] = (unsigned char)(bits >> (8 * k));
}

/* Makes both checksums of a file right again after a deliberate change. */
static void reseal(unsigned char *bytes, size_t size) {
    put_u32(bytes + kHeaderChecksum, crc32_of(bytes, kHeaderChecksum));
    put_u32(bytes + size - 4, crc32_of(bytes, size - 4));
}

/* Writes to `path` the file `good` with another format version and more
 * flags, its checksums made right again (bytes: scratch of `size`). */
static void write_with_header(const char *path, unsigned char *bytes, const unsigned char *good, size_t size,
                              uint32_t version, uint32_t more_flags) {
    memcpy(bytes, good, size);
    put_u32(bytes + kOffsetVersion, version);
    put_u32(bytes + kOffsetFlags, get_u32(bytes + kOffsetFlags) | more_flags);
    reseal(bytes, size);
    write_file(path, bytes, size);
}

/* Everything a host can read back, bit for bit: heights, the five ledger
 * figures, the stable step, and the step information (the cell updates only
 * when `with_cost`: a loaded grid looks at every tile once more, which costs
 * work but changes no result). */
static void require_same(const dpsm_grid *a, const dpsm_grid *b, int with_cost, const char *when) {
    int64_t nx, ny, nx2, ny2;
    CHECK_OK(a, dpsm_get_shape(a, &nx, &ny));
    CHECK_OK(b, dpsm_get_shape(b, &nx2, &ny2));
    REQUIRE(nx == nx2 && ny == ny2, "%s: shapes %lld x %lld and %lld x %lld", when, (long long)nx, (long long)ny,
            (long long)nx2, (long long)ny2);
    const size_t n = (size_t)(nx * ny);
    double *ha = malloc(sizeof(double) * n), *hb = malloc(sizeof(double) * n);
    CHECK_OK(a, dpsm_get_heights(a, ha));
    CHECK_OK(b, dpsm_get_heights(b, hb));
    size_t differ = 0;
    for (size_t c = 0; c < n; ++c) differ += memcmp(&ha[c], &hb[c], sizeof(double)) != 0;
    REQUIRE(differ == 0, "%s: %zu of %zu heights differ", when, differ, n);
    for (int q = DPSM_MASS_TOTAL; q <= DPSM_MASS_UNMET; ++q) {
        double ma, mb;
        CHECK_OK(a, dpsm_get_mass(a, q, &ma));
        CHECK_OK(b, dpsm_get_mass(b, q, &mb));
        REQUIRE(memcmp(&ma, &mb, sizeof ma) == 0, "%s: mass quantity %d is %.17g and %.17g", when, q, ma, mb);
    }
    for (int item = DPSM_INFO_SUBSTEPS; item <= DPSM_INFO_CELL_UPDATES; ++item) {
        if (item == DPSM_INFO_CELL_UPDATES && !with_cost) continue;
        double va, vb;
        CHECK_OK(a, dpsm_get_step_info(a, item, &va));
        CHECK_OK(b, dpsm_get_step_info(b, item, &vb));
        REQUIRE(memcmp(&va, &vb, sizeof va) == 0, "%s: step info %d is %.17g and %.17g", when, item, va, vb);
    }
    double da, db;
    CHECK_OK(a, dpsm_stable_dt(a, &da));
    CHECK_OK(b, dpsm_stable_dt(b, &db));
    REQUIRE(memcmp(&da, &db, sizeof da) == 0, "%s: stable steps %.17g and %.17g", when, da, db);
    free(ha);
    free(hb);
}

/* What a host couples, as dpsm_save must keep it: what left through each side
 * the grid has, bit for bit, and whether face fluxes are recorded. Right after
 * a load the loaded grid's fluxes read 0 (the file holds none); after the same
 * steps they equal the saved grid's. */
static void require_same_coupling(const dpsm_grid *a, const dpsm_grid *b, int just_loaded, const char *when) {
    for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side) {
        double va = 0.0, vb = 0.0;
        const int sa = dpsm_get_side_outflow(a, side, &va), sb = dpsm_get_side_outflow(b, side, &vb);
        REQUIRE(sa == sb && memcmp(&va, &vb, sizeof va) == 0, "%s: side %d took %.17g (%s) and %.17g (%s)", when,
                side, va, dpsm_status_string(sa), vb, dpsm_status_string(sb));
    }
    int64_t nx, ny;
    CHECK_OK(a, dpsm_get_shape(a, &nx, &ny));
    const int two_d = dpsm_get_side_outflow(a, DPSM_YMIN, &(double){0.0}) == DPSM_OK;
    const size_t nfx = (size_t)((nx + 1) * ny), nfy = two_d ? (size_t)(nx * (ny + 1)) : 0;
    double *xa = calloc(nfx, sizeof(double)), *xb = calloc(nfx, sizeof(double));
    double *ya = calloc(nfy + 1, sizeof(double)), *yb = calloc(nfy + 1, sizeof(double));
    const int sa = dpsm_get_face_fluxes(a, xa, two_d ? ya : NULL), sb = dpsm_get_face_fluxes(b, xb, two_d ? yb : NULL);
    REQUIRE(sa == sb, "%s: face fluxes %s and %s", when, dpsm_status_string(sa), dpsm_status_string(sb));
    if (sa == DPSM_OK) {
        size_t differ = 0, nonzero = 0;
        for (size_t f = 0; f < nfx; ++f) {
            differ += memcmp(&xa[f], &xb[f], sizeof(double)) != 0;
            nonzero += xb[f] != 0.0;
        }
        for (size_t f = 0; f < nfy; ++f) {
            differ += memcmp(&ya[f], &yb[f], sizeof(double)) != 0;
            nonzero += yb[f] != 0.0;
        }
        if (just_loaded)
            REQUIRE(nonzero == 0, "%s: %zu faces of the loaded grid read other than 0 before a step", when, nonzero);
        else
            REQUIRE(differ == 0, "%s: %zu of %zu face fluxes differ", when, differ, nfx + nfy);
    }
    free(xa);
    free(xb);
    free(ya);
    free(yb);
}

/* A reproducible rough terrain in [0, amplitude). */
static void rough(double *h, size_t n, double amplitude, unsigned seed) {
    unsigned s = seed;
    for (size_t c = 0; c < n; ++c) {
        s = s * 1664525u + 1013904223u;
        h[c] = amplitude * (double)(s >> 8) / (double)(1u << 24);
    }
}

/* The calls a host makes after the restart, applied to both grids alike. */
typedef void (*continuation)(dpsm_grid *g, int round);

/* Saves `g` mid-run, loads it, checks the loaded grid reads back the same,
 * that saving it again gives the same bytes, then runs `more` on both and
 * compares after each round. */
static void require_continues(dpsm_grid *g, continuation more, int rounds, const char *name) {
    char path[300], again[300];
    path_of(path, sizeof path, name);
    snprintf(again, sizeof again, "%s.again", path);
    CHECK_OK(g, dpsm_save(g, path));
    dpsm_grid *loaded = NULL;
    CHECK_OK(NULL, dpsm_load(path, &loaded));
    assert_non_null(loaded);
    require_same(g, loaded, 1, name);
    require_same_coupling(g, loaded, 1, name);
    /* Every field comes back exactly: the loaded grid writes the same file. */
    CHECK_OK(loaded, dpsm_save(loaded, again));
    size_t n1, n2;
    unsigned char *b1 = read_file(path, &n1), *b2 = read_file(again, &n2);
    REQUIRE(n1 == n2 && memcmp(b1, b2, n1) == 0, "%s: the loaded grid saves a different file (%zu, %zu bytes)", name,
            n1, n2);
    REQUIRE(crc32_of(b1, n1 - 4) == get_u32(b1 + n1 - 4), "%s: the last 4 bytes are not the file's CRC-32", name);
    print_message("%s: %zu bytes, continues bit for bit over %d rounds\n", name, n1, rounds);
    free(b1);
    free(b2);
    for (int round = 0; round < rounds; ++round) {
        more(g, round);
        more(loaded, round);
        char when[64];
        snprintf(when, sizeof when, "%s, round %d", name, round);
        require_same(g, loaded, 0, when);
        require_same_coupling(g, loaded, 0, when);
    }
    dpsm_destroy(loaded);
}

/* ---- the scenes ------------------------------------------------------------ */

enum { kNx = 70, kNy = 50 };  /* more than one tile of 64 x 64 cells */

static void continue_full(dpsm_grid *g, int round) {
    CHECK_OK(g, dpsm_step(g, 0.02));
    if (round == 1) {
        /* The host drops sand on a block and changes the source. */
        double dh[6 * 4];
        for (int k = 0; k < 24; ++k) dh[k] = 0.05 * (k % 5);
        CHECK_OK(g, dpsm_add_heights_region(g, 30, 20, 6, 4, dh));
        double *q = calloc(kNx * kNy, sizeof(double));
        for (int c = 0; c < kNx * kNy; ++c) q[c] = (c % kNx) < 20 ? -0.3 : 0.01;
        CHECK_OK(g, dpsm_set_source(g, q));
        free(q);
    }
    if (round == 3) CHECK_OK(g, dpsm_step(g, 5.0));
}

/* Every feature at once: obstacles and open cells, open sides (one held at
 * levels that vary along it, a wall side with levels of its own), a source
 * with erosion on a bed (some of it unmet), an angle field, exponent 1.5, a
 * static angle, face fluxes recorded, both schemes, several threads. */
static void test_every_feature_continues_bit_for_bit(void **state) {
    (void)state;
    for (int scheme = DPSM_SCHEME_PAIRWISE; scheme <= DPSM_SCHEME_ISOTROPIC; ++scheme) {
        const size_t n = kNx * kNy;
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, dpsm_create_2d(kNx, kNy, 0.1, 0.08, &g));
        CHECK_OK(g, dpsm_set_scheme(g, scheme));
        CHECK_OK(g, dpsm_set_repose_angle(g, 0.55));
        CHECK_OK(g, dpsm_set_mobility(g, 1.7));
        CHECK_OK(g, dpsm_set_rest_tolerance(g, 3e-6));
        CHECK_OK(g, dpsm_set_max_substeps(g, 5000000));
        CHECK_OK(g, dpsm_set_threads(g, 2));
        CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN));
        CHECK_OK(g, dpsm_set_boundary(g, DPSM_YMIN, DPSM_OPEN));
        double *h = malloc(sizeof(double) * n), *zb = malloc(sizeof(double) * n);
        double *q = malloc(sizeof(double) * n), *theta = malloc(sizeof(double) * n);
        uint8_t *kinds = malloc(n);
        rough(h, n, 0.3, 11u);
        for (size_t c = 0; c < n; ++c) {
            const double x = (double)(c % kNx) * 0.1, y = (double)(c / kNx) * 0.08;
            h[c] += fmax(0.0, 2.0 - 1.5 * hypot(x - 3.5, y - 2.0));
            zb[c] = h[c] - ((c % kNx) < 20 ? 0.02 : 0.5); /* thin sand on the left */
            q[c] = (c % kNx) < 20 ? -0.5 : 0.02 * (double)(c % 3);
            theta[c] = 0.5 + 0.1 * (double)((c / 7) % 3);
            kinds[c] = DPSM_CELL_SAND;
        }
        for (int j = 10; j < 14; ++j)
            for (int i = 45; i < 50; ++i) kinds[i + kNx * j] = DPSM_CELL_WALL;
        kinds[5 + kNx * 40] = DPSM_CELL_OPEN;
        kinds[66 + kNx * 45] = DPSM_CELL_OPEN;
        CHECK_OK(g, dpsm_set_heights(g, h));
        CHECK_OK(g, dpsm_set_cell_kinds(g, kinds));
        CHECK_OK(g, dpsm_set_bedrock(g, zb));
        CHECK_OK(g, dpsm_set_repose_angle_field(g, theta));
        CHECK_OK(g, dpsm_set_flux_exponent(g, 1.5));
        CHECK_OK(g, dpsm_set_static_angle(g, 0.62));
        CHECK_OK(g, dpsm_set_source(g, q));
        double levels[kNx];
        for (int k = 0; k < kNx; ++k) levels[k] = 0.05 + 0.01 * (double)(k % 7);
        CHECK_OK(g, dpsm_set_side_levels(g, DPSM_XMAX, levels));
        CHECK_OK(g, dpsm_set_side_levels(g, DPSM_YMAX, levels));
        CHECK_OK(g, dpsm_set_face_flux_recording(g, 1));
        for (int k = 0; k < 3; ++k) CHECK_OK(g, dpsm_step(g, 0.03));
        double unmet, outflow;
        CHECK_OK(g, dpsm_get_mass(g, DPSM_MASS_UNMET, &unmet));
        CHECK_OK(g, dpsm_get_mass(g, DPSM_MASS_OUTFLOW, &outflow));
        print_message("scheme %d at the save: unmet %.6g, outflow %.6g\n", scheme, unmet, outflow);
        /* The accounts the file must carry are not trivially 0. */
        REQUIRE(unmet > 0.0 && outflow != 0.0, "unmet %g, outflow %g", unmet, outflow);
        require_continues(g, continue_full, 5, scheme ? "full_isotropic.dpsm" : "full_pairwise.dpsm");
        free(h);
        free(zb);
        free(q);
        free(theta);
        free(kinds);
        dpsm_destroy(g);
    }
}

static void continue_plain(dpsm_grid *g, int round) { CHECK_OK(g, dpsm_step(g, round == 2 ? 10.0 : 0.01)); }

static void test_plain_2d_continues_bit_for_bit(void **state) {
    (void)state;
    const int64_t nx = 64, ny = 64;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(nx, ny, 0.1, 0.1, &g));
    double *h = malloc(sizeof(double) * nx * ny);
    for (int64_t c = 0; c < nx * ny; ++c)
        h[c] = fmax(0.0, 2.0 - 2.0 * hypot((double)(c % nx) * 0.1 - 3.2, (double)(c / nx) * 0.1 - 3.2));
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_step(g, 0.02));
    require_continues(g, continue_plain, 4, "plain_64x64.dpsm");
    free(h);
    dpsm_destroy(g);
}

static void continue_1d(dpsm_grid *g, int round) {
    if (round == 1) CHECK_OK(g, dpsm_set_source(g, NULL));
    CHECK_OK(g, dpsm_step(g, 0.05));
}

static void test_1d_continues_bit_for_bit(void **state) {
    (void)state;
    const int64_t nx = 90;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_1d(nx, 0.05, &g));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN));
    double h[90], q[90], zb[90];
    rough(h, 90, 0.2, 5u);
    for (int c = 0; c < 90; ++c) {
        h[c] += c < 30 ? 3.0 - 0.1 * c : 0.0;
        zb[c] = h[c] - 0.05;
        q[c] = c > 60 ? -0.2 : 0.05;
    }
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_bedrock(g, zb));
    CHECK_OK(g, dpsm_set_source(g, q));
    CHECK_OK(g, dpsm_set_flux_exponent(g, 2.0));
    CHECK_OK(g, dpsm_set_static_angle(g, 0.7));
    const double level = 0.4;
    CHECK_OK(g, dpsm_set_side_levels(g, DPSM_XMAX, &level));
    CHECK_OK(g, dpsm_set_face_flux_recording(g, 1));
    CHECK_OK(g, dpsm_step(g, 0.05));
    require_continues(g, continue_1d, 4, "line.dpsm");
    dpsm_destroy(g);
}

static void continue_axisymmetric(dpsm_grid *g, int round) { CHECK_OK(g, dpsm_step(g, round == 3 ? 50.0 : 0.01)); }

static void test_axisymmetric_continues_bit_for_bit(void **state) {
    (void)state;
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_axisymmetric(60, 0.05, &g));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN));
    double h[60], theta[60];
    for (int c = 0; c < 60; ++c) {
        h[c] = c < 20 ? 2.0 : 0.0;
        theta[c] = 0.5 + 0.002 * c;
    }
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_repose_angle_field(g, theta));
    CHECK_OK(g, dpsm_set_face_flux_recording(g, 1));
    CHECK_OK(g, dpsm_step(g, 0.02));
    require_continues(g, continue_axisymmetric, 4, "rings.dpsm");
    dpsm_destroy(g);
}

/* ---- damaged files ------------------------------------------------------------ */

/* A small file with every optional array: source, bed, angle field, moving
 * cells; time-accurate, so that it is a file of version 1. */
static unsigned char *small_file(const char *path, size_t *size) {
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(5, 4, 0.1, 0.1, &g));
    CHECK_OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE));
    double h[20], zb[20], q[20], theta[20];
    for (int c = 0; c < 20; ++c) {
        h[c] = 0.1 * c;
        zb[c] = h[c] - 0.5;
        q[c] = 0.01;
        theta[c] = 0.5;
    }
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_bedrock(g, zb));
    CHECK_OK(g, dpsm_set_source(g, q));
    CHECK_OK(g, dpsm_set_repose_angle_field(g, theta));
    CHECK_OK(g, dpsm_set_static_angle(g, 0.6));
    CHECK_OK(g, dpsm_step(g, 0.1));
    CHECK_OK(g, dpsm_save(g, path));
    dpsm_destroy(g);
    return read_file(path, size);
}

/* A small file with every part of version 4: a 5 x 4 grid whose open side
 * XMAX is held at levels and has taken sand, a wall side YMIN with levels of
 * its own, face fluxes recorded; time-accurate. */
enum { kCoupledBytes = kHeaderBytes + 20 * 13 + 4 * 16 + 8 * (4 + 5) + 4 };
static unsigned char *small_coupled_file(const char *path, size_t *size) {
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(5, 4, 0.1, 0.1, &g));
    CHECK_OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE));
    double h[20], levels[5] = {0.01, 0.02, 0.03, 0.04, 0.05};
    for (int c = 0; c < 20; ++c) h[c] = 0.3 * (c % 5);
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN));
    CHECK_OK(g, dpsm_set_side_levels(g, DPSM_XMAX, levels));
    CHECK_OK(g, dpsm_set_side_levels(g, DPSM_YMIN, levels));
    CHECK_OK(g, dpsm_set_face_flux_recording(g, 1));
    CHECK_OK(g, dpsm_step(g, 0.1));
    CHECK_OK(g, dpsm_save(g, path));
    dpsm_destroy(g);
    return read_file(path, size);
}

/* dpsm_load must refuse the file with DPSM_ERR_BAD_FILE, make no grid and
 * name the file; `phrase` (if any) must be in the message. */
static void require_refused(const char *path, const char *phrase, const char *what) {
    dpsm_grid *out = (dpsm_grid *)&out; /* not NULL: a failure must reset it */
    const int status = dpsm_load(path, &out);
    const char *message = dpsm_last_error(NULL);
    REQUIRE(status == DPSM_ERR_BAD_FILE, "%s: dpsm_load returned %s (%s)", what, dpsm_status_string(status), message);
    REQUIRE(out == NULL, "%s: *out is not NULL after a failure", what);
    REQUIRE(strstr(message, path) != NULL && strstr(message, "dpsm_load") != NULL,
            "%s: the message does not name the function and the file: %s", what, message);
    if (phrase) REQUIRE(strstr(message, phrase) != NULL, "%s: the message lacks '%s': %s", what, phrase, message);
}

/* The file `good` with the double at `offset` replaced by `value`, its
 * checksums made right again, written to `path`: dpsm_load must refuse it
 * with `phrase` in the message (bytes: scratch of `size`). */
static void require_refused_with_f64(const char *path, unsigned char *bytes, const unsigned char *good, size_t size,
                                     size_t offset, double value, const char *phrase, const char *what) {
    memcpy(bytes, good, size);
    put_f64(bytes + offset, value);
    reseal(bytes, size);
    write_file(path, bytes, size);
    require_refused(path, phrase, what);
}

/* Every byte changed, of a file with every array (version 1) and of one
 * with every part of version 4. */
static void every_changed_byte_is_refused(int coupled) {
    char path[300], bad[300];
    path_of(path, sizeof path, "small.dpsm");
    path_of(bad, sizeof bad, "changed.dpsm");
    size_t size;
    unsigned char *good = coupled ? small_coupled_file(path, &size) : small_file(path, &size);
    const size_t want = coupled ? kCoupledBytes : kHeaderBytes + 20 * (8 + 4 + 1 + 8 + 8 + 8 + 1) + 4;
    REQUIRE(size == want, "the small file has %zu bytes, not %zu", size, want);
    REQUIRE(get_u32(good + kOffsetVersion) == (coupled ? 4u : 1u), "the small file is of version %u",
            get_u32(good + kOffsetVersion));
    unsigned char *bytes = malloc(size);
    const unsigned char masks[2] = {0xff, 0x01};
    int tried = 0;
    for (int m = 0; m < 2; ++m)
        for (size_t at = 0; at < size; ++at) {
            memcpy(bytes, good, size);
            bytes[at] ^= masks[m];
            write_file(bad, bytes, size);
            char what[96];
            snprintf(what, sizeof what, "byte %zu ^ 0x%02x", at, masks[m]);
            /* The part of the file each byte lies in says which message. */
            const char *phrase = at < 8 ? "not a dpsm restart file"
                                 : at < 12 ? NULL /* a newer version, or version 0 */
                                 : at < kHeaderBytes ? "checksum mismatch in its header"
                                                     : "checksum mismatch";
            require_refused(bad, phrase, what);
            ++tried;
        }
    print_message("%d changed files of %zu bytes, all refused\n", tried, size);
    /* The intact file still loads. */
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_load(path, &g));
    dpsm_destroy(g);
    free(bytes);
    free(good);
}

static void test_every_changed_byte_is_refused(void **state) {
    (void)state;
    every_changed_byte_is_refused(0);
    every_changed_byte_is_refused(1);
}

static void every_truncation_is_refused(int coupled) {
    char path[300], cut[300];
    path_of(path, sizeof path, "small.dpsm");
    path_of(cut, sizeof cut, "cut.dpsm");
    size_t size;
    unsigned char *good = coupled ? small_coupled_file(path, &size) : small_file(path, &size);
    for (size_t length = 0; length < size; ++length) {
        write_file(cut, good, length);
        char what[64];
        snprintf(what, sizeof what, "the first %zu bytes", length);
        require_refused(cut, length == 0 ? "is empty" : "truncated", what);
    }
    /* The message says how much was expected and found. */
    write_file(cut, good, size - 1);
    char expected[128];
    snprintf(expected, sizeof expected, "expected %zu bytes, found %zu", size, size - 1);
    require_refused(cut, expected, "one byte short");
    /* One byte more is refused too. */
    unsigned char *longer = malloc(size + 1);
    memcpy(longer, good, size);
    longer[size] = 0;
    write_file(cut, longer, size + 1);
    require_refused(cut, "data after the end", "one byte more");
    print_message("%zu truncations and one extension of %zu bytes, all refused\n", size, size);
    free(longer);
    free(good);
}

static void test_every_truncation_is_refused(void **state) {
    (void)state;
    every_truncation_is_refused(0);
    every_truncation_is_refused(1);
}

/* Behind intact checksums, every value is still checked as a setter would. */
static void test_values_are_checked_behind_the_checksum(void **state) {
    (void)state;
    char path[300], bad[300];
    path_of(path, sizeof path, "small.dpsm");
    path_of(bad, sizeof bad, "resealed.dpsm");
    size_t size;
    unsigned char *good = small_file(path, &size);
    REQUIRE(crc32_of((const unsigned char *)"123456789", 9) == 0xcbf43926u, "the test's CRC-32 is not the standard one");
    REQUIRE(get_u32(good + kHeaderChecksum) == crc32_of(good, kHeaderChecksum), "the header's checksum is not its CRC-32");
    unsigned char *bytes = malloc(size);

    REQUIRE(get_u32(good + kOffsetVersion) == 1, "the small file is of version %u, not 1",
            get_u32(good + kOffsetVersion));
    memcpy(bytes, good, size);
    put_u32(bytes + kOffsetVersion, 10);
    reseal(bytes, size);
    write_file(bad, bytes, size);
    require_refused(bad, "written by a newer dpsm, version 10", "version 10");

    /* The relaxations' flags: DPSM_RELAX_AUTO's needs version 3, and a file
     * cannot ask for both. */
    write_with_header(bad, bytes, good, size, 2, 64u);
    require_refused(bad, "need version 3", "the flag of DPSM_RELAX_AUTO in version 2");
    write_with_header(bad, bytes, good, size, 3, 64u | 32u);
    require_refused(bad, "2 relaxation flags are set", "both relaxations");
    /* DPSM_RELAX_LOCAL_STEPS's flag needs version 9, and alone. */
    write_with_header(bad, bytes, good, size, 8, 1u << 18);
    require_refused(bad, "need version 9", "the flag of DPSM_RELAX_LOCAL_STEPS in version 8");
    write_with_header(bad, bytes, good, size, 9, (1u << 18) | 64u);
    require_refused(bad, "2 relaxation flags are set", "local steps and DPSM_RELAX_AUTO");
    /* Version 4's parts need version 4: the recording flag (no data of its own). */
    write_with_header(bad, bytes, good, size, 3, 1u << 12);
    require_refused(bad, "need version 4", "the recording flag in version 3");
    /* Version 6's flag, a mesh whose indices count from 1, needs version 6 and a mesh. */
    write_with_header(bad, bytes, good, size, 5, 1u << 15);
    require_refused(bad, "need version 6", "the flag of a mesh from 1 in version 5");
    write_with_header(bad, bytes, good, size, 6, 1u << 15);
    require_refused(bad, "holds no mesh", "the flag of a mesh from 1 on a grid");
    /* Version 7's flag, a part of a distributed mesh, needs version 7 and a mesh. */
    write_with_header(bad, bytes, good, size, 6, 1u << 16);
    require_refused(bad, "need version 7", "the flag of a mesh's part in version 6");
    write_with_header(bad, bytes, good, size, 7, 1u << 16);
    require_refused(bad, "holds no mesh", "the flag of a mesh's part on a grid");
    /* Version 8's flag, a mesh in longitude and latitude, needs version 8 and a mesh. */
    write_with_header(bad, bytes, good, size, 7, 1u << 17);
    require_refused(bad, "need version 8", "the flag of a geographic mesh in version 7");
    write_with_header(bad, bytes, good, size, 8, 1u << 17);
    require_refused(bad, "holds no mesh", "the flag of a geographic mesh on a grid");

    require_refused_with_f64(bad, bytes, good, size, kOffsetRepose, 2.0, "angle of repose 2 radians",
                             "a repose angle of 2");

    memcpy(bytes, good, size);
    bytes[kHeaderBytes + 20 * 12 + 7] = 3; /* kinds[7] */
    reseal(bytes, size);
    write_file(bad, bytes, size);
    require_refused(bad, "kinds[7] (cell i = 2, j = 1) = 3", "a cell kind 3");

    /* h[4], below its bed, then NaN. */
    require_refused_with_f64(bad, bytes, good, size, kHeaderBytes + 8 * 4, -1.0, "below its bed",
                             "a height below the bed");
    require_refused_with_f64(bad, bytes, good, size, kHeaderBytes + 8 * 4, NAN, "h[4]", "a NaN height");

    /* A header that claims a huge grid is refused by the size of the file,
     * before anything of that size is allocated. */
    memcpy(bytes, good, size);
    put_u32(bytes + kOffsetNx, 0x40000000u);
    reseal(bytes, size);
    write_file(bad, bytes, size);
    require_refused(bad, "truncated: expected", "nx = 2^30");
    free(bytes);
    free(good);
}

static void put_u64(unsigned char *p, uint64_t v) {
    for (int k = 0; k < 8; ++k) p[k] = (unsigned char)(v >> (8 * k));
}

/* The small file as rank `rank` of `ranks` would have saved it at (i0, j0) of
 * a global grid: version 2, the block flag, the block record after the header. */
static unsigned char *as_block(const unsigned char *good, size_t size, uint32_t version, int64_t nxg, int64_t nyg,
                               int64_t i0, int64_t j0, int32_t rank, int32_t ranks, size_t *block_size) {
    *block_size = size + 48;
    unsigned char *b = malloc(*block_size);
    memcpy(b, good, kHeaderBytes);
    memcpy(b + kHeaderBytes + 48, good + kHeaderBytes, size - kHeaderBytes);
    put_u32(b + kOffsetVersion, version);
    put_u32(b + kOffsetFlags, get_u32(b + kOffsetFlags) | 16u);
    unsigned char *r = b + kHeaderBytes;
    put_u64(r, 0x1234abcdu);
    put_u64(r + 8, (uint64_t)nxg);
    put_u64(r + 16, (uint64_t)nyg);
    put_u64(r + 24, (uint64_t)i0);
    put_u64(r + 32, (uint64_t)j0);
    put_u32(r + 40, (uint32_t)rank);
    put_u32(r + 44, (uint32_t)ranks);
    reseal(b, *block_size);
    return b;
}

/* A block of a distributed grid (version 2, written by dpsm_save on one rank
 * of a distributed grid) is not a grid of its own: dpsm_load refuses it and
 * names dpsm_load_mpi; a damaged block record is refused as a bad file. */
static void test_block_files_need_dpsm_load_mpi(void **state) {
    (void)state;
    char path[300], bad[300];
    path_of(path, sizeof path, "small.dpsm");
    path_of(bad, sizeof bad, "block.dpsm");
    size_t size, n;
    unsigned char *good = small_file(path, &size); /* 5 x 4 cells */

    unsigned char *b = as_block(good, size, 2, 10, 8, 5, 4, 1, 2, &n);
    write_file(bad, b, n);
    dpsm_grid *out = (dpsm_grid *)&out;
    int status = dpsm_load(bad, &out);
    const char *message = dpsm_last_error(NULL);
    REQUIRE(status == DPSM_ERR_NOT_APPLICABLE && out == NULL, "a block file: dpsm_load returned %s (%s)",
            dpsm_status_string(status), message);
    REQUIRE(strstr(message, "rank 1 of a grid distributed over 2 ranks") && strstr(message, "dpsm_load_mpi"),
            "a block file: the message does not say what it is and what reads it: %s", message);
    /* Every changed byte of a block file, its block record included, is a bad file. */
    unsigned char *changed = malloc(n);
    const unsigned char masks[2] = {0xff, 0x01};
    for (int m = 0; m < 2; ++m)
        for (size_t at = 0; at < n; ++at) {
            memcpy(changed, b, n);
            changed[at] ^= masks[m];
            write_file(bad, changed, n);
            char what[96];
            snprintf(what, sizeof what, "block file, byte %zu ^ 0x%02x", at, masks[m]);
            require_refused(bad, at < 8 ? "not a dpsm restart file" : at < 12 ? NULL
                                 : at < kHeaderBytes ? "checksum mismatch in its header" : "checksum mismatch",
                            what);
        }
    print_message("%zu changed block files of %zu bytes, all refused\n", 2 * n, n);
    free(changed);
    free(b);

    struct {
        uint32_t version;
        int64_t nxg, nyg, i0, j0;
        int32_t rank, ranks;
        const char *phrase;
    } wrong[] = {
        {1, 10, 8, 5, 4, 1, 2, "need version 2"},
        {2, 10, 8, 5, 4, 2, 2, "rank 2 is not one of its 2 ranks"},
        {2, 10, 8, 5, 4, 0, 0, "says 0 ranks"},
        {2, 10, 8, 6, 4, 1, 2, "does not lie in its global grid"},
        {2, 10, 8, 5, -1, 1, 2, "does not lie in its global grid"},
        {2, 0, 8, 0, 0, 1, 2, "global grid of 0 x 8 cells is not valid"},
    };
    for (size_t k = 0; k < sizeof wrong / sizeof *wrong; ++k) {
        b = as_block(good, size, wrong[k].version, wrong[k].nxg, wrong[k].nyg, wrong[k].i0, wrong[k].j0,
                     wrong[k].rank, wrong[k].ranks, &n);
        write_file(bad, b, n);
        require_refused(bad, wrong[k].phrase, wrong[k].phrase);
        free(b);
    }
    /* The flag without the record: the file is 48 bytes short. */
    unsigned char *bytes = malloc(size);
    write_with_header(bad, bytes, good, size, 2, 16u);
    require_refused(bad, "truncated", "the block flag without its record");
    /* Version 2 without the flag is a grid of its own. */
    write_with_header(bad, bytes, good, size, 2, 0u);
    out = NULL;
    CHECK_OK(NULL, dpsm_load(bad, &out));
    dpsm_destroy(out);
    free(bytes);
    free(good);
}

/* ---- files that cannot be read or written ----------------------------------- */

static void require_io_failure(int status, const char *message, const char *path, const char *what) {
    REQUIRE(status == DPSM_ERR_IO, "%s: returned %s (%s)", what, dpsm_status_string(status), message);
    REQUIRE(strstr(message, path) != NULL, "%s: the message does not name %s: %s", what, path, message);
}

static void test_files_that_cannot_be_used(void **state) {
    (void)state;
    char missing[300], empty[300];
    path_of(missing, sizeof missing, "missing.dpsm");
    path_of(empty, sizeof empty, "empty.dpsm");
    dpsm_grid *out = (dpsm_grid *)&out;
    int status = dpsm_load(missing, &out);
    require_io_failure(status, dpsm_last_error(NULL), missing, "a missing file");
    assert_null(out);
    assert_non_null(strstr(dpsm_last_error(NULL), "No such file"));
    out = (dpsm_grid *)&out;
    status = dpsm_load(dir, &out);
    require_io_failure(status, dpsm_last_error(NULL), dir, "a directory");
    assert_null(out);
    write_file(empty, (const unsigned char *)"", 0);
    require_refused(empty, "is empty", "an empty file");

    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_1d(8, 0.1, &g));
    const char *unwritable = "/nonexistent-dir/x";
    status = dpsm_save(g, unwritable);
    require_io_failure(status, dpsm_last_error(g), unwritable, "saving into a missing directory");
    assert_non_null(strstr(dpsm_last_error(g), "dpsm_save"));
    /* A directory is no file to replace, and no temporary file stays behind. */
    char tmp[300];
    snprintf(tmp, sizeof tmp, "%s.tmp", dir);
    status = dpsm_save(g, dir);
    require_io_failure(status, dpsm_last_error(g), dir, "saving over a directory");
    struct stat st;
    REQUIRE(stat(tmp, &st) != 0, "%s is left behind", tmp);
    /* The grid is as it was and works. */
    CHECK_OK(g, dpsm_step(g, 0.1));
    assert_string_equal(dpsm_last_error(g), "");
    dpsm_destroy(g);
}

/* A save that fails leaves the file it would have replaced as it was. */
static void test_failed_save_leaves_the_old_file(void **state) {
    (void)state;
    char path[300], tmp[310];
    path_of(path, sizeof path, "kept.dpsm");
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(6, 5, 0.1, 0.1, &g));
    double h[30];
    for (int c = 0; c < 30; ++c) h[c] = 0.3 * (c % 4);
    CHECK_OK(g, dpsm_set_heights(g, h));
    CHECK_OK(g, dpsm_save(g, path));
    size_t size_before;
    unsigned char *before = read_file(path, &size_before);
    /* The temporary file cannot be made: a directory stands in its way. */
    REQUIRE(mkdir(tmp, 0700) == 0, "cannot make %s", tmp);
    CHECK_OK(g, dpsm_step(g, 1.0));
    const int status = dpsm_save(g, path);
    require_io_failure(status, dpsm_last_error(g), path, "saving with the temporary file blocked");
    size_t size_after;
    unsigned char *after = read_file(path, &size_after);
    REQUIRE(size_after == size_before && memcmp(before, after, size_before) == 0, "the old file changed");
    rmdir(tmp);
    /* And it is still a good file of the grid as it was saved. */
    dpsm_grid *loaded = NULL;
    CHECK_OK(NULL, dpsm_load(path, &loaded));
    double h2[30];
    CHECK_OK(loaded, dpsm_get_heights(loaded, h2));
    assert_memory_equal(h, h2, sizeof h);
    /* A save that succeeds replaces it. */
    CHECK_OK(g, dpsm_save(g, path));
    free(after);
    after = read_file(path, &size_after);
    REQUIRE(memcmp(before, after, size_before) != 0, "a successful save did not replace the file");
    free(before);
    free(after);
    dpsm_destroy(loaded);
    dpsm_destroy(g);
}

static void test_null_arguments(void **state) {
    (void)state;
    char path[300];
    path_of(path, sizeof path, "null.dpsm");
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_1d(4, 0.1, &g));
    assert_int_equal(dpsm_save(NULL, path), DPSM_ERR_NULL_POINTER);
    assert_non_null(strstr(dpsm_last_error(NULL), "dpsm_save"));
    assert_int_equal(dpsm_save(g, NULL), DPSM_ERR_NULL_POINTER);
    assert_non_null(strstr(dpsm_last_error(g), "path"));
    dpsm_grid *out = (dpsm_grid *)&out;
    assert_int_equal(dpsm_load(NULL, &out), DPSM_ERR_NULL_POINTER);
    assert_null(out);
    assert_non_null(strstr(dpsm_last_error(NULL), "path"));
    CHECK_OK(g, dpsm_save(g, path));
    assert_int_equal(dpsm_load(path, NULL), DPSM_ERR_NULL_POINTER);
    assert_non_null(strstr(dpsm_last_error(NULL), "out"));
    dpsm_destroy(g);
}

/* Version 4: written exactly when a grid has side levels, sand that left
 * through a side, or its face fluxes recorded (each alone makes it, and adds
 * its bytes); behind intact checksums its values are checked too. */
static void test_version_4(void **state) {
    (void)state;
    char path[300], bad[300];
    path_of(path, sizeof path, "v4.dpsm");
    path_of(bad, sizeof bad, "v4_bad.dpsm");
    const size_t base = kHeaderBytes + 20 * 13 + 4;
    const double levels[5] = {0.1, 0.2, 0.3, 0.4, 0.5}, pile = 3.0;
    for (int part = 0; part < 4; ++part) {
        dpsm_grid *g = NULL;
        CHECK_OK(NULL, dpsm_create_2d(5, 4, 0.1, 0.1, &g));
        CHECK_OK(g, dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE));
        size_t more = 0;
        if (part == 1) {
            CHECK_OK(g, dpsm_set_side_levels(g, DPSM_YMAX, levels)); /* on a wall side */
            more = 8 * 5;
        }
        if (part == 2) CHECK_OK(g, dpsm_set_face_flux_recording(g, 1));
        if (part == 3) { /* a pile that leaves through XMIN, a side made a wall again */
            CHECK_OK(g, dpsm_set_heights_region(g, 0, 1, 1, 1, &pile));
            CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMIN, DPSM_OPEN));
            CHECK_OK(g, dpsm_step(g, 1.0));
            CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMIN, DPSM_WALL));
            more = 4 * 16;
        }
        CHECK_OK(g, dpsm_save(g, path));
        size_t size;
        unsigned char *file = read_file(path, &size);
        const uint32_t version = get_u32(file + kOffsetVersion);
        REQUIRE(version == (part == 0 ? 1u : 4u) && size == base + more,
                "part %d: version %u and %zu bytes, expected %u and %zu", part, version, size, part == 0 ? 1u : 4u,
                base + more);
        dpsm_grid *loaded = NULL;
        CHECK_OK(NULL, dpsm_load(path, &loaded));
        require_same(g, loaded, 1, "a file of version 4");
        require_same_coupling(g, loaded, 1, "a file of version 4");
        free(file);
        dpsm_destroy(g);
        dpsm_destroy(loaded);
    }

    /* Behind the checksums: a level or a side's account that is not finite. */
    size_t size;
    unsigned char *good = small_coupled_file(path, &size), *bytes = malloc(size);
    const size_t accounts = kHeaderBytes + 20 * 13, xmax_levels = accounts + 4 * 16;
    require_refused_with_f64(bad, bytes, good, size, xmax_levels + 8 * 2, NAN, "the level beyond face 2 of side 1",
                             "a NaN level");
    require_refused_with_f64(bad, bytes, good, size, xmax_levels + 8 * 4 + 8 * 1, 2e50, /* YMIN's second */
                             "the level beyond face 1 of side 2", "a level out of range");
    require_refused_with_f64(bad, bytes, good, size, accounts + 16 * 1 + 8, INFINITY, /* XMAX's correction */
                             "ledger account is not finite", "an infinite side account");
    /* Levels of a side a 1D grid does not have. */
    dpsm_grid *line = NULL;
    CHECK_OK(NULL, dpsm_create_1d(6, 0.1, &line));
    CHECK_OK(line, dpsm_set_side_levels(line, DPSM_XMAX, levels));
    CHECK_OK(line, dpsm_save(line, path));
    dpsm_destroy(line);
    free(good);
    free(bytes);
    good = read_file(path, &size);
    bytes = malloc(size);
    memcpy(bytes, good, size);
    put_u32(bytes + kOffsetFlags, (get_u32(bytes + kOffsetFlags) & ~(1u << 9)) | (1u << 10));
    reseal(bytes, size);
    write_file(bad, bytes, size);
    require_refused(bad, "levels beyond side 2", "levels beyond the y side of a line");
    free(good);
    free(bytes);
}

/* The figure of the report: a 64 x 64 grid with and without every array. */
static void test_file_sizes(void **state) {
    (void)state;
    char path[300];
    path_of(path, sizeof path, "size.dpsm");
    dpsm_grid *g = NULL;
    CHECK_OK(NULL, dpsm_create_2d(64, 64, 0.1, 0.1, &g));
    CHECK_OK(g, dpsm_save(g, path));
    size_t plain, full;
    free(read_file(path, &plain));
    double *v = calloc(64 * 64, sizeof(double));
    CHECK_OK(g, dpsm_set_source(g, v));
    CHECK_OK(g, dpsm_set_bedrock(g, v));
    for (int c = 0; c < 64 * 64; ++c) v[c] = 0.5;
    CHECK_OK(g, dpsm_set_repose_angle_field(g, v));
    CHECK_OK(g, dpsm_set_static_angle(g, 0.6));
    CHECK_OK(g, dpsm_save(g, path));
    free(read_file(path, &full));
    print_message("64 x 64: %zu bytes plain, %zu bytes with every optional array\n", plain, full);
    assert_int_equal(plain, kHeaderBytes + 64 * 64 * 13 + 4);
    assert_int_equal(full, kHeaderBytes + 64 * 64 * 38 + 4);
    free(v);
    dpsm_destroy(g);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_feature_continues_bit_for_bit),
        cmocka_unit_test(test_plain_2d_continues_bit_for_bit),
        cmocka_unit_test(test_1d_continues_bit_for_bit),
        cmocka_unit_test(test_axisymmetric_continues_bit_for_bit),
        cmocka_unit_test(test_every_changed_byte_is_refused),
        cmocka_unit_test(test_every_truncation_is_refused),
        cmocka_unit_test(test_values_are_checked_behind_the_checksum),
        cmocka_unit_test(test_version_4),
        cmocka_unit_test(test_block_files_need_dpsm_load_mpi),
        cmocka_unit_test(test_files_that_cannot_be_used),
        cmocka_unit_test(test_failed_save_leaves_the_old_file),
        cmocka_unit_test(test_null_arguments),
        cmocka_unit_test(test_file_sizes),
    };
    return cmocka_run_group_tests(tests, make_dir, remove_dir);
}
