#include "model/distribution.hpp"

namespace dpsm {

std::string on_rank(const char *function, const Failure &failure) {
    const std::string prefix = std::string(function) + ": ";
    std::string text = failure.message;
    if (text.compare(0, prefix.size(), prefix) == 0) text = text.substr(prefix.size());
    return prefix + "on rank " + std::to_string(failure.rank) + ": " + text;
}

}  // namespace dpsm
