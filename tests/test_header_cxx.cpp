// The public header used from C++17: it compiles as C++ (extern "C", no C-only
// constructs), the functions link with C linkage, and a few calls behave.
// Returns 0 only if every check holds.
#include <dpsm/dpsm.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <type_traits>
#include <vector>

static_assert(DPSM_OK == 0, "DPSM_OK must be 0");
static_assert(std::is_same<decltype(&dpsm_step), int (*)(dpsm_grid *, double)>::value, "dpsm_step signature");
static_assert(std::is_same<decltype(&dpsm_get_heights), int (*)(const dpsm_grid *, double *)>::value,
              "dpsm_get_heights signature");
static_assert(std::is_same<decltype(&dpsm_create_2d),
                           int (*)(std::int64_t, std::int64_t, double, double, dpsm_grid **)>::value,
              "dpsm_create_2d signature");

namespace {

int failures = 0;

void check(bool ok, const char *what) {
    if (!ok) {
        std::fprintf(stderr, "FAILED: %s\n", what);
        ++failures;
    }
}

}  // namespace

int main() {
    check(dpsm_version_number() == DPSM_VERSION_NUMBER, "version number matches the header");
    check(std::strcmp(dpsm_version_string(), DPSM_VERSION_STRING) == 0, "version string matches the header");
    check(std::strcmp(dpsm_status_string(DPSM_ERR_INVALID_VALUE), "DPSM_ERR_INVALID_VALUE") == 0, "status string");

    constexpr std::int64_t nx = 9, ny = 7;
    dpsm_grid *g = nullptr;
    check(dpsm_create_2d(nx, ny, 0.5, 0.5, &g) == DPSM_OK && g != nullptr, "dpsm_create_2d");
    if (!g) return 1;
    std::int64_t gx = 0, gy = 0;
    check(dpsm_get_shape(g, &gx, &gy) == DPSM_OK && gx == nx && gy == ny, "dpsm_get_shape");

    std::vector<double> h(static_cast<std::size_t>(nx * ny), 0.0);
    h[static_cast<std::size_t>(4 + nx * 3)] = 5.0;
    check(dpsm_set_heights(g, h.data()) == DPSM_OK, "dpsm_set_heights");
    double m0 = 0.0;
    check(dpsm_get_mass(g, DPSM_MASS_TOTAL, &m0) == DPSM_OK && std::fabs(m0 - 5.0 * 0.25) < 1e-15, "initial mass");
    check(dpsm_step(g, 100.0) == DPSM_OK, "dpsm_step");
    double rest = 0.0, m1 = 0.0;
    check(dpsm_get_step_info(g, DPSM_INFO_AT_REST, &rest) == DPSM_OK && rest == 1.0, "at rest after the collapse");
    check(dpsm_get_mass(g, DPSM_MASS_TOTAL, &m1) == DPSM_OK && std::fabs(m1 - m0) <= 1e-14 * m0,
          "mass kept between walls");
    check(dpsm_get_heights(g, h.data()) == DPSM_OK && h[static_cast<std::size_t>(4 + nx * 3)] < 5.0,
          "the pile spread");

    check(dpsm_set_mobility(g, -1.0) == DPSM_ERR_INVALID_VALUE, "bad mobility refused");
    const char *msg = dpsm_last_error(g);
    check(msg != nullptr && std::strstr(msg, "dpsm_set_mobility") != nullptr, "message names the function");
    check(dpsm_set_mobility(g, 2.0) == DPSM_OK && dpsm_last_error(g)[0] == '\0', "message cleared by success");
    check(dpsm_step(nullptr, 1.0) == DPSM_ERR_NULL_POINTER, "NULL grid refused");

    dpsm_destroy(g);
    dpsm_destroy(nullptr);
    if (failures == 0) std::printf("test_header_cxx: all checks passed\n");
    return failures == 0 ? 0 : 1;
}
