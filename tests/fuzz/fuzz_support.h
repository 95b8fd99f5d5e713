/* What the fuzz harnesses (fuzz_api.c, fuzz_mpi.c) share: reading the input
 * byte by byte, failing loudly with the operation under way, an optional
 * trace, the harness's own random numbers and an allocation that cannot
 * fail quietly. A harness defines FUZZ_NAME (its name in messages) before
 * including this, and sets g_op and g_opcount as it goes. */
#ifndef DPSM_TESTS_FUZZ_SUPPORT_H
#define DPSM_TESTS_FUZZ_SUPPORT_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#ifndef FUZZ_NAME
#error "define FUZZ_NAME before including fuzz_support.h"
#endif

typedef struct {
    const uint8_t *p;
    size_t n, at;
} reader_t;

static inline unsigned u8(reader_t *r) { return r->at < r->n ? r->p[r->at++] : 0u; }
static inline unsigned u16(reader_t *r) { return u8(r) | (u8(r) << 8); }
static inline int more(const reader_t *r) { return r->at < r->n; }

static const char *g_op = "?"; /* the operation under way, for messages */
static long g_opcount;

#if defined(__GNUC__)
__attribute__((format(printf, 1, 2), noreturn))
#endif
static inline void die(const char *fmt, ...) {
    va_list ap;
    fprintf(stderr, "\n" FUZZ_NAME ": check failed in operation %ld (%s): ", g_opcount, g_op);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\n");
    abort();
}

/* DPSM_FUZZ_TRACE=1: one line per call on stderr (to see what an input does). */
static inline int trace_on(void) {
    static int on = -1;
    if (on < 0) {
        const char *e = getenv("DPSM_FUZZ_TRACE");
        on = e && *e && *e != '0';
    }
    return on;
}

#if defined(__GNUC__)
__attribute__((format(printf, 1, 2)))
#endif
static inline void trace(const char *fmt, ...) {
    if (!trace_on()) return;
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "  [%ld] ", g_opcount);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\n");
}

/* The harness's own random numbers, seeded from the input (xorshift*). */
typedef struct {
    uint64_t s;
} prng_t;

static inline uint64_t prng_next(prng_t *p) {
    uint64_t x = p->s;
    x ^= x >> 12;
    x ^= x << 25;
    x ^= x >> 27;
    p->s = x;
    return x * 0x2545F4914F6CDD1DULL;
}
static inline double prng_unit(prng_t *p) { return (double)(prng_next(p) >> 11) * (1.0 / 9007199254740992.0); }
static inline unsigned prng_below(prng_t *p, unsigned n) { return (unsigned)(prng_next(p) % n); }

static inline void *xcalloc(size_t n, size_t size) {
    void *p = calloc(n ? n : 1, size);
    if (!p) die("out of memory");
    return p;
}

#endif
