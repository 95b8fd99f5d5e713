// The one exception type of the core. The C boundary (api/capi.cpp) turns it into a
// status code and a per-handle message; nothing else may cross that boundary.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace dpsm {

class Error : public std::runtime_error {
public:
    Error(int status, const std::string &message) : std::runtime_error(message), status_(status) {}
    int status() const noexcept { return status_; }

private:
    int status_;
};

// Throws Error(status) with the message "function: parts...", numbers with
// every digit they have.
template <class... Parts>
[[noreturn]] void fail(int status, const char *function, const Parts &...parts) {
    std::ostringstream msg;
    msg.precision(17);
    msg << function << ": ";
    (msg << ... << parts);
    throw Error(status, msg.str());
}

}  // namespace dpsm
