/* netCDF fields over the cells, for config_build(). */
#ifndef DPSM_CONFIG_NETCDF_INPUT_H
#define DPSM_CONFIG_NETCDF_INPUT_H

#include "config/config.h"

/* Reads `variable` of the file into `values`, refusing it unless it has
 * `rank` dimensions of lengths (length0) or (length0, length1) and finite
 * values within the supported range. */
int netcdf_read_field(const char *path, const char *variable, int rank, size_t length0, size_t length1, double *values,
                      char *message, size_t size);

/* What the attributes of `variable` say about the sign of its values: -1
 * for a depth (CF `positive = "down"`, or a `standard_name` that names a
 * depth, as sea_floor_depth_below_geoid and ADCIRC's depth_below_geoid), 1
 * for an elevation (`positive = "up"`, or a `standard_name` that names an
 * elevation, altitude or height), 0 when they say neither or the file is
 * not netCDF. `said` receives the attribute that says it. */
int netcdf_field_sign(const char *path, const char *variable, char *said, size_t size);

#endif
