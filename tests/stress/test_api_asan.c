/* tests/test_api.c under AddressSanitizer (DPSM_TESTS_UNDER_ASAN=ON, set by
 * scripts/sanitize asan): the same program, without
 * test_create_too_large_to_allocate. That test asks for 2^59 bytes and expects
 * std::bad_alloc (DPSM_ERR_OUT_OF_MEMORY); ASan's operator new aborts the
 * process on such a request instead of throwing, whatever its options. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

int dpsm_test_api_main(int argc, char **argv); /* test_api.c's main, renamed */

int main(int argc, char **argv) {
    cmocka_set_skip_filter("test_create_too_large_to_allocate");
    return dpsm_test_api_main(argc, argv);
}
