/* netCDF fields over the cells, for config_build(). */
#ifndef DPSM_CONFIG_NETCDF_INPUT_H
#define DPSM_CONFIG_NETCDF_INPUT_H

#include "config/config.h"

/* Reads `variable` of the file into `values`, refusing it unless it has
 * `rank` dimensions of lengths (length0) or (length0, length1) and finite
 * values within the supported range. */
int netcdf_read_field(const char *path, const char *variable, int rank, size_t length0, size_t length1, double *values,
                      char *message, size_t size);

#endif
