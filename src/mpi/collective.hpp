// What the two kinds of distributed grid share (distributed.cpp: blocks of a
// 2D grid; distributed_mesh.cpp: parts of a mesh): MPI calls that throw
// Error, the communicator's checks, the collectives of model/distribution.hpp
// over a communicator, and a Distribution over a duplicate of the host's
// communicator that agrees on a step's parameters.
#pragma once

#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

#include "model/distribution.hpp"

namespace dpsm {

// Throws Error(DPSM_ERR_INTERNAL) naming `what` unless `code` is MPI_SUCCESS.
void check_mpi(int code, const char *what);

// Checks that MPI is running and `comm` is an intracommunicator; its rank and size.
void check_communicator(MPI_Comm comm, const char *fn, int &rank, int &size);

// The collectives over a communicator the caller owns (a constructor's, a
// load's, before there is a grid).
class Communicator final : public Collectives {
public:
    explicit Communicator(MPI_Comm comm) : comm_(comm) {}
    int rank() const override;
    int ranks() const override;
    double sum(double local) const override;
    double max(double local) const override;
    bool sum_unless_refused(double local, bool refused, double &total) const override;
    Failure first_failure(int status, const std::string &message) const override;
    std::uint64_t shared_mark() const override;

private:
    MPI_Comm comm_;
};

// A Distribution over its own communicator (a duplicate of the host's,
// freed with it).
class CollectiveDistribution : public Distribution {
public:
    explicit CollectiveDistribution(MPI_Comm comm) : comm_(comm), ranks_(comm) {}
    ~CollectiveDistribution() override;

    void agree_on_substeps(std::vector<SubstepSummary> &levels) const override;
    int rank() const override { return ranks_.rank(); }
    int ranks() const override { return ranks_.ranks(); }
    double sum(double local) const override { return ranks_.sum(local); }
    double max(double local) const override { return ranks_.max(local); }
    bool sum_unless_refused(double local, bool refused, double &total) const override {
        return ranks_.sum_unless_refused(local, refused, total);
    }
    Failure first_failure(int status, const std::string &message) const override {
        return ranks_.first_failure(status, message);
    }
    std::uint64_t shared_mark() const override { return ranks_.shared_mark(); }

protected:
    // One MAX all-reduce of `flags` (minima as negated values) together with
    // the step's parameters, which every rank must share; throws on every rank
    // alike when a rank refused the step or the ranks differ. Returns the
    // reduced flags.
    std::vector<double> agree_on_step(const Grid &grid, double dt, bool refused, std::vector<double> flags) const;

    MPI_Comm comm_;

private:
    Communicator ranks_;
    // agree_on_substeps' values, kept between sub-steps: it runs in every
    // one, and an allocation each time is what a sanitizer's run pays most for.
    mutable std::vector<double> substep_values_;
};

}  // namespace dpsm
