/* dpsm_version.h on its own, as C (tests/abi/CMakeLists.txt: C99 and C11,
 * -Wall -Wextra -Werror -pedantic). */
#include <dpsm/dpsm_version.h>

#if !defined(DPSM_VERSION_MAJOR) || !defined(DPSM_VERSION_MINOR) || !defined(DPSM_VERSION_PATCH)
#error "dpsm_version.h does not define the version"
#endif
#if DPSM_VERSION_NUMBER != DPSM_VERSION_MAJOR * 10000 + DPSM_VERSION_MINOR * 100 + DPSM_VERSION_PATCH
#error "DPSM_VERSION_NUMBER does not match its parts"
#endif

/* ISO C wants a declaration in every translation unit. */
const char dpsm_version_h_string[] = DPSM_VERSION_STRING;
