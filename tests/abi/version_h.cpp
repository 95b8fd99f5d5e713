// dpsm_version.h on its own, as C++17 (tests/abi/CMakeLists.txt).
#include <dpsm/dpsm_version.h>

static_assert(DPSM_VERSION_NUMBER == DPSM_VERSION_MAJOR * 10000 + DPSM_VERSION_MINOR * 100 + DPSM_VERSION_PATCH,
              "DPSM_VERSION_NUMBER does not match its parts");
constexpr const char *dpsm_version_h_string = DPSM_VERSION_STRING;
static_assert(dpsm_version_h_string[0] != '\0', "empty DPSM_VERSION_STRING");
