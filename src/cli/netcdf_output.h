/* The netCDF file `dpsm run` writes: dims (time, y, x) on 2d grids, (time,
 * x) on 1d and axisymmetric grids, (time, cell) with a UGRID mesh on meshes
 * ((time, node) on dual meshes, whose cells are the nodes);
 * the ledger's figures as time series. */
#ifndef DPSM_CLI_NETCDF_OUTPUT_H
#define DPSM_CLI_NETCDF_OUTPUT_H

#include <stddef.h>

#include "config/config.h"

/* The ledger figures in the file's order: total, sourced, external, outflow, unmet. */
#define OUTPUT_LEDGER_FIGURES 5

struct output {
    const char *path;
    int file, open;
    int time_var, h_var, x_var, y_var, faces_var;
    int ledger_vars[OUTPUT_LEDGER_FIGURES];
    int64_t mesh_width;
    size_t cells, snapshots;
};

/* Creates the file (replacing one that is there) with its coordinates or mesh;
 * `history` is the command line. */
int output_open(struct output *out, const struct config *c, const struct config_scene *s, const char *history,
                char *message, size_t size);
/* Appends one snapshot: the time, the heights of every cell, the ledger. */
int output_snapshot(struct output *out, double time, const double *heights, const double ledger[OUTPUT_LEDGER_FIGURES],
                    char *message, size_t size);
int output_close(struct output *out, char *message, size_t size);

#endif
