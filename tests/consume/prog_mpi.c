/* Built against an installed dpsm with `pkg-config dpsm-mpi` and run under
 * mpiexec by run.sh: each rank owns a strip of a 40 x 30 walled grid; a
 * collapsing column conserves its mass, which dpsm_get_mass reports globally. */
#include <math.h>
#include <stdio.h>

#include <mpi.h>

#include <dpsm/dpsm_mpi.h>

int main(int argc, char **argv) {
    MPI_Init(&argc, &argv);
    int rank, size;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    const int64_t nx = 40, ny = 30;
    int64_t i0 = rank * nx / size, ni = (rank + 1) * nx / size - i0;
    dpsm_grid *g = NULL;
    int status = dpsm_create_2d_mpi(MPI_COMM_WORLD, nx, ny, i0, 0, ni, ny, 1.0, 1.0, &g);
    if (status != DPSM_OK) {
        fprintf(stderr, "rank %d: %s\n", rank, dpsm_last_error(NULL));
        MPI_Abort(MPI_COMM_WORLD, 1);
    }
    double h[40 * 30], expected = 0.0;
    for (int64_t j = 0; j < ny; ++j)
        for (int64_t i = 0; i < ni; ++i) {
            double x = (double)(i0 + i) - 19.5, y = (double)j - 14.5;
            h[i + ni * j] = x * x + y * y < 64.0 ? 10.0 : 0.0;
        }
    for (int64_t j = 0; j < ny; ++j)
        for (int64_t i = 0; i < nx; ++i) {
            double x = (double)i - 19.5, y = (double)j - 14.5;
            expected += x * x + y * y < 64.0 ? 10.0 : 0.0;
        }
    double total = 0.0, dt = 0.0;
    if (dpsm_set_heights(g, h) || dpsm_stable_dt(g, &dt) || dpsm_step(g, 50 * dt) ||
        dpsm_get_mass(g, DPSM_MASS_TOTAL, &total)) {
        fprintf(stderr, "rank %d: %s\n", rank, dpsm_last_error(g));
        MPI_Abort(MPI_COMM_WORLD, 1);
    }
    dpsm_destroy(g);
    int ok = fabs(total - expected) <= 1e-9 * expected;
    if (!ok) fprintf(stderr, "rank %d: global mass %.17g, expected %.17g\n", rank, total, expected);
    if (rank == 0 && ok) printf("prog_mpi on %d ranks: %s, global mass %g\n", size, dpsm_version_string(), total);
    MPI_Finalize();
    return ok ? 0 : 1;
}
