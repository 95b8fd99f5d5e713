/* Small netCDF files for the tests of the configuration and the BMI
 * component: a UGRID mesh of mixed polygons and fields over the cells. */
#ifndef DPSM_TESTS_UGRID_FILE_H
#define DPSM_TESTS_UGRID_FILE_H

#include <stddef.h>

/* The test mesh: nodes on a 3 x 3 lattice of spacing 1 (node i + 3 j at
 * (i, j)), three unit squares and two triangles over the top right square,
 * written with node indices from `start_index` (0 or 1) and the triangles
 * padded with _FillValue; the coordinates have units "m". */
#define UGRID_TEST_NODES 9
#define UGRID_TEST_FACES 5
#define UGRID_TEST_EDGES 13
extern const int ugrid_test_face_nodes[UGRID_TEST_FACES][4]; /* from 0, -1 pads */

/* Writes the mesh; returns 0 or a netCDF status. */
int write_ugrid_test_mesh(const char *path, int start_index);

/* Writes a double variable `name` of dimensions `dims` (1 or 2 names, with
 * `lengths`) holding `values`; returns 0 or a netCDF status. */
int write_field_file(const char *path, const char *name, int rank, const char *const *dims, const size_t *lengths,
                     const double *values);

#endif
