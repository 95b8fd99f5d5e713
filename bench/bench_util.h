/* What the benchmark and validation programs share: a clock, checked calls,
 * memory. Define DPSM_TOOL_NAME before including to name the program in
 * messages. */
#ifndef DPSM_BENCH_UTIL_H
#define DPSM_BENCH_UTIL_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <dpsm/dpsm.h>

#ifndef DPSM_TOOL_NAME
#define DPSM_TOOL_NAME "dpsm-bench"
#endif

#define CHECK(g, call)                                                                             \
    do {                                                                                           \
        int status_ = (call);                                                                      \
        if (status_ != DPSM_OK) {                                                                  \
            fprintf(stderr, DPSM_TOOL_NAME ": %s failed: %s: %s\n", #call, dpsm_status_string(status_), \
                    dpsm_last_error(g));                                                           \
            exit(1);                                                                               \
        }                                                                                          \
    } while (0)

/* Wall-clock time, or with DPSM_BENCH_CLOCK=cpu the CPU time of the process
 * (all its threads): on a machine shared with other jobs that time does not
 * count the time slices they take, so single-thread comparisons stay fair. */
static inline double now_seconds(void) {
    const char *clock = getenv("DPSM_BENCH_CLOCK");
    struct timespec ts;
    clock_gettime(clock && strcmp(clock, "cpu") == 0 ? CLOCK_PROCESS_CPUTIME_ID : CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static inline void *xcalloc(size_t n, size_t size) {
    void *p = calloc(n, size);
    if (!p) {
        fprintf(stderr, DPSM_TOOL_NAME ": out of memory\n");
        exit(1);
    }
    return p;
}

/* A subcommand: its name, what runs it (argv holds the arguments after the
 * name) and a line of help. */
typedef struct {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *help;
} command;

static inline void print_usage(FILE *out, const command *commands, size_t count) {
    fprintf(out, "usage: " DPSM_TOOL_NAME " COMMAND ARGS...   (dpsm %s)\n", dpsm_version_string());
    for (size_t k = 0; k < count; ++k) fprintf(out, "  %-15s %s\n", commands[k].name, commands[k].help);
}

/* The whole main() of a tool made of subcommands. */
static inline int run_command(const command *commands, size_t count, int argc, char **argv) {
    if (argc < 2 || !strcmp(argv[1], "-h") || !strcmp(argv[1], "--help")) {
        print_usage(argc < 2 ? stderr : stdout, commands, count);
        return argc < 2 ? 2 : 0;
    }
    for (size_t k = 0; k < count; ++k)
        if (!strcmp(argv[1], commands[k].name)) return commands[k].run(argc - 2, argv + 2);
    fprintf(stderr, DPSM_TOOL_NAME ": unknown command '%s'\n", argv[1]);
    print_usage(stderr, commands, count);
    return 2;
}

/* The speed subcommands (speed.c). */
int cmd_throughput(int argc, char **argv);
int cmd_sparse(int argc, char **argv);
int cmd_idle(int argc, char **argv);
int cmd_cone(int argc, char **argv);
int cmd_deposits(int argc, char **argv);
int cmd_wind(int argc, char **argv);
int cmd_short(int argc, char **argv);
int cmd_physics(int argc, char **argv);
int cmd_steps(int argc, char **argv); /* relax_study.c */
int cmd_sts(int argc, char **argv);   /* sts_study.c */
int cmd_mesh_accuracy(int argc, char **argv); /* mesh_study.c */
int cmd_mesh(int argc, char **argv);          /* mesh_study.c */
int cmd_mesh_wind(int argc, char **argv);     /* mesh_study.c */
int cmd_lts(int argc, char **argv);           /* lts_study.c */
int cmd_mesh_graded(int argc, char **argv);   /* lts_study.c */
int cmd_lts_compare(int argc, char **argv);   /* lts_study.c */
int cmd_mesh_energies(int argc, char **argv); /* energy_study.c */
int cmd_mesh_plane(int argc, char **argv);    /* energy_study.c */
/* A plane three times steeper than repose with ripples, n x n cells of width 1 (speed.c). */
void steep_surface(double *h, int64_t n);

#endif
