// The handle behind the C API's dpsm_grid, shared by the C boundary
// (api/capi.cpp) and the optional MPI component's constructors (src/mpi/).
#pragma once

#include <string>

#include "model/grid.hpp"
#include "stepping/engine_for.hpp"

struct dpsm_grid {
    // The engine's state is the grid's from the start, so that it hears of
    // every change a host makes.
    explicit dpsm_grid(const dpsm::Geometry &geometry) : core(geometry) {
        core.set_engine_state(dpsm::engine_for(core).make_state(core));
    }
    dpsm::Grid core;
    mutable std::string last_error;
};
