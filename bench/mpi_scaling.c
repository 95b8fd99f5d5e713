/* dpsm-bench-mpi: strong and weak scaling of distributed grids, and the cost
 * of their communication measured on its own. Run under mpiexec; prints CSV
 * on rank 0 (a log on stderr). Never run by the tests.
 *
 *   mpiexec -n P dpsm-bench-mpi strong N [SWEEPS]   global N x N grid, P strips of rows
 *   mpiexec -n P dpsm-bench-mpi weak N [SWEEPS]     an N x N block per rank, global N x (P N)
 *   mpiexec -n P dpsm-bench-mpi comm N [REPEATS]    the halo exchange and the all-reduces alone
 *
 * The scene is fully active (every face steeper than the angle of repose: a
 * steep plane with ripples, open sides), so every sweep visits every cell.
 * Each dpsm_step is one sweep of 4 sub-steps (dt = 4 stable steps); one
 * OpenMP thread per rank, so that ranks and not threads share the cores.
 * Times are the slowest rank's (MPI_Wtime, after a barrier), the best of 3.
 * Each line also gives the same blocks stepped as independent serial grids,
 * all ranks at once: what the cores give without communication, so that a
 * loaded machine's noise is not taken for the cost of MPI.
 *
 * comm times, with the same layout of strips (each rank sends 5 rows of
 * heights and residuals, as doubles, to each neighbour), one halo exchange
 * (MPI_Isend / MPI_Irecv / MPI_Waitall, as distributed.cpp does) and one
 * MPI_Allreduce of 8 doubles (the one after each sweep).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mpi.h>

#include <dpsm/dpsm.h>
#include <dpsm/dpsm_mpi.h>

static int rank_, size_;

#define CHECK(g, call)                                                                                   \
    do {                                                                                                 \
        int status_ = (call);                                                                            \
        if (status_ != DPSM_OK) {                                                                        \
            fprintf(stderr, "dpsm-bench-mpi (rank %d): %s failed: %s\n", rank_, #call, dpsm_last_error(g)); \
            MPI_Abort(MPI_COMM_WORLD, 1);                                                                \
        }                                                                                                \
    } while (0)

static void split(int64_t n, int parts, int k, int64_t *start, int64_t *count) {
    int64_t base = n / parts, extra = n % parts;
    *start = k * base + (k < extra ? k : extra);
    *count = base + (k < extra ? 1 : 0);
}

/* The slowest rank's seconds per step over `sweeps` steps of one sweep each:
 * of its block of the distributed grid, or (alone) of a serial grid of the
 * block's size, every rank at the same time: the compute alone, under the
 * same sharing of cores and memory, without any communication. */
static double time_steps(int64_t nx, int64_t ny, int sweeps, int alone, double *updates_per_step) {
    int64_t j0, nj;
    split(ny, size_, rank_, &j0, &nj);
    dpsm_grid *g = NULL;
    if (alone)
        CHECK(NULL, dpsm_create_2d(nx, nj, 1.0, 1.0, &g));
    else
        CHECK(NULL, dpsm_create_2d_mpi(MPI_COMM_WORLD, nx, ny, 0, j0, nx, nj, 1.0, 1.0, &g));
    CHECK(g, dpsm_set_threads(g, 1));
    CHECK(g, dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE)); /* sweeps, as the distributed grid takes */
    CHECK(g, dpsm_set_repose_angle(g, 30.0 * 3.14159265358979323846 / 180.0));
    for (int side = DPSM_XMIN; side <= DPSM_YMAX; ++side) CHECK(g, dpsm_set_boundary(g, side, DPSM_OPEN));
    double *h = malloc((size_t)(nx * nj) * sizeof(double));
    for (int64_t j = 0; j < nj; ++j)
        for (int64_t i = 0; i < nx; ++i) {
            double y = (double)(j0 + j);
            h[i + nx * j] = 2.0 * (double)i + 1.5 * y + 0.3 * sin(0.7 * (double)i) * cos(0.3 * y);
        }
    CHECK(g, dpsm_set_heights(g, h));
    free(h);
    double dt;
    CHECK(g, dpsm_stable_dt(g, &dt));
    CHECK(g, dpsm_step(g, 4.0 * dt)); /* warm up */
    double best = INFINITY;
    for (int round = 0; round < 3; ++round) {
        MPI_Barrier(MPI_COMM_WORLD);
        double t0 = MPI_Wtime();
        for (int s = 0; s < sweeps; ++s) CHECK(g, dpsm_step(g, 4.0 * dt));
        double mine = (MPI_Wtime() - t0) / sweeps, slowest = 0;
        MPI_Allreduce(&mine, &slowest, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
        if (slowest < best) best = slowest;
    }
    CHECK(g, dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, updates_per_step));
    dpsm_destroy(g);
    return best;
}

/* Seconds of one halo exchange (5 rows of heights and residuals each way)
 * and of one 8-double all-reduce, with strips of rows of width nx. */
static void time_comm(int64_t nx, int repeats, double *halo_seconds, double *allreduce_seconds, double *halo_bytes) {
    const int depth = 5;
    const int64_t n = 2 * depth * nx; /* heights and residuals as doubles, as distributed.cpp sends them */
    double *send[2], *recv[2];
    for (int k = 0; k < 2; ++k) {
        send[k] = calloc((size_t)n + 1, sizeof(double));
        recv[k] = calloc((size_t)n + 1, sizeof(double));
    }
    int neighbours[2] = {rank_ - 1, rank_ + 1};
    int count = 0;
    for (int k = 0; k < 2; ++k) count += neighbours[k] >= 0 && neighbours[k] < size_;
    *halo_bytes = (double)count * (double)(n + 1) * sizeof(double);
    double best_halo = INFINITY, best_reduce = INFINITY;
    for (int round = 0; round < 3; ++round) {
        MPI_Barrier(MPI_COMM_WORLD);
        double t0 = MPI_Wtime();
        for (int r = 0; r < repeats; ++r) {
            MPI_Request req[4];
            int m = 0;
            for (int k = 0; k < 2; ++k)
                if (neighbours[k] >= 0 && neighbours[k] < size_)
                    MPI_Irecv(recv[k], (int)n + 1, MPI_DOUBLE, neighbours[k], 7, MPI_COMM_WORLD, &req[m++]);
            for (int k = 0; k < 2; ++k)
                if (neighbours[k] >= 0 && neighbours[k] < size_)
                    MPI_Isend(send[k], (int)n + 1, MPI_DOUBLE, neighbours[k], 7, MPI_COMM_WORLD, &req[m++]);
            MPI_Waitall(m, req, MPI_STATUSES_IGNORE);
        }
        double mine = (MPI_Wtime() - t0) / repeats, slowest = 0;
        MPI_Allreduce(&mine, &slowest, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
        if (slowest < best_halo) best_halo = slowest;

        double v[8] = {0}, w[8];
        MPI_Barrier(MPI_COMM_WORLD);
        t0 = MPI_Wtime();
        for (int r = 0; r < repeats; ++r) MPI_Allreduce(v, w, 8, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
        mine = (MPI_Wtime() - t0) / repeats;
        MPI_Allreduce(&mine, &slowest, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
        if (slowest < best_reduce) best_reduce = slowest;
    }
    *halo_seconds = best_halo;
    *allreduce_seconds = best_reduce;
    for (int k = 0; k < 2; ++k) {
        free(send[k]);
        free(recv[k]);
    }
}

int main(int argc, char **argv) {
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    if (argc < 3 || (strcmp(argv[1], "strong") && strcmp(argv[1], "weak") && strcmp(argv[1], "comm"))) {
        if (rank_ == 0) fprintf(stderr, "usage: mpiexec -n P %s strong|weak|comm N [SWEEPS|REPEATS]\n", argv[0]);
        MPI_Finalize();
        return 2;
    }
    const int64_t n = atoll(argv[2]);
    const int repeat = argc > 3 ? atoi(argv[3]) : 0;
    if (!strcmp(argv[1], "comm")) {
        double halo, reduce, bytes;
        time_comm(n, repeat > 0 ? repeat : 2000, &halo, &reduce, &bytes);
        if (rank_ == 0) {
            printf("mode,ranks,width,halo_bytes_per_rank,halo_exchange_s,allreduce_8_doubles_s\n");
            printf("comm,%d,%lld,%.0f,%.3e,%.3e\n", size_, (long long)n, bytes, halo, reduce);
        }
    } else {
        const int weak = !strcmp(argv[1], "weak");
        const int64_t nx = n, ny = weak ? n * size_ : n;
        double updates = 0, alone_updates = 0;
        const int sweeps = repeat > 0 ? repeat : 10;
        const double seconds = time_steps(nx, ny, sweeps, 0, &updates);
        const double alone = time_steps(nx, ny, sweeps, 1, &alone_updates);
        if (rank_ == 0) {
            printf("mode,ranks,nx_global,ny_global,cells_per_rank,seconds_per_sweep,mcell_updates_per_s,"
                   "blocks_alone_seconds_per_sweep\n");
            printf("%s,%d,%lld,%lld,%lld,%.4e,%.1f,%.4e\n", argv[1], size_, (long long)nx, (long long)ny,
                   (long long)(nx * ny / size_), seconds, updates / seconds / 1e6, alone);
        }
    }
    MPI_Finalize();
    return 0;
}
