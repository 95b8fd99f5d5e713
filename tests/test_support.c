#include "test_support.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdio.h>

#include <cmocka.h>

void check_ok_(const dpsm_grid *g, int status, const char *text, const char *file, int line) {
    if (status != DPSM_OK) {
        print_error("%s returned %s: %s\n", text, dpsm_status_string(status), dpsm_last_error(g));
        _fail(file, line);
    }
}

void require_at(int cond, const char *file, int line, const char *fmt, ...) {
    if (cond) return;
    va_list ap;
    va_start(ap, fmt);
    vprint_error(fmt, ap);
    va_end(ap);
    print_error("\n");
    _fail(file, line);
}

double step_info_of(const dpsm_grid *g, int item) {
    double v = -1.0;
    CHECK_OK(g, dpsm_get_step_info(g, item, &v));
    return v;
}

double mass_of(const dpsm_grid *g, int quantity) {
    double v = 0.0;
    CHECK_OK(g, dpsm_get_mass(g, quantity, &v));
    return v;
}

ledger_t read_ledger(const dpsm_grid *g) {
    ledger_t l;
    CHECK_OK(g, dpsm_get_mass(g, DPSM_MASS_TOTAL, &l.total));
    CHECK_OK(g, dpsm_get_mass(g, DPSM_MASS_SOURCED, &l.sourced));
    CHECK_OK(g, dpsm_get_mass(g, DPSM_MASS_EXTERNAL, &l.external));
    CHECK_OK(g, dpsm_get_mass(g, DPSM_MASS_OUTFLOW, &l.outflow));
    return l;
}

double ledger_residual(const dpsm_grid *g) {
    const ledger_t l = read_ledger(g);
    double scale = fmax(fmax(fabs(l.total), fabs(l.sourced)), fmax(fabs(l.external), fabs(l.outflow)));
    if (scale == 0.0) scale = 1.0;
    return fabs(l.total - (l.sourced + l.external - l.outflow)) / scale;
}

double max_of(const double *v, size_t n) {
    double m = -INFINITY;
    for (size_t i = 0; i < n; ++i) m = fmax(m, v[i]);
    return m;
}

double min_of(const double *v, size_t n) {
    double m = INFINITY;
    for (size_t i = 0; i < n; ++i) m = fmin(m, v[i]);
    return m;
}

double max_face_slope(const double *h, const uint8_t *kinds, int64_t nx, int64_t ny, double dx, double dy) {
    double s = 0.0;
    for (int64_t j = 0; j < ny; ++j)
        for (int64_t i = 0; i < nx; ++i) {
            const int64_t c = i + nx * j;
            if (kinds && kinds[c] != DPSM_CELL_SAND) continue;
            if (i + 1 < nx && (!kinds || kinds[c + 1] == DPSM_CELL_SAND)) s = fmax(s, fabs(h[c + 1] - h[c]) / dx);
            if (j + 1 < ny && (!kinds || kinds[c + nx] == DPSM_CELL_SAND)) s = fmax(s, fabs(h[c + nx] - h[c]) / dy);
        }
    return s;
}

void set_all_sides(dpsm_grid *g, int kind, int dim) {
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMIN, kind));
    CHECK_OK(g, dpsm_set_boundary(g, DPSM_XMAX, kind));
    if (dim == 2) {
        CHECK_OK(g, dpsm_set_boundary(g, DPSM_YMIN, kind));
        CHECK_OK(g, dpsm_set_boundary(g, DPSM_YMAX, kind));
    }
}
