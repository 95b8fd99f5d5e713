// What the two kinds of distributed grid share (distributed.cpp: blocks of a
// 2D grid; distributed_mesh.cpp: parts of a mesh): MPI calls that throw
// Error, the communicator's checks, and a Decomposition over a duplicate of
// the host's communicator that agrees on a step's parameters, sums figures in
// rank order, and tells every rank which rank failed.
#pragma once

#include <mpi.h>

#include <cstdint>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "api/handle.hpp"
#include "dpsm/dpsm.h"
#include "model/error.hpp"
#include "mpi/decomposition.hpp"

namespace dpsm {

// Throws Error(DPSM_ERR_INTERNAL) naming `what` unless `code` is MPI_SUCCESS.
void check_mpi(int code, const char *what);

// Checks that MPI is running and `comm` is an intracommunicator; its rank and size.
void check_communicator(MPI_Comm comm, const char *fn, int &rank, int &size);

// Runs `body` (which makes a grid without a handle to report on) and turns
// whatever it throws into a status and the message of dpsm_last_error(NULL).
template <class Body>
int without_grid(const char *fn, Body &&body) noexcept {
    try {
        body();
        set_error_without_grid("");
        return DPSM_OK;
    } catch (const Error &e) {
        set_error_without_grid(e.what());
        return e.status();
    } catch (const std::bad_alloc &) {
        set_error_without_grid((std::string(fn) + ": out of memory").c_str());
        return DPSM_ERR_OUT_OF_MEMORY;
    } catch (const std::exception &e) {
        set_error_without_grid(e.what());
        return DPSM_ERR_INTERNAL;
    } catch (...) {
        set_error_without_grid("dpsm: internal error of unknown kind");
        return DPSM_ERR_INTERNAL;
    }
}

// A Decomposition over its own communicator (a duplicate of the host's,
// freed with it).
class CollectiveDecomposition : public Decomposition {
public:
    explicit CollectiveDecomposition(MPI_Comm comm) : comm_(comm) {}
    ~CollectiveDecomposition() override;

    void after_sweep(std::vector<SubstepSummary> &levels) override;
    double sum(double local) const override;
    bool sum_unless_refused(double local, bool refused, double &total) const override;
    int rank() const override;
    int ranks() const override;
    std::uint64_t shared_mark() const override;
    void first_failure(int status, int &failed_rank, int &failed_status) const override;

protected:
    // One MAX all-reduce of `flags` (minima as negated values) together with
    // the step's parameters, which every rank must share; throws on every rank
    // alike when a rank refused the step or the ranks differ. Returns the
    // reduced flags.
    std::vector<double> agree_on_step(const Grid &grid, double dt, bool refused, std::vector<double> flags) const;

    MPI_Comm comm_;
};

}  // namespace dpsm
