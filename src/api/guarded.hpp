// How every entry point of the C API (api/capi.cpp, and the MPI component's
// constructors) runs the core: whatever it throws becomes a status and a
// message, kept on the handle or, with no handle, per thread
// (dpsm_last_error). No C++ exception crosses the C boundary.
#pragma once

#include <exception>
#include <new>
#include <string>

#include "api/handle.hpp"
#include "dpsm/dpsm.h"
#include "model/error.hpp"

namespace dpsm {

// Keeps `message` as the handle's last error (g null: this thread's); "" clears it.
void record_error(const dpsm_grid *g, const char *message) noexcept;

template <class Body>
int guarded(const dpsm_grid *g, const char *function, Body &&body) noexcept {
    try {
        body();
        record_error(g, "");
        return DPSM_OK;
    } catch (const Error &e) {
        record_error(g, e.what());
        return e.status();
    } catch (const std::bad_alloc &) {
        record_error(g, (std::string(function) + ": out of memory").c_str());
        return DPSM_ERR_OUT_OF_MEMORY;
    } catch (const std::exception &e) {
        record_error(g, e.what());
        return DPSM_ERR_INTERNAL;
    } catch (...) {
        record_error(g, "dpsm: internal error of unknown kind");
        return DPSM_ERR_INTERNAL;
    }
}

}  // namespace dpsm
