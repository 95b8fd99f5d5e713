/* The state of one dpsm BMI component and what its two source files share:
 * bmi_dpsm.c (run, time, variables, values) and bmi_grids.c (grids). */
#ifndef DPSM_BMI_COMPONENT_H
#define DPSM_BMI_COMPONENT_H

#include <dpsm/bmi.h>

#include "config/config.h"

/* Where a variable lives. On a mesh the flux sits on grid 1, a copy of the
 * mesh, at its edges, and the scalars move up to grid 2: grids are numbered
 * in this order, skipping what the grid kind lacks. */
enum place { PLACE_CELLS, PLACE_FLUX_X, PLACE_FLUX_Y, PLACE_EDGES, PLACE_SCALAR };

enum variable {
    VAR_ELEVATION,
    VAR_BEDROCK,
    VAR_DEPOSITION_RATE,
    VAR_REPOSE_ANGLE,
    VAR_FLUX_X,
    VAR_FLUX_Y,
    VAR_FLUX_EDGES,
    VAR_TOTAL_VOLUME,
    VAR_SOURCED_VOLUME,
    VAR_OUTFLOW_VOLUME,
    VAR_EXTERNAL_VOLUME,
    VAR_UNMET_VOLUME,
    VAR_COUNT
};

struct component {
    struct config config;
    struct config_scene scene;
    double time;
    int64_t nx, ny; /* cells along x and y (ny = 1 on 1d and axisymmetric grids) */
    int has_bedrock;
    /* One buffer per variable, what get_value_ptr() hands out: refreshed
     * after initialize, every update and every set. */
    double *values[VAR_COUNT];
    int64_t sizes[VAR_COUNT];
    /* Face volumes summed over the steps of the current update. */
    double *carried_x, *carried_y;
};

/* The place of a variable on this component's grid kind, or -1 when the
 * kind has no such variable (a y flux on a 1d grid, an edge flux on a grid). */
int component_place(const struct component *c, enum variable v);
/* The grid number of a place, or -1 when the kind has no such place. */
int component_grid_of(const struct component *c, enum place p);
/* The place a grid number stands for, or -1. */
int component_place_of_grid(const struct component *c, int grid);

/* Writes "dpsm bmi: <function>: <message>" to stderr and returns BMI_FAILURE. */
int component_fail(const char *function, const char *format, ...);
/* The component of a table, or NULL (and a message) when it is not initialized. */
struct component *component_of(Bmi *self, const char *function);

/* The grid functions of bmi_grids.c. */
void component_register_grids(Bmi *model);

#endif
