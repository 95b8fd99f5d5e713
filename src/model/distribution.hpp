// What a step needs from a distributed run, whatever carries it: agreement
// before a step, global sums, the first failure on any rank, the traffic it
// caused. The MPI component (src/mpi/) implements it; a serial grid has none
// and never pays for any of it. How an engine's cells reach the ranks beside
// it is the engine's own interface (structured/halo.hpp for blocks of a
// grid, mesh/ghost_exchange.hpp for parts of a mesh), which the same object
// implements and the engine finds on the grid's Distribution.
#pragma once

#include <cstdint>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "dpsm/dpsm.h"
#include "model/changes.hpp"
#include "model/error.hpp"

namespace dpsm {

class Engine;
class Grid;
struct SubstepSummary;

// What every rank must agree on before a step (each a global figure; on a
// serial grid, the grid's own).
struct StepAgreement {
    bool source_active = false;   // a source acts somewhere
    bool has_open_cells = false;  // open cells somewhere
    bool may_move = false;        // some cell anywhere may move
    double open_level_min = 0.0, open_level_max = 0.0;  // over all open cells (when there are any)
    double side_level_min = 0.0, side_level_max = 0.0;  // over the levels beyond the open sides (0 where none)
    bool any_side_open = false;  // a side, or a face of a mesh's domain edge, is open
};

// A rank that failed, as every rank learns of it (rank -1: none failed).
struct Failure {
    int rank = -1;
    int status = DPSM_OK;
    std::string message;
};

// The collectives that any call over several ranks needs, with or without a
// grid (a constructor has none yet).
class Collectives {
public:
    virtual ~Collectives() = default;
    virtual int rank() const = 0;
    virtual int ranks() const = 0;
    // The sum over all ranks, the same on every rank (added in rank order).
    virtual double sum(double local) const = 0;
    // The largest over all ranks, the same on every rank.
    virtual double max(double local) const = 0;
    // As sum(), for a call that a rank may have refused (its `local` is then
    // ignored): false on every rank when any rank refused.
    virtual bool sum_unless_refused(double local, bool refused, double &total) const = 0;
    // Every rank passes its own status (DPSM_OK when it succeeded) and the
    // message of its failure; every rank gets the lowest failing rank's.
    virtual Failure first_failure(int status, const std::string &message) const = 0;
    // A number that every rank gets alike and that differs from one call to
    // the next (and between runs): the mark of one save.
    virtual std::uint64_t shared_mark() const = 0;
};

// Runs `body` on this rank; then every rank learns whether any rank failed,
// and when one did, every rank throws: a rank that failed its own error, the
// others Error(status of the lowest failing rank, describe(that Failure)).
// The one way in which calls over several ranks fail alike.
template <class Body, class Describe>
void on_every_rank(const Collectives &ranks, const char *function, Body &&body, Describe &&describe) {
    int status = DPSM_OK;
    std::string message;
    try {
        body();
    } catch (const Error &e) {
        status = e.status();
        message = e.what();
    } catch (const std::bad_alloc &) {
        status = DPSM_ERR_OUT_OF_MEMORY;
        message = std::string(function) + ": out of memory on this rank";
    }
    const Failure failure = ranks.first_failure(status, message);
    if (status != DPSM_OK) throw Error(status, message);
    if (failure.rank >= 0) throw Error(failure.status, describe(failure));
}

// The same, telling the other ranks "function: on rank R: " and the failing
// rank's own message.
std::string on_rank(const char *function, const Failure &failure);
template <class Body>
void on_every_rank(const Collectives &ranks, const char *function, Body &&body) {
    on_every_rank(ranks, function, std::forward<Body>(body),
                  [&](const Failure &failure) { return on_rank(function, failure); });
}

// Where a grid lies in the distributed grid it is part of, as a restart file
// records it: a block's first cell (i0, j0) in a global grid of global_nx x
// global_ny cells; a part of a mesh: global_nx is the global mesh's cells.
struct DistributedPlace {
    std::int64_t global_nx = 0, global_ny = 0, i0 = 0, j0 = 0;
};

// A grid's part in a distributed grid. It hears of the host's edits (so
// that the ghosts take them before the next step).
class Distribution : public Collectives, public ChangeListener {
public:
    // Collective, at the start of dpsm_step: gives the ghosts what hosts
    // changed on any rank since the last step, checks that every rank steps
    // the same dt with the same parameters (throws Error otherwise, on every
    // rank alike), gives the grid the smallest angle of repose of all ranks
    // (it sets the sub-step) and returns the global flags. A rank whose own
    // call was refused still takes part, with `refused`, so that the others
    // do not wait for it: then every rank throws, before anything changed
    // (the refusing rank's caller reports its own reason).
    virtual StepAgreement agree_before_step(Grid &grid, const Engine &engine, double dt, bool refused) = 0;
    // Collective, after each sweep: whether each of its sub-steps moved
    // anything and its largest excess slope, over all ranks, and the fewest
    // sub-steps any rank says it stands for.
    virtual void agree_on_substeps(std::vector<SubstepSummary> &levels) const = 0;
    virtual DistributedPlace place() const = 0;
    // The sub-steps taken between two exchanges of ghost values (0.5: two
    // exchanges in each sub-step).
    virtual double substeps_per_exchange(const Grid &grid) const = 0;
    // The point-to-point messages of ghost cells' values this rank sent, and
    // their bytes, since the last call (collectives are not counted).
    void take_traffic(double &messages, double &bytes) {
        messages = messages_sent_;
        bytes = bytes_sent_;
        messages_sent_ = bytes_sent_ = 0.0;
    }

protected:
    void count_message(double bytes) {
        messages_sent_ += 1.0;
        bytes_sent_ += bytes;
    }

private:
    double messages_sent_ = 0.0, bytes_sent_ = 0.0;
};

}  // namespace dpsm
