/* dpsm: the command line.
 *
 *   dpsm run CONFIG.yaml   runs the configuration (docs/guide_bmi.md lists its
 *                          keys) to its end time, shows progress, writes
 *                          snapshots and the ledger to output.file every
 *                          output.every seconds, prints the mass balance
 *   dpsm plot OUT.nc [-o FILE] [--show]
 *                          draws that output: hands over to the Python
 *                          package (dpsm/plot.py), which needs matplotlib
 *   dpsm --version
 *
 * Exit status: 0 done, 1 the run failed (the reason on stderr), 2 a usage error. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli/netcdf_output.h"
#include "config/config.h"

static const int kLedgerQuantities[OUTPUT_LEDGER_FIGURES] = {DPSM_MASS_TOTAL, DPSM_MASS_SOURCED, DPSM_MASS_EXTERNAL,
                                                             DPSM_MASS_OUTFLOW, DPSM_MASS_UNMET};

static void usage(FILE *to) {
    fprintf(to, "usage: dpsm run CONFIG.yaml    run a configuration to its end time (docs/guide_bmi.md)\n"
                "       dpsm plot OUT.nc [-o FILE] [--show]\n"
                "                              draw the last snapshot and the ledger of a run's output to\n"
                "                              OUT.png (or FILE); runs python3 -m dpsm plot, or $DPSM_PYTHON\n"
                "       dpsm --version\n");
}

static double wall_seconds(void) {
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}

struct progress {
    int terminal;
    double started, end;
    long steps;
    size_t snapshots;
};

/* One line of progress: overwritten in place on a terminal, a line of its
 * own otherwise (then only at snapshots, so a log stays short). */
static void show(const struct progress *p, double t, long moving, int at_snapshot) {
    if (!p->terminal && !at_snapshot) return;
    double elapsed = wall_seconds() - p->started;
    double left = t > 0 ? elapsed * (p->end - t) / t : 0;
    printf("%st = %.6g / %.6g s  steps %ld  cells moving %ld  snapshots %zu  time left %.1f s%s",
           p->terminal ? "\r" : "", t, p->end, p->steps, moving, p->snapshots, left, p->terminal ? "   " : "\n");
    fflush(stdout);
}

struct run {
    struct config config;
    struct config_scene scene;
    struct output output;
    double *heights, *before;
    char message[CONFIG_MESSAGE_MAX];
};

static int fail(struct run *r, const char *what) {
    fprintf(stderr, "dpsm run: %s\n", what ? what : r->message);
    return 1;
}

static void read_ledger(const struct run *r, double ledger[OUTPUT_LEDGER_FIGURES]) {
    for (int k = 0; k < OUTPUT_LEDGER_FIGURES; ++k) dpsm_get_mass(r->scene.grid, kLedgerQuantities[k], &ledger[k]);
}

static int snapshot(struct run *r, double t, struct progress *p) {
    if (!r->config.has_output) return 0;
    double ledger[OUTPUT_LEDGER_FIGURES];
    read_ledger(r, ledger);
    if (output_snapshot(&r->output, t, r->heights, ledger, r->message, sizeof r->message)) return fail(r, NULL);
    p->snapshots = r->output.snapshots;
    return 0;
}

/* Steps from t to `target` in time steps and a final partial one that lands
 * on it exactly, as the BMI component's update_until does. */
static int advance(struct run *r, double *t, double target, struct progress *p, long *moving) {
    double dt = r->config.time_step;
    while (*t < target) {
        int last = target - *t <= dt * (1 + 1e-6);
        double this_dt = last ? target - *t : dt;
        memcpy(r->before, r->heights, (size_t)r->scene.cell_count * sizeof *r->before);
        if (config_scene_before_step(&r->scene, r->message, sizeof r->message)) {
            if (p->terminal) putchar('\n');
            fprintf(stderr, "dpsm run: before the step at t = %.17g s: %s\n", *t, r->message);
            return 1;
        }
        if (dpsm_step(r->scene.grid, this_dt) != DPSM_OK) {
            if (p->terminal) putchar('\n');
            fprintf(stderr, "dpsm run: the step at t = %.17g s failed: %s\n", *t, dpsm_last_error(r->scene.grid));
            return 1;
        }
        dpsm_get_heights(r->scene.grid, r->heights);
        *moving = 0;
        for (int64_t k = 0; k < r->scene.cell_count; ++k) *moving += r->heights[k] != r->before[k];
        *t = last ? target : *t + dt;
        ++p->steps;
        show(p, *t, *moving, 0);
    }
    return 0;
}

/* What was read: the mesh file, its cells, its coordinates, its edge. */
static void describe_mesh(const struct run *r) {
    const struct config_mesh *m = &r->scene.mesh;
    const struct config *c = &r->config;
    printf("mesh: %s (%s%s%s), %lld nodes, %lld faces%s\n", c->mesh_file, m->format, m->topology[0] ? " topology " : "",
           m->topology, (long long)m->node_count, (long long)m->face_count,
           m->faces_from_edges ? " built from its edges" : "");
    printf("cells: %lld (%s), coordinates %s%s%s%s\n", (long long)r->scene.cell_count,
           r->scene.cells_at_nodes ? "the median dual: one per node" : "one per face",
           r->scene.geographic ? "geographic (degrees; lengths and areas on the sphere)" : "projected (metres)",
           c->coordinates != CONFIG_COORDINATES_FROM_FILE ? ", as grid.coordinates says" : "",
           c->coordinates == CONFIG_COORDINATES_FROM_FILE && m->coordinates != CONFIG_COORDINATES_FROM_FILE ? ", as " : "",
           c->coordinates == CONFIG_COORDINATES_FROM_FILE && m->coordinates != CONFIG_COORDINATES_FROM_FILE
               ? m->coordinates_said
               : "");
    int64_t edge = 0;
    for (int64_t f = 0; f < r->scene.face_count; ++f) edge += r->scene.face_cells[2 * f + 1] < 0;
    char level[CONFIG_PATH_MAX + CONFIG_NAME_MAX + 64];
    if (c->level_kind == CONFIG_LEVEL_NUMBER) snprintf(level, sizeof level, "%g m", c->level);
    else if (c->level_kind == CONFIG_LEVEL_CELL) snprintf(level, sizeof level, "each face's cell's own, before every step");
    else if (c->level_kind == CONFIG_LEVEL_FILE)
        snprintf(level, sizeof level, "\"%s\" of %s%s", c->level_variable, c->level_file,
                 c->level_positive < 0 ? " (depths, negated)" : "");
    else snprintf(level, sizeof level, "0 m");
    char named[512] = "";
    for (int k = 0; k < c->group_count; ++k) {
        strncat(named, k ? ", " : "", sizeof named - strlen(named) - 1);
        strncat(named, c->groups[k], sizeof named - strlen(named) - 1);
    }
    const int open = c->boundary[DPSM_MESH_EDGE] == DPSM_OPEN;
    printf("edge: %lld faces on the domain edge (%d groups in the file): %s%s%s%s%s\n", (long long)edge,
           m->group_count, open ? "open" : "walls", c->group_count ? (open ? ", walls: " : ", open: ") : "", named,
           open || (c->group_count && c->groups_open) ? "; the level beyond open faces: " : "",
           open || (c->group_count && c->groups_open) ? level : "");
}

static void print_balance(const struct run *r) {
    double ledger[OUTPUT_LEDGER_FIGURES];
    read_ledger(r, ledger);
    double closing = ledger[0] - (ledger[1] + ledger[2] - ledger[3]);
    printf("mass balance (m3, since the start):\n"
           "  total     %.17g\n"
           "  sourced   %.17g\n"
           "  external  %.17g   (the initial heights included)\n"
           "  outflow   %.17g\n"
           "  unmet     %.17g\n"
           "  total - (sourced + external - outflow) = %.3g\n",
           ledger[0], ledger[1], ledger[2], ledger[3], ledger[4], closing);
}

static int run(const char *path) {
    static struct run r; /* the configuration is large; nothing else uses it */
    if (config_read(path, &r.config, r.message, sizeof r.message) ||
        config_build(&r.config, &r.scene, r.message, sizeof r.message))
        return fail(&r, NULL);
    if (r.scene.has_mesh) describe_mesh(&r);
    int64_t n = r.scene.cell_count;
    r.heights = malloc((size_t)n * sizeof *r.heights);
    r.before = malloc((size_t)n * sizeof *r.before);
    if (!r.heights || !r.before) return fail(&r, "out of memory");
    dpsm_get_heights(r.scene.grid, r.heights);
    char history[CONFIG_PATH_MAX + 16];
    snprintf(history, sizeof history, "dpsm run %s", path);
    if (r.config.has_output && output_open(&r.output, &r.config, &r.scene, history, r.message, sizeof r.message))
        return fail(&r, NULL);

    struct progress p = {isatty(STDOUT_FILENO), wall_seconds(), r.config.time_end, 0, 0};
    double t = 0, every = r.config.has_output ? r.config.output_every : r.config.time_end;
    long moving = 0, intervals = 0;
    int failed = snapshot(&r, 0, &p);
    while (!failed && t < r.config.time_end) {
        /* Snapshot times are multiples of `every`, the end time included; one
         * that falls within a millionth of a step of the end is the end. */
        double target = (double)(++intervals) * every;
        if (target >= r.config.time_end - 1e-6 * r.config.time_step) target = r.config.time_end;
        failed = advance(&r, &t, target, &p, &moving) || snapshot(&r, t, &p);
        if (!failed) show(&p, t, moving, 1);
    }
    if (p.terminal) putchar('\n');
    if (r.config.has_output && output_close(&r.output, r.message, sizeof r.message) && !failed) failed = fail(&r, NULL);
    if (!failed) {
        if (r.config.has_output) printf("wrote %zu snapshots to %s\n", r.output.snapshots, r.config.output_file);
        print_balance(&r);
    }
    free(r.heights);
    free(r.before);
    config_scene_free(&r.scene);
    return failed;
}

/* What `python3 -m dpsm plot ARGS` runs, with one message instead of Python's
 * "No module named dpsm" when the package cannot be imported. */
static const char kPlotBootstrap[] =
    "import sys\n"
    "try:\n"
    "    from dpsm.__main__ import main\n"
    "except ImportError as e:\n"
    "    sys.exit('dpsm plot: the Python package dpsm cannot be imported by %s (%s); put the folder that holds '\n"
    "             'dpsm/ on PYTHONPATH, install dpsm (cmake --install, pip install .) or set DPSM_PYTHON to a '\n"
    "             'python3 that has it' % (sys.executable, e))\n"
    "sys.exit(main(['plot'] + sys.argv[1:]))\n";

/* The installed program finds the Python package installed with it
 * (DPSM_CLI_PYTHONDIR, relative to bin/), which a python3 does not look in
 * for every prefix; it goes ahead of PYTHONPATH, so the package matches the
 * program. */
static void find_installed_package(void) {
#if defined(DPSM_CLI_PYTHONDIR) && defined(__linux__)
    char self[PATH_MAX], package[PATH_MAX + 64];
    ssize_t length = readlink("/proc/self/exe", self, sizeof self - 1);
    if (length <= 0) return;
    self[length] = '\0';
    char *slash = strrchr(self, '/');
    if (!slash) return;
    *slash = '\0';
    snprintf(package, sizeof package, "%s/%s/dpsm/__init__.py", self, DPSM_CLI_PYTHONDIR);
    if (access(package, R_OK) != 0) return;
    *strrchr(package, '/') = '\0';
    *strrchr(package, '/') = '\0';
    const char *before = getenv("PYTHONPATH");
    if (before && *before) {
        size_t size = strlen(package) + strlen(before) + 2;
        char *joined = malloc(size);
        if (!joined) return;
        snprintf(joined, size, "%s:%s", package, before);
        setenv("PYTHONPATH", joined, 1);
        free(joined);
    } else {
        setenv("PYTHONPATH", package, 1);
    }
#endif
}

/* `dpsm plot ARGS`: the drawing is Python's (matplotlib); this process
 * becomes the interpreter, so its exit status is the plot's. */
static int plot(int argc, char **argv) {
    const char *python = getenv("DPSM_PYTHON");
    if (!python || !*python) python = "python3";
    char **args = calloc((size_t)argc + 4, sizeof *args);
    if (!args) {
        fprintf(stderr, "dpsm plot: out of memory\n");
        return 1;
    }
    args[0] = (char *)python;
    args[1] = "-c";
    args[2] = (char *)kPlotBootstrap;
    for (int k = 0; k < argc; ++k) args[3 + k] = argv[k];
    find_installed_package();
    fflush(stdout);
    execvp(python, args);
    fprintf(stderr,
            "dpsm plot: cannot run the Python interpreter \"%s\" (%s); dpsm plot needs python3 with matplotlib, "
            "numpy and netCDF4 (Debian: apt-get install python3 python3-matplotlib python3-numpy python3-netcdf4) "
            "and the dpsm package on PYTHONPATH; DPSM_PYTHON names another interpreter\n",
            python, strerror(errno));
    free(args);
    return 1;
}

int main(int argc, char **argv) {
    if (argc == 2 && (strcmp(argv[1], "--version") == 0 || strcmp(argv[1], "-V") == 0)) {
        printf("dpsm %s\n", dpsm_version_string());
        return 0;
    }
    if (argc == 2 && (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0)) {
        usage(stdout);
        return 0;
    }
    if (argc == 3 && strcmp(argv[1], "run") == 0) return run(argv[2]);
    if (argc >= 3 && strcmp(argv[1], "plot") == 0) return plot(argc - 2, argv + 2);
    if (argc >= 2 && strcmp(argv[1], "run") == 0)
        fprintf(stderr, "dpsm run: expected one configuration file\n");
    else if (argc >= 2 && strcmp(argv[1], "plot") == 0)
        fprintf(stderr, "dpsm plot: expected the netCDF file written by dpsm run\n");
    else if (argc >= 2)
        fprintf(stderr, "dpsm: unknown command \"%s\"\n", argv[1]);
    usage(stderr);
    return 2;
}
