#include "mpi/collective.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>

#include "model/engine.hpp"
#include "model/grid.hpp"
#include "model/ledger.hpp"

namespace dpsm {

void check_mpi(int code, const char *what) {
    if (code == MPI_SUCCESS) return;
    char text[MPI_MAX_ERROR_STRING];
    int length = 0;
    MPI_Error_string(code, text, &length);
    throw Error(DPSM_ERR_INTERNAL, std::string("dpsm (MPI): ") + what + " failed: " + std::string(text, length));
}

void check_communicator(MPI_Comm comm, const char *fn, int &rank, int &size) {
    int initialized = 0, finalized = 0;
    MPI_Initialized(&initialized);
    MPI_Finalized(&finalized);
    if (!initialized || finalized)
        fail(DPSM_ERR_INVALID_VALUE, fn, "MPI is ", finalized ? "finalized" : "not initialized", "; call ", fn,
             " between MPI_Init and MPI_Finalize");
    if (comm == MPI_COMM_NULL) fail(DPSM_ERR_INVALID_VALUE, fn, "comm is MPI_COMM_NULL");
    int inter = 0;
    check_mpi(MPI_Comm_test_inter(comm, &inter), "MPI_Comm_test_inter");
    if (inter) fail(DPSM_ERR_INVALID_VALUE, fn, "comm is an intercommunicator; pass an intracommunicator");
    check_mpi(MPI_Comm_rank(comm, &rank), "MPI_Comm_rank");
    check_mpi(MPI_Comm_size(comm, &size), "MPI_Comm_size");
}

CollectiveDistribution::~CollectiveDistribution() {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized) MPI_Comm_free(&comm_);
}

std::vector<double> CollectiveDistribution::agree_on_step(const Grid &grid, double dt, bool refused,
                                                           std::vector<double> flags) const {
    const bool mesh = grid.geometry().is_mesh();
    const std::size_t first_flag = 1, first_parameter = 1 + flags.size();
    std::vector<double> v{refused ? 1.0 : 0.0};
    v.insert(v.end(), flags.begin(), flags.end());
    std::vector<double> parameters = {refused ? 0.0 : dt,
                                      grid.repose_angle(),
                                      grid.mobility(),
                                      grid.rest_tolerance(),
                                      static_cast<double>(grid.scheme()),
                                      static_cast<double>(grid.max_substeps()),
                                      // Every rank must run the same kernel on its shared faces.
                                      grid.bed().empty() ? 0.0 : 1.0,
                                      grid.angle_field().empty() ? 0.0 : 1.0,
                                      grid.flux_exponent(),
                                      grid.static_angle()};
    std::vector<const char *> names = {"dt",
                                       "the repose angle (dpsm_set_repose_angle)",
                                       "the mobility (dpsm_set_mobility)",
                                       "the rest tolerance (dpsm_set_rest_tolerance)",
                                       "the scheme (dpsm_set_scheme)",
                                       "the sub-step limit (dpsm_set_max_substeps)",
                                       "whether they have a bed (dpsm_set_bedrock, on every rank or none)",
                                       "whether they have an angle field (dpsm_set_repose_angle_field, on every rank "
                                       "or none)",
                                       "the flux exponent (dpsm_set_flux_exponent)",
                                       "the static angle (dpsm_set_static_angle)"};
    if (mesh) {
        parameters.push_back(grid.side_open(0) ? 1.0 : 0.0);
        names.push_back("the domain edge's kind (dpsm_set_boundary with DPSM_MESH_EDGE)");
    } else {
        static const char *const sides[] = {"side DPSM_XMIN (dpsm_set_boundary)", "side DPSM_XMAX (dpsm_set_boundary)",
                                            "side DPSM_YMIN (dpsm_set_boundary)", "side DPSM_YMAX (dpsm_set_boundary)"};
        for (int side = 0; side < 4; ++side) {
            parameters.push_back(grid.side_open(side) ? 1.0 : 0.0);
            names.push_back(sides[side]);
        }
    }
    for (double p : parameters) {
        v.push_back(p);
        v.push_back(-p);
    }
    check_mpi(MPI_Allreduce(MPI_IN_PLACE, v.data(), static_cast<int>(v.size()), MPI_DOUBLE, MPI_MAX, comm_),
              "MPI_Allreduce before dpsm_step");
    if (v[0] != 0.0)
        throw Error(DPSM_ERR_INVALID_VALUE,
                    "dpsm_step: another rank of the distributed grid refused the step (its dt is not finite "
                    "or not positive, or it was set to DPSM_RELAX_TO_REST), so no rank stepped; every rank "
                    "must step the same dt");
    for (std::size_t k = 0; k < parameters.size(); ++k) {
        const double hi = v[first_parameter + 2 * k], lo = -v[first_parameter + 2 * k + 1];
        if (hi != lo) {
            std::ostringstream msg;
            msg.precision(17);
            msg << "dpsm_step: the ranks of the distributed grid differ in " << names[k] << " (from " << lo << " to "
                << hi << "); every rank must step the same dt with the same parameters";
            throw Error(DPSM_ERR_INVALID_VALUE, msg.str());
        }
    }
    return std::vector<double>(v.begin() + static_cast<std::ptrdiff_t>(first_flag),
                               v.begin() + static_cast<std::ptrdiff_t>(first_parameter));
}

void CollectiveDistribution::agree_on_substeps(std::vector<SubstepSummary> &levels) const {
    std::vector<double> &v = substep_values_;
    v.clear();
    for (const SubstepSummary &level : levels) {
        v.push_back(level.moved ? 1.0 : 0.0);
        v.push_back(level.max_excess_slope);
        v.push_back(-static_cast<double>(level.substeps));  // the fewest
    }
    check_mpi(MPI_Allreduce(MPI_IN_PLACE, v.data(), static_cast<int>(v.size()), MPI_DOUBLE, MPI_MAX, comm_),
              "MPI_Allreduce after a sweep");
    for (std::size_t s = 0; s < levels.size(); ++s) {
        levels[s].moved = v[3 * s] != 0.0;
        levels[s].max_excess_slope = v[3 * s + 1];
        levels[s].substeps = static_cast<std::int64_t>(-v[3 * s + 2]);
    }
}

bool Communicator::sum_unless_refused(double local, bool refused, double &total) const {
    std::vector<double> mine = {refused ? 0.0 : local, refused ? 1.0 : 0.0}, all(2 * static_cast<std::size_t>(ranks()));
    check_mpi(MPI_Allgather(mine.data(), 2, MPI_DOUBLE, all.data(), 2, MPI_DOUBLE, comm_), "MPI_Allgather of a sum");
    CompensatedSum sum;
    bool any_refused = false;
    for (std::size_t r = 0; r < all.size(); r += 2) {
        sum.add(all[r]);
        any_refused = any_refused || all[r + 1] != 0.0;
    }
    total = sum.value();
    return !any_refused;
}

double Communicator::sum(double local) const {
    double total = 0.0;
    sum_unless_refused(local, false, total);
    return total;
}

double Communicator::max(double local) const {
    double largest = local;
    check_mpi(MPI_Allreduce(MPI_IN_PLACE, &largest, 1, MPI_DOUBLE, MPI_MAX, comm_), "MPI_Allreduce of a maximum");
    return largest;
}

int Communicator::rank() const {
    int rank = 0;
    MPI_Comm_rank(comm_, &rank);
    return rank;
}

int Communicator::ranks() const {
    int size = 1;
    MPI_Comm_size(comm_, &size);
    return size;
}

std::uint64_t Communicator::shared_mark() const {
    std::uint64_t mark = 0;
    if (rank() == 0) {
        // The clock alone would do between saves of one run; the random
        // bits tell apart runs that save at the same instant.
        mark = static_cast<std::uint64_t>(std::chrono::system_clock::now().time_since_epoch().count());
        try {
            std::random_device device;
            mark ^= (static_cast<std::uint64_t>(device()) << 32) ^ device();
        } catch (const std::exception &) {
            // No random device here: the clock's mark stands.
        }
    }
    check_mpi(MPI_Bcast(&mark, 1, MPI_UINT64_T, 0, comm_), "MPI_Bcast of the save's mark");
    return mark;
}

Failure Communicator::first_failure(int status, const std::string &message) const {
    const int me = rank(), size = ranks();
    std::vector<int> all(static_cast<std::size_t>(size));
    check_mpi(MPI_Allgather(&status, 1, MPI_INT, all.data(), 1, MPI_INT, comm_), "MPI_Allgather of the statuses");
    Failure failure;
    for (int r = 0; r < size && failure.rank < 0; ++r)
        if (all[static_cast<std::size_t>(r)] != DPSM_OK) {
            failure.rank = r;
            failure.status = all[static_cast<std::size_t>(r)];
        }
    if (failure.rank < 0) return failure;
    // The failing rank's message, to every rank.
    int length = me == failure.rank ? static_cast<int>(message.size()) : 0;
    check_mpi(MPI_Bcast(&length, 1, MPI_INT, failure.rank, comm_), "MPI_Bcast of a message");
    failure.message = me == failure.rank ? message : std::string(static_cast<std::size_t>(length), ' ');
    check_mpi(MPI_Bcast(&failure.message[0], length, MPI_CHAR, failure.rank, comm_), "MPI_Bcast of a message");
    return failure;
}

}  // namespace dpsm
