/* What the MPI tests share: a check that counts and reports a failure with
 * the rank, without stopping (every rank must reach the collective calls
 * that follow), and OK() for a dpsm call that must succeed. */
#ifndef DPSM_TESTS_MPI_CHECK_H
#define DPSM_TESTS_MPI_CHECK_H

#include <stdarg.h>
#include <stdio.h>

#include <dpsm/dpsm.h>

static int rank_, size_;
static long failures_;
static long checks_;

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static void require(int cond, const char *fmt, ...) {
    ++checks_;
    if (cond) return;
    ++failures_;
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "FAIL (rank %d of %d): ", rank_, size_);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

#define OK(g, call)                                                                                       \
    do {                                                                                                  \
        int status_ = (call);                                                                             \
        require(status_ == DPSM_OK, "%s:%d: %s returned %s: %s", __FILE__, __LINE__, #call,               \
                dpsm_status_string(status_), dpsm_last_error(g));                                         \
    } while (0)

#endif
