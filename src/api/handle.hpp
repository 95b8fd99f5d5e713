// The handle behind the C API's dpsm_grid, shared by the C boundary
// (api/capi.cpp) and the optional MPI component's constructor (src/mpi/).
#pragma once

#include <string>

#include "model/grid.hpp"

struct dpsm_grid {
    explicit dpsm_grid(const dpsm::Geometry &geometry) : core(geometry) {}
    dpsm::Grid core;
    mutable std::string last_error;
};

namespace dpsm {
// Sets (or, with "", clears) the message dpsm_last_error(NULL) returns on
// this thread: for constructors that fail before there is a handle.
void set_error_without_grid(const char *message) noexcept;
}  // namespace dpsm
